//! Light-field quilts (Widmer et al. 2015, §5.3) on the atrium: antialiased views (`s x s`
//! rays per pixel, box-filtered) are exactly the filtered warps of their supersampled cameras
//! and score against the BVH truth of the same rays and filter; a diagnostic splits the
//! error of a near view into view-dependent shading, reconstruction and tracing.

use parallax_bvh::{Bvh, Hit};
use parallax_core::{Image, Ray, Rgb};
use parallax_render::reference::shade::Shader;
use parallax_scene::Scene;
use parallax_screen::TraceResult;
use parallax_synth::dof::truth::masked_psnr;
use parallax_synth::lightfield::quilt::{QuiltSpec, QuiltViews, assemble, tile};
use parallax_synth::lightfield::{
    box_filter, bvh_pinhole, bvh_pinhole_aa, quilt_reference, render_views, render_views_aa,
    spp_side, supersampled,
};
use parallax_synth::method::{Method, MethodOptions, Synthesizer};
use parallax_synth::warp::{PixelRays, RayWarp, warp_view_with};
use parallax_synth::{Reference, Shading, score};

fn atrium() -> (Scene, Bvh) {
    let scene = Scene::load("atrium").unwrap();
    let bvh = Bvh::try_build(&scene.mesh).unwrap();
    (scene, bvh)
}

/// Three views in a row over `cone` degrees (the middle one at the reference), tiles
/// `w x h`, their reference at `scale` times the tile with `layers` layers, and its
/// quad-tree.
fn quilt(
    scene: &Scene,
    bvh: &Bvh,
    w: u32,
    h: u32,
    cone: f32,
    scale: u32,
    layers: usize,
) -> (QuiltViews, Reference, Synthesizer) {
    let mut spec = QuiltSpec::new(3, 1, w, h);
    spec.view_cone_deg = cone;
    let views = QuiltViews::new(spec, &scene.camera(None).unwrap(), None).unwrap();
    let (r, _) = quilt_reference(scene, bvh, &views, scale, layers, Shading::Fixed, 0).unwrap();
    let s = Synthesizer::build(Method::QuadTree, &r, &MethodOptions::default()).unwrap();
    (views, r, s)
}

#[test]
fn spp_and_box_filter() {
    assert_eq!(spp_side(1).unwrap(), 1);
    assert_eq!(spp_side(9).unwrap(), 3);
    for bad in [0, 2, 8, 81] {
        assert!(spp_side(bad).unwrap_err().to_string().contains("square"));
    }
    // The mean of each block: a ramp in x averages to its block centre.
    let img = Image::from_fn(6, 4, |x, y| Rgb::new(x as f32, y as f32, 1.0)).unwrap();
    let f = box_filter(&img, 2).unwrap();
    assert_eq!((f.width(), f.height()), (3, 2));
    assert_eq!(*f.get(2, 1), Rgb::new(4.5, 2.5, 1.0));
    assert!(box_filter(&img, 4).is_err());
}

