//! Tests of `affine.rs`.

use super::*;

/// A xorshift stream of floats in (-2, 2) with NaN, infinities and 1e38 mixed in (one in 16).
fn values(seed: u64) -> impl FnMut() -> f32 {
    let mut x = seed;
    move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let u = (x >> 40) as f32 / (1u64 << 24) as f32;
        match x & 63 {
            0 => f32::NAN,
            1 => f32::INFINITY,
            2 => -f32::INFINITY,
            3 => 1e38,
            _ => (u - 0.5) * 4.0,
        }
    }
}

/// An affine form of random lanes from `v` (its magnitudes `amx`, `amy`, `n1` made `>= 0`).
fn random_affine(v: &mut impl FnMut() -> Vec4) -> AffineTri {
    AffineTri {
        mx: v(),
        my: v(),
        mz: v(),
        amx: v().abs(),
        amy: v().abs(),
        n1: v().abs(),
    }
}

/// The branch-free word equals [`PacketBox::classify_edges`] on random boxes and affine
/// forms, with huge, infinite and NaN values.
#[test]
fn classify_bits_equals_classify_edges() {
    let mut f = values(0x9e37_79b9_7f4a_7c15);
    let mut seen = [0u32; 4];
    for _ in 0..200_000 {
        let kb = f().abs() * 0.01;
        let bound = f().abs() * 0.01;
        let mut v = || Vec4::new(f(), f(), f(), f());
        let pb = PacketBox {
            xc: v(),
            yc: v(),
            rx: v().abs(),
            ry: v().abs(),
            ka: v().abs() * 0.01,
            kb,
        };
        let a = random_affine(&mut v);
        let (class, skip) = pb.classify_edges(&a, bound);
        let word = match class {
            PacketClass::Out => CLASS_OUT,
            PacketClass::In => CLASS_IN,
            PacketClass::Partial => skip,
        };
        assert_eq!(pb.classify_bits(&a, bound), word, "{pb:?} {a:?} {bound}");
        let k = match class {
            PacketClass::Out => 0,
            PacketClass::In => 1,
            PacketClass::Partial if skip != 0 => 2,
            PacketClass::Partial => 3,
        };
        seen[k] += 1;
    }
    assert!(seen.iter().all(|&c| c > 500), "{seen:?}");
}

/// [`BoxLanes::classify`] gives every lane's packet the class word of
/// [`PacketBox::classify_bits`] on its own box, on random boxes and forms with NaN,
/// infinite and huge values (the portable sixteen lanes, and AVX-512 where detected).
#[test]
fn box_lanes_classify_equals_classify_bits() {
    use crate::cast::lanes16::V16;
    use parallax_core::simd::Lanes;
    let mut f = values(0x2545_f491_4f6c_dd1d);
    let mut seen = [0u32; 4];
    for _ in 0..20_000 {
        let bound = f().abs() * 0.01;
        let mut v = || Vec4::new(f(), f(), f(), f());
        let a = random_affine(&mut v);
        let boxes: [[f32; 6]; 16] = std::array::from_fn(|_| {
            [
                f(),
                f(),
                f().abs(),
                f().abs(),
                f().abs() * 0.01,
                f().abs() * 0.01,
            ]
        });
        let lane = |k: usize| V16::from_fn(|l| boxes[l][k]);
        let bl = BoxLanes {
            xc: lane(0),
            yc: lane(1),
            rx: lane(2),
            ry: lane(3),
            ka: lane(4),
            kb: lane(5),
        };
        let c = bl.classify(&a, bound);
        #[cfg(target_arch = "x86_64")]
        if crate::cast::isa::avx512_detected() {
            // SAFETY: AVX-512F detected.
            assert_eq!(unsafe { z16_classes(&boxes, &a, bound) }, c);
        }
        for (k, b) in boxes.iter().enumerate() {
            let pb = PacketBox {
                xc: Vec4::splat(b[0]),
                yc: Vec4::splat(b[1]),
                rx: Vec4::splat(b[2]),
                ry: Vec4::splat(b[3]),
                ka: Vec4::splat(b[4]),
                kb: b[5],
            };
            assert_eq!(pb.scalars().map(f32::to_bits), b.map(f32::to_bits));
            let word = pb.classify_bits(&a, bound);
            assert_eq!(c.code(k as u32, a.small()), word, "{pb:?} {a:?} {bound}");
            seen[match word {
                CLASS_OUT => 0,
                CLASS_IN => 1,
                0 => 2,
                _ => 3,
            }] += 1;
        }
    }
    assert!(seen.iter().all(|&c| c > 500), "{seen:?}");
}

/// [`BoxLanes::classify`] with [`crate::cast::lanes512::Z16`] lanes.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn z16_classes(boxes: &[[f32; 6]; 16], a: &AffineTri, bound: f32) -> LaneClasses {
    use crate::cast::lanes16::LaneReduce;
    use crate::cast::lanes512::Z16;
    let lane = |k: usize| Z16::load16(&std::array::from_fn(|l| boxes[l][k]));
    BoxLanes {
        xc: lane(0),
        yc: lane(1),
        rx: lane(2),
        ry: lane(3),
        ka: lane(4),
        kb: lane(5),
    }
    .classify(a, bound)
}
