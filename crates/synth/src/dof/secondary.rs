//! The secondary samples of Widmer et al. 2015, §5.2: lens samples that are not traced but
//! intersected with the plane of the quad-tree leaf the primary lens ray hit, and weighted
//! by how well the intersection agrees with the captured depth there (Fig. 8).
//!
//! For a secondary ray `r` and the hit leaf's cube-space plane `N·P = c` (the plane node
//! the traversal tested, [`QuadTree::effective_node`]), pulled back to a world plane
//! through the cube's projective map ([`UnitCube`]), `r` meets the plane at `P`; no sample
//! when that is behind `r`'s origin, outside the reference's image, or the plane is parallel
//! to `r`. At `P` the layer's own pixel plane (the captured sample's tangent plane, the
//! per-pixel plane of §3.2) gives the captured depth `d_b` at that sub-pixel position, the
//! intersection's depth is `d_i`, and the sample weighs
//!
//! ```text
//! w = exp(-((d_i - d_b) / d_b)^2 / sigma^2)
//! ```
//!
//! (0 where the pixel holds no plane: nothing captured there). Its colour is the warp's
//! depth-aware bilinear colour of a hit at `P` ([`Resample::Bilinear`], the default of
//! [`super::DofOptions::secondary_resample`], [`RayWarp::colour`]) or the layer's colour at
//! that pixel ([`Resample::Nearest`]: cheaper, noisier; measured in `docs/notes/synth.md`). The lens ray's colour is
//! `(c_0 + sum_j w_j c_j) / (1 + sum_j w_j)` with `c_0` the traced ray's colour.
//!
//! **Invariant:** a secondary sample equal to the primary lens ray gets weight 1 up to the
//! plane fit (the leaf plane and the pixel plane agree at the hit) — tested.

use std::ops::AddAssign;

use glam::{Mat3, UVec2, Vec4};
use parallax_core::{GBuffer, Image, Ray, Rgb};
use parallax_scene::camera::Pinhole;
use parallax_screen::quadtree::node::decode_plane;
use parallax_screen::{QuadTree, QuadTreeTracer, TraceResult, UnitCube};
use serde::Serialize;

use crate::layers::Reference;
use crate::warp::{RayWarp, Resample};

/// Counters of the secondary samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SecondaryStats {
    /// Secondary samples generated.
    pub samples: u64,
    /// Samples whose ray met the leaf plane inside the cube and landed on a captured pixel.
    pub on_plane: u64,
    /// Sum of their weights in units of `2^-24` (an integer, so the sum does not depend on
    /// the order rows are added in: thread-count independent).
    pub weight_q24: u64,
}

/// Scale of [`SecondaryStats::weight_q24`].
const Q24: f32 = (1u32 << 24) as f32;

impl SecondaryStats {
    /// Mean weight per generated sample (1 = every sample counted fully).
    pub fn mean_weight(&self) -> f64 {
        self.weight_q24 as f64 / Q24 as f64 / self.samples.max(1) as f64
    }
}

impl AddAssign for SecondaryStats {
    fn add_assign(&mut self, o: Self) {
        self.samples += o.samples;
        self.on_plane += o.on_plane;
        self.weight_q24 += o.weight_q24;
    }
}

/// The quad-tree's leaf planes and the layers' pixel planes, for secondary samples.
pub struct LeafPlanes<'a> {
    trees: &'a [QuadTree],
    layers: &'a [GBuffer],
    colors: &'a [Image<Rgb>],
    resample: Resample,
    cube: &'a UnitCube,
    camera: &'a Pinhole,
    /// World -> reference camera rotation (the frame's transpose).
    to_camera: Mat3,
    inv_sigma2: f32,
}

impl<'a> LeafPlanes<'a> {
    /// The planes of `tracer` (built over `reference`) with weight width `sigma`, samples
    /// coloured with `resample`.
    pub fn new(
        tracer: &'a QuadTreeTracer,
        reference: &'a Reference,
        sigma: f32,
        resample: Resample,
    ) -> Self {
        Self {
            trees: &tracer.trees,
            layers: &reference.layers,
            colors: &reference.colors,
            resample,
            cube: &reference.cube,
            camera: &reference.camera,
            to_camera: reference.camera.frame.basis.transpose(),
            inv_sigma2: 1.0 / (sigma * sigma),
        }
    }

