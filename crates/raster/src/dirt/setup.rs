//! Triangle setup of the DIRT build (§4.1.1 "Fill Depth": "a geometry shader outputs each
//! primitive ... to the fragment shader"): a triangle is taken to the view's camera space in
//! f64, culled or clipped against the near plane and a guard band around the film, projected
//! to `(film x, film y, w = 1 / view depth)`, and given the plane of `w` over the film.
//!
//! **Fast path.** Most triangles lie wholly inside all five clip planes (no clipping) or
//! wholly outside one of them (culled); only the rest go through Sutherland-Hodgman.
//!
//! **The `w` plane.** A triangle's plane `n . q = d` in camera space meets the ray through film
//! position `(x, y)`, direction `(u, v, -1)` with `u = a0 + x ax`, `v = b0 - y by`, at view
//! depth `d / (n . dir)`, so `w = (n.x u + n.y v - n.z) / d` is affine in `(x, y)` (exact, also
//! for a triangle clipped by the near plane: the clipped polygon lies in the same plane). The
//! plane is dropped (`None`) for a triangle whose plane passes within `1e-7` (relative) of the
//! eye, seen edge-on: evaluating it there would amplify rounding; such a triangle's depth
//! range in a cell is the range over its row slab instead (wider, still conservative).

use glam::{DVec3, Vec3};
use parallax_scene::TriangleMesh;
use parallax_scene::camera::Pinhole;

use super::clip::Poly;

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

/// A set-up triangle: its clipped projection (vertices `(film x, film y, w)`), its `w` plane
/// and the absolute depth margin for it.
pub(super) struct TriSetup {
    pub poly: Poly,
    pub plane: Option<WPlane>,
    pub abs_margin: f64,
}

/// The view in f64: rotation rows (camera space = R (p - eye)), projection constants and the
/// near + guard clip planes (camera space, `n . q + d >= 0` inside).
pub(super) struct ViewXf {
    rows: [DVec3; 3],
    eye: DVec3,
    eye_mag: f64,
    tx: f64,
    ty: f64,
    shift: (f64, f64),
    pub w: f64,
    pub h: f64,
    planes: [(DVec3, f64); 5],
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
        ViewXf {
            rows: [
                b.x_axis.as_dvec3(),
                b.y_axis.as_dvec3(),
                b.z_axis.as_dvec3(),
            ],
            eye,
            eye_mag: eye.abs().max_element(),
            tx,
            ty,
            shift: (sx, sy),
            w,
            h,
            planes: [
                (DVec3::new(0.0, 0.0, -1.0), -near),
                (DVec3::new(1.0, 0.0, ax_lo), 0.0),
                (DVec3::new(-1.0, 0.0, -ax_hi), 0.0),
                (DVec3::new(0.0, 1.0, ay_lo), 0.0),
                (DVec3::new(0.0, -1.0, -ay_hi), 0.0),
            ],
        }
    }

    #[inline]
    fn to_camera(&self, p: Vec3) -> DVec3 {
        let d = p.as_dvec3() - self.eye;
        DVec3::new(
            self.rows[0].dot(d),
            self.rows[1].dot(d),
            self.rows[2].dot(d),
        )
    }

    /// Camera point (in front) -> (film x, film y, 1 / view depth); inverse of
    /// `Pinhole::camera_dir`.
    #[inline]
    fn project(&self, q: DVec3) -> DVec3 {
        let inv = 1.0 / -q.z;
        let nx = q.x * inv / self.tx - self.shift.0;
        let ny = q.y * inv / self.ty - self.shift.1;
        DVec3::new((nx + 1.0) * 0.5 * self.w, (1.0 - ny) * 0.5 * self.h, inv)
    }

    /// The `w` plane of the camera-space triangle `q` (module docs).
    fn w_plane(&self, q: &[DVec3; 3]) -> Option<WPlane> {
        let n = (q[1] - q[0]).cross(q[2] - q[0]);
        let d = n.dot(q[0]);
        let scale = n.length() * (q[0].length() + q[1].length() + q[2].length());
        if !(d.abs() > EDGE_ON * scale) {
            return None;
        }
        // u = a0 + ax x, v = b0 - by y with the projection of `project`.
        let ax = 2.0 * self.tx / self.w;
        let a0 = (self.shift.0 - 1.0) * self.tx;
        let by = 2.0 * self.ty / self.h;
        let b0 = (self.shift.1 + 1.0) * self.ty;
        Some(WPlane {
            p0: (n.x * a0 + n.y * b0 - n.z) / d,
            px: n.x * ax / d,
            py: -n.y * by / d,
        })
    }

    /// Triangle `t` set up for the fill (module docs); `None` if nothing of it is left in the
    /// view (or it is not finite).
    pub fn setup(&self, mesh: &TriangleMesh, t: usize) -> Option<TriSetup> {
        let [a, b, c] = mesh.triangle(t);
        let q = [self.to_camera(a), self.to_camera(b), self.to_camera(c)];
        if !q.iter().all(|v| v.is_finite()) {
            return None;
        }
        // Which planes cut the triangle (a bit per plane), or cull it.
        let mut cut = 0u32;
        for (k, &(n, d)) in self.planes.iter().enumerate() {
            let inside = q.map(|v| n.dot(v) + d >= 0.0);
            match inside {
                [false, false, false] => return None,
                [true, true, true] => {}
                _ => cut |= 1 << k,
            }
        }
        let mut poly = Poly::from_triangle(q);
        if cut != 0 {
            for (k, &(n, d)) in self.planes.iter().enumerate() {
                if cut >> k & 1 != 0 {
                    poly = poly.clip_plane(n, d);
                    if poly.n == 0 {
                        return None;
                    }
                }
            }
        }
        for v in &mut poly.v[..poly.n] {
            *v = self.project(*v);
        }
        let world_mag = a.abs().max(b.abs()).max(c.abs()).max_element() as f64;
        let dist = q.iter().map(|v| v.length()).fold(0.0, f64::max);
        let abs_margin = DEPTH_ABS_ULPS * f32::EPSILON as f64 * (dist + world_mag + self.eye_mag);
        Some(TriSetup {
            poly,
            plane: self.w_plane(&q),
            abs_margin,
        })
    }
}
