//! The NDC-like unit cube of a pinhole reference view (Widmer et al. 2015, §3.2: "both
//! construction and ray tracing are done in a variant of NDC space, where all potential scene
//! points are inside of a unit cube").
//!
//! **Definition.** Let `q = frame.to_camera(p)` and `d = -q.z` the view depth. A world point
//! `p` with `near <= d <= far` in the reference frustum maps to
//!
//! ```text
//! x = film_x / width,  y = film_y / height,  z = (1/near - 1/d) / (1/near - 1/far)
//! ```
//!
//! where `film = Pinhole::film_of_camera_point(q)` (y grows down; off-axis `shift` included).
//! So pixel `(i, j)` covers exactly the **footprint square** `[i/W, (i+1)/W] x [j/H, (j+1)/H]`,
//! `z = 0` is the near plane and `z = 1` the far plane, and `z` grows with depth.
//!
//! **Derivation.** `film_x / W = ½ (q.x / (d tan_half_x) - shift.x + 1)` and
//! `film_y / H = ½ (1 - q.y / (d tan_half_y) + shift.y)`; with `B = 1 / (1/near - 1/far)`,
//! `A = B / near`, `z = A - B / d`. All three are (affine in `q`) / `d`, so the map is the
//! projective map of the homogeneous matrix `M` with rows (acting on camera `(q, 1)`)
//!
//! ```text
//! X = [ ½/tan_half_x, 0,            -½(1 - shift.x), 0 ]
//! Y = [ 0,            -½/tan_half_y, -½(1 + shift.y), 0 ]
//! Z = [ 0,            0,            -A,               -B ]
//! W = [ 0,            0,            -1,               0 ]      (W = d > 0)
//! ```
//!
//! A projective map sends lines to lines and planes to planes (a plane covector `π` maps to
//! `M^-T π`), which is why a per-pixel plane stays a plane and a ray stays a segment. Rays are
//! clipped in **world** parameter `t` first: with `W > 0` every face of the cube is a linear
//! inequality in `t` (`near <= W <= far`, `0 <= X <= W`, `0 <= Y <= W`).
//!
//! `near` and `far` are chosen by the caller ([`UnitCube::fit_depths`] picks them around the
//! captured depths): a finite far plane keeps the cube bounded, and a near plane not much
//! smaller than the nearest surface keeps `z` well resolved in f32. Maps are evaluated in f64.

use glam::{DMat4, DVec4, Vec3};
use parallax_core::Ray;
use parallax_scene::camera::Pinhole;

use crate::ScreenError;

/// Where [`UnitCube::fit`] puts the cube's near plane, i.e. where every traced ray starts.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub enum CubeNear {
    /// Half the nearest captured depth (our default): nothing can be hit in front of the
    /// nearest captured surface, so every tracer starts its rays there — a global empty-space
    /// skip that shortens screen-space rays (most of all the DDA's march). Not in the paper.
    #[default]
    Fitted,
    /// A camera near plane at this view depth in metres (Widmer et al. 2015, §3.2: the NDC
    /// cube holds "all potential scene points", i.e. the camera frustum, so rays start at the
    /// camera's near plane — the setting of their Tables 2-4). Never placed behind half the
    /// nearest captured depth, so every captured point stays inside the cube.
    Camera(f32),
}

/// The unit cube of a pinhole reference view between `near` and `far` view depth.
#[derive(Clone, Debug, PartialEq)]
pub struct UnitCube {
    pub camera: Pinhole,
    pub near: f32,
    pub far: f32,
    /// World `(p, 1)` -> homogeneous cube `(X, Y, Z, W)`, `W` = view depth.
    pub world_to_cube: DMat4,
    /// Its inverse.
    pub cube_to_world: DMat4,
}

/// A world ray clipped to the cube: the straight cube segment `p0 -> p1` and the world
/// parameters `t0 < t1` of its ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CubeSegment {
    pub p0: Vec3,
    pub p1: Vec3,
    pub t0: f32,
    pub t1: f32,
    /// View depths (homogeneous `W`) at the ends, for [`CubeSegment::world_t`].
    pub w0: f64,
    pub w1: f64,
}

impl CubeSegment {
    /// Cube point at segment parameter `s` in `[0, 1]`.
    #[inline]
    pub fn at(&self, s: f32) -> Vec3 {
        self.p0 + (self.p1 - self.p0) * s
    }

