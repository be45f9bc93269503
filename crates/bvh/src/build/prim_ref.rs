//! The build's triangle reference ([`PrimRef`], 32 bytes: its box in two SSE vectors and its
//! triangle's id, as Embree's `PrimRef`) and the box in SSE lanes ([`BoxA`]) that the binners
//! accumulate.

use glam::{Vec3, Vec3A, Vec4};
use parallax_core::Aabb;

/// The `w` bits of [`PrimRef::lo`] are `id + ID_BIAS`: a normal float for every id below
/// 2^27 (exponent field 1..=16), so the centroid's `w` lane (`lo + hi`, `hi.w = 0`) never
/// computes with a denormal (which would cost a microcode assist per addition).
const ID_BIAS: u32 = 1 << 23;

/// A triangle reference, 32 bytes: its bounds as two 4-lane vectors (SSE min / max per
/// reference and bin, as Embree's `PrimRef`) with its index in the scene's mesh in the
/// fourth lane of `lo`.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(crate) struct PrimRef {
    pub(super) lo: Vec4,
    pub(super) hi: Vec4,
}

const _: () = assert!(std::mem::size_of::<PrimRef>() == 32);

impl PrimRef {
    pub fn new(min: Vec3, max: Vec3, id: u32) -> Self {
        debug_assert!((id as usize) < crate::node::MAX_TRIANGLES);
        Self {
            lo: min.extend(f32::from_bits(id + ID_BIAS)),
            hi: max.extend(0.0),
        }
    }

    /// The triangle's index in the mesh.
    #[inline(always)]
    pub fn id(&self) -> u32 {
        self.lo.w.to_bits() - ID_BIAS
    }

    #[inline(always)]
    pub(super) fn min(&self) -> Vec3A {
        Vec3A::from_vec4(self.lo)
    }

    #[inline(always)]
    pub(super) fn max(&self) -> Vec3A {
        Vec3A::from_vec4(self.hi)
    }

    /// The same triangle with the box `b` (a clipped piece, `spatial.rs`).
    #[inline(always)]
    pub(super) fn with_box(&self, b: BoxA) -> Self {
        Self {
            lo: b.min.extend(self.lo.w),
            hi: b.max.extend(0.0),
        }
    }

    /// The box's minimum and maximum on `axis` (0, 1 or 2) from memory, without a dynamic
    /// lane index.
    #[inline(always)]
    pub(super) fn axis_min_max(&self, axis: usize) -> (f32, f32) {
        // SAFETY: `PrimRef` is `repr(C)` of two `Vec4`, i.e. eight `f32` without padding.
        let a = unsafe { &*(self as *const PrimRef as *const [f32; 8]) };
        (a[axis & 3], a[4 + (axis & 3)])
    }

    /// Twice the box centre (the factor 2 cancels in binning). Lane `w` is a normal float.
    #[inline(always)]
    pub(super) fn centroid2(&self) -> Vec3A {
        self.min() + self.max()
    }
}

/// A box in 4-lane vectors (lane `w` ignored). Its `min` / `max` are glam's `a < b ? a : b`
/// and `a > b ? a : b` per lane, as `Vec3`'s, so the boxes equal those of `Aabb` bit for bit.
#[derive(Clone, Copy)]
pub(super) struct BoxA {
    pub(super) min: Vec3A,
    pub(super) max: Vec3A,
}

impl BoxA {
    pub(super) const EMPTY: BoxA = BoxA {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
    };

    #[inline(always)]
    pub(super) fn union(self, o: BoxA) -> BoxA {
        BoxA {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    #[inline(always)]
    pub(super) fn grow(self, p: Vec3A) -> BoxA {
        BoxA {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    #[inline(always)]
    pub(super) fn aabb(self) -> Aabb {
        Aabb {
            min: self.min.into(),
            max: self.max.into(),
        }
    }
}

/// A box as eight lanes: its minimum, then its maximum negated (Embree's layout), so that the
/// union of two boxes is one lane-wise minimum (one 8-lane `vminps` with AVX). `union` keeps
/// the operand order of [`BoxA::union`] (`minps` returns its second operand on equal values
/// and NaN, as `maxps` does, and negation only flips signs), so [`NegBox::boxa`] of a union
/// is bit for bit the union of the [`BoxA`]s.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub(super) struct NegBox(pub(super) [Vec4; 2]);

impl NegBox {
    pub(super) const EMPTY: NegBox = NegBox([Vec4::INFINITY, Vec4::INFINITY]);

    #[inline(always)]
    pub(super) fn of(r: &PrimRef) -> NegBox {
        NegBox([r.lo, -r.hi])
    }

    #[inline(always)]
    pub(super) fn union(self, o: NegBox) -> NegBox {
        NegBox([self.0[0].min(o.0[0]), self.0[1].min(o.0[1])])
    }

    #[inline(always)]
    pub(super) fn boxa(self) -> BoxA {
        BoxA {
            min: Vec3A::from_vec4(self.0[0]),
            max: Vec3A::from_vec4(-self.0[1]),
        }
    }

    /// [`Aabb::surface_area`] of [`NegBox::boxa`], bit for bit, from the lanes: the same
    /// emptiness test (`!(min <= max)` on some axis gives 0), the same extent (`max - min`,
    /// then `d > 0 ? d : 0`, which turns the NaN of an infinite side into 0) and the same sum
    /// of products in the same order.
    #[inline(always)]
    pub(super) fn area(self) -> f32 {
        let (lo, hi) = (self.0[0], -self.0[1]);
        if lo.cmple(hi).bitmask() & 7 != 7 {
            return 0.0;
        }
        let e = (hi - lo).max(Vec4::ZERO);
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }
}
