//! The affine packet test: HVVR's per-pixel form of the sample test (Hunt et al. 2018, §5.5;
//! HVVR's `IntersectTriangleThread`: edge values at the pixel centre plus their derivatives in
//! the subsample offset), used to decide a whole packet of subsample rays against a set-up
//! triangle at once, with a rigorous float error bound, before any per-lane work.
//!
//! **What it does.** For a pinhole camera (and each eye of the stereo rig) the unnormalised
//! camera-space direction through film position `f = (fx, fy)` is
//! `v(f) = ((2 fx / w - 1 + sx) tx, (1 - 2 fy / h + sy) ty, -1)`, affine in `f`, and the
//! world direction is `B v / |v|` (`B` the camera basis). So a set-up triangle's edge value
//! `n_i . d` (`cast/setup/mod.rs`) is, up to the positive factor `1 / |v|`, the affine function
//! `L_i(v) = m_i . v` with the camera-space covector `m_i = B^T n_i`, computed once per tile and
//! triangle ([`AffineTri`], three edges in the lanes of one SSE register). A packet's film
//! positions lie in a box; its image in camera space is a box `[xc ± rx] x [yc ± ry] x {-1}`
//! ([`PacketBox`]), and over it `L_i` ranges over `m . (xc, yc, -1) ± (|m_x| rx + |m_y| ry)`:
//! per packet and triangle that is 2 multiply-adds per edge for the centre and 2 for the
//! radius (HVVR's centre value and offset derivatives, with the offset table replaced by its
//! bounding box), for all three edges in one SSE register. If for some edge the whole range
//! lies below `-tau_i`, every ray of the packet is certainly outside; if for every edge it lies
//! above `tau_i`, every ray is certainly inside; otherwise the packet is *partial* and each lane
//! takes the existing per-lane test (set-up value with the edge band, the watertight test
//! inside the band). At 16 spp a packet is one pixel, so most packet-triangle pairs are decided
//! here; at 1 spp a packet is a 4 x 4-pixel Morton block.
//!
//! **Invariant** (why the output is unchanged): a packet classified *out* has, for every lane,
//! an edge whose watertight edge function is negative; a packet classified *in* has, for every
//! lane, three positive watertight edge functions. So every lane's coverage decision equals the
//! watertight test's, exactly as the per-lane band test's decisions do, and the depth rule
//! (which reads the same `g . d` of the same float ray) is untouched: the buffer is identical
//! to the one without this test (`tests/affine.rs` compares both, bit for bit).
//!
//! **Per-edge decisions** (the hierarchical test of a partial packet, `classify_edges`): an
//! edge whose range lies above `tau_i` has, for every lane, a positive watertight edge function
//! (step 2 below); the per-lane test then takes the smallest value over the other edges only.
//! Its decisions are still the watertight test's: above the band every tested edge is
//! certainly inside and the skipped ones are, below minus the band one tested edge is
//! certainly outside, and within the band the watertight test decides. So the buffer is the
//! same (`tests/affine.rs`). Skipped only when every `|n_i|_1 < 1e37`: no edge value overflows,
//! so the minimum of a subset of finite values does not depend on the order.
//!
//! **The bound.** Notation: `U = 2^-24`; `n` the stored (float) covector, `n*` the exact
//! `a_i x a_{i+1}` of the rounded `a_i`; `d` the float ray of a lane, `v` its float camera
//! direction, `v*` the exact `v(f)` at the lane's float film position `f`; `rb >= max_j |B_j|_2`
//! (rows of `B`, computed), `bmax >= max |B_jk|`. `TriSetup::bound` covers (tri.rs) the
//! covector error `|n - n*| . |d| <= 3.1 U |a_i|_1 |e_i|_1 |d|_inf` plus the watertight test's
//! error `W |d|_inf`, so a lane with real `n . d > bound |d|_inf` is certainly inside that edge
//! (and `< -bound |d|_inf` certainly outside).
//!
//! 1. Ray generation: `|x - x*| <= e_x = 4.1 U tx (|2 fx / w| + 1 + |sx|)` (division,
//!    subtraction, addition, product; the factor 2 is exact), likewise `e_y`; `|len - |v|| <=
//!    2.5 U |v|` (three positive squares, a square root), each `v_k / len` one more rounding,
//!    `B u` a 3-term dot product (`3 U sum_k |B_jk| |u_k|`), and `|v / |v| - v* / |v*|| <= 2
//!    |v - v*| / |v*|` with `|v*| >= 1` (`z = -1`): per component
//!    `|d - B v* / |v*||_inf <= Delta = rb (6.6 U + 3.47 (e_x + e_y))`, so
//!    `n . d >= L*(v*) / |v*| - |n|_1 Delta` and `|d|_inf <= rb + Delta`, where
//!    `L*(v) = (B^T n) . v` with the exact `B^T n`.
//! 2. With `Vmax >= |v*|` over the box: if `min_box L* > tau_i = Vmax (bound (rb + Delta) +
//!    |n_i|_1 Delta) + eps_i`, then for every lane `n . d >= min L* / Vmax - |n|_1 Delta >
//!    bound |d|_inf`: certainly inside. Symmetrically for `max_box L* < -tau_i`: outside.
//! 3. The float evaluation: `m = fl(B^T n)` loses `3 U bmax |n|_1` per component, the centre
//!    value (3 terms) `3 U`, the radius (2 terms) `2 U`, the final difference `1 U`, each of
//!    `bmax |n|_1 S` with `S = |xc| + rx + |yc| + ry + 1`: `eps_i = 9.1 U bmax |n_i|_1 S`.
//! 4. The packet's camera box holds every lane's exact `v*`: the film box is the exact float
//!    minimum and maximum of the lanes' film positions (the same float operations, monotone),
//!    `x(f)` is monotone in `f` (`tx > 0`), `e_x` widens it, and the centre / radius rounding
//!    is covered by `2 U (|xl| + |xh|)` and a final `(1 + 8 U)`.
//!
//! Every U-term is doubled (first-order analysis, as `TriSetup::bound`); `Vmax`, `S`, `Delta`
//! and `tau` are rounded up by `1.01`.
//!
//! **Per-frame factors.** `tau_i = |n_i|_1 ka + bound kb`: `ka`, `kb` depend on the packet only
//! through `e_x`, `e_y` (increasing in the largest `|f|`) and `|xc| + rx`, `|yc| + ry` (which
//! enter `Vmax` and `S`), and every float operation of them is monotone increasing in these.
//! So [`FilmFrame`] computes them once, at the worst case of the eye's film rectangle
//! `[0, w] x [0, h]` (`|f| = w`, `h`; `|xc| + rx <= (m + e + 4 U m)(1 + 8 U) 1.001`, `m` the
//! largest `|x(f)|` over the rectangle, which bounds `max(|xl|, |xh|)` of every packet inside
//! by the monotone evaluation; the factor 1.001 covers the packet's own centre / radius
//! rounding, `~6 U`), and a packet whose film box lies inside the rectangle takes them with
//! its centre and radius (radius with the rectangle's `e_x`, `e_y`): a box containing the
//! per-packet one and a larger `tau`, so still rigorous. Other packets take the per-packet
//! factors. NaN or infinite values make both comparisons false
//! (partial: the per-lane test decides). Tests (`tests/affine.rs`): the classification never
//! contradicts the watertight test on random and adversarial rays (rays through edges and
//! shared vertices, grazing triangles), and whole casts equal the casts without it.
//!
//! **Parameters** (set through [`crate::CastOptions::affine`]):
//!
//! | name | type | default | meaning |
//! |---|---|---|---|
//! | `affine` | bool | true | run the packet test before the per-lane test (pinhole and stereo tiles, `SetupExactness::Edges`) |

