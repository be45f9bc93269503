//! Camera models: round trips (film -> ray -> project), fields of view, stereo geometry, cube-map
//! coverage, thin-lens focus, ray differentials against finite differences, and error cases.
//! Error cases and the property tests over random poses: `cameras_errors.rs`.

use glam::{DVec3, Vec2, Vec3};
use parallax_scene::camera::{
    Camera, CameraModel, CameraOptions, CameraRay, CubeMap, Eye, ModelKind, Pinhole, ThinLens,
    eye_camera,
};

#[path = "common/camera_fixtures.rs"]
mod fixtures;
use fixtures::Rng;
use fixtures::*;

#[test]
fn film_ray_project_round_trips_for_every_model_and_channel() {
    let opts = CameraOptions::default();
    for kind in ModelKind::ALL {
        let cam = build(kind, &desc(), &opts);
        let (mut checked, mut uncovered, mut skipped) = (0, 0, 0);
        let positions = film_positions(&cam, 7);
        for &film in &positions {
            if near_pole(&cam, film) {
                skipped += 1;
                continue;
            }
            for c in 0..3 {
                let Some(ray) = cam.generate_ray(film, LENS_CENTRE, c) else {
                    assert!(
                        !is_covered(&cam, film),
                        "{kind:?}: no ray at covered {film}"
                    );
                    uncovered += 1;
                    continue;
                };
                assert!(
                    is_covered(&cam, film),
                    "{kind:?}: ray outside coverage {film}"
                );
                assert!((ray.ray.dir.length() - 1.0).abs() < 1e-5);
                let pc = project_channel(&cam, film, c);
                for t in [0.25, 1.0, 5.0, 40.0] {
                    let p = ray.ray.at(t);
                    let back = cam
                        .project(p, pc)
                        .unwrap_or_else(|| panic!("{kind:?} c{c}: {film} t={t} not projected"));
                    let err = film_distance(&cam, back, film);
                    assert!(
                        err < 1e-3,
                        "{kind:?} c{c}: {film} t={t} -> {back} ({err} px)"
                    );
                    assert!(ray.view_depth(t) > 0.0, "{kind:?}: depth along the ray");
                    checked += 1;
                }
            }
        }
        assert_eq!(checked + 4 * uncovered, 4 * 3 * (positions.len() - skipped));
        assert!(
            skipped < positions.len() / 10,
            "{kind:?}: {skipped} skipped"
        );
        if kind == ModelKind::Fisheye {
            // The corners outside the inscribed ellipse (1 - pi/4 of the film).
            let frac = uncovered as f32 / (3 * (W * H + 400)) as f32;
            assert!(
                (frac - (1.0 - std::f32::consts::FRAC_PI_4)).abs() < 0.03,
                "{frac}"
            );
        } else {
            assert_eq!(uncovered, 0, "{kind:?}");
        }
    }
}

/// Angle between two directions, accurate also for tiny angles (atan2 of |a x b| and a . b).
fn angle(a: Vec3, b: Vec3) -> f64 {
    let (a, b) = (a.as_dvec3(), b.as_dvec3());
    a.cross(b).length().atan2(a.dot(b))
}

/// The angle the ray sweeps (degrees) as the film position runs from `a` to `b`.
fn sweep(cam: &dyn CameraModel, a: Vec2, b: Vec2, channel: usize) -> f64 {
    let n = 256;
    let dir = |i: usize| {
        let f = a + (b - a) * (i as f32 / n as f32);
        cam.generate_ray(f, LENS_CENTRE, channel)
            .unwrap_or_else(|| panic!("no ray at {f}"))
            .ray
            .dir
    };
    (0..n)
        .map(|i| angle(dir(i), dir(i + 1)))
        .sum::<f64>()
        .to_degrees()
}

fn sweeps(cam: &dyn CameraModel, channel: usize) -> (f64, f64) {
    let (w, h) = (cam.width() as f32, cam.height() as f32);
    (
        sweep(cam, Vec2::new(0.0, h / 2.0), Vec2::new(w, h / 2.0), channel),
        sweep(cam, Vec2::new(w / 2.0, 0.0), Vec2::new(w / 2.0, h), channel),
    )
}

