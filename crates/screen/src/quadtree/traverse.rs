//! Stackless quad-tree traversal of one layer (Widmer et al. 2015, §4).
//!
//! State: the current ray parameter `s` and a node `(level, Qx, Qy)`. Per step:
//!
//! - the node's parameter interval `[t_in, t_out]` is the ray's slab interval over the node's
//!   screen rectangle, clipped to `[s, s_hi]`;
//! - **plane node**: exact ray-plane test over `[t_in, t_out]` — a sign change of
//!   `f(s) = N·P(s) - c` is the hit, no refinement (§3.1); both ends behind the plane
//!   (`f < 0`) is an occlusion-volume entry at `t_in` (§4.1; the same rule as
//!   [`crate::BruteForcePlanes`]). Planes flagged `O` are tested from `crack_dilation`
//!   pixels of travel before `t_in` (crack dilation, §3.2);
//! - **AABB node**: the ray's `z` range over `[t_in, t_out]` against `[min z, max z]`; while
//!   occlusion information is still wanted the box is **extruded** to `[min z, 1]` (§4.1:
//!   "we never explicitly create this occlusion volume, but rather extrude a given node during
//!   intersection testing"). On a hit the traversal descends to the child whose quadrant
//!   holds the entry point `P(t_in)` (ties broken by the ray direction);
//! - on a miss the successor at the same level is the neighbour across the exit edge
//!   (smaller of the two slab exits; both on a tie), and the traversal restarts
//!   `findMSB((Qx ^ Qx*) | (Qy ^ Qy*))` levels up, i.e. one level below the last common
//!   ancestor (Frisken & Perry 2002), capped at the top level.
//!
//! Deviation: the traversal starts one level below the level whose nodes exceed the
//! segment's screen extent, or at the start pixel's effective plane node if that is higher
//! (one load from the per-pixel plane level stored at build time), instead of the root;
//! box tests only cull, so the result is unchanged and the first few always-passing box
//! tests are skipped. Invariant: no ancestor of the current node is a plane (true at the
//! start; a successor's parent is an ancestor of the node it came from).
//!
//! **`z` slabs** (the ray against a box in 3D, where the plain form tests the box's `z`
//! range over the node's `xy` interval): the traversal starts where the ray's
//! cube `z` reaches `QuadTree::z_floor` — the smallest lower bound of the top-level
//! nodes (the root box's `z` slab) minus a margin of `Z_SKIP_MARGIN = 1e-3` — and a
//! descent into a box starts at the ray's entry into the box's `[zmin, ..]` slab (minus
//! the same margin) instead of its `xy` entry. Exact: box ranges are conservative over
//! the (crack-dilated) plane footprints below them and include the cascade's trigger
//! depths, and occlusion volumes lie behind planes, so the skipped part of the ray is in
//! front of every plane by at least the margin in `z`: no hit, occlusion entry or trigger
//! entry there, and the f32 plane tests the plain form would have made there are far from
//! a sign change (and a node straddling the new start gets the same sign-change decision
//! and the same root: the root is past the start). `q.s_lo` stays the floor of crack
//! dilation and inpainting. (Where a plane steep in the cube near the top level makes the
//! floor 0, only the descent rule applies.)
//!
//! **Regional floor**: the same argument holds for the floor over just the
//! top-level nodes the segment can cross: for a ray moving along `x` only (a horizontal
//! stereo baseline) the nodes of its row from its start column on in its direction
//! (`QuadTree::z_floor_dir`, indexed by integers known at the ray's setup), otherwise the
//! rectangle of top-level nodes spanned by its pixels at `s_lo` and `s_hi`
//! (`QuadTree::z_floor_rect`, a `tw^2 th^2` table of range minima). The skipped part
//! only passes over (and only dilated plane tests of) those nodes, all above it by the
//! margin. A regional floor less than `Z_REGION_MIN_GAIN = 0.05` above the global one is
//! stored as the global one, and the traversal takes the regional value in a predicted
//! branch: where it equals the global floor (all of atrium's rays) the start does not wait
//! for the table load. There are no regional floors where the global floor is 0 (they cost
//! more time than their saved visits there).
//!
//! **Plane test with the unscaled normal** `(g_x, g_y, -1)`
//! ([`super::node::decode_plane_unscaled`]): the traversal uses only signs of `f` and the
//! root `-f(0) / f'`, which a power-of-two scale of the normal leaves bit-identical (the
//! scale commutes with IEEE rounding in the normal range), so the decode's `max`, exponent
//! extraction and scaling leave the chain from the node load to the hit decision.
//!
//! Implementation (same results as the plain form of §4): both axes' slabs are one 4-lane
//! operation; on an axis the ray does not move along (`dg == 0`, e.g. every epipolar
//! segment of a horizontal stereo baseline) the descent's child and the successor's exit
//! edge come from per-ray integers and a predicted branch, so the next node's index never
//! waits for the slab arithmetic (that dependency chain, not the instruction count, sets the
//! time).
//!
//! **Codegen to keep:** the traversal loop of `trace_layers` must hold no `cmov` after the
//! `bsr` of the level jump (objdump): `raise_level` hides its identity behind `black_box` so
//! that LLVM does not fold the successor's top-level cap into a `cmov` on the chain to the
//! next node index.
//!
//! The loop carries a hard bound of `(W + H + 2) (2 levels + 2)` steps (every pixel column
//! the segment crosses, each reached after at most `levels` descents); hitting it ends the
//! layer with what was found. Nothing allocates; the hot loop is f32. Node loads are
//! unchecked (`get_unchecked`) under an invariant stated and debug-asserted at the load
//! (the level index and node coordinates stay inside the padded level arrays), so the
//! debug-build tests check it on every step.
//!
//! Measurements (visits, instructions and time per ray of each of these choices):
//! `docs/notes/quadtree.md`.

