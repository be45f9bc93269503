//! Resolve (Hunt et al. 2018, §5.1 and §5.6): visibility buffer -> one linear colour per sample,
//! by MSAA (shade once per distinct triangle of a sample) or SSAA (shade every subsample).
//!
//! - **MSAA**: the sample's subsamples are grouped by triangle (HVVR's `(triangle, mask)` gbuffer
//!   entries, §5.5); each distinct triangle is shaded once and weighted by its coverage
//!   `count / spp`. *Where* it is shaded: at the **centre-most covered subsample ray** — the
//!   subsample of that triangle whose footprint offset is nearest the sample centre (lowest
//!   index on ties). HVVR intersects the sample's centre ray with each entry's triangle; we take
//!   a covered subsample instead because that ray really hits the triangle, so the shading point
//!   lies on it (the centre ray meets the plane possibly outside the triangle, where
//!   interpolated attributes extrapolate), and for `spp = 1` MSAA is then exactly SSAA.
//! - **SSAA**: every subsample that hit is shaded with its own ray, weight `1 / spp`.
//! - Misses contribute the background (environment) weighted by their count, without a shade
//!   invocation.
//!
//! Shade invocations are counted (HVVR's "shade samples per non-empty pixel", Tables 2 and 4).

use glam::Vec3;
use parallax_core::NO_ID;
use rayon::prelude::*;

use crate::shade::VrShader;
use crate::{SampleSet, VisibilityBuffer};

/// How a sample's subsamples are shaded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadingMode {
    Msaa,
    Ssaa,
}

impl ShadingMode {
    pub fn name(self) -> &'static str {
        match self {
            ShadingMode::Msaa => "msaa",
            ShadingMode::Ssaa => "ssaa",
        }
    }
}

/// Resolved samples: linear colour per sample and shade counts.
#[derive(Clone, Debug)]
pub struct Resolved {
    /// Linear RGB per sample (the sample's full colour; per-channel sets use one channel).
    pub colors: Vec<Vec3>,
    /// Shade invocations.
    pub shades: u64,
    /// Samples with at least one subsample hit.
    pub nonempty: u64,
}

impl Resolved {
    /// Average shade invocations per sample with any hit (HVVR Table 4's figure).
    pub fn shades_per_nonempty(&self) -> f64 {
        self.shades as f64 / self.nonempty.max(1) as f64
    }
}

/// Distinct triangles of one sample's subsamples: `(triangle, coverage, centre-most
/// subsample)`, in first-seen order, written into `out` (length >= spp); returns how many.
/// `dist2[k]` is the squared footprint offset of subsample `k`.
pub fn group_by_triangle(prims: &[u32], dist2: &[f32], out: &mut [(u32, u32, usize)]) -> usize {
    let mut n = 0;
    for (k, &p) in prims.iter().enumerate() {
        if p == NO_ID {
            continue;
        }
        match out[..n].iter_mut().find(|e| e.0 == p) {
            Some(e) => {
                e.1 += 1;
                if dist2[k] < dist2[e.2] {
                    e.2 = k;
                }
            }
            None => {
                out[n] = (p, 1, k);
                n += 1;
            }
        }
    }
    n
}

/// Shades every sample of `set` from its visibility `vis` (parallel over samples).
pub fn resolve(
    set: &SampleSet,
    vis: &VisibilityBuffer,
    shader: &VrShader,
    mode: ShadingMode,
) -> Resolved {
    let spp = set.spp as usize;
    assert_eq!(
        vis.prim.len(),
        set.ray_count(),
        "buffer of another sample set"
    );
    let dist2: Vec<f32> = set.offsets.iter().map(|o| o.length_squared()).collect();
    let inv = 1.0 / spp as f32;
    let bg = shader.background();
    let per_sample: Vec<(Vec3, u32)> = vis
        .prim
        .par_chunks(spp)
        .enumerate()
        .map_init(
            || vec![(0u32, 0u32, 0usize); spp],
            |groups, (i, prims)| {
                let mut color = Vec3::ZERO;
                let mut shades = 0u32;
                let misses = prims.iter().filter(|&&p| p == NO_ID).count();
                match mode {
                    ShadingMode::Msaa => {
                        let n = group_by_triangle(prims, &dist2, groups);
                        for &(prim, count, k) in &groups[..n] {
                            if let Some(ray) = set.subsample_ray(i, k) {
                                color += shader.shade(&ray, prim) * (count as f32 * inv);
                                shades += 1;
                            }
                        }
                    }
                    ShadingMode::Ssaa => {
                        for (k, &prim) in prims.iter().enumerate() {
                            if prim == NO_ID {
                                continue;
                            }
                            if let Some(ray) = set.subsample_ray(i, k) {
                                color += shader.shade(&ray, prim) * inv;
                                shades += 1;
                            }
                        }
                    }
                }
                color += bg * (misses as f32 * inv);
                (color, shades)
            },
        )
        .collect();
    let shades = per_sample.iter().map(|p| p.1 as u64).sum();
    let nonempty = per_sample.iter().filter(|p| p.1 > 0).count() as u64;
    Resolved {
        colors: per_sample.into_iter().map(|p| p.0).collect(),
        shades,
        nonempty,
    }
}

/// Number of distinct `(sample, triangle)` pairs of a buffer: what MSAA must shade.
pub fn distinct_pairs(vis: &VisibilityBuffer) -> u64 {
    let spp = vis.spp as usize;
    let zero = vec![0.0; spp];
    let mut groups = vec![(0u32, 0u32, 0usize); spp];
    vis.prim
        .chunks(spp)
        .map(|p| group_by_triangle(p, &zero, &mut groups) as u64)
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_count_coverage_and_pick_the_centre_most() {
        let prims = [5, NO_ID, 7, 5, 5, 7];
        let d = [0.3, 0.0, 0.2, 0.1, 0.2, 0.05];
        let mut out = [(0, 0, 0); 6];
        let n = group_by_triangle(&prims, &d, &mut out);
        assert_eq!(&out[..n], &[(5, 3, 3), (7, 2, 5)]);
    }
}