use glam::{Mat3, Vec3, Vec4};
use parallax_scene::camera::{Camera, Pinhole};

use crate::SampleSet;
use parallax_core::simd::{Lanes, abs_lanes};

/// Unit roundoff of f32 (`2^-24`), the `U` of the bound above (the same constant as the
/// watertight set-up's in `tri.rs`).
const U: f32 = f32::EPSILON * 0.5;

/// A pinhole's film-to-camera map and basis, for the tile's eye (module docs).
#[derive(Clone, Copy, Debug)]
pub struct FilmFrame {
    /// Columns of `B` as SSE registers (lane 3 = 0).
    b: [Vec4; 3],
    w: f32,
    h: f32,
    tx: f32,
    ty: f32,
    sx: f32,
    sy: f32,
    /// Film x offset of the eye (0, or the eye width for the right eye of a stereo rig).
    x0: f32,
    /// Film x range of the eye (rays outside it come from the other eye or none).
    fx_lo: f32,
    fx_hi: f32,
    /// `>= max_j |B_j|_2` and `>= max |B_jk|` (rounded up).
    rb: f32,
    bmax: f32,
    /// The per-packet factors for every packet inside the eye's film rectangle `[0, w] x
    /// [0, h]` (eye-local; module docs, "Per-frame factors"): `e_x`, `e_y`, `ka`, `kb` at the
    /// rectangle's worst case; `region` false if they are not finite.
    ex: f32,
    ey: f32,
    ka: f32,
    kb: f32,
    region: bool,
    /// Per lane `[x(fx0), x(fx1), y(fy1), y(fy0)]` of [`PacketBox::new`] in one register: the
    /// film sizes `[w, w, h, h]`, shifts `[sx, sx, sy, sy]` and tangents `[tx, tx, ty, ty]`;
    /// the generator roundings `[ex, ey, ex, ey]` of the region.
    wv: Vec4,
    sv: Vec4,
    tv: Vec4,
    ev: Vec4,
    /// The float ray's distance `Delta` from `B v* / |v*|` per component (module docs, step
    /// 1) for every film position of the region (`+inf` without a region).
    delta: f32,
}

