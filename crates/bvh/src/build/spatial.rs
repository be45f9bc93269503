//! Spatial splits: the SBVH build (Stich, Friedrich & Dietrich 2009, "Spatial Splits in
//! Bounding Volume Hierarchies", HPG 2009), the default of the binned SAH build
//! ([`BuildOptions::spatial_splits`]; `false` builds the object-split tree).
//!
//! Per node (§4):
//! - the binned object split of the parent module, and the surface area `λ` of the overlap of
//!   its two children's boxes;
//! - if `λ > α · A(root)` (§4.5, `split_alpha`) and `λ > β · A(node)` (`split_overlap`: the
//!   object split's children overlap by a sizeable part of the node itself, which the root
//!   rule alone does not ask of large nodes), the node has at least [`MIN_SPATIAL_REFS`]
//!   references and duplication budget is left, a spatial split: up to `SPATIAL_BINS`
//!   equal-width bins per axis over the node's box (`4 + n / 20`, as the object bins); each
//!   reference records an entry (and its box) in the bin of its minimum and an exit (and its
//!   box) in the bin of its maximum; a sweep gives `A(left) N(entries left) + A(right)
//!   N(exits right)` per plane (§4.2), each side's box being the union of the references' boxes
//!   clipped to the side's bins (computed from the per-bin unions, `sweep_axis`); a bin keeps
//!   its boxes as the minimum and the negated maximum (`NegBox`, Embree's layout), so that a
//!   union is one 8-lane minimum (AVX, with a portable twin tested equal);
//! - the cheaper of the two (or a leaf) is taken. A spatial split sends each reference that
//!   straddles the plane to both sides with "chopped" boxes (the box of the triangle's part on
//!   that side, intersected with the reference's box, §4.2), unless moving it whole to one side
//!   is cheaper ("reference unsplitting", §4.4).
//!
//! The binning clips boxes, not triangles (the paper chops the triangle in every bin it
//! crosses): on Sponza and the classroom that estimate chose trees with the same nodes per ray
//! as exact chopping (within 0.3%) at a fraction of the binning cost (`docs/notes/bvh.md`).
//! The partition always chops exactly.
//!
//! **Exact bounds.** The piece of a reference on one side of a plane is bounded by the
//! triangle's vertices on that side and its edges' crossings of the plane; the crossings are
//! widened by a relative `2^-18` on the two other axes (more than the rounding of the edge
//! interpolation), so every piece's box contains the exact part of the triangle it stands for,
//! and the pieces of one triangle cover it. A ray's closest hit therefore lies in the box of a
//! leaf holding the triangle, and the traversal (which tests the whole triangle in every leaf)
//! finds it.
//!
//! **Duplication budget** (as Embree's split factor): the reference array gets
//! `split_budget · n` spare slots; a node owns a capacity range and splits its spare slots
//! between its children in proportion to their reference counts. A spatial split is taken
//! only if both sides fit the node's capacity. The arena layout of [`BTree`] is over capacity
//! slots (a subtree owning capacity `c` owns `2 c - 1` arena slots), so the recursion keeps
//! writing disjoint slices in parallel; slots past a node's references stay unused.

use glam::{Vec3, Vec3A};
use parallax_core::Aabb;
use rayon::prelude::*;

use super::object_bins::{sah_count, trunc3};
use super::prim_ref::{BoxA, NegBox};
use super::{
    BNode, BTree, Bins, MAX_SAH_DEPTH, PAR_BIN_THRESHOLD, PrimRef, find_object_split, median_split,
    new_arena, new_bins, node_bounds, object_partition,
};
use crate::options::BuildOptions;

/// Most spatial bins per axis (Embree's `SPATIAL_BINS` is 16 as well); smaller nodes get
/// fewer, as the object bins (`4 + n / 20`): a reference is clipped once per boundary it
/// crosses, and in small nodes most references cross most bins.
const SPATIAL_BINS: usize = 16;

