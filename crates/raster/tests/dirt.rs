//! DIRT capture (Vardis et al. 2017, §4.1): conservativeness against the BVH ground truth
//! (every triangle hit by any ray through a cell's footprint is listed there, inside the cell's
//! depth bounds and in the bucket eq. 1 gives for the hit depth), tightness, the mip chain,
//! memory accounting, determinism and bad input.

use glam::{Mat3, Vec2, Vec3};
use parallax_bvh::{Bvh, Hit};
use parallax_core::Rng;
use parallax_raster::dirt::{
    CellDepth, DirtCapture, DirtCube, DirtError, DirtOptions, DirtViews, DirtViewsOptions,
    LevelInfo, bucket_mask,
};
use parallax_scene::camera::{CameraFrame, CameraModel, CubeMap, Pinhole};
use parallax_scene::{CameraDesc, Scene, TriangleMesh};
use proptest::prelude::*;

/// What a conservativeness check covered.
#[derive(Default, Debug)]
struct Checked {
    rays: u64,
    hits: u64,
}

/// Film positions in cell `(cx, cy)`: the 4 corners, 4 random points on the edges and
/// `interior` random points inside.
fn cell_samples(cap: &DirtCapture, cx: u32, cy: u32, interior: u32, rng: &mut Rng) -> Vec<Vec2> {
    let [x0, y0, x1, y1] = cap.cell_rect(cx, cy);
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let mut v = vec![
        Vec2::new(x0, y0),
        Vec2::new(x1, y0),
        Vec2::new(x0, y1),
        Vec2::new(x1, y1),
        Vec2::new(lerp(x0, x1, rng.next_f32()), y0),
        Vec2::new(lerp(x0, x1, rng.next_f32()), y1),
        Vec2::new(x0, lerp(y0, y1, rng.next_f32())),
        Vec2::new(x1, lerp(y0, y1, rng.next_f32())),
    ];
    for _ in 0..interior {
        let u = rng.next_vec2();
        v.push(Vec2::new(lerp(x0, x1, u.x), lerp(y0, y1, u.y)));
    }
    v
}

/// Every BVH hit (all along the ray, and the closest) through every sampled film position of
/// every cell must be listed in that cell, lie in its depth bounds and be in the bucket of its
/// depth. Hits closer than the near plane are not captured by design and are skipped.
fn check_conservative(
    mesh: &TriangleMesh,
    bvh: &Bvh,
    cap: &DirtCapture,
    interior: u32,
    seed: u64,
) -> Checked {
    let cam = cap.view();
    let near = cap.options().near;
    let (nx, ny) = cap.cells();
    let mut rng = Rng::new(seed, 7);
    let mut hits: Vec<Hit> = Vec::new();
    let mut out = Checked::default();
    for cy in 0..ny {
        for cx in 0..nx {
            let (zmin, zmax) = cap.depth_bounds(cx, cy);
            let list = cap.pixel_triangles(cx, cy);
            for film in cell_samples(cap, cx, cy, interior, &mut rng) {
                let cr = cam.generate_ray(film, Vec2::splat(0.5), 0).unwrap();
                bvh.all_hits(&cr.ray, &mut hits);
                out.rays += 1;
                if let Some(c) = bvh.closest_hit(&cr.ray) {
                    assert!(
                        cr.view_depth(c.t) < near * 1.01 || list.binary_search(&c.prim).is_ok(),
                        "closest hit {c:?} missing from cell ({cx},{cy}) film {film}"
                    );
                }
                for h in &hits {
                    let d = cr.view_depth(h.t);
                    if d < near * 1.01 {
                        continue;
                    }
                    out.hits += 1;
                    let tri = mesh.triangle(h.prim as usize);
                    assert!(
                        list.binary_search(&h.prim).is_ok(),
                        "triangle {} ({tri:?}) hit at depth {d} through film {film} is not in \
                         cell ({cx},{cy}) of {nx}x{ny} (tile {})",
                        h.prim,
                        cap.tile_size()
                    );
                    assert!(
                        zmin <= d && d <= zmax,
                        "hit depth {d} of triangle {} outside cell ({cx},{cy}) bounds \
                         [{zmin}, {zmax}] (film {film})",
                        h.prim
                    );
                    let b = cap.bucket_of(cx, cy, d);
                    assert!(
                        cap.bucket(cx, cy, b).contains(&h.prim),
                        "triangle {} hit at depth {d} not in bucket {b} of cell ({cx},{cy}) \
                         (bounds [{zmin}, {zmax}])",
                        h.prim
                    );
                }
            }
        }
    }
    out
}

