//! Subsample rays in SIMD lanes (Hunt et al. 2018, §5.5, "threads are mapped 1:1 with pixels
//! or subpixels": SIMD lanes over rays instead of GPU threads): a packet's rays generated in
//! lanes for the pinhole and stereo models (the f32 operations of `Pinhole::generate_ray`,
//! lane by lane: bit-identical rays) and per lane otherwise; the set-up kernel's full packets
//! of one sample's subsamples (`gen_one_sample`) and of sixteen 1-spp samples (`gen_spp1`)
//! take their film positions lane-wise too. The watertight kernel that tests such packets
//! against a tile's leaves is `packet_kernel.rs`.

use glam::{Vec2, Vec3};
use parallax_core::Ray;
use parallax_core::simd::Lanes;
use parallax_scene::camera::{Camera, CameraFrame, Distorted, Fisheye, Pinhole, ThinLens};

use crate::SampleSet;
use crate::cast::lanes16::LaneReduce;
use crate::cast::stored::RayBuffer;
/// Most rays per packet (the 16-lane set-up kernel, [`crate::cast::lanes16`]).
pub const MAX_LANES: usize = 16;

/// Up to [`MAX_LANES`] rays in SoA lanes.
#[derive(Clone, Copy)]
pub struct RaysN<L> {
    pub o: [L; 3],
    pub d: [L; 3],
    /// Lanes holding a valid ray.
    pub valid: u32,
}

impl<L: Lanes> RaysN<L> {
    #[inline(always)]
    pub fn lane(&self, l: usize) -> Ray {
        Ray::new(
            Vec3::new(self.o[0].get(l), self.o[1].get(l), self.o[2].get(l)),
            Vec3::new(self.d[0].get(l), self.d[1].get(l), self.d[2].get(l)),
        )
    }
}

/// `Pinhole::generate_ray` on `N` film positions (lane-wise the same f32 operations:
/// `camera_dir`, then [`unit_to_world`]).
#[inline(always)]
fn pinhole_n<L: Lanes>(p: &Pinhole, fx: L, fy: L) -> ([L; 3], [L; 3]) {
    let (x, y) = camera_xy(p, fx, fy);
    unit_to_world(&p.frame, x, y, L::splat(-1.0))
}

/// `Pinhole::camera_dir`'s `x` and `y` (its `z` is `-1`) on `N` film positions, lane-wise the
/// same f32 operations.
#[inline(always)]
fn camera_xy<L: Lanes>(p: &Pinhole, fx: L, fy: L) -> (L, L) {
    let w = L::splat(p.width as f32);
    let h = L::splat(p.height as f32);
    let one = L::splat(1.0);
    let ndc_x = L::splat(2.0) * fx / w - one;
    let ndc_y = one - L::splat(2.0) * fy / h;
    let x = (ndc_x + L::splat(p.shift.x)) * L::splat(p.tan_half_x());
    let y = (ndc_y + L::splat(p.shift.y)) * L::splat(p.tan_half_y);
    (x, y)
}

/// `Distorted::ray` on `N` film positions of colour `channel` (0-2): lane-wise the same f32
/// operations (`lens_coords`, `|n|^2`, the gain `1 + s (k1 + k2 s)`, `n g tan_half_y`, then
/// [`unit_to_world`]).
#[inline(always)]
fn distorted_n<L: Lanes>(c: &Distorted, fx: L, fy: L, channel: usize) -> ([L; 3], [L; 3]) {
    let p = &c.pinhole;
    let hh = 0.5 * p.height as f32;
    let nx = (fx - L::splat(0.5 * p.width as f32)) / L::splat(hh);
    let ny = (L::splat(hh) - fy) / L::splat(hh);
    let s = nx * nx + ny * ny;
    let [k1, k2] = c.coeffs[channel];
    let g = L::splat(1.0) + s * (L::splat(k1) + L::splat(k2) * s);
    let t = L::splat(p.tan_half_y);
    unit_to_world(&p.frame, nx * g * t, ny * g * t, L::splat(-1.0))
}

