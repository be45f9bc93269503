//! Benchmarks behind `parallax bench warp | upsample | compression`: each reproduces a table or
//! figure of Widmer et al. 2015 on any scene and view and returns rows that the CLI prints as a
//! Markdown table and JSON (field names shared with `parallax_render::bench`).

pub mod compression;
pub mod trace;
pub mod upsample;
pub mod warp;
