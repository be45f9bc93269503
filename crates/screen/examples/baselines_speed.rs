//! Speed and quality of the screen-space baselines (Widmer et al. 2015, Table 2 setting):
//! atrium at 1600x900, 2 captured layers, the rays of a stereo eye (the reference pinhole moved
//! 0.0325 m along its right axis, one ray per pixel centre). Per tracer: Mrays/s (best of 3,
//! all threads), steps per ray, and hit agreement with the BVH (fraction of the eye's BVH hits
//! that the tracer hits within one pixel footprint of the true hit); the DDA over a range of
//! `max_steps` to find the smallest artifact-free value (where agreement stops improving), as
//! Widmer tuned it; build times and bytes.
//!
//! `CARGO_TARGET_DIR=/work/target-h2 cargo run --release -p parallax-screen --example baselines_speed [scene] [WxH]`

use std::time::Instant;

use glam::{Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_core::Ray;
use parallax_raster::{RasterOptions, View, capture_layers};
use parallax_scene::{Scene, camera::Pinhole};
use parallax_screen::{
    BruteForcePlanes, DdaOptions, DdaTracer, HiZOptions, HiZTracer, MinMaxOptions, MinMaxTracer,
    NormalSource, ScreenTracer, TraceResult, TraceStats, UnitCube,
};
use rayon::prelude::*;

struct Bench {
    rays: Vec<Ray>,
    /// True hit position and its pixel footprint, per ray (None: BVH miss).
    truth: Vec<Option<(Vec3, f32)>>,
}

/// Process CPU time (user + system) in seconds, from /proc/self/stat (clock ticks of 10 ms):
/// on a machine shared with other jobs wall time says little, CPU time per ray is stable.
fn cpu_seconds() -> f64 {
    let s = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = s.rsplit_once(')').map_or("", |r| r.1);
    let f: Vec<&str> = rest.split_whitespace().collect();
    let tick = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    // Fields 14 and 15 of the whole line are 12 and 13 after the ')'.
    (tick(11) + tick(12)) / 100.0
}

/// (Mrays/s best of `reps` wall clock, Mrays per CPU second (mean over reps), stats of one
/// pass, agreement fraction).
fn run(b: &Bench, tr: &dyn ScreenTracer, reps: usize) -> (f64, f64, TraceStats, f64) {
    let mut best = f64::INFINITY;
    let cpu0 = cpu_seconds();
    let mut out = Vec::new();
    let mut stats = TraceStats::default();
    for _ in 0..reps {
        let t = Instant::now();
        let res: Vec<(Vec<TraceResult>, TraceStats)> = b
            .rays
            .par_chunks(1600)
            .map(|chunk| {
                let mut st = TraceStats::default();
                let r = chunk.iter().map(|ray| tr.trace(ray, &mut st)).collect();
                (r, st)
            })
            .collect();
        best = best.min(t.elapsed().as_secs_f64());
        stats = TraceStats::default();
        out.clear();
        for (r, st) in res {
            stats += st;
            out.extend(r);
        }
    }
    let cpu = (cpu_seconds() - cpu0) / reps as f64;
    let (mut agree, mut total) = (0u64, 0u64);
    for (r, t) in out.iter().zip(&b.truth) {
        if let Some((p, fp)) = t {
            total += 1;
            if let TraceResult::Hit { position, .. } = r
                && (*position - *p).length() <= *fp
            {
                agree += 1;
            }
        }
    }
    (
        b.rays.len() as f64 / best / 1e6,
        b.rays.len() as f64 / cpu / 1e6,
        stats,
        agree as f64 / total as f64,
    )
}

fn row(name: &str, b: &Bench, tr: &dyn ScreenTracer, reps: usize) -> f64 {
    let (mrays, cpu_mrays, st, agree) = run(b, tr, reps);
    let n = st.rays as f64;
    println!(
        "| {name} | {mrays:.1} | {cpu_mrays:.1} | {:.1} | {:.1} | {:.4} | {:.3} | {:.4} |",
        st.steps as f64 / n,
        st.plane_tests as f64 / n,
        agree,
        st.hits as f64 / n,
        st.occlusion_volumes as f64 / n,
    );
    agree
}

/// The rays of an eye moved `shift` m along the reference's right axis, with BVH truth.
fn bench(cam: &Pinhole, bvh: &Bvh, shift: f32) -> Bench {
    let (w, h) = (cam.width, cam.height);
    let eye = cam.frame.position + cam.frame.right() * shift;
    let rays: Vec<Ray> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            Ray::new(
                eye,
                cam.frame.dir_to_world(cam.camera_dir(film)).normalize(),
            )
        })
        .collect();
    let truth: Vec<Option<(Vec3, f32)>> = rays
        .par_iter()
        .map(|r| {
            bvh.closest_hit(r).map(|hit| {
                let p = r.at(hit.t);
                let depth = -cam.frame.to_camera(p).z;
                (p, 2.0 * cam.tan_half_y * depth / h as f32)
            })
        })
        .collect();
    Bench { rays, truth }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene_name = args.get(1).map_or("atrium", |s| s.as_str());
    let (w, h) = args
        .get(2)
        .and_then(|s| s.split_once('x'))
        .map_or((1600, 900), |(a, b)| {
            (a.parse().unwrap(), b.parse().unwrap())
        });
    let scene = Scene::load(scene_name).expect("scene");
    let cam = Pinhole::new(&scene.camera(None).unwrap(), w, h).unwrap();
    let view = View::from_pinhole(&cam).unwrap();
    let t = Instant::now();
    let cap = capture_layers(&scene, &view, &RasterOptions::layers(2)).unwrap();
    let cap_ms = t.elapsed().as_secs_f64() * 1e3;
    let layers = &cap.layers.layers;
    let cube = UnitCube::fit_depths(&cam, layers.iter().map(|g| &g.depth[..])).unwrap();
    let bvh = Bvh::build(&scene.mesh);
    let b = bench(&cam, &bvh, 0.0325);
    println!(
        "{scene_name} {w}x{h}, 2 layers (capture {cap_ms:.0} ms), cube near {:.3} far {:.2}, {} threads, stereo eye 0.0325 m",
        cube.near,
        cube.far,
        rayon::current_num_threads()
    );
    println!(
        "\n| tracer | Mrays/s (wall, best) | Mrays per CPU-s | steps/ray | plane tests/ray | agree (1 footprint) | hits/ray | occl/ray |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    // DDA max_steps sweep (1 and 2 layers).
    for nl in [1usize, 2] {
        let mut prev = -1.0;
        let mut chosen = None;
        for ms in [4u32, 8, 16, 32, 64, 128, 200, 500] {
            let opts = DdaOptions {
                layers: nl,
                max_steps: ms,
                ..Default::default()
            };
            let tr = DdaTracer::new(&cube, layers, &opts).unwrap();
            let a = row(&format!("DDA {nl} layer(s), max_steps {ms}"), &b, &tr, 3);
            if chosen.is_none() && a - prev < 1e-4 && prev >= 0.0 {
                chosen = Some(ms);
            }
            prev = a;
        }
        println!(
            "| (DDA {nl}: agreement stops improving at max_steps ~{chosen:?}) | | | | | | | |"
        );
    }
    for (name, opts) in [
        ("MinMax bilinear, 2 layers", MinMaxOptions::default()),
        (
            "MinMax flat, 2 layers",
            MinMaxOptions {
                bilinear: false,
                ..Default::default()
            },
        ),
        (
            "MinMax bilinear, 1 layer",
            MinMaxOptions {
                layers: 1,
                ..Default::default()
            },
        ),
    ] {
        let tr = MinMaxTracer::new(&cube, layers, &opts).unwrap();
        row(name, &b, &tr, 3);
        println!(
            "| (build ms per layer {:?}, {} bytes) | | | | | | | |",
            tr.build_ms()
                .iter()
                .map(|v| format!("{v:.1}"))
                .collect::<Vec<_>>(),
            tr.bytes()
        );
    }
    for (name, opts) in [
        ("HiZ, 2 layers", HiZOptions::default()),
        (
            "HiZ, 1 layer",
            HiZOptions {
                layers: 1,
                ..Default::default()
            },
        ),
    ] {
        let tr = HiZTracer::new(&cube, layers, &opts).unwrap();
        row(name, &b, &tr, 3);
        println!(
            "| (build ms per layer {:?}, {} bytes) | | | | | | | |",
            tr.build_ms()
                .iter()
                .map(|v| format!("{v:.1}"))
                .collect::<Vec<_>>(),
            tr.bytes()
        );
    }
    // z_thickness sweep (DDA, 1 layer): too thin misses surfaces between samples, too thick
    // makes rays hit behind thin objects.
    for th in [0.01f32, 0.03, 0.1, 0.3, 1.0] {
        let opts = DdaOptions {
            layers: 1,
            z_thickness: th,
            ..Default::default()
        };
        let tr = DdaTracer::new(&cube, layers, &opts).unwrap();
        row(&format!("DDA 1 layer, z_thickness {th}"), &b, &tr, 1);
    }
    let brute = BruteForcePlanes::new(cube.clone(), &cap, NormalSource::GBuffer).unwrap();
    row("BruteForcePlanes (reference)", &b, &brute, 1);
    row(
        "BVH closest hit (exact, for scale)",
        &b,
        &BvhTracer(&bvh),
        1,
    );

    // A large reprojection: 0.3 m to the right (disocclusions; the second layer matters).
    let b = bench(&cam, &bvh, 0.3);
    println!("\n0.3 m shift\n");
    println!(
        "| tracer | Mrays/s (wall, best) | Mrays per CPU-s | steps/ray | plane tests/ray | agree (1 footprint) | hits/ray | occl/ray |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let dda = |n| DdaOptions {
        layers: n,
        ..Default::default()
    };
    let mm = |n| MinMaxOptions {
        layers: n,
        ..Default::default()
    };
    let hz = |n| HiZOptions {
        layers: n,
        ..Default::default()
    };
    let tracers: Vec<(&str, Box<dyn ScreenTracer>)> = vec![
        (
            "DDA 1 layer",
            Box::new(DdaTracer::new(&cube, layers, &dda(1)).unwrap()),
        ),
        (
            "DDA 2 layers",
            Box::new(DdaTracer::new(&cube, layers, &dda(2)).unwrap()),
        ),
        (
            "MinMax bilinear, 1 layer",
            Box::new(MinMaxTracer::new(&cube, layers, &mm(1)).unwrap()),
        ),
        (
            "MinMax bilinear, 2 layers",
            Box::new(MinMaxTracer::new(&cube, layers, &mm(2)).unwrap()),
        ),
        (
            "HiZ, 1 layer",
            Box::new(HiZTracer::new(&cube, layers, &hz(1)).unwrap()),
        ),
        (
            "HiZ, 2 layers",
            Box::new(HiZTracer::new(&cube, layers, &hz(2)).unwrap()),
        ),
        ("BruteForcePlanes (reference)", Box::new(brute)),
    ];
    for (name, tr) in &tracers {
        row(name, &b, tr.as_ref(), 1);
    }
}

/// The exact BVH behind the tracer interface, to put the numbers in scale.
struct BvhTracer<'a>(&'a Bvh);

impl ScreenTracer for BvhTracer<'_> {
    fn trace(&self, ray: &Ray, stats: &mut TraceStats) -> TraceResult {
        stats.rays += 1;
        match self.0.closest_hit(ray) {
            Some(h) => {
                stats.hits += 1;
                TraceResult::Hit {
                    layer: 0,
                    pixel: glam::UVec2::ZERO,
                    position: ray.at(h.t),
                    t: h.t,
                }
            }
            None => TraceResult::Miss,
        }
    }
}
