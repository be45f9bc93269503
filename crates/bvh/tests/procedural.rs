//! BVH queries equal brute force on procedural meshes, including rays along axes and rays lying
//! exactly in box-face planes.

mod common;

use common::*;
use glam::Vec3;
use parallax_bvh::{BuildOptions, Bvh, TraversalStats};
use parallax_core::Ray;
use parallax_scene::TriangleMesh;

/// Both builds (the default SBVH and the object-split tree) answer as brute force; returns the
/// default build's hits.
fn check_mesh(mesh: &TriangleMesh, rays: &[Ray], what: &str) -> usize {
    let mut hits = [0; 2];
    for (k, opts) in [BuildOptions::default(), object_splits()]
        .iter()
        .enumerate()
    {
        let bvh = Bvh::build_with(mesh, opts);
        for r in rays {
            hits[k] += check_closest(&bvh, mesh, r, what).is_some() as usize;
        }
        for r in rays.iter().step_by(7) {
            check_all(&bvh, mesh, r, what);
        }
    }
    assert_eq!(hits[0], hits[1], "{what}");
    hits[0]
}

#[test]
fn random_soups_match_brute_force() {
    for (n, size, seed) in [
        (1usize, 0.5, 1u64),
        (7, 0.3, 2),
        (300, 0.2, 3),
        (5000, 0.05, 4),
    ] {
        let mesh = soup(n, size, seed);
        let rays = random_rays(1500, Vec3::splat(-1.5), Vec3::splat(1.5), seed + 10);
        let hits = check_mesh(&mesh, &rays, &format!("soup {n}"));
        // The comparison is only meaningful if rays actually hit something.
        if n >= 300 {
            assert!(hits > rays.len() / 10, "soup {n}: only {hits} hits");
        }
    }
}

#[test]
fn closed_meshes_and_grid_match_brute_force() {
    let meshes = [
        ("icosphere", icosphere(3)),
        ("uv sphere", uv_sphere(16, 24)),
        ("cube", cube()),
        ("grid", grid(40)),
    ];
    for (name, mesh) in &meshes {
        let rays = random_rays(1500, Vec3::splat(-1.3), Vec3::splat(1.3), 99);
        let hits = check_mesh(mesh, &rays, name);
        assert!(hits > 150, "{name}: only {hits} hits");
    }
}

#[test]
fn build_options_do_not_change_results() {
    let mesh = soup(2000, 0.1, 5);
    let rays = random_rays(500, Vec3::splat(-1.5), Vec3::splat(1.5), 6);
    let shapes = [
        BuildOptions {
            max_leaf_size: 1,
            bins: 2,
            ..Default::default()
        },
        BuildOptions {
            max_leaf_size: 15,
            bins: 32,
            ..Default::default()
        },
        BuildOptions {
            max_leaf_size: 1000,
            bins: 0,
            traversal_cost: f32::NAN,
            intersection_cost: -1.0,
            parallel_threshold: 0,
            ..Default::default()
        },
        // The SAH per triangle (the earlier default), and out-of-range block sizes (clamped).
        BuildOptions {
            sah_block_size: 1,
            max_leaf_size: 4,
            ..Default::default()
        },
        BuildOptions {
            sah_block_size: 0,
            ..Default::default()
        },
        BuildOptions {
            sah_block_size: 100,
            max_leaf_size: 15,
            ..Default::default()
        },
    ];
    // Each shape option with spatial splits (the default) and without.
    let both = shapes.iter().flat_map(|o| {
        [true, false].map(|spatial_splits| BuildOptions {
            spatial_splits,
            ..o.clone()
        })
    });
    let spatial = [
        // Spatial splits: no budget, every overlap (alpha 0), a large budget, invalid values.
        BuildOptions {
            spatial_splits: true,
            split_budget: 0.0,
            ..Default::default()
        },
        BuildOptions {
            spatial_splits: true,
            split_alpha: 0.0,
            split_overlap: 0.0,
            split_budget: 4.0,
            max_leaf_size: 1,
            parallel_threshold: 0,
            ..Default::default()
        },
        BuildOptions {
            spatial_splits: true,
            split_alpha: f32::NAN,
            split_overlap: f32::NAN,
            split_budget: f32::INFINITY,
            bins: 3,
            ..Default::default()
        },
    ];
    for opts in both.chain(spatial) {
        let bvh = Bvh::build_with(&mesh, &opts);
        assert_eq!(bvh.triangle_count(), 2000);
        for r in &rays {
            check_closest(&bvh, &mesh, r, &format!("{opts:?}"));
            check_all(&bvh, &mesh, r, &format!("{opts:?}"));
        }
    }
}

