//! Benchmarks behind `parallax bench ...`: each reproduces a measurement of a paper or an issue
//! on any scene and camera, and returns rows that the CLI prints as a Markdown table and JSON.

pub mod compression;
pub mod rays;
pub mod trace;
pub mod upsample;
pub mod warp;
