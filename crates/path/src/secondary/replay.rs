//! Every tracer on identical rays: the reference (BVH) renderer's batches replayed through the
//! other tracers, their answers scored against the reference's (hit agreement), their trace
//! times taken in interleaved rounds (best round per tracer and batch), and every tracer's own
//! image scored against the reference image (PSNR / SSIM).
//!
//! **Agreement** of one ray: both miss; or both hit and either on the same primitive or at
//! positions within `tolerance` (world units); for shadow rays, the same occlusion answer.
//! Disagreements are split into `only_reference` (the reference hits, the other misses),
//! `only_other`, and `differ` (both hit elsewhere: `early` when the other's hit is nearer);
//! `outside` counts disagreements whose reference hit lies outside the other structure's box
//! (for shadow rays: whose segment leaves the box), the part a region of interest gives up.
//!
//! **Scores:** [`parallax_render::score`] (the display transform of the PNGs, PSNR with peak
//! 1, mean per-channel SSIM), the same as every other technique's.

use parallax_core::{Aabb, Image, Ray, Rgb, WorldHit, WorldStats, WorldTracer};
use serde::Serialize;

use super::render::{Answers, Batch, trace_closest, trace_occluded};

/// Counts of a ray-for-ray comparison (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Agreement {
    pub rays: u64,
    pub agree: u64,
    pub both_miss: u64,
    pub only_reference: u64,
    pub only_other: u64,
    pub differ: u64,
    /// Of `differ`: the other's hit nearer than the reference's.
    pub early: u64,
    /// Disagreements whose reference hit (shadow: segment) leaves the other's box.
    pub outside: u64,
}

impl Agreement {
    /// Fraction of rays that agree (1 for no rays).
    pub fn fraction(&self) -> f64 {
        if self.rays == 0 {
            1.0
        } else {
            self.agree as f64 / self.rays as f64
        }
    }
}

impl std::ops::AddAssign for Agreement {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
        self.agree += o.agree;
        self.both_miss += o.both_miss;
        self.only_reference += o.only_reference;
        self.only_other += o.only_other;
        self.differ += o.differ;
        self.early += o.early;
        self.outside += o.outside;
    }
}

/// Agreement of closest-hit answers `other` with `reference` (same rays).
pub fn agree_closest(
    reference: &[Option<WorldHit>],
    other: &[Option<WorldHit>],
    tolerance: f32,
    bounds: Option<&Aabb>,
) -> Agreement {
    let mut a = Agreement::default();
    for (r, o) in reference.iter().zip(other) {
        a.rays += 1;
        match (r, o) {
            (None, None) => {
                a.agree += 1;
                a.both_miss += 1;
                continue;
            }
            (Some(r), Some(o))
                if r.prim == o.prim || r.position.distance(o.position) < tolerance =>
            {
                a.agree += 1;
                continue;
            }
            (Some(r), Some(o)) => {
                a.differ += 1;
                a.early += (o.t < r.t) as u64;
            }
            (Some(_), None) => a.only_reference += 1,
            (None, Some(_)) => a.only_other += 1,
        }
        if let (Some(h), Some(b)) = (r, bounds) {
            a.outside += (!b.contains(h.position)) as u64;
        }
    }
    a
}

/// Agreement of occlusion answers (shadow rays).
pub fn agree_occluded(
    rays: &[Ray],
    reference: &[bool],
    other: &[bool],
    bounds: Option<&Aabb>,
) -> Agreement {
    let mut a = Agreement::default();
    for ((ray, &r), &o) in rays.iter().zip(reference).zip(other) {
        a.rays += 1;
        if r == o {
            a.agree += 1;
            a.both_miss += (!r) as u64;
            continue;
        }
        if r {
            a.only_reference += 1;
        } else {
            a.only_other += 1;
        }
        if let Some(b) = bounds {
            let end = ray.at(if ray.t_max.is_finite() {
                ray.t_max
            } else {
                1e30
            });
            a.outside += (!b.contains(end)) as u64;
        }
    }
    a
}

/// PSNR (dB) and SSIM of `image` against `truth` (module docs).
pub fn score(image: &Image<Rgb>, truth: &Image<Rgb>) -> parallax_core::Result<(f64, f64)> {
    let s = parallax_render::score::score(image, truth)?;
    Ok((s.psnr, s.ssim))
}

/// A tracer to compare, with what the comparison reports about it.
pub struct Contender<'a> {
    pub tracer: &'a dyn WorldTracer,
    /// Its build time (ms), reported as is.
    pub build_ms: f64,
    /// Its box, if it only covers part of the scene (classifies disagreements).
    pub bounds: Option<Aabb>,
}

/// One tracer on the reference's rays of one effect and bounce (`bounce` = -1: all bounces).
#[derive(Clone, Debug, Default, Serialize)]
pub struct EffectRow {
    pub method: String,
    pub effect: String,
    pub bounce: i32,
    pub rays: u64,
    pub agreement: f64,
    pub counts: Agreement,
    /// Best round's trace wall time (sum over the bounces for `bounce` = -1).
    pub ms_trace: f64,
    pub mrays_per_s: f64,
    pub nodes_per_ray: f64,
    pub tests_per_ray: f64,
    pub steps_per_ray: f64,
    pub pct_truncated: f64,
}

/// A set of rays with the reference's answers, labelled for the rows (an effect's name, or
/// a synthetic set's).
#[derive(Clone, Copy, Debug)]
pub struct RayBatch<'a> {
    pub label: &'a str,
    /// -1 when the set has no bounce.
    pub bounce: i32,
    pub rays: &'a [Ray],
    pub answers: &'a Answers,
}

