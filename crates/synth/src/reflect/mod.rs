//! Ray-traced specular and glossy reflections through a cube map of the scene (Widmer et al.
//! 2015, §5.4, Table 5, Figs. 11-13).
//!
//! **Pipeline.** (1) A cube map of `N` colour + depth layers (1 or 2) is captured at the
//! camera's eye and a screen-space structure is built per face ([`cube`]: `T_cm`); (2) the
//! camera's view is rasterized and shaded ([`crate::layers`], one layer: `T_ref`); (3) at
//! every pixel whose surface reflects ([`lobe`]: mirrors, and glossy metals as normalised
//! Blinn-Phong lobes) `N_p` reflection rays are sampled (stratified over the lobe, as depth of
//! field stratifies its lens) and traced through the cube map, face by face
//! ([`parallax_screen::cubemap`]); a ray that reaches another reflective surface bounces on
//! (one sampled direction) until `N_b` segments, a diffuse surface ends it with its colour,
//! a miss takes the environment ([`render`]: `T_rr`). Pixels that do not reflect keep their
//! shaded colour. The paper rasterizes "the reflective objects only"; we rasterize the whole
//! view once (the same primary hits, and the image around the reflectors).
//!
//! **Extra samples** (`N_s`, §5.4 "followed by `N_s` extra samples per ray"): after a glossy
//! primary vertex's traced ray, `N_s` more directions from the same lobe stratum are not
//! traced when the traced ray ended on a diffuse surface: each is intersected with that hit's
//! plane only and looked up in the cube map, weighted by depth agreement (the secondary
//! samples of depth of field, [`cube`]); the ray's colour is the weighted mean (the traced ray
//! with weight 1). After a traced ray that bounced on, its extra samples weigh 0; a stratum
//! whose traced direction falls below the surface adds nothing. Mirrors draw no extra
//! samples (every one is the same direction). With `trace_below > 0` (not in the paper) an
//! extra sample whose lookup weighs less than `trace_below` — its plane misses the surface
//! the lobe direction reaches — is traced as a full path instead (weight 1, as the truth).
//!
//! **Antialiasing** (`reflect --spp`): the view is captured at `s` times its size
//! ([`crate::lightfield::supersampled`]), every reflector renders all its `s x s` primary
//! pixels and the image is box-filtered to the view's size
//! ([`ReflectionImage::box_filtered`]); the truth is the BVH reflector on the same rays with
//! the same filter.
//!
//! **Ground truth** ([`truth`]): the same renderer with the BVH as [`Reflector`] — the same
//! primary hits and sample directions, every segment traced exactly, extra samples traced as
//! full paths, each surface coloured as a cube-map sample of it would be (or, with
//! [`TruthColour::AlongTheRay`], by its physical radiance along the ray).
//!
//! **Cube maps at the objects** ([`objects`], `--cube-at objects`; **not the paper's
//! method**, Umenhoffer et al. 2007's placement, Fig. 12's comparison): one cube map at the
//! centre of each reflective object instead of one at the camera; a ray is traced in the
//! cube map of the object it leaves ([`Reflector::trace_from`]). [`setup::CubeMaps`] builds
//! either placement, its reflectors and its truth.
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `n_p` | u32 | 3 | reflection rays per reflective pixel, `1..=`[`MAX_PRIMARY`] |
//! | `n_s` | u32 | 8 | extra samples per glossy primary ray, `0..=`[`MAX_EXTRA`] |
//! | `n_b` | u32 | 1 | traced segments per path (bounces), `1..=`[`MAX_BOUNCES`] |
//! | `sigma` | f32 | 0.02 | width of the extra samples' depth weight (relative depth), `> 0` |
//! | `offset_px` | f32 | 1.5 | reflection rays start this many cube-face pixel footprints (at the origin's distance from the eye) off their surface, so a sampled surface does not reflect itself, `>= 0`, finite |
//! | `trace_below` | f32 | 0 | extra samples whose plane-lookup weight is below this are traced as paths, `0..=1` (0: never, the paper) |
//! | `seed` | u64 | 0 | seed of the per-pixel direction streams |
//!
//! **Invariants:** the image is bit-identical for any thread count (per-pixel streams:
//! `Rng::for_pixel(seed, x, y, 0)` for the primary directions, consumed the same whatever the
//! tracer finds, and stream `1 + i` for path `i`'s later bounces); every reflector sees the
//! same primary hits and the same rays from them.

pub mod cube;
pub mod lobe;
pub mod objects;
pub mod render;
pub mod setup;
pub mod truth;

use glam::{UVec2, Vec2, Vec3};
use parallax_core::{Ray, WorldStats};
use parallax_scene::Scene;
use serde::Serialize;

use crate::SynthError;
pub use cube::{CubeReflector, CubeTimes, ReflectionCube};
pub use lobe::Lobe;
pub use objects::{CubeAt, CubeCentres, ObjectCubeReflector, ObjectCubes};
pub use render::{ReflectionImage, render_reflections};
pub use setup::CubeMaps;
pub use truth::{BvhReflector, TruthColour};

