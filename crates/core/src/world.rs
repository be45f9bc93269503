//! The world-space tracer interface: closest hit and occlusion for a ray that starts anywhere
//! and goes anywhere (DESIGN.md, "the second seam").
//!
//! Secondary rays (path tracing, reflections, refractions, shadows) are not tied to one view,
//! so the screen-space interface of `parallax-screen` does not fit them. Every structure that
//! can answer a world-space ray implements [`WorldTracer`]: the BVH (exact), DIRT's per-pixel
//! primitive lists (exact: analytic intersection of conservative lists), the layered depth
//! cube and Widmer's cube-map quad-trees (sampled). Applications are written once against it,
//! and every structure is compared on identical rays.
//!
//! **Exact and sampled hits.** An exact tracer finds the scene triangle and the barycentrics
//! of the hit; it returns [`HitSurface::Exact`] and the consumer fetches normals, material and
//! texture from the scene by `prim` and `barycentrics` (DIRT §4.2's fetch pass, done once per
//! hit that is shaded, not per triangle tested). A sampled tracer answers from stored samples
//! (depth, normal, albedo, material, and the primitive id where the capture kept it); it
//! returns [`HitSurface::Sampled`] with those values.
//!
//! **Invariants** (every implementation):
//! - a hit has `ray.t_min < t < ray.t_max` and `position == ray.at(t)` up to rounding (sampled
//!   tracers may report the stored sample's position instead, within their tolerance);
//! - [`WorldTracer::occluded`] is true exactly when [`WorldTracer::closest_hit`] would return
//!   a hit (it may stop at the first one);
//! - an invalid ray ([`Ray::is_valid`] false: NaN or zero direction) misses, and every
//!   traversal loop is bounded (rays cut by a bound count in [`WorldStats::truncated`]);
//! - the answer does not depend on the thread or on the order rays are asked in.

use std::iter::Sum;
use std::ops::{Add, AddAssign};

use glam::{Vec2, Vec3};

use crate::image::NO_ID;
use crate::math::Ray;

/// Surface attributes stored by a sampled structure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledSurface {
    /// Unit normal of the sample (geometric and shading: a sample stores one).
    pub normal: Vec3,
    /// Linear RGB albedo (base colour times texture).
    pub albedo: Vec3,
    /// Material id, [`NO_ID`] if the capture did not keep it.
    pub material_id: u32,
}

/// Where the attributes of a hit come from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HitSurface {
    /// Analytic hit on `prim` at `barycentrics`: fetch attributes from the scene.
    Exact,
    /// A stored sample's attributes.
    Sampled(SampledSurface),
}

/// A world-space hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldHit {
    /// Ray parameter, in `(ray.t_min, ray.t_max)`.
    pub t: f32,
    /// World-space position.
    pub position: Vec3,
    /// Scene triangle, [`NO_ID`] where the structure does not know it.
    pub prim: u32,
    /// Barycentrics `(b1, b2)` on `prim` (`b0 = 1 - b1 - b2`); zero for sampled hits.
    pub barycentrics: Vec2,
    pub surface: HitSurface,
}

impl WorldHit {
    /// An exact hit of `ray` on triangle `prim` at parameter `t`.
    #[inline]
    pub fn exact(ray: &Ray, t: f32, prim: u32, barycentrics: Vec2) -> Self {
        Self {
            t,
            position: ray.at(t),
            prim,
            barycentrics,
            surface: HitSurface::Exact,
        }
    }

    /// True when the primitive is known.
    #[inline]
    pub fn has_prim(&self) -> bool {
        self.prim != NO_ID
    }
}

/// What a world-space tracer did, summed over rays with `+=` or `.sum()`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct WorldStats {
    /// Rays asked (closest hit and occlusion).
    pub rays: u64,
    /// Hierarchy nodes / cells / texels visited.
    pub nodes: u64,
    /// Primitive or sample tests.
    pub tests: u64,
    /// Steps of marching loops (DDA cells, buckets, face switches).
    pub steps: u64,
    /// Rays whose traversal ran out of its step bound (the answer may be wrong).
    pub truncated: u64,
}

impl WorldStats {
    /// Average over rays of a counter (0 when no ray was traced).
    pub fn per_ray(&self, counter: u64) -> f64 {
        if self.rays == 0 {
            0.0
        } else {
            counter as f64 / self.rays as f64
        }
    }
}

impl AddAssign for WorldStats {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
        self.nodes += o.nodes;
        self.tests += o.tests;
        self.steps += o.steps;
        self.truncated += o.truncated;
    }
}

impl Add for WorldStats {
    type Output = Self;
    fn add(mut self, o: Self) -> Self {
        self += o;
        self
    }
}

impl Sum for WorldStats {
    fn sum<I: Iterator<Item = Self>>(iter: I) -> Self {
        iter.fold(Self::default(), Add::add)
    }
}

/// A structure that answers world-space rays (see the module docs for the invariants).
pub trait WorldTracer: Sync {
    /// Short name for tables and flags (`bvh`, `dirt`, `ldc`, ...).
    fn name(&self) -> &str;

    /// True when hits are analytic on scene triangles ([`HitSurface::Exact`]).
    fn is_exact(&self) -> bool;

    /// The first surface along `ray` within `(t_min, t_max)`.
    fn closest_hit(&self, ray: &Ray, stats: &mut WorldStats) -> Option<WorldHit>;

    /// Is there any surface along `ray` within `(t_min, t_max)`?
    fn occluded(&self, ray: &Ray, stats: &mut WorldStats) -> bool;

    /// Closest hits of a batch of rays (`out[i]` for `rays[i]`); structures that exploit
    /// coherence (packets, per-view buckets) override it. Same answers as one ray at a time.
    fn closest_hits(&self, rays: &[Ray], out: &mut [Option<WorldHit>], stats: &mut WorldStats) {
        for (ray, o) in rays.iter().zip(out.iter_mut()) {
            *o = self.closest_hit(ray, stats);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_sum() {
        let a = WorldStats {
            rays: 1,
            nodes: 2,
            tests: 3,
            steps: 4,
            truncated: 0,
        };
        let s: WorldStats = [a, a].into_iter().sum();
        assert_eq!(s.rays, 2);
        assert_eq!(s.steps, 8);
        assert_eq!(s.per_ray(s.nodes), 2.0);
        assert_eq!(WorldStats::default().per_ray(0), 0.0);
    }

    #[test]
    fn exact_hit_position_is_on_the_ray() {
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        let h = WorldHit::exact(&ray, 2.0, 7, Vec2::new(0.25, 0.5));
        assert_eq!(h.position, Vec3::new(2.0, 0.0, 0.0));
        assert!(h.has_prim());
        assert_eq!(h.surface, HitSurface::Exact);
    }
}
