//! [`UnitCube::clip_ray_oct_into`]: the f64 cube clip of [`UnitCube::clip_ray`] for eight
//! rays at once, one ray per lane of AVX-512 `f64` `zmm` registers (Widmer et al. 2015, §3.2;
//! the application is a batch of depth-of-field lens rays, §5.2, `quadtree/batch.rs`).
//!
//! **Same bits.** Every lane performs [`UnitCube::clip_ray_quad`]'s operations (the scalar
//! clip's IEEE operations in its order, `space_pair.rs`): the homogeneous origin and
//! direction as separate products and sums, each face's root `-alpha / beta`, the running
//! `lo` / `hi` updates in face order as selects under `root > lo` / `root < hi` (here
//! `__mmask8` masks and `vblendmpd` instead of vector masks and `vblendvpd`), the empty test
//! of a face with `beta == 0` (or NaN) and `alpha < 0`, the end points `a + b t` with one
//! reciprocal of `w`, and the clamp `maxpd` with `0` second, then `minpd` with `1` second.
//! Negation is an `xor` of the sign bit and `|hi|` an `and` of it away, as in the narrower
//! forms. Rays the scalar clip rejects up front (not valid, a NaN bound) send all eight
//! through the portable twin.
//!
//! **Why.** The eight rays of a batch share each of the 8 `f64` divisions (6 face roots, 2
//! reciprocals) and all the face and end-point arithmetic: half the instructions of two
//! four-lane clips.
//!
//! **Twin and dispatch.** With AVX-512F (checked at run time) the lanes; otherwise (and off
//! x86_64) [`UnitCube::clip_ray_oct_twin`], two [`UnitCube::clip_ray_quad_into`] (AVX lanes
//! or SSE2 pairs). Valgrind runs no AVX-512 code, so instruction counts under callgrind are
//! those of the twin. Test: `tests::oct_equals_scalar` (every field's bits, the random and
//! degenerate rays of the four-lane test in windows of 8).

use glam::Vec3;
use parallax_core::Ray;

use crate::{CubeSegment, UnitCube};

impl UnitCube {
    /// [`Self::clip_ray`] of eight rays written into `out`: the same results bit for bit
    /// (module docs).
    #[inline]
    pub fn clip_ray_oct_into(&self, r: &[Ray; 8], out: &mut [Option<CubeSegment>; 8]) {
        #[cfg(target_arch = "x86_64")]
        {
            let ok = |r: &Ray| r.is_valid() && !r.t_min.is_nan() && !r.t_max.is_nan();
            if std::arch::is_x86_feature_detected!("avx512f") && r.iter().all(ok) {
                // SAFETY: AVX-512F is available (checked above).
                unsafe { self.clip_oct_avx512(r, out) };
                return;
            }
        }
        self.clip_ray_oct_twin(r, out);
    }

    /// The portable twin of [`Self::clip_ray_oct_into`]: two four-ray clips.
    #[inline]
    pub fn clip_ray_oct_twin(&self, r: &[Ray; 8], out: &mut [Option<CubeSegment>; 8]) {
        let (ra, rb) = r.split_at(4);
        let (oa, ob) = out.split_at_mut(4);
        self.clip_ray_quad_into(
            ra.try_into().expect("four rays"),
            oa.try_into().expect("four segments"),
        );
        self.clip_ray_quad_into(
            rb.try_into().expect("four rays"),
            ob.try_into().expect("four segments"),
        );
    }

