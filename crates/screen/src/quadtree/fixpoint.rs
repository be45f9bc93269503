//! The cascade's pruning fixed point (Widmer et al. 2015, §3.3 pruning with the exact
//! cascading of [`super::cascade`]), computed incrementally.
//!
//! **What is computed** — the same levels and trigger depths as the definition
//! (`fixed_point_reference` in `prune.rs`): seed the blocked pixels with the trigger depths of
//! the pixel planes, prune, compute the trigger depths of the effective planes, block the
//! pixels that became unsafe, rebuild, until no pixel is added. This version does less work
//! per iteration, with the same results bit for bit (`tests/quadtree_build.rs` compares
//! whole trees with the definition's build):
//!
//! - the pixel planes' trigger depths are computed by the leaf pass, each row right after
//!   its leaves (`pixel_triggers_row`, no second pass over level 0); the pixel planes are
//!   decoded from the leaves only where a deeper plane needs them (pixel centres tabulated
//!   per column and row), not copied into a [`LayerPlanes`] first; on x86_64 (two levels or
//!   more) the same pass makes level 1, each row right after the leaves of its two child rows
//!   and with their blocked pixels (`leaves_and_level1` in `build.rs`), so the pruning goes
//!   on from level 2 without reading level 0 again; on x86_64 four pixels
//!   per step, one per lane (`trigger_lanes`; eight with AVX2, `trigger_avx2`), elsewhere each pixel's four footprint corners
//!   in lanes ([`super::cascade::pixel_trigger_lanes`]);
//! - the blocked pixels are kept as a list, not a `W x H` map: pruning marks only their
//!   ancestors ([`Blocked::List`]) and the unsafe pixels are marked through their ancestors
//!   only (`QuadTree::mark_unsafe_listed`; ~1 % of the pixels on atrium); the pixels the
//!   passes below evaluate are never blocked ones, except pixels whose trigger depth is
//!   their pixel plane's (finite only if listed), so no lookup is needed;
//! - the effective levels are kept as the tree's plane levels (`W x H`, 0 where the
//!   pixel's effective node is its own leaf or where it has none, [`plane_levels`]): made
//!   from level 1 down, so level 0 (the largest array) is not read again, and they are the
//!   finished tree's [`super::QuadTree::plane_levels`] without a conversion pass;
//! - a pixel whose effective node is its own leaf (level 0) or none has the pixel planes'
//!   trigger depth: only pixels under merged nodes are evaluated against their proxy plane,
//!   by runs (the pixels of one effective node in a row all have its level; a merged node
//!   has the same run in both rows of a pair `2m`, `2m + 1`: one decode and one certificate
//!   per node and pair of rows, `merged_triggers`); on x86_64 runs of level >= 2 four
//!   pixels per step and two adjacent level-1 runs together, one pixel per lane
//!   (`trigger_lanes`); with AVX2 the pair certificates of the runs of levels 1 to 3 are
//!   taken eight nodes at a time and the scan visits only the runs left, by windows of 64
//!   pixels (`merged_cert`);
//! - a rebuild only recomputes the ancestors of the newly blocked pixels: every other node
//!   has the same children and the same "may merge" answer as before. A recomputed node may
//!   not merge (it covers a blocked pixel), so it is an AABB or empty;
//! - after a rebuild only pixels whose effective level changed are evaluated again: a plane
//!   node that stays effective was not recomputed (recomputed nodes are never planes), so
//!   its pixels keep their trigger depth. Those pixels are found from the recomputed nodes
//!   that were planes (`refill`): no pass over the whole image per iteration.
//!
//! **Invariants:** the blocked set only grows, so the loop ends; level 0 is never changed.

use core::mem::MaybeUninit;

use glam::Vec4;
use rayon::prelude::*;

use super::cascade::{deeper_front, pixel_trigger_lanes, proxy_safe_front};
use super::merge::MergeCtx;
use super::node::NO_PLANE;
use super::node::{Node, decode_plane, decode_plane_at};
use super::prune::Blocked;
use super::tree::{Level, plane_levels};
use crate::LayerPlanes;

