//! [`DdaTracer`]: perspective-correct screen-space DDA ray marching, McGuire & Mara 2014,
//! "Efficient GPU Screen-Space Ray Tracing" (JCGT 3(4)) — the "DDA" baseline of Widmer et al.
//! 2015 (Tables 2-4), single- and two-layer.
//!
//! Our own Rust of the paper's listing, in the reference view's unit cube ([`UnitCube`]):
//!
//! 1. **Clip** the world ray to the view frustum (the paper clips to the near plane only and
//!    marches until it leaves the screen; clipping all six faces up front is the same march
//!    with fewer wasted steps) and to `max_distance`.
//! 2. **Project** both ends: screen points `P0, P1` (pixels) and `k = 1 / w` (`w` = view depth)
//!    are affine along the screen-space line, so they are interpolated linearly; the ray's view
//!    depth at any step is `1 / k` (the paper's `Q.z / k`).
//! 3. **March** along the major screen axis, `stride` pixels per step, starting `jitter`
//!    strides in. A step samples the pixel under `P` and tests the ray's depth interval over
//!    the step (half a stride either side, the paper's `rayZMin, rayZMax`) against the layer's
//!    **thickness interval** `[depth, depth + z_thickness]`; a hit when they overlap.
//! 4. **Two layers** (Mara et al. 2013/2014, deep G-buffers): the same step tests both layers'
//!    intervals (layer 0 first) — a ray passing behind a foreground surface can hit the
//!    second-nearest surface stored behind it.
//!
//! Result mapping: the hit's depth is the layer depth clamped to the step's ray-depth interval;
//! `t` and the position are the ray's at that depth. A ray that ends (left the frustum, or ran
//! out of `max_steps`) without a hit but went more than `z_thickness` behind the deepest
//! *covered* layer of the pixel (layer 0 where layer 1 is empty) reports
//! [`TraceResult::OcclusionVolume`] at the first such step (the marcher has no information
//! there); otherwise [`TraceResult::Miss`].
//!
//! **Parameters** ([`DdaOptions`]):
//!
//! | name | type | default | meaning |
//! |---|---|---|---|
//! | `stride` | f32 | 1 | pixels per step along the major axis (>= 1) |
//! | `jitter` | f32 | 0 | fraction of a stride by which the first sample is offset |
//! | `z_thickness` | f32 | 0.1 m | thickness ascribed to each depth sample: catches the surface within a pixel and the neighbours the 1-pixel line skips, still lets rays pass behind thin objects |
//! | `max_steps` | u32 | 260 | step bound: minimal artifact-free value for stereo warping at 1600x900 from a 0.1 m camera near plane, tuned as Widmer et al. 2015 (§5.1) tuned theirs (200 stereo / 500 upsampling at their resolution); longer reprojections need more (`parallax bench warp \| upsample --dda-sweep`) |
//! | `max_distance` | f32 | inf | world distance bound along the ray |
//! | `layers` | usize | 2 | layers marched together: 1 or 2 |
//!
//! How both defaults were measured (and what the fitted cube and upsampling need):
//! `docs/notes/screen.md`. The warp's layer-0 guard (`parallax_synth::warp`) does not use it: its DDA marches every
//! segment to its end (`max(W, H) + 2` steps).

use std::time::Instant;

use glam::UVec2;
use parallax_core::{GBuffer, Ray};

use crate::depth_layers::{Clip, LayerHit, PixelRay, check_layers, finish};
use crate::{ScreenError, ScreenTracer, TraceResult, TraceStats, UnitCube};

/// Default [`DdaOptions::max_steps`] (module docs: the minimal artifact-free value for
/// stereo warping at 1600x900 in Widmer et al.'s camera-near-plane setting).
pub const DEFAULT_MAX_STEPS: u32 = 260;

/// Options of [`DdaTracer`] (the paper's parameters).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DdaOptions {
    /// Pixels per step along the major axis (>= 1).
    pub stride: f32,
    /// Fraction of a stride to offset the first sample (0..1).
    pub jitter: f32,
    /// Thickness ascribed to each depth sample, view-depth units (metres).
    pub z_thickness: f32,
    /// Maximum steps per ray (default 260: minimal artifact-free for stereo warping at
    /// 1600x900 from a 0.1 m camera near plane, module docs; Widmer et al. tuned 200 for
    /// stereo warping, 500 for temporal upsampling, 25 for depth of field).
    pub max_steps: u32,
    /// Maximum world distance along the ray.
    pub max_distance: f32,
    /// Layers marched simultaneously: 1 or 2.
    pub layers: usize,
}

impl Default for DdaOptions {
    fn default() -> Self {
        Self {
            stride: 1.0,
            jitter: 0.0,
            z_thickness: 0.1,
            max_steps: DEFAULT_MAX_STEPS,
            max_distance: f32::INFINITY,
            layers: 2,
        }
    }
}

/// Perspective-correct DDA over one or two depth layers.
#[derive(Clone, Debug)]
pub struct DdaTracer {
    pub cube: UnitCube,
    pub opts: DdaOptions,
    clip: Clip,
    /// Number of layers used (1 or 2).
    nl: usize,
    /// View depths, interleaved per pixel (`nl` values), `+inf` where empty.
    depth: Vec<f32>,
    build_ms: f64,
}