    /// The lanes of [`Self::clip_ray_oct_into`] for eight valid rays (module docs).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    unsafe fn clip_oct_avx512(&self, r: &[Ray; 8], out: &mut [Option<CubeSegment>; 8]) {
        use std::arch::x86_64::*;
        // SAFETY (whole body): AVX-512F (and the AVX it implies) is enabled for this
        // function; the stores write eight-element arrays.
        unsafe {
            let m = &self.world_to_cube;
            // Lane `i` is `r[i]`; `f32 -> f64` is exact (`vcvtps2pd` = `as f64`).
            let lanes = |f: fn(&Ray) -> f32| {
                _mm256_set_ps(
                    f(&r[7]),
                    f(&r[6]),
                    f(&r[5]),
                    f(&r[4]),
                    f(&r[3]),
                    f(&r[2]),
                    f(&r[1]),
                    f(&r[0]),
                )
            };
            let oct = |f: fn(&Ray) -> f32| _mm512_cvtps_pd(lanes(f));
            let (ox, oy, oz) = (
                oct(|r| r.origin.x),
                oct(|r| r.origin.y),
                oct(|r| r.origin.z),
            );
            let (dx, dy, dz) = (oct(|r| r.dir.x), oct(|r| r.dir.y), oct(|r| r.dir.z));
            let s = _mm512_set1_pd;
            let b = |c: usize| {
                _mm512_add_pd(
                    _mm512_add_pd(
                        _mm512_mul_pd(s(m.x_axis[c]), dx),
                        _mm512_mul_pd(s(m.y_axis[c]), dy),
                    ),
                    _mm512_mul_pd(s(m.z_axis[c]), dz),
                )
            };
            let a = |c: usize| {
                _mm512_add_pd(
                    _mm512_add_pd(
                        _mm512_add_pd(
                            _mm512_mul_pd(s(m.x_axis[c]), ox),
                            _mm512_mul_pd(s(m.y_axis[c]), oy),
                        ),
                        _mm512_mul_pd(s(m.z_axis[c]), oz),
                    ),
                    s(m.w_axis[c]),
                )
            };
            let (bx, by, bz, bw) = (b(0), b(1), b(2), b(3));
            let (ax, ay, az, aw) = (a(0), a(1), a(2), a(3));
            // `t_start`: `t_min` where `t_min > 0`, else `+0` (an `and` with the mask).
            let tmin = lanes(|r| r.t_min);
            let tmin = _mm256_and_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(tmin, _mm256_setzero_ps()), tmin);
            let mut lo = _mm512_cvtps_pd(tmin);
            let mut hi = oct(|r| r.t_max);
            let (near, far) = (s(self.near as f64), s(self.far as f64));
            let zero = _mm512_setzero_pd();
            let sign = _mm512_castpd_si512(s(-0.0));
            let neg =
                |v: __m512d| _mm512_castsi512_pd(_mm512_xor_si512(_mm512_castpd_si512(v), sign));
            let faces = [
                (_mm512_sub_pd(aw, near), bw),
                (_mm512_sub_pd(far, aw), neg(bw)),
                (ax, bx),
                (_mm512_sub_pd(aw, ax), _mm512_sub_pd(bw, bx)),
                (ay, by),
                (_mm512_sub_pd(aw, ay), _mm512_sub_pd(bw, by)),
            ];
            let mut empty: __mmask8 = 0;
            for (alpha, beta) in faces {
                let root = _mm512_div_pd(neg(alpha), beta);
                let up = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(beta, zero);
                let down = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(beta, zero);
                let up_lo = up & _mm512_cmp_pd_mask::<_CMP_GT_OQ>(root, lo);
                lo = _mm512_mask_blend_pd(up_lo, lo, root);
                let down_hi = down & _mm512_cmp_pd_mask::<_CMP_LT_OQ>(root, hi);
                hi = _mm512_mask_blend_pd(down_hi, hi, root);
                empty |= !(up | down) & _mm512_cmp_pd_mask::<_CMP_LT_OQ>(alpha, zero);
            }
            let abs_hi = _mm512_castsi512_pd(_mm512_andnot_si512(sign, _mm512_castpd_si512(hi)));
            let keep = !empty
                & _mm512_cmp_pd_mask::<_CMP_LT_OQ>(lo, hi)
                & _mm512_cmp_pd_mask::<_CMP_LT_OQ>(abs_hi, s(f64::INFINITY));
            if keep == 0 {
                *out = [None; 8];
                return;
            }
            let at = |t: __m512d| {
                (
                    _mm512_add_pd(ax, _mm512_mul_pd(bx, t)),
                    _mm512_add_pd(ay, _mm512_mul_pd(by, t)),
                    _mm512_add_pd(az, _mm512_mul_pd(bz, t)),
                    _mm512_add_pd(aw, _mm512_mul_pd(bw, t)),
                )
            };
            let one = s(1.0);
            let c01 = |v: __m512d| _mm512_cvtpd_ps(_mm512_min_pd(_mm512_max_pd(v, zero), one));
            let point = |h: (__m512d, __m512d, __m512d, __m512d)| {
                let r = _mm512_div_pd(one, h.3);
                let mut out = [[0.0f32; 8]; 3];
                _mm256_storeu_ps(out[0].as_mut_ptr(), c01(_mm512_mul_pd(h.0, r)));
                _mm256_storeu_ps(out[1].as_mut_ptr(), c01(_mm512_mul_pd(h.1, r)));
                _mm256_storeu_ps(out[2].as_mut_ptr(), c01(_mm512_mul_pd(h.2, r)));
                let mut w = [0.0f64; 8];
                _mm512_storeu_pd(w.as_mut_ptr(), h.3);
                (out, w)
            };
            let (p0, w0) = point(at(lo));
            let (p1, w1) = point(at(hi));
            let mut t = [[0.0f32; 8]; 2];
            _mm256_storeu_ps(t[0].as_mut_ptr(), _mm512_cvtpd_ps(lo));
            _mm256_storeu_ps(t[1].as_mut_ptr(), _mm512_cvtpd_ps(hi));
            // A plain loop, not `array::from_fn` (its closure is not inlined into a
            // `target_feature` function).
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
    use parallax_core::Ray;

    use crate::space_pair::tests::{bits, test_rays};

    #[test]
    fn oct_equals_scalar() {
        let cube = crate::space::tests::cube();
        let rays = test_rays(&cube);
        let eye = cube.camera.frame.position;
        let mut clipped = 0;
        for w in rays.windows(8) {
            let w: &[Ray; 8] = w.try_into().unwrap();
            // Both forms overwrite every slot (here pre-filled with a segment).
            let fill = cube.clip_ray(&Ray::new(eye, glam::Vec3::NEG_Z));
            assert!(fill.is_some());
            let (mut oct, mut twin) = ([fill; 8], [fill; 8]);
            cube.clip_ray_oct_into(w, &mut oct);
            cube.clip_ray_oct_twin(w, &mut twin);
            for ((r, o), t) in w.iter().zip(&oct).zip(&twin) {
                let one = cube.clip_ray(r);
                assert_eq!(bits(&one), bits(o), "{r:?}");
                assert_eq!(bits(&one), bits(t), "{r:?}");
                clipped += one.is_some() as usize;
            }
        }
        assert!(clipped > rays.len(), "{clipped} of {} windows", rays.len());
    }
}
