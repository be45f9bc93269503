//! One screen band of the DIRT build: conservative rasterization of its triangles into its
//! cells with each cell-triangle pair's view-depth range (DIRT Fig. 6a), "Fill Depth" (§4.1.1)
//! and "Fill Primitives" (§4.1.2, eq. 1) as count / prefix sum / fill.
//!
//! **Coverage.** For each cell row the triangle's projection touches, the polygon is cut to the
//! row's slab (widened by [`FILM_MARGIN_PX`]); every cell column in the x range of that cut
//! (widened too) overlaps the triangle, because the cut is convex.
//!
//! **Depth range of a cell** (`w = 1 / depth`). The default, [`CellDepth::Corners`]: the range
//! of the triangle's `w` plane over the cell's (widened) rectangle — its corners — intersected
//! with the exact range over the row's cut; exact for cells inside the triangle, and a
//! superset of the exact range at its edges, in O(1) per cell. [`CellDepth::Exact`], the slow
//! twin: the exact range over the triangle cut to the cell (Sutherland-Hodgman's vertex set).
//! Both are widened by a relative `2^-16` and the triangle's absolute margin (module docs of
//! `dirt`).

use std::sync::atomic::{AtomicU64, Ordering};

use parallax_scene::TriangleMesh;

use super::setup::{TriSetup, ViewXf};
use super::{
    CellDepth, CellRecord, DirtError, DirtOptions, FILM_MARGIN_PX, bucket_index, bucket_mask,
    bucket_scale,
};

/// Relative margin on a clipped depth range.
const DEPTH_REL_MARGIN: f64 = 1.0 / 65536.0;

/// One cell-triangle pair with the (widened) view-depth range.
#[derive(Clone, Copy)]
pub(super) struct Fragment {
    cell: u32,
    tri: u32,
    zlo: f32,
    zhi: f32,
}

/// The cell grid and its split into bands of whole cell rows.
pub(super) struct Grid {
    pub s: u32,
    pub cells_x: u32,
    pub cells_y: u32,
    pub buckets: u32,
    pub band_rows: u32,
}

impl Grid {
    /// Cells a film interval `[v0, v1]` (widened by the margin) can touch, clamped to
    /// `[lo, hi)`.
    #[inline]
    pub fn span(v0: f64, v1: f64, s: u32, lo: u32, hi: u32) -> Option<(u32, u32)> {
        let m = FILM_MARGIN_PX;
        let a = ((v0 - m) / s as f64).floor() - 1.0;
        let b = ((v1 + m) / s as f64).floor();
        let a = a.max(lo as f64);
        let b = b.min(hi as f64 - 1.0);
        (a <= b).then_some((a as u32, b as u32))
    }
}

/// A band's share of the result.
pub(super) struct BandOut {
    /// `[zmin, zmax]` per cell.
    pub bounds: Vec<[f32; 2]>,
    pub cells: Vec<CellRecord>,
    /// Local exclusive prefix sums, `cells * B + 1`.
    pub offsets: Vec<u32>,
    pub ids: Vec<u32>,
    pub fragments: u64,
}

/// Widens `[zlo, zhi]` by the margins and rounds outward to f32.
#[inline]
fn widen(zlo: f64, zhi: f64, abs_margin: f64) -> (f32, f32) {
    let lo = zlo * (1.0 - DEPTH_REL_MARGIN) - abs_margin;
    let hi = zhi * (1.0 + DEPTH_REL_MARGIN) + abs_margin;
    let (mut l, mut h) = (lo as f32, hi as f32);
    if (l as f64) > lo {
        l = l.next_down();
    }
    if (h as f64) < hi {
        h = h.next_up();
    }
    (l.max(0.0), h)
}

/// The `w` range of a set-up triangle over cell column `[left, right]` of a row whose slab
/// `[top, bottom]` cuts the triangle to `row` (`(min, max)` of its vertices).
#[inline(always)]
fn cell_w_range(
    tri: &TriSetup,
    row_w: (f64, f64),
    (left, right): (f64, f64),
    (top, bottom): (f64, f64),
) -> (f64, f64) {
    let Some(p) = tri.plane else {
        return row_w;
    };
    let (ax, bx) = (p.px * left, p.px * right);
    let (ay, by) = (p.py * top, p.py * bottom);
    let lo = (p.p0 + ax.min(bx) + ay.min(by)).max(row_w.0);
    let hi = (p.p0 + ax.max(bx) + ay.max(by)).min(row_w.1);
    if lo <= hi { (lo, hi) } else { row_w }
}

