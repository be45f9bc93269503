//! What a render did: paths, rays per bounce, the time of each pass kind, and the tracer's
//! own work counters.
//!
//! Bounce `b` is the `b`-th segment of every path (0 = camera rays); bounces past
//! [`TRACKED_BOUNCES`] are summed into the last entry. Times are thread CPU time summed over
//! the workers (each wavefront times its own passes), so `rays / seconds` is a per-thread rate.

use parallax_core::WorldStats;
use serde::Serialize;

/// Bounces with their own statistics entry; later ones share the last.
pub const TRACKED_BOUNCES: usize = 16;

/// Rays and pass times of one bounce.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct BounceStats {
    /// Closest-hit rays (one per live path).
    pub rays: u64,
    /// Of those, rays that hit a surface.
    pub hits: u64,
    /// Shadow (occlusion) rays of next-event estimation at this bounce's vertices.
    pub shadow_rays: u64,
    /// Nanoseconds in the trace pass (closest hits).
    pub trace_ns: u64,
    /// Nanoseconds in the fetch pass (hit attributes).
    pub fetch_ns: u64,
    /// Nanoseconds in the shade pass (estimator).
    pub shade_ns: u64,
    /// Nanoseconds in the occlusion pass (shadow rays).
    pub shadow_ns: u64,
}

impl BounceStats {
    fn add(&mut self, o: &BounceStats) {
        self.rays += o.rays;
        self.hits += o.hits;
        self.shadow_rays += o.shadow_rays;
        self.trace_ns += o.trace_ns;
        self.fetch_ns += o.fetch_ns;
        self.shade_ns += o.shade_ns;
        self.shadow_ns += o.shadow_ns;
    }
}

/// Statistics of one or more passes, merged with [`PathStats::merge`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PathStats {
    /// Camera paths started.
    pub paths: u64,
    /// Per bounce (see the module docs).
    pub bounces: Vec<BounceStats>,
    /// The tracer's counters over all rays.
    pub world: WorldStats,
    /// Wall-clock nanoseconds the workers spent rendering tiles, summed over the workers:
    /// threads x render seconds minus this is the time workers had no tile to render.
    pub work_ns: u64,
}

impl Default for PathStats {
    fn default() -> Self {
        Self {
            paths: 0,
            bounces: vec![BounceStats::default(); TRACKED_BOUNCES],
            world: WorldStats::default(),
            work_ns: 0,
        }
    }
}

impl PathStats {
    /// The entry of bounce `b`.
    #[inline]
    pub fn bounce_mut(&mut self, b: u32) -> &mut BounceStats {
        let i = (b as usize).min(TRACKED_BOUNCES - 1);
        &mut self.bounces[i]
    }

    pub fn merge(&mut self, o: &PathStats) {
        self.paths += o.paths;
        for (a, b) in self.bounces.iter_mut().zip(&o.bounces) {
            a.add(b);
        }
        self.world += o.world;
        self.work_ns += o.work_ns;
    }

    /// Closest-hit plus shadow rays.
    pub fn rays(&self) -> u64 {
        self.bounces.iter().map(|b| b.rays + b.shadow_rays).sum()
    }

    /// Summed nanoseconds of the four passes.
    pub fn pass_ns(&self) -> u64 {
        self.bounces
            .iter()
            .map(|b| b.trace_ns + b.fetch_ns + b.shade_ns + b.shadow_ns)
            .sum()
    }

    /// The last bounce with any ray, plus one.
    pub fn depth(&self) -> usize {
        self.bounces
            .iter()
            .rposition(|b| b.rays > 0)
            .map_or(0, |i| i + 1)
    }
}
