//! [`BruteForcePlanes`]: the slow twin of every fast screen-space structure. Each layer's
//! per-pixel planes ([`crate::planes`]) are tested against the ray's unit-cube segment, each
//! only inside its pixel's footprint column (Widmer et al. 2015, §3.2; the quad-tree of §3.3-4
//! must return exactly these hits when lossless).
//!
//! Per pixel whose footprint the segment's xy bounding box touches: the segment is clipped to
//! the footprint square (`s` in `[sa, sb]`), and the plane value `f(s) = n · P(s) - c` is
//! evaluated at both ends.
//!
//! - `f(sa)` and `f(sb)` of different sign (or zero): the ray crosses the plane inside the
//!   footprint — a **hit** at `f(s) = 0` (from either side: surfaces are two-sided, as in the
//!   BVH). A ray cannot go from in front of a plane to behind it within the footprint without
//!   this hit.
//! - both negative: the ray runs behind the plane inside the footprint — it is inside the
//!   layer's **occlusion volume** (§4.1) from `sa` on.
//!
//! The result is the closest hit over all layers (world `t`) and, separately, the first
//! occlusion-volume entry; [`ScreenTracer::trace`] returns the hit if any, else the occlusion
//! crossing, else `Miss`. Cost: one plane test per pixel in the segment's bounding box per
//! layer — fine for tests on small captures, never for benchmarks.

use glam::{UVec2, Vec3};
use parallax_core::Ray;
use parallax_raster::LayerCapture;
use parallax_scene::camera::Pinhole;

use crate::{
    LayerPlanes, NormalSource, ScreenError, ScreenTracer, TraceResult, TraceStats, UnitCube,
};

/// Every pixel plane of every layer, tested one by one.
#[derive(Clone, Debug)]
pub struct BruteForcePlanes {
    pub cube: UnitCube,
    pub layers: Vec<LayerPlanes>,
}

/// A layer, a pixel and a world ray parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayerPixelT {
    pub layer: u32,
    pub pixel: UVec2,
    pub t: f32,
}

/// The full answer of the brute-force tracer.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BruteResult {
    /// Closest plane hit over all layers.
    pub hit: Option<LayerPixelT>,
    /// First occlusion-volume entry over all layers (may lie before or after `hit`).
    pub occlusion: Option<LayerPixelT>,
}

impl BruteForcePlanes {
    /// From a capture of the pinhole `camera` (the capture's view must be that camera's), with
    /// the unit cube fitted around the captured depths ([`UnitCube::fit_depths`]).
    pub fn from_capture(
        capture: &LayerCapture,
        camera: &Pinhole,
        source: NormalSource,
    ) -> Result<Self, ScreenError> {
        if (capture.view.width, capture.view.height) != (camera.width, camera.height) {
            return Err(ScreenError::Mismatch(
                "capture and camera sizes differ".into(),
            ));
        }
        let cube =
            UnitCube::fit_depths(camera, capture.layers.layers.iter().map(|g| &g.depth[..]))?;
        Self::new(cube, capture, source)
    }

