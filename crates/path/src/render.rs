//! The render: every tile's samples, up to a sample count or for as long as a time budget
//! allows.
//!
//! The units of work (one sample of one tile) go to the workers as [`crate::schedule`] hands
//! them out: no barrier between samples, and with a time budget one more sample of every pixel
//! (a round) is started only when the rate measured so far says it ends within the budget. At
//! least one sample per pixel is always taken. A round is never split, so every pixel has the
//! same count, and because the film adds samples in index order (see [`crate::film`]) the
//! image is the one a sample count of that many gives, bit for bit, at any thread count.

use std::ops::Range;
use std::time::Instant;

use parallax_core::{Image, Rgb, WorldTracer};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel};

use crate::error::Result;
use crate::estimator::Integrator;
use crate::film::Film;
use crate::options::PathOptions;
use crate::record::PathRecord;
use crate::schedule::{self, Target};
use crate::stats::PathStats;
use crate::wavefront::Wavefront;

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

    /// Adds samples `samples` of every pixel to `film` (every tile of which holds samples
    /// `..samples.start`); `progress(n)` is called with the pixel samples each finished unit
    /// added. Returns the pass's statistics and, with `record`,
    /// every ray it traced.
    pub fn render_samples(
        &self,
        film: &mut Film,
        samples: Range<u32>,
        record: bool,
        progress: &(dyn Fn(u64) + Sync),
    ) -> (PathStats, Option<PathRecord>) {
        let (stats, _, rec) = schedule::run(
            &self.wavefront(),
            film,
            samples.start,
            Target::Fixed(samples.end),
            record,
            progress,
        );
        (stats, rec)
    }

    fn wavefront(&self) -> Wavefront<'_> {
        Wavefront {
            scene: self.scene,
            camera: self.camera,
            tracer: self.tracer,
            integrator: &self.integrator,
            seed: self.opts.seed,
        }
    }

    /// The render (see the module docs).
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
        let target = match self.opts.time_budget {
            Some(budget) => Target::Budget {
                max: self.opts.spp,
                budget,
                start,
            },
            None => Target::Fixed(self.opts.spp),
        };
        let (stats, done, all) =
            schedule::run(&self.wavefront(), &mut film, 0, target, record, progress);
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
