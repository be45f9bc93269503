//! Tests of `kernel.rs`.

use super::*;
use crate::cast::lanes16::V16;
use crate::test_streams::uniform;

/// A packet's base direction (near-axis components shrunk) and its lanes' spread.
fn packet_direction(f: &mut impl FnMut() -> f32) -> ([f32; 3], f32) {
    let base = [f() - 0.5, f() - 0.5, f() - 0.5].map(|c| if c.abs() < 0.05 { c * 1e-3 } else { c });
    (base, 10f32.powi(-(((f() * 5.0) as i32) + 1)))
}

/// The four-run interval test decides every run as the one-run test, on packets of nearby
/// directions (random signs, near-axis components) and boxes from tiny to huge, straddling
/// the origin's planes, with limits from 0 to infinity.
#[test]
fn interval_reaches4_equals_per_run() {
    let mut f = uniform(0x2545_f491_4f6c_dd1d);
    let (mut tested, mut reached) = (0, 0);
    for _ in 0..3000 {
        let (base, spread) = packet_direction(&mut f);
        let d = [0, 1, 2].map(|a| V16::from_fn(|_| base[a] + (f() - 0.5) * spread));
        let p = PacketSlab::<V16>::with_interval(d);
        if !p.has_interval() {
            continue;
        }
        let mut rb = RunBoxes16::default();
        let q = (f() * 4.0) as usize % 4;
        let mut segs = [None; 4];
        for (r, seg) in segs.iter_mut().enumerate() {
            let s = 10f32.powi((f() * 8.0) as i32 - 3);
            let c = [f() - 0.5, f() - 0.5, f() - 0.5].map(|v| v * 4.0 * s);
            let h = [f(), f(), f()].map(|v| v * s);
            let lo = Vec4::new(c[0] - h[0], c[1] - h[1], c[2] - h[2], 0.0);
            let hi = Vec4::new(c[0] + h[0], c[1] + h[1], c[2] + h[2], 0.0);
            for a in 0..3 {
                rb.lo[a][4 * q + r] = lo[a];
                rb.hi[a][4 * q + r] = hi[a];
            }
            *seg = Some(Segment {
                end: 0,
                near: 0.0,
                lo,
                hi,
            });
        }
        for lim in [f32::INFINITY, 0.0, f() * 10.0, f() * 1e4] {
            let bits = p.interval_reaches4(&rb, q, lim);
            for (r, seg) in segs.iter().enumerate() {
                let one = p.interval_reaches(seg.as_ref().unwrap(), lim);
                assert_eq!(bits >> r & 1 != 0, one, "{rb:?} {lim}");
                tested += 1;
                reached += one as u32;
            }
        }
    }
    assert!(
        reached > tested / 50 && reached < tested * 49 / 50,
        "{reached} {tested}"
    );
}

