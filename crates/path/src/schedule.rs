//! The work units of a render and how the workers share them: a unit is one sample of one
//! tile (one wavefront, [`crate::wavefront`]), and every worker takes the next unit itself,
//! without a barrier between samples, until every tile has reached the target sample count.
//!
//! A worker takes, among the tiles nobody is rendering, the one with the fewest samples below
//! the target. When there is none, a time-budgeted render may raise the target by one sample
//! (a *round*: one more sample of every pixel) if the round fits in the time left after the
//! samples already promised ([`round_fits`]); once a round is refused the target is final.
//! Workers therefore wait only at the end of the render, for the units still running, and the
//! decision to take one more sample is made at the last moment with the rate measured over
//! all units so far (a pass structure decides a pass at once and waits for its slowest tile).
//!
//! | parameter | type | meaning |
//! |---|---|---|
//! | `first` | u32 | sample every tile starts at |
//! | [`Target::Fixed`] | u32 | render samples `first..end` of every tile |
//! | [`Target::Budget`] | `max`, `budget` s, `start` | rounds while the next fits in `budget` seconds after `start`, at most `max` samples |
//!
//! **Invariants:** a tile's samples are rendered one at a time in index order (a tile is
//! never in two units at once), so each pixel adds its samples in order (see [`crate::film`])
//! and the image does not depend on the thread count or on when units ran; every tile ends at
//! the same sample count; the ray record is sorted by tile, then sample, whatever order the
//! units ran in.

use std::sync::Mutex;
use std::time::Instant;

use crate::film::{Film, TileFilm};
use crate::record::PathRecord;
use crate::stats::PathStats;
use crate::wavefront::{Scratch, Wavefront};

/// How many samples every tile gets.
#[derive(Clone, Copy, Debug)]
pub enum Target {
    /// Samples `first..end`.
    Fixed(u32),
    /// Rounds of one sample per pixel while the next fits in `budget` seconds after `start`;
    /// at least one, at most `max` samples in all.
    Budget {
        max: u32,
        budget: f64,
        start: Instant,
    },
}

/// Whether one more round of `round` pixel samples fits in the budget: at the rate measured
/// so far (`completed` pixel samples in `elapsed` seconds), the `promised` pixel samples not yet
/// finished and then the round end by `budget` seconds.
pub fn round_fits(elapsed: f64, completed: u64, promised: u64, round: u64, budget: f64) -> bool {
    if completed == 0 || elapsed <= 0.0 {
        return false;
    }
    let rate = completed as f64 / elapsed;
    elapsed + (promised + round) as f64 / rate <= budget
}

/// The shared progress of the units.
struct Board {
    /// Samples finished per tile (the next unit of tile `i` is sample `done[i]`).
    done: Vec<u32>,
    busy: Vec<bool>,
    /// Every tile renders the samples below this.
    target: u32,
    /// The target is final (a round was refused, or it is fixed).
    closed: bool,
    /// Pixel samples finished.
    completed: u64,
}

impl Board {
    /// The next unit (tile, sample) for a worker, raising the target where the budget allows;
    /// `None`: nothing is left for this worker.
    fn claim(&mut self, pixels: &[u64], target: &Target) -> Option<(usize, u32)> {
        loop {
            let next = (0..self.done.len())
                .filter(|&i| !self.busy[i] && self.done[i] < self.target)
                .min_by_key(|&i| self.done[i]);
            if let Some(i) = next {
                self.busy[i] = true;
                return Some((i, self.done[i]));
            }
            if self.closed || !self.raise(pixels, target) {
                self.closed = true;
                return None;
            }
        }
    }

    fn raise(&mut self, pixels: &[u64], target: &Target) -> bool {
        let Target::Budget { max, budget, start } = *target else {
            return false;
        };
        if self.target >= max {
            return false;
        }
        let promised: u64 = (self.done.iter().zip(pixels))
            .map(|(&d, &p)| (self.target - d) as u64 * p)
            .sum();
        let round: u64 = pixels.iter().sum();
        let elapsed = start.elapsed().as_secs_f64();
        if !round_fits(elapsed, self.completed, promised, round, budget) {
            return false;
        }
        self.target += 1;
        true
    }
}

