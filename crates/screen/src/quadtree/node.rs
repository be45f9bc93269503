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
//!   (relative error `<= 2^-22`, about `2.4e-7`). `b` = two f16: the plane's **z increments
//!   across the node's footprint**, `dz_x = g_x 2^l / W` (low half) and `dz_y = g_y 2^l / H`
//!   (high half), where `g = (dz/dx, dz/dy) = -(N.x, N.y) / N.z` is the cube-space gradient
//!   of the plane (`z = z_c + g·((x, y) - centre)`), clamped to `±65504` (the f16 maximum).
//!
//! We store `z_c` rather than the paper's `-(P·N)` offset because `z_c` is positive for every
//! point inside the cube (so the sign bit is free for the tag, as §3.4 requires) and it is
//! well conditioned, while `N·P` has no fixed sign. The decoded plane is
//! `N·P = c` with `N = (g_x, g_y, -1)` scaled by a power of two to near unit length
//! ([`Node::test_normal`]: no square root) and `c = N·(x_c, y_c, z_c)`, evaluated in f32 by
//! [`decode_plane`] — the *same* function builds the brute-force twin of a tree
//! ([`super::QuadTree::effective_planes`]).
//!
//! **Why slopes, not the paper's `N.x, N.y`** (Fig. 3 stores `N.x`, `N.y` as f16 and
//! implies `N.z`; the format — an f32 word with the sign tag plus two f16 — is unchanged).
//! Reconstructing `N.z = -sqrt(1 - N.x² - N.y²)` is ill-conditioned exactly where it
//! matters: a surface seen nearly edge-on has a cube normal nearly perpendicular to `z`
//! (`|N.z|` small), `dN.z = (N.x dN.x + N.y dN.y) / N.z`, and f16 rounds `N.x` near 1 to a
//! step of `2^-11`. On atrium at 800x450 the exact normal `(0.99999, 0.00056, -0.0041)`
//! decoded to `(1, 0.00056, 0)`: a plane vertical in the cube, i.e. a wall through the whole
//! cube depth in front of its pixel's real surface. In the camera-near cube
//! ([`crate::CubeNear::Camera`]) every ray starts at the camera's near plane and crosses
//! those walls in front of the scene: 99 of 720,000 stereo rays turned from miss into a
//! spurious hit and 358 hit another pixel than brute force over the exact planes (examples
//! `quadtree_precision.rs`), costing 0.4 dB of warp PSNR at 800x450. The slope encoding has no
//! cancellation: every f16 rounding is relative (`<= 2^-11` of the increment, or `2^-25`
//! absolute below the f16 normal range), so the decoded plane's `z` at a footprint corner
//! is off by at most `2^-11 (|dz_x| + |dz_y|) / 2 + 2^-25` plus the `z_c` rounding — a
//! fraction `2^-12` of the plane's own `z` spread over its footprint (as a distance: that
//! times `|N.z|`, plus a few f32 ulps of decoding; tests below and
//! `tests/quadtree_precision.rs` on atrium in both cubes). Scaling by the
//! node's footprint (`2^l`) keeps that bound level-independent: a merged node of 256 pixels
//! is not coarser than a leaf. A slope beyond `±65504` per footprint (the plane crosses the
//! whole cube depth within `1/65504` of its footprint) is clamped: the plane's footprint
//! crossing moves by at most `2^l / 65504` pixels. Decoding needs no square root (the
//! paper's `N.z` does): the test normal is scaled by a power of two ([`Node::test_normal`]).
//!
//! Measurements of the slope encoding against `N.x, N.y`: `docs/notes/quadtree.md`.

use glam::Vec3;

/// An effective level ([`super::QuadTree::effective_levels`]): no plane node above or at this
/// node.
pub(crate) const NO_PLANE: u8 = u8::MAX;

