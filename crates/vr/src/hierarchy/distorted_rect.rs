//! The lens-distorted eye's rectangles (`pose.rs`, "the lens-distorted eye"; Hunt et al. 2018,
//! §5.1: the tile bounds computed once from the lens parameters) sixteen subsample rays at a
//! time. The radial gain is not monotone in the film position, so a tile's rectangle is the
//! extremes of every ray's camera-space `(x, y)`: 20.7 M rays per eye at 1080x1200 and 16 spp.
//!
//! **Same values as the scalar definition** (`pose::distorted_rect_scalar`, one
//! `Distorted::camera_vector` per ray). Each lane does `camera_vector`'s f32 operations on the
//! same operands in its order: the film position `film + offset * footprint`, then the
//! caster's own `cast::packet::distorted_xy` (the lens coordinates, `s = n_x^2 + n_y^2`, the
//! gain `1 + s (k1 + k2 s)` of the sample's colour channel, `(n g) tan_half_y`). IEEE operations round per lane whatever the width, nothing is fused, so every
//! lane's `(x, y)` is the scalar's, and the extremes of the same values are the same values
//! (`pose.rs` makes the rectangle, with a zero bound as `+0`: the sign of a zero extreme
//! depends on the order of the compares). Rays of channels past 2 are never cast and take no
//! part; a non-finite vector makes the rectangle unbounded, as in the scalar form. Test:
//! `pose.rs`, `lanes_equal_the_scalar_definition`.
//!
//! | parameter | value |
//! |---|---|
//! | rays per step | 16 (`(sample, subsample)` pairs in the tile's order) |
//! | target features | the caster's AVX-512 tier where detected, else the portable `V16` |

use parallax_core::simd::Lanes;
use parallax_scene::camera::Distorted;

use crate::SampleSet;
use crate::cast::lanes16::V16;
use crate::cast::packet::distorted_xy;

/// The extremes `([x0, x1], [y0, y1])` of the camera-space vectors of every subsample ray of
/// the samples `idx` (module docs; `x0 > x1` when there is no valid ray); `None` if one is not
/// finite (the rectangle is then unbounded).
pub(super) type Extremes = Option<([f32; 2], [f32; 2])>;

/// [`Extremes`] of the samples `idx` (module docs), in the widest lanes this CPU has.
pub(super) fn distorted_extremes(set: &SampleSet, c: &Distorted, idx: &[u32]) -> Extremes {
    #[cfg(target_arch = "x86_64")]
    if crate::cast::isa::avx512_detected() {
        // SAFETY: the AVX-512 tier detected.
        return unsafe { extremes_avx512(set, c, idx) };
    }
    extremes_lanes::<V16>(set, c, idx)
}

/// [`distorted_extremes`] in AVX-512 lanes.
///
/// # Safety
/// The CPU must have the AVX-512 tier (`crate::cast::isa::avx512_detected`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512bw,avx512dq,avx2,bmi1,bmi2,lzcnt,popcnt")]
unsafe fn extremes_avx512(set: &SampleSet, c: &Distorted, idx: &[u32]) -> Extremes {
    extremes_lanes::<crate::cast::lanes512::Z16>(set, c, idx)
}

/// [`distorted_extremes`] with the lanes `L` (sixteen of them).
#[inline(always)]
pub(super) fn extremes_lanes<L: Lanes>(set: &SampleSet, c: &Distorted, idx: &[u32]) -> Extremes {
    debug_assert_eq!(L::N, 16);
    let zero = L::splat(0.0);
    let (inf, ninf) = (L::splat(f32::INFINITY), L::splat(f32::NEG_INFINITY));
    let (mut lo_x, mut lo_y, mut hi_x, mut hi_y) = (inf, inf, ninf, ninf);
    let spp = set.offsets.len();
    let total = idx.len() * spp;
    // The step's operands, lane by lane (lanes without a valid ray keep stale values: masked).
    let (mut fx, mut fy, mut k1, mut k2) = ([0f32; 16], [0f32; 16], [0f32; 16], [0f32; 16]);
    let mut j = 0;
    while j < total {
        let n = (total - j).min(16);
        let mut valid = 0u32;
        for l in 0..n {
            let (i, k) = (idx[(j + l) / spp], (j + l) % spp);
            let s = &set.samples[i as usize];
            let Some(&[a, b]) = c.coeffs.get(s.channel as usize) else {
                continue;
            };
            let f = s.film + set.offsets[k] * s.footprint;
            (fx[l], fy[l], k1[l], k2[l]) = (f.x, f.y, a, b);
            valid |= 1 << l;
        }
        j += n;
        if valid == 0 {
            continue;
        }
        let (x, y) = (L::from_fn(|l| fx[l]), L::from_fn(|l| fy[l]));
        let (a, b) = (L::from_fn(|l| k1[l]), L::from_fn(|l| k2[l]));
        let (vx, vy) = distorted_xy(c, x, y, a, b);
        // Finite: ordered compares against both infinities (false on NaN).
        let finite = L::and(
            L::and(vx.lt(inf), vx.gt(ninf)),
            L::and(vy.lt(inf), vy.gt(ninf)),
        );
        if valid & !L::bits(finite) != 0 {
            return None;
        }
        let m = L::from_fn(|l| (valid >> l & 1) as f32).gt(zero);
        lo_x = L::select(m, vx, inf).min_or_rhs(lo_x);
        lo_y = L::select(m, vy, inf).min_or_rhs(lo_y);
        hi_x = L::select(m, vx, ninf).max_or_rhs(hi_x);
        hi_y = L::select(m, vy, ninf).max_or_rhs(hi_y);
    }
    // The lanes' extremes (once per tile; a loop, not a closure: see `cast/packet.rs`).
    let (mut x0, mut y0, mut x1, mut y1) = (lo_x.get(0), lo_y.get(0), hi_x.get(0), hi_y.get(0));
    for l in 1..16 {
        (x0, y0) = (x0.min(lo_x.get(l)), y0.min(lo_y.get(l)));
        (x1, y1) = (x1.max(hi_x.get(l)), y1.max(hi_y.get(l)));
    }
    Some(([x0, x1], [y0, y1]))
}
