//! `parallax bench dof --equal-quality`: the quad-tree against the DDA at **equal quality**
//! (Widmer et al. 2015, §5.2, Table 4's claim that the quad-tree is faster at equal quality).
//!
//! At equal lens rays the two methods do not give equal images: the quad-tree's exact
//! plane intersection is more accurate per lens ray than the DDA's march, and the DDA's
//! step bound saturates below the quad-tree's PSNR (`docs/notes/synth.md`). Equal quality is
//! therefore read on the time axis: both methods render plain lens sampling (`N_sec = 1`) at
//! a sweep of lens rays per pixel `N_pri` (the DDA at one step bound), in the same run and
//! the same interleaved rounds ([`super::dof::run`]: the entries of one `N_pri` back to
//! back, every second round reversed); for each quad-tree row the DDA's CPU time at the
//! quad-tree's PSNR is interpolated on its curve and divided into the quad-tree's time.
//!
//! **Interpolation** ([`time_at_psnr`]): the DDA's rows ordered by `N_pri`; the first two
//! consecutive rows whose PSNRs bracket the target (`p0 <= p <= p1`, `p0 < p1`), linear in
//! `log T` against PSNR (PSNR grows about linearly in `log N_pri`, and `T` about linearly in
//! `N_pri`). Outside the measured range: no value (never extrapolated). Whether each
//! method's PSNR rises strictly with `N_pri` over the sweep is reported
//! ([`strictly_rising`]); on a curve that does not, the first bracketing pair (the cheapest)
//! is taken.
//!
//! **Rounds**: the ratio of the best rounds (each row's fastest round), and one ratio per
//! round from that round's times only (the DDA's curve of the round, the quad-tree's time of
//! the round; PSNR is the same in every round): median and range
//! ([`parallax_core::spread::Spread`]).
//!
//! | parameter | default | meaning |
//! |---|---|---|
//! | `n_pri` | [`DEFAULT_N_PRI`] (2-12) | lens rays per pixel of both sweeps |
//! | `dda_max_steps` | the bench's tuned DDA bound | the DDA's step bound |

use parallax_core::spread::Spread;

use super::dof::{DofEntry, DofRow, EqualQuality};
use crate::method::Method;

/// Lens rays per pixel of the equal-quality sweep (both methods, `N_sec = 1`).
pub const DEFAULT_N_PRI: [u32; 8] = [2, 3, 4, 5, 6, 8, 10, 12];

/// The sweep's entries: per layer count, per `N_pri`, the quad-tree (cascade, no
/// inpainting) and the DDA at `dda_max_steps`, plain lens sampling.
pub fn entries(layers: &[usize], n_pri: &[u32], dda_max_steps: u32) -> Vec<DofEntry> {
    let mut v = Vec::new();
    for &layers in layers {
        for &n in n_pri {
            for (method, steps) in [(Method::QuadTree, 0), (Method::Dda, dda_max_steps)] {
                v.push(DofEntry {
                    method,
                    layers,
                    inpaint: false,
                    dda_max_steps: steps,
                    n_pri: n,
                    n_sec: 1,
                });
            }
        }
    }
    v
}

/// The CPU time at `psnr` on `curve` (`(psnr, ms)` ordered by `N_pri`): `exp` of the
/// linear interpolation of `ln ms` between the first two consecutive points whose PSNRs
/// bracket `psnr` (`p0 <= psnr <= p1`, `p0 < p1`), with the index of the first of them;
/// `None` outside the measured range (no extrapolation) or at a non-finite input.
pub fn time_at_psnr(curve: &[(f64, f64)], psnr: f64) -> Option<(f64, usize)> {
    if !psnr.is_finite() {
        return None;
    }
    for (i, w) in curve.windows(2).enumerate() {
        let ((p0, t0), (p1, t1)) = (w[0], w[1]);
        if !(p0 < p1 && p0 <= psnr && psnr <= p1 && t0 > 0.0 && t1 > 0.0) {
            continue;
        }
        // A measured row's own time where its PSNR is hit exactly.
        let t = if psnr == p0 {
            t0
        } else if psnr == p1 {
            t1
        } else {
            let f = (psnr - p0) / (p1 - p0);
            (t0.ln() + f * (t1.ln() - t0.ln())).exp()
        };
        return Some((t, i));
    }
    None
}

/// PSNR rises strictly along `curve` (`(psnr, ms)` ordered by `N_pri`).
pub fn strictly_rising(curve: &[(f64, f64)]) -> bool {
    curve.windows(2).all(|w| w[0].0 < w[1].0)
}

