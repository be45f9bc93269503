//! Flag `O` (Widmer et al. 2015, §3.2) with G-buffer normals
//! ([`NormalSource::GBufferFlagged`], [`parallax_screen::planes::crack_flags`]):
//! set on both sides of a depth step and next to uncovered pixels, not on a tilted flat
//! floor; the quad-tree's leaves carry the same flags as [`LayerPlanes`].

mod quadtree_util;

use glam::{Vec2, Vec3};
use parallax_core::GBuffer;
use parallax_screen::{LayerPlanes, NormalSource, QuadTreeOptions, QuadTreeTracer};
use quadtree_util::*;

const W: u32 = 64;
const H: u32 = 48;
/// The foreground square (pixels `[X0, X1) x [Y0, Y1)`).
const X0: u32 = 20;
const X1: u32 = 40;
const Y0: u32 = 15;
const Y1: u32 = 30;

/// A tilted floor-like plane through (0, 0, -6) with a fronto-parallel square at depth 2 in
/// front of it; exact G-buffer normals. `hole`: one uncovered pixel on the floor.
fn scene(hole: Option<(u32, u32)>) -> (parallax_scene::camera::Pinhole, GBuffer) {
    let cam = camera(W, H);
    let mut g = GBuffer::new(W, H).unwrap();
    let n_floor = Vec3::new(0.0, 0.6, 1.0).normalize();
    let c_floor = n_floor.dot(Vec3::new(0.0, 0.0, -6.0));
    for j in 0..H {
        for i in 0..W {
            if hole == Some((i, j)) {
                continue;
            }
            let k = (j * W + i) as usize;
            let r = film_dir(&cam, Vec2::new(i as f32 + 0.5, j as f32 + 0.5));
            let fwd = cam.frame.forward();
            let (d, n) = if (X0..X1).contains(&i) && (Y0..Y1).contains(&j) {
                (2.0, Vec3::Z)
            } else {
                let t = c_floor / n_floor.dot(r);
                (t * r.dot(fwd), n_floor)
            };
            g.depth[k] = d;
            g.normal[k] = n;
            g.position[k] = cam.frame.position + r * (d / r.dot(fwd));
        }
    }
    (cam, g)
}

/// Pixels within one pixel (8-neighbourhood) of the square's boundary, on either side.
fn near_edge(i: u32, j: u32) -> bool {
    let inside =
        |i: i64, j: i64| (X0 as i64..X1 as i64).contains(&i) && (Y0 as i64..Y1 as i64).contains(&j);
    let me = inside(i as i64, j as i64);
    (-1..=1).any(|dy| (-1..=1).any(|dx| inside(i as i64 + dx, j as i64 + dy) != me))
}

#[test]
fn gbuffer_flags_at_depth_step_not_on_flat_floor() {
    let (cam, g) = scene(None);
    let cube = cube(&cam, std::slice::from_ref(&g));
    let plain = LayerPlanes::build(&cube, &g, NormalSource::GBuffer).unwrap();
    assert!(
        plain.flag.iter().all(|f| !f),
        "plain G-buffer normals flag nothing"
    );
    let planes = LayerPlanes::build(&cube, &g, NormalSource::gbuffer_flagged()).unwrap();
    let mut flagged_edge = 0;
    for j in 0..H {
        for i in 0..W {
            let k = (j * W + i) as usize;
            let f = planes.flag[k];
            // 4-neighbours across the step: always flagged.
            let step4 = [(1i64, 0i64), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .any(|(dx, dy)| {
                    let (x, y) = (i as i64 + dx, j as i64 + dy);
                    let inside = |i: i64, j: i64| {
                        (X0 as i64..X1 as i64).contains(&i) && (Y0 as i64..Y1 as i64).contains(&j)
                    };
                    x >= 0
                        && y >= 0
                        && x < W as i64
                        && y < H as i64
                        && inside(x, y) != inside(i as i64, j as i64)
                });
            if step4 {
                assert!(f, "pixel ({i}, {j}) at the depth step is not flagged");
                flagged_edge += 1;
            } else if !near_edge(i, j) {
                assert!(!f, "pixel ({i}, {j}) on a flat surface is flagged");
            }
        }
    }
    // Both sides of the square's four edges (the four inside corner pixels touch two edges).
    assert_eq!(flagged_edge, (4 * ((X1 - X0) + (Y1 - Y0)) - 4) as usize);

    // The quad-tree leaves (decoded f16 planes) carry the same flags.
    let qt = QuadTreeTracer::build(
        &cube,
        std::slice::from_ref(&g),
        &QuadTreeOptions {
            normals: NormalSource::gbuffer_flagged(),
            ..QuadTreeOptions::lossless()
        },
    )
    .unwrap();
    let eff = qt.trees[0].effective_planes();
    assert_eq!(eff.flag, planes.flag);

    // A finite upper gap bound (cracks only) leaves the depth step unflagged.
    let cracks_only = NormalSource::GBufferFlagged {
        min_rel_gap: 1e-4,
        max_rel_gap: 1e-2,
    };
    let p2 = LayerPlanes::build(&cube, &g, cracks_only).unwrap();
    assert!(p2.flag.iter().all(|f| !f));
}

#[test]
fn gbuffer_flags_next_to_uncovered_pixel() {
    let (cam, g) = scene(Some((5, 5)));
    let cube = cube(&cam, std::slice::from_ref(&g));
    let planes = LayerPlanes::build(&cube, &g, NormalSource::gbuffer_flagged()).unwrap();
    let f = |i: u32, j: u32| planes.flag[(j * W + i) as usize];
    assert!(!f(5, 5), "an uncovered pixel has no flag");
    for (i, j) in [(4, 5), (6, 5), (5, 4), (5, 6)] {
        assert!(f(i, j), "({i}, {j}) next to the hole");
    }
    assert!(
        !f(4, 4) && !f(6, 6) && !f(8, 5),
        "diagonal / farther pixels"
    );
}
