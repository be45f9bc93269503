//! DIRT's tracer: world-space rays traced through the per-view primitive lists of the capture
//! (Vardis et al. 2017, "DIRT: Deferred Image-based Ray Tracing", §4.2.1 "Trace Pass" and
//! Algorithm 1), behind the world-space tracer interface ([`WorldTracer`]).
//!
//! - [`view`](self): a view's projection as plane constants; a ray clipped to a view's frustum
//!   and expressed in it (§4.2.1 "Screen-space ray tracing");
//! - `walk`: Hi-Z over the min-max mips and bucket tracing in the finest cells (Algorithm 1),
//!   with the argument why the answer is exact;
//! - `slabs`: per mip texel, the mask of occupied reciprocal-depth slabs (from the cells'
//!   non-empty buckets), the walk's second skip test, and why a skip by it is exact;
//! - `cells`: one cache line per finest cell (its record, bucket ends and first list
//!   entries as `u16`; the rest of the lists after the lines), the walk's read of a cell and
//!   its ids;
//! - `tri4`: the ray-triangle tests of a bucket, four triangles at a time, and the per-ray
//!   mailbox;
//! - this file: the multi-view driver (§4.2.1: "If no valid hit is found within the current
//!   view, the process is repeated for each subsequent view the ray intersects").
//!
//! **Multi-view** (Vardis et al. 2016, as the GPU code's `traceScreenSpaceRay_abuffer`): the
//! views are the camera's (optional) and a cube map of six 90-degree faces around the
//! camera's eye. The ray is first clipped to the bounds of the triangle buffer (the far plane:
//! a ray that leaves it meets nothing more). The part inside the camera frustum (a convex
//! set: one parameter interval) is traced in the camera view; the parts before and after it in
//! the cube. In the cube, each face's frustum cuts one interval out of the ray; the intervals
//! are traced in ray order, so a ray that leaves a face through a side continues in the face
//! that contains the exit point, and a ray that reaches the far end of its last interval stops.
//! Neighbouring faces share their side planes bit for bit (see `view`), so the intervals meet
//! without gaps. Only the neighbourhood of the eye closer than the capture's near plane is seen
//! by no view. A ray that leaves every view without a hit is a miss.
//!
//! **Invariants:**
//! - the tracer reads only the capture ([`DirtViews`]: triangle buffer, depth bounds, mips,
//!   id lists), never the scene;
//! - every answer equals the BVH's (the same triangle and bit-identical `t` and barycentrics),
//!   up to exact ties in `t` (coplanar duplicates: DIRT keeps the lower triangle id, the BVH the
//!   lower index in its leaf order) and hits closer to the eye than the capture's near plane;
//! - every loop is bounded: a view's walk by `max_steps` (`view.rs`) derived from its grid size
//!   (walks cut by it are counted in [`WorldStats::truncated`]); at most seven views per ray;
//! - invalid rays ([`Ray::is_valid`] false) and rays that leave every view miss;
//! - the tracer runs one of three compiled copies of the same source, picked once per tracer
//!   (`Isa::detect`): the build's baseline (the portable twin), or where the CPU has them
//!   x86-64-v3's AVX2, BMI1/2 and LZCNT (VEX three-operand float ops, `shlx`/`shrx` for the
//!   walk's variable shifts), or those and AVX-512 F/VL/BW/DQ (32 vector registers). No FMA is
//!   enabled and Rust never contracts a multiply and an add: the same operations, so the same
//!   answers and counters on each ([`DirtTracer::copies`], tested equal).
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `face_size` | u32 | 256 | cube face size in pixels ([`DirtViewsOptions`](parallax_raster::dirt::DirtViewsOptions)) |
//! | `tile_size` | u32 | 1 | `S`: one list per `S x S` pixel tile, in every view |
//! | `buckets` | u32 | 8 | `B` depth buckets per cell |
//! | camera view | `Option<Pinhole>` | the render camera | the camera's grid (film size / `S`) |
//!
//! Measurements (speed against the BVH, build times, memory, the `B` and `S` sweeps) are in
//! `docs/notes/dirt.md`.