/// Nodes with fewer references do not try spatial splits. Measured (`docs/notes/bvh.md`,
/// 2026-12-03): the splits taken are in large nodes, and the nodes below 256 references
/// held most of the binning work while changing nodes per ray by under 1%.
const MIN_SPATIAL_REFS: usize = 256;

/// Triangle corners by reference id.
pub(crate) type Corners<'a> = &'a (dyn Fn(u32) -> [Vec3; 3] + Sync);

struct Ctx<'a> {
    corners: Corners<'a>,
    opts: &'a BuildOptions,
    /// `α · A(root)`: object splits whose children overlap by more try a spatial split.
    min_overlap: f32,
}

/// The references' capacity for `n` triangles: `n` and the duplication budget (module docs).
pub(crate) fn reference_capacity(n: usize, opts: &BuildOptions) -> usize {
    n + (n as f64 * opts.split_budget as f64) as usize
}

/// Builds the binary tree with spatial splits over the `n` references at the start of `refs`
/// (`n > 0`, one reference per triangle; `refs.len()` is [`reference_capacity`]`(n)`, the rest
/// being room for the duplicates); on return every leaf's range in `refs` holds that leaf's
/// references (clipped boxes, the triangle's id), and slots outside leaves are unused.
pub(crate) fn build_binary_spatial(
    refs: &mut [PrimRef],
    n: usize,
    corners: Corners<'_>,
    opts: &BuildOptions,
) -> BTree {
    let cap = refs.len();
    debug_assert_eq!(cap, reference_capacity(n, opts));
    let (init, spare) = refs.split_at_mut(n);
    spare.fill(init[0]);
    let mut nodes = new_arena(2 * cap - 1);
    let (root_box, _) = node_bounds(&refs[..n]);
    let ctx = Ctx {
        corners,
        opts,
        min_overlap: opts.split_alpha * root_box.surface_area(),
    };
    let root = build_rec(refs, n, 0, &mut nodes, 0, &ctx, &mut new_bins());
    BTree { nodes, root }
}

/// Builds the subtree over the `n` references at the start of `refs` (the capacity range from
/// `offset` on, `refs.len()` slots) into `arena` (`2 refs.len() - 1` slots); returns its root.
fn build_rec(
    refs: &mut [PrimRef],
    n: usize,
    offset: u32,
    arena: &mut [BNode],
    depth: u32,
    ctx: &Ctx,
    scratch: &mut Bins,
) -> u32 {
    let cap = refs.len();
    let opts = ctx.opts;
    debug_assert!(n >= 1 && n <= cap && arena.len() == 2 * cap - 1);
    let (bounds, cbounds) = node_bounds(&refs[..n]);
    let leaf = |arena: &mut [BNode]| {
        arena[0] = BNode::Leaf {
            bounds,
            start: offset,
            count: n as u32,
        };
        2 * offset
    };
    if n <= 1 {
        return leaf(arena);
    }
    let (n_l, n_r) = if depth >= MAX_SAH_DEPTH || cbounds.extent().max_element() <= 0.0 {
        if n <= opts.max_leaf_size {
            return leaf(arena);
        }
        let mid = median_split(&mut refs[..n], &cbounds);
        (mid, n - mid)
    } else {
        match split(refs, n, &bounds, &cbounds, ctx, scratch) {
            Some(s) => s,
            None => return leaf(arena),
        }
    };
    // The left side keeps its references at the front; the right side's (now at
    // `n_l..n_l + n_r`) move to the start of its capacity range. A left side too small for
    // spatial splits gets no spare slots (the right side then stays where it is).
    let spare = cap - n_l - n_r;
    let c_l = if n_l >= MIN_SPATIAL_REFS {
        n_l + (spare as u64 * n_l as u64 / (n_l + n_r) as u64) as usize
    } else {
        n_l
    };
    if c_l != n_l {
        refs.copy_within(n_l..n_l + n_r, c_l);
    }
    let (l, r) = refs.split_at_mut(c_l);
    let off_r = offset + c_l as u32;
    let (arena_l, rest) = arena.split_at_mut(2 * c_l - 1);
    let (slot, arena_r) = rest.split_first_mut().expect("2 cap - 1 slots");
    let (a, b) = if n > opts.parallel_threshold {
        rayon::join(
            || build_rec(l, n_l, offset, arena_l, depth + 1, ctx, scratch),
            || build_rec(r, n_r, off_r, arena_r, depth + 1, ctx, &mut new_bins()),
        )
    } else {
        (
            build_rec(l, n_l, offset, arena_l, depth + 1, ctx, scratch),
            build_rec(r, n_r, off_r, arena_r, depth + 1, ctx, scratch),
        )
    };
    *slot = BNode::Inner {
        bounds,
        children: [a, b],
    };
    2 * off_r - 1
}

