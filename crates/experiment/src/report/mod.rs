//! `parallax report`: one self-contained HTML page per set of results folders, and the image
//! gallery `parallax demo` leaves in its folder.
//!
//! Per experiment the page shows, for every sweep point, the result images; an image `X.png`
//! with a ground truth `X.bvh.png` beside it gets a wipe slider between the two and an error
//! heatmap with its colour scale ([`heatmap`]); `X.hits.png` (hit-type map: misses red,
//! occlusion volumes blue) and `X.heat.png` (work heatmap) are shown next to it. Then all rows
//! of all points as one sortable table (the point's sweep values as the first columns), and
//! plots ([`plot`]): quality vs time (PSNR over the time column of the table) and speed vs
//! parameter (Mrays/s and the ratio of the first method to each other one over the first
//! parameter that takes several values).
//!
//! Images are referenced beside the page (relative paths) when the page is in the results
//! folder, else inlined as base64 data URIs (`inline`), so the page never needs the network.
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `dirs` | folders | (required) | results folders of `parallax run` (each with `results.json`) |
//! | `page` | file | `DIR/index.html` for one folder | where the page goes |
//! | `inline` | bool | false | inline every image (always on when the page is elsewhere) |

mod gallery;
pub mod heatmap;
pub mod html;
pub mod plot;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use base64::Engine;
use serde_json::Value;

use crate::error::ExperimentError;
use crate::results::{RESULTS_FILE, RunResults, read_json};
use html::{Cell, esc};
use plot::{Series, plot_svg};

pub use gallery::{GalleryItem, write_captioned_gallery, write_gallery};

/// Columns tried, in order, as the time axis of "quality vs time".
pub const TIME_KEYS: [&str; 7] = [
    "ms_view",
    "ms_total",
    "ms_frame",
    "ms_amortized",
    "trace_ms",
    "ms",
    "seconds",
];
/// Columns tried, in order, as the series name of a row.
pub const SERIES_KEYS: [&str; 5] = ["method", "visibility", "tracer", "mode", "scheme"];
/// Row columns tried (after the sweep's own keys) as the parameter axis of "speed vs parameter".
pub const PARAM_KEYS: [&str; 6] = [
    "layers",
    "samples_per_pixel",
    "spp",
    "frames",
    "dda_max_steps",
    "aperture",
];

/// How image sources are written.
struct Sources {
    base: PathBuf,
    inline: bool,
    /// Where generated images go when not inlined (relative to `base`).
    generated: PathBuf,
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ExperimentError + '_ {
    move |source| ExperimentError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn data_uri(bytes: &[u8]) -> String {
    format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    )
}

impl Sources {
    fn file(&self, rel: &str) -> Result<String, ExperimentError> {
        if self.inline {
            let p = self.base.join(rel);
            Ok(data_uri(&std::fs::read(&p).map_err(io(&p))?))
        } else {
            Ok(rel.replace('\\', "/"))
        }
    }

    fn generated(&self, name: &str, bytes: &[u8]) -> Result<String, ExperimentError> {
        if self.inline {
            return Ok(data_uri(bytes));
        }
        let rel = self.generated.join(name);
        let p = self.base.join(&rel);
        if let Some(d) = p.parent() {
            std::fs::create_dir_all(d).map_err(io(d))?;
        }
        std::fs::write(&p, bytes).map_err(io(&p))?;
        Ok(rel.to_string_lossy().replace('\\', "/"))
    }
}