impl FilmFrame {
    fn new(p: &Pinhole, x0: f32, fx_lo: f32, fx_hi: f32) -> Option<Self> {
        let m: Mat3 = p.frame.basis;
        let (w, h) = (p.width as f32, p.height as f32);
        let (tx, ty) = (p.tan_half_x(), p.tan_half_y);
        let ok = [w, h, tx, ty, p.shift.x, p.shift.y]
            .iter()
            .all(|x| x.is_finite())
            && w > 0.0
            && h > 0.0
            && tx > 0.0
            && ty > 0.0
            && m.is_finite();
        if !ok {
            return None;
        }
        let rows = [m.row(0), m.row(1), m.row(2)];
        let rb = rows.iter().map(|r| r.length()).fold(0.0, f32::max) * 1.001;
        let bmax = rows
            .iter()
            .map(|r| r.abs().max_element())
            .fold(0.0, f32::max)
            * 1.001;
        let mut fr = FilmFrame {
            b: [
                m.x_axis.extend(0.0),
                m.y_axis.extend(0.0),
                m.z_axis.extend(0.0),
            ],
            w,
            h,
            tx,
            ty,
            sx: p.shift.x,
            sy: p.shift.y,
            x0,
            fx_lo,
            fx_hi,
            rb,
            bmax,
            ex: 0.0,
            ey: 0.0,
            ka: 0.0,
            kb: 0.0,
            region: false,
            wv: Vec4::new(w, w, h, h),
            sv: Vec4::new(p.shift.x, p.shift.x, p.shift.y, p.shift.y),
            tv: Vec4::new(tx, tx, ty, ty),
            ev: Vec4::ZERO,
            delta: f32::INFINITY,
        };
        // The rectangle's worst case (module docs, "Per-frame factors"): `e_x`, `e_y` at
        // `|f| = w`, `h`; `|xc| + rx` bounded by the largest `|x|` over the rectangle `m` as
        // `(m + e + 4 U m)(1 + 8 U)`, with a margin of 1e-3 for the packets' own rounding.
        let ex = fr.e_x(w);
        let ey = fr.e_y(h);
        let mx = fr.xf(0.0).abs().max(fr.xf(w).abs());
        let my = fr.yf(0.0).abs().max(fr.yf(h).abs());
        let ax = (mx + ex + 4.0 * U * mx) * (1.0 + 8.0 * U) * 1.001;
        let ay = (my + ey + 4.0 * U * my) * (1.0 + 8.0 * U) * 1.001;
        let (ka, kb) = fr.factors(ax, ay, ex, ey);
        if [ex, ey, ka, kb, ax, ay].iter().all(|x| x.is_finite()) {
            (fr.ex, fr.ey, fr.ka, fr.kb, fr.region) = (ex, ey, ka, kb, true);
            fr.ev = Vec4::new(ex, ey, ex, ey);
            fr.delta = fr.delta_of(ex, ey);
        }
        Some(fr)
    }

    /// `x(f)` with the generator's float operations (monotone increasing in `f`).
    #[inline(always)]
    fn xf(&self, f: f32) -> f32 {
        (2.0 * f / self.w - 1.0 + self.sx) * self.tx
    }