fn assert_close(a: f64, b: f64, tol: f64, what: &str) {
    assert!((a - b).abs() <= tol, "{what}: {a} vs {b}");
}

#[test]
fn planar_models_cover_the_pose_field_of_view() {
    let d = desc();
    let opts = CameraOptions::default();
    let fov_x = 2.0 * ((27.5f64).to_radians().tan() * W as f64 / H as f64).atan();
    for kind in [ModelKind::Pinhole, ModelKind::ThinLens] {
        let (h, v) = sweeps(&build(kind, &d, &opts), 0);
        assert_close(v, 55.0, 1e-2, "vertical fov");
        assert_close(h, fov_x.to_degrees(), 1e-2, "horizontal fov");
    }
    // Stereo: each eye is a pinhole of the pose's fov on its half of the film.
    let Camera::Stereo(rig) = build(ModelKind::Stereo, &d, &opts) else {
        unreachable!()
    };
    for eye in [Eye::Left, Eye::Right] {
        let e = rig.eye(eye);
        let (_, v) = sweeps(e, 0);
        assert_close(v, 55.0, 1e-2, "eye vertical fov");
    }
    let hw = (W / 2) as f32;
    let left_half = sweep(&rig, Vec2::new(0.0, 16.0), Vec2::new(hw - 1e-3, 16.0), 0);
    let right_half = sweep(&rig, Vec2::new(hw, 16.0), Vec2::new(2.0 * hw, 16.0), 0);
    let eye_fov_x = 2.0 * ((27.5f64).to_radians().tan() * hw as f64 / H as f64).atan();
    assert_close(
        left_half,
        eye_fov_x.to_degrees(),
        1e-2,
        "left eye horizontal",
    );
    assert_close(
        right_half,
        eye_fov_x.to_degrees(),
        1e-2,
        "right eye horizontal",
    );
    // Orthographic: parallel rays; the default view is 2 |target - eye| tan(fov/2) tall.
    let ortho = build(ModelKind::Orthographic, &d, &opts);
    let top = ortho
        .generate_ray(Vec2::new(24.0, 0.0), LENS_CENTRE, 0)
        .unwrap();
    let bottom = ortho
        .generate_ray(Vec2::new(24.0, 32.0), LENS_CENTRE, 0)
        .unwrap();
    let left = ortho
        .generate_ray(Vec2::new(0.0, 16.0), LENS_CENTRE, 0)
        .unwrap();
    let right = ortho
        .generate_ray(Vec2::new(48.0, 16.0), LENS_CENTRE, 0)
        .unwrap();
    let expect = 2.0 * (d.target - d.eye).length() * (27.5f32).to_radians().tan();
    assert!(((top.ray.origin - bottom.ray.origin).length() - expect).abs() < 1e-4);
    assert!(((left.ray.origin - right.ray.origin).length() - 1.5 * expect).abs() < 1e-4);
    assert!(angle(top.ray.dir, bottom.ray.dir) < 1e-7);
    assert!(angle(top.ray.dir, d.target - d.eye) < 1e-6);
    let explicit = Camera::new(
        ModelKind::Orthographic,
        &d,
        W,
        H,
        &CameraOptions {
            ortho_height: Some(3.0),
            ..opts
        },
    )
    .unwrap();
    let t = explicit
        .generate_ray(Vec2::new(24.0, 0.0), LENS_CENTRE, 0)
        .unwrap();
    let b = explicit
        .generate_ray(Vec2::new(24.0, 32.0), LENS_CENTRE, 0)
        .unwrap();
    assert!(((t.ray.origin - b.ray.origin).length() - 3.0).abs() < 1e-5);
}

