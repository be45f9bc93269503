//! Camera models: invalid poses, sizes and options are rejected with clear errors, and property
//! tests over random poses. Round trips, fields of view and differentials: `cameras.rs`.

use glam::{Vec2, Vec3};
use parallax_scene::camera::{Camera, CameraModel, CameraOptions, ModelKind, StereoRig, ThinLens};
use parallax_scene::{CameraDesc, SceneError};
use proptest::prelude::*;

#[path = "common/camera_fixtures.rs"]
mod fixtures;
use fixtures::*;

fn camera_error(r: Result<Camera, SceneError>) -> String {
    match r {
        Err(SceneError::Camera(m)) => m,
        Err(other) => panic!("expected a camera error, got {other}"),
        Ok(_) => panic!("expected an error"),
    }
}

#[test]
fn invalid_cameras_are_rejected_with_clear_errors() {
    let d = desc();
    let opts = CameraOptions::default();
    for kind in ModelKind::ALL {
        let new = |desc: &CameraDesc, w: u32, h: u32, o: &CameraOptions| {
            camera_error(Camera::new(kind, desc, w, h, o))
        };
        assert!(new(&d, 0, 10, &opts).contains("width and height"));
        assert!(new(&d, 10, 0, &opts).contains("width and height"));
        assert!(new(&d, 20000, 20000, &opts).contains("2^28"));
        let nan = CameraDesc {
            eye: Vec3::new(f32::NAN, 0.0, 0.0),
            ..d
        };
        assert!(new(&nan, 8, 8, &opts).contains("finite"));
        let same = CameraDesc { target: d.eye, ..d };
        assert!(new(&same, 8, 8, &opts).contains("target must differ"));
        let parallel = CameraDesc {
            up: d.target - d.eye,
            ..d
        };
        assert!(new(&parallel, 8, 8, &opts).contains("parallel"));
        let bad = |o: CameraOptions, what: &str| {
            let m = new(&d, 8, 8, &o);
            assert!(m.contains(what), "{kind:?}: {m:?} should mention {what:?}");
        };
        bad(
            CameraOptions {
                aperture_radius: -0.1,
                ..opts.clone()
            },
            "aperture",
        );
        bad(
            CameraOptions {
                aperture_radius: f32::NAN,
                ..opts.clone()
            },
            "aperture",
        );
        bad(
            CameraOptions {
                focus_distance: Some(0.0),
                ..opts.clone()
            },
            "focus",
        );
        bad(
            CameraOptions {
                ipd: -0.01,
                ..opts.clone()
            },
            "ipd",
        );
        bad(
            CameraOptions {
                ortho_height: Some(-1.0),
                ..opts.clone()
            },
            "ortho",
        );
        let inf_fov = Some(Vec2::new(f32::INFINITY, 90.0));
        bad(
            CameraOptions {
                fov_deg: inf_fov,
                ..opts.clone()
            },
            "fov",
        );
        let nan_k = [[0.1, f32::NAN], [0.0; 2], [0.0; 2]];
        bad(
            CameraOptions {
                distortion: nan_k,
                ..opts.clone()
            },
            "distortion",
        );
    }
    let model = |kind, o: CameraOptions| camera_error(Camera::new(kind, &d, 8, 8, &o));
    let fov = |x, y| CameraOptions {
        fov_deg: Some(Vec2::new(x, y)),
        ..Default::default()
    };
    assert!(model(ModelKind::Equirect, fov(400.0, 90.0)).contains("equirect fov"));
    assert!(model(ModelKind::Equirect, fov(90.0, 190.0)).contains("equirect fov"));
    assert!(model(ModelKind::Fisheye, fov(0.0, 90.0)).contains("fisheye fov"));
    assert!(model(ModelKind::Fisheye, fov(200.0, 361.0)).contains("fisheye fov"));
    let folding = CameraOptions {
        distortion: [[-0.6, 0.0]; 3],
        ..Default::default()
    };
    assert!(model(ModelKind::Distorted, folding).contains("fold"));
    // Composite films: the per-view size times the view count must stay valid.
    let m = camera_error(Camera::new(ModelKind::Stereo, &d, 12000, 12000, &opts));
    assert!(m.contains("2^28"), "{m}");
    match StereoRig::new(&d, u32::MAX, 1, 0.1) {
        Err(SceneError::Camera(m)) => assert!(m.contains("32 bits"), "{m}"),
        other => panic!("{other:?}"),
    }
    let m = camera_error(Camera::new(ModelKind::Cube, &d, 7000, 1, &opts));
    assert!(m.contains("2^28"), "{m}");
    // Film sizes of the composite models.
    let s = Camera::new(ModelKind::Stereo, &d, 10, 7, &opts).unwrap();
    assert_eq!((s.width(), s.height()), (20, 7));
    let c = Camera::new(ModelKind::Cube, &d, 10, 7, &opts).unwrap();
    assert_eq!((c.width(), c.height()), (60, 10));
    // Model names parse back.
    for kind in ModelKind::ALL {
        assert_eq!(ModelKind::parse(kind.name()).unwrap(), kind);
        assert_eq!(build(kind, &d, &opts).kind(), kind);
    }
    assert!(ModelKind::parse("tilt-shift").is_err());
}

