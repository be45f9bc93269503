//! The colour and kind of a trace result in the stereo warp's per-pixel loop
//! ([`super`], module docs "Colour resampling" and "Visible samples first"): hit ->
//! the hit layer's colour, depth-aware bilinear at the hit's projected sub-pixel position;
//! miss -> the environment; occlusion volume -> the crossed pixel's colour.
//!
//! [`Resolver`] is built once per warp: it holds every layer's depth / normal / position /
//! colour as flat slices and the per-warp constants, so the per-pixel work is the f64
//! projection of the hit, an inline floor and the 2x2 blend with no per-pixel lookups of
//! layers or image sizes and no calls. Every arithmetic operation and its order are those of
//! the straightforward version (kept as the slow twin in this file's tests), so the output is
//! bit-identical to it.

use glam::{UVec2, Vec3};
use parallax_core::Rgb;
use parallax_core::math::{FLOOR_EXACT, floor_i32};
use parallax_screen::{TraceResult, UnitCube};

use super::hit::{HitKind, Resample, SAME_SURFACE_PX};
use crate::layers::Reference;

/// One layer as flat row-major slices (colours and G-buffer share size and index).
struct LayerSlices<'a> {
    depth: &'a [f32],
    normal: &'a [Vec3],
    position: &'a [Vec3],
    color: &'a [Rgb],
    w: u32,
    h: u32,
}

impl LayerSlices<'_> {
    /// Sample `i` is covered and lies on the surface through `p` with normal `n` (within
    /// `tol` of the plane, normals within 60°): [`super::hit::same_surface`].
    #[inline(always)]
    fn same_surface(&self, i: usize, p: Vec3, n: Vec3, tol: f32) -> bool {
        let d = self.depth[i];
        d.is_finite()
            && d > 0.0
            && n.dot(self.normal[i]) > 0.5
            && n.dot(self.position[i] - p).abs() <= tol
    }
}

/// Per-warp colour lookup of trace results (module docs).
pub(super) struct Resolver<'a> {
    layers: Vec<LayerSlices<'a>>,
    cube: &'a UnitCube,
    background: Rgb,
    /// `reference.camera.tan_half_y` and `reference.height() as f32` (the same-surface tolerance).
    tan_half_y: f32,
    height: f32,
    resample: Resample,
}

impl<'a> Resolver<'a> {
    /// The lookup of `reference`'s layers. A layer whose colour image does not match its
    /// G-buffer's size (not produced by [`Reference`]'s constructors) is left out with the
    /// layers after it: their answers take the environment colour.
    pub(super) fn new(reference: &'a Reference, resample: Resample) -> Self {
        let layers = reference
            .layers
            .iter()
            .zip(&reference.colors)
            .map_while(|(g, c)| {
                let n = g.depth.len();
                (c.width() == g.width()
                    && c.height() == g.height()
                    && c.data().len() == n
                    && g.normal.len() == n
                    && g.position.len() == n)
                    .then(|| LayerSlices {
                        depth: &g.depth,
                        normal: &g.normal,
                        position: &g.position,
                        color: c.data(),
                        w: g.width(),
                        h: g.height(),
                    })
            })
            .collect();
        Self {
            layers,
            cube: &reference.cube,
            background: reference.background,
            tan_half_y: reference.camera.tan_half_y,
            height: reference.height() as f32,
            resample,
        }
    }

    /// The colour and kind of one trace result.
    #[inline(always)]
    pub(super) fn resolve(&self, r: TraceResult) -> (Rgb, HitKind) {
        match r {
            TraceResult::Hit {
                layer,
                pixel,
                position,
                ..
            } => {
                let c = match self.resample {
                    Resample::Nearest => self.fetch(layer, pixel),
                    Resample::Bilinear => self
                        .bilinear(layer, pixel, position)
                        .unwrap_or_else(|| self.fetch(layer, pixel)),
                };
                (c, HitKind::Hit(layer as u8))
            }
            TraceResult::Miss => (self.background, HitKind::Miss),
            TraceResult::OcclusionVolume { layer, pixel, .. } => {
                (self.fetch(layer, pixel), HitKind::Occlusion(layer as u8))
            }
        }
    }

