//! Marking the unsafe pixels of the cascade (Widmer et al. 2015, §3.3 with the exact
//! cascading of [`super::cascade`]: a node's AABB range is lowered to the smallest trigger
//! depth below it, a plane node flagged) from the list of unsafe pixels only:
//! [`QuadTree::mark_unsafe_listed`], the same nodes with the same minima as
//! [`QuadTree::mark_unsafe`], which scans every pixel.
//!
//! Only the listed pixels' ancestors are visited, level by level, as lists in row-major
//! order without repeats: the pixels come in ascending order, so the listed nodes of rows
//! `2m` and `2m + 1` of a level are a contiguous part of its list, each row ascending, and
//! one merge of the two by `x / 2` gives the parents in row `m` in order, each once with the
//! smallest trigger depth of its listed children — no dense array of minima per level and
//! no sort. The lower levels are marked by two halves of the list in parallel, split at a
//! pixel row that no node of those levels straddles; their lists concatenated are the one
//! list the levels above go on from. The fixed point ([`super::fixpoint`]) hands over that ascending list by one merge
//! of its two ascending parts, the pixels listed by the leaf pass and those its iterations
//! blocked, keeping the finite ones ([`merge_finite`]).

use super::node::Node;
use super::tree::QuadTree;

/// The halves are split at a multiple of `2^SPLIT_LEVEL` pixel rows: levels up to
/// `SPLIT_LEVEL` are marked by the two halves in parallel, the (short) lists above serially.
const SPLIT_LEVEL: usize = 5;

/// A listed node: `(x, y, trigger depth)`.
type Entry = (u32, u32, f32);

impl QuadTree {
    /// [`Self::mark_unsafe`] given the unsafe pixels `px` (indices `j W + i`, those with a
    /// finite `tz`, ascending): only their ancestors are visited. Per level the marked nodes
    /// are a list in row-major order without repeats: level 0's are the pixels, and a
    /// level's list gives the next one's by one merge per row pair (`parents_listed`: the
    /// parents of rows `2m` and `2m + 1`, both ascending, each parent once with the smallest
    /// trigger depth of its listed children), no dense array of minima; each listed node is
    /// marked once with its minimum — the same nodes with the same minima as
    /// [`Self::mark_unsafe`] (the trigger depths are `+0` or positive and never NaN, so their
    /// minimum does not depend on the order or grouping it is taken in). Levels `0..=s`
    /// (`s = min(SPLIT_LEVEL, top)`) are marked by two halves of the list in parallel
    /// (`rayon::join`), split at a pixel row `ys`, a multiple of `2^s` near the median
    /// pixel's row: every node of those levels lies in one half, the halves' nodes are
    /// disjoint row ranges of each level, and their level-`s` lists concatenated are the
    /// list of one pass; the levels above go on from it serially. Returns the top level's
    /// minima (dense, as [`Self::mark_unsafe`]).
    pub(crate) fn mark_unsafe_listed(&mut self, tz: Vec<f32>, px: &[u32]) -> Vec<f32> {
        debug_assert!(px.windows(2).all(|p| p[0] < p[1]), "ascending");
        let (w, nl) = (self.width, self.levels.len());
        let s = (nl - 1).min(SPLIT_LEVEL);
        let ys = px.get(px.len() / 2).map_or(0, |&k| ((k / w) >> s) << s);
        let ks = px.partition_point(|&k| k < ys * w);
        let (mut lo, mut hi): (Vec<_>, Vec<_>) = self.levels[..=s]
            .iter_mut()
            .enumerate()
            .map(|(l, lv)| {
                let (a, b) = lv.nodes.split_at_mut(((ys >> l) * lv.w) as usize);
                ((a, lv.w), (b, lv.w))
            })
            .unzip();
        let (tzr, (pa, pb)) = (&tz, px.split_at(ks));
        let (mut cur, upper) = rayon::join(
            || mark_part(&mut lo, w, 0, tzr, pa),
            || mark_part(&mut hi, w, ys, tzr, pb),
        );
        cur.extend_from_slice(&upper);
        let mut next: Vec<Entry> = Vec::with_capacity(cur.len());
        for l in s + 1..nl {
            let lv = &mut self.levels[l];
            parents_listed(&cur, &mut next);
            for &(x, y, t) in &next {
                lv.nodes[(y * lv.w + x) as usize].mark_unsafe(t);
            }
            core::mem::swap(&mut cur, &mut next);
        }
        let top = &self.levels[nl - 1];
        let mut mins = vec![f32::INFINITY; top.nodes.len()];
        for &(x, y, t) in &cur {
            mins[(y * top.w + x) as usize] = t;
        }
        self.trigger_z = tz;
        mins
    }
}

