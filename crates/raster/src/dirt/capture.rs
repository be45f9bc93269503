//! The capture's types (options, errors, stats, the per-cell record and the capture itself),
//! the bucket arithmetic shared with the tracer, and read access to a built capture (the
//! module docs of [`super`] describe the structure; the build is in `build.rs`).

use super::mip::{LevelInfo, MipLevel};
use parallax_scene::camera::Pinhole;
use serde::Serialize;

/// Film-space margin (pixels) added on every side of a cell before clipping.
pub const FILM_MARGIN_PX: f64 = 1.0 / 256.0;
/// Largest allowed tile size.
pub const MAX_TILE_SIZE: u32 = 1 << 12;
/// Largest allowed bucket count.
pub const MAX_BUCKETS: u32 = 1024;
/// Largest allowed `cells * buckets` (size of the offsets array).
pub const MAX_CELL_BUCKETS: u64 = 1 << 28;

/// How the depth range of a triangle in a cell is computed (module docs of `fill`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum CellDepth {
    /// The triangle's depth plane over the cell's corners, cut to its range in the cell row:
    /// O(1) per cell, exact inside the triangle, wider at its edges.
    #[default]
    Corners,
    /// The exact range over the triangle clipped to the cell (the slow twin).
    Exact,
}

/// Build options (see the module table).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DirtOptions {
    pub tile_size: u32,
    pub buckets: u32,
    pub near: f32,
    pub max_entries: u64,
    pub cell_depth: CellDepth,
}

impl Default for DirtOptions {
    fn default() -> Self {
        Self {
            tile_size: 1,
            buckets: 8,
            near: 1e-4,
            max_entries: 1 << 28,
            cell_depth: CellDepth::Corners,
        }
    }
}

/// Why a capture could not be built.
#[derive(Debug, thiserror::Error)]
pub enum DirtError {
    #[error("invalid DIRT option: {0}")]
    InvalidOptions(String),
    #[error("invalid view for DIRT capture: {0}")]
    InvalidView(String),
    #[error("DIRT capture too large: more than {max} list entries (max_entries)")]
    TooLarge { max: u64 },
}

/// What a build did (counts and per-stage wall times).
#[derive(Clone, Debug, Default, Serialize)]
pub struct DirtStats {
    pub width: u32,
    pub height: u32,
    pub tile_size: u32,
    pub buckets: u32,
    pub cells_x: u32,
    pub cells_y: u32,
    /// Triangles in the mesh.
    pub triangles: u64,
    /// Triangles with a non-empty clipped projection (overlapping the view).
    pub triangles_in_view: u64,
    /// Cell-triangle pairs (clipped primitive samples `n_p`).
    pub fragments: u64,
    /// Id entries over all buckets (`c * n_p`).
    pub entries: u64,
    /// Cells with at least one triangle.
    pub nonempty_cells: u64,
    pub bytes: u64,
    /// Triangle setup (transform, near/guard clip, projection) and the rasterization right
    /// after it (cells and depth ranges of every triangle, kept per screen band). Views built
    /// together (`DirtViews`) share this stage: each is billed its wall time in proportion to
    /// the view's fragments.
    pub setup_ms: f64,
    /// Depth bounds and bucket fill (parallel over bands).
    pub fill_ms: f64,
    /// Concatenating the bands into the flat arrays.
    pub assemble_ms: f64,
    pub mip_ms: f64,
    pub total_ms: f64,
}

/// One view's DIRT acceleration structure (depth bounds + mip chain + id buffer).
#[derive(Clone, Debug)]
pub struct DirtCapture {
    pub(super) view: Pinhole,
    pub(super) opts: DirtOptions,
    pub(super) cells_x: u32,
    pub(super) cells_y: u32,
    pub(super) offsets: Vec<u32>,
    pub(super) ids: Vec<u32>,
    pub(super) levels: Vec<LevelInfo>,
    /// `[zmin, zmax]` of every texel of every mip level.
    pub(super) bounds: Vec<[f32; 2]>,
    /// `bounds` as reciprocal depths `[1 / max, 1 / min]` ([`super::mip::reciprocal`]).
    pub(super) recip_bounds: Vec<[f32; 2]>,
    /// What the tracer reads of every cell at once.
    pub(super) cells: Vec<CellRecord>,
    pub(super) stats: DirtStats,
}