/// `SampleSet::fast_subsample_ray` of a thin lens on `N` film positions with one lens sample
/// `lens`: lane-wise the same f32 operations (`camera_dir` as [`pinhole_n`], times the focus
/// distance, minus the lens point, then [`unit_to_world`]); every lane's origin is the lens
/// point in the world, computed once as the per-lane path computes it.
#[inline(always)]
fn thin_lens_n<L: Lanes>(c: &ThinLens, lens: Vec2, fx: L, fy: L) -> ([L; 3], [L; 3]) {
    let p = &c.pinhole;
    let (x, y) = camera_xy(p, fx, fy);
    let f = c.focus_distance;
    let pl = c.lens_point(lens);
    let dx = x * L::splat(f) - L::splat(pl.x);
    let dy = y * L::splat(f) - L::splat(pl.y);
    // (`camera_dir`'s `z = -1` times `f` is `-f` exactly.)
    let dz = L::splat(-f - pl.z);
    let (_, d) = unit_to_world(&p.frame, dx, dy, dz);
    let o = p.frame.position + p.frame.dir_to_world(pl);
    ([L::splat(o.x), L::splat(o.y), L::splat(o.z)], d)
}

/// `Fisheye::ray` on `N` film positions (`Fisheye::dir_lanes`, then the frame turn of
/// [`unit_to_world`] without the normalising, as `dir_to_world`); the lanes outside the image
/// ellipse are invalid.
#[inline(always)]
fn fisheye_n<L: Lanes>(c: &Fisheye, fx: L, fy: L) -> ([L; 3], [L; 3], u32) {
    let ([x, y, z], _, _, inside) = c.dir_lanes(fx, fy);
    let (o, d) = turn_to_world(&c.frame, x, y, z);
    (o, d, L::bits(inside))
}

/// The camera-space direction `(x, y, z)` normalised and turned into the world by `frame`,
/// with the frame's origin: lane-wise `Vec3::length`, `d / len`, `Mat3 * Vec3`.
#[inline(always)]
fn unit_to_world<L: Lanes>(frame: &CameraFrame, x: L, y: L, z: L) -> ([L; 3], [L; 3]) {
    let len = (x * x + y * y + z * z).sqrt();
    turn_to_world(frame, x / len, y / len, z / len)
}

/// The camera-space direction `(x, y, z)` turned into the world by `frame` (lane-wise
/// `Mat3 * Vec3`), with the frame's origin.
#[inline(always)]
fn turn_to_world<L: Lanes>(frame: &CameraFrame, x: L, y: L, z: L) -> ([L; 3], [L; 3]) {
    // No closures here: inside an AVX-512 entry point a closure would call the lane
    // intrinsics out of line (closures have no target features, `cast/lanes512.rs`).
    let m = &frame.basis;
    let d = [
        L::splat(m.x_axis.x) * x + L::splat(m.y_axis.x) * y + L::splat(m.z_axis.x) * z,
        L::splat(m.x_axis.y) * x + L::splat(m.y_axis.y) * y + L::splat(m.z_axis.y) * z,
        L::splat(m.x_axis.z) * x + L::splat(m.y_axis.z) * y + L::splat(m.z_axis.z) * z,
    ];
    let o = frame.position;
    ([L::splat(o.x), L::splat(o.y), L::splat(o.z)], d)
}

/// The subsample rays `(sample, k)` of `pairs` (up to `L::N`) into lanes, read from `stored`
/// when given (HVVR Table 3's naive ray buffer, `cast/stored.rs`), else generated.
#[inline(always)]
pub(crate) fn gen_n<L: Lanes>(
    set: &SampleSet,
    stored: Option<&RayBuffer>,
    pairs: &[(u32, u32)],
) -> RaysN<L> {
    gen_n_film(set, stored, pairs).0
}

