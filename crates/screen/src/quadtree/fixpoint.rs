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
//! - the pixel planes are decoded from the level-0 nodes where they are needed, not copied
//!   into a [`LayerPlanes`] first, and each pixel's four footprint corners are evaluated in
//!   lanes ([`super::cascade::pixel_trigger_lanes`]);
//! - a pixel whose effective node is its own leaf (level 0) or none has the pixel planes'
//!   trigger depth: only pixels under merged nodes are evaluated against their proxy plane
//!   (decoded once per run of a row);
//! - a rebuild only recomputes the ancestors of the newly blocked pixels: every other node
//!   has the same children and the same "may merge" answer as before. A recomputed node may
//!   not merge (it covers a blocked pixel), so it is an AABB or empty;
//! - after a rebuild only pixels whose effective level changed are evaluated again: a plane
//!   node that stays effective was not recomputed (recomputed nodes are never planes), so
//!   its pixels keep their trigger depth.
//!
//! **Invariants:** the blocked set only grows, so the loop ends; level 0 is never changed.

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::cascade::pixel_trigger_lanes;
use super::merge::MergeCtx;
use super::node::{Node, decode_plane};
use super::tree::{Level, NO_PLANE, effective_levels};
use crate::LayerPlanes;

/// The levels after pruning to the fixed point, the trigger depths (`W x H`) and the
/// effective levels of the final levels (`levels[0].w x levels[0].h`,
/// [`super::QuadTree::effective_levels`]). `deeper` is not empty.
pub(super) fn fixed_point(
    ctx: &MergeCtx,
    level0: Level,
    nlev: u32,
    (w, h): (u32, u32),
    deeper: &[LayerPlanes],
) -> (Vec<Level>, Vec<f32>, Vec<u8>) {
    let mut tz_px = vec![f32::INFINITY; (w * h) as usize];
    let l0 = std::slice::from_ref(&level0);
    fill_triggers(&mut tz_px, ctx, w, deeper, |i, j| Some(pixel_key(l0, i, j)));
    let mut blocked: Vec<bool> = tz_px.iter().map(|z| z.is_finite()).collect();
    let mut levels = super::prune::prune(ctx, level0, nlev, &blocked, w, h);
    let mut eff = effective_levels(&levels);
    if ctx.never {
        return (levels, tz_px, eff);
    }
    // Trigger depths of the effective planes: the pixel planes' except under merged nodes.
    let mut tz = tz_px.clone();
    let w0 = levels[0].w;
    fill_triggers(&mut tz, ctx, w, deeper, |i, j| {
        let l = eff[(j * w0 + i) as usize];
        (l != NO_PLANE && l > 0).then(|| Some(ancestor_key(&levels, l, i, j)))
    });
    loop {
        let newly: Vec<u32> = (0..w * h)
            .filter(|&k| tz[k as usize].is_finite() && !blocked[k as usize])
            .collect();
        if newly.is_empty() {
            return (levels, tz, eff);
        }
        for &k in &newly {
            blocked[k as usize] = true;
        }
        reprune(ctx, &mut levels, &newly, w);
        let prev = std::mem::replace(&mut eff, effective_levels(&levels));
        let (levels, eff) = (&levels, &eff);
        fill_triggers(&mut tz, ctx, w, deeper, |i, j| {
            let k = (j * w0 + i) as usize;
            let l = eff[k];
            if l == prev[k] {
                None
            } else if l == NO_PLANE || l == 0 {
                // Its own leaf again: the pixel plane's trigger depth (same computation).
                Some(pixel_key(levels, i, j))
            } else {
                Some(Some(ancestor_key(levels, l, i, j)))
            }
        });
    }
}

/// Pixel `(i, j)`'s leaf as a [`fill_triggers`] key, if it is a plane.
#[inline]
fn pixel_key(levels: &[Level], i: u32, j: u32) -> Option<Key> {
    let node = levels[0].nodes[(j * levels[0].w + i) as usize];
    node.is_plane().then_some((node, 0, i, j))
}

/// Pixel `(i, j)`'s ancestor at level `l` (a plane node) as a [`fill_triggers`] key.
#[inline]
fn ancestor_key(levels: &[Level], l: u8, i: u32, j: u32) -> Key {
    let l = l as u32;
    let (qx, qy) = (i >> l, j >> l);
    let lv = &levels[l as usize];
    (lv.nodes[(qy * lv.w + qx) as usize], l, qx, qy)
}

/// A plane node with its level and position.
type Key = (Node, u32, u32, u32);

/// Per pixel `(i, j)` of `tz` (`W x H`, rows in parallel) with `plane(i, j) = Some(p)`: the
/// trigger depth of the decoded plane of node `p` ([`decode_plane`]; `None`: empty) at that
/// pixel against `deeper`; pixels where `plane` answers `None` keep their value. A node
/// covering a run of a row is decoded once (the decode is a function of the key).
fn fill_triggers(
    tz: &mut [f32],
    ctx: &MergeCtx,
    w: u32,
    deeper: &[LayerPlanes],
    plane: impl Fn(u32, u32) -> Option<Option<Key>> + Sync,
) {
    let (wf, hf) = (ctx.wf, ctx.hf);
    // The footprints' `x` edges, `i / W` (the definition's divisions, once per column).
    let xe: Vec<f32> = (0..=w).map(|i| i as f32 / wf).collect();
    tz.par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(j, row)| {
            let j = j as u32;
            let ys = Vec4::new(j as f32, j as f32, (j + 1) as f32, (j + 1) as f32) / hf;
            let mut last: Option<(Key, (Vec3, f32))> = None;
            for (i, t) in row.iter_mut().enumerate() {
                let i = i as u32;
                let Some(key) = plane(i, j) else {
                    continue;
                };
                let p = key.map(|key| match last {
                    Some((k, p)) if k == key => p,
                    _ => {
                        let (node, l, qx, qy) = key;
                        let p = decode_plane(node, l, qx, qy, wf, hf);
                        last = Some((key, p));
                        p
                    }
                });
                let (x0, x1) = (xe[i as usize], xe[i as usize + 1]);
                let xs = Vec4::new(x0, x1, x0, x1);
                *t = pixel_trigger_lanes((j * w + i) as usize, xs, ys, p, deeper);
            }
        });
}

/// Recomputes the ancestors of the pixels `newly` (indices `j W + i`, just blocked) level by
/// level, bottom-up; none of them may merge.
fn reprune(ctx: &MergeCtx, levels: &mut [Level], newly: &[u32], w: u32) {
    let mut cur: Vec<(u32, u32)> = newly.iter().map(|&k| (k / w, k % w)).collect();
    for l in 1..levels.len() {
        let mut next: Vec<(u32, u32)> = cur.iter().map(|&(y, x)| (y >> 1, x >> 1)).collect();
        next.sort_unstable();
        next.dedup();
        let (lo, hi) = levels.split_at_mut(l);
        let (child, par) = (&lo[l - 1], &mut hi[0]);
        for &(qy, qx) in &next {
            par.nodes[(qy * par.w + qx) as usize] =
                super::prune::parent_of(ctx, child, l as u32, qx, qy, false);
        }
        cur = next;
    }
}