/// `split_overlap`: a spatial split needs the object split's child overlap to exceed that
/// fraction of the node's own area. At 1 no overlap can (it lies inside the node), so nothing
/// is duplicated; lowering it lets more nodes split (here: 16 large triangles across 3000
/// small ones). Every setting answers as brute force.
#[test]
fn split_overlap_limits_the_spatial_splits() {
    let mut mesh = soup(3000, 0.2, 21);
    mesh.append(&soup(16, 1.0, 22), 0);
    let rays = random_rays(400, Vec3::splat(-2.0), Vec3::splat(2.0), 12);
    let refs = |split_overlap: f32| {
        let opts = BuildOptions {
            spatial_splits: true,
            split_overlap,
            ..Default::default()
        };
        let bvh = Bvh::build_with(&mesh, &opts);
        for r in &rays {
            check_closest(&bvh, &mesh, r, &format!("split_overlap {split_overlap}"));
        }
        bvh.reference_count()
    };
    let default = BuildOptions::default().split_overlap;
    let (none, half, dflt) = (refs(1.0), refs(0.5), refs(default));
    assert_eq!(none, 3016);
    assert!(half > none, "{half}");
    assert!(dflt > half, "{dflt} {half}");
}

/// Rays with zero direction components (`inv_dir = ±inf`), many of them lying exactly in the
/// planes of box faces and passing exactly through edges and vertices (`0 * inf = NaN` in the
/// slab test must not cull).
#[test]
fn axis_parallel_rays_on_box_faces_match_brute_force() {
    let mesh = cube_lattice(4);
    let bvh = Bvh::build(&mesh);
    let mut hits = 0;
    let coords: Vec<f32> = (-2..=22).map(|i| i as f32 * 0.5).collect();
    for axis in 0..3 {
        for sign in [1.0f32, -1.0] {
            for &a in &coords {
                for &b in &coords {
                    let mut o = Vec3::ZERO;
                    o[axis] = if sign > 0.0 { -5.0 } else { 15.0 };
                    o[(axis + 1) % 3] = a;
                    o[(axis + 2) % 3] = b;
                    // +0 and -0 in the zero components.
                    for zero in [0.0f32, -0.0] {
                        let mut d = Vec3::splat(zero);
                        d[axis] = sign;
                        let r = Ray::new(o, d);
                        hits += check_closest(&bvh, &mesh, &r, "lattice").is_some() as usize;
                    }
                }
            }
        }
    }
    assert!(hits > 500, "only {hits} hits");
    // Rays in a face plane with two non-zero components, and rays starting on a face.
    let mut rng = Rng::new(3);
    for _ in 0..2000 {
        let mut o = rng.vec3_in(Vec3::splat(-1.0), Vec3::splat(10.0));
        let mut d = rng.dir();
        let k = (rng.next_u32() % 3) as usize;
        // Snap one coordinate to a face plane (cube faces lie at 3i +- 0.5).
        o[k] = 3.0 * (rng.next_u32() % 4) as f32 + if rng.f32() < 0.5 { 0.5 } else { -0.5 };
        if rng.f32() < 0.5 {
            d[k] = 0.0;
        }
        check_closest(&bvh, &mesh, &Ray::new(o, d), "face plane");
    }
    check_all(
        &bvh,
        &mesh,
        &Ray::new(Vec3::new(-5.0, 0.5, 0.5), Vec3::X),
        "edge row",
    );
}

