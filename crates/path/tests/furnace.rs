//! Closed-form checks of the estimator (white furnaces).
//!
//! 1. A convex Lambertian sphere of albedo 1 under a constant environment `L` returns `L`
//!    at every pixel, with zero variance: BSDF sampling alone gives `L` (no ray re-hits a convex
//!    surface); with environment connections (`env_nee = 1`) both strategies sample the cosine
//!    lobe, so each of the two MIS-weighted terms is exactly `L / 2`; with `env_nee = 1/2` the
//!    weights are 4/5 and 1/5 and the connection, taken half the time, counts twice. The bound
//!    is float rounding (1e-4 relative).
//! 2. The inside of a closed box whose walls emit `Le` and reflect albedo `ρ`: every radiance
//!    is `Le / (1 - ρ)` (the rendering equation's uniform solution). The estimator is noisy
//!    here (light choice, Russian roulette); the image mean must lie within 5 standard errors,
//!    the standard error computed from the render's own per-pixel variances (independent
//!    streams per pixel and sample, so the central limit theorem applies to the mean over
//!    pixels), plus the truncation bias `ρ^max_depth Le / (1 - ρ)` (negligible at depth 64).
//! 3. A smooth glass sphere (and a thin-glass one) under `L`: every path leaves with
//!    radiance `L` (reflection and refraction only redirect light; the `1 / eta²` of entering
//!    cancels on leaving), so the mean is `L` within 5 standard errors (Russian roulette
//!    with `q = min(throughput · eta², 0.95)` is the noise).

mod common;

use common::*;
use glam::Vec3;
use parallax_path::PathOptions;
use parallax_render::bsdf::MaterialMode;
use parallax_scene::{Material, MaterialKind};

#[test]
fn lambertian_sphere_in_a_uniform_sky_returns_the_sky_exactly() {
    let l = Vec3::new(0.5, 0.7, 1.1);
    let s = scene(
        "furnace",
        icosphere(Vec3::ZERO, 1.0, 2),
        Material::diffuse("white", Vec3::ONE),
        l,
    );
    let cam = pinhole(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 45.0, 24, 24);
    for env_nee in [0.0, 0.5, 1.0] {
        let out = render(
            &s,
            &cam,
            PathOptions {
                spp: 4,
                materials: MaterialMode::Diffuse,
                env_nee,
                ..PathOptions::default()
            },
        );
        // env_nee = 1/2 is not zero-variance: the connection is taken half the time. Its
        // weights (4/5 BSDF, 1/5 x 2 connection) still make every sample L or L (4/5 + 2/5) or
        // L (4/5), so check the mean there and every pixel elsewhere.
        if env_nee == 0.5 {
            let (mean, se) = mean_and_se(&out);
            let expect = l.element_sum() as f64 / 3.0;
            assert!(
                (mean - expect).abs() <= 5.0 * se + 1e-4,
                "{mean} vs {expect}"
            );
            continue;
        }
        for (i, p) in out.image.data().iter().enumerate() {
            let err = ((*p - l) / l).abs().max_element();
            assert!(err < 1e-4, "env_nee {env_nee}, pixel {i}: {p} vs {l}");
        }
        // The sphere covers the middle of the film: those pixels bounced, and with
        // connections they cast shadow rays.
        assert!(out.stats.bounces[1].rays > 0);
        assert_eq!(out.stats.bounces[0].shadow_rays > 0, env_nee > 0.0);
    }
}

#[test]
fn emitting_box_converges_to_le_over_one_minus_albedo() {
    let (rho, le) = (0.5f32, 1.0f32);
    let mat = Material {
        emissive: Vec3::splat(le),
        ..Material::diffuse("wall", Vec3::splat(rho))
    };
    let s = scene("box", inward_cube(1.0), mat, Vec3::ZERO);
    let cam = pinhole(
        Vec3::new(0.1, -0.2, 0.3),
        Vec3::new(0.5, 0.3, -1.0),
        90.0,
        16,
        16,
    );
    for materials in [MaterialMode::Diffuse, MaterialMode::AsIs] {
        if materials == MaterialMode::AsIs {
            // As-is the material is glTF metallic-roughness, not Lambertian: only check that
            // it converges below the Lambertian value (its energy loss is the GGX layer's).
            let out = render(
                &s,
                &cam,
                PathOptions {
                    spp: 16,
                    max_depth: 64,
                    materials,
                    ..PathOptions::default()
                },
            );
            let (mean, _) = mean_and_se(&out);
            assert!(mean > 1.0 && mean < 2.0, "{mean}");
            continue;
        }
        let out = render(
            &s,
            &cam,
            PathOptions {
                spp: 64,
                max_depth: 64,
                materials,
                ..PathOptions::default()
            },
        );
        let (mean, se) = mean_and_se(&out);
        let expect = (le / (1.0 - rho)) as f64;
        let bias = rho.powi(64) as f64 * expect;
        assert!(se > 0.0 && se < 0.02, "standard error {se}");
        assert!(
            (mean - expect).abs() <= 5.0 * se + bias,
            "mean {mean} vs {expect} (se {se})"
        );
    }
}

