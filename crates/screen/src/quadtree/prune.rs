//! Bottom-up pruning of a whole tree (Widmer et al. 2015, §3.3): the levels above the
//! leaves, one [`MergeCtx::parent`] per node, in parallel over rows; and the cascade's
//! pruning fixed point by its definition (the slow twin of [`super::fixpoint`]). The lane
//! kernels learn which parents of a row may merge from the row's blocked flags ([`Allow`],
//! eight parents at a time by one multiplication).
//!
//! **Invariants:** a node containing a blocked pixel never merges; level 0 is not changed;
//! a node over padding only (beyond `ceil(W / 2^l) x ceil(H / 2^l)` at level `l`) is
//! empty, so the fast path writes it without reading its children.

use rayon::prelude::*;

use super::merge::MergeCtx;
use super::node::{NO_PLANE, Node};
use super::tree::{Level, decoded_planes, effective_levels, par_rows};
use crate::LayerPlanes;

/// The cascade's pruning fixed point by its definition (the slow twin of
/// [`super::fixpoint::fixed_point`], same results): trigger depths from the pixel planes
/// block merging over unsafe pixels. Pixels (`W x H`) no node may merge over are seeded with
/// the pixel-plane analysis, then grown to a fixed point: a merged proxy plane deviates from
/// its pixels' own planes by up to the merge tolerance (§3.3, `gamma_dist`, far above the
/// safety margin), so a pixel safe against its own plane can be unsafe against the proxy
/// the traversal tests (a deeper plane in front of it: found by proptest,
/// `quadtree_cascade.rs`). Such pixels are blocked too and the levels rebuilt; the set only
/// grows, so this ends (in practice after one extra pass, or none). Returns the levels, the
/// trigger depths and the plane levels (`W x H`: the effective level of every pixel by the
/// top-down definition, 0 where that is its own leaf or where it has none).
pub(super) fn fixed_point_reference(
    ctx: &MergeCtx,
    level0: Level,
    nlev: u32,
    (w, h): (u32, u32),
    deeper: &[LayerPlanes],
) -> (Vec<Level>, Vec<f32>, Vec<u8>) {
    let tz = {
        let px = leaf_planes(&level0, w, h, ctx.wf, ctx.hf);
        super::cascade::trigger_depths(&px, deeper)
    };
    let mut blocked_px: Vec<bool> = tz.iter().map(|z| z.is_finite()).collect();
    let mut first = Some(level0);
    let mut levels: Vec<Level> = Vec::new();
    let tz = loop {
        // Level 0 is never changed by pruning: reuse it on a rebuild.
        let l0 = first
            .take()
            .unwrap_or_else(|| std::mem::take(&mut levels).swap_remove(0));
        levels = prune(ctx, l0, nlev, Blocked::Pixels(&blocked_px), w, h);
        if ctx.never {
            // No merging: the effective planes are the pixel planes.
            break tz;
        }
        let eff = decoded_planes(w, h, ctx.wf, ctx.hf, super::tree::no_rows, |i, j| {
            let n0 = levels[0].nodes[(j * levels[0].w + i) as usize];
            if !n0.is_plane() {
                return None;
            }
            let mut best = (n0, 0u32, i, j);
            for (l, lv) in levels.iter().enumerate().skip(1) {
                let (qx, qy) = (i >> l, j >> l);
                let n = lv.nodes[(qy * lv.w + qx) as usize];
                if !n.is_plane() {
                    break;
                }
                best = (n, l as u32, qx, qy);
            }
            Some(best)
        });
        let tz_eff = super::cascade::trigger_depths(&eff, deeper);
        let mut grew = false;
        for (b, z) in blocked_px.iter_mut().zip(&tz_eff) {
            if z.is_finite() && !*b {
                *b = true;
                grew = true;
            }
        }
        if !grew {
            // Every unsafe pixel is blocked, i.e. its effective plane is its pixel
            // plane, and `tz_eff` was computed from the planes the traversal tests.
            break tz_eff;
        }
    };
    let eff = effective_levels(&levels);
    let w0 = levels[0].w as usize;
    let plane_level = par_rows((w * h) as usize, w as usize, 0u8, |j, row| {
        for (v, &l) in row.iter_mut().zip(&eff[j * w0..]) {
            *v = if l == NO_PLANE { 0 } else { l };
        }
    });
    (levels, tz, plane_level)
}