#[test]
fn segments_respect_the_interval() {
    let mesh = icosphere(2);
    let bvh = Bvh::build(&mesh);
    let mut rng = Rng::new(8);
    for _ in 0..500 {
        let o = rng.vec3_in(Vec3::splat(-2.0), Vec3::splat(2.0));
        let d = rng.dir();
        let (t0, t1) = (rng.range(-1.0, 2.0), rng.range(0.0, 4.0));
        let r = Ray::segment(o, d, t0, t1);
        if let Some(h) = check_closest(&bvh, &mesh, &r, "segment") {
            assert!(h.t > t0 && h.t < t1);
        }
        check_all(&bvh, &mesh, &r, "segment");
    }
}

#[test]
fn empty_and_single_triangle_meshes() {
    let empty = TriangleMesh::default();
    let bvh = Bvh::build(&empty);
    assert_eq!(bvh.node_count(), 0);
    assert!(bvh.bounds().is_empty());
    let r = Ray::new(Vec3::ZERO, Vec3::X);
    assert!(bvh.closest_hit(&r).is_none());
    assert!(!bvh.any_hit(&r));
    let mut out = vec![];
    bvh.all_hits(&r, &mut out);
    assert!(out.is_empty());

    let one = mesh_from(
        vec![
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(0.0, 1.0, -1.0),
        ],
        vec![[0, 1, 2]],
    );
    let bvh = Bvh::build(&one);
    assert_eq!(bvh.node_count(), 1);
    let h = bvh
        .closest_hit(&Ray::new(Vec3::new(0.25, 0.5, 0.0), -Vec3::Z))
        .unwrap();
    assert_eq!(h.prim, 0);
    assert!((h.t - 1.0).abs() < 1e-6 && (h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6);
    assert!(
        bvh.closest_hit(&Ray::new(Vec3::new(0.75, 0.5, 0.0), -Vec3::Z))
            .is_none()
    );
}

#[test]
fn degenerate_triangles_and_invalid_rays_never_panic() {
    // Points, segments and coincident triangles.
    let mut p = vec![Vec3::ONE; 30];
    p.extend((0..30).map(|i| Vec3::new(i as f32, 0.0, 0.0)));
    p.extend([Vec3::ZERO, Vec3::X, Vec3::Y]);
    let mut idx: Vec<[u32; 3]> = (0..10).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    idx.extend((0..10).map(|i| [30 + 3 * i, 31 + 3 * i, 32 + 3 * i]));
    idx.extend((0..50).map(|_| [60, 61, 62]));
    let mesh = mesh_from(p, idx);
    let bvh = Bvh::build(&mesh);
    let rays = random_rays(500, Vec3::splat(-1.0), Vec3::splat(2.0), 1);
    for r in &rays {
        check_closest(&bvh, &mesh, r, "degenerate");
    }
    let h = bvh
        .closest_hit(&Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z))
        .unwrap();
    assert!((h.t - 1.0).abs() < 1e-6);
    let mut out = vec![];
    bvh.all_hits(&Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z), &mut out);
    assert_eq!(out.len(), 50);
    for bad in [
        Ray::new(Vec3::NAN, Vec3::X),
        Ray::new(Vec3::ZERO, Vec3::ZERO),
        Ray::new(Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0)),
        Ray::segment(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, 2.0, 1.0),
        Ray::segment(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, f32::NAN, 1.0),
    ] {
        assert!(bvh.closest_hit(&bad).is_none());
        assert!(!bvh.any_hit(&bad));
        bvh.all_hits(&bad, &mut out);
        assert!(out.is_empty());
    }
}

