//! Run statistics: what `--stats FILE.json` writes and benchmarks print.

use std::time::Instant;

use serde::Serialize;

/// Timings and counts of one run. `stages` are in execution order.
#[derive(Clone, Debug, Default, Serialize)]
pub struct RunStats {
    pub scene: String,
    pub camera_model: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub triangles: usize,
    /// All rays traced (primary, shadow, secondary).
    pub rays: u64,
    /// Wall-clock seconds of the whole run (load to image).
    pub seconds: f64,
    /// Rays per second of the tracing stages, in millions.
    pub mrays_per_s: f64,
    pub build_ms: f64,
    pub threads: usize,
    pub stages: Vec<Stage>,
}

/// One named stage and its wall-clock milliseconds.
#[derive(Clone, Debug, Serialize)]
pub struct Stage {
    pub name: String,
    pub ms: f64,
}

/// Times consecutive stages.
pub struct StageTimer {
    start: Instant,
    last: Instant,
    pub stages: Vec<Stage>,
}

impl Default for StageTimer {
    fn default() -> Self {
        Self::new()
    }
}

impl StageTimer {
    pub fn new() -> Self {
        let now = Instant::now();
        Self {
            start: now,
            last: now,
            stages: Vec::new(),
        }
    }

    /// Ends the current stage under `name`; returns its milliseconds.
    pub fn stage(&mut self, name: &str) -> f64 {
        let now = Instant::now();
        let ms = (now - self.last).as_secs_f64() * 1e3;
        self.last = now;
        self.stages.push(Stage {
            name: name.to_string(),
            ms,
        });
        ms
    }

    /// Seconds since the timer started.
    pub fn total_seconds(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// Milliseconds of the stage named `name` (0 if absent).
    pub fn ms(&self, name: &str) -> f64 {
        self.stages
            .iter()
            .filter(|s| s.name == name)
            .map(|s| s.ms)
            .sum()
    }
}
