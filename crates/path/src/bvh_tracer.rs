//! The BVH as the path tracer calls it: the same answers as the BVH's own world-space tracer
//! (`impl WorldTracer for Bvh` in `parallax-bvh`), traced with fewer instructions.
//!
//! - **Batches** ([`WorldTracer::closest_hits`]): the wavefront's trace pass hands its rays over
//!   in one call; runs of [`PACKET_SIZE`] consecutive rays that share their origin bit for bit
//!   (a pinhole camera's rays, which the wavefront lays out in 4x4 pixel blocks) go through
//!   the BVH's packet kernel ([`Bvh::closest_hit_packet`]: interval culling of the whole
//!   packet, where the CPU has AVX-512: [`packets_pay`]); every other ray is traced alone
//!   ([`Bvh::closest_hit`]), without a virtual call per ray.
//! - **Work counters**: only rays are counted ([`WorldStats::rays`]); nodes and triangle tests
//!   are not (the per-node counters cost ~4% of the path tracer's instructions on Sponza, and
//!   `bench rays` reports them for the same BVH).
//!
//! **Invariant:** every answer equals the BVH's own (`Bvh::closest_hit` / `Bvh::any_hit`) bit
//! for bit: the packet kernel returns exactly the single-ray hit (prim, t, u, v), so images do
//! not depend on which rays were packed (the tests here check it ray for ray).
//!
//! | parameter | type | meaning |
//! |---|---|---|
//! | `bvh` | [`Bvh`] | the scene's BVH (built by [`crate::tracers::build_tracer`]) |
//! | packet | [`PACKET_SIZE`] rays | consecutive rays with one origin traced together |

use glam::Vec2;
use parallax_bvh::{Bvh, Hit, PACKET_SIZE};
use parallax_core::{Ray, WorldHit, WorldStats, WorldTracer};

/// The scene's BVH behind the world-space tracer interface, with packets for shared-origin
/// batches (see the module docs).
pub struct BvhTracer {
    pub bvh: Bvh,
    /// Trace shared-origin runs as packets (default: where the CPU has AVX-512).
    pub packets: bool,
}

impl BvhTracer {
    /// Packets where the CPU has AVX-512 ([`packets_pay`]).
    pub fn new(bvh: Bvh) -> Self {
        Self {
            bvh,
            packets: packets_pay(),
        }
    }

    /// With packets on or off whatever the CPU (the answers are the same either way).
    pub fn with_packets(bvh: Bvh, packets: bool) -> Self {
        Self { bvh, packets }
    }
}

/// True where the packet kernel runs its AVX-512 lanes. Elsewhere it runs its portable
/// twin, which costs more than the AVX2 single-ray kernel on camera rays (callgrind, 160x90
/// camera rays: 2630 vs 1470 instructions per ray on Sponza, 4800 vs 1160 on the classroom),
/// so rays are traced one by one there.
pub fn packets_pay() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}

#[inline]
fn world_hit(ray: &Ray, h: Option<Hit>) -> Option<WorldHit> {
    h.map(|h| WorldHit::exact(ray, h.t, h.prim, Vec2::new(h.u, h.v)))
}

/// True when all rays of `rays` start at the same point (bit for bit).
#[inline]
fn shared_origin(rays: &[Ray]) -> bool {
    let o = rays[0].origin.to_array().map(f32::to_bits);
    rays[1..]
        .iter()
        .all(|r| r.origin.to_array().map(f32::to_bits) == o)
}

impl WorldTracer for BvhTracer {
    fn name(&self) -> &str {
        "bvh"
    }

    fn is_exact(&self) -> bool {
        true
    }

    fn closest_hit(&self, ray: &Ray, stats: &mut WorldStats) -> Option<WorldHit> {
        stats.rays += 1;
        world_hit(ray, self.bvh.closest_hit(ray))
    }

    fn occluded(&self, ray: &Ray, stats: &mut WorldStats) -> bool {
        stats.rays += 1;
        self.bvh.any_hit(ray)
    }

