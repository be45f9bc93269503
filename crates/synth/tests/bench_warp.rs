//! `bench warp`'s interleaved rounds (`parallax_synth::bench::warp`): every method measured
//! round-robin gives the rows, in order, and the images, stats and scores of measuring each
//! method alone; only the times differ.

use parallax_bvh::Bvh;
use parallax_scene::Scene;
use parallax_synth::bench::warp::{
    StereoSetup, WarpRow, eye_truths, measure, measure_interleaved, reference, run,
};
use parallax_synth::method::{Method, MethodOptions, Synthesizer};
use parallax_synth::stereo::stereo_eyes;
use parallax_synth::{CubeNear, Shading};

mod bench_util;

fn setup(scene: &Scene) -> StereoSetup {
    StereoSetup {
        desc: scene.camera(None).unwrap(),
        width: 64,
        height: 48,
        ipd: 0.26,
        shading: Shading::Fixed,
        seed: 0,
        score: true,
        repeats: 2,
    }
}

/// Everything of a row but the times: bit-exact for tracers (NaN equals NaN); the mesh warp
/// (rasterized in parallel, ulp-level run-to-run differences) and PSNR / SSIM (a parallel f64
/// sum, whose order varies from run to run) to 9 significant digits.
fn results(r: &WarpRow) -> String {
    let f = |v: f64| {
        if r.method == "mesh" {
            format!("{v:.8e}")
        } else {
            v.to_bits().to_string()
        }
    };
    let score = |v: f64| format!("{v:.8e}");
    format!(
        "{} {} {:?} {:?} {} {} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
        r.method,
        r.layers,
        r.dda_max_steps,
        r.error,
        r.cube_near,
        r.repeats,
        r.near_m.to_bits(),
        r.far_m.to_bits(),
        f(r.nodes_per_ray),
        f(r.tests_per_ray),
        f(r.pct_layer2),
        f(r.pct_miss),
        f(r.pct_occlusion),
        f(r.pct_truncated),
        score(r.psnr),
        score(r.ssim),
    )
}

#[test]
fn interleaved_rounds_equal_each_method_alone() {
    let scene = Scene::load("atrium").unwrap();
    let bvh = Bvh::try_build(&scene.mesh).unwrap();
    let s = setup(&scene);
    let truths = eye_truths(&scene, &bvh, &s).unwrap();
    let r = reference(&scene, &bvh, &s, 2).unwrap();
    let near = MethodOptions {
        cube_near: CubeNear::Camera(0.1),
        ..MethodOptions::default()
    };
    let dda = |steps| MethodOptions {
        dda_max_steps: steps,
        ..near
    };
    let entries = [
        (Method::MinMax, near),
        (Method::Dda, dda(4)),
        (Method::Brute, near),
        (Method::Dda, dda(300)),
        (Method::Mesh, near),
    ];
    let together = measure_interleaved(&scene.name, &r, &s, &entries, Some(&truths), &|_| {});
    assert_eq!(together.len(), entries.len());
    let eyes = stereo_eyes(&s.desc, 64, 48, s.ipd).unwrap();
    let mut fitted = r.clone();
    fitted.fit_cube(near.cube_near).unwrap();
    for ((m, o), (row, views)) in entries.iter().zip(&together) {
        let (alone, alone_views) = measure(&scene.name, &r, &s, *m, o, Some(&truths));
        assert_eq!(row.method, m.name());
        assert!(row.error.is_none(), "{row:?}");
        assert_eq!(results(row), results(&alone), "{m}");
        assert!(row.psnr > 10.0 || row.dda_max_steps == Some(4), "{row:?}");
        let (v, va) = (views.as_ref().unwrap(), alone_views.as_ref().unwrap());
        // The views equal those of the method built and run directly.
        let direct = Synthesizer::build(*m, &fitted, o).unwrap();
        for (k, eye) in eyes.iter().enumerate() {
            let d = direct.view(&fitted, eye).unwrap();
            for w in [&v.views[k], &va.views[k]] {
                if *m == Method::Mesh {
                    let diff = w.image.data().iter().zip(d.image.data());
                    let max = diff
                        .map(|(a, b)| (*a - *b).abs().max_element())
                        .fold(0.0, f32::max);
                    assert!(max < 1e-4, "mesh eye {k}: {max}");
                    continue;
                }
                assert_eq!(w.image.data(), d.image.data(), "{m} eye {k}");
                assert_eq!(w.kinds, d.kinds);
                assert_eq!(w.work, d.work);
                assert_eq!(w.stats, d.stats);
            }
        }
        // Times: best of the rounds, finite; trace-only columns for tracers only.
        assert!(row.ms_view > 0.0 && row.ms_view.is_finite(), "{row:?}");
        // CPU time is measured where the platform has it (no wall-clock bound: a loaded
        // machine may deschedule the process for any time).
        assert!(
            row.ms_view_cpu.is_nan() || (row.ms_view_cpu >= 0.0 && row.ms_view_cpu.is_finite()),
            "{row:?}"
        );
        if m.is_tracer() {
            assert!(row.ms_trace > 0.0 && row.ms_trace.is_finite(), "{row:?}");
            assert!(row.trace_mrays_per_s > 0.0 && row.trace_cpu_mrays_per_s > 0.0);
        } else {
            assert!(row.ms_trace.is_nan() && row.ms_raygen.is_nan());
        }
    }
    // Ray generation is shared by every tracer of the rounds (identical rays).
    let gens: Vec<u64> = together
        .iter()
        .filter(|(row, _)| row.method != "mesh")
        .map(|(row, _)| row.ms_raygen.to_bits())
        .collect();
    assert!(gens.windows(2).all(|g| g[0] == g[1]), "{gens:?}");
    // Four steps from a 0.1 m near plane do not reach the surfaces, 300 do: the DDA rows
    // are not mixed up.
    let lost = |k: usize| together[k].0.pct_miss + together[k].0.pct_occlusion;
    assert!(lost(1) > lost(3) + 1.0, "{} vs {}", lost(1), lost(3));
    // The rays the 4-step DDA lost are the ones it reports as truncated; 300 steps and the
    // hierarchies (whose bounds are safety bounds) truncate none.
    let truncated: Vec<f64> = together.iter().map(|(row, _)| row.pct_truncated).collect();
    assert!(truncated[1] > 50.0, "{truncated:?}");
    assert!(
        together
            .iter()
            .enumerate()
            .all(|(k, (row, _))| k == 1 || row.pct_truncated == 0.0),
        "{truncated:?}"
    );
}

