//! HVVR resolve (§5.1, §5.6) on small frames: MSAA against SSAA, shade counts, and the grid
//! reconstruction of a per-ray visibility buffer against the reference G-buffer.

use glam::Vec3;
use parallax_bvh::Bvh;
use parallax_core::image::png::{ToneMapping, Tonemap, tonemap_image};
use parallax_core::{Image, psnr_rgb};
use parallax_render::reference::render_gbuffer;
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_vr::SampleSet;
use parallax_vr::frame::{FrameOptions, Visibility, render_eye, visibility};
use parallax_vr::presets::{Dof, Preset, eye_cameras};
use parallax_vr::reconstruct::{grid_ids, reconstruct};
use parallax_vr::resolve::{ShadingMode, distinct_pairs, resolve};
use parallax_vr::shade::{ShadeOptions, VrShader};

const W: u32 = 64;
const H: u32 = 48;

fn setup(name: &str) -> (Scene, Bvh) {
    let scene = Scene::load(name).unwrap();
    let bvh = Bvh::build(&scene.mesh);
    (scene, bvh)
}

fn camera(scene: &Scene, model: ModelKind) -> Camera {
    let desc = scene.camera(None).unwrap();
    Camera::new(model, &desc, W, H, &CameraOptions::default()).unwrap()
}

fn display(img: &Image<Vec3>) -> Image<Vec3> {
    tonemap_image(
        img,
        &ToneMapping {
            exposure: 0.0,
            tonemap: Tonemap::AcesFilmic,
        },
    )
}

#[test]
fn spp1_msaa_equals_ssaa_exactly() {
    for (name, model) in [
        ("cornell", ModelKind::Pinhole),
        ("atrium", ModelKind::Distorted),
    ] {
        let (scene, bvh) = setup(name);
        let set = SampleSet::grid(camera(&scene, model), 1);
        let vis = visibility(Visibility::PerRay, &bvh, &set).unwrap();
        let shader = VrShader::new(&scene, &bvh, ShadeOptions::default());
        let m = resolve(&set, &vis, &shader, ShadingMode::Msaa);
        let s = resolve(&set, &vis, &shader, ShadingMode::Ssaa);
        assert_eq!(m.colors, s.colors, "{name}");
        assert_eq!(m.shades, s.shades);
        assert!(m.shades > 0);
    }
}

#[test]
fn msaa_shades_each_distinct_triangle_once_and_stays_close_to_ssaa() {
    // Measured at 64x48, ACES-tonemapped display values: atrium 61.8 dB, cornell 57.1 dB.
    for (name, spp, min_psnr) in [("atrium", 8, 45.0), ("cornell", 16, 45.0)] {
        let (scene, bvh) = setup(name);
        let set = SampleSet::grid(camera(&scene, ModelKind::Pinhole), spp);
        let vis = visibility(Visibility::PerRay, &bvh, &set).unwrap();
        let shader = VrShader::new(&scene, &bvh, ShadeOptions::default());
        let m = resolve(&set, &vis, &shader, ShadingMode::Msaa);
        let s = resolve(&set, &vis, &shader, ShadingMode::Ssaa);
        let hits = vis.prim.iter().filter(|&&p| p != u32::MAX).count() as u64;
        assert_eq!(s.shades, hits, "{name}: SSAA shades every hit subsample");
        assert_eq!(m.shades, distinct_pairs(&vis), "{name}");
        assert!(m.shades <= s.shades);
        // MSAA shades far less: about one shade per sample (HVVR Table 4: 1.2 vs 31).
        assert!(
            m.shades_per_nonempty() < 0.5 * s.shades_per_nonempty(),
            "{name}: msaa {} ssaa {}",
            m.shades_per_nonempty(),
            s.shades_per_nonempty()
        );
        let a = display(&reconstruct(&set, &m.colors));
        let b = display(&reconstruct(&set, &s.colors));
        let p = psnr_rgb(&a, &b, 1.0).unwrap();
        eprintln!(
            "{name} spp {spp}: MSAA vs SSAA PSNR {p:.2} dB, shades/pixel {:.3} vs {:.3}",
            m.shades_per_nonempty(),
            s.shades_per_nonempty()
        );
        assert!(p > min_psnr, "{name}: PSNR {p}");
    }
}

#[test]
fn grid_reconstruction_reproduces_the_reference_gbuffer_ids() {
    for name in ["atrium", "cornell"] {
        let (scene, bvh) = setup(name);
        let cam = camera(&scene, ModelKind::Pinhole);
        let reference = render_gbuffer(&scene, &bvh, &cam);
        let set = SampleSet::grid(cam, 1);
        let vis = visibility(Visibility::PerRay, &bvh, &set).unwrap();
        let ids = grid_ids(&set, &vis);
        assert_eq!(ids.data(), reference.primitive_id.as_slice(), "{name}");
    }
}

