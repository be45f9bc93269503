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
    pub(crate) fn sanitized(&self) -> Self {
        let finite_pos = |x: f32, d: f32| if x.is_finite() && x > 0.0 { x } else { d };
        Self {
            bins: self.bins.clamp(2, MAX_BINS),
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
