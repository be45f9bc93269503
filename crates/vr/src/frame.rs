//! One HVVR frame (Hunt et al. 2018, §5): scene update (animate + BVH refit, §5.2), then per
//! eye: sample set -> visibility (the one switch between visibility methods, [`visibility`]) ->
//! resolve / shade (§5.6) -> reconstruct, with stage timings.

use std::time::Instant;

use rayon::prelude::*;

use parallax_bvh::{Bvh, BvhError};
use parallax_core::{Image, Rgb};
use parallax_scene::animation::{Animate, AnimationError};
use parallax_scene::camera::Camera;
use parallax_scene::{Scene, SceneError, TriangleMesh};

use crate::reconstruct::reconstruct;
use crate::resolve::{Resolved, ShadingMode, resolve};
use crate::shade::{ShadeOptions, VrShader};
use crate::{
    CastOptions, CastStats, Hierarchy, HierarchyError, PatternError, Sample, SampleSet, SampleTest,
    SetupExactness, VisibilityBuffer, cast_opts, trace_per_ray,
};

/// Errors of a VR frame.
#[derive(Debug, thiserror::Error)]
pub enum VrError {
    #[error("{0}")]
    Pattern(#[from] PatternError),
    #[error("{0}")]
    Hierarchy(#[from] HierarchyError),
    #[error("{0}")]
    Scene(#[from] SceneError),
    #[error("{0}")]
    Bvh(#[from] BvhError),
    #[error("{0}")]
    Animation(#[from] AnimationError),
    #[error("{0}")]
    Invalid(String),
}

/// Which visibility method fills the buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Visibility {
    /// Every subsample ray traced on its own through the BVH (single rays; the ray tracers of
    /// HVVR's Table 6 are in `bench/table6.rs`).
    PerRay,
    /// HVVR's block / tile beam caster (§5.3-5.5) with its default sample test (the per-tile
    /// triangle set-up, `cast/setup/mod.rs`).
    Beam,
    /// The beam caster with the exact watertight sample test (`intersect.rs`: bit-identical to
    /// per-ray traversal).
    BeamWatertight,
    /// The beam caster's set-up test with [`SetupExactness::Full`] (bit-identical to per-ray
    /// traversal, up to ~25% slower than the default set-up test; `cast/setup/mod.rs`).
    BeamExact,
}

impl Visibility {
    pub fn name(self) -> &'static str {
        match self {
            Visibility::PerRay => "per-ray",
            Visibility::Beam => "beam",
            Visibility::BeamWatertight => "beam-watertight",
            Visibility::BeamExact => "beam-exact",
        }
    }

    pub fn parse(s: &str) -> Result<Self, String> {
        match s {
            "per-ray" => Ok(Visibility::PerRay),
            "beam" => Ok(Visibility::Beam),
            "beam-watertight" => Ok(Visibility::BeamWatertight),
            "beam-exact" => Ok(Visibility::BeamExact),
            _ => Err(format!(
                "unknown visibility method {s:?}; expected per-ray or beam (or beam-watertight, \
                 beam-exact)"
            )),
        }
    }
}

/// What a visibility method precomputes once per sample set: nothing for per-ray tracing,
/// the tile / block hierarchy with its beams for the beam caster (HVVR builds it once per
/// sample pattern, not per frame, §5.1).
pub fn prepare(method: Visibility, set: &SampleSet) -> Result<Option<Hierarchy>, VrError> {
    Ok(match method {
        Visibility::PerRay => None,
        Visibility::Beam | Visibility::BeamWatertight | Visibility::BeamExact => {
            Some(Hierarchy::build(set)?)
        }
    })
}

/// Visibility of `set` by `method` with its precomputed `prepared` data (from [`prepare`]; built
/// here when `None`) and the beam caster's stage statistics: the only place the method is
/// chosen.
pub fn visibility_prepared(
    method: Visibility,
    bvh: &Bvh,
    set: &SampleSet,
    prepared: Option<&Hierarchy>,
) -> Result<(VisibilityBuffer, Option<CastStats>), VrError> {
    let mut out = VisibilityBuffer::new(set);
    let stats = visibility_into(method, bvh, set, prepared, &mut out)?;
    Ok((out, stats))
}

/// [`visibility_prepared`] into a buffer made for `set` ([`VisibilityBuffer::new`]) and reused
/// frame after frame, as a renderer would: every entry is overwritten, nothing is allocated.
pub fn visibility_into(
    method: Visibility,
    bvh: &Bvh,
    set: &SampleSet,
    prepared: Option<&Hierarchy>,
    out: &mut VisibilityBuffer,
) -> Result<Option<CastStats>, VrError> {
    assert!(
        out.prim.len() == set.ray_count() && out.t.len() == set.ray_count() && out.spp == set.spp,
        "visibility buffer made for another sample set"
    );
    if prepared.is_some_and(|h| h.camera != set.camera) {
        return Err(VrError::Invalid(
            "hierarchy built for another camera or pose: move it with Hierarchy::repose".into(),
        ));
    }
    Ok(match method {
        Visibility::PerRay => {
            trace_per_ray(bvh, set, out);
            None
        }
        Visibility::Beam | Visibility::BeamWatertight | Visibility::BeamExact => {
            let opts = match method {
                Visibility::BeamExact => CastOptions {
                    exactness: SetupExactness::Full,
                    ..CastOptions::default()
                },
                Visibility::BeamWatertight => CastOptions {
                    test: SampleTest::Watertight,
                    lanes: 4,
                    ..CastOptions::default()
                },
                _ => CastOptions::default(),
            };
            match prepared {
                Some(h) => Some(cast_opts(bvh, set, h, out, opts)),
                None => Some(cast_opts(bvh, set, &Hierarchy::build(set)?, out, opts)),
            }
        }
    })
}

/// Visibility of `set` by `method` (preparation included).
pub fn visibility(
    method: Visibility,
    bvh: &Bvh,
    set: &SampleSet,
) -> Result<VisibilityBuffer, VrError> {
    Ok(visibility_prepared(method, bvh, set, None)?.0)
}

/// Stage times of the scene update (HVVR Table 1's "vert xform" and the refit stages).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct UpdateTimings {
    pub animate_ms: f64,
    pub refit_ms: f64,
}

/// Poses `mesh` at time `t` and refits `bvh` to it (§5.2). `anim` is the scene's
/// [`parallax_scene::animation::Animation`] (glTF clips and skins when the file has them, else
/// the rigid props) or any one kind.
pub fn update_scene(
    anim: &impl Animate,
    mesh: &mut TriangleMesh,
    bvh: &mut Bvh,
    t: f32,
) -> Result<UpdateTimings, VrError> {
    let start = Instant::now();
    anim.apply(mesh, t)?;
    let animate_ms = start.elapsed().as_secs_f64() * 1e3;
    let refit = bvh.refit(mesh)?;
    Ok(UpdateTimings {
        animate_ms,
        refit_ms: refit.as_secs_f64() * 1e3,
    })
}

/// How to render a frame.
#[derive(Clone, Copy, Debug)]
pub struct FrameOptions {
    /// Subsamples per sample (1, 4, 8, 16 or 32).
    pub spp: u32,
    pub mode: ShadingMode,
    pub visibility: Visibility,
    pub shade: ShadeOptions,
}

/// Stage times of one eye (ms).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct EyeTimings {
    pub samples_ms: f64,
    /// The whole visibility stage, [`EyeTimings::hierarchy_ms`] included.
    pub visibility_ms: f64,
    /// The beam caster's hierarchy: built (the first frame) or moved to this frame's head
    /// pose ([`Hierarchy::repose`]); 0 for per-ray visibility.
    pub hierarchy_ms: f64,
    pub shade_ms: f64,
    pub reconstruct_ms: f64,
}

/// One rendered eye.
pub struct EyeFrame {
    pub set: SampleSet,
    pub vis: VisibilityBuffer,
    pub resolved: Resolved,
    /// Linear display image.
    pub image: Image<Rgb>,
    pub timings: EyeTimings,
}

/// Renders one eye through `camera` on a grid sample set.
pub fn render_eye(
    scene: &Scene,
    bvh: &Bvh,
    camera: Camera,
    opts: &FrameOptions,
) -> Result<EyeFrame, VrError> {
    if !matches!(opts.spp, 1 | 4 | 8 | 16 | 32) {
        return Err(VrError::Invalid(format!(
            "samples per pixel must be 1, 4, 8, 16 or 32, got {}",
            opts.spp
        )));
    }
    let t = Instant::now();
    let set = SampleSet::grid(camera, opts.spp);
    let samples_ms = ms(t);
    let mut eye = render_eye_set(scene, bvh, set, opts)?;
    eye.timings.samples_ms = samples_ms;
    Ok(eye)
}

/// Renders one eye's sample set `set` (its `spp` must be `opts.spp`).
pub fn render_eye_set(
    scene: &Scene,
    bvh: &Bvh,
    set: SampleSet,
    opts: &FrameOptions,
) -> Result<EyeFrame, VrError> {
    render_eye_with(scene, bvh, set, opts, &mut EyeState::new())
}

/// What one eye keeps from frame to frame in HVVR's frame loop: the beam caster's hierarchy,
/// computed once and moved to each new head pose (§5.1), and the visibility buffer of an
/// earlier frame, written over rather than allocated and filled again (every visibility method
/// writes every entry: the beam caster's tiles and blocks without rays clear their own,
/// `tests/cast.rs` `a_reused_buffer_equals_a_fresh_one`). At 16 spp a 1080x1200 eye's buffer is
/// 166 MB.
///
/// [`Hierarchy::repose`] moves the beams of the samples the hierarchy was built for; a set with
/// other samples (a foveated set whose gaze moved, another pattern) needs a new hierarchy. So
/// the state keeps those samples and subsample tables and compares each frame's set with them
/// (a parallel comparison, ~3 ms for 1.3 M samples): equal, the hierarchy is moved; else built
/// anew.
#[derive(Default)]
pub struct EyeState {
    hierarchy: Option<Hierarchy>,
    built_for: Option<SampleTables>,
    spare: Option<VisibilityBuffer>,
    /// Frames follow: a build also takes what the moves need ([`Hierarchy::prepare_moves`]),
    /// so that each later frame's hierarchy time is the move alone.
    moving: bool,
}

/// A set's samples and subsample tables, without its camera.
struct SampleTables {
    samples: Vec<Sample>,
    offsets: Vec<glam::Vec2>,
    lens: Vec<glam::Vec2>,
}

impl SampleTables {
    fn of(set: &SampleSet) -> Self {
        Self {
            samples: set.samples.clone(),
            offsets: set.offsets.clone(),
            lens: set.lens.clone(),
        }
    }