    /// `y(f)` with the generator's float operations (monotone decreasing in `f`).
    #[inline(always)]
    fn yf(&self, f: f32) -> f32 {
        (1.0 - 2.0 * f / self.h + self.sy) * self.ty
    }

    /// The rounding `e_x` of `x(f)` for `|f| <= fxm` (module docs, step 1).
    #[inline(always)]
    fn e_x(&self, fxm: f32) -> f32 {
        4.1 * U * self.tx * (2.0 * fxm / self.w + 1.0 + self.sx.abs()) * 1.01
    }

    /// The rounding `e_y` of `y(f)` for `|f| <= fym`.
    #[inline(always)]
    fn e_y(&self, fym: f32) -> f32 {
        4.1 * U * self.ty * (2.0 * fym / self.h + 1.0 + self.sy.abs()) * 1.01
    }

    /// `Delta = rb (13.2 U + 6.94 (e_x + e_y))` (doubled U-terms, module docs step 1): the
    /// float ray's distance from `B v* / |v*|` per component, for generator roundings `ex`,
    /// `ey`.
    #[inline(always)]
    fn delta_of(&self, ex: f32, ey: f32) -> f32 {
        self.rb * (13.2 * U + 6.94 * (ex + ey)) * 1.01
    }

    /// `(ka, kb)` of `tau = n1 ka + bound kb` for a camera box with `|xc| + rx <= ax`,
    /// `|yc| + ry <= ay` and generator roundings `ex`, `ey` (module docs, steps 1-3; every
    /// operation monotone increasing in the four arguments).
    #[inline(always)]
    fn factors(&self, ax: f32, ay: f32, ex: f32, ey: f32) -> (f32, f32) {
        let vmax = (1.0 + ax * ax + ay * ay).sqrt() * 1.01;
        let s = (ax + ay + 1.0) * 1.01;
        // Doubled U-terms (module docs): Delta = rb (13.2 U + 6.94 (e_x + e_y)).
        let delta = self.delta_of(ex, ey);
        let ka = (vmax * delta + 18.2 * U * self.bmax * s) * 1.01;
        let kb = vmax * (self.rb + delta) * 1.01;
        (ka, kb)
    }

    /// The frame of the eye whose origin is `origin` and whose film holds the tile's first
    /// sample `film_x`; `None` for cameras without an affine film map (everything but the
    /// pinhole and the stereo rig).
    pub fn of(set: &SampleSet, origin: Vec3, film_x: f32) -> Option<Self> {
        match &set.camera {
            Camera::Pinhole(p) => {
                (p.frame.position == origin).then_some(())?;
                Self::new(p, 0.0, f32::NEG_INFINITY, f32::INFINITY)
            }
            Camera::Stereo(rig) => {
                let w = rig.eye_width() as f32;
                let (e, x0, lo, hi) = if film_x < w {
                    (0, 0.0, 0.0, w)
                } else {
                    (1, w, w, 2.0 * w)
                };
                let p = &rig.eyes[e];
                (p.frame.position == origin).then_some(())?;
                Self::new(p, x0, lo, hi)
            }
            _ => None,
        }
    }

    /// The stereo eye test of the ray generation for film x in `[fx0, fx1]`: x in `[0, w)`
    /// left, `[w, 2w]` right (the whole film for a pinhole).
    #[inline(always)]
    fn in_eye(&self, fx0: f32, fx1: f32) -> bool {
        if self.x0 == 0.0 {
            fx0 >= self.fx_lo && fx1 < self.fx_hi
        } else {
            fx0 >= self.fx_lo && fx1 <= self.fx_hi
        }
    }

    /// Whether a packet whose lanes' float film positions lie in `[fx0, fx1] x [fy0, fy1]`
    /// (before the eye's x offset) is inside the eye and its film rectangle, where the
    /// frame's factors and `Delta` hold (module docs, "Per-frame factors").
    #[inline(always)]
    pub fn in_region(&self, fx0: f32, fx1: f32, fy0: f32, fy1: f32) -> bool {
        let inside = self.in_eye(fx0, fx1);
        let (gx0, gx1) = if self.x0 == 0.0 {
            (fx0, fx1)
        } else {
            (fx0 - self.x0, fx1 - self.x0)
        };
        self.region
            && inside
            && fx0 <= fx1
            && fy0 <= fy1
            && gx0 >= 0.0
            && gx1 <= self.w
            && fy0 >= 0.0
            && fy1 <= self.h
    }