fn scene_file(rel: &str) -> TriangleMesh {
    let p = format!(
        "{}/../../../shared/scenes/{rel}",
        env!("CARGO_MANIFEST_DIR")
    );
    Scene::load(&p).unwrap().mesh
}

fn pinhole(eye: [f32; 3], target: [f32; 3], fov: f32, w: u32, h: u32) -> Pinhole {
    let desc = CameraDesc::new(Vec3::from(eye), Vec3::from(target), Vec3::Y, fov);
    Pinhole::new(&desc, w, h).unwrap()
}

fn opts(tile_size: u32, buckets: u32) -> DirtOptions {
    DirtOptions {
        tile_size,
        buckets,
        ..DirtOptions::default()
    }
}

/// Conservativeness on a mesh for tile sizes 1 and 4; returns (average distinct triangles per
/// non-empty pixel cell, triangle count).
fn check_scene(mesh: &TriangleMesh, cam: &Pinhole, interior: u32) -> f64 {
    let bvh = Bvh::build(mesh);
    let mut avg = 0.0;
    for (tile, buckets) in [(1, 8), (4, 4)] {
        let cap = DirtCapture::build(mesh, cam, &opts(tile, buckets)).unwrap();
        let c = check_conservative(mesh, &bvh, &cap, interior, tile as u64);
        assert!(c.hits > c.rays / 4, "too few hits to mean anything: {c:?}");
        check_masks(&cap);
        if tile == 1 {
            let st = cap.stats();
            avg = st.fragments as f64 / st.nonempty_cells.max(1) as f64;
        }
    }
    avg
}

#[test]
fn conservative_on_builtin_scenes() {
    for name in ["cornell", "atrium", "foliage"] {
        let scene = Scene::load(name).unwrap();
        let cam = Pinhole::new(&scene.camera(None).unwrap(), 48, 32).unwrap();
        let avg = check_scene(&scene.mesh, &cam, 4);
        let n = scene.mesh.triangle_count() as f64;
        // Tightness: a pixel lists a small fraction of the scene.
        assert!(avg < 0.05 * n, "{name}: {avg} triangles per pixel of {n}");
    }
}

#[test]
fn conservative_on_sponza() {
    let mesh = scene_file("sponza_dabrovic/sponza_dabrovic.glb");
    let cam = pinhole([-9.0, 3.5, 0.0], [8.0, 5.0, 0.0], 60.0, 48, 32);
    let avg = check_scene(&mesh, &cam, 3);
    assert!(avg < 0.01 * mesh.triangle_count() as f64, "{avg}");
}

#[test]
fn conservative_on_bunny() {
    let mesh = scene_file("stanford_bunny/bun_zipper.ply");
    let cam = pinhole([-0.017, 0.14, 0.25], [-0.017, 0.105, 0.0], 40.0, 48, 32);
    let avg = check_scene(&mesh, &cam, 3);
    assert!(avg < 0.01 * mesh.triangle_count() as f64, "{avg}");
}

#[test]
fn conservative_on_cube_faces() {
    let scene = Scene::load("atrium").unwrap();
    let cube = CubeMap::new(&scene.camera(None).unwrap(), 16).unwrap();
    let bvh = Bvh::build(&scene.mesh);
    for tile in [1, 4] {
        let dc = DirtCube::build(&scene.mesh, &cube, &opts(tile, 4)).unwrap();
        assert_eq!(dc.faces.len(), 6);
        let mut hits = 0;
        for (i, face) in dc.faces.iter().enumerate() {
            hits += check_conservative(&scene.mesh, &bvh, face, 4, i as u64).hits;
        }
        assert!(hits > 1000, "{hits}");
        assert_eq!(dc.bytes(), dc.faces.iter().map(|f| f.bytes()).sum::<u64>());
    }
}

