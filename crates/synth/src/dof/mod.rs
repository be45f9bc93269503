//! Thin-lens depth of field by screen-space ray tracing (Widmer et al. 2015, §5.2, Table 4,
//! Figs. 8-9).
//!
//! Every output pixel casts `N_pri` **lens rays**: lens samples stratified over the aperture
//! (an `a x b` grid of strata of `[0, 1)^2` with `a b = N_pri`, one jittered sample per
//! stratum, mapped to the disk by the concentric map of Shirley & Chiu 1997 inside
//! [`ThinLens::generate_ray`]), each through the point its film position focuses on (the
//! existing camera model, `parallax_scene::camera::thin_lens`). Each lens ray is traced
//! through the layers of a pinhole reference at the lens centre with any screen-space tracer
//! (the quad-tree over 1 or 2 layers, its single-layer inpainting mode of §4.1 — Fig. 9c —,
//! or the DDA baseline) and coloured exactly as the stereo warp colours its rays
//! ([`crate::warp::RayWarp`]: depth-aware bilinear resampling, the layer-0 guard, the
//! occlusion-volume fill). The pixel is the mean over its lens rays.
//!
//! **Secondary samples** (§5.2, [`secondary`]; quad-tree only): a lens ray that hits a
//! plane leaf is followed by `N_sec - 1` further lens samples from the *same stratum* ("in
//! close proximity to the primary ray, using the same random distribution") that are not
//! traced: each is intersected with the hit leaf's plane only, coloured at the
//! intersection, and weighted by `exp(-(z_i - z_b)^2 / sigma^2)` — `z_i` the intersection's
//! depth, `z_b` the layer's depth at the same screen point — so samples that land "in the
//! air" beside the hit surface fade out. The lens ray's colour is the weighted mean of its
//! `N_sec` samples (the traced one with weight 1). `N_sec = 1` is plain lens sampling.
//!
//! **Depth measure** (ours; the paper does not say in which units `z` is): `z_i - z_b` is the
//! *relative view-depth* difference `(d_i - d_b) / d_b`, so one `sigma` fits every scene
//! scale and both cube near planes, and `z_b` is the layer's pixel plane evaluated at the
//! intersection's sub-pixel position (the depth buffer reconstructed between pixel centres),
//! so a sample on the hit surface weighs 1 up to the plane fit's error even on steep
//! surfaces. Default `sigma = 0.02` (2 % of the depth): measured in `docs/notes/synth.md`.
//!
//! **Guard band** ([`setup::DofSetup`]): lens rays from the rim of the aperture leave the
//! lens-centre frustum near the image border by up to the circle of confusion, so the
//! reference is captured `guard` pixels wider on every side (same pixel size, same centre).
//!
//! **Batches** (speed only): with `N_sec = 1` and the quad-tree, a row's lens rays are traced
//! `LENS_BATCH` (8) at a time with [`QuadTreeTracer::trace_batch`] (clip, set-up and start of
//! every ray of the batch before the first walk: the per-ray set-up is a latency chain that
//! the batch's rays then overlap); the samples, their order, every result and every pixel's
//! sum are those of one ray at a time (test `tests/dof_batch.rs`). Secondary samples follow
//! their primary's result, so `N_sec > 1` traces one ray at a time; the other tracers (the
//! DDA baseline) too.
//!
//! **Invariants:** the image is bit-identical for any thread count (per-pixel random stream
//! `Rng::for_pixel(seed, x, y, 0)`, consumed in a fixed order; rows write only their own
//! pixels); with `aperture = 0` every lens ray is the pinhole ray of the pixel centre, so the
//! image is the warp of the reference to its own view.
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `n_pri` | u32 | 8 | lens rays traced per pixel, `1..=`[`MAX_PRIMARY`] |
//! | `n_sec` | u32 | 1 | colour samples per lens ray including the traced one, `1..=`[`MAX_SECONDARY`]; `> 1` needs the quad-tree |
//! | `sigma` | f32 | 0.02 | width of the secondary weight in relative depth, `> 0` |
//! | `seed` | u64 | 0 | seed of the per-pixel lens-sample streams |
//! | `warp` | [`WarpOptions`] | default | colour resampling, layer-0 guard, occlusion fill of the lens rays |
//! | `secondary_resample` | [`Resample`] | bilinear | colour of a secondary sample: depth-aware bilinear at its hit, or its pixel's ([`secondary`]) |