    /// Bounds `(lo, hi)` per world axis of the float ray directions of every lane of sixteen
    /// packets inside the region ([`Self::in_region`]), from their camera boxes in the lanes
    /// of `xc, yc, rx, ry` (rows of [`PacketBox::scalars`]). Over a box, `B v` is affine (its
    /// range from the centre and radius) and `|v|` lies between the box's nearest and
    /// farthest point's length, so `B v / |v|` lies in a box per axis; the float ray is
    /// within `Delta` of it (module docs, step 1). Widened by the rounding of these
    /// operations (8 U of the magnitudes covers the three-term centre, the two-term radius,
    /// the two sums and the products with `1 / |v|`).
    #[inline(always)]
    pub fn dir_rows<L: Lanes>(&self, [xc, yc, rx, ry]: [L; 4]) -> ([L; 3], [L; 3]) {
        let zero = L::splat(0.0);
        let one = L::splat(1.0);
        let (axc, ayc) = (abs_lanes(xc), abs_lanes(yc));
        let (ax, ay) = (axc + rx, ayc + ry);
        let (nx, ny) = ((axc - rx).max_or_rhs(zero), (ayc - ry).max_or_rhs(zero));
        let vmax = (one + ax * ax + ay * ay).sqrt() * L::splat(1.0 + 4.0 * U);
        let vmin = (one + nx * nx + ny * ny).sqrt() * L::splat(1.0 - 4.0 * U);
        let (ivmin, ivmax) = (one / vmin, one / vmax);
        let mut lo = [zero; 3];
        let mut hi = [zero; 3];
        for a in 0..3 {
            let (b0, b1, b2) = (self.b[0][a], self.b[1][a], self.b[2][a]);
            let c = L::splat(b0) * xc + L::splat(b1) * yc - L::splat(b2);
            let r = L::splat(b0.abs()) * rx + L::splat(b1.abs()) * ry;
            let e = (L::splat(b0.abs()) * axc + L::splat(b1.abs()) * ayc + L::splat(b2.abs()) + r)
                * L::splat(8.0 * U);
            let (l, h) = (c - r - e, c + r + e);
            let dl = L::select(l.lt(zero), l * ivmin, l * ivmax);
            let dh = L::select(h.gt(zero), h * ivmin, h * ivmax);
            let pad =
                L::splat(self.delta * 1.01) + (abs_lanes(dl) + abs_lanes(dh)) * L::splat(8.0 * U);
            (lo[a], hi[a]) = (dl - pad, dh + pad);
        }
        (lo, hi)
    }

    /// The affine form of set-up covectors `n` (module docs).
    pub fn affine(&self, n: &[[f32; 3]; 3]) -> AffineTri {
        // m_k = B_k . n (column k of B: the camera axis k in world space), per edge in lanes.
        let nx = Vec4::new(n[0][0], n[1][0], n[2][0], 0.0);
        let ny = Vec4::new(n[0][1], n[1][1], n[2][1], 0.0);
        let nz = Vec4::new(n[0][2], n[1][2], n[2][2], 0.0);
        let col = |c: Vec4| Vec4::splat(c.x) * nx + Vec4::splat(c.y) * ny + Vec4::splat(c.z) * nz;
        let (mx, my, mz) = (col(self.b[0]), col(self.b[1]), col(self.b[2]));
        AffineTri {
            mx,
            my,
            mz,
            amx: mx.abs(),
            amy: my.abs(),
            n1: nx.abs() + ny.abs() + nz.abs(),
        }
    }
}

/// A set-up triangle's three edge covectors in camera space (`m_i = B^T n_i`, lanes 0-2;
/// lane 3 = 0), their absolute values and `|n_i|_1` (rounded as computed; module docs).
#[derive(Clone, Copy, Debug, Default)]
pub struct AffineTri {
    mx: Vec4,
    my: Vec4,
    mz: Vec4,
    amx: Vec4,
    amy: Vec4,
    n1: Vec4,
}

/// A packet's camera-space box and the per-packet factors of `tau` (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PacketBox {
    xc: Vec4,
    yc: Vec4,
    rx: Vec4,
    ry: Vec4,
    /// `tau_i = n1_i ka + bound kb`.
    ka: Vec4,
    kb: f32,
}

