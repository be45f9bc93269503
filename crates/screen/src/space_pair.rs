//! [`UnitCube::clip_ray_pair`]: the f64 cube clip of [`UnitCube::clip_ray`] for two rays at
//! once, one ray per lane of an SSE2 `f64` register (Widmer et al. 2015, §3.2: rays are
//! traced as straight segments of the unit cube; the application is depth of field, §5.2,
//! whose short lens rays spend a quarter of their tracer's instructions in this clip).
//!
//! **Same bits.** Every lane performs the scalar clip's IEEE operations in the same order:
//! the products and sums of the homogeneous origin and direction, each face's root
//! `-alpha / beta`, the running `lo` / `hi` updates `if root > lo { root } else { lo }` in
//! face order (so even the sign of a zero bound is the scalar one), the end points
//! `a + b t` with one reciprocal of `w` and three products, and the clamp to `[0, 1]`
//! as the scalar code compiles it (`maxpd` with `0` second, then `minpd` with `1` second:
//! NaN and `-0` give `+0`). The scalar clip's branches on the sign of `beta` become lane
//! masks; a face with `beta == 0` (or NaN) and `alpha < 0` marks its lane empty, as the
//! scalar early return does. Rays the scalar clip rejects up front (not valid, a NaN bound)
//! go through [`UnitCube::clip_ray`] (both of the pair). Test: `tests::pair_equals_scalar`
//! (every field's bits, random and degenerate rays).
//!
//! **Why.** Two rays share each of the 8 `f64` divisions (6 face roots, 2 reciprocals), the
//! divider's throughput being what a batch of short rays waits on, and the face branches
//! (mispredicted where a ray's exit face changes) disappear. Off x86_64 the pair is two
//! scalar clips (the portable twin).
//!
//! [`UnitCube::clip_ray_quad`] does the same for four rays in the four lanes of AVX `f64`
//! `ymm` registers (run-time CPU check; the twin is two pairs): the 8 divisions of four rays
//! are 8 `vdivpd`, and the face and end-point arithmetic is shared by four rays instead of
//! two.

use glam::Vec3;
use parallax_core::Ray;

use crate::space::t_start;
use crate::{CubeSegment, UnitCube};

