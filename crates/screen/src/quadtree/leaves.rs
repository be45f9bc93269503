//! The leaves of a G-buffer layer (Widmer et al. 2015, §3.2; the definition is in
//! `build.rs`'s module docs): pixel `(i, j)` with a finite positive depth and a non-zero
//! normal becomes the level-0 plane node of the world plane through its sample point (the
//! pixel-centre ray at the captured view depth), its cube gradient computed in f64 from the
//! mapped plane ([`UnitCube::map_plane`]'s covector) and stored as f16 slopes, `z_c` the
//! sample's cube `z`; degenerate maps and samples in front of the near plane give
//! [`Node::EMPTY`].
//!
//! A row at a time, with what every pixel needs computed once: the transposed inverse cube
//! map, the per-column and per-row terms of the pixel-centre directions (the same products
//! as `camera_dir` / `dir_to_world`, so the same sums), and [`UnitCube::z_of_depth`]'s
//! constant terms (the same f64 values). Three paths, one set of bits:
//!
//! - the definitions (`reference`: the camera's own functions, `map_gradient`,
//!   [`Node::plane_with_gradient`]), which `QuadTreeTracer::build_reference` runs;
//! - one pixel at a time in SSE2 lanes (`leaf_lanes`, the x86_64 baseline);
//! - four pixels at a time in AVX2 lanes (`leaf_avx2`, under run-time detection), the row's
//!   last `W mod 4` pixels by the SSE2 path.
//!
//! `tests/quadtree_build.rs` compares the fast build with the reference tree for tree;
//! `leaf_avx2`'s own test compares its rows with the SSE2 path pixel for pixel.

use glam::Vec3;

use super::node::{FLAG_CRACK, Node};
use crate::UnitCube;

/// The leaves of a G-buffer layer (module docs).
pub(super) struct Leaves<'a> {
    cube: &'a UnitCube,
    depth: &'a [f32],
    normals: &'a [Vec3],
    /// Flag `O` per pixel (depth normals), if any.
    flags: Option<&'a [bool]>,
    mt: glam::DMat4,
    /// `mt` and the node's scale for the lanes of `leaf_lanes`.
    #[cfg(target_arch = "x86_64")]
    map: super::leaf_lanes::LeafMap,
    /// The same constants for `leaf_avx2`, if the CPU has AVX2.
    #[cfg(target_arch = "x86_64")]
    map4: Option<super::leaf_avx2::LeafMap4>,
    col: Vec<Vec3>,
    /// `col` as three columns (x, y, z) for `leaf_avx2`.
    #[cfg(target_arch = "x86_64")]
    col_soa: [Vec<f32>; 3],
    row: Vec<Vec3>,
    back: Vec3,
    /// `1 / near` and `1 / near - 1 / far`, in f64.
    inv_near: f64,
    z_den: f64,
    wf: f32,
    hf: f32,
}

impl<'a> Leaves<'a> {
    /// The leaves of the `w x h` layer with view depths `depth` and world normals `normals`
    /// (flag `O` per pixel from `flags`) captured from `cube.camera`.
    pub(super) fn new(
        cube: &'a UnitCube,
        depth: &'a [f32],
        normals: &'a [Vec3],
        flags: Option<&'a [bool]>,
        w: u32,
        h: u32,
    ) -> Self {
        let cam = &cube.camera;
        let (tx, ty) = (cam.tan_half_x(), cam.tan_half_y);
        let b = cam.frame.basis;
        let (cw, ch) = (cam.width as f32, cam.height as f32);
        let (n, f) = (cube.near as f64, cube.far as f64);
        let mt = cube.cube_to_world.transpose();
        // The world direction through a pixel centre, `basis * camera_dir(film)`, is
        // `(x_axis dx + y_axis dy) + z_axis (-1)` (glam's `Mat3 * Vec3` order): its column
        // and row terms are tabulated once, the same products, so the sum is the same bits.
        let col: Vec<Vec3> = (0..w)
            .map(|i| b.x_axis * ((2.0 * (i as f32 + 0.5) / cw - 1.0 + cam.shift.x) * tx))
            .collect();
        let back = b.z_axis * -1.0;
        let (inv_near, z_den) = (1.0 / n, 1.0 / n - 1.0 / f);
        Self {
            cube,
            depth,
            normals,
            flags,
            mt,
            #[cfg(target_arch = "x86_64")]
            map: super::leaf_lanes::LeafMap::new(&mt, w as f32, h as f32),
            #[cfg(target_arch = "x86_64")]
            map4: super::leaf_avx2::LeafMap4::new(
                &mt,
                cam.frame.position,
                back,
                inv_near,
                z_den,
                w as f32,
                h as f32,
            ),
            #[cfg(target_arch = "x86_64")]
            col_soa: [
                col.iter().map(|c| c.x).collect(),
                col.iter().map(|c| c.y).collect(),
                col.iter().map(|c| c.z).collect(),
            ],
            col,
            row: (0..h)
                .map(|j| b.y_axis * ((1.0 - 2.0 * (j as f32 + 0.5) / ch + cam.shift.y) * ty))
                .collect(),
            back,
            inv_near,
            z_den,
            wf: w as f32,
            hf: h as f32,
        }
    }