/// The packet test's decision for one set-up triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PacketClass {
    /// Every ray certainly outside (one edge).
    Out,
    /// Every ray certainly inside (all three edges).
    In,
    /// Decide per lane.
    Partial,
}

/// Edges are skipped per packet (`PacketBox::classify_edges`) only for triangles whose
/// covectors all have `|n_i|_1` below this: every float edge value `n_i . d` (`|d_k| <= 1.01`)
/// is then finite, so the smallest of any subset of them is independent of the order.
const N1_SKIP: f32 = 1e37;

/// [`PacketBox::classify_bits`] of an `Out` packet.
pub const CLASS_OUT: u32 = 16;
/// [`PacketBox::classify_bits`] of an `In` packet.
pub const CLASS_IN: u32 = 8;

/// `true` in lanes 0-1.
const XY: glam::BVec4A = glam::BVec4A::from_array([true, true, false, false]);

/// `true` in lanes 0-2.
const XYZ: glam::BVec4A = glam::BVec4A::from_array([true, true, true, false]);

impl PacketBox {
    /// The box of a packet whose lanes' float film positions lie in `[fx0, fx1] x [fy0, fy1]`
    /// (exact float minimum and maximum of the lanes' `film + offset * footprint`, before the
    /// eye's x offset); `None` if it leaves the frame's eye or is not finite.
    #[inline(always)]
    pub fn new(fr: &FilmFrame, fx0: f32, fx1: f32, fy0: f32, fy1: f32) -> Option<Self> {
        Self::new_in(fr, fr.in_region(fx0, fx1, fy0, fy1), fx0, fx1, fy0, fy1)
    }

    /// [`PacketBox::new`] for a caller that has asked [`FilmFrame::in_region`] already
    /// (`region`, its answer for this box).
    #[inline(always)]
    pub fn new_in(
        fr: &FilmFrame,
        region: bool,
        fx0: f32,
        fx1: f32,
        fy0: f32,
        fy1: f32,
    ) -> Option<Self> {
        // Inside the eye's film rectangle (eye-local): the frame's factors (module docs,
        // "Per-frame factors"), no per-packet bound; `x(f)`, `y(f)` of the four film
        // coordinates and the two sides' centre and radius in one register each, per lane
        // the operations of `FilmFrame::xf` / `yf` and `side` below in their order (the same
        // bits; tested against `new_general` below).
        if region {
            let film = if fr.x0 == 0.0 {
                Vec4::new(fx0, fx1, fy1, fy0)
            } else {
                Vec4::new(fx0 - fr.x0, fx1 - fr.x0, fy1, fy0)
            };
            let q = Vec4::splat(2.0) * film / fr.wv;
            let u = Vec4::select(XY, q - Vec4::ONE, Vec4::ONE - q);
            // [xl, xh, yl, yh]
            let v = (u + fr.sv) * fr.tv;
            let (l, h) = (Vec4::new(v.x, v.z, 0.0, 0.0), Vec4::new(v.y, v.w, 0.0, 0.0));
            let c = Vec4::splat(0.5) * (l + h);
            let r =
                (Vec4::splat(0.5) * (h - l) + fr.ev + Vec4::splat(2.0 * U) * (l.abs() + h.abs()))
                    * Vec4::splat(1.0 + 8.0 * U);
            return Some(PacketBox {
                xc: Vec4::splat(c.x),
                yc: Vec4::splat(c.y),
                rx: Vec4::splat(r.x),
                ry: Vec4::splat(r.y),
                ka: Vec4::splat(fr.ka),
                kb: fr.kb,
            });
        }
        Self::new_general(fr, fx0, fx1, fy0, fy1)
    }

