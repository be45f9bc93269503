//! parallax-embree: Embree 3 (Wald et al. 2014, "Embree: a kernel framework for efficient CPU
//! ray tracing") in the same process as parallax's BVH, as the baseline its speed is measured
//! against (`parallax bench rays`) on the *same* rays.
//!
//! The `embree` cargo feature links Debian's Embree 3.13 (`libembree3`, installed by
//! `scripts/install-embree.sh`) through the `embree3` binding crate (Embree 3.13.5's C API,
//! safe wrappers; maintained). Without the feature this crate still compiles, with the same
//! API: [`EmbreeScene::new`] then returns [`EmbreeError::NotEnabled`], whose message says how
//! to enable it, and no Embree code is linked. The workspace, its tests and CI never need Embree.
//!
//! What is wrapped: one triangle geometry per scene (primitive id = triangle index of the
//! parallax mesh), closest hit with `rtcIntersect1`, `rtcIntersect8`, `rtcIntersect16` (SoA
//! packets, the coherent context flag) and `rtcIntersect1M` (ray streams), any hit with
//! `rtcOccluded1`. The tracing calls run with the FTZ/DAZ flags Embree asks for ("for
//! performance reasons ... the application should enable flush-to-zero and denormals-are-zero
//! mode", Embree 3 API, §Performance recommendations), set and restored around each call batch,
//! so the caller's threads keep IEEE semantics for parallax's own (exact) code.
//!
//! | option ([`Options`]) | type | default | meaning |
//! |---|---|---|---|
//! | `quality` | [`Quality`] | `High` | Embree's BVH build quality (`RTC_BUILD_QUALITY_*`; `High` adds spatial splits) |
//! | `robust` | bool | false | `RTC_SCENE_FLAG_ROBUST` (watertight-leaning traversal and intersection, slower) |
//!
//! **Invariant:** the crate never fakes an answer: without the feature no [`EmbreeScene`] can
//! exist (its constructor fails), so nothing can report Embree numbers that Embree did not make.

#[cfg(not(feature = "embree"))]
mod disabled;
#[cfg(feature = "embree")]
mod enabled;
#[cfg_attr(not(feature = "embree"), allow(dead_code))]
mod mxcsr;

#[cfg(not(feature = "embree"))]
pub use disabled::EmbreeScene;
#[cfg(feature = "embree")]
pub use enabled::EmbreeScene;

/// Whether this build links Embree (the `embree` feature).
pub const ENABLED: bool = cfg!(feature = "embree");

/// How to get the Embree rows, for messages of benches built without the feature.
pub const ENABLE_HINT: &str = "Embree baseline not built in: install Embree 3 with \
`scripts/install-embree.sh` (Debian's libembree-dev), then build with `--features embree`, \
e.g. `cargo run --release --features embree -- bench rays ...`";

/// A closest hit as Embree reports it: triangle index of the mesh, ray parameter `t`, and the
/// barycentrics of vertices 1 and 2 (Embree's `u`, `v`: `P = (1-u-v) p0 + u p1 + v p2`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmbreeHit {
    pub prim: u32,
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

/// Widest packet [`EmbreeScene::closest_hit_packets`] traces.
pub const MAX_PACKET: usize = 16;

/// Embree's BVH build quality (`RTCBuildQuality`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Quality {
    /// Morton-code build.
    Low,
    /// Embree's default: binned SAH.
    Medium,
    /// Binned SAH with spatial splits (SBVH): the fastest traversal, the slowest build.
    #[default]
    High,
}

impl Quality {
    pub fn name(self) -> &'static str {
        match self {
            Quality::Low => "low",
            Quality::Medium => "medium",
            Quality::High => "high",
        }
    }
}

impl std::str::FromStr for Quality {
    type Err = EmbreeError;

    fn from_str(s: &str) -> Result<Self, EmbreeError> {
        match s {
            "low" => Ok(Quality::Low),
            "medium" => Ok(Quality::Medium),
            "high" => Ok(Quality::High),
            _ => Err(EmbreeError::UnknownQuality(s.to_string())),
        }
    }
}

/// Scene build options (table in the crate docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Options {
    pub quality: Quality,
    pub robust: bool,
}

/// What went wrong talking to Embree.
#[derive(Debug, thiserror::Error)]
pub enum EmbreeError {
    #[error("{ENABLE_HINT}")]
    NotEnabled,
    #[error("Embree call {call} failed: {code}")]
    Call { call: &'static str, code: String },
    #[error("triangle {triangle} indexes vertex {index}, but the mesh has {vertices} vertices")]
    BadIndex {
        triangle: usize,
        index: u32,
        vertices: usize,
    },
    #[error("unknown Embree build quality {0:?} (low, medium or high)")]
    UnknownQuality(String),
    #[error("mesh too large for Embree's 32-bit ids: {0} triangles or vertices")]
    TooLarge(usize),
}

/// Checks a mesh before it is handed to Embree (Embree itself does not check indices).
pub(crate) fn validate(mesh: &parallax_scene::TriangleMesh) -> Result<(), EmbreeError> {
    let (nv, nt) = (mesh.positions.len(), mesh.indices.len());
    if nt > u32::MAX as usize / 2 || nv > u32::MAX as usize / 2 {
        return Err(EmbreeError::TooLarge(nt.max(nv)));
    }
    for (triangle, tri) in mesh.indices.iter().enumerate() {
        if let Some(&index) = tri.iter().find(|&&i| i as usize >= nv) {
            return Err(EmbreeError::BadIndex {
                triangle,
                index,
                vertices: nv,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
