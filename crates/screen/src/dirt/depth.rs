//! Per-triangle depth ranges of a view, and the skip of a listed triangle whose range misses
//! the ray's depth span in the cell being traced (a finer form of Vardis et al. 2017, §4.2.1,
//! Alg. 1 line 9: the buckets the ray's depth span overlaps, here per list entry).
//!
//! A bucket lists every triangle whose depth range overlaps the bucket's, so a triangle in a
//! bucket the ray crosses can still lie wholly before or after the ray's depths in the cell
//! (a bucket is `1 / B` of the cell's depth range; a ray crossing a cell at a slant spans a
//! small part of it). Such a triangle's hit, if any, is at a depth the ray reaches in another
//! cell: there the triangle is listed too (the capture lists it in every cell its clipped part
//! overlaps, `walk` module docs) and the ray's depth span contains the hit's depth, so it is
//! tested there. Skipping it here is exact: it is not marked in the mailbox (`tri4`), so the
//! later cell tests it.
//!
//! **Rounding.** Both sides are widened so that the comparison never drops a triangle whose
//! hit lies in the span:
//! - a triangle's range ([`ranges`]) is `[min, max]` of its corners' view depths
//!   `-r_z · (p - eye)`, each off by at most a few ulps of `|p - eye|_1`; widened by
//!   `REL · max |p - eye|_1` over the corners (`REL = 2^-15`: 512 ulps);
//! - the ray's span in a cell ([`Span::new`]) is `[min, max]` of the walk's depths at the cell's
//!   entry and exit (`1 / w`, within a few ulps of the ray's depth there, `walk` module docs),
//!   widened by `REL` of each end and by the segment's own rounding bound
//!   `REL · (|o|_1 + t_end |d|_1)` (the view-space ray `o + t d`, `Segment::margin`).
//!
//! A NaN or infinite corner gives a range that compares false or spans everything: never
//! skipped. Views without ranges (empty: unit tests of the lists alone) skip nothing.

use glam::Vec3;
use parallax_raster::dirt::DirtTri;

use super::view::ViewConsts;

/// Relative widening of both sides (module docs).
pub(crate) const REL: f32 = 1.0 / 32768.0;

/// The bits of `2^-16`: depths at or below it have key 0.
const KEY_FLOOR: u32 = (127 - 16) << 23;
/// Low bits of a positive `f32`'s bits dropped by [`key`]: 11 mantissa bits kept.
const KEY_SHIFT: u32 = 12;

/// [`key`] of a span's or range's low end: 0 for NaN (where [`key`] gives the top key, for a
/// high end), so that a NaN end never makes anything miss.
#[inline(always)]
pub(crate) fn key_lo(z: f32) -> u32 {
    if z.is_nan() { 0 } else { key(z) }
}

/// A depth's `u16` key: `floor` of its `f32` bits above `2^-16`'s, in steps of `2^12` (11
/// mantissa bits: ~0.05 %), clamped to `u16` (depths past `2^16` share the top key); 0 for a
/// depth at or below `2^-16` and for `-inf`, the top key for `+inf` and NaN. Non-decreasing
/// in the depth (the bits of positive floats are), so keys of overlapping intervals overlap.
#[inline(always)]
pub(crate) fn key(z: f32) -> u32 {
    if z > 0.0 {
        (z.to_bits().saturating_sub(KEY_FLOOR) >> KEY_SHIFT).min(u16::MAX as u32)
    } else if z <= 0.0 {
        0
    } else {
        u16::MAX as u32
    }
}

/// The view depth range of each triangle, widened (module docs), as the [`key`]s of its ends
/// in one word (`lo | hi << 16`).
pub(crate) fn ranges(vc: &ViewConsts, tris: &[DirtTri]) -> Vec<u32> {
    tris.iter()
        .map(|t| {
            let [lo, hi] = range(vc, t);
            key_lo(lo) | key(hi) << 16
        })
        .collect()
}

/// Triangle `t`'s widened view depth range (module docs); everything for a NaN corner.
#[inline(always)]
fn range(vc: &ViewConsts, t: &DirtTri) -> [f32; 2] {
    let axis = vc.rows[2];
    let l1 = |q: Vec3| q.x.abs() + q.y.abs() + q.z.abs();
    let q = [t.p0 - vc.eye, t.p1 - vc.eye, t.p2 - vc.eye];
    let z = q.map(|q| -axis.dot(q));
    let m = REL * l1(q[0]).max(l1(q[1])).max(l1(q[2]));
    let lo = z[0].min(z[1]).min(z[2]);
    let hi = z[0].max(z[1]).max(z[2]);
    if lo.is_nan() || hi.is_nan() || m.is_nan() {
        [f32::NEG_INFINITY, f32::INFINITY]
    } else {
        [lo - m, hi + m]
    }
}

/// The ray's widened depth span in one cell and the view's triangle ranges.
#[derive(Clone, Copy)]
pub(crate) struct Span<'z> {
    ranges: &'z [u32],
    /// The [`key`]s of the span's ends.
    lo: u32,
    hi: u32,
}