    fn closest_hits(&self, rays: &[Ray], out: &mut [Option<WorldHit>], stats: &mut WorldStats) {
        stats.rays += rays.len() as u64;
        let mut packet = [None; PACKET_SIZE];
        for (r, o) in rays.chunks(PACKET_SIZE).zip(out.chunks_mut(PACKET_SIZE)) {
            if self.packets && r.len() == PACKET_SIZE && shared_origin(r) {
                self.bvh.closest_hit_packet(r, &mut packet);
                for ((ray, h), o) in r.iter().zip(packet).zip(o.iter_mut()) {
                    *o = world_hit(ray, h);
                }
            } else {
                for (ray, o) in r.iter().zip(o.iter_mut()) {
                    *o = world_hit(ray, self.bvh.closest_hit(ray));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use parallax_scene::Scene;

    use super::*;

    /// Rays of a 16x16 pinhole fan from one eye (packets), then the same directions from
    /// scattered origins (single rays), a segment and an invalid ray.
    fn rays(scene: &Scene) -> Vec<Ray> {
        let cam = &scene.cameras[0].desc;
        let fwd = (cam.target - cam.eye).normalize();
        let right = fwd.cross(Vec3::Y).normalize();
        let up = right.cross(fwd);
        let mut rays = Vec::new();
        for y in 0..16 {
            for x in 0..16 {
                let d = fwd + right * ((x as f32 - 7.5) / 40.0) + up * ((y as f32 - 7.5) / 40.0);
                rays.push(Ray::new(cam.eye, d.normalize()));
            }
        }
        for i in 0..40 {
            let d = rays[i * 5].dir;
            let o = cam.eye + Vec3::new(0.01 * i as f32, 0.003 * i as f32, 0.0);
            rays.push(Ray::new(o, d));
        }
        rays.push(Ray::segment(cam.eye, fwd, 0.0, 0.5));
        rays.push(Ray::new(Vec3::NAN, fwd));
        rays
    }

    #[test]
    fn batches_answer_as_the_bvh_ray_for_ray() {
        let scene = Scene::load("cornell").unwrap();
        let bvh = Bvh::build(&scene.mesh);
        let rays = rays(&scene);
        for packets in [true, false] {
            let tracer = BvhTracer::with_packets(Bvh::build(&scene.mesh), packets);
            agrees(&tracer, &bvh, &rays);
        }
        assert!(shared_origin(&rays[..16]) && !shared_origin(&rays[256..272]));
    }

    fn agrees(tracer: &BvhTracer, bvh: &Bvh, rays: &[Ray]) {
        let mut out = vec![None; rays.len()];
        let mut stats = WorldStats::default();
        tracer.closest_hits(rays, &mut out, &mut stats);
        assert_eq!(stats.rays, rays.len() as u64);
        let mut hits = 0;
        for (ray, got) in rays.iter().zip(&out) {
            let want = WorldTracer::closest_hit(bvh, ray, &mut WorldStats::default());
            assert_eq!(got.map(|h| h.t.to_bits()), want.map(|h| h.t.to_bits()));
            assert_eq!(got.map(|h| h.prim), want.map(|h| h.prim));
            assert_eq!(
                got.map(|h| h.barycentrics.to_array().map(f32::to_bits)),
                want.map(|h| h.barycentrics.to_array().map(f32::to_bits))
            );
            assert_eq!(
                got.map(|h| h.position.to_array().map(f32::to_bits)),
                want.map(|h| h.position.to_array().map(f32::to_bits))
            );
            assert_eq!(
                tracer.occluded(ray, &mut stats),
                WorldTracer::occluded(bvh, ray, &mut WorldStats::default())
            );
            hits += got.is_some() as usize;
        }
        // The fan sees the box's walls; the segment and the invalid ray hit nothing.
        assert!(hits >= 256, "{hits}");
        assert!(out[out.len() - 1].is_none() && out[out.len() - 2].is_none());
    }
}