    /// [`PacketBox::new`] lane by lane (scalar), for every packet (the reference of the
    /// register form above, and the path of packets outside the eye's film rectangle).
    #[inline(never)]
    pub fn new_general(fr: &FilmFrame, fx0: f32, fx1: f32, fy0: f32, fy1: f32) -> Option<Self> {
        if !(fr.in_eye(fx0, fx1) && fx0 <= fx1 && fy0 <= fy1) {
            return None;
        }
        // The eye's film x (`fx - w` for the right eye: monotone, as the generator's).
        let (fx0, fx1) = if fr.x0 == 0.0 {
            (fx0, fx1)
        } else {
            (fx0 - fr.x0, fx1 - fr.x0)
        };
        // x(f) and y(f) with the generator's float operations (monotone: x up, y down).
        let (xl, xh) = (fr.xf(fx0), fr.xf(fx1));
        let (yl, yh) = (fr.yf(fy1), fr.yf(fy0));
        let side = |l: f32, h: f32, e: f32| {
            let c = 0.5 * (l + h);
            let r = (0.5 * (h - l) + e + 2.0 * U * (l.abs() + h.abs())) * (1.0 + 8.0 * U);
            (c, r)
        };
        // Inside the eye's film rectangle: the frame's factors (module docs, "Per-frame
        // factors"), no per-packet bound.
        if fr.region && fx0 >= 0.0 && fx1 <= fr.w && fy0 >= 0.0 && fy1 <= fr.h {
            let (xc, rx) = side(xl, xh, fr.ex);
            let (yc, ry) = side(yl, yh, fr.ey);
            return Some(PacketBox {
                xc: Vec4::splat(xc),
                yc: Vec4::splat(yc),
                rx: Vec4::splat(rx),
                ry: Vec4::splat(ry),
                ka: Vec4::splat(fr.ka),
                kb: fr.kb,
            });
        }
        let fxm = fx0.abs().max(fx1.abs());
        let fym = fy0.abs().max(fy1.abs());
        let (ex, ey) = (fr.e_x(fxm), fr.e_y(fym));
        let (xc, rx) = side(xl, xh, ex);
        let (yc, ry) = side(yl, yh, ey);
        let (ka, kb) = fr.factors(xc.abs() + rx, yc.abs() + ry, ex, ey);
        if !(ka.is_finite() && kb.is_finite() && xc.is_finite() && yc.is_finite()) {
            return None;
        }
        Some(PacketBox {
            xc: Vec4::splat(xc),
            yc: Vec4::splat(yc),
            rx: Vec4::splat(rx),
            ry: Vec4::splat(ry),
            ka: Vec4::splat(ka),
            kb,
        })
    }

    /// Classifies a set-up triangle (its affine form `a`, edge band `bound`) for every ray of
    /// the packet (module docs).
    /// The box's centre, radii and factors as scalars `[xc, yc, rx, ry, ka, kb]` (every lane
    /// of its registers holds the same value): one packet's entries of [`BoxLanes`].
    #[inline(always)]
    pub fn scalars(&self) -> [f32; 6] {
        [
            self.xc.x, self.yc.x, self.rx.x, self.ry.x, self.ka.x, self.kb,
        ]
    }

    #[inline(always)]
    pub fn classify(&self, a: &AffineTri, bound: f32) -> PacketClass {
        self.classify_edges(a, bound).0
    }

    /// [`PacketBox::classify_edges`] as one word, without branches (for a run's triangles in
    /// one pass, `cast/setup/edges.rs`): [`CLASS_OUT`] for `Out`, [`CLASS_IN`] for `In`, else
    /// the skip bits of a partial packet (bits 0-2). The same compares of the same values.
    #[inline(always)]
    pub fn classify_bits(&self, a: &AffineTri, bound: f32) -> u32 {
        let c = a.mx * self.xc + a.my * self.yc - a.mz;
        let r = a.amx * self.rx + a.amy * self.ry;
        let tau = a.n1 * self.ka + Vec4::splat(bound * self.kb);
        let hi = c + r;
        let lo = c - r;
        let out = (((hi + tau).cmplt(Vec4::ZERO) & XYZ).bitmask() != 0) as u32;
        let inn = (lo - tau).cmpgt(Vec4::ZERO).bitmask() & 7;
        let small = (a.n1.cmplt(Vec4::splat(N1_SKIP)).bitmask() & 7 == 7) as u32;
        let all = (inn == 7) as u32;
        // Partial: the inside edges when every covector is small, else none. (Masks, not
        // selects: the class changes from triangle to triangle, a branch would mispredict.)
        let partial = inn & small.wrapping_neg() & all.wrapping_sub(1);
        let code = (all * CLASS_IN) | partial;
        (code & out.wrapping_sub(1)) | (out * CLASS_OUT)
    }

