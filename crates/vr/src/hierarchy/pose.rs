//! Moving a hierarchy's beams to a new head pose without regenerating its rays (Hunt et al.
//! 2018, §5.1: the tile and block bounds "may be computed once, at the beginning of time, based
//! upon the lens parameters of the system"; per frame the camera only moves them).
//!
//! **What is pose-free.** For the pinhole and each eye of the stereo rig, the subsample ray
//! through film position `f` is `d = fl(B fl(v / |v|))` with the camera-space direction
//! `v = (x(f), y(f), -1)` (`Pinhole::camera_dir`) and `B` the camera basis. `x(f)` is computed
//! by float operations that are monotone in `f` (a division by the positive width, an addition,
//! a product with the positive `tan`), and the film positions `film + offset * footprint` are
//! monotone in the offset. So the float `x` of every ray of a tile lies in `[x(lo), x(hi)]`,
//! `lo` and `hi` the smallest and largest float film `x` of its samples at the extreme offsets;
//! likewise `y` (decreasing in `f`). This camera-space rectangle ([`Rect`]) depends on the film,
//! the samples and the intrinsics only; the build stores one per tile and per block.
//!
//! **The world beam of a rectangle** ([`rect_beam`]). The exact directions `w = B v / |v|`,
//! `v` in the rectangle, span the convex cone of the four corner directions `q_k = B (x_i, y_j,
//! -1)` (computed in f64). Over that cone:
//! - the dominant-axis slopes `w_b / |w_a|` are a central projection of the cone, whose image is
//!   the convex hull of the corners' images: their extrema are the corners' (Overbeck et al.'s
//!   beam of four rays);
//! - `s w_a / |B v|` is at least its smallest corner value `c` (the set `{w : s w_a >= c |w|}`
//!   is a convex cone containing the corners), and `|B v| >= sqrt(1 - e) |v|` with
//!   `e = 3 max |B^T B - I|`, so `s w_a >= alpha = c sqrt(1 - e)`.
//! - The float ray is within `delta = 13.2 U rb` of `w` per component (`rb >= max_j |B_j|_2`:
//!   the normalising, `2.5 U` for `|v|` and one rounding per quotient, and the 3-term product;
//!   the U-terms doubled as in `cast/setup/affine.rs`, step 1, where `v` itself is exact here).
//!   So its slope `d_b / |d_a|` is within `delta (1 + |u|) / (alpha - delta)` of `w`'s, and the
//!   caster's float slope one rounding further; the beam's slopes are widened by both and
//!   rounded outwards to f32. The axis is accepted where `alpha - delta >= MIN_DOMINANT`, as
//!   [`crate::beam::BeamBuilder::finish`] requires of its rays; otherwise the beam is
//!   [`Beam::EVERYTHING`] (every box partial: slower, never wrong).
//!
//! The lens-distorted eye (`Distorted`) has the same ray form with `v = (x, y, -1)` from its
//! radial gain, which is not monotone in the film position: its rectangles are the extremes
//! over every ray of the tile (`Distorted::camera_vector`), computed once at the build.
//!
//! **The fisheye** (up to 210 degrees: no single `z = -1` plane holds its rays) has rays
//! `d = fl(B u)` with a pose-free float camera-space vector `u` (`Fisheye::camera_vector`, the
//! generators' bits). A tile's rectangle is taken in its own camera-space basis
//! `L = [e1, e2, -c]` ([`Rect::basis`]), `c` the rays' mean direction: every `u` is the positive
//! multiple `-q_z L (q_x / -q_z, q_y / -q_z, -1)` of `q = L^-1 u` (computed in f64 and padded by
//! `1e-9 (1 + |x|)`, far above its `~1e-15` error; a ray more than ~87 degrees off `c` leaves
//! the rectangle unbounded). [`rect_beam`] then runs with `B L` for `B`: the corners' cone holds
//! every `B u`, and `|fl(B u) - B u| <= 3.1 U rb |u|`, below the pinhole's `delta`. A block's
//! rectangle comes from its own rays (the union of its tiles' would mix bases).
//!
//! **The thin lens** has the same form per lens sample `k`: the ray's direction is `fl(B u)`
//! with the pose-free `u = fl(d / |d|)`, `d` from the focus point to the lens point
//! (`ThinLens::camera_vector`), and its origin `o_k = fl(p + fl(B l_k))` for the camera-space
//! lens point `l_k`. Its rectangles are taken as the fisheye's (a basis per rectangle): one per
//! tile and block over every lens sample, and one per tile and lens sample for the caster's
//! lens beams ([`crate::Hierarchy::lens_beams`]). Moving them recomputes each `o_k` by the
//! generator's own operations (the rays' origins bit for bit): a lens beam's origin is its
//! `o_k`, a tile's or block's the box of every `o_k`.
//!
//! The origin is otherwise the eye's position, the rays' origin bit for bit. Tiles whose subsamples fall
//! on both eyes of a stereo film (a footprint across the eyes' seam) take the beam of their
//! rays instead (`rays_of`), and their block [`Beam::EVERYTHING`].
//!
//! `tests/repose.rs`: every subsample ray of a moved camera lies in its tile's moved beam (with
//! no tolerance), and the cast with a moved hierarchy equals the per-ray trace of the moved
//! camera.

