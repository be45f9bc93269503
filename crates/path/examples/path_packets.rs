//! In-process A/B of the path tracer's camera-ray packets: renders one view with the BVH
//! behind [`BvhTracer`] with packets on and off, alternately, `REPS` times each, on one
//! thread, and prints the best trace-pass thread CPU time of the camera rays (bounce 0) and of
//! the whole render of each, their ratios, and whether the two images are equal bit for bit.
//!
//! ```sh
//! cargo build --release -p parallax-path --example path_packets
//! target/release/examples/path_packets ../shared/scenes/sponza_dabrovic/sponza_dabrovic.glb \
//!     -9,3.5,0 8,5,0 60 160 90 16 5
//! ```
//!
//! Arguments: `SCENE EYE TARGET FOV_Y WIDTH HEIGHT SPP REPS` (`--materials diffuse`, the
//! scene's lights or the default sky, max depth 16).

use std::time::Instant;

use glam::Vec3;
use parallax_bvh::Bvh;
use parallax_path::bvh_tracer::{BvhTracer, packets_pay};
use parallax_path::{LightOverrides, PathOptions, PathTracer, apply_lighting};
use parallax_render::bsdf::MaterialMode;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_scene::{CameraDesc, Scene};

fn vec3(s: &str) -> Vec3 {
    let v: Vec<f32> = s.split(',').map(|x| x.parse().expect("a number")).collect();
    Vec3::new(v[0], v[1], v[2])
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let arg = |i: usize| a.get(i).map(String::as_str);
    let mut scene = Scene::load(arg(1).unwrap_or("atrium")).expect("scene");
    apply_lighting(&mut scene, &LightOverrides::default()).expect("lighting");
    let desc = match (arg(2), arg(3)) {
        (Some(e), Some(t)) => CameraDesc::new(
            vec3(e),
            vec3(t),
            Vec3::Y,
            arg(4).map_or(60.0, |f| f.parse().unwrap()),
        ),
        _ => scene.camera(None).expect("camera"),
    };
    let num = |i: usize, d: u32| arg(i).map_or(d, |s| s.parse().unwrap());
    let (w, h, spp, reps) = (num(5, 160), num(6, 90), num(7, 16), num(8, 5));
    let camera =
        Camera::new(ModelKind::Pinhole, &desc, w, h, &CameraOptions::default()).expect("camera");
    let opts = PathOptions {
        spp,
        materials: MaterialMode::Diffuse,
        ..PathOptions::default()
    };
    let tracers = [true, false].map(|p| BvhTracer::with_packets(Bvh::build(&scene.mesh), p));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut best = [(f64::INFINITY, f64::INFINITY); 2];
    let mut images = [None, None];
    for _ in 0..reps {
        for (k, t) in tracers.iter().enumerate() {
            let pt = PathTracer::new(&scene, &camera, t, opts.clone()).expect("options");
            let start = Instant::now();
            let out = pool.install(|| pt.render(&|_| {}));
            let wall = start.elapsed().as_secs_f64() * 1e3;
            let cam = out.stats.bounces[0].trace_ns as f64 * 1e-6;
            best[k] = (best[k].0.min(cam), best[k].1.min(wall));
            images[k] = Some(out.image);
        }
    }
    let same = images[0] == images[1];
    println!(
        "packets_pay {}; camera-ray trace ms: packets {:.1}, single {:.1} (ratio {:.2}); render ms: packets {:.0}, single {:.0} (ratio {:.3}); images equal: {same}",
        packets_pay(),
        best[0].0,
        best[1].0,
        best[1].0 / best[0].0,
        best[0].1,
        best[1].1,
        best[1].1 / best[0].1
    );
}
