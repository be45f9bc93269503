//! The reference of view synthesis: `N` rasterized depth layers of a pinhole view with a
//! colour per layer sample (Widmer et al. 2015, Fig. 1a: "reference view color+depth buffers
//! for the first and second layer").
//!
//! Layers come from [`parallax_raster::capture_layers`] (k-buffer, no separation). Every
//! covered sample of every layer is shaded exactly as the BVH reference renderer shades a
//! camera-ray hit ([`Shader::radiance_from_hit`]): the ray is the reference pixel-centre ray,
//! the hit the sample's primitive and barycentrics, so hidden layers get the colour the
//! reference eye would see if the surfaces in front were removed (view-dependent terms seen
//! from the reference eye, as a rasterizer's deferred shading would give). Layer 0 uses the
//! same per-pixel random stream as [`parallax_render::reference::render()`] with one sample per pixel, so
//! it reproduces that render wherever rasterized and traced primary visibility agree.
//!
//! **Noise.** The reference shading is Monte Carlo (sky visibility, emitter samples): with
//! per-pixel streams two renders of the same view differ by ~16 dB PSNR at one sample, which
//! would swamp every view-synthesis error. [`Shading::Fixed`] (the default here) gives every
//! shading point the same random stream, so shading is a deterministic function of the surface
//! point, its normal and the view direction — a banded but noise-free image, identical in the
//! reference and in the ground truth ([`parallax_render::score::ground_truth`] uses the same choice).
//! [`Shading::PerPixel`] reproduces [`parallax_render::reference::render()`] at one sample per pixel.
//!
//! `T_ref` = capture + shade (+ the tracer build, added by the caller).

use std::sync::Arc;
use std::time::Instant;

use glam::Vec2;
use parallax_bvh::{Bvh, Hit};
use parallax_core::image::GBuffer;
use parallax_core::{Image, Rgb};
use parallax_raster::raster::TriangleFilter;
use parallax_raster::{RasterOptions, View, capture_layers, capture_layers_filtered};
use parallax_render::score::Shading;
use parallax_scene::Scene;
use parallax_scene::camera::{CameraModel, Pinhole};
use parallax_screen::{CubeNear, UnitCube};
use serde::Serialize;

use crate::SynthError;
use crate::environment::Environment;
use parallax_render::reference::shade::Shader;
use parallax_render::tiles::for_each_pixel;

/// The most depth layers the view-synthesis commands and benches capture per reference.
pub const MAX_LAYERS: usize = 8;

/// Checks a list of layer counts: not empty, each in `1..=MAX_LAYERS`.
pub fn check_layers(layers: &[usize]) -> Result<(), SynthError> {
    if layers.is_empty() || layers.iter().any(|&l| l == 0 || l > MAX_LAYERS) {
        return Err(SynthError::Invalid(format!(
            "layers must be in 1..={MAX_LAYERS}, got {layers:?}"
        )));
    }
    Ok(())
}

/// Milliseconds of building a reference.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ReferenceTimes {
    /// Rasterizing the layers.
    pub capture_ms: f64,
    /// Shading every layer sample (BVH shadow rays).
    pub shade_ms: f64,
    /// Building the screen-space structure (set by the caller).
    pub build_ms: f64,
}

impl ReferenceTimes {
    /// `T_ref`: capture + shade + build.
    pub fn total_ms(&self) -> f64 {
        self.capture_ms + self.shade_ms + self.build_ms
    }
}

/// Colour + depth layers of one pinhole view.
#[derive(Clone, Debug)]
pub struct Reference {
    pub camera: Pinhole,
    /// Layer 0 = nearest surface, then depth peeled.
    pub layers: Vec<GBuffer>,
    /// Linear colour of every layer sample (environment colour where uncovered).
    pub colors: Vec<Image<Rgb>>,
    /// The unit cube around the captured depths (§3.2), its near plane chosen by
    /// [`Self::cube_near`]; every tracer built over this reference and the warp use it.
    pub cube: UnitCube,
    /// How [`Self::cube`]'s near plane was placed ([`CubeNear`]; capture fits
    /// [`CubeNear::Fitted`], [`Self::fit_cube`] changes it).
    pub cube_near: CubeNear,
    /// Colour of rays that miss everything (the scene's environment).
    pub background: Rgb,
    /// Colours by direction of the pixels without depth of a colour + depth input
    /// ([`crate::environment`]); misses take them instead of [`Self::background`]. `None` for
    /// rendered references (their misses see the scene's constant environment).
    pub environment: Option<Arc<Environment>>,
    pub times: ReferenceTimes,
}