/// [`gen_n`], and the lanes' film box `(min, max)` (the exact float range of their
/// `film + offset * footprint`) when the per-lane generator computed the film positions
/// (`None` for stored rays, one-sample packets and NaN positions).
#[inline(always)]
pub(crate) fn gen_n_film<L: Lanes>(
    set: &SampleSet,
    stored: Option<&RayBuffer>,
    pairs: &[(u32, u32)],
) -> (RaysN<L>, Option<(Vec2, Vec2)>) {
    let n = pairs.len();
    if let Some(buf) = stored {
        return (read_n(set, buf, pairs), None);
    }
    if let Some(r) = gen_one_sample(set, pairs) {
        return (r, None);
    }
    let mut film = [Vec2::ZERO; MAX_LANES];
    let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    let mut nan = false;
    for (l, &(i, k)) in pairs.iter().enumerate() {
        let s = &set.samples[i as usize];
        let f = s.film + set.offsets[k as usize] * s.footprint;
        film[l] = f;
        lo = lo.min(f);
        hi = hi.max(f);
        nan |= f.is_nan();
    }
    let f0 = film[0];
    for f in film.iter_mut().skip(n) {
        *f = f0;
    }
    let full = (1u32 << n) - 1;
    let fx = L::from_fn(|l| film[l].x);
    let fy = L::from_fn(|l| film[l].y);
    let bx = (!nan).then_some((lo, hi));
    match &set.camera {
        Camera::Pinhole(p) => {
            let (o, d) = pinhole_n(p, fx, fy);
            return (RaysN { o, d, valid: full }, bx);
        }
        Camera::Stereo(rig) => {
            // Every lane in `[0, 2w]`, and all left (`< w`) or all right (`>= w`): the range
            // decides it as the lane-by-lane test would (no NaN among the lanes).
            let w = rig.eye_width() as f32;
            let inside = !nan && lo.x >= 0.0 && hi.x <= 2.0 * w;
            let (left, right) = (hi.x < w, lo.x >= w);
            if inside && (left || right) {
                let (p, fx) = if left {
                    (&rig.eyes[0], fx)
                } else {
                    (&rig.eyes[1], fx - L::splat(w))
                };
                let (o, d) = pinhole_n(p, fx, fy);
                return (RaysN { o, d, valid: full }, bx);
            }
        }
        Camera::Distorted(c) if !nan => {
            // Every lane of one colour channel (the usual packet: one sample's subsamples).
            let ch = set.samples[pairs[0].0 as usize].channel;
            if ch <= 2
                && pairs[..n]
                    .iter()
                    .all(|&(i, _)| set.samples[i as usize].channel == ch)
            {
                let (o, d) = distorted_n(c, fx, fy, ch as usize);
                return (RaysN { o, d, valid: full }, bx);
            }
        }
        Camera::Fisheye(c) => {
            let (o, d, inside) = fisheye_n(c, fx, fy);
            return (
                RaysN {
                    o,
                    d,
                    valid: inside & full,
                },
                bx,
            );
        }
        // One lens sample in every lane (the caster's packets of a thin-lens tile, one lens
        // sample at a time: `cast/mod.rs`).
        Camera::ThinLens(c) if !nan && pairs[..n].iter().all(|&(_, k)| k == pairs[0].1) => {
            let (o, d) = thin_lens_n(c, set.lens[pairs[0].1 as usize], fx, fy);
            return (RaysN { o, d, valid: full }, bx);
        }
        _ => {}
    }
    let mut rays = [None::<Ray>; MAX_LANES];
    let mut valid = 0;
    for (l, &(i, k)) in pairs.iter().enumerate() {
        rays[l] = set.fast_subsample_ray(i as usize, k as usize);
        valid |= (rays[l].is_some() as u32) << l;
    }
    let comp = |a: usize, origin: bool| {
        L::from_fn(|l| rays[l].map_or(0.0, |r| if origin { r.origin[a] } else { r.dir[a] }))
    };
    let rays = RaysN {
        o: [comp(0, true), comp(1, true), comp(2, true)],
        d: [comp(0, false), comp(1, false), comp(2, false)],
        valid,
    };
    (rays, bx)
}

