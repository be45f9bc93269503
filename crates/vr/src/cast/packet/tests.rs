//! Tests of `cast/packet.rs`: every lane generator against the per-lane one, bit for bit.

use glam::{Vec3, Vec4};
use parallax_scene::CameraDesc;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};

use super::*;
use crate::cast::lanes16::V16;

/// `gen_samples` equals the per-lane generator bit for bit (rays and film box) on random
/// and consecutive packets of whole samples (`L::N / spp` of them) of a pinhole and a
/// stereo camera, gathering through the indices and (at 1 spp) loading contiguous film
/// lanes alike; it declines only packets across the stereo eyes.
fn check<L: LaneReduce>(set: &SampleSet, seed: u64) -> (u32, u32) {
    let (mut s, n) = (seed, set.samples.len() as u64);
    let spp = set.spp as usize;
    let per = L::N / spp;
    let off = (
        L::from_fn(|l| set.offsets[l % spp].x),
        L::from_fn(|l| set.offsets[l % spp].y),
    );
    let shift = spp.trailing_zeros();
    let (mut some, mut none) = (0, 0);
    for p in 0..400 {
        let mut idx = [0u32; MAX_LANES];
        for (l, i) in idx.iter_mut().enumerate().take(per) {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            *i = if p % 2 == 0 {
                (s >> 33) as u32 % n as u32
            } else {
                ((p as u64 * 7 + l as u64) % n) as u32
            };
        }
        let pairs: Vec<(u32, u32)> = idx[..per]
            .iter()
            .flat_map(|&i| (0..spp as u32).map(move |k| (i, k)))
            .collect();
        let (want, wbox) = gen_n_film::<L>(set, None, &pairs);
        // The same packet from contiguous film lanes (`Hierarchy::film`'s layout, 1 spp).
        let soa = [
            idx.map(|i| set.samples[i as usize].film.x),
            idx.map(|i| set.samples[i as usize].film.y),
            idx.map(|i| set.samples[i as usize].footprint),
        ];
        let film = [&soa[0][..L::N], &soa[1][..L::N], &soa[2][..L::N]];
        let loaded = (spp == 1)
            .then(|| gen_samples::<L>(set, Some(film), &idx[..per], shift, off))
            .flatten();
        let Some((got, (lo, hi))) = gen_samples::<L>(set, None, &idx[..per], shift, off) else {
            assert!(matches!(set.camera, Camera::Stereo(_)));
            assert!(loaded.is_none());
            none += 1;
            continue;
        };
        if spp == 1 {
            let (lgot, lbox) = loaded.expect("the same packet");
            assert_eq!(lbox, (lo, hi));
            for a in 0..3 {
                for l in 0..L::N {
                    assert_eq!(lgot.d[a].get(l).to_bits(), got.d[a].get(l).to_bits());
                    assert_eq!(lgot.o[a].get(l).to_bits(), got.o[a].get(l).to_bits());
                }
            }
        }
        some += 1;
        assert_eq!(got.valid, want.valid);
        for a in 0..3 {
            for l in 0..L::N {
                assert_eq!(got.o[a].get(l).to_bits(), want.o[a].get(l).to_bits());
                assert_eq!(got.d[a].get(l).to_bits(), want.d[a].get(l).to_bits());
            }
        }
        // (The generator's box, when it made one; equal up to the sign of a zero.)
        if let Some(w) = wbox {
            assert_eq!(w, (lo, hi));
        }
    }
    (some, none)
}

/// A camera of `kind` on a 48 x 40 film, looking somewhere oblique.
fn oblique_camera(kind: ModelKind, fov: f32, opts: &CameraOptions) -> Camera {
    let desc = CameraDesc::new(
        Vec3::new(0.3, -1.2, 2.0),
        Vec3::new(1.0, 0.5, -3.0),
        Vec3::Y,
        fov,
    );
    Camera::new(kind, &desc, 48, 40, opts).unwrap()
}