/// Chooses between a leaf, the object split and a spatial split of the node over
/// `refs[..n]`; for a split, lays out its sides at `refs[..n_l]` and `refs[n_l..n_l + n_r]`
/// (`n_l + n_r <= refs.len()`) and returns `(n_l, n_r)`.
fn split(
    refs: &mut [PrimRef],
    n: usize,
    bounds: &Aabb,
    cbounds: &Aabb,
    ctx: &Ctx,
    scratch: &mut Bins,
) -> Option<(usize, usize)> {
    let opts = ctx.opts;
    let o = find_object_split(&refs[..n], cbounds, opts, scratch);
    let mut best = o.cost;
    let mut spatial = None;
    if o.cost.is_finite() && n < refs.len() && n >= MIN_SPATIAL_REFS {
        let (bl, br) = (
            scratch.union(o.axis, 0..o.split),
            scratch.union(o.axis, o.split..o.binner.bins),
        );
        let overlap = BoxA {
            min: bl.min.max(br.min),
            max: bl.max.min(br.max),
        };
        let lambda = overlap.aabb().surface_area();
        if lambda > ctx.min_overlap
            && lambda > opts.split_overlap * bounds.surface_area()
            && let Some(s) = find_spatial_split(&refs[..n], bounds, opts.sah_block_size)
            && s.cost < best
            && (s.n_l + s.n_r) as usize <= refs.len()
        {
            best = s.cost;
            spatial = Some(s);
        }
    }
    let area = bounds.surface_area();
    let split_cost = opts.traversal_cost * area + opts.intersection_cost * best;
    let leaf_cost = opts.intersection_cost * area * sah_count(n as u32, opts.sah_block_size);
    if n <= opts.max_leaf_size && leaf_cost <= split_cost {
        return None;
    }
    if let Some(s) = spatial {
        let (n_l, n_r) = spatial_partition(refs, n, &s, ctx);
        if n_l > 0 && n_r > 0 {
            return Some((n_l, n_r));
        }
        // Chopping (a side without a part of some triangle) and unsplitting moved every
        // reference to one side: split those (still covering the node) at the median.
        let m = n_l + n_r;
        let (_, cb) = node_bounds(&refs[..m]);
        let mid = median_split(&mut refs[..m], &cb);
        return Some((mid, m - mid));
    }
    let mid = if o.cost.is_finite() {
        object_partition(&mut refs[..n], &o, cbounds)
    } else {
        median_split(&mut refs[..n], cbounds)
    };
    Some((mid, n - mid))
}

/// One spatial bin of one axis: the references whose box starts in it (`enter`, and the union
/// of their boxes) and those whose box ends in it (`exit`, likewise).
#[derive(Clone, Copy, Debug, PartialEq)]
struct SBin {
    enter_box: NegBox,
    exit_box: NegBox,
    enter: u32,
    exit: u32,
}

const EMPTY_SBIN: SBin = SBin {
    enter_box: NegBox::EMPTY,
    exit_box: NegBox::EMPTY,
    enter: 0,
    exit: 0,
};

type SBins = [[SBin; SPATIAL_BINS]; 3];

