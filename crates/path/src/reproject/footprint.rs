//! Backward reprojection of one pixel (Mäkitalo et al. 2019, §4.1; Nehab et al. 2007): the
//! target pixel's world position is projected into the source view, the source pixels around
//! that film position are weighted by a separable tent (radius 1 = the paper's bilinear
//! weights over the 4 closest pixel centres), neighbours whose world position or shading
//! normal differ from the target's beyond the limits are discarded, and the weights of the
//! rest are renormalised. The same footprint serves the stereo (right eye -> left eye) and the
//! temporal (previous frame -> current frame) reprojection and any per-pixel value (colour,
//! history length).
//!
//! The tests (as BMFR's `accumulate_noisy_data`, Koskela et al. 2019): a neighbour is kept when
//! `|p_s - p_t|² < position²` and `|n_s - n_t|² < chord²` with `chord = 2 sin(normal / 2)` (the
//! distance of two unit normals `normal` apart). Both are strict, so zero limits discard every
//! neighbour. With [`Tests::plane`] the position test measures the neighbour's distance from
//! the target's tangent plane, `|(p_s - p_t) · n_t|`, instead of the full distance: offsets
//! along the surface (a neighbour one pixel away on a grazing floor, the jitter of the primary
//! rays) pass, steps off the surface (an occluder, a disocclusion) still fail. Not the paper's
//! test (it compares the two world positions); ours, as the plane-distance tests of SVGF-style
//! filters.
//!
//! | parameter | type | meaning |
//! |---|---|---|
//! | [`Kernel::radius`] | f32 in [1, 2] | tent radius in source pixels (1: bilinear over 2x2 neighbours; 2: 4x4; integer radii reproduce linear ramps exactly, others only approximately) |
//! | [`Tests::position`] | f32 (scene units) | largest world-position difference kept |
//! | [`Tests::normal_deg`] | f32 (degrees) | largest shading-normal angle kept |
//! | [`Tests::plane`] | bool | position test against the target's tangent plane (false: the paper's distance) |
//!
//! **Invariants:** a footprint's kept weights sum to one (`inv_weight` renormalises); a pixel
//! is [`Outcome::Reused`] exactly when at least one neighbour with non-zero weight passed both
//! tests; the result depends only on the two views, never on the thread count. The bilinear
//! taps are tested in SSE lanes on x86-64 (`lanes.rs`), bit for bit as the scalar loop
//! (tested).

use std::ops::{Add, Mul};

use glam::{Vec3, Vec4, Vec4Swizzles};
use rayon::prelude::*;

use super::buffers::{EyeView, Texel};
use super::isa::Isa;
#[cfg(target_arch = "x86_64")]
use super::lanes::bilinear_taps_x4;
use super::projector::{Projector, floor_xy};
use super::sampler::thread_ns;

/// What became of a target pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Outcome {
    /// Filled from the source (at least one neighbour kept).
    #[default]
    Reused = 0,
    /// The position projects outside the source view (or behind its camera).
    Outside = 1,
    /// Every neighbour failed the world-position test (or saw the sky).
    Position = 2,
    /// Some neighbour passed the position test, none the normal test.
    Normal = 3,
    /// The target pixel sees the sky: its value is the environment, known without a sample.
    Background = 4,
}

impl Outcome {
    /// True when the pixel needs a new sample (the source could not give it anything).
    #[inline]
    pub fn is_discarded(self) -> bool {
        matches!(self, Outcome::Outside | Outcome::Position | Outcome::Normal)
    }
}

/// The reconstruction kernel: a separable tent over source pixel centres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kernel {
    /// Radius in source pixels, in `[1, 2]`; 1 is bilinear interpolation.
    pub radius: f32,
}

impl Kernel {
    /// The paper's bilinear weights.
    pub const BILINEAR: Kernel = Kernel { radius: 1.0 };

    /// Taps per axis: offsets `1 - half ..= half` from the pixel left of (above) the sample.
    #[inline]
    fn half(self) -> i32 {
        self.radius.ceil() as i32
    }

    #[inline]
    fn weight(self, d: f32) -> f32 {
        (1.0 - d.abs() / self.radius).max(0.0)
    }
}