fn soup(tris: &[[[f32; 3]; 3]]) -> TriangleMesh {
    let mut m = TriangleMesh::default();
    for t in tris {
        let base = m.positions.len() as u32;
        m.positions.extend(t.iter().map(|&p| Vec3::from(p)));
        m.normals.extend([Vec3::ZERO; 3]);
        m.uvs.extend([Vec2::ZERO; 3]);
        m.indices.push([base, base + 1, base + 2]);
        m.material_ids.push(0);
    }
    m
}

/// A camera at the origin looking down -Z (optionally rotated about Y).
fn origin_cam(w: u32, h: u32, fov: f32, yaw: f32) -> Pinhole {
    let r = Mat3::from_rotation_y(yaw);
    Pinhole::from_frame(
        CameraFrame {
            position: Vec3::ZERO,
            basis: r,
        },
        w,
        h,
        (fov.to_radians() * 0.5).tan(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, .. ProptestConfig::default() })]

    /// Random soups around the eye: triangles in front, behind, straddling the near and eye
    /// planes, some tiny, some huge, for random tile sizes, bucket counts and near planes.
    #[test]
    fn conservative_on_random_soups(
        tris in prop::collection::vec(
            prop::array::uniform3(prop::array::uniform3(-4.0f32..4.0)), 1..40),
        tiny in prop::collection::vec(
            (prop::array::uniform3(-2.0f32..2.0), prop::array::uniform3(-0.05f32..0.05),
             prop::array::uniform3(-0.05f32..0.05)), 0..20),
        tile_pow in 0u32..3, buckets in 1u32..9, near_pow in 1i32..4,
        fov in 30.0f32..120.0, yaw in -1.0f32..1.0,
    ) {
        let mut all = tris.clone();
        for (p, a, b) in &tiny {
            let p = Vec3::from(*p);
            all.push([p.into(), (p + Vec3::from(*a)).into(), (p + Vec3::from(*b)).into()]);
        }
        let mesh = soup(&all);
        let bvh = Bvh::build(&mesh);
        let cam = origin_cam(24, 16, fov, yaw);
        let o = DirtOptions {
            tile_size: 1 << tile_pow,
            buckets,
            near: 10f32.powi(-near_pow),
            ..DirtOptions::default()
        };
        let cap = DirtCapture::build(&mesh, &cam, &o).unwrap();
        check_conservative(&mesh, &bvh, &cap, 6, tris.len() as u64);
        check_masks(&cap);
        // The slow twin: exact per-cell clipping lists the same triangles in the same cells,
        // within bounds the default (corner) ranges contain.
        let exact = DirtCapture::build(&mesh, &cam, &DirtOptions { cell_depth: CellDepth::Exact, ..o }).unwrap();
        check_conservative(&mesh, &bvh, &exact, 6, tris.len() as u64);
        prop_assert_eq!(cap.stats().fragments, exact.stats().fragments);
        let (nx, ny) = cap.cells();
        for y in 0..ny {
            for x in 0..nx {
                prop_assert_eq!(cap.pixel_triangles(x, y), exact.pixel_triangles(x, y));
                let ((a0, a1), (b0, b1)) = (cap.depth_bounds(x, y), exact.depth_bounds(x, y));
                prop_assert!(a0 <= b0 && a1 >= b1, "cell ({x},{y}): [{a0}, {a1}] vs exact [{b0}, {b1}]");
            }
        }
    }
}

/// Each cell's record: its bounds, the eq. 1 scale and exactly the bits of its non-empty
/// buckets.
fn check_masks(cap: &DirtCapture) {
    let (nx, ny) = cap.cells();
    let b = cap.buckets();
    for y in 0..ny {
        for x in 0..nx {
            let want = (0..b)
                .filter(|&k| !cap.bucket(x, y, k).is_empty())
                .fold(0, |m, k| m | bucket_mask(k, k, b));
            let r = cap.cell_records()[(y * nx + x) as usize];
            assert_eq!(r.mask, want, "cell ({x},{y})");
            let (lo, hi) = cap.depth_bounds(x, y);
            assert_eq!((r.zmin, r.zmax), (lo, hi));
            assert_eq!(r.scale, parallax_raster::dirt::bucket_scale(lo, hi, b));
        }
    }
}