/// Largest `n_p`.
pub const MAX_PRIMARY: u32 = 1024;
/// Largest `n_s`.
pub const MAX_EXTRA: u32 = 256;
/// Largest `n_b`.
pub const MAX_BOUNCES: u32 = 16;

/// Options of [`render_reflections`] (module table).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ReflectOptions {
    pub n_p: u32,
    pub n_s: u32,
    pub n_b: u32,
    pub sigma: f32,
    pub offset_px: f32,
    pub trace_below: f32,
    pub seed: u64,
}

impl Default for ReflectOptions {
    fn default() -> Self {
        Self {
            n_p: 3,
            n_s: 8,
            n_b: 1,
            sigma: crate::dof::DEFAULT_SIGMA,
            offset_px: 1.5,
            trace_below: 0.0,
            seed: 0,
        }
    }
}

impl ReflectOptions {
    /// Checks the ranges of the parameter table.
    pub fn validate(&self) -> Result<(), SynthError> {
        let bad = |what: String| Err(SynthError::Invalid(what));
        if !(1..=MAX_PRIMARY).contains(&self.n_p) {
            return bad(format!(
                "N_p (reflection rays per pixel) must be in 1..={MAX_PRIMARY}, got {}",
                self.n_p
            ));
        }
        if self.n_s > MAX_EXTRA {
            return bad(format!(
                "N_s (extra samples per ray) must be in 0..={MAX_EXTRA}, got {}",
                self.n_s
            ));
        }
        if !(1..=MAX_BOUNCES).contains(&self.n_b) {
            return bad(format!(
                "N_b (bounces) must be in 1..={MAX_BOUNCES}, got {}",
                self.n_b
            ));
        }
        if !(self.sigma.is_finite() && self.sigma > 0.0) {
            return bad(format!(
                "sigma of the extra samples' weight must be finite and > 0, got {}",
                self.sigma
            ));
        }
        if !(self.offset_px.is_finite() && self.offset_px >= 0.0) {
            return bad(format!(
                "the ray offset must be finite and >= 0 pixels, got {}",
                self.offset_px
            ));
        }
        if !(0.0..=1.0).contains(&self.trace_below) {
            return bad(format!(
                "the extra samples' tracing weight must be in 0..=1, got {}",
                self.trace_below
            ));
        }
        Ok(())
    }
}

/// A surface a reflection ray reached.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// Ray parameter.
    pub t: f32,
    pub position: Vec3,
    /// Unit normal facing the ray.
    pub normal: Vec3,
    pub material_id: u32,
    pub albedo: Vec3,
    /// Scene triangle and barycentrics (where known).
    pub prim: u32,
    pub barycentrics: Vec2,
    /// The cube-map sample that answered: face, layer, pixel (`None` for exact hits).
    pub sample: Option<(u8, u8, UVec2)>,
    /// The sampled hit is the inpainted answer of an occlusion volume (the ray passed behind
    /// the sample's surface), not a hit on it.
    pub occlusion: bool,
    /// The cube map the ray was traced in (its index among the reflector's cube maps: 0 for
    /// the one cube at the camera, the object's for [`CubeAt::Objects`]); the truth colours
    /// the hit towards that cube's centre ([`TruthColour::TowardsCube`]).
    pub cube: u16,
}

/// What answers the reflection renderer's rays: the cube map's structures or the BVH.
pub trait Reflector: Sync {
    /// Row label (`cubemap-quadtree`, `cubemap-dda`, `bvh`).
    fn name(&self) -> String;

    /// The scene whose materials the hits' ids refer to.
    fn scene(&self) -> &Scene;

    /// The first surface along `ray`, counting the ray in `stats`.
    fn trace(&self, ray: &Ray, stats: &mut WorldStats) -> Option<SurfaceHit>;

    /// [`Self::trace`] of a ray that leaves the surface of scene triangle `from` (the
    /// renderer always says where its rays start): a reflector with one cube map per
    /// reflective object ([`CubeAt::Objects`]) traces it in the cube map of `from`'s object.
    fn trace_from(&self, ray: &Ray, from: u32, stats: &mut WorldStats) -> Option<SurfaceHit> {
        let _ = from;
        self.trace(ray, stats)
    }

    /// The colour of `ray`'s hit `hit`: the radiance its point sends towards the cube map's
    /// eye (asked only where a path ends, so tracing alone does not pay for it).
    fn colour(&self, ray: &Ray, hit: &SurfaceHit) -> Vec3;

    /// True when extra samples are traced as full paths (the ground truth) rather than
    /// looked up with [`Self::plane_sample`].
    fn traces_extras(&self) -> bool {
        false
    }

    /// An extra sample `ray` of the lobe whose traced ray ended at `hit` (a diffuse
    /// surface): its colour and weight from `hit`'s plane (weight 0: no sample).
    fn plane_sample(&self, hit: &SurfaceHit, ray: &Ray, sigma: f32) -> (Vec3, f32);

    /// The lobe of `hit`'s material (`None`: diffuse, the path ends).
    fn lobe(&self, hit: &SurfaceHit) -> Option<Lobe> {
        let m = self.scene().materials.get(hit.material_id as usize)?;
        Lobe::of(m, hit.albedo)
    }
}