impl Reference {
    pub fn width(&self) -> u32 {
        self.camera.width
    }
    pub fn height(&self) -> u32 {
        self.camera.height
    }

    /// The colour of a ray in world direction `dir` that misses every layer: the input's
    /// environment by direction, else [`Self::background`].
    #[inline]
    pub fn environment_colour(&self, dir: glam::Vec3) -> Rgb {
        match &self.environment {
            Some(e) => e.lookup(dir),
            None => self.background,
        }
    }

    /// Refits [`Self::cube`] around the captured depths of every layer with its near plane
    /// at `near` ([`UnitCube::fit`]): [`CubeNear::Fitted`] starts every ray at half the
    /// nearest captured depth (our global empty-space skip), [`CubeNear::Camera`] at the
    /// camera near plane (Widmer et al. 2015, §3.2: the NDC cube is the camera frustum, the
    /// setting of their Tables 2-3). The far plane (twice the farthest depth) is the same
    /// for both. A no-op when the cube already has that setting.
    pub fn fit_cube(&mut self, near: CubeNear) -> Result<(), SynthError> {
        if near != self.cube_near {
            self.cube =
                UnitCube::fit(&self.camera, self.layers.iter().map(|g| &g.depth[..]), near)?;
            self.cube_near = near;
        }
        Ok(())
    }
}

/// Which surfaces the layers behind layer 0 hold.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum HiddenLayers {
    /// Every surface along the pixel ray (plain depth peeling / k-buffer): behind a closed
    /// object's front face comes its own back face.
    All,
    /// Only triangles facing the reference eye (geometric normal towards the eye) in layers
    /// 1.., so the layer behind a solid object is the next front surface (the surface a
    /// disocclusion reveals). Layer 0 is unfiltered. Assumes consistently wound (outward)
    /// closed meshes; open, single-sided geometry seen from behind is dropped from layers 1...
    /// The default: with `All`, rays slipping through cracks between layer-0 pixel planes hit
    /// back faces, and two layers score below one (`docs/notes/synth.md`).
    #[default]
    FrontFacing,
}

/// Rasterizes `layers` depth layers of `camera`'s view of `scene` (hidden layers:
/// [`HiddenLayers::default`]) and shades them (seed of the random streams: `seed`).
pub fn capture_reference(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Pinhole,
    layers: usize,
    shading: Shading,
    seed: u64,
) -> Result<Reference, SynthError> {
    capture_reference_with(
        scene,
        bvh,
        camera,
        layers,
        HiddenLayers::default(),
        shading,
        seed,
    )
}

/// [`capture_reference`] with a choice of hidden layers.
pub fn capture_reference_with(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Pinhole,
    layers: usize,
    hidden: HiddenLayers,
    shading: Shading,
    seed: u64,
) -> Result<Reference, SynthError> {
    let (gbuffers, colors, capture_ms, shade_ms) =
        shaded_layers(scene, bvh, camera, layers, hidden, None, shading, seed)?;
    let cube = UnitCube::fit_depths(camera, gbuffers.iter().map(|g| &g.depth[..]))?;
    Ok(Reference {
        camera: camera.clone(),
        layers: gbuffers,
        colors,
        cube,
        cube_near: CubeNear::Fitted,
        background: scene.environment,
        environment: None,
        times: ReferenceTimes {
            capture_ms,
            shade_ms,
            build_ms: 0.0,
        },
    })
}

/// What [`shaded_layers`] returns: the layers, their colours, and the milliseconds of
/// capturing and of shading.
pub(crate) type ShadedLayers = (Vec<GBuffer>, Vec<Image<Rgb>>, f64, f64);

