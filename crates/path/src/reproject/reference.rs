//! References and n-spp error curves (Mäkitalo et al. 2019, §3-4: "comparisons to a pristine
//! reference that is ray traced with thousands of samples per pixel"), one progressive render
//! per frame and eye with the path tracer ([`crate::PathTracer`], the paper's estimator):
//! samples `0..N` give the curve (the image after each sample is scored against the
//! reference), samples `N..R` the reference, so the curve, the reference and the measured
//! images are independent (see [`super::metric`] for the use of the reference's own noise).
//!
//! Renders are cached on disk under a content address ([`super::fingerprint`]): the scene's
//! geometry, materials, textures and lights, the eye's camera and film, the frame, `R`, `N`,
//! the seed and the estimator's options. A file holds the curve, the reference noise and the
//! reference image; a missing, truncated or mismatching file is rendered again.
//!
//! | parameter | type | default (bench) | meaning |
//! |---|---|---|---|
//! | `spp` | u32 | 256 | `R`: samples of the whole render (the reference has `R - N`) |
//! | `curve_spp` | u32 | 32 | `N`: largest n of the error curve; `R > N` |
//! | `seed` | u64 | from the run's seed | stream of the render, distinct from every traced frame's |

use std::io::Write;
use std::path::{Path, PathBuf};

use glam::Vec3;
use parallax_core::WorldTracer;
use parallax_render::bsdf::MaterialMode;
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, Pinhole};

use super::error::{ReprojectError, Result, option_error};
use super::fingerprint::Fingerprint;
use super::metric::{ErrorCurve, mse};
use super::sampler::PaperSampler;
use crate::options::MAX_SPP;
use crate::render::PathTracer;

/// What a reference render takes (module table).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReferenceSpec {
    pub spp: u32,
    pub curve_spp: u32,
}

impl ReferenceSpec {
    /// `R > N >= 1`, `R` within the path tracer's limit.
    pub fn validate(&self) -> Result<()> {
        if self.curve_spp == 0 {
            return option_error("--curve-spp must be at least 1");
        }
        if self.spp <= self.curve_spp {
            return option_error(format!(
                "--reference-spp ({}) must exceed the error curve's largest n (--curve-spp {}): \
                 the reference is made of the samples after the curve's",
                self.spp, self.curve_spp
            ));
        }
        if self.spp > MAX_SPP {
            return option_error(format!(
                "--reference-spp must be at most {MAX_SPP}, got {}",
                self.spp
            ));
        }
        Ok(())
    }
}

/// The reference and error curve of one frame and eye.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameReference {
    /// Mean of samples `N..R`, linear RGB, row-major.
    pub image: Vec<Vec3>,
    pub curve: ErrorCurve,
    /// Loaded from the cache (not rendered).
    pub cached: bool,
}

