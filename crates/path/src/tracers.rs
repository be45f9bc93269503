//! The `--tracer` factory: the one place that builds a world-space tracer
//! ([`parallax_core::WorldTracer`]) for a scene and a camera, so that every command and bench
//! runs the same path tracer over any structure.
//!
//! | name | structure | hits | built from |
//! |---|---|---|---|
//! | `bvh` | binned-SAH 4-wide BVH ([`parallax_bvh::Bvh`]) | exact | the scene's triangles |
//!
//! Image-space structures that need the camera (DIRT's views around it, the layered depth
//! cube's capture) add their variant here; [`TracerOptions`] carries their parameters.

use std::time::Instant;

use parallax_bvh::Bvh;
use parallax_core::WorldTracer;
use parallax_scene::Scene;
use parallax_scene::camera::Camera;

use crate::error::{PathError, Result};

/// Which structure answers the path tracer's rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TracerKind {
    /// The exact BVH over the scene's triangles (the reference).
    #[default]
    Bvh,
}

impl TracerKind {
    pub const ALL: [TracerKind; 1] = [TracerKind::Bvh];

    pub fn name(self) -> &'static str {
        match self {
            TracerKind::Bvh => "bvh",
        }
    }

    pub fn parse(s: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| PathError::UnknownTracer {
                name: s.to_string(),
                known: Self::ALL.map(|k| k.name()).join(", "),
            })
    }
}

/// Parameters of the structures that have any (none for the BVH).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TracerOptions {}

/// A built tracer and what building it cost.
pub struct BuiltTracer {
    pub tracer: Box<dyn WorldTracer>,
    /// Wall-clock milliseconds of the build.
    pub build_ms: f64,
}

/// Builds the `kind` tracer for `scene` seen by `camera`.
pub fn build_tracer(
    kind: TracerKind,
    scene: &Scene,
    _camera: &Camera,
    _opts: &TracerOptions,
) -> Result<BuiltTracer> {
    let start = Instant::now();
    let tracer: Box<dyn WorldTracer> = match kind {
        TracerKind::Bvh => Box::new(Bvh::try_build(&scene.mesh).map_err(|e| PathError::Build {
            tracer: kind.name().into(),
            message: e.to_string(),
        })?),
    };
    Ok(BuiltTracer {
        tracer,
        build_ms: start.elapsed().as_secs_f64() * 1e3,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_names_list_the_known() {
        for k in TracerKind::ALL {
            assert_eq!(TracerKind::parse(k.name()).unwrap(), k);
        }
        let e = TracerKind::parse("octree").unwrap_err().to_string();
        assert!(e.contains("octree") && e.contains("bvh"), "{e}");
    }
}