#[test]
fn bucket_masks_of_ranges() {
    assert_eq!(bucket_mask(0, 0, 8), 1);
    assert_eq!(bucket_mask(2, 4, 8), 0b11100);
    assert_eq!(bucket_mask(0, 31, 32), u32::MAX);
    assert_eq!(bucket_mask(31, 31, 32), 1 << 31);
    // 64 buckets: groups of 2; 100: groups of 4.
    assert_eq!(bucket_mask(4, 5, 64), 0b100);
    assert_eq!(bucket_mask(3, 6, 64), 0b1110);
    assert_eq!(bucket_mask(8, 11, 100), 0b100);
    assert_eq!(bucket_mask(0, 1023, 1024), u32::MAX);
    for b in [1, 7, 64, 65, 300, 1024] {
        for lo in (0..b).step_by(5) {
            for hi in (lo..b).step_by(7) {
                let m = bucket_mask(lo, hi, b);
                // The union of the single-bucket masks.
                let u = (lo..=hi).fold(0, |m, k| m | bucket_mask(k, k, b));
                assert_eq!(m, u, "{lo}..={hi} of {b}");
            }
        }
    }
}

#[test]
fn near_plane_and_behind_the_camera() {
    // Entirely behind; straddling the eye plane; a huge floor through the eye's feet.
    let mesh = soup(&[
        [[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [0.0, 1.0, 2.0]],
        [[-1.0, -0.5, 1.0], [1.0, -0.5, -3.0], [0.0, 0.5, -3.0]],
        [[-50.0, -1.0, 50.0], [50.0, -1.0, 50.0], [0.0, -1.0, -50.0]],
    ]);
    let cam = origin_cam(32, 24, 90.0, 0.0);
    let bvh = Bvh::build(&mesh);
    for near in [1e-4, 0.1, 2.0] {
        let o = DirtOptions {
            near,
            ..DirtOptions::default()
        };
        let cap = DirtCapture::build(&mesh, &cam, &o).unwrap();
        assert!(!cap.ids().contains(&0), "triangle behind the camera listed");
        let c = check_conservative(&mesh, &bvh, &cap, 6, 3);
        assert!(c.hits > 500, "{c:?}");
        // Nothing closer than the near plane is captured.
        let (nx, ny) = cap.cells();
        for y in 0..ny {
            for x in 0..nx {
                let (lo, _) = cap.depth_bounds(x, y);
                assert!(lo >= near * 0.999, "{lo} < near {near}");
            }
        }
    }
}

#[test]
fn tight_footprint_and_depth() {
    // A fronto-parallel triangle at depth 5 covering film x in [8, 20], y in [4, 16] (w=48,
    // h=32, fov 90: film = 24 + 24 x/5 ...).
    let cam = origin_cam(48, 32, 90.0, 0.0);
    let at = |fx: f32, fy: f32| {
        let d = cam.camera_dir(Vec2::new(fx, fy)) * 5.0;
        [d.x, d.y, d.z]
    };
    let mesh = soup(&[[at(8.0, 4.0), at(20.0, 4.0), at(8.0, 16.0)]]);
    let cap = DirtCapture::build(&mesh, &cam, &DirtOptions::default()).unwrap();
    let st = cap.stats();
    // Area 72 px^2, perimeter ~41 px: conservative coverage is at most area + perimeter + ...
    assert!(
        st.fragments >= 72 && st.fragments <= 72 + 2 * 41 + 4,
        "{}",
        st.fragments
    );
    // A lone flat triangle's (widened) range is its cells' whole range: all 8 buckets.
    assert_eq!(st.entries, 8 * st.fragments);
    for y in 0..32 {
        for x in 0..48 {
            let listed = !cap.cell_entries(x, y).is_empty();
            let near_tri = (7..=20).contains(&x) && (3..=16).contains(&y);
            assert!(
                !listed || near_tri,
                "({x},{y}) listed far from the triangle"
            );
            if listed {
                let (lo, hi) = cap.depth_bounds(x, y);
                assert!(
                    (lo - 5.0).abs() < 1e-3 && (hi - 5.0).abs() < 1e-3,
                    "{lo} {hi}"
                );
            }
        }
    }
    // Interior pixels are listed.
    assert_eq!(cap.pixel_triangles(10, 6), vec![0]);
}

#[test]
fn buckets_split_a_slanted_surface() {
    // Two triangles in one pixel column at different depths: the far one must not be in the
    // near bucket.
    let cam = origin_cam(8, 8, 60.0, 0.0);
    let mesh = soup(&[
        [[-10.0, -10.0, -1.0], [10.0, -10.0, -1.0], [0.0, 10.0, -1.0]],
        [[-10.0, -10.0, -9.0], [10.0, -10.0, -9.0], [0.0, 10.0, -9.0]],
    ]);
    let cap = DirtCapture::build(&mesh, &cam, &opts(1, 4)).unwrap();
    assert_eq!(cap.bucket(4, 4, 0), &[0]);
    assert_eq!(cap.bucket(4, 4, 3), &[1]);
    assert!(cap.bucket(4, 4, 1).is_empty() && cap.bucket(4, 4, 2).is_empty());
}

#[test]
fn mip_chain_is_exact_min_max_of_children() {
    let scene = Scene::load("atrium").unwrap();
    for (w, h, tile) in [(48, 32, 1), (45, 27, 1), (45, 27, 4)] {
        let cam = Pinhole::new(&scene.camera(None).unwrap(), w, h).unwrap();
        let cap = DirtCapture::build(&scene.mesh, &cam, &opts(tile, 4)).unwrap();
        let l0 = cap.mip(0);
        assert_eq!((l0.width, l0.height), cap.cells());
        for y in 0..l0.height {
            for x in 0..l0.width {
                assert_eq!(l0.get(x, y), cap.depth_bounds(x, y));
            }
        }
        for k in 1..cap.mip_levels() {
            let (c, p) = (cap.mip(k - 1), cap.mip(k));
            assert_eq!(
                (p.width, p.height),
                (c.width.div_ceil(2), c.height.div_ceil(2))
            );
            for y in 0..p.height {
                for x in 0..p.width {
                    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
                    for cy in 2 * y..(2 * y + 2).min(c.height) {
                        for cx in 2 * x..(2 * x + 2).min(c.width) {
                            let (a, b) = c.get(cx, cy);
                            lo = lo.min(a);
                            hi = hi.max(b);
                        }
                    }
                    assert_eq!(p.get(x, y), (lo, hi), "level {k} texel ({x},{y})");
                }
            }
        }
        let top = cap.mip(cap.mip_levels() - 1);
        assert_eq!((top.width, top.height), (1, 1));
        let (lo, hi) = top.get(0, 0);
        assert!(lo > 0.0 && lo < hi);
    }
}

#[test]
fn bytes_are_the_flat_arrays() {
    let scene = Scene::load("cornell").unwrap();
    let cam = Pinhole::new(&scene.camera(None).unwrap(), 40, 30).unwrap();
    for (tile, buckets) in [(1, 8), (2, 3), (4, 1)] {
        let cap = DirtCapture::build(&scene.mesh, &cam, &opts(tile, buckets)).unwrap();
        let (nx, ny) = cap.cells();
        assert_eq!(cap.offsets().len() as u64, (nx * ny * buckets) as u64 + 1);
        assert_eq!(cap.ids().len() as u64, cap.stats().entries);
        let texels: u64 = (0..cap.mip_levels())
            .map(|k| (cap.mip(k).width * cap.mip(k).height) as u64)
            .sum();
        let expect = 4 * cap.offsets().len() as u64
            + 4 * cap.ids().len() as u64
            + 8 * texels
            + 8 * texels // the reciprocal chain
            + 16 * (nx * ny) as u64
            + (cap.mip_levels() * std::mem::size_of::<LevelInfo>()) as u64;
        assert_eq!(cap.bytes(), expect);
        assert_eq!(cap.stats().bytes, expect);
        assert!(cap.stats().entries >= cap.stats().fragments);
        assert!(cap.stats().fragments > 0);
    }
}

#[test]
fn deterministic_across_thread_counts() {
    let scene = Scene::load("foliage").unwrap();
    let cam = Pinhole::new(&scene.camera(None).unwrap(), 64, 40).unwrap();
    let build = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| DirtCapture::build(&scene.mesh, &cam, &opts(2, 5)).unwrap())
    };
    let (a, b) = (build(1), build(3));
    assert_eq!(a.offsets(), b.offsets());
    assert_eq!(a.ids(), b.ids());
    assert_eq!(a.mip(0).bounds, b.mip(0).bounds);
    assert_eq!(a.cell_records(), b.cell_records());
    // Ids ascend within each bucket.
    let (nx, ny) = a.cells();
    for y in 0..ny {
        for x in 0..nx {
            for k in 0..5 {
                assert!(a.bucket(x, y, k).windows(2).all(|w| w[0] < w[1]));
            }
        }
    }
}