/// The object-split build (`spatial_splits: false`, the CLI's `--no-spatial-splits`).
fn object_splits() -> BuildOptions {
    BuildOptions {
        spatial_splits: false,
        ..Default::default()
    }
}

/// The tree's structure, for either build: children after parents in both trees, every inner
/// child's box its node's bounds, leaves within the size bound, the 8-wide tree over the same
/// leaves (each entry of `triangles()` in exactly one 8-wide leaf), and per 4-wide leaf box
/// `b` and triangle of the leaf: the triangle's box meets `b`, and `b` lies inside the union
/// of the leaf's triangle boxes (a leaf's box is the union of its references' boxes, each
/// inside its triangle's box: the whole box in the object-split build, a clipped piece of it
/// after a spatial split). Returns the 4-wide leaf boxes holding each primitive.
fn check_structure(bvh: &Bvh, mesh: &TriangleMesh) -> Vec<Vec<parallax_core::Aabb>> {
    let max_leaf = BuildOptions::default().max_leaf_size as u32;
    let mut leaf_boxes = vec![Vec::new(); mesh.triangle_count()];
    for (i, n) in bvh.nodes().iter().enumerate() {
        assert!((1..=4).contains(&n.num_children));
        for lane in 0..n.num_children as usize {
            let b = n.child_bounds(lane);
            match parallax_bvh::ChildRef::decode(n.child[lane]) {
                parallax_bvh::ChildRef::Inner(c) => {
                    assert!(c as usize > i);
                    assert_eq!(bvh.nodes()[c as usize].bounds(), b);
                }
                parallax_bvh::ChildRef::Leaf { first, count } => {
                    assert!((1..=max_leaf).contains(&count));
                    let mut union = parallax_core::Aabb::EMPTY;
                    for k in bvh.leaf_triangles(first, count) {
                        let tb = bvh.triangles()[k].bounds();
                        assert!(
                            tb.min.cmple(b.max).all() && b.min.cmple(tb.max).all(),
                            "leaf box {b:?} misses its triangle's box {tb:?}"
                        );
                        union = union.union(tb);
                        leaf_boxes[bvh.prim_ids()[k] as usize].push(b);
                    }
                    assert!(union.contains(b.min) && union.contains(b.max));
                }
            }
        }
    }
    let mut seen8 = vec![0u32; bvh.triangles().len()];
    for (i, n) in bvh.nodes8().iter().enumerate() {
        assert!((1..=8).contains(&n.num_children));
        for lane in 0..8 {
            let b = n.child_bounds(lane);
            if lane >= n.num_children as usize {
                assert!(b.is_empty() && n.child[lane] == parallax_bvh::node::EMPTY);
                continue;
            }
            match parallax_bvh::ChildRef::decode(n.child[lane]) {
                parallax_bvh::ChildRef::Inner(c) => {
                    assert!(c as usize > i);
                    assert_eq!(bvh.nodes8()[c as usize].bounds(), b);
                }
                parallax_bvh::ChildRef::Leaf { first, count } => {
                    for t in bvh.leaf_triangles(first, count) {
                        seen8[t] += 1;
                        let tb = bvh.triangles()[t].bounds();
                        assert!(tb.min.cmple(b.max).all() && b.min.cmple(tb.max).all());
                    }
                }
            }
        }
    }
    assert!(seen8.iter().all(|&c| c == 1));
    assert_eq!(bvh.nodes8()[0].bounds(), mesh.bounds());
    assert_eq!(bvh.bounds(), mesh.bounds());
    leaf_boxes
}