/// Equal-width bins over the node's box on each axis.
#[derive(Clone, Copy)]
struct Grid {
    bins: usize,
    lo: [f32; 3],
    width: [f32; 3],
    scale: [f32; 3],
    /// `lo` and `scale` in lanes (`w` = 0, so that a reference's `w` lane, its id bits, gives
    /// 0 and never a denormal), and `bins - 1` in every lane: [`Grid::bins3`].
    lo_v: Vec3A,
    scale_v: Vec3A,
    last_v: Vec3A,
}

impl Grid {
    fn new(bounds: &Aabb, bins: usize) -> Self {
        let e = bounds.extent();
        let mut g = Grid {
            bins,
            lo: bounds.min.to_array(),
            width: [0.0; 3],
            scale: [0.0; 3],
            lo_v: Vec3A::ZERO,
            scale_v: Vec3A::ZERO,
            last_v: Vec3A::splat((bins - 1) as f32),
        };
        for a in 0..3 {
            if e[a] > 0.0 {
                g.width[a] = e[a] / bins as f32;
                g.scale[a] = bins as f32 * (1.0 - 1e-6) / e[a];
            }
        }
        g.lo_v = Vec3A::from_vec4(bounds.min.extend(0.0));
        g.scale_v = Vec3A::from_vec4(Vec3::from(g.scale).extend(0.0));
        g
    }

    /// The bin of coordinate `x` on axis `a`: the scalar definition, which the tests hold
    /// [`Grid::bins3`] and [`Grid::at_or_after`] to.
    #[cfg(test)]
    fn bin(&self, x: f32, a: usize) -> usize {
        let i = (((x - self.lo[a]) * self.scale[a]) as i32).clamp(0, self.bins as i32 - 1);
        i as usize & (SPATIAL_BINS - 1)
    }

    /// [`Grid::bin`] of the three coordinates of `p` at once, in lanes: the same subtraction
    /// and product, then `last < f ? last : f` (keeps a NaN) and `x > 0 ? x : 0` (turns it and
    /// negatives into 0) before the truncation, which is `(f as i32).clamp(0, bins - 1)` for
    /// every `f` (as the object binner's `Binner::bin`).
    #[inline(always)]
    fn bins3(&self, p: Vec3A) -> [usize; 3] {
        let f = (p - self.lo_v) * self.scale_v;
        let i = trunc3(self.last_v.min(f).max(Vec3A::ZERO));
        [
            i[0] as usize & (SPATIAL_BINS - 1),
            i[1] as usize & (SPATIAL_BINS - 1),
            i[2] as usize & (SPATIAL_BINS - 1),
        ]
    }

    /// Bit `a` set when [`Grid::bin`] of `p[a]` is `split` or more (`split` in `1..bins`):
    /// `(f as i32).clamp(0, bins - 1) >= split` holds exactly when `f >= split` (the
    /// truncation of `f < split` is below `split`, a NaN bins to 0 and compares false), with
    /// `f` the same subtraction and product as in [`Grid::bin`], in lanes.
    #[inline(always)]
    fn at_or_after(&self, p: Vec3A, split: usize) -> u32 {
        let f = (p - self.lo_v) * self.scale_v;
        f.cmpge(Vec3A::splat(split as f32)).bitmask()
    }

    /// The plane between bins `i - 1` and `i`.
    #[inline(always)]
    fn plane(&self, i: usize, a: usize) -> f32 {
        self.lo[a] + i as f32 * self.width[a]
    }
}

/// The best spatial split found: unnormalised SAH cost, axis, plane, the sides' boxes and
/// reference counts as the bins estimate them.
struct SpatialSplit {
    cost: f32,
    axis: usize,
    split: usize,
    grid: Grid,
    left: BoxA,
    right: BoxA,
    n_l: u32,
    n_r: u32,
}

/// The spatial bins of `refs`: [`bin_spatial_avx`] where the CPU has AVX, else
/// [`bin_spatial_portable`] (tested equal).
fn bin_spatial(refs: &[PrimRef], grid: &Grid) -> SBins {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx") {
        // SAFETY: AVX is present.
        return unsafe { bin_spatial_avx(refs, grid) };
    }
    bin_spatial_portable(refs, grid)
}

