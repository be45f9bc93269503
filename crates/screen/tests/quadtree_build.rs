//! The quad-tree build's fast paths equal their definitions bit for bit: the per-pixel
//! effective plane level (top-down, one pass per level) and the effective planes (each merged
//! node decoded once per row) against the per-pixel climb of `QuadTree::effective_node`, on
//! lossy trees of random height fields, one layer and the two-layer cascade (whose pruning
//! fixed point runs on the fast effective planes).

mod quadtree_util;

use parallax_screen::{LayerPlanes, QuadTree, QuadTreeOptions, QuadTreeTracer};
use quadtree_util::*;

fn same_planes(a: &LayerPlanes, b: &LayerPlanes) -> bool {
    a.width == b.width
        && a.height == b.height
        && a.flag == b.flag
        && a.offset
            .iter()
            .map(|o| o.to_bits())
            .eq(b.offset.iter().map(|o| o.to_bits()))
        && a.normal
            .iter()
            .flat_map(|n| n.to_array().map(f32::to_bits))
            .eq(b.normal.iter().flat_map(|n| n.to_array().map(f32::to_bits)))
}

fn check(t: &QuadTree, what: &str) -> usize {
    let fast = t.effective_planes();
    let slow = t.effective_planes_by_climbing();
    assert!(same_planes(&fast, &slow), "{what}: effective planes differ");
    let (w, h) = (fast.width, fast.height);
    let mut merged = 0;
    for j in 0..h {
        for i in 0..w {
            let want = t.effective_node(i, j).map_or(0, |(_, l, _, _)| l as u8);
            assert_eq!(
                t.plane_levels()[(j * w + i) as usize],
                want,
                "{what}: ({i},{j})"
            );
            merged += (want > 0) as usize;
        }
    }
    merged
}

#[test]
fn fast_effective_levels_and_planes_equal_the_climb() {
    let lossy = QuadTreeOptions {
        gamma_norm: 10f32.to_radians().cos(),
        gamma_dist: 1e-2,
        ..QuadTreeOptions::default()
    };
    let mut merged = 0;
    for (seed, (w, h)) in [(1u64, (37u32, 23u32)), (2, (64, 64)), (3, (50, 17))] {
        let cam = camera(w, h);
        for empty in [0.0, 0.15] {
            let g = height_field(&cam, seed, empty);
            let layers = [g.clone(), behind(&g, seed)];
            let cube = cube(&cam, &layers);
            for opts in [QuadTreeOptions::default(), lossy] {
                let one = QuadTree::build(&cube, &g, &opts).unwrap();
                merged += check(&one, &format!("{seed} {w}x{h} 1 layer"));
                let two = QuadTreeTracer::build(&cube, &layers, &opts).unwrap();
                for (k, t) in two.trees.iter().enumerate() {
                    merged += check(t, &format!("{seed} {w}x{h} 2 layers, tree {k}"));
                }
            }
        }
    }
    // The lossy trees merge: the test covers merged nodes, not only pixel planes.
    assert!(merged > 1000, "{merged} pixels under merged nodes");
}

/// Every field of two trees (nodes, trigger depths, effective levels, floors) bit for bit.
fn same_tree(a: &QuadTree, b: &QuadTree) -> bool {
    // `PartialEq` compares the f32 fields by value: also compare the planes' bits.
    a == b && same_planes(&a.effective_planes(), &b.effective_planes())
}

#[test]
fn fast_build_equals_the_reference_build() {
    let lossy = QuadTreeOptions {
        gamma_norm: 10f32.to_radians().cos(),
        gamma_dist: 1e-2,
        ..QuadTreeOptions::default()
    };
    let loose = QuadTreeOptions {
        gamma_norm: 30f32.to_radians().cos(),
        gamma_dist: 5e-2,
        adaptive: true,
        ..QuadTreeOptions::default()
    };
    let flagged = QuadTreeOptions {
        normals: parallax_screen::NormalSource::GBufferFlagged {
            min_rel_gap: 0.01,
            max_rel_gap: 0.05,
        },
        ..lossy
    };
    let depth = QuadTreeOptions {
        normals: parallax_screen::NormalSource::Depth {
            max_rel_error: 0.05,
        },
        ..lossy
    };
    // Fewer levels than the image needs (`max_levels` 3 and 1: a top level of 4 x 4-pixel
    // nodes, and the leaves alone).
    let shallow = QuadTreeOptions {
        max_levels: 3,
        ..lossy
    };
    let flat = QuadTreeOptions {
        max_levels: 1,
        ..lossy
    };
    let all = [
        QuadTreeOptions::default(),
        QuadTreeOptions::lossless(),
        lossy,
        loose,
        flagged,
        depth,
        shallow,
        flat,
    ];
    let mut trees = 0;
    for (seed, (w, h)) in [
        (4u64, (37u32, 23u32)),
        (5, (64, 64)),
        (6, (50, 17)),
        (7, (96, 40)),
    ] {
        let cam = camera(w, h);
        for empty in [0.0, 0.15] {
            let g = height_field(&cam, seed, empty);
            let g1 = behind(&g, seed);
            let layers = [g.clone(), g1.clone(), behind(&g1, seed + 100)];
            let cube = cube(&cam, &layers);
            for opts in all {
                for n in 1..=3 {
                    let fast = QuadTreeTracer::build(&cube, &layers[..n], &opts).unwrap();
                    let slow = QuadTreeTracer::build_reference(&cube, &layers[..n], &opts).unwrap();
                    for (k, (a, b)) in fast.trees.iter().zip(&slow.trees).enumerate() {
                        assert!(
                            same_tree(a, b),
                            "{seed} {w}x{h} empty {empty} {opts:?}: {n} layers, tree {k}"
                        );
                        trees += 1;
                    }
                }
            }
        }
    }
    assert_eq!(trees, 4 * 2 * 8 * 6);
}