    /// [`PacketBox::classify`] and, for a partial packet, the bits of the edges every ray of
    /// the packet is certainly inside (edge `i`: bit `i`), whose per-lane test can be skipped
    /// (module docs, "Per-edge decisions"); 0 for the other classes and for triangles with a
    /// covector `|n_i|_1 >= 1e37` (no edge value may overflow where edges are skipped).
    #[inline(always)]
    pub fn classify_edges(&self, a: &AffineTri, bound: f32) -> (PacketClass, u32) {
        let c = a.mx * self.xc + a.my * self.yc - a.mz;
        let r = a.amx * self.rx + a.amy * self.ry;
        let tau = a.n1 * self.ka + Vec4::splat(bound * self.kb);
        let hi = c + r;
        let lo = c - r;
        // Out: one edge with its largest value below -tau.
        let out = (hi + tau).cmplt(Vec4::ZERO) & XYZ;
        if out.any() {
            return (PacketClass::Out, 0);
        }
        let inn = (lo - tau).cmpgt(Vec4::ZERO).bitmask() & 7;
        if inn == 7 {
            (PacketClass::In, 0)
        } else if inn != 0 && a.n1.cmplt(Vec4::splat(N1_SKIP)).bitmask() & 7 == 7 {
            (PacketClass::Partial, inn)
        } else {
            (PacketClass::Partial, 0)
        }
    }
}

/// The boxes of `L::N` packets in lanes ([`PacketBox::scalars`] of each packet, one lane per
/// packet): [`BoxLanes::classify`] decides one triangle against all of them at once.
#[derive(Clone, Copy)]
pub struct BoxLanes<L> {
    pub xc: L,
    pub yc: L,
    pub rx: L,
    pub ry: L,
    pub ka: L,
    pub kb: L,
}

/// [`BoxLanes::classify`] of one triangle against `L::N` packets: lane bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LaneClasses {
    /// Packets certainly outside some edge.
    pub out: u32,
    /// Per edge, the packets certainly inside it.
    pub inn: [u32; 3],
}

impl LaneClasses {
    /// Packet `k`'s class word of [`PacketBox::classify_bits`] (`CLASS_OUT`, `CLASS_IN` or
    /// the skipped edges), given whether the triangle's covectors are small enough to skip
    /// edges (`small`: [`AffineTri::small`]).
    #[inline(always)]
    pub fn code(&self, k: u32, small: bool) -> u32 {
        if self.out >> k & 1 != 0 {
            return CLASS_OUT;
        }
        let inn =
            (self.inn[0] >> k & 1) | (self.inn[1] >> k & 1) << 1 | (self.inn[2] >> k & 1) << 2;
        if inn == 7 {
            CLASS_IN
        } else if small {
            inn
        } else {
            0
        }
    }
}

impl AffineTri {
    /// Whether every edge's `|n_i|_1` is below [`N1_SKIP`] (module docs, "per-edge
    /// decisions"): the partial packets' certainly-inside edges may be skipped.
    #[inline(always)]
    pub fn small(&self) -> bool {
        self.n1.cmplt(Vec4::splat(N1_SKIP)).bitmask() & 7 == 7
    }
}

impl<L: parallax_core::simd::Lanes> BoxLanes<L> {
    /// [`PacketBox::classify_bits`] of the triangle `a` (band `bound`) against every lane's
    /// packet: per edge and lane the same float operations in the same order (so lane `k`'s
    /// [`LaneClasses::code`] equals `classify_bits` of packet `k`'s box, bit for bit; tested
    /// below).
    #[inline(always)]
    pub fn classify(&self, a: &AffineTri, bound: f32) -> LaneClasses {
        let zero = L::splat(0.0);
        let bk = L::splat(bound) * self.kb;
        let mut out = 0u32;
        let mut inn = [0u32; 3];
        for (e, inn_e) in inn.iter_mut().enumerate() {
            let c = L::splat(a.mx[e]) * self.xc + L::splat(a.my[e]) * self.yc - L::splat(a.mz[e]);
            let r = L::splat(a.amx[e]) * self.rx + L::splat(a.amy[e]) * self.ry;
            let tau = L::splat(a.n1[e]) * self.ka + bk;
            let (hi, lo) = (c + r, c - r);
            out |= L::bits((hi + tau).lt(zero));
            *inn_e = L::bits((lo - tau).gt(zero));
        }
        LaneClasses { out, inn }
    }
}

#[cfg(test)]
mod tests;
