//! Thread CPU time of the beam caster vs per-ray BVH traversal on one thread (stable on a
//! loaded machine: interleaved rounds, best of each).
//!
//! `cargo run --release -p parallax-render --example vr_cast_cpu [-- scene eye_w h spp rounds
//! edges|full|watertight [beam-only]]` (defaults: atrium 540 600 16 5 edges; stereo rig, film
//! 2 eye_w x h; `scene` a built-in name or a model path, e.g.
//! `../shared/scenes/sponza_dabrovic/sponza_dabrovic.glb` from the repository root; `edges` =
//! the set-up kernel with [`SetupExactness::Edges`] (default), `full` = with
//! [`SetupExactness::Full`], `watertight` = the watertight kernel, `edges-plain` = `edges`
//! without the affine packet test, `edges-affine` = `edges` with it on every kernel: `CastOptions::affine_always`, `edges-walk` = `edges` without the sweep: `CastOptions::sweep`). Optional further arguments:
//! `lanes` (8th, default 4: `CastOptions::lanes`; a suffix `sse` / `avx2` caps `CastOptions::isa`
//! at that tier, e.g. `16sse` the portable twin) and a head pose `eye target fov_y` (9th-11th,
//! e.g. `-9,3.5,0 8,5,0 60`; default the scene's camera). `BVH_SPATIAL=0` builds the BVH
//! without spatial splits (the object-split tree; default: the SBVH, `Bvh::build`). Also prints
//! the hierarchy's build time and the time to move it to a head turned by a degree and
//! back (`Hierarchy::repose`); the cast runs on the moved-back hierarchy.

