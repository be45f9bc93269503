//! One layer's quad-tree: leaves from per-pixel planes (Widmer et al. 2015, §3.2) and
//! bottom-up adaptive pruning (§3.3).
//!
//! **Leaves.** Pixel `(i, j)` with a plane in [`LayerPlanes`] becomes a plane node with the
//! plane's cube gradient (computed in f64 from the mapped plane, stored as f16 slopes across
//! the footprint, [`super::node`]) and `z_c` = the cube `z` of the pixel's sample (the
//! pixel-centre ray at the captured view depth, which the plane passes through), flag `O`
//! from the normal source. Pixels without a plane, and samples in front of the cube's near plane (`z < 0`,
//! only possible with a caller-made cube narrower than the depths), are empty.
//!
//! **Pruning (§3.3).** A parent becomes a plane node iff
//! 1. all four children are plane nodes;
//! 2. with the proxy normal `N` = the normalised mean of the (decoded) child normals, every
//!    child normal satisfies `N·N_i > gamma_norm` (angle below `acos(gamma_norm)`);
//! 3. the *corner distance* is below `gamma_dist`: for the 16 points `p_ij` = child `i`'s
//!    plane at its footprint corner `j`, the proxy offset is the least-squares solution of
//!    §3.3 with `v = (0, 0, 1)`, `c = mean_ij(N·p_ij)`, and the corner distance is
//!    `max_ij |N·p_ij - c| / |N·v|` — the distance along the reference view direction
//!    (cube `z` units) between child plane and proxy plane at each child corner.
//!
//! Otherwise the parent is an AABB node whose `[min z, max z]` is the union of its children's
//! ranges; a plane child contributes its plane's `z` at its four footprint corners (a plane
//! is linear, so that is its exact range over the footprint; the footprint is dilated by the
//! crack dilation for flagged planes), widened by [`Z_EPS`](super::tree::Z_EPS) and clamped to `[0, 1]` (the
//! ray never leaves the cube). Boxes are therefore conservative: the traversal never skips a
//! node holding a plane the ray crosses. Merging is evaluated on the *decoded* children, so
//! the error bound of condition 3 refers to what the tree actually stores (up to the proxy's
//! own f16/f32 rounding).
//!
//! Every level is built in parallel over rows (rayon). **Fast paths, same bits:** the leaves
//! are made a row at a time (`leaves.rs`), their directions from per-column and per-row
//! tables of the same products and `z` with [`UnitCube::z_of_depth`]'s constant terms
//! computed once, four pixels at a time in AVX2 lanes (`leaf_avx2`, run-time detection) or
//! one pixel at a time in SSE2 lanes (`leaf_lanes`);
//! a level's merges run with four parents in lanes (`merge_rows`); without deeper layers the
//! per-pixel plane levels come from level 1 down (`tree::plane_levels`); with deeper layers
//! the pruning fixed point is computed incrementally (`fixpoint`), its pixel-plane trigger
//! depths in the leaf pass. `QuadTree::build_cascaded` with `reference` runs the scalar
//! definitions instead (`QuadTreeTracer::build_reference`); the tests compare the two tree
//! for tree (`tests/quadtree_build.rs`).

use glam::Vec3;
use parallax_core::{GBuffer, Image};
use parallax_raster::normals::normals_from_depth;
use rayon::prelude::*;

use super::QuadTreeOptions;
use super::leaves::Leaves;
use super::merge::MergeCtx;
use super::node::{FLAG_CRACK, Node};
use super::prune::Blocked;
use super::tree::{
    Level, QuadTree, Z_FLOOR_TABLE_MAX, Z_REGION_MIN_GAIN, Z_SKIP_MARGIN, init_row, plane_levels,
};
use crate::planes::layer_size;
use crate::{LayerPlanes, NormalSource, ScreenError, UnitCube};

impl QuadTree {
    /// Builds the tree of `layer` (captured from `cube.camera`). The leaves are computed in
    /// parallel with exactly the arithmetic of [`LayerPlanes::build`] (same per-pixel sample
    /// point and [`UnitCube::map_plane`]).
    pub fn build(
        cube: &UnitCube,
        layer: &GBuffer,
        opts: &QuadTreeOptions,
    ) -> Result<Self, ScreenError> {
        Self::build_cascaded(cube, layer, opts, &[], false)
    }

