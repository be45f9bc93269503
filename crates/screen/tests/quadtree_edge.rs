//! Termination and defined results for awkward rays (Widmer et al. 2015, §4 traversal with a
//! hard step bound): rays leaving the frustum, parallel to the image plane, through empty
//! pixels, starting behind the near plane or the camera, along pixel boundaries, NaN/inf,
//! zero-size and reversed segments — in both modes, with 1 and 2 layers. Each result must
//! equal brute force over the decoded planes (or be `Miss` for invalid rays), and the work
//! must stay under the step bound.

mod quadtree_util;

use glam::Vec3;
use parallax_core::{GBuffer, Ray};
use parallax_screen::{
    LayerMode, QuadTreeOptions, QuadTreeTracer, ScreenTracer, TraceResult, TraceStats, UnitCube,
};
use quadtree_util::*;

fn awkward_rays(qt: &QuadTreeTracer) -> Vec<Ray> {
    let c = &qt.cube;
    let cam = &c.camera;
    let eye = cam.frame.position;
    let fwd = cam.frame.forward();
    let right = cam.frame.right();
    let up = cam.frame.up();
    let mut v = vec![
        // Leaving the frustum / never entering it.
        Ray::new(eye, -fwd),
        Ray::new(eye + fwd * 3.0, right),
        Ray::new(eye + fwd * 3.0, up),
        Ray::new(eye + fwd * 3.0, -right + up * 0.5),
        Ray::new(eye + right * 100.0, fwd),
        // Parallel to the image plane, inside the frustum.
        Ray::new(eye + fwd * 2.5 - right * 0.5, right),
        Ray::new(eye + fwd * 4.0 + up * 0.3, -up),
        // Starting behind the camera and behind the near plane.
        Ray::new(eye - fwd * 2.0, fwd),
        Ray::new(
            eye - fwd * 2.0 + right * 0.2,
            (fwd + right * 0.1).normalize(),
        ),
        Ray::new(eye + fwd * (c.near * 0.5), (fwd - up * 0.2).normalize()),
        Ray::new(eye, fwd),
        // Along pixel boundaries (x = 1/2 of an even width, y = 1/4).
        Ray::new(
            c.to_world(Vec3::new(0.5, 0.5, 0.1)),
            (c.to_world(Vec3::new(0.5, 0.25, 0.95)) - c.to_world(Vec3::new(0.5, 0.5, 0.1)))
                .normalize(),
        ),
        Ray::new(
            c.to_world(Vec3::new(0.25, 0.5, 0.0)),
            (c.to_world(Vec3::new(0.25, 0.5, 1.0)) - c.to_world(Vec3::new(0.25, 0.5, 0.0)))
                .normalize(),
        ),
        // Zero-size, reversed, tiny and bounded segments.
        Ray::segment(eye, fwd, 3.0, 3.0),
        Ray::segment(eye, fwd, 5.0, 2.0),
        Ray::segment(eye, fwd, 2.0, 2.0 + 1e-6),
        Ray::segment(eye, fwd, 0.0, 0.1),
        Ray::segment(eye + right * 0.03, fwd, -5.0, 1e30),
    ];
    // Grazing rays along the image diagonal.
    for k in 0..8 {
        let a = k as f32 * 0.785;
        v.push(Ray::new(
            eye + fwd * 1.5,
            (right * a.cos() + up * a.sin() + fwd * 0.05).normalize(),
        ));
    }
    v
}

fn invalid_rays() -> Vec<Ray> {
    vec![
        Ray::new(Vec3::ZERO, Vec3::new(f32::NAN, 0.0, -1.0)),
        Ray::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::new(0.0, 0.0, -1.0)),
        Ray::new(Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, -1.0)),
        Ray::new(Vec3::new(0.0, f32::NEG_INFINITY, 0.0), -Vec3::Z),
        Ray::new(Vec3::ZERO, Vec3::ZERO),
        Ray::segment(Vec3::ZERO, -Vec3::Z, f32::NAN, 1.0),
        Ray::segment(Vec3::ZERO, -Vec3::Z, 0.0, f32::NAN),
    ]
}