    /// From a capture and an explicit cube.
    pub fn new(
        cube: UnitCube,
        capture: &LayerCapture,
        source: NormalSource,
    ) -> Result<Self, ScreenError> {
        let layers = capture
            .layers
            .layers
            .iter()
            .map(|g| LayerPlanes::build(&cube, g, source))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self { cube, layers })
    }

    /// Closest hit and first occlusion-volume entry of `ray`.
    pub fn trace_detailed(&self, ray: &Ray, stats: &mut TraceStats) -> BruteResult {
        let mut out = BruteResult::default();
        let Some(seg) = self.cube.clip_ray(ray) else {
            return out;
        };
        let (w, h) = (self.cube.camera.width, self.cube.camera.height);
        let (wf, hf) = (w as f32, h as f32);
        let d = seg.p1 - seg.p0;
        let lo = seg.p0.min(seg.p1);
        let hi = seg.p0.max(seg.p1);
        let ix = |v: f32, n: u32, nf: f32| ((v * nf).floor().max(0.0) as u32).min(n - 1);
        let (x0, x1) = (ix(lo.x, w, wf), ix(hi.x, w, wf));
        let (y0, y1) = (ix(lo.y, h, hf), ix(hi.y, h, hf));
        let (mut best_s, mut occ_s) = (f32::INFINITY, f32::INFINITY);
        for (li, planes) in self.layers.iter().enumerate() {
            for j in y0..=y1 {
                for i in x0..=x1 {
                    stats.steps += 1;
                    let k = (j * w + i) as usize;
                    if !planes.covered(k) {
                        continue;
                    }
                    let Some((sa, sb)) = clip_to_square(
                        seg.p0,
                        d,
                        [i as f32 / wf, (i + 1) as f32 / wf],
                        [j as f32 / hf, (j + 1) as f32 / hf],
                    ) else {
                        continue;
                    };
                    stats.plane_tests += 1;
                    let n = planes.normal[k];
                    let f0 = planes.side(k, seg.p0);
                    let fd = n.dot(d);
                    let (fa, fb) = (f0 + fd * sa, f0 + fd * sb);
                    let pixel = UVec2::new(i, j);
                    if (fa <= 0.0) != (fb <= 0.0) || fa == 0.0 || fb == 0.0 {
                        let s = if fd != 0.0 {
                            (-f0 / fd).clamp(sa, sb)
                        } else {
                            sa
                        };
                        if s < best_s {
                            best_s = s;
                            out.hit = Some(LayerPixelT {
                                layer: li as u32,
                                pixel,
                                t: 0.0,
                            });
                        }
                    } else if fa < 0.0 && sa < occ_s {
                        occ_s = sa;
                        out.occlusion = Some(LayerPixelT {
                            layer: li as u32,
                            pixel,
                            t: 0.0,
                        });
                    }
                }
            }
        }
        if let Some(hit) = out.hit.as_mut() {
            hit.t = seg.world_t(best_s);
        }
        if let Some(occ) = out.occlusion.as_mut() {
            occ.t = seg.world_t(occ_s);
        }
        out
    }
}

/// Parameter interval `[sa, sb]` of `p0 + s d`, `s` in `[0, 1]`, inside the square
/// `xr x yr` (slab test, closed intervals).
#[inline]
fn clip_to_square(p0: Vec3, d: Vec3, xr: [f32; 2], yr: [f32; 2]) -> Option<(f32, f32)> {
    let (mut sa, mut sb) = (0.0f32, 1.0f32);
    for (o, dd, r) in [(p0.x, d.x, xr), (p0.y, d.y, yr)] {
        if dd == 0.0 {
            if o < r[0] || o > r[1] {
                return None;
            }
        } else {
            let (t0, t1) = ((r[0] - o) / dd, (r[1] - o) / dd);
            sa = sa.max(t0.min(t1));
            sb = sb.min(t0.max(t1));
        }
    }
    (sa <= sb).then_some((sa, sb))
}

impl ScreenTracer for BruteForcePlanes {
    fn trace(&self, ray: &Ray, stats: &mut TraceStats) -> TraceResult {
        stats.rays += 1;
        let r = self.trace_detailed(ray, stats);
        if let Some(hit) = r.hit {
            stats.hits += 1;
            TraceResult::Hit {
                layer: hit.layer,
                pixel: hit.pixel,
                position: ray.at(hit.t),
                t: hit.t,
            }
        } else if let Some(o) = r.occlusion {
            stats.occlusion_volumes += 1;
            TraceResult::OcclusionVolume {
                layer: o.layer,
                pixel: o.pixel,
                t: o.t,
            }
        } else {
            TraceResult::Miss
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_clip() {
        let p0 = Vec3::new(0.0, 0.5, 0.0);
        let d = Vec3::new(1.0, 0.0, 1.0);
        assert_eq!(
            clip_to_square(p0, d, [0.25, 0.5], [0.0, 1.0]),
            Some((0.25, 0.5))
        );
        assert_eq!(clip_to_square(p0, d, [0.25, 0.5], [0.6, 1.0]), None);
    }
}
