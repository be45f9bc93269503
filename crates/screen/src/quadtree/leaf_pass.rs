//! The build's leaf pass with level 1 (x86_64, two levels or more; Widmer et al. 2015,
//! §3.2 leaves and §3.3 pruning): the leaves are made by pairs of pixel rows, and level-1
//! row `m` right after the leaves of its two child rows `2m`, `2m + 1`, while they are in
//! cache, by the row kernel of the pruning (`MergeCtx::parent_row_fast_of`) — the nodes of
//! [`super::prune::prune`]'s level 1, so the pruning goes on from level 2 without reading
//! level 0 again. Without deeper layers no pixel is blocked (`leaves_with_level1`); with
//! them (the cascade's fixed point, [`super::fixpoint`]) each row's pixel-plane trigger
//! depths follow its leaves and the level-1 parents over a listed pixel do not merge
//! (`leaves_and_level1`).

use rayon::prelude::*;

use super::merge::MergeCtx;
use super::node::Node;
use super::tree::{Level, init_row};
use crate::LayerPlanes;

/// The fixed point's leaf pass with level 1 (x86_64, two levels or more): per pair of pixel
/// rows `2m`, `2m + 1` of `image` (level 0's image rows, padded width `w0`), the rows' leaves
/// (`leaf_row`) and their pixel-plane trigger depths and deeper fronts
/// ([`super::fixpoint::pixel_triggers_row`]), then level-1 row `m` from them while they are in
/// cache — the nodes of [`super::prune::prune`]'s level 1 with the same blocked pixels (the
/// pair's listed ones), by the same row kernel. Returns level 1 (`w0 / 2 x h0 / 2`, padding
/// rows empty) and `(tz, listed, fronts)` as the row-by-row pass makes them.
#[allow(clippy::type_complexity)]
pub(super) fn leaves_and_level1(
    image: &mut [core::mem::MaybeUninit<Node>],
    (w, h, w0, h0): (u32, u32, u32, u32),
    ctx: &MergeCtx,
    deeper: &[LayerPlanes],
    leaf_row: &(impl Fn(&mut [Node], u32) + Sync),
) -> (Level, (Vec<f32>, Vec<u32>, Vec<f32>)) {
    let (wu, w0u, n_px) = (w as usize, w0 as usize, (w * h) as usize);
    let (pw, ph) = (w0u / 2, (h0 / 2) as usize);
    // Level-1 rows and columns over the image; the other rows are padding (empty).
    let (ih, iw) = ((h as usize).div_ceil(2), wu.div_ceil(2));
    let cols = super::fixpoint::Columns::new(w, ctx.wf);
    let (mut tz, mut fronts) = (Vec::with_capacity(n_px), Vec::with_capacity(n_px));
    let mut l1: Vec<Node> = Vec::with_capacity(pw * ph);
    let (l1_img, l1_pad) = l1.spare_capacity_mut()[..pw * ph].split_at_mut(ih * pw);
    l1_pad.par_chunks_mut(pw).for_each(|row| {
        init_row(row, Node::EMPTY);
    });
    // The second child row of the last pair when `h` is odd: a padding row (empty).
    let empty = vec![Node::EMPTY; if h % 2 == 1 { w0u } else { 0 }];
    let listed: Vec<u32> = image
        .par_chunks_mut(2 * w0u)
        .zip(tz.spare_capacity_mut()[..n_px].par_chunks_mut(2 * wu))
        .zip(fronts.spare_capacity_mut()[..n_px].par_chunks_mut(2 * wu))
        .zip(l1_img.par_chunks_mut(pw))
        .enumerate()
        .flat_map_iter(|(m, (((rows, t), f), out))| {
            let j0 = 2 * m as u32;
            let (r0, r1) = rows.split_at_mut(w0u);
            let ((t0, t1), (f0, f1)) = (t.split_at_mut(wu), f.split_at_mut(wu));
            let r0 = init_row(r0, Node::EMPTY);
            leaf_row(r0, j0);
            let pt = |t, f, row: &[Node], j| {
                super::fixpoint::pixel_triggers_row(t, f, row, j, ctx, &cols, deeper)
            };
            let mut listed = pt(t0, f0, r0, j0);
            if !r1.is_empty() {
                let r1 = init_row(r1, Node::EMPTY);
                leaf_row(r1, j0 + 1);
                listed.append(&mut pt(t1, f1, r1, j0 + 1));
            }
            // Level-1 row `m`: its parents over a listed pixel do not merge.
            let mut blocked = vec![false; pw];
            let base = j0 as usize * wu;
            for &k in &listed {
                let d = k as usize - base;
                blocked[(if d >= wu { d - wu } else { d }) >> 1] = true;
            }
            let allow = super::prune::Allow(Some(&blocked));
            level1_row(ctx, rows, &empty, m as u32, out, iw.min(pw), allow);
            listed
        })
        .collect();
    // SAFETY: the pairs cover `0..n_px` (`pixel_triggers_row` wrote every value) and level
    // 1's image rows; the padding rows were initialised above.
    unsafe {
        tz.set_len(n_px);
        fronts.set_len(n_px);
        l1.set_len(pw * ph);
    }
    let level1 = Level {
        w: pw as u32,
        h: ph as u32,
        nodes: l1,
    };
    (level1, (tz, listed, fronts))
}