/// The neighbour tests, squared for the inner loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tests {
    /// Largest world-position difference kept (scene units).
    pub position: f32,
    /// Largest shading-normal angle kept (degrees).
    pub normal_deg: f32,
    /// Distance from the target's tangent plane instead of the full distance (module docs).
    pub plane: bool,
}

impl Tests {
    /// The limits squared, once per pass rather than per pixel (the chord needs a sine).
    #[inline]
    fn limits(self) -> Limits {
        let chord = 2.0 * (0.5 * self.normal_deg.to_radians()).sin();
        Limits {
            pos2: self.position * self.position,
            nrm2: chord * chord,
            plane: self.plane,
        }
    }
}

/// [`Tests`] as the inner loop compares them.
#[derive(Clone, Copy, Debug)]
struct Limits {
    pos2: f32,
    nrm2: f32,
    plane: bool,
}

/// Where a target pixel's value comes from in the source: the kept neighbours (a bit per tap,
/// row-major over the kernel's taps from `(x0, y0)`) and their weights' normaliser.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Footprint {
    pub x0: i32,
    pub y0: i32,
    /// Offset of the projected position from the centre of the source pixel left of (above)
    /// it, `(x0 + half - 1, y0 + half - 1)` with `half = ceil(radius)`, in `[0, 1)`.
    pub fx: f32,
    pub fy: f32,
    pub mask: u16,
    pub outcome: Outcome,
    /// The bilinear kernel's four taps all lie inside the source (false for wider kernels).
    pub taps_inside: bool,
    /// One over the sum of the kept weights (0 when nothing was kept).
    pub inv_weight: f32,
    /// Where `taps_inside`: the four taps' bilinear weights (row-major from `(x0, y0)`, the
    /// products of the tent weights of their column and row) with the dropped taps' lanes
    /// +0, computed once by the footprint for its gathers; zero otherwise.
    pub weights: Vec4,
}

/// A value a footprint can average.
pub trait Blendable: Copy + Default + Add<Output = Self> + Mul<f32, Output = Self> {
    /// The bilinear sum of four taps' values `v` (row-major) with weights `wt` (lanes, in tap
    /// order), of the taps whose `mask` bit is set: `0 + t0 + t1 + t2 + t3` with `t_k =
    /// v[k] * wt[k]` for a kept tap and `+0` for a dropped one. Adding +0 instead of nothing
    /// changes no sum (one that starts at +0 is never -0), so this is the tap loop's sum bit
    /// for bit. A kept tap's weight is positive and a dropped tap's lane of `wt` is +0
    /// ([`Footprint::weights`]), so `wt[k] > 0` is the tap's `mask` bit.
    #[inline(always)]
    fn sum_taps(v: [Self; 4], wt: Vec4, mask: u16) -> Self {
        let tap = |k: u32, v: Self, w: f32| {
            if mask & (1 << k) != 0 {
                v * w
            } else {
                Self::default()
            }
        };
        Self::default()
            + tap(0, v[0], wt.x)
            + tap(1, v[1], wt.y)
            + tap(2, v[2], wt.z)
            + tap(3, v[3], wt.w)
    }
}
impl Blendable for f32 {}
impl Blendable for Vec3 {}
/// A colour with a fourth value gathered alongside (a history's colour and length): each lane
/// is summed with exactly the scalar operations of a `Vec3` or `f32` gather.
impl Blendable for Vec4 {
    /// The trait's sum without branches: the products of dropped taps (the `mask` bits clear,
    /// i.e. the lanes where `wt[k] > 0` is false) are cleared with a lane mask (x86-64), so a
    /// dropped tap adds +0 whatever its value.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn sum_taps(v: [Self; 4], wt: Vec4, _mask: u16) -> Self {
        use std::arch::x86_64::*;
        // SAFETY: SSE2 is part of x86-64.
        unsafe {
            let w: __m128 = wt.into();
            let m = _mm_cmpgt_ps(w, _mm_setzero_ps());
            let t0 = _mm_and_ps(
                _mm_mul_ps(v[0].into(), _mm_shuffle_ps::<0x00>(w, w)),
                _mm_shuffle_ps::<0x00>(m, m),
            );
            let t1 = _mm_and_ps(
                _mm_mul_ps(v[1].into(), _mm_shuffle_ps::<0x55>(w, w)),
                _mm_shuffle_ps::<0x55>(m, m),
            );
            let t2 = _mm_and_ps(
                _mm_mul_ps(v[2].into(), _mm_shuffle_ps::<0xAA>(w, w)),
                _mm_shuffle_ps::<0xAA>(m, m),
            );
            let t3 = _mm_and_ps(
                _mm_mul_ps(v[3].into(), _mm_shuffle_ps::<0xFF>(w, w)),
                _mm_shuffle_ps::<0xFF>(m, m),
            );
            let s = _mm_add_ps(_mm_setzero_ps(), t0);
            let s = _mm_add_ps(_mm_add_ps(_mm_add_ps(s, t1), t2), t3);
            s.into()
        }
    }
}

