//! The naive ray source of HVVR's Table 3 (Hunt et al. 2018, §6.2): every subsample ray of a
//! sample set stored up front in a high-resolution ray buffer ([`RayBuffer`]), which the caster
//! reads instead of generating the rays just in time from the samples' film positions and the
//! shared offset table (§5.1, the default). The stored rays are [`SampleSet::subsample_ray`]'s,
//! bit-identical to the generated ones, so both sources give the same buffer (tested in
//! `tests/cast.rs`); the difference is the memory read per ray: 24 bytes here against a
//! 20-byte [`crate::Sample`] per `spp` rays.
//!
//! The set-up kernel (tiles with a shared origin: every camera but the thin lens) reads the
//! buffer; tiles of the watertight kernel generate their rays as usual.

use glam::Vec3;

use crate::SampleSet;

/// Every subsample ray of a set, index `sample * spp + k`: origin and direction (`d = 0`
/// where the camera has no ray).
#[derive(Clone, Debug, Default)]
pub struct RayBuffer {
    pub rays: Vec<[f32; 6]>,
}

impl RayBuffer {
    /// Stores every subsample ray of `set` (in parallel).
    pub fn new(set: &SampleSet) -> Self {
        use rayon::prelude::*;
        let spp = set.spp as usize;
        let rays = (0..set.ray_count())
            .into_par_iter()
            .map(|j| match set.subsample_ray(j / spp, j % spp) {
                Some(r) => {
                    let (o, d) = (r.origin, r.dir);
                    [o.x, o.y, o.z, d.x, d.y, d.z]
                }
                None => [0.0; 6],
            })
            .collect();
        RayBuffer { rays }
    }

    /// Bytes of the stored rays.
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(self.rays.as_slice())
    }

    /// Ray `j`: `(origin, direction, valid)`.
    #[inline(always)]
    pub fn get(&self, j: usize) -> (Vec3, Vec3, bool) {
        let r = &self.rays[j];
        let d = Vec3::new(r[3], r[4], r[5]);
        (Vec3::new(r[0], r[1], r[2]), d, d != Vec3::ZERO)
    }
}
