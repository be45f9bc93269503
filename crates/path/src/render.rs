//! The progressive render: passes of samples over every tile until the sample count or the
//! time budget is reached.
//!
//! Pass sizes double (1, 1, 2, 4, ... samples per pixel) so that a time budget is met closely:
//! after each pass the time per sample is known, and the next pass takes only as many samples
//! as fit in the time left (none: stop). At least one sample per pixel is always taken. Passes
//! never split a sample, so every pixel has the same count, and because the film adds samples in
//! index order (see [`crate::film`]) the image is the one a single pass of that many samples
//! gives, bit for bit, at any thread count.

use std::ops::Range;
use std::time::Instant;

use parallax_core::{Image, Rgb, WorldTracer};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel};
use rayon::prelude::*;

use crate::error::Result;
use crate::estimator::Integrator;
use crate::film::Film;
use crate::options::PathOptions;
use crate::record::PathRecord;
use crate::stats::PathStats;
use crate::wavefront::{Scratch, Wavefront};

/// A finished render.
pub struct PathOutput {
    /// Per-pixel mean radiance (linear RGB).
    pub image: Image<Rgb>,
    /// Per-pixel variance of the mean, per channel.
    pub variance: Image<Rgb>,
    /// Samples per pixel taken.
    pub counts: Image<u32>,
    /// Samples per pixel taken (the same at every pixel).
    pub spp: u32,
    /// Wall-clock seconds of the passes.
    pub seconds: f64,
    pub stats: PathStats,
}

/// The path tracer of one scene, camera and tracer.
pub struct PathTracer<'a> {
    pub scene: &'a Scene,
    pub camera: &'a Camera,
    pub tracer: &'a dyn WorldTracer,
    pub opts: PathOptions,
    integrator: Integrator<'a>,
}

impl<'a> PathTracer<'a> {
    /// Checks the options; the scene's lights are used as they are (see
    /// [`crate::lighting::apply_lighting`] for overrides and the default sky).
    pub fn new(
        scene: &'a Scene,
        camera: &'a Camera,
        tracer: &'a dyn WorldTracer,
        opts: PathOptions,
    ) -> Result<Self> {
        opts.validate()?;
        let mut integrator = Integrator::new(
            scene,
            opts.materials,
            opts.max_depth,
            opts.rr_depth,
            opts.env_nee,
        );
        integrator.final_nee = opts.final_nee;
        Ok(Self {
            scene,
            camera,
            tracer,
            opts,
            integrator,
        })
    }

    /// An empty film of the camera's size.
    pub fn film(&self) -> Film {
        Film::new(self.camera.width(), self.camera.height(), self.opts.tile)
    }

    /// Adds samples `samples` of every pixel to `film`; `progress(n)` is called with the pixel
    /// samples each finished tile added. Returns the pass's statistics and, with `record`,
    /// every ray it traced.
    pub fn render_samples(
        &self,
        film: &mut Film,
        samples: Range<u32>,
        record: bool,
        progress: &(dyn Fn(u64) + Sync),
    ) -> (PathStats, Option<PathRecord>) {
        let wf = Wavefront {
            scene: self.scene,
            camera: self.camera,
            tracer: self.tracer,
            integrator: &self.integrator,
            seed: self.opts.seed,
        };
        let count = samples.len() as u64;
        let per_tile: Vec<(PathStats, Option<PathRecord>)> = film
            .tiles
            .par_iter_mut()
            .map_init(Scratch::default, |scratch, tf| {
                let mut stats = PathStats::default();
                let mut rec = record.then(PathRecord::default);
                wf.run_tile(tf, samples.clone(), scratch, &mut stats, rec.as_mut());
                progress(tf.tile.pixels() as u64 * count);
                (stats, rec)
            })
            .collect();
        let mut stats = PathStats::default();
        let mut all = record.then(PathRecord::default);
        for (s, r) in per_tile {
            stats.merge(&s);
            if let (Some(a), Some(r)) = (all.as_mut(), r) {
                a.append(r);
            }
        }
        (stats, all)
    }

    /// The progressive render (see the module docs).
    pub fn render(&self, progress: &(dyn Fn(u64) + Sync)) -> PathOutput {
        self.render_impl(false, progress).0
    }

    /// [`Self::render`] with every ray recorded.
    pub fn render_recorded(&self, progress: &(dyn Fn(u64) + Sync)) -> (PathOutput, PathRecord) {
        let (out, rec) = self.render_impl(true, progress);
        (out, rec.unwrap_or_default())
    }

    fn render_impl(
        &self,
        record: bool,
        progress: &(dyn Fn(u64) + Sync),
    ) -> (PathOutput, Option<PathRecord>) {
        let start = Instant::now();
        let mut film = self.film();
        let mut stats = PathStats::default();
        let mut all = record.then(PathRecord::default);
        let target = self.opts.spp;
        let mut done = 0u32;
        let mut pass = 1u32;
        while done < target {
            let n = pass.min(target - done);
            let (s, r) = self.render_samples(&mut film, done..done + n, record, progress);
            stats.merge(&s);
            if let (Some(a), Some(r)) = (all.as_mut(), r) {
                a.append(r);
            }
            done += n;
            let elapsed = start.elapsed().as_secs_f64();
            pass = match self.opts.time_budget {
                Some(budget) => {
                    let per_sample = elapsed / done as f64;
                    let fit = ((budget - elapsed) / per_sample).floor();
                    if fit < 1.0 {
                        break;
                    }
                    (fit as u32).min(done.max(1))
                }
                None => done,
            };
        }
        let out = PathOutput {
            image: film.mean(),
            variance: film.variance_of_mean(),
            counts: film.counts(),
            spp: done,
            seconds: start.elapsed().as_secs_f64(),
            stats,
        };
        (out, all)
    }
}