impl Footprint {
    fn discarded(outcome: Outcome) -> Self {
        Self {
            outcome,
            ..Self::default()
        }
    }

    /// The weighted mean of the kept neighbours' `values` (row-major, source `width`); zero
    /// when nothing was kept.
    #[inline]
    pub fn gather<T: Blendable>(&self, kernel: Kernel, values: &[T], width: u32) -> T {
        if kernel == Kernel::BILINEAR {
            self.gather_in::<true, T>(kernel, values, width)
        } else {
            self.gather_in::<false, T>(kernel, values, width)
        }
    }

    /// [`Self::gather`]; `BILINEAR` fixes the kernel at compile time (same arithmetic, the
    /// tap loops unrolled).
    #[inline(always)]
    fn gather_in<const BILINEAR: bool, T: Blendable>(
        &self,
        kernel: Kernel,
        values: &[T],
        width: u32,
    ) -> T {
        let kernel = if BILINEAR { Kernel::BILINEAR } else { kernel };
        let mut acc = T::default();
        if self.mask == 0 {
            return acc;
        }
        if BILINEAR && self.taps_inside {
            let w = width as usize;
            let i0 = self.y0 as usize * w + self.x0 as usize;
            // One range check for both rows (the indices below are within `w + 2`).
            if let Some(r) = values.get(i0..i0 + w + 2) {
                return self.gather_bilinear([r[0], r[1], r[w], r[w + 1]]);
            }
        }
        let half = kernel.half();
        let taps = 2 * half;
        let mut bit = 0;
        for ty in 0..taps {
            let wy = kernel.weight((ty - half + 1) as f32 - self.fy);
            for tx in 0..taps {
                if self.mask & (1 << bit) != 0 {
                    let wx = kernel.weight((tx - half + 1) as f32 - self.fx);
                    let (x, y) = (self.x0 + tx, self.y0 + ty);
                    acc = acc + values[y as usize * width as usize + x as usize] * (wx * wy);
                }
                bit += 1;
            }
        }
        acc * self.inv_weight
    }

    /// The bilinear gather of the four taps' values (row-major from `(x0, y0)`), all inside
    /// the source: each kept tap's value times its weight (the footprint's
    /// [`Footprint::weights`], the tent weights in the lanes of one vector), summed in tap
    /// order from zero, times the normaliser. A dropped tap adds +0 instead of nothing, which
    /// changes no sum (a sum that starts at +0 is never -0), so the result is the tap loop's
    /// bit for bit (tested).
    #[inline(always)]
    fn gather_bilinear<T: Blendable>(&self, v: [T; 4]) -> T {
        T::sum_taps(v, self.weights, self.mask) * self.inv_weight
    }
}

/// The bilinear weights of the four taps (row-major from `(x0, y0)`) of a sample at offset
/// `f` (lanes x, y) from the tap `(x0, y0)`: `kernel.weight(tx - fx) * kernel.weight(ty - fy)`
/// of [`Kernel::BILINEAR`] bit for bit, the tent weights in the lanes of one vector (a
/// division by the radius 1 is exact and dropped).
#[inline(always)]
fn bilinear_weights(f: Vec4) -> Vec4 {
    let d = Vec4::new(0.0, 1.0, 0.0, 1.0) - f.xxyy();
    let w = (Vec4::ONE - d.abs()).max(Vec4::ZERO);
    w.xyxy() * w.zzww()
}

/// The footprint of a target pixel seeing `t` in `source`.
pub fn footprint(source: &EyeView, t: &Texel, kernel: Kernel, tests: Tests) -> Footprint {
    Reprojector::new(source, kernel, tests).footprint(t)
}

