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
//! [`QuadTree::trace_layer`] is [`QuadTree::layer_start`] (the `z`-floor skip, start level and
//! node) followed by [`QuadTree::layer_walk`] (the loop), so that a batch of rays can compute
//! all its starts before the first walk (`super::batch`); the per-ray set-up is
//! [`RaySetup`] (`super::setup`).
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

use glam::UVec2;

use super::node::{FLAG_CRACK, FLAG_UNSAFE, decode_plane, decode_plane_unscaled, plane_z};
pub use super::setup::RaySetup;
use super::setup::{clamp_in, fmax, fmin};
use super::tree::QuadTree;
use crate::TraceStats;

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

/// Where a layer traversal starts ([`QuadTree::layer_start`]): ray parameter `s` and node
/// `(l, qx, qy)`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LayerStart {
    pub s: f32,
    pub l: usize,
    pub qx: u32,
    pub qy: u32,
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

impl Query {
    /// The whole segment, no trigger depth, no stop at occlusion: one layer without
    /// inpainting.
    pub const WHOLE: Query = Query {
        s_lo: 0.0,
        s_hi: 1.0,
        hi_inclusive: true,
        want_trigger: false,
        stop_at_ov: false,
    };
}

impl QuadTree {
    /// Traverses this layer along `ray` over `[q.s_lo, q.s_hi]` (§4); stops at the first hit
    /// (or, with `stop_at_ov`, the first occlusion-volume entry).
    #[inline(always)]
    pub fn trace_layer(&self, ray: &RaySetup, q: &Query, stats: &mut TraceStats) -> LayerEvents {
        match self.layer_start(ray, q) {
            Some(start) => self.layer_walk(ray, q, start, stats),
            None => LayerEvents::default(),
        }
    }

    /// The start of [`Self::trace_layer`]: the `z`-floor skip, the start level and node
    /// (module docs); `None` when nothing of the window is left to traverse (no events, no
    /// work counted). Split from the walk so that a batch of rays can compute all its
    /// starts before the first walk (`quadtree/batch.rs`).
    #[inline(always)]
    pub fn layer_start(&self, ray: &RaySetup, q: &Query) -> Option<LayerStart> {
        if !(q.s_lo <= q.s_hi) {
            return None;
        }
        let top = self.levels.len() - 1;
        let (w, h) = (self.width, self.height);
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
                return None;
            }
        }
        // Start level: the paper starts at the root. Starting lower is equivalent (box tests
        // only cull) provided no plane ancestor is skipped: start one level below the first
        // level whose nodes exceed the segment's screen extent, or at the topmost plane
        // ancestor.
        let (cx, cy) = (ray.start_cell(0, s, w - 1), ray.start_cell(1, s, h - 1));
        // Plain compares (`dg` is finite: the segment's ends are clamped to the cube).
        let ext = fmax(ray.dg[0].abs(), ray.dg[1].abs()) * (q.s_hi - s);
        let mut l = if ext < 1e6 {
            // `0 <= ext` (`s <= q.s_hi` here), so `ext + 2` is in `[2, 1e6 + 2)`.
            debug_assert!(ext >= 0.0);
            // SAFETY: `ext + 2` is in `[2, 1e6 + 2)` (above): it truncates to an in-range
            // `u32` (no saturation code needed, unlike `as`).
            let e = unsafe { (ext + 2.0).to_int_unchecked::<u32>() };
            // ~ceil(log2(ext + 2)) without libm, one level lower: measured fewer visits
            // (the z-entry descent below skips the start box's front part anyway).
            ((32 - e.leading_zeros()) as usize)
                .saturating_sub(1)
                .min(top)
        } else {
            top
        };
        // The topmost plane ancestor of the start pixel, precomputed per pixel at build
        // time (one load instead of one node load per level above `l`).
        debug_assert!(cx < w && cy < h && self.plane_level.len() == (w * h) as usize);
        // SAFETY: `cx <= W - 1` and `cy <= H - 1` (the start cells' clamps), and the table
        // holds `W x H` entries (debug-asserted).
        let pl = unsafe { *self.plane_level.get_unchecked((cy * w + cx) as usize) } as usize;
        if pl > l {
            // A real (predicted) branch, not a select: the start node's index then need not
            // wait for this load.
            l = raise_level(pl);
        }
        Some(LayerStart {
            s,
            l,
            qx: cx >> l,
            qy: cy >> l,
        })
    }

    /// The walk of [`Self::trace_layer`] from `start` ([`Self::layer_start`] of the same
    /// `ray` and `q`): the stackless loop of §4 (module docs).
    #[inline(always)]
    pub fn layer_walk(
        &self,
        ray: &RaySetup,
        q: &Query,
        start: LayerStart,
        stats: &mut TraceStats,
    ) -> LayerEvents {
        let mut ev = LayerEvents::default();
        let top = self.levels.len() - 1;
        let (w, h) = (self.width, self.height);
        let (wf, hf) = (self.wf, self.hf);
        let bound = (w as u64 + h as u64 + 2) * (2 * self.levels.len() as u64 + 2);
        let crack_s = self.crack_px * ray.s_per_px;
        let mut need_ext = true;
        let LayerStart {
            mut s,
            mut l,
            mut qx,
            mut qy,
        } = start;
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
    /// rectangle; clamping to the image keeps that), or the global floor where the start
    /// node's own entry is the global floor (then so is the rectangle's: no end cells
    /// needed). Needs a non-empty table.
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
        // Pre-test on the start node alone (its one-node rectangle): every rectangle holding
        // it has a floor at most that node's (a minimum over more nodes; the table's rounding
        // to the global floor is monotone), so where that is the global floor the
        // rectangle's is too, and the end cells and the rectangle's index are not needed.
        let k1 = (((ya * th + ya) * tw + xa) * tw + xa) as usize;
        debug_assert!(k1 < self.z_floor_rect.len());
        // SAFETY: `xa <= (W - 1) >> top < tw`, `ya < th`: `k1 < tw^2 th^2` (debug-asserted).
        let f1 = unsafe { *self.z_floor_rect.get_unchecked(k1) };
        if f1 <= self.z_floor {
            return self.z_floor;
        }
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
