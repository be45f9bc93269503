//! Depth of field traces a pixel's lens rays through the quad-tree in batches
//! (`QuadTreeTracer::trace_batch`): the image, the work counters and the hit / miss /
//! occlusion counts equal those of tracing the same lens rays one at a time (the loop
//! `render_dof` ran before, written out here), bit for bit, on several scenes, with 1 and 2
//! layers, inpainting, both cube near planes, and `N_pri` below, at and above the batch size;
//! with secondary samples (`N_sec > 1`, whose lens rays `render_dof` traces one at a time)
//! the same image, counters and secondary statistics as this loop too.

use glam::{Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_core::Rgb;
use parallax_core::sampling::Rng;
use parallax_scene::Scene;
use parallax_scene::camera::ThinLens;
use parallax_screen::TraceResult;
use parallax_screen::{CubeNear, TraceStats};
use parallax_synth::Shading;
use parallax_synth::dof::secondary::{LeafPlanes, SecondaryStats};
use parallax_synth::dof::setup::guard_px;
use parallax_synth::dof::{
    DofOptions, DofSetup, DofStructure, LensRays, capture_dof_reference, lens_strata, render_dof,
};
use parallax_synth::method::{Method, MethodOptions};
use parallax_synth::warp::{HitKind, RayWarp};

/// `render_dof` one lens ray at a time (its loop before the batches): image, counters,
/// misses, occlusions, lens rays from layer 1 or deeper, secondary statistics.
fn one_at_a_time(
    st: &DofStructure,
    r: &parallax_synth::layers::Reference,
    lens: &ThinLens,
    o: &DofOptions,
) -> (Vec<Rgb>, TraceStats, u64, u64, u64, SecondaryStats) {
    let tracer = st.tracer();
    let DofStructure::QuadTree(qt) = st else {
        panic!("the quad-tree")
    };
    let sec = LeafPlanes::new(qt, r, o.sigma, o.secondary_resample);
    let mut sec_stats = SecondaryStats::default();
    let per_ray = RayWarp::new(r, &o.warp);
    let lr = LensRays::new(lens);
    let (cols, rows) = lens_strata(o.n_pri);
    let cell = Vec2::new(1.0 / cols as f32, 1.0 / rows as f32);
    let (mut stats, mut misses, mut occl, mut deep) = (TraceStats::default(), 0, 0, 0);
    let mut img = Vec::new();
    for y in 0..lens.pinhole.height {
        for x in 0..lens.pinhole.width {
            let p_focus = lr.focus_point(lens, Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let mut rng = Rng::for_pixel(o.seed, x, y, 0);
            let mut sum = Vec3::ZERO;
            for i in 0..o.n_pri {
                let corner = Vec2::new((i % cols) as f32, (i / cols) as f32);
                let ray = lr.ray(p_focus, (corner + rng.next_vec2()) * cell);
                let (mut c, kind, res) = per_ray.answer(tracer, &ray, &mut stats);
                if let TraceResult::Hit { layer, pixel, .. } = res
                    && o.n_sec > 1
                {
                    c = sec.blend(
                        &per_ray,
                        layer,
                        pixel,
                        c,
                        (1..o.n_sec).map(|_| lr.ray(p_focus, (corner + rng.next_vec2()) * cell)),
                        &mut sec_stats,
                    );
                }
                match kind {
                    HitKind::Miss => misses += 1,
                    HitKind::Occlusion(l) => {
                        occl += 1;
                        deep += (l >= 1) as u64;
                    }
                    HitKind::Hit(l) => deep += (l >= 1) as u64,
                }
                sum += c;
            }
            img.push(sum / o.n_pri as f32);
        }
    }
    (img, stats, misses, occl, deep, sec_stats)
}

#[test]
fn batched_lens_rays_equal_one_at_a_time() {
    for (name, w, h, aperture) in [
        ("atrium", 96, 54, 0.08),
        ("cornell", 64, 48, 0.05),
        ("foliage", 80, 48, 0.1),
        ("mirrors", 64, 40, 0.05),
    ] {
        let scene = Scene::load(name).unwrap();
        let bvh = Bvh::try_build(&scene.mesh).unwrap();
        let lens = ThinLens::new(&scene.camera(None).unwrap(), w, h, aperture, None).unwrap();
        let guard = guard_px(&bvh, &lens);
        let s = DofSetup { lens, guard };
        for layers in [1, 2] {
            let base = capture_dof_reference(&scene, &bvh, &s, layers, Shading::Fixed, 0).unwrap();
            for near in [CubeNear::Fitted, CubeNear::Camera(0.1)] {
                for inpaint in [false, true] {
                    let mut r = base.clone();
                    r.fit_cube(near).unwrap();
                    let mo = MethodOptions {
                        inpaint,
                        cube_near: near,
                        ..MethodOptions::default()
                    };
                    let st = DofStructure::build(Method::QuadTree, &r, &mo).unwrap();
                    for (n_pri, n_sec) in [(3, 1), (8, 1), (11, 1), (3, 4), (8, 2), (11, 3)] {
                        let o = DofOptions {
                            n_pri,
                            n_sec,
                            ..DofOptions::default()
                        };
                        let what = format!(
                            "{name} {layers} layer(s) {near:?} inpaint {inpaint} {n_pri}/{n_sec}"
                        );
                        let d = render_dof(&st, &r, &s.lens, &o).unwrap();
                        let (img, stats, misses, occl, deep, sec) =
                            one_at_a_time(&st, &r, &s.lens, &o);
                        assert_eq!(d.secondary, sec, "{what}");
                        if n_sec > 1 {
                            assert!(sec.samples > 0, "{what}");
                        }
                        assert_eq!(d.image.data(), &img[..], "{what}");
                        assert_eq!(d.stats, stats, "{what}");
                        assert_eq!(
                            (d.misses, d.occlusions, d.deep),
                            (misses, occl, deep),
                            "{what}"
                        );
                        assert!(stats.hits > stats.rays / 2, "{what}: {stats:?}");
                    }
                }
            }
        }
    }
}