/// `1 / (zmax - zmin) * B` of a cell, 0 when the range is empty or degenerate.
#[inline]
pub fn bucket_scale(zmin: f32, zmax: f32, buckets: u32) -> f32 {
    let range = zmax - zmin;
    if range > 0.0 && range.is_finite() {
        buckets as f32 / range
    } else {
        0.0
    }
}

/// DIRT eq. 1: `floor(B * (z - zmin) / (zmax - zmin))`, clamped to `[0, B - 1]`, as
/// `(z - zmin) * scale` with `scale` from [`bucket_scale`]. Monotone non-decreasing in `z`
/// (each f32 step is), so a depth inside a triangle's clipped range maps between the
/// triangle's `b_min` and `b_max`.
#[inline]
pub fn bucket_index(zmin: f32, scale: f32, buckets: u32, z: f32) -> u32 {
    let v = (z - zmin) * scale;
    if v > 0.0 {
        (v as u32).min(buckets - 1)
    } else {
        0
    }
}

/// The bits of buckets `b0..=b1` of `buckets` in a cell's non-empty mask: bit `b` for bucket
/// `b` when `buckets <= 32`, else bit `i` for buckets `i * g .. (i + 1) * g` with
/// `g = ceil(buckets / 32)`.
#[inline(always)]
pub fn bucket_mask(b0: u32, b1: u32, buckets: u32) -> u32 {
    let upto = |b: u32| if b >= 31 { u32::MAX } else { (2u32 << b) - 1 };
    if buckets <= 32 {
        // One bit per bucket (no integer division on the tracer's path).
        return upto(b1) & !(upto(b0) >> 1);
    }
    let g = buckets.div_ceil(32);
    let (lo, hi) = (b0 / g, b1 / g);
    upto(hi) & !(upto(lo) >> 1)
}

/// A cell as the tracer reads it, in one 16-byte load: its depth bounds, the eq. 1 scale
/// [`bucket_scale`] of its range and the mask of its non-empty buckets ([`bucket_mask`]; the
/// GPU version reads a bucket's null head pointer instead).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct CellRecord {
    pub zmin: f32,
    pub zmax: f32,
    pub scale: f32,
    pub mask: u32,
}