use glam::{UVec2, Vec3, Vec4};

use super::node::{FLAG_CRACK, FLAG_UNSAFE, decode_plane, decode_plane_unscaled, plane_z};
use super::tree::{QuadTree, Z_SKIP_MARGIN};
use crate::{CubeSegment, TraceStats};

#[inline(always)]
fn fmax(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// A cube segment prepared for traversal (cube and grid units).
#[derive(Clone, Copy, Debug)]
pub struct RaySetup {
    pub p0: Vec3,
    pub d: Vec3,
    /// Grid-space origin and direction (`x W`, `y H`).
    pub o: [f32; 2],
    pub dg: [f32; 2],
    /// Slab origin and reciprocal of the traversal loop: `o` and `inv`, except on an axis
    /// with `dg == 0`, where they are the start pixel's centre and `+inf` (see
    /// [`Self::slabs`]).
    so: [f32; 2],
    sinv: [f32; 2],
    /// The slab of both axes as one 4-lane operation (`x` near, `y` near, `x` far, `y`
    /// far; [`Self::slabs`]): per-lane sides `[tie_x, tie_y, 1 - tie_x, 1 - tie_y]`, origins
    /// `[so_x, so_y, so_x, so_y]` and reciprocals likewise.
    side4: Vec4,
    so4: Vec4,
    sinv4: Vec4,
    /// Parameter length of one pixel of screen travel (for dilations).
    pub s_per_px: f32,
    /// The `z` entry of a box (descent start, [`QuadTree::trace_layer`]): `(zmin - zoff) *
    /// inv_dz` with `zoff = p0.z + Z_SKIP_MARGIN`, `inv_dz = 1 / d.z` for `d.z > 0`, else 0.
    zoff: f32,
    inv_dz: f32,
    /// Per axis: the ray does not move along it (`dg == 0`), and then `floor(o)` (see the
    /// descent in [`QuadTree::trace_layer`]).
    par: [bool; 2],
    floor_o: [u32; 2],
    /// On a `par` axis: the pixel `cell(a, s, 0, W - 1)` (the same for every finite `s`).
    pcell: [u32; 2],
}

impl RaySetup {
    #[inline(always)]
    pub fn new(seg: &CubeSegment, w: f32, h: f32) -> Self {
        let d = seg.p1 - seg.p0;
        let o = [seg.p0.x * w, seg.p0.y * h];
        let dg = [d.x * w, d.y * h];
        let inv = [1.0 / dg[0], 1.0 / dg[1]];
        let tie = [(dg[0] < 0.0) as u32 as f32, (dg[1] < 0.0) as u32 as f32];
        let mut r = Self {
            p0: seg.p0,
            d,
            o,
            dg,
            so: o,
            sinv: inv,
            side4: Vec4::new(tie[0], tie[1], 1.0 - tie[0], 1.0 - tie[1]),
            so4: Vec4::ZERO,
            sinv4: Vec4::ZERO,
            // `1 / max(|dg|)` without a third division: division is correctly rounded and
            // monotone, so `1 / max(|a|, |b|) == min(1 / |a|, 1 / |b|)` exactly (`inf` when
            // both are 0).
            s_per_px: fmin(inv[0].abs(), inv[1].abs()),
            zoff: seg.p0.z + Z_SKIP_MARGIN,
            inv_dz: if d.z > 0.0 { 1.0 / d.z } else { 0.0 },
            par: [false; 2],
            floor_o: [0; 2],
            pcell: [0; 2],
        };
        // An axis the ray does not move along: the traversal never leaves the start pixel's
        // column (row) on it — its pixel is `cell(a, s, ..)` for every `s`, and a descent
        // picks the child holding it (same tie rule) — so every visited node's slab on it
        // holds the pixel centre strictly inside: with `so` = that centre and `sinv = +inf`
        // the slab is exactly `(-inf, +inf)` (a ray parallel to the slab inside it) without
        // a per-node test. (A node of the padding beyond the image
        // may miss the centre; it is empty, and the parameters the traversal takes from its
        // slab — `t_out` and the exit edge — are the same.)
        if dg[0] == 0.0 || dg[1] == 0.0 {
            r.axis_parallel(w, h);
        }
        r.so4 = Vec4::new(r.so[0], r.so[1], r.so[0], r.so[1]);
        r.sinv4 = Vec4::new(r.sinv[0], r.sinv[1], r.sinv[0], r.sinv[1]);
        r
    }

    /// The `dg == 0` axes of [`Self::new`] (common: a horizontal stereo baseline makes
    /// every epipolar segment horizontal).
    #[inline(always)]
    fn axis_parallel(&mut self, w: f32, h: f32) {
        for (a, hi) in [(0, w as u32 - 1), (1, h as u32 - 1)] {
            if self.dg[a] == 0.0 {
                self.pcell[a] = self.cell0(a, hi);
                self.so[a] = self.pcell[a] as f32 + 0.5;
                self.sinv[a] = f32::INFINITY;
                self.par[a] = true;
                // `floor(o)` for `o >= 0` (saturating: NaN and negatives to 0, which keeps
                // the descent test below: `o < 0` is below every mid line `m >= 1`).
                self.floor_o[a] = self.o[a] as u32;
            }
        }
    }

    /// Entry and exit parameters `(x in, y in, x out, y out)` of the node rectangle
    /// `[x0, x0 + size] x [y0, y0 + size]`: per axis the two products `(side - o) * inv`
    /// of the slab test (the near side is `x0 + size * tie`, exact), without branches, both
    /// axes in one 4-lane operation (each lane the same IEEE operations as the scalar form).
    #[inline(always)]
    fn slabs(&self, x0: f32, y0: f32, size: f32) -> Vec4 {
        let side = Vec4::new(x0, y0, x0, y0) + self.side4 * size;
        (side - self.so4) * self.sinv4
    }

    /// Grid coordinate on axis `a` at `s`.
    #[inline(always)]
    pub fn at(&self, a: usize, s: f32) -> f32 {
        self.o[a] + self.dg[a] * s
    }

    /// First parameter in `[a, b]` where the ray's cube `z >= tz`.
    #[inline(always)]
    pub fn z_entry(&self, a: f32, b: f32, tz: f32) -> Option<f32> {
        let za = self.p0.z + self.d.z * a;
        if za >= tz {
            return Some(a);
        }
        let zb = self.p0.z + self.d.z * b;
        if zb >= tz && self.d.z > 0.0 {
            Some(clamp_in((tz - self.p0.z) / self.d.z, a, b))
        } else {
            None
        }
    }

    /// [`Self::cell`]`(a, s, 0, hi)`, from [`Self::pcell`] on an axis the ray does not move
    /// along (`o + 0 s = o`: the same value for every finite `s`).
    #[inline(always)]
    fn start_cell(&self, a: usize, s: f32, hi: u32) -> u32 {
        if self.par[a] {
            debug_assert_eq!(self.pcell[a], self.cell(a, s, 0, hi));
            self.pcell[a]
        } else if s == 0.0 {
            // `o + dg * 0 = o` (`dg` finite; a signed zero floors the same).
            self.cell0(a, hi)
        } else {
            self.cell(a, s, 0, hi)
        }
    }

    /// [`Self::cell`]`(a, 0, 0, hi)` (the start pixel of a ray from the segment's start),
    /// with a short dependency chain: it feeds the start node's index. For `0 <= o < 1e7`
    /// (always, with the f64 clip: `p0` is in `[0, 1]`) the floor is the truncation, and
    /// the tie rule and the clamps are integer operations — ~15 cycles of latency instead
    /// of ~45 for the general form's float selects; otherwise the general form.
    #[inline(always)]
    #[allow(clippy::manual_range_contains)]
    fn cell0(&self, a: usize, hi: u32) -> u32 {
        let x = self.o[a];
        if x >= 0.0 && x < 1.0e7 {
            // SAFETY: `0 <= x < 1e7`, so it truncates to an in-range `i32`.
            let t = unsafe { x.to_int_unchecked::<i32>() };
            let t = t - ((t as f32 == x) & (self.dg[a] < 0.0)) as i32;
            let c = (t.max(0) as u32).min(hi);
            debug_assert_eq!(c, self.cell(a, 0.0, 0, hi));
            c
        } else {
            self.cell(a, 0.0, 0, hi)
        }
    }

    /// [`Self::cell`]`(a, s, lo, hi)` for `0 <= lo <= hi <= W - 1`: on a `par` axis the
    /// nested clamp `clamp(clamp(c, 0, W - 1), lo, hi) = clamp(c, lo, hi)` of `pcell`.
    #[inline(always)]
    fn cell_in(&self, a: usize, s: f32, lo: u32, hi: u32) -> u32 {
        if self.par[a] {
            let c = self.pcell[a].max(lo).min(hi);
            debug_assert_eq!(c, self.cell(a, s, lo, hi));
            c
        } else {
            self.cell(a, s, lo, hi)
        }
    }

    /// Pixel cell on axis `a` at `s` (boundary ties go along the direction), clamped to
    /// `[lo, hi]` (`lo <= hi < 2^31`).
    ///
    /// Integer form with a short dependency chain (it feeds the hit pixel and, in a cascade,
    /// the start node): every `x <= 0` (and NaN) yields `lo` — its floor, minus the tie, is
    /// at most 0 — so `x` is clamped to `[0, 1e7]` first, where the floor is the truncation,
    /// and the tie rule and the clamps are integer operations. Same result as the float form
    /// (floor, tie, clamp) it replaced, for every `x`.
    #[inline(always)]
    fn cell(&self, a: usize, s: f32, lo: u32, hi: u32) -> u32 {
        let x = self.at(a, s);
        let x = if x > 0.0 { x } else { 0.0 };
        let x = if x < 1.0e7 { x } else { 1.0e7 };
        // SAFETY: `x` is in `[0, 1e7]` (not NaN) after the selects above, so it truncates to
        // an in-range `i32` (no saturation code needed, unlike `as`).
        let t = unsafe { x.to_int_unchecked::<i32>() };
        // A boundary tie goes to the lower cell when moving down the axis.
        let t = t - ((t as f32 == x) & (self.dg[a] < 0.0)) as i32;
        (t.max(lo as i32) as u32).min(hi)
    }
}

/// `x` clamped to `[lo, hi]` (`lo <= hi`): `f32::clamp` without its `lo <= hi` assertion,
/// which kept it out of line (a call per hit). Same result (NaN stays NaN).
#[inline(always)]
fn clamp_in(x: f32, lo: f32, hi: f32) -> f32 {
    let x = if x < lo { lo } else { x };
    if x > hi { hi } else { x }
}

/// The identity, out of line: keeps `if pl > l { l = pl }` a branch instead of a select
/// (see its uses). `black_box` hides that it returns its argument: otherwise LLVM may
/// still infer it (a `returned` argument) and fold the branch back into a `cmov` on the
/// loop's chain to the next node index — which happened after an unrelated edit of the
/// start and cost ~4 ns per visited node (~20 % on the camera cube).
#[cold]
#[inline(never)]
fn raise_level(pl: usize) -> usize {
    std::hint::black_box(pl)
}

/// What one layer's traversal found, in segment parameters.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LayerEvents {
    /// First plane hit (`s`, pixel).
    pub hit: Option<(f32, UVec2)>,
    /// First entry into the cascade trigger region (see [`super::cascade`]).
    pub trigger: Option<f32>,
    /// First occlusion-volume entry (`s`, pixel), brute-force semantics.
    pub ov: Option<(f32, UVec2)>,
    /// The step bound was hit.
    pub truncated: bool,
}