/// A source view, kernel and tests prepared for many footprints (the limits squared and the
/// source camera's projection constants computed once).
#[derive(Clone, Copy, Debug)]
pub struct Reprojector<'a> {
    source: &'a EyeView,
    proj: Projector,
    kernel: Kernel,
    lim: Limits,
}

impl<'a> Reprojector<'a> {
    pub fn new(source: &'a EyeView, kernel: Kernel, tests: Tests) -> Self {
        Self {
            source,
            proj: Projector::new(&source.camera),
            kernel,
            lim: tests.limits(),
        }
    }

    /// [`footprint`] in the prepared source with the prepared kernel and tests.
    #[inline(always)]
    pub fn footprint(&self, t: &Texel) -> Footprint {
        if self.kernel == Kernel::BILINEAR {
            footprint_in::<true, true>(self.source, &self.proj, t, self.kernel, self.lim)
        } else {
            footprint_in::<false, false>(self.source, &self.proj, t, self.kernel, self.lim)
        }
    }
}

/// [`footprint`]; `BILINEAR` fixes the kernel at compile time: the same arithmetic (a
/// division by the radius 1 is exact), the taps unrolled; `LANES` (with `BILINEAR`, on
/// x86-64) tests the four taps in the lanes of one SSE vector ([`bilinear_taps_x4`]) where
/// all four lie inside the source.
#[inline(always)]
fn footprint_in<const BILINEAR: bool, const LANES: bool>(
    source: &EyeView,
    proj: &Projector,
    t: &Texel,
    kernel: Kernel,
    lim: Limits,
) -> Footprint {
    let kernel = if BILINEAR { Kernel::BILINEAR } else { kernel };
    if !t.is_hit() {
        return Footprint::discarded(Outcome::Background);
    }
    // The film position `f` minus 0.5 (`Pinhole::project` bit for bit).
    let Some(s) = proj.project(t.position_lanes()) else {
        return Footprint::discarded(Outcome::Outside);
    };
    // The bilinear taps all inside the source (the common case, tested in SSE lanes):
    // `floor(s) >= 0` is `s >= 0` and `floor(s) + 1 < n` is `s < n - 1` (integer bounds,
    // exact), both axes in lanes x, y; such a position also passes the range check below.
    #[cfg(target_arch = "x86_64")]
    if BILINEAR && LANES {
        let inner = s.cmpge(Vec4::ZERO) & s.cmplt(proj.size() - Vec4::ONE);
        if inner.bitmask() & 3 == 3 {
            let (x0, y0, frac) = floor_xy(s);
            let (pos2, nrm2, plane) = (lim.pos2, lim.nrm2, lim.plane);
            let wt = bilinear_weights(frac);
            let (mask, sum, inside, near, kept) =
                bilinear_taps_x4(source, t, x0, y0, wt, pos2, nrm2, plane);
            return placed(x0, y0, frac.x, frac.y, mask, sum, inside, near, Some(kept));
        }
    }
    let (pos2, nrm2) = (lim.pos2, lim.nrm2);
    let half = kernel.half();
    let (w, h) = (source.width() as i32, source.height() as i32);
    // Pixel centres are at integer + 0.5: the tap left of (above) the sample is floor(f - 0.5).
    // With `reach` an integer, `floor(s) > -reach` is `s >= 1 - reach` and `floor(s) < n +
    // reach` is `s < n + reach`, so the range is checked before the floor (exact below 2^23,
    // far beyond any film); a non-finite `f` fails it (NaN compares false) and is outside.
    // Both axes at once: `sx >= 1 - reach && sx < w + reach` (and y) in lanes x, y.
    let reach = half as f32 + 1.0;
    let in_range = s.cmpge(Vec4::splat(1.0 - reach)) & s.cmplt(proj.size() + Vec4::splat(reach));
    if in_range.bitmask() & 3 != 3 {
        return Footprint::discarded(Outcome::Outside);
    }
    let (ix, iy, frac) = floor_xy(s);
    let (fx, fy) = (frac.x, frac.y);
    let (x0, y0) = (ix - half + 1, iy - half + 1);
    let taps = 2 * half;
    let (mut mask, mut sum, mut bit) = (0u16, 0.0f32, 0);
    let (mut inside, mut near) = (false, false);
    for ty in 0..taps {
        let wy = kernel.weight((ty - half + 1) as f32 - fy);
        let y = y0 + ty;
        for tx in 0..taps {
            let x = x0 + tx;
            let wx = kernel.weight((tx - half + 1) as f32 - fx);
            let wt = wx * wy;
            if wt > 0.0 && x >= 0 && y >= 0 && x < w && y < h {
                inside = true;
                let s = &source.texels[y as usize * w as usize + x as usize];
                let d = s.position - t.position;
                let d2 = if lim.plane {
                    let h = d.dot(t.normal);
                    h * h
                } else {
                    d.length_squared()
                };
                if s.is_hit() && d2 < pos2 {
                    near = true;
                    if (s.normal - t.normal).length_squared() < nrm2 {
                        mask |= 1 << bit;
                        sum += wt;
                    }
                }
            }
            bit += 1;
        }
    }
    let taps_inside = kernel == Kernel::BILINEAR && x0 >= 0 && y0 >= 0 && x0 + 1 < w && y0 + 1 < h;
    // The four tent weights of a bilinear footprint inside the source, the dropped taps'
    // lanes +0.
    let kept = taps_inside.then(|| {
        let wt = bilinear_weights(frac).to_array();
        Vec4::from_array(std::array::from_fn(|k| {
            if mask & (1 << k) != 0 { wt[k] } else { 0.0 }
        }))
    });
    placed(x0, y0, fx, fy, mask, sum, inside, near, kept)
}

