//! The error type of the crate: every message names the file and, for a key, its line.

use std::path::PathBuf;

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