use glam::{DMat3, DVec3, Vec2, Vec3};
use parallax_core::Aabb;
use parallax_scene::camera::{Camera, CameraFrame, Fisheye, Pinhole, ThinLens};

use crate::SampleSet;
use crate::beam::{Beam, MIN_DOMINANT};

/// Unit roundoff of f32 (`2^-24`).
const U: f64 = f32::EPSILON as f64 * 0.5;

/// A camera-space rectangle `[x0, x1] x [y0, y1]` (at `z = -1`) holding the float direction of
/// every ray of a tile or block, and the eye (0, or 1 for the right eye of a stereo rig) whose
/// frame turns it into the world; `eye = BOTH_EYES` for a tile with rays of both eyes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    pub x: [f32; 2],
    pub y: [f32; 2],
    pub eye: u8,
    /// The camera-space basis of the coordinates: every ray's camera-space vector is a positive
    /// multiple of `basis * (x, y, -1)` for some `(x, y)` in the rectangle. The identity for
    /// the pinhole, the stereo rig and the distorted eye; a frame about the rays' mean
    /// direction for the fisheye (module docs).
    pub basis: DMat3,
}

/// [`Rect::eye`] of a tile with rays of both stereo eyes.
pub const BOTH_EYES: u8 = u8::MAX;

impl Rect {
    /// The union of two rectangles of one eye and one basis ([`BOTH_EYES`] if the eyes or the
    /// bases differ).
    pub fn union(self, o: Rect) -> Rect {
        Rect {
            x: [self.x[0].min(o.x[0]), self.x[1].max(o.x[1])],
            y: [self.y[0].min(o.y[0]), self.y[1].max(o.y[1])],
            eye: if self.eye == o.eye && self.basis == o.basis {
                self.eye
            } else {
                BOTH_EYES
            },
            basis: self.basis,
        }
    }
}

/// The pinhole eyes of a camera whose film positions map monotonically to its camera-space
/// directions (the pinhole alone, or the stereo rig's two), with the film width of one eye
/// (`+inf` for the pinhole); `None` for other models.
fn eyes(camera: &Camera) -> Option<(&[Pinhole], f32)> {
    match camera {
        Camera::Pinhole(p) => Some((std::slice::from_ref(p), f32::INFINITY)),
        Camera::Stereo(r) => Some((&r.eyes, r.eye_width() as f32)),
        _ => None,
    }
}

/// Whether the beams of `camera`'s sets can be moved: the models whose rays are `fl(B fl(v /
/// |v|))` from the eye with a camera-space `v = (x, y, -1)` — the pinhole, the stereo rig
/// and the lens-distorted eye (whose `x`, `y` are not monotone in the film: its rectangles
/// come from every ray, [`rect_of`]) — and the fisheye and the thin lens (`fl(B u)`, their
/// rectangles in a basis per rectangle).
pub fn movable(camera: &Camera) -> bool {
    eyes(camera).is_some()
        || matches!(
            camera,
            Camera::Distorted(_) | Camera::Fisheye(_) | Camera::ThinLens(_)
        )
}

