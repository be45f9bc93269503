//! The sample hierarchy (HVVR §5): tiles and blocks partition the samples within their size
//! bounds, and no subsample ray leaves its tile's or its block's beam, for every camera model.

use glam::{Vec2, Vec3};
use parallax_scene::CameraDesc;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_vr::hierarchy::{BLOCK_TILES, tile_samples, tile_samples_of};
use parallax_vr::{Hierarchy, SampleSet};
use proptest::prelude::*;

const KINDS: [ModelKind; 8] = [
    ModelKind::Pinhole,
    ModelKind::Orthographic,
    ModelKind::ThinLens,
    ModelKind::Stereo,
    ModelKind::Cube,
    ModelKind::Equirect,
    ModelKind::Fisheye,
    ModelKind::Distorted,
];

fn check(set: &SampleSet) -> Result<(), TestCaseError> {
    let h = Hierarchy::build(set).unwrap();
    let mut seen = vec![false; set.samples.len()];
    for &i in &h.order {
        prop_assert!(!seen[i as usize]);
        seen[i as usize] = true;
    }
    prop_assert!(seen.iter().all(|&s| s));
    let mut tiles_seen = 0;
    for b in &h.blocks {
        prop_assert!(b.tile_count as usize <= BLOCK_TILES && b.tile_count > 0);
        prop_assert_eq!(b.first_tile as usize, tiles_seen);
        tiles_seen += b.tile_count as usize;
        let first = b.first_tile as usize;
        for (ti, t) in h.tiles[first..first + b.tile_count as usize]
            .iter()
            .enumerate()
        {
            prop_assert!(t.len as usize <= tile_samples_of(set) && t.len > 0);
            let spp = set.spp as usize;
            let lens = h.lens_beams.get((first + ti) * spp..(first + ti + 1) * spp);
            for &i in &h.order[t.start as usize..(t.start + t.len) as usize] {
                for k in 0..spp {
                    if let Some(r) = set.subsample_ray(i as usize, k) {
                        prop_assert!(t.beam.contains_ray(&r, 0.0), "tile beam misses a ray");
                        prop_assert!(b.beam.contains_ray(&r, 0.0), "block beam misses a ray");
                        if let Some(lb) = lens {
                            let beam = &lb[k];
                            prop_assert!(beam.contains_ray(&r, 0.0), "lens beam misses a ray");
                            // One origin per lens sample: the set-up kernel's.
                            prop_assert!(
                                beam.origin.min == r.origin && beam.origin.max == r.origin
                            );
                        }
                    }
                }
            }
        }
        // Lens beams exactly for thin lenses at more than one subsample.
        let thin = matches!(set.camera, Camera::ThinLens(_)) && set.spp > 1;
        prop_assert_eq!(
            h.lens_beams.len(),
            if thin {
                h.tiles.len() * set.spp as usize
            } else {
                0
            }
        );
    }
    prop_assert_eq!(tiles_seen, h.tiles.len());
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn subsample_rays_stay_in_their_beams(
        kind in 0usize..8,
        w in 8u32..80,
        h in 8u32..60,
        spp in 1u32..6,
        eye in prop::array::uniform3(-3.0f32..3.0),
        look in prop::array::uniform3(-1.0f32..1.0),
        fov in 20.0f32..120.0,
    ) {
        let eye = Vec3::from(eye);
        let look = Vec3::from(look);
        prop_assume!(look.length() > 0.1 && look.normalize().dot(Vec3::Y).abs() < 0.95);
        let desc = CameraDesc::new(eye, eye + look, Vec3::Y, fov);
        let cam = Camera::new(KINDS[kind], &desc, w, h, &CameraOptions::default()).unwrap();
        check(&SampleSet::grid(cam.clone(), spp))?;
        let gaze = Vec2::new(cam_w(&cam) * 0.3, cam_h(&cam) * 0.6);
        check(&SampleSet::foveated(cam, gaze, 5.0, 0.3, spp).unwrap())?;
    }
}

fn cam_w(c: &Camera) -> f32 {
    use parallax_scene::camera::CameraModel;
    c.width() as f32
}

fn cam_h(c: &Camera) -> f32 {
    use parallax_scene::camera::CameraModel;
    c.height() as f32
}

#[test]
fn grid_tiles_are_16_by_8_from_8_spp() {
    let desc = CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0);
    let cam = Camera::new(
        ModelKind::Pinhole,
        &desc,
        256,
        128,
        &CameraOptions::default(),
    )
    .unwrap();
    // HVVR's 16 x 8 pixel tiles from 8 spp up; 32 x 32 pixels (1024 rays) at 1 spp.
    for (spp, tile, extent) in [(8, 128, Vec2::new(15.0, 7.0)), (1, 1024, Vec2::splat(31.0))] {
        let set = SampleSet::grid(cam.clone(), spp);
        let h = Hierarchy::build(&set).unwrap();
        assert_eq!(tile_samples(spp), tile);
        assert_eq!(h.tiles.len(), 256 * 128 / tile, "spp {spp}");
        assert_eq!(h.blocks.len(), 4);
        // The 1-spp film lanes: sample `order[p]`'s film position and footprint at `p`.
        if spp == 1 {
            for (p, &i) in h.order.iter().enumerate() {
                let s = &set.samples[i as usize];
                let got = [h.film[0][p], h.film[1][p], h.film[2][p]];
                assert_eq!(got, [s.film.x, s.film.y, s.footprint]);
            }
        } else {
            assert!(h.film.iter().all(Vec::is_empty));
        }
        for t in &h.tiles {
            let (mut lo, mut hi) = (Vec2::INFINITY, Vec2::NEG_INFINITY);
            for &i in &h.order[t.start as usize..(t.start + t.len) as usize] {
                lo = lo.min(set.samples[i as usize].film);
                hi = hi.max(set.samples[i as usize].film);
            }
            assert_eq!(hi - lo, extent, "spp {spp}");
        }
    }
}

/// A thin lens at 8 spp is cast one lens point at a time: 32 x 32 pixel tiles (1024 rays per
/// lens point, as a 1-spp tile), one lens beam per tile and lens sample.
#[test]
fn thin_lens_tiles_hold_1024_samples() {
    let desc = CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0);
    let cam = Camera::new(
        ModelKind::ThinLens,
        &desc,
        256,
        128,
        &CameraOptions::default(),
    )
    .unwrap();
    let set = SampleSet::depth_of_field(cam, 8).unwrap();
    let h = Hierarchy::build(&set).unwrap();
    assert_eq!(tile_samples_of(&set), 1024);
    assert_eq!(h.tiles.len(), 256 * 128 / 1024);
    assert_eq!(h.lens_beams.len(), h.tiles.len() * 8);
    assert!(h.lens_beams.iter().all(|b| !b.everything));
}

#[test]
fn wide_fisheye_blocks_are_split_not_unbounded() {
    // 210 x 130 degrees on a small film: one block would span more than a hemisphere.
    let desc = CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0);
    let cam = Camera::new(ModelKind::Fisheye, &desc, 96, 64, &CameraOptions::default()).unwrap();
    let set = SampleSet::wide_fov(cam, 2).unwrap();
    let h = Hierarchy::build(&set).unwrap();
    assert!(h.blocks.len() > 1);
    assert!(h.blocks.iter().all(|b| !b.beam.everything));
    assert!(h.tiles.iter().all(|t| !t.beam.everything));
}
