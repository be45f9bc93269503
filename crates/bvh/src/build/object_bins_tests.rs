//! Unit tests of `object_bins.rs`: the lane bin indices, the bins with the negated maximum.

use super::*;
use glam::Vec4;

#[test]
fn lane_bin_index_equals_the_scalar_clamp() {
    let mut s = 11u32;
    let mut rnd = || {
        s = s.wrapping_mul(747796405).wrapping_add(2891336453);
        s
    };
    let special = [
        0.0,
        -0.0,
        0.5,
        0.999_999_9,
        1.0,
        30.999_998,
        31.0,
        31.5,
        32.0,
        1e9,
        3e9,
        -0.5,
        -1.0,
        -3e9,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        f32::MIN_POSITIVE,
    ];
    for bins in [2usize, 5, 17, 32] {
        let binner = Binner {
            min: Vec3A::ZERO,
            scale: Vec3A::ONE,
            last: Vec3A::splat((bins - 1) as f32),
            bins,
        };
        let check = |f: Vec3A| {
            let b = binner.bin(f);
            for axis in 0..3 {
                assert_eq!(b[axis], binner.index(f[axis]), "{f:?} {bins}");
                assert_eq!(b[axis], binner.bin_axis(f, axis), "{f:?} {bins}");
            }
            let g = binner.last.min(f).max(Vec3A::ZERO);
            assert_eq!(trunc3(g)[..3], trunc3_portable(g)[..3], "{g:?}");
        };
        for &x in &special {
            for &y in &special {
                check(Vec3A::new(x, y, special[(rnd() % 18) as usize]));
            }
        }
        for _ in 0..100_000 {
            let f = f32::from_bits(rnd());
            let g = (rnd() % 4000) as f32 / 100.0 - 2.0;
            check(Vec3A::new(f, g, -g));
        }
    }
}

/// Uniform values in `[-half, half)` from a 32-bit LCG.
fn uniform(seed: u32, half: f32) -> impl FnMut() -> f32 {
    let mut s = seed;
    move || {
        s = s.wrapping_mul(747796405).wrapping_add(2891336453);
        (s >> 8) as f32 / (1 << 24) as f32 * 2.0 * half - half
    }
}

/// Coordinates on a quarter grid in `[-8, 8)`, and one in four a special value (signed
/// zeros, infinities, NaN), so that equal values, signed zeros and NaNs reach the unions.
fn coords(seed: u32) -> impl FnMut() -> f32 {
    let special = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
    ];
    let (mut rnd, mut pick) = (uniform(seed, 8.0), uniform(seed + 1, 1.0));
    move || {
        let u = pick();
        if u < -0.5 {
            special[((u + 1.0) * 14.0) as usize % special.len()]
        } else {
            (rnd() * 4.0).round() / 4.0
        }
    }
}

fn lanes(b: &NegBox) -> [[u32; 4]; 2] {
    b.0.map(|x| x.to_array().map(f32::to_bits))
}

/// [`NegBox::area`] is bit for bit [`Aabb::surface_area`] of [`NegBox::boxa`]: empty boxes,
/// sides of infinite length and NaN coordinates included.
#[test]
fn negated_max_area_equals_the_aabb_area() {
    let mut c = coords(3);
    let (mut empty, mut infinite, mut finite) = (0, 0, 0);
    for _ in 0..200_000 {
        let (a, b) = (Vec4::new(c(), c(), c(), c()), Vec4::new(c(), c(), c(), c()));
        // Mostly ordered boxes (min <= max), some not.
        let (lo, hi) = if c() < 6.0 {
            (a.min(b), a.max(b))
        } else {
            (a, b)
        };
        let nb = NegBox([lo, -hi]);
        let want = nb.boxa().aabb().surface_area();
        assert_eq!(nb.area().to_bits(), want.to_bits(), "{lo:?} {hi:?}");
        if want == 0.0 {
            empty += 1;
        } else if want.is_infinite() {
            infinite += 1;
        } else {
            finite += 1;
        }
    }
    assert!(empty > 0 && infinite > 0 && finite > 0);
}

/// References with special coordinates, bounded boxes (min <= max on every axis).
fn special_refs(seed: u32, n: u32) -> Vec<PrimRef> {
    let mut c = coords(seed);
    (0..n)
        .map(|id| {
            let a = Vec3::new(c(), c(), c());
            let b = Vec3::new(c(), c(), c());
            PrimRef::new(a.min(b), a.max(b), id)
        })
        .collect()
}