    fn same(&self, set: &SampleSet) -> bool {
        const CHUNK: usize = 1 << 14;
        self.offsets == set.offsets
            && self.lens == set.lens
            && self.samples.len() == set.samples.len()
            && self
                .samples
                .par_chunks(CHUNK)
                .zip(set.samples.par_chunks(CHUNK))
                .all(|(a, b)| a == b)
    }
}

impl EyeState {
    /// No hierarchy and no buffer yet: the first frame builds and allocates them.
    pub fn new() -> Self {
        Self::default()
    }

    /// [`EyeState::new`] for a loop whose head will move: each build also takes what the
    /// moves need ([`Hierarchy::prepare_moves`], timed with the build).
    pub fn moving() -> Self {
        Self {
            moving: true,
            ..Self::default()
        }
    }

    /// Gives a finished frame's visibility buffer back, for the next frame of this eye, and
    /// returns its sample set: the next frame's set is this one with the moved camera (HVVR
    /// computes the sample pattern once), not a new pattern computed again.
    pub fn recycle(&mut self, frame: EyeFrame) -> SampleSet {
        self.spare = Some(frame.vis);
        frame.set
    }

    /// The spare buffer if it fits `set`, else a new one.
    fn buffer_for(&mut self, set: &SampleSet) -> VisibilityBuffer {
        match self.spare.take() {
            Some(v) if v.spp == set.spp && v.prim.len() == set.ray_count() => v,
            _ => VisibilityBuffer::new(set),
        }
    }
}

/// [`render_eye_set`] keeping what `state` holds from frame to frame ([`EyeState`]): the
/// hierarchy is moved to `set`'s camera ([`Hierarchy::repose`]: a head that moved since the
/// last frame) when `set` has the samples it was built for, else built; the visibility buffer
/// is the one [`EyeState::recycle`] gave back, if it fits.
pub fn render_eye_with(
    scene: &Scene,
    bvh: &Bvh,
    set: SampleSet,
    opts: &FrameOptions,
    state: &mut EyeState,
) -> Result<EyeFrame, VrError> {
    if set.spp != opts.spp {
        return Err(VrError::Invalid(format!(
            "sample set has {} subsamples per sample, options say {}",
            set.spp, opts.spp
        )));
    }
    let samples_ms = 0.0;
    let t = Instant::now();
    let same = state.built_for.as_ref().is_some_and(|b| b.same(&set));
    match &mut state.hierarchy {
        Some(h) if same && opts.visibility != Visibility::PerRay => h.repose(&set)?,
        hierarchy => {
            *hierarchy = prepare(opts.visibility, &set)?;
            if let Some(h) = hierarchy.as_mut().filter(|_| state.moving) {
                h.prepare_moves(&set);
            }
            state.built_for = hierarchy.as_ref().map(|_| SampleTables::of(&set));
        }
    }
    let hierarchy_ms = ms(t);
    let mut vis = state.buffer_for(&set);
    visibility_into(
        opts.visibility,
        bvh,
        &set,
        state.hierarchy.as_ref(),
        &mut vis,
    )?;
    let visibility_ms = ms(t);
    let t = Instant::now();
    let shader = VrShader::new(scene, bvh, opts.shade);
    let resolved = resolve(&set, &vis, &shader, opts.mode);
    let shade_ms = ms(t);
    let t = Instant::now();
    let image = reconstruct(&set, &resolved.colors);
    let reconstruct_ms = ms(t);
    Ok(EyeFrame {
        set,
        vis,
        resolved,
        image,
        timings: EyeTimings {
            samples_ms,
            visibility_ms,
            hierarchy_ms,
            shade_ms,
            reconstruct_ms,
        },
    })
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
