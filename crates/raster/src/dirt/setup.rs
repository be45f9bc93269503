//! Triangle setup of the DIRT build (§4.1.1 "Fill Depth": "a geometry shader outputs each
//! primitive ... to the fragment shader"): a triangle is taken to the view's camera space in
//! f64, culled or clipped against the near plane and a guard band around the film, projected
//! to `(film x, film y, w = 1 / view depth)`, and given the plane of `w` over the film.
//!
//! **Fast path.** Most triangles lie wholly inside all five clip planes (no clipping) or
//! wholly outside one of them (culled); only the rest go through Sutherland-Hodgman. The test
//! is by outcodes (a bit per plane and corner), the near plane first (it alone culls the
//! triangles behind a cube face); a view whose rotation rows are signed coordinate axes (the
//! cube faces) transforms by picking components instead of dot products (the same values);
//! finiteness is checked once per triangle for all views, and so are the corners' offsets
//! from the eye for views that share it (the camera view and the cube faces around its eye).
//! The cube faces' outcode test is made for all six at once ([`FaceCull`], `cull.rs`), and
//! only the faces it keeps are set up; a kept face with every corner inside every plane (the
//! cull says so too) skips its own outcode test.
//!
//! **The `w` plane.** A triangle's plane `n . q = d` in camera space meets the ray through film
//! position `(x, y)`, direction `(u, v, -1)` with `u = a0 + x ax`, `v = b0 - y by`, at view
//! depth `d / (n . dir)`, so `w = (n.x u + n.y v - n.z) / d` is affine in `(x, y)` (exact, also
//! for a triangle clipped by the near plane: the clipped polygon lies in the same plane). The
//! plane is dropped (`None`) for a triangle whose plane passes within `1e-7` (relative) of the
//! eye, seen edge-on: evaluating it there would amplify rounding; such a triangle's depth
//! range in a cell is the range over its row slab instead (wider, still conservative).

use glam::DVec3;
use parallax_scene::TriangleMesh;
use parallax_scene::camera::Pinhole;

use super::clip::Poly;
use super::cull::{AxisView, FaceCull};

/// Guard band (pixels) around the film: triangles are clipped to it in camera space before
/// projection, so projected coordinates stay small (well conditioned) whatever the near plane.
const GUARD_PX: f64 = 2.0;
/// Absolute depth margin, in units of f32::EPSILON times the triangle's coordinate scale.
const DEPTH_ABS_ULPS: f64 = 32.0;
/// A plane whose offset from the eye is below this fraction of `|n| |q|` is "edge-on".
const EDGE_ON: f64 = 1e-7;

/// `w = p0 + px * x + py * y` over the film.
#[derive(Clone, Copy, Debug)]
pub(super) struct WPlane {
    pub p0: f64,
    pub px: f64,
    pub py: f64,
}

/// A set-up triangle (its clipped projection, vertices `(film x, film y, w)`, is the
/// [`Poly`] [`ViewXf::setup`] wrote), with its `w` plane and the absolute depth margin for it.
#[derive(Clone, Copy, Debug)]
pub(super) struct SetupEntry {
    pub tri: u32,
    pub plane: Option<WPlane>,
    pub abs_margin: f64,
    /// Film y range of the polygon.
    pub y: (f64, f64),
    /// Film x and `w` ranges of the polygon (its row span when it lies inside one row slab).
    pub x: (f64, f64),
    pub w: (f64, f64),
}

/// Triangles per task of the fused setup and rasterization (`build.rs`).
pub(super) const SETUP_CHUNK: usize = 1 << 11;

