//! parallax-experiment: what `parallax run`, `parallax report` and `parallax merge` share
//! below the command line: the experiment file ([`schema`], TOML), its parameter sweep
//! ([`sweep`]), the shard a process runs ([`shard`]), the results folder and the merge of
//! shard folders ([`results`]), and the self-contained HTML report ([`report`]). It knows
//! nothing of the techniques: a point becomes the flags of a `parallax bench` subcommand,
//! which the CLI parses and runs through the same code as when typed by hand.

pub mod error;
pub mod report;
pub mod results;
pub mod schema;
pub mod shard;
pub mod sweep;

pub use error::ExperimentError;
pub use schema::{Axis, Entry, Experiment, Images};
pub use shard::Shard;
pub use sweep::Point;
pub use toml;