/// The figures of a list of image files (relative to `src.base`): see the module docs.
fn image_figures(images: &[String], src: &Sources, tag: &str) -> Result<String, ExperimentError> {
    let has = |s: &str| images.iter().any(|i| i == s);
    let mut out = String::from("<div class=\"grid\">");
    for img in images {
        let Some(stem) = img.strip_suffix(".png") else {
            continue;
        };
        let derived = [".bvh", ".hits", ".heat", ".error"]
            .iter()
            .any(|s| stem.ends_with(s) && has(&format!("{}.png", &stem[..stem.len() - s.len()])));
        if derived {
            continue;
        }
        let name = Path::new(stem)
            .file_name()
            .map_or(stem.to_string(), |n| n.to_string_lossy().into_owned());
        let truth = format!("{stem}.bvh.png");
        if has(&truth) {
            out += &truth_figures(img, &truth, &name, src, tag)?;
        } else {
            out += &html::figure(&src.file(img)?, &name);
        }
        for (suffix, what) in [
            (".hits.png", "hit types (red: miss, blue: occlusion volume)"),
            (".heat.png", "work per pixel"),
        ] {
            let f = format!("{stem}{suffix}");
            if has(&f) {
                out += &html::figure(&src.file(&f)?, &format!("{name}: {what}"));
            }
        }
    }
    Ok(out + "</div>")
}

/// A result beside its ground truth: the wipe slider between the two and the error heatmap
/// (written as `{tag}{name}.error.png`) with its colour scale.
fn truth_figures(
    img: &str,
    truth: &str,
    name: &str,
    src: &Sources,
    tag: &str,
) -> Result<String, ExperimentError> {
    let mut out = html::wipe(&src.file(img)?, &src.file(truth)?, name);
    let h = heatmap::error_heatmap(&src.base.join(img), &src.base.join(truth))?;
    let uri = src.generated(&format!("{tag}{name}.error.png"), &h.png)?;
    out += &format!(
        "<figure><img src=\"{}\" alt=\"error\"><figcaption>{}: |result - truth|, mean {:.2} / 255</figcaption>{}</figure>",
        esc(&uri),
        esc(name),
        h.mean_error,
        heatmap::scale_svg(h.scale_max)
    );
    Ok(out)
}

/// A row of the table with its point.
struct Row<'a> {
    point: usize,
    params: BTreeMap<&'a str, &'a Value>,
    fields: &'a serde_json::Map<String, Value>,
}

impl Row<'_> {
    fn get(&self, k: &str) -> Option<&Value> {
        self.fields.get(k).or_else(|| self.params.get(k).copied())
    }
    fn num(&self, k: &str) -> Option<f64> {
        self.get(k).and_then(Value::as_f64)
    }
    /// The series name: the first of [`SERIES_KEYS`], then `k=v` of each of `split`.
    fn series_in(&self, split: &[&str]) -> String {
        let mut name = SERIES_KEYS
            .iter()
            .find_map(|k| self.fields.get(*k).and_then(Value::as_str))
            .unwrap_or("rows")
            .to_string();
        for k in split {
            if let Some(v) = self.get(k) {
                name += &format!(" {k}={}", v.as_str().map_or(v.to_string(), str::to_string));
            }
        }
        name
    }
    fn series(&self) -> String {
        self.series_in(&[])
    }
    /// Every string field but the series name: rows that agree on it are comparable.
    fn context(&self, series_key: &str) -> Vec<(String, String)> {
        let mut v: Vec<(String, String)> = self
            .fields
            .iter()
            .filter(|(k, _)| {
                k.as_str() != series_key && k.as_str() != "note" && k.as_str() != "error"
            })
            .filter_map(|(k, x)| x.as_str().map(|s| (k.clone(), s.to_string())))
            .collect();
        v.push(("#point".into(), self.point.to_string()));
        v
    }
}

fn rows_of(r: &RunResults) -> Vec<Row<'_>> {
    let mut out = Vec::new();
    for p in &r.points {
        let params: BTreeMap<&str, &Value> = p
            .params
            .iter()
            .map(|q| (q.key.as_str(), &q.value))
            .collect();
        for row in p.rows.as_array().into_iter().flatten() {
            if let Some(fields) = row.as_object() {
                out.push(Row {
                    point: p.index,
                    params: params.clone(),
                    fields,
                });
            }
        }
    }
    out
}

/// Columns that split a plot's series when they take several values and are not its x axis.
const SPLIT_KEYS: [&str; 4] = ["layers", "samples_per_pixel", "shading", "scheme"];

