//! The sweep (`cast/setup/sweep.rs`): casts with the tile's triangles swept over its packets
//! equal casts with the run walk per packet bit for bit, on every 16-lane tier this CPU has,
//! at 16 and 32 spp, for the pinhole, foveated and stereo sets it runs on; the other schemes
//! (lens-distorted, fisheye, thin lens) and other spp keep the walk.

use glam::Vec2;
use parallax_bvh::Bvh;
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_vr::{CastOptions, Hierarchy, Isa, SampleSet, VisibilityBuffer, cast_opts};

const W: u32 = 96;
const H: u32 = 72;

fn camera(scene: &Scene, kind: ModelKind, w: u32, h: u32) -> Camera {
    let desc = scene.camera(None).unwrap();
    Camera::new(kind, &desc, w, h, &CameraOptions::default()).unwrap()
}

/// The sample sets, and whether the sweep takes their tiles.
fn sets(scene: &Scene, spp: u32) -> Vec<(&'static str, SampleSet, bool)> {
    let pinhole = || camera(scene, ModelKind::Pinhole, W, H);
    vec![
        ("grid", SampleSet::grid(pinhole(), spp), true),
        (
            "foveated",
            SampleSet::foveated(pinhole(), Vec2::new(40.0, 30.0), 10.0, 0.15, spp).unwrap(),
            true,
        ),
        (
            "stereo",
            SampleSet::grid(camera(scene, ModelKind::Stereo, W / 2, H), spp),
            true,
        ),
        (
            "distorted",
            SampleSet::distorted(camera(scene, ModelKind::Distorted, W, H), spp).unwrap(),
            false,
        ),
        (
            "fisheye",
            SampleSet::wide_fov(camera(scene, ModelKind::Fisheye, W, H), spp).unwrap(),
            false,
        ),
    ]
}

/// Casts `set` walked and swept on each 16-lane tier: equal buffers; returns the swept tiles
/// and all set-up tiles of the last swept cast.
fn swept_equals_walked(bvh: &Bvh, set: &SampleSet, label: &str) -> (u64, u64) {
    let h = Hierarchy::build(set).unwrap();
    let walk = CastOptions {
        sweep: false,
        ..CastOptions::default()
    };
    let mut walked = VisibilityBuffer::new(set);
    let st = cast_opts(bvh, set, &h, &mut walked, walk);
    assert_eq!(st.setup_swept_tiles, 0, "{label}: swept without the option");
    let mut counts = (0, 0);
    for isa in [Isa::Sse, Isa::Avx2, Isa::Avx512] {
        if isa.available() != isa {
            eprintln!("{label}: {isa:?} not detected, not compared");
            continue;
        }
        let opts = CastOptions {
            isa,
            ..CastOptions::default()
        };
        assert!(opts.sweep, "the sweep is the default");
        let mut swept = VisibilityBuffer::new(set);
        let st = cast_opts(bvh, set, &h, &mut swept, opts);
        assert_eq!(st.setup_rescues, 0, "{label} {isa:?}");
        let diff = (0..swept.prim.len())
            .filter(|&j| {
                swept.prim[j] != walked.prim[j] || swept.t[j].to_bits() != walked.t[j].to_bits()
            })
            .count();
        assert_eq!(diff, 0, "{label} {isa:?}: {diff} subsamples differ");
        counts = (st.setup_swept_tiles, st.setup_tiles);
    }
    let hits = walked.prim.iter().filter(|&&p| p != u32::MAX).count();
    assert!(hits > walked.prim.len() / 50, "{label}: scene not in view");
    counts
}

#[test]
fn sweep_equals_the_walk() {
    for name in ["atrium", "cornell"] {
        let scene = Scene::load(name).unwrap();
        let bvh = Bvh::build(&scene.mesh);
        for spp in [16, 32] {
            for (scheme, set, sweeps) in sets(&scene, spp) {
                let label = format!("{name} {scheme} {spp} spp");
                let (swept, tiles) = swept_equals_walked(&bvh, &set, &label);
                eprintln!("{label}: {swept} of {tiles} set-up tiles swept");
                if sweeps {
                    assert_eq!(swept, tiles, "{label}: a tile was walked");
                } else {
                    assert_eq!(swept, 0, "{label}: swept");
                }
            }
        }
    }
}

/// At 1, 4 and 8 spp a packet is not one sample's chunk of sixteen subsamples: the walk runs.
#[test]
fn other_spp_keep_the_walk() {
    let scene = Scene::load("atrium").unwrap();
    let bvh = Bvh::build(&scene.mesh);
    for spp in [1, 4, 8] {
        let set = SampleSet::grid(camera(&scene, ModelKind::Pinhole, W, H), spp);
        let (swept, _) = swept_equals_walked(&bvh, &set, &format!("grid {spp} spp"));
        assert_eq!(swept, 0, "{spp} spp swept");
    }
}
