//! [`QuadTreeTracer::trace_batch`]: many rays at once, in phases (the application: the lens
//! rays of one pixel in depth of field, Widmer et al. 2015, §5.2 — short rays whose
//! per-ray set-up costs as much as their traversal).
//!
//! **What changes, what does not.** Every ray gets exactly the operations of
//! [`QuadTreeTracer::trace_ray`] — the f64 cube clip, [`RaySetup::new`], the start of
//! [`QuadTree::layer_start`] and the walk of [`QuadTree::layer_walk`] — so results and work
//! counters are bit for bit those of tracing the rays one by one (test
//! `tests/quadtree_batch.rs`). Only the order differs: up to [`BATCH`] rays are clipped,
//! then set up and started, then walked. The set-up is a chain of dependent divisions and
//! conversions ending in the start node's index (`docs/notes/quadtree.md`, "latency, not
//! instructions"); one ray at a time the CPU waits on it, and a mispredicted branch of the
//! walk (about three per ray) discards the next ray's set-up that had started. In phases the
//! chains of the batch's rays are independent and overlap, and each walk starts from a
//! finished set-up.
//!
//! With one layer in cascade mode (the common case of depth of field) the layer's start is
//! part of the second phase; with several layers or inpainting the cascade runs ray by ray
//! after the clip and set-up phases (a deeper layer's window depends on the layer before).
//! The clip phase takes four rays at a time ([`crate::UnitCube::clip_ray_quad_into`]: SIMD
//! lanes with every lane doing the one-ray operations, the segments written straight into the
//! phase's array), and the set-up is built in place in the array the walks read. The opt-in
//! f32 clip traces the rays one by one.

use parallax_core::Ray;

use super::LayerMode;
use super::cascade::{QuadTreeTracer, one_layer_result};
use super::traverse::{LayerStart, Query, RaySetup};
use crate::{CubeSegment, ScreenTracer, TraceResult, TraceStats};

/// Rays per phase of [`QuadTreeTracer::trace_batch`].
pub const BATCH: usize = 8;
const _: () = assert!(
    BATCH.is_multiple_of(4),
    "the clip phase takes four rays at a time"
);

impl QuadTreeTracer {
    /// Traces `rays[i]` into `out[i]` (equal lengths), adding the work to `stats`: the same
    /// results and counters as [`ScreenTracer::trace`] per ray (module docs).
    pub fn trace_batch(&self, rays: &[Ray], out: &mut [TraceResult], stats: &mut TraceStats) {
        assert_eq!(rays.len(), out.len(), "one result per ray");
        if self.f32_clip {
            for (ray, o) in rays.iter().zip(out.iter_mut()) {
                *o = self.trace(ray, stats);
            }
            return;
        }
        let one = self.trees.len() == 1 && self.opts.mode == LayerMode::Cascade;
        for (rays, out) in rays.chunks(BATCH).zip(out.chunks_mut(BATCH)) {
            if one {
                self.one_layer_phases(rays, out, stats);
            } else {
                self.cascade_phases(rays, out, stats);
            }
        }
    }

    /// The f64 cube clips of at most [`BATCH`] rays into `segs`, four at a time
    /// ([`crate::UnitCube::clip_ray_quad`]; a remainder in a pair and alone: all the bits of
    /// [`crate::UnitCube::clip_ray`]).
    #[inline(always)]
    fn clip_phase(&self, rays: &[Ray], segs: &mut [Option<CubeSegment>; BATCH]) {
        debug_assert!(rays.len() <= BATCH);
        for (seg, ray) in segs.chunks_exact_mut(4).zip(rays.chunks(4)) {
            match ray {
                [_, _, _, _] => {
                    let quad: &[Ray; 4] = ray.try_into().expect("four rays");
                    let seg: &mut [Option<CubeSegment>; 4] = seg.try_into().expect("four segments");
                    self.cube.clip_ray_quad_into(quad, seg);
                }
                [r0, r1, r2] => {
                    let [s0, s1] = self.cube.clip_ray_pair(r0, r1);
                    seg[0] = s0;
                    seg[1] = s1;
                    seg[2] = self.cube.clip_ray(r2);
                }
                [r0, r1] => {
                    let [s0, s1] = self.cube.clip_ray_pair(r0, r1);
                    seg[0] = s0;
                    seg[1] = s1;
                }
                [r0] => seg[0] = self.cube.clip_ray(r0),
                _ => {}
            }
        }
    }

    /// At most [`BATCH`] rays through several layers (or with inpainting): clip, set-up, then
    /// the cascade of [`QuadTreeTracer::trace_ray`] ray by ray.
    #[inline(always)]
    fn cascade_phases(&self, rays: &[Ray], out: &mut [TraceResult], stats: &mut TraceStats) {
        debug_assert!(rays.len() <= BATCH && rays.len() == out.len());
        let t0 = &self.trees[0];
        let mut segs: [Option<CubeSegment>; BATCH] = [None; BATCH];
        self.clip_phase(rays, &mut segs);
        let mut setups: [Option<RaySetup>; BATCH] = [None; BATCH];
        for (rs, seg) in setups.iter_mut().zip(&segs) {
            *rs = seg.as_ref().map(|seg| RaySetup::new(seg, t0.wf, t0.hf));
        }
        for (i, (ray, o)) in rays.iter().zip(out.iter_mut()).enumerate() {
            stats.rays += 1;
            *o = match (&segs[i], &setups[i]) {
                (Some(seg), Some(rs)) => self.trace_segment(ray, seg, rs, stats).0,
                _ => TraceResult::Miss,
            };
        }
    }

    /// At most [`BATCH`] rays through the single layer in three phases: clip, set-up and
    /// start, walk and result (the one-layer path of [`QuadTreeTracer::trace_ray`]).
    #[inline(always)]
    fn one_layer_phases(&self, rays: &[Ray], out: &mut [TraceResult], stats: &mut TraceStats) {
        debug_assert!(rays.len() <= BATCH && rays.len() == out.len());
        let t0 = &self.trees[0];
        let q = Query::WHOLE;
        let mut segs: [Option<CubeSegment>; BATCH] = [None; BATCH];
        self.clip_phase(rays, &mut segs);
        let mut started: [Option<(RaySetup, Option<LayerStart>)>; BATCH] = [None; BATCH];
        for (st, seg) in started.iter_mut().zip(&segs) {
            if let Some(seg) = seg {
                // Set up in place (no copy of the set-up into the array).
                let (rs, start) = st.insert((RaySetup::new(seg, t0.wf, t0.hf), None));
                *start = t0.layer_start(rs, &q);
            }
        }
        for (i, (ray, o)) in rays.iter().zip(out.iter_mut()).enumerate() {
            stats.rays += 1;
            *o = match (&segs[i], &started[i]) {
                (Some(seg), Some((rs, Some(start)))) => {
                    let ev = t0.layer_walk(rs, &q, *start, stats);
                    one_layer_result(ray, seg, &ev, stats)
                }
                _ => TraceResult::Miss,
            };
        }
    }
}
