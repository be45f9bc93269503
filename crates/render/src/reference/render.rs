//! The reference render: G-buffer and shaded image in one pass over screen tiles.

use glam::{Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_core::image::GBuffer;
use parallax_core::sampling::Rng;
use parallax_core::{Image, Rgb};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel};

use parallax_core::image::GSample;

use super::gbuffer::{gsample, pack};
use super::shade::{Shader, sample_2d};
use crate::tiles::for_each_pixel;

/// Options of a reference render.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// Samples per pixel (>= 1). One sample goes through the pixel centre.
    pub spp: u32,
    /// Seed of the per-pixel random streams.
    pub seed: u64,
    /// Also produce the G-buffer (one extra primary ray per pixel).
    pub gbuffer: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            spp: 1,
            seed: 0,
            gbuffer: true,
        }
    }
}

/// What a reference render returns.
pub struct RenderOutput {
    pub image: Image<Rgb>,
    pub gbuffer: Option<GBuffer>,
    /// Every ray traced (primary, shadow, specular, G-buffer).
    pub rays: u64,
}

#[derive(Clone, Copy)]
struct Pixel {
    color: Vec3,
    g: GSample,
    rays: u64,
}

/// Renders `camera`'s view of `scene`. `progress(n)` is called as pixels complete.
pub fn render(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Camera,
    opts: &RenderOptions,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderOutput {
    let (w, h) = (camera.width(), camera.height());
    let spp = opts.spp.max(1);
    let shader = Shader::new(scene, bvh);
    let channels = camera.channel_count();
    let mut pixels = vec![
        Pixel {
            color: Vec3::ZERO,
            g: GSample::MISS,
            rays: 0
        };
        w as usize * h as usize
    ];
    for_each_pixel(
        w,
        h,
        &mut pixels,
        |x, y, out| {
            let mut rays = 0u64;
            let mut sum = Vec3::ZERO;
            for s in 0..spp {
                let mut rng = Rng::for_pixel(opts.seed, x, y, s);
                let film = Vec2::new(x as f32, y as f32) + sample_2d(&mut rng, spp);
                let lens = sample_2d(&mut rng, spp);
                // Per-channel models (lens distortion) trace one ray per colour channel.
                for c in 0..channels {
                    let Some(cr) = camera.generate_ray(film, lens, c) else {
                        continue;
                    };
                    let l = shader.radiance(cr.ray, &mut rng, &mut rays);
                    if channels == 1 {
                        sum += l;
                    } else {
                        sum[c] += l[c];
                    }
                }
            }
            out.color = sum / spp as f32;
            if opts.gbuffer {
                out.g = gsample(scene, bvh, camera, x, y);
                rays += 1;
            }
            out.rays = rays;
        },
        progress,
    );
    let rays = pixels.iter().map(|p| p.rays).sum();
    let image = Image::from_vec(w, h, pixels.iter().map(|p| p.color).collect())
        .expect("camera size is valid");
    let gbuffer = opts
        .gbuffer
        .then(|| pack(w, h, &pixels.iter().map(|p| p.g).collect::<Vec<_>>()));
    RenderOutput {
        image,
        gbuffer,
        rays,
    }
}
