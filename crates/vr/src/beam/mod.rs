//! Beam culling of the 4-wide BVH (Hunt et al. 2018, §5.3-5.4): the entry-point search that
//! shares traversal across all rays of a block and then of a tile.
//!
//! - [`block_cull`] (§5.3): a block's beam ([`crate::beam::Beam`]) traverses the BVH
//!   from the root with an explicit stack, always refining the entry of the thickest box along
//!   the beam's dominant axis; each child box is Miss (dropped), Contained (an entry point) or
//!   Partial (refined further). It stops when the stack is empty or stack + entry points reach
//!   a fixed budget ([`BLOCK_ENTRIES`] = 64, as HVVR), and returns the entry points sorted by
//!   near depth along the dominant axis.
//! - [`tile_cull`] (§5.4): a tile's beam starts from its block's entry points (not the root) and
//!   traverses to the leaves; the result is the tile's list of leaves (blocks of four triangles,
//!   [`parallax_bvh::Tri4`]) sorted by near depth, which the sample test walks front to back.
//!
//! The box tests come in two twins with bit-identical arithmetic ([`Classify4`]):
//! [`SimdBeam`] tests the four children of a `Node4` at once (glam `Vec4`, SSE on x86_64,
//! the portable form of `simd.rs`), [`ScalarBeam`] tests them one by one with the plain scalar
//! `PreparedBeam::test_box`. The traversal is shared, so the two produce identical lists
//! (tested in `tests/beam_cull.rs`).

mod cull;
mod shape;

pub use cull::{
    BLOCK_ENTRIES, Classify4, CullScratch, Entry, LeafRef, ScalarBeam, SimdBeam, block_cull,
    tile_cull,
};
pub use shape::{
    BEAM_TOLERANCE, Beam, BeamBuilder, BeamTest, LaneBeamBuilder, MIN_DOMINANT, PreparedBeam,
    plane_range1, plane_range2,
};