    /// [`Self::build`] for a layer followed by the `deeper` layers' effective planes: the
    /// cascade trigger depths are computed from this layer's effective planes, pruning never
    /// merges over an unsafe pixel (so its effective plane is the pixel plane the trigger
    /// depth was derived from; a pixel that only a merged proxy plane makes unsafe is
    /// blocked and the levels rebuilt, to a fixed point), and the unsafe pixels are marked
    /// (see [`super::cascade`]). `reference`: by the scalar definitions (the slow twin).
    pub(crate) fn build_cascaded(
        cube: &UnitCube,
        layer: &GBuffer,
        opts: &QuadTreeOptions,
        deeper: &[LayerPlanes],
        reference: bool,
    ) -> Result<Self, ScreenError> {
        let cam = &cube.camera;
        let (w, h) = layer_size(cube, layer)?;
        let depth_normals;
        let (normals, flags): (&[Vec3], Option<&[bool]>) = match opts.normals {
            NormalSource::GBuffer | NormalSource::GBufferFlagged { .. } => (&layer.normal, None),
            NormalSource::Depth { max_rel_error } => {
                let depth = Image::from_vec(w, h, layer.depth.clone())?;
                depth_normals = normals_from_depth(&depth, cam, max_rel_error)?;
                (
                    depth_normals.normals.data(),
                    Some(depth_normals.discontinuity.data()),
                )
            }
        };
        let leaves = Leaves::new(cube, &layer.depth, normals, flags, w, h);
        let NormalSource::GBufferFlagged {
            min_rel_gap,
            max_rel_gap,
        } = opts.normals
        else {
            return Self::from_leaf_rows(cube, w, h, opts, deeper, reference, |row, j| {
                leaves.row(row, j, reference)
            });
        };
        // G-buffer normals: the leaves first, then flag `O` from their decoded planes
        // ([`crate::planes::crack_flags`]).
        let mut nodes = vec![Node::EMPTY; (w as usize) * (h as usize)];
        nodes
            .par_chunks_mut(w as usize)
            .enumerate()
            .for_each(|(j, row)| leaves.row(row, j as u32, reference));
        let o = gbuffer_flags(cube, w, h, &nodes, min_rel_gap, max_rel_gap);
        Self::from_leaf_rows(cube, w, h, opts, deeper, reference, |row, j| {
            let k0 = (j * w) as usize;
            for (i, out) in row[..w as usize].iter_mut().enumerate() {
                let n = nodes[k0 + i];
                *out = if o[k0 + i] {
                    Node {
                        a: n.a | FLAG_CRACK,
                        ..n
                    }
                } else {
                    n
                };
            }
        })
    }

    /// Builds the tree from precomputed planes and the layer's view depths.
    pub fn from_planes(
        cube: &UnitCube,
        planes: &LayerPlanes,
        depth: &[f32],
        opts: &QuadTreeOptions,
    ) -> Result<Self, ScreenError> {
        let (w, h) = (planes.width, planes.height);
        if (w, h) != (cube.camera.width, cube.camera.height) || depth.len() != planes.normal.len() {
            return Err(ScreenError::Mismatch(format!(
                "planes {w}x{h} / {} depths vs camera {}x{}",
                depth.len(),
                cube.camera.width,
                cube.camera.height
            )));
        }
        let leaf = |k: usize| {
            if !planes.covered(k) {
                return Node::EMPTY;
            }
            let n = planes.normal[k];
            let flags = if planes.flag[k] { FLAG_CRACK } else { 0 };
            // Gradient of the plane `n·P = c`: `-(n.x, n.y) / n.z` (`n.z <= 0`).
            let (gx, gy) = (n.x / -n.z, n.y / -n.z);
            let (wf, hf) = (w as f32, h as f32);
            Node::plane_with_gradient(cube.z_of_depth(depth[k]), gx, gy, 0, wf, hf, flags)
                .unwrap_or(Node::EMPTY)
        };
        Self::from_leaf_rows(cube, w, h, opts, &[], false, |row, j| {
            let k0 = (j * w) as usize;
            for (i, out) in row[..w as usize].iter_mut().enumerate() {
                *out = leaf(k0 + i);
            }
        })
    }