/// The levels after pruning to the fixed point, the trigger depths (`W x H`), the plane
/// levels of the final levels (`W x H`, [`plane_levels`]: the effective level, 0 where that
/// is the pixel's own leaf or where it has none), and the unsafe pixels (indices `j W + i` of the
/// finite trigger depths, ascending). `deeper` is not empty; `(tz, listed)`: the trigger
/// depths of the pixel planes and the pixels where they are finite, ascending, and the
/// pixels' deeper fronts (computed with the leaves, [`pixel_triggers_row`] per row);
/// `first`: level 0, and level 1 if the leaf pass made it (the pruning goes on from there).
pub(super) fn fixed_point(
    ctx: &MergeCtx,
    first: Vec<Level>,
    nlev: u32,
    (w, h): (u32, u32),
    deeper: &[LayerPlanes],
    (mut tz, mut listed, fronts): (Vec<f32>, Vec<u32>, Vec<f32>),
) -> (Vec<Level>, Vec<f32>, Vec<u8>, Option<Vec<u32>>) {
    // The pixels with a finite trigger depth are the blocked ones (`listed`). No map of
    // them is needed: a pixel under a merged node is not blocked (its node would not have
    // merged, and the set only grows), and a pixel whose effective node is its own leaf
    // gets the trigger depth of its pixel plane, finite only if it was listed from the start.
    let mut levels = super::prune::prune_from(ctx, first, nlev, Blocked::List(&listed), w, h);
    let mut eff = plane_levels(&levels, w, h);
    if ctx.never {
        return (levels, tz, eff, Some(listed));
    }
    // Trigger depths of the effective planes: the pixel planes' except under merged nodes,
    // which hold no blocked pixel, so only they can be newly unsafe.
    let mut newly = merged_triggers(&mut tz, &fronts, ctx, w, deeper, &levels, &eff);
    // The pixels blocked by the iterations (not in `listed`: they were under merged nodes).
    let mut added: Vec<u32> = Vec::new();
    while !newly.is_empty() {
        added.extend_from_slice(&newly);
        let dissolved = reprune(ctx, &mut levels, &newly, w);
        newly = refill(&mut tz, &mut eff, ctx, (w, h), deeper, &levels, &dissolved);
    }
    // The pixels listed by the leaf pass keep their pixel planes' (finite) trigger depths.
    debug_assert!(listed.iter().all(|&k| tz[k as usize].is_finite()));
    if !added.is_empty() {
        added.sort_unstable();
        // A pixel blocked after a proxy made it unsafe may be safe against its own plane.
        listed = super::mark_listed::merge_finite(&listed, &added, &tz);
    }
    (levels, tz, eff, Some(listed))
}