/// The object-split build (`spatial_splits: false`): every triangle in exactly one leaf, whose
/// box holds the whole triangle; the trees' sizes and the traversal's work counts.
#[test]
fn structure_invariants_and_stats() {
    let mesh = soup(3000, 0.05, 11);
    let bvh = Bvh::build_with(&mesh, &object_splits());
    let leaf_boxes = check_structure(&bvh, &mesh);
    assert_eq!(bvh.reference_count(), 3000);
    for (p, boxes) in leaf_boxes.iter().enumerate() {
        assert_eq!(boxes.len(), 1, "triangle {p}");
        let tb = parallax_core::Aabb::from_points(mesh.triangle(p));
        assert!(boxes[0].contains(tb.min) && boxes[0].contains(tb.max));
    }
    // (261 vs 354 nodes here: leaves of up to eight leave fewer 4-wide nodes to merge.)
    assert!(
        bvh.nodes8().len() * 4 < bvh.node_count() * 3,
        "8-wide is not wider: {} vs {}",
        bvh.nodes8().len(),
        bvh.node_count()
    );
    assert!(bvh.bytes() >= bvh.node_count() * 128 + 3000 * 40);
    // A 4-wide tree over 3000 triangles in leaves of <= 8 needs at least 94 nodes; SAH trees
    // are far from degenerate (depth well below the object count).
    assert!(
        bvh.node_count() >= 94 && bvh.depth() <= 20,
        "{} {}",
        bvh.node_count(),
        bvh.depth()
    );
    check_stats(&bvh);
}

/// The traversal's work counts on 1000 random rays: the stats variants answer as the plain
/// queries, the 8-wide tree visits fewer nodes than the 4-wide one, culling works.
fn check_stats(bvh: &Bvh) {
    let rays = random_rays(1000, Vec3::splat(-1.5), Vec3::splat(1.5), 12);
    let mut s = TraversalStats::default();
    let mut any = TraversalStats::default();
    for r in &rays {
        assert_eq!(bvh.closest_hit_with_stats(r, &mut s), bvh.closest_hit(r));
        assert_eq!(bvh.any_hit_with_stats(r, &mut any), bvh.any_hit(r));
    }
    assert_eq!(s.rays, 1000);
    assert!(s.box_tests >= s.nodes_visited && s.box_tests <= 8 * s.nodes_visited);
    let mut s4 = TraversalStats::default();
    for r in &rays {
        assert_eq!(bvh.closest_hit4_with_stats(r, &mut s4), bvh.closest_hit(r));
    }
    assert!(s4.box_tests >= s4.nodes_visited && s4.box_tests <= 4 * s4.nodes_visited);
    assert!(s.nodes_visited < s4.nodes_visited, "{s:?} vs {s4:?}");
    // Culling works: far fewer triangle tests than brute force (3000 per ray), and an any-hit
    // query does no more work than a closest-hit query.
    assert!(s.per_ray(s.triangle_tests) < 150.0, "{s:?}");
    assert!(any.triangle_tests <= s.triangle_tests, "{any:?} vs {s:?}");
}

