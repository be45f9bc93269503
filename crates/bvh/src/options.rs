//! Build parameters of the BVH and the reasons a build or refit is refused.

use std::fmt;

use crate::node;

/// Most SAH bins per axis (the bin arrays are fixed-size).
pub(crate) const MAX_BINS: usize = 32;

/// Build parameters.
///
/// | parameter | type | default | meaning |
/// |---|---|---|---|
/// | `bins` | usize | 32 | SAH bins per axis (Wald 2007 uses 16-32), clamped to 2..=32 |
/// | `max_leaf_size` | usize | 8 | most triangles per leaf (two blocks of four), clamped to 1..=15 |
/// | `traversal_cost` | f32 | 1.0 | SAH cost of visiting a node, relative to... |
/// | `intersection_cost` | f32 | 1.0 | ...the cost of one triangle test (of one block of `sah_block_size`) |
/// | `sah_block_size` | usize | 4 | the SAH counts a leaf's triangles in blocks of this many (`ceil(n / size)`), clamped to 1..=4 |
/// | `parallel_threshold` | usize | 4096 | nodes above this many triangles build their children in parallel |
/// | `spatial_splits` | bool | true | also consider spatial splits (SBVH, Stich et al. 2009; `build/spatial.rs`); false: object splits only, each triangle in one leaf |
/// | `split_alpha` | f32 | 1e-5 | SBVH: try spatial splits where the object split's child overlap exceeds this fraction of the root's area |
/// | `split_overlap` | f32 | 0.2 | SBVH: ...and also this fraction of the node's own area (0: the root rule alone) |
/// | `split_budget` | f32 | 0.3 | SBVH: most duplicated references, as a fraction of the triangle count, clamped to 0..=4 |
///
/// With `spatial_splits` (the default), a triangle can sit in several leaves:
/// [`crate::Bvh::triangles`] then holds more entries than the mesh has triangles (at most
/// `split_budget · n` more; the queries report each primitive once). Spatial splits are the
/// default because the SBVH answers random single rays with fewer nodes and triangles
/// (instructions per bounce ray: Sponza -19 %, classroom -5 %) and, with `split_overlap`,
/// costs packets of primary rays nothing measurable (`docs/notes/bvh.md`, "the SBVH as the
/// default build"); its build takes about 1.7x the object-split build's time. Closest-hit
/// ties keep their rule: the blocks hold primitive ids, so an exact tie in `t` between
/// different triangles goes to the lowest primitive id whichever copy a ray reaches, in either
/// build (`tests/ties.rs`).
#[derive(Clone, Debug, PartialEq)]
pub struct BuildOptions {
    pub bins: usize,
    pub max_leaf_size: usize,
    pub traversal_cost: f32,
    pub intersection_cost: f32,
    pub sah_block_size: usize,
    pub parallel_threshold: usize,
    pub spatial_splits: bool,
    pub split_alpha: f32,
    pub split_budget: f32,
    pub split_overlap: f32,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            bins: 32,
            max_leaf_size: 8,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            sah_block_size: 4,
            parallel_threshold: 4096,
            spatial_splits: true,
            split_alpha: 1e-5,
            split_budget: 0.3,
            split_overlap: 0.2,
        }
    }
}

impl BuildOptions {
    pub(crate) fn sanitized(&self) -> Self {
        let finite_pos = |x: f32, d: f32| if x.is_finite() && x > 0.0 { x } else { d };
        Self {
            bins: self.bins.clamp(2, MAX_BINS),
            max_leaf_size: self.max_leaf_size.clamp(1, node::MAX_LEAF_SIZE),
            traversal_cost: finite_pos(self.traversal_cost, 1.0),
            intersection_cost: finite_pos(self.intersection_cost, 1.0),
            sah_block_size: self.sah_block_size.clamp(1, 4),
            parallel_threshold: self.parallel_threshold.max(64),
            spatial_splits: self.spatial_splits,
            split_alpha: if self.split_alpha >= 0.0 {
                self.split_alpha
            } else {
                1e-5
            },
            split_budget: if self.split_budget.is_finite() {
                self.split_budget.clamp(0.0, 4.0)
            } else {
                0.3
            },
            split_overlap: if self.split_overlap >= 0.0 {
                self.split_overlap
            } else {
                0.2
            },
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