/// Whether a block's rectangle is taken from its rays rather than as the union of its tiles'
/// (the fisheye and the thin lens: each tile has its own basis).
pub fn block_rect_from_rays(camera: &Camera) -> bool {
    matches!(camera, Camera::Fisheye(_) | Camera::ThinLens(_))
}

/// The rays' origins of a [`movable`] camera at its pose: per lens sample of `set` for the
/// thin lens (`fl(p + fl(B l_k))`, the generators' operations), else the one eye position
/// (`None` for a stereo rig: its tiles take their eye's position).
pub fn lens_origins(set: &SampleSet) -> Option<Vec<Vec3>> {
    match &set.camera {
        Camera::ThinLens(c) => {
            let f = &c.pinhole.frame;
            Some(
                set.lens
                    .iter()
                    .map(|&l| f.position + f.dir_to_world(c.lens_point(l)))
                    .collect(),
            )
        }
        _ => None,
    }
}

/// `a` with the camera frames of `b`, if both are the same [`movable`] model.
pub fn with_frames_of(a: &Camera, b: &Camera) -> Option<Camera> {
    let mut c = a.clone();
    match (&mut c, b) {
        (Camera::Pinhole(p), Camera::Pinhole(q)) => p.frame = q.frame,
        (Camera::Stereo(r), Camera::Stereo(q)) => {
            for (e, f) in r.eyes.iter_mut().zip(&q.eyes) {
                e.frame = f.frame;
            }
        }
        (Camera::Distorted(d), Camera::Distorted(q)) => d.pinhole.frame = q.pinhole.frame,
        (Camera::Fisheye(f), Camera::Fisheye(q)) => f.frame = q.frame,
        (Camera::ThinLens(t), Camera::ThinLens(q)) => t.pinhole.frame = q.pinhole.frame,
        _ => return None,
    }
    Some(c)
}

/// The frame of eye `eye` of a [`movable`] camera.
pub fn eye_frame(camera: &Camera, eye: u8) -> Option<&CameraFrame> {
    match camera {
        Camera::Distorted(d) => (eye == 0).then_some(&d.pinhole.frame),
        Camera::Fisheye(f) => (eye == 0).then_some(&f.frame),
        Camera::ThinLens(t) => (eye == 0).then_some(&t.pinhole.frame),
        c => eyes(c)?.0.get(eye as usize).map(|p| &p.frame),
    }
}

/// The camera-space rectangle of the rays of samples `idx` of `set` (module docs); `None`
/// for a camera [`movable`] does not take.
pub fn rect_of(set: &SampleSet, idx: &[u32]) -> Option<Rect> {
    match &set.camera {
        Camera::Distorted(c) => return Some(distorted_rect(set, c, idx)),
        Camera::Fisheye(f) => return Some(fisheye_rect(set, f, idx)),
        Camera::ThinLens(c) => return Some(lens_rect(set, c, idx, 0..set.lens.len())),
        _ => {}
    }
    let (eyes, w) = eyes(&set.camera)?;
    let (mut olo, mut ohi) = (Vec2::INFINITY, Vec2::NEG_INFINITY);
    for o in &set.offsets {
        olo = olo.min(*o);
        ohi = ohi.max(*o);
    }
    // Film extremes: `film + offset * footprint` is monotone in the offset (either way, by the
    // footprint's sign), so each sample's lie at its two extreme offsets.
    let (mut flo, mut fhi) = (Vec2::INFINITY, Vec2::NEG_INFINITY);
    for &i in idx {
        let s = &set.samples[i as usize];
        let (a, b) = (s.film + olo * s.footprint, s.film + ohi * s.footprint);
        flo = flo.min(a.min(b));
        fhi = fhi.max(a.max(b));
    }
    if !(flo.is_finite() && fhi.is_finite()) {
        return Some(UNBOUNDED);
    }
    // The eye of every ray (as the generators pick it: `x < w` left, else right).
    let (eye, shift) = if fhi.x < w {
        (0, 0.0)
    } else if flo.x >= w {
        (1, w)
    } else {
        return Some(Rect {
            x: [0.0; 2],
            y: [0.0; 2],
            eye: BOTH_EYES,
            basis: DMat3::IDENTITY,
        });
    };
    let p = &eyes[eye as usize];
    // The generator's own operations (`camera_dir`), at the film extremes: `x` increases and
    // `y` decreases with the film position.
    let (lo, hi) = (
        p.camera_dir(Vec2::new(flo.x - shift, fhi.y)),
        p.camera_dir(Vec2::new(fhi.x - shift, flo.y)),
    );
    Some(Rect {
        x: [lo.x, hi.x],
        y: [lo.y, hi.y],
        eye,
        basis: DMat3::IDENTITY,
    })
}