/// Fills `equal_quality` of every quad-tree row of the sweep in `rows` (module docs): the
/// DDA rows of the same layer count (and `dda_max_steps`, plain sampling) form the curve.
pub fn analyse(rows: &mut [DofRow], dda_max_steps: u32) {
    let ok = |r: &DofRow| r.error.is_none() && r.n_sec == 1 && !r.inpaint;
    let sorted = |method: &str, layers: usize, rows: &[DofRow]| -> Vec<usize> {
        let mut v: Vec<usize> = (0..rows.len())
            .filter(|&i| {
                let r = &rows[i];
                ok(r)
                    && r.method == method
                    && r.layers == layers
                    && (method != "dda" || r.dda_max_steps == Some(dda_max_steps))
            })
            .collect();
        v.sort_by_key(|&i| rows[i].n_pri);
        v
    };
    let mut layer_counts: Vec<usize> = rows.iter().map(|r| r.layers).collect();
    layer_counts.sort_unstable();
    layer_counts.dedup();
    for layers in layer_counts {
        let dda = sorted("dda", layers, rows);
        let qt = sorted("quadtree", layers, rows);
        let curve: Vec<(f64, f64)> = dda
            .iter()
            .map(|&i| (rows[i].psnr, rows[i].ms_dof_cpu))
            .collect();
        let qt_curve: Vec<(f64, f64)> = qt
            .iter()
            .map(|&i| (rows[i].psnr, rows[i].ms_dof_cpu))
            .collect();
        let (dda_rising, qt_rising) = (strictly_rising(&curve), strictly_rising(&qt_curve));
        let n_rounds = dda
            .iter()
            .chain(&qt)
            .map(|&i| rows[i].ms_dof_cpu_rounds.len())
            .min()
            .unwrap_or(0);
        for &q in &qt {
            let psnr = rows[q].psnr;
            let best = time_at_psnr(&curve, psnr);
            let cpu_ratio_rounds: Vec<f64> = (0..n_rounds)
                .map(|k| {
                    let c: Vec<(f64, f64)> = dda
                        .iter()
                        .map(|&i| (rows[i].psnr, rows[i].ms_dof_cpu_rounds[k]))
                        .collect();
                    time_at_psnr(&c, psnr)
                        .map_or(f64::NAN, |(t, _)| rows[q].ms_dof_cpu_rounds[k] / t)
                })
                .collect();
            let ms = best.map_or(f64::NAN, |(t, _)| t);
            rows[q].equal_quality = Some(EqualQuality {
                dda_max_steps,
                dda_n_pri_bracket: best.map(|(_, i)| [rows[dda[i]].n_pri, rows[dda[i + 1]].n_pri]),
                dda_psnr_bracket: best.map(|(_, i)| [rows[dda[i]].psnr, rows[dda[i + 1]].psnr]),
                ms_dda_cpu_at_psnr: ms,
                cpu_ratio: rows[q].ms_dof_cpu / ms,
                cpu_ratio_spread: Spread::of(&cpu_ratio_rounds),
                cpu_ratio_rounds,
                dda_psnr_rising: dda_rising,
                quadtree_psnr_rising: qt_rising,
            });
        }
    }
}

