//! The methods of Widmer et al. 2015, §5.1 and the ONE factory that builds their tracers.
//!
//! | name | what | paper |
//! |---|---|---|
//! | `quadtree` | adaptive quad-tree of planes / boxes (`parallax_screen::quadtree`) | §3-4, "Our" |
//! | `dda` | perspective-correct DDA ray marching (McGuire & Mara 2014) | "DDA" |
//! | `minmax` | min-max pyramid height-field tracing (Tevs et al. 2008) | "Height-field tracing" |
//! | `hiz` | hierarchical-Z tracing | baseline |
//! | `mesh` | forward warping of a grid mesh ([`crate::mesh_warp`]), not a tracer | "Mesh-based warping" |
//! | `brute` | every pixel plane of every layer ([`BruteForcePlanes`]), the slow twin | - |
//!

use std::fmt;
use std::str::FromStr;

use parallax_core::image::GBuffer;
pub use parallax_screen::NormalSource;
use parallax_screen::{
    BruteForcePlanes, CubeNear, DdaOptions, DdaTracer, HiZOptions, HiZTracer, LayerMode,
    LayerPlanes, MinMaxOptions, MinMaxTracer, QuadTreeOptions, QuadTreeTracer, ScreenTracer,
    UnitCube,
};
use serde::Serialize;

use parallax_scene::camera::Pinhole;

use crate::SynthError;
use crate::layers::Reference;
use crate::mesh_warp::GridMesh;
use crate::warp::{WarpOptions, WarpedView, warp_view_with};

/// A view-synthesis method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    QuadTree,
    Dda,
    MinMax,
    HiZ,
    Mesh,
    Brute,
}

impl Method {
    /// Every method, fastest-expected first.
    pub const ALL: [Method; 6] = [
        Method::QuadTree,
        Method::Dda,
        Method::MinMax,
        Method::HiZ,
        Method::Mesh,
        Method::Brute,
    ];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Method::QuadTree => "quadtree",
            Method::Dda => "dda",
            Method::MinMax => "minmax",
            Method::HiZ => "hiz",
            Method::Mesh => "mesh",
            Method::Brute => "brute",
        }
    }

    /// True for methods that trace rays (all but `mesh`).
    pub fn is_tracer(self) -> bool {
        self != Method::Mesh
    }

    /// A comma list of names (`"quadtree,dda"`, or `"all"`).
    pub fn parse_list(s: &str) -> Result<Vec<Method>, SynthError> {
        if s.trim() == "all" {
            return Ok(Method::ALL.to_vec());
        }
        s.split(',')
            .filter(|t| !t.trim().is_empty())
            .map(|t| t.trim().parse())
            .collect()
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = SynthError;
    fn from_str(s: &str) -> Result<Self, SynthError> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s.to_ascii_lowercase())
            .ok_or_else(|| SynthError::UnknownMethod(s.to_string()))
    }
}

/// Options of every method, passed through unchanged to the structure that uses them.
///
/// | option | type | default | used by | meaning |
/// |---|---|---|---|---|
/// | `normals` | [`NormalSource`] | G-buffer | all tracers | where per-pixel plane normals come from |
/// | `dda_max_steps` | u32 | 260 | dda | march step bound ([`parallax_screen::DdaOptions`]: minimal artifact-free for 1600x900 stereo from a 0.1 m camera near plane; fitted cube: 16; paper: 200 stereo, 500 upsampling) |
/// | `gamma_norm` | f32 (cos) | cos 3° | quadtree | normal-similarity merge threshold (§3.3, §6) |
/// | `gamma_dist` | f32 | 1e-5 | quadtree | plane-distance merge threshold (§3.3, §6), in `z` units of Widmer's NDC cube (0.1 m camera near plane) whatever `cube_near` is ([`gamma_dist_scale`]) |
/// | `adaptive` | bool | false | quadtree | depth-adaptive thresholds (§6, Fig. 15) |
/// | `max_levels` | `Option<u32>` | None (full) | quadtree | levels of the tree |
/// | `inpaint` | bool | false | quadtree | single-layer inpainting traversal (§4.1) |
/// | `mesh_max_rel_jump` | f32 | inf | mesh | split grid triangles whose depths differ by more than this fraction |
/// | `warp` | [`WarpOptions`] | bilinear + layer-0 guard (a)+(b)+(c) + nearest-background fill | all tracers | colour resampling and layer-0 guard of [`crate::warp`] |
/// | `cube_near` | [`CubeNear`] | fitted | all tracers | near plane of the reference's unit cube, where every ray starts (applied by [`crate::stereo::warp_stereo`] and [`crate::upsample::upsample`] through [`Reference::fit_cube`]) |
///
/// **`cube_near`.** [`CubeNear::Fitted`] (ours) starts rays at half the nearest captured
/// depth, a global empty-space skip; [`CubeNear::Camera`] at a camera near plane, Widmer et
/// al.'s NDC cube (§3.2), whose long screen-space rays are why their DDA needed 200 / 500
/// max steps. The choice does not change what a ray hits (nothing is captured in front of
/// half the nearest depth), only how far each tracer walks before reaching it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MethodOptions {
    #[serde(skip)]
    pub normals: NormalSource,
    pub dda_max_steps: u32,
    pub gamma_norm: f32,
    pub gamma_dist: f32,
    pub adaptive: bool,
    pub max_levels: Option<u32>,
    pub inpaint: bool,
    pub mesh_max_rel_jump: f32,
    pub warp: WarpOptions,
    pub cube_near: CubeNear,
}