#[test]
fn bad_input_is_an_error() {
    let mesh = Scene::load("cornell").unwrap().mesh;
    let cam = origin_cam(16, 16, 60.0, 0.0);
    let bad = |o: DirtOptions| {
        matches!(
            DirtCapture::build(&mesh, &cam, &o),
            Err(DirtError::InvalidOptions(_))
        )
    };
    assert!(bad(opts(3, 4)));
    assert!(bad(opts(0, 4)));
    assert!(bad(opts(1 << 20, 4)));
    assert!(bad(opts(1, 0)));
    assert!(bad(DirtOptions {
        near: 0.0,
        ..DirtOptions::default()
    }));
    assert!(bad(DirtOptions {
        near: f32::NAN,
        ..DirtOptions::default()
    }));
    assert!(bad(DirtOptions {
        max_entries: 0,
        ..DirtOptions::default()
    }));
    // Zero-size and absurd views.
    for (w, h) in [(0, 16), (16, 0), (1 << 20, 1 << 20)] {
        let c = origin_cam(w.max(1), h.max(1), 60.0, 0.0);
        let c = Pinhole {
            width: w,
            height: h,
            ..c
        };
        assert!(matches!(
            DirtCapture::build(&mesh, &c, &DirtOptions::default()),
            Err(DirtError::InvalidView(_))
        ));
    }
    // Too many cell-buckets for the offsets array: refused before allocating.
    let big = origin_cam(16384, 16384, 60.0, 0.0);
    assert!(matches!(
        DirtCapture::build(&mesh, &big, &opts(1, 64)),
        Err(DirtError::InvalidOptions(_))
    ));
    // The entry budget is enforced.
    let scene = Scene::load("atrium").unwrap();
    let cam = Pinhole::new(&scene.camera(None).unwrap(), 64, 48).unwrap();
    let r = DirtCapture::build(
        &scene.mesh,
        &cam,
        &DirtOptions {
            max_entries: 100,
            ..DirtOptions::default()
        },
    );
    assert!(matches!(r, Err(DirtError::TooLarge { max: 100 })), "{r:?}");
    // A non-finite camera.
    let mut c = origin_cam(16, 16, 60.0, 0.0);
    c.frame.position.x = f32::NAN;
    assert!(matches!(
        DirtCapture::build(&mesh, &c, &DirtOptions::default()),
        Err(DirtError::InvalidView(_))
    ));
    // An empty mesh is fine: everything empty.
    let cap = DirtCapture::build(&TriangleMesh::default(), &cam, &DirtOptions::default()).unwrap();
    assert!(cap.ids().is_empty() && cap.depth_bounds(0, 0) == (f32::INFINITY, f32::NEG_INFINITY));
}