    /// The colour of one layer pixel (the environment outside the image).
    #[inline(always)]
    fn fetch(&self, layer: u32, p: UVec2) -> Rgb {
        match self.layers.get(layer as usize) {
            Some(l) if p.x < l.w && p.y < l.h => {
                l.color[p.y as usize * l.w as usize + p.x as usize]
            }
            _ => self.background,
        }
    }

    /// Depth-aware bilinear colour of a hit at world `position` answered by `pixel` of
    /// `layer`; `None` when the hit pixel is not one of the four neighbours of the projected
    /// position (the caller takes the nearest colour).
    #[inline(always)]
    fn bilinear(&self, layer: u32, pixel: UVec2, position: Vec3) -> Option<Rgb> {
        let g = self.layers.get(layer as usize)?;
        let (w, h) = (g.w, g.h);
        if pixel.x >= w || pixel.y >= h {
            return None;
        }
        let hc = self.cube.homogeneous(position);
        if !(hc.w > 0.0) {
            return None;
        }
        let depth = hc.w as f32;
        // Film position minus the pixel-centre offset: integer values are pixel centres.
        let fx = (hc.x / hc.w) as f32 * w as f32 - 0.5;
        let fy = (hc.y / hc.w) as f32 * h as f32 - 0.5;
        // Non-finite or |f| >= 2^23 (then an integer beyond any image, > w and h): the hit
        // pixel is not a neighbour, as the range test below would find.
        if !(fx.abs() < FLOOR_EXACT && fy.abs() < FLOOR_EXACT) {
            return None;
        }
        let (x0, y0) = (floor_i32(fx), floor_i32(fy));
        // `fx - fx.floor()` except for fx = -0.0 (floor -0.0, here +0.0: tx = -0.0 instead
        // of +0.0, which changes no weight: 1 - tx = 1, tx * wy = ±0 is not > 0).
        let (tx, ty) = (fx - x0 as f32, fy - y0 as f32);
        let (px, py) = (pixel.x as i64, pixel.y as i64);
        let (x0, y0) = (x0 as i64, y0 as i64);
        if !(x0..=x0 + 1).contains(&px) || !(y0..=y0 + 1).contains(&py) {
            return None;
        }
        let hi = pixel.y as usize * w as usize + pixel.x as usize;
        let (p_hit, n_hit) = (g.position[hi], g.normal[hi]);
        // `same_surface_tol`, same operations.
        let footprint = depth * 2.0 * self.tan_half_y / self.height;
        let tol = SAME_SURFACE_PX * footprint + 1e-4 * depth;
        let cell = Cell::new(x0, y0, tx, ty, w, h);
        // A deeper layer's hit blends the layer-0 samples of its surface when there are any.
        if layer >= 1 {
            let g0 = &self.layers[0];
            let visible = cell.blend(g0.color, |i| g0.same_surface(i, p_hit, n_hit, tol));
            if visible.is_some() {
                return visible;
            }
        }
        cell.blend(g.color, |i| i == hi || g.same_surface(i, p_hit, n_hit, tol))
    }
}

/// The 2x2 pixel centres around a sub-pixel position whose top-left corner `(x0, y0)` lies
/// in `[-1, w - 1] x [-1, h - 1]`: their row-major indices, whether they lie in the image,
/// and their bilinear weights, in the blend order (0,0), (1,0), (0,1), (1,1).
struct Cell {
    idx: [usize; 4],
    inside: [bool; 4],
    wgt: [f32; 4],
}

impl Cell {
    #[inline(always)]
    fn new(x0: i64, y0: i64, tx: f32, ty: f32, w: u32, h: u32) -> Self {
        let (w, h) = (w as i64, h as i64);
        let (vx, vy) = ([x0 >= 0, x0 + 1 < w], [y0 >= 0, y0 + 1 < h]);
        let base = y0 * w + x0;
        let at = |dx: i64, dy: i64| (base + dy * w + dx).max(0) as usize;
        let (wx, wy) = ([1.0 - tx, tx], [1.0 - ty, ty]);
        Self {
            idx: [at(0, 0), at(1, 0), at(0, 1), at(1, 1)],
            inside: [vx[0] & vy[0], vx[1] & vy[0], vx[0] & vy[1], vx[1] & vy[1]],
            wgt: [wx[0] * wy[0], wx[1] * wy[0], wx[0] * wy[1], wx[1] * wy[1]],
        }
    }

