//! The demo's depth of field (Widmer et al. 2015, §5.2) and light-field quilt (§5.3): each runs
//! as the typed `parallax dof` / `parallax lightfield` command line, parsed and dispatched as
//! `parallax run` does, into `OUT/synth/`; the images are then copied into the demo folder
//! under demo names (the method's image beside its BVH ground truth).

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, anyhow};

use super::run::Shell;
use crate::demo_piece::{DemoPiece, section};

/// One demo piece: a command line and the images it leaves.
struct Piece {
    label: &'static str,
    title: &'static str,
    what: String,
    size: String,
    args: Vec<String>,
    /// (file written by the command, name in the demo folder)
    copies: Vec<(String, &'static str)>,
}

/// Runs the depth-of-field and quilt pieces on `scene` at about `w x h` per image.
pub fn synth_views(
    scene: &str,
    w: u32,
    h: u32,
    out: &Path,
    shell: &Shell,
) -> Result<Vec<DemoPiece>> {
    let work = out.join("synth");
    let (w, h) = (w.max(8), h.max(8));
    let (vw, vh) = ((w / 2).max(4), (h / 2).max(4));
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    let pieces = [
        Piece {
            label: "dof_quadtree",
            title: "Depth of field (§5.2)",
            what: "thin-lens rays traced through a 2-layer quad-tree of one pinhole capture, 8 lens rays x 4 secondary samples per pixel, vs the BVH thin lens".into(),
            size: format!("{w}x{h}"),
            args: s(&[
                "dof", "--scene", scene, "--width", &w.to_string(), "--height", &h.to_string(),
                "--layers", "2", "--method", "quadtree", "--n-pri", "8", "--n-sec", "4",
                "--truth-spp", "16",
            ]),
            copies: vec![("dof.png".into(), "dof_quadtree.png"), ("dof.bvh.png".into(), "dof_bvh.png")],
        },
        Piece {
            label: "quilt",
            title: "Light field: a Looking Glass quilt (§5.3)",
            what: "4x2 views over a 35 deg cone, view 0 bottom left, 2 x 2 rays per pixel (box-filtered) traced through one 2-layer reference capture, vs the BVH's views through the same rays".into(),
            size: format!("8x {vw}x{vh}"),
            args: s(&[
                "lightfield", "--kind", "quilt", "--scene", scene, "--cols", "4", "--rows", "2",
                "--view-width", &vw.to_string(), "--view-height", &vh.to_string(),
                "--layers", "2", "--spp", "4", "--name", "quilt", "--json",
                &work.join("quilt").join("rows.json").display().to_string(),
            ]),
            copies: Vec::new(),
        },
    ];
    let mut done = Vec::new();
    for p in pieces {
        let dir = work.join(p.label);
        let mut argv = vec!["parallax".to_string()];
        argv.extend(p.args);
        argv.extend(["--out".to_string(), dir.display().to_string()]);
        let job = (shell.parse)(&argv).map_err(|e| anyhow!("demo {}: {e}", p.label))?;
        let t = Instant::now();
        job(true).with_context(|| format!("demo {}", p.label))?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let (copies, what) = if p.copies.is_empty() {
            let (near, far) = quilt_psnr(&dir.join("rows.json"))?;
            (
                quilt_copies(&dir)?,
                format!(
                    "{}; PSNR vs the BVH view: {near:.1} dB for the 2 views nearest the reference, {far:.1} dB for the outermost",
                    p.what
                ),
            )
        } else {
            (p.copies, p.what)
        };
        for (from, to) in &copies {
            let dst = out.join(to);
            std::fs::copy(dir.join(from), &dst)
                .with_context(|| format!("copying {} to {}", from, dst.display()))?;
        }
        done.push(DemoPiece {
            label: p.label.into(),
            section: section::WIDMER,
            title: p.title.into(),
            what,
            size: p.size,
            spp: "-".into(),
            mrays: None,
            ms,
            images: vec![copies[0].1.to_string()],
            truth: copies.get(1).map(|c| c.1.to_string()),
        });
    }
    Ok(done)
}

/// The quilt and its BVH twin (their names carry the `_qs{cols}x{rows}a{aspect}` suffix).
fn quilt_copies(dir: &Path) -> Result<Vec<(String, &'static str)>> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
        .filter(|n| n.starts_with("quilt") && n.ends_with(".png"))
        .collect();
    names.sort();
    let method = names.iter().find(|n| !n.contains(".bvh"));
    let truth = names.iter().find(|n| n.contains(".bvh"));
    match (method, truth) {
        (Some(m), Some(t)) => Ok(vec![(m.clone(), "quilt.png"), (t.clone(), "quilt_bvh.png")]),
        _ => Err(anyhow!(
            "the quilt command left no quilt in {}",
            dir.display()
        )),
    }
}

/// Mean PSNR of the two views nearest the reference, and of the outermost two, from the
/// quilt command's JSON rows.
fn quilt_psnr(rows: &Path) -> Result<(f64, f64)> {
    let text =
        std::fs::read_to_string(rows).with_context(|| format!("reading {}", rows.display()))?;
    let v: serde_json::Value = serde_json::from_str(&text)?;
    let mut views: Vec<(f64, f64)> = v
        .as_array()
        .ok_or_else(|| anyhow!("{}: not a list of rows", rows.display()))?
        .iter()
        .filter_map(|r| Some((r["offset_m"].as_f64()?.abs(), r["psnr"].as_f64()?)))
        .collect();
    anyhow::ensure!(views.len() >= 2, "{}: fewer than 2 views", rows.display());
    views.sort_by(|a, b| a.0.total_cmp(&b.0));
    let n = views.len();
    Ok((
        (views[0].1 + views[1].1) / 2.0,
        (views[n - 1].1 + views[n - 2].1) / 2.0,
    ))
}
