//! The visibility buffer (Hunt et al. 2018, §5.5 output): the closest triangle of every
//! subsample ray of a [`SampleSet`], indexed `sample * spp + subsample`. The paper emits
//! (triangle, sample-mask) pairs per tile; a flat per-subsample array carries the same
//! information and lets every method be compared subsample by subsample. Both arrays are
//! [`HugeBuf`]s: on transparent huge pages where the system allows, and cache-line aligned,
//! so the caster's whole-packet runs of 16 entries are whole lines for its non-temporal
//! stores.

use parallax_bvh::Bvh;
use parallax_core::NO_ID;
use parallax_core::huge_pages::HugeBuf;
use rayon::prelude::*;

use crate::SampleSet;

/// Closest hits of every subsample ray.
#[derive(Clone, Debug, PartialEq)]
pub struct VisibilityBuffer {
    pub spp: u32,
    /// Original (mesh) triangle index of the closest hit, or [`NO_ID`].
    pub prim: HugeBuf<u32>,
    /// World ray parameter of the closest hit (`f32::INFINITY` when none).
    pub t: HugeBuf<f32>,
}

impl VisibilityBuffer {
    /// An empty buffer for `set` (every subsample a miss).
    pub fn new(set: &SampleSet) -> Self {
        let n = set.ray_count();
        Self {
            spp: set.spp,
            prim: HugeBuf::new(n, NO_ID),
            t: HugeBuf::new(n, f32::INFINITY),
        }
    }

    /// Fraction of subsamples on which `self` and `other` report the same triangle.
    pub fn agreement(&self, other: &VisibilityBuffer) -> f64 {
        if self.prim.is_empty() {
            return 1.0;
        }
        let same = self
            .prim
            .iter()
            .zip(&other.prim)
            .filter(|(a, b)| a == b)
            .count();
        same as f64 / self.prim.len() as f64
    }
}

/// The per-ray baseline: every subsample ray traced on its own through the BVH
/// (parallel over samples).
pub fn trace_per_ray(bvh: &Bvh, set: &SampleSet, out: &mut VisibilityBuffer) {
    let spp = set.spp as usize;
    out.prim
        .par_chunks_mut(spp)
        .zip(out.t.par_chunks_mut(spp))
        .enumerate()
        .for_each(|(i, (prim, t))| {
            for k in 0..spp {
                let hit = set
                    .subsample_ray(i, k)
                    .and_then(|ray| bvh.closest_hit(&ray));
                (prim[k], t[k]) = match hit {
                    Some(h) => (h.prim, h.t),
                    None => (NO_ID, f32::INFINITY),
                };
            }
        });
}
