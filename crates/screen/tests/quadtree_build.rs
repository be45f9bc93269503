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