/// A rectangle [`rect_beam`] turns into [`Beam::EVERYTHING`] (non-finite rays).
const UNBOUNDED: Rect = Rect {
    x: [f32::NEG_INFINITY, f32::INFINITY],
    y: [f32::NEG_INFINITY, f32::INFINITY],
    eye: 0,
    basis: DMat3::IDENTITY,
};

/// [`rect_of`] for the lens-distorted eye: the extremes of every ray's camera-space `(x, y)`
/// in lanes (`distorted_rect.rs`; the values of [`distorted_rect_scalar`]).
fn distorted_rect(set: &SampleSet, c: &parallax_scene::camera::Distorted, idx: &[u32]) -> Rect {
    match super::distorted_rect::distorted_extremes(set, c, idx) {
        Some((x, y)) => distorted_rect_of(x, y),
        None => UNBOUNDED,
    }
}

/// [`rect_of`] for the lens-distorted eye by its definition: the extremes of every ray's
/// camera-space `(x, y)` (`Distorted::camera_vector`), one ray at a time. The build runs the
/// same in lanes (`distorted_rect.rs`, the same values; tested against this).
#[cfg(test)]
fn distorted_rect_scalar(
    set: &SampleSet,
    c: &parallax_scene::camera::Distorted,
    idx: &[u32],
) -> Rect {
    let (mut lo, mut hi) = (Vec2::INFINITY, Vec2::NEG_INFINITY);
    for &i in idx {
        let s = &set.samples[i as usize];
        for o in &set.offsets {
            // Rays of channels past 2 are invalid (never cast).
            if let Some(v) = c.camera_vector(s.film + *o * s.footprint, s.channel as usize) {
                if !(v.x.is_finite() && v.y.is_finite()) {
                    return UNBOUNDED;
                }
                lo = lo.min(v.truncate());
                hi = hi.max(v.truncate());
            }
        }
    }
    distorted_rect_of([lo.x, hi.x], [lo.y, hi.y])
}

/// The distorted eye's rectangle of the extremes `x`, `y` of its rays: a point rectangle at
/// the origin where there is no valid ray (the tile casts nothing); a zero bound as `+0`.
fn distorted_rect_of(x: [f32; 2], y: [f32; 2]) -> Rect {
    let (x, y) = if x[0] > x[1] {
        ([0.0; 2], [0.0; 2])
    } else {
        // `v + 0.0` is `v` but for `-0.0`, which becomes `+0.0`.
        (x.map(|v| v + 0.0), y.map(|v| v + 0.0))
    };
    Rect {
        x,
        y,
        eye: 0,
        basis: DMat3::IDENTITY,
    }
}

/// [`rect_of`] for the fisheye: the rectangle of the rays' camera-space vectors
/// (`Fisheye::camera_vector`) in a basis about their mean direction (module docs).
fn fisheye_rect(set: &SampleSet, f: &Fisheye, idx: &[u32]) -> Rect {
    let mut us = Vec::with_capacity(idx.len() * set.offsets.len());
    for &i in idx {
        let s = &set.samples[i as usize];
        for o in &set.offsets {
            // Rays outside the image circle are invalid (never cast).
            if let Some(u) = f.camera_vector(s.film + *o * s.footprint) {
                us.push(u);
            }
        }
    }
    vectors_rect(&us)
}

/// [`rect_of`] for the thin lens, over the subsamples `ks` of the samples `idx` (each with its
/// own lens sample): the rectangle of the rays' camera-space directions
/// (`ThinLens::camera_vector`) in a basis about their mean (module docs).
pub fn lens_rect(set: &SampleSet, c: &ThinLens, idx: &[u32], ks: std::ops::Range<usize>) -> Rect {
    let mut us = Vec::with_capacity(idx.len() * ks.len());
    for &i in idx {
        let s = &set.samples[i as usize];
        for k in ks.clone() {
            us.push(c.camera_vector(s.film + set.offsets[k] * s.footprint, set.lens[k]));
        }
    }
    vectors_rect(&us)
}