/// The footprint of a target placed in the source, from its kept taps; `kept` are the
/// bilinear taps' weights with the dropped taps' lanes +0 when all four taps lie inside the
/// source (the footprint's `taps_inside`), else `None`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn placed(
    x0: i32,
    y0: i32,
    fx: f32,
    fy: f32,
    mask: u16,
    sum: f32,
    inside: bool,
    near: bool,
    kept: Option<Vec4>,
) -> Footprint {
    let outcome = match (mask != 0, inside, near) {
        (true, _, _) => Outcome::Reused,
        (false, false, _) => Outcome::Outside,
        (false, true, false) => Outcome::Position,
        (false, true, true) => Outcome::Normal,
    };
    Footprint {
        x0,
        y0,
        fx,
        fy,
        mask,
        outcome,
        taps_inside: kept.is_some(),
        inv_weight: if sum > 0.0 { 1.0 / sum } else { 0.0 },
        weights: kept.unwrap_or(Vec4::ZERO),
    }
}

/// Rows per parallel work item of the image passes.
pub(crate) const BAND_ROWS: usize = 8;

/// The footprint of every pixel of `target` in `source`, into `out`; returns the thread CPU
/// nanoseconds spent. Runs in the build of [`Isa::detect`].
pub fn footprints(
    target: &EyeView,
    source: &EyeView,
    kernel: Kernel,
    tests: Tests,
    out: &mut Vec<Footprint>,
) -> u64 {
    footprints_with(target, source, kernel, tests, out, Isa::detect())
}

/// [`footprints`] in the build of `isa` (every build's footprints are the same bit for bit).
pub fn footprints_with(
    target: &EyeView,
    source: &EyeView,
    kernel: Kernel,
    tests: Tests,
    out: &mut Vec<Footprint>,
    isa: Isa,
) -> u64 {
    let w = target.width() as usize;
    out.resize(target.len(), Footprint::default());
    let proj = Projector::new(&source.camera);
    let ns: Vec<u64> = out
        .par_chunks_mut(w * BAND_ROWS)
        .zip(target.texels.par_chunks(w * BAND_ROWS))
        .map(|(fps, texels)| {
            let t0 = thread_ns();
            let lim = tests.limits();
            isa.run(
                #[inline(always)]
                || {
                    if kernel == Kernel::BILINEAR {
                        for (fp, t) in fps.iter_mut().zip(texels) {
                            *fp = footprint_in::<true, true>(source, &proj, t, kernel, lim);
                        }
                    } else {
                        for (fp, t) in fps.iter_mut().zip(texels) {
                            *fp = footprint_in::<false, false>(source, &proj, t, kernel, lim);
                        }
                    }
                },
            );
            thread_ns().saturating_sub(t0)
        })
        .collect();
    ns.iter().sum()
}

#[cfg(test)]
mod tests;