#[test]
fn views_are_deterministic_across_thread_counts() {
    let scene = Scene::load("atrium").unwrap();
    let desc = scene.camera(None).unwrap();
    let cam = Pinhole::new(&desc, 64, 40).unwrap();
    let build = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let o = DirtViewsOptions {
            face_size: 24,
            capture: opts(2, 5),
            camera_tile_size: None,
        };
        pool.install(|| DirtViews::build(&scene.mesh, Some(&cam), desc.eye, &o).unwrap())
    };
    let (a, b) = (build(1), build(3));
    assert_eq!(a.triangles.as_slice(), b.triangles.as_slice());
    for (x, y) in a.views().zip(b.views()) {
        assert_eq!(x.offsets(), y.offsets());
        assert_eq!(x.ids(), y.ids());
        assert_eq!(x.cell_records(), y.cell_records());
        assert_eq!(x.mip_arrays().1, y.mip_arrays().1);
    }
    assert_eq!(a.views().count(), 7);
}

/// A camera view with its own tile size is the capture that view gets alone at that size, and
/// the cube faces keep theirs (the views share only the setup pass and the entry budget).
#[test]
fn camera_tile_size_sets_the_camera_view_s() {
    let scene = Scene::load("atrium").unwrap();
    let desc = scene.camera(None).unwrap();
    let cam = Pinhole::new(&desc, 64, 40).unwrap();
    let build = |camera_tile_size| {
        let o = DirtViewsOptions {
            face_size: 24,
            capture: opts(2, 5),
            camera_tile_size,
        };
        DirtViews::build(&scene.mesh, Some(&cam), desc.eye, &o).unwrap()
    };
    let (coarse, same) = (build(Some(8)), build(None));
    let c = coarse.camera.as_ref().unwrap();
    assert_eq!(c.tile_size(), 8);
    assert_eq!((c.stats().cells_x, c.stats().cells_y), (8, 5));
    let alone = DirtCapture::build(&scene.mesh, &cam, &opts(8, 5)).unwrap();
    assert_eq!(c.offsets(), alone.offsets());
    assert_eq!(c.ids(), alone.ids());
    assert_eq!(c.cell_records(), alone.cell_records());
    assert_eq!(c.mip_arrays().1, alone.mip_arrays().1);
    for (x, y) in coarse.cube.faces.iter().zip(&same.cube.faces) {
        assert_eq!(x.tile_size(), 2);
        assert_eq!(x.offsets(), y.offsets());
        assert_eq!(x.ids(), y.ids());
        assert_eq!(x.mip_arrays().1, y.mip_arrays().1);
    }
    let fine = same.camera.as_ref().unwrap();
    assert_eq!(fine.tile_size(), 2);
    assert!(c.stats().fragments < fine.stats().fragments);
    assert!(c.stats().fragments > 0);
}

