//! Benchmarks of path tracing behind `parallax bench ...`: each returns rows that the CLI
//! prints as Markdown and writes as JSON.
//!
//! - [`path`]: paths/s, Mrays/s per bounce, RMSE against a high-spp reference at equal spp and
//!   equal time, per tracer.
//! - [`dirt`]: DIRT's Tables 1-3 (Vardis et al. 2017): DIRT against the BVH on the rays of
//!   [`dirt_rays`] (build, Mrays/s per ray type, memory, `B` and `S` sweeps), and
//!   [`dirt_path`]: DIRT's path tracer against the BVH's (per-bounce hit agreement, PSNR).

pub mod dirt;
pub mod dirt_path;
pub mod dirt_rays;
pub mod path;