/// `bin_into` (AVX below `AVX_BIN_MAX` references, the portable loop from there on) gives
/// the portable loop's bins on both sides of the limit, over scratch left dirty by a
/// previous node.
#[test]
fn bin_into_equals_the_portable_loop_on_both_sides_of_the_avx_limit() {
    let all = special_refs(23, 3 * AVX_BIN_MAX as u32);
    for n in [AVX_BIN_MAX - 1, AVX_BIN_MAX, 3 * AVX_BIN_MAX] {
        let refs = &all[..n];
        for nb in [2usize, 9, 32] {
            let cb = Aabb::new(Vec3::splat(-16.0), Vec3::splat(16.0));
            let binner = Binner::new(&cb, nb);
            let mut want = new_bins();
            bin_into_portable(refs, &binner, &mut want);
            let mut got = new_bins();
            bin_into(&all[n / 2..], &Binner::new(&cb, 32), &mut got);
            bin_into(refs, &binner, &mut got);
            for a in 0..3 {
                for i in 0..nb {
                    assert_eq!(
                        lanes(&got.boxes[a][i]),
                        lanes(&want.boxes[a][i]),
                        "{n} {nb}"
                    );
                }
            }
            assert_eq!(got.counts[..nb], want.counts[..nb], "{n} {nb}");
            assert_eq!(
                want.counts[..nb].iter().map(|c| c[0]).sum::<u32>(),
                n as u32
            );
        }
    }
}

/// The bins of [`bin_into_avx`] and [`bin_into_portable`] are bit for bit equal, and their
/// [`NegBox::boxa`] is bit for bit the union of the references' [`BoxA`]s in reference order
/// (the binning before the negated maximum), with the same counts.
#[test]
#[allow(clippy::needless_range_loop)] // the loop indices address several arrays in step
fn negated_max_object_bins_equal_the_box_unions() {
    let refs = special_refs(21, 5000);
    for bins in [2usize, 9, 32] {
        let cb = Aabb::new(Vec3::splat(-16.0), Vec3::splat(16.0));
        let binner = Binner::new(&cb, bins);
        let mut portable = new_bins();
        bin_into_portable(&refs, &binner, &mut portable);
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx") {
            let mut avx = new_bins();
            // SAFETY: AVX checked.
            unsafe { bin_into_avx(&refs, &binner, &mut avx) };
            for a in 0..3 {
                for i in 0..MAX_BINS {
                    assert_eq!(lanes(&portable.boxes[a][i]), lanes(&avx.boxes[a][i]));
                }
            }
            assert_eq!(portable.counts, avx.counts);
        }
        let mut want = [[(BoxA::EMPTY, 0u32); MAX_BINS]; 3];
        for r in &refs {
            let b = binner.bin(r.centroid2());
            for a in 0..3 {
                let w = &mut want[a][b[a]];
                w.0 = w.0.union(BoxA {
                    min: r.min(),
                    max: r.max(),
                });
                w.1 += 1;
            }
        }
        let bits = |v: Vec3A| v.to_array().map(f32::to_bits);
        let mut special = 0;
        for a in 0..3 {
            for i in 0..bins {
                let (got, w) = (portable.boxes[a][i].boxa(), want[a][i].0);
                assert_eq!((bits(got.min), bits(got.max)), (bits(w.min), bits(w.max)));
                assert_eq!(portable.counts[i][a], want[a][i].1);
                let l = [got.min.to_array(), got.max.to_array()];
                special += l
                    .iter()
                    .flatten()
                    .filter(|x| !x.is_finite() || **x == 0.0)
                    .count();
            }
        }
        // The special values reached the bins.
        assert!(special > 0);
    }
}

