//! Flag groups shared by the commands, flattened into each (`#[command(flatten)]`): the scene
//! and camera ([`ViewArgs`], every command that renders or measures a view), the options of the
//! view-synthesis methods ([`SynthArgs`]), their image size ([`SynthSize`]) and method / layer
//! selections ([`MethodArgs`], [`MethodListArgs`]), and the value parsers they share. Values
//! are checked here, once, by clap (enums, comma lists, ranges), so a command receives valid
//! flags.

use anyhow::{Context, Result, bail, ensure};
use clap::{Args, ValueEnum};
use glam::Vec3;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_scene::{CameraDesc, Scene};
use parallax_synth::layers::check_layers;
use parallax_synth::method::{Method, MethodOptions, NormalSource, parse_cube_near};
use parallax_synth::warp::{OcclusionFill, Resample, WarpOptions};
use parallax_synth::{CubeNear, Shading};

/// `--scene` and the camera flags of `render` (every `bench` command takes them too).
#[derive(Args, Clone, Debug)]
pub struct ViewArgs {
    /// A built-in scene name (see `parallax scenes`) or a .gltf / .glb / .obj / .ply file.
    #[arg(long, default_value = "atrium")]
    pub scene: String,
    /// A named camera of the scene (default: the scene's first camera).
    #[arg(long, conflicts_with_all = ["eye", "target"])]
    pub camera: Option<String>,
    /// Eye position: three values `--eye x y z`, or `--eye=x,y,z` (the `=` form is needed when
    /// the comma list starts with a minus sign).
    #[arg(long, num_args = 1..=3, value_delimiter = ',', allow_negative_numbers = true)]
    pub eye: Option<Vec<f32>>,
    /// Look-at target: x,y,z.
    #[arg(long, num_args = 1..=3, value_delimiter = ',', allow_negative_numbers = true, requires = "eye")]
    pub target: Option<Vec<f32>>,
    /// Up vector: x,y,z.
    #[arg(long, num_args = 1..=3, value_delimiter = ',', allow_negative_numbers = true, default_value = "0,1,0")]
    pub up: Vec<f32>,
    /// Vertical field of view in degrees (default: the named camera's, else 60).
    #[arg(long)]
    pub fov_y: Option<f32>,
    /// Camera model.
    #[arg(long, default_value = "pinhole", value_parser = parse_model)]
    pub model: ModelKind,
    /// Thin lens: aperture radius in metres.
    #[arg(long)]
    pub aperture: Option<f32>,
    /// Thin lens: focus distance in metres (default: distance to the target).
    #[arg(long)]
    pub focus: Option<f32>,
    /// Stereo: interpupillary distance in metres.
    #[arg(long, default_value_t = 0.065)]
    pub ipd: f32,
    /// Fisheye / equirect field of view: H,V degrees.
    #[arg(long, num_args = 1..=2, value_delimiter = ',')]
    pub fov: Option<Vec<f32>>,
}

fn parse_model(s: &str) -> Result<ModelKind, String> {
    ModelKind::parse(s).map_err(|e| e.to_string())
}