impl<'a> From<&'a Batch> for RayBatch<'a> {
    fn from(b: &'a Batch) -> Self {
        Self {
            label: b.effect.name(),
            bounce: b.bounce as i32,
            rays: &b.rays,
            answers: &b.answers,
        }
    }
}

/// The answers and work of replaying `batch` through `tracer`.
fn replay_batch(tracer: &dyn WorldTracer, batch: &RayBatch) -> (Answers, WorldStats, f64) {
    match batch.answers {
        Answers::Closest(_) => {
            let (h, s, ms) = trace_closest(tracer, batch.rays);
            (Answers::Closest(h), s, ms)
        }
        Answers::Occluded(_) => {
            let (o, s, ms) = trace_occluded(tracer, batch.rays);
            (Answers::Occluded(o), s, ms)
        }
    }
}

fn agreement(
    batch: &RayBatch,
    other: &Answers,
    tolerance: f32,
    bounds: Option<&Aabb>,
) -> Agreement {
    match (batch.answers, other) {
        (Answers::Closest(r), Answers::Closest(o)) => agree_closest(r, o, tolerance, bounds),
        (Answers::Occluded(r), Answers::Occluded(o)) => agree_occluded(batch.rays, r, o, bounds),
        _ => unreachable!("a replay answers in the batch's kind"),
    }
}

fn row(method: &str, label: &str, bounce: i32, a: Agreement, s: WorldStats, ms: f64) -> EffectRow {
    let per = |c: u64| s.per_ray(c);
    EffectRow {
        method: method.to_string(),
        effect: label.to_string(),
        bounce,
        rays: a.rays,
        agreement: a.fraction(),
        counts: a,
        ms_trace: ms,
        mrays_per_s: if ms > 0.0 {
            a.rays as f64 / (ms * 1e3)
        } else {
            0.0
        },
        nodes_per_ray: per(s.nodes),
        tests_per_ray: per(s.tests),
        steps_per_ray: per(s.steps),
        pct_truncated: 100.0 * per(s.truncated),
    }
}

/// Replays the reference's `batches` through every contender (the reference tracer itself
/// included, for its times) in `repeats` interleaved rounds and returns one row per tracer,
/// label and bounce plus, for labels with bounces, one per tracer and label over all bounces
/// (`bounce = -1`); labels in order of first appearance.
pub fn replay_rows(
    batches: &[RayBatch],
    contenders: &[Contender],
    repeats: u32,
    tolerance: f32,
) -> Vec<EffectRow> {
    let repeats = repeats.max(1);
    let mut best = vec![vec![f64::INFINITY; batches.len()]; contenders.len()];
    // Scored in the last round (answers are the same in every round).
    let mut scored =
        vec![vec![(Agreement::default(), WorldStats::default()); batches.len()]; contenders.len()];
    for round in 0..repeats {
        for (ci, c) in contenders.iter().enumerate() {
            for (bi, b) in batches.iter().enumerate() {
                let (ans, stats, ms) = replay_batch(c.tracer, b);
                best[ci][bi] = best[ci][bi].min(ms);
                if round + 1 == repeats {
                    scored[ci][bi] = (agreement(b, &ans, tolerance, c.bounds.as_ref()), stats);
                }
            }
        }
    }
    let mut labels: Vec<&str> = Vec::new();
    for b in batches {
        if !labels.contains(&b.label) {
            labels.push(b.label);
        }
    }
    let mut rows = Vec::new();
    for (ci, c) in contenders.iter().enumerate() {
        let name = c.tracer.name();
        for &label in &labels {
            let mut total = (Agreement::default(), WorldStats::default(), 0.0);
            let mut parts = 0;
            for (bi, b) in batches.iter().enumerate().filter(|(_, b)| b.label == label) {
                let (a, stats) = scored[ci][bi];
                if b.bounce >= 0 {
                    rows.push(row(name, label, b.bounce, a, stats, best[ci][bi]));
                }
                total.0 += a;
                total.1 += stats;
                total.2 += best[ci][bi];
                parts += 1;
            }
            if parts > 0 {
                rows.push(row(name, label, -1, total.0, total.1, total.2));
            }
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use glam::{Vec2, Vec3};

    use super::*;

    fn hit(prim: u32, t: f32) -> Option<WorldHit> {
        let r = Ray::new(Vec3::ZERO, Vec3::X);
        Some(WorldHit::exact(&r, t, prim, Vec2::ZERO))
    }

    #[test]
    fn agreement_counts_each_case() {
        let rays = vec![Ray::new(Vec3::ZERO, Vec3::X); 5];
        let r = [hit(1, 1.0), hit(2, 2.0), hit(3, 3.0), None, None];
        let o = [hit(1, 5.0), hit(9, 2.0005), hit(4, 1.0), None, hit(5, 1.0)];
        let a = agree_closest(&r, &o, 1e-3, None);
        assert_eq!((a.rays, a.agree, a.both_miss), (5, 3, 1));
        assert_eq!((a.differ, a.early, a.only_other), (1, 1, 1));
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(2.5));
        let a = agree_closest(&r, &o, 1e-3, Some(&b));
        assert_eq!(a.outside, 1, "the reference hit at x = 3 is outside");
        let s = agree_occluded(&rays, &[true, false, true], &[true, true, false], None);
        assert_eq!((s.agree, s.only_other, s.only_reference), (1, 1, 1));
    }
}