#[test]
fn antialiased_tiles_are_filtered_renders_of_their_views() {
    let (scene, bvh) = atrium();
    let (views, r, synth) = quilt(&scene, &bvh, 48, 36, 3.75, 3, 2);
    let tracer = synth.tracer().unwrap();
    let opts = MethodOptions::default().warp;
    // One ray per pixel: the images of the plain renders.
    let one = render_views_aa(tracer, &r, &views, &opts, 1).unwrap();
    let plain = render_views(tracer, &r, &views, &opts);
    for (a, b) in one.iter().zip(&plain) {
        assert!(a.image.data() == b.image.data());
    }
    // 2 x 2 rays: tile i of the quilt is the box-filtered warp of view i's camera at twice
    // the size.
    let aa = render_views_aa(tracer, &r, &views, &opts, 2).unwrap();
    let images: Vec<Image<Rgb>> = aa.iter().map(|v| v.image.clone()).collect();
    let q = assemble(&views.spec, &images).unwrap();
    for i in 0..3 {
        let cam = supersampled(&views.camera(i), 2);
        assert_eq!((cam.width, cam.height), (96, 72));
        let v = warp_view_with(tracer, &r, &cam, &opts);
        let expect = box_filter(&v.image, 2).unwrap();
        assert!(
            tile(&views.spec, &q, i).unwrap().data() == expect.data(),
            "view {i}"
        );
        assert_eq!(aa[i as usize].rays.image.width(), 96);
    }
    // Scored against the truth of the same rays and filter: the filtered side views are
    // closer to their truth than the one-ray views to theirs (the aliasing of single point
    // samples is what the one-ray score mostly measures, docs/notes/synth.md).
    for i in [0, 2] {
        let cam = views.camera(i);
        let t1 = bvh_pinhole(&scene, &bvh, &cam, Shading::Fixed, 0).unwrap();
        let t4 = bvh_pinhole_aa(&scene, &bvh, &cam, 2, Shading::Fixed, 0).unwrap();
        let p1 = score(&one[i as usize].image, &t1.image).unwrap().psnr;
        let p4 = score(&aa[i as usize].image, &t4.image).unwrap().psnr;
        println!("view {i}: 1 ray {p1:.2} dB, 2x2 rays {p4:.2} dB");
        assert!(p4 > p1 + 0.5, "view {i}: {p4} vs {p1}");
        assert!(p1 > 20.0, "view {i}: {p1}");
    }
}