/// The rectangle of the camera-space vectors `us` in a basis about their mean direction (module
/// docs, the fisheye); unbounded for a non-finite vector or one more than ~87 degrees off the
/// mean, a point rectangle for none.
// (A test is negated so that a NaN fails it.)
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn vectors_rect(us: &[Vec3]) -> Rect {
    if !us.iter().all(|u| u.is_finite()) {
        return UNBOUNDED;
    }
    let us: Vec<DVec3> = us.iter().map(|u| u.as_dvec3()).collect();
    let c = us
        .iter()
        .map(|u| *u / u.length())
        .sum::<DVec3>()
        .normalize_or_zero();
    if c == DVec3::ZERO {
        // No valid ray (a point rectangle: the tile casts nothing), or no mean direction.
        return if us.is_empty() {
            Rect {
                x: [0.0; 2],
                y: [0.0; 2],
                eye: 0,
                basis: DMat3::IDENTITY,
            }
        } else {
            UNBOUNDED
        };
    }
    let e1 = c.any_orthonormal_vector();
    let basis = DMat3::from_cols(e1, c.cross(e1), -c);
    let inv = basis.inverse();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for u in &us {
        let q = inv * *u;
        let w = -q.z;
        if !(w > 0.05 * u.length()) {
            return UNBOUNDED;
        }
        for (k, v) in [q.x / w, q.y / w].into_iter().enumerate() {
            lo[k] = lo[k].min(v);
            hi[k] = hi[k].max(v);
        }
    }
    let pad = |v: f64| 1e-9 * (1.0 + v.abs());
    let side = |k: usize| {
        [
            ((lo[k] - pad(lo[k])) as f32).next_down(),
            ((hi[k] + pad(hi[k])) as f32).next_up(),
        ]
    };
    Rect {
        x: side(0),
        y: side(1),
        eye: 0,
        basis,
    }
}

/// The world beam of the rays of rectangle `r` through `frame` from the eye's position
/// (module docs).
pub fn rect_beam(frame: &CameraFrame, r: &Rect) -> Beam {
    rect_beam_from(frame, r, Aabb::EMPTY.grow(frame.position))
}