fn distinct(rows: &[Row], k: &str) -> usize {
    let mut v: Vec<String> = rows
        .iter()
        .filter_map(|r| r.get(k).map(Value::to_string))
        .collect();
    v.sort();
    v.dedup();
    v.len()
}

fn group(rows: &[Row], x: &str, y: &str) -> Vec<Series> {
    let split: Vec<&str> = SPLIT_KEYS
        .iter()
        .copied()
        .filter(|k| *k != x && distinct(rows, k) >= 2)
        .collect();
    let mut series: Vec<Series> = Vec::new();
    for r in rows {
        let (Some(a), Some(b)) = (r.num(x), r.num(y)) else {
            continue;
        };
        let name = r.series_in(&split);
        match series.iter_mut().find(|s| s.name == name) {
            Some(s) => s.points.push((a, b)),
            None => series.push(Series {
                name,
                points: vec![(a, b)],
            }),
        }
    }
    series
}

/// The plots of one experiment (see the module docs).
fn plots(r: &RunResults, rows: &[Row]) -> Result<Vec<String>, ExperimentError> {
    let mut out = Vec::new();
    let has = |k: &str| rows.iter().any(|r| r.num(k).is_some());
    if let Some(t) = TIME_KEYS.iter().find(|k| has(k))
        && has("psnr")
    {
        out.extend(plot_svg(
            "quality vs time",
            t,
            "PSNR dB",
            &group(rows, t, "psnr"),
            false,
        )?);
    }
    let sweep_keys: Vec<&str> = r
        .points
        .first()
        .map(|p| p.params.iter().map(|q| q.key.as_str()).collect())
        .unwrap_or_default();
    let param = sweep_keys
        .iter()
        .copied()
        .chain(PARAM_KEYS)
        .find(|k| rows.iter().any(|r| r.num(k).is_some()) && distinct(rows, k) >= 2);
    let speed = ["mrays_per_s", "paths_per_s"].into_iter().find(|k| has(k));
    if let (Some(x), Some(y)) = (param, speed) {
        out.extend(plot_svg(
            &format!("{y} vs {x}"),
            x,
            y,
            &group(rows, x, y),
            true,
        )?);
        let series_key = SERIES_KEYS
            .iter()
            .find(|k| {
                rows.iter()
                    .any(|r| r.fields.get(**k).is_some_and(Value::is_string))
            })
            .copied()
            .unwrap_or("");
        let reference = rows.first().map(Row::series).unwrap_or_default();
        let mut ratios: Vec<Series> = Vec::new();
        for o in rows.iter().filter(|o| o.series() != reference) {
            let Some(base) = rows.iter().find(|b| {
                b.series() == reference
                    && b.num(x) == o.num(x)
                    && b.context(series_key) == o.context(series_key)
            }) else {
                continue;
            };
            let (Some(a), Some(b), Some(px)) = (base.num(y), o.num(y), o.num(x)) else {
                continue;
            };
            let split: Vec<&str> = SPLIT_KEYS
                .iter()
                .copied()
                .filter(|k| *k != x && distinct(rows, k) >= 2)
                .collect();
            let name = format!("{reference} / {}", o.series_in(&split));
            match ratios.iter_mut().find(|s| s.name == name) {
                Some(s) => s.points.push((px, a / b)),
                None => ratios.push(Series {
                    name,
                    points: vec![(px, a / b)],
                }),
            }
        }
        out.extend(plot_svg(
            &format!("speed ratio vs {x}"),
            x,
            &format!("{y} ratio"),
            &ratios,
            true,
        )?);
    }
    Ok(out)
}