/// What a layer traversal looks for.
#[derive(Clone, Copy, Debug)]
pub struct Query {
    pub s_lo: f32,
    pub s_hi: f32,
    /// Accept a hit at exactly `s_hi`.
    pub hi_inclusive: bool,
    pub want_trigger: bool,
    /// Stop at the first occlusion-volume entry (inpaint mode).
    pub stop_at_ov: bool,
}

impl QuadTree {
    /// Traverses this layer along `ray` over `[q.s_lo, q.s_hi]` (§4); stops at the first hit
    /// (or, with `stop_at_ov`, the first occlusion-volume entry).
    #[inline(always)]
    pub fn trace_layer(&self, ray: &RaySetup, q: &Query, stats: &mut TraceStats) -> LayerEvents {
        let mut ev = LayerEvents::default();
        if !(q.s_lo <= q.s_hi) {
            return ev;
        }
        let top = self.levels.len() - 1;
        let (w, h) = (self.width, self.height);
        let (wf, hf) = (self.wf, self.hf);
        let bound = (w as u64 + h as u64 + 2) * (2 * self.levels.len() as u64 + 2);
        let crack_s = self.crack_px * ray.s_per_px;
        let mut need_ext = true;
        let mut s = q.s_lo;
        // The ray against the root box's `z` slab (§4 tests the ray against the root AABB
        // first): in front of `z_floor` there is nothing to hit, no occlusion volume and
        // no trigger region, so the traversal starts where the ray's `z` reaches it
        // (`QuadTree::z_floor`; the boxes the skipped part crossed would all have been
        // culled). `q.s_lo` stays the floor of crack dilation and inpainting.
        // `z_floor > 0` first (fixed per tree, predicted): with a floor of 0 (e.g. a plane
        // steep in the cube near the top level) the start does not wait for the division.
        //
        // Regional floor: the floor over the rectangle of top-level nodes spanned by the
        // segment's pixels at `s_lo` and `s_hi` (it holds every node the traversal can visit;
        // `QuadTree::z_floor_rect`). Kept only when above the global floor: a predicted
        // branch (not a select), so the start does not wait for the table load where the
        // regional floor is the global one.
        let mut zf = self.z_floor;
        if !self.z_floor_dir.is_empty()
            && ray.d.z > 0.0
            && (ray.par[1] || !self.z_floor_rect.is_empty())
        {
            let fr = self.region_floor(ray, q);
            if fr > zf {
                // `black_box`: keeps this a branch (not a `max` on the chain), without the
                // call of [`raise_level`] (which made LLVM keep values around it in memory).
                zf = std::hint::black_box(fr);
            }
        }
        if zf > 0.0 && ray.d.z > 0.0 {
            s = fmax(s, (zf - ray.p0.z) / ray.d.z);
            if !(s <= q.s_hi) {
                return ev;
            }
        }
        // Start level: the paper starts at the root. Starting lower is equivalent (box tests
        // only cull) provided no plane ancestor is skipped: start one level below the first
        // level whose nodes exceed the segment's screen extent, or at the topmost plane
        // ancestor.
        let (cx, cy) = (ray.start_cell(0, s, w - 1), ray.start_cell(1, s, h - 1));
        let ext = ray.dg[0].abs().max(ray.dg[1].abs()) * (q.s_hi - s);
        let mut l = if ext < 1e6 {
            // ~ceil(log2(ext + 2)) without libm, one level lower: measured fewer visits
            // (the z-entry descent below skips the start box's front part anyway).
            ((32 - ((ext + 2.0) as u32).leading_zeros()) as usize)
                .saturating_sub(1)
                .min(top)
        } else {
            top
        };
        // The topmost plane ancestor of the start pixel, precomputed per pixel at build
        // time (one load instead of one node load per level above `l`).
        let pl = self.plane_level[(cy * w + cx) as usize] as usize;
        if pl > l {
            // A real (predicted) branch, not a select: the start node's index then need not
            // wait for this load.
            l = raise_level(pl);
        }
        let mut qx = cx >> l;
        let mut qy = cy >> l;
        // Counters live in registers; `stats` is written once at the end. Only the step
        // budget and the plane tests are counted in the loop; the box tests and visits
        // follow from them at the end.
        let step_x = if ray.dg[0] > 0.0 { 1u32 } else { u32::MAX };
        let step_y = if ray.dg[1] > 0.0 { 1u32 } else { u32::MAX };
        // Descent tie rule (entry point exactly on the mid line): towards the direction.
        let (pos_x, pos_y) = (ray.dg[0] >= 0.0, ray.dg[1] >= 0.0);
        // Last column / row index of level-`l` nodes holding image pixels.
        let (wm, hm) = (w - 1, h - 1);
        let mut left = bound;
        let mut n_plane = 0u64;
        let mut plane_break = false;
        let levels = self.levels.as_slice();
        loop {
            if left == 0 {
                ev.truncated = true;
                break;
            }
            left -= 1;
            // SAFETY (invariant, debug-asserted): `l <= top` and `(qx, qy)` indexes level
            // `l`, whose `w x h` is the padded image scaled by `2^-l` (`w << l >= W`).
            // True at the start (`cx <= W - 1`, `l <= top`); kept by a descent (`l >= 1`,
            // and a child `2 qx + 1 < 2 w` of level `l - 1`) and by a successor (checked
            // `nx <= (W - 1) >> l < w` below, then `nx >> sh <= (W - 1) >> nl` at level
            // `nl <= top`).
            debug_assert!(l <= top);
            let lv = unsafe { levels.get_unchecked(l) };
            debug_assert!(qx < lv.w && qy < lv.h);
            let node = unsafe { *lv.nodes.get_unchecked((qy * lv.w + qx) as usize) };
            // `2^l` from its exponent bits; node corners are integers below 2^24: exact.
            let size = f32::from_bits((127 + l as u32) << 23);
            let (x0, y0) = ((qx << l) as i32 as f32, (qy << l) as i32 as f32);
            let t4 = ray.slabs(x0, y0, size);
            let (txi, tyi, txo, tyo) = (t4.x, t4.y, t4.z, t4.w);
            // Plain compares (slab values are never NaN): no NaN-aware min/max in the loop.
            let t_in = fmax(fmax(s, txi), tyi);
            let t_out = fmin(fmin(txo, tyo), q.s_hi);
            let mut descend = false;
            let mut s_down = t_in;
            if node.is_plane() {
                n_plane += 1;
                if t_in <= t_out {
                    // Unscaled normal: the same signs and root bit for bit (node.rs).
                    let (n, c) = decode_plane_unscaled(node, l as u32, qx, qy, wf, hf);
                    let flags = node.flags();
                    let mut trig = None;
                    // `want_trigger` first: fixed per layer, it keeps the data-dependent flag
                    // test (mispredicted ~0.2 times per ray) out of single-layer traces.
                    if q.want_trigger && flags & FLAG_UNSAFE != 0 && ev.trigger.is_none() {
                        trig = if l == 0 {
                            let tz = self.trigger_z[(qy * w + qx) as usize];
                            ray.z_entry(t_in, t_out, tz)
                        } else {
                            Some(t_in)
                        };
                    }
                    let f0 = n.dot(ray.p0) - c;
                    let fd = n.dot(ray.d);
                    let ta = if flags & FLAG_CRACK != 0 {
                        (t_in - crack_s).max(q.s_lo)
                    } else {
                        t_in
                    };
                    let fa = f0 + fd * ta;
                    let fb = f0 + fd * t_out;
                    if (fa <= 0.0) != (fb <= 0.0) || fa == 0.0 || fb == 0.0 {
                        let sh = if fd != 0.0 {
                            clamp_in(-f0 / fd, ta, t_out)
                        } else {
                            ta
                        };
                        // A ray already behind the plane where it enters the footprint
                        // (crossing it from behind, a hit of the two-sided plane) is in
                        // the trigger region `{f < 0}` from `t_in` on: deeper layers must
                        // be traced from there (cascade.rs, Lemma 2). Found by proptest.
                        if trig.is_none()
                            && q.want_trigger
                            && ev.trigger.is_none()
                            && f0 + fd * t_in < 0.0
                        {
                            trig = Some(t_in);
                        }
                        if let Some(t) = trig
                            && t <= sh
                        {
                            ev.trigger = Some(t);
                        }
                        if sh < q.s_hi || (q.hi_inclusive && sh <= q.s_hi) {
                            let px = self.pixel_in(ray, sh, l, qx, qy);
                            ev.hit = Some((sh, px));
                        }
                        plane_break = true;
                        break;
                    } else if fa < 0.0 && ev.ov.is_none() {
                        ev.ov = Some((t_in, self.pixel_in(ray, t_in, l, qx, qy)));
                        if q.want_trigger && ev.trigger.is_none() {
                            trig = Some(t_in);
                        }
                        if q.stop_at_ov {
                            ev.trigger = ev.trigger.or(trig);
                            plane_break = true;
                            break;
                        }
                    }
                    if ev.trigger.is_none() {
                        ev.trigger = trig;
                    }
                    need_ext = (q.want_trigger && ev.trigger.is_none()) || ev.ov.is_none();
                }
            } else if t_in <= t_out {
                let za = ray.p0.z + ray.d.z * t_in;
                let zb = ray.p0.z + ray.d.z * t_out;
                let (zlo, zhi) = (fmin(za, zb), fmax(za, zb));
                let (zmin, zmax) = node.zrange();
                // One combined branch (hit or miss is data-dependent).
                if (zhi >= zmin) & ((zlo <= zmax) | need_ext) {
                    if l == 0 {
                        // A pixel-level AABB holds no plane: it is an empty pixel marked
                        // unsafe for cascading (its whole column triggers).
                        if q.want_trigger && ev.trigger.is_none() {
                            ev.trigger = ray.z_entry(t_in, t_out, zmin);
                            need_ext = ev.trigger.is_none() || ev.ov.is_none();
                        }
                    } else {
                        descend = true;
                        // The ray enters the box's `z` slab at `z = zmin` (the 3D slab test):
                        // before that it is in front of everything below (with
                        // `Z_SKIP_MARGIN`), so the descent starts there, clamped to the
                        // node's interval (`inv_dz = 0` when `d.z <= 0`: no skip).
                        s_down = fmin(fmax(t_in, (zmin - ray.zoff) * ray.inv_dz), t_out);
                    }
                }
            }
            if descend {
                s = s_down;
                l -= 1;
                // Mid lines `x0 + size / 2`: exact.
                let half = size * 0.5;
                let (mid_x, mid_y) = (x0 + half, y0 + half);
                // Short-circuit on purpose: predicted branches keep the child choice off
                // the loop's data-dependency chain (the branch-free form was ~15 % slower).
                // On an axis the ray does not move along (`par`, per ray: a predicted
                // branch) the entry coordinate is the constant `o` (`o + 0 * s`, `s`
                // finite), and the comparison with the integer mid line
                // `m = (2 q + 1) 2^l` (`l` is now the child level) is `o >= m` (`pos` holds
                // for `dg = ±0`) <=> `floor(o) >= m` <=> `floor(o) >> l > 2 q`: an integer
                // test instead of a data-dependent branch (that branch mispredicted ~1.1
                // times per ray on horizontal stereo rays: the row's side is random).
                let rx = if ray.par[0] {
                    (ray.floor_o[0] >> l) > 2 * qx
                } else {
                    let ex = ray.at(0, s);
                    ex > mid_x || (ex == mid_x && pos_x)
                };
                let ry = if ray.par[1] {
                    (ray.floor_o[1] >> l) > 2 * qy
                } else {
                    let ey = ray.at(1, s);
                    ey > mid_y || (ey == mid_y && pos_y)
                };
                // The float comparison it replaces, on every descent of the debug-build tests.
                debug_assert!({
                    let (ex, ey) = (ray.at(0, s), ray.at(1, s));
                    rx == (ex > mid_x || (ex == mid_x && pos_x))
                        && ry == (ey > mid_y || (ey == mid_y && pos_y))
                });
                qx = 2 * qx + rx as u32;
                qy = 2 * qy + ry as u32;
                continue;
            }
            if t_out >= q.s_hi {
                break;
            }
            s = fmax(s, t_out); // neither is NaN
            // Successor across the exit edge (§4). `step` is +1 or -1 (wrapping) per axis,
            // fixed per ray. A ray moving along one axis only (`par` on the other: its slab
            // there is `(-inf, +inf)`, so it exits across the moving axis) takes a predicted
            // branch: the next node's index then does not wait for the slab arithmetic (the
            // branch-free form puts `txo <= tyo` on the loop's data-dependency chain). The
            // guard keeps the result identical in every case (`txo < tyo` is exactly the
            // case where the branch-free form steps in x only).
            let (nx, ny) = if ray.par[1] && txo < tyo {
                (qx.wrapping_add(step_x), qy)
            } else if ray.par[0] && tyo < txo {
                (qx, qy.wrapping_add(step_y))
            } else {
                // General rays: branch-free (the exit axis is data-dependent).
                (
                    qx.wrapping_add(step_x & 0u32.wrapping_sub((txo <= tyo) as u32)),
                    qy.wrapping_add(step_y & 0u32.wrapping_sub((tyo <= txo) as u32)),
                )
            };
            // Off the image (a wrapped `-1` is `u32::MAX`): `nx << l < W` iff
            // `nx <= (W - 1) >> l`.
            if nx > wm >> l || ny > hm >> l {
                break;
            }
            let diff = (qx ^ nx) | (qy ^ ny);
            let up = (31 - diff.leading_zeros()) as usize;
            // Capped at the top level: a (cold) branch, not a select on the chain to the
            // next node index.
            let mut nl = l + up;
            if nl > top {
                nl = raise_level(top);
            }
            let sh = nl - l;
            qx = nx >> sh;
            qy = ny >> sh;
            l = nl;
        }
        let steps = bound - left + ev.truncated as u64;
        let tested = bound - left;
        stats.steps += steps;
        stats.plane_tests += n_plane;
        stats.box_tests += tested - n_plane;
        stats.nodes_visited += tested - plane_break as u64;
        stats.truncated += ev.truncated as u64;
        ev
    }

