//! `parallax bench warp --color-depth-input`: stereo warping of a colour + depth pair as a
//! user brings it (Widmer et al. 2015, §5.1 with the input of [`crate::input`]): the BVH
//! render of the reference view (its colour, sky included) and its view depth (no depth where
//! the sky is), read as one layer with depth-reconstructed normals, warped to both eyes by
//! each method; PSNR against the BVH eye views over the whole image and over the **surface**
//! pixels only (where the eye's BVH G-buffer holds a surface), so that sky colour does not
//! mask the surfaces' error.

use std::time::Instant;

use parallax_bvh::Bvh;
use parallax_render::reference::render_gbuffer;
use parallax_render::score::ground_truth;
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, Pinhole};
use serde::Serialize;

use super::warp::StereoSetup;
use crate::SynthError;
use crate::dof::truth::masked_psnr;
use crate::input::reference_from_images;
use crate::method::{Method, MethodOptions, Synthesizer};
use crate::stereo::stereo_eyes;
use crate::{Reference, score};

/// One method's warp of the colour + depth input.
#[derive(Clone, Debug, Serialize)]
pub struct InputRow {
    pub method: String,
    pub layers: usize,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    /// Mean over both eyes, whole image.
    pub psnr: f64,
    /// Mean over both eyes, surface pixels only (module docs).
    pub psnr_surfaces: f64,
    /// Mean over both eyes, sky pixels only (`NaN` when the eyes see none).
    pub psnr_sky: f64,
    /// Both eyes' warp milliseconds.
    pub ms_view: f64,
}

/// The single-layer reference made from the BVH render + depth of `setup`'s reference view.
pub fn input_reference(
    scene: &Scene,
    bvh: &Bvh,
    setup: &StereoSetup,
) -> Result<Reference, SynthError> {
    let cam = Pinhole::new(&setup.desc, setup.width, setup.height)?;
    let color = ground_truth(scene, bvh, &cam, setup.shading, setup.seed);
    let g = render_gbuffer(scene, bvh, &Camera::Pinhole(cam.clone()));
    let depth = parallax_core::Image::from_vec(cam.width, cam.height, g.depth)?;
    reference_from_images(color, &depth, &setup.desc, scene.environment)
}

/// Warps the colour + depth input of `setup` with every method (module docs).
pub fn run(
    scene: &Scene,
    bvh: &Bvh,
    setup: &StereoSetup,
    methods: &[Method],
    opts: &MethodOptions,
    progress: &dyn Fn(&str),
) -> Result<Vec<InputRow>, SynthError> {
    progress("colour + depth input");
    let mut reference = input_reference(scene, bvh, setup)?;
    reference.fit_cube(opts.cube_near)?;
    let eyes = stereo_eyes(&setup.desc, setup.width, setup.height, setup.ipd)?;
    progress("BVH eye views");
    let truths = eyes
        .clone()
        .map(|e| ground_truth(scene, bvh, &e, setup.shading, setup.seed));
    let surfaces = eyes.clone().map(|e| {
        render_gbuffer(scene, bvh, &Camera::Pinhole(e))
            .depth
            .iter()
            .map(|d| d.is_finite() && *d > 0.0)
            .collect::<Vec<bool>>()
    });
    let mut rows = Vec::new();
    for &m in methods {
        progress(&format!("{m}"));
        let synth = Synthesizer::build(m, &reference, opts)?;
        let (mut psnr, mut surf, mut sky, mut ms) = (0.0, 0.0, 0.0, 0.0);
        for k in 0..2 {
            let t = Instant::now();
            let v = synth.view(&reference, &eyes[k])?;
            ms += t.elapsed().as_secs_f64() * 1e3;
            psnr += 0.5 * score(&v.image, &truths[k])?.psnr;
            surf += 0.5 * masked_psnr(&v.image, &truths[k], &surfaces[k])?;
            let not: Vec<bool> = surfaces[k].iter().map(|s| !s).collect();
            sky += 0.5 * masked_psnr(&v.image, &truths[k], &not)?;
        }
        rows.push(InputRow {
            method: m.name().into(),
            layers: 1,
            scene: scene.name.clone(),
            width: setup.width,
            height: setup.height,
            psnr,
            psnr_surfaces: surf,
            psnr_sky: sky,
            ms_view: ms,
        });
    }
    Ok(rows)
}