pub mod secondary;
pub mod setup;
pub mod truth;

use std::time::Instant;

use glam::{Mat3, Vec2, Vec3};
use parallax_core::cpu_time::{ms_between, thread_cpu_ns};
use parallax_core::sampling::Rng;
use parallax_core::sampling::warp::concentric_disk;
use parallax_core::{Image, Ray, Rgb};
use parallax_scene::camera::{CameraModel, ThinLens};
use parallax_screen::{QuadTreeTracer, ScreenTracer, TraceResult, TraceStats};
use rayon::prelude::*;
use serde::Serialize;

use crate::SynthError;
use crate::layers::Reference;
use crate::method::{Method, MethodOptions, build_tracer, gamma_dist_scale, quadtree_options};
use crate::warp::{HitKind, RayWarp, Resample, WarpOptions};
pub use secondary::SecondaryStats;
pub use setup::{DofSetup, capture_dof_reference};

/// Largest `n_pri` accepted (lens rays per pixel).
pub const MAX_PRIMARY: u32 = 4096;
/// Largest `n_sec` accepted (colour samples per lens ray).
pub const MAX_SECONDARY: u32 = 256;
/// Lens rays of a pixel handed to [`QuadTreeTracer::trace_batch`] at once.
const LENS_BATCH: usize = 8;
/// Default `sigma` of the secondary weight (relative depth, module docs).
pub const DEFAULT_SIGMA: f32 = 0.02;

/// Options of [`render_dof`] (module docs, parameter table).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DofOptions {
    pub n_pri: u32,
    pub n_sec: u32,
    pub sigma: f32,
    pub seed: u64,
    pub warp: WarpOptions,
    pub secondary_resample: Resample,
}

impl Default for DofOptions {
    fn default() -> Self {
        Self {
            n_pri: 8,
            n_sec: 1,
            sigma: DEFAULT_SIGMA,
            seed: 0,
            warp: WarpOptions::default(),
            secondary_resample: Resample::Bilinear,
        }
    }
}

impl DofOptions {
    /// Checks the ranges of the parameter table.
    pub fn validate(&self) -> Result<(), SynthError> {
        if !(1..=MAX_PRIMARY).contains(&self.n_pri) {
            return Err(SynthError::Invalid(format!(
                "N_pri (lens rays per pixel) must be in 1..={MAX_PRIMARY}, got {}",
                self.n_pri
            )));
        }
        if !(1..=MAX_SECONDARY).contains(&self.n_sec) {
            return Err(SynthError::Invalid(format!(
                "N_sec (colour samples per lens ray) must be in 1..={MAX_SECONDARY}, got {}",
                self.n_sec
            )));
        }
        if !(self.sigma.is_finite() && self.sigma > 0.0) {
            return Err(SynthError::Invalid(format!(
                "sigma of the secondary weight must be finite and > 0, got {}",
                self.sigma
            )));
        }
        Ok(())
    }
}

/// The `cols x rows` grid of lens strata for `n` rays: `rows` the largest divisor of `n`
/// not above `sqrt(n)` (8 -> 4 x 2, 4 -> 2 x 2, a prime -> `n x 1`).
pub fn lens_strata(n: u32) -> (u32, u32) {
    let n = n.max(1);
    let rows = (1..=n)
        .take_while(|r| r * r <= n)
        .filter(|r| n.is_multiple_of(*r))
        .last()
        .unwrap_or(1);
    (n / rows, rows)
}

