//! A driver for A/B timings and instruction-count profiles of the reprojection passes: traces
//! the frames of a stereo sequence once (right eye at 1 spp, left eye's G-buffer), then runs
//! the methods over them `REPS` times inside [`passes`] (histories restarted each time) and
//! prints, per method, the best repetition's thread CPU ms per frame of each mode next to the
//! right eye's 1-spp trace.
//!
//! ```sh
//! cargo build --release -p parallax-path --example reproject_cost
//! target/release/examples/reproject_cost atrium 320 180 6 5 paper,bmfr,ours
//! valgrind --tool=callgrind --toggle-collect='reproject_cost::passes' \
//!   target/release/examples/reproject_cost atrium 160 90 4 1 ours
//! ```
//!
//! Arguments: `SCENE WIDTH HEIGHT FRAMES REPS METHODS` (defaults: atrium 320 180 6 5
//! paper,bmfr,ours). The passes run inside one rayon pool of `RAYON_NUM_THREADS` threads
//! (default 1), so under callgrind `--toggle-collect` on [`passes`] counts them and nothing
//! else but the left pixels traced after the stereo tests (`PaperSampler::trace_pixels`,
//! listed by `callgrind_annotate --inclusive=yes`).

use std::sync::Arc;

use glam::Vec3;
use parallax_path::reproject::sequence::{NORMAL_DEG, default_tests, eye_pinhole, eye_seed};
use parallax_path::reproject::{
    Dataset, EyeView, FrameWorld, Method, MethodState, PaperSampler, Tests, Variant,
    method::FrameInputs,
};
use parallax_render::bsdf::MaterialMode;
use parallax_scene::Scene;
use parallax_scene::camera::Eye;

/// One traced frame.
struct Traced {
    right: Arc<EyeView>,
    right_radiance: Vec<Vec3>,
    left: Arc<EyeView>,
    left_background: Vec<Vec3>,
    left_seed: u64,
    trace_ns: u64,
}

/// Every method over every frame, histories restarted; per method and frame the thread CPU
/// ns of (stereo, temporal, stereo + temporal).
#[inline(never)]
fn passes(
    sampler: &PaperSampler,
    frames: &[Traced],
    tests: Tests,
    states: &mut [MethodState],
) -> Vec<[u64; 3]> {
    let mut ns = vec![[0u64; 3]; states.len()];
    for s in states.iter_mut() {
        s.reset();
    }
    for f in frames {
        let inp = FrameInputs {
            sampler,
            right: f.right.clone(),
            right_radiance: &f.right_radiance,
            left: f.left.clone(),
            left_background: &f.left_background,
            left_seed: f.left_seed,
            tests,
        };
        for (s, n) in states.iter_mut().zip(&mut ns) {
            let out = s.step(&inp);
            n[0] += out.stereo.reproject_ns;
            n[1] += out.temporal.reproject_ns;
            n[2] += out.combined.reproject_ns;
        }
    }
    ns
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: &str| args.get(i).cloned().unwrap_or_else(|| d.to_string());
    let scene = arg(1, "atrium");
    let (w, h): (u32, u32) = (
        arg(2, "320").parse().unwrap(),
        arg(3, "180").parse().unwrap(),
    );
    let nframes: u32 = arg(4, "6").parse().unwrap();
    let reps: u32 = arg(5, "5").parse().unwrap();
    let methods = arg(6, "paper,bmfr,ours");
    let threads: usize = std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    let mut world =
        Dataset::new(Scene::load(&scene).expect("scene"), Variant::Base).expect("dataset");
    let materials = MaterialMode::AsIs;
    let ipd = 0.065;
    let mut frames = Vec::new();
    let mut tests = None;
    for f in 0..nframes {
        world.pose(f).expect("pose");
        let head = world.head(f);
        let rc = eye_pinhole(&head, ipd, Eye::Right, w, h).expect("camera");
        let lc = eye_pinhole(&head, ipd, Eye::Left, w, h).expect("camera");
        let sampler = PaperSampler::new(world.scene(), world.tracer(), materials);
        let (rs, ls) = (eye_seed(0, f, Eye::Right), eye_seed(0, f, Eye::Left));
        let mut right = EyeView::new(rc);
        let mut right_radiance = vec![Vec3::ZERO; right.len()];
        let cost = pool.install(|| sampler.trace_eye(rs, &mut right, &mut right_radiance));
        let mut left = EyeView::new(lc);
        let mut left_background = vec![Vec3::ZERO; left.len()];
        pool.install(|| sampler.trace_gbuffer(ls, &mut left, &mut left_background));
        tests.get_or_insert_with(|| Tests {
            position: default_tests(&right).map_or(0.0, |d| d.position),
            normal_deg: NORMAL_DEG,
            plane: false,
        });
        frames.push(Traced {
            right: Arc::new(right),
            right_radiance,
            left: Arc::new(left),
            left_background,
            left_seed: ls,
            trace_ns: cost.cpu_ns,
        });
    }
    let tests = tests.expect("a frame");
    let sampler = PaperSampler::new(world.scene(), world.tracer(), materials);
    let mut states: Vec<MethodState> = methods
        .split(',')
        .map(|m| MethodState::new(Method::named(m).expect("method")))
        .collect();
    let mut best = vec![[u64::MAX; 3]; states.len()];
    for _ in 0..reps {
        let ns = pool.install(|| passes(&sampler, &frames, tests, &mut states));
        for (b, n) in best.iter_mut().zip(&ns) {
            for k in 0..3 {
                b[k] = b[k].min(n[k]);
            }
        }
    }
    let per_frame = |ns: u64| ns as f64 * 1e-6 / nframes as f64;
    let trace = per_frame(frames.iter().map(|f| f.trace_ns).sum());
    println!(
        "{scene} {w}x{h}, {nframes} frames, {threads} thread(s), best of {reps}: trace 1 spp {trace:.3} ms/frame"
    );
    for (s, b) in states.iter().zip(&best) {
        let [st, te, co] = b.map(per_frame);
        println!(
            "{:>6}: stereo {st:.3} ms ({:.4}x)  temporal {te:.3} ms ({:.4}x)  stereo+temporal {co:.3} ms ({:.4}x)",
            s.method.name,
            st / trace,
            te / trace,
            co / trace
        );
    }
}
