//! Lossy (default) pruning, §3.3: the tree still equals brute force over its *own* decoded
//! planes (every pixel of a merged node carrying the proxy plane), agrees with brute force
//! over the original per-pixel planes on a high fraction of rays (measured), and prunes.
//! Also depth-reconstructed normals (flag `O`, crack dilation).

mod quadtree_util;

use parallax_raster::{RasterOptions, View, capture_layers};
use parallax_scene::{Scene, camera::Pinhole};
use parallax_screen::{
    BruteForcePlanes, LayerPlanes, NormalSource, QuadTreeOptions, QuadTreeTracer,
};
use quadtree_util::*;

fn capture(name: &str, w: u32, h: u32) -> (Pinhole, Vec<parallax_core::GBuffer>) {
    let scene = Scene::load(name).unwrap();
    let cam = Pinhole::new(&scene.camera(None).unwrap(), w, h).unwrap();
    let cap = capture_layers(
        &scene,
        &View::from_pinhole(&cam).unwrap(),
        &RasterOptions::layers(1),
    )
    .unwrap();
    (cam, cap.layers.layers.clone())
}

#[test]
fn lossy_tree_equals_its_twin_and_mostly_the_original_planes() {
    for (name, w, h) in [("atrium", 160, 90), ("cornell", 96, 72)] {
        let (cam, layers) = capture(name, w, h);
        let cube = cube(&cam, &layers);
        let orig = BruteForcePlanes {
            cube: cube.clone(),
            layers: vec![LayerPlanes::build(&cube, &layers[0], NormalSource::GBuffer).unwrap()],
        };
        let lossless =
            QuadTreeTracer::build(&cube, &layers, &exact(QuadTreeOptions::lossless())).unwrap();
        for (label, opts) in [
            ("default", QuadTreeOptions::default()),
            (
                "adaptive",
                QuadTreeOptions {
                    adaptive: true,
                    ..Default::default()
                },
            ),
            (
                "aggressive",
                QuadTreeOptions {
                    gamma_norm: 10f32.to_radians().cos(),
                    gamma_dist: 1e-3,
                    ..Default::default()
                },
            ),
        ] {
            let qt = QuadTreeTracer::build(&cube, &layers, &exact(opts)).unwrap();
            let t0 = &qt.trees[0];
            assert!(
                t0.node_count() < lossless.trees[0].node_count(),
                "{name} {label}: no pruning"
            );
            let bf = twin(&qt);
            let mut all = rays(&cam, &layers[0], 1500, 0.3, 4);
            all.extend(stereo_rays(&cam, 0.0325));
            let (t, first, st) = run(&qt, &bf, &all, 1e-4);
            assert_eq!(t.differ, 0, "{name} {label}: {t:?} {first:?}");
            assert!(t.edge * 100 <= t.total(), "{t:?}");
            // Against the original planes: kinds/pixels mostly agree; t within 1e-3.
            let (o, _, _) = run(&qt, &orig, &all, 1e-3);
            let frac = (o.equal + o.edge) as f64 / o.total() as f64;
            let (_, _, sl) = run(&lossless, &bf, &all, 1e-4);
            eprintln!(
                "{name} {label}: nodes {} (lossless {}), plane nodes {}, agreement with original planes {:.2}%, nodes/ray {:.2} (lossless {:.2})",
                t0.node_count(),
                lossless.trees[0].node_count(),
                t0.plane_node_count(),
                100.0 * frac,
                st.nodes_visited as f64 / st.rays as f64,
                sl.nodes_visited as f64 / sl.rays as f64,
            );
            if label != "aggressive" {
                assert!(frac > 0.97, "{name} {label}: {frac}");
            }
        }
    }
}

#[test]
fn depth_normals_crack_dilation() {
    let (cam, layers) = capture("atrium", 160, 90);
    let cube = cube(&cam, &layers);
    let depth = NormalSource::Depth {
        max_rel_error: 0.01,
    };
    // Without dilation: exactly the quantised depth-normal planes.
    let exact = QuadTreeOptions {
        normals: depth,
        crack_dilation: 0.0,
        ..QuadTreeOptions::lossless()
    };
    let qt = QuadTreeTracer::build(&cube, &layers, &exact).unwrap();
    let flagged = qt.trees[0]
        .effective_planes()
        .flag
        .iter()
        .filter(|f| **f)
        .count();
    assert!(flagged > 0);
    let bf = twin(&qt);
    let all = rays(&cam, &layers[0], 1500, 0.3, 8);
    let (t, first, _) = run(&qt, &bf, &all, 1e-4);
    assert_eq!(t.differ, 0, "{t:?} {first:?}");
    // With dilation: flagged planes are hit slightly outside their footprints, so some
    // occlusion entries / misses at cracks become hits; everything else is unchanged.
    let dil = QuadTreeTracer::build(
        &cube,
        &layers,
        &QuadTreeOptions {
            crack_dilation: 0.5,
            ..exact
        },
    )
    .unwrap();
    let (d, _, _) = run(&dil, &bf, &all, 1e-4);
    eprintln!("depth normals: {flagged} flagged px; dilated vs exact {d:?}, exact {t:?}");
    assert!(d.hits >= t.hits, "{d:?} vs {t:?}");
    assert!(d.differ * 10 < d.total(), "{d:?}");
}