/// Node `(qx, qy)` at level `l` from its four children in `child` (level `l - 1`), merged
/// only if `allow` (§3.3, [`MergeCtx::parent`]).
#[inline]
pub(super) fn parent_of(
    ctx: &MergeCtx,
    child: &Level,
    l: u32,
    qx: u32,
    qy: u32,
    allow: bool,
) -> Node {
    let cl = l - 1;
    let mut kids = [Node::EMPTY; 4];
    let mut pos = [(0u32, 0u32); 4];
    for (c, (kid, p)) in kids.iter_mut().zip(pos.iter_mut()).enumerate() {
        let (cx, cy) = (2 * qx + (c as u32 & 1), 2 * qy + (c as u32 >> 1));
        *p = (cx, cy);
        *kid = child.nodes[(cy * child.w + cx) as usize];
    }
    ctx.parent(l, qx, qy, cl, &kids, &pos, allow)
}

/// Which parents of one row may merge (contain no blocked pixel): all (`None`), or those
/// whose flag in the row's blocked flags (one `bool` per parent of the level's row, parent
/// `qx` at index `qx`) is false.
#[derive(Clone, Copy)]
pub(super) struct Allow<'a>(pub(super) Option<&'a [bool]>);

impl Allow<'_> {
    /// Whether parent `qx` may merge.
    #[inline(always)]
    pub(super) fn get(self, qx: u32) -> bool {
        self.0.is_none_or(|b| !b[qx as usize])
    }

    /// Bit `p` (`p < 8`) set iff parent `qx0 + p` may merge (bits of parents beyond the row:
    /// set). Eight flags are one little-endian `u64` of 0 / 1 bytes; the product by
    /// `0x0102_0408_1020_4080` puts byte `i`'s bit at bit `56 + i` (its terms `2^(8i + 7j +
    /// 7)` have distinct exponents, so nothing carries).
    #[inline(always)]
    pub(super) fn mask8(self, qx0: usize) -> u32 {
        let Some(b) = self.0 else { return 0xff };
        if let Some(eight) = b.get(qx0..qx0 + 8) {
            let eight: &[bool; 8] = eight.try_into().expect("eight flags");
            let v = u64::from_le_bytes(eight.map(u8::from));
            let blocked = (v & 0x0101_0101_0101_0101).wrapping_mul(0x0102_0408_1020_4080) >> 56;
            return !(blocked as u32) & 0xff;
        }
        (0..8).fold(0, |m, p| {
            m | (u32::from(b.get(qx0 + p).is_none_or(|&x| !x)) << p)
        })
    }
}

