//! The quad-tree of one captured layer (Widmer et al. 2015, §3): its levels of 64-bit nodes
//! ([`super::node`]), level 0 = pixels, and what the traversal and the cascade read from it —
//! the effective plane of a pixel, the cascade trigger depths and the `z` floors where a ray's
//! traversal may start. Built by `build.rs`, walked by `traverse.rs`.
//!
//! **Invariants:** every level is a flat row-major array of `w x h` nodes (`w, h` halved,
//! rounded up, per level); AABB `z` ranges are conservative (a node's range holds every plane
//! below it over its footprint, widened by [`Z_EPS`]); `z_floor <= ` every entry of
//! `z_floor_rect` and `z_floor_dir`.

use std::mem::MaybeUninit;

use glam::Vec3;
use rayon::prelude::*;

use super::node::{FLAG_CRACK, NO_PLANE, Node, decode_plane};
use crate::LayerPlanes;

/// Widening of plane z ranges in AABBs (a few f32 ulps at `z = 1`).
pub const Z_EPS: f32 = 1e-6;

/// One level: a flat row-major array of `w x h` nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    pub w: u32,
    pub h: u32,
    pub nodes: Vec<Node>,
}

/// The quad-tree of one captured layer (§3).
#[derive(Clone, Debug, PartialEq)]
pub struct QuadTree {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) wf: f32,
    pub(crate) hf: f32,
    /// Level 0 = pixels.
    pub(crate) levels: Vec<Level>,
    /// Crack dilation in pixels (traversal side).
    pub(crate) crack_px: f32,
    /// Per pixel (`W x H`), the trigger depth of unsafe pixels (cascade); empty when the
    /// layer is the last one.
    pub(crate) trigger_z: Vec<f32>,
    /// The number of finite [`Self::trigger_z`] entries (unsafe pixels).
    pub(crate) unsafe_count: usize,
    /// The highest level holding any plane node (0 when there is none; reported by the
    /// examples).
    pub(crate) plane_top: usize,
    /// Per pixel (`W x H`), the level of its effective plane node (the topmost plane
    /// ancestor, [`Self::effective_node`]); 0 where that is the pixel itself or where the
    /// pixel has no plane. The traversal's start needs this one load instead of a
    /// plane-ancestor check over the levels above the start level ([`super::traverse`]).
    pub(crate) plane_level: Vec<u8>,
    /// Cube `z` below which the ray meets nothing of this tree: the smallest lower `z` bound
    /// of the top-level nodes (conservative AABB ranges, the footprint range of a plane node
    /// there, every trigger depth) minus [`Z_SKIP_MARGIN`]. The traversal starts where the
    /// ray's `z` reaches it — the `z` slab of the ray against the root box ([`super::traverse`]).
    pub(crate) z_floor: f32,
    /// Regional floors: per rectangle of top-level nodes holding image pixels
    /// (`tw x th` of them; rows `r0 <= r1`, columns `c0 <= c1`), the floor of
    /// [`Self::z_floor`] taken over those nodes only (their lower `z` bound and the trigger
    /// depths of their pixels), at `((r0 th + r1) tw + c0) tw + c1`; `z_floor` itself where
    /// that is less than [`Z_REGION_MIN_GAIN`] above it (so every entry is `>= z_floor`). Empty (the global floor only) when the table would exceed
    /// [`Z_FLOOR_TABLE_MAX`] entries.
    pub(crate) z_floor_rect: Vec<f32>,
    /// Directional regional floors for rays moving along `x` only: per top-level node
    /// `(c, r)` holding image pixels, at `2 (r tw + c) + back`, the floor over the nodes
    /// `c..tw` of row `r` (`back = 0`) or `0..=c` (`back = 1`).
    pub(crate) z_floor_dir: Vec<f32>,
    pub(crate) z_floor_tw: u32,
    pub(crate) z_floor_th: u32,
}

/// Smallest gain in cube `z` over `QuadTree::z_floor` for which a regional floor
/// (`QuadTree::z_floor_dir`) is used.
pub const Z_REGION_MIN_GAIN: f32 = 0.05;

/// Largest `QuadTree::z_floor_rect` (`tw^2 th^2` entries; 4096 is e.g. 8 x 8 top-level
/// nodes).
pub const Z_FLOOR_TABLE_MAX: usize = 4096;