/// The layers of [`capture_reference_with`] and their colours, with the milliseconds of
/// capturing and of shading; a view that sees nothing gives empty layers (environment
/// colour), not an error. `only` (when given) keeps the triangles it accepts out of nothing
/// else: every layer, layer 0 included, rasterizes only them (the per-object cube maps of
/// [`crate::reflect::objects`] leave their own object's far side out); `None` is the plain
/// capture.
#[allow(clippy::too_many_arguments)]
#[allow(clippy::needless_range_loop)] // the index addresses several arrays in step
pub(crate) fn shaded_layers(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Pinhole,
    layers: usize,
    hidden: HiddenLayers,
    only: Option<TriangleFilter>,
    shading: Shading,
    seed: u64,
) -> Result<ShadedLayers, SynthError> {
    let t = Instant::now();
    let view = View::from_pinhole(camera)?;
    let capture = match only {
        None => capture_layers(scene, &view, &RasterOptions::layers(layers))?,
        Some(f) => capture_layers_filtered(scene, &view, &RasterOptions::layers(layers), Some(f))?,
    };
    let mut gbuffers = capture.layers.layers;
    if hidden == HiddenLayers::FrontFacing && layers > 1 {
        let eye = camera.frame.position;
        let mesh = &scene.mesh;
        let front = |prim: u32| {
            let [p0, _, _] = mesh.triangle(prim as usize);
            mesh.geometric_normal(prim as usize).dot(eye - p0) > 0.0 && only.is_none_or(|f| f(prim))
        };
        let filtered =
            capture_layers_filtered(scene, &view, &RasterOptions::layers(layers), Some(&front))?;
        // Layer k >= 1: the k-th front-facing surface behind layer 0.
        let behind = filtered.layers.layers;
        let d0s = gbuffers[0].depth.clone();
        for k in 1..layers {
            let mut g = GBuffer::new(camera.width, camera.height)?;
            for i in 0..g.len() {
                let d0 = d0s[i];
                // The j-th front-facing fragment strictly behind layer 0's depth.
                let mut seen = 0;
                for b in behind.iter() {
                    let s = b.sample_at(i);
                    if s.is_hit() && s.depth > d0 * (1.0 + 1e-4) {
                        seen += 1;
                        if seen == k {
                            g.set_at(i, s);
                            break;
                        }
                    }
                }
            }
            gbuffers[k] = g;
        }
    }
    let capture_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let shader = Shader::new(scene, bvh);
    let colors = gbuffers
        .iter()
        .enumerate()
        .map(|(k, g)| shade_layer(&shader, camera, g, k as u32, shading, seed))
        .collect();
    let shade_ms = t.elapsed().as_secs_f64() * 1e3;
    Ok((gbuffers, colors, capture_ms, shade_ms))
}

/// Shades every covered sample of layer `k` (see the module docs).
fn shade_layer(
    shader: &Shader,
    camera: &Pinhole,
    g: &GBuffer,
    k: u32,
    shading: Shading,
    seed: u64,
) -> Image<Rgb> {
    let (w, h) = (camera.width, camera.height);
    let env = shader.scene.environment;
    let mut out = vec![env; w as usize * h as usize];
    for_each_pixel(
        w,
        h,
        &mut out,
        |x, y, c| {
            let s = g.get(x, y);
            if !s.is_hit() || s.primitive_id as usize >= shader.scene.mesh.triangle_count() {
                return;
            }
            let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let Some(cr) = camera.generate_ray(film, Vec2::splat(0.5), 1) else {
                return;
            };
            let hit = Hit {
                prim: s.primitive_id,
                t: (s.position - cr.ray.origin).dot(cr.ray.dir).max(0.0),
                u: s.barycentrics.x,
                v: s.barycentrics.y,
            };
            let mut rng = shading.rng(seed, x, y, k);
            let mut rays = 0;
            *c = shader.radiance_from_hit(cr.ray, hit, &mut rng, &mut rays);
        },
        &|_| {},
    );
    Image::from_vec(w, h, out).expect("camera size is valid")
}
