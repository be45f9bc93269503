//! One file per subcommand.

pub mod bench;
pub mod bench_dirt;
pub mod bench_synth;
pub mod bench_vr;
pub mod capture;
pub mod demo;
pub mod demo_synth;
pub mod dof;
pub mod info;
pub mod input;
pub mod lightfield;
pub mod merge;
pub mod path;
pub mod reflect;
pub mod render;
pub mod report;
pub mod reproject;
pub mod run;
pub mod secondary;
pub mod upsample;
pub mod vr;
pub mod warp;