impl DirtCapture {
    pub fn view(&self) -> &Pinhole {
        &self.view
    }
    pub fn options(&self) -> &DirtOptions {
        &self.opts
    }
    pub fn tile_size(&self) -> u32 {
        self.opts.tile_size
    }
    pub fn buckets(&self) -> u32 {
        self.opts.buckets
    }
    /// Cell grid size `(ceil(W / S), ceil(H / S))`.
    pub fn cells(&self) -> (u32, u32) {
        (self.cells_x, self.cells_y)
    }
    /// The cell containing film position `film` (pixels), if on the film; the right/bottom
    /// film border belongs to the last cell.
    pub fn cell_of_film(&self, film: glam::Vec2) -> Option<(u32, u32)> {
        let (w, h) = (self.view.width as f32, self.view.height as f32);
        if !(film.x >= 0.0 && film.y >= 0.0 && film.x <= w && film.y <= h) {
            return None;
        }
        let s = self.opts.tile_size as f32;
        let cx = ((film.x / s) as u32).min(self.cells_x - 1);
        let cy = ((film.y / s) as u32).min(self.cells_y - 1);
        Some((cx, cy))
    }
    /// The film rectangle `[x0, x1] x [y0, y1]` (pixels) of cell `(cx, cy)`.
    pub fn cell_rect(&self, cx: u32, cy: u32) -> [f32; 4] {
        let s = self.opts.tile_size;
        [
            (cx * s) as f32,
            (cy * s) as f32,
            ((cx + 1) * s).min(self.view.width) as f32,
            ((cy + 1) * s).min(self.view.height) as f32,
        ]
    }
    #[inline]
    fn cell_index(&self, cx: u32, cy: u32) -> usize {
        assert!(
            cx < self.cells_x && cy < self.cells_y,
            "cell ({cx}, {cy}) outside the grid"
        );
        cy as usize * self.cells_x as usize + cx as usize
    }
    /// `(zmin, zmax)` of cell `(cx, cy)` over all its triangles' clipped parts (`(+inf, -inf)`
    /// if empty).
    pub fn depth_bounds(&self, cx: u32, cy: u32) -> (f32, f32) {
        let [lo, hi] = self.bounds[self.cell_index(cx, cy)];
        (lo, hi)
    }
    /// The bucket of view depth `z` in cell `(cx, cy)` (DIRT eq. 1, clamped).
    pub fn bucket_of(&self, cx: u32, cy: u32, z: f32) -> u32 {
        let (lo, hi) = self.depth_bounds(cx, cy);
        bucket_index(
            lo,
            bucket_scale(lo, hi, self.opts.buckets),
            self.opts.buckets,
            z,
        )
    }
    /// Nominal depth interval `[zmin + b r / B, zmin + (b + 1) r / B]` of bucket `b`.
    pub fn bucket_range(&self, cx: u32, cy: u32, b: u32) -> (f32, f32) {
        let (lo, hi) = self.depth_bounds(cx, cy);
        let step = (hi - lo) / self.opts.buckets as f32;
        (lo + b as f32 * step, lo + (b + 1) as f32 * step)
    }
    /// Triangle ids in bucket `b` of cell `(cx, cy)` (ascending).
    pub fn bucket(&self, cx: u32, cy: u32, b: u32) -> &[u32] {
        assert!(b < self.opts.buckets, "bucket {b} out of range");
        let k = self.cell_index(cx, cy) * self.opts.buckets as usize + b as usize;
        &self.ids[self.offsets[k] as usize..self.offsets[k + 1] as usize]
    }
    /// All entries of cell `(cx, cy)`, bucket after bucket (a triangle spanning several buckets
    /// appears once per bucket).
    pub fn cell_entries(&self, cx: u32, cy: u32) -> &[u32] {
        let b = self.opts.buckets as usize;
        let k = self.cell_index(cx, cy) * b;
        &self.ids[self.offsets[k] as usize..self.offsets[k + b] as usize]
    }
    /// The distinct triangle ids of cell `(cx, cy)`, sorted (allocates; for tests and tools).
    pub fn pixel_triangles(&self, cx: u32, cy: u32) -> Vec<u32> {
        let mut v = self.cell_entries(cx, cy).to_vec();
        v.sort_unstable();
        v.dedup();
        v
    }
    /// Number of mip levels (down to 1 x 1).
    pub fn mip_levels(&self) -> usize {
        self.levels.len()
    }
    /// Mip level `level` of the depth bounds (level 0 = per cell).
    pub fn mip(&self, level: usize) -> MipLevel<'_> {
        let l = self.levels[level];
        let n = l.width as usize * l.height as usize;
        MipLevel {
            width: l.width,
            height: l.height,
            bounds: &self.bounds[l.offset..l.offset + n],
        }
    }
    /// The whole mip chain as flat arrays: the level table and `[min, max]` of every texel of
    /// every level (level `k` at `levels[k].offset`, row-major).
    pub fn mip_arrays(&self) -> (&[LevelInfo], &[[f32; 2]]) {
        (&self.levels, &self.bounds)
    }
    /// The mip chain as reciprocal depth bounds `[1 / max, 1 / min]` (widened outward; layout
    /// of [`Self::mip_arrays`]): what the tracer's walk reads.
    pub fn recip_mip(&self) -> &[[f32; 2]] {
        &self.recip_bounds
    }
    /// Per cell (row-major), its [`CellRecord`].
    pub fn cell_records(&self) -> &[CellRecord] {
        &self.cells
    }
    /// CSR offsets, `cells * B + 1` entries: bucket `b` of cell `c` is
    /// `ids[offsets[c * B + b]..offsets[c * B + b + 1]]`.
    pub fn offsets(&self) -> &[u32] {
        &self.offsets
    }
    /// All list entries (scene triangle indices).
    pub fn ids(&self) -> &[u32] {
        &self.ids
    }
    /// Bytes held by the flat arrays (offsets, ids, mip bounds and their reciprocals, cell
    /// records, level table).
    pub fn bytes(&self) -> u64 {
        (std::mem::size_of_val(self.offsets.as_slice())
            + std::mem::size_of_val(self.ids.as_slice())
            + std::mem::size_of_val(self.bounds.as_slice())
            + std::mem::size_of_val(self.recip_bounds.as_slice())
            + std::mem::size_of_val(self.cells.as_slice())
            + std::mem::size_of_val(self.levels.as_slice())) as u64
    }
    pub fn stats(&self) -> &DirtStats {
        &self.stats
    }
}