impl Default for MethodOptions {
    fn default() -> Self {
        Self {
            normals: NormalSource::GBuffer,
            dda_max_steps: DdaOptions::default().max_steps,
            gamma_norm: 3f32.to_radians().cos(),
            gamma_dist: 1e-5,
            adaptive: false,
            max_levels: None,
            inpaint: false,
            mesh_max_rel_jump: f32::INFINITY,
            warp: WarpOptions::default(),
            cube_near: CubeNear::Fitted,
        }
    }
}

/// Builds the screen-space tracer of `method` over `layers` (all of the size of `cube`'s
/// camera). `mesh` is not a tracer: use [`crate::mesh_warp`].
pub fn build_tracer(
    method: Method,
    cube: &UnitCube,
    layers: &[GBuffer],
    opts: &MethodOptions,
) -> Result<Box<dyn ScreenTracer>, SynthError> {
    if layers.is_empty() {
        return Err(SynthError::Invalid("no layers to trace".into()));
    }
    let n = layers.len();
    match method {
        Method::QuadTree => {
            let mut q = quadtree_options(opts);
            q.gamma_dist *= gamma_dist_scale(cube, layers)?;
            Ok(Box::new(QuadTreeTracer::build(cube, layers, &q)?))
        }
        Method::Dda => {
            let o = DdaOptions {
                max_steps: opts.dda_max_steps,
                layers: n,
                ..Default::default()
            };
            Ok(Box::new(DdaTracer::new(cube, layers, &o)?))
        }
        Method::MinMax => {
            let o = MinMaxOptions {
                layers: n,
                ..Default::default()
            };
            Ok(Box::new(MinMaxTracer::new(cube, layers, &o)?))
        }
        Method::HiZ => Ok(Box::new(HiZTracer::new(
            cube,
            layers,
            &HiZOptions {
                layers: n,
                ..Default::default()
            },
        )?)),
        Method::Mesh => Err(SynthError::Invalid(
            "mesh is a forward warp, not a tracer".into(),
        )),
        Method::Brute => Ok(Box::new(brute(cube, layers, opts.normals)?)),
    }
}

/// The camera near plane (metres) of Widmer et al.'s NDC cube as we set it: the `camera`
/// setting of [`parse_cube_near`], and the cube in whose `z` units `gamma_dist` is given
/// ([`gamma_dist_scale`]).
pub const CAMERA_NEAR_M: f32 = 0.1;

/// The factor that turns a `gamma_dist` given in units of **Widmer's NDC cube** (§3.2, §6:
/// the camera frustum, here with a [`CAMERA_NEAR_M`] near plane, where the paper's default
/// `1e-5` is stated) into units of `cube`'s `z`. Cube `z` is inverse depth scaled by
/// `1 / (1/near - 1/far)`, so one `z` unit of the fitted cube ([`CubeNear::Fitted`], near =
/// half the nearest depth) spans ~16x less inverse depth than one of the NDC cube: this
/// factor keeps the merge tolerance the same in inverse depth whatever the cube, so the near
/// plane changes where rays start but not how much the tree simplifies. `1.0` for the NDC
/// cube itself.
///
/// (Why NDC-cube units: `docs/notes/synth.md`.)
pub fn gamma_dist_scale(cube: &UnitCube, layers: &[GBuffer]) -> Result<f32, SynthError> {
    let ndc = UnitCube::fit(
        &cube.camera,
        layers.iter().map(|g| &g.depth[..]),
        CubeNear::Camera(CAMERA_NEAR_M),
    )?;
    let span = |c: &UnitCube| 1.0 / c.near as f64 - 1.0 / c.far as f64;
    Ok((span(&ndc) / span(cube)) as f32)
}