    /// The tree whose leaves of pixel row `j` (the first `w` nodes of a padded level-0 row)
    /// `leaf_row(row, j)` writes.
    fn from_leaf_rows(
        cube: &UnitCube,
        w: u32,
        h: u32,
        opts: &QuadTreeOptions,
        deeper: &[LayerPlanes],
        reference: bool,
        leaf_row: impl Fn(&mut [Node], u32) + Sync,
    ) -> Result<Self, ScreenError> {
        if !(opts.crack_dilation.is_finite() && opts.crack_dilation >= 0.0) {
            return Err(ScreenError::InvalidSpace(format!(
                "crack_dilation must be finite and >= 0, got {}",
                opts.crack_dilation
            )));
        }
        let full = 32 - (w.max(h) - 1).leading_zeros() + 1; // ceil(log2 max) + 1
        let nlev = opts.max_levels.clamp(1, full.max(1));
        let top = nlev - 1;
        let top_w = w.div_ceil(1 << top);
        let top_h = h.div_ceil(1 << top);
        let (wf, hf) = (w as f32, h as f32);
        let ctx = MergeCtx {
            wf,
            hf,
            cos_norm: opts.gamma_norm,
            gamma_dist: opts.gamma_dist,
            adaptive: opts.adaptive,
            near: cube.near as f64,
            far: cube.far as f64,
            crack_px: opts.crack_dilation,
            never: !(opts.gamma_norm < 1.0 && opts.gamma_dist > 0.0),
            lanes: !reference,
        };

        // Level 0: leaves (§3.2).
        // Every row is set empty right before its leaves are written (in cache, no fill pass
        // over the level first), the padding rows below the image too.
        let (w0, h0) = (top_w << top, top_h << top);
        let (n0, n_img, n_px) = ((w0 * h0) as usize, (w0 * h) as usize, (w * h) as usize);
        let mut leaves: Vec<Node> = Vec::with_capacity(n0);
        // With deeper layers (fast path), each row's pixel-plane trigger depths right after
        // its leaves (`fixpoint`), and the pixels where they are finite.
        let mut px_triggers = None;
        let (image, padding) = leaves.spare_capacity_mut()[..n0].split_at_mut(n_img);
        padding.par_chunks_mut(w0 as usize).for_each(|row| {
            init_row(row, Node::EMPTY);
        });
        // Level 1 when made in the leaf pass (`leaves_and_level1`).
        #[cfg_attr(not(target_arch = "x86_64"), allow(unused_mut))]
        let mut level1: Option<Level> = None;
        #[cfg(target_arch = "x86_64")]
        if !deeper.is_empty() && !reference && nlev >= 2 {
            let (l1, px) = leaves_and_level1(image, (w, h, w0, h0), &ctx, deeper, &leaf_row);
            level1 = Some(l1);
            px_triggers = Some(px);
        }
        if level1.is_some() {
            // Made with level 1 above.
        } else if !deeper.is_empty() && !reference {
            let cols = super::fixpoint::Columns::new(w, wf);
            // Every value is written by the row pass (`pixel_triggers_row`).
            let (mut tz, mut fronts) = (Vec::with_capacity(n_px), Vec::with_capacity(n_px));
            let listed: Vec<u32> = image
                .par_chunks_mut(w0 as usize)
                .zip(tz.spare_capacity_mut()[..n_px].par_chunks_mut(w as usize))
                .zip(fronts.spare_capacity_mut()[..n_px].par_chunks_mut(w as usize))
                .enumerate()
                .flat_map_iter(|(j, ((row, t), f))| {
                    let j = j as u32;
                    let row = init_row(row, Node::EMPTY);
                    leaf_row(row, j);
                    super::fixpoint::pixel_triggers_row(t, f, row, j, &ctx, &cols, deeper)
                })
                .collect();
            // SAFETY: the rows cover `0..n_px` and `pixel_triggers_row` wrote every value.
            unsafe {
                tz.set_len(n_px);
                fronts.set_len(n_px);
            }
            px_triggers = Some((tz, listed, fronts));
        } else {
            image
                .par_chunks_mut(w0 as usize)
                .enumerate()
                .for_each(|(j, row)| leaf_row(init_row(row, Node::EMPTY), j as u32));
        }
        // SAFETY: the image rows and the padding rows cover `0..n0`, each initialised by
        // `init_row`.
        unsafe { leaves.set_len(n0) };
        let level0 = Level {
            w: w0,
            h: h0,
            nodes: leaves,
        };
        let (levels, tz, eff, unsafe_px) = if deeper.is_empty() {
            let levels = super::prune::prune(&ctx, level0, nlev, Blocked::None, w, h);
            // No cascade: the plane levels straight from level 1 (`plane_levels`).
            (levels, Vec::new(), Vec::new(), None)
        } else if reference {
            let (levels, tz, eff) =
                super::prune::fixed_point_reference(&ctx, level0, nlev, (w, h), deeper);
            (levels, tz, eff, None)
        } else {
            let px = px_triggers.expect("computed with the leaves");
            let first = [Some(level0), level1].into_iter().flatten().collect();
            super::fixpoint::fixed_point(&ctx, first, nlev, (w, h), deeper, px)
        };
        let mut tree = Self::from_levels(w, h, levels, opts.crack_dilation);
        // Top-down: the small upper levels are scanned first.
        tree.plane_top = (0..tree.levels.len())
            .rev()
            .find(|&l| tree.levels[l].nodes.iter().any(|n| n.is_plane()))
            .unwrap_or(0);
        let top_tz = match unsafe_px {
            _ if tz.is_empty() => Vec::new(),
            Some(px) => {
                // The listed pixels are exactly those with a finite trigger depth.
                tree.unsafe_count = px.len();
                tree.mark_unsafe_listed(tz, &px)
            }
            None => {
                tree.unsafe_count = tz.iter().filter(|z| z.is_finite()).count();
                tree.mark_unsafe(tz)
            }
        };
        // `mark_unsafe` changes flags and AABB ranges but no node kinds: `eff` (the plane
        // levels of the fixed point's final levels) still holds.
        tree.plane_level = if eff.is_empty() {
            plane_levels(&tree.levels, w, h)
        } else {
            eff
        };
        // After `mark_unsafe` (it lowers AABB ranges to trigger depths).
        tree.set_z_floors(&ctx, &top_tz);
        Ok(tree)
    }