/// After a rebuild: the effective levels and trigger depths of the pixels under the
/// `dissolved` nodes (recomputed nodes that were planes; `(level, qx, qy)`), and the pixels
/// that became unsafe there and are not yet blocked (under a still-plane child of level >= 1:
/// its pixels are not blocked; a child of level 0 is a pixel whose trigger depth is its
/// pixel plane's, finite only if it is blocked). A dissolved node's ancestors are
/// recomputed too (they are ancestors of the same newly blocked pixels), so they are not
/// planes; each child of a dissolved node that is still a plane (was not recomputed: every
/// child of a plane node is a plane, and recomputed nodes are not) is now the topmost plane
/// over its footprint, i.e. those pixels' effective node — exactly the pixels whose
/// effective level changed (a recomputed node that was not a plane was above every effective
/// node under it).
#[allow(clippy::too_many_arguments)]
fn refill(
    tz: &mut [f32],
    eff: &mut [u8],
    ctx: &MergeCtx,
    (w, h): (u32, u32),
    deeper: &[LayerPlanes],
    levels: &[Level],
    dissolved: &[(u32, u32, u32)],
) -> Vec<u32> {
    // The still-plane children of the dissolved nodes: disjoint footprints.
    let mut kids: Vec<(u32, u32, u32)> = Vec::new();
    for &(l, qx, qy) in dissolved {
        let cl = l - 1;
        let child = &levels[cl as usize];
        for c in 0..4 {
            let (cx, cy) = (2 * qx + (c & 1), 2 * qy + (c >> 1));
            if child.nodes[(cy * child.w + cx) as usize].is_plane() {
                kids.push((cl, cx, cy));
            }
        }
    }
    let (wf, hf) = (ctx.wf, ctx.hf);
    // Per footprint, the pixels' new trigger depths (in parallel), written afterwards.
    let vals: Vec<Vec<(u32, f32)>> = kids
        .par_iter()
        .map(|&(l, qx, qy)| {
            let (x0, y0) = (qx << l, qy << l);
            let (x1, y1) = (((qx + 1) << l).min(w), ((qy + 1) << l).min(h));
            let mut out = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
            // A merged node: one decode for its whole footprint.
            let merged = (l > 0).then(|| {
                let lv = &levels[l as usize];
                decode_plane(lv.nodes[(qy * lv.w + qx) as usize], l, qx, qy, wf, hf)
            });
            for j in y0..y1 {
                let ys = Vec4::new(j as f32, j as f32, (j + 1) as f32, (j + 1) as f32) / hf;
                for i in x0..x1 {
                    let xs = Vec4::new(
                        i as f32 / wf,
                        (i + 1) as f32 / wf,
                        i as f32 / wf,
                        (i + 1) as f32 / wf,
                    );
                    let k = j * w + i;
                    let t = pixel_trigger_lanes(
                        k as usize,
                        xs,
                        ys,
                        || match merged {
                            Some(p) => Some(p),
                            None => pixel_key(levels, i, j)
                                .map(|(node, l, qx, qy)| decode_plane(node, l, qx, qy, wf, hf)),
                        },
                        deeper,
                    );
                    out.push((k, t));
                }
            }
            out
        })
        .collect();
    // A plane node's footprint lies inside the image (padding nodes are empty, and a
    // plane node's descendants are all planes); clipped to it all the same.
    for &(l, qx, qy) in &kids {
        let (x0, y0) = (qx << l, qy << l);
        let (x1, y1) = (((qx + 1) << l).min(w), ((qy + 1) << l).min(h));
        for y in y0..y1 {
            let row = (y * w) as usize;
            eff[row + x0 as usize..row + x1 as usize].fill(l as u8);
        }
    }
    let mut newly = Vec::new();
    for (&(l, _, _), vals) in kids.iter().zip(vals) {
        for (k, t) in vals {
            tz[k as usize] = t;
            if l > 0 && t.is_finite() {
                newly.push(k);
            }
        }
    }
    newly
}

/// Pixel `(i, j)`'s leaf as a key, if it is a plane.
#[inline]
fn pixel_key(levels: &[Level], i: u32, j: u32) -> Option<Key> {
    let node = levels[0].nodes[(j * levels[0].w + i) as usize];
    node.is_plane().then_some((node, 0, i, j))
}

/// A plane node with its level and position.
type Key = (Node, u32, u32, u32);

/// Per-column tables of the trigger passes: the footprints' `x` edges `x0 = i / W`, `x1 =
/// (i + 1) / W` (the definition's divisions, once per column) as the lanes `(x0, x1, x0,
/// x1)` of [`pixel_trigger_lanes`], and the pixel centres `((i + 0.5) 1) / W` of
/// `node_centre` at level 0.
pub(super) struct Columns {
    xs: Vec<Vec4>,
    xc: Vec<f32>,
    /// The edges `i / W`, `i = 0..=W`.
    xe: Vec<f32>,
}

impl Columns {
    pub(super) fn new(w: u32, wf: f32) -> Self {
        let xe: Vec<f32> = (0..=w).map(|i| i as f32 / wf).collect();
        let xs = xe
            .windows(2)
            .map(|e| Vec4::new(e[0], e[1], e[0], e[1]))
            .collect();
        Self {
            xc: (0..w).map(|i| ((i as f32 + 0.5) * 1.0) / wf).collect(),
            xs,
            xe,
        }
    }
}

