//! The leaves and the lowest pruning levels of one layer's quad-tree (Widmer et al. 2015,
//! §3.2-3.3) in bands of rows: one parallel task per band of `2^k` pixel rows writes the
//! band's leaves (and whatever the caller computes per leaf row, e.g. the cascade's
//! pixel-plane trigger depths) and then its parents at levels `1..=k`, each level's rows from
//! the band's rows of the level below while they are still in cache. The levels above `k`
//! are pruned level by level as before (`prune::prune_from`).
//!
//! The nodes are those of the level-by-level build: a level-0 row is set empty and then
//! gets its leaves (padding rows stay empty); a parent row is set empty and, if it lies over
//! the image, its first `ceil(W / 2^l)` parents are computed by
//! [`MergeCtx::parent_row_fast`] from the same two child rows with the same blocked flags
//! (a parent is blocked when one of the band's listed pixels lies in its footprint — the
//! listed pixels of a band are the only ones under its parents, since bands are unions of
//! whole footprints at every level `<= k`). Only the order in which rows are computed
//! changes, so the trees are the same bit for bit (`tests/quadtree_build.rs`).

use core::mem::MaybeUninit;

use rayon::prelude::*;

use super::fixpoint::{Columns, fixed_point, pixel_triggers_row};
use super::merge::MergeCtx;
use super::node::Node;
use super::prune::{Allow, Blocked, prune_from};
use super::tree::{Level, init_row};
use crate::LayerPlanes;

/// Levels below this many levels from the top and at most `2^BAND_LEVELS` pixel rows per
/// band: a band's level-0 rows (`2^4 x W0` nodes, 224 KiB at `W0 = 1792`) stay in L2 until
/// its level-1 rows read them.
pub(super) const BAND_LEVELS: u32 = 4;

/// Levels `0..=k` of a `w x h` layer padded to `w0 x h0` (`h0` a multiple of `2^k`), and the
/// listed pixels (indices `j w + i`, ascending) that `leaf_row` reported; a listed pixel
/// blocks its ancestors from merging. `leaf_row(e, r, row, j, listed)` writes the leaves of
/// image row `j` (row `r` of its band) into the first `w` nodes of `row` (set empty), given
/// the band's item of `extra` (one per band, `h0 / 2^k` of them), and appends the row's
/// listed pixels in ascending order. Lane kernels only (`ctx.lanes`, x86_64).
pub(super) fn low_levels<E: Send>(
    ctx: &MergeCtx,
    (w, h): (u32, u32),
    (w0, h0): (u32, u32),
    k: u32,
    extra: Vec<E>,
    leaf_row: impl Fn(&mut E, u32, &mut [Node], u32, &mut Vec<u32>) + Sync,
) -> (Vec<Level>, Vec<u32>) {
    let band = 1usize << k;
    let nb = h0 as usize >> k;
    assert_eq!(nb << k, h0 as usize, "bands cover the padded level 0");
    assert_eq!(extra.len(), nb, "one extra item per band");
    let dims: Vec<(usize, usize)> = (0..=k)
        .map(|l| ((w0 >> l) as usize, (h0 >> l) as usize))
        .collect();
    let mut vecs: Vec<Vec<Node>> = dims
        .iter()
        .map(|&(lw, lh)| Vec::with_capacity(lw * lh))
        .collect();
    // Per band, its rows of every level (disjoint chunks of the levels' spare capacity).
    let mut per_band: Vec<Vec<&mut [MaybeUninit<Node>]>> = (0..nb)
        .map(|_| Vec::with_capacity(k as usize + 1))
        .collect();
    for (l, v) in vecs.iter_mut().enumerate() {
        let (lw, lh) = dims[l];
        let chunk = lw * (band >> l);
        for (b, c) in v.spare_capacity_mut()[..lw * lh]
            .chunks_mut(chunk)
            .enumerate()
        {
            per_band[b].push(c);
        }
    }
    let listed_per_band: Vec<Vec<u32>> = per_band
        .into_par_iter()
        .zip(extra)
        .enumerate()
        .map(|(b, (mut s, mut e))| {
            let mut listed = Vec::new();
            let mut done: Vec<&mut [Node]> = Vec::with_capacity(k as usize + 1);
            // Level 0: each row set empty in cache right before its leaves.
            let l0 = core::mem::take(&mut s[0]);
            let w0 = w0 as usize;
            for (r, row) in l0.chunks_mut(w0).enumerate() {
                let j = (b * band + r) as u32;
                let row = init_row(row, Node::EMPTY);
                if j < h {
                    leaf_row(&mut e, r as u32, row, j, &mut listed);
                }
            }
            // SAFETY: every row of `l0` was initialised by `init_row`; `MaybeUninit<Node>`
            // has `Node`'s layout.
            done.push(unsafe { &mut *(l0 as *mut [MaybeUninit<Node>] as *mut [Node]) });
            let mut flags: Vec<bool> = Vec::new();
            for l in 1..=k {
                let (pw, cw) = (dims[l as usize].0, dims[l as usize - 1].0);
                let rows = band >> l;
                let q0 = b * rows;
                // The parents over the image; the others stay empty (only padding below).
                let (iw, ih) = (((w - 1) >> l) as usize + 1, ((h - 1) >> l) as usize + 1);
                if !listed.is_empty() {
                    flags.clear();
                    flags.resize(rows * pw, false);
                    for &p in &listed {
                        let (x, y) = ((p % w) as usize, (p / w) as usize);
                        flags[((y >> l) - q0) * pw + (x >> l)] = true;
                    }
                }
                let parents = init_row(core::mem::take(&mut s[l as usize]), Node::EMPTY);
                let child: &[Node] = &*done[l as usize - 1];
                for (rr, row) in parents.chunks_mut(pw).enumerate() {
                    let qy = q0 + rr;
                    if qy >= ih {
                        break;
                    }
                    let c = &child[2 * rr * cw..(2 * rr + 2) * cw];
                    let allow = Allow((!listed.is_empty()).then(|| &flags[rr * pw..(rr + 1) * pw]));
                    let n = iw.min(pw);
                    ctx.parent_row_fast(c.split_at(cw), l, qy as u32, &mut row[..n], allow);
                }
                done.push(parents);
            }
            listed
        })
        .collect();
    // SAFETY: the bands' chunks cover each level's `lw x lh` nodes, all initialised above.
    let levels = vecs
        .into_iter()
        .zip(&dims)
        .map(|(mut nodes, &(lw, lh))| {
            unsafe { nodes.set_len(lw * lh) };
            Level {
                w: lw as u32,
                h: lh as u32,
                nodes,
            }
        })
        .collect();
    (levels, listed_per_band.concat())
}