    /// The blend of `colors` over the in-image pixels with positive weight whose index
    /// `keep` accepts, weights renormalised; `None` when they carry no weight.
    #[inline(always)]
    fn blend(&self, colors: &[Rgb], keep: impl Fn(usize) -> bool) -> Option<Rgb> {
        let mut sum = Vec3::ZERO;
        let mut wsum = 0.0f32;
        for k in 0..4 {
            let (i, wgt) = (self.idx[k], self.wgt[k]);
            if self.inside[k] && wgt > 0.0 && keep(i) {
                sum += colors[i] * wgt;
                wsum += wgt;
            }
        }
        (wsum > 1e-6).then(|| sum / wsum)
    }
}

#[cfg(test)]
mod tests {
    //! The resolver against the straightforward version it replaced (the slow twin:
    //! per-pixel `Option` lookups of layers and images, `f32::floor`, a closure per blend).

    use glam::Vec2;
    use parallax_core::{GBuffer, Image};
    use parallax_scene::camera::{CameraModel, Eye, Pinhole, StereoRig};
    use parallax_scene::{CameraDesc, Scene};
    use parallax_screen::{BruteForcePlanes, LayerPlanes, NormalSource, ScreenTracer};

    use super::*;
    use crate::layers::capture_reference;
    use crate::warp::hit::{same_surface, same_surface_tol};
    use parallax_render::score::Shading;

    fn twin_resolve(reference: &Reference, r: TraceResult, resample: Resample) -> (Rgb, HitKind) {
        match r {
            TraceResult::Hit {
                layer,
                pixel,
                position,
                ..
            } => {
                let c = match resample {
                    Resample::Nearest => twin_fetch(reference, layer, pixel),
                    Resample::Bilinear => twin_bilinear(reference, layer, pixel, position)
                        .unwrap_or_else(|| twin_fetch(reference, layer, pixel)),
                };
                (c, HitKind::Hit(layer as u8))
            }
            TraceResult::Miss => (reference.background, HitKind::Miss),
            TraceResult::OcclusionVolume { layer, pixel, .. } => (
                twin_fetch(reference, layer, pixel),
                HitKind::Occlusion(layer as u8),
            ),
        }
    }

    fn twin_fetch(reference: &Reference, layer: u32, p: UVec2) -> Rgb {
        reference
            .colors
            .get(layer as usize)
            .filter(|c| p.x < c.width() && p.y < c.height())
            .map(|c| *c.get(p.x, p.y))
            .unwrap_or(reference.background)
    }