/// Plane flag: the paper's `O`, "close to a depth discontinuity" (§3.2): the plane is
/// tested over a footprint dilated backwards along the ray ([`super::QuadTreeOptions::crack_dilation`]).
pub const FLAG_CRACK: u32 = 1;
/// Plane flag: a deeper layer's plane may come in front of this plane inside the footprint
/// (or this layer is empty where a deeper one is not); the whole footprint column then
/// counts as occlusion volume for cascading ([`super::cascade`]).
pub const FLAG_UNSAFE: u32 = 2;
const FLAG_MASK: u32 = 3;
const SIGN: u32 = 0x8000_0000;
/// Largest finite f16.
const F16_MAX: f32 = 65504.0;

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

    /// A plane node from `z_c` and the plane's z increments `dzx`, `dzy` across the node's
    /// footprint (module docs; clamped to `±65504`); `None` unless `z_c` is finite and
    /// `>= 0` and the increments are not NaN.
    #[inline]
    pub fn plane(zc: f32, dzx: f32, dzy: f32, flags: u32) -> Option<Node> {
        if !(zc.is_finite() && zc >= 0.0) || dzx.is_nan() || dzy.is_nan() {
            return None;
        }
        // Round to a 21-bit mantissa (may carry into the exponent: still correct).
        let bits = (zc.to_bits() + 2) & !FLAG_MASK;
        let hx = f32_to_f16_bits(dzx.clamp(-F16_MAX, F16_MAX)) as u32;
        let hy = f32_to_f16_bits(dzy.clamp(-F16_MAX, F16_MAX)) as u32;
        Some(Node {
            a: SIGN | bits | (flags & FLAG_MASK),
            b: hx | (hy << 16),
        })
    }

    /// A plane node at `level` of a `w x h` image from `z_c` and the plane's cube gradient
    /// `(gx, gy) = (dz/dx, dz/dy)` (may be infinite: clamped; `None` for NaN).
    #[inline]
    pub fn plane_with_gradient(
        zc: f32,
        gx: f32,
        gy: f32,
        level: u32,
        w: f32,
        h: f32,
        flags: u32,
    ) -> Option<Node> {
        let size = (1u32 << level) as f32;
        // `inf * size / w` stays infinite and is clamped; a zero gradient stays exactly 0.
        Node::plane(zc, gx * (size / w), gy * (size / h), flags)
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

    /// The stored z increments `(dz_x, dz_y)` across the node's footprint (module docs).
    #[inline(always)]
    pub fn increments(self) -> (f32, f32) {
        (
            f16_bits_to_f32(self.b as u16),
            f16_bits_to_f32((self.b >> 16) as u16),
        )
    }

    /// Decoded cube gradient `(dz/dx, dz/dy)` of a plane node at `level` of a `w x h`
    /// image (the increments times `w / 2^l`, `h / 2^l`; `2^-l` is exact).
    #[inline(always)]
    pub fn gradient(self, level: u32, w: f32, h: f32) -> (f32, f32) {
        let (ex, ey) = self.increments();
        // `w 2^-level` exactly, by lowering the exponent (w >= 1, level < 32: stays normal).
        let (ws, hs) = (
            f32::from_bits(w.to_bits() - (level << 23)),
            f32::from_bits(h.to_bits() - (level << 23)),
        );
        (ex * ws, ey * hs)
    }

    /// Decoded unit normal of a plane node at `level` (`N.z < 0`, towards the eye):
    /// `(g_x, g_y, -1)` normalised.
    #[inline(always)]
    pub fn normal(self, level: u32, w: f32, h: f32) -> Vec3 {
        let (gx, gy) = self.gradient(level, w, h);
        let r = 1.0 / (1.0 + gx * gx + gy * gy).sqrt();
        Vec3::new(gx * r, gy * r, -r)
    }

    /// The plane-test normal of [`decode_plane`]: `(g_x, g_y, -1)` scaled by the power of
    /// two `2^-floor(log2 max(1, |g_x|, |g_y|))`, so `|N|` is in `[1, 2 sqrt 3)` — near
    /// unit, which keeps the f32 plane test `N·P - c` and the cascade's margin
    /// ([`super::cascade`]) at the scale they had with unit normals — without a square root
    /// or a division (exact scaling: exponent bits only). Same direction as
    /// [`Self::normal`].
    #[inline(always)]
    pub fn test_normal(self, level: u32, w: f32, h: f32) -> Vec3 {
        let (gx, gy) = self.gradient(level, w, h);
        // max(1, |gx|, |gy|) with plain compares (`maxss`; never NaN: |g| <= 65504 W).
        let (ax, ay) = (gx.abs(), gy.abs());
        let m = if ax > ay { ax } else { ay };
        let m = if m > 1.0 { m } else { 1.0 };
        // 2^-e for m in [2^e, 2^(e+1)): exponent field 127 - e = 254 - (127 + e).
        let s = f32::from_bits(0x7f00_0000 - (m.to_bits() & 0x7f80_0000));
        Vec3::new(gx * s, gy * s, -s)
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

/// Exact f16 -> f32 conversion of a *finite* half (the stored slopes), branch-free and
/// inlinable. `half`'s `to_f32` dispatches at run time (F16C detection) to an out-of-line
/// function; in the traversal loop those two calls per plane test forced the loop's f32
/// state to be spilled around them. A normal half is its bits shifted into an f32's
/// exponent/mantissa field with the exponent rebiased by an integer add (`+112 << 23`); a
/// subnormal half (or zero) is its 10-bit mantissa, converted from an integer, times `2^-24`
/// — both exact, and a mask selects one, so the result equals `f16::to_f32` bit for bit
/// (checked for all finite halves in the tests below). No f32 **subnormal** appears on the
/// way: the former decode (shift, then multiply by `2^112`) made one out of every subnormal
/// half, and a multiplication with a subnormal operand takes a slow microcode assist —
/// rare for the paper's `N.x, N.y`, common for the slopes of fronto-parallel surfaces
/// (~10 % of the traversal's time on atrium; examples `quadtree_speed.rs --time`).
#[inline(always)]
pub fn f16_bits_to_f32(h: u16) -> f32 {
    let h = h as u32;
    let mag = h & 0x7fff;
    let normal = (mag << 13) + 0x3800_0000; // exponent field + (127 - 15)
    let sub = (mag as f32 * f32::from_bits(0x3380_0000)).to_bits(); // * 2^-24
    let is_sub = 0u32.wrapping_sub((mag < 0x400) as u32);
    f32::from_bits((sub & is_sub) | (normal & !is_sub) | ((h & 0x8000) << 16))
}

/// Exact f32 -> f16 conversion (round to nearest, ties to even) of a value that is not NaN
/// and at most 65504 in magnitude (the clamped slopes), inlinable and without `half`'s run-time
/// dispatch (an out-of-line call per value in the build's leaf loop). The rounding is
/// F. Giesen's "float_to_half_fast3_rtne": a normal half by adding the rebias and the
/// round-to-nearest-even bias to the bits; a subnormal half (or zero) by an f32 addition of
/// `2^-1` (IEEE addition rounds the dropped bits to nearest even); both computed and one
/// selected without a branch. Equal to
/// `f16::from_f32` bit for bit (tests below: every half and the f32 values around each
/// rounding boundary).
#[inline(always)]
pub fn f32_to_f16_bits(v: f32) -> u16 {
    let x = v.to_bits();
    let sign = (x >> 16) & 0x8000;
    let a = x & 0x7fff_ffff;
    // All three cases computed, one selected by masks: no branch (the slopes of nearly
    // fronto-parallel planes straddle the subnormal boundary, a branch there mispredicts).
    // |v| < 2^-14: a subnormal half; the magic 0.5 aligns the half's mantissa.
    let magic = f32::from_bits(((127 - 15) + (23 - 10) + 1) << 23);
    let sub = (f32::from_bits(a) + magic)
        .to_bits()
        .wrapping_sub(magic.to_bits());
    // A normal half: rebias the exponent, round to nearest even.
    let odd = (a >> 13) & 1;
    let normal = a
        .wrapping_add(((15u32.wrapping_sub(127)) << 23).wrapping_add(0xfff))
        .wrapping_add(odd)
        >> 13;
    // |v| >= 65536: infinity (never a NaN here).
    let is_inf = 0u32.wrapping_sub((a >= 0x4780_0000) as u32);
    let is_sub = 0u32.wrapping_sub((a < 0x3880_0000) as u32);
    let h = (0x7c00 & is_inf) | (sub & is_sub) | (normal & !(is_sub | is_inf));
    (sign | h) as u16
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

/// [`decode_plane`] without the power-of-two scale of [`Node::test_normal`]: `N = (g_x,
/// g_y, -1)`, `c = N·(x_c, y_c, z_c)` — the traversal's plane test. The traversal uses
/// only the sign of `f = N·P - c`, of its values at two parameters, and the root
/// `-f(0) / f'`; scaling `N` by a power of two `2^-e` scales every product, sum and
/// difference of that evaluation by exactly `2^-e` (IEEE rounding commutes with it while
/// no value leaves the normal range) and cancels exactly in the root, so these are the
/// same bits as with [`decode_plane`]'s normal, ~10 cycles sooner (no `max`, exponent
/// extraction and scaling between the node load and the hit decision, the end of every
/// ray's dependency chain). The scaled normal stays the stored definition: the brute-force
/// twin and the cascade's safety margin (in units of `f`) use [`decode_plane`].
#[inline(always)]
pub fn decode_plane_unscaled(
    node: Node,
    level: u32,
    qx: u32,
    qy: u32,
    w: f32,
    h: f32,
) -> (Vec3, f32) {
    let (gx, gy) = node.gradient(level, w, h);
    let n = Vec3::new(gx, gy, -1.0);
    let (xc, yc) = node_centre(level, qx, qy, w, h);
    (n, n.dot(Vec3::new(xc, yc, node.zc())))
}

/// Decoded plane `(N, c)` with `N·P = c` of a plane node at `level`, `(qx, qy)`: `N` =
/// [`Node::test_normal`] from the stored slopes (not unit length: `|N|` in `[1, 2 sqrt 3)`,
/// module docs), `c = N·(x_c, y_c, z_c)` in f32.
#[inline(always)]
pub fn decode_plane(node: Node, level: u32, qx: u32, qy: u32, w: f32, h: f32) -> (Vec3, f32) {
    let n = node.test_normal(level, w, h);
    let (xc, yc) = node_centre(level, qx, qy, w, h);
    (n, n.dot(Vec3::new(xc, yc, node.zc())))
}

/// [`decode_plane`] with the node's footprint centre `(xc, yc)` given (the values of
/// [`node_centre`], e.g. tabulated per column and row).
#[inline(always)]
pub fn decode_plane_at(node: Node, level: u32, xc: f32, yc: f32, w: f32, h: f32) -> (Vec3, f32) {
    let n = node.test_normal(level, w, h);
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
    use half::f16;

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
    fn f16_encode_matches_half() {
        let check = |v: f32| {
            if !v.is_nan() && v.abs() <= F16_MAX {
                assert_eq!(
                    f32_to_f16_bits(v),
                    f16::from_f32(v).to_bits(),
                    "{v:e} ({:#x})",
                    v.to_bits()
                );
            }
        };
        // Every half, and the f32 values at and around each midpoint between two halves.
        for h in 0..=u16::MAX {
            let a = f16::from_bits(h).to_f32();
            let b = f16::from_bits(h.wrapping_add(1)).to_f32();
            check(a);
            if a.is_finite() && b.is_finite() && (a < 0.0) == (b < 0.0) {
                let m = 0.5 * (a as f64 + b as f64);
                let mb = (m as f32).to_bits();
                for d in [-2i32, -1, 0, 1, 2] {
                    check(f32::from_bits(mb.wrapping_add_signed(d)));
                }
            }
        }
        // A spread of f32 bit patterns (every exponent, many mantissas).
        for k in 0..(1u32 << 22) {
            check(f32::from_bits(k.wrapping_mul(1021)));
        }
        for v in [
            0.0,
            -0.0,
            65504.0,
            -65504.0,
            65519.99,
            5.9604645e-8,
            2.9802322e-8,
        ] {
            check(v);
        }
    }

    #[test]
    fn encode_decode() {
        let n = Node::plane(0.75, 0.1, -0.2, FLAG_CRACK).unwrap();
        assert!(n.is_plane() && !n.is_empty());
        assert!((n.zc() - 0.75).abs() < 1e-6);
        assert_eq!(n.flags(), FLAG_CRACK);
        // Level 1 of a 64 x 32 image: gradient = increments * (32, 16).
        let (gx, gy) = n.gradient(1, 64.0, 32.0);
        assert!(
            (gx - 3.2).abs() < 2e-3 && (gy + 3.2).abs() < 2e-3,
            "{gx} {gy}"
        );
        let nn = n.normal(1, 64.0, 32.0);
        let want = Vec3::new(3.2, -3.2, -1.0).normalize();
        assert!((nn - want).length() < 1e-3 && (nn.length() - 1.0).abs() < 1e-6);
        let mut m = n;
        m.mark_unsafe(0.5);
        assert_eq!(m.flags(), FLAG_CRACK | FLAG_UNSAFE);
        assert_eq!(m.zc(), n.zc());
        assert!(Node::EMPTY.is_empty() && !Node::EMPTY.is_plane());
        let b = Node::aabb(-0.5, 0.9);
        assert!(!b.is_plane() && b.zrange() == (0.0, 0.9));
        assert!(Node::plane(-0.1, 0.0, 0.0, 0).is_none());
        assert!(Node::plane(0.5, f32::NAN, 0.0, 0).is_none());
        assert!(Node::plane(0.0, 0.0, 0.0, 0).unwrap().is_plane());
        assert_eq!(size_of::<Node>(), 8);
    }

    /// The grazing plane of the module docs (atrium, 800x450, camera-near cube): the paper's
    /// `N.x, N.y` encoding made it vertical; the slopes keep its gradient to `2^-11`.
    #[test]
    fn grazing_plane_keeps_its_slope() {
        let exact = Vec3::new(0.999_991_4, 0.000_558_165, -0.004_102_197);
        let (gx, gy) = (-exact.x / exact.z, -exact.y / exact.z);
        let n = Node::plane_with_gradient(0.98, gx, gy, 0, 800.0, 450.0, 0).unwrap();
        let (dx, dy) = n.gradient(0, 800.0, 450.0);
        assert!(((dx - gx) / gx).abs() < 4.9e-4 && ((dy - gy) / gy).abs() < 4.9e-4);
        let nn = n.normal(0, 800.0, 450.0);
        assert!(((nn.z - exact.z) / exact.z).abs() < 1e-3, "{nn} vs {exact}");
        // The paper's encoding: N.x rounds to 1 in f16 and N.z to 0.
        let hx = f16::from_f32(exact.x).to_f32();
        assert_eq!(hx, 1.0);
        // Vertical and steeper-than-f16 planes clamp; a flat one stays exactly flat.
        let v = Node::plane_with_gradient(0.5, f32::INFINITY, -1e9, 0, 800.0, 450.0, 0).unwrap();
        assert_eq!(v.increments(), (65504.0, -65504.0));
        assert!(v.normal(0, 800.0, 450.0).is_finite());
        let f = Node::plane_with_gradient(0.5, 0.0, -0.0, 3, 800.0, 450.0, 0).unwrap();
        assert_eq!(f.normal(3, 800.0, 450.0), Vec3::new(0.0, 0.0, -1.0));
        assert_eq!(f.test_normal(3, 800.0, 450.0), Vec3::new(0.0, 0.0, -1.0));
    }

    /// The test normal is `(g, -1)` times an exact power of two, of near unit length.
    #[test]
    fn test_normal_is_a_scaled_gradient() {
        for e in -30..=30 {
            for (a, b) in [(1.0f32, 0.3f32), (-0.2, 1.0), (0.7, -0.7)] {
                let g = 10f32.powf(e as f32 / 4.0);
                let n = Node::plane(0.6, a * g, b * g, 0).unwrap();
                let (gx, gy) = n.gradient(2, 640.0, 360.0);
                let t = n.test_normal(2, 640.0, 360.0);
                let s = -t.z;
                assert_eq!(s, f32::from_bits(s.to_bits() & 0x7f80_0000), "power of two");
                assert_eq!((t.x, t.y), (gx * s, gy * s));
                let len = t.length();
                assert!(len >= 1.0 && len < 2.0 * 3f32.sqrt(), "{len}");
                let u = n.normal(2, 640.0, 360.0);
                assert!((t / len - u).length() < 1e-5, "{t} {u}");
            }
        }
    }

    /// Encoding error bound of the module docs: the exact plane's points at the footprint
    /// corners lie within `2^-11 (|dz_x| + |dz_y|) / 2 + 2^-25` in cube `z` of the decoded
    /// plane (`z_c` is exact here), i.e. within that times `|N.z|` in distance — plus the
    /// f32 rounding of decoding (`c`, normalisation: a few ulps of distance). Measured as
    /// the distance `|N·X - c|` of the decoded unit-normal plane, which stays well
    /// conditioned for planes steep in the cube (where `z` along the plane is not), over
    /// slopes from 1e-9 to 1e4 per footprint at every level.
    #[test]
    fn corner_error_bound() {
        let (w, h) = (1600.0f32, 900.0f32);
        let mut worst = 0.0f64;
        for level in 0..9u32 {
            for e in -90..=40 {
                for sign in [-1.0f64, 1.0] {
                    let size = (1u32 << level) as f64;
                    // Increments per footprint from ~1e-9 to ~1e4.
                    let ex = sign * 10f64.powf(e as f64 / 10.0) * 1.2345;
                    let (gx, gy) = (ex * w as f64 / size, -0.37 * ex * h as f64 / size);
                    let zc = 0.75f32; // exact in 21 bits
                    let n = Node::plane_with_gradient(zc, gx as f32, gy as f32, level, w, h, 0)
                        .unwrap();
                    let (xc, yc) = node_centre(level, 3, 2, w, h);
                    let (nn, c) = decode_plane(n, level, 3, 2, w, h);
                    let (hx, hy) = (0.5 * size / w as f64, 0.5 * size / h as f64);
                    let nz = 1.0 / (1.0 + gx * gx + gy * gy).sqrt();
                    let bound_z = (gx.abs() * hx + gy.abs() * hy) * 2f64.powi(-11) + 2f64.powi(-25);
                    let bound = bound_z * nz + 4.0 * f32::EPSILON as f64;
                    for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
                        let (x, y) = (xc as f64 + sx * hx, yc as f64 + sy * hy);
                        let z = zc as f64 + gx * sx * hx + gy * sy * hy;
                        let dist = (nn.as_dvec3().dot(glam::DVec3::new(x, y, z)) - c as f64).abs()
                            / nn.as_dvec3().length();
                        assert!(dist <= bound, "level {level} g {gx}: {dist} > {bound}");
                        worst = worst.max(dist / bound);
                    }
                }
            }
        }
        assert!(worst > 0.01, "the bound is not vacuous: {worst}");
    }
}
