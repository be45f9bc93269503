//! Layered depth cubes (Bürger et al. 2007, §1.2-1.3) against the BVH: every triangle in exactly
//! one LDI; the BVH's hits along each axis through the pixel centres are the LDI's samples (same
//! primitive, same depth); coarse bounds enclose their blocks exactly; the all-layers capture's
//! first layers equal the k-buffer's.

use glam::Vec3;
use parallax_bvh::{Bvh, Hit};
use parallax_core::Ray;
use parallax_raster::ldc::{LayeredDepthCube, LdcOptions, dominant_axis};
use parallax_raster::{RasterOptions, View, capture_all_layers, capture_layers};
use parallax_scene::Scene;
use parallax_scene::camera::Pinhole;

fn shared(rel: &str) -> String {
    format!(
        "{}/../../../shared/scenes/{rel}",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn scenes() -> Vec<(String, Scene, u32)> {
    let mut out = vec![
        ("cornell".to_string(), Scene::load("cornell").unwrap(), 96),
        ("atrium".to_string(), Scene::load("atrium").unwrap(), 96),
    ];
    let bunny = shared("stanford_bunny/bun_zipper.ply");
    if std::path::Path::new(&bunny).exists() {
        out.push(("bunny".to_string(), Scene::load(&bunny).unwrap(), 96));
    } else {
        eprintln!("skipping missing {bunny}");
    }
    out
}

#[test]
fn every_triangle_lands_in_exactly_one_ldi() {
    for (name, scene, res) in scenes() {
        // Finer than the other tests so that even the bunny has triangles spanning pixels.
        let ldc = LayeredDepthCube::build(&scene, 3 * res, &LdcOptions::default()).unwrap();
        let mesh = &scene.mesh;
        let n = mesh.indices.len();
        // The assignment: the largest |normal component| (independently of the tie rule).
        for p in 0..n {
            let a = dominant_axis(mesh, p);
            let [v0, v1, v2] = mesh.triangle(p);
            let nn = (v1 - v0).cross(v2 - v0).abs();
            assert!(
                (0..3).all(|k| nn[a] >= nn[k]),
                "{name} prim {p}: {nn} -> {a}"
            );
        }
        let per_ldi: Vec<usize> = ldc.stats.ldis.iter().map(|l| l.triangles).collect();
        assert_eq!(per_ldi.iter().sum::<usize>(), n, "{name}");
        // The samples: each primitive appears in one LDI only, that of its axis.
        let mut seen = vec![u8::MAX; n];
        let mut with_samples = 0usize;
        for ldi in &ldc.ldis {
            for &p in &ldi.capture.primitive_id {
                let p = p as usize;
                assert_eq!(dominant_axis(mesh, p), ldi.axis, "{name} prim {p}");
                if seen[p] == u8::MAX {
                    seen[p] = ldi.axis as u8;
                    with_samples += 1;
                }
                assert_eq!(seen[p] as usize, ldi.axis, "{name} prim {p} in two LDIs");
            }
        }
        // A triangle whose projection onto its LDI's image plane has an inscribed circle wider
        // than a pixel diagonal contains a whole pixel, hence a pixel centre: it has samples.
        let s = ldc.pixel_size;
        let mut big = 0usize;
        for (p, &got) in seen.iter().enumerate() {
            let a = dominant_axis(mesh, p);
            let (u, v) = parallax_raster::ldc::image_axes(a);
            let q = mesh.triangle(p).map(|w| glam::Vec2::new(w[u], w[v]));
            let area2 = (q[1] - q[0]).perp_dot(q[2] - q[0]).abs();
            let perim = q[0].distance(q[1]) + q[1].distance(q[2]) + q[2].distance(q[0]);
            if perim > 0.0 && area2 / perim > 0.75 * s {
                big += 1;
                assert_eq!(got as usize, a, "{name} prim {p}: big but no samples");
            }
        }
        assert!(big > 0, "{name}");
        eprintln!(
            "{name}: {n} triangles, per LDI {per_ldi:?}, {with_samples} with samples ({big} \
             surely), {} samples, max depth complexity {}, {} bytes",
            ldc.stats.samples,
            ldc.stats.max_depth_complexity,
            ldc.bytes()
        );
        assert_eq!(ldc.bytes(), ldc.stats.bytes);
    }
}

/// Depth tolerance: BVH `t` is an f32 ray-triangle distance (error ~ a few ulps of the box
/// size), the LDI depth an f64 plane evaluation at the pixel centre rounded to f32. Measured
/// largest difference: 2e-7 of the box's longest side (atrium).
fn tolerance(ldc: &LayeredDepthCube) -> f32 {
    1e-5 * ldc.bounds.extent().max_element()
}

#[test]
fn bvh_rays_along_each_axis_find_the_ldi_samples() {
    for (name, scene, res) in scenes() {
        let ldc = LayeredDepthCube::build(&scene, res, &LdcOptions::default()).unwrap();
        let bvh = Bvh::build(&scene.mesh);
        let tol = tolerance(&ldc);
        let mut hits: Vec<Hit> = Vec::new();
        for ldi in &ldc.ldis {
            let a = ldi.axis;
            let cap = &ldi.capture;
            let mut dir = Vec3::ZERO;
            dir[a] = 1.0;
            let (mut bvh_hits, mut found, mut samples, mut matched) = (0usize, 0, 0usize, 0);
            let (mut max_err, mut max_edge) = (0f32, 0f64);
            for y in 0..cap.height() {
                for x in 0..cap.width() {
                    let ray = Ray::new(ldc.pixel_ray_origin(a, x, y), dir);
                    bvh.all_hits(&ray, &mut hits);
                    hits.retain(|h| dominant_axis(&scene.mesh, h.prim as usize) == a);
                    let r = cap.range(x, y);
                    // Samples are sorted front to back.
                    assert!(cap.depth[r.clone()].windows(2).all(|w| w[0] <= w[1]));
                    let near = |p: u32, d: f32| {
                        r.clone()
                            .find(|&i| cap.primitive_id[i] == p && (cap.depth[i] - d).abs() <= tol)
                    };
                    bvh_hits += hits.len();
                    for h in &hits {
                        if let Some(i) = near(h.prim, h.t) {
                            found += 1;
                            max_err = max_err.max((cap.depth[i] - h.t).abs());
                        } else {
                            let e = edge_distance_px(&ldc, &scene, a, x, y, h.prim);
                            max_edge = max_edge.max(e);
                        }
                    }
                    samples += r.len();
                    for i in r.clone() {
                        let p = cap.primitive_id[i];
                        let d = cap.depth[i];
                        if hits.iter().any(|h| h.prim == p && (h.t - d).abs() <= tol) {
                            matched += 1;
                        } else {
                            let e = edge_distance_px(&ldc, &scene, a, x, y, p);
                            max_edge = max_edge.max(e);
                        }
                    }
                }
            }
            let fwd = found as f64 / bvh_hits.max(1) as f64;
            let back = matched as f64 / samples.max(1) as f64;
            eprintln!(
                "{name} axis {a}: {}x{}, {bvh_hits} BVH hits ({fwd:.5} found), {samples} samples \
                 ({back:.5} hit by the BVH), max |depth - t| {max_err:e} (tol {tol:e}), mismatches within {max_edge:e} px of an edge",
                cap.width(),
                cap.height()
            );
            assert!(bvh_hits > 0 && samples > 0, "{name} axis {a}");
            assert!(fwd >= 0.995, "{name} axis {a}: {fwd}");
            assert!(back >= 0.995, "{name} axis {a}: {back}");
            assert!(max_err <= tol);
            // Disagreements are pixel centres on a triangle edge (the rasterizer snaps vertices
            // to 1/4096 pixel and applies the top-left rule; the BVH's watertight test may
            // report both triangles of a shared edge; snapping moves an edge by <= 1.2e-4 px).
            assert!(
                max_edge <= 1e-3,
                "{name} axis {a}: mismatch {max_edge} px from an edge"
            );
        }
    }
}

/// Distance in pixels from the centre of pixel `(x, y)` of LDI `axis` to the nearest edge line of
/// triangle `prim` projected onto the image plane.
fn edge_distance_px(
    ldc: &LayeredDepthCube,
    scene: &Scene,
    axis: usize,
    x: u32,
    y: u32,
    prim: u32,
) -> f64 {
    let (u, v) = parallax_raster::ldc::image_axes(axis);
    let s = ldc.pixel_size as f64;
    let lo = ldc.bounds.min.as_dvec3();
    let q = scene
        .mesh
        .triangle(prim as usize)
        .map(|w| glam::DVec2::new((w[u] as f64 - lo[u]) / s, (w[v] as f64 - lo[v]) / s));
    let c = glam::DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
    (0..3)
        .map(|k| {
            let (a, b) = (q[k], q[(k + 1) % 3]);
            let d = b - a;
            (d.perp_dot(c - a) / d.length()).abs()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn coarse_grid_encloses_each_block_exactly() {
    for block in [8, 16] {
        for (name, scene, res) in scenes() {
            let opts = LdcOptions {
                block,
                ..LdcOptions::default()
            };
            let ldc = LayeredDepthCube::build(&scene, res, &opts).unwrap();
            for ldi in &ldc.ldis {
                let (cap, g) = (&ldi.capture, &ldi.coarse);
                assert_eq!(g.blocks_x, cap.width().div_ceil(block));
                assert_eq!(g.blocks_y, cap.height().div_ceil(block));
                let mut want = vec![[f32::INFINITY, f32::NEG_INFINITY]; g.bounds.len()];
                for y in 0..cap.height() {
                    for x in 0..cap.width() {
                        let b = &mut want[((y / block) * g.blocks_x + x / block) as usize];
                        for i in cap.range(x, y) {
                            b[0] = b[0].min(cap.depth[i]);
                            b[1] = b[1].max(cap.depth[i]);
                        }
                    }
                }
                assert_eq!(g.bounds, want, "{name} axis {} block {block}", ldi.axis);
                let empty = want.iter().filter(|b| b[0] > b[1]).count();
                eprintln!(
                    "{name} axis {} block {block}: {} blocks, {empty} empty",
                    ldi.axis,
                    want.len()
                );
            }
        }
    }
}

#[test]
fn all_layers_start_with_the_kbuffer_layers() {
    const K: usize = 4;
    for (name, scene, _) in scenes() {
        let desc = scene.camera(None).unwrap_or_else(|_| {
            let b = scene.mesh.bounds();
            parallax_scene::CameraDesc::new(
                b.center() + Vec3::new(0.0, 0.0, 2.0 * b.extent().max_element()),
                b.center(),
                Vec3::Y,
                40.0,
            )
        });
        let cam = Pinhole::new(&desc, 80, 60).unwrap();
        let view = View::from_pinhole(&cam).unwrap();
        let all = capture_all_layers(&scene, &view, None, 1 << 24).unwrap();
        let kb = capture_layers(&scene, &view, &RasterOptions::layers(K)).unwrap();
        let mut deeper = 0usize;
        for y in 0..60 {
            for x in 0..80 {
                let r = all.range(x, y);
                deeper += (r.len() > K) as usize;
                for k in 0..K {
                    let g = kb.layers.layer(k).get(x, y);
                    if k < r.len() {
                        let i = r.start + k;
                        assert_eq!(
                            (
                                all.primitive_id[i],
                                all.depth[i],
                                all.normal[i],
                                all.albedo[i]
                            ),
                            (g.primitive_id, g.depth, g.normal, g.albedo),
                            "{name} ({x}, {y}) layer {k}"
                        );
                    } else {
                        assert_eq!(g.primitive_id, parallax_core::NO_ID);
                    }
                }
            }
        }
        assert_eq!(all.stats.samples, all.len());
        assert_eq!(all.offsets.len(), 80 * 60 + 1);
        eprintln!(
            "{name}: {} samples, {deeper} pixels deeper than {K}, max depth complexity {}",
            all.len(),
            all.stats.max_depth_complexity
        );
    }
}

#[test]
fn invalid_inputs_are_errors() {
    let scene = Scene::load("cornell").unwrap();
    let o = LdcOptions::default();
    assert!(LayeredDepthCube::build(&scene, 0, &o).is_err());
    assert!(LayeredDepthCube::build(&scene, 1 << 20, &o).is_err());
    let bad = LdcOptions { block: 0, ..o };
    assert!(LayeredDepthCube::build(&scene, 32, &bad).is_err());
    let tiny = LdcOptions {
        max_samples: 10,
        ..o
    };
    assert!(LayeredDepthCube::build(&scene, 32, &tiny).is_err());
    let mut empty = scene.clone();
    empty.mesh = Default::default();
    assert!(LayeredDepthCube::build(&empty, 32, &o).is_err());
}

#[test]
fn normals_follow_the_winding_and_geometric_normals_are_the_triangles() {
    for (name, scene, res) in scenes() {
        let ldc = LayeredDepthCube::build(&scene, res, &LdcOptions::default()).unwrap();
        let mesh = &scene.mesh;
        for ldi in &ldc.ldis {
            let cap = &ldi.capture;
            assert_eq!(ldi.geometric_normal.len(), cap.len());
            for i in 0..cap.len() {
                let p = cap.primitive_id[i] as usize;
                let ng = mesh.geometric_normal(p);
                assert_eq!(ldi.geometric_normal[i], ng, "{name}");
                // The shading normal stays in the geometric normal's hemisphere (winding side).
                assert!(
                    cap.normal[i].dot(ng) > 0.0,
                    "{name} axis {} sample {i}",
                    ldi.axis
                );
            }
        }
        let s = &ldc.stats;
        for ms in [s.assign_ms, s.peel_ms, s.orient_ms, s.grid_ms] {
            assert!(
                ms >= 0.0 && ms <= s.total_ms,
                "{name}: stage {ms} of {}",
                s.total_ms
            );
        }
        assert!(s.assign_ms + s.peel_ms + s.orient_ms + s.grid_ms <= s.total_ms);
    }
}

#[test]
fn a_region_of_interest_fits_the_cube_and_clips_the_rest() {
    let scene = Scene::load("cornell").unwrap();
    // The lower half of the box: the floor and the lower parts of walls and objects.
    let roi = [Vec3::new(-2.0, -1.0, -2.0), Vec3::new(2.0, 1.0, 2.0)];
    let opts = LdcOptions {
        roi: Some(roi),
        ..LdcOptions::default()
    };
    let full = LayeredDepthCube::build(&scene, 128, &LdcOptions::default()).unwrap();
    let fitted = LayeredDepthCube::build(&scene, 128, &opts).unwrap();
    assert!(fitted.stats.roi && !full.stats.roi);
    let b = scene.mesh.bounds();
    assert!(fitted.bounds.max.y < 1.0 + 2.0 * fitted.pixel_size);
    assert!(fitted.bounds.min.x < b.min.x + 0.01);
    // Every sample lies inside the fitted box.
    for ldi in &fitted.ldis {
        let ext = fitted.bounds.extent()[ldi.axis];
        assert!(ldi.capture.depth.iter().all(|&d| d >= 0.0 && d <= ext));
        for y in 0..ldi.capture.height() {
            for x in 0..ldi.capture.width() {
                for i in ldi.capture.range(x, y) {
                    let mut p = fitted.pixel_ray_origin(ldi.axis, x, y);
                    p[ldi.axis] += ldi.capture.depth[i];
                    assert!(
                        p.y <= fitted.bounds.max.y + 1e-4,
                        "sample at {p} above the ROI"
                    );
                }
            }
        }
    }
    assert!(fitted.stats.samples < full.stats.samples);
    // A box that misses the scene, or an inverted one, is an error.
    for bad in [
        [Vec3::splat(10.0), Vec3::splat(11.0)],
        [Vec3::ONE, Vec3::ZERO],
        [Vec3::NAN, Vec3::ONE],
    ] {
        let o = LdcOptions {
            roi: Some(bad),
            ..LdcOptions::default()
        };
        assert!(LayeredDepthCube::build(&scene, 64, &o).is_err(), "{bad:?}");
    }
}

#[test]
fn depth_complexity_beyond_the_layer_limit_is_an_error() {
    let scene = Scene::load("cornell").unwrap();
    let ldc = LayeredDepthCube::build(&scene, 64, &LdcOptions::default()).unwrap();
    let need = ldc.stats.max_depth_complexity;
    assert!(need >= 2);
    let exact = LdcOptions {
        max_layers: need,
        ..LdcOptions::default()
    };
    assert!(LayeredDepthCube::build(&scene, 64, &exact).is_ok());
    let short = LdcOptions {
        max_layers: need - 1,
        ..LdcOptions::default()
    };
    let e = LayeredDepthCube::build(&scene, 64, &short)
        .unwrap_err()
        .to_string();
    assert!(e.contains("layers") && e.contains(&need.to_string()), "{e}");
    let zero = LdcOptions {
        max_layers: 0,
        ..LdcOptions::default()
    };
    assert!(LayeredDepthCube::build(&scene, 64, &zero).is_err());
}