/// The sixteen-run interval test (`V16`, and `Z16` where AVX-512F is detected) decides
/// every run as the one-run test, and each half of it equals the eight-run test (`Y8`,
/// where AVX2 is detected), on the packets and boxes of the four-run test above,
/// including unused lanes past the last run (zero boxes, as in `TileTris::runs16`).
#[test]
fn interval_reaches16_equals_per_run() {
    let mut f = uniform(0x9e37_79b9_7f4a_7c15);
    let (mut tested, mut reached, mut halves) = (0, 0, 0);
    for _ in 0..1500 {
        let (base, spread) = packet_direction(&mut f);
        let dl: [[f32; 16]; 3] =
            [0, 1, 2].map(|a| std::array::from_fn(|_| base[a] + (f() - 0.5) * spread));
        let d = dl.map(|x| V16::from_fn(|l| x[l]));
        let p = PacketSlab::<V16>::with_interval(d);
        if !p.has_interval() {
            continue;
        }
        let used = 1 + (f() * 16.0) as usize % 16;
        let mut rb = RunBoxes16::default();
        let mut segs = [Segment {
            end: 0,
            near: 0.0,
            lo: Vec4::ZERO,
            hi: Vec4::ZERO,
        }; 16];
        for (r, seg) in segs.iter_mut().enumerate().take(used) {
            let s = 10f32.powi((f() * 8.0) as i32 - 3);
            let c = [f() - 0.5, f() - 0.5, f() - 0.5].map(|v| v * 4.0 * s);
            let h = [f(), f(), f()].map(|v| v * s);
            seg.lo = Vec4::new(c[0] - h[0], c[1] - h[1], c[2] - h[2], 0.0);
            seg.hi = Vec4::new(c[0] + h[0], c[1] + h[1], c[2] + h[2], 0.0);
            for a in 0..3 {
                rb.lo[a][r] = seg.lo[a];
                rb.hi[a][r] = seg.hi[a];
            }
        }
        for lim in [f32::INFINITY, 0.0, f() * 10.0, f() * 1e4] {
            let bits = p.interval_reaches16(&rb, lim);
            for (r, seg) in segs.iter().enumerate() {
                let one = p.interval_reaches(seg, lim);
                assert_eq!(bits >> r & 1 != 0, one, "{rb:?} {lim}");
                tested += 1;
                reached += one as u32;
            }
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx512f") {
                // SAFETY: AVX-512F was detected.
                assert_eq!(unsafe { z16_bits(dl, &rb, lim) }, bits);
            }
            #[cfg(target_arch = "x86_64")]
            if crate::cast::isa::avx2_detected() {
                for h in 0..2 {
                    // SAFETY: AVX2 was detected.
                    let b8 = unsafe { y8_bits(dl, &rb, h, lim) };
                    assert_eq!(b8, bits >> (8 * h) & 0xFF, "{rb:?} {lim} half {h}");
                    halves += 1;
                }
            }
        }
    }
    assert!(
        reached > tested / 50 && reached < tested * 49 / 50,
        "{reached} {tested}"
    );
    #[cfg(target_arch = "x86_64")]
    if crate::cast::isa::avx2_detected() {
        assert!(halves > 0);
    } else {
        eprintln!("AVX2 not detected: the eight-run test not compared");
    }
    let _ = halves;
}

/// [`PacketSlab::interval_reaches8`] with `Y8` lanes on the interval of the sixteen-lane
/// packet `dl` (`Y16`, as the AVX2 kernel runs it).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn y8_bits(dl: [[f32; 16]; 3], rb: &RunBoxes16, h: usize, lim: f32) -> u32 {
    use crate::cast::lanes256::{Y8, Y16};
    let d = [
        Y16::load16(&dl[0]),
        Y16::load16(&dl[1]),
        Y16::load16(&dl[2]),
    ];
    PacketSlab::<Y16>::with_interval(d).interval_reaches8::<Y8>(rb, h, lim)
}

/// [`PacketSlab::interval_reaches16`] with `Z16` lanes.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn z16_bits(dl: [[f32; 16]; 3], rb: &RunBoxes16, lim: f32) -> u32 {
    use crate::cast::lanes512::Z16;
    let d = [
        Z16::load16(&dl[0]),
        Z16::load16(&dl[1]),
        Z16::load16(&dl[2]),
    ];
    PacketSlab::<Z16>::with_interval(d).interval_reaches16(rb, lim)
}

