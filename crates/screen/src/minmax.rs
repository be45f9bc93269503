//! [`MinMaxTracer`]: height-field ray tracing with maximum (min-max) mipmaps, Tevs, Ihrke &
//! Seidel 2008, "Maximum mipmaps for fast, accurate, and scalable dynamic height field
//! rendering" — the "height-field tracing" baseline of Widmer et al. 2015 (Tables 2-3).
//!
//! Per layer, in the unit cube of the reference view ([`UnitCube`], `x, y` = film / size, `z`
//! affine in `1 / depth`):
//!
//! - **Height patches** (Tevs §3): every covered pixel holds a bilinear patch over its
//!   footprint, its four corner heights the mean cube `z` of the pixels sharing that corner
//!   that continue the pixel's surface (view depth within `continuity` relative of its own —
//!   so patches never stretch a "rubber sheet" over a depth discontinuity, where Tevs' terrain
//!   has none). With `bilinear = false` the patch is flat at the pixel's own `z` (the setting
//!   Widmer used for speed: "we have disabled bilinear patch interpolation").
//! - **Min-max mipmap** (Tevs §4): level 0 holds per pixel the patch's min `z` and the max `z`
//!   of the back of its `z_thickness` shell; level `l` reduces `2 x 2` cells. Empty pixels
//!   (no surface) have no height: both bounds `+inf` (never descended, and a cell containing
//!   one never counts as "entirely in front of the ray").
//! - **Traversal** (`depth_layers::traverse`): the iterative version (Tevs §4.2, the one Widmer timed):
//!   descend when the ray's `z` range over the cell overlaps `[min, max]`, else step to the
//!   cell exit and go up a level; rays moving away first jump to the cell's min plane.
//! - **Refinement** (Tevs §4.3): at a pixel where `f(s) = z_ray(s) - patch(x(s), y(s))`
//!   changes sign across the footprint, `refine_steps` bisection steps and a final secant
//!   step give the hit. A ray entering the footprint from the side at most `z_thickness`
//!   behind the patch hits its wall; farther behind it is in the occlusion volume
//!   (thin-shell semantics, `depth_layers.rs`).
//! - **Layers** (Widmer §4.1): each layer is its own height field; the next layer is traced
//!   only for rays that went behind the previous one (cascade), from that point on.
//!
//! Simplifications: a ray dipping into and out of a bilinear patch inside one footprint
//! without a sign change at the footprint's ends is not seen (as in Tevs' iterative version).

use std::time::Instant;

use parallax_core::{GBuffer, Ray};
use rayon::prelude::*;

use crate::depth_layers::{
    Clip, DepthMap, Leaf, PixelRay, Pyramid, cascade, check_layers, covered, finish, traverse,
};
use crate::{ScreenError, ScreenTracer, TraceResult, TraceStats, UnitCube};

/// Options of [`MinMaxTracer`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MinMaxOptions {
    /// Bisection steps of the intersection refinement (Tevs §4.3). 8 steps locate the hit to
    /// 1/256 of a footprint crossing; the final secant step makes it exact on planar patches.
    pub refine_steps: u32,
    /// Hard bound on traversal iterations per layer (a safety bound: the hierarchy rarely
    /// needs more than a few dozen).
    pub max_steps: u32,
    /// Bilinear patches (Tevs) or flat per-pixel heights (Widmer's speed setting).
    pub bilinear: bool,
    /// Neighbours whose view depth differs by at most this fraction are the same surface
    /// (shared patch corners).
    pub continuity: f32,
    /// Shell thickness in view-depth units (metres) for side-wall hits.
    pub z_thickness: f32,
    /// Use at most this many layers (cascade).
    pub layers: usize,
    /// Maximum world distance along the ray.
    pub max_distance: f32,
}

impl Default for MinMaxOptions {
    fn default() -> Self {
        Self {
            refine_steps: 8,
            max_steps: 2000,
            bilinear: true,
            continuity: 0.05,
            z_thickness: 0.1,
            layers: 2,
            max_distance: f32::INFINITY,
        }
    }
}

/// One layer: patch corners (cube `z`, order `(0,0), (1,0), (0,1), (1,1)`) and the mipmap.
#[derive(Clone, Debug)]
struct MinMaxLayer {
    corners: Vec<[f32; 4]>,
    pyramid: Pyramid<2>,
}

/// Min-max mipmap height-field tracer over the captured layers.
#[derive(Clone, Debug)]
pub struct MinMaxTracer {
    pub cube: UnitCube,
    pub opts: MinMaxOptions,
    clip: Clip,
    map: DepthMap,
    layers: Vec<MinMaxLayer>,
    build_ms: Vec<f64>,
}

impl MinMaxTracer {
    /// Builds the patches and mipmaps of the first `opts.layers` of `layers` (captured from
    /// `cube.camera`).
    pub fn new(
        cube: &UnitCube,
        layers: &[GBuffer],
        opts: &MinMaxOptions,
    ) -> Result<Self, ScreenError> {
        let n = check_layers(cube, layers, opts.layers)?;
        if !(opts.z_thickness >= 0.0 && opts.continuity >= 0.0) {
            return Err(ScreenError::InvalidSpace(
                "z_thickness and continuity must be >= 0".into(),
            ));
        }
        let map = DepthMap::new(cube);
        let mut out = Vec::with_capacity(n);
        let mut build_ms = Vec::with_capacity(n);
        for g in &layers[..n] {
            let t = Instant::now();
            out.push(build_layer(cube, &map, g, opts));
            build_ms.push(t.elapsed().as_secs_f64() * 1e3);
        }
        Ok(Self {
            cube: cube.clone(),
            opts: *opts,
            clip: Clip::new(cube),
            map,
            layers: out,
            build_ms,
        })
    }