impl<'z> Span<'z> {
    /// Skips nothing.
    #[cfg(test)]
    pub const ALL: Span<'static> = Span {
        ranges: &[],
        lo: 0,
        hi: u16::MAX as u32,
    };

    /// The span between the depths `a` and `b` (either order), widened by `REL` of each and
    /// by `margin` (module docs); everything when either is NaN.
    #[inline(always)]
    pub fn new(ranges: &'z [u32], a: f32, b: f32, margin: f32) -> Span<'z> {
        let (lo, hi) = if a <= b {
            (a, b)
        } else if b < a {
            (b, a)
        } else {
            (f32::NEG_INFINITY, f32::INFINITY)
        };
        Span {
            ranges,
            lo: key_lo(lo - (lo.abs() * REL + margin)),
            hi: key(hi + (hi.abs() * REL + margin)),
        }
    }

    /// Whether triangle `id`'s range misses the span (false for a NaN span or no ranges).
    #[inline(always)]
    pub fn misses(&self, id: u32) -> bool {
        match self.ranges.get(id as usize) {
            Some(&r) => r & 0xffff > self.hi || r >> 16 < self.lo,
            None => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every point of a triangle (corners and interior points, computed in f32) has a view
    /// depth strictly inside the triangle's widened range and a key inside its keys, on a
    /// random soup's views.
    #[test]
    fn ranges_hold_the_triangles_points() {
        use parallax_raster::dirt::{DirtViews, DirtViewsOptions};
        let mut rng = parallax_core::sampling::Rng::for_pixel(5, 6, 7, 8);
        let soup = super::super::test_soup::random_soup(&mut rng, 400);
        let opts = DirtViewsOptions {
            face_size: 16,
            ..DirtViewsOptions::default()
        };
        let views =
            DirtViews::build(&soup, None, glam::Vec3::new(0.1, 0.2, 0.3), &opts).expect("build");
        let tris = views.triangles.as_slice();
        let mut inside = 0u32;
        for cap in views.views() {
            let vc = ViewConsts::new(cap);
            let keys = ranges(&vc, tris);
            assert_eq!(keys.len(), tris.len());
            for (t, &k) in tris.iter().zip(&keys) {
                let r = range(&vc, t);
                let k = [k & 0xffff, k >> 16];
                assert!(r[0] < r[1] && k[0] <= k[1]);
                for c in 0..12 {
                    let (u, v) = match c {
                        0 => (0.0, 0.0),
                        1 => (1.0, 0.0),
                        2 => (0.0, 1.0),
                        _ => (rng.next_f32(), rng.next_f32()),
                    };
                    let (u, v) = if u + v > 1.0 {
                        (1.0 - u, 1.0 - v)
                    } else {
                        (u, v)
                    };
                    let p = t.p0 + (t.p1 - t.p0) * u + (t.p2 - t.p0) * v;
                    let z = vc.ray(p, Vec3::X).depth(0.0);
                    assert!(r[0] < z && z < r[1], "depth {z} outside {r:?}");
                    assert!(k[0] <= key(z) && key(z) <= k[1]);
                    inside += (z > 0.0) as u32;
                }
            }
        }
        assert!(
            inside > 1000,
            "too few points in front of the views: {inside}"
        );
    }

    /// [`key`] is non-decreasing over depths of every magnitude and sign, with its ends where
    /// the docs say.
    #[test]
    fn key_is_monotone() {
        let mut zs = vec![
            f32::NEG_INFINITY,
            -1e30,
            -1.0,
            -0.0,
            0.0,
            1e-45,
            1e-20,
            1.0 / 65536.0,
            1e-4,
            0.5,
            1.0,
            1.0001,
            3.0,
            1000.0,
            65536.0,
            1e6,
            1e30,
            f32::MAX,
            f32::INFINITY,
        ];
        let mut rng = parallax_core::sampling::Rng::for_pixel(9, 8, 7, 6);
        for _ in 0..2000 {
            zs.push(f32::from_bits(rng.next_u32() & 0x7fff_ffff).min(f32::INFINITY));
        }
        zs.retain(|z| !z.is_nan());
        zs.sort_by(f32::total_cmp);
        for w in zs.windows(2) {
            assert!(key(w[0]) <= key(w[1]), "{} {}", w[0], w[1]);
        }
        assert_eq!(key(1.0 / 65536.0), 0);
        assert!(key(1.0) < key(1.001) && key(1.001) < key(2.0));
        assert_eq!(key(f32::INFINITY), u16::MAX as u32);
        assert_eq!(key(f32::NAN), u16::MAX as u32);
        assert_eq!(key_lo(f32::NAN), 0);
        assert_eq!(key_lo(2.0), key(2.0));
    }

    /// [`Span::misses`]: disjoint ranges miss, touching and overlapping ones do not, and no
    /// ranges or a NaN end miss nothing.
    #[test]
    fn span_misses_only_disjoint_ranges() {
        let k = |a: f32, b: f32| key(a) | key(b) << 16;
        let ranges = [k(1.0, 2.0), k(3.0, 4.0), k(2.5, 2.6), k(0.0, f32::INFINITY)];
        let s = Span::new(&ranges, 2.9, 2.0, 0.0);
        assert_eq!(
            (0..4).map(|i| s.misses(i)).collect::<Vec<_>>(),
            [false, true, false, false]
        );
        let s = Span::new(&ranges, 4.5, 5.0, 0.0);
        assert!(s.misses(0) && s.misses(1) && s.misses(2) && !s.misses(3));
        assert!(!s.misses(7));
        let nan_or_inf = [
            (f32::NAN, 1.0),
            (1.0, f32::NAN),
            (f32::NAN, f32::NAN),
            (f32::INFINITY, f32::INFINITY),
        ];
        for (a, b) in nan_or_inf {
            let n = Span::new(&ranges, a, b, 0.0);
            assert!((0..4).all(|i| !n.misses(i)), "{a} {b}");
        }
        assert!((0..4).all(|i| !Span::ALL.misses(i)));
    }
}