mod best;
mod cells;
mod slabs;
#[cfg(test)]
mod test_soup;
mod tri4;
mod view;
mod walk;

use glam::{Vec2, Vec3};
use parallax_core::math::WatertightRay;
use parallax_core::{Ray, WorldHit, WorldStats, WorldTracer};
use parallax_raster::dirt::DirtViews;
use parallax_scene::camera::CubeMap;
use rayon::prelude::*;

use best::Best;
pub use best::DirtCounters;
use cells::CellLines;
use slabs::Slabs;
use tri4::Query;
use view::{Exit, Isa, ViewConsts, ViewRay};
use walk::{WalkEnd, walk};

/// DIRT behind the world-space tracer interface (module docs).
#[derive(Clone, Debug)]
pub struct DirtTracer {
    views: DirtViews,
    /// The camera view's constants (if any), then the six faces'.
    consts: Vec<ViewConsts>,
    /// The views' mip texels with their depth-slab masks (`slabs`), in the order of `consts`.
    slabs: Vec<Slabs>,
    /// The views' level-0 cells, one cache line each (`cells`), in the order of `consts`.
    cells: Vec<CellLines>,
    /// Per cube face, the face across its left, right, top and bottom film edges.
    neighbours: [[usize; 4]; 6],
    /// The instruction set the tracer runs on (the same results on each).
    isa: Isa,
}

impl DirtTracer {
    /// A tracer over a built capture.
    pub fn new(views: DirtViews) -> DirtTracer {
        let consts = views.views().map(ViewConsts::new).collect();
        // The views' masks are independent: built side by side (`bench dirt` times this
        // construction as part of DIRT's build).
        let captures: Vec<_> = views.views().collect();
        let (slabs, cells) = captures
            .into_par_iter()
            .map(|cap| (Slabs::new(cap), CellLines::new(cap)))
            .unzip();
        let neighbours = std::array::from_fn(|i| {
            let b = views.cube.cube.face_camera(i).frame.basis;
            [-b.x_axis, b.x_axis, b.y_axis, -b.y_axis].map(CubeMap::face_of)
        });
        DirtTracer {
            views,
            consts,
            slabs,
            cells,
            neighbours,
            isa: Isa::detect(),
        }
    }

    /// Bytes of the walk's own copy of the mip texels (reciprocal bounds and slab mask),
    /// beside the capture's [`DirtViews::bytes`].
    pub fn texel_bytes(&self) -> u64 {
        self.slabs
            .iter()
            .map(|s| std::mem::size_of_val(s.texels.as_slice()) as u64)
            .sum()
    }

    /// Bytes of the walk's own line per level-0 cell (`cells`: record, bucket ends, the lists'
    /// entries in the lines and after them),
    /// beside the capture's [`DirtViews::bytes`].
    pub fn cell_line_bytes(&self) -> u64 {
        self.cells
            .iter()
            .map(|c| std::mem::size_of_val(c.lines.as_slice()) as u64)
            .sum()
    }

    /// The same tracer on every compiled copy this CPU runs (module docs), the build's
    /// baseline (the portable twin) first, the copy [`Self::new`] picks last: the same answers
    /// and counters on each. For tests and for in-process comparisons of the copies.
    pub fn copies(&self) -> Vec<(&'static str, DirtTracer)> {
        Isa::available()
            .into_iter()
            .map(|isa| {
                let mut t = self.clone();
                t.isa = isa;
                for vc in &mut t.consts {
                    vc.isa = isa;
                }
                let name = match isa {
                    Isa::Baseline => "baseline",
                    Isa::X86V3 => "x86-64-v3",
                    Isa::X86V4 => "x86-64-v3+avx512",
                };
                (name, t)
            })
            .collect()
    }

    /// The capture this tracer reads.
    pub fn views(&self) -> &DirtViews {
        &self.views
    }

    fn has_camera(&self) -> bool {
        self.views.camera.is_some()
    }

