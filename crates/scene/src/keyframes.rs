//! Keyframe samplers of glTF animations (glTF 2.0 spec §3.11 "Animations" and Appendix C
//! "Animation sampler interpolation modes"): STEP, LINEAR (spherical linear interpolation for
//! rotations) and CUBICSPLINE (cubic Hermite with in/out tangents per keyframe).
//!
//! Values are stored as [`Vec4`]: translations and scales use `xyz`, rotations are unit
//! quaternions `(x, y, z, w)`. Before the first keyframe and after the last the value is clamped
//! to the nearest end (spec §3.11).

use glam::{Quat, Vec4};

/// How a sampler interpolates between keyframes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// The value of the keyframe at or before `t`.
    Step,
    /// Linear for vectors, slerp for rotations.
    Linear,
    /// Cubic Hermite spline; three values per keyframe: in-tangent, value, out-tangent.
    CubicSpline,
}

/// A keyframe curve: increasing times and the values at them.
#[derive(Clone, Debug, PartialEq)]
pub struct Sampler {
    pub interpolation: Interpolation,
    /// Keyframe times (s), strictly increasing, at least one.
    pub times: Vec<f32>,
    /// One value per keyframe, or three (`a_k`, `v_k`, `b_k`) for [`Interpolation::CubicSpline`].
    pub values: Vec<Vec4>,
}

/// Why a sampler is unusable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SamplerError {
    #[error("sampler has no keyframes")]
    Empty,
    #[error("keyframe time {index} ({time}) is not finite or not greater than the previous one")]
    NotIncreasing { index: usize, time: f32 },
    #[error("{values} output values for {times} keyframes ({per} per keyframe expected)")]
    CountMismatch {
        times: usize,
        values: usize,
        per: usize,
    },
    #[error("output value {0} is not finite")]
    NonFinite(usize),
    #[error("rotation value {0} is a zero quaternion")]
    ZeroRotation(usize),
}

impl Sampler {
    /// Checks the invariants (non-empty, strictly increasing finite times, value count, finite
    /// values) and, when `rotation`, normalises the keyframe quaternions (tangents are kept).
    pub fn new(
        interpolation: Interpolation,
        times: Vec<f32>,
        mut values: Vec<Vec4>,
        rotation: bool,
    ) -> Result<Self, SamplerError> {
        if times.is_empty() {
            return Err(SamplerError::Empty);
        }
        for (i, &t) in times.iter().enumerate() {
            if !t.is_finite() || (i > 0 && t <= times[i - 1]) {
                return Err(SamplerError::NotIncreasing { index: i, time: t });
            }
        }
        let per = if interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        if values.len() != times.len() * per {
            return Err(SamplerError::CountMismatch {
                times: times.len(),
                values: values.len(),
                per,
            });
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(SamplerError::NonFinite(i));
        }
        if rotation {
            for (i, v) in values.iter_mut().enumerate() {
                if per == 3 && i % 3 != 1 {
                    continue;
                }
                let len = v.length();
                if len < 1e-12 {
                    return Err(SamplerError::ZeroRotation(i));
                }
                *v /= len;
            }
        }
        Ok(Self {
            interpolation,
            times,
            values,
        })
    }

    /// Time of the last keyframe.
    pub fn end(&self) -> f32 {
        *self.times.last().expect("samplers are not empty")
    }

    fn value(&self, k: usize) -> Vec4 {
        match self.interpolation {
            Interpolation::CubicSpline => self.values[3 * k + 1],
            _ => self.values[k],
        }
    }

    /// The keyframe interval of `t`: `(k, s)` with `times[k] <= t < times[k+1]` and `s` the
    /// fraction of the interval; `None` when `t` is outside (clamped by the caller).
    fn locate(&self, t: f32) -> Option<(usize, f32)> {
        let n = self.times.len();
        if n < 2 || t.is_nan() || t <= self.times[0] || t >= self.times[n - 1] {
            return None;
        }
        // First index whose time is > t, minus one: 0 <= k < n - 1.
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        Some((k, ((t - t0) / (t1 - t0)).clamp(0.0, 1.0)))
    }

    /// The vector value at time `t` (translation or scale; `w` is carried along).
    pub fn sample_vec(&self, t: f32) -> Vec4 {
        self.sample(t, false)
    }

    /// The rotation at time `t` (unit quaternion).
    pub fn sample_rotation(&self, t: f32) -> Quat {
        Quat::from_vec4(self.sample(t, true)).normalize()
    }

    fn sample(&self, t: f32, rotation: bool) -> Vec4 {
        let Some((k, s)) = self.locate(t) else {
            return if t > self.times[0] {
                self.value(self.times.len() - 1)
            } else {
                self.value(0)
            };
        };
        match self.interpolation {
            Interpolation::Step => self.values[k],
            Interpolation::Linear if rotation => slerp(self.values[k], self.values[k + 1], s),
            Interpolation::Linear => self.values[k].lerp(self.values[k + 1], s),
            Interpolation::CubicSpline => {
                // Spec Appendix C: p(s) = (2s³-3s²+1) v_k + td (s³-2s²+s) b_k
                //                       + (-2s³+3s²) v_k+1 + td (s³-s²) a_k+1
                let td = self.times[k + 1] - self.times[k];
                let (s2, s3) = (s * s, s * s * s);
                let v0 = self.values[3 * k + 1];
                let b0 = self.values[3 * k + 2];
                let a1 = self.values[3 * (k + 1)];
                let v1 = self.values[3 * (k + 1) + 1];
                let p = v0 * (2.0 * s3 - 3.0 * s2 + 1.0)
                    + b0 * (td * (s3 - 2.0 * s2 + s))
                    + v1 * (-2.0 * s3 + 3.0 * s2)
                    + a1 * (td * (s3 - s2));
                if rotation { p.normalize_or_zero() } else { p }
            }
        }
    }
}