/// Diagnostic (`cargo test --release -p parallax-synth --test lightfield -- --ignored
/// --nocapture error_split`): the side views of a 3-view quilt on the atrium, their error
/// against the BVH truth `T` split over the pixels whose true surface a reference layer holds:
/// - `T` vs `R`: `R` shades the same true hit from the reference eye (what a reference
///   sample of that point holds): the view-dependent shading no reference view can hold;
/// - `R` vs `O`: `O` looks the exact true hit up in the reference (the warp's colour
///   resampling at the true position): the reconstruction from the reference's samples;
/// - `O` vs `S`: `S` is the synthesis: where the tracer's answer differs from the truth.
#[test]
#[ignore]
fn error_split() {
    let (scene, bvh) = atrium();
    let shader = Shader::new(&scene, &bvh);
    for (cone, scale, s) in [
        (3.75, 3, 1),
        (0.375, 3, 1),
        (3.75, 5, 1),
        (3.75, 3, 2),
        (3.75, 3, 3),
    ] {
        let (views, r, synth) = quilt(&scene, &bvh, 320, 240, cone, scale, 2);
        let opts = MethodOptions::default().warp;
        let warp = RayWarp::new(&r, &opts);
        let eye = r.camera.frame.position;
        let rendered = render_views_aa(synth.tracer().unwrap(), &r, &views, &opts, s).unwrap();
        for i in [0u32, 2] {
            let cam = supersampled(&views.camera(i), s);
            let truth = bvh_pinhole(&scene, &bvh, &cam, Shading::Fixed, 0)
                .unwrap()
                .image;
            let rays = PixelRays::new(&cam);
            let n = (cam.width * cam.height) as usize;
            // Pixels no layer holds (and the sky) keep the truth in R and O.
            let (mut rr, mut oo) = (truth.data().to_vec(), truth.data().to_vec());
            let mut held = vec![false; n];
            // Held pixels whose traced answer is the true surface (within 1% of its distance);
            // pixels whose truth is the sky; surfaces no layer holds.
            let (mut same, mut sky, mut unheld) = (vec![false; n], vec![false; n], vec![false; n]);
            let tracer = synth.tracer().unwrap();
            for y in 0..cam.height {
                for x in 0..cam.width {
                    let k = (y * cam.width + x) as usize;
                    let ray = rays.row(y).ray(x);
                    let Some(h) = bvh.closest_hit(&ray) else {
                        sky[k] = true;
                        continue;
                    };
                    let p = ray.at(h.t);
                    unheld[k] = true;
                    let d = p - eye;
                    let ref_ray = Ray::new(eye, d.normalize());
                    let hit = Hit { t: d.length(), ..h };
                    let mut rng = Shading::Fixed.rng(0, 0, 0, 0);
                    rr[k] = shader.radiance_from_hit(ref_ray, hit, &mut rng, &mut 0);
                    // The layer whose sample under p holds p's triangle.
                    let Some(f) = parallax_scene::camera::CameraModel::project(&r.camera, p, 0)
                    else {
                        continue;
                    };
                    if !(f.x >= 0.0 && f.y >= 0.0) {
                        continue;
                    }
                    let q = glam::UVec2::new(f.x as u32, f.y as u32);
                    if q.x >= r.width() || q.y >= r.height() {
                        continue;
                    }
                    let Some(layer) = r.layers.iter().position(|g| {
                        let i = g.index(q.x, q.y);
                        g.depth[i].is_finite() && (g.position[i] - p).length() <= 0.01 * d.length()
                    }) else {
                        continue;
                    };
                    let answer = TraceResult::Hit {
                        layer: layer as u32,
                        pixel: q,
                        position: p,
                        t: h.t,
                    };
                    oo[k] = warp.colour(&ray, answer).0;
                    held[k] = true;
                    unheld[k] = false;
                    let a = warp.trace(tracer, &ray, &mut Default::default());
                    same[k] = a
                        .hit_t()
                        .is_some_and(|t| (ray.at(t) - p).length() <= 0.01 * d.length());
                }
            }
            let img = |v: Vec<Rgb>| Image::from_vec(cam.width, cam.height, v).unwrap();
            let (rr, oo) = (img(rr), img(oo));
            let synth_img = &rendered[i as usize].rays.image;
            let m = |a: &Image<Rgb>, b: &Image<Rgb>| masked_psnr(a, b, &held).unwrap();
            let share = held.iter().filter(|h| **h).count() as f64 / n as f64;
            println!(
                "cone {cone} scale {scale} {s}x{s} rays, view {i} (offset {:+.3} m): S-T {:.2} dB over all pixels; over the {:.1}% a layer holds: S-T {:.2}, R-T (view-dependent shading) {:.2}, O-R (reconstruction) {:.2}, O-T {:.2}, S-O (tracing) {:.2}",
                views.offset(i),
                score(synth_img, &truth).unwrap().psnr,
                100.0 * share,
                m(synth_img, &truth),
                m(&rr, &truth),
                m(&oo, &rr),
                m(&oo, &truth),
                m(synth_img, &oo),
            );
            let other: Vec<bool> = (0..n).map(|k| held[k] && !same[k]).collect();
            let frac = |m: &[bool]| 100.0 * m.iter().filter(|b| **b).count() as f64 / n as f64;
            let mp = |a: &Image<Rgb>, b: &Image<Rgb>, m: &[bool]| masked_psnr(a, b, m).unwrap();
            println!(
                "  S-O {:.2} dB over the {:.1}% answered on the true surface, {:.2} dB over the {:.1}% answered elsewhere; S-T {:.2} dB over the {:.1}% sky, {:.2} dB over the {:.1}% surfaces no layer holds",
                mp(synth_img, &oo, &same),
                frac(&same),
                mp(synth_img, &oo, &other),
                frac(&other),
                mp(synth_img, &truth, &sky),
                frac(&sky),
                mp(synth_img, &truth, &unheld),
                frac(&unheld),
            );
            if s > 1 {
                let t = box_filter(&truth, s).unwrap();
                let f = |a: &Image<Rgb>| score(&box_filter(a, s).unwrap(), &t).unwrap().psnr;
                println!(
                    "  box-filtered to the tile: S-T {:.2}, R-T {:.2}, O-T {:.2} dB",
                    f(synth_img),
                    f(&rr),
                    f(&oo)
                );
            }
        }
    }
}