/// The sortable table of every row.
fn rows_table(r: &RunResults, rows: &[Row]) -> String {
    let mut columns: Vec<String> = vec!["point".into()];
    if let Some(p) = r.points.first() {
        columns.extend(p.params.iter().map(|q| q.key.clone()));
    }
    let nparams = columns.len();
    // The series names (method, mode, ...) first, then the other scalar fields, then nested
    // ones (lists, records), each in first-seen order.
    for k in SERIES_KEYS {
        if rows.iter().any(|r| r.fields.contains_key(k)) && !columns.iter().any(|c| c == k) {
            columns.push(k.to_string());
        }
    }
    for nested in [false, true] {
        for row in rows {
            for (k, v) in row.fields {
                if (v.is_array() || v.is_object()) == nested && !columns.contains(k) {
                    columns.push(k.clone());
                }
            }
        }
    }
    let cells: Vec<Vec<Cell>> = rows
        .iter()
        .map(|row| {
            let mut c = vec![Cell::of(Some(&Value::from(row.point)))];
            for k in &columns[1..nparams] {
                c.push(Cell::of(row.params.get(k.as_str()).copied()));
            }
            for k in &columns[nparams..] {
                c.push(Cell::of(row.fields.get(k)));
            }
            c
        })
        .collect();
    html::table(&columns, &cells)
}

/// The section of one results folder and the experiment's title.
fn section(dir: &Path, src: &Sources) -> Result<(String, String), ExperimentError> {
    let r: RunResults = read_json(&dir.join(RESULTS_FILE))?;
    let rows = rows_of(&r);
    let mut s = format!(
        "<h2>{}</h2><p class=\"meta\">bench <code>{}</code>, experiment <code>{}</code>, {} point(s), {} row(s)</p>",
        esc(&r.title),
        esc(&r.bench),
        esc(&r.experiment),
        r.points.len(),
        rows.len()
    );
    let figs = plots(&r, &rows)?;
    if !figs.is_empty() {
        s += "<div class=\"grid\">";
        for f in figs {
            s += &format!("<figure class=\"plot\">{f}</figure>");
        }
        s += "</div>";
    }
    s += "<h3>rows</h3>";
    s += &rows_table(&r, &rows);
    for p in &r.points {
        let params: Vec<String> = p
            .params
            .iter()
            .map(|q| format!("{} = {}", q.key, q.value))
            .collect();
        s += &format!(
            "<h3>point {}{}</h3><p class=\"meta\"><code>parallax bench {}</code></p>",
            p.index,
            if params.is_empty() {
                String::new()
            } else {
                format!(": {}", esc(&params.join(", ")))
            },
            esc(&p.bench_args.join(" "))
        );
        for (k, v) in &p.extra {
            if let Some(obj) = v.as_object() {
                let cols: Vec<String> = obj.keys().cloned().collect();
                let row: Vec<Cell> = obj.values().map(|x| Cell::of(Some(x))).collect();
                s += &format!(
                    "<p class=\"meta\">{}</p>{}",
                    esc(k),
                    html::table(&cols, &[row])
                );
            }
        }
        if !p.images.is_empty() {
            s += &image_figures(&p.images, src, &format!("p{:04}-", p.index))?;
        }
    }
    Ok((s, r.title))
}

fn same_dir(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

/// Writes the report of `dirs` to `page` (default: `DIR/index.html` of a single folder);
/// returns the page's path.
pub fn write_report(
    dirs: &[PathBuf],
    page: Option<&Path>,
    inline: bool,
) -> Result<PathBuf, ExperimentError> {
    let page = match (page, dirs) {
        (Some(p), _) => p.to_path_buf(),
        (None, [d]) => d.join("index.html"),
        (None, []) => return Err(ExperimentError::Report("no results folder given".into())),
        (None, _) => {
            return Err(ExperimentError::Report(
                "several results folders: give the page with --out".into(),
            ));
        }
    };
    let page_dir = page
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(page_dir).map_err(io(page_dir))?;
    let mut body = String::new();
    let mut titles = Vec::new();
    for d in dirs {
        let src = Sources {
            base: d.clone(),
            inline: inline || !same_dir(d, page_dir),
            generated: PathBuf::from("report"),
        };
        let (text, title) = section(d, &src)?;
        body += &text;
        titles.push(title);
    }
    let title = format!("parallax report: {}", titles.join(", "));
    std::fs::write(&page, html::page(&title, &body)).map_err(io(&page))?;
    Ok(page)
}