    /// The closest hit, with DIRT's own work counters.
    pub fn closest_hit_counted(&self, ray: &Ray, counters: &mut DirtCounters) -> Option<WorldHit> {
        let b = self.trace(ray, false, counters);
        b.found()
            .then(|| WorldHit::exact(ray, b.t, b.prim, Vec2::new(b.u, b.v)))
    }

    /// Occlusion, with DIRT's own work counters.
    pub fn occluded_counted(&self, ray: &Ray, counters: &mut DirtCounters) -> bool {
        self.trace(ray, true, counters).found()
    }

    fn trace(&self, ray: &Ray, any: bool, counters: &mut DirtCounters) -> Best {
        #[cfg(target_arch = "x86_64")]
        match self.isa {
            // SAFETY: `Isa::detect` chose the copy: the CPU has its features.
            Isa::X86V4 => return unsafe { self.trace_v4(ray, any, counters) },
            Isa::X86V3 => return unsafe { self.trace_v3(ray, any, counters) },
            Isa::Baseline => {}
        }
        self.trace_body(ray, any, counters)
    }

    /// [`Self::trace`] compiled for x86-64-v3 (module docs).
    ///
    /// # Safety
    /// The CPU must have the features (`Isa::detect`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn trace_v3(&self, ray: &Ray, any: bool, counters: &mut DirtCounters) -> Best {
        self.trace_body(ray, any, counters)
    }

    /// [`Self::trace`] compiled for x86-64-v3 and AVX-512 F/VL/BW/DQ (module docs).
    ///
    /// # Safety
    /// The CPU must have the features (`Isa::detect`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt,avx512f,avx512vl,avx512bw,avx512dq")]
    unsafe fn trace_v4(&self, ray: &Ray, any: bool, counters: &mut DirtCounters) -> Best {
        self.trace_body(ray, any, counters)
    }

    #[inline(always)]
    fn trace_body(&self, ray: &Ray, any: bool, counters: &mut DirtCounters) -> Best {
        if !ray.is_valid() {
            return Best::NONE;
        }
        let bounds = self.views.triangles.bounds();
        if bounds.is_empty() {
            return Best::NONE;
        }
        // The far plane: the bounds of every triangle.
        let Some((t0, t1)) = bounds.intersect(ray, ray.dir.recip()) else {
            return Best::NONE;
        };
        let wt = WatertightRay::new(ray);
        let mut q = Query::new(wt, self.views.triangles.as_slice(), any);
        self.trace_views(ray, t0, t1, &mut q);
        *counters += q.counters;
        q.best
    }

    #[inline(always)]
    fn trace_views(&self, ray: &Ray, t0: f32, t1: f32, q: &mut Query) {
        // (No closure: it would be compiled without the tracer copy's target features and
        // called out of line once per ray.)
        let camera = if self.has_camera() {
            let vc = &self.consts[0];
            let vr = vc.ray(ray.origin, ray.dir);
            Some((vc, vr, vc.clip(&vr, t0, t1)))
        } else {
            None
        };
        match camera {
            Some((vc, vr, Some((a, b)))) => {
                if self.trace_cube(ray, t0, a, q) == WalkEnd::Done {
                    return;
                }
                let cap = self.views.camera.as_ref().expect("camera view");
                if walk(vc, cap, &self.slabs[0], &self.cells[0], &vr, a, b, q) == WalkEnd::Done
                    || accepted(q, b)
                {
                    return;
                }
                self.trace_cube(ray, b, t1, q);
            }
            _ => {
                self.trace_cube(ray, t0, t1, q);
            }
        }
    }

    /// The cube faces over `[s0, s1]`, in ray order: the face that holds the start, then
    /// across the edge the ray leaves it by, the face that holds the exit point (they share the
    /// edge's plane, so the next interval starts exactly where the last one ended). Where that
    /// does not continue the interval without a gap (a start or exit on a face corner within
    /// rounding, or the near plane), every face is clipped instead ([`Self::trace_cube_all`]).
    #[inline(always)]
    fn trace_cube(&self, ray: &Ray, s0: f32, s1: f32, q: &mut Query) -> WalkEnd {
        if !(s0 < s1) {
            return WalkEnd::Continue;
        }
        let first = self.has_camera() as usize;
        let p = ray.at(s0) - self.views.cube.cube.eye;
        let mut f = CubeMap::face_of(if p == Vec3::ZERO { ray.dir } else { p });
        let mut s = s0;
        for _ in 0..8 {
            let vc = &self.consts[first + f];
            let vr = vc.ray(ray.origin, ray.dir);
            let Some((lo, hi, exit)) = vc.clip_exit(&vr, s, s1).filter(|&(lo, ..)| lo <= s) else {
                break;
            };
            let faces = &self.views.cube.faces;
            let end = walk(
                vc,
                &faces[f],
                &self.slabs[first + f],
                &self.cells[first + f],
                &vr,
                lo,
                hi,
                q,
            );
            if end == WalkEnd::Done || accepted(q, hi) {
                return WalkEnd::Done;
            }
            f = match exit {
                Exit::End => return WalkEnd::Continue,
                Exit::Near => {
                    s = hi;
                    break;
                }
                Exit::Left => self.neighbours[f][0],
                Exit::Right => self.neighbours[f][1],
                Exit::Top => self.neighbours[f][2],
                Exit::Bottom => self.neighbours[f][3],
            };
            s = hi;
        }
        self.trace_cube_all(ray, s, s1, q)
    }

    /// Every face clipped over `[s0, s1]`, the intervals traced in ray order.
    fn trace_cube_all(&self, ray: &Ray, s0: f32, s1: f32, q: &mut Query) -> WalkEnd {
        if !(s0 < s1) {
            return WalkEnd::Continue;
        }
        let first = self.has_camera() as usize;
        let mut parts: [(f32, f32, usize, Option<ViewRay>); 6] = [(0.0, 0.0, 0, None); 6];
        let mut n = 0;
        for f in 0..6 {
            let vc = &self.consts[first + f];
            let vr = vc.ray(ray.origin, ray.dir);
            if let Some((lo, hi)) = vc.clip(&vr, s0, s1) {
                parts[n] = (lo, hi, f, Some(vr));
                n += 1;
            }
        }
        let parts = &mut parts[..n];
        parts.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        for &(lo, hi, f, vr) in parts.iter() {
            if accepted(q, lo) {
                return WalkEnd::Done;
            }
            let vr = vr.expect("clipped part has its ray");
            let end = walk(
                &self.consts[first + f],
                &self.views.cube.faces[f],
                &self.slabs[first + f],
                &self.cells[first + f],
                &vr,
                lo,
                hi,
                q,
            );
            if end == WalkEnd::Done || accepted(q, hi) {
                return WalkEnd::Done;
            }
        }
        WalkEnd::Continue
    }
}

/// True when the best hit so far is final because everything up to `t` has been traced.
#[inline]
fn accepted(q: &Query, t: f32) -> bool {
    q.best.found() && q.best.t <= t
}

impl WorldTracer for DirtTracer {
    fn name(&self) -> &str {
        "dirt"
    }

    fn is_exact(&self) -> bool {
        true
    }

    fn closest_hit(&self, ray: &Ray, stats: &mut WorldStats) -> Option<WorldHit> {
        let mut c = DirtCounters::default();
        let hit = self.closest_hit_counted(ray, &mut c);
        add(stats, &c);
        hit
    }

    fn occluded(&self, ray: &Ray, stats: &mut WorldStats) -> bool {
        let mut c = DirtCounters::default();
        let hit = self.occluded_counted(ray, &mut c);
        add(stats, &c);
        hit
    }
}

#[inline]
fn add(stats: &mut WorldStats, c: &DirtCounters) {
    stats.rays += 1;
    stats.nodes += c.texels;
    stats.tests += c.tests;
    stats.steps += c.buckets + c.views;
    stats.truncated += (c.truncated > 0) as u64;
}