/// Level-1 row `m` into `out` (its image parents; `out` is the whole row, uninitialised,
/// set empty first) from the pair of initialised level-0 rows `rows` (`2 w0` nodes, or
/// `w0` for the last pair of an odd height, completed by the empty row `empty`).
fn level1_row(
    ctx: &MergeCtx,
    rows: &[core::mem::MaybeUninit<Node>],
    empty: &[Node],
    m: u32,
    out: &mut [core::mem::MaybeUninit<Node>],
    iw: usize,
    allow: super::prune::Allow,
) {
    // SAFETY: both rows of the pair were initialised (`init_row`).
    let two = unsafe { &*(rows as *const [_] as *const [Node]) };
    let scratch;
    // A short pair is one row, as long as `empty`; a full pair is twice as long.
    let two = if two.len() != empty.len() {
        two
    } else {
        scratch = [two, empty].concat();
        &scratch[..]
    };
    let out = init_row(out, Node::EMPTY);
    ctx.parent_row_fast_of(two, 1, m, &mut out[..iw], allow);
}

/// The 1-layer build's leaf pass with level 1 (x86_64, two levels or more): per pair of
/// pixel rows of `image` (level 0's image rows, padded width `w0`) the rows' leaves
/// (`leaf_row`), then level-1 row `m` from them while they are in cache (no blocked pixel:
/// the nodes of [`super::prune::prune`]'s level 1, by the same row kernel). Returns level 1
/// (`w0 / 2 x h0 / 2`, padding rows empty).
pub(super) fn leaves_with_level1(
    image: &mut [core::mem::MaybeUninit<Node>],
    (w, h, w0, h0): (u32, u32, u32, u32),
    ctx: &MergeCtx,
    leaf_row: &(impl Fn(&mut [Node], u32) + Sync),
) -> Level {
    let w0u = w0 as usize;
    let (pw, ph) = (w0u / 2, (h0 / 2) as usize);
    let (ih, iw) = ((h as usize).div_ceil(2), (w as usize).div_ceil(2));
    let mut l1: Vec<Node> = Vec::with_capacity(pw * ph);
    let (l1_img, l1_pad) = l1.spare_capacity_mut()[..pw * ph].split_at_mut(ih * pw);
    l1_pad.par_chunks_mut(pw).for_each(|row| {
        init_row(row, Node::EMPTY);
    });
    let empty = vec![Node::EMPTY; if h % 2 == 1 { w0u } else { 0 }];
    image
        .par_chunks_mut(2 * w0u)
        .zip(l1_img.par_chunks_mut(pw))
        .enumerate()
        .for_each(|(m, (rows, out))| {
            let j0 = 2 * m as u32;
            let (r0, r1) = rows.split_at_mut(w0u);
            leaf_row(init_row(r0, Node::EMPTY), j0);
            if !r1.is_empty() {
                leaf_row(init_row(r1, Node::EMPTY), j0 + 1);
            }
            let allow = super::prune::Allow(None);
            level1_row(ctx, rows, &empty, m as u32, out, iw.min(pw), allow);
        });
    // SAFETY: the pairs cover level 1's image rows; the padding rows were initialised above.
    unsafe { l1.set_len(pw * ph) };
    Level {
        w: pw as u32,
        h: ph as u32,
        nodes: l1,
    }
}