/// The levels, trigger depths, plane levels and unsafe pixels of one layer (the fast path
/// of `QuadTree::build_cascaded`): levels `0..=k` in bands ([`low_levels`]; with `deeper`
/// layers each leaf row's pixel-plane trigger depths right after its leaves, and its
/// unsafe pixels block their ancestors), the levels above by [`prune_from`], and with
/// `deeper` layers the pruning fixed point ([`super::fixpoint::fixed_point`]).
pub(super) fn banded(
    ctx: &MergeCtx,
    (w, h): (u32, u32),
    (w0, h0): (u32, u32),
    nlev: u32,
    deeper: &[LayerPlanes],
    leaf_row: &(impl Fn(&mut [Node], u32) + Sync),
) -> (Vec<Level>, Vec<f32>, Vec<u8>, Option<Vec<u32>>) {
    let k = BAND_LEVELS.min(nlev - 1);
    let (band, nb) = (1usize << k, (h0 >> k) as usize);
    if deeper.is_empty() {
        let (low, _) = low_levels(ctx, (w, h), (w0, h0), k, vec![(); nb], |_, _, row, j, _| {
            leaf_row(row, j)
        });
        let levels = prune_from(ctx, low, nlev, Blocked::None, w, h);
        return (levels, Vec::new(), Vec::new(), None);
    }
    let (n_px, wu) = ((w * h) as usize, w as usize);
    let cols = Columns::new(w, ctx.wf);
    // Every value is written by the row pass (`pixel_triggers_row`).
    let (mut tz, mut fronts) = (Vec::with_capacity(n_px), Vec::with_capacity(n_px));
    let mut extra: Vec<(&mut [MaybeUninit<f32>], &mut [MaybeUninit<f32>])> = tz
        .spare_capacity_mut()[..n_px]
        .chunks_mut(band * wu)
        .zip(fronts.spare_capacity_mut()[..n_px].chunks_mut(band * wu))
        .collect();
    // Bands of padding rows only: no trigger depths.
    extra.resize_with(nb, Default::default);
    let (low, listed) = low_levels(
        ctx,
        (w, h),
        (w0, h0),
        k,
        extra,
        |(t, f), r, row, j, listed| {
            let r = r as usize;
            let (t, f) = (&mut t[r * wu..(r + 1) * wu], &mut f[r * wu..(r + 1) * wu]);
            leaf_row(row, j);
            listed.extend(pixel_triggers_row(t, f, row, j, ctx, &cols, deeper));
        },
    );
    // SAFETY: the bands' rows cover `0..n_px` and `pixel_triggers_row` wrote every value.
    unsafe {
        tz.set_len(n_px);
        fronts.set_len(n_px);
    }
    fixed_point(ctx, low, nlev, (w, h), deeper, (tz, listed, fronts))
}
