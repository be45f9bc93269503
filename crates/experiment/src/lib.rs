//! parallax-experiment: what `parallax run`, `parallax report` and `parallax merge` share
//! below the command line: the experiment file ([`schema`], TOML), its parameter sweep
//! ([`sweep`]), the shard a process runs ([`shard`]), the results folder and the merge of
//! shard folders ([`results`]), and the self-contained HTML report ([`report`]). It knows
//! nothing of the techniques: a point becomes the flags of a `parallax bench` subcommand,
//! which the CLI parses and runs through the same code as when typed by hand.

pub mod report;
pub mod results;
pub mod schema;
pub mod shard;
pub mod sweep;

use std::path::PathBuf;

pub use schema::{Axis, Entry, Experiment, Images};
pub use shard::Shard;
pub use sweep::Point;
pub use toml;

/// Errors of experiment files, shards, merges and reports. Each names the file and, for a
/// key, its line.
#[derive(Debug, thiserror::Error)]
pub enum ExperimentError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}:{line}: {message}", file.display())]
    Syntax {
        file: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{}:{line}: key `{key}`: {message}", file.display())]
    Key {
        file: PathBuf,
        line: usize,
        key: String,
        message: String,
    },
    #[error(
        "{}: the sweep has {points} points ({axes}), more than max_points = {max}; raise max_points or shrink the sweep",
        file.display()
    )]
    TooManyPoints {
        file: PathBuf,
        points: u64,
        max: u64,
        axes: String,
    },
    #[error("shard: {0}")]
    Shard(String),
    #[error("merge: {0}")]
    Merge(String),
    #[error("{}: {message}", path.display())]
    Json { path: PathBuf, message: String },
    #[error("report: {0}")]
    Report(String),
}