/// [`gen_n_film`] for a full packet of one subsample per sample (`spp == 1`; `idx` the
/// packet's `L::N` samples) of a pinhole or stereo camera, without the `(sample, k)` pairs:
/// the samples' film positions and footprints in lanes — loaded from `film` (the packet's
/// `[x, y, footprint]` in `idx` order, [`crate::Hierarchy::film`]: contiguous loads) when
/// given, else gathered through `idx` — then `film + offsets[0] *
/// footprint` lane-wise (the per-lane path's f32 operations), the film box by one lane
/// minimum and maximum (equal to the per-lane path's box up to the sign of a zero, which no
/// use of the box sees). `None` (the per-lane path decides) for other cameras, a NaN position
/// or a packet across the stereo eyes.
#[inline(always)]
pub(crate) fn gen_spp1<L: LaneReduce>(
    set: &SampleSet,
    film: Option<[&[f32]; 3]>,
    idx: &[u32],
) -> Option<(RaysN<L>, (Vec2, Vec2))> {
    let (x, y, fp) = if let Some([x, y, f]) = film {
        (L::load_n(x), L::load_n(y), L::load_n(f))
    } else {
        let (mut x, mut y, mut f) = (
            [0.0f32; MAX_LANES],
            [0.0f32; MAX_LANES],
            [0.0f32; MAX_LANES],
        );
        for (l, &i) in idx[..L::N].iter().enumerate() {
            let s = &set.samples[i as usize];
            (x[l], y[l], f[l]) = (s.film.x, s.film.y, s.footprint);
        }
        (
            L::from_fn(|l| x[l]),
            L::from_fn(|l| y[l]),
            L::from_fn(|l| f[l]),
        )
    };
    let o = set.offsets[0];
    let fx = x + L::splat(o.x) * fp;
    let fy = y + L::splat(o.y) * fp;
    if L::bits(L::or(fx.ne(fx), fy.ne(fy))) != 0 {
        return None;
    }
    let (lo, hi) = (
        Vec2::new(fx.hmin(), fy.hmin()),
        Vec2::new(fx.hmax(), fy.hmax()),
    );
    let full = (1u32 << L::N) - 1;
    let (p, fx) = match &set.camera {
        Camera::Pinhole(p) => (p, fx),
        Camera::Stereo(rig) => {
            // As `gen_n_film`: every lane in `[0, 2w]`, and all left or all right.
            let w = rig.eye_width() as f32;
            let inside = lo.x >= 0.0 && hi.x <= 2.0 * w;
            let (left, right) = (hi.x < w, lo.x >= w);
            if !(inside && (left || right)) {
                return None;
            }
            if left {
                (&rig.eyes[0], fx)
            } else {
                (&rig.eyes[1], fx - L::splat(w))
            }
        }
        _ => return None,
    };
    let (o, d) = pinhole_n(p, fx, fy);
    Some((RaysN { o, d, valid: full }, (lo, hi)))
}

/// [`gen_n`] for a full packet of one sample's consecutive subsamples `k0..k0 + N` (a pixel
/// at 16 spp, half a pixel at 32) of a pinhole or stereo camera: the film positions
/// `film + offsets[k] * footprint` lane-wise (the same f32 operations as the per-lane path),
/// and the stereo eye test from the smallest and largest offset (`x -> film + x * footprint`
/// is monotone for `footprint >= 0`, so they bound every lane exactly as the per-lane test).
/// `None` for any other packet (the per-lane path).
#[inline(always)]
fn gen_one_sample<L: Lanes>(set: &SampleSet, pairs: &[(u32, u32)]) -> Option<RaysN<L>> {
    let n = pairs.len();
    let (i0, k0) = pairs[0];
    if n != L::N || pairs[n - 1] != (i0, k0 + n as u32 - 1) {
        return None;
    }
    if !pairs
        .iter()
        .enumerate()
        .all(|(l, &(i, k))| i == i0 && k == k0 + l as u32)
    {
        return None;
    }
    let offs = &set.offsets[k0 as usize..k0 as usize + n];
    let (mut lo, mut hi) = (offs[0].x, offs[0].x);
    for o in offs {
        lo = lo.min(o.x);
        hi = hi.max(o.x);
    }
    let ox = L::from_fn(|l| offs[l].x);
    let oy = L::from_fn(|l| offs[l].y);
    sample_chunk(set, i0, ox, oy, lo, hi)
}