fn vec3(name: &str, v: &[f32]) -> Result<Vec3> {
    match v {
        [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
        _ => bail!("--{name} expects three numbers x,y,z, got {v:?}"),
    }
}

impl ViewArgs {
    /// Loads the scene named by `--scene`.
    pub fn load_scene(&self) -> Result<Scene> {
        Scene::load(&self.scene).with_context(|| format!("loading scene {:?}", self.scene))
    }

    /// The camera pose from `--camera` or `--eye/--target/--up/--fov-y`.
    pub fn camera_desc(&self, scene: &Scene) -> Result<CameraDesc> {
        let mut desc = match (&self.eye, &self.target) {
            (Some(eye), target) => {
                let eye = vec3("eye", eye)?;
                let target = match target {
                    Some(t) => vec3("target", t)?,
                    None => bail!("--eye needs --target"),
                };
                CameraDesc::new(eye, target, vec3("up", &self.up)?, 60.0)
            }
            (None, _) => scene.camera(self.camera.as_deref())?,
        };
        if let Some(f) = self.fov_y {
            desc.fov_y_deg = f;
        }
        desc.validate()?;
        Ok(desc)
    }

    /// Checks `--ipd` for the view-synthesis commands: finite and >= 0.
    pub fn check_ipd(&self) -> Result<()> {
        ensure!(
            self.ipd.is_finite() && self.ipd >= 0.0,
            "--ipd must be finite and >= 0, got {}",
            self.ipd
        );
        Ok(())
    }

    /// The camera model options from the flags.
    pub fn camera_options(&self) -> Result<CameraOptions> {
        let mut o = CameraOptions {
            ipd: self.ipd,
            focus_distance: self.focus,
            ..CameraOptions::default()
        };
        if let Some(a) = self.aperture {
            o.aperture_radius = a;
        }
        if let Some(f) = &self.fov {
            o.fov_deg = Some(match f.as_slice() {
                [h, v] => glam::Vec2::new(*h, *v),
                [h] => glam::Vec2::new(*h, *h),
                _ => bail!("--fov expects H,V degrees"),
            });
        }
        Ok(o)
    }

    /// The camera for a `width x height` film.
    pub fn camera(&self, scene: &Scene, width: u32, height: u32) -> Result<Camera> {
        let desc = self.camera_desc(scene)?;
        Ok(Camera::new(
            self.model,
            &desc,
            width,
            height,
            &self.camera_options()?,
        )?)
    }
}

/// Options of the synthesis methods (shared by `warp`, `upsample` and the synthesis benches).
#[derive(Args, Clone, Debug)]
pub struct SynthArgs {
    /// Random streams of the reference layers' shading and of the ground truth.
    #[arg(long, value_enum, default_value_t = ShadingArg::Fixed)]
    pub shading: ShadingArg,
    /// Seed of the shading streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Per-pixel plane normals of the tracers.
    #[arg(long, value_enum, default_value_t = NormalsArg::Gbuffer)]
    pub normals: NormalsArg,
    /// DDA: march step bound. Default for stereo (`warp`, `bench warp | compression`): 260,
    /// minimal artifact-free at 1600x900 from a 0.1 m camera near plane (--near fitted needs
    /// only 16); for upsampling (`upsample`, `bench upsample`): 1400 (700 at 800x450, doubled
    /// for 1600x900). The paper used 200 / 500 at its resolution. Sweep with
    /// `bench warp | upsample --dda-sweep`.
    #[arg(long)]
    pub dda_max_steps: Option<u32>,
    /// Near plane of the reference's unit cube, where every traced ray starts: `fitted` (half
    /// the nearest captured depth, our global empty-space skip) or a camera near plane in
    /// metres, e.g. `0.1` (Widmer et al. 2015's NDC cube = the camera frustum, the setting of
    /// their Tables 2-3; `camera` = 0.1).
    #[arg(long, default_value = "fitted", value_parser = parse_near)]
    pub near: CubeNear,
    /// Quad-tree: normal threshold gamma_norm as an angle in degrees (cos of it is used).
    #[arg(long, default_value_t = 3.0)]
    pub gamma_norm_deg: f32,
    /// Quad-tree: plane-distance threshold gamma_dist, in z units of Widmer's NDC cube (the camera frustum from a 0.1 m near plane, where the paper states its 1e-5), rescaled to the cube in use.
    #[arg(long, default_value_t = 1e-5)]
    pub gamma_dist: f32,
    /// Quad-tree: depth-adaptive thresholds (§6).
    #[arg(long)]
    pub adaptive: bool,
    /// Quad-tree: single-layer inpainting traversal (§4.1).
    #[arg(long)]
    pub inpaint: bool,
    /// Mesh warp: tear triangles whose corner depths differ by more than this fraction
    /// (default: never, background triangles stretch over disocclusions).
    #[arg(long)]
    pub mesh_max_rel_jump: Option<f32>,
    /// Tracers: nearest-pixel colour of a hit instead of depth-aware bilinear resampling.
    #[arg(long)]
    pub nearest: bool,
    /// Tracers: no layer-0 guard of answers from deeper layers (neither part).
    #[arg(long)]
    pub no_layer0_guard: bool,
    /// Tracers: no side-entry part (a) of the layer-0 guard.
    #[arg(long)]
    pub no_side_entry_guard: bool,
    /// Tracers: no DDA re-check parts (b) and (c) of the layer-0 guard.
    #[arg(long)]
    pub no_dda_recheck: bool,
    /// Tracers: colour of occlusion-volume answers (default: background).
    #[arg(long, value_enum)]
    pub ov_fill: Option<OvFillArg>,
    /// Do not render the BVH ground truth (no PSNR / SSIM).
    #[arg(long)]
    pub no_score: bool,
}

fn parse_near(s: &str) -> Result<CubeNear, String> {
    parse_cube_near(s).map_err(|e| e.to_string())
}

/// `--shading`: which random streams the reference layers and the ground truth draw from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ShadingArg {
    /// One random stream for every shading point: noise-free, comparable.
    Fixed,
    /// The reference renderer's per-pixel streams.
    #[value(alias = "perpixel")]
    PerPixel,
}

impl From<ShadingArg> for Shading {
    fn from(s: ShadingArg) -> Shading {
        match s {
            ShadingArg::Fixed => Shading::Fixed,
            ShadingArg::PerPixel => Shading::PerPixel,
        }
    }
}