/// The pixels (of a `W x H` layer) no node may merge over.
#[derive(Clone, Copy)]
pub(super) enum Blocked<'a> {
    /// None.
    None,
    /// Per pixel, whether it is blocked (the definition: every node scans its pixels).
    Pixels(&'a [bool]),
    /// The blocked pixels' indices `j W + i` (any order): each marks its ancestors.
    List(&'a [u32]),
}

/// Levels `0..nlev` of a tree: `level0` and the levels built from it by pruning (§3.3),
/// never merging a node that contains a blocked pixel.
pub(super) fn prune(
    ctx: &MergeCtx,
    level0: Level,
    nlev: u32,
    blocked_px: Blocked,
    w: u32,
    h: u32,
) -> Vec<Level> {
    prune_from(ctx, vec![level0], nlev, blocked_px, w, h)
}

/// [`prune`] continued from its first levels `levels` (level 0 and possibly more, built as
/// [`prune`] builds them; more than level 0 only with [`Blocked::None`] or
/// [`Blocked::List`]): the levels `levels.len()..nlev` added.
pub(super) fn prune_from(
    ctx: &MergeCtx,
    mut levels: Vec<Level>,
    nlev: u32,
    blocked_px: Blocked,
    w: u32,
    h: u32,
) -> Vec<Level> {
    debug_assert!(levels.len() == 1 || !matches!(blocked_px, Blocked::Pixels(_)));
    let mut blocked: Vec<bool> = Vec::new();
    // The listed pixels' coordinates, one division each (not one per level).
    let xy: Vec<(u32, u32)> = match blocked_px {
        Blocked::List(px) => px.iter().map(|&k| (k % w, k / w)).collect(),
        _ => Vec::new(),
    };
    for l in levels.len() as u32..nlev {
        let child = levels.last().unwrap();
        let (pw, ph) = (child.w / 2, child.h / 2);
        match blocked_px {
            Blocked::None => {}
            Blocked::Pixels(blocked_px) => {
                // A node is blocked when one of its children is (level 1: an image pixel).
                let mut next = vec![false; (pw * ph) as usize];
                let prev = &blocked;
                next.par_chunks_mut(pw as usize)
                    .enumerate()
                    .for_each(|(qy, row)| {
                        let qy = qy as u32;
                        for (qx, b) in row.iter_mut().enumerate() {
                            let qx = qx as u32;
                            *b = (0..4).any(|c| {
                                let (x, y) = (2 * qx + (c & 1), 2 * qy + (c >> 1));
                                if l == 1 {
                                    x < w && y < h && blocked_px[(y * w + x) as usize]
                                } else {
                                    prev[(y * child.w + x) as usize]
                                }
                            });
                        }
                    });
                blocked = next;
            }
            Blocked::List(_) => {
                // The same nodes: the ancestors at level `l` of the blocked pixels.
                let mut next = vec![false; (pw * ph) as usize];
                for &(x, y) in &xy {
                    next[((y >> l) * pw + (x >> l)) as usize] = true;
                }
                blocked = next;
            }
        }
        let blocked = &blocked;
        // The parents over the image (`ceil(W / 2^l) x ceil(H / 2^l)`); the others have only
        // padding children, which are empty at every level, so they are empty.
        let (iw, ih) = (((w - 1) >> l) + 1, ((h - 1) >> l) + 1);
        // Each row set empty in cache right before its parents are written.
        let nodes = par_rows((pw * ph) as usize, pw as usize, Node::EMPTY, |qy, row| {
            let qy = qy as u32;
            let allow = Allow(
                (!blocked.is_empty())
                    .then(|| &blocked[(qy * pw) as usize..((qy + 1) * pw) as usize]),
            );
            #[cfg(target_arch = "x86_64")]
            if ctx.lanes {
                // Padding parents stay empty (set by `par_rows`; their children are not read).
                if qy < ih {
                    // Eight (AVX2) or four parents per step, children straight from their
                    // two rows.
                    let n = (iw as usize).min(row.len());
                    let row = &mut row[..n];
                    ctx.parent_row_fast(child, l, qy, row, allow);
                }
                return;
            }
            for (qx, out) in row.iter_mut().enumerate() {
                let qx = qx as u32;
                *out = parent_of(ctx, child, l, qx, qy, allow.get(qx));
            }
        });
        levels.push(Level {
            w: pw,
            h: ph,
            nodes,
        });
    }
    levels
}

/// The decoded pixel planes of a level-0 array in [`LayerPlanes`] form.
fn leaf_planes(level0: &Level, w: u32, h: u32, wf: f32, hf: f32) -> LayerPlanes {
    decoded_planes(w, h, wf, hf, super::tree::no_rows, |i, j| {
        let node = level0.nodes[(j * level0.w + i) as usize];
        node.is_plane().then_some((node, 0, i, j))
    })
}

#[cfg(test)]
mod tests {
    use super::super::merge::MergeCtx;
    use super::super::node::Node;
    use super::super::test_rng::Rng;
    use super::super::tree::Level;
    use super::{Allow, Blocked, prune, prune_from};

    /// Pruning with the blocked pixels as a list (each marks its ancestors) equals pruning
    /// with the pixel flags (every node scans its pixels), level for level bit for bit, from level 0 and from levels 0 and 1, in lanes
    /// and by the scalar definition: near-coplanar planes that merge up to the top unless
    /// blocked, odd sizes, sparse and clustered blocked pixels (and none). The blocking
    /// changes > 1000 nodes against no blocked pixel, so the lists matter.
    #[test]
    fn list_blocking_equals_the_pixel_flags() {
        let mut rng = Rng(0x5851_f42d_4c95_7f2d);
        let mut changed = 0usize;
        for (case, (w, h, nlev, frac)) in [
            (37u32, 23u32, 6u32, 0.02f32),
            (150, 97, 9, 0.01),
            (150, 97, 9, 0.1),
            (64, 64, 7, 0.0),
            (201, 120, 5, 0.03),
            (90, 131, 3, 0.05),
        ]
        .into_iter()
        .enumerate()
        {
            let ctx = MergeCtx {
                wf: w as f32,
                hf: h as f32,
                cos_norm: 0.95,
                gamma_dist: 1e-2,
                lanes: case % 2 == 0,
                never: false,
                ..MergeCtx::test_case(0)
            };
            let top = nlev - 1;
            let (w0, h0) = (w.div_ceil(1 << top) << top, h.div_ceil(1 << top) << top);
            let (z0, ax, ay) = (rng.f(0.3, 0.6), rng.f(-0.1, 0.1), rng.f(-0.1, 0.1));
            let nodes: Vec<Node> = (0..w0 * h0)
                .map(|k| {
                    let (x, y) = (k % w0, k / w0);
                    if x >= w || y >= h || rng.next().is_multiple_of(50) {
                        return Node::EMPTY;
                    }
                    let (xc, yc) = ((x as f32 + 0.5) / ctx.wf, (y as f32 + 0.5) / ctx.hf);
                    let z = z0 + ax * xc + ay * yc + rng.f(-1e-5, 1e-5);
                    Node::plane_with_gradient(z, ax, ay, 0, ctx.wf, ctx.hf, 0)
                        .unwrap_or(Node::EMPTY)
                })
                .collect();
            let level0 = Level {
                w: w0,
                h: h0,
                nodes,
            };
            let mut flags = vec![false; (w * h) as usize];
            let mut k = 0;
            while k < flags.len() {
                if rng.f(0.0, 1.0) < frac {
                    let run = 1 + (rng.next() % 9) as usize;
                    let end = (k + run).min(flags.len());
                    flags[k..end].fill(true);
                    k += run;
                }
                k += 1;
            }
            let px: Vec<u32> = (0..w * h).filter(|&k| flags[k as usize]).collect();
            let want = prune(&ctx, level0.clone(), nlev, Blocked::Pixels(&flags), w, h);
            let got = prune(&ctx, level0.clone(), nlev, Blocked::List(&px), w, h);
            assert!(got == want, "case {case}: from level 0");
            let first = want[..2].to_vec();
            let got = prune_from(&ctx, first, nlev, Blocked::List(&px), w, h);
            assert!(got == want, "case {case}: from levels 0 and 1");
            let free = prune(&ctx, level0, nlev, Blocked::None, w, h);
            changed += free
                .iter()
                .zip(&want)
                .map(|(a, b)| a.nodes.iter().zip(&b.nodes).filter(|(x, y)| x != y).count())
                .sum::<usize>();
        }
        assert!(changed > 1000, "{changed} nodes changed by the blocking");
    }

    /// `Allow::mask8` equals `Allow::get` per parent for every pattern of eight flags, at
    /// every offset of a row, including the row's last parents (fewer than eight left).
    #[test]
    fn mask8_equals_the_flags() {
        assert_eq!(Allow(None).mask8(5), 0xff);
        for pattern in 0..=255u32 {
            let row: Vec<bool> = (0..21).map(|i| (pattern >> (i % 8)) & 1 == 1).collect();
            let allow = Allow(Some(&row));
            for qx0 in 0..row.len() {
                let want = (0..8).fold(0, |m, p| {
                    let ok = qx0 + p >= row.len() || allow.get((qx0 + p) as u32);
                    m | (u32::from(ok) << p)
                });
                assert_eq!(allow.mask8(qx0), want, "pattern {pattern:#x}, offset {qx0}");
            }
        }
    }
}