#[test]
fn run_rows_in_order_with_errors_and_sweep() {
    let scene = Scene::load("atrium").unwrap();
    let bvh = Bvh::try_build(&scene.mesh).unwrap();
    let s = StereoSetup {
        score: false,
        ..setup(&scene)
    };
    let methods = bench_util::SWEEP_METHODS;
    let rows = run(
        &scene,
        &bvh,
        &s,
        &methods,
        &[1, 2],
        &MethodOptions::default(),
        &[3, 40],
        &|_| {},
    )
    .unwrap();
    bench_util::assert_sweep_order(
        rows.iter()
            .map(|r| (r.method.as_str(), r.layers, r.dda_max_steps)),
        [3, 40],
    );
    // Each row's results are those of measuring the method alone on its reference.
    for n in [1, 2] {
        let r = reference(&scene, &bvh, &s, n).unwrap();
        for row in rows.iter().filter(|row| row.layers == n) {
            let m: Method = row.method.parse().unwrap();
            let o = MethodOptions {
                dda_max_steps: row
                    .dda_max_steps
                    .unwrap_or(MethodOptions::default().dda_max_steps),
                ..MethodOptions::default()
            };
            let (alone, _) = measure(&scene.name, &r, &s, m, &o, None);
            assert_eq!(results(row), results(&alone), "{m} {n}");
            assert!(row.psnr.is_nan() && row.error.is_none());
        }
    }
}

#[test]
fn build_errors_become_error_rows_and_others_still_run() {
    let scene = Scene::load("atrium").unwrap();
    let bvh = Bvh::try_build(&scene.mesh).unwrap();
    let s = StereoSetup {
        score: false,
        repeats: 1,
        ..setup(&scene)
    };
    let r = reference(&scene, &bvh, &s, 1).unwrap();
    // A negative camera near plane is rejected when the cube is fitted.
    let bad = MethodOptions {
        cube_near: CubeNear::Camera(-1.0),
        ..MethodOptions::default()
    };
    let rows = measure_interleaved(
        &scene.name,
        &r,
        &s,
        &[
            (Method::Dda, bad),
            (Method::Brute, MethodOptions::default()),
        ],
        None,
        &|_| {},
    );
    let (alone, _) = measure(&scene.name, &r, &s, Method::Dda, &bad, None);
    assert_eq!(results(&rows[0].0), results(&alone));
    assert!(
        rows[0].0.error.is_some() && rows[0].1.is_none(),
        "{:?}",
        rows[0].0
    );
    assert!(
        rows[1].0.error.is_none() && rows[1].1.is_some(),
        "{:?}",
        rows[1].0
    );
    assert!(rows[1].0.ms_trace > 0.0);
}
