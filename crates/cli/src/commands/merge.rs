//! `parallax merge SHARD_DIR... --out DIR`: joins the folders of a sharded job (`parallax run
//! --shard`, `parallax upsample --shard`) into the output of one unsharded run
//! (`parallax_experiment::results::merge`: shards checked disjoint and complete); for an
//! experiment also its report.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// The shards' output folders (each with shard.json).
    #[arg(required = true)]
    pub shards: Vec<PathBuf>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Do not write the report of a merged experiment.
    #[arg(long)]
    pub no_report: bool,
}

pub fn run(a: &MergeArgs, quiet: bool) -> Result<()> {
    let s = parallax_experiment::results::merge(&a.shards, &a.out)?;
    if !quiet {
        println!(
            "merged {} {} shard(s), {} items, {} files into {}",
            s.shards,
            s.kind,
            s.items,
            s.files,
            a.out.display()
        );
    }
    if s.kind == "run" && !a.no_report {
        let page =
            parallax_experiment::report::write_report(std::slice::from_ref(&a.out), None, false)?;
        if !quiet {
            println!("report: {}", page.display());
        }
    }
    Ok(())
}