    /// World ray parameter of the cube point at `s`: the projective map is not affine along
    /// the ray; with `λ = s w0 / (s w0 + (1 - s) w1)`, `t = t0 + λ (t1 - t0)` (from
    /// `P(λ) = ((1-λ) w0 p0 + λ w1 p1) / ((1-λ) w0 + λ w1)`).
    #[inline]
    pub fn world_t(&self, s: f32) -> f32 {
        let s = s as f64;
        let den = s * self.w0 + (1.0 - s) * self.w1;
        let lambda = if den > 0.0 { s * self.w0 / den } else { s };
        (self.t0 as f64 + lambda * (self.t1 as f64 - self.t0 as f64)) as f32
    }
}

impl UnitCube {
    /// The cube of `camera` between view depths `near` and `far` (`0 < near < far < inf`).
    pub fn new(camera: &Pinhole, near: f32, far: f32) -> Result<Self, ScreenError> {
        if !(near.is_finite() && far.is_finite() && near > 0.0 && far > near) {
            return Err(ScreenError::InvalidSpace(format!(
                "need 0 < near < far < inf, got near {near}, far {far}"
            )));
        }
        let thy = camera.tan_half_y as f64;
        let thx = thy * camera.width as f64 / camera.height as f64;
        if !(thy.is_finite() && thy > 0.0 && camera.width > 0 && camera.height > 0) {
            return Err(ScreenError::InvalidSpace(format!(
                "invalid pinhole: {}x{}, tan_half_y {thy}",
                camera.width, camera.height
            )));
        }
        let b = 1.0 / (1.0 / near as f64 - 1.0 / far as f64);
        let a = b / near as f64;
        let (sx, sy) = (camera.shift.x as f64, camera.shift.y as f64);
        let proj = DMat4::from_cols_array_2d(&[
            [0.5 / thx, 0.0, -0.5 * (1.0 - sx), 0.0],
            [0.0, -0.5 / thy, -0.5 * (1.0 + sy), 0.0],
            [0.0, 0.0, -a, -b],
            [0.0, 0.0, -1.0, 0.0],
        ])
        .transpose();
        let basis = camera.frame.basis.as_dmat3();
        let rt = basis.transpose();
        let tr = -(rt * camera.frame.position.as_dvec3());
        let view = DMat4::from_cols(
            rt.x_axis.extend(0.0),
            rt.y_axis.extend(0.0),
            rt.z_axis.extend(0.0),
            tr.extend(1.0),
        );
        let m = proj * view;
        if !m.is_finite() || m.determinant() == 0.0 {
            return Err(ScreenError::InvalidSpace("singular camera frame".into()));
        }
        Ok(Self {
            camera: camera.clone(),
            near,
            far,
            world_to_cube: m,
            cube_to_world: m.inverse(),
        })
    }