impl UnitCube {
    /// [`Self::clip_ray`] of `r0` and `r1`: the same results bit for bit (module docs).
    #[inline]
    pub fn clip_ray_pair(&self, r0: &Ray, r1: &Ray) -> [Option<CubeSegment>; 2] {
        let ok = |r: &Ray| r.is_valid() && !r.t_min.is_nan() && !r.t_max.is_nan();
        if !(ok(r0) && ok(r1)) {
            return [self.clip_ray(r0), self.clip_ray(r1)];
        }
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: SSE2 is part of the x86_64 baseline.
            unsafe { self.clip_pair_sse2(r0, r1) }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            [self.clip_ray(r0), self.clip_ray(r1)]
        }
    }

    /// The lanes of [`Self::clip_ray_pair`] for two valid rays (module docs).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn clip_pair_sse2(&self, r0: &Ray, r1: &Ray) -> [Option<CubeSegment>; 2] {
        use std::arch::x86_64::*;
        // SAFETY (whole body): SSE2 is part of the x86_64 baseline; the stores write
        // two-element arrays.
        unsafe {
            let m = &self.world_to_cube;
            // Lane 0 is `r0`, lane 1 is `r1`.
            let pair = |a: f32, b: f32| _mm_set_pd(b as f64, a as f64);
            let (ox, oy, oz) = (
                pair(r0.origin.x, r1.origin.x),
                pair(r0.origin.y, r1.origin.y),
                pair(r0.origin.z, r1.origin.z),
            );
            let (dx, dy, dz) = (
                pair(r0.dir.x, r1.dir.x),
                pair(r0.dir.y, r1.dir.y),
                pair(r0.dir.z, r1.dir.z),
            );
            let s = _mm_set1_pd;
            // Row `c` of `b = X dx + Y dy + Z dz` and `a = X ox + Y oy + Z oz + W`, in the
            // scalar code's order of operations.
            let b = |c: usize| {
                _mm_add_pd(
                    _mm_add_pd(
                        _mm_mul_pd(s(m.x_axis[c]), dx),
                        _mm_mul_pd(s(m.y_axis[c]), dy),
                    ),
                    _mm_mul_pd(s(m.z_axis[c]), dz),
                )
            };
            let a = |c: usize| {
                _mm_add_pd(
                    _mm_add_pd(
                        _mm_add_pd(
                            _mm_mul_pd(s(m.x_axis[c]), ox),
                            _mm_mul_pd(s(m.y_axis[c]), oy),
                        ),
                        _mm_mul_pd(s(m.z_axis[c]), oz),
                    ),
                    s(m.w_axis[c]),
                )
            };
            let (bx, by, bz, bw) = (b(0), b(1), b(2), b(3));
            let (ax, ay, az, aw) = (a(0), a(1), a(2), a(3));
            let mut lo = _mm_set_pd(t_start(r1.t_min), t_start(r0.t_min));
            let mut hi = _mm_set_pd(r1.t_max as f64, r0.t_max as f64);
            let (near, far) = (s(self.near as f64), s(self.far as f64));
            let zero = _mm_setzero_pd();
            let sign = s(-0.0);
            let neg = |v: __m128d| _mm_xor_pd(v, sign);
            let faces = [
                (_mm_sub_pd(aw, near), bw),
                (_mm_sub_pd(far, aw), neg(bw)),
                (ax, bx),
                (_mm_sub_pd(aw, ax), _mm_sub_pd(bw, bx)),
                (ay, by),
                (_mm_sub_pd(aw, ay), _mm_sub_pd(bw, by)),
            ];
            let select = |m: __m128d, x: __m128d, y: __m128d| {
                _mm_or_pd(_mm_and_pd(m, x), _mm_andnot_pd(m, y))
            };
            let mut empty = zero;
            for (alpha, beta) in faces {
                let root = _mm_div_pd(neg(alpha), beta);
                let up = _mm_cmpgt_pd(beta, zero);
                let down = _mm_cmplt_pd(beta, zero);
                lo = select(_mm_and_pd(up, _mm_cmpgt_pd(root, lo)), root, lo);
                hi = select(_mm_and_pd(down, _mm_cmplt_pd(root, hi)), root, hi);
                empty = _mm_or_pd(
                    empty,
                    _mm_andnot_pd(_mm_or_pd(up, down), _mm_cmplt_pd(alpha, zero)),
                );
            }
            // `lo < hi && hi.is_finite()` (`|hi| < inf` is false for NaN).
            let abs_hi = _mm_andnot_pd(sign, hi);
            let keep = _mm_andnot_pd(
                empty,
                _mm_and_pd(_mm_cmplt_pd(lo, hi), _mm_cmplt_pd(abs_hi, s(f64::INFINITY))),
            );
            let keep = _mm_movemask_pd(keep);
            if keep == 0 {
                return [None, None];
            }
            let at = |t: __m128d| {
                (
                    _mm_add_pd(ax, _mm_mul_pd(bx, t)),
                    _mm_add_pd(ay, _mm_mul_pd(by, t)),
                    _mm_add_pd(az, _mm_mul_pd(bz, t)),
                    _mm_add_pd(aw, _mm_mul_pd(bw, t)),
                )
            };
            let one = s(1.0);
            // `v.max(0.0).min(1.0)` as the scalar clip compiles it (module docs).
            let c01 = |v: __m128d| _mm_cvtpd_ps(_mm_min_pd(_mm_max_pd(v, zero), one));
            let point = |h: (__m128d, __m128d, __m128d, __m128d)| {
                let r = _mm_div_pd(one, h.3);
                let mut out = [[0.0f32; 4]; 3];
                _mm_storeu_ps(out[0].as_mut_ptr(), c01(_mm_mul_pd(h.0, r)));
                _mm_storeu_ps(out[1].as_mut_ptr(), c01(_mm_mul_pd(h.1, r)));
                _mm_storeu_ps(out[2].as_mut_ptr(), c01(_mm_mul_pd(h.2, r)));
                let mut w = [0.0f64; 2];
                _mm_storeu_pd(w.as_mut_ptr(), h.3);
                (out, w)
            };
            let (p0, w0) = point(at(lo));
            let (p1, w1) = point(at(hi));
            let mut t = [[0.0f32; 4]; 2];
            _mm_storeu_ps(t[0].as_mut_ptr(), _mm_cvtpd_ps(lo));
            _mm_storeu_ps(t[1].as_mut_ptr(), _mm_cvtpd_ps(hi));
            let lane = |i: usize| {
                (keep & (1 << i) != 0).then(|| CubeSegment {
                    p0: Vec3::new(p0[0][i], p0[1][i], p0[2][i]),
                    p1: Vec3::new(p1[0][i], p1[1][i], p1[2][i]),
                    t0: t[0][i],
                    t1: t[1][i],
                    w0: w0[i],
                    w1: w1[i],
                })
            };
            [lane(0), lane(1)]
        }
    }

    /// [`Self::clip_ray`] of four rays: the same results bit for bit. With AVX (checked at
    /// run time) the four rays are the four lanes of `f64` `ymm` registers, every lane doing
    /// the scalar clip's operations as [`Self::clip_ray_pair`]'s two; otherwise (and off
    /// x86_64) two [`Self::clip_ray_pair`]s, the portable twin.
    #[inline]
    pub fn clip_ray_quad(&self, r: &[Ray; 4]) -> [Option<CubeSegment>; 4] {
        let mut out = [None; 4];
        self.clip_ray_quad_into(r, &mut out);
        out
    }

    /// [`Self::clip_ray_quad`] written into `out` (the batches' clip phase: the segments go
    /// straight into the caller's array, not through a returned copy).
    #[inline]
    pub fn clip_ray_quad_into(&self, r: &[Ray; 4], out: &mut [Option<CubeSegment>; 4]) {
        #[cfg(target_arch = "x86_64")]
        {
            let ok = |r: &Ray| r.is_valid() && !r.t_min.is_nan() && !r.t_max.is_nan();
            if std::arch::is_x86_feature_detected!("avx") && r.iter().all(ok) {
                // SAFETY: AVX is available (checked above).
                unsafe { self.clip_quad_avx(r, out) };
                return;
            }
        }
        *out = self.clip_ray_quad_twin(r);
    }

    /// The portable twin of [`Self::clip_ray_quad`]: two pairs.
    #[inline]
    pub fn clip_ray_quad_twin(&self, r: &[Ray; 4]) -> [Option<CubeSegment>; 4] {
        let [a, b] = self.clip_ray_pair(&r[0], &r[1]);
        let [c, d] = self.clip_ray_pair(&r[2], &r[3]);
        [a, b, c, d]
    }

    /// The lanes of [`Self::clip_ray_quad`] for four valid rays (module docs: the pair's
    /// operations, four lanes wide).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn clip_quad_avx(&self, r: &[Ray; 4], out: &mut [Option<CubeSegment>; 4]) {
        use std::arch::x86_64::*;
        // SAFETY (whole body): AVX is enabled for this function; the stores write
        // four-element arrays.
        unsafe {
            let m = &self.world_to_cube;
            // Lane `i` is `r[i]`; `f32 -> f64` is exact (`cvtps2pd` = `as f64`).
            let quad = |f: fn(&Ray) -> f32| {
                _mm256_cvtps_pd(_mm_set_ps(f(&r[3]), f(&r[2]), f(&r[1]), f(&r[0])))
            };
            let (ox, oy, oz) = (
                quad(|r| r.origin.x),
                quad(|r| r.origin.y),
                quad(|r| r.origin.z),
            );
            let (dx, dy, dz) = (quad(|r| r.dir.x), quad(|r| r.dir.y), quad(|r| r.dir.z));
            let s = _mm256_set1_pd;
            let b = |c: usize| {
                _mm256_add_pd(
                    _mm256_add_pd(
                        _mm256_mul_pd(s(m.x_axis[c]), dx),
                        _mm256_mul_pd(s(m.y_axis[c]), dy),
                    ),
                    _mm256_mul_pd(s(m.z_axis[c]), dz),
                )
            };
            let a = |c: usize| {
                _mm256_add_pd(
                    _mm256_add_pd(
                        _mm256_add_pd(
                            _mm256_mul_pd(s(m.x_axis[c]), ox),
                            _mm256_mul_pd(s(m.y_axis[c]), oy),
                        ),
                        _mm256_mul_pd(s(m.z_axis[c]), oz),
                    ),
                    s(m.w_axis[c]),
                )
            };
            let (bx, by, bz, bw) = (b(0), b(1), b(2), b(3));
            let (ax, ay, az, aw) = (a(0), a(1), a(2), a(3));
            // `t_start`: `t_min` where `t_min > 0`, else `+0` (an `and` with the mask).
            let tmin = _mm_set_ps(r[3].t_min, r[2].t_min, r[1].t_min, r[0].t_min);
            let tmin = _mm_and_ps(_mm_cmpgt_ps(tmin, _mm_setzero_ps()), tmin);
            let mut lo = _mm256_cvtps_pd(tmin);
            let mut hi = quad(|r| r.t_max);
            let (near, far) = (s(self.near as f64), s(self.far as f64));
            let zero = _mm256_setzero_pd();
            let sign = s(-0.0);
            let neg = |v: __m256d| _mm256_xor_pd(v, sign);
            let faces = [
                (_mm256_sub_pd(aw, near), bw),
                (_mm256_sub_pd(far, aw), neg(bw)),
                (ax, bx),
                (_mm256_sub_pd(aw, ax), _mm256_sub_pd(bw, bx)),
                (ay, by),
                (_mm256_sub_pd(aw, ay), _mm256_sub_pd(bw, by)),
            ];
            let mut empty = zero;
            for (alpha, beta) in faces {
                let root = _mm256_div_pd(neg(alpha), beta);
                let up = _mm256_cmp_pd::<_CMP_GT_OQ>(beta, zero);
                let down = _mm256_cmp_pd::<_CMP_LT_OQ>(beta, zero);
                let up_lo = _mm256_and_pd(up, _mm256_cmp_pd::<_CMP_GT_OQ>(root, lo));
                lo = _mm256_blendv_pd(lo, root, up_lo);
                let down_hi = _mm256_and_pd(down, _mm256_cmp_pd::<_CMP_LT_OQ>(root, hi));
                hi = _mm256_blendv_pd(hi, root, down_hi);
                empty = _mm256_or_pd(
                    empty,
                    _mm256_andnot_pd(
                        _mm256_or_pd(up, down),
                        _mm256_cmp_pd::<_CMP_LT_OQ>(alpha, zero),
                    ),
                );
            }
            let abs_hi = _mm256_andnot_pd(sign, hi);
            let keep = _mm256_andnot_pd(
                empty,
                _mm256_and_pd(
                    _mm256_cmp_pd::<_CMP_LT_OQ>(lo, hi),
                    _mm256_cmp_pd::<_CMP_LT_OQ>(abs_hi, s(f64::INFINITY)),
                ),
            );
            let keep = _mm256_movemask_pd(keep);
            if keep == 0 {
                *out = [None; 4];
                return;
            }
            let at = |t: __m256d| {
                (
                    _mm256_add_pd(ax, _mm256_mul_pd(bx, t)),
                    _mm256_add_pd(ay, _mm256_mul_pd(by, t)),
                    _mm256_add_pd(az, _mm256_mul_pd(bz, t)),
                    _mm256_add_pd(aw, _mm256_mul_pd(bw, t)),
                )
            };
            let one = s(1.0);
            let c01 = |v: __m256d| _mm256_cvtpd_ps(_mm256_min_pd(_mm256_max_pd(v, zero), one));
            let point = |h: (__m256d, __m256d, __m256d, __m256d)| {
                let r = _mm256_div_pd(one, h.3);
                let mut out = [[0.0f32; 4]; 3];
                _mm_storeu_ps(out[0].as_mut_ptr(), c01(_mm256_mul_pd(h.0, r)));
                _mm_storeu_ps(out[1].as_mut_ptr(), c01(_mm256_mul_pd(h.1, r)));
                _mm_storeu_ps(out[2].as_mut_ptr(), c01(_mm256_mul_pd(h.2, r)));
                let mut w = [0.0f64; 4];
                _mm256_storeu_pd(w.as_mut_ptr(), h.3);
                (out, w)
            };
            let (p0, w0) = point(at(lo));
            let (p1, w1) = point(at(hi));
            let mut t = [[0.0f32; 4]; 2];
            _mm_storeu_ps(t[0].as_mut_ptr(), _mm256_cvtpd_ps(lo));
            _mm_storeu_ps(t[1].as_mut_ptr(), _mm256_cvtpd_ps(hi));
            // A plain loop, not `array::from_fn`: its closure is not inlined into this
            // `target_feature` function (a call per lane).
            for (i, o) in out.iter_mut().enumerate() {
                *o = if keep & (1 << i) != 0 {
                    Some(CubeSegment {
                        p0: Vec3::new(p0[0][i], p0[1][i], p0[2][i]),
                        p1: Vec3::new(p1[0][i], p1[1][i], p1[2][i]),
                        t0: t[0][i],
                        t1: t[1][i],
                        w0: w0[i],
                        w1: w1[i],
                    })
                } else {
                    None
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::{Vec2, Vec3};
    use parallax_core::Ray;

    use crate::CubeSegment;

    /// Every field's bits (`==` would let a signed zero or a NaN pass).
    fn bits(s: &Option<CubeSegment>) -> Option<[u64; 10]> {
        s.map(|s| {
            [
                s.p0.x.to_bits() as u64,
                s.p0.y.to_bits() as u64,
                s.p0.z.to_bits() as u64,
                s.p1.x.to_bits() as u64,
                s.p1.y.to_bits() as u64,
                s.p1.z.to_bits() as u64,
                s.t0.to_bits() as u64,
                s.t1.to_bits() as u64,
                s.w0.to_bits(),
                s.w1.to_bits(),
            ]
        })
    }

    struct Xs(u64);
    impl Xs {
        fn f(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    #[test]
    fn pair_and_quad_equal_scalar() {
        let cube = crate::space::tests::cube();
        let cam = &cube.camera;
        let eye = cam.frame.position;
        let mut rng = Xs(0x9e37_79b9_7f4a_7c15);
        let mut rays = Vec::new();
        for i in 0..4000 {
            let mut v = || Vec3::new(rng.f(), rng.f(), rng.f()) * 2.0 - 1.0;
            let (o, d) = match i % 5 {
                // From the eye (the depth-of-field lens rays' case) and near it.
                0 => (eye, v()),
                1 => (eye + v() * 0.05, v()),
                // Anywhere, and along axes (zero direction components: `beta == 0` faces).
                2 => (eye + v() * 10.0, v()),
                3 => (eye + v() * 5.0, v() * Vec3::new(1.0, 0.0, 1.0)),
                _ => (eye + v() * 5.0, Vec3::new(0.0, 0.0, -1.0 + v().x)),
            };
            let mut r = Ray::new(o, d);
            match i % 7 {
                0 => r.t_min = -0.0,
                1 => r.t_min = 0.5,
                2 => r.t_max = 3.0,
                3 => r.t_max = f32::INFINITY,
                _ => {}
            }
            rays.push(r);
        }
        // Rays through the cube's corners and along its faces (roots on a face, `-0`
        // coordinates), and rays the scalar clip rejects.
        for (x, y) in [
            (0.0, 0.0),
            (64.0, 48.0),
            (0.0, 24.0),
            (32.0, 0.0),
            (64.0, 10.0),
        ] {
            let dir = cam.frame.dir_to_world(cam.camera_dir(Vec2::new(x, y)));
            rays.push(Ray::new(eye, dir));
            rays.push(Ray::new(eye + dir, -dir));
        }
        let mut bad = Ray::new(eye, Vec3::X);
        bad.t_max = f32::NAN;
        rays.push(bad);
        rays.push(Ray::new(eye, Vec3::ZERO));
        let mut clipped = 0;
        for w in rays.windows(4) {
            let w: &[Ray; 4] = w.try_into().unwrap();
            let (quad, twin) = (cube.clip_ray_quad(w), cube.clip_ray_quad_twin(w));
            // The in-place form overwrites every slot (here pre-filled with a segment).
            let mut into = [cube.clip_ray(&Ray::new(eye, Vec3::NEG_Z)); 4];
            assert!(into[0].is_some());
            cube.clip_ray_quad_into(w, &mut into);
            for (((r, q), t), i) in w.iter().zip(&quad).zip(&twin).zip(&into) {
                let one = cube.clip_ray(r);
                assert_eq!(bits(&one), bits(q), "{r:?}");
                assert_eq!(bits(&one), bits(t), "{r:?}");
                assert_eq!(bits(&one), bits(i), "{r:?}");
            }
        }
        for w in rays.windows(2) {
            let pair = cube.clip_ray_pair(&w[0], &w[1]);
            for (r, p) in w.iter().zip(&pair) {
                let one = cube.clip_ray(r);
                assert_eq!(bits(&one), bits(p), "{r:?}");
                clipped += one.is_some() as usize;
            }
        }
        assert!(clipped > rays.len() / 4, "{clipped} of {}", rays.len());
    }
}