/// The rays of [`gen_one_sample`] from the chunk's offsets in lanes (`ox`, `oy`) and the
/// smallest and largest x offset (`lo`, `hi`): the same rays, for callers that keep the
/// offset lanes of a tile.
#[inline(always)]
pub(crate) fn sample_chunk<L: Lanes>(
    set: &SampleSet,
    i0: u32,
    ox: L,
    oy: L,
    lo: f32,
    hi: f32,
) -> Option<RaysN<L>> {
    let n = L::N;
    let s = &set.samples[i0 as usize];
    let fp = s.footprint;
    if !(fp >= 0.0) {
        return None;
    }
    let full = (1u32 << n) - 1;
    let fp_v = L::splat(fp);
    let fx = L::splat(s.film.x) + ox * fp_v;
    let fy = L::splat(s.film.y) + oy * fp_v;
    match &set.camera {
        Camera::Pinhole(p) => {
            let (o, d) = pinhole_n(p, fx, fy);
            Some(RaysN { o, d, valid: full })
        }
        Camera::Stereo(rig) => {
            let w = rig.eye_width() as f32;
            let (lo, hi) = (s.film.x + lo * fp, s.film.x + hi * fp);
            let inside = lo >= 0.0 && hi <= 2.0 * w;
            let (left, right) = (hi < w, lo >= w);
            if !(inside && (left || right)) {
                return None;
            }
            let (p, fx) = if left {
                (&rig.eyes[0], fx)
            } else {
                (&rig.eyes[1], fx - L::splat(w))
            };
            let (o, d) = pinhole_n(p, fx, fy);
            Some(RaysN { o, d, valid: full })
        }
        _ => None,
    }
}

/// [`sample_chunk`] for the lens-distorted (one colour channel) and fisheye models: the same
/// lane-wise film positions, then `distorted_n` / `fisheye_n`. Apart from `sample_chunk`,
/// which the set-up kernel calls for its one-sample packets: these arms there made the
/// pinhole eyes' 16-spp cast 4-6 % slower (`docs/notes/vr.md`); the kernel reaches them
/// through [`gen_n_film`].
#[inline(always)]
pub(crate) fn sample_chunk_lens<L: Lanes>(
    set: &SampleSet,
    i0: u32,
    ox: L,
    oy: L,
) -> Option<RaysN<L>> {
    let s = &set.samples[i0 as usize];
    let fp = s.footprint;
    if !(fp >= 0.0) {
        return None;
    }
    let full = (1u32 << L::N) - 1;
    let fp_v = L::splat(fp);
    let fx = L::splat(s.film.x) + ox * fp_v;
    let fy = L::splat(s.film.y) + oy * fp_v;
    match &set.camera {
        Camera::Distorted(c) if s.channel <= 2 => {
            let (o, d) = distorted_n(c, fx, fy, s.channel as usize);
            Some(RaysN { o, d, valid: full })
        }
        Camera::Fisheye(c) => {
            let (o, d, inside) = fisheye_n(c, fx, fy);
            Some(RaysN {
                o,
                d,
                valid: inside & full,
            })
        }
        _ => None,
    }
}

/// [`gen_n`] from a stored ray buffer: the same lanes (lanes past `pairs.len()` repeat lane 0).
#[inline(always)]
fn read_n<L: Lanes>(set: &SampleSet, buf: &RayBuffer, pairs: &[(u32, u32)]) -> RaysN<L> {
    let spp = set.spp as usize;
    let mut r = [[0.0f32; MAX_LANES]; 6];
    let mut valid = 0;
    for l in 0..L::N {
        let (i, k) = pairs[if l < pairs.len() { l } else { 0 }];
        let x = &buf.rays[i as usize * spp + k as usize];
        for (c, rc) in r.iter_mut().enumerate() {
            rc[l] = x[c];
        }
        let ok = x[3] != 0.0 || x[4] != 0.0 || x[5] != 0.0;
        valid |= ((ok && l < pairs.len()) as u32) << l;
    }
    RaysN {
        o: [
            L::from_fn(|l| r[0][l]),
            L::from_fn(|l| r[1][l]),
            L::from_fn(|l| r[2][l]),
        ],
        d: [
            L::from_fn(|l| r[3][l]),
            L::from_fn(|l| r[4][l]),
            L::from_fn(|l| r[5][l]),
        ],
        valid,
    }
}