fn check(layers: &[GBuffer], w: u32, h: u32, mode: LayerMode) {
    let cam = camera(w, h);
    let cube = UnitCube::fit_depths(&cam, layers.iter().map(|g| &g.depth[..]))
        .unwrap_or_else(|_| UnitCube::new(&cam, 0.25, 30.0).unwrap());
    let opts = exact(QuadTreeOptions {
        mode,
        ..QuadTreeOptions::lossless()
    });
    let qt = QuadTreeTracer::build(&cube, layers, &opts).unwrap();
    let bf = twin(&qt);
    let levels = qt.trees[0].level_count() as u64;
    let bound = (w as u64 + h as u64 + 2) * (2 * levels + 2) * layers.len() as u64;
    for r in invalid_rays() {
        let mut s = TraceStats::default();
        assert_eq!(qt.trace(&r, &mut s), TraceResult::Miss, "{r:?}");
    }
    let rays = awkward_rays(&qt);
    for r in &rays {
        let mut s = TraceStats::default();
        let a = qt.trace(r, &mut s);
        assert!(s.steps <= bound, "{r:?}: {} steps > {bound}", s.steps);
        if mode == LayerMode::Cascade {
            let b = bf.trace(r, &mut TraceStats::default());
            assert_ne!(
                compare(&a, &b, 1e-4),
                Verdict::Differ,
                "{r:?}: {a:?} vs {b:?}"
            );
        }
    }
    if mode == LayerMode::Cascade {
        let (t, first, _) = run(&qt, &bf, &rays, 1e-4);
        assert_eq!(t.differ, 0, "{first:?}");
    }
}

#[test]
fn awkward_rays_terminate_with_brute_force_results() {
    for (w, h) in [(38, 24), (64, 48), (1, 1), (3, 70)] {
        let cam = camera(w, h);
        let g0 = height_field(&cam, 5, 0.3);
        let mut g1 = g0.clone();
        for d in g1.depth.iter_mut() {
            *d += 0.7;
        }
        for mode in [LayerMode::Cascade, LayerMode::Inpaint] {
            check(std::slice::from_ref(&g0), w, h, mode);
            check(&[g0.clone(), g1.clone()], w, h, mode);
        }
    }
}

#[test]
fn empty_layer_misses_everything() {
    let cam = camera(40, 30);
    let g = height_field(&cam, 1, 0.0);
    let cube = cube(&cam, std::slice::from_ref(&g));
    let empty = GBuffer::new(40, 30).unwrap();
    let qt = QuadTreeTracer::build(&cube, &[empty], &QuadTreeOptions::default()).unwrap();
    assert_eq!(qt.trees[0].node_count(), 0);
    let mut s = TraceStats::default();
    for r in rays(&cam, &g, 200, 0.3, 1) {
        assert_eq!(qt.trace(&r, &mut s), TraceResult::Miss);
    }
    assert!(s.nodes_visited <= 200 * 16, "{s:?}");
}

#[test]
fn build_rejects_mismatched_sizes_and_bad_options() {
    let cam = camera(40, 30);
    let g = height_field(&cam, 1, 0.0);
    let cube = cube(&cam, std::slice::from_ref(&g));
    let other = GBuffer::new(41, 30).unwrap();
    assert!(QuadTreeTracer::build(&cube, &[other], &QuadTreeOptions::default()).is_err());
    assert!(QuadTreeTracer::build(&cube, &[], &QuadTreeOptions::default()).is_err());
    let bad = QuadTreeOptions {
        crack_dilation: f32::NAN,
        ..Default::default()
    };
    assert!(QuadTreeTracer::build(&cube, std::slice::from_ref(&g), &bad).is_err());
    // max_levels 0 and huge are clamped.
    for max_levels in [0, 1, 100] {
        let o = QuadTreeOptions {
            max_levels,
            ..Default::default()
        };
        let qt = QuadTreeTracer::build(&cube, std::slice::from_ref(&g), &o).unwrap();
        assert!((1..=7).contains(&qt.trees[0].level_count()));
    }
}
