//! `parallax report RESULTS_DIR...`: the HTML page of `parallax run` results
//! (`parallax_experiment::report`): images beside their ground truth with a wipe slider and
//! error heatmaps, the rows as a sortable table, and plots. A folder without `results.json`
//! (e.g. `out/demo`, `out/warp`) gets the gallery of its PNGs.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// Results folders of `parallax run` (each with results.json), or one folder of images.
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// The page (default: DIR/index.html for one folder; required for several).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Inline every image as base64 (one file to send around).
    #[arg(long)]
    pub inline: bool,
}

pub fn run(a: &ReportArgs, quiet: bool) -> Result<()> {
    use parallax_experiment::report;
    let page = match a.dirs.as_slice() {
        [d] if !d.join(parallax_experiment::results::RESULTS_FILE).exists() && a.out.is_none() => {
            let title = format!("parallax: {}", d.display());
            report::write_gallery(d, &title)?
        }
        dirs => report::write_report(dirs, a.out.as_deref(), a.inline)?,
    };
    if !quiet {
        println!("report: {}", page.display());
    }
    Ok(())
}