fn bin_spatial_portable(refs: &[PrimRef], grid: &Grid) -> SBins {
    let mut bins = [[EMPTY_SBIN; SPATIAL_BINS]; 3];
    let [b_x, b_y, b_z] = &mut bins;
    for r in refs {
        let bx = NegBox::of(r);
        let (b0, b1) = (grid.bins3(r.min()), grid.bins3(r.max()));
        bin_axis(bx, b0[0], b1[0], b_x);
        bin_axis(bx, b0[1], b1[1], b_y);
        bin_axis(bx, b0[2], b1[2], b_z);
    }
    bins
}

/// [`bin_spatial_portable`] with each box union as one 8-lane `vminps` (and the reference's
/// [`NegBox`] as one load and one sign flip).
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn bin_spatial_avx(refs: &[PrimRef], grid: &Grid) -> SBins {
    use std::arch::x86_64::*;
    let mut bins = [[EMPTY_SBIN; SPATIAL_BINS]; 3];
    let neg_hi = _mm256_setr_ps(0.0, 0.0, 0.0, 0.0, -0.0, -0.0, -0.0, -0.0);
    for r in refs {
        // SAFETY: `PrimRef` is `lo`, `hi` in 32 aligned bytes (`repr(C, align(32))`), as
        // `NegBox`; the bins are `NegBox`es.
        unsafe {
            let v = _mm256_xor_ps(_mm256_load_ps(r as *const PrimRef as *const f32), neg_hi);
            let (b0, b1) = (grid.bins3(r.min()), grid.bins3(r.max()));
            for (a, axis) in bins.iter_mut().enumerate() {
                let e = &mut axis[b0[a]];
                e.enter += 1;
                let p = &mut e.enter_box as *mut NegBox as *mut f32;
                _mm256_store_ps(p, _mm256_min_ps(_mm256_load_ps(p), v));
                let x = &mut axis[b1[a]];
                x.exit += 1;
                let p = &mut x.exit_box as *mut NegBox as *mut f32;
                _mm256_store_ps(p, _mm256_min_ps(_mm256_load_ps(p), v));
            }
        }
    }
    bins
}

/// Bins one reference (box `bx`, from bin `b0` to bin `b1`) on axis `A`: an entry (and its
/// box) in the bin of its minimum, an exit (and its box) in the bin of its maximum. The sweep
/// clips the unions to the plane ([`sweep_axis`]), which gives the boxes of the reference's
/// box clipped to every bin it crosses (module docs: the binning does not clip the triangle)
/// without visiting those bins. An axis of zero extent (scale 0) is binned too, all in bin 0,
/// and the sweep skips it.
#[inline(always)]
fn bin_axis(bx: NegBox, b0: usize, b1: usize, bins: &mut [SBin; SPATIAL_BINS]) {
    let e = &mut bins[b0];
    e.enter += 1;
    e.enter_box = e.enter_box.union(bx);
    let x = &mut bins[b1];
    x.exit += 1;
    x.exit_box = x.exit_box.union(bx);
}

fn merge_sbins(mut a: SBins, b: SBins) -> SBins {
    for (x, y) in a.iter_mut().flatten().zip(b.iter().flatten()) {
        x.enter_box = x.enter_box.union(y.enter_box);
        x.exit_box = x.exit_box.union(y.exit_box);
        x.enter += y.enter;
        x.exit += y.exit;
    }
    a
}

fn find_spatial_split(refs: &[PrimRef], bounds: &Aabb, block: usize) -> Option<SpatialSplit> {
    let grid = Grid::new(bounds, SPATIAL_BINS.min(4 + refs.len() / 20));
    let bins = if refs.len() > PAR_BIN_THRESHOLD {
        refs.par_chunks(8192)
            .map(|c| bin_spatial(c, &grid))
            .reduce(|| [[EMPTY_SBIN; SPATIAL_BINS]; 3], merge_sbins)
    } else {
        bin_spatial(refs, &grid)
    };
    let mut best: Option<SpatialSplit> = None;
    for (axis, bins) in bins.iter().enumerate() {
        if grid.scale[axis] == 0.0 {
            continue;
        }
        sweep_axis(bins, &grid, axis, block, &mut best);
    }
    best
}