#[test]
fn equirect_and_fisheye_span_their_stated_fields_of_view() {
    let d = desc();
    for (kind, fov, expect) in [
        (ModelKind::Equirect, None, (360.0, 180.0)),
        (
            ModelKind::Equirect,
            Some(Vec2::new(200.0, 100.0)),
            (200.0, 100.0),
        ),
        (ModelKind::Fisheye, None, (210.0, 130.0)),
        (
            ModelKind::Fisheye,
            Some(Vec2::new(300.0, 200.0)),
            (300.0, 200.0),
        ),
        (
            ModelKind::Fisheye,
            Some(Vec2::new(90.0, 60.0)),
            (90.0, 60.0),
        ),
    ] {
        let opts = CameraOptions {
            fov_deg: fov,
            ..Default::default()
        };
        let cam = build(kind, &d, &opts);
        let (h, v) = sweeps(&cam, 0);
        assert_close(h, expect.0, 1e-2, &format!("{kind:?} {fov:?} horizontal"));
        assert_close(v, expect.1, 1e-2, &format!("{kind:?} {fov:?} vertical"));
        // The edge rays sit half the fov from forward (left/right of it, up/down).
        let fwd = (d.target - d.eye).normalize();
        let ray = |x: f32, y: f32| cam.generate_ray(Vec2::new(x, y), LENS_CENTRE, 0).unwrap();
        let (r, t) = (ray(W as f32, 16.0), ray(24.0, 0.0));
        if expect.0 < 360.0 {
            assert_close(
                angle(r.ray.dir, fwd).to_degrees(),
                expect.0 / 2.0,
                1e-3,
                "right",
            );
        }
        assert_close(
            angle(t.ray.dir, fwd).to_degrees(),
            expect.1 / 2.0,
            1e-3,
            "top",
        );
        let CameraRay { depth_axis, .. } = r;
        assert_eq!(
            depth_axis, r.ray.dir,
            "spherical models measure radial depth"
        );
    }
}

#[test]
fn distorted_view_keeps_the_pose_fov_at_the_centre_and_splits_colours() {
    let d = desc();
    let opts = CameraOptions::default();
    let cam = build(ModelKind::Distorted, &d, &opts);
    let pin = Pinhole::new(&d, W, H).unwrap();
    let centre = Vec2::new(24.0, 16.0);
    let p = pin.generate_ray(centre, LENS_CENTRE, 0).unwrap();
    for c in 0..3 {
        let r = cam.generate_ray(centre, LENS_CENTRE, c).unwrap();
        assert!(angle(r.ray.dir, p.ray.dir) < 1e-6);
        // Same angular pixel size at the centre as the undistorted pinhole.
        let dx = r.differential.d_dir_dx.length() / p.differential.d_dir_dx.length();
        let dy = r.differential.d_dir_dy.length() / p.differential.d_dir_dy.length();
        assert!(
            (dx - 1.0).abs() < 1e-5 && (dy - 1.0).abs() < 1e-5,
            "{dx} {dy}"
        );
        // Top edge of the centre column: r_d = 1, so tan(angle) = tan(fov/2) (1 + k1 + k2).
        let [k1, k2] = opts.distortion[c];
        let expect = ((27.5f64).to_radians().tan() * (1.0 + k1 as f64 + k2 as f64)).atan();
        let (_, v) = sweeps(&cam, c);
        assert_close(v, 2.0 * expect.to_degrees(), 1e-2, "distorted vertical");
    }
    // Chromatic: at the film corner red, green and blue look in different directions.
    let corner = Vec2::new(1.0, 1.0);
    let r = cam.generate_ray(corner, LENS_CENTRE, 0).unwrap().ray.dir;
    let b = cam.generate_ray(corner, LENS_CENTRE, 2).unwrap().ray.dir;
    assert!(angle(r, b).to_degrees() > 0.5);
}