/// `--normals`: where the tracers' per-pixel plane normals come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum NormalsArg {
    /// The G-buffer's shading normals.
    Gbuffer,
    /// The G-buffer's normals with the crack flag O at plane gaps (quad-tree crack dilation).
    GbufferFlagged,
    /// Reconstructed from depth (Widmer et al.'s).
    Depth,
}

impl From<NormalsArg> for NormalSource {
    fn from(n: NormalsArg) -> NormalSource {
        match n {
            NormalsArg::Gbuffer => NormalSource::GBuffer,
            NormalsArg::GbufferFlagged => NormalSource::gbuffer_flagged(),
            NormalsArg::Depth => NormalSource::Depth {
                max_rel_error: parallax_raster::normals::DEFAULT_MAX_REL_ERROR,
            },
        }
    }
}

/// `--ov-fill`: the colour of occlusion-volume answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OvFillArg {
    /// The pixel the tracer reports.
    Crossed,
    /// The nearest background pixel along the epipolar line (Widmer et al. 2015, Fig. 6e).
    Background,
}

impl From<OvFillArg> for OcclusionFill {
    fn from(f: OvFillArg) -> OcclusionFill {
        match f {
            OvFillArg::Crossed => OcclusionFill::Crossed,
            OvFillArg::Background => OcclusionFill::NearestBackground,
        }
    }
}

/// Default DDA max steps of the upsampling commands (see `--dda-max-steps`).
pub const DDA_MAX_STEPS_UPSAMPLE: u32 = 1400;

impl SynthArgs {
    /// The shading streams of references and ground truths.
    pub fn shading(&self) -> Shading {
        self.shading.into()
    }

    /// The method options of temporal upsampling (the upsampling DDA default).
    pub fn upsample_options(&self) -> Result<MethodOptions> {
        let mut o = self.method_options()?;
        o.dda_max_steps = self.dda_max_steps.unwrap_or(DDA_MAX_STEPS_UPSAMPLE);
        Ok(o)
    }

    /// The method options (stereo warping defaults).
    pub fn method_options(&self) -> Result<MethodOptions> {
        ensure!(
            self.gamma_norm_deg.is_finite() && (0.0..=90.0).contains(&self.gamma_norm_deg),
            "--gamma-norm-deg must be in 0..=90, got {}",
            self.gamma_norm_deg
        );
        ensure!(
            self.gamma_dist.is_finite() && self.gamma_dist >= 0.0,
            "--gamma-dist must be >= 0, got {}",
            self.gamma_dist
        );
        let jump = self.mesh_max_rel_jump.unwrap_or(f32::INFINITY);
        ensure!(jump >= 0.0, "--mesh-max-rel-jump must be >= 0, got {jump}");
        Ok(MethodOptions {
            normals: self.normals.into(),
            dda_max_steps: self
                .dda_max_steps
                .unwrap_or(MethodOptions::default().dda_max_steps),
            gamma_norm: self.gamma_norm_deg.to_radians().cos(),
            gamma_dist: self.gamma_dist,
            adaptive: self.adaptive,
            max_levels: None,
            inpaint: self.inpaint,
            mesh_max_rel_jump: jump,
            warp: WarpOptions {
                resample: if self.nearest {
                    Resample::Nearest
                } else {
                    Resample::Bilinear
                },
                side_entry_guard: !(self.no_layer0_guard || self.no_side_entry_guard),
                dda_recheck: !(self.no_layer0_guard || self.no_dda_recheck),
                fill: self
                    .ov_fill
                    .map_or(WarpOptions::default().fill, OcclusionFill::from),
                ..WarpOptions::default()
            },
            cube_near: self.near,
        })
    }
}

/// `--width --height` of the view-synthesis commands (each eye, each frame; Widmer et al.
/// 2015's 1600x900).
#[derive(Args, Clone, Copy, Debug)]
pub struct SynthSize {
    /// Image width (each eye, each frame, and the reference).
    #[arg(long, default_value_t = 1600)]
    pub width: u32,
    /// Image height.
    #[arg(long, default_value_t = 900)]
    pub height: u32,
    /// Memory budget in GiB: the run's estimated footprint must fit before anything is
    /// allocated (see `SynthSize::check_memory`).
    #[arg(long, default_value_t = 16.0)]
    pub memory_budget_gib: f64,
}

/// Estimated heap bytes per pixel and captured layer of a view-synthesis run (G-buffer,
/// shaded colour, per-pixel planes, tracer structure), and per pixel for the synthesised
/// views: measured as the max-RSS slope of `parallax warp --scene atrium --width 800
/// --height 450 --no-score --layers 1` vs `--layers 4` (61.6 MB vs 203.9 MB: 135 B per pixel
/// and layer), rounded up.
pub const BYTES_PER_PIXEL_LAYER: f64 = 160.0;
pub const BYTES_PER_PIXEL_VIEWS: f64 = 128.0;

