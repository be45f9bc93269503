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
use crate::samples::Sample;
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
    let [k1, k2] = c.coeffs[channel];
    let (x, y) = distorted_xy(c, fx, fy, L::splat(k1), L::splat(k2));
    unit_to_world(&c.pinhole.frame, x, y, L::splat(-1.0))
}

/// `Distorted::camera_vector`'s `x`, `y` (its `z` is `-1`) on `N` film positions with the gain
/// coefficients `k1`, `k2` per lane (each lane's colour channel): lane-wise the same f32
/// operations (`lens_coords`, `|n|^2`, the gain `1 + s (k1 + k2 s)`, `(n g) tan_half_y`).
#[inline(always)]
pub(crate) fn distorted_xy<L: Lanes>(c: &Distorted, fx: L, fy: L, k1: L, k2: L) -> (L, L) {
    let p = &c.pinhole;
    let hh = 0.5 * p.height as f32;
    let nx = (fx - L::splat(0.5 * p.width as f32)) / L::splat(hh);
    let ny = (L::splat(hh) - fy) / L::splat(hh);
    let s = nx * nx + ny * ny;
    let g = L::splat(1.0) + s * (k1 + k2 * s);
    let t = L::splat(p.tan_half_y);
    (nx * g * t, ny * g * t)
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

/// [`gen_n_film`] for a full packet of whole samples' subsamples (`spp` dividing `L::N`: at 1
/// spp sixteen samples, at 8 spp two, each sample's subsamples `0..spp` in order; `idx` the
/// packet's `L::N / spp` samples) of a pinhole or stereo camera, without the `(sample, k)`
/// pairs: the samples' film positions and footprints in lanes — loaded from `film` (1 spp
/// only: the packet's `[x, y, footprint]` in `idx` order, [`crate::Hierarchy::film`]:
/// contiguous loads) when given, else gathered through `idx` — then `film + offset *
/// footprint` lane-wise with `off` the lanes' offsets `offsets[l % spp]` (the per-lane path's
/// f32 operations), the film box by one lane minimum and maximum (equal to the per-lane path's
/// box up to the sign of a zero, which no use of the box sees). `None` (the per-lane path
/// decides) for other cameras, a NaN position or a packet across the stereo eyes.
#[inline(always)]
pub(crate) fn gen_samples<L: LaneReduce>(
    set: &SampleSet,
    film: Option<[&[f32]; 3]>,
    idx: &[u32],
    spp_shift: u32,
    off: (L, L),
) -> Option<(RaysN<L>, (Vec2, Vec2))> {
    let (x, y, fp) = if let Some([x, y, f]) = film {
        (L::load_n(x), L::load_n(y), L::load_n(f))
    } else {
        let (mut x, mut y, mut f) = (
            [0.0f32; MAX_LANES],
            [0.0f32; MAX_LANES],
            [0.0f32; MAX_LANES],
        );
        for l in 0..L::N {
            let s = &set.samples[idx[l >> spp_shift] as usize];
            (x[l], y[l], f[l]) = (s.film.x, s.film.y, s.footprint);
        }
        (
            L::from_fn(|l| x[l]),
            L::from_fn(|l| y[l]),
            L::from_fn(|l| f[l]),
        )
    };
    let fx = x + off.0 * fp;
    let fy = y + off.1 * fp;
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
    let s = &set.samples[i0 as usize];
    let fp = s.footprint;
    let (fx, fy) = chunk_film(s, ox, oy)?;
    let full = (1u32 << L::N) - 1;
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

/// The film positions `film + offset * footprint` of sample `s`'s chunk in lanes (the
/// offsets `ox`, `oy`; the per-lane path's f32 operations); `None` for a negative or NaN
/// footprint (the per-lane path decides).
#[inline(always)]
fn chunk_film<L: Lanes>(s: &Sample, ox: L, oy: L) -> Option<(L, L)> {
    let fp = s.footprint;
    if fp.is_nan() || fp < 0.0 {
        return None;
    }
    let fp_v = L::splat(fp);
    Some((
        L::splat(s.film.x) + ox * fp_v,
        L::splat(s.film.y) + oy * fp_v,
    ))
}

/// [`sample_chunk`] for the lens-distorted (one colour channel) and fisheye models: the same
/// lane-wise film positions, then `distorted_n` / `fisheye_n`. A function of its own, picked
/// once per tile by the set-up kernel: these arms inside `sample_chunk`'s `match` made the
/// pinhole eyes' 16-spp cast 4-6 % slower (`docs/notes/vr.md`).
#[inline(always)]
pub(crate) fn sample_chunk_lens<L: Lanes>(
    set: &SampleSet,
    i0: u32,
    ox: L,
    oy: L,
) -> Option<RaysN<L>> {
    let s = &set.samples[i0 as usize];
    let (fx, fy) = chunk_film(s, ox, oy)?;
    let full = (1u32 << L::N) - 1;
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
mod tests;