#[test]
fn stereo_eyes_are_ipd_apart_and_parallel() {
    let d = desc();
    for ipd in [0.0, 0.065, 0.3] {
        let opts = CameraOptions {
            ipd,
            ..Default::default()
        };
        let Camera::Stereo(rig) = build(ModelKind::Stereo, &d, &opts) else {
            unreachable!()
        };
        let (l, r) = (rig.eye(Eye::Left), rig.eye(Eye::Right));
        let sep = r.frame.position - l.frame.position;
        assert!((sep.length() - ipd).abs() < 1e-6, "{ipd}");
        if ipd > 0.0 {
            // f32 positions near (1, 2, 3): the difference carries ~2e-7 m of rounding.
            assert!(angle(sep, l.frame.right()) < 2e-5, "separated along right");
        }
        assert!(((l.frame.position + r.frame.position) * 0.5 - d.eye).length() < 1e-6);
        assert!((l.frame.basis - r.frame.basis).abs_diff_eq(glam::Mat3::ZERO, 1e-7));
        // The same pixel of both eyes: parallel rays.
        for film in [Vec2::new(3.5, 7.5), Vec2::new(20.25, 30.0)] {
            let a = rig.generate_ray(film, LENS_CENTRE, 0).unwrap();
            let b = rig
                .generate_ray(film + Vec2::new(24.0, 0.0), LENS_CENTRE, 0)
                .unwrap();
            assert!(angle(a.ray.dir, b.ray.dir) < 1e-6);
            assert!((b.ray.origin - a.ray.origin - sep).length() < 1e-6);
        }
        // A point at depth z: disparity = ipd * focal_px / z (pixels).
        let z = 4.0;
        let p = d.eye + (d.target - d.eye).normalize() * z;
        let (pl, pr) = (rig.project(p, 0).unwrap(), rig.project(p, 1).unwrap());
        let focal_px = H as f32 / 2.0 / (27.5f32).to_radians().tan();
        let disparity = pl.x - (pr.x - 24.0);
        assert!((disparity - ipd * focal_px / z).abs() < 1e-3, "{disparity}");
        let desc_l = eye_camera(&d, ipd, Eye::Left).unwrap();
        assert_eq!(l, &Pinhole::new(&desc_l, 24, H).unwrap());
    }
}

#[test]
fn cube_faces_are_90_degrees_and_tile_the_sphere() {
    let d = desc();
    let face = 16u32;
    let cube = CubeMap::new(&d, face).unwrap();
    let s = face as f32;
    for i in 0..6 {
        let fc = cube.face_camera(i);
        let (h, v) = sweeps(&fc, 0);
        assert_close(h, 90.0, 1e-2, "face horizontal");
        assert_close(v, 90.0, 1e-2, "face vertical");
        let c = cube.generate_ray(Vec2::new((i as f32 + 0.5) * s, s / 2.0), LENS_CENTRE, 0);
        let c = c.unwrap();
        assert!(angle(c.ray.dir, parallax_scene::camera::cube::FACE_AXES[i]) < 1e-6);
        assert_eq!(c.depth_axis, parallax_scene::camera::cube::FACE_AXES[i]);
    }
    // Random directions land on exactly one face and come back.
    let inside = |f: Vec2| f.x >= 0.0 && f.x <= s && f.y >= 0.0 && f.y <= s;
    let mut rng = Rng(99);
    let mut per_face = [0usize; 6];
    for _ in 0..3000 {
        let dir = rng.unit_vector();
        let p = d.eye + dir * 3.0;
        let hits: Vec<usize> = (0..6)
            .filter(|&i| cube.face_camera(i).project(p, 0).is_some_and(inside))
            .collect();
        assert_eq!(hits.len(), 1, "{dir}: faces {hits:?}");
        let f = cube.project(p, 0).unwrap();
        assert_eq!((f.x / s) as usize, hits[0]);
        per_face[hits[0]] += 1;
        let back = cube.generate_ray(f, LENS_CENTRE, 0).unwrap();
        assert!(angle(back.ray.dir, dir) < 1e-5, "{dir}");
    }
    // Roughly a sixth each (binomial sd ~ 20).
    assert!(
        per_face.iter().all(|&n| (400..600).contains(&n)),
        "{per_face:?}"
    );
    // No gaps: every edge ray of a face is an edge ray of a neighbour face.
    for i in 0..6 {
        let fc = cube.face_camera(i);
        for k in 0..=8 {
            let t = k as f32 / 8.0 * s;
            for film in [
                Vec2::new(0.0, t),
                Vec2::new(s, t),
                Vec2::new(t, 0.0),
                Vec2::new(t, s),
            ] {
                let dir = fc.generate_ray(film, LENS_CENTRE, 0).unwrap().ray.dir;
                let p = d.eye + dir;
                let on_edge = |f: Vec2| {
                    inside(f.clamp(Vec2::ZERO, Vec2::splat(s)))
                        && (f - f.clamp(Vec2::ZERO, Vec2::splat(s))).length() < 1e-4
                        && [f.x, f.y, s - f.x, s - f.y].iter().any(|e| e.abs() < 1e-4)
                };
                let faces: Vec<usize> = (0..6)
                    .filter(|&j| cube.face_camera(j).project(p, 0).is_some_and(on_edge))
                    .collect();
                assert!(
                    faces.len() >= 2 && faces.contains(&i),
                    "{i} {film}: {faces:?}"
                );
            }
        }
    }
}

