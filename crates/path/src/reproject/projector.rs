//! A pinhole's projection prepared for the footprints of a pass: `Pinhole::project` bit for
//! bit, with the camera's constants (the transposed basis, `tan_half_x`, the window shift, the
//! film size) computed once per pass instead of per point, and the x and y chains computed in
//! the lanes of one vector (glam's `Vec3A` / `Vec4`: SSE on x86-64), so the four chained
//! divisions `q.x / -q.z / tan_half_x`, `q.y / -q.z / tan_half_y` are two vector divisions.
//!
//! **Invariants:** [`Projector::project`] returns `Pinhole::project(p, 0) - 0.5` (the film
//! position relative to pixel centres), or `None` where `Pinhole::project` does, for every
//! point, bit for bit: every lane does the scalar operations in the scalar order (IEEE
//! division and multiplication are correctly rounded per lane; `1 - y` is computed as
//! `1 + (-y)`, which IEEE 754 defines as the same operation). Tested against the camera.

use glam::{Vec3A, Vec4};
#[cfg(not(target_arch = "x86_64"))]
use parallax_core::math::floor_i32;
use parallax_scene::camera::Pinhole;

/// `Pinhole::project` with the camera's constants prepared (module docs).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Projector {
    position: Vec3A,
    /// Columns of the transposed camera basis (world -> camera).
    cols: [Vec3A; 3],
    /// `(tan_half_x, tan_half_y, 1, 1)`.
    tan_half: Vec4,
    /// `(shift.x, shift.y, 0, 0)`.
    shift: Vec4,
    /// `(1, -1, 1, 1)`: negates y so that `1 - y` is `1 + (-y)`.
    flip: Vec4,
    /// `(width, height, 1, 1)`.
    size: Vec4,
}

impl Projector {
    pub(crate) fn new(camera: &Pinhole) -> Self {
        let t = camera.frame.basis.transpose();
        Self {
            position: camera.frame.position.into(),
            cols: [t.x_axis.into(), t.y_axis.into(), t.z_axis.into()],
            tan_half: Vec4::new(camera.tan_half_x(), camera.tan_half_y, 1.0, 1.0),
            shift: Vec4::new(camera.shift.x, camera.shift.y, 0.0, 0.0),
            flip: Vec4::new(1.0, -1.0, 1.0, 1.0),
            size: Vec4::new(camera.width as f32, camera.height as f32, 1.0, 1.0),
        }
    }

    /// `(width, height)` in lanes x, y (z and w are 1).
    #[inline(always)]
    pub(crate) fn size(&self) -> Vec4 {
        self.size
    }

    /// The film position of `p` minus 0.5 in x and y (lanes x, y; z and w are unspecified):
    /// `camera.project(p, 0) - 0.5` bit for bit; `None` for points behind or on the eye
    /// plane.
    #[inline(always)]
    pub(crate) fn project(&self, p: Vec3A) -> Option<Vec4> {
        // `basis^T * (p - position)`: glam's `Mat3 * Vec3` sums the columns in this order.
        let d = p - self.position;
        let q = self.cols[0] * d.x + self.cols[1] * d.y + self.cols[2] * d.z;
        if q.z >= 0.0 {
            return None;
        }
        // (q.x / -q.z / tan_half_x - shift.x, q.y / -q.z / tan_half_y - shift.y)
        let a = q.extend(1.0) / Vec4::splat(-q.z) / self.tan_half - self.shift;
        // ((x + 1) * 0.5 * width, (1 - y) * 0.5 * height) - 0.5
        Some((a * self.flip + Vec4::ONE) * 0.5 * self.size - Vec4::splat(0.5))
    }
}

/// `floor` of lanes x and y of `s` as integers, and `s` minus them (lanes x, y; z and w are
/// unspecified): `parallax_core::math::floor_i32` and `s - floor as f32` bit for bit (the same truncation, compare
/// and step, two lanes at a time on x86-64), for `|s.x|, |s.y| <` 2^23.
#[inline(always)]
pub(crate) fn floor_xy(s: Vec4) -> (i32, i32, Vec4) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE2 is part of x86-64.
    unsafe {
        use std::arch::x86_64::*;
        let v: __m128 = s.into();
        let t = _mm_cvttps_epi32(v);
        // Truncation rounds negative non-integers up: step down where `t as f32 > s` (the
        // compare mask is -1).
        let down = _mm_cmplt_ps(v, _mm_cvtepi32_ps(t));
        let i = _mm_add_epi32(t, _mm_castps_si128(down));
        let frac = _mm_sub_ps(v, _mm_cvtepi32_ps(i));
        (
            _mm_cvtsi128_si32(i),
            _mm_cvtsi128_si32(_mm_shuffle_epi32::<0x55>(i)),
            frac.into(),
        )
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let (ix, iy) = (floor_i32(s.x), floor_i32(s.y));
        (ix, iy, s - Vec4::new(ix as f32, iy as f32, 0.0, 0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec2, Vec3};
    use parallax_scene::CameraDesc;
    use parallax_scene::camera::CameraModel;

    #[test]
    fn projector_equals_the_pinhole_bit_for_bit() {
        let mut rng = 0x1234_5678_9abc_def0u64;
        let mut next = || {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((rng >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
        };
        let desc = CameraDesc::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(0.3, 1.5, -2.0),
            Vec3::Y,
            50.0,
        );
        let (mut seen, mut behind) = (0, 0);
        for cam in [
            Pinhole::new(&desc, 64, 48).unwrap(),
            Pinhole::new(&desc, 320, 180)
                .unwrap()
                .with_shift(Vec2::new(0.031, -0.017)),
        ] {
            let proj = Projector::new(&cam);
            for _ in 0..20_000 {
                let p = Vec3::new(next() * 20.0, next() * 20.0, next() * 20.0);
                let want = cam.project(p, 0);
                match (proj.project(p.into()), want) {
                    (Some(s), Some(f)) => {
                        let fm = f - Vec2::splat(0.5);
                        assert_eq!(
                            [s.x.to_bits(), s.y.to_bits()],
                            [fm.x.to_bits(), fm.y.to_bits()],
                            "{p}"
                        );
                        seen += 1;
                    }
                    (None, None) => behind += 1,
                    (a, b) => panic!("{p}: {a:?} vs {b:?}"),
                }
            }
        }
        assert!(seen > 10_000 && behind > 1_000, "{seen} {behind}");
    }

    #[test]
    fn floor_xy_equals_floor_i32() {
        use parallax_core::math::floor_i32;
        let vals = [
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            -2.0,
            0.999_999_9,
            -0.999_999_9,
            1e-30,
            -1e-30,
            319.999_97,
            -1.000_000_1,
            8_388_607.5,
            -8_388_607.5,
        ];
        for &x in &vals {
            for &y in &vals {
                let (ix, iy, f) = floor_xy(Vec4::new(x, y, f32::NAN, 1e30));
                assert_eq!((ix, iy), (floor_i32(x), floor_i32(y)), "{x} {y}");
                assert_eq!(
                    [f.x.to_bits(), f.y.to_bits()],
                    [(x - ix as f32).to_bits(), (y - iy as f32).to_bits()]
                );
            }
        }
    }
}