    /// The world-space plane `(n, w)` (`n·X + w = 0`, `|n| = 1`) of the leaf the traversal
    /// uses at `pixel` of `layer`: the cube plane `N·P = c` pulled back through the cube's
    /// projective map, `π = M^T (N, -c)` (f64, then normalised).
    #[inline]
    fn leaf(&self, layer: u32, pixel: UVec2) -> Option<Vec4> {
        let tree = self.trees.get(layer as usize)?;
        let (node, l, qx, qy) = tree.effective_node(pixel.x, pixel.y)?;
        let (w, h) = tree.size();
        let (n, c) = decode_plane(node, l, qx, qy, w as f32, h as f32);
        let pi = self.cube.world_to_cube.transpose() * n.as_dvec3().extend(-c as f64);
        let len = pi.truncate().length();
        (len.is_finite() && len > 0.0).then(|| (pi / len).as_vec4())
    }

    /// One secondary sample `ray` against the world plane `plane` of `layer`'s leaf: the hit
    /// it stands for and its weight (module docs), `None` when it meets the plane behind its
    /// origin or outside the reference's image, or lands where the layer holds nothing. The
    /// intersection `X` (`t = -π·(o, 1) / π·(d, 0)`) is the cube-space one (the map is
    /// projective); the pixel plane at `X` is the captured sample's tangent plane
    /// (`position p`, `normal n`), which the reference eye `e`'s ray through `X` meets at
    /// depth `d_b`, so that `(d_i - d_b) / d_b = n·(X - p) / n·(p - e)`.
    #[inline]
    pub fn sample(&self, layer: u32, plane: Vec4, ray: &Ray) -> Option<(TraceResult, f32)> {
        let n = plane.truncate();
        let t = -(n.dot(ray.origin) + plane.w) / n.dot(ray.dir);
        if !(t > ray.t_min && t < ray.t_max) {
            return None;
        }
        let x = ray.at(t);
        let eye = self.camera.frame.position;
        let q = self.to_camera * (x - eye);
        let film = self.camera.film_of_camera_point(q)?;
        let g = &self.layers[layer as usize];
        let (w, h) = (g.width(), g.height());
        if !(film.x >= 0.0 && film.y >= 0.0 && film.x < w as f32 && film.y < h as f32) {
            return None;
        }
        let (px, py) = (film.x as u32, film.y as u32);
        let i = g.index(px, py);
        if !(g.depth[i].is_finite() && g.depth[i] > 0.0) {
            return None;
        }
        let (p, ng) = (g.position[i], g.normal[i]);
        let rel = ng.dot(x - p) / ng.dot(p - eye);
        let weight = (-rel * rel * self.inv_sigma2).exp();
        let hit = TraceResult::Hit {
            layer,
            pixel: UVec2::new(px, py),
            position: x,
            t,
        };
        Some((hit, if weight.is_nan() { 0.0 } else { weight }))
    }

    /// The colour of a lens ray that hit `pixel` of `layer` with colour `primary`, blended
    /// with its secondary samples `rays` (module docs).
    pub fn blend(
        &self,
        per_ray: &RayWarp,
        layer: u32,
        pixel: UVec2,
        primary: Rgb,
        rays: impl Iterator<Item = Ray>,
        stats: &mut SecondaryStats,
    ) -> Rgb {
        let Some(plane) = self.leaf(layer, pixel) else {
            return primary;
        };
        let (mut sum, mut wsum) = (primary, 1.0f32);
        for ray in rays {
            stats.samples += 1;
            let Some((hit, wgt)) = self.sample(layer, plane, &ray) else {
                continue;
            };
            stats.on_plane += 1;
            stats.weight_q24 += (wgt * Q24) as u64;
            if wgt > 0.0 {
                let c = match (self.resample, hit) {
                    (Resample::Nearest, TraceResult::Hit { layer, pixel, .. }) => self
                        .colors
                        .get(layer as usize)
                        .map_or(Rgb::ZERO, |c| *c.get(pixel.x, pixel.y)),
                    _ => per_ray.colour(&ray, hit).0,
                };
                sum += c * wgt;
                wsum += wgt;
            }
        }
        sum / wsum
    }
}