/// What one worker gathered.
#[derive(Default)]
struct WorkerOut {
    stats: PathStats,
    /// (tile, sample, record) per unit.
    records: Vec<(usize, u32, PathRecord)>,
}

/// Renders units of every tile of `film` from sample `first` on until `target` is reached
/// (see the module docs) on the current rayon pool's threads; returns the statistics, the
/// samples per pixel reached and, with `record`, every ray.
pub fn run(
    wf: &Wavefront<'_>,
    film: &mut Film,
    first: u32,
    target: Target,
    record: bool,
    progress: &(dyn Fn(u64) + Sync),
) -> (PathStats, u32, Option<PathRecord>) {
    let tiles: Vec<Mutex<TileFilm>> = std::mem::take(&mut film.tiles)
        .into_iter()
        .map(Mutex::new)
        .collect();
    let pixels: Vec<u64> = tiles
        .iter()
        .map(|t| t.lock().expect("not poisoned").tile.pixels() as u64)
        .collect();
    let (start_target, closed) = match target {
        Target::Fixed(end) => (end.max(first), true),
        Target::Budget { max, .. } => ((first + 1).min(max.max(first)), false),
    };
    let board = Mutex::new(Board {
        done: vec![first; tiles.len()],
        busy: vec![false; tiles.len()],
        target: start_target,
        closed,
        completed: 0,
    });
    let outs: Mutex<Vec<WorkerOut>> = Mutex::new(Vec::new());
    let worker = || {
        let mut scratch = Scratch::default();
        let mut out = WorkerOut::default();
        loop {
            let claimed = board.lock().expect("not poisoned").claim(&pixels, &target);
            let Some((i, s)) = claimed else { break };
            let t = Instant::now();
            let mut rec = record.then(PathRecord::default);
            {
                let mut tf = tiles[i].lock().expect("not poisoned");
                wf.run_tile(
                    &mut tf,
                    s..s + 1,
                    &mut scratch,
                    &mut out.stats,
                    rec.as_mut(),
                );
            }
            out.stats.work_ns += t.elapsed().as_nanos() as u64;
            if let Some(r) = rec {
                out.records.push((i, s, r));
            }
            progress(pixels[i]);
            let mut b = board.lock().expect("not poisoned");
            b.done[i] += 1;
            b.busy[i] = false;
            b.completed += pixels[i];
        }
        outs.lock().expect("not poisoned").push(out);
    };
    rayon::scope(|sc| {
        for _ in 0..rayon::current_num_threads() {
            sc.spawn(|_| worker());
        }
    });
    film.tiles = tiles
        .into_iter()
        .map(|t| t.into_inner().expect("not poisoned"))
        .collect();
    let board = board.into_inner().expect("not poisoned");
    debug_assert!(board.done.iter().all(|&d| d == board.target));
    let mut stats = PathStats::default();
    let mut records = Vec::new();
    for o in outs.into_inner().expect("not poisoned") {
        stats.merge(&o.stats);
        records.extend(o.records);
    }
    let all = record.then(|| {
        records.sort_by_key(|&(i, s, _)| (i, s));
        let mut all = PathRecord::default();
        for (_, _, r) in records {
            all.append(r);
        }
        all
    });
    (stats, board.target, all)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_round_fits_when_the_promised_samples_and_it_end_by_the_budget() {
        // 100 pixel samples in 1 s: 100 per second.
        assert!(round_fits(1.0, 100, 0, 100, 2.0));
        assert!(!round_fits(1.0, 100, 1, 100, 2.0));
        // 50 promised (0.5 s) and a round of 100 (1 s) after 1 s: 2.5 s.
        assert!(round_fits(1.0, 100, 50, 100, 2.5));
        assert!(!round_fits(1.0, 100, 50, 100, 2.49));
        // Nothing measured yet: no estimate, no round.
        assert!(!round_fits(0.0, 0, 0, 100, 10.0));
    }
}