/// Rasterizes the band's triangles (ascending ids) into its cells.
#[allow(clippy::too_many_arguments)]
pub(super) fn fill_band(
    mesh: &TriangleMesh,
    xf: &ViewXf,
    g: &Grid,
    opts: &DirtOptions,
    band: u32,
    tris: &[u32],
    frags: &mut Vec<Fragment>,
    budget: &AtomicU64,
) -> Result<BandOut, DirtError> {
    frags.clear();
    let m = FILM_MARGIN_PX;
    let s = g.s as f64;
    let row0 = band * g.band_rows;
    let row1 = (row0 + g.band_rows).min(g.cells_y);
    let ncells = ((row1 - row0) * g.cells_x) as usize;
    let mut zmin = vec![f32::INFINITY; ncells];
    let mut zmax = vec![f32::NEG_INFINITY; ncells];
    for &t in tris {
        let Some(tri) = xf.setup(mesh, t as usize) else {
            continue;
        };
        let before = frags.len();
        let Some((y0, y1)) = tri.poly.range(1) else {
            continue;
        };
        let Some((r0, r1)) = Grid::span(y0, y1, g.s, row0, row1) else {
            continue;
        };
        for r in r0..=r1 {
            let top = r as f64 * s - m;
            let bottom = ((r as f64 + 1.0) * s).min(xf.h) + m;
            let Some((lo, hi)) = tri.poly.span_in_slab(1, top, bottom) else {
                continue;
            };
            let Some((c0, c1)) = Grid::span(lo.x, hi.x, g.s, 0, g.cells_x) else {
                continue;
            };
            let row_poly = match opts.cell_depth {
                CellDepth::Exact => {
                    Some(tri.poly.clip_axis(1, top, 1.0).clip_axis(1, bottom, -1.0))
                }
                CellDepth::Corners => None,
            };
            for c in c0..=c1 {
                let left = c as f64 * s - m;
                let right = ((c as f64 + 1.0) * s).min(xf.w) + m;
                // The cut is convex: the column overlaps it iff it overlaps its x range.
                if right < lo.x || left > hi.x {
                    continue;
                }
                let (wlo, whi) = match &row_poly {
                    Some(rp) => match rp.z_range_in_strip(left, right) {
                        Some(r) => r,
                        None => continue,
                    },
                    None => cell_w_range(&tri, (lo.z, hi.z), (left, right), (top, bottom)),
                };
                // w = 1 / depth > 0 after the near clip.
                let (zlo, zhi) = widen(1.0 / whi, 1.0 / wlo, tri.abs_margin);
                let cell = (r - row0) * g.cells_x + c;
                // Fill Depth (§4.1.1).
                let k = cell as usize;
                zmin[k] = zmin[k].min(zlo);
                zmax[k] = zmax[k].max(zhi);
                frags.push(Fragment {
                    cell,
                    tri: t,
                    zlo,
                    zhi,
                });
            }
        }
        let added = (frags.len() - before) as u64;
        if budget.fetch_add(added, Ordering::Relaxed) + added > opts.max_entries {
            return Err(DirtError::TooLarge {
                max: opts.max_entries,
            });
        }
    }

    // Fill Primitives (§4.1.2): count per bucket (eq. 1a/1b), prefix sum, fill.
    let nb = g.buckets as usize;
    let scale: Vec<f32> = (0..ncells)
        .map(|c| bucket_scale(zmin[c], zmax[c], g.buckets))
        .collect();
    let brange = |f: &Fragment| {
        let c = f.cell as usize;
        (
            bucket_index(zmin[c], scale[c], g.buckets, f.zlo) as usize,
            bucket_index(zmin[c], scale[c], g.buckets, f.zhi) as usize,
        )
    };
    let mut offsets = vec![0u32; ncells * nb + 1];
    let mut total = 0u64;
    for f in frags.iter() {
        let (b0, b1) = brange(f);
        let base = f.cell as usize * nb;
        for o in &mut offsets[base + b0 + 1..=base + b1 + 1] {
            *o += 1;
        }
        total += (b1 - b0 + 1) as u64;
    }
    // Entries beyond fragments (triangles in several buckets) count against the budget too.
    let extra = total - frags.len() as u64;
    if budget.fetch_add(extra, Ordering::Relaxed) + extra > opts.max_entries {
        return Err(DirtError::TooLarge {
            max: opts.max_entries,
        });
    }
    let cells = (0..ncells)
        .map(|c| {
            let counts = &offsets[c * nb + 1..(c + 1) * nb + 1];
            let mask = counts
                .iter()
                .enumerate()
                .filter(|&(_, &n)| n > 0)
                .fold(0, |m, (b, _)| {
                    m | bucket_mask(b as u32, b as u32, g.buckets)
                });
            CellRecord {
                zmin: zmin[c],
                zmax: zmax[c],
                scale: scale[c],
                mask,
            }
        })
        .collect();
    for k in 0..ncells * nb {
        offsets[k + 1] += offsets[k];
    }
    let mut cursor = offsets.clone();
    let mut ids = vec![0u32; total as usize];
    for f in frags.iter() {
        let (b0, b1) = brange(f);
        let base = f.cell as usize * nb;
        for cur in &mut cursor[base + b0..=base + b1] {
            ids[*cur as usize] = f.tri;
            *cur += 1;
        }
    }
    Ok(BandOut {
        bounds: zmin.into_iter().zip(zmax).map(|(a, b)| [a, b]).collect(),
        cells,
        offsets,
        ids,
        fragments: frags.len() as u64,
    })
}