/// Margin of `QuadTree::z_floor` in cube `z`: before the traversal's start the ray is at
/// least this far in front of every plane (in `z` at the same `x, y`), so the f32 plane
/// tests there, which the original start from the segment's beginning would have done, are
/// far from a sign change.
pub const Z_SKIP_MARGIN: f32 = 1e-3;

impl QuadTree {
    /// A tree over a `w x h` image with the given levels and nothing derived yet: no
    /// trigger depths, unsafe pixels, plane top or depth floor (the build fills them).
    pub(super) fn from_levels(w: u32, h: u32, levels: Vec<Level>, crack_px: f32) -> Self {
        Self {
            width: w,
            height: h,
            wf: w as f32,
            hf: h as f32,
            levels,
            crack_px,
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

    /// The highest level holding a plane node (0 when there is none).
    pub fn plane_top(&self) -> usize {
        self.plane_top
    }

    /// Number of levels (including the pixel level).
    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// Image size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Node `(qx, qy)` at `level` (`Node::EMPTY` outside the padded grid).
    pub fn node(&self, level: usize, qx: u32, qy: u32) -> Node {
        let lv = &self.levels[level];
        if qx < lv.w && qy < lv.h {
            lv.nodes[(qy * lv.w + qx) as usize]
        } else {
            Node::EMPTY
        }
    }

    /// Bytes of the node arrays (all levels, padding included; 8 bytes per node).
    pub fn bytes(&self) -> usize {
        self.levels
            .iter()
            .map(|l| l.nodes.len() * size_of::<Node>())
            .sum()
    }

    /// Nodes reachable by the traversal (non-empty nodes whose ancestors are all AABBs).
    pub fn node_count(&self) -> usize {
        self.count().0
    }

    /// Per pixel (`W x H`, row-major), the level of its effective plane node (0 where that
    /// is the pixel itself or where it has none): what the traversal's start loads.
    pub fn plane_levels(&self) -> &[u8] {
        &self.plane_level
    }

    /// Plane nodes reachable by the traversal (leaves of the pruned tree).
    pub fn plane_node_count(&self) -> usize {
        self.count().1
    }

    fn count(&self) -> (usize, usize) {
        let top = self.levels.len() - 1;
        let lv = &self.levels[top];
        let mut acc = (0, 0);
        for qy in 0..lv.h {
            for qx in 0..lv.w {
                self.count_rec(top, qx, qy, &mut acc);
            }
        }
        acc
    }

    fn count_rec(&self, l: usize, qx: u32, qy: u32, acc: &mut (usize, usize)) {
        let n = self.node(l, qx, qy);
        if n.is_plane() {
            acc.0 += 1;
            acc.1 += 1;
        } else if !n.is_empty() {
            acc.0 += 1;
            if l > 0 {
                for c in 0..4 {
                    self.count_rec(l - 1, 2 * qx + (c & 1), 2 * qy + (c >> 1), acc);
                }
            }
        }
    }

    /// The plane node the traversal uses at pixel `(i, j)` (the topmost plane ancestor) with
    /// its level and position, if any.
    pub fn effective_node(&self, i: u32, j: u32) -> Option<(Node, u32, u32, u32)> {
        // A plane node's descendants are all planes (§3.3 condition 1), so along the path
        // the planes are exactly levels 0..=L_p: climb from the pixel while the parent is a
        // plane.
        let n0 = self.node(0, i, j);
        if !n0.is_plane() {
            return None;
        }
        let mut best = (n0, 0u32, i, j);
        for l in 1..self.levels.len() {
            let (qx, qy) = (i >> l, j >> l);
            let n = self.node(l, qx, qy);
            if !n.is_plane() {
                break;
            }
            best = (n, l as u32, qx, qy);
        }
        Some(best)
    }

    /// The brute-force twin of this tree: per pixel, the decoded plane of its effective
    /// plane node ([`Self::effective_node`]) in [`LayerPlanes`] form (offset computed by the
    /// same f32 code as the traversal). With lossless settings these are the quantised pixel
    /// planes; with lossy settings every pixel of a merged node carries the proxy plane.
    /// `flag` holds the crack flag `O`.
    ///
    /// Computed from the effective levels (`effective_levels`: one pass per level, no climb),
    /// each merged node decoded once per run of a row it covers; equal to
    /// [`Self::effective_planes_by_climbing`] bit for bit (tested).
    pub fn effective_planes(&self) -> LayerPlanes {
        let lv = self.effective_levels();
        let w0 = self.levels[0].w;
        // Sixteen pixels per step where the CPU has AVX-512 (`eff_planes_avx512`, the same
        // bits), the rest of each row below.
        #[cfg(target_arch = "x86_64")]
        let rows = super::eff_planes_avx512::available()
            .then(|| {
                let levels: Vec<_> = self.levels.iter().map(|lv| (&lv.nodes[..], lv.w)).collect();
                super::eff_planes_avx512::PlaneRows::new(&levels, self.wf, self.hf)
            })
            .flatten();
        let fast = |j: u32, n: &mut [_], o: &mut [_], f: &mut [_]| {
            #[cfg(target_arch = "x86_64")]
            if let Some(r) = &rows {
                let k0 = (j * w0) as usize;
                // SAFETY: the CPU has AVX-512 (checked); `lv` are the effective levels of
                // these levels.
                return unsafe { r.row16(j, &lv[k0..k0 + n.len()], n, o, f) };
            }
            let _ = (j, n, o, f);
            0
        };
        decoded_planes(self.width, self.height, self.wf, self.hf, fast, |i, j| {
            let l = lv[(j * w0 + i) as usize];
            (l != NO_PLANE).then(|| {
                let l = l as u32;
                let (qx, qy) = (i >> l, j >> l);
                (self.node(l as usize, qx, qy), l, qx, qy)
            })
        })
    }

    /// [`Self::effective_planes`] by the definition: per pixel, climb to its effective node
    /// ([`Self::effective_node`]) and decode it (the slow twin of the tests).
    pub fn effective_planes_by_climbing(&self) -> LayerPlanes {
        decoded_planes(
            self.width,
            self.height,
            self.wf,
            self.hf,
            no_rows,
            |i, j| self.effective_node(i, j),
        )
    }

    /// Per level-0 node (`levels[0].w x levels[0].h`, padding included), the level of its
    /// effective plane node ([`Self::effective_node`]), [`NO_PLANE`] where it has none:
    /// computed top-down, one pass per level (a node inherits its parent's effective level,
    /// else is its own effective node when it is a plane). Equal to the per-pixel climb
    /// because a plane node's descendants are all planes (§3.3 condition 1).
    pub(crate) fn effective_levels(&self) -> Vec<u8> {
        effective_levels(&self.levels)
    }
}

/// The row kernel of [`decoded_planes`] that does nothing (every pixel by the scalar loop).
pub(crate) fn no_rows(
    _: u32,
    _: &mut [MaybeUninit<Vec3>],
    _: &mut [MaybeUninit<f32>],
    _: &mut [MaybeUninit<bool>],
) -> usize {
    0
}

/// [`QuadTree::effective_levels`] of the levels `levels` (level 0 first).
pub(crate) fn effective_levels(levels: &[Level]) -> Vec<u8> {
    effective_levels_down_to(levels, 0)
}

/// [`effective_levels`] per node of level `bottom` (`levels[bottom].w x levels[bottom].h`).
fn effective_levels_down_to(levels: &[Level], bottom: usize) -> Vec<u8> {
    let top = levels.len() - 1;
    let mut cur: Vec<u8> = levels[top]
        .nodes
        .iter()
        .map(|n| if n.is_plane() { top as u8 } else { NO_PLANE })
        .collect();
    for l in (bottom..top).rev() {
        let (lw, pw) = (levels[l].w as usize, levels[l + 1].w as usize);
        let nodes = &levels[l].nodes;
        let parent = &cur;
        // Below the top level a level's width is even (`lw = 2 pw`).
        cur = par_rows(nodes.len(), lw, NO_PLANE, |y, row| {
            let prow = &parent[(y / 2) * pw..(y / 2 + 1) * pw];
            let nrow = &nodes[y * lw..(y + 1) * lw];
            #[cfg(target_arch = "x86_64")]
            let done = super::eff_lanes::eff_row16(row, prow, nrow, l as u8);
            #[cfg(not(target_arch = "x86_64"))]
            let done = 0;
            eff_row(row, prow, nrow, l as u8, done);
        });
    }
    cur
}

/// One row of [`effective_levels`] at level `l` from position `from` on: `row[x]` = the
/// parent's effective level `prow[x / 2]` unless that is [`NO_PLANE`], else `l` where node
/// `nrow[x]` is a plane, else [`NO_PLANE`] (the definition; `eff_lanes` does sixteen nodes
/// per step).
pub(crate) fn eff_row(row: &mut [u8], prow: &[u8], nrow: &[Node], l: u8, from: usize) {
    for (x, (v, n)) in row.iter_mut().zip(nrow).enumerate().skip(from) {
        let p = prow[x / 2];
        *v = if p != NO_PLANE {
            p
        } else if n.is_plane() {
            l
        } else {
            NO_PLANE
        };
    }
}

/// [`QuadTree::plane_level`] (`w x h` pixels) of the levels `levels`: the effective levels
/// down to level 1, then per pixel its parent's (`NO_PLANE` as 0) — a pixel whose parent has
/// no plane ancestor-or-self is its own effective node or has none, 0 either way, so level 0
/// itself is not read.
pub(crate) fn plane_levels(levels: &[Level], w: u32, h: u32) -> Vec<u8> {
    if levels.len() == 1 {
        return vec![0u8; (w * h) as usize];
    }
    let e1 = effective_levels_down_to(levels, 1);
    let w1 = levels[1].w as usize;
    par_rows((w * h) as usize, w as usize, 0u8, |j, row| {
        let prow = &e1[(j / 2) * w1..];
        // Per level-1 node its two pixels of the row (vectorised), then an odd last one.
        let level = |p: u8| if p == NO_PLANE { 0 } else { p };
        let mut pairs = row.chunks_exact_mut(2);
        for (pair, &p) in (&mut pairs).zip(prow) {
            let v = level(p);
            pair[0] = v;
            pair[1] = v;
        }
        if let [last] = pairs.into_remainder() {
            *last = level(prow[(w as usize - 1) / 2]);
        }
    })
}

/// Sets every element of `row` (part of a `Vec`'s spare capacity) to `value` and returns it
/// initialised. The build's full-resolution arrays are set a row at a time right before the
/// row is written (the row is then in cache) instead of by a fill or zeroing pass over the
/// whole allocation first ([`par_rows`]).
#[inline]
pub(crate) fn init_row<T: Copy>(row: &mut [MaybeUninit<T>], value: T) -> &mut [T] {
    for x in row.iter_mut() {
        x.write(value);
    }
    // SAFETY: every element was just initialised; `MaybeUninit<T>` has `T`'s layout.
    unsafe { &mut *(row as *mut [MaybeUninit<T>] as *mut [T]) }
}

/// Vectors of at most this many values are made by [`par_rows`] on the calling thread (the
/// small levels of the pruning and of the effective levels: a parallel pass costs a join,
/// which under load waits for a descheduled thread, for a few microseconds of work).
pub(crate) const SERIAL_ROWS_MAX: usize = 4096;

/// A vector of `len` values made in parallel by rows of `row_len` (the last may be
/// shorter; on the calling thread when `len <= SERIAL_ROWS_MAX`): row `r` is set to `value`
/// ([`init_row`]) and handed to `f(r, row)`.
pub(crate) fn par_rows<T: Copy + Send + Sync>(
    len: usize,
    row_len: usize,
    value: T,
    f: impl Fn(usize, &mut [T]) + Sync + Send,
) -> Vec<T> {
    let mut v = Vec::with_capacity(len);
    // One code path for both (a second call site of `f` changes what LLVM inlines into
    // it): a minimum length above the row count keeps rayon from splitting, so the rows
    // run on the calling thread without a join.
    let min_rows = if len <= SERIAL_ROWS_MAX {
        usize::MAX
    } else {
        1
    };
    v.spare_capacity_mut()[..len]
        .par_chunks_mut(row_len.max(1))
        .with_min_len(min_rows)
        .enumerate()
        .for_each(|(r, row)| f(r, init_row(row, value)));
    // SAFETY: the rows cover `0..len` and each was initialised by `init_row`.
    unsafe { v.set_len(len) };
    v
}

/// A node with its level and position: `(node, level, qx, qy)`.
type NodeAt = (Node, u32, u32, u32);

/// Per pixel `(i, j)` of a `w x h` layer, the decoded plane of the node `node_of(i, j)`
/// (`(node, level, qx, qy)`, or `None` for no plane) in [`LayerPlanes`] form, rows in parallel.
/// `row_fast(j, normal, offset, flag)` may write the first pixels of row `j` itself (the same
/// values) and returns how many it wrote; the rest are decoded here ([`no_rows`]: none).
pub(crate) fn decoded_planes(
    w: u32,
    h: u32,
    wf: f32,
    hf: f32,
    row_fast: impl Fn(
        u32,
        &mut [MaybeUninit<Vec3>],
        &mut [MaybeUninit<f32>],
        &mut [MaybeUninit<bool>],
    ) -> usize
    + Sync,
    node_of: impl Fn(u32, u32) -> Option<NodeAt> + Sync,
) -> LayerPlanes {
    let n = (w * h) as usize;
    let (mut normal, mut offset, mut flag) = (
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    );
    normal.spare_capacity_mut()[..n]
        .par_chunks_mut(w as usize)
        .zip(offset.spare_capacity_mut()[..n].par_chunks_mut(w as usize))
        .zip(flag.spare_capacity_mut()[..n].par_chunks_mut(w as usize))
        .enumerate()
        .for_each(|(j, ((nrow, orow), frow))| {
            // The previous pixel's node and its decoded plane: a merged node covers a run of
            // pixels of the row, decoded once (the decode is a function of the node and its
            // position only). Every pixel of the row is written (zero where no plane).
            let mut last: Option<(NodeAt, Vec3, f32)> = None;
            let done = row_fast(j as u32, nrow, orow, frow);
            for (i, ((nv, ov), fv)) in nrow.iter_mut().zip(orow).zip(frow).enumerate().skip(done) {
                let (nn, c, f) = match node_of(i as u32, j as u32) {
                    Some(key) => {
                        let (nn, c) = match last {
                            Some((k, nn, c)) if k == key => (nn, c),
                            _ => {
                                let (node, l, qx, qy) = key;
                                let (nn, c) = decode_plane(node, l, qx, qy, wf, hf);
                                last = Some((key, nn, c));
                                (nn, c)
                            }
                        };
                        (nn, c, key.0.flags() & FLAG_CRACK != 0)
                    }
                    None => (Vec3::ZERO, 0.0, false),
                };
                nv.write(nn);
                ov.write(c);
                fv.write(f);
            }
        });
    // SAFETY: the rows cover `0..n` (`w` values each) and every value was written above.
    unsafe {
        normal.set_len(n);
        offset.set_len(n);
        flag.set_len(n);
    }
    LayerPlanes {
        width: w,
        height: h,
        normal,
        offset,
        flag,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadtree::eff_lanes::eff_row16;
    use crate::quadtree::test_rng::Rng;

    /// `eff_lanes`' sixteen-node rows: random rows (plane, AABB and empty nodes; parents with and without an effective
    /// level; lengths not multiples of 16) equal the scalar definition byte for byte.
    #[test]
    fn rows_equal_the_scalar_rows() {
        let mut rng = Rng(0x00ef_f1ec_7175_0001);
        for case in 0..200usize {
            let lw = 2 * (1 + case % 40);
            let l = (case % 9) as u8;
            let nrow: Vec<Node> = (0..lw)
                .map(|_| match rng.next() % 3 {
                    0 => Node::EMPTY,
                    1 => Node::aabb(rng.f(0.0, 0.5), rng.f(0.5, 1.0)),
                    _ => Node::plane_with_gradient(
                        rng.f(0.0, 1.0),
                        rng.f(-1.0, 1.0),
                        rng.f(-1.0, 1.0),
                        0,
                        64.0,
                        64.0,
                        (rng.next() % 4) as u32,
                    )
                    .unwrap_or(Node::EMPTY),
                })
                .collect();
            let prow: Vec<u8> = (0..lw / 2)
                .map(|_| match rng.next() % 3 {
                    0 => l + 1 + (rng.next() % 3) as u8,
                    _ => NO_PLANE,
                })
                .collect();
            let (mut fast, mut want) = (vec![0u8; lw], vec![0u8; lw]);
            let n = eff_row16(&mut fast, &prow, &nrow, l);
            assert_eq!(n, lw & !15);
            eff_row(&mut fast, &prow, &nrow, l, n);
            eff_row(&mut want, &prow, &nrow, l, 0);
            assert_eq!(fast, want, "case {case}");
        }
    }
}
