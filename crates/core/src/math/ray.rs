//! Rays and ray differentials.

use glam::Vec3;

/// A ray `origin + t * dir` restricted to `t_min < t < t_max`.
///
/// `dir` need not be normalised; `t` is measured in units of `dir`. Every ray generator of
/// parallax produces unit directions, so `t` is then a distance in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    pub t_min: f32,
    pub t_max: f32,
}

impl Ray {
    /// A ray over `(0, +inf)`.
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self {
            origin,
            dir,
            t_min: 0.0,
            t_max: f32::INFINITY,
        }
    }

    /// A ray over `(t_min, t_max)`.
    #[inline]
    pub fn segment(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
        Self {
            origin,
            dir,
            t_min,
            t_max,
        }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }

    /// True when origin and direction are finite and the direction is non-zero.
    #[inline]
    pub fn is_valid(&self) -> bool {
        self.origin.is_finite() && self.dir.is_finite() && self.dir.length_squared() > 0.0
    }
}

/// Screen-space derivatives of a ray's origin and direction (Igehy 1999): how the ray moves
/// when the film position moves by one pixel in x and in y. They describe the pixel footprint
/// that HVVR's beams bound and that texture filtering uses.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayDifferential {
    pub d_origin_dx: Vec3,
    pub d_origin_dy: Vec3,
    pub d_dir_dx: Vec3,
    pub d_dir_dy: Vec3,
}

impl RayDifferential {
    /// The footprint half-width (metres) of the pixel at distance `t` along the ray: the larger
    /// of the two axis extents.
    pub fn footprint_at(&self, t: f32) -> f32 {
        let dx = self.d_origin_dx + self.d_dir_dx * t;
        let dy = self.d_origin_dy + self.d_dir_dy * t;
        0.5 * dx.length().max(dy.length())
    }
}
