//! Sweep expansion: the cartesian product of the `[sweep]` axes, in file order with the last
//! axis varying fastest, numbered from 0, and the translation of a key and value to the flags
//! of a subcommand (`width = 800` -> `--width=800`, `dda_sweep = [200, 400]` ->
//! `--dda-sweep=200,400`, `ssaa = true` -> `--ssaa`, `false` -> nothing).
//!
//! Invariants: the point count is computed with checked arithmetic and compared with
//! `max_points` before any point is built, so a sweep of 10^9 points is an error, not an
//! allocation; point `i` is the same point in every run (sharding relies on it).

use serde::Serialize;
use toml::Value;

use crate::error::ExperimentError;
use crate::schema::{Entry, Experiment};

/// One point of the sweep: its index and the value of every axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    pub index: usize,
    pub params: Vec<Entry>,
}

/// A parameter of a point as written into the results (`key`, value as JSON).
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Param {
    pub key: String,
    pub value: serde_json::Value,
}

impl Point {
    /// The parameters as JSON pairs.
    pub fn json_params(&self) -> Vec<Param> {
        self.params
            .iter()
            .map(|e| Param {
                key: e.key.clone(),
                value: to_json(&e.value),
            })
            .collect()
    }
}

/// A TOML scalar or array as JSON (datetimes and tables, which the schema rejects, as strings).
pub fn to_json(v: &Value) -> serde_json::Value {
    match v {
        Value::String(s) => s.clone().into(),
        Value::Integer(i) => (*i).into(),
        Value::Float(f) => serde_json::Number::from_f64(*f)
            .map_or(serde_json::Value::Null, serde_json::Value::Number),
        Value::Boolean(b) => (*b).into(),
        Value::Array(a) => a.iter().map(to_json).collect(),
        other => other.to_string().into(),
    }
}

/// The command-line text of a scalar.
fn scalar_text(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Float(f) => format!("{f}"),
        other => other.to_string(),
    }
}

/// The flag name of a key: `dda_max_steps` -> `dda-max-steps`.
pub fn flag_name(key: &str) -> String {
    key.replace('_', "-")
}

/// The flags of one `key = value` (see the module docs).
pub fn flag_args(e: &Entry) -> Vec<String> {
    let flag = flag_name(&e.key);
    match &e.value {
        Value::Boolean(true) => vec![format!("--{flag}")],
        Value::Boolean(false) => vec![],
        Value::Array(items) => {
            let list: Vec<String> = items.iter().map(scalar_text).collect();
            vec![format!("--{flag}={}", list.join(","))]
        }
        v => vec![format!("--{flag}={}", scalar_text(v))],
    }
}

impl Experiment {
    /// The number of sweep points (1 without a sweep), or an error above `max_points`.
    pub fn point_count(&self) -> Result<usize, ExperimentError> {
        let mut n: u64 = 1;
        for a in &self.sweep {
            n = n.saturating_mul(a.values.len() as u64);
        }
        if n > self.max_points {
            let axes: Vec<String> = self
                .sweep
                .iter()
                .map(|a| format!("{} ({} values, line {})", a.key, a.values.len(), a.line))
                .collect();
            return Err(ExperimentError::TooManyPoints {
                file: self.file.clone(),
                points: n,
                max: self.max_points,
                axes: axes.join(" x "),
            });
        }
        Ok(n as usize)
    }

    /// Every point of the sweep, in index order.
    pub fn points(&self) -> Result<Vec<Point>, ExperimentError> {
        let n = self.point_count()?;
        Ok((0..n).map(|i| self.point(i)).collect())
    }

    /// Point `index` (< [`Self::point_count`]): mixed-radix digits of the index, last axis
    /// fastest.
    pub fn point(&self, index: usize) -> Point {
        let mut rest = index;
        let mut params = vec![None; self.sweep.len()];
        for (k, a) in self.sweep.iter().enumerate().rev() {
            let d = rest % a.values.len();
            rest /= a.values.len();
            params[k] = Some(Entry {
                key: a.key.clone(),
                value: a.values[d].clone(),
                line: a.line,
            });
        }
        Point {
            index,
            params: params.into_iter().flatten().collect(),
        }
    }

    /// The `[args]` entries followed by the point's sweep entries.
    pub fn entries_of<'a>(&'a self, p: &'a Point) -> impl Iterator<Item = &'a Entry> {
        self.args.iter().chain(p.params.iter())
    }
}
