//! Benchmarks behind `parallax bench rays`: rows that the CLI prints as a Markdown table and
//! JSON. The technique crates keep their own benches (`parallax_synth::bench`,
//! `parallax_vr::bench`) and reuse [`rays::make_rays`]'s camera rays where they apply.

pub mod rays;
