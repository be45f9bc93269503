//! The world-space tracers the secondary-ray renderer and `bench ldc` can be asked for by
//! name: `bvh` (the exact reference) and `ldc` (the two-level layered depth cube). A small
//! selection of this module's own, kept until the crate's shared tracer factory exists.
//!
//! | name | structure | built from |
//! |---|---|---|
//! | `bvh` | binned-SAH BVH, exact hits | the scene's triangles |
//! | `ldc` | [`LdcTracer`] over a [`LayeredDepthCube`] | the three all-layers LDIs at `resolution` |

use std::time::Instant;

use parallax_bvh::Bvh;
use parallax_core::{Aabb, WorldTracer};
use parallax_raster::ldc::{LayeredDepthCube, LdcOptions, LdcStats};
use parallax_scene::Scene;
use parallax_screen::ldc::{LdcTraceOptions, LdcTracer};
use serde::Serialize;

use super::SecondaryError;

/// A tracer by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum TracerKind {
    Bvh,
    Ldc,
}

impl TracerKind {
    pub fn name(self) -> &'static str {
        match self {
            TracerKind::Bvh => "bvh",
            TracerKind::Ldc => "ldc",
        }
    }

    /// A comma list of tracer names, without duplicates.
    pub fn parse_list(list: &str) -> Result<Vec<Self>, SecondaryError> {
        let mut out = Vec::new();
        for w in list.split(',').map(str::trim).filter(|w| !w.is_empty()) {
            let k = match w {
                "bvh" => TracerKind::Bvh,
                "ldc" => TracerKind::Ldc,
                _ => {
                    return Err(SecondaryError::InvalidOptions(format!(
                        "unknown tracer {w:?} (expected bvh or ldc)"
                    )));
                }
            };
            if !out.contains(&k) {
                out.push(k);
            }
        }
        if out.is_empty() {
            return Err(SecondaryError::InvalidOptions("no tracer given".into()));
        }
        Ok(out)
    }
}

/// How the `ldc` tracer is built.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LdcSettings {
    /// Pixels along the cube's longest side.
    pub resolution: u32,
    pub build: LdcOptions,
    pub trace: LdcTraceOptions,
}

impl Default for LdcSettings {
    fn default() -> Self {
        Self {
            resolution: 1024,
            build: LdcOptions::default(),
            trace: LdcTraceOptions::default(),
        }
    }
}

/// A built tracer and what it cost.
pub struct BuiltTracer {
    pub kind: TracerKind,
    pub tracer: Box<dyn WorldTracer>,
    /// Wall time of the whole build (ms).
    pub build_ms: f64,
    /// The box the structure covers, when it covers only part of the scene.
    pub bounds: Option<Aabb>,
    /// Bytes of the structure.
    pub bytes: usize,
    /// The LDC's build stats (`ldc` only).
    pub ldc: Option<LdcStats>,
}

/// Builds tracer `kind` over `scene`.
pub fn build(
    kind: TracerKind,
    scene: &Scene,
    ldc: &LdcSettings,
) -> Result<BuiltTracer, SecondaryError> {
    let start = Instant::now();
    Ok(match kind {
        TracerKind::Bvh => {
            let bvh = Bvh::try_build(&scene.mesh)?;
            let bytes = bvh.bytes();
            BuiltTracer {
                kind,
                tracer: Box::new(bvh),
                build_ms: start.elapsed().as_secs_f64() * 1e3,
                bounds: None,
                bytes,
                ldc: None,
            }
        }
        TracerKind::Ldc => {
            let cube = LayeredDepthCube::build(scene, ldc.resolution, &ldc.build)?;
            let stats = cube.stats;
            let bounds = ldc.build.roi.map(|_| cube.bounds);
            let tracer = LdcTracer::new(cube, ldc.trace)?;
            let bytes = tracer.bytes();
            BuiltTracer {
                kind,
                tracer: Box::new(tracer),
                build_ms: start.elapsed().as_secs_f64() * 1e3,
                bounds,
                bytes,
                ldc: Some(stats),
            }
        }
    })
}
