//! Marking the unsafe pixels of the cascade (Widmer et al. 2015, §3.3: a node's AABB range
//! is lowered to the smallest trigger depth below it) from the list of unsafe pixels only:
//! [`QuadTree::mark_unsafe_listed`], the same nodes with the same minima as
//! [`QuadTree::mark_unsafe`], which scans every pixel.
//!
//! Only the listed pixels' ancestors are visited. Per level, a dense array of the nodes'
//! smallest trigger depth below them is filled from the nodes listed for the level below (no
//! sort): at level 1 the listed pixels, above it the distinct nodes the level below listed (a
//! node is listed when its minimum is first lowered from `+inf`), and each listed node is
//! marked once with its minimum. The lists stay ordered by row (the pixels come in ascending
//! order), so every level is done in parallel by bands of rows: a band takes the contiguous
//! part of the list whose parents lie in its rows, and the bands' lists, concatenated in
//! band order, are the list of one pass in order.

use rayon::prelude::*;

use super::tree::{QuadTree, par_rows};

/// Rows of a level per parallel band (bands of level 1 hold `2 BAND_ROWS` pixel rows).
const BAND_ROWS: usize = 16;

/// A listed node: `(x, y, trigger depth)`.
type Entry = (u32, u32, f32);

impl QuadTree {
    /// [`Self::mark_unsafe`] given the unsafe pixels `px` (indices `j W + i`, those with a
    /// finite `tz`, ascending): only their ancestors are visited (module docs) — the same
    /// nodes with the same minima as [`Self::mark_unsafe`] (the trigger depths are `+0` or
    /// positive and never NaN, so their minimum does not depend on the order or grouping
    /// it is taken in; marking a node again with the same value changes nothing). Returns
    /// the top level's minima.
    pub(crate) fn mark_unsafe_listed(&mut self, tz: Vec<f32>, px: &[u32]) -> Vec<f32> {
        debug_assert!(px.is_sorted(), "the unsafe pixels come in ascending order");
        let (w, nl) = (self.width, self.levels.len());
        // The pixels' coordinates and trigger depths, one division each.
        let mut cur: Vec<Entry> = px.iter().map(|&k| (k % w, k / w, tz[k as usize])).collect();
        let l0 = &mut self.levels[0];
        let lw0 = l0.w as usize;
        l0.nodes
            .par_chunks_mut(BAND_ROWS * lw0)
            .enumerate()
            .for_each(|(b, nodes)| {
                let y0 = (b * BAND_ROWS) as u32;
                for &(x, y, t) in band(&cur, y0, BAND_ROWS as u32, 0) {
                    nodes[(y - y0) as usize * lw0 + x as usize].mark_unsafe(t);
                }
            });
        let mut mins: Vec<f32> = Vec::new();
        if nl == 1 {
            mins.resize(l0.nodes.len(), f32::INFINITY);
            for &(x, y, t) in &cur {
                mins[(y * l0.w + x) as usize] = t;
            }
        }
        for l in 1..nl {
            let lv = &mut self.levels[l];
            // The dense minima set to `+inf` (level 1's is the largest; the levels above
            // shrink, so its allocation is reused).
            let (len, lw) = (lv.nodes.len(), lv.w as usize);
            if l == 1 {
                mins = par_rows(len, lw, f32::INFINITY, |_, _| {});
            } else {
                mins.truncate(len);
            }
            let child = &cur;
            let bands: Vec<Vec<Entry>> = lv
                .nodes
                .par_chunks_mut(BAND_ROWS * lw)
                .zip(mins.par_chunks_mut(BAND_ROWS * lw))
                .enumerate()
                .map(|(b, (nodes, m))| {
                    if l > 1 {
                        m.fill(f32::INFINITY);
                    }
                    let y0 = (b * BAND_ROWS) as u32;
                    let mut out: Vec<Entry> = Vec::new();
                    for &(x, y, t) in band(child, y0, BAND_ROWS as u32, 1) {
                        let (x, y) = (x >> 1, y >> 1);
                        let v = &mut m[(y - y0) as usize * lw + x as usize];
                        if *v == f32::INFINITY {
                            out.push((x, y, 0.0));
                        }
                        if t < *v {
                            *v = t;
                        }
                    }
                    for e in out.iter_mut() {
                        let i = (e.1 - y0) as usize * lw + e.0 as usize;
                        e.2 = m[i];
                        nodes[i].mark_unsafe(e.2);
                    }
                    out
                })
                .collect();
            // One copy per band (items one at a time through rayon's list collect cost
            // more than the marking).
            cur = bands.concat();
        }
        self.trigger_z = tz;
        mins
    }
}

/// The entries of `list` (ordered by `y`) whose `y >> shift` lies in `y0..y0 + rows`.
fn band(list: &[Entry], y0: u32, rows: u32, shift: u32) -> &[Entry] {
    let lo = list.partition_point(|e| (e.1 >> shift) < y0);
    let hi = lo + list[lo..].partition_point(|e| (e.1 >> shift) < y0 + rows);
    &list[lo..hi]
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
                        if rng.next() % 3 == 0 {
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
        QuadTree {
            width: w,
            height: h,
            wf: w as f32,
            hf: h as f32,
            levels,
            crack_px: 0.0,
            trigger_z: Vec::new(),
            unsafe_count: 0,
            plane_top: 0,
            plane_level: Vec::new(),
            z_floor: 0.0,
            z_floor_rect: Vec::new(),
            z_floor_dir: Vec::new(),
            z_floor_tw: 0,
            z_floor_th: 0,
        }
    }

    /// The banded marking from the list equals the scan of every pixel: every node bit for
    /// bit, the trigger depths and the top level's minima, on images whose level-1 rows span
    /// several bands, with sparse and clustered unsafe pixels (and none, and one level).
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
                        *t = if rng.next() % 8 == 0 {
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
}