fn pose() -> impl Strategy<Value = CameraDesc> {
    (
        prop::array::uniform3(-10.0f32..10.0),
        prop::array::uniform3(-1.0f32..1.0),
        0.5f32..20.0,
        prop::array::uniform3(-1.0f32..1.0),
        20.0f32..150.0,
    )
        .prop_filter_map("degenerate pose", |(e, f, dist, u, fov)| {
            let (f, u) = (Vec3::from(f), Vec3::from(u));
            if f.length() < 0.1
                || u.length() < 0.1
                || f.normalize().cross(u.normalize()).length() < 0.1
            {
                return None;
            }
            let eye = Vec3::from(e);
            Some(CameraDesc::new(eye, eye + f.normalize() * dist, u, fov))
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Any pose, any model, any channel: film -> ray -> point -> film.
    #[test]
    fn round_trip_under_random_poses(
        desc in pose(),
        kind in prop::sample::select(ModelKind::ALL.to_vec()),
        film01 in prop::array::uniform2(0.02f32..0.98),
        t in 1.0f32..20.0,
        c in 0usize..3,
    ) {
        let cam = build(kind, &desc, &CameraOptions::default());
        let film = Vec2::from(film01) * Vec2::new(cam.width() as f32, cam.height() as f32);
        if let Some(ray) = cam.generate_ray(film, LENS_CENTRE, c) {
            let back = cam.project(ray.ray.at(t), project_channel(&cam, film, c));
            prop_assert!(back.is_some(), "{:?} not projected", kind);
            let err = film_distance(&cam, back.unwrap(), film);
            prop_assert!(err < 1e-3, "{:?} c{}: {} -> {:?} ({} px)", kind, c, film, back, err);
        } else {
            prop_assert!(!is_covered(&cam, film));
        }
    }

    /// The concentric lens map covers the aperture disk: every lens sample's origin is within
    /// the aperture radius and the focus point is shared.
    #[test]
    fn thin_lens_origins_stay_on_the_aperture(
        lens in prop::array::uniform2(0.0f32..1.0),
        aperture in 0.0f32..0.5,
        focus in 0.2f32..30.0,
    ) {
        let d = desc();
        let tl = ThinLens::new(&d, 16, 12, aperture, Some(focus)).unwrap();
        let film = Vec2::new(5.5, 3.5);
        let r = tl.generate_ray(film, Vec2::from(lens), 0).unwrap();
        prop_assert!((r.ray.origin - d.eye).length() <= aperture * (1.0 + 1e-5) + 1e-6);
        let fwd = (d.target - d.eye).normalize();
        let p = r.ray.at(focus / r.ray.dir.dot(fwd));
        prop_assert!((p - tl.focus_point(film)).length() < 1e-5 * focus.max(1.0) * 10.0);
    }
}