    /// The regional `z` floor of a ray over `[q.s_lo, q.s_hi]`: the entry of
    /// [`Self::z_floor_rect`] for the rectangle of top-level nodes spanned by the pixels at
    /// both ends (the segment is straight, so every image pixel it crosses lies in that
    /// rectangle; clamping to the image keeps that). Needs a non-empty table.
    #[inline(always)]
    fn region_floor(&self, ray: &RaySetup, q: &Query) -> f32 {
        let top = self.levels.len() - 1;
        let (wm, hm) = (self.width - 1, self.height - 1);
        let (tw, th) = (self.z_floor_tw, self.z_floor_th);
        if ray.par[1] {
            // Moving along `x` only (a horizontal stereo baseline): the row's nodes from the
            // start column on in the ray's direction, from integers known at the ray's setup
            // (no cell at `s_hi` on the chain to the start node).
            let r = ray.pcell[1] >> top;
            let c = ray.start_cell(0, q.s_lo, wm) >> top;
            let k = (2 * (r * tw + c) + (ray.dg[0] < 0.0) as u32) as usize;
            debug_assert!(r < th && c < tw && k < self.z_floor_dir.len());
            // SAFETY: `r <= (H - 1) >> top < th`, `c <= (W - 1) >> top < tw`: `k < 2 tw th`,
            // the table's length (debug-asserted).
            return unsafe { *self.z_floor_dir.get_unchecked(k) };
        }
        let xa = ray.start_cell(0, q.s_lo, wm) >> top;
        let ya = ray.start_cell(1, q.s_lo, hm) >> top;
        let xb = ray.cell_in(0, q.s_hi, 0, wm) >> top;
        let yb = ray.cell_in(1, q.s_hi, 0, hm) >> top;
        let (c0, c1) = (xa.min(xb), xa.max(xb));
        let (r0, r1) = (ya.min(yb), ya.max(yb));
        debug_assert!(c1 < tw && r1 < th);
        let k = (((r0 * th + r1) * tw + c0) * tw + c1) as usize;
        debug_assert!(k < self.z_floor_rect.len());
        // SAFETY: `c0 <= c1 <= (W - 1) >> top < tw` and likewise rows, so `k < tw^2 th^2`,
        // the table's length (debug-asserted).
        unsafe { *self.z_floor_rect.get_unchecked(k) }
    }

    /// The pixel of point `P(s)` inside node `(qx, qy)` at level `l`.
    #[inline(always)]
    fn pixel_in(&self, ray: &RaySetup, s: f32, l: usize, qx: u32, qy: u32) -> UVec2 {
        if l == 0 {
            return UVec2::new(qx, qy);
        }
        let x0 = qx << l;
        let y0 = qy << l;
        let x1 = (x0 + (1 << l) - 1).min(self.width - 1);
        let y1 = (y0 + (1 << l) - 1).min(self.height - 1);
        UVec2::new(ray.cell_in(0, s, x0, x1), ray.cell_in(1, s, y0, y1))
    }

    /// Cube `z` of the effective plane at pixel `(i, j)` at cube `(x, y)`, if any (tests).
    pub fn plane_z_at(&self, i: u32, j: u32, x: f32, y: f32) -> Option<f32> {
        let (node, l, qx, qy) = self.effective_node(i, j)?;
        let (n, c) = decode_plane(node, l, qx, qy, self.wf, self.hf);
        Some(plane_z(n, c, x, y))
    }
}