/// The lens rays of a thin lens with the per-view and per-pixel constants hoisted and
/// without ray differentials: for lens sample `u`, the ray from the lens point
/// `A concentric_disk(u)` (camera space, `z = 0`) through the pixel's focus point (the
/// lens-centre ray's point at view depth `F`) — [`ThinLens::generate_ray`]'s ray, with the
/// concentric map of `parallax_core::sampling::warp`.
#[derive(Clone, Copy, Debug)]
pub struct LensRays {
    origin: Vec3,
    basis: Mat3,
    aperture: f32,
    focus: f32,
}

impl LensRays {
    pub fn new(lens: &ThinLens) -> Self {
        Self {
            origin: lens.pinhole.frame.position,
            basis: lens.pinhole.frame.basis,
            aperture: lens.aperture_radius,
            focus: lens.focus_distance,
        }
    }

    /// The camera-space focus point of film position `film` of `lens`.
    #[inline]
    pub fn focus_point(&self, lens: &ThinLens, film: Vec2) -> Vec3 {
        lens.pinhole.camera_dir(film) * self.focus
    }

    /// The world ray of lens sample `u` through camera-space focus point `p_focus`.
    #[inline(always)]
    pub fn ray(&self, p_focus: Vec3, u: Vec2) -> Ray {
        let d = concentric_disk(u) * self.aperture;
        let p_lens = Vec3::new(d.x, d.y, 0.0);
        let dir = p_focus - p_lens;
        Ray::new(
            self.origin + self.basis * p_lens,
            self.basis * (dir / dir.length()),
        )
    }
}

/// The structure a depth-of-field image is traced through: the quad-tree (whose plane
/// leaves the secondary samples need) or any other screen-space tracer.
#[allow(clippy::large_enum_variant)] // one per reference image, never stored in bulk: no boxing
pub enum DofStructure {
    QuadTree(QuadTreeTracer),
    Other(Method, Box<dyn ScreenTracer>),
}

impl DofStructure {
    /// Builds `method` over `reference`'s layers (its cube as fitted: call
    /// [`Reference::fit_cube`] first for another near plane). The quad-tree is built as
    /// [`build_tracer`] builds it.
    pub fn build(
        method: Method,
        reference: &Reference,
        opts: &MethodOptions,
    ) -> Result<Self, SynthError> {
        if reference.cube_near != opts.cube_near {
            return Err(SynthError::Invalid(
                "the reference's cube near plane differs from the options': call Reference::fit_cube".into(),
            ));
        }
        match method {
            Method::QuadTree => {
                if reference.layers.is_empty() {
                    return Err(SynthError::Invalid("no layers to trace".into()));
                }
                let mut q = quadtree_options(opts);
                q.gamma_dist *= gamma_dist_scale(&reference.cube, &reference.layers)?;
                Ok(Self::QuadTree(QuadTreeTracer::build(
                    &reference.cube,
                    &reference.layers,
                    &q,
                )?))
            }
            m => Ok(Self::Other(
                m,
                build_tracer(m, &reference.cube, &reference.layers, opts)?,
            )),
        }
    }

    /// The tracer.
    pub fn tracer(&self) -> &dyn ScreenTracer {
        match self {
            Self::QuadTree(q) => q,
            Self::Other(_, t) => t.as_ref(),
        }
    }

    /// The method's name.
    pub fn method(&self) -> Method {
        match self {
            Self::QuadTree(_) => Method::QuadTree,
            Self::Other(m, _) => *m,
        }
    }
}

/// A depth-of-field image.
#[derive(Clone, Debug)]
pub struct DofImage {
    pub image: Image<Rgb>,
    /// Work of the lens rays (and of the layer-0 guard's re-traces).
    pub stats: TraceStats,
    /// Lens rays traced (`N_pri` per pixel).
    pub lens_rays: u64,
    /// Lens rays answered from layer 1 or deeper, misses and occlusion volumes.
    pub deep: u64,
    pub misses: u64,
    pub occlusions: u64,
    pub secondary: SecondaryStats,
    /// Wall-clock milliseconds of tracing and colouring (`T_dof`).
    pub ms: f64,
    /// CPU milliseconds of the threads that rendered the rows (robust on a loaded machine;
    /// NaN without a thread clock).
    pub cpu_ms: f64,
}

