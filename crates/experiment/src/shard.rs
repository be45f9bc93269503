//! Which part of a long job this process runs: `--shard I/N` (0-based I < N), else a cluster
//! scheduler's array index from the environment: Slurm job arrays (`SLURM_ARRAY_TASK_ID`,
//! minus `SLURM_ARRAY_TASK_MIN` when set, of `SLURM_ARRAY_TASK_COUNT` tasks) or Kubernetes
//! Indexed Jobs (`JOB_COMPLETION_INDEX`; the count comes from `--shard-count`, the Job's
//! `completions`). The flag wins over the environment; Slurm over Kubernetes.
//!
//! Invariants: `index < count`, `count >= 1`; [`Shard::items`] and [`Shard::block`] split
//! `0..total` into `count` disjoint parts whose union is `0..total`, whatever the total.
//!
//! | input | type | meaning |
//! |---|---|---|
//! | `--shard I/N` | string | run part I of N |
//! | `--shard-count N` | integer | the N of an environment index without its own count |
//! | `SLURM_ARRAY_TASK_ID`, `SLURM_ARRAY_TASK_MIN`, `SLURM_ARRAY_TASK_COUNT` | env | Slurm job array |
//! | `JOB_COMPLETION_INDEX` | env | Kubernetes Indexed Job |

use std::ops::Range;

use serde::{Deserialize, Serialize};

use crate::error::ExperimentError;

/// Part `index` of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

/// Largest accepted shard count (a guard against typos such as `--shard 0/1000000000`).
pub const MAX_SHARDS: usize = 1_000_000;

fn bad(msg: String) -> ExperimentError {
    ExperimentError::Shard(msg)
}

fn number(what: &str, s: &str) -> Result<usize, ExperimentError> {
    s.trim()
        .parse::<usize>()
        .map_err(|_| bad(format!("{what} must be a non-negative integer, got {s:?}")))
}

impl Shard {
    /// A checked shard.
    pub fn new(index: usize, count: usize) -> Result<Self, ExperimentError> {
        if count == 0 || count > MAX_SHARDS {
            return Err(bad(format!(
                "shard count must be in 1..={MAX_SHARDS}, got {count}"
            )));
        }
        if index >= count {
            return Err(bad(format!(
                "shard index {index} out of range for {count} shards (indices are 0..{count})"
            )));
        }
        Ok(Shard { index, count })
    }

    /// Parses `I/N`.
    pub fn parse(s: &str) -> Result<Self, ExperimentError> {
        let Some((i, n)) = s.split_once('/') else {
            return Err(bad(format!("expected I/N (e.g. 0/4), got {s:?}")));
        };
        Shard::new(number("shard index", i)?, number("shard count", n)?)
    }

    /// The shard of this process: `flag` (`--shard`), else the scheduler's environment read
    /// through `env`, else `None` (run everything).
    pub fn resolve(
        flag: Option<&str>,
        count_flag: Option<usize>,
        env: impl Fn(&str) -> Option<String>,
    ) -> Result<Option<Self>, ExperimentError> {
        if let Some(f) = flag {
            let s = Shard::parse(f)?;
            if let Some(c) = count_flag.filter(|&c| c != s.count) {
                return Err(bad(format!("--shard {f} disagrees with --shard-count {c}")));
            }
            return Ok(Some(s));
        }
        if let Some(id) = env("SLURM_ARRAY_TASK_ID") {
            let id = number("SLURM_ARRAY_TASK_ID", &id)?;
            let min = match env("SLURM_ARRAY_TASK_MIN") {
                Some(m) => number("SLURM_ARRAY_TASK_MIN", &m)?,
                None => 0,
            };
            let index = id.checked_sub(min).ok_or_else(|| {
                bad(format!(
                    "SLURM_ARRAY_TASK_ID {id} below SLURM_ARRAY_TASK_MIN {min}"
                ))
            })?;
            let count = match (env("SLURM_ARRAY_TASK_COUNT"), count_flag) {
                (_, Some(c)) => c,
                (Some(c), None) => number("SLURM_ARRAY_TASK_COUNT", &c)?,
                (None, None) => {
                    return Err(bad(
                        "SLURM_ARRAY_TASK_ID is set but neither SLURM_ARRAY_TASK_COUNT nor --shard-count".into(),
                    ));
                }
            };
            return Shard::new(index, count).map(Some);
        }
        if let Some(i) = env("JOB_COMPLETION_INDEX") {
            let index = number("JOB_COMPLETION_INDEX", &i)?;
            let Some(count) = count_flag else {
                return Err(bad(
                    "JOB_COMPLETION_INDEX is set: give the Job's completions as --shard-count"
                        .into(),
                ));
            };
            return Shard::new(index, count).map(Some);
        }
        Ok(None)
    }

    /// [`Shard::resolve`] over the process environment.
    pub fn from_flags(
        flag: Option<&str>,
        count_flag: Option<usize>,
    ) -> Result<Option<Self>, ExperimentError> {
        Shard::resolve(flag, count_flag, |k| std::env::var(k).ok())
    }

    /// Round-robin part of `0..total`: the items `i` with `i % count == index`.
    pub fn items(&self, total: usize) -> Vec<usize> {
        (self.index..total).step_by(self.count).collect()
    }

    /// Contiguous part of `0..total`: the `index`-th of `count` near-equal blocks.
    pub fn block(&self, total: usize) -> Range<usize> {
        let at = |k: usize| (k as u128 * total as u128 / self.count as u128) as usize;
        at(self.index)..at(self.index + 1)
    }

    /// `I-of-N`, for file names.
    pub fn tag(&self) -> String {
        format!("{}-of-{}", self.index, self.count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(pairs: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |k| pairs.iter().find(|p| p.0 == k).map(|p| p.1.to_string())
    }

    #[test]
    fn parse_and_reject() {
        assert_eq!(Shard::parse("1/4").unwrap(), Shard { index: 1, count: 4 });
        for s in ["4/4", "0/0", "x/2", "1", "-1/2", "0/2000000000"] {
            assert!(Shard::parse(s).is_err(), "{s}");
        }
    }

    #[test]
    fn environment_order() {
        let e = env(&[
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("JOB_COMPLETION_INDEX", "0"),
        ]);
        assert_eq!(
            Shard::resolve(None, None, &e).unwrap(),
            Some(Shard { index: 2, count: 4 })
        );
        assert_eq!(
            Shard::resolve(Some("0/2"), None, &e).unwrap(),
            Some(Shard { index: 0, count: 2 })
        );
        let k = env(&[("JOB_COMPLETION_INDEX", "2")]);
        assert!(Shard::resolve(None, None, &k).is_err());
        assert_eq!(
            Shard::resolve(None, Some(3), &k).unwrap(),
            Some(Shard { index: 2, count: 3 })
        );
        assert_eq!(Shard::resolve(None, Some(3), env(&[])).unwrap(), None);
    }

    #[test]
    fn parts_cover_exactly() {
        for total in [0, 1, 5, 17] {
            for count in 1..6 {
                let mut seen = vec![0; total];
                let mut blocks = vec![0; total];
                for index in 0..count {
                    let s = Shard::new(index, count).unwrap();
                    s.items(total).iter().for_each(|&i| seen[i] += 1);
                    s.block(total).for_each(|i| blocks[i] += 1);
                }
                assert!(
                    seen.iter().chain(&blocks).all(|&c| c == 1),
                    "{total} {count}"
                );
            }
        }
    }
}