/// [`edge_reach`] (the edges-first order of `edges.rs`) decides every lane as
/// [`edge_band`]: the inside mask and the band's bits from its two results, and no lane
/// inside or in the band where it reaches none; on random covectors, directions, bands
/// (zero, tiny, huge, infinite), edge subsets and candidate masks, with huge covectors
/// and directions whose products overflow (infinite and NaN edge values).
#[test]
fn edge_reach_equals_edge_band() {
    let mut f = uniform(0x5851_f42d_4c95_7f2d);
    let (mut skipped, mut inside_any, mut unsure_any, mut nan_lanes) = (0, 0, 0, 0);
    for i in 0..20_000 {
        let big = if i % 7 == 0 { 1e30 } else { 1.0 };
        let n = [0, 1, 2].map(|_| [f(), f(), f()].map(|c| (c - 0.5) * 2.0 * big));
        let bound = match i % 5 {
            0 => 0.0,
            1 => f32::INFINITY,
            2 => f() * 1e-6,
            _ => f() * 0.1,
        };
        let tr = TriSetup {
            n,
            g: [0.0; 3],
            tri: 0,
            src: 0,
            bound,
            rho: f32::NAN,
            all_in: false,
        };
        let scale = if i % 11 == 0 { 1e10 } else { 1.0 };
        let valid = if i % 3 == 0 {
            (f() * 65536.0) as u32 & 0xffff
        } else {
            0xffff
        };
        let base = [f() - 0.5, f() - 0.5, f() - 0.5];
        let d = [0, 1, 2].map(|a| {
            V16::from_fn(|l| {
                if valid >> l & 1 == 0 {
                    0.0
                } else {
                    (base[a] + (f() - 0.5) * 0.2) * scale
                }
            })
        });
        let dinf = (0..16).fold(0.0f32, |m, l| {
            m.max(
                d[0].get(l)
                    .abs()
                    .max(d[1].get(l).abs())
                    .max(d[2].get(l).abs()),
            )
        });
        let ge = V16::from_fn(|_| if f() < 0.8 { 1.0 } else { 0.0 }).gt(V16::splat(0.0));
        let cand = V16::bits(ge) & valid;
        let need = 1 + (f() * 7.0) as u32 % 7;
        let (inside, unsure) = edge_band(&tr, d, dinf, ge, cand, need);
        let (above, reach) = edge_reach(&tr, d, dinf, valid, need);
        let inn = V16::and(ge, above);
        assert_eq!(V16::bits(inn), V16::bits(inside), "{tr:?} {need}");
        assert_eq!(reach & cand & !V16::bits(inn), unsure, "{tr:?} {need}");
        if reach == 0 {
            assert_eq!((V16::bits(inside) & valid, unsure), (0, 0), "{tr:?}");
            skipped += 1;
        }
        inside_any += (V16::bits(inside) & valid != 0) as u32;
        unsure_any += (unsure != 0) as u32;
        let m = min_edge_of(&tr.n, d, need);
        nan_lanes += (0..16).filter(|&l| m.get(l).is_nan()).count();
    }
    assert!(
        skipped > 1000 && inside_any > 1000 && unsure_any > 100,
        "{skipped} {inside_any} {unsure_any}"
    );
    assert!(nan_lanes > 0, "no NaN edge value tested");
}

/// The branch-free edge subset equals the `match` form bit for bit, for every subset, on
/// finite, huge (overflowing), infinite and NaN edge values.
#[test]
fn min_edge_of_equals_the_match_form() {
    let mut f = uniform(0x2545_f491_4f6c_dd1d);
    let (mut nan, mut inf) = (0, 0);
    for i in 0..20_000 {
        let big = match i % 6 {
            0 => 1e30,
            1 => f32::INFINITY,
            _ => 1.0,
        };
        let mut n = [0, 1, 2].map(|_| [f(), f(), f()].map(|c| (c - 0.5) * 2.0 * big));
        if i % 13 == 0 {
            n[i / 13 % 3][i % 3] = f32::NAN;
        }
        let scale = if i % 11 == 0 { 1e10 } else { 1.0 };
        let d = [0, 1, 2].map(|_| V16::from_fn(|_| (f() - 0.5) * scale));
        for need in 1..8 {
            let a = min_edge_of(&n, d, need);
            let b = min_edge_of_match(&n, d, need);
            for l in 0..16 {
                assert_eq!(a.get(l).to_bits(), b.get(l).to_bits(), "{n:?} {need} {l}");
                nan += a.get(l).is_nan() as u32;
                inf += a.get(l).is_infinite() as u32;
            }
        }
    }
    assert!(nan > 100 && inf > 100, "{nan} {inf}");
}