/// The plane sweep over the bins of one axis; keeps the cheapest split in `best`.
///
/// The box of the left side at plane `i` is the union of the references' boxes clipped to
/// the bins `0..i`: a reference that ends left of the plane (`exit` bin `< i`) adds its whole
/// box; one that starts left and ends right adds its box with the maximum on the axis lowered
/// to the plane. Since `min(max(a, b), p) = max(min(a, p), min(b, p))`, that is the union of
/// the exit boxes of bins `0..i` and the union of the entry boxes of bins `0..i` with its
/// maximum lowered to the plane (a box clipped that way lies inside the reference's whole box
/// when the reference also ends left). The right side mirrors it. These are the boxes (and
/// the costs) of clipping each reference to every bin it crosses, without visiting those bins.
fn sweep_axis(
    bins: &[SBin; SPATIAL_BINS],
    grid: &Grid,
    axis: usize,
    block: usize,
    best: &mut Option<SpatialSplit>,
) {
    let nb = grid.bins;
    let mut right = [(BoxA::EMPTY, 0u32, 0.0f32); SPATIAL_BINS];
    let (mut whole, mut cut, mut cnt) = (BoxA::EMPTY, BoxA::EMPTY, 0u32);
    for i in (1..nb).rev() {
        whole = whole.union(bins[i].enter_box.boxa());
        cut = cut.union(bins[i].exit_box.boxa());
        cnt += bins[i].exit;
        let mut c = cut;
        c.min[axis] = c.min[axis].max(grid.plane(i, axis));
        let acc = whole.union(c);
        right[i] = (acc, cnt, acc.aabb().surface_area() * sah_count(cnt, block));
    }
    let (mut whole, mut cut, mut cnt) = (BoxA::EMPTY, BoxA::EMPTY, 0u32);
    for i in 1..nb {
        whole = whole.union(bins[i - 1].exit_box.boxa());
        cut = cut.union(bins[i - 1].enter_box.boxa());
        cnt += bins[i - 1].enter;
        let (rb, rn, rc) = right[i];
        if cnt == 0 || rn == 0 {
            continue;
        }
        let mut c = cut;
        c.max[axis] = c.max[axis].min(grid.plane(i, axis));
        let acc = whole.union(c);
        let cost = acc.aabb().surface_area() * sah_count(cnt, block) + rc;
        if best.as_ref().is_none_or(|b| cost < b.cost) {
            *best = Some(SpatialSplit {
                cost,
                axis,
                split: i,
                grid: *grid,
                left: acc,
                right: rb,
                n_l: cnt,
                n_r: rn,
            });
        }
    }
}