#[test]
fn per_channel_frames_fill_each_channel_from_its_own_rays() {
    let (scene, bvh) = setup("atrium");
    let desc = scene.camera(None).unwrap();
    let mut spec = Preset::RiftCv1.spec();
    spec.width = W;
    spec.height = H;
    let [left, right] = eye_cameras(&spec, &desc, None).unwrap();
    let opts = FrameOptions {
        spp: 4,
        mode: ShadingMode::Msaa,
        visibility: Visibility::PerRay,
        shade: ShadeOptions::default(),
    };
    let l = render_eye(&scene, &bvh, left, &opts).unwrap();
    let r = render_eye(&scene, &bvh, right, &opts).unwrap();
    assert_eq!(l.set.samples.len(), (W * H * 3) as usize);
    // Pixel channel c equals channel c of sample (pixel, c).
    for (i, p) in l.image.data().iter().enumerate() {
        for c in 0..3 {
            assert_eq!(p[c], l.resolved.colors[i * 3 + c][c]);
        }
    }
    // The eyes see different views.
    assert_ne!(l.image.data(), r.image.data());
    // The beam caster's exact (watertight) visibility is the per-ray visibility, so the frames
    // are identical; its default set-up kernel agrees up to edge ties.
    let beam = FrameOptions {
        visibility: Visibility::BeamWatertight,
        ..opts
    };
    let cam = camera(&scene, ModelKind::Pinhole);
    let b = render_eye(&scene, &bvh, cam.clone(), &beam).unwrap();
    let p = render_eye(&scene, &bvh, cam.clone(), &opts).unwrap();
    assert_eq!(b.vis, p.vis);
    assert_eq!(b.image.data(), p.image.data());
    let setup = FrameOptions {
        visibility: Visibility::Beam,
        ..opts
    };
    let s = render_eye(&scene, &bvh, cam, &setup).unwrap();
    assert!(
        s.vis.agreement(&p.vis) >= 0.999,
        "{}",
        s.vis.agreement(&p.vis)
    );
}

#[test]
fn defocus_raises_the_msaa_shade_count() {
    // HVVR Table 5: shade samples per pixel grow as the focus moves away from the content
    // (1.45 at 0.5 m to 2.94 at 0.1 m) because a pixel's subsamples spread over more triangles.
    let (scene, bvh) = setup("atrium");
    let desc = scene.camera(None).unwrap();
    let mut spec = Preset::Custom.spec();
    spec.width = W;
    spec.height = H;
    let opts = FrameOptions {
        spp: 16,
        mode: ShadingMode::Msaa,
        visibility: Visibility::PerRay,
        shade: ShadeOptions::default(),
    };
    let mut last = 0.0;
    for dof in [
        None,
        Some(Dof {
            aperture: 0.05,
            focus: 0.3,
        }),
    ] {
        let [l, _] = eye_cameras(&spec, &desc, dof).unwrap();
        let e = render_eye(&scene, &bvh, l, &opts).unwrap();
        let s = e.resolved.shades_per_nonempty();
        eprintln!("dof {dof:?}: {s:.3} shades per non-empty pixel");
        assert!(s > last, "{dof:?}: {s} <= {last}");
        last = s;
    }
}

/// Mean of the linear RGB channels.
fn mean(img: &Image<Vec3>) -> f64 {
    img.data()
        .iter()
        .map(|c| c.element_sum() as f64)
        .sum::<f64>()
        / (3 * img.data().len()) as f64
}

#[test]
fn shadows_on_bring_the_frame_to_the_reference_renderers_light() {
    // With shadows the sky term is occluded as in the reference renderer (its sky visibility
    // rays), so the two frames receive the same light on average; without shadows the sky
    // lights every surface fully and the atrium's arcades come out brighter.
    use parallax_render::reference::{RenderOptions, render};
    let (scene, bvh) = setup("atrium");
    let cam = camera(&scene, ModelKind::Pinhole);
    let set = SampleSet::grid(cam.clone(), 4);
    let vis = visibility(Visibility::PerRay, &bvh, &set).unwrap();
    let frame = |shadows| {
        let shader = VrShader::new(&scene, &bvh, ShadeOptions { shadows });
        let r = resolve(&set, &vis, &shader, ShadingMode::Msaa);
        mean(&reconstruct(&set, &r.colors))
    };
    let (on, off) = (frame(true), frame(false));
    let opts = RenderOptions {
        spp: 64,
        seed: 3,
        gbuffer: false,
    };
    let reference = mean(&render(&scene, &bvh, &cam, &opts, &|_| {}).image);
    println!("mean radiance: vr shadows {on:.4}, vr no shadows {off:.4}, reference {reference:.4}");
    assert!((on / reference - 1.0).abs() < 0.05, "{on} vs {reference}");
    assert!(off > 1.2 * reference, "{off} vs {reference}");
}