    /// The cube with `near = min_depth / 2` and `far = 2 max_depth` over the finite positive
    /// values of `depths` (view depths of the captured layers); errors when there is none.
    /// Same as [`Self::fit`] with [`CubeNear::Fitted`].
    pub fn fit_depths<'a>(
        camera: &Pinhole,
        depths: impl IntoIterator<Item = &'a [f32]>,
    ) -> Result<Self, ScreenError> {
        Self::fit(camera, depths, CubeNear::Fitted)
    }

    /// The cube around the captured depths with its near plane chosen by `near`
    /// ([`CubeNear`]) and `far = 2 max_depth`; errors when no depth is finite and positive,
    /// or when a camera near plane is not finite and positive.
    pub fn fit<'a>(
        camera: &Pinhole,
        depths: impl IntoIterator<Item = &'a [f32]>,
        near: CubeNear,
    ) -> Result<Self, ScreenError> {
        let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
        for layer in depths {
            for &d in layer {
                if d.is_finite() && d > 0.0 {
                    lo = lo.min(d);
                    hi = hi.max(d);
                }
            }
        }
        if !lo.is_finite() {
            return Err(ScreenError::InvalidSpace("no captured depth".into()));
        }
        let near = match near {
            CubeNear::Fitted => lo * 0.5,
            CubeNear::Camera(n) if n.is_finite() && n > 0.0 => n.min(lo * 0.5),
            CubeNear::Camera(n) => {
                return Err(ScreenError::InvalidSpace(format!(
                    "camera near plane {n} must be finite and positive"
                )));
            }
        };
        Self::new(camera, near, hi * 2.0)
    }

    /// World point -> homogeneous cube point (f64).
    #[inline]
    pub fn homogeneous(&self, p: Vec3) -> DVec4 {
        self.world_to_cube * p.as_dvec3().extend(1.0)
    }

    /// World point -> cube point (`None` on or behind the eye plane). Points outside the
    /// frustum map outside `[0, 1]^3`.
    #[inline]
    pub fn to_cube(&self, p: Vec3) -> Option<Vec3> {
        let h = self.homogeneous(p);
        (h.w > 0.0).then(|| (h.truncate() / h.w).as_vec3())
    }

    /// Cube point -> world point (inverse of [`Self::to_cube`]).
    #[inline]
    pub fn to_world(&self, c: Vec3) -> Vec3 {
        let h = self.cube_to_world * c.as_dvec3().extend(1.0);
        (h.truncate() / h.w).as_vec3()
    }

    /// The cube point of pixel-centre film position `(x + 0.5, y + 0.5)` at view depth `d`.
    #[inline]
    pub fn pixel_point(&self, x: u32, y: u32, d: f32) -> Vec3 {
        Vec3::new(
            (x as f32 + 0.5) / self.camera.width as f32,
            (y as f32 + 0.5) / self.camera.height as f32,
            self.z_of_depth(d),
        )
    }

    /// Cube `z` of view depth `d`.
    #[inline]
    pub fn z_of_depth(&self, d: f32) -> f32 {
        let (n, f) = (self.near as f64, self.far as f64);
        ((1.0 / n - 1.0 / d as f64) / (1.0 / n - 1.0 / f)) as f32
    }

    /// World plane through `p` with normal `n` -> cube plane `(normal, c)` with
    /// `normal · P = c`, `|normal| = 1`, oriented so `normal.z <= 0` (towards the eye); `None`
    /// when degenerate. Covector transform `π' = M^-T π`.
    pub fn map_plane(&self, p: Vec3, n: Vec3) -> Option<(Vec3, f32)> {
        let (p, n) = (p.as_dvec3(), n.as_dvec3());
        let pi = n.extend(-n.dot(p));
        let q = self.cube_to_world.transpose() * pi;
        let len = q.truncate().length();
        if !(len.is_finite() && len > 0.0) {
            return None;
        }
        let mut q = q / len;
        if q.z > 0.0 {
            q = -q;
        }
        Some((q.truncate().as_vec3(), (-q.w) as f32))
    }

    /// Clips the world ray to the cube: `None` when no part of `(t_min, t_max)` lies inside
    /// (also for invalid rays). Never panics.
    ///
    /// f64 throughout (the f32 version is not exact at pixel boundaries: a ray in the plane
    /// `y = j/H` can round to the other side). Per-ray cost kept low: the direction skips the
    /// matrix's translation column, each face is one division and plain compares (no
    /// NaN-aware `max`/`min`: every value is finite for a valid ray; the branches on the
    /// sign of `beta` follow the ray direction and predict well), and each end point is
    /// one reciprocal and three products instead of three divisions (the error, ~1 ulp of
    /// f64, vanishes in the rounding to f32: a coordinate that is exactly `j/H` in f64 stays
    /// exactly that in f32).
    pub fn clip_ray(&self, ray: &Ray) -> Option<CubeSegment> {
        if !ray.is_valid() || ray.t_min.is_nan() || ray.t_max.is_nan() {
            return None;
        }
        let m = &self.world_to_cube;
        let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
        let b = m.x_axis * d.x + m.y_axis * d.y + m.z_axis * d.z;
        let a = m.x_axis * o.x + m.y_axis * o.y + m.z_axis * o.z + m.w_axis;
        let (mut lo, mut hi) = (t_start(ray.t_min), ray.t_max as f64);
        let (near, far) = (self.near as f64, self.far as f64);
        // Each face: alpha + beta t >= 0.
        let faces = [
            (a.w - near, b.w),
            (far - a.w, -b.w),
            (a.x, b.x),
            (a.w - a.x, b.w - b.x),
            (a.y, b.y),
            (a.w - a.y, b.w - b.y),
        ];
        for (alpha, beta) in faces {
            if beta > 0.0 {
                let root = -alpha / beta;
                lo = if root > lo { root } else { lo };
            } else if beta < 0.0 {
                let root = -alpha / beta;
                hi = if root < hi { root } else { hi };
            } else if alpha < 0.0 {
                return None;
            }
        }
        if !(lo < hi && hi.is_finite()) {
            return None;
        }
        let h0 = a + b * lo;
        let h1 = a + b * hi;
        // Clamp to [0, 1] (NaN to 0, as `DVec3::clamp` did).
        // `max`/`min` compile to branch-free code (compares here mispredicted: the clamps
        // bind on a data-dependent part of the rays); `f64::clamp` would keep NaN.
        #[allow(clippy::manual_clamp)]
        let c01 = |v: f64| v.max(0.0).min(1.0) as f32;
        let point = |h: DVec4| {
            let r = 1.0 / h.w;
            Vec3::new(c01(h.x * r), c01(h.y * r), c01(h.z * r))
        };
        Some(CubeSegment {
            p0: point(h0),
            p1: point(h1),
            t0: lo as f32,
            t1: hi as f32,
            w0: h0.w,
            w1: h1.w,
        })
    }
}

