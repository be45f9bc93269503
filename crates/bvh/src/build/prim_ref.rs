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
