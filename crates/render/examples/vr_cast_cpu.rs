//! Thread CPU time of the beam caster vs per-ray BVH traversal on one thread (stable on a
//! loaded machine: interleaved rounds, best of each).
//!
//! `cargo run --release -p parallax-render --example vr_cast_cpu [-- scene eye_w h spp rounds
//! setup|watertight [beam-only]]` (defaults: atrium 540 600 16 5 setup; stereo rig, film 2 eye_w x h).

use parallax_bvh::Bvh;
use parallax_core::cpu_time::{ms_between, thread_cpu_ns};
use parallax_render::vr::{
    CastOptions, Hierarchy, SampleSet, SampleTest, VisibilityBuffer, cast_opts, trace_per_ray,
};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: &str| args.get(i).cloned().unwrap_or_else(|| d.to_string());
    let scene_name = arg(1, "atrium");
    let eye_w: u32 = arg(2, "540").parse().unwrap();
    let h: u32 = arg(3, "600").parse().unwrap();
    let spp: u32 = arg(4, "16").parse().unwrap();
    let rounds: usize = arg(5, "5").parse().unwrap();
    let test = match arg(6, "setup").as_str() {
        "watertight" => SampleTest::Watertight,
        _ => SampleTest::TileSetup,
    };
    // `beam-only` as the 7th argument skips the per-ray baseline (for instruction counts).
    let beam_only = arg(7, "") == "beam-only";
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        let scene = Scene::load(&scene_name).expect("scene");
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
        let set = SampleSet::grid(cam, spp);
        let hier = Hierarchy::build(&set).unwrap();
        let opts = CastOptions { test, lanes: 4 };
        let mut beam = VisibilityBuffer::new(&set);
        let mut reference = VisibilityBuffer::new(&set);
        let (mut best_beam, mut best_ray) = (f64::INFINITY, f64::INFINITY);
        let mut stats = Default::default();
        for _ in 0..rounds {
            let a = thread_cpu_ns();
            stats = cast_opts(&bvh, &set, &hier, &mut beam, opts);
            let b = thread_cpu_ns();
            if !beam_only {
                trace_per_ray(&bvh, &set, &mut reference);
            }
            let c = thread_cpu_ns();
            best_beam = best_beam.min(ms_between(a, b));
            best_ray = best_ray.min(ms_between(b, c));
        }
        let n = set.ray_count() as f64;
        println!(
            "{scene_name} {}x{h} spp {spp} {test:?}: beam {best_beam:.1} ms = {:.2} Mrays/s, per-ray \
             {best_ray:.1} ms = {:.2} Mrays/s, ratio {:.3}x, agreement {:.6} (thread CPU, best of {rounds})",
            2 * eye_w,
            n / best_beam / 1e3,
            n / best_ray / 1e3,
            best_ray / best_beam,
            beam.agreement(&reference)
        );
        let s: parallax_render::vr::CastStats = stats;
        println!(
            "  set-up: {:.3} packet-triangle tests / ray, band (watertight) tests {:.4} of the \
             ray-triangle tests, winner t tests {:.3} / ray, rescues {}",
            s.tri_tests as f64 / s.rays.max(1) as f64,
            s.setup_exact_tests as f64 / s.setup_pair_tests.max(1) as f64,
            s.setup_final_tests as f64 / s.rays.max(1) as f64,
            s.setup_rescues
        );
    });
}
