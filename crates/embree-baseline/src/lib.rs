//! parallax-embree-baseline: Embree 3 as the ray-throughput bar for parallax's BVH.
//!
//! The foundation issue sets the bar for primary rays at Embree's throughput on the same
//! machine. This crate (outside the main workspace, so CI never needs Embree) wraps the Embree 3
//! C API through a small hand-written FFI ([`ffi`]) in a safe [`EmbreeScene`] (closest hit,
//! occlusion, 8/16-wide packets), and its binary (`src/main.rs`) times Embree and
//! `parallax_bvh::Bvh` on identical rays in one process, checks that they agree, and prints a
//! Markdown table.
//!
//! Install Embree with `./install-deps.sh` (Debian's `libembree-dev`, Embree 3.13).

pub mod cputime;
pub mod embree;
pub mod ffi;
pub mod packets;
pub mod procedural;

pub use embree::{BuildOptions, EmbreeError, EmbreeScene, MAX_PACKET, PrimHit, Quality};

/// Whether two closest-hit answers agree: both miss, or both hit the same triangle, or both hit
/// at `t` within `rel_tol` relative (two triangles meeting at the hit point).
pub fn hits_agree(a: Option<PrimHit>, b: Option<PrimHit>, rel_tol: f32) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some((pa, ta)), Some((pb, tb))) => {
            pa == pb || (ta - tb).abs() <= rel_tol * ta.abs().max(tb.abs()).max(1e-6)
        }
        _ => false,
    }
}

#[cfg(test)]
mod tests;