/// Result of a packet: per lane the closest `(t, index in Bvh::triangles)` (`u32::MAX` = none).
#[derive(Clone, Copy, Debug)]
pub struct ClosestN {
    pub t: [f32; MAX_LANES],
    pub tri: [u32; MAX_LANES],
}

#[cfg(test)]
mod tests {
    use glam::{Vec3, Vec4};
    use parallax_scene::CameraDesc;
    use parallax_scene::camera::{Camera, CameraOptions, ModelKind};

    use super::*;
    use crate::cast::lanes16::V16;

    /// `gen_spp1` equals the per-lane generator bit for bit (rays and film box) on random and
    /// consecutive 1-spp packets of a pinhole and a stereo camera, gathering through the
    /// indices and loading contiguous film lanes alike; it declines only packets across the
    /// stereo eyes.
    fn check<L: LaneReduce>(set: &SampleSet, seed: u64) -> (u32, u32) {
        let (mut s, n) = (seed, set.samples.len() as u64);
        let (mut some, mut none) = (0, 0);
        for p in 0..400 {
            let mut idx = [0u32; MAX_LANES];
            for (l, i) in idx.iter_mut().enumerate().take(L::N) {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                *i = if p % 2 == 0 {
                    (s >> 33) as u32 % n as u32
                } else {
                    ((p as u64 * 7 + l as u64) % n) as u32
                };
            }
            let pairs: Vec<(u32, u32)> = idx[..L::N].iter().map(|&i| (i, 0)).collect();
            let (want, wbox) = gen_n_film::<L>(set, None, &pairs);
            // The same packet from contiguous film lanes (`Hierarchy::film`'s layout).
            let soa = [
                idx.map(|i| set.samples[i as usize].film.x),
                idx.map(|i| set.samples[i as usize].film.y),
                idx.map(|i| set.samples[i as usize].footprint),
            ];
            let film = [&soa[0][..L::N], &soa[1][..L::N], &soa[2][..L::N]];
            let loaded = gen_spp1::<L>(set, Some(film), &idx[..L::N]);
            let Some((got, (lo, hi))) = gen_spp1::<L>(set, None, &idx[..L::N]) else {
                assert!(matches!(set.camera, Camera::Stereo(_)));
                assert!(loaded.is_none());
                none += 1;
                continue;
            };
            let (lgot, lbox) = loaded.expect("the same packet");
            assert_eq!(lbox, (lo, hi));
            for a in 0..3 {
                for l in 0..L::N {
                    assert_eq!(lgot.d[a].get(l).to_bits(), got.d[a].get(l).to_bits());
                    assert_eq!(lgot.o[a].get(l).to_bits(), got.o[a].get(l).to_bits());
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
            assert_eq!(wbox, Some((lo, hi)));
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
        if p % 2 == 0 {
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
    fn spp1_packets_equal_the_per_lane_generator() {
        let desc = CameraDesc::new(
            Vec3::new(0.3, -1.2, 2.0),
            Vec3::new(1.0, 0.5, -3.0),
            Vec3::Y,
            50.0,
        );
        for kind in [ModelKind::Pinhole, ModelKind::Stereo] {
            let cam = Camera::new(kind, &desc, 40, 24, &CameraOptions::default()).unwrap();
            let set = SampleSet::grid(cam, 1);
            let (some16, none16) = check::<V16>(&set, 1);
            let (some4, _) = check::<Vec4>(&set, 2);
            assert!(some16 > 100 && some4 > 100, "{kind:?}: {some16} {some4}");
            if kind == ModelKind::Stereo {
                assert!(none16 > 0, "no packet across the eyes");
            }
        }
    }
}