/// Marks the listed pixels `px` (ascending, all in pixel rows `y0..`) and their ancestors in
/// `levels` (per level from 0 the nodes of rows `y0 >> l..` and the level's width) and
/// returns the last level's list (global coordinates).
fn mark_part(
    levels: &mut [(&mut [Node], u32)],
    w: u32,
    y0: u32,
    tz: &[f32],
    px: &[u32],
) -> Vec<Entry> {
    // The pixels' coordinates and trigger depths, marked; ascending, so the row only grows
    // (no division).
    let mut cur: Vec<Entry> = Vec::with_capacity(px.len());
    let (nodes, lw) = &mut levels[0];
    let (mut y, mut row) = (y0, y0 * w);
    for &k in px {
        while k - row >= w {
            y += 1;
            row += w;
        }
        let (x, t) = (k - row, tz[k as usize]);
        nodes[((y - y0) * *lw + x) as usize].mark_unsafe(t);
        cur.push((x, y, t));
    }
    let mut next: Vec<Entry> = Vec::with_capacity(cur.len());
    for (l, (nodes, lw)) in levels.iter_mut().enumerate().skip(1) {
        let yl = y0 >> l;
        parents_listed(&cur, &mut next);
        for &(x, y, t) in &next {
            nodes[((y - yl) * *lw + x) as usize].mark_unsafe(t);
        }
        core::mem::swap(&mut cur, &mut next);
    }
    cur
}

/// The parents of the listed nodes `cur` (`(x, y, minimum)`, row-major without repeats) as
/// the same kind of list in `out` (cleared first), each with the smallest minimum of its
/// listed children: per parent row `m`, the listed nodes of rows `2m` and `2m + 1` (a
/// contiguous part of `cur`, each row ascending in `x`) merged by `x / 2`.
fn parents_listed(cur: &[Entry], out: &mut Vec<Entry>) {
    out.clear();
    let n = cur.len();
    let mut s = 0;
    while s < n {
        let m = cur[s].1 >> 1;
        // Rows `2m` (`s..e0`, possibly empty) and `2m + 1` (`e0..e1`).
        let e0 = s + cur[s..].partition_point(|e| e.1 == 2 * m);
        let e1 = e0 + cur[e0..].partition_point(|e| e.1 == 2 * m + 1);
        let (a, b) = (&cur[s..e0], &cur[e0..e1]);
        let (mut i, mut j) = (0, 0);
        while i < a.len() || j < b.len() {
            let qa = a.get(i).map_or(u32::MAX, |e| e.0 >> 1);
            let qb = b.get(j).map_or(u32::MAX, |e| e.0 >> 1);
            let q = qa.min(qb);
            let mut t = f32::INFINITY;
            while i < a.len() && a[i].0 >> 1 == q {
                if a[i].2 < t {
                    t = a[i].2;
                }
                i += 1;
            }
            while j < b.len() && b[j].0 >> 1 == q {
                if b[j].2 < t {
                    t = b[j].2;
                }
                j += 1;
            }
            out.push((q, m, t));
        }
        s = e1;
    }
}

