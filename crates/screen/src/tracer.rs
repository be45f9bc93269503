//! The central seam (DESIGN.md): one interface every image-space structure implements.
//!
//! Every structure answers "where does this world-space ray first hit the surfaces captured in
//! these layers?", reports the layer, the pixel, the world position and the world ray
//! parameter, says when the ray instead passed through an **occlusion volume**, and counts its
//! work so benchmarks compare structures on identical rays.
//!
//! **Occlusion volume** (Widmer et al. 2015, §4.1): the space behind a layer's surface as seen
//! from the reference eye — at pixel `p` the part of `p`'s viewing frustum (its footprint
//! column in the unit cube) behind `p`'s plane. The capture knows nothing about what is there,
//! so a ray that enters it without first hitting a captured surface has no trustworthy answer
//! from that layer: a deeper layer (or the ground truth) must decide. Pixels that captured no
//! surface have no occlusion volume (the space is known to be empty up to the far plane).

use std::ops::{Add, AddAssign};

use glam::{UVec2, Vec3};
use parallax_core::Ray;
use serde::Serialize;

/// What a screen-space trace found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TraceResult {
    /// The ray hit the captured surface of `layer` at `pixel`.
    Hit {
        layer: u32,
        pixel: UVec2,
        /// World-space hit position (`ray.at(t)`).
        position: Vec3,
        /// World ray parameter of the hit (in units of `ray.dir`).
        t: f32,
    },
    /// The ray left the reference frustum (or never entered it) without hitting anything.
    Miss,
    /// No captured surface was hit, but the ray passed behind `layer`'s surface at `pixel`
    /// (an occlusion-volume crossing, §4.1) entering at world parameter `t`.
    OcclusionVolume { layer: u32, pixel: UVec2, t: f32 },
}

impl TraceResult {
    /// The world ray parameter of a hit, if any.
    pub fn hit_t(&self) -> Option<f32> {
        match *self {
            TraceResult::Hit { t, .. } => Some(t),
            _ => None,
        }
    }
}

/// Work counters of tracing (summed over rays).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct TraceStats {
    /// Rays traced.
    pub rays: u64,
    /// Hierarchy nodes visited (0 for flat structures).
    pub nodes_visited: u64,
    /// Ray-box (ABB) tests.
    pub box_tests: u64,
    /// Ray-plane (leaf / pixel plane) tests.
    pub plane_tests: u64,
    /// Traversal steps (loop iterations).
    pub steps: u64,
    /// Rays that returned [`TraceResult::Hit`].
    pub hits: u64,
    /// Rays that returned [`TraceResult::OcclusionVolume`].
    pub occlusion_volumes: u64,
    /// Traversals (per ray and layer) that ran out of their step bound before the end of
    /// the ray's segment and answered with what they had found: for the DDA, whose
    /// `max_steps` is a tuned cap, a sign that the cap is too small for the view.
    pub truncated: u64,
}

impl AddAssign for TraceStats {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
        self.nodes_visited += o.nodes_visited;
        self.box_tests += o.box_tests;
        self.plane_tests += o.plane_tests;
        self.steps += o.steps;
        self.hits += o.hits;
        self.occlusion_volumes += o.occlusion_volumes;
        self.truncated += o.truncated;
    }
}

impl Add for TraceStats {
    type Output = Self;
    fn add(mut self, o: Self) -> Self {
        self += o;
        self
    }
}

/// An image-space structure that traces world-space rays against captured layers.
/// Object safe: applications hold a `&dyn ScreenTracer`.
pub trait ScreenTracer: Send + Sync {
    /// Traces `ray` (world space, over `(ray.t_min, ray.t_max)`), adding its work to `stats`.
    fn trace(&self, ray: &Ray, stats: &mut TraceStats) -> TraceResult;
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Never;
    impl ScreenTracer for Never {
        fn trace(&self, _: &Ray, stats: &mut TraceStats) -> TraceResult {
            stats.rays += 1;
            TraceResult::Miss
        }
    }

    #[test]
    fn object_safe_and_stats_add() {
        let t: &dyn ScreenTracer = &Never;
        let mut s = TraceStats::default();
        assert_eq!(
            t.trace(&Ray::new(Vec3::ZERO, Vec3::X), &mut s),
            TraceResult::Miss
        );
        let sum = s + TraceStats {
            plane_tests: 3,
            ..Default::default()
        };
        assert_eq!((sum.rays, sum.plane_tests), (1, 3));
    }
}