#[test]
fn glass_spheres_in_a_uniform_sky_return_the_sky_on_average() {
    let l = Vec3::splat(0.8);
    for (name, kind, materials) in [
        (
            "glass",
            MaterialKind::Dielectric { ior: 1.5 },
            MaterialMode::AsIs,
        ),
        (
            "thin",
            MaterialKind::Dielectric { ior: 1.5 },
            MaterialMode::Diffuse,
        ),
    ] {
        let mat = Material {
            kind,
            ..Material::diffuse(name, Vec3::ONE)
        };
        let s = scene(name, icosphere(Vec3::ZERO, 1.0, 2), mat, l);
        let cam = pinhole(Vec3::new(0.0, 0.0, 2.5), Vec3::ZERO, 40.0, 16, 16);
        let out = render(
            &s,
            &cam,
            PathOptions {
                spp: 64,
                max_depth: 256,
                materials,
                ..PathOptions::default()
            },
        );
        let (mean, se) = mean_and_se(&out);
        assert!(se > 0.0, "{name}: Russian roulette must add noise");
        assert!(
            (mean - 0.8).abs() <= 5.0 * se,
            "{name}: mean {mean} vs 0.8 (se {se})"
        );
        assert!(out.stats.depth() > 5, "{name}: paths stop too early");
    }
}

#[test]
fn a_point_light_over_a_lambertian_floor_matches_the_closed_form() {
    // Floor y = 0 (a big quad facing +y), albedo 0.5, point light of intensity I at height h:
    // direct radiance at x is rho / pi * I * h / d^3. max_depth 2 = direct light only.
    let mut m = parallax_scene::TriangleMesh::default();
    let e = 50.0;
    m.positions = vec![
        Vec3::new(-e, 0.0, -e),
        Vec3::new(e, 0.0, -e),
        Vec3::new(e, 0.0, e),
        Vec3::new(-e, 0.0, e),
    ];
    m.normals = vec![Vec3::ZERO; 4];
    m.uvs = vec![glam::Vec2::ZERO; 4];
    m.indices = vec![[0, 2, 1], [0, 3, 2]];
    m.material_ids = vec![0, 0];
    let mut s = scene(
        "floor",
        m,
        Material::diffuse("floor", Vec3::splat(0.5)),
        Vec3::ZERO,
    );
    let (i, h) = (10.0f32, 2.0f32);
    s.lights = vec![parallax_scene::Light::Point {
        position: Vec3::new(0.0, h, 0.0),
        intensity: Vec3::splat(i),
    }];
    // Looking down at the floor near the light: pixel centres map to floor points.
    let cam = pinhole(
        Vec3::new(0.3, 5.0, 0.0),
        Vec3::new(0.3, 0.0, 1.0),
        30.0,
        8,
        8,
    );
    let out = render(
        &s,
        &cam,
        PathOptions {
            spp: 256,
            max_depth: 2,
            materials: MaterialMode::Diffuse,
            ..PathOptions::default()
        },
    );
    use parallax_scene::camera::CameraModel;
    for y in 0..8 {
        for x in 0..8 {
            let r = cam
                .generate_ray(
                    glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5),
                    glam::Vec2::ZERO,
                    0,
                )
                .unwrap()
                .ray;
            let t = -r.origin.y / r.dir.y;
            let p = r.at(t);
            let d = (Vec3::new(0.0, h, 0.0) - p).length();
            let expect = 0.5 / std::f32::consts::PI * i * h / (d * d * d);
            let got = out.image.get(x, y).x;
            // The pixel averages the footprint: 2% covers the curvature over one pixel.
            assert!(
                (got - expect).abs() < 0.02 * expect,
                "pixel {x},{y}: {got} vs {expect}"
            );
        }
    }
}