    fn twin_bilinear(
        reference: &Reference,
        layer: u32,
        pixel: UVec2,
        position: Vec3,
    ) -> Option<Rgb> {
        let g: &GBuffer = reference.layers.get(layer as usize)?;
        let colors = reference.colors.get(layer as usize)?;
        let (w, h) = (g.width(), g.height());
        if pixel.x >= w || pixel.y >= h {
            return None;
        }
        let hc = reference.cube.homogeneous(position);
        if !(hc.w > 0.0) {
            return None;
        }
        let depth = hc.w as f32;
        let fx = (hc.x / hc.w) as f32 * w as f32 - 0.5;
        let fy = (hc.y / hc.w) as f32 * h as f32 - 0.5;
        if !(fx.is_finite() && fy.is_finite()) {
            return None;
        }
        let (x0, y0) = (fx.floor(), fy.floor());
        let (tx, ty) = (fx - x0, fy - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let (px, py) = (pixel.x as i64, pixel.y as i64);
        if !(x0..=x0 + 1).contains(&px) || !(y0..=y0 + 1).contains(&py) {
            return None;
        }
        let hi = g.index(pixel.x, pixel.y);
        let (p_hit, n_hit) = (g.position[hi], g.normal[hi]);
        let tol = same_surface_tol(reference, depth);
        if layer >= 1 {
            let (g0, c0) = (&reference.layers[0], &reference.colors[0]);
            let visible = twin_blend(c0, (x0, y0), (tx, ty), |i| {
                same_surface(g0, i, p_hit, n_hit, tol)
            });
            if visible.is_some() {
                return visible;
            }
        }
        twin_blend(colors, (x0, y0), (tx, ty), |i| {
            i == hi || same_surface(g, i, p_hit, n_hit, tol)
        })
    }

    fn twin_blend(
        colors: &Image<Rgb>,
        (x0, y0): (i64, i64),
        (tx, ty): (f32, f32),
        keep: impl Fn(usize) -> bool,
    ) -> Option<Rgb> {
        let (w, h) = (colors.width() as i64, colors.height() as i64);
        let mut sum = Vec3::ZERO;
        let mut wsum = 0.0f32;
        for (dy, wy) in [(0, 1.0 - ty), (1, ty)] {
            for (dx, wx) in [(0, 1.0 - tx), (1, tx)] {
                let (x, y) = (x0 + dx, y0 + dy);
                if x < 0 || y < 0 || x >= w || y >= h {
                    continue;
                }
                let (x, y) = (x as u32, y as u32);
                let wgt = wx * wy;
                if wgt > 0.0 && keep(colors.index(x, y)) {
                    sum += *colors.get(x, y) * wgt;
                    wsum += wgt;
                }
            }
        }
        (wsum > 1e-6).then(|| sum / wsum)
    }

    fn bits(c: Rgb) -> [u32; 3] {
        c.to_array().map(f32::to_bits)
    }

    /// Every trace result of a warp (hits of both layers, misses, occlusion volumes) and
    /// synthetic hits around them resolve bit-identically to the slow twin.
    #[test]
    fn resolver_equals_slow_twin() {
        let scene = Scene::load("atrium").unwrap();
        let bvh = parallax_bvh::Bvh::try_build(&scene.mesh).unwrap();
        let desc: CameraDesc = scene.camera(None).unwrap();
        let cam = Pinhole::new(&desc, 96, 64).unwrap();
        let r = capture_reference(&scene, &bvh, &cam, 2, Shading::Fixed, 0).unwrap();
        // The brute-force tracer and the stereo eyes as `method::build_tracer(Method::Brute)`
        // and `stereo::stereo_eyes` make them (MethodOptions::default normals: the G-buffer's).
        let tracer = BruteForcePlanes {
            cube: r.cube.clone(),
            layers: (r.layers.iter())
                .map(|g| LayerPlanes::build(&r.cube, g, NormalSource::GBuffer).unwrap())
                .collect(),
        };
        let rig = StereoRig::new(&desc, 96, 64, 0.5).unwrap();
        let eyes = [rig.eye(Eye::Left).clone(), rig.eye(Eye::Right).clone()];
        let (mut n, mut deep, mut blended) = (0, 0, 0);
        for resample in [Resample::Bilinear, Resample::Nearest] {
            let fast = Resolver::new(&r, resample);
            for eye in &eyes {
                for y in 0..64 {
                    for x in 0..96 {
                        let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                        let ray = eye.generate_ray(film, Vec2::splat(0.5), 1).unwrap().ray;
                        let mut s = Default::default();
                        let t = tracer.trace(&ray, &mut s);
                        let mut cases = vec![t];
                        // Off-centre and off-layer variants of hits.
                        if let TraceResult::Hit {
                            layer,
                            pixel,
                            position,
                            t,
                        } = t
                        {
                            for (dp, l) in [
                                (Vec3::new(0.03, -0.02, 0.01), layer),
                                (Vec3::ZERO, 1 - layer.min(1)),
                                (Vec3::ZERO, 7),
                                (Vec3::new(-5.0, 2.0, 3.0), layer),
                            ] {
                                cases.push(TraceResult::Hit {
                                    layer: l,
                                    pixel,
                                    position: position + dp,
                                    t,
                                });
                            }
                            cases.push(TraceResult::Hit {
                                layer,
                                pixel: UVec2::new(pixel.x + 1000, pixel.y),
                                position,
                                t,
                            });
                            deep += (layer >= 1) as u32;
                        }
                        for c in cases {
                            let (a, ka) = fast.resolve(c);
                            let (b, kb) = twin_resolve(&r, c, resample);
                            assert_eq!((bits(a), ka), (bits(b), kb), "{c:?} {resample:?}");
                            blended += (bits(a) != bits(twin_fetch(&r, 0, UVec2::ZERO))) as u32;
                            n += 1;
                        }
                    }
                }
            }
        }
        assert!(
            n > 40_000 && deep > 0 && blended > 1000,
            "{n} {deep} {blended}"
        );
    }
}
