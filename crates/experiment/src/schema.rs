//! The experiment file: a TOML document that names a benchmark (`bench = "warp"`, one of the
//! `parallax bench` subcommands), its flags (`[args]`), a cartesian parameter sweep
//! (`[sweep]`), the subcommand that writes the point's images (`[images]`) and the output
//! folder. Parsing keeps every key's line, so later checks (unknown flag, wrong value type,
//! empty sweep) name the file, the line, the key and what was expected.
//!
//! Invariants: a parsed [`Experiment`] has a non-empty `bench`, only scalar or
//! array-of-scalar values in `[args]` / `[images]`, and non-empty arrays in `[sweep]`; keys keep
//! the order of the file.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `title` | string | the file stem | heading of the report |
//! | `bench` | string | (required) | the `parallax bench` subcommand whose rows are the table |
//! | `out` | string | `out/experiments/<stem>` | output folder (`parallax run --out` overrides) |
//! | `max_points` | integer | 10 000 | refuse sweeps with more points |
//! | `[args]` | table | empty | flags of the bench (`width = 800` is `--width 800`) |
//! | `[sweep]` | table of arrays | empty | each key takes every value of its array; the points are the cartesian product |
//! | `[images]` | table | none | `command = "warp"` plus its own flags: the subcommand run once per point into the point's folder |

use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::{Spanned, Value};

use crate::error::ExperimentError;

/// Default [`Experiment::max_points`].
pub const DEFAULT_MAX_POINTS: u64 = 10_000;

/// One `key = value` of the file with the line it is on (1-based).
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    pub key: String,
    pub value: Value,
    pub line: usize,
}

/// A sweep axis: a key and its values, with the line of the key.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    pub key: String,
    pub values: Vec<Value>,
    pub line: usize,
}

/// The `[images]` table: the subcommand that writes a point's images and its own flags.
#[derive(Clone, Debug, PartialEq)]
pub struct Images {
    pub command: String,
    pub line: usize,
    pub args: Vec<Entry>,
}