    /// Build time of each layer (patches + mipmap), milliseconds.
    pub fn build_ms(&self) -> Vec<f64> {
        self.build_ms.clone()
    }

    /// Bytes of the patches and mipmaps.
    pub fn bytes(&self) -> usize {
        self.layers
            .iter()
            .map(|l| l.corners.len() * size_of::<[f32; 4]>() + l.pyramid.bytes())
            .sum()
    }
}

fn build_layer(cube: &UnitCube, map: &DepthMap, g: &GBuffer, opts: &MinMaxOptions) -> MinMaxLayer {
    let (w, h) = (cube.camera.width as i64, cube.camera.height as i64);
    let depth = &g.depth;
    // Cube z once per pixel (one division each); +inf where empty.
    let zs: Vec<f32> = depth
        .iter()
        .map(|&d| if covered(d) { map.z(d) } else { f32::INFINITY })
        .collect();
    let mut corners = vec![[f32::INFINITY; 4]; depth.len()];
    let mut base = vec![[f32::INFINITY; 2]; depth.len()];
    corners
        .par_chunks_mut(w as usize)
        .zip(base.par_chunks_mut(w as usize))
        .enumerate()
        .for_each(|(j, (crow, brow))| {
            let j = j as i64;
            for i in 0..w {
                let k = (j * w + i) as usize;
                let dp = depth[k];
                if !covered(dp) {
                    continue;
                }
                let zp = zs[k];
                let mut c = [zp; 4];
                if opts.bilinear {
                    let tol = opts.continuity * dp;
                    for (ci, (a, b)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
                        let (mut sum, mut cnt) = (0.0f32, 0u32);
                        for y in (j + b - 1).max(0)..=(j + b).min(h - 1) {
                            for x in (i + a - 1).max(0)..=(i + a).min(w - 1) {
                                let q = (y * w + x) as usize;
                                // Empty neighbours have an infinite depth and fail the test.
                                if zs[q].is_finite() && (depth[q] - dp).abs() <= tol {
                                    sum += zs[q];
                                    cnt += 1;
                                }
                            }
                        }
                        c[ci] = sum / cnt as f32;
                    }
                }
                let lo = c.iter().copied().fold(f32::INFINITY, f32::min);
                let hi = c.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                crow[i as usize] = c;
                brow[i as usize] = [lo, map.z_behind(hi, opts.z_thickness)];
            }
        });
    let pyramid = Pyramid::build(cube.camera.width, cube.camera.height, base, |a, c| {
        a[0] = a[0].min(c[0]);
        a[1] = a[1].max(c[1]);
    });
    MinMaxLayer { corners, pyramid }
}

#[inline]
fn bilerp(c: &[f32; 4], u: f32, v: f32) -> f32 {
    let top = c[0] + (c[1] - c[0]) * u;
    let bot = c[2] + (c[3] - c[2]) * u;
    top + (bot - top) * v
}

impl MinMaxTracer {
    #[inline]
    fn leaf(&self, layer: &MinMaxLayer, pr: &PixelRay, ix: u32, iy: u32, sa: f32, sb: f32) -> Leaf {
        let c = &layer.corners[(iy * self.cube.camera.width + ix) as usize];
        let (fx, fy) = (ix as f32, iy as f32);
        let f = |s: f32| {
            let q = pr.at(s);
            q.z - bilerp(c, (q.x - fx).clamp(0.0, 1.0), (q.y - fy).clamp(0.0, 1.0))
        };
        let (fa, fb) = (f(sa), f(sb));
        if (fa <= 0.0) != (fb <= 0.0) || fa == 0.0 || fb == 0.0 {
            if fa == 0.0 {
                return Leaf::Hit(sa);
            }
            let (mut lo, mut hi, mut flo, mut fhi) = (sa, sb, fa, fb);
            for _ in 0..self.opts.refine_steps {
                let mid = 0.5 * (lo + hi);
                let fm = f(mid);
                if (fm <= 0.0) == (flo <= 0.0) {
                    (lo, flo) = (mid, fm);
                } else {
                    (hi, fhi) = (mid, fm);
                }
            }
            let den = flo - fhi;
            let s = if den != 0.0 {
                (lo + (hi - lo) * flo / den).clamp(lo, hi)
            } else {
                lo
            };
            Leaf::Hit(s)
        } else if fa > 0.0 {
            let za = pr.o.z + pr.d.z * sa;
            if za <= self.map.z_behind(za - fa, self.opts.z_thickness) {
                Leaf::Hit(sa)
            } else {
                Leaf::Occluded(sa)
            }
        } else {
            Leaf::Nothing
        }
    }
}

impl ScreenTracer for MinMaxTracer {
    fn trace(&self, ray: &Ray, stats: &mut TraceStats) -> TraceResult {
        stats.rays += 1;
        let Some(pr) = PixelRay::new(&self.clip, ray, self.opts.max_distance) else {
            return TraceResult::Miss;
        };
        let (best, occ) = cascade(self.layers.len(), |li, s0, s1| {
            let layer = &self.layers[li];
            traverse(
                &layer.pyramid,
                &pr,
                s0,
                s1,
                self.opts.max_steps,
                stats,
                |ix, iy, sa, sb| self.leaf(layer, &pr, ix, iy, sa, sb),
            )
        });
        finish(ray, &pr, best, occ, stats)
    }
}
