//! [`HiZTracer`]: Hi-Z screen-space tracing, Uludag 2014, "Hi-Z Screen-Space Cone-Traced
//! Reflections" (GPU Pro 5): a min-depth pyramid and the cell-crossing loop that moves the ray
//! to a cell's min plane and goes a level down on a potential hit, and to the cell's exit and a
//! level up otherwise (`depth_layers::traverse` with one bound per cell).
//!
//! Per layer, in the unit cube of the reference view: level 0 holds each pixel's cube `z`
//! (flat per-pixel heights, as Uludag's depth buffer), level `l` the min over `2 x 2` cells;
//! empty pixels hold `+inf`. At a pixel the ray hits the flat height if it crosses it inside the
//! footprint (exact, no refinement needed), or the pixel's wall if it enters the footprint at
//! most `z_thickness` behind it; farther behind it is in the occlusion volume and continues
//! (Uludag's original treats the depth buffer as infinitely thick and stops there; the
//! thickness test is the common fix, and it lets deeper layers resolve disocclusions).
//!
//! With only a min bound a ray behind a surface cannot skip: every cell it crosses there is a
//! "potential hit" and is descended to level 0 — the cost the min-max mipmaps avoid
//! ([`crate::minmax`]). Layers are traced as a cascade (Widmer et al. 2015, §4.1).

use std::time::Instant;

use parallax_core::{GBuffer, Ray};

use crate::depth_layers::{
    Clip, DepthMap, Leaf, PixelRay, Pyramid, cascade, check_layers, covered, finish, traverse,
};
use crate::{ScreenError, ScreenTracer, TraceResult, TraceStats, UnitCube};

/// Options of [`HiZTracer`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HiZOptions {
    /// Hard bound on traversal iterations per layer.
    pub max_steps: u32,
    /// Shell thickness in view-depth units (metres) for side-wall hits.
    pub z_thickness: f32,
    /// Use at most this many layers (cascade).
    pub layers: usize,
    /// Maximum world distance along the ray.
    pub max_distance: f32,
}

impl Default for HiZOptions {
    fn default() -> Self {
        Self {
            max_steps: 2000,
            z_thickness: 0.1,
            layers: 2,
            max_distance: f32::INFINITY,
        }
    }
}

/// Hi-Z (min-depth pyramid) tracer over the captured layers.
#[derive(Clone, Debug)]
pub struct HiZTracer {
    pub cube: UnitCube,
    pub opts: HiZOptions,
    clip: Clip,
    map: DepthMap,
    layers: Vec<Pyramid<1>>,
    build_ms: Vec<f64>,
}

impl HiZTracer {
    /// Builds the min pyramids of the first `opts.layers` of `layers`.
    pub fn new(
        cube: &UnitCube,
        layers: &[GBuffer],
        opts: &HiZOptions,
    ) -> Result<Self, ScreenError> {
        let n = check_layers(cube, layers, opts.layers)?;
        if opts.z_thickness.is_nan() || opts.z_thickness < 0.0 {
            return Err(ScreenError::InvalidSpace("z_thickness must be >= 0".into()));
        }
        let map = DepthMap::new(cube);
        let (mut out, mut build_ms) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for g in &layers[..n] {
            let t = Instant::now();
            let base: Vec<[f32; 1]> = g
                .depth
                .iter()
                .map(|&d| [if covered(d) { map.z(d) } else { f32::INFINITY }])
                .collect();
            out.push(Pyramid::build(
                cube.camera.width,
                cube.camera.height,
                base,
                |a, c| a[0] = a[0].min(c[0]),
            ));
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

    /// Build time of each layer's pyramid, milliseconds.
    pub fn build_ms(&self) -> Vec<f64> {
        self.build_ms.clone()
    }

    /// Bytes of the pyramids.
    pub fn bytes(&self) -> usize {
        self.layers.iter().map(|p| p.bytes()).sum()
    }

    #[inline]
    fn leaf(&self, pyr: &Pyramid<1>, pr: &PixelRay, ix: u32, iy: u32, sa: f32, sb: f32) -> Leaf {
        let hz = pyr.data[(iy * self.cube.camera.width + ix) as usize][0];
        let (za, zb) = (pr.o.z + pr.d.z * sa, pr.o.z + pr.d.z * sb);
        let (fa, fb) = (za - hz, zb - hz);
        if (fa <= 0.0) != (fb <= 0.0) || fa == 0.0 || fb == 0.0 {
            let s = if pr.d.z != 0.0 {
                ((hz - pr.o.z) / pr.d.z).clamp(sa, sb)
            } else {
                sa
            };
            Leaf::Hit(s)
        } else if fa > 0.0 {
            if za <= self.map.z_behind(hz, self.opts.z_thickness) {
                Leaf::Hit(sa)
            } else {
                Leaf::Occluded(sa)
            }
        } else {
            Leaf::Nothing
        }
    }
}

impl ScreenTracer for HiZTracer {
    fn trace(&self, ray: &Ray, stats: &mut TraceStats) -> TraceResult {
        stats.rays += 1;
        let Some(pr) = PixelRay::new(&self.clip, ray, self.opts.max_distance) else {
            return TraceResult::Miss;
        };
        let (best, occ) = cascade(self.layers.len(), |li, s0, s1| {
            let pyr = &self.layers[li];
            traverse(
                pyr,
                &pr,
                s0,
                s1,
                self.opts.max_steps,
                stats,
                |ix, iy, sa, sb| self.leaf(pyr, &pr, ix, iy, sa, sb),
            )
        });
        finish(ray, &pr, best, occ, stats)
    }
}