/// The trigger depths (`tz`, `W x H`, pairs of rows in parallel) of the pixels under merged
/// nodes (plane level `eff > 0`, `W x H`) against `deeper`, from their effective node's decoded
/// plane ([`decode_plane`]); other pixels keep their value. The pixels of one effective node
/// in a row are one run (they all have its level); none of them is blocked (a node over a
/// blocked pixel does not merge). A merged node (level >= 1) covers both
/// rows `2m`, `2m + 1` of a pair with the same run, so the runs are found in the pair's
/// first row and each node's plane is decoded once per pair. A run whose pixels' deeper
/// fronts (`fronts`, [`deeper_front`]) all reach the certificate threshold
/// ([`proxy_safe_front`]) over the node's footprint in both rows is safe against its plane
/// without evaluating its corners: its pixels keep `+inf` (they are not blocked, so their
/// pixel planes' trigger depth is `+inf`). Otherwise each row is done as a row of its own
/// (`merged_run`: the threshold over the row, then groups of four and pixels). Returns the
/// pixels (indices `j W + i`, ascending) that got a finite trigger depth.
#[allow(clippy::too_many_arguments)]
fn merged_triggers(
    tz: &mut [f32],
    fronts: &[f32],
    ctx: &MergeCtx,
    w: u32,
    deeper: &[LayerPlanes],
    levels: &[Level],
    eff: &[u8],
) -> Vec<u32> {
    let cols = Columns::new(w, ctx.wf);
    let (wf, hf) = (ctx.wf, ctx.hf);
    let wu = w as usize;
    // The pair certificates of runs of levels 1 to `MAX_LEVEL` eight nodes at a time in
    // AVX2 lanes (`merged_cert`, the same answers), where the CPU has it.
    #[cfg(target_arch = "x86_64")]
    let lanes = super::merged_cert::available()
        .then(|| super::merged_cert::LevelCols::new(&cols.xe, wf, hf));
    let run = RunCtx {
        cols: &cols,
        wf,
        hf,
        wu,
        deeper,
        levels,
    };
    tz.par_chunks_mut(2 * wu)
        .enumerate()
        .flat_map_iter(|(m, rows)| {
            let j = 2 * m;
            let base = j * wu;
            // Row `j`'s effective levels: its runs of level >= 1 are row `j + 1`'s.
            let er = &eff[j * wu..(j + 1) * wu];
            let (row0, row1) = rows.split_at_mut(wu);
            let fr0 = &fronts[base..base + wu];
            let fr1 = if row1.is_empty() {
                &[][..]
            } else {
                &fronts[base + wu..base + 2 * wu]
            };
            let j = j as u32;
            // The pair's `y` range (row `j`'s alone when it has no second row).
            let y_pair = (
                (j as f32) / hf,
                ((j + 1 + !row1.is_empty() as u32) as f32) / hf,
            );
            let (mut newly0, mut newly1) = (Vec::new(), Vec::new());
            // With AVX2, whole windows of 64 pixels of the pair (up to `lanes_end`) at a
            // time: the pixels still to scan (`todo`: the runs of levels 1 to `MAX_LEVEL`
            // that the lanes did not certify, and the runs of higher levels) of the window
            // that ends at `wend` (`merged_cert::uncertified64`).
            #[cfg(target_arch = "x86_64")]
            let pair = match &lanes {
                Some(lc) if !row1.is_empty() => {
                    super::merged_cert::PairRows::new(levels, lc, j, y_pair, (wf, hf), (fr0, fr1))
                }
                _ => None,
            };
            #[cfg(target_arch = "x86_64")]
            let lanes_end = pair.as_ref().map_or(0, |p| p.end);
            #[cfg(target_arch = "x86_64")]
            let (mut todo, mut wend) = (0u64, 0usize);
            let mut i = 0;
            while i < wu {
                #[cfg(target_arch = "x86_64")]
                if i < lanes_end {
                    if i >= wend {
                        let w0 = i & !63;
                        // SAFETY: `pair` is `Some` only where `available()`; `w0 + 64 <=
                        // lanes_end`.
                        todo = unsafe {
                            super::merged_cert::uncertified64(
                                &er[w0..w0 + 64],
                                pair.as_ref().unwrap(),
                                w0,
                            )
                        };
                        wend = w0 + 64;
                    }
                    // `i` is at a run's end or a window's start: the next pixel to scan is
                    // the start of a run.
                    let w0 = wend - 64;
                    let rest = todo & (u64::MAX << (i - w0));
                    if rest == 0 {
                        i = wend;
                        continue;
                    }
                    i = w0 + rest.trailing_zeros() as usize;
                }
                let l = er[i];
                if l == NO_PLANE || l == 0 {
                    // Eight levels of 0 or `NO_PLANE` at once (each byte `b` is `(b & 1)
                    // 255` then), else one.
                    if i % 8 == 0 && i + 8 <= wu {
                        let v = u64::from_le_bytes(er[i..i + 8].try_into().unwrap());
                        if (v & 0x0101_0101_0101_0101) * 255 == v {
                            i += 8;
                            continue;
                        }
                    }
                    i += 1;
                    continue;
                }
                let l = l as u32;
                let (qx, qy) = (i as u32 >> l, j >> l);
                let lv = &levels[l as usize];
                debug_assert_eq!(i % (1 << l), 0, "a run starts at its node's first column");
                let p = decode_plane(lv.nodes[(qy * lv.w + qx) as usize], l, qx, qy, wf, hf);
                let end = (((qx + 1) << l) as usize).min(wu);
                let t_pair = proxy_safe_front(p, (cols.xe[i], cols.xe[end]), y_pair);
                if certified(&fr0[i..end], t_pair) && certified(&fr1[i..end.min(fr1.len())], t_pair)
                {
                    i = end;
                    continue;
                }
                let next0 = run.merged_run(row0, fr0, er, j, (i, end), (l, qx, qy), p, &mut newly0);
                let next1 = if row1.is_empty() {
                    next0
                } else {
                    run.merged_run(row1, fr1, er, j + 1, (i, end), (l, qx, qy), p, &mut newly1)
                };
                // One row may have done two level-1 runs in lanes where the other's first
                // run was certified: the other row's second run on its own, as that row's
                // scan would have come to it.
                let next = next0.max(next1);
                for (row, fr, jr, next_r, newly) in [
                    (&mut *row0, fr0, j, next0, &mut newly0),
                    (&mut *row1, fr1, j + 1, next1, &mut newly1),
                ] {
                    let mut n = next_r;
                    while n < next {
                        let qx = n as u32 >> l;
                        let p =
                            decode_plane(lv.nodes[(qy * lv.w + qx) as usize], l, qx, qy, wf, hf);
                        let end = (((qx + 1) << l) as usize).min(wu);
                        n = run.merged_run(row, fr, er, jr, (n, end), (l, qx, qy), p, newly);
                    }
                }
                i = next;
            }
            newly0.append(&mut newly1);
            newly0
        })
        .collect()
}