impl DofImage {
    /// Lens rays per second of `T_dof`, in millions.
    pub fn mrays_per_s(&self) -> f64 {
        if self.ms > 0.0 {
            self.lens_rays as f64 / (self.ms * 1e3)
        } else {
            0.0
        }
    }

    /// Lens rays per CPU-second of the rendering threads, in millions (one core's rate).
    pub fn mrays_per_cpu_s(&self) -> f64 {
        self.lens_rays as f64 / (self.cpu_ms * 1e3)
    }

    /// % of lens rays answered from layer 1 or deeper.
    pub fn pct_deep(&self) -> f64 {
        100.0 * self.deep as f64 / self.lens_rays.max(1) as f64
    }
}

/// Per-row counters of [`render_dof`].
#[derive(Clone, Copy, Default)]
struct RowCounts {
    stats: TraceStats,
    deep: u64,
    misses: u64,
    occlusions: u64,
    secondary: SecondaryStats,
    cpu_ms: f64,
}

impl RowCounts {
    /// Counts a lens ray's answer.
    #[inline(always)]
    fn tally(&mut self, kind: HitKind) {
        match kind {
            HitKind::Hit(l) if l >= 1 => self.deep += 1,
            HitKind::Occlusion(l) if l >= 1 => self.deep += 1,
            _ => {}
        }
        match kind {
            HitKind::Miss => self.misses += 1,
            HitKind::Occlusion(_) => self.occlusions += 1,
            HitKind::Hit(_) => {}
        }
    }

    fn add(mut self, o: Self) -> Self {
        self.stats += o.stats;
        self.deep += o.deep;
        self.misses += o.misses;
        self.occlusions += o.occlusions;
        self.secondary += o.secondary;
        self.cpu_ms += o.cpu_ms;
        self
    }
}

/// One row `y` of [`render_dof`] with `N_sec = 1` through the quad-tree: the row's lens rays,
/// made pixel by pixel in the order of the one-ray-at-a-time loop (the same samples), traced
/// in batches of [`LENS_BATCH`] that may span pixels ([`QuadTreeTracer::trace_batch`]: the
/// same results); each ray's colour is added to its pixel in the ray's order, so every
/// pixel's sum is the same. `row` holds zeros on entry.
#[allow(clippy::too_many_arguments)]
fn batched_row(
    qt: &QuadTreeTracer,
    per_ray: &RayWarp,
    lens_rays: &LensRays,
    lens: &ThinLens,
    opts: &DofOptions,
    y: u32,
    row: &mut [Rgb],
    c: &mut RowCounts,
) {
    let (cols, rows) = lens_strata(opts.n_pri);
    let cell = Vec2::new(1.0 / cols as f32, 1.0 / rows as f32);
    let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); LENS_BATCH];
    let mut px = [0usize; LENS_BATCH];
    let mut found = [TraceResult::Miss; LENS_BATCH];
    let mut flush = |rays: &[Ray], px: &[usize], row: &mut [Rgb], c: &mut RowCounts| {
        let found = &mut found[..rays.len()];
        qt.trace_batch(rays, found, &mut c.stats);
        for ((ray, &r), &x) in rays.iter().zip(found.iter()).zip(px) {
            let r = per_ray.guarded(ray, r, &mut c.stats);
            let (colour, kind) = per_ray.colour(ray, r);
            c.tally(kind);
            row[x] += colour;
        }
    };
    let mut n = 0;
    for x in 0..row.len() {
        let film = Vec2::new(x as u32 as f32 + 0.5, y as f32 + 0.5);
        let p_focus = lens_rays.focus_point(lens, film);
        let mut rng = Rng::for_pixel(opts.seed, x as u32, y, 0);
        for i in 0..opts.n_pri {
            let corner = Vec2::new((i % cols) as f32, (i / cols) as f32);
            rays[n] = lens_rays.ray(p_focus, (corner + rng.next_vec2()) * cell);
            px[n] = x;
            n += 1;
            if n == LENS_BATCH {
                flush(&rays, &px, row, c);
                n = 0;
            }
        }
    }
    flush(&rays[..n], &px[..n], row, c);
    for out in row.iter_mut() {
        *out /= opts.n_pri as f32;
    }
}