/// Spherical linear interpolation of unit quaternions along the shorter arc (glTF 2.0 spec
/// Appendix C, "Spherical linear interpolation"); normalised linear interpolation (nlerp) where
/// the two are nearly parallel (angle below ~0.06 degrees), where slerp divides by ~0.
pub fn slerp(a: Vec4, b: Vec4, s: f32) -> Vec4 {
    let mut d = a.dot(b);
    let b = if d < 0.0 {
        d = -d;
        -b
    } else {
        b
    };
    if d > 1.0 - 1e-6 {
        return a.lerp(b, s).normalize_or_zero();
    }
    let angle = d.min(1.0).acos();
    let sin = angle.sin();
    (a * ((1.0 - s) * angle).sin() + b * (s * angle).sin()) / sin
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(axis_angle_y: f32) -> Vec4 {
        Vec4::from(Quat::from_rotation_y(axis_angle_y))
    }

    #[test]
    fn clamps_steps_and_interpolates() {
        let times = vec![1.0, 2.0, 4.0];
        let values = vec![Vec4::ZERO, Vec4::ONE, Vec4::splat(3.0)];
        let lin =
            Sampler::new(Interpolation::Linear, times.clone(), values.clone(), false).unwrap();
        assert_eq!(lin.sample_vec(0.0), Vec4::ZERO);
        assert_eq!(lin.sample_vec(1.5), Vec4::splat(0.5));
        assert_eq!(lin.sample_vec(3.0), Vec4::splat(2.0));
        assert_eq!(lin.sample_vec(9.0), Vec4::splat(3.0));
        assert_eq!(lin.sample_vec(f32::NAN), Vec4::ZERO);
        let step = Sampler::new(Interpolation::Step, times, values, false).unwrap();
        assert_eq!(step.sample_vec(1.99), Vec4::ZERO);
        assert_eq!(step.sample_vec(2.0), Vec4::ONE);
        assert_eq!(step.sample_vec(3.9), Vec4::ONE);
    }

    #[test]
    fn slerp_follows_the_short_arc_at_constant_speed() {
        let a = q(0.0);
        let b = q(1.2);
        for s in [0.0, 0.25, 0.5, 0.9, 1.0] {
            let r = slerp(a, b, s);
            assert!(r.abs_diff_eq(q(1.2 * s), 1e-6), "{s}: {r}");
            // -b is the same rotation: the result is the same rotation (up to sign).
            let r2 = slerp(a, -b, s);
            assert!(r2.dot(r).abs() > 1.0 - 1e-6, "{s}");
        }
        assert!(slerp(a, a, 0.3).abs_diff_eq(a, 1e-7));
    }

    #[test]
    fn cubic_spline_with_zero_tangents_is_smoothstep() {
        let v = |x: f32| Vec4::splat(x);
        let values = vec![v(0.0), v(0.0), v(0.0), v(0.0), v(1.0), v(0.0)];
        let c = Sampler::new(Interpolation::CubicSpline, vec![0.0, 2.0], values, false).unwrap();
        assert!((c.sample_vec(1.0).x - 0.5).abs() < 1e-6);
        assert!((c.sample_vec(0.5).x - (3.0 * 0.0625 - 2.0 * 0.015625)).abs() < 1e-6);
        assert_eq!(c.sample_vec(5.0).x, 1.0);
    }

    #[test]
    fn malformed_samplers_are_errors() {
        let one = vec![Vec4::ZERO; 2];
        assert_eq!(
            Sampler::new(Interpolation::Linear, vec![0.0, 0.0], one.clone(), false),
            Err(SamplerError::NotIncreasing {
                index: 1,
                time: 0.0
            })
        );
        assert!(matches!(
            Sampler::new(
                Interpolation::Linear,
                vec![f32::NAN, 1.0],
                one.clone(),
                false
            ),
            Err(SamplerError::NotIncreasing { index: 0, .. })
        ));
        assert!(matches!(
            Sampler::new(
                Interpolation::CubicSpline,
                vec![0.0, 1.0],
                one.clone(),
                false
            ),
            Err(SamplerError::CountMismatch { .. })
        ));
        assert_eq!(
            Sampler::new(Interpolation::Linear, vec![], vec![], false),
            Err(SamplerError::Empty)
        );
        assert_eq!(
            Sampler::new(Interpolation::Step, vec![0.0, 1.0], one, true),
            Err(SamplerError::ZeroRotation(0))
        );
        let nan = vec![Vec4::ZERO, Vec4::NAN];
        assert_eq!(
            Sampler::new(Interpolation::Step, vec![0.0, 1.0], nan, false),
            Err(SamplerError::NonFinite(1))
        );
    }
}
