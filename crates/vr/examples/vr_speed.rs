//! HVVR beam caster vs per-ray BVH traversal (Hunt et al. 2018, Table 5 / 6 workload): atrium,
//! stereo rig 1080 x 1200 per eye (film 2160 x 1200), spp 1, 8, 16, 32.
//!
//! `cargo run --release -p parallax-render --example vr_speed [-- scene eye_w h spp,spp,.. lanes
//! setup|watertight]` (defaults: atrium 1080 1200 1,8,16,32 4 setup)
//!
//! Prints per spp: hierarchy build time, the beam caster's wall time and Mrays/s (best of 3),
//! the per-ray baseline's (best of 2),
//! per-stage CPU ms (summed over threads), the per-ray baseline's Mrays/s on the same rays, the
//! speed-up and the agreement of the two visibility buffers.

use std::time::Instant;

use parallax_bvh::Bvh;
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_vr::{
    CastOptions, Hierarchy, SampleSet, SampleTest, VisibilityBuffer, cast_opts, trace_per_ray,
};

/// The per-ray baseline with the caster's cheap ray generation (`fast_subsample_ray`), to
/// separate the traversal saving from the ray-generation saving.
fn trace_per_ray_fast(bvh: &Bvh, set: &SampleSet, out: &mut VisibilityBuffer) {
    use rayon::prelude::*;
    let spp = set.spp as usize;
    out.prim
        .par_chunks_mut(spp)
        .zip(out.t.par_chunks_mut(spp))
        .enumerate()
        .for_each(|(i, (prim, t))| {
            for k in 0..spp {
                let hit = set
                    .fast_subsample_ray(i, k)
                    .and_then(|ray| bvh.closest_hit(&ray));
                (prim[k], t[k]) = match hit {
                    Some(h) => (h.prim, h.t),
                    None => (u32::MAX, f32::INFINITY),
                };
            }
        });
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene_name = args.get(1).map(String::as_str).unwrap_or("atrium");
    let eye_w: u32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1080);
    let h: u32 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1200);
    let spps: Vec<u32> = args
        .get(4)
        .map(|s| s.split(',').filter_map(|x| x.parse().ok()).collect())
        .unwrap_or_else(|| vec![1, 8, 16, 32]);
    // Sample-test kernel: 4 = SSE packets (default), 8 = AVX2 packets, 1 = one ray at a time.
    let lanes: usize = args.get(5).and_then(|s| s.parse().ok()).unwrap_or(4);
    // Sample test: `setup` (HVVR's per-tile triangle set-up, the default) or `watertight`.
    let test = match args.get(6).map(String::as_str) {
        Some("watertight") => SampleTest::Watertight,
        _ => SampleTest::TileSetup,
    };
    let opts = CastOptions {
        test,
        lanes,
        ..CastOptions::default()
    };
    let scene = Scene::load(scene_name).expect("scene");
    let bvh = Bvh::build(&scene.mesh);
    let desc = scene.camera(None).unwrap();
    let cam = Camera::new(
        ModelKind::Stereo,
        &desc,
        eye_w,
        h,
        &CameraOptions::default(),
    )
    .unwrap();
    println!(
        "{scene_name}: {} triangles, {} nodes; stereo {}x{} per eye (film {}x{}), {} threads, {lanes}-lane {test:?} sample test",
        bvh.triangle_count(),
        bvh.node_count(),
        eye_w,
        h,
        2 * eye_w,
        h,
        rayon::current_num_threads()
    );
    for spp in spps {
        let set = SampleSet::grid(cam.clone(), spp);
        let t = Instant::now();
        let hier = Hierarchy::build(&set).unwrap();
        let build = t.elapsed();
        let mut beam = VisibilityBuffer::new(&set);
        let mut best = None;
        for _ in 0..3 {
            let s = cast_opts(&bvh, &set, &hier, &mut beam, opts);
            if best.is_none_or(|b: parallax_vr::CastStats| s.wall < b.wall) {
                best = Some(s);
            }
        }
        let s = best.unwrap();
        // Best of two for the baseline too (the machine's load varies between runs).
        let mut reference = VisibilityBuffer::new(&set);
        let mut per_ray = std::time::Duration::MAX;
        for _ in 0..2 {
            let t = Instant::now();
            trace_per_ray(&bvh, &set, &mut reference);
            per_ray = per_ray.min(t.elapsed());
        }
        let mut fast = VisibilityBuffer::new(&set);
        let t = Instant::now();
        trace_per_ray_fast(&bvh, &set, &mut fast);
        let per_ray_fast = t.elapsed();
        assert_eq!(fast.prim, reference.prim);
        let n = set.ray_count() as f64;
        let beam_rate = n / s.wall.as_secs_f64() / 1e6;
        let ray_rate = n / per_ray.as_secs_f64() / 1e6;
        println!(
            "spp {spp:2}: {:.1} M rays | hierarchy {:.0} ms ({} tiles, {} blocks) | beam {:.1} ms = {:.1} Mrays/s \
             [cpu ms: block cull {:.1}, tile cull {:.1}, sample test {:.1}; {:.1} entries/block, {:.1} leaves/tile, {:.2} group + {:.2} leaf tests/ray] \
             | per-ray {:.1} ms = {:.1} Mrays/s (with the caster's ray generation: {:.1} Mrays/s) | speed-up {:.2}x | agreement {:.6}",
            n / 1e6,
            build.as_secs_f64() * 1e3,
            hier.tiles.len(),
            hier.blocks.len(),
            s.wall.as_secs_f64() * 1e3,
            beam_rate,
            s.block_cull.as_secs_f64() * 1e3,
            s.tile_cull.as_secs_f64() * 1e3,
            s.sample_test.as_secs_f64() * 1e3,
            s.entry_points as f64 / s.blocks.max(1) as f64,
            s.tile_leaves as f64 / s.tiles.max(1) as f64,
            s.group_tests as f64 / s.rays.max(1) as f64,
            s.leaf_tests as f64 / s.rays.max(1) as f64,
            per_ray.as_secs_f64() * 1e3,
            ray_rate,
            n / per_ray_fast.as_secs_f64() / 1e6,
            beam_rate / ray_rate,
            beam.agreement(&reference)
        );
    }
}