/// The default build, the SBVH (`spatial_splits: true`), on a mesh whose large triangles it
/// splits: every triangle in at least one leaf, the copies within the duplication budget
/// (`n + split_budget n` references), and every point of a triangle inside the box of a leaf
/// holding it (the pieces' boxes cover the triangle: what makes the traversal exact, module
/// docs of `build/spatial.rs`), checked at the vertices, edge midpoints, centroid and random
/// points, with a tolerance of 1e-6 of the scene size for the rounding of the points.
#[test]
fn sbvh_structure_invariants() {
    assert!(BuildOptions::default().spatial_splits);
    let mut mesh = soup(3000, 0.2, 21);
    mesh.append(&soup(16, 1.0, 22), 0);
    let n = mesh.triangle_count();
    let bvh = Bvh::build(&mesh);
    let leaf_boxes = check_structure(&bvh, &mesh);
    let budget = BuildOptions::default().split_budget;
    assert!(bvh.reference_count() > n, "no reference was split");
    assert!(bvh.reference_count() <= n + (n as f64 * budget as f64) as usize);
    assert_eq!(bvh.triangle_count(), n);
    let tol = 1e-6 * mesh.bounds().extent().max_element();
    let mut rng = Rng::new(23);
    let mut split = 0;
    for (p, boxes) in leaf_boxes.iter().enumerate() {
        assert!(!boxes.is_empty(), "triangle {p} in no leaf");
        split += (boxes.len() > 1) as usize;
        let [a, b, c] = mesh.triangle(p);
        let mut points = vec![a, b, c, (a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5];
        points.push((a + b + c) / 3.0);
        for _ in 0..20 {
            let (u, v) = (rng.f32(), rng.f32());
            let (u, v) = if u + v > 1.0 {
                (1.0 - u, 1.0 - v)
            } else {
                (u, v)
            };
            points.push(a + (b - a) * u + (c - a) * v);
        }
        for q in points {
            assert!(
                boxes
                    .iter()
                    .any(|bx| (q - bx.min).min_element() >= -tol
                        && (bx.max - q).min_element() >= -tol),
                "triangle {p}: point {q} in none of its {} leaf boxes",
                boxes.len()
            );
        }
    }
    assert!(split > 0);
    check_stats(&bvh);
}

/// The SAH in blocks of four (the default) packs leaves to the 4-triangle blocks the traversal
/// tests: on a triangle soup it needs fewer nodes and fewer blocks than the SAH per triangle
/// with leaves of at most four (measured on the scenes: about 40% fewer of both), and both
/// trees answer every query as brute force does (above).
#[test]
fn sah_in_blocks_packs_leaves() {
    let mesh = soup(4000, 0.05, 11);
    let per_tri = Bvh::build_with(
        &mesh,
        &BuildOptions {
            sah_block_size: 1,
            max_leaf_size: 4,
            ..Default::default()
        },
    );
    let blocks = Bvh::build(&mesh);
    let (n1, n4) = (per_tri.nodes8().len(), blocks.nodes8().len());
    let (b1, b4) = (per_tri.blocks().len(), blocks.blocks().len());
    assert!(
        n4 < n1 && b4 < b1,
        "nodes8 {n1} -> {n4}, blocks {b1} -> {b4}"
    );
    // Lanes used: the references over four lanes per block.
    let fill = |b: &Bvh| b.reference_count() as f64 / (4 * b.blocks().len()) as f64;
    assert!(
        fill(&blocks) > fill(&per_tri),
        "{} vs {}",
        fill(&per_tri),
        fill(&blocks)
    );
}

/// `Bvh::block_copies` marks exactly the block lanes whose triangle id sits in more than one
/// lane of the blocks (the SBVH's split triangles), and is empty for the object-split tree
/// (every triangle once); a refit keeps it.
#[test]
fn block_copies_mark_the_split_triangles() {
    let mut mesh = soup(3000, 0.2, 21);
    mesh.append(&soup(16, 1.0, 22), 0);
    let bvh = Bvh::build(&mesh);
    assert!(bvh.reference_count() > mesh.triangle_count());
    let mut count = vec![0u32; mesh.triangle_count()];
    for b in bvh.blocks() {
        for &id in b.tri.iter().filter(|&&id| id != u32::MAX) {
            count[id as usize] += 1;
        }
    }
    let copies = bvh.block_copies();
    assert_eq!(copies.len(), bvh.blocks().len());
    let mut marked = 0;
    for (b, &m) in bvh.blocks().iter().zip(copies) {
        for l in 0..4 {
            let want = b.tri[l] != u32::MAX && count[b.tri[l] as usize] > 1;
            assert_eq!(m >> l & 1 != 0, want, "{:?} lane {l}", b.tri);
            marked += want as usize;
        }
        assert_eq!(m >> 4, 0);
    }
    assert!(marked > 0);
    let mut refit = bvh.clone();
    refit.refit(&mesh).unwrap();
    assert_eq!(refit.block_copies(), copies);
    let plain = Bvh::build_with(
        &mesh,
        &BuildOptions {
            spatial_splits: false,
            ..BuildOptions::default()
        },
    );
    assert!(plain.block_copies().is_empty());
}