/// A pseudo-random `u64` below `m` per call (LCG).
fn rng(mut s: u64) -> impl FnMut(u64) -> u64 {
    move |m| {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 33) % m
    }
}

/// `gen_n_film` of `pairs` in `L` lanes against `fast_subsample_ray` per lane: a lane is
/// valid iff the per-lane generator gives a ray, and then its origin and direction are the
/// same bits. Returns the number of rays.
fn same_as_per_lane<L: Lanes>(set: &SampleSet, pairs: &[(u32, u32)]) -> u32 {
    let (got, _) = gen_n_film::<L>(set, None, pairs);
    let mut rays = 0;
    for (l, &(i, k)) in pairs.iter().enumerate() {
        let want = set.fast_subsample_ray(i as usize, k as usize);
        assert_eq!(
            got.valid >> l & 1 == 1,
            want.is_some(),
            "lane {l} of {pairs:?}"
        );
        let Some(want) = want else { continue };
        rays += 1;
        let r = got.lane(l);
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        assert_eq!(bits(r.origin), bits(want.origin), "lane {l} of {pairs:?}");
        assert_eq!(bits(r.dir), bits(want.dir), "lane {l} of {pairs:?}");
    }
    rays
}

/// `sample_chunk_lens` of sample `i`'s subsamples `k0..k0 + 4` in four lanes against
/// `fast_subsample_ray` per lane (valid lanes and bits).
fn one_sample_chunk_as_per_lane(set: &SampleSet, i: u32, k0: u32) {
    let o = &set.offsets[k0 as usize..k0 as usize + 4];
    let (ox, oy) = (Vec4::from_fn(|l| o[l].x), Vec4::from_fn(|l| o[l].y));
    let got = sample_chunk_lens::<Vec4>(set, i, ox, oy).expect("a chunk");
    for l in 0..4 {
        let want = set.fast_subsample_ray(i as usize, (k0 + l as u32) as usize);
        assert_eq!(got.valid >> l & 1 == 1, want.is_some(), "lane {l}");
        if let Some(want) = want {
            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
            assert_eq!(bits(got.lane(l).dir), bits(want.dir), "lane {l}");
            assert_eq!(bits(got.lane(l).origin), bits(want.origin), "lane {l}");
        }
    }
}

/// [`same_as_per_lane`] in 16 lanes for even `p`, 4 for odd.
fn same_as_per_lane_16_or_4(set: &SampleSet, pairs: &[(u32, u32)], p: usize) -> u32 {
    if p.is_multiple_of(2) {
        same_as_per_lane::<V16>(set, pairs)
    } else {
        same_as_per_lane::<Vec4>(set, pairs)
    }
}

/// `gen_n_film` on a lens-distorted camera (`distorted_n` for packets of one colour
/// channel, the per-lane path for mixed ones) equals `fast_subsample_ray` lane by lane, bit
/// for bit, on random packets of random subsamples, in 16 and 4 lanes.
#[test]
fn distorted_packets_equal_the_per_lane_generator() {
    let cam = oblique_camera(ModelKind::Distorted, 70.0, &CameraOptions::default());
    let mut set = SampleSet::grid(cam, 8);
    let mut next = rng(9);
    for smp in set.samples.iter_mut() {
        smp.channel = next(3) as u8;
    }
    let n = set.samples.len() as u64;
    for p in 0..600 {
        let lanes = if p % 2 == 0 { 16 } else { 4 };
        // Mostly one channel per packet (the lanes' path), every fifth packet mixed.
        let ch = next(3) as u8;
        let mut pairs = Vec::new();
        if p % 4 == 1 {
            // One sample's consecutive subsamples (`sample_chunk_lens`).
            let (i, k0) = (next(n) as u32, 4 * next(2) as u32);
            one_sample_chunk_as_per_lane(&set, i, k0);
        }
        while pairs.len() < lanes {
            let i = next(n) as usize;
            if p % 5 == 0 || set.samples[i].channel == ch {
                pairs.push((i as u32, next(8) as u32));
            }
        }
        assert_eq!(same_as_per_lane_16_or_4(&set, &pairs, p), lanes as u32);
    }
}