impl DdaTracer {
    /// Uses the first `opts.layers` (1 or 2) of `layers` (captured from `cube.camera`).
    pub fn new(
        cube: &UnitCube,
        layers: &[GBuffer],
        opts: &DdaOptions,
    ) -> Result<Self, ScreenError> {
        if !(1..=2).contains(&opts.layers) {
            return Err(ScreenError::Mismatch(format!(
                "the DDA marches 1 or 2 layers, asked for {}",
                opts.layers
            )));
        }
        let stride_ok = opts.stride >= 1.0 && opts.stride.is_finite();
        let jitter_ok = (0.0..=1.0).contains(&opts.jitter);
        let thick_ok = opts.z_thickness >= 0.0; // false for NaN
        if !(stride_ok && jitter_ok && thick_ok) {
            return Err(ScreenError::InvalidSpace(format!(
                "need stride >= 1, jitter in [0, 1], z_thickness >= 0: {opts:?}"
            )));
        }
        let nl = check_layers(cube, layers, opts.layers)?;
        let t = Instant::now();
        let n = layers[0].depth.len();
        let mut depth = vec![f32::INFINITY; n * nl];
        for (l, g) in layers[..nl].iter().enumerate() {
            for (k, &d) in g.depth.iter().enumerate() {
                if d.is_finite() && d > 0.0 {
                    depth[k * nl + l] = d;
                }
            }
        }
        Ok(Self {
            cube: cube.clone(),
            opts: *opts,
            clip: Clip::new(cube),
            nl,
            depth,
            build_ms: t.elapsed().as_secs_f64() * 1e3,
        })
    }

    /// Bytes of the depth layers the DDA reads.
    pub fn bytes(&self) -> usize {
        self.depth.len() * size_of::<f32>()
    }

    /// Time to gather the depth layers, milliseconds (the DDA has no structure to build).
    pub fn build_ms(&self) -> Vec<f64> {
        vec![self.build_ms]
    }

    #[inline(always)]
    fn march<const L: usize>(
        &self,
        ray: &Ray,
        pr: &PixelRay,
        stats: &mut TraceStats,
    ) -> TraceResult {
        let (w, h) = (self.cube.camera.width, self.cube.camera.height);
        let (k0, k1) = (1.0 / pr.seg.w0 as f32, 1.0 / pr.seg.w1 as f32);
        let dk = k1 - k0;
        let (px, py) = (pr.o.x, pr.o.y);
        let (mut dx, mut dy) = (pr.d.x, pr.d.y);
        if dx * dx + dy * dy < 1e-4 {
            // Degenerate screen line: cover at least one pixel (as the paper does).
            dx += 0.01;
            dy += 0.01;
        }
        let major = dx.abs().max(dy.abs());
        let ds = self.opts.stride / major;
        let half = 0.5 * ds;
        let thick = self.opts.z_thickness;
        let mut s = self.opts.jitter * ds;
        let mut z_prev = pr.seg.w0 as f32;
        let mut occ: Option<LayerHit> = None;
        let mut steps = 0u32;
        // The paper stops at the last sample with `s <= 1`, leaving the final half stride
        // untested; on the short screen lines of small reprojections (a few pixels) that
        // loses hits, so the march runs until the step's interval reaches the end.
        while s - half < 1.0 && steps < self.opts.max_steps {
            steps += 1;
            let s_hi = (s + half).min(1.0);
            let z_next = 1.0 / (k0 + dk * s_hi);
            let (zmin, zmax) = if z_prev <= z_next {
                (z_prev, z_next)
            } else {
                (z_next, z_prev)
            };
            let sp = s.min(1.0);
            let ix = ((px + dx * sp) as u32).min(w - 1);
            let iy = ((py + dy * sp) as u32).min(h - 1);
            let k = (iy * w + ix) as usize * L;
            let d = &self.depth[k..k + L];
            for (l, &dl) in d.iter().enumerate() {
                if zmax >= dl && zmin <= dl + thick {
                    stats.steps += steps as u64;
                    let dh = dl.clamp(zmin, zmax);
                    let s_lo = (s - half).max(0.0);
                    let sh = if dk != 0.0 {
                        ((1.0 / dh - k0) / dk).clamp(s_lo, s_hi)
                    } else {
                        s
                    };
                    return finish(
                        ray,
                        pr,
                        Some((sh, l as u32, UVec2::new(ix, iy))),
                        None,
                        stats,
                    );
                }
            }
            // The deepest *covered* layer of the pixel: where layer 1 is empty (nothing
            // captured behind layer 0) a ray behind layer 0 is in layer 0's occlusion volume.
            // Testing the empty layer 1 (`+inf`) instead never flagged it, so such rays ended
            // as misses (environment colour): on the atrium stereo pair (1600x900) that turned
            // 0.2% of the pixels into misses carrying half of the squared error (2 layers
            // 26.7 dB against 28.9 dB with 1 layer).
            let deepest = if L > 1 && !d[L - 1].is_finite() {
                0
            } else {
                L - 1
            };
            if occ.is_none() && zmin > d[deepest] + thick {
                occ = Some(((s - half).max(0.0), deepest as u32, UVec2::new(ix, iy)));
            }
            z_prev = z_next;
            s += ds;
        }
        stats.steps += steps as u64;
        stats.truncated += (s - half < 1.0) as u64;
        finish(ray, pr, None, occ, stats)
    }
}

impl ScreenTracer for DdaTracer {
    fn trace(&self, ray: &Ray, stats: &mut TraceStats) -> TraceResult {
        stats.rays += 1;
        let Some(pr) = PixelRay::new(&self.clip, ray, self.opts.max_distance) else {
            return TraceResult::Miss;
        };
        if self.nl == 1 {
            self.march::<1>(ray, &pr, stats)
        } else {
            self.march::<2>(ray, &pr, stats)
        }
    }
}