    /// [`Self::z_floor`] and the regional table [`Self::z_floor_rect`]: per top-level node
    /// holding image pixels its lower `z` bound (AABB range, or the footprint range of a
    /// plane node) and the trigger depths of its pixels; the floors subtract
    /// [`Z_SKIP_MARGIN`] and are clamped to 0. `top_tz`: per top-level node the smallest
    /// trigger depth under it (of [`Self::mark_unsafe`]; empty: none).
    fn set_z_floors(&mut self, ctx: &MergeCtx, top_tz: &[f32]) {
        let top = self.levels.len() - 1;
        let (w, h) = (self.width, self.height);
        let (tw, th) = (((w - 1) >> top) + 1, ((h - 1) >> top) + 1);
        let lv = &self.levels[top];
        let mut zn = vec![f32::INFINITY; (tw * th) as usize];
        for qy in 0..th {
            for qx in 0..tw {
                let n = lv.nodes[(qy * lv.w + qx) as usize];
                zn[(qy * tw + qx) as usize] = if n.is_plane() {
                    ctx.zrange(n, top as u32).0
                } else {
                    n.zrange().0
                };
            }
        }
        if !top_tz.is_empty() {
            // The smallest finite trigger depth of each top-level node's pixels.
            for qy in 0..th {
                for qx in 0..tw {
                    let z = top_tz[(qy * lv.w + qx) as usize];
                    let k = (qy * tw + qx) as usize;
                    if z.is_finite() && z < zn[k] {
                        zn[k] = z;
                    }
                }
            }
        }
        let floor = |z: f32| {
            if z - Z_SKIP_MARGIN > 0.0 {
                z - Z_SKIP_MARGIN
            } else {
                0.0
            }
        };
        // Nodes of the padding beyond the image are never visited (the traversal stops at
        // the image's edge), so only image nodes count, as before.
        self.z_floor = floor(zn.iter().copied().fold(f32::INFINITY, f32::min));
        let (tw_, th_) = (tw as usize, th as usize);
        if self.z_floor <= 0.0 {
            // A global floor of 0: regional floors would cost more time (the lookup and the
            // division on the chain to the start node) than their saved visits
            // (docs/notes/quadtree.md, regional floors): none.
            self.z_floor_dir = Vec::new();
            self.z_floor_rect = Vec::new();
            return;
        }
        self.z_floor_tw = tw;
        self.z_floor_th = th;
        let mut dir = vec![0.0; 2 * tw_ * th_];
        for r in 0..th_ {
            let row = &zn[r * tw_..(r + 1) * tw_];
            let mut m = f32::INFINITY;
            for c in (0..tw_).rev() {
                m = m.min(row[c]);
                dir[2 * (r * tw_ + c)] = floor(m);
            }
            let mut m = f32::INFINITY;
            for c in 0..tw_ {
                m = m.min(row[c]);
                dir[2 * (r * tw_ + c) + 1] = floor(m);
            }
        }
        // A regional floor only a little above the global one skips little and costs the
        // taken branch's longer chain to the start node (docs/notes/quadtree.md): keep the
        // global floor there.
        for f in &mut dir {
            if *f < self.z_floor + Z_REGION_MIN_GAIN {
                *f = self.z_floor;
            }
        }
        self.z_floor_dir = dir;
        if tw_ * tw_ * th_ * th_ > Z_FLOOR_TABLE_MAX {
            self.z_floor_rect = Vec::new();
            return;
        }
        let mut rect = vec![f32::INFINITY; tw_ * tw_ * th_ * th_];
        for r0 in 0..th_ {
            for r1 in r0..th_ {
                for c0 in 0..tw_ {
                    let mut m = f32::INFINITY;
                    for c1 in c0..tw_ {
                        for r in r0..=r1 {
                            m = m.min(zn[r * tw_ + c1]);
                        }
                        let f = floor(m);
                        rect[((r0 * th_ + r1) * tw_ + c0) * tw_ + c1] =
                            if f < self.z_floor + Z_REGION_MIN_GAIN {
                                self.z_floor
                            } else {
                                f
                            };
                    }
                }
            }
        }
        self.z_floor_rect = rect;
        self.z_floor_tw = tw;
        self.z_floor_th = th;
    }

