//! View synthesis with screen-space ray tracing: the applications of Widmer et al. 2015, §5.1
//! (stereo warping, Table 2; 15 -> 60 Hz temporal upsampling, Table 3) and their baseline,
//! mesh-based forward warping.
//!
//! Pipeline: a **reference** ([`layers::Reference`]) is `N` rasterized depth layers of a
//! pinhole view, every layer sample shaded with the reference renderer's shading so each
//! layer has a colour image, plus the fitted unit cube (§3.2). A **tracer** built over the
//! layers ([`method::build_tracer`], the one factory of every screen-space structure) answers
//! each target pixel's ray; [`warp::warp_view`] turns the answers into colour (hit: the hit
//! layer's colour resampled depth-aware bilinearly at the hit's sub-pixel position; miss: the environment; occlusion volume: the nearest background pixel
//! behind the crossed occluder edge — the inpainting of §4.1 / Fig. 6e). [`mesh_warp`] forward-warps layer 0 as a
//! grid mesh instead (§5.1, "one vertex per input image pixel"). Every result is scored
//! against the BVH reference render of the same camera ([`score()`]).
//!
//! - [`method`]: `Method` (quadtree | dda | minmax | hiz | mesh | brute) and the factory;
//! - [`layers`]: reference capture + shading (`T_ref`);
//! - [`warp`]: per-pixel tracing into a target pinhole, hit-type and work images;
//! - [`stereo`]: the stereo pair of a cyclopean reference (Table 2);
//! - [`upsample`]: 15 -> 60 Hz along a camera path (Table 3);
//! - [`mesh_warp`]: the forward-warping baseline;
//! - [`input`]: a colour + depth image pair as a single-layer reference;
//! - [`environment`]: the input's pixels without depth as colours by direction (misses);
//! - [`dof`]: thin-lens depth of field through the layers (§5.2, Table 4, Figs. 8-9);
//! - [`lightfield`]: Looking Glass quilts and near-eye elemental images (§5.3);
//! - [`reflect`]: specular and glossy reflections through a cube map's quad-trees (§5.4);
//! - [`margin`]: references widened for rays that start off the reference eye;
//! - [`bench`](mod@bench): `parallax bench warp | upsample | compression` (Tables 2-3, Fig. 14/15);
//! - scoring: [`score()`] and [`Shading`] come from `parallax_render::score` (PSNR / SSIM against
//!   the BVH ground truth).
//!
//! **Invariants:** every method warps the same reference (same layers, colours and unit
//! cube) with the same pixel rays, so rows differ only by the structure; every result is
//! deterministic and independent of the thread count.
//!
//! Measurements behind the defaults: `docs/notes/synth.md` (the quad-tree's own:
//! `docs/notes/quadtree.md`, the baselines': `docs/notes/screen.md`).

pub mod bench;
pub mod dof;
pub mod environment;
pub mod input;
pub mod layers;
pub mod lightfield;
pub mod margin;
pub mod mesh_warp;
pub mod method;
pub mod reflect;
pub mod stereo;
pub mod upsample;
pub mod warp;

pub use layers::{
    HiddenLayers, Reference, ReferenceTimes, capture_reference, capture_reference_with,
};
pub use method::{Method, MethodOptions, build_tracer, cube_near_name, parse_cube_near};
pub use parallax_render::score::{Score, Shading, score};
pub use parallax_screen::CubeNear;
pub use warp::{HitKind, WarpedView, warp_view};

/// Errors of view synthesis.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    #[error("unknown method {0:?}; expected quadtree, dda, minmax, hiz, mesh or brute")]
    UnknownMethod(String),
    #[error("invalid argument: {0}")]
    Invalid(String),
    #[error(transparent)]
    Screen(#[from] parallax_screen::ScreenError),
    #[error(transparent)]
    Raster(#[from] parallax_raster::RasterError),
    #[error(transparent)]
    Scene(#[from] parallax_scene::SceneError),
    #[error(transparent)]
    Core(#[from] parallax_core::CoreError),
    #[error(transparent)]
    Bvh(#[from] parallax_bvh::BvhError),
}
