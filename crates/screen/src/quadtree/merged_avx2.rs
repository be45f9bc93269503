//! The cascade trigger depths ([`super::cascade`], `pixel_trigger`) of eight pixels of a
//! row against merged nodes' planes, one pixel per AVX2 lane (run-time detection): the fast
//! path of `fixpoint::merged_triggers` (Widmer et al. 2015, §3.3: a pixel under a merged
//! node is tested against the node's plane), `trigger_lanes::merged_triggers4` /
//! `merged_pair_triggers4` with eight lanes. The eight pixels are one run of eight of a
//! node of level >= 3, two runs of four of two level-2 nodes, or four runs of two of four
//! level-1 nodes (`N` = 1, 2, 4 planes, `8 / N` consecutive lanes each).
//!
//! Every lane does `trigger_lanes::triggers4`'s operations in its order (its module docs
//! list them): per deeper layer in order the covered and edge-on lanes (`front = 0` and
//! unsafe), per footprint corner `(x0, y0), (x1, y0), (x0, y1), (x1, y1)` the deeper plane's
//! `z = ((c_j - n_j.x x) - n_j.y y) / n_j.z`, the running minimum by the same
//! compare-select, the own plane's `f = ((n.x x + n.y y) + n.z z) - c` against
//! `-SAFE_MARGIN`; the trigger depth `max(front - margin, +0)` of unsafe lanes, `+inf`
//! elsewhere. IEEE products, sums, differences and divisions are correctly rounded per lane
//! and nothing is fused (no FMA is enabled), so the trigger depths are the same bits; the
//! products two corners share are computed once (the same operations on the same
//! operands). The test below compares the kernel with the four-lane kernels.

use core::arch::x86_64::*;

use glam::Vec3;

use super::cascade::SAFE_MARGIN;
use super::trigger_avx2::soa8;
use crate::LayerPlanes;

/// Whether this CPU runs [`merged_triggers8`] (AVX2).
pub(super) fn available() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
}