/// The view in f64: rotation rows (camera space = R (p - eye)), projection constants and the
/// near + guard clip planes (camera space, `n . q + d >= 0` inside).
pub(super) struct ViewXf {
    rows: [DVec3; 3],
    /// The guard planes' slopes (`q.x + ax_lo q.z >= 0` ...).
    slopes: [f64; 4],
    /// `[a0, 1 / ax, b0, 1 / by]`: film x = `(u - a0) / ax`, film y = `(b0 - v) / by` of the
    /// slopes `u = q.x / depth`, `v = q.y / depth`.
    film: [f64; 4],
    near: f64,
    eye: DVec3,
    eye_mag: f64,
    pub w: f64,
    pub h: f64,
    planes: [(DVec3, f64); 5],
    /// `Some` when every rotation row is a signed coordinate axis (the cube map's faces): row
    /// `i` picks component `axes[i].0` of `p - eye` times `axes[i].1` (exactly its dot
    /// product, up to the sign of a zero).
    axes: Option<[(usize, f64); 3]>,
}

/// `(k, ±1)` if `r` is `±e_k` exactly.
fn signed_axis(r: DVec3) -> Option<(usize, f64)> {
    let a = r.to_array();
    let k = (0..3).find(|&k| a[k].abs() == 1.0)?;
    (0..3).all(|j| j == k || a[j] == 0.0).then_some((k, a[k]))
}

impl ViewXf {
    pub fn new(view: &Pinhole, near: f64) -> ViewXf {
        let b = view.frame.basis;
        let (w, h) = (view.width as f64, view.height as f64);
        // The same f32 constants the pinhole's ray generation uses.
        let tx = view.tan_half_x() as f64;
        let ty = view.tan_half_y as f64;
        let (sx, sy) = (view.shift.x as f64, view.shift.y as f64);
        // film x >= -g  <=>  q.x / -q.z >= (ndc_lo + sx) tx  <=>  q.x + a q.z >= 0, and so on.
        let (gx, gy) = (2.0 * GUARD_PX / w, 2.0 * GUARD_PX / h);
        let ax_lo = (-1.0 - gx + sx) * tx;
        let ax_hi = (1.0 + gx + sx) * tx;
        // film y grows down: film y >= -g <=> ndc y <= 1 + gy; film y <= h + g <=> ndc y >= -1 - gy.
        let ay_hi = (1.0 + gy + sy) * ty;
        let ay_lo = (-1.0 - gy + sy) * ty;
        let eye = view.frame.position.as_dvec3();
        let rows = [
            b.x_axis.as_dvec3(),
            b.y_axis.as_dvec3(),
            b.z_axis.as_dvec3(),
        ];
        let axes = match rows.map(signed_axis) {
            [Some(a), Some(b), Some(c)] => Some([a, b, c]),
            _ => None,
        };
        ViewXf {
            rows,
            slopes: [ax_lo, ax_hi, ay_lo, ay_hi],
            film: [
                (sx - 1.0) * tx,
                w / (2.0 * tx),
                (sy + 1.0) * ty,
                h / (2.0 * ty),
            ],
            near,
            eye,
            eye_mag: eye.abs().max_element(),
            w,
            h,
            planes: [
                (DVec3::new(0.0, 0.0, -1.0), -near),
                (DVec3::new(1.0, 0.0, ax_lo), 0.0),
                (DVec3::new(-1.0, 0.0, -ax_hi), 0.0),
                (DVec3::new(0.0, 1.0, ay_lo), 0.0),
                (DVec3::new(0.0, -1.0, -ay_hi), 0.0),
            ],
            axes,
        }
    }

    /// What [`FaceCull`] needs of this view.
    pub fn axis_view(&self) -> AxisView {
        AxisView {
            axes: self.axes,
            slopes: self.slopes,
            near: self.near,
            eye: self.eye,
        }
    }

    /// Whether [`Self::setup`] drops the triangle with corner offsets `d` by its outcodes.
    #[cfg(test)]
    pub fn outcode_culled(&self, d: &[[f64; 3]; 3]) -> bool {
        let q = [self.rotate(d[0]), self.rotate(d[1]), self.rotate(d[2])];
        self.cut(&q).is_none()
    }

    /// The outcode bits [`Self::setup`] clips by (`None`: culled).
    #[cfg(test)]
    pub fn outcode_cut(&self, d: &[[f64; 3]; 3]) -> Option<u32> {
        let q = [self.rotate(d[0]), self.rotate(d[1]), self.rotate(d[2])];
        self.cut(&q)
    }

