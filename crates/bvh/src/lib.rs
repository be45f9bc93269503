//! parallax-bvh: the object-space BVH and the exact reference ray tracer, the ground truth that
//! every image-space result of parallax is scored against.
//!
//! - **Build** ([`Bvh::build`]): binned SAH over triangle centroids (Wald 2007), parallel with
//!   rayon, producing a binary tree that is collapsed twice by opening the children of largest
//!   surface area (Wald, Benthin & Boulos 2008; Ernst & Greiner 2008): into 4-wide nodes
//!   (`collapse.rs`) and into 8-wide nodes (`collapse8.rs`) over the same leaves.
//! - **Layouts**: [`Node4`] (`node.rs`), 128-byte SoA nodes in depth-first preorder with leaf
//!   children first and triangles in traversal order, as HVVR (Hunt et al. 2018, §5) lays out
//!   its 4-wide BVH for beam traversal and linear refit; [`Node8`] (`node8.rs`), 256-byte SoA
//!   nodes (Embree's `BVH8`, Wald et al. 2014 §3.1), the tree the ray queries traverse.
//! - **Traversal** (`traverse8.rs`): single rays over the 8-wide tree, explicit fixed-size
//!   stack, one 8-lane slab test per node (AVX2 behind runtime detection, portable twin) with
//!   the robust far scaling of Ize 2013, children near-to-far, and the watertight triangle test
//!   of Woop, Benthin & Wald 2013 ([`WatertightRay`]) on four leaf triangles at once (SoA blocks
//!   [`Tri4`], `tri4.rs`; lanes with an exactly-zero edge function fall back to the scalar
//!   test): closest hit, any hit, all hits. `traverse.rs` is the same loop over the 4-wide tree
//!   ([`Bvh::closest_hit4`], ...), kept as the twin; `closest_hit_scalar` / `any_hit_scalar` use
//!   the per-triangle scalar test. `_with_stats` variants count the work ([`TraversalStats`]).
//!   Closest-hit ties in `t` go to the lower triangle index.
//! - **Packets** ([`Bvh::closest_hit_packet`], `packet8.rs`): up to [`PACKET_SIZE`] = 16
//!   coherent rays traverse the 8-wide tree together, one SIMD lane per ray (AVX-512 behind
//!   runtime detection, portable twin, `lanes16.rs`), with interval culling of whole packets
//!   and a SIMD-over-rays triangle test; each ray's answer is exactly its single-ray answer.
//!   `packet.rs` is the 4-wide predecessor ([`Bvh::closest_hit_packet4`]).
//! - **Refit** ([`Bvh::refit`], `refit.rs`): new vertex positions, same topology (HVVR §5.2),
//!   both trees.
//! - **Beam culling** lives with HVVR in `parallax-vr` (`parallax_vr::beam`): it walks the
//!   4-wide nodes (public in [`node`]) with a bounding beam of many rays.
//! - **Reference** ([`brute_force_closest`], [`brute_force_all`]): every triangle, same test.
//!
//! **Why our own BVH and not a crate (e.g. obvhs, bvh):** the HVVR beam traversal needs this
//! exact node layout (SoA 4-wide boxes it can test against a beam's planes), control over the
//! traversal order and the stack (entry-point search stops part-way and resumes from a saved
//! stack, HVVR §5.3-5.4), the preorder layout for linear refit, and exact (watertight, robust)
//! answers that equal brute force; a general-purpose crate hides those.
//!
//! **Invariant:** for any ray, [`Bvh::closest_hit`] returns a hit at the same `t` as
//! [`brute_force_closest`] (the same triangle unless two are hit at the same `t`), and
//! [`Bvh::all_hits`] the same set as [`brute_force_all`]: the BVH only culls, never decides.
//! Every fast path (8-wide AVX2, 16-lane AVX-512 packets, the 4-wide tree) returns bit for bit
//! what its twin returns (`tests/simd_twins.rs`, `tests/packets.rs`).
//!
//! Measurements and what was tried and dropped: `docs/notes/bvh.md`.
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

/// A bounding volume hierarchy over a [`TriangleMesh`]: a 4-wide and an 8-wide tree over the
/// same leaves (see the crate docs).
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