/// Renders `lens`'s view with depth of field through `structure` (built over `reference`,
/// the pinhole at the lens centre, possibly with a guard band) — module docs.
pub fn render_dof(
    structure: &DofStructure,
    reference: &Reference,
    lens: &ThinLens,
    opts: &DofOptions,
) -> Result<DofImage, SynthError> {
    opts.validate()?;
    let secondaries = match structure {
        DofStructure::QuadTree(q) => Some(secondary::LeafPlanes::new(
            q,
            reference,
            opts.sigma,
            opts.secondary_resample,
        )),
        DofStructure::Other(m, _) if opts.n_sec > 1 => {
            return Err(SynthError::Invalid(format!(
                "secondary samples (N_sec = {}) intersect the hit leaf's plane: they need the quad-tree, not {m}",
                opts.n_sec
            )));
        }
        DofStructure::Other(..) => None,
    };
    let tracer = structure.tracer();
    // Plain lens sampling through the quad-tree traces a pixel's lens rays in batches (the
    // secondaries' samples follow their primary's result, so `N_sec > 1` keeps the order
    // of one ray at a time).
    let batched = match structure {
        DofStructure::QuadTree(q) if opts.n_sec == 1 => Some(q),
        _ => None,
    };
    let per_ray = RayWarp::new(reference, &opts.warp);
    let lens_rays = LensRays::new(lens);
    let (w, h) = (lens.width(), lens.height());
    let (cols, rows) = lens_strata(opts.n_pri);
    let cell = Vec2::new(1.0 / cols as f32, 1.0 / rows as f32);
    let mut image = vec![Rgb::ZERO; w as usize * h as usize];
    let start = Instant::now();
    let counts = image
        .par_chunks_mut(w as usize)
        .enumerate()
        .map(|(y, row)| {
            let c0 = thread_cpu_ns();
            let mut c = RowCounts::default();
            if let Some(qt) = batched {
                batched_row(qt, &per_ray, &lens_rays, lens, opts, y as u32, row, &mut c);
                c.cpu_ms = ms_between(c0, thread_cpu_ns());
                return c;
            }
            for (x, out) in row.iter_mut().enumerate() {
                let (x, y) = (x as u32, y as u32);
                let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let p_focus = lens_rays.focus_point(lens, film);
                let mut rng = Rng::for_pixel(opts.seed, x, y, 0);
                let mut sum = Vec3::ZERO;
                for i in 0..opts.n_pri {
                    let corner = Vec2::new((i % cols) as f32, (i / cols) as f32);
                    let mut lens_sample = || (corner + rng.next_vec2()) * cell;
                    let ray = lens_rays.ray(p_focus, lens_sample());
                    let (colour, kind, r) = per_ray.answer(tracer, &ray, &mut c.stats);
                    c.tally(kind);
                    let mut ray_colour = colour;
                    if let (Some(sec), TraceResult::Hit { layer, pixel, .. }) = (&secondaries, r)
                        && opts.n_sec > 1
                    {
                        ray_colour = sec.blend(
                            &per_ray,
                            layer,
                            pixel,
                            colour,
                            (1..opts.n_sec).map(|_| lens_rays.ray(p_focus, lens_sample())),
                            &mut c.secondary,
                        );
                    }
                    sum += ray_colour;
                }
                *out = sum / opts.n_pri as f32;
            }
            c.cpu_ms = ms_between(c0, thread_cpu_ns());
            c
        })
        .reduce(RowCounts::default, RowCounts::add);
    let ms = start.elapsed().as_secs_f64() * 1e3;
    Ok(DofImage {
        image: Image::from_vec(w, h, image)?,
        stats: counts.stats,
        lens_rays: w as u64 * h as u64 * opts.n_pri as u64,
        deep: counts.deep,
        misses: counts.misses,
        occlusions: counts.occlusions,
        secondary: counts.secondary,
        ms,
        cpu_ms: counts.cpu_ms,
    })
}