/// What [`merged_triggers`]' rows share.
struct RunCtx<'a> {
    cols: &'a Columns,
    wf: f32,
    hf: f32,
    wu: usize,
    deeper: &'a [LayerPlanes],
    levels: &'a [Level],
}

impl RunCtx<'_> {
    /// The trigger depths of row `j`'s run `i .. end` of the merged node `(l, qx, qy)` with
    /// the decoded plane `p` into `row` (the row's trigger depths; `fr` its deeper fronts,
    /// `er` the effective levels of the pair's first row, whose runs of level >= 1 are this
    /// row's): the run is certified as a whole, then per group of four and per pixel, the
    /// rest evaluated exactly; on x86_64 two level-1 runs starting at a multiple of 4 are
    /// done together in lanes. Pushes the pixels that got a finite trigger depth on `newly`; returns the end of what it did (`end`, or `i + 4` for two level-1
    /// runs).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn merged_run(
        &self,
        row: &mut [f32],
        fr: &[f32],
        er: &[u8],
        j: u32,
        (mut i, end): (usize, usize),
        (l, qx, qy): (u32, u32, u32),
        p: (glam::Vec3, f32),
        newly: &mut Vec<u32>,
    ) -> usize {
        let (cols, wf, hf, wu, deeper) = (self.cols, self.wf, self.hf, self.wu, self.deeper);
        let base = j as usize * wu;
        let ys = Vec4::new(j as f32, j as f32, (j + 1) as f32, (j + 1) as f32) / hf;
        // The row's top and bottom edge (the same f32 quotients as `ys`' lanes).
        let y = (ys.x, ys.z);
        let t_run = proxy_safe_front(p, (cols.xe[i], cols.xe[end]), y);
        if certified(&fr[i..end], t_run) {
            return end;
        }
        // Two runs of two pixels (level 1) starting at a multiple of 4: four pixels in
        // lanes, each pair with its node's plane (`trigger_lanes`, same bits).
        #[cfg(target_arch = "x86_64")]
        if l == 1 && i % 4 == 0 && i + 4 <= wu && er[i + 2] == 1 {
            let lv = &self.levels[l as usize];
            let q = lv.nodes[(qy * lv.w + qx + 1) as usize];
            let pb = decode_plane(q, l, qx + 1, qy, wf, hf);
            let t = super::trigger_lanes::merged_pair_triggers4(
                base + i,
                p,
                pb,
                &cols.xe[i..],
                y,
                deeper,
            );
            store_triggers4(t, base + i, &mut row[i..], newly);
            return i + 4;
        }
        // Runs of 4 pixels or more (levels >= 2, starting at a multiple of 4): four pixels
        // per step in lanes (`trigger_lanes`, same bits).
        #[cfg(target_arch = "x86_64")]
        if l >= 2 {
            while i + 4 <= end {
                if certified(&fr[i..i + 4], t_run) {
                    i += 4;
                    continue;
                }
                let t =
                    super::trigger_lanes::merged_triggers4(base + i, p, &cols.xe[i..], y, deeper);
                store_triggers4(t, base + i, &mut row[i..], newly);
                i += 4;
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = (er, qx, qy, wf, l);
        for (ii, t) in row.iter_mut().enumerate().take(end).skip(i) {
            if fr[ii] >= t_run {
                continue;
            }
            let k = base + ii;
            *t = pixel_trigger_lanes(k, cols.xs[ii], ys, || Some(p), deeper);
            if t.is_finite() {
                newly.push(k as u32);
            }
        }
        end
    }
}

/// Whether every deeper front in `f` reaches `t` (no early exit: vectorised).
#[inline]
fn certified(f: &[f32], t: f32) -> bool {
    f.iter().fold(true, |all, &v| all & (v >= t))
}

/// The pixel planes' trigger depths of row `j` (`tz`, `W` values) from the row's leaves
/// `nodes` (the build runs it right after the row's leaves, while they are in cache), and
/// the row's deeper fronts (`fronts`, [`deeper_front`]); every value of `tz` and `fronts` is
/// written (they may be uninitialised before). Returns the row's pixels with a finite
/// trigger depth.
pub(super) fn pixel_triggers_row(
    tz: &mut [MaybeUninit<f32>],
    fronts: &mut [MaybeUninit<f32>],
    nodes: &[Node],
    j: u32,
    ctx: &MergeCtx,
    cols: &Columns,
    deeper: &[LayerPlanes],
) -> Vec<u32> {
    // Every key differs (one leaf per pixel): no decode cache, the centre from the tables.
    let (wf, hf) = (ctx.wf, ctx.hf);
    let base = j as usize * tz.len();
    let ys = Vec4::new(j as f32, j as f32, (j + 1) as f32, (j + 1) as f32) / hf;
    let yc = ((j as f32 + 0.5) * 1.0) / hf;
    let mut listed = Vec::new();
    // Four pixels per step in lanes (`trigger_lanes`, same bits), the rest one by one.
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    {
        let y = ((j as f32) / hf, ((j + 1) as f32) / hf, yc);
        if super::trigger_avx512::available() {
            // Sixteen pixels per step (`trigger_avx512`, same bits).
            // SAFETY: the CPU has what the kernel needs (checked).
            done = unsafe {
                super::trigger_avx512::pixel_triggers_row16(
                    tz,
                    fronts,
                    nodes,
                    base,
                    &cols.xe,
                    &cols.xc,
                    y,
                    (wf, hf),
                    deeper,
                    &mut listed,
                )
            };
        }
        if std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("f16c")
        {
            // Eight pixels per step (`trigger_avx2`, same bits).
            // SAFETY: the CPU has AVX2 and F16C (checked); the slices from `done` on are
            // the row's rest.
            done += unsafe {
                super::trigger_avx2::pixel_triggers_row8(
                    &mut tz[done..],
                    &mut fronts[done..],
                    &nodes[done..],
                    base + done,
                    &cols.xe[done..],
                    &cols.xc[done..],
                    y,
                    (wf, hf),
                    deeper,
                    &mut listed,
                )
            };
        }
        while done + 4 <= tz.len() {
            let i = done;
            let (t, f) = super::trigger_lanes::pixel_triggers4(
                base + i,
                &nodes[i..],
                &cols.xe[i..],
                &cols.xc[i..],
                y,
                (wf, hf),
                deeper,
            );
            for (d, v) in f.to_array().into_iter().enumerate() {
                fronts[i + d].write(v);
            }
            for (d, v) in t.to_array().into_iter().enumerate() {
                tz[i + d].write(v);
                if v.is_finite() {
                    listed.push((base + i + d) as u32);
                }
            }
            done += 4;
        }
    }
    for (i, ((t, &node), (&xs, &xc))) in tz
        .iter_mut()
        .zip(nodes)
        .zip(cols.xs.iter().zip(&cols.xc))
        .enumerate()
        .skip(done)
    {
        let k = base + i;
        let t = *t.write(pixel_trigger_lanes(
            k,
            xs,
            ys,
            || {
                node.is_plane()
                    .then(|| decode_plane_at(node, 0, xc, yc, wf, hf))
            },
            deeper,
        ));
        if t.is_finite() {
            listed.push(k as u32);
        }
        fronts[i].write(deeper_front(
            k,
            (cols.xe[i], cols.xe[i + 1], ys.x, ys.z),
            deeper,
        ));
    }
    listed
}

/// Recomputes the ancestors of the pixels `newly` (indices `j W + i`, just blocked) level by
/// level, bottom-up; none of them may merge. Returns the recomputed nodes that were planes
/// before (`(level, qx, qy)`).
fn reprune(ctx: &MergeCtx, levels: &mut [Level], newly: &[u32], w: u32) -> Vec<(u32, u32, u32)> {
    let mut dissolved = Vec::new();
    let mut cur: Vec<(u32, u32)> = newly.iter().map(|&k| (k / w, k % w)).collect();
    for l in 1..levels.len() {
        let mut next: Vec<(u32, u32)> = cur.iter().map(|&(y, x)| (y >> 1, x >> 1)).collect();
        next.sort_unstable();
        next.dedup();
        let (lo, hi) = levels.split_at_mut(l);
        let (child, par) = (&lo[l - 1], &mut hi[0]);
        for &(qy, qx) in &next {
            let node = &mut par.nodes[(qy * par.w + qx) as usize];
            if node.is_plane() {
                dissolved.push((l as u32, qx, qy));
            }
            *node = super::prune::parent_of(ctx, child, l as u32, qx, qy, false);
        }
        cur = next;
    }
    dissolved
}

/// Stores four lanes' trigger depths of pixels `k0..k0 + 4` in `row[..4]` and lists those
/// that became finite (newly blocked).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn store_triggers4(t: glam::Vec4, k0: usize, row: &mut [f32], newly: &mut Vec<u32>) {
    for (d, v) in t.to_array().into_iter().enumerate() {
        row[d] = v;
        if v.is_finite() {
            newly.push((k0 + d) as u32);
        }
    }
}