    /// Marks pixels unsafe for cascading: `tz[k]` (`W x H`) is the cube `z` from which the
    /// column of pixel `k` belongs to the trigger region (`+inf`: safe). Pixel-level plane
    /// nodes get [`super::node::FLAG_UNSAFE`] and keep `tz` in [`Self::trigger_z`]; empty
    /// pixels become AABBs `(tz, -inf)`; every AABB above lowers its `min z` to the minimum
    /// `tz` below it; merged plane nodes above an unsafe pixel get the flag and trigger on
    /// footprint entry (conservative). Returns, per top-level node (`levels[top].w x
    /// levels[top].h`), the smallest `tz` under it.
    pub(crate) fn mark_unsafe(&mut self, tz: Vec<f32>) -> Vec<f32> {
        let (w, h) = (self.width as usize, self.height as usize);
        let nl = self.levels.len();
        if nl == 1 {
            let nodes = &mut self.levels[0].nodes;
            for (node, &m) in nodes.iter_mut().zip(&tz) {
                if m.is_finite() {
                    node.mark_unsafe(m);
                }
            }
            // The top level is level 0: its minima are `tz` itself.
            self.trigger_z = tz;
            return self.trigger_z.clone();
        }
        // Levels 0 and 1 in one pass over `tz` (`W x H`; the padding has no trigger depth):
        // per level-1 row, its two pixel rows are marked and their minima taken.
        let (lo, hi) = self.levels.split_at_mut(1);
        let (w0, w1) = (lo[0].w as usize, hi[0].w as usize);
        let mut cur = vec![f32::INFINITY; hi[0].nodes.len()];
        let tzr = &tz;
        lo[0]
            .nodes
            .par_chunks_mut(2 * w0)
            .zip(hi[0].nodes.par_chunks_mut(w1))
            .zip(cur.par_chunks_mut(w1))
            .enumerate()
            .for_each(|(qy, ((n0, n1), m1))| {
                for dy in 0..2 {
                    let y = 2 * qy + dy;
                    if y >= h {
                        break;
                    }
                    let t = &tzr[y * w..(y + 1) * w];
                    for (node, &m) in n0[dy * w0..].iter_mut().zip(t) {
                        if m.is_finite() {
                            node.mark_unsafe(m);
                        }
                    }
                }
                let c = |x: usize, y: usize| {
                    if x < w && y < h {
                        tzr[y * w + x]
                    } else {
                        f32::INFINITY
                    }
                };
                for (qx, (node, v)) in n1.iter_mut().zip(m1.iter_mut()).enumerate() {
                    let (x, y) = (2 * qx, 2 * qy);
                    let m = c(x, y)
                        .min(c(x + 1, y))
                        .min(c(x, y + 1))
                        .min(c(x + 1, y + 1));
                    *v = m;
                    if m.is_finite() {
                        node.mark_unsafe(m);
                    }
                }
            });
        // Per node, the smallest trigger depth under it (from the level below), marked in
        // the same pass.
        for l in 2..nl {
            let (cw, pw) = (self.levels[l - 1].w as usize, self.levels[l].w as usize);
            let mut next = vec![f32::INFINITY; self.levels[l].nodes.len()];
            let child = &cur;
            self.levels[l]
                .nodes
                .par_chunks_mut(pw)
                .zip(next.par_chunks_mut(pw))
                .enumerate()
                .for_each(|(qy, (nodes, row))| {
                    let c0 = &child[2 * qy * cw..];
                    let c1 = &child[(2 * qy + 1) * cw..];
                    for (qx, (node, v)) in nodes.iter_mut().zip(row.iter_mut()).enumerate() {
                        let x = 2 * qx;
                        let m = c0[x].min(c0[x + 1]).min(c1[x]).min(c1[x + 1]);
                        *v = m;
                        if m.is_finite() {
                            node.mark_unsafe(m);
                        }
                    }
                });
            cur = next;
        }
        self.trigger_z = tz;
        cur
    }
}