    #[cfg(test)]
    fn to_camera(&self, p: DVec3) -> DVec3 {
        self.rotate((p - self.eye).to_array())
    }

    /// Camera-space point of the world offset `d = p - eye` (the rotation rows, or the picked
    /// components of an axis view).
    #[inline(always)]
    fn rotate(&self, d: [f64; 3]) -> DVec3 {
        if let Some([a, b, c]) = self.axes {
            return DVec3::new(a.1 * d[a.0], b.1 * d[b.0], c.1 * d[c.0]);
        }
        let d = DVec3::from_array(d);
        DVec3::new(
            self.rows[0].dot(d),
            self.rows[1].dot(d),
            self.rows[2].dot(d),
        )
    }

    /// The outcode of camera point `q` against the four guard planes: bit `k` set when it is
    /// outside clip plane `k` (signed distance not `>= 0`) of `planes`, `k = 1..5`, written out
    /// (two non-zero terms each); bit 0, the near plane, is [`Self::near_out`].
    #[inline(always)]
    fn guard_outcode(&self, q: DVec3) -> u32 {
        let [ax_lo, ax_hi, ay_lo, ay_hi] = self.slopes;
        let out = |d: f64| (!(d >= 0.0)) as u32;
        out(q.x + ax_lo * q.z) << 1
            | out(-q.x - ax_hi * q.z) << 2
            | out(q.y + ay_lo * q.z) << 3
            | out(-q.y - ay_hi * q.z) << 4
    }

    /// 1 when camera point `q` is outside the near plane (plane 0 of `planes`), else 0.
    #[inline(always)]
    fn near_out(&self, q: DVec3) -> u32 {
        (!(-q.z - self.near >= 0.0)) as u32
    }

    /// Camera point (in front) -> (film x, film y, 1 / view depth); inverse of
    /// `Pinhole::camera_dir` (as `(u - a0) / ax` and `(b0 - v) / by` of the slopes `u, v`).
    #[inline(always)]
    fn project(&self, q: DVec3) -> DVec3 {
        let inv = 1.0 / -q.z;
        let [a0, inv_ax, b0, inv_by] = self.film;
        DVec3::new((q.x * inv - a0) * inv_ax, (b0 - q.y * inv) * inv_by, inv)
    }

    /// The `w` plane of the camera-space triangle `q` (module docs).
    #[inline(always)]
    fn w_plane(&self, q: &[DVec3; 3]) -> Option<WPlane> {
        let n = (q[1] - q[0]).cross(q[2] - q[0]);
        let d = n.dot(q[0]);
        // |n| |q| bounded from above without square roots (1-norms): a stricter test.
        let qn = q[0].abs().element_sum() + q[1].abs().element_sum() + q[2].abs().element_sum();
        if !(d.abs() > EDGE_ON * n.abs().element_sum() * qn) {
            return None;
        }
        // u = a0 + ax x, v = b0 - by y with the projection of `project`.
        let [a0, inv_ax, b0, inv_by] = self.film;
        let inv_d = 1.0 / d;
        Some(WPlane {
            p0: (n.x * a0 + n.y * b0 - n.z) * inv_d,
            px: n.x * inv_d / inv_ax,
            py: -n.y * inv_d / inv_by,
        })
    }

    /// The planes camera-space triangle `q` crosses (bit `k`: some corner outside plane `k`
    /// of `planes`), or `None` when all three corners are outside one plane (culled).
    #[inline(always)]
    fn cut(&self, q: &[DVec3; 3]) -> Option<u32> {
        // The near plane first: it alone culls most triangles behind a cube face.
        let n = [
            self.near_out(q[0]),
            self.near_out(q[1]),
            self.near_out(q[2]),
        ];
        if n[0] & n[1] & n[2] != 0 {
            return None;
        }
        let o = [
            self.guard_outcode(q[0]) | n[0],
            self.guard_outcode(q[1]) | n[1],
            self.guard_outcode(q[2]) | n[2],
        ];
        if o[0] & o[1] & o[2] != 0 {
            return None;
        }
        Some(o[0] | o[1] | o[2])
    }