/// The clip's start parameter `max(t_min, 0)` with `+0` for `t_min = -0` (what `maxss` with
/// `0` as its second operand gives, as `f32::max` compiled here; spelled out because the
/// sign of a zero `f32::max` returns is not specified and differs between inlining sites).
#[inline(always)]
pub(crate) fn t_start(t_min: f32) -> f64 {
    (if t_min > 0.0 { t_min } else { 0.0 }) as f64
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use glam::Vec2;
    use parallax_scene::CameraDesc;

    /// A shifted 64x48 camera's cube, near 0.5, far 20 (also `space_pair`'s tests).
    pub(crate) fn cube() -> UnitCube {
        let desc = CameraDesc::new(
            Vec3::new(0.3, 1.0, 4.0),
            Vec3::new(0.0, 0.8, 0.0),
            Vec3::Y,
            50.0,
        );
        let cam = Pinhole::new(&desc, 64, 48)
            .unwrap()
            .with_shift(Vec2::new(0.1, -0.05));
        UnitCube::new(&cam, 0.5, 20.0).unwrap()
    }

    #[test]
    fn fit_places_the_near_plane() {
        let cam = cube().camera;
        let depths = [2.0f32, f32::INFINITY, 6.0, 0.0];
        let fitted = UnitCube::fit(&cam, [&depths[..]], CubeNear::Fitted).unwrap();
        assert_eq!((fitted.near, fitted.far), (1.0, 12.0));
        assert_eq!(fitted, UnitCube::fit_depths(&cam, [&depths[..]]).unwrap());
        let camera = UnitCube::fit(&cam, [&depths[..]], CubeNear::Camera(0.1)).unwrap();
        assert_eq!((camera.near, camera.far), (0.1, 12.0));
        // A near plane behind the nearest surface is pulled in front of it.
        let pulled = UnitCube::fit(&cam, [&depths[..]], CubeNear::Camera(5.0)).unwrap();
        assert_eq!(pulled.near, 1.0);
        for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert!(UnitCube::fit(&cam, [&depths[..]], CubeNear::Camera(bad)).is_err());
        }
    }

    #[test]
    fn frustum_corners_and_film_match() {
        let c = cube();
        let cam = &c.camera;
        for (film, d) in [
            (Vec2::new(0.0, 0.0), 0.5),
            (Vec2::new(64.0, 48.0), 20.0),
            (Vec2::new(10.5, 7.25), 3.0),
        ] {
            let dir = cam.frame.dir_to_world(cam.camera_dir(film));
            let p = cam.frame.position + dir * d;
            let u = c.to_cube(p).unwrap();
            assert!((u.x - film.x / 64.0).abs() < 1e-5 && (u.y - film.y / 48.0).abs() < 1e-5);
            assert!((u.z - c.z_of_depth(d)).abs() < 1e-5, "{u}");
            assert!((c.to_world(u) - p).length() < 1e-4 * d);
        }
        assert!(c.z_of_depth(0.5).abs() < 1e-6 && (c.z_of_depth(20.0) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn bad_ranges_error() {
        let c = cube();
        assert!(UnitCube::new(&c.camera, 0.0, 1.0).is_err());
        assert!(UnitCube::new(&c.camera, 1.0, f32::INFINITY).is_err());
        assert!(UnitCube::new(&c.camera, 2.0, 1.0).is_err());
    }
}