/// The equal-quality table of the analysed `rows` (Markdown), with a line per layer count
/// on whether the PSNR curves rise strictly.
pub fn markdown(rows: &[DofRow]) -> String {
    let mut s = String::from(
        "| layers | quad-tree N_pri | quad-tree PSNR dB / SSIM | quad-tree CPU ms | DDA steps | DDA N_pri bracket (PSNR dB) | DDA CPU ms at the quad-tree's PSNR | CPU ratio quad-tree / DDA (best rounds) | median of per-round ratios | per-round range |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut notes: Vec<String> = Vec::new();
    for r in rows {
        let Some(e) = &r.equal_quality else { continue };
        let bracket = match (e.dda_n_pri_bracket, e.dda_psnr_bracket) {
            (Some([a, b]), Some([pa, pb])) => format!("{a}-{b} ({pa:.2}-{pb:.2})"),
            _ => "outside the DDA's range".into(),
        };
        let f = |v: f64, d: usize| {
            if v.is_nan() {
                "-".to_string()
            } else {
                format!("{v:.d$}")
            }
        };
        s += &format!(
            "| {} | {} | {:.2} / {:.4} | {:.1} | {} | {bracket} | {} | {} | {} | {} |\n",
            r.layers,
            r.n_pri,
            r.psnr,
            r.ssim,
            r.ms_dof_cpu,
            e.dda_max_steps,
            f(e.ms_dda_cpu_at_psnr, 1),
            f(e.cpu_ratio, 3),
            f(e.cpu_ratio_spread.median, 3),
            if e.cpu_ratio_spread.min.is_nan() {
                "-".to_string()
            } else {
                format!(
                    "{:.3}-{:.3}",
                    e.cpu_ratio_spread.min, e.cpu_ratio_spread.max
                )
            },
        );
        let note = format!(
            "{} layer(s): PSNR rises strictly with N_pri over the sweep: DDA {}, quad-tree {}",
            r.layers,
            if e.dda_psnr_rising { "yes" } else { "NO" },
            if e.quadtree_psnr_rising { "yes" } else { "NO" }
        );
        if !notes.contains(&note) {
            notes.push(note);
        }
    }
    for n in notes {
        s += &format!("\n{n}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_log_time_between_the_bracketing_rows() {
        // PSNR 30, 32, 33 dB at 100, 200, 400 ms.
        let c = [(30.0, 100.0), (32.0, 200.0), (33.0, 400.0)];
        // Half-way in PSNR between the first two: the geometric mean of their times.
        let (t, i) = time_at_psnr(&c, 31.0).unwrap();
        assert_eq!(i, 0);
        assert!((t - 200f64.sqrt() * 10.0).abs() < 1e-9, "{t}");
        let (t, i) = time_at_psnr(&c, 32.75).unwrap();
        assert_eq!(i, 1);
        assert!((t - 200.0 * 2f64.powf(0.75)).abs() < 1e-9, "{t}");
        // The measured ends are in range, beyond them nothing.
        assert_eq!(time_at_psnr(&c, 30.0), Some((100.0, 0)));
        assert_eq!(time_at_psnr(&c, 33.0), Some((400.0, 1)));
        assert_eq!(time_at_psnr(&c, 29.99), None);
        assert_eq!(time_at_psnr(&c, 33.01), None);
        assert_eq!(time_at_psnr(&c, f64::NAN), None);
        assert_eq!(time_at_psnr(&c[..1], 30.0), None);
        assert!(strictly_rising(&c));
        // A dip: the first bracketing pair is taken, and the curve is flagged.
        let d = [(30.0, 100.0), (32.0, 200.0), (31.0, 300.0), (34.0, 400.0)];
        assert!(!strictly_rising(&d));
        assert_eq!(time_at_psnr(&d, 31.5).unwrap().1, 0);
        // A flat pair brackets nothing; the next pair does.
        let e = [(30.0, 100.0), (30.0, 200.0), (32.0, 400.0)];
        assert_eq!(time_at_psnr(&e, 30.0).unwrap(), (200.0, 1));
    }

    fn row(method: &str, n_pri: u32, psnr: f64, rounds: &[f64]) -> DofRow {
        DofRow {
            method: method.into(),
            layers: 1,
            n_pri,
            n_sec: 1,
            dda_max_steps: (method == "dda").then_some(32),
            psnr,
            ms_dof_cpu: rounds.iter().copied().fold(f64::INFINITY, f64::min),
            ms_dof_cpu_rounds: rounds.to_vec(),
            ..DofRow::default()
        }
    }

    #[test]
    fn analyse_reads_the_dda_curve_at_the_quadtree_psnr() {
        let mut rows = vec![
            row("quadtree", 2, 31.0, &[90.0, 80.0]),
            row("dda", 2, 30.0, &[100.0, 110.0]),
            row("quadtree", 4, 33.5, &[160.0, 150.0]),
            row("dda", 4, 32.0, &[200.0, 180.0]),
            row("dda", 8, 33.0, &[400.0, 420.0]),
            // Another step bound: not on the curve.
            DofRow {
                dda_max_steps: Some(8),
                ..row("dda", 3, 31.0, &[1.0, 1.0])
            },
        ];
        analyse(&mut rows, 32);
        let e = rows[0].equal_quality.as_ref().unwrap();
        assert_eq!(e.dda_n_pri_bracket, Some([2, 4]));
        // Best rounds: DDA 100 and 180 ms, half-way: sqrt(100 * 180).
        assert!((e.ms_dda_cpu_at_psnr - 18000f64.sqrt()).abs() < 1e-9);
        assert!((e.cpu_ratio - 80.0 / 18000f64.sqrt()).abs() < 1e-12);
        let r0 = 90.0 / 20000f64.sqrt();
        let r1 = 80.0 / (110.0f64 * 180.0).sqrt();
        assert!((e.cpu_ratio_rounds[0] - r0).abs() < 1e-12);
        assert!((e.cpu_ratio_rounds[1] - r1).abs() < 1e-12);
        assert!((e.cpu_ratio_spread.min - r0.min(r1)).abs() < 1e-12);
        assert!(e.dda_psnr_rising && e.quadtree_psnr_rising);
        // Above the DDA's best PSNR: no value, no extrapolation.
        let e = rows[2].equal_quality.as_ref().unwrap();
        assert_eq!(e.dda_n_pri_bracket, None);
        assert!(e.cpu_ratio.is_nan() && e.cpu_ratio_rounds.iter().all(|r| r.is_nan()));
        assert!(rows[1].equal_quality.is_none());
        assert!(markdown(&rows).contains("outside the DDA's range"));
    }
}