    /// Sets triangle `t` up for the fill (module docs): its entry, with its clipped
    /// projection written to `poly`, or `None` when nothing of it is left in the view; `d` are
    /// its finite corners minus the view's eye.
    #[inline(always)]
    pub fn setup(
        &self,
        t: usize,
        d: &[[f64; 3]; 3],
        world_mag: f64,
        poly: &mut Poly,
    ) -> Option<SetupEntry> {
        self.setup_with(t, d, world_mag, poly, false)
    }

    /// [`Self::setup`]; with `inside`, the caller knows every corner is inside every clip
    /// plane (all outcodes zero, [`FaceCull::keep`]) and the outcode test is skipped.
    #[inline(always)]
    fn setup_with(
        &self,
        t: usize,
        d: &[[f64; 3]; 3],
        world_mag: f64,
        poly: &mut Poly,
        inside: bool,
    ) -> Option<SetupEntry> {
        let q = [self.rotate(d[0]), self.rotate(d[1]), self.rotate(d[2])];
        // Outside one plane with all three corners: culled; else the planes some corner is
        // outside of cut it.
        let cut = if inside { 0 } else { self.cut(&q)? };
        if cut == 0 {
            poly.v[0] = self.project(q[0]);
            poly.v[1] = self.project(q[1]);
            poly.v[2] = self.project(q[2]);
            poly.n = 3;
        } else {
            let mut p = Poly::from_triangle(q);
            for (k, &(n, d)) in self.planes.iter().enumerate() {
                if cut >> k & 1 != 0 {
                    p = p.clip_plane(n, d);
                    if p.n == 0 {
                        return None;
                    }
                }
            }
            for (o, &v) in poly.v.iter_mut().zip(p.verts()) {
                *o = self.project(v);
            }
            poly.n = p.n;
        }
        let (lo, hi) = poly
            .verts()
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        // The farthest vertex from the eye, bounded by its 1-norm (no square root).
        let far = q.iter().map(|v| v.abs().element_sum()).fold(0.0, f64::max);
        Some(SetupEntry {
            tri: t as u32,
            plane: self.w_plane(&q),
            abs_margin: DEPTH_ABS_ULPS * f32::EPSILON as f64 * (far + world_mag + self.eye_mag),
            y: (lo.y, hi.y),
            x: (lo.x, hi.x),
            w: (lo.z, hi.z),
        })
    }

    /// Triangles `range` of `mesh` set up for each of `views`, in triangle order (each
    /// triangle for every view in turn): `f(view, entry, polygon)` for each one left in a
    /// view; stops at `f`'s first error. Each triangle's corners are read and converted once
    /// for all views, and their offsets from the eye once for the views that share it
    /// (`same_eye[k]`: view `k` has the eye of view `k - 1`; the camera view and the cube
    /// faces around its eye). With `cull`, the setup of its member views runs only for the
    /// faces it keeps (the same entries: it drops just what their outcodes drop).
    #[inline(always)]
    pub fn setup_range<E>(
        views: &[ViewXf],
        same_eye: &[bool],
        cull: Option<&FaceCull>,
        mesh: &TriangleMesh,
        range: std::ops::Range<usize>,
        mut f: impl FnMut(usize, &SetupEntry, &[DVec3]) -> Result<(), E>,
    ) -> Result<(), E> {
        let mut poly = Poly::EMPTY;
        let first = cull.map_or(usize::MAX, |c| c.first_view());
        for t in range {
            let [a, b, c] = mesh.triangle(t);
            // Finite corners have finite camera-space points in every view (f32
            // magnitudes cannot overflow the f64 transform).
            if !(a.is_finite() && b.is_finite() && c.is_finite()) {
                continue;
            }
            let world_mag = a.abs().max(b.abs()).max(c.abs()).max_element() as f64;
            let p = [a.as_dvec3(), b.as_dvec3(), c.as_dvec3()];
            let mut d = [[0.0; 3]; 3];
            let mut k = 0;
            while k < views.len() {
                let xf = &views[k];
                if !same_eye[k] {
                    d = p.map(|p| (p - xf.eye).to_array());
                }
                if let (true, Some(c)) = (k == first, cull) {
                    // The group's views (consecutive, one eye): only the kept ones.
                    let (mut keep, inside) = c.keep(&d);
                    while keep != 0 {
                        let j = keep.trailing_zeros() as usize;
                        keep &= keep - 1;
                        let inside = inside >> j & 1 != 0;
                        if let Some(e) = views[j].setup_with(t, &d, world_mag, &mut poly, inside) {
                            f(j, &e, poly.verts())?;
                        }
                    }
                    k += c.len();
                    continue;
                }
                if let Some(e) = xf.setup(t, &d, world_mag, &mut poly) {
                    f(k, &e, poly.verts())?;
                }
                k += 1;
            }
        }
        Ok(())
    }

