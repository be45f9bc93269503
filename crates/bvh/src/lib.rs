//! parallax-bvh: the object-space BVH and the exact reference ray tracer, the ground truth that
//! every image-space result of parallax is scored against.
//!
//! - **Build** ([`Bvh::build`]): binned SAH over triangle centroids (Wald 2007), parallel with
//!   rayon, producing a binary tree that is collapsed into 4-wide nodes by opening the children
//!   of largest surface area (Wald, Benthin & Boulos 2008; Ernst & Greiner 2008). `build.rs`,
//!   `collapse.rs`.
//! - **Layout** ([`Node4`], `node.rs`): 128-byte SoA nodes (`min_x[4], max_x[4], ...`), in
//!   depth-first preorder with leaf children first and triangles in traversal order, as HVVR
//!   (Hunt et al. 2018, §5) lays out its 4-wide BVH for beam traversal and linear refit.
//! - **Traversal** (`traverse.rs`): single rays, explicit fixed-size stack, one 4-wide SIMD slab
//!   test per node with the robust far scaling of Ize 2013, children near-to-far, and the
//!   watertight triangle test of Woop, Benthin & Wald 2013 ([`WatertightRay`]), run on four
//!   leaf triangles at once (SoA blocks [`Tri4`], `tri4.rs`; lanes with an exactly-zero edge
//!   function fall back to the scalar test): closest hit, any hit, all hits. `_with_stats`
//!   variants count the work ([`TraversalStats`]); `closest_hit_scalar` / `any_hit_scalar`
//!   are the per-triangle scalar twins. Closest-hit ties in `t` go to the lower triangle index.
//! - **Packets** ([`Bvh::closest_hit_packet`], `packet.rs`): up to [`PACKET_SIZE`] = 16 coherent
//!   rays traverse together, SIMD over rays at inner nodes (AVX2 behind runtime detection, SSE
//!   / portable twin), each ray's answer exactly its single-ray answer.
//! - **Refit** ([`Bvh::refit`], `refit.rs`): new vertex positions, same topology (HVVR §5.2).
//! - **Beam culling** lives with HVVR in `parallax-vr` (`parallax_vr::beam`): it walks these
//!   nodes (public in [`node`]) with a bounding beam of many rays.
//! - **Reference** ([`brute_force_closest`], [`brute_force_all`]): every triangle, same test.
//!
//! **Why our own BVH and not a crate (e.g. obvhs, bvh):** the HVVR beam traversal that follows
//! needs this exact node layout (SoA 4-wide boxes it can test against a beam's planes), control
//! over the traversal order and the stack (entry-point search stops part-way and resumes from a
//! saved stack, HVVR §5.3-5.4), and the preorder layout for linear refit. A general-purpose crate
//! hides those.
//!
//! **Invariant:** for any ray, [`Bvh::closest_hit`] returns a hit at the same `t` as
//! [`brute_force_closest`] (the same triangle unless two are hit at the same `t`), and
//! [`Bvh::all_hits`] the same set as [`brute_force_all`]: the BVH only culls, never decides.
//!
//! **Measured / what we tried** (release, `examples/bvh_throughput.rs`, Sponza 66k triangles, a
//! 2-core VM shared with other jobs, load 3-7, so absolute numbers are noisy): build 115-160 ms
//! (2 threads), refit 1.6-3 ms; closest hit ~9 Mrays/s coherent (1024x768 camera grid, 2.3
//! nodes/ray) and ~1.35 Mrays/s random (origins in the bounds, 12 nodes + 4.8 triangles/ray),
//! any hit ~9 / ~2.8 Mrays/s; 2 threads gave 1.0-1.4x (the machine was loaded). Profiles of the
//! random rays are dominated by cache misses on node and triangle loads. Tried: a 64-entry
//! instead of a 256-entry stack (the zeroed stack array costs a 2 KB memset per ray) — no
//! measurable difference, kept 256 for the depth bound. Not yet measured: a plain binary-BVH
//! traversal for comparison, compressed (quantised) nodes, and per-node bin counts for small
//! build nodes (the fixed 3 x 32-bin array is re-zeroed per node and shows in build profiles).
//!
//! **Measured, SIMD leaves and packets** (release, single thread, loaded 2-core VM, best of 5;
//! `examples/trace_stats.rs` on Sponza 1280x720 from (-9, 3.5, 0) towards (8, 5, 0), fov 60:
//! 17.7 nodes, 69 boxes, 2.2 leaves and 5.4 triangles per ray). The 4-wide leaf test gave
//! only +4-12% over the scalar per-triangle test (3.0 -> 3.3 Mrays/s): with ~5 triangles per
//! ray the time is in the inner nodes. perf on the single-ray loop shows the slab test with the
//! ray's values spilled to the stack and node-load stalls, ~60 cycles per node. Packets of 16
//! rays (4x4 tiles) with an SSE node test (4 groups of 4 rays) were only 1.1x single rays
//! (3.7 Mrays/s, compute-bound on the 16-ray x 4-child slab tests); the same loop on two AVX2
//! halves gave 7.3 Mrays/s (2.2x single rays). Embree's `rtcIntersect16` is still ~3x that:
//! it uses AVX-512 (one register per 16 rays) and an 8-wide BVH. Not yet tried: an AVX-512
//! node test, SIMD-over-rays leaf tests for packets sharing one axis permutation, frustum
//! culling of whole packets, and 8-wide nodes for single rays.
//!
//! **Measured, single-ray loop** (`examples/single_ray.rs`: thread CPU time, best of 8, Sponza
//! view above, A/B runs interleaved on the loaded 2-core VM, so +-10% noise per run; closest
//! hit Mrays/s primary / shadow / random 300k, before -> after): 2.8-3.4 / 3.4-4.2 / 1.7-2.2
//! -> 3.3-3.8 / 4.5-5.0 / 2.0-2.4; any hit primary 4.0-5.1 -> 5.0-5.8. What helped: stack
//! entries as `u64` keys `t_bits << 32 | child` with a branch-free 5-comparator sorting network
//! for 3-4 hit children (was an insertion sort through memory), unchecked node and stack
//! access, `t_max` starting the far accumulator (one `min` less per node), near/far planes as
//! byte offsets (no shift per load). Tried and dropped (no gain beyond noise): compiling the
//! loop with AVX2 behind runtime detection (VEX encodings; primary was ~8% slower), prefetching
//! hit inner children (neutral to slightly worse, the Sponza nodes stay cached), the sorting
//! network for 2 children too (branch-free 2-4 path; neutral), near-to-far order for any hit
//! (neutral). Not done on purpose: Embree's `t = box * inv - org * inv` with FMA: the rounding
//! of `org * inv` is an absolute error of `eps |org * inv|`, not relative to `t`, so Ize's
//! relative far scaling no longer makes the test conservative (Embree's default mode is not
//! robust either). Found on the way: culling against the bare closest-hit `t` let the visit
//! order change the answer (a triangle on a box face hit 1 ulp below the box's computed entry
//! distance); slab tests and pops now compare against `t_max * (1 + 2 gamma(3))`.
//!
//! [`WatertightRay`]: parallax_core::math::WatertightRay

