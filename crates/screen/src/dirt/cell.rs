//! Bucket tracing in one level-0 cell of a DIRT view (Vardis et al. 2017, §4.2.1 and
//! Algorithm 1 lines 7-22): the buckets of the ray's depth span in the cell, in ray order, the
//! empty ones skipped by the cell record's mask, every listed triangle tested (`tri4`), and
//! the acceptance of the best hit once the walk has reached it (the rule and why it is exact:
//! `walk`'s module docs).
//!
//! | parameter | meaning |
//! |---|---|
//! | `B` (`ViewConsts::buckets`) | depth buckets per cell; above 32, the mask holds groups of `ceil(B / 32)` |

use parallax_raster::dirt::{DirtCapture, bucket_index};

use super::segment::Segment;
use super::tri4::Query;
use super::view::{ViewConsts, ViewRay};

/// `λ` of the best hit so far, computed once per best hit.
pub(super) struct HitLambda {
    t: f32,
    l: f32,
}

impl HitLambda {
    pub(super) const NONE: HitLambda = HitLambda {
        t: f32::NAN,
        l: 0.0,
    };

    #[inline]
    pub(super) fn get(&mut self, seg: &Segment, r: &ViewRay, t: f32) -> f32 {
        if self.t != t {
            *self = HitLambda {
                t,
                l: seg.lambda_of(r, t),
            };
        }
        self.l
    }
}

/// A level-0 cell the walk traces.
pub(super) struct Cell {
    pub(super) index: usize,
    /// The cell's eq. 1 constants (its record).
    pub(super) zmin: f32,
    pub(super) scale: f32,
    /// Its non-empty buckets ([`parallax_raster::dirt::bucket_mask`]).
    pub(super) mask: u32,
    /// The buckets of the ray's depth at entry and at exit.
    pub(super) buckets: (u32, u32),
    /// `λ` where the ray leaves the cell.
    pub(super) l_exit: f32,
}

/// Bucket tracing in one cell whose range of buckets holds a triangle (Alg. 1 lines 7-22);
/// true when the answer is known. Inlined into the walk's loop (a call would store and reload
/// the walk's state around it: every XMM register is caller-saved).
#[inline(always)]
pub(super) fn trace_cell<const ISA: u8>(
    vc: &ViewConsts,
    cap: &DirtCapture,
    r: &ViewRay,
    seg: &Segment,
    c: &Cell,
    hit_l: &mut HitLambda,
    q: &mut Query,
) -> bool {
    let (lo, scale, nb) = (c.zmin, c.scale, vc.buckets);
    let (b_a, b_b) = c.buckets;
    let (offsets, ids) = (cap.offsets(), cap.ids());
    let base = c.index * nb as usize;
    let ascending = b_a <= b_b;
    let mut b = b_a;
    loop {
        if any_bucket(c.mask, b, b, nb) {
            q.counters.buckets += 1;
            let k = base + b as usize;
            if q.test::<ISA>(&ids[offsets[k] as usize..offsets[k + 1] as usize]) {
                return true;
            }
        }
        if q.best.found() && hit_l.get(seg, r, q.best.t) <= c.l_exit {
            // Accept once the walk has reached the hit's bucket (module docs).
            let bb = bucket_index(lo, scale, nb, r.depth(q.best.t));
            if (ascending && bb <= b) || (!ascending && bb >= b) {
                return true;
            }
        }
        if b == b_b {
            return false;
        }
        if ascending {
            b += 1;
        } else {
            b -= 1;
        }
    }
}

/// [`bucket_index`] (eq. 1) with the conversion done by `cvttss2si` on 64 bits, which needs
/// no saturation fix-ups: for `v > 0` below `2^63` it is `floor(v)`, above (and `+inf`) it is
/// `i64::MIN`, `2^63` as `u64`; either way the `min` with `buckets - 1` gives what the
/// saturating `v as u32` gives. Tested equal to [`bucket_index`].
#[inline(always)]
pub(super) fn bucket_at(zmin: f32, scale: f32, buckets: u32, z: f32) -> u32 {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cvttss_si64, _mm_set_ss};
        let v = (z - zmin) * scale;
        if v > 0.0 {
            // SAFETY: SSE is part of the x86_64 baseline.
            let i = unsafe { _mm_cvttss_si64(_mm_set_ss(v)) } as u64;
            i.min(buckets as u64 - 1) as u32
        } else {
            0
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    bucket_index(zmin, scale, buckets, z)
}

/// Whether `mask` (a cell's non-empty buckets, [`parallax_raster::dirt::bucket_mask`]) has a bit of buckets
/// `b0..=b1` (`b0 <= b1 < buckets`): `mask & bucket_mask(b0, b1, buckets) != 0` in two
/// shifts (the bits at and above `b0`'s, then only the `b1 - b0 + 1` lowest kept).
#[inline(always)]
pub(super) fn any_bucket(mask: u32, b0: u32, b1: u32, buckets: u32) -> bool {
    let (lo, hi) = if buckets <= 32 {
        (b0, b1)
    } else {
        let g = buckets.div_ceil(32);
        (b0 / g, b1 / g)
    };
    ((mask >> (lo & 31)) << ((31 - (hi - lo)) & 31)) != 0
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_raster::dirt::bucket_mask;

    /// [`bucket_at`] is [`bucket_index`].
    #[test]
    fn bucket_at_is_bucket_index() {
        let zs = [
            0.0f32,
            -1.0,
            0.5,
            1.0,
            1.000_001,
            2.5,
            3.999_999,
            4.0,
            7.75,
            100.0,
            1e9,
            4.3e9,
            1e19,
            1e30,
            f32::MAX,
            f32::INFINITY,
            f32::NAN,
        ];
        for buckets in [1u32, 2, 16, 32, 255, 1 << 20] {
            for &(zmin, scale) in &[(0.0f32, 1.0f32), (1.0, 0.37), (0.25, 16.0), (2.0, 1e-3)] {
                for &z in &zs {
                    for z in [z, z + zmin, z * 0.5 + zmin] {
                        assert_eq!(
                            bucket_at(zmin, scale, buckets, z),
                            bucket_index(zmin, scale, buckets, z),
                            "z {z} zmin {zmin} scale {scale} buckets {buckets}"
                        );
                    }
                }
            }
        }
    }

    /// [`any_bucket`] is the mask test by [`bucket_mask`].
    #[test]
    fn any_bucket_is_the_mask_test() {
        let masks = [
            0u32,
            1,
            0x8000_0000,
            u32::MAX,
            0x0001_0000,
            0x5555_5555,
            0xa0a0_0001,
            0x0000_0ff0,
        ];
        for buckets in [1u32, 2, 7, 16, 31, 32, 33, 48, 64, 100, 255] {
            for b0 in 0..buckets {
                for b1 in b0..buckets {
                    for &m in &masks {
                        assert_eq!(
                            any_bucket(m, b0, b1, buckets),
                            m & bucket_mask(b0, b1, buckets) != 0,
                            "mask {m:#x} buckets {b0}..={b1} of {buckets}"
                        );
                    }
                }
            }
        }
    }
}