    /// `same_eye` of [`Self::setup_range`] for `views`.
    pub fn same_eyes(views: &[ViewXf]) -> Vec<bool> {
        (0..views.len())
            .map(|k| k > 0 && views[k].eye == views[k - 1].eye)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use parallax_scene::camera::CubeMap;

    /// Camera-space points and outcodes of the fast paths (axis rows, written-out planes)
    /// equal the general rotation and the plane list on random points, for the six cube faces
    /// (axis rows) and a general camera.
    #[test]
    fn fast_transform_and_outcodes_equal_the_general_ones() {
        let cube = CubeMap {
            eye: Vec3::new(0.5, -1.25, 3.0),
            face: 16,
        };
        let desc = parallax_scene::CameraDesc::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-2.0, 0.5, 0.0),
            Vec3::Y,
            50.0,
        );
        let mut views: Vec<Pinhole> = (0..6).map(|i| cube.face_camera(i)).collect();
        views.push(Pinhole::new(&desc, 64, 32).unwrap());
        let mut rng = parallax_core::Rng::new(9, 4);
        let mut cut = [0u32; 5];
        for (i, v) in views.iter().enumerate() {
            let xf = ViewXf::new(v, 1e-3);
            assert_eq!(xf.axes.is_some(), i < 6, "view {i}");
            for _ in 0..5000 {
                let mut c = || (rng.next_f32() as f64 - 0.5) * 20.0;
                let p = DVec3::new(c(), c(), c());
                let d = p - xf.eye;
                let general = DVec3::new(xf.rows[0].dot(d), xf.rows[1].dot(d), xf.rows[2].dot(d));
                let q = xf.to_camera(p);
                assert_eq!(q, general, "view {i} point {p}");
                let code = xf.near_out(q) | xf.guard_outcode(q);
                let reference = xf.planes.iter().enumerate().fold(0, |c, (k, &(n, o))| {
                    c | ((!(n.dot(q) + o >= 0.0)) as u32) << k
                });
                assert_eq!(code, reference, "view {i} point {q}");
                for (k, c) in cut.iter_mut().enumerate() {
                    *c += code >> k & 1;
                }
            }
        }
        // Every plane was crossed by some points, and not by all.
        assert!(
            cut.iter().all(|&c| c > 100 && c < 7 * 5000 - 100),
            "{cut:?}"
        );
    }

    fn axis_views(xfs: &[ViewXf]) -> Vec<AxisView> {
        xfs.iter().map(ViewXf::axis_view).collect()
    }

    /// The cull keeps exactly the faces whose setup does not drop the triangle by its
    /// outcodes (never one the setup keeps), the AVX2 and scalar bits the same, on random
    /// triangles around the eye: small and large, near the faces' boundary planes (`x = ±y`
    /// ...), through the near plane, with zero components.
    #[test]
    fn cull_equals_the_setup_outcodes() {
        for (eye, face) in [(Vec3::new(0.5, -1.25, 3.0), 32), (Vec3::ZERO, 128)] {
            let cube = CubeMap { eye, face };
            let desc =
                parallax_scene::CameraDesc::new(eye, Vec3::new(-2.0, 0.5, 0.0), Vec3::Y, 50.0);
            let mut views: Vec<Pinhole> = vec![Pinhole::new(&desc, 64, 32).unwrap()];
            views.extend((0..6).map(|i| cube.face_camera(i)));
            let xfs: Vec<ViewXf> = views.iter().map(|v| ViewXf::new(v, 1e-3)).collect();
            let cull = FaceCull::new(&axis_views(&xfs)).expect("the six faces");
            assert_eq!(cull.members(), 0b111_1110);
            assert_eq!((cull.first_view(), cull.len()), (1, 6));
            let e = eye.as_dvec3();
            let mut rng = parallax_core::Rng::new(5, 7);
            let mut poly = Poly::EMPTY;
            let (mut kept, mut dropped, mut clipped_away) = (0u64, 0u64, 0u64);
            let (mut n_inside, mut n_cut) = (0u64, 0u64);
            for i in 0..20_000 {
                let mut u = || rng.next_f32() as f64 - 0.5;
                let size = [1e-3, 0.1, 2.0, 50.0][i % 4];
                let centre = DVec3::new(u(), u(), u()) * [0.01, 1.0, 10.0][i % 3];
                let mut corner = |c: DVec3| {
                    let mut p = c + DVec3::new(u(), u(), u()) * size;
                    // Corners on the faces' boundary planes, the axes, the near plane.
                    match i % 9 {
                        0 => p.y = p.x,
                        1 => p.z = -p.x,
                        2 => p.x = 0.0,
                        3 => p.y = 1e-3,
                        4 => p.z = -1e-3,
                        _ => {}
                    }
                    // Through f32, as the mesh holds them.
                    (p + e).as_vec3().as_dvec3()
                };
                let p = [corner(centre), corner(centre), corner(centre)];
                let d = p.map(|p| (p - e).to_array());
                let (keep, inside) = cull.keep(&d);
                assert_eq!((keep, inside), cull.keep_portable(&d), "triangle {i}");
                for (k, xf) in xfs.iter().enumerate().skip(1) {
                    let entry = xf.setup(0, &d, 1.0, &mut poly);
                    let outcode_culled = xf.outcode_culled(&d);
                    assert_eq!(keep >> k & 1 == 0, outcode_culled, "triangle {i} face {k}");
                    let uncut = xf.outcode_cut(&d) == Some(0);
                    assert_eq!(inside >> k & 1 != 0, uncut, "triangle {i} face {k}");
                    n_inside += uncut as u64;
                    n_cut += (!uncut && !outcode_culled) as u64;
                    if outcode_culled {
                        assert!(entry.is_none(), "triangle {i} face {k}");
                        dropped += 1;
                    } else if entry.is_some() {
                        kept += 1;
                    } else {
                        clipped_away += 1;
                    }
                }
            }
            assert!(
                kept > 10_000 && dropped > 50_000,
                "{kept} {dropped} {clipped_away}"
            );
            // Both kinds of kept face were met.
            assert!(n_inside > 1000 && n_cut > 1000, "{n_inside} {n_cut}");
        }
    }

    /// Views whose guard slopes differ in magnitude (a non-square face) form no group.
    #[test]
    fn unequal_slopes_form_no_group() {
        let cube = CubeMap {
            eye: Vec3::ZERO,
            face: 16,
        };
        let mut faces: Vec<Pinhole> = (0..6).map(|i| cube.face_camera(i)).collect();
        faces[3].width = 20;
        let xfs: Vec<ViewXf> = faces.iter().map(|v| ViewXf::new(v, 1e-3)).collect();
        assert!(FaceCull::new(&axis_views(&xfs)).is_none());
        let xfs: Vec<ViewXf> = faces[..3].iter().map(|v| ViewXf::new(v, 1e-3)).collect();
        assert!(FaceCull::new(&axis_views(&xfs)).is_some());
    }
}
