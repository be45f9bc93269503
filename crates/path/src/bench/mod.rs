//! Benchmarks of path tracing behind `parallax bench ...`: each returns rows that the CLI
//! prints as Markdown and writes as JSON.
//!
//! - [`path`]: paths/s, Mrays/s per bounce, RMSE against a high-spp reference at equal spp and
//!   equal time, per tracer.

pub mod path;
