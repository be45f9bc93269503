//! End-to-end run of `parallax bench dof --equal-quality` at a tiny size: the sweep's rows
//! in the JSON and the DDA's time at each quad-tree row's PSNR read from the bracketing DDA
//! rows (log time linear in PSNR), never extrapolated.

mod common;

use common::{parallax, stderr};

#[test]
fn bench_dof_equal_quality_interpolates_the_dda_curve() {
    let d = common::out_dir("dof", "equal");
    let j = d.join("dof.json");
    let n_pri = [1u64, 2, 4, 8, 16];
    let o = parallax(&[
        "--threads",
        "2",
        "bench",
        "dof",
        "--scene",
        "atrium",
        "--width",
        "96",
        "--height",
        "54",
        "--aperture",
        "0.05",
        "--truth-spp",
        "16",
        "--dda-sweep",
        "32",
        "--repeats",
        "2",
        "--layers",
        "1",
        "--equal-quality",
        "--equal-quality-n-pri",
        "1,2,4,8,16",
        "--json",
        j.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("at equal quality"), "{out}");
    let rows: serde_json::Value = serde_json::from_slice(&std::fs::read(&j).unwrap()).unwrap();
    let rows = rows.as_array().unwrap();
    // Both methods at every N_pri, plain lens sampling, nothing else.
    assert_eq!(rows.len(), 2 * n_pri.len());
    let row = |method: &str, n: u64| {
        rows.iter()
            .find(|r| r["method"] == method && r["n_pri"] == n)
            .unwrap_or_else(|| panic!("no {method} {n} row"))
    };
    let mut bracketed = 0;
    for &n in &n_pri {
        let q = row("quadtree", n);
        assert_eq!(q["n_sec"], 1);
        assert_eq!(q["ms_dof_cpu_rounds"].as_array().unwrap().len(), 2);
        let e = &q["equal_quality"];
        assert_eq!(e["dda_max_steps"], 32, "{q}");
        assert!(row("dda", n).get("equal_quality").is_none());
        let psnr = q["psnr"].as_f64().unwrap();
        let Some(b) = e["dda_n_pri_bracket"].as_array() else {
            // Outside the DDA's range: no time, no ratio.
            assert!(
                e["ms_dda_cpu_at_psnr"].is_null() && e["cpu_ratio"].is_null(),
                "{e}"
            );
            continue;
        };
        bracketed += 1;
        let (a, b) = (
            row("dda", b[0].as_u64().unwrap()),
            row("dda", b[1].as_u64().unwrap()),
        );
        let (pa, pb) = (a["psnr"].as_f64().unwrap(), b["psnr"].as_f64().unwrap());
        assert!(pa <= psnr && psnr <= pb, "{pa} {psnr} {pb}");
        // ln T linear in PSNR between the bracketing rows' best rounds.
        let (ta, tb) = (
            a["ms_dof_cpu"].as_f64().unwrap(),
            b["ms_dof_cpu"].as_f64().unwrap(),
        );
        let f = (psnr - pa) / (pb - pa);
        let want = (ta.ln() + f * (tb.ln() - ta.ln())).exp();
        let got = e["ms_dda_cpu_at_psnr"].as_f64().unwrap();
        assert!((got - want).abs() <= 1e-9 * want, "{got} {want}");
        let ratio = e["cpu_ratio"].as_f64().unwrap();
        assert!((ratio - q["ms_dof_cpu"].as_f64().unwrap() / want).abs() < 1e-9);
        let rounds = e["cpu_ratio_rounds"].as_array().unwrap();
        assert_eq!(rounds.len(), 2);
        let spread = &e["cpu_ratio_spread"];
        let (lo, hi) = (
            spread["min"].as_f64().unwrap(),
            spread["max"].as_f64().unwrap(),
        );
        for r in rounds {
            let r = r.as_f64().unwrap();
            assert!(r > 0.0 && lo <= r && r <= hi, "{e}");
        }
    }
    // On this view the DDA's PSNR rises from below the quad-tree's 1-ray PSNR to above its
    // 16-ray PSNR (measured: all five rows bracketed).
    assert!(
        bracketed >= 1,
        "no quad-tree row inside the DDA's range: {out}"
    );
}
