//! The built-in procedural scenes: loading, validity, sizes, closed solids, cameras, camera
//! paths, foliage depth complexity and determinism. Brute force on purpose (no BVH here): the
//! scenes are small enough, and these checks are what the BVH will later be compared against.

use std::collections::HashMap;

use glam::{Affine3A, Quat, Vec3};
use parallax_core::math::{Ray, WatertightRay};
use parallax_scene::builtin::{self, shapes::MeshBuilder};
use parallax_scene::{CameraDesc, Scene, TriangleMesh};

fn scenes() -> Vec<Scene> {
    builtin::NAMES
        .iter()
        .map(|n| builtin::by_name(n).expect("built-in scene"))
        .collect()
}

/// Position key for edge matching; `+ 0.0` merges -0 into +0.
fn key(p: Vec3) -> [u32; 3] {
    (p + Vec3::ZERO).to_array().map(f32::to_bits)
}

/// Every directed edge (by position) of triangles `tris` occurs exactly once and its reverse
/// exactly once: a closed, consistently oriented 2-manifold (possibly of several components).
fn check_closed(mesh: &TriangleMesh, tris: std::ops::Range<usize>) -> Result<(), String> {
    let mut edges: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::new();
    for i in tris {
        let p = mesh.triangle(i).map(key);
        for (a, b) in [(p[0], p[1]), (p[1], p[2]), (p[2], p[0])] {
            if a == b {
                return Err(format!("triangle {i} has a degenerate edge"));
            }
            *edges.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &edges {
        let back = edges.get(&(b, a)).copied().unwrap_or(0);
        if n != 1 || back != 1 {
            let f = |k: [u32; 3]| k.map(f32::from_bits);
            return Err(format!(
                "edge {:?} -> {:?} used {n} times, reverse {back} times",
                f(a),
                f(b)
            ));
        }
    }
    Ok(())
}

/// Signed volume (divergence theorem); positive when the faces point outwards.
fn signed_volume(mesh: &TriangleMesh, tris: std::ops::Range<usize>) -> f64 {
    tris.map(|i| {
        let [a, b, c] = mesh.triangle(i).map(|p| p.as_dvec3());
        a.dot(b.cross(c)) / 6.0
    })
    .sum()
}

fn solid_ranges(mesh: &TriangleMesh) -> Vec<std::ops::Range<usize>> {
    mesh.objects
        .iter()
        .filter(|o| o.name.starts_with("solid:"))
        .map(|o| o.first_triangle as usize..(o.first_triangle + o.triangle_count) as usize)
        .collect()
}

/// Number of crossings of the ray with the triangles of closed objects: even outside solids.
fn solid_crossings(mesh: &TriangleMesh, solids: &[std::ops::Range<usize>], ray: &Ray) -> usize {
    let wr = WatertightRay::new(ray);
    solids
        .iter()
        .flat_map(|r| r.clone())
        .filter(|&i| {
            let [a, b, c] = mesh.triangle(i);
            wr.intersect(a, b, c).is_some()
        })
        .count()
}

/// All hits of a ray (any object), and the closest distance.
fn all_hits(mesh: &TriangleMesh, ray: &Ray) -> (usize, f32) {
    let wr = WatertightRay::new(ray);
    let mut count = 0;
    let mut closest = f32::INFINITY;
    for i in 0..mesh.triangle_count() {
        let [a, b, c] = mesh.triangle(i);
        if let Some(h) = wr.intersect(a, b, c) {
            count += 1;
            closest = closest.min(h.t);
        }
    }
    (count, closest)
}

/// The eye is outside every closed solid: crossings along +X and an oblique direction are even.
fn assert_eye_outside(scene: &Scene, solids: &[std::ops::Range<usize>], eye: Vec3, what: &str) {
    for dir in [Vec3::X, Vec3::new(0.31, 0.17, -0.93).normalize()] {
        let n = solid_crossings(&scene.mesh, solids, &Ray::new(eye, dir));
        assert_eq!(
            n % 2,
            0,
            "{}: {what} eye {eye} is inside a solid ({n} crossings along {dir})",
            scene.name
        );
    }
}

/// Pinhole ray through normalised film position `(sx, sy)` in [-1, 1]^2 (y up).
fn camera_ray(c: &CameraDesc, aspect: f32, sx: f32, sy: f32) -> Ray {
    let f = (c.target - c.eye).normalize();
    let r = f.cross(c.up).normalize();
    let u = r.cross(f);
    let t = (0.5 * c.fov_y_deg.to_radians()).tan();
    Ray::new(
        c.eye,
        (f + r * (sx * t * aspect) + u * (sy * t)).normalize(),
    )
}

#[test]
fn every_name_loads_validates_and_is_complete() {
    assert_eq!(
        builtin::NAMES,
        &["atrium", "cornell", "foliage", "mirrors", "mirrors-open"]
    );
    for &name in builtin::NAMES {
        let s = builtin::by_name(name).unwrap();
        let loaded = Scene::load(name).unwrap();
        assert_eq!(s.name, name);
        assert_eq!(loaded.name, name);
        assert_eq!(loaded.mesh.triangle_count(), s.mesh.triangle_count());
        s.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(!builtin::describe(name).is_empty());
        let emissive = s.materials.iter().any(|m| m.is_emissive());
        assert!(!s.lights.is_empty() || emissive, "{name} has no light");
        assert!(s.environment.is_finite() && s.environment.min_element() >= 0.0);
        assert!(!s.cameras.is_empty());
        for c in &s.cameras {
            c.desc
                .validate()
                .unwrap_or_else(|e| panic!("{name}/{}: {e}", c.name));
        }
        assert!(
            s.mesh.uvs.iter().all(|uv| uv.is_finite()),
            "{name}: non-finite uv"
        );
        let p = s.camera_path.as_ref().expect("camera path");
        assert_eq!((p.frames, p.fps), (60, 30.0));
        assert!(
            s.mesh.objects.iter().all(|o| o.triangle_count > 0),
            "{name}: empty object"
        );
    }
    // Open-sky scenes have a sky; the Cornell box is lit by its emissive quad alone.
    assert!(
        builtin::by_name("atrium")
            .unwrap()
            .environment
            .min_element()
            > 0.0
    );
    assert!(builtin::by_name("nope").is_none());
    assert_eq!(builtin::describe("nope"), "");
    assert!(Scene::load("nope").is_err());
}

#[test]
fn triangle_counts_and_bounds_are_as_designed() {
    for s in scenes() {
        let n = s.mesh.triangle_count();
        let e = s.bounds().extent();
        let (tri_range, ext_min, ext_max) = match s.name.as_str() {
            "atrium" => (
                20_000..80_000,
                Vec3::new(12.0, 9.0, 30.0),
                Vec3::new(14.0, 11.0, 32.0),
            ),
            "cornell" => (1_000..20_000, Vec3::splat(2.0), Vec3::splat(2.2)),
            "foliage" => (
                50_000..150_000,
                Vec3::new(199.0, 5.0, 199.0),
                Vec3::new(201.0, 9.0, 201.0),
            ),
            "mirrors" => (
                5_000..20_000,
                Vec3::new(8.1, 4.1, 10.6),
                Vec3::new(8.3, 4.3, 10.8),
            ),
            "mirrors-open" => (
                8_000..25_000,
                Vec3::new(299.9, 2.6, 299.9),
                Vec3::new(300.1, 2.8, 300.1),
            ),
            other => panic!("unexpected scene {other}"),
        };
        println!(
            "{}: {n} triangles, {} objects, extent {e}",
            s.name,
            s.mesh.objects.len()
        );
        assert!(tri_range.contains(&n), "{}: {n} triangles", s.name);
        assert!(
            e.cmpge(ext_min).all() && e.cmple(ext_max).all(),
            "{}: extent {e}",
            s.name
        );
        // The ground / floor is at y = 0, not below the bounds' bottom by more than a slab.
        assert!(
            s.bounds().min.y > -0.3 && s.bounds().min.y < 0.0,
            "{}",
            s.name
        );
    }
}

#[test]
fn solids_are_closed_outward_and_normals_agree() {
    for s in scenes() {
        let solids = solid_ranges(&s.mesh);
        let solid_tris: usize = solids.iter().map(|r| r.len()).sum();
        // Everything but the Cornell light quad is a closed solid.
        let open = s.mesh.triangle_count() - solid_tris;
        assert!(
            open <= 2,
            "{}: {open} triangles outside closed objects",
            s.name
        );
        for (o, r) in s
            .mesh
            .objects
            .iter()
            .filter(|o| o.name.starts_with("solid:"))
            .zip(&solids)
        {
            check_closed(&s.mesh, r.clone())
                .unwrap_or_else(|e| panic!("{}/{}: {e}", s.name, o.name));
            let v = signed_volume(&s.mesh, r.clone());
            assert!(v > 0.0, "{}/{}: signed volume {v}", s.name, o.name);
        }
        // Shading normals, where given, lie on the outer side of their triangle.
        let m = &s.mesh;
        for i in 0..m.triangle_count() {
            let g = m.geometric_normal(i);
            assert!(g != Vec3::ZERO, "{}: degenerate triangle {i}", s.name);
            for v in m.indices[i] {
                let n = m.normals[v as usize];
                if n != Vec3::ZERO {
                    assert!(
                        (n.length() - 1.0).abs() < 1e-3,
                        "{}: normal {n} not unit",
                        s.name
                    );
                    assert!(
                        n.dot(g) > 0.5,
                        "{}: triangle {i} normal {n} vs face {g}",
                        s.name
                    );
                }
            }
        }
    }
}

#[test]
fn shapes_are_closed_with_the_expected_volume() {
    let xf =
        Affine3A::from_rotation_translation(Quat::from_rotation_y(0.7), Vec3::new(1.0, 2.0, 3.0));
    let n = 64u32;
    let polygon = 0.5 * n as f64 * (std::f64::consts::TAU / n as f64).sin();
    let (r, s, h, d) = (1.0f32, 0.5f32, 1.6f32, 0.8f32);
    // Inscribed half-polygon of the arch opening (24 segments).
    let half_poly = 0.5 * 24.0 * (std::f64::consts::PI / 24.0).sin();
    type Build = Box<dyn Fn(&mut MeshBuilder)>;
    let cases: Vec<(&str, Build, f64, f64)> = vec![
        (
            "box",
            Box::new(move |b| b.boxed(xf, Vec3::new(1.0, 1.5, 2.0), 0)),
            24.0,
            1e-4,
        ),
        (
            "cuboid",
            Box::new(|b| b.cuboid(Vec3::ZERO, Vec3::new(2.0, 1.0, 0.5), 0)),
            1.0,
            1e-4,
        ),
        (
            "tiled slab",
            Box::new(|b| {
                b.tiled_slab(
                    &[-3.0, -1.0, 0.5, 2.0],
                    &[0.0, 1.0, 4.0],
                    [-0.25, 0.0],
                    |_, _| 0,
                    0,
                )
            }),
            5.0 * 4.0 * 0.25,
            1e-4,
        ),
        (
            "cylinder",
            Box::new(move |b| b.cylinder(Vec3::ONE, Vec3::new(1.0, 1.0, 3.0), 1.0, 1.0, n, 0)),
            polygon * 2.0,
            1e-4,
        ),
        (
            "sphere",
            Box::new(|b| b.sphere(Vec3::ZERO, 1.0, 96, 48, 0)),
            4.0 / 3.0 * std::f64::consts::PI,
            5e-3,
        ),
        (
            "arch",
            Box::new(move |b| b.arch(xf, r, s, h, d, 24, 0)),
            (2.0 * (r + s) as f64 * h as f64 - half_poly * (r * r) as f64) * d as f64,
            1e-4,
        ),
        (
            "sheet",
            Box::new(|b| {
                b.sheet(8, 5, 0.02, 0, |u, v| {
                    (Vec3::new(2.0 * u, 3.0 * v, 0.0), Vec3::Z)
                })
            }),
            6.0 * 0.02,
            1e-3,
        ),
        (
            "tetra",
            Box::new(|b| b.tetra([Vec3::ZERO, Vec3::Y, Vec3::X, Vec3::Z], 0)),
            1.0 / 6.0,
            1e-5,
        ),
        (
            "strand",
            Box::new(|b| {
                b.strand(
                    &[Vec3::ZERO, Vec3::Y, Vec3::new(0.3, 2.0, 0.0)],
                    &[(0.1, 0.02), (0.07, 0.015), (0.0, 0.0)],
                    Vec3::X,
                    3,
                    0,
                )
            }),
            f64::NAN,
            0.0,
        ),
    ];
    for (name, build, expected, tol) in cases {
        let mut b = MeshBuilder::new();
        b.object(name, |b| build(b));
        let m = b.finish();
        assert_eq!(m.objects.len(), 1);
        assert_eq!(m.objects[0].triangle_count as usize, m.triangle_count());
        m.validate(1).unwrap();
        check_closed(&m, 0..m.triangle_count()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let v = signed_volume(&m, 0..m.triangle_count());
        assert!(v > 0.0, "{name}: volume {v}");
        if expected.is_finite() {
            assert!(
                (v - expected).abs() <= tol * expected.max(1.0),
                "{name}: volume {v}, expected {expected}"
            );
        }
    }
}

#[test]
fn tiled_floors_have_no_inner_walls() {
    // Every triangle of a floor slab lies on its bounding box: adjacent tiles as separate boxes
    // would leave coincident walls between them, surfaces no ray reaches that hidden depth
    // layers nevertheless capture (black answers in cube-map reflections of the far ground).
    for name in ["mirrors", "mirrors-open"] {
        let s = Scene::load(name).unwrap();
        let o = s
            .mesh
            .objects
            .iter()
            .find(|o| o.name == "solid:floor")
            .unwrap();
        let r = o.first_triangle as usize..(o.first_triangle + o.triangle_count) as usize;
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for i in r.clone() {
            for p in s.mesh.triangle(i) {
                (lo, hi) = (lo.min(p), hi.max(p));
            }
        }
        for i in r {
            let t = s.mesh.triangle(i);
            let on = |a: usize, v: f32| t.iter().all(|p| p[a] == v);
            assert!(
                (0..3).any(|a| on(a, lo[a]) || on(a, hi[a])),
                "{name}: floor triangle {i} {t:?} inside the slab"
            );
        }
    }
}

#[test]
fn named_cameras_see_geometry_from_outside_solids() {
    for s in scenes() {
        let solids = solid_ranges(&s.mesh);
        let bounds = s.bounds();
        for c in &s.cameras {
            let ray = camera_ray(&c.desc, 16.0 / 9.0, 0.0, 0.0);
            let inv = ray.dir.recip();
            assert!(
                bounds.intersect(&ray, inv).is_some(),
                "{}/{} looks away",
                s.name,
                c.name
            );
            let (hits, t) = all_hits(&s.mesh, &ray);
            assert!(
                hits > 0 && t < 100.0,
                "{}/{}: centre ray hits nothing",
                s.name,
                c.name
            );
            // Most of a square frame (inner 80 %) shows geometry, not sky.
            let mut seen = 0;
            for j in 0..5 {
                for i in 0..5 {
                    let (sx, sy) = (0.4 * i as f32 - 0.8, 0.4 * j as f32 - 0.8);
                    seen += (all_hits(&s.mesh, &camera_ray(&c.desc, 1.0, sx, sy)).0 > 0) as usize;
                }
            }
            assert!(seen >= 13, "{}/{}: only {seen}/25 rays hit", s.name, c.name);
            assert_eye_outside(&s, &solids, c.desc.eye, &c.name);
        }
    }
}

#[test]
fn camera_paths_are_valid_continuous_and_outside_solids() {
    for s in scenes() {
        let solids = solid_ranges(&s.mesh);
        let p = s.camera_path.as_ref().unwrap();
        let frames: Vec<CameraDesc> = (0..p.frames).map(|i| p.frame(i)).collect();
        let mut travelled = 0.0;
        for (i, f) in frames.iter().enumerate() {
            f.validate()
                .unwrap_or_else(|e| panic!("{} frame {i}: {e}", s.name));
            if i % 6 == 0 {
                assert_eye_outside(&s, &solids, f.eye, &format!("frame {i}"));
            }
        }
        for w in frames.windows(2) {
            let step = w[0].eye.distance(w[1].eye);
            let turn = (w[0].target - w[0].eye)
                .normalize()
                .angle_between((w[1].target - w[1].eye).normalize());
            assert!(step < 0.2, "{}: eye jumps {step} m in one frame", s.name);
            assert!(
                turn < 3f32.to_radians(),
                "{}: view turns {turn} rad in one frame",
                s.name
            );
            travelled += step;
        }
        println!(
            "{}: path travels {travelled:.2} m over {} frames",
            s.name, p.frames
        );
        assert!(
            travelled > 0.5,
            "{}: the camera barely moves ({travelled} m)",
            s.name
        );
    }
}

#[test]
fn foliage_depth_complexity_is_high() {
    let s = builtin::by_name("foliage").unwrap();
    let cam = s.camera(Some("main")).unwrap();
    let mut counts = Vec::with_capacity(16 * 9);
    for j in 0..9 {
        for i in 0..16 {
            let sx = (i as f32 + 0.5) / 16.0 * 2.0 - 1.0;
            let sy = 1.0 - (j as f32 + 0.5) / 9.0 * 2.0;
            counts.push(all_hits(&s.mesh, &camera_ray(&cam, 16.0 / 9.0, sx, sy)).0);
        }
    }
    counts.sort_unstable();
    let median = counts[counts.len() / 2];
    println!(
        "foliage depth complexity: min {} median {median} max {}",
        counts[0],
        counts[counts.len() - 1]
    );
    assert!(median >= 8, "median depth complexity {median}");
}

#[test]
fn generation_is_deterministic() {
    for &name in builtin::NAMES {
        let t = std::time::Instant::now();
        let a = builtin::by_name(name).unwrap();
        let elapsed = t.elapsed();
        let b = builtin::by_name(name).unwrap();
        println!("{name}: generated in {elapsed:?}");
        assert_eq!(a.mesh, b.mesh, "{name}");
        assert_eq!(a.cameras, b.cameras, "{name}");
        assert_eq!(a.camera_path, b.camera_path, "{name}");
        assert_eq!(a.materials, b.materials, "{name}");
    }
}

#[test]
fn the_checks_themselves_catch_holes_flips_and_insides() {
    let mut b = MeshBuilder::new();
    b.object("solid:box", |b| b.cuboid(Vec3::ZERO, Vec3::ONE, 0));
    let closed = b.finish();
    assert!(check_closed(&closed, 0..12).is_ok());
    // A hole: one triangle missing.
    assert!(check_closed(&closed, 0..11).is_err());
    // A flipped face: edges no longer pair up with opposite orientation.
    let mut flipped = closed.clone();
    flipped.indices[0].swap(1, 2);
    assert!(check_closed(&flipped, 0..12).is_err());
    // Parity: odd from inside, even from outside.
    let solids = solid_ranges(&closed);
    let inside = Ray::new(Vec3::splat(0.5), Vec3::X);
    let outside = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::X);
    assert_eq!(solid_crossings(&closed, &solids, &inside), 1);
    assert_eq!(solid_crossings(&closed, &solids, &outside), 2);
}