/// Applies the spatial split `s` to `refs[..n]`: references entirely left of the plane stay
/// at the front, those entirely right follow them; a straddling one goes whole to one side
/// when that is cheaper (unsplitting, §4.4), else its clipped pieces go to both. Returns the
/// side sizes (their sum fits `refs.len()`: the sweep's counts bound it, and the caller checked
/// them).
fn spatial_partition(
    refs: &mut [PrimRef],
    n: usize,
    s: &SpatialSplit,
    ctx: &Ctx,
) -> (usize, usize) {
    let (a, pos) = (s.axis, s.grid.plane(s.split, s.axis));
    let bit = 1u32 << a;
    let (mut lb, mut rb) = (s.left, s.right);
    let (mut nl, mut nr) = (s.n_l as f32, s.n_r as f32);
    let mut right: Vec<PrimRef> = Vec::with_capacity(s.n_r as usize);
    let mut w = 0;
    for i in 0..n {
        let r = refs[i];
        let bx = BoxA {
            min: r.min(),
            max: r.max(),
        };
        // `bin(max) < split`, `bin(min) >= split` ([`Grid::at_or_after`]).
        if s.grid.at_or_after(bx.max, s.split) & bit == 0 {
            refs[w] = r;
            w += 1;
            continue;
        }
        if s.grid.at_or_after(bx.min, s.split) & bit != 0 {
            right.push(r);
            continue;
        }
        let (l, rr) = split_box(&(ctx.corners)(r.id()), bx, a, pos);
        let (l_empty, r_empty) = (is_empty(l), is_empty(rr));
        if l_empty || r_empty {
            // Only one side holds a part of the triangle: that part, whole.
            if l_empty {
                right.push(r.with_box(rr));
            } else {
                refs[w] = r.with_box(l);
                w += 1;
            }
            continue;
        }
        let (al, ar) = (area(lb), area(rb));
        let c_split = al * nl + ar * nr;
        let c_left = area(lb.union(bx)) * nl + ar * (nr - 1.0);
        let c_right = al * (nl - 1.0) + area(rb.union(bx)) * nr;
        if c_left < c_split && c_left <= c_right {
            lb = lb.union(bx);
            nr -= 1.0;
            refs[w] = r;
            w += 1;
        } else if c_right < c_split {
            rb = rb.union(bx);
            nl -= 1.0;
            right.push(r);
        } else {
            refs[w] = r.with_box(l);
            w += 1;
            right.push(r.with_box(rr));
        }
    }
    debug_assert!(w + right.len() <= refs.len());
    refs[w..w + right.len()].copy_from_slice(&right);
    (w, right.len())
}

#[inline(always)]
fn area(b: BoxA) -> f32 {
    b.aabb().surface_area()
}

#[inline(always)]
fn is_empty(b: BoxA) -> bool {
    b.min.cmpgt(b.max).any()
}

/// The boxes of the parts of triangle `tri` on either side of the plane `x[a] = pos`,
/// intersected with `bx` (the box of the part of the triangle the reference stands for);
/// conservative (module docs). A side without a part of the triangle gets an empty box.
fn split_box(tri: &[Vec3; 3], bx: BoxA, a: usize, pos: f32) -> (BoxA, BoxA) {
    let tri = tri.map(Vec3A::from);
    match a {
        0 => split_box_axis::<0>(&tri, bx, pos),
        1 => split_box_axis::<1>(&tri, bx, pos),
        _ => split_box_axis::<2>(&tri, bx, pos),
    }
}

/// [`split_box`] on the axis `A`.
#[inline(always)]
fn split_box_axis<const A: usize>(tri: &[Vec3A; 3], bx: BoxA, pos: f32) -> (BoxA, BoxA) {
    let (mut l, mut r) = (BoxA::EMPTY, BoxA::EMPTY);
    // Relative widening of the crossings on the two other axes (zero on the split axis).
    let pad = Vec3A::select(
        glam::BVec3A::new(A == 0, A == 1, A == 2),
        Vec3A::ZERO,
        Vec3A::splat(1.0 / (1 << 18) as f32),
    );
    let on_plane = glam::BVec3A::new(A == 0, A == 1, A == 2);
    for k in 0..3 {
        let (v, w) = (tri[k], tri[(k + 1) % 3]);
        let (va, wa) = (v[A], w[A]);
        if va <= pos {
            l = l.grow(v);
        }
        if va >= pos {
            r = r.grow(v);
        }
        if (va < pos && wa > pos) || (va > pos && wa < pos) {
            let t = ((pos - va) / (wa - va)).clamp(0.0, 1.0);
            let p = Vec3A::select(on_plane, Vec3A::splat(pos), v + (w - v) * t);
            let m = v.abs().max(w.abs()) * pad;
            let c = BoxA {
                min: p - m,
                max: p + m,
            };
            l = l.union(c);
            r = r.union(c);
        }
    }
    let clip = |b: BoxA| BoxA {
        min: b.min.max(bx.min),
        max: b.max.min(bx.max),
    };
    (clip(l), clip(r))
}

#[cfg(test)]
#[path = "spatial_tests.rs"]
mod tests;