/// `gen_n_film` on a thin lens (`thin_lens_n` for packets of one lens sample, the per-lane
/// path for mixed ones) equals `fast_subsample_ray` lane by lane, bit for bit, origins
/// included, on random packets in 16 and 4 lanes.
#[test]
fn thin_lens_packets_equal_the_per_lane_generator() {
    let opts = CameraOptions {
        aperture_radius: 0.07,
        ..CameraOptions::default()
    };
    let cam = oblique_camera(ModelKind::ThinLens, 55.0, &opts);
    let set = SampleSet::depth_of_field(cam, 8).unwrap();
    let mut next = rng(5);
    let n = set.samples.len() as u64;
    let mut lanes_path = 0;
    for p in 0..600 {
        let lanes = if p % 2 == 0 { 16 } else { 4 };
        // One lens sample per packet (the lanes' path), every fifth packet mixed.
        let k = next(8) as u32;
        let pairs: Vec<(u32, u32)> = (0..lanes)
            .map(|_| {
                let kk = if p % 5 == 0 { next(8) as u32 } else { k };
                (next(n) as u32, kk)
            })
            .collect();
        lanes_path += pairs.iter().all(|&(_, kk)| kk == pairs[0].1) as u32;
        assert_eq!(same_as_per_lane_16_or_4(&set, &pairs, p), lanes as u32);
    }
    assert!(lanes_path > 400, "{lanes_path} packets of one lens sample");
}

/// `gen_n_film` on a fisheye (`fisheye_n`) equals `fast_subsample_ray` lane by lane, bit
/// for bit, and its valid lanes are those with a ray (the corners outside the image
/// ellipse have none), on random packets in 16 and 4 lanes.
#[test]
fn fisheye_packets_equal_the_per_lane_generator() {
    let cam = oblique_camera(ModelKind::Fisheye, 55.0, &CameraOptions::default());
    // The grid (corners included), not `wide_fov`, which drops the corners.
    let set = SampleSet::grid(cam, 4);
    let mut next = rng(11);
    let n = set.samples.len() as u64;
    let (mut rays, mut lanes) = (0, 0);
    for p in 0..600 {
        if p % 4 == 1 {
            // One sample's subsamples (`sample_chunk_lens`).
            one_sample_chunk_as_per_lane(&set, next(n) as u32, 0);
        }
        let pairs: Vec<(u32, u32)> = (0..if p % 2 == 0 { 16 } else { 4 })
            .map(|_| (next(n) as u32, next(4) as u32))
            .collect();
        lanes += pairs.len() as u32;
        rays += same_as_per_lane_16_or_4(&set, &pairs, p);
    }
    assert!(
        rays > 3000 && lanes - rays > 100,
        "{rays} rays of {lanes} lanes"
    );
}

#[test]
fn whole_sample_packets_equal_the_per_lane_generator() {
    let desc = CameraDesc::new(
        Vec3::new(0.3, -1.2, 2.0),
        Vec3::new(1.0, 0.5, -3.0),
        Vec3::Y,
        50.0,
    );
    for kind in [ModelKind::Pinhole, ModelKind::Stereo] {
        let cam = Camera::new(kind, &desc, 40, 24, &CameraOptions::default()).unwrap();
        for (spp, spp4) in [(1, 1), (8, 4), (16, 2)] {
            let (set, set4) = (
                SampleSet::grid(cam.clone(), spp),
                SampleSet::grid(cam.clone(), spp4),
            );
            let (some16, none16) = check::<V16>(&set, 1);
            let (some4, _) = check::<Vec4>(&set4, 2);
            assert!(some16 > 100 && some4 > 100, "{kind:?}: {some16} {some4}");
            if kind == ModelKind::Stereo && spp == 1 {
                assert!(none16 > 0, "no packet across the eyes");
            }
        }
    }
}