#[test]
fn thin_lens_samples_converge_on_the_focus_plane() {
    let d = desc();
    let focus = 2.5;
    let tl = ThinLens::new(&d, W, H, 0.1, Some(focus)).unwrap();
    let fwd = (d.target - d.eye).normalize();
    let mut rng = Rng(5);
    for film in [
        Vec2::new(24.0, 16.0),
        Vec2::new(0.5, 31.5),
        Vec2::new(40.25, 3.75),
    ] {
        let p_focus = tl.focus_point(film);
        let centre = tl.generate_ray(film, LENS_CENTRE, 0).unwrap();
        assert!((centre.ray.origin - d.eye).length() < 1e-6);
        assert!(angle(centre.ray.dir, p_focus - d.eye) < 1e-6);
        let mut max_spread = 0.0f32;
        for _ in 0..64 {
            let lens = Vec2::new(rng.next_f32(), rng.next_f32());
            let r = tl.generate_ray(film, lens, 0).unwrap();
            // The origin lies on the lens disk (in the eye plane) ...
            let off = r.ray.origin - d.eye;
            assert!(off.dot(fwd).abs() < 1e-6 && off.length() <= 0.1 + 1e-6);
            // ... and the ray meets the focus plane at the focus point.
            let t = focus / r.ray.dir.dot(fwd);
            assert!((r.ray.at(t) - p_focus).length() < 1e-5, "{film} {lens}");
            // At twice the focus distance the rays spread by the lens offset (blur).
            let t2 = 2.0 * focus / r.ray.dir.dot(fwd);
            let c2 = centre.ray.at(2.0 * focus / centre.ray.dir.dot(fwd));
            let spread = (r.ray.at(t2) - c2).length();
            assert!((spread - off.length()).abs() < 1e-5);
            max_spread = max_spread.max(spread);
        }
        assert!(max_spread > 0.05, "{max_spread}");
        // The rim of the lens (concentric map of the square's edge) is at the aperture radius.
        let rim = tl.generate_ray(film, Vec2::new(1.0, 0.5), 0).unwrap();
        assert!(((rim.ray.origin - d.eye).length() - 0.1).abs() < 1e-6);
    }
}

/// Central finite difference of origin and direction over +-`h` pixels.
fn finite_difference(cam: &Camera, film: Vec2, lens: Vec2, c: usize, step: Vec2) -> (DVec3, DVec3) {
    let h = 0.05f32;
    let a = cam.generate_ray(film - step * h, lens, c).unwrap().ray;
    let b = cam.generate_ray(film + step * h, lens, c).unwrap().ray;
    let k = 1.0 / (2.0 * h as f64);
    (
        (b.origin.as_dvec3() - a.origin.as_dvec3()) * k,
        (b.dir.as_dvec3() - a.dir.as_dvec3()) * k,
    )
}