/// [`rect_beam`] for rays whose origins lie in `origin` (a thin lens's lens points).
// (The tests are negated so that a NaN fails them.)
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn rect_beam_from(frame: &CameraFrame, r: &Rect, origin: Aabb) -> Beam {
    if r.eye == BOTH_EYES || !(r.x.iter().chain(&r.y).all(|v| v.is_finite())) {
        return Beam::EVERYTHING;
    }
    let b = DMat3::from_cols(
        frame.basis.x_axis.as_dvec3(),
        frame.basis.y_axis.as_dvec3(),
        frame.basis.z_axis.as_dvec3(),
    ) * r.basis;
    let rows = b.transpose();
    let rb = [rows.x_axis, rows.y_axis, rows.z_axis]
        .iter()
        .map(|r| r.length())
        .fold(0.0, f64::max)
        * (1.0 + 1e-9);
    let delta = 13.2 * U * rb * 1.01;
    let g = b.transpose() * b - DMat3::IDENTITY;
    let e = 3.0
        * [g.x_axis, g.y_axis, g.z_axis]
            .iter()
            .map(|c| c.abs().max_element())
            .fold(0.0, f64::max);
    if !(e < 0.5) {
        return Beam::EVERYTHING;
    }
    let shrink = (1.0 - e).sqrt() * (1.0 - 1e-12);
    let corners = [
        b * DVec3::new(r.x[0] as f64, r.y[0] as f64, -1.0),
        b * DVec3::new(r.x[1] as f64, r.y[0] as f64, -1.0),
        b * DVec3::new(r.x[0] as f64, r.y[1] as f64, -1.0),
        b * DVec3::new(r.x[1] as f64, r.y[1] as f64, -1.0),
    ];
    let mean: DVec3 = corners.iter().map(|q| *q / q.length()).sum();
    let mut axes = [0usize, 1, 2];
    let m = mean.abs();
    axes.sort_by(|&i, &j| m[j].total_cmp(&m[i]));
    for a in axes {
        let s = if mean[a] >= 0.0 { 1.0 } else { -1.0 };
        let c = corners
            .iter()
            .map(|q| s * q[a] / q.length())
            .fold(f64::INFINITY, f64::min);
        let alpha = c * shrink;
        if !(alpha - delta >= MIN_DOMINANT as f64) {
            continue;
        }
        let (bx, cx) = ((a + 1) % 3, (a + 2) % 3);
        let range = |k: usize| {
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for q in &corners {
                let u = q[k] / q[a].abs();
                lo = lo.min(u);
                hi = hi.max(u);
            }
            let m = delta * (1.0 + lo.abs().max(hi.abs())) / (alpha - delta);
            let pad = |u: f64| m + 2.0 * U * (u.abs() + m) + 1e-12 * (1.0 + u.abs());
            [
                ((lo - pad(lo)) as f32).next_down(),
                ((hi + pad(hi)) as f32).next_up(),
            ]
        };
        return Beam {
            axis: a as u8,
            sign: s as f32,
            u: range(bx),
            v: range(cx),
            origin,
            everything: false,
        };
    }
    Beam::EVERYTHING
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cast::lanes16::V16;
    use crate::hierarchy::distorted_rect::extremes_lanes;
    use glam::Vec3;
    use parallax_scene::CameraDesc;
    use parallax_scene::camera::{Camera, CameraOptions, ModelKind};

    /// The rectangles in lanes (the dispatched tier and the portable `V16`) equal the scalar
    /// definition bit for bit: per-channel distorted sets at 1, 4, 8 and 16 spp, grids too,
    /// over runs of samples of every length (a partial last step, runs shorter than a step) and
    /// every sample alone, and a sample set with a sample of an invalid channel and one with a
    /// non-finite film.
    #[test]
    fn lanes_equal_the_scalar_definition() {
        let desc = CameraDesc::new(Vec3::new(0.2, 1.0, 3.0), Vec3::ZERO, Vec3::Y, 70.0);
        let cam = Camera::new(
            ModelKind::Distorted,
            &desc,
            36,
            40,
            &CameraOptions::default(),
        )
        .unwrap();
        let Camera::Distorted(c) = &cam else {
            unreachable!()
        };
        let bits = |r: Rect| (r.x.map(f32::to_bits), r.y.map(f32::to_bits));
        let mut sets = Vec::new();
        for spp in [1, 4, 8, 16] {
            sets.push(SampleSet::distorted(cam.clone(), spp).unwrap());
            sets.push(SampleSet::grid(cam.clone(), spp));
        }
        let mut odd = SampleSet::distorted(cam.clone(), 4).unwrap();
        odd.samples[5].channel = 3;
        sets.push(odd.clone());
        odd.samples[9].film.x = f32::NAN;
        sets.push(odd);
        let mut checked = 0;
        for set in &sets {
            let n = set.samples.len() as u32;
            for (start, len) in [(0, n), (0, 1), (3, 5), (7, 17), (n - 33, 33), (11, 0)] {
                let idx: Vec<u32> = (start..start + len).collect();
                let want = bits(distorted_rect_scalar(set, c, &idx));
                assert_eq!(bits(distorted_rect(set, c, &idx)), want, "{start} {len}");
                let portable = extremes_lanes::<V16>(set, c, &idx);
                let portable = portable.map_or(UNBOUNDED, |(x, y)| distorted_rect_of(x, y));
                assert_eq!(bits(portable), want, "{start} {len}");
                checked += 1;
            }
            // Every sample alone: its rays are the extremes, so each ray's bits count.
            for i in 0..n {
                let want = bits(distorted_rect_scalar(set, c, &[i]));
                assert_eq!(bits(distorted_rect(set, c, &[i])), want, "sample {i}");
            }
        }
        assert_eq!(checked, 60);
        // The invalid channel takes no part, the NaN film makes the rectangle unbounded.
        let nan_set = &sets[9];
        assert_eq!(distorted_rect(nan_set, c, &[9]), UNBOUNDED);
        assert_eq!(distorted_rect(&sets[8], c, &[5]).x, [0.0; 2]);
    }
}