impl SynthSize {
    /// Checks `width x height x (layers x 160 B + 128 B)` against `--memory-budget-gib`
    /// (resolution x layers x channels, before any allocation): a clear error above it.
    pub fn check_memory(&self, layers: usize) -> Result<()> {
        ensure!(
            self.memory_budget_gib.is_finite() && self.memory_budget_gib > 0.0,
            "--memory-budget-gib must be > 0, got {}",
            self.memory_budget_gib
        );
        let px = self.width as f64 * self.height as f64;
        let need = px * (layers as f64 * BYTES_PER_PIXEL_LAYER + BYTES_PER_PIXEL_VIEWS);
        let gib = need / (1u64 << 30) as f64;
        ensure!(
            gib <= self.memory_budget_gib,
            "{}x{} with {layers} layer(s) needs about {gib:.1} GiB, over --memory-budget-gib {}; lower the size or layers or raise the budget",
            self.width,
            self.height,
            self.memory_budget_gib
        );
        Ok(())
    }
}

/// `--method` and `--layers` of the commands that run one method (`warp`, `upsample`).
#[derive(Args, Clone, Copy, Debug)]
pub struct MethodArgs {
    /// quadtree, dda, minmax, hiz, mesh or brute.
    #[arg(long, default_value = "quadtree", value_parser = parse_method)]
    pub method: Method,
    /// Depth layers of the reference (1..=8; the mesh warp uses layer 0 only).
    #[arg(long, default_value_t = 2, value_parser = layer_count)]
    pub layers: usize,
}

impl MethodArgs {
    /// The layers to capture: `--layers`, or 1 for the mesh warp (layer 0 only).
    pub fn capture_layers(&self) -> usize {
        if self.method == Method::Mesh {
            1
        } else {
            self.layers
        }
    }
}

/// `--method`, `--layers` and `--dda-sweep` of the benches that compare methods (`bench warp`,
/// `bench upsample`).
#[derive(Args, Clone, Debug)]
pub struct MethodListArgs {
    /// Comma list of methods, or "all".
    #[arg(long, value_delimiter = ',', default_value = "all", value_parser = method_entry)]
    pub method: Vec<MethodEntry>,
    /// Comma list of layer counts (each 1..=8).
    #[arg(long, value_delimiter = ',', default_value = "1,2", value_parser = layer_count)]
    pub layers: Vec<usize>,
    /// DDA: one row per max-steps value of this comma list (e.g. 8,16,32,64,100000) instead of
    /// --dda-max-steps, and the minimal artifact-free value is printed (Widmer's tuning).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..=10_000_000))]
    pub dda_sweep: Vec<u32>,
}

impl MethodListArgs {
    /// The methods, `all` expanded, in the order given.
    pub fn methods(&self) -> Vec<Method> {
        self.method
            .iter()
            .flat_map(|e| match e {
                MethodEntry::All => Method::ALL.to_vec(),
                MethodEntry::One(m) => vec![*m],
            })
            .collect()
    }
}

/// One entry of a `--method` list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MethodEntry {
    All,
    One(Method),
}

fn method_entry(s: &str) -> Result<MethodEntry, String> {
    if s.trim() == "all" {
        Ok(MethodEntry::All)
    } else {
        parse_method(s.trim()).map(MethodEntry::One)
    }
}

/// A method name (the library's names and error).
pub fn parse_method(s: &str) -> Result<Method, String> {
    s.parse::<Method>().map_err(|e| e.to_string())
}

/// A layer count of a view-synthesis reference (the library's range check).
pub fn layer_count(s: &str) -> Result<usize, String> {
    let n: usize = s
        .trim()
        .parse()
        .map_err(|_| format!("expected a layer count, got {s:?}"))?;
    check_layers(&[n]).map_err(|e| e.to_string())?;
    Ok(n)
}

/// `--msaa`: subsamples per pixel of the VR commands.
pub fn msaa_spp(s: &str) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(v @ (1 | 4 | 8 | 16 | 32)) => Ok(v),
        _ => Err(format!(
            "samples per pixel must be one of 1, 4, 8, 16, 32, got {s:?}"
        )),
    }
}

/// `--frames` of the upsampling commands: output frames at 60 Hz.
pub fn frame_count(s: &str) -> Result<u32, String> {
    match s.trim().parse::<i64>() {
        Ok(n) if (1..=100_000).contains(&n) => Ok(n as u32),
        _ => Err(format!("--frames must be in 1..=100000, got {s}")),
    }
}