    /// The leaves of pixel row `j` into `out[..W]`; `reference`: the pixel direction by
    /// the camera's own function and [`UnitCube::z_of_depth`] (the definitions).
    pub(super) fn row(&self, out: &mut [Node], j: u32, reference: bool) {
        if reference {
            self.row_with::<true>(out, j)
        } else {
            self.row_with::<false>(out, j)
        }
    }

    #[inline(always)]
    fn row_with<const REFERENCE: bool>(&self, out: &mut [Node], j: u32) {
        let w = self.col.len();
        let k0 = j as usize * w;
        let (depth, normals) = (&self.depth[k0..k0 + w], &self.normals[k0..k0 + w]);
        let rj = self.row[j as usize];
        let cam = &self.cube.camera;
        #[allow(unused_mut)]
        let mut start = 0;
        #[cfg(target_arch = "x86_64")]
        if let (false, Some(map4)) = (REFERENCE, &self.map4) {
            // SAFETY: `map4` exists only if the CPU has AVX2 (`LeafMap4::new`).
            start = unsafe {
                map4.row(
                    [&self.col_soa[0], &self.col_soa[1], &self.col_soa[2]],
                    rj,
                    depth,
                    normals,
                    self.flags.map(|f| &f[k0..k0 + w]),
                    &mut out[..w],
                )
            };
        }
        for (i, o) in out[..w].iter_mut().enumerate().skip(start) {
            let d = depth[i];
            let n = normals[i];
            *o = if !(d.is_finite() && d > 0.0) || n == Vec3::ZERO {
                Node::EMPTY
            } else {
                let dir = if REFERENCE {
                    let film = glam::Vec2::new(i as f32 + 0.5, j as f32 + 0.5);
                    cam.frame.dir_to_world(cam.camera_dir(film))
                } else {
                    (self.col[i] + rj) + self.back
                };
                let p = cam.frame.position + dir * d;
                #[cfg(target_arch = "x86_64")]
                if !REFERENCE {
                    // The same map and node in SSE2 lanes (`leaf_lanes`).
                    let f = if self.flags.is_some_and(|f| f[k0 + i]) {
                        FLAG_CRACK
                    } else {
                        0
                    };
                    let z = ((self.inv_near - 1.0 / d as f64) / self.z_den) as f32;
                    *o = self.map.leaf(p, n, z, f);
                    continue;
                }
                match map_gradient(&self.mt, p, n) {
                    None => Node::EMPTY,
                    Some((gx, gy)) => {
                        let f = if self.flags.is_some_and(|f| f[k0 + i]) {
                            FLAG_CRACK
                        } else {
                            0
                        };
                        let z = if REFERENCE {
                            self.cube.z_of_depth(d)
                        } else {
                            ((self.inv_near - 1.0 / d as f64) / self.z_den) as f32
                        };
                        Node::plane_with_gradient(z, gx, gy, 0, self.wf, self.hf, f)
                            .unwrap_or(Node::EMPTY)
                    }
                }
            };
        }
    }
}

/// The cube gradient `(dz/dx, dz/dy)` of the plane of [`UnitCube::map_plane`] with the
/// transposed inverse map `mt` precomputed, in f64 from the unnormalised cube covector `q`
/// (`-(q.x, q.y) / q.z`, infinite for a plane vertical in the cube; the node clamps it).
/// `None` when degenerate (also when the plane is vertical *and* parallel to `x` or `y`
/// with a zero numerator, `0 / 0`).
#[inline]
fn map_gradient(mt: &glam::DMat4, p: Vec3, n: Vec3) -> Option<(f32, f32)> {
    let (p, n) = (p.as_dvec3(), n.as_dvec3());
    let q = *mt * n.extend(-n.dot(p));
    // `|q.xyz|` finite and > 0 (as `map_plane` asks), without its square root: the same
    // answer, since the square root of a non-negative value is finite and positive exactly
    // when the value is.
    let len2 = q.truncate().length_squared();
    if !(len2.is_finite() && len2 > 0.0) {
        return None;
    }
    // Orientation-free: the gradient is the same for q and -q.
    let g = |a: f64| {
        let v = a / -q.z;
        if v.is_nan() { None } else { Some(v as f32) }
    };
    Some((g(q.x)?, g(q.y)?))
}