/// [`sweep_avx`] returns the cost bits, axis and bin of [`sweep_portable`] on the bins of
/// random nodes (sizes 2 to 2000, quarter-grid coordinates so that equal costs occur, some
/// nodes flat on an axis, some on the diagonal so that all three axes tie), for the blocks
/// of 1, 2 and 4.
#[test]
fn lane_sweep_equals_the_scalar_sweep() {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx") {
        let mut rnd = uniform(31, 1.0);
        let (mut ties, mut splits, mut none) = (0, 0, 0);
        for node in 0..3000u32 {
            let n = 2 + ((rnd() + 1.0) * 0.5 * [8.0, 60.0, 2000.0][node as usize % 3]) as u32;
            let mut c = uniform(1000 + node, 8.0);
            let kind = node % 5;
            let refs: Vec<PrimRef> = (0..n)
                .map(|id| {
                    let q = |x: f32| (x * 2.0).round() / 2.0;
                    let p = match kind {
                        0 => Vec3::splat(q(c())),
                        1 => Vec3::new(q(c()), 1.0, q(c())),
                        _ => Vec3::new(q(c()), q(c()), q(c())),
                    };
                    let e = Vec3::new(q(c()).abs(), q(c()).abs(), q(c()).abs()) * 0.25;
                    PrimRef::new(p, p + e, id)
                })
                .collect();
            let (_, cb) = super::super::node_bounds(&refs);
            let nb = 32usize.min(4 + refs.len() / 20).max(2);
            let binner = Binner::new(&cb, nb);
            let mut bins = new_bins();
            bin_into_portable(&refs, &binner, &mut bins);
            let skip = [0, 1, 2].map(|a| binner.scale[a] == 0.0);
            for block in [1usize, 2, 4] {
                let want = sweep_portable(&bins, nb, refs.len(), skip, block);
                // SAFETY: AVX checked.
                let got = unsafe { sweep_avx(&bins, nb, refs.len(), skip, block) };
                assert_eq!(
                    (got.0.to_bits(), got.1, got.2),
                    (want.0.to_bits(), want.1, want.2)
                );
                if want.0.is_finite() {
                    splits += 1;
                } else {
                    none += 1;
                }
                // Another axis reaches the same least cost: the first axis must win.
                let per_axis = [0, 1, 2].map(|a| {
                    let mut s = [true; 3];
                    s[a] = skip[a];
                    s.iter_mut().enumerate().for_each(|(b, x)| *x |= b != a);
                    sweep_portable(&bins, nb, refs.len(), s, block).0
                });
                if want.0.is_finite() && per_axis.iter().filter(|&&x| x == want.0).count() > 1 {
                    ties += 1;
                }
            }
        }
        assert!(splits > 0 && ties > 0, "{splits} {ties} {none}");
    }
}

/// [`area3`]'s three lanes are bit for bit [`NegBox::area`] of its three boxes, on boxes with
/// special coordinates (empty, infinite sides, NaN).
#[test]
fn lane_areas_equal_the_negated_max_area() {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx") {
        use std::arch::x86_64::*;
        let mut c = coords(41);
        let mut boxes = || {
            let (a, b) = (Vec4::new(c(), c(), c(), c()), Vec4::new(c(), c(), c(), c()));
            let (lo, hi) = if c() < 6.0 {
                (a.min(b), a.max(b))
            } else {
                (a, b)
            };
            NegBox([lo, -hi])
        };
        let mut kinds = [0usize; 3];
        for _ in 0..100_000 {
            let b = [boxes(), boxes(), boxes()];
            // SAFETY: AVX checked; `NegBox` is 32 aligned bytes.
            let got: [f32; 4] = unsafe {
                let v = |x: &NegBox| _mm256_load_ps(x as *const NegBox as *const f32);
                std::mem::transmute(area3(v(&b[0]), v(&b[1]), v(&b[2])))
            };
            for a in 0..3 {
                let want = b[a].area();
                assert_eq!(got[a].to_bits(), want.to_bits(), "{:?}", b[a]);
                kinds[if want == 0.0 {
                    0
                } else if want.is_finite() {
                    1
                } else {
                    2
                }] += 1;
            }
        }
        assert!(kinds.iter().all(|&k| k > 0), "{kinds:?}");
    }
}

/// [`Binner::left_of`] is `bin_axis(centroid, axis) < split` for every split, on centroids at
/// special values and exactly on the split planes (it fails if `>=` becomes `>`).
#[test]
fn side_by_compare_equals_the_bin_index() {
    let special = [
        0.0,
        -0.0,
        0.5,
        1.0,
        1.5,
        2.0,
        2.999_999_8,
        3.0,
        16.0,
        31.0,
        31.5,
        32.0,
        1e9,
        -0.5,
        -1.0,
        -1e9,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        f32::MIN_POSITIVE,
    ];
    let mut rnd = uniform(51, 40.0);
    let mut on_plane = 0;
    for bins in [2usize, 5, 17, 32] {
        for scale in [Vec3A::ONE, Vec3A::new(0.5, 2.0, 0.0)] {
            let binner = Binner {
                min: Vec3A::ZERO,
                scale,
                last: Vec3A::splat((bins - 1) as f32),
                bins,
            };
            let mut values: Vec<f32> = special.to_vec();
            values.extend((0..200).map(|_| rnd()));
            values.extend((0..bins).map(|i| i as f32 / 0.5));
            for &v in &values {
                // Centroid `v + 0` on x, y, z (the reference's `hi` is 0).
                let r = PrimRef::new(Vec3::splat(v), Vec3::ZERO, 7);
                for axis in 0..3 {
                    for split in 1..bins {
                        let want = binner.bin_axis(r.centroid2(), axis) < split;
                        assert_eq!(binner.left_of(axis, split)(&r), want, "{v} {axis} {split}");
                        let f = (r.centroid2()[axis] - binner.min[axis]) * binner.scale[axis];
                        on_plane += (f == split as f32) as usize;
                    }
                }
            }
        }
    }
    assert!(on_plane > 0);
}
