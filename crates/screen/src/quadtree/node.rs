//! The 64-bit quad-tree node (Widmer et al. 2015, §3.4, Fig. 3).
//!
//! Two 32-bit words `a`, `b`. The **sign bit of `a`** is the tag:
//!
//! - **AABB** (sign 0): `a` = `min z` (f32, clamped to `>= +0.0`), `b` = `max z` (f32). The
//!   box is the node's screen rectangle times `[min z, max z]` in the unit cube. An **empty**
//!   node (no geometry below it, also every padding node) is `(+inf, -inf)`: every box test,
//!   extruded or not, misses it.
//! - **Plane** (sign 1): `a` = `-(z_c)` where `z_c >= 0` is the plane's cube `z` at the
//!   centre of the node's footprint (the paper's `P_proxy`: "we only store the Z coordinate
//!   of P_origin, as its 2D coordinates are known from the node position"). The two lowest
//!   mantissa bits of `a` carry flags ([`FLAG_CRACK`] = the paper's `O`, [`FLAG_UNSAFE`] =
//!   the cascade flag of [`super::cascade`]), so `z_c` is rounded to a 21-bit mantissa
//!   (relative error `<= 2^-22`, about `2.4e-7`). `b` = `N.x` (f16, low half) and `N.y`
//!   (f16, high half) of the unit cube normal; `N.z = -sqrt(max(0, 1 - N.x² - N.y²))`
//!   (normals face the eye, `N.z <= 0`).
//!
//! We store `z_c` rather than the paper's `-(P·N)` offset because `z_c` is positive for every
//! point inside the cube (so the sign bit is free for the tag, as §3.4 requires) and it is
//! well conditioned, while `N·P` has no fixed sign. The decoded plane is
//! `N·P = c` with `c = N·(x_c, y_c, z_c)` evaluated in f32 by [`decode_plane`] — the *same*
//! function builds the brute-force twin of a tree ([`super::QuadTree::effective_planes`]).
//!
//! **Precision.** f16 normals have 11 significant bits: near a fronto-parallel normal
//! (`N.x, N.y` small) the absolute error is tiny, at grazing normals it is up to `2^-11`
//! and `N.z` (reconstructed) is ill-conditioned — a plane whose normal is nearly
//! perpendicular to the view direction is tilted by up to a few 1e-4 rad. Over a pixel
//! footprint (`1/W` in cube `x`) that moves the plane by ~1e-7 in `z`, the same order as
//! the `z_c` rounding. Consequence: hits on the quantised planes equal brute force over the
//! *decoded* planes (what the tests check), and differ from brute force over the original
//! f32 planes by those rounding amounts.

use glam::Vec3;
use half::f16;

/// Plane flag: the paper's `O`, "close to a depth discontinuity" (§3.2): the plane is
/// tested over a footprint dilated backwards along the ray ([`super::QuadTreeOptions::crack_dilation`]).
pub const FLAG_CRACK: u32 = 1;
/// Plane flag: a deeper layer's plane may come in front of this plane inside the footprint
/// (or this layer is empty where a deeper one is not); the whole footprint column then
/// counts as occlusion volume for cascading ([`super::cascade`]).
pub const FLAG_UNSAFE: u32 = 2;
const FLAG_MASK: u32 = 3;
const SIGN: u32 = 0x8000_0000;

/// One quad-tree node: 64 bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C, align(8))]
pub struct Node {
    pub a: u32,
    pub b: u32,
}

impl Node {
    /// The empty node: an AABB that no box test hits.
    pub const EMPTY: Node = Node {
        a: 0x7f80_0000, // +inf
        b: 0xff80_0000, // -inf
    };

    /// An AABB node `[zmin, zmax]` (`zmin` clamped to `+0.0`, NaN to 0: conservative, the
    /// ray never has `z < 0` inside the cube).
    #[inline]
    pub fn aabb(zmin: f32, zmax: f32) -> Node {
        let zmin = if zmin > 0.0 { zmin } else { 0.0 };
        let zmax = if zmax.is_nan() { 1.0 } else { zmax };
        Node {
            a: zmin.to_bits(),
            b: zmax.to_bits(),
        }
    }

    /// A plane node; `None` unless `z_c` is finite and `>= 0` and the normal components
    /// are finite.
    pub fn plane(zc: f32, nx: f32, ny: f32, flags: u32) -> Option<Node> {
        if !(zc.is_finite() && zc >= 0.0 && nx.is_finite() && ny.is_finite()) {
            return None;
        }
        // Round to a 21-bit mantissa (may carry into the exponent: still correct).
        let bits = (zc.to_bits() + 2) & !FLAG_MASK;
        let hx = f16::from_f32(nx).to_bits() as u32;
        let hy = f16::from_f32(ny).to_bits() as u32;
        Some(Node {
            a: SIGN | bits | (flags & FLAG_MASK),
            b: hx | (hy << 16),
        })
    }

    #[inline(always)]
    pub fn is_plane(self) -> bool {
        self.a & SIGN != 0
    }