use parallax_bvh::{BuildOptions, Bvh};
use parallax_core::cpu_time::{ms_between, thread_cpu_ns};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_vr::{
    CastOptions, Hierarchy, Isa, SampleSet, SampleTest, SetupExactness, VisibilityBuffer,
    cast_opts, trace_per_ray,
};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: &str| args.get(i).cloned().unwrap_or_else(|| d.to_string());
    let scene_name = arg(1, "atrium");
    let eye_w: u32 = arg(2, "540").parse().unwrap();
    let h: u32 = arg(3, "600").parse().unwrap();
    let spp: u32 = arg(4, "16").parse().unwrap();
    let rounds: usize = arg(5, "5").parse().unwrap();
    let mode = arg(6, "edges");
    let (test, exactness) = match mode.as_str() {
        "watertight" => (SampleTest::Watertight, SetupExactness::Full),
        "full" => (SampleTest::TileSetup, SetupExactness::Full),
        "edges" | "setup" | "edges-plain" | "edges-affine" | "edges-walk" => {
            (SampleTest::TileSetup, SetupExactness::Edges)
        }
        m => panic!("unknown mode {m:?}: edges, full or watertight"),
    };
    // `beam-only` as the 7th argument skips the per-ray baseline (for instruction counts).
    let beam_only = arg(7, "") == "beam-only";
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        let scene = Scene::load(&scene_name).expect("scene");
        let bvh = Bvh::build_with(
            &scene.mesh,
            &BuildOptions {
                spatial_splits: std::env::var("BVH_SPATIAL").map_or(true, |v| v != "0"),
                ..Default::default()
            },
        );
        let v3 = |s: &str| {
            let c: Vec<f32> = s.split(',').map(|x| x.parse().unwrap()).collect();
            glam::Vec3::new(c[0], c[1], c[2])
        };
        let desc = match args.get(11) {
            Some(fov) => parallax_scene::CameraDesc::new(
                v3(&args[9]),
                v3(&args[10]),
                glam::Vec3::Y,
                fov.parse().unwrap(),
            ),
            None => scene.camera(None).unwrap(),
        };
        let cam = Camera::new(
            ModelKind::Stereo,
            &desc,
            eye_w,
            h,
            &CameraOptions::default(),
        )
        .unwrap();
        let set = SampleSet::grid(cam, spp);
        // The hierarchy moved to a head turned by a degree and back (`Hierarchy::repose`:
        // what a moving head costs per frame instead of a build).
        let turned = {
            let d = desc.turned(1.0);
            let cam = Camera::new(ModelKind::Stereo, &d, eye_w, h, &CameraOptions::default());
            SampleSet {
                camera: cam.unwrap(),
                ..set.clone()
            }
        };
        let a = thread_cpu_ns();
        let mut hier = Hierarchy::build(&set).unwrap();
        let b = thread_cpu_ns();
        hier.repose(&turned).unwrap();
        let c = thread_cpu_ns();
        hier.repose(&set).unwrap();
        let d = thread_cpu_ns();
        println!(
            "hierarchy: build {:.1} ms, moved to a turned head {:.2} ms and back {:.2} ms (thread CPU)",
            ms_between(a, b),
            ms_between(b, c),
            ms_between(c, d)
        );
        let opts = CastOptions {
            test,
            // `16sse`: the portable 16-lane twin (SSE tier); `16avx2`: at most the AVX2 tier.
            lanes: arg(8, "4")
                .trim_end_matches("sse")
                .trim_end_matches("avx2")
                .parse()
                .unwrap(),
            exactness,
            isa: match arg(8, "4") {
                l if l.ends_with("sse") => Isa::Sse,
                l if l.ends_with("avx2") => Isa::Avx2,
                _ => Isa::Avx512,
            },
            // `edges-plain`: without the affine packet test (`cast/setup/affine.rs`).
            affine: mode != "edges-plain",
            // `edges-affine`: the affine packet test on every kernel.
            affine_always: mode == "edges-affine",
            // `edges-walk`: the run walk per packet instead of the sweep (`cast/setup/sweep.rs`).
            sweep: mode != "edges-walk",
        };
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
            "{scene_name} {}x{h} spp {spp} {mode}: beam {best_beam:.1} ms = {:.2} Mrays/s, per-ray \
             {best_ray:.1} ms = {:.2} Mrays/s, ratio {:.3}x, agreement {:.6} (thread CPU, best of {rounds})",
            2 * eye_w,
            n / best_beam / 1e3,
            n / best_ray / 1e3,
            best_ray / best_beam,
            beam.agreement(&reference)
        );
        // FNV-1a of the buffer (triangle and `t` bits of every subsample): equal buffers, equal
        // hashes (compares builds and modes).
        let mut hash = 0xcbf2_9ce4_8422_2325u64;
        for (p, t) in beam.prim.iter().zip(&beam.t) {
            for x in [*p, t.to_bits()] {
                hash = (hash ^ x as u64).wrapping_mul(0x0100_0000_01b3);
            }
        }
        println!("  buffer hash {hash:016x}");
        let tris = (stats.tris_all_out + stats.tris_partial + stats.tris_all_in).max(1) as f64;
        println!(
            "  set-up triangles: all-out {:.4} partial {:.4} all-in {:.4} of {tris}, packet-triangle tests / ray {:.4}; \
             {} repeated list entries dropped (a split triangle's other leaves)",
            stats.tris_all_out as f64 / tris,
            stats.tris_partial as f64 / tris,
            stats.tris_all_in as f64 / tris,
            stats.tri_tests as f64 / stats.rays.max(1) as f64,
            stats.tris_repeated
        );
        println!(
            "  last round: block cull {:.1} ms, tile cull + set-up {:.1} ms, sample test {:.1} ms",
            stats.block_cull.as_secs_f64() * 1e3,
            stats.tile_cull.as_secs_f64() * 1e3,
            stats.sample_test.as_secs_f64() * 1e3
        );
        let s: parallax_vr::CastStats = stats;
        println!(
            "  set-up: {:.3} packet-triangle tests / ray, band (watertight) tests {:.4} of the \
             ray-triangle tests (edge band {:.4}), winner t tests {:.3} / ray, rescues {}",
            s.tri_tests as f64 / s.rays.max(1) as f64,
            s.setup_exact_tests as f64 / s.setup_pair_tests.max(1) as f64,
            s.setup_edge_band as f64 / s.setup_pair_tests.max(1) as f64,
            s.setup_final_tests as f64 / s.rays.max(1) as f64,
            s.setup_rescues
        );
        println!(
            "  affine packet test: {:.4} of the packet-triangle tests all out, {:.4} all in",
            s.setup_packet_out as f64 / s.tri_tests.max(1) as f64,
            s.setup_packet_in as f64 / s.tri_tests.max(1) as f64,
        );
    });
}
