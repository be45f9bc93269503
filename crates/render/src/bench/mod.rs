//! Benchmarks behind `parallax bench rays`: rows that the CLI prints as a Markdown table and
//! JSON. The technique crates keep their own benches (`parallax_synth::bench`,
//! `parallax_vr::bench`) and may reuse [`rays::primary_tiled`] and [`rays::bounce_rays`] where
//! they apply.

pub mod rays;
