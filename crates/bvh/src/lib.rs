//! parallax-bvh: the object-space BVH and the exact reference ray tracer, the ground truth that
//! every image-space result of parallax is scored against.
//!
//! - **Build** ([`Bvh::build`]): binned SAH over triangle centroids (Wald 2007), parallel with
//!   rayon, with spatial splits by default ([`BuildOptions::spatial_splits`]: SBVH, Stich,
//!   Friedrich & Dietrich 2009, `build/spatial.rs`; a triangle may then sit in several leaves
//!   and every query still reports it once; `spatial_splits: false` builds the object-split
//!   tree, each triangle in one leaf), producing a binary tree that is collapsed twice by opening the children of largest
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
//!   test; for closest hits a leaf of two blocks is tested in one 8-lane pass, `lanes8.rs`):
//!   closest hit, any hit, all hits. `traverse.rs` is the same loop over the 4-wide tree
//!   ([`Bvh::closest_hit4`], ...), kept as the twin; `closest_hit_scalar` / `any_hit_scalar` use
//!   the per-triangle scalar test. `_with_stats` variants count the work ([`TraversalStats`]).
//!   Closest-hit ties in `t` go to the lower primitive id (the scene's triangle index).
//! - **Packets** ([`Bvh::closest_hit_packet`], `packet8.rs`): up to [`PACKET_SIZE`] = 16
//!   coherent rays traverse the 8-wide tree together, one SIMD lane per ray (AVX-512 or AVX2
//!   behind runtime detection, portable twin, `lanes16.rs`; [`PacketLanes`]), with interval culling of whole packets
//!   and a SIMD-over-rays triangle test (`packet_leaf.rs`); each ray's answer is exactly its
//!   single-ray answer.
//!   `packet.rs` is the 4-wide predecessor ([`Bvh::closest_hit_packet4`]).
//!   [`Bvh::closest_hit_packet64`] (`packet64.rs`): up to [`PACKET64_SIZE`] = 64 rays (an 8x8
//!   camera tile as four 4x4 groups) share one stack and one interval test of the whole packet
//!   per node, then one per group (`packet_interval.rs`); leaves and pops per group.
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
//! **Invariant:** for any ray, [`Bvh::closest_hit`] returns exactly the hit of
//! [`brute_force_closest`] (an exact tie in `t` goes to the lowest primitive id in both, with
//! or without spatial splits: the triangle blocks hold primitive ids, so the rule does not
//! depend on the tree or on which copy of a split triangle a ray reaches), and
//! [`Bvh::all_hits`] the same set as [`brute_force_all`]: the BVH only culls, never decides.
//! Every fast path (8-wide AVX2, 16-lane AVX-512 and AVX2 packets, the 4-wide tree) returns bit for bit
//! what its twin returns (`tests/simd_twins.rs`, `tests/packets.rs`).
//!
//! Measurements and what was tried and dropped: `docs/notes/bvh.md`.
//!
//! [`WatertightRay`]: parallax_core::math::WatertightRay

mod build;
mod bvh;
mod collapse;
mod collapse8;
mod construct;
mod hit;
mod keys8;
mod lanes16;
mod lanes8;
#[cfg(target_arch = "x86_64")]
mod leaf8;
pub mod node;
pub mod node8;
mod options;
mod packet;
mod packet64;
mod packet8;
mod packet_interval;
mod packet_lanes;
mod packet_leaf;
mod packet_setup;
mod reference;
mod refit;
mod stats;
mod traverse;
mod traverse8;
mod tri;
mod tri4;
mod world;

pub use bvh::Bvh;
pub use hit::Hit;
pub use node::{ChildRef, Node4};
pub use node8::Node8;
pub use options::{BuildOptions, BvhError};
pub use packet_lanes::PacketLanes;
pub use packet8::PACKET_SIZE;
pub use packet64::PACKET64_SIZE;
pub use reference::{brute_force_all, brute_force_closest};
pub use stats::{Counter, NoStats, TraversalStats};
pub use tri::Tri;
pub use tri4::{Tri4, Tri4Hits, Tri4Ray};