/// The fixed point's leaf pass with level 1 (x86_64, two levels or more): per pair of pixel
/// rows `2m`, `2m + 1` of `image` (level 0's image rows, padded width `w0`), the rows' leaves
/// (`leaf_row`) and their pixel-plane trigger depths and deeper fronts
/// ([`super::fixpoint::pixel_triggers_row`]), then level-1 row `m` from them while they are in
/// cache — the nodes of [`super::prune::prune`]'s level 1 with the same blocked pixels (the
/// pair's listed ones), by the same row kernel. Returns level 1 (`w0 / 2 x h0 / 2`, padding
/// rows empty) and `(tz, listed, fronts)` as the row-by-row pass makes them.
#[cfg(target_arch = "x86_64")]
#[allow(clippy::type_complexity)]
fn leaves_and_level1(
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
            // SAFETY: both rows of the pair were initialised (`init_row`).
            let two = unsafe { &*(rows as *const [_] as *const [Node]) };
            let scratch;
            let two = if two.len() == 2 * w0u {
                two
            } else {
                scratch = [two, &empty[..]].concat();
                &scratch[..]
            };
            let out = init_row(out, Node::EMPTY);
            let allow = super::prune::Allow(Some(&blocked));
            ctx.parent_row_fast_of(two, 1, m as u32, &mut out[..iw.min(pw)], allow);
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

/// Flag `O` of G-buffer leaves: [`crate::planes::crack_flags`] over the decoded leaf planes
/// (the quantised planes the traversal intersects).
fn gbuffer_flags(
    cube: &UnitCube,
    w: u32,
    h: u32,
    leaves: &[Node],
    min_rel_gap: f32,
    max_rel_gap: f32,
) -> Vec<bool> {
    crate::planes::crack_flags(cube, w, h, min_rel_gap, max_rel_gap, |k| {
        let node = leaves[k];
        if !node.is_plane() {
            return None;
        }
        let (gx, gy) = node.gradient(0, w as f32, h as f32);
        Some((node.zc(), gx, gy))
    })
}