/// Renders the reference of `camera` (module docs); `progress(n)` gets pixel samples done.
pub fn render_reference(
    scene: &Scene,
    tracer: &dyn WorldTracer,
    camera: &Pinhole,
    materials: MaterialMode,
    spec: ReferenceSpec,
    seed: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<FrameReference> {
    spec.validate()?;
    let cam = Camera::Pinhole(camera.clone());
    let opts = PaperSampler::path_options(materials, spec.spp, seed);
    let pt = PathTracer::new(scene, &cam, tracer, opts)?;
    let mut film = pt.film();
    pt.render_samples(&mut film, spec.curve_spp..spec.spp, false, progress);
    let image = film.mean().into_vec();
    let var = film.variance_of_mean();
    let noise = var
        .data()
        .iter()
        .map(|v| v.as_dvec3().element_sum())
        .sum::<f64>()
        / (3 * var.len()).max(1) as f64;
    let mut curve_film = pt.film();
    let mut curve = Vec::with_capacity(spec.curve_spp as usize);
    for n in 0..spec.curve_spp {
        pt.render_samples(&mut curve_film, n..n + 1, false, progress);
        curve.push(mse(curve_film.mean().data(), &image));
    }
    Ok(FrameReference {
        image,
        curve: ErrorCurve {
            mse: curve,
            reference_noise: noise,
        },
        cached: false,
    })
}

/// Bumped whenever the file layout or the estimator changes what a reference holds.
const CACHE_VERSION: u64 = 1;
const MAGIC: &[u8; 8] = b"PXREPRJ1";

/// The content address of one reference: `scene` is [`Fingerprint::scene_content`] of the
/// scene (computed once per sequence); the lights are read from `lit`.
#[allow(clippy::too_many_arguments)]
pub fn cache_key(
    scene: &Fingerprint,
    lit: &Scene,
    camera: &Pinhole,
    frame: u32,
    spec: ReferenceSpec,
    seed: u64,
    materials: MaterialMode,
) -> String {
    let mut f = *scene;
    f.lights(lit)
        .u64(CACHE_VERSION)
        .vec3(camera.frame.position)
        .vec3(camera.frame.basis.x_axis)
        .vec3(camera.frame.basis.y_axis)
        .vec3(camera.frame.basis.z_axis)
        .f32(camera.tan_half_y)
        .vec3(camera.shift.extend(0.0))
        .u64(((camera.width as u64) << 32) | camera.height as u64)
        .u64(frame as u64)
        .u64(((spec.spp as u64) << 32) | spec.curve_spp as u64)
        .u64(seed)
        .str(materials.name())
        .u64(super::sampler::PAPER_MAX_DEPTH as u64);
    f.hex()
}

/// A folder of cached references (`None`: no caching).
#[derive(Clone, Debug, Default)]
pub struct ReferenceCache {
    pub dir: Option<PathBuf>,
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ReprojectError + '_ {
    move |source| ReprojectError::Io {
        path: path.to_path_buf(),
        source,
    }
}

impl ReferenceCache {
    /// The cached reference under `key` for a `pixels`-pixel film and `spec`, or `render()`'s
    /// (then stored).
    pub fn get_or_render(
        &self,
        key: &str,
        pixels: usize,
        spec: ReferenceSpec,
        render: impl FnOnce() -> Result<FrameReference>,
    ) -> Result<FrameReference> {
        let Some(dir) = &self.dir else {
            return render();
        };
        let path = dir.join(format!("{key}.ref"));
        if let Ok(bytes) = std::fs::read(&path)
            && let Some(r) = decode(&bytes, pixels, spec)
        {
            return Ok(r);
        }
        let r = render()?;
        std::fs::create_dir_all(dir).map_err(io_err(dir))?;
        let tmp = dir.join(format!("{key}.ref.tmp{}", std::process::id()));
        let mut file = std::fs::File::create(&tmp).map_err(io_err(&tmp))?;
        file.write_all(&encode(&r, spec)).map_err(io_err(&tmp))?;
        drop(file);
        std::fs::rename(&tmp, &path).map_err(io_err(&path))?;
        Ok(r)
    }
}

fn encode(r: &FrameReference, spec: ReferenceSpec) -> Vec<u8> {
    let mut b = Vec::with_capacity(40 + r.curve.mse.len() * 8 + r.image.len() * 12);
    b.extend_from_slice(MAGIC);
    for v in [spec.spp as u64, spec.curve_spp as u64, r.image.len() as u64] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.extend_from_slice(&r.curve.reference_noise.to_le_bytes());
    for m in &r.curve.mse {
        b.extend_from_slice(&m.to_le_bytes());
    }
    for p in &r.image {
        for c in p.to_array() {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    b
}

fn decode(b: &[u8], pixels: usize, spec: ReferenceSpec) -> Option<FrameReference> {
    let word = |i: usize| -> Option<[u8; 8]> { b.get(i..i + 8)?.try_into().ok() };
    if b.get(..8)? != MAGIC {
        return None;
    }
    let (spp, n, len) = (
        u64::from_le_bytes(word(8)?),
        u64::from_le_bytes(word(16)?),
        u64::from_le_bytes(word(24)?),
    );
    if spp != spec.spp as u64 || n != spec.curve_spp as u64 || len != pixels as u64 {
        return None;
    }
    let n = n as usize;
    if b.len() != 40 + n * 8 + pixels * 12 {
        return None;
    }
    let noise = f64::from_le_bytes(word(32)?);
    let curve = (0..n)
        .map(|k| word(40 + 8 * k).map(f64::from_le_bytes))
        .collect::<Option<Vec<_>>>()?;
    let base = 40 + 8 * n;
    let f = |i: usize| f32::from_le_bytes(b[base + 4 * i..base + 4 * i + 4].try_into().unwrap());
    let image = (0..pixels)
        .map(|p| Vec3::new(f(3 * p), f(3 * p + 1), f(3 * p + 2)))
        .collect();
    Some(FrameReference {
        image,
        curve: ErrorCurve {
            mse: curve,
            reference_noise: noise,
        },
        cached: true,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spec_rejects_a_reference_below_the_curve() {
        let ok = ReferenceSpec {
            spp: 64,
            curve_spp: 16,
        };
        assert!(ok.validate().is_ok());
        for (spp, n) in [(16, 16), (8, 16), (64, 0)] {
            let e = ReferenceSpec { spp, curve_spp: n }
                .validate()
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("--reference-spp") || e.contains("--curve-spp"),
                "{e}"
            );
        }
    }

    #[test]
    fn cache_round_trips_and_rejects_other_sizes() {
        let dir = std::env::temp_dir().join(format!("parallax-refcache-{}", std::process::id()));
        let cache = ReferenceCache {
            dir: Some(dir.clone()),
        };
        let spec = ReferenceSpec {
            spp: 8,
            curve_spp: 2,
        };
        let r = FrameReference {
            image: vec![Vec3::new(1.0, 2.0, 3.0), Vec3::splat(0.5)],
            curve: ErrorCurve {
                mse: vec![0.5, 0.25],
                reference_noise: 0.01,
            },
            cached: false,
        };
        let first = cache.get_or_render("k", 2, spec, || Ok(r.clone())).unwrap();
        assert!(!first.cached);
        let again = cache
            .get_or_render("k", 2, spec, || panic!("must come from the cache"))
            .unwrap();
        assert!(again.cached && again.image == r.image && again.curve == r.curve);
        // Another film size under the same key is rendered again.
        let other = cache.get_or_render("k", 3, spec, || Ok(r.clone())).unwrap();
        assert!(!other.cached);
        std::fs::remove_dir_all(dir).ok();
    }
}