/// The quad-tree options of `opts` (the quad-tree's own defaults for everything else;
/// `gamma_dist` in NDC-cube units, see [`gamma_dist_scale`]).
pub fn quadtree_options(opts: &MethodOptions) -> QuadTreeOptions {
    let d = QuadTreeOptions::default();
    QuadTreeOptions {
        gamma_norm: opts.gamma_norm,
        gamma_dist: opts.gamma_dist,
        adaptive: opts.adaptive,
        max_levels: opts.max_levels.unwrap_or(d.max_levels),
        normals: opts.normals,
        mode: if opts.inpaint {
            LayerMode::Inpaint
        } else {
            LayerMode::Cascade
        },
        ..d
    }
}

fn brute(
    cube: &UnitCube,
    layers: &[GBuffer],
    normals: NormalSource,
) -> Result<BruteForcePlanes, SynthError> {
    let planes = layers
        .iter()
        .map(|g| LayerPlanes::build(cube, g, normals))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(BruteForcePlanes {
        cube: cube.clone(),
        layers: planes,
    })
}

/// A built method: a screen-space tracer, or the grid mesh of the forward warp.
pub enum Synthesizer {
    Tracer(Box<dyn ScreenTracer>, WarpOptions),
    Mesh(GridMesh),
}

impl Synthesizer {
    /// Builds `method` over `reference` (the structure build of `T_ref`). Errors when the
    /// reference's cube was fitted with another near plane than `opts.cube_near` (call
    /// [`Reference::fit_cube`] first, as [`crate::stereo::warp_stereo`] does).
    pub fn build(
        method: Method,
        reference: &Reference,
        opts: &MethodOptions,
    ) -> Result<Self, SynthError> {
        if reference.cube_near != opts.cube_near {
            return Err(SynthError::Invalid(format!(
                "the reference's cube near plane is {}, the options ask for {}: call Reference::fit_cube",
                cube_near_name(reference.cube_near),
                cube_near_name(opts.cube_near)
            )));
        }
        Ok(match method {
            Method::Mesh => Synthesizer::Mesh(GridMesh::build(reference, opts.mesh_max_rel_jump)?),
            m => Synthesizer::Tracer(
                build_tracer(m, &reference.cube, &reference.layers, opts)?,
                opts.warp,
            ),
        })
    }

    /// The tracer (`None` for the mesh warp).
    pub fn tracer(&self) -> Option<&dyn ScreenTracer> {
        match self {
            Synthesizer::Tracer(t, _) => Some(t.as_ref()),
            Synthesizer::Mesh(_) => None,
        }
    }

    /// Synthesises `target`'s view of `reference`.
    pub fn view(&self, reference: &Reference, target: &Pinhole) -> Result<WarpedView, SynthError> {
        match self {
            Synthesizer::Tracer(t, w) => Ok(warp_view_with(t.as_ref(), reference, target, w)),
            Synthesizer::Mesh(m) => m.warp(target),
        }
    }
}

/// Parses a cube near-plane setting: `fitted` ([`CubeNear::Fitted`]) or a camera near plane
/// in metres (`0.1`, [`CubeNear::Camera`], Widmer's setting); `camera` alone means 0.1 m.
pub fn parse_cube_near(s: &str) -> Result<CubeNear, SynthError> {
    let t = s.trim().to_ascii_lowercase();
    let metres = match t.as_str() {
        "fitted" => return Ok(CubeNear::Fitted),
        "camera" => CAMERA_NEAR_M,
        v => v
            .strip_prefix("camera:")
            .unwrap_or(v)
            .parse::<f32>()
            .map_err(|_| {
                SynthError::Invalid(format!(
                    "near plane {s:?}: expected fitted, camera or a distance in metres"
                ))
            })?,
    };
    if !(metres.is_finite() && metres > 0.0) {
        return Err(SynthError::Invalid(format!(
            "camera near plane must be finite and > 0 m, got {s:?}"
        )));
    }
    Ok(CubeNear::Camera(metres))
}

/// The label of a cube near-plane setting: `fitted` or `camera <metres> m`.
pub fn cube_near_name(near: CubeNear) -> String {
    match near {
        CubeNear::Fitted => "fitted".into(),
        CubeNear::Camera(m) => format!("camera {m} m"),
    }
}