mod build;
mod collapse;
mod collapse8;
mod lanes16;
pub mod node;
pub mod node8;
mod packet;
mod packet8;
mod reference;
mod refit;
mod simd;
mod stats;
mod traverse;
mod traverse8;
mod tri;
mod tri4;
mod world;

use std::fmt;
use std::time::{Duration, Instant};

use parallax_core::Aabb;
use parallax_scene::TriangleMesh;
use rayon::prelude::*;

pub use node::{ChildRef, Node4};
pub use node8::Node8;
pub use packet8::PACKET_SIZE;
pub use reference::{brute_force_all, brute_force_closest};
pub use stats::{Counter, NoStats, TraversalStats};
pub use tri::Tri;
pub use tri4::{Tri4, Tri4Hits, Tri4Ray};

/// A ray-triangle hit: the scene's triangle index, the ray parameter and the barycentrics of the
/// triangle's vertices 1 and 2 (`P = (1 - u - v) * p0 + u * p1 + v * p2`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub prim: u32,
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

/// Build parameters.
///
/// | parameter | type | default | meaning |
/// |---|---|---|---|
/// | `bins` | usize | 32 | SAH bins per axis (Wald 2007 uses 16-32), clamped to 2..=32 |
/// | `max_leaf_size` | usize | 4 | most triangles per leaf, clamped to 1..=15 |
/// | `traversal_cost` | f32 | 1.0 | SAH cost of visiting a node, relative to... |
/// | `intersection_cost` | f32 | 1.0 | ...the cost of one triangle test |
/// | `parallel_threshold` | usize | 4096 | nodes above this many triangles build their children in parallel |
#[derive(Clone, Debug, PartialEq)]
pub struct BuildOptions {
    pub bins: usize,
    pub max_leaf_size: usize,
    pub traversal_cost: f32,
    pub intersection_cost: f32,
    pub parallel_threshold: usize,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            bins: 32,
            max_leaf_size: 4,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            parallel_threshold: 4096,
        }
    }
}