#[test]
fn differentials_agree_with_finite_differences() {
    let opts = CameraOptions::default();
    let lens = Vec2::new(0.3, 0.85);
    for kind in ModelKind::ALL {
        let cam = build(kind, &desc(), &opts);
        let (w, h) = (cam.width() as f32, cam.height() as f32);
        let mut rng = Rng(kind as u64 + 11);
        let mut checked = 0;
        for _ in 0..200 {
            let film = Vec2::new(rng.next_f32() * w, rng.next_f32() * h);
            // Stay 0.1 px away from view seams (stereo halves, cube faces) and the film edge.
            let seam = match kind {
                ModelKind::Stereo => w / 2.0,
                ModelKind::Cube => h,
                _ => w,
            };
            let fx = film.x % seam;
            if fx < 0.1 || fx > seam - 0.1 || film.y < 0.1 || film.y > h - 0.1 {
                continue;
            }
            if !is_covered(&cam, film - Vec2::splat(0.1))
                || !is_covered(&cam, film + Vec2::splat(0.1))
                || !is_covered(&cam, film + Vec2::new(0.1, -0.1))
                || !is_covered(&cam, film + Vec2::new(-0.1, 0.1))
            {
                continue;
            }
            for c in 0..3 {
                let r = cam.generate_ray(film, lens, c).unwrap();
                let diff = r.differential;
                for (step, d_o, d_d) in [
                    (Vec2::X, diff.d_origin_dx, diff.d_dir_dx),
                    (Vec2::Y, diff.d_origin_dy, diff.d_dir_dy),
                ] {
                    let (fo, fd) = finite_difference(&cam, film, lens, c, step);
                    let e_o = (d_o.as_dvec3() - fo).length();
                    let e_d = (d_d.as_dvec3() - fd).length();
                    assert!(
                        e_o <= 1e-3 * fo.length() + 2e-5,
                        "{kind:?} c{c} {film} {step}: origin {d_o} vs {fo}"
                    );
                    assert!(
                        e_d <= 1e-3 * fd.length() + 2e-5,
                        "{kind:?} c{c} {film} {step}: dir {d_d} vs {fd}"
                    );
                    // The differential is a real footprint (non-degenerate).
                    assert!(fo.length() + fd.length() > 1e-3, "{kind:?}");
                    checked += 1;
                }
            }
        }
        assert!(checked > 300, "{kind:?}: {checked}");
    }
}

/// `CameraModel::ray` is `generate_ray`'s ray bit for bit, for every model and channel, on
/// random film positions inside, on and outside the film (and NaN), random lens samples and an
/// out-of-range channel; both say `None` at the same places.
#[test]
fn ray_alone_equals_the_generated_ray() {
    let opts = CameraOptions::default();
    let mut rng = Rng(0x7a1e_5eed);
    let mut range = |lo: f32, hi: f32| lo + (hi - lo) * rng.next_f32();
    let bits = |r: &parallax_core::Ray| {
        [r.origin.to_array(), r.dir.to_array()].map(|v| v.map(f32::to_bits))
    };
    for kind in ModelKind::ALL {
        let cam = build(kind, &desc(), &opts);
        let (w, h) = (cam.width() as f32, cam.height() as f32);
        let mut films: Vec<Vec2> = (0..2000)
            .map(|_| Vec2::new(range(-0.2, 1.2) * w, range(-0.2, 1.2) * h))
            .collect();
        films.extend([
            Vec2::ZERO,
            Vec2::new(w, h),
            Vec2::new(w, h) * 0.5,
            Vec2::NAN,
        ]);
        let (mut some, mut none) = (0, 0);
        for &film in &films {
            let lens = Vec2::new(range(0.0, 1.0), range(0.0, 1.0));
            for c in 0..4 {
                let full = cam.generate_ray(film, lens, c).map(|r| bits(&r.ray));
                let alone = cam.ray(film, lens, c).map(|r| bits(&r));
                assert_eq!(alone, full, "{kind:?} film {film} lens {lens} channel {c}");
                if full.is_some() { some += 1 } else { none += 1 }
            }
        }
        assert!(some > 1000, "{kind:?}: {some} rays, {none} none");
    }
}