/// A parsed experiment file.
#[derive(Clone, Debug, PartialEq)]
pub struct Experiment {
    /// The file it was read from (for messages; `<string>` when parsed from text).
    pub file: PathBuf,
    pub title: String,
    pub bench: String,
    pub bench_line: usize,
    pub out: PathBuf,
    pub max_points: u64,
    pub args: Vec<Entry>,
    pub sweep: Vec<Axis>,
    pub images: Option<Images>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawExperiment {
    title: Option<String>,
    bench: Spanned<String>,
    out: Option<String>,
    max_points: Option<Spanned<i64>>,
    #[serde(default)]
    args: std::collections::BTreeMap<String, Spanned<Value>>,
    #[serde(default)]
    sweep: std::collections::BTreeMap<String, Spanned<Value>>,
    images: Option<std::collections::BTreeMap<String, Spanned<Value>>>,
}

/// 1-based line of byte offset `at` in `text`.
pub fn line_of(text: &str, at: usize) -> usize {
    1 + text.as_bytes()[..at.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// The TOML type name of a value (for messages).
pub fn type_name(v: &Value) -> &'static str {
    match v {
        Value::String(_) => "string",
        Value::Integer(_) => "integer",
        Value::Float(_) => "float",
        Value::Boolean(_) => "boolean",
        Value::Datetime(_) => "datetime",
        Value::Array(_) => "array",
        Value::Table(_) => "table",
    }
}

fn is_scalar(v: &Value) -> bool {
    matches!(
        v,
        Value::String(_) | Value::Integer(_) | Value::Float(_) | Value::Boolean(_)
    )
}

impl Experiment {
    /// Reads and parses an experiment file.
    pub fn from_file(path: &Path) -> Result<Self, ExperimentError> {
        let text = std::fs::read_to_string(path).map_err(|e| ExperimentError::Io {
            path: path.to_path_buf(),
            source: e,
        })?;
        Self::parse(&text, path)
    }

    /// Parses the text of an experiment file; `file` names it in messages and gives the
    /// default title and output folder.
    pub fn parse(text: &str, file: &Path) -> Result<Self, ExperimentError> {
        let raw: RawExperiment = toml::from_str(text).map_err(|e| {
            let line = e.span().map_or(0, |s| line_of(text, s.start));
            ExperimentError::Syntax {
                file: file.to_path_buf(),
                line,
                message: e.message().to_string(),
            }
        })?;
        let at = |span: Range<usize>| line_of(text, span.start);
        let err = |line: usize, key: &str, message: String| ExperimentError::Key {
            file: file.to_path_buf(),
            line,
            key: key.to_string(),
            message,
        };
        let stem = file
            .file_stem()
            .map_or("experiment".into(), |s| s.to_string_lossy().into_owned());
        let bench_line = at(raw.bench.span());
        let bench = raw.bench.into_inner();
        if bench.trim().is_empty() {
            return Err(err(bench_line, "bench", "expected a bench name".into()));
        }
        let max_points = match raw.max_points {
            None => DEFAULT_MAX_POINTS,
            Some(m) => {
                let line = at(m.span());
                u64::try_from(*m.get_ref())
                    .ok()
                    .filter(|&n| n >= 1)
                    .ok_or_else(|| err(line, "max_points", "expected an integer >= 1".into()))?
            }
        };
        let entries = |table: std::collections::BTreeMap<String, Spanned<Value>>,
                       section: &str|
         -> Result<Vec<Entry>, ExperimentError> {
            let mut out = Vec::new();
            for (key, v) in table {
                let line = at(v.span());
                let value = v.into_inner();
                let ok = match &value {
                    Value::Array(items) => items.iter().all(is_scalar),
                    other => is_scalar(other),
                };
                if !ok {
                    return Err(err(
                        line,
                        &format!("{section}.{key}"),
                        format!(
                            "expected a string, number, boolean or array of them, got {}",
                            type_name(&value)
                        ),
                    ));
                }
                out.push(Entry { key, value, line });
            }
            out.sort_by_key(|e| e.line);
            Ok(out)
        };
        let args = entries(raw.args, "args")?;
        let mut sweep = Vec::new();
        for e in entries(raw.sweep, "sweep")? {
            let key = format!("sweep.{}", e.key);
            let Value::Array(values) = e.value else {
                return Err(err(
                    e.line,
                    &key,
                    format!("expected an array of values, got {}", type_name(&e.value)),
                ));
            };
            if values.is_empty() {
                return Err(err(
                    e.line,
                    &key,
                    "empty sweep: expected at least one value".into(),
                ));
            }
            if let Some(a) = args.iter().find(|a| a.key == e.key) {
                return Err(err(
                    e.line,
                    &key,
                    format!("also set in [args] at line {}", a.line),
                ));
            }
            sweep.push(Axis {
                key: e.key,
                values,
                line: e.line,
            });
        }
        let images = match raw.images {
            None => None,
            Some(t) => {
                let mut args = entries(t, "images")?;
                let Some(i) = args.iter().position(|e| e.key == "command") else {
                    return Err(err(
                        0,
                        "images.command",
                        "missing: expected the subcommand that writes the images, e.g. command = \"warp\"".into(),
                    ));
                };
                let c = args.remove(i);
                let Value::String(command) = c.value else {
                    return Err(err(
                        c.line,
                        "images.command",
                        format!("expected a string, got {}", type_name(&c.value)),
                    ));
                };
                Some(Images {
                    command,
                    line: c.line,
                    args,
                })
            }
        };
        Ok(Experiment {
            file: file.to_path_buf(),
            title: raw.title.unwrap_or_else(|| stem.clone()),
            bench,
            bench_line,
            out: raw
                .out
                .map_or_else(|| Path::new("out/experiments").join(&stem), PathBuf::from),
            max_points,
            args,
            sweep,
            images,
        })
    }

    /// An error about `key` on `line` of this file.
    pub fn key_error(&self, line: usize, key: &str, message: impl Into<String>) -> ExperimentError {
        ExperimentError::Key {
            file: self.file.clone(),
            line,
            key: key.to_string(),
            message: message.into(),
        }
    }
}