/// The pixels of `a` and `b` (ascending, disjoint) whose trigger depth in `tz` is finite,
/// ascending: one merge of the two lists.
pub(super) fn merge_finite(a: &[u32], b: &[u32], tz: &[f32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        let k = if a[i] < b[j] {
            i += 1;
            a[i - 1]
        } else {
            j += 1;
            b[j - 1]
        };
        if tz[k as usize].is_finite() {
            out.push(k);
        }
    }
    for &k in a[i..].iter().chain(&b[j..]) {
        if tz[k as usize].is_finite() {
            out.push(k);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::node::Node;
    use super::super::test_rng::Rng;
    use super::super::tree::{Level, QuadTree};

    /// A tree of `nlev` padded levels (as the build lays them out) of random AABB and plane
    /// nodes over a `w x h` image.
    fn random_tree(rng: &mut Rng, w: u32, h: u32, nlev: u32) -> QuadTree {
        let top = nlev - 1;
        let (w0, h0) = (w.div_ceil(1 << top) << top, h.div_ceil(1 << top) << top);
        let levels = (0..nlev)
            .map(|l| {
                let (lw, lh) = (w0 >> l, h0 >> l);
                let nodes = (0..lw * lh)
                    .map(|_| {
                        let z = rng.f(0.0, 1.0);
                        if rng.next().is_multiple_of(3) {
                            let (gx, gy) = (rng.f(-0.5, 0.5), rng.f(-0.5, 0.5));
                            Node::plane_with_gradient(z, gx, gy, l, w as f32, h as f32, 0)
                                .unwrap_or(Node::EMPTY)
                        } else {
                            Node::aabb(z, z + rng.f(0.0, 0.5))
                        }
                    })
                    .collect();
                Level {
                    w: lw,
                    h: lh,
                    nodes,
                }
            })
            .collect();
        QuadTree::from_levels(w, h, levels, 0.0)
    }

    /// The marking from the list equals the scan of every pixel: every node bit for
    /// bit, the trigger depths and the top level's minima, on images of odd and even sizes, with sparse and clustered unsafe pixels (and none, and one level). The two
    /// halves split below the top (8 and 9 levels: levels above `SPLIT_LEVEL` go on from
    /// the concatenated lists) and at the top (4 levels, one level) are both covered.
    #[test]
    fn listed_marking_equals_the_scan() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mut marked = 0usize;
        for (w, h, nlev, frac) in [
            (37u32, 23u32, 4u32, 0.1f32),
            (150, 200, 8, 0.02),
            (150, 200, 8, 0.3),
            (300, 97, 9, 0.05),
            (64, 70, 1, 0.1),
            (90, 130, 6, 0.0),
        ] {
            let tree = random_tree(&mut rng, w, h, nlev);
            let mut tz = vec![f32::INFINITY; (w * h) as usize];
            // Clustered: whole runs of a row unsafe, else single pixels.
            let mut k = 0usize;
            while k < tz.len() {
                if rng.f(0.0, 1.0) < frac {
                    let run = 1 + (rng.next() % 12) as usize;
                    let end = (k + run).min(tz.len());
                    for t in tz[k..end].iter_mut() {
                        *t = if rng.next().is_multiple_of(8) {
                            0.0
                        } else {
                            rng.f(0.0, 1.2)
                        };
                    }
                    k += run;
                }
                k += 1;
            }
            let px: Vec<u32> = (0..tz.len() as u32)
                .filter(|&k| tz[k as usize].is_finite())
                .collect();
            let (mut scan, mut listed) = (tree.clone(), tree.clone());
            let a = scan.mark_unsafe(tz.clone());
            let b = listed.mark_unsafe_listed(tz, &px);
            assert_eq!(
                a.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                b.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                "{w}x{h}: top minima"
            );
            assert!(scan == listed, "{w}x{h}, {nlev} levels: trees differ");
            marked += scan
                .levels
                .iter()
                .zip(&tree.levels)
                .map(|(s, t)| s.nodes.iter().zip(&t.nodes).filter(|(x, y)| x != y).count())
                .sum::<usize>();
        }
        // The marking changed nodes: the comparison is not between two untouched trees.
        assert!(marked > 1000, "{marked} nodes marked");
    }

    /// The merge keeps exactly the finite pixels of both lists, ascending: against a sort
    /// of their concatenation filtered, on random disjoint lists (one or both empty too).
    #[test]
    fn merge_equals_the_sorted_filter() {
        let mut rng = Rng(0x2545_f491_4f6c_dd1d);
        let mut kept = 0usize;
        for case in 0..200u32 {
            let n = 1 + rng.next() % 3000;
            let tz: Vec<f32> = (0..n)
                .map(|_| match rng.next() % 4 {
                    0 => f32::INFINITY,
                    1 => 0.0,
                    _ => rng.f(0.0, 1.0),
                })
                .collect();
            // Each pixel in `a`, in `b` or in neither (`b` empty in every fifth case).
            let (mut a, mut b) = (Vec::new(), Vec::new());
            for k in 0..n as u32 {
                match rng.next() % 5 {
                    0 | 1 => a.push(k),
                    2 if case % 5 != 0 => b.push(k),
                    _ => {}
                }
            }
            let got = super::super::mark_listed::merge_finite(&a, &b, &tz);
            let mut want: Vec<u32> = a.iter().chain(&b).copied().collect();
            want.retain(|&k| tz[k as usize].is_finite());
            want.sort_unstable();
            assert_eq!(got, want, "case {case}");
            kept += got.len();
        }
        assert!(kept > 10_000, "{kept} pixels kept");
    }
}