impl BuildOptions {
    fn sanitized(&self) -> Self {
        let finite_pos = |x: f32, d: f32| if x.is_finite() && x > 0.0 { x } else { d };
        Self {
            bins: self.bins.clamp(2, build::MAX_BINS),
            max_leaf_size: self.max_leaf_size.clamp(1, node::MAX_LEAF_SIZE),
            traversal_cost: finite_pos(self.traversal_cost, 1.0),
            intersection_cost: finite_pos(self.intersection_cost, 1.0),
            parallel_threshold: self.parallel_threshold.max(64),
        }
    }
}

/// Why a build or refit was refused.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BvhError {
    /// More triangles than the node encoding can index ([`node::MAX_TRIANGLES`]).
    TooManyTriangles { count: usize },
    /// A triangle refers to a vertex that does not exist.
    IndexOutOfRange { triangle: usize },
    /// `refit` got a mesh with a different number of triangles.
    TopologyChanged { built: usize, given: usize },
}

impl fmt::Display for BvhError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BvhError::TooManyTriangles { count } => write!(
                f,
                "mesh has {count} triangles; the BVH supports at most {}",
                node::MAX_TRIANGLES
            ),
            BvhError::IndexOutOfRange { triangle } => {
                write!(f, "triangle {triangle} has a vertex index out of range")
            }
            BvhError::TopologyChanged { built, given } => write!(
                f,
                "refit needs the same triangles: built over {built}, given {given}"
            ),
        }
    }
}

impl std::error::Error for BvhError {}

/// A 4-wide bounding volume hierarchy over a [`TriangleMesh`] (see the crate docs).
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node4>,
    /// The 8-wide traversal tree over the same leaves (`node8.rs`).
    nodes8: Vec<Node8>,
    tris: Vec<Tri>,
    prim_ids: Vec<u32>,
    blocks: Vec<tri4::Tri4>,
    bounds: Aabb,
    depth: u32,
    build_time: Duration,
}

impl Bvh {
    /// Builds with the default [`BuildOptions`]. Panics only where [`Bvh::try_build_with`]
    /// returns an error (an invalid mesh; loaders validate meshes, so this is a bug upstream).
    pub fn build(mesh: &TriangleMesh) -> Bvh {
        Self::build_with(mesh, &BuildOptions::default())
    }

    /// Builds with the default options, or explains why the mesh cannot be indexed.
    pub fn try_build(mesh: &TriangleMesh) -> Result<Bvh, BvhError> {
        Self::try_build_with(mesh, &BuildOptions::default())
    }

    /// Builds with explicit options; panics as [`Bvh::build`].
    pub fn build_with(mesh: &TriangleMesh, opts: &BuildOptions) -> Bvh {
        Self::try_build_with(mesh, opts).unwrap_or_else(|e| panic!("BVH build: {e}"))
    }