/// The trigger depths of the pixels `k .. k + 8` (one row, columns `i .. i + 8`) against
/// the planes `(n, c)` of `planes` (plane `p` in lanes `p 8 / N .. (p + 1) 8 / N`), from
/// the footprint edges `xe[i .. i + 9]` (`x / W`) and the row's edges `y0`, `y1` (module
/// docs), into `out[..8]`; returns the lanes with a finite trigger depth as bits.
///
/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn merged_triggers8<const N: usize>(
    k: usize,
    planes: [(Vec3, f32); N],
    xe: &[f32],
    (y0, y1): (f32, f32),
    deeper: &[LayerPlanes],
    out: &mut [f32],
) -> u32 {
    const { assert!(N == 1 || N == 2 || N == 4) };
    let (xe, out) = (&xe[..9], &mut out[..8]);
    let s = _mm256_set1_ps;
    let (pnx, pny, pnz, pc) = if N == 1 {
        let (n, c) = planes[0];
        (s(n.x), s(n.y), s(n.z), s(c))
    } else {
        let mut v = [[0.0f32; 8]; 4];
        for d in 0..8 {
            let (n, c) = planes[d * N / 8];
            (v[0][d], v[1][d], v[2][d], v[3][d]) = (n.x, n.y, n.z, c);
        }
        // SAFETY: eight floats each.
        unsafe {
            (
                _mm256_loadu_ps(v[0].as_ptr()),
                _mm256_loadu_ps(v[1].as_ptr()),
                _mm256_loadu_ps(v[2].as_ptr()),
                _mm256_loadu_ps(v[3].as_ptr()),
            )
        }
    };
    // SAFETY: `xe` holds nine floats.
    let (x0, x1) = unsafe {
        (
            _mm256_loadu_ps(xe.as_ptr()),
            _mm256_loadu_ps(xe.as_ptr().add(1)),
        )
    };
    let (sy0, sy1) = (s(y0), s(y1));
    let margin = s(-SAFE_MARGIN);
    // The own plane's `n.x x + n.y y` per corner, once for all deeper layers.
    let (px0, px1) = (_mm256_mul_ps(pnx, x0), _mm256_mul_ps(pnx, x1));
    let (py0, py1) = (_mm256_mul_ps(pny, sy0), _mm256_mul_ps(pny, sy1));
    let q = [
        _mm256_add_ps(px0, py0),
        _mm256_add_ps(px1, py0),
        _mm256_add_ps(px0, py1),
        _mm256_add_ps(px1, py1),
    ];
    let mut front = s(f32::INFINITY);
    let mut bad = _mm256_setzero_ps();
    for pj in deeper {
        let (normal, offset) = (&pj.normal[k..k + 8], &pj.offset[k..k + 8]);
        // SAFETY: eight `Vec3`s and eight floats (sliced above).
        let ((nx, ny, nz), cj) =
            unsafe { (soa8(normal.as_ptr()), _mm256_loadu_ps(offset.as_ptr())) };
        let z0 = _mm256_setzero_ps();
        let covered = _mm256_or_ps(
            _mm256_or_ps(
                _mm256_cmp_ps::<_CMP_NEQ_UQ>(nx, z0),
                _mm256_cmp_ps::<_CMP_NEQ_UQ>(ny, z0),
            ),
            _mm256_cmp_ps::<_CMP_NEQ_UQ>(nz, z0),
        );
        // `!(nj.z < -1e-6)`: unsafe, `front = 0`.
        let edge = _mm256_andnot_ps(_mm256_cmp_ps::<_CMP_LT_OS>(nz, s(-1e-6)), covered);
        bad = _mm256_or_ps(bad, edge);
        front = _mm256_blendv_ps(front, z0, edge);
        let live = _mm256_andnot_ps(edge, covered);
        if _mm256_movemask_ps(live) == 0 {
            continue;
        }
        let (c0, c1) = (
            _mm256_sub_ps(cj, _mm256_mul_ps(nx, x0)),
            _mm256_sub_ps(cj, _mm256_mul_ps(nx, x1)),
        );
        let (ny0, ny1) = (_mm256_mul_ps(ny, sy0), _mm256_mul_ps(ny, sy1));
        let z = [
            _mm256_div_ps(_mm256_sub_ps(c0, ny0), nz),
            _mm256_div_ps(_mm256_sub_ps(c1, ny0), nz),
            _mm256_div_ps(_mm256_sub_ps(c0, ny1), nz),
            _mm256_div_ps(_mm256_sub_ps(c1, ny1), nz),
        ];
        // A live lane is bad where `f <= -margin` fails at some corner (NaN included).
        let mut unsafe_any = _mm256_setzero_ps();
        for c in 0..4 {
            let lower = _mm256_and_ps(live, _mm256_cmp_ps::<_CMP_LT_OS>(z[c], front));
            front = _mm256_blendv_ps(front, z[c], lower);
            let f = _mm256_sub_ps(_mm256_add_ps(q[c], _mm256_mul_ps(pnz, z[c])), pc);
            unsafe_any = _mm256_or_ps(unsafe_any, _mm256_cmp_ps::<_CMP_NLE_UQ>(f, margin));
        }
        bad = _mm256_or_ps(bad, _mm256_and_ps(live, unsafe_any));
    }
    let t = _mm256_sub_ps(front, s(SAFE_MARGIN));
    let t = _mm256_and_ps(_mm256_cmp_ps::<_CMP_GT_OS>(t, _mm256_setzero_ps()), t);
    let t = _mm256_blendv_ps(s(f32::INFINITY), t, bad);
    // SAFETY: `out` holds eight floats.
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), t) };
    // The finite ones: `|t| < inf`.
    _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(
        _mm256_andnot_ps(s(-0.0), t),
        s(f32::INFINITY),
    )) as u32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadtree::test_rng::Rng;
    use crate::quadtree::trigger_lanes::{merged_pair_triggers4, merged_triggers4};

    /// A random plane `(n, c)` through a point near depth `zc` at `(x, y)`.
    fn plane(rng: &mut Rng, (x, y): (f32, f32)) -> (Vec3, f32) {
        let n = match rng.next() % 8 {
            // Steep planes (large slopes) and an edge-on one.
            0 => Vec3::new(rng.f(-40.0, 40.0), rng.f(-40.0, 40.0), -1.0),
            1 => Vec3::new(1.0, 0.0, 0.0),
            _ => Vec3::new(rng.f(-2.0, 2.0), rng.f(-2.0, 2.0), -1.0),
        };
        let zc = rng.f(-1.0, 0.0);
        (n, n.dot(Vec3::new(x, y, zc)))
    }

    /// The eight-lane kernel equals the four-lane kernels bit for bit, for one, two and
    /// four planes: random planes over one to three deeper layers with covered, uncovered
    /// and edge-on pixels, NaN normals and planes in front of and behind the merged ones.
    #[test]
    fn lanes_equal_the_four_lane_kernels() {
        if !available() {
            eprintln!("no AVX2: nothing to compare");
            return;
        }
        let mut rng = Rng(0x5eed_0f_8a4e_1234);
        let (wf, hf) = (1600.0f32, 900.0f32);
        let w = 64usize;
        let (mut finite, mut total) = (0usize, 0usize);
        for case in 0..600u32 {
            let j = case % 5;
            let rows = 5usize;
            let deeper: Vec<LayerPlanes> = (0..1 + case % 3)
                .map(|_| {
                    let n = w * rows;
                    let normal: Vec<Vec3> = (0..n)
                        .map(|_| match rng.next() % 10 {
                            0 => Vec3::ZERO,
                            1 => Vec3::new(1.0, 0.0, 0.0),
                            2 => Vec3::new(0.6, 0.8, -1e-7),
                            3 => Vec3::new(f32::NAN, 0.0, -1.0),
                            _ => Vec3::new(rng.f(-0.5, 0.5), rng.f(-0.5, 0.5), -1.0).normalize(),
                        })
                        .collect();
                    let offset = (0..n).map(|_| rng.f(-1.2, 0.2)).collect();
                    LayerPlanes {
                        width: w as u32,
                        height: rows as u32,
                        normal,
                        offset,
                        flag: vec![false; n],
                    }
                })
                .collect();
            let xe: Vec<f32> = (0..=w).map(|i| i as f32 / wf).collect();
            let y = ((j as f32) / hf, ((j + 1) as f32) / hf);
            let i = 8 * (rng.next() as usize % (w / 8));
            let k = j as usize * w + i;
            let at = (xe[i], y.0);
            let p: [(Vec3, f32); 4] = core::array::from_fn(|_| plane(&mut rng, at));
            let mut got = [0.0f32; 8];
            let want: [f32; 8];
            let bits;
            // SAFETY: AVX2 (checked above).
            unsafe {
                match case % 3 {
                    0 => {
                        bits = merged_triggers8(k, [p[0]], &xe[i..], y, &deeper, &mut got);
                        let a = merged_triggers4(k, p[0], &xe[i..], y, &deeper).to_array();
                        let b = merged_triggers4(k + 4, p[0], &xe[i + 4..], y, &deeper);
                        want = core::array::from_fn(|d| if d < 4 { a[d] } else { b[d - 4] });
                    }
                    1 => {
                        bits = merged_triggers8(k, [p[0], p[1]], &xe[i..], y, &deeper, &mut got);
                        let a = merged_triggers4(k, p[0], &xe[i..], y, &deeper).to_array();
                        let b = merged_triggers4(k + 4, p[1], &xe[i + 4..], y, &deeper);
                        want = core::array::from_fn(|d| if d < 4 { a[d] } else { b[d - 4] });
                    }
                    _ => {
                        bits = merged_triggers8(k, p, &xe[i..], y, &deeper, &mut got);
                        let a = merged_pair_triggers4(k, p[0], p[1], &xe[i..], y, &deeper);
                        let b = merged_pair_triggers4(k + 4, p[2], p[3], &xe[i + 4..], y, &deeper);
                        let a = a.to_array();
                        want = core::array::from_fn(|d| if d < 4 { a[d] } else { b[d - 4] });
                    }
                }
            }
            for d in 0..8 {
                assert_eq!(got[d].to_bits(), want[d].to_bits(), "case {case} lane {d}");
                assert_eq!(
                    bits >> d & 1 == 1,
                    want[d].is_finite(),
                    "case {case} lane {d}"
                );
                finite += want[d].is_finite() as usize;
            }
            total += 8;
        }
        assert!(
            finite > total / 10 && finite < total * 9 / 10,
            "{finite} of {total} finite"
        );
    }
}