#[test]
fn tile_flags_set_the_camera_and_face_s() {
    let base = DirtViewsOptions::TRACING;
    let sizes = |o: DirtViewsOptions| (o.capture.tile_size, o.camera_tile_size);
    assert_eq!(sizes(base.with_tile_flags(None, None)), (4, Some(8)));
    assert_eq!(sizes(base.with_tile_flags(Some(2), None)), (2, None));
    assert_eq!(sizes(base.with_tile_flags(None, Some(16))), (4, Some(16)));
    assert_eq!(
        sizes(base.with_tile_flags(Some(2), Some(16))),
        (2, Some(16))
    );
}

/// The views are set up and rasterized together: each view is billed that stage's wall time
/// in proportion to its fragments, so the views' `setup_ms` are proportional to their
/// fragment counts (and the camera view, with most fragments, gets the largest share).
#[test]
fn setup_time_is_billed_by_fragments() {
    let scene = Scene::load("atrium").unwrap();
    let desc = scene.camera(None).unwrap();
    let cam = Pinhole::new(&desc, 256, 128).unwrap();
    let o = DirtViewsOptions {
        face_size: 32,
        capture: opts(1, 8),
        camera_tile_size: None,
    };
    let views = DirtViews::build(&scene.mesh, Some(&cam), desc.eye, &o).unwrap();
    let st: Vec<_> = views.views().map(|v| v.stats().clone()).collect();
    let (ms, frags): (f64, u64) = st
        .iter()
        .map(|s| (s.setup_ms, s.fragments))
        .fold((0.0, 0), |(a, b), (m, f)| (a + m, b + f));
    assert!(ms > 0.0 && frags > 0);
    for s in &st {
        let want = ms * s.fragments as f64 / frags as f64;
        assert!(
            (s.setup_ms - want).abs() <= 1e-9 * ms,
            "{} ms for {} of {frags} fragments (want {want})",
            s.setup_ms,
            s.fragments
        );
    }
    assert!(st[0].fragments > st[1].fragments && st[0].setup_ms > st[1].setup_ms);
}