    #[inline(always)]
    pub fn is_empty(self) -> bool {
        !self.is_plane() && f32::from_bits(self.a) > f32::from_bits(self.b)
    }

    /// `(zmin, zmax)` of an AABB node.
    #[inline(always)]
    pub fn zrange(self) -> (f32, f32) {
        (f32::from_bits(self.a), f32::from_bits(self.b))
    }

    /// Flags of a plane node.
    #[inline(always)]
    pub fn flags(self) -> u32 {
        self.a & FLAG_MASK
    }

    /// `z_c` of a plane node.
    #[inline(always)]
    pub fn zc(self) -> f32 {
        f32::from_bits(self.a & !(SIGN | FLAG_MASK))
    }

    /// Decoded unit-ish normal of a plane node (`N.z` reconstructed, `<= 0`).
    #[inline(always)]
    pub fn normal(self) -> Vec3 {
        let nx = f16_bits_to_f32(self.b as u16);
        let ny = f16_bits_to_f32((self.b >> 16) as u16);
        let nz = -(1.0 - nx * nx - ny * ny).max(0.0).sqrt();
        Vec3::new(nx, ny, nz)
    }

    /// Sets the plane flag / lowers an AABB's `zmin` to `tz` (see [`super::cascade`]).
    pub(crate) fn mark_unsafe(&mut self, tz: f32) {
        if self.is_plane() {
            self.a |= FLAG_UNSAFE;
        } else {
            let (lo, _) = self.zrange();
            let z = if tz < lo { tz.max(0.0) } else { lo };
            self.a = z.to_bits();
        }
    }
}

/// Exact f16 -> f32 conversion of a *finite* half (the stored normal components), branch-free
/// and inlinable. `half`'s `to_f32` dispatches at run time (F16C detection) to an
/// out-of-line function; in the traversal loop those two calls per plane test forced the
/// loop's f32 state to be spilled around them. Shifting the 15 magnitude bits into an f32's
/// exponent/mantissa field gives the value times `2^-112` (also for subnormal halves and
/// zero), and the multiplication by `2^112` is exact, so the result equals
/// `f16::to_f32` bit for bit (checked for all finite halves in the tests below).
#[inline(always)]
pub fn f16_bits_to_f32(h: u16) -> f32 {
    let h = h as u32;
    let mag = f32::from_bits((h & 0x7fff) << 13) * f32::from_bits(0x7780_0000); // 2^112
    f32::from_bits(mag.to_bits() | ((h & 0x8000) << 16))
}

/// Cube-space centre of node `(qx, qy)` at `level` of a `w x h` image.
#[inline(always)]
pub fn node_centre(level: u32, qx: u32, qy: u32, w: f32, h: f32) -> (f32, f32) {
    let size = (1u32 << level) as f32;
    (
        ((qx as f32 + 0.5) * size) / w,
        ((qy as f32 + 0.5) * size) / h,
    )
}

/// Decoded plane `(N, c)` with `N·P = c` of a plane node at `level`, `(qx, qy)`.
#[inline(always)]
pub fn decode_plane(node: Node, level: u32, qx: u32, qy: u32, w: f32, h: f32) -> (Vec3, f32) {
    let n = node.normal();
    let (xc, yc) = node_centre(level, qx, qy, w, h);
    (n, n.dot(Vec3::new(xc, yc, node.zc())))
}

/// Cube `z` of plane `(n, c)` at `(x, y)` (infinite or NaN for planes with `n.z == 0`).
#[inline(always)]
pub fn plane_z(n: Vec3, c: f32, x: f32, y: f32) -> f32 {
    (c - n.x * x - n.y * y) / n.z
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f16_decode_matches_half() {
        for h in 0..=u16::MAX {
            let r = f16::from_bits(h);
            if r.is_finite() {
                assert_eq!(f16_bits_to_f32(h).to_bits(), r.to_f32().to_bits(), "{h:#x}");
            }
        }
    }

    #[test]
    fn encode_decode() {
        let n = Node::plane(0.75, 0.1, -0.2, FLAG_CRACK).unwrap();
        assert!(n.is_plane() && !n.is_empty());
        assert!((n.zc() - 0.75).abs() < 1e-6);
        assert_eq!(n.flags(), FLAG_CRACK);
        let nn = n.normal();
        assert!((nn - Vec3::new(0.1, -0.2, -(1.0f32 - 0.05).sqrt())).length() < 1e-3);
        let mut m = n;
        m.mark_unsafe(0.5);
        assert_eq!(m.flags(), FLAG_CRACK | FLAG_UNSAFE);
        assert_eq!(m.zc(), n.zc());
        assert!(Node::EMPTY.is_empty() && !Node::EMPTY.is_plane());
        let b = Node::aabb(-0.5, 0.9);
        assert!(!b.is_plane() && b.zrange() == (0.0, 0.9));
        assert!(Node::plane(-0.1, 0.0, 0.0, 0).is_none());
        assert!(Node::plane(0.0, 0.0, 0.0, 0).unwrap().is_plane());
        assert_eq!(size_of::<Node>(), 8);
    }
}
