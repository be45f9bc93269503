//! `bench upsample`'s interleaved methods (`parallax_synth::bench::upsample`): rows in order,
//! each with the numbers (not the times) of running the method alone over the path.

use parallax_bvh::Bvh;
use parallax_scene::Scene;
use parallax_synth::Shading;
use parallax_synth::bench::upsample::{UpsampleRow, UpsampleSetup, measure, run};
use parallax_synth::method::{Method, MethodOptions};
use parallax_synth::upsample::scene_path;

mod bench_util;

/// Everything of a row but the times: bit-exact for tracers; the mesh warp (rasterized
/// in parallel, ulp-level run-to-run differences) and PSNR / SSIM (a parallel f64 sum, whose
/// order varies from run to run) to 9 significant digits.
fn results(r: &UpsampleRow) -> String {
    let nums = [
        r.near_m as f64,
        r.far_m as f64,
        r.nodes_per_ray,
        r.pct_layer2,
        r.pct_miss,
        r.pct_occlusion,
        r.psnr,
        r.ssim,
    ];
    let nums: Vec<String> = if r.method == "mesh" {
        nums.iter().map(|v| format!("{v:.8e}")).collect()
    } else {
        let (exact, score) = nums.split_at(6);
        let exact = exact.iter().map(|v| v.to_bits().to_string());
        exact
            .chain(score.iter().map(|v| format!("{v:.8e}")))
            .collect()
    };
    format!(
        "{} {} {:?} {:?} {} {} {:?}",
        r.method, r.layers, r.dda_max_steps, r.error, r.cube_near, r.frames, nums,
    )
}

#[test]
fn interleaved_rows_equal_each_method_alone() {
    let scene = Scene::load("atrium").unwrap();
    let bvh = Bvh::try_build(&scene.mesh).unwrap();
    let path = scene_path(&scene).unwrap();
    let setup = UpsampleSetup {
        width: 64,
        height: 48,
        frames: 6,
        shading: Shading::Fixed,
        seed: 0,
        score: true,
    };
    let methods = bench_util::SWEEP_METHODS;
    let opts = MethodOptions::default();
    let rows = run(
        &scene,
        &bvh,
        &path,
        &setup,
        &methods,
        &[1, 2],
        &opts,
        &[2, 300],
        &|_| {},
    )
    .unwrap();
    bench_util::assert_sweep_order(
        rows.iter()
            .map(|r| (r.method.as_str(), r.layers, r.dda_max_steps)),
        [2, 300],
    );
    for row in &rows {
        let m: Method = row.method.parse().unwrap();
        let o = MethodOptions {
            dda_max_steps: row.dda_max_steps.unwrap_or(opts.dda_max_steps),
            ..opts
        };
        let alone = measure(&scene, &bvh, &path, &setup, m, row.layers, &o, &|_| {});
        assert_eq!(results(row), results(&alone), "{m} {}", row.layers);
        assert!(
            row.error.is_none() && row.ms_view > 0.0 && row.ms_ref > 0.0,
            "{row:?}"
        );
        assert!(row.psnr > 10.0 || row.dda_max_steps == Some(2), "{row:?}");
    }
    // The DDA rows are not mixed up: two steps lose more pixels than 300.
    let lost = |k: usize| rows[k].pct_miss + rows[k].pct_occlusion;
    assert!(lost(2) > lost(3) + 1.0, "{} {}", lost(2), lost(3));
}