    /// Builds, or explains why the mesh cannot be indexed. An empty mesh gives an empty BVH
    /// that every ray misses. Degenerate triangles are kept (the triangle test never hits them).
    pub fn try_build_with(mesh: &TriangleMesh, opts: &BuildOptions) -> Result<Bvh, BvhError> {
        let start = Instant::now();
        let opts = opts.sanitized();
        let n = mesh.triangle_count();
        if n > node::MAX_TRIANGLES {
            return Err(BvhError::TooManyTriangles { count: n });
        }
        let nv = mesh.positions.len();
        if let Some(t) = mesh
            .indices
            .par_iter()
            .position_any(|t| t.iter().any(|&i| i as usize >= nv))
        {
            return Err(BvhError::IndexOutOfRange { triangle: t });
        }
        if n == 0 {
            return Ok(Bvh {
                nodes: Vec::new(),
                nodes8: Vec::new(),
                tris: Vec::new(),
                prim_ids: Vec::new(),
                blocks: Vec::new(),
                bounds: Aabb::EMPTY,
                depth: 0,
                build_time: start.elapsed(),
            });
        }
        let mut refs: Vec<build::PrimRef> = (0..n)
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| {
                let [a, b, c] = mesh.triangle(i);
                build::PrimRef {
                    min: a.min(b).min(c),
                    max: a.max(b).max(c),
                    id: i as u32,
                }
            })
            .collect();
        let root = build::build_binary(&mut refs, &opts);
        let c = collapse::collapse(&root, &refs, |id| mesh.triangle(id as usize));
        let c8 = collapse8::collapse8(&root, &c.leaf_blocks, c.nodes.len() / 2 + 1);
        // The binary tree is freed here, inside the timed build.
        drop(root);
        assert!(
            3 * c.depth as usize + 1 < traverse::STACK_SIZE
                && 7 * c8.depth as usize + 1 < traverse8::STACK8_SIZE,
            "BVH depth {} / {} exceeds the traversal stack",
            c.depth,
            c8.depth
        );
        let bounds = c.nodes[0].bounds();
        Ok(Bvh {
            nodes: c.nodes,
            nodes8: c8.nodes,
            tris: c.tris,
            prim_ids: c.prim_ids,
            blocks: c.blocks,
            bounds,
            depth: c.depth,
            build_time: start.elapsed(),
        })
    }

    /// Number of 4-wide nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The 8-wide traversal tree, root first, in depth-first preorder (layout in [`node8`]).
    pub fn nodes8(&self) -> &[Node8] {
        &self.nodes8
    }

    /// Number of triangles indexed.
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// Memory held by nodes, triangle copies (plain and in blocks of four) and the primitive
    /// map, in bytes.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node4>()
            + self.nodes8.len() * size_of::<Node8>()
            + self.tris.len() * size_of::<Tri>()
            + self.blocks.len() * size_of::<Tri4>()
            + self.prim_ids.len() * size_of::<u32>()
    }

    /// Bounds of all triangles (empty for an empty mesh).
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Depth in 4-wide nodes (root = 1; 0 when empty).
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// Wall time of the build (including the collapse and the triangle gather).
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// The nodes, root first, in depth-first preorder (layout in [`node`]).
    pub fn nodes(&self) -> &[Node4] {
        &self.nodes
    }

    /// The triangle copies in leaf order; leaf `(first, count)` refers to
    /// `triangles()[leaf_triangles(first, count)]`.
    pub fn triangles(&self) -> &[Tri] {
        &self.tris
    }

    /// The leaves' triangles in blocks of four, leaf order (layout in `tri4.rs`).
    pub fn blocks(&self) -> &[Tri4] {
        &self.blocks
    }

    /// The range in [`Bvh::triangles`] of the leaf `ChildRef::Leaf { first, count }` (`first`
    /// is its first block). Panics on a reference that is not a leaf of this BVH.
    pub fn leaf_triangles(&self, first: u32, count: u32) -> std::ops::Range<usize> {
        if count == 0 {
            return 0..0;
        }
        let start = self.blocks[first as usize].tri[0] as usize;
        start..start + count as usize
    }

    /// The scene's triangle index of each entry of [`Bvh::triangles`].
    pub fn prim_ids(&self) -> &[u32] {
        &self.prim_ids
    }
}
