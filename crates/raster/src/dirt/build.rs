//! The DIRT build (§4.1): triangle setup and binning to screen bands, then per band (in
//! parallel, each band owning its cell rows) the conservative rasterization with per-cell
//! depth ranges (Fig. 6a), Fill Depth (§4.1.1) and the count / prefix-sum / fill of the
//! buckets (§4.1.2, eq. 1) (`fill`); finally the bands are concatenated into the flat CSR
//! arrays and the mip chain is built. Several views of one mesh (the camera view and the cube
//! faces of [`super::DirtViews`]) share one setup pass over the mesh ([`build_views`]); a
//! view's set-up triangles stay in the chunks the parallel setup made them in.

use std::sync::atomic::AtomicU64;
use std::time::Instant;

use parallax_scene::TriangleMesh;
use parallax_scene::camera::Pinhole;
use rayon::prelude::*;

use super::capture::{
    DirtCapture, DirtError, DirtOptions, DirtStats, MAX_BUCKETS, MAX_CELL_BUCKETS, MAX_TILE_SIZE,
};
use super::fill::{BandOut, FillJob, Grid, fill_band};
use super::mip;
use super::setup::{Setups, ViewXf};

/// Target number of screen bands (a band = whole cell rows, so bands concatenate in order).
const TARGET_BANDS: u32 = 64;

fn validate(view: &Pinhole, opts: &DirtOptions) -> Result<(), DirtError> {
    let bad = |s: String| Err(DirtError::InvalidOptions(s));
    if !opts.tile_size.is_power_of_two() || opts.tile_size > MAX_TILE_SIZE {
        return bad(format!(
            "tile_size {} must be a power of two in 1..={MAX_TILE_SIZE}",
            opts.tile_size
        ));
    }
    if opts.buckets == 0 || opts.buckets > MAX_BUCKETS {
        return bad(format!(
            "buckets {} must be in 1..={MAX_BUCKETS}",
            opts.buckets
        ));
    }
    if !(opts.near.is_finite() && opts.near > 0.0) {
        return bad(format!("near {} must be finite and > 0", opts.near));
    }
    if opts.max_entries == 0 || opts.max_entries >= u32::MAX as u64 {
        return bad(format!(
            "max_entries {} must be in 1..2^32-1",
            opts.max_entries
        ));
    }
    parallax_core::image::check_size(view.width, view.height)
        .map_err(|e| DirtError::InvalidView(e.to_string()))?;
    let f = &view.frame;
    let finite = view.tan_half_y.is_finite()
        && view.tan_half_y > 0.0
        && view.tan_half_x().is_finite()
        && view.shift.is_finite()
        && f.position.is_finite()
        && f.basis.is_finite();
    if !finite {
        return Err(DirtError::InvalidView(
            "camera frame, field of view and shift must be finite, tan_half_y > 0".into(),
        ));
    }
    Ok(())
}

/// The cell grid of `view` (checked against the size limits).
fn grid(view: &Pinhole, opts: &DirtOptions) -> Result<Grid, DirtError> {
    validate(view, opts)?;
    let s = opts.tile_size;
    let cells_x = view.width.div_ceil(s);
    let cells_y = view.height.div_ceil(s);
    let cell_count = cells_x as u64 * cells_y as u64;
    if cell_count * opts.buckets as u64 > MAX_CELL_BUCKETS {
        return Err(DirtError::InvalidOptions(format!(
            "{cell_count} cells x {} buckets exceeds {MAX_CELL_BUCKETS}",
            opts.buckets
        )));
    }
    Ok(Grid {
        s,
        cells_x,
        cells_y,
        buckets: opts.buckets,
        band_rows: cells_y.div_ceil(TARGET_BANDS).max(1),
    })
}

impl DirtCapture {
    /// Builds the capture of `mesh` seen by `view` (DIRT §4.1: Fill Depth, Mipmap Depth,
    /// Fill Primitives).
    pub fn build(
        mesh: &parallax_scene::TriangleMesh,
        view: &Pinhole,
        opts: &DirtOptions,
    ) -> Result<DirtCapture, DirtError> {
        build(mesh, view, opts)
    }
}

pub(super) fn build(
    mesh: &TriangleMesh,
    view: &Pinhole,
    opts: &DirtOptions,
) -> Result<DirtCapture, DirtError> {
    let t_start = Instant::now();
    let grid = grid(view, opts)?;
    let xf = ViewXf::new(view, opts.near as f64);
    let setups = xf.setup_all(mesh);
    finish(mesh, view, opts, grid, &xf, setups, ms(t_start))
}

/// The captures of several views of one mesh (the cube map's faces), with the triangle setup
/// done in one pass over the mesh for all of them ([`ViewXf::setup_all_views`]); each face's
/// entry budget is what the faces before it left of `opts.max_entries`.
pub(super) fn build_views(
    mesh: &TriangleMesh,
    views: &[Pinhole],
    opts: &DirtOptions,
) -> Result<Vec<DirtCapture>, DirtError> {
    let t_start = Instant::now();
    let grids = views
        .iter()
        .map(|v| grid(v, opts))
        .collect::<Result<Vec<_>, _>>()?;
    let xfs: Vec<ViewXf> = views
        .iter()
        .map(|v| ViewXf::new(v, opts.near as f64))
        .collect();
    let setups = ViewXf::setup_all_views(&xfs, mesh);
    let setup_ms = ms(t_start) / views.len().max(1) as f64;
    let mut left = opts.max_entries;
    let mut out = Vec::with_capacity(views.len());
    for (((view, grid), xf), setups) in views.iter().zip(grids).zip(&xfs).zip(setups) {
        let face_opts = DirtOptions {
            max_entries: left.max(1),
            ..*opts
        };
        let cap = finish(mesh, view, &face_opts, grid, xf, setups, setup_ms)?;
        left = left.saturating_sub(cap.stats.entries);
        out.push(cap);
    }
    Ok(out)
}

/// Binning, fill and assembly of one view from its set-up triangles (`setup_before` ms were
/// spent setting them up).
#[allow(clippy::too_many_arguments)]
fn finish(
    mesh: &TriangleMesh,
    view: &Pinhole,
    opts: &DirtOptions,
    grid: Grid,
    xf: &ViewXf,
    setups: Setups,
    setup_before: f64,
) -> Result<DirtCapture, DirtError> {
    let t_start = Instant::now();
    let (s, cells_x, cells_y, band_rows) = (grid.s, grid.cells_x, grid.cells_y, grid.band_rows);
    let cell_count = cells_x as u64 * cells_y as u64;
    let bands = cells_y.div_ceil(band_rows);
    let ntri = mesh.triangle_count();

    // 1. Binning: which bands each set-up triangle's clipped projection touches.
    let t_bin = Instant::now();
    let spans: Vec<(u32, u32, u32)> = setups
        .iter()
        .map(|(key, e)| {
            Grid::span(e.y.0, e.y.1, s, 0, cells_y).map_or((key, 1, 0), |(r0, r1)| {
                (key, r0 / band_rows, r1 / band_rows)
            })
        })
        .collect();
    let mut band_start = vec![0u32; bands as usize + 1];
    let mut in_view = 0u64;
    for &(_, b0, b1) in &spans {
        if b0 <= b1 {
            in_view += 1;
            for b in b0..=b1 {
                band_start[b as usize + 1] += 1;
            }
        }
    }
    for b in 0..bands as usize {
        band_start[b + 1] += band_start[b];
    }
    let mut band_entries = vec![0u32; band_start[bands as usize] as usize];
    let mut cursor = band_start.clone();
    for &(key, b0, b1) in &spans {
        for b in b0..=b1 {
            band_entries[cursor[b as usize] as usize] = key;
            cursor[b as usize] += 1;
        }
    }
    drop(spans);
    let setup_ms = setup_before + ms(t_bin);

    // 2. Per band: clip, Fill Depth, count / prefix / fill.
    let t_fill = Instant::now();
    let budget = AtomicU64::new(0);
    let job = FillJob {
        setups: &setups,
        xf,
        grid: &grid,
        opts,
        budget: &budget,
    };
    let outs: Vec<Result<BandOut, DirtError>> = (0..bands)
        .into_par_iter()
        .map(|band| {
            let entries = &band_entries
                [band_start[band as usize] as usize..band_start[band as usize + 1] as usize];
            fill_band(&job, band, entries)
        })
        .collect();
    let outs: Vec<BandOut> = outs.into_iter().collect::<Result<_, _>>()?;
    let fill_ms = ms(t_fill);

    // 3. Assemble the flat arrays.
    let t_asm = Instant::now();
    let entries: u64 = outs.iter().map(|o| o.ids.len() as u64).sum();
    let fragments: u64 = outs.iter().map(|o| o.fragments).sum();
    let (levels, texels) = mip::layout(cells_x, cells_y);
    let mut bounds = vec![mip::EMPTY; texels];
    let nb = opts.buckets as usize;
    let mut offsets = Vec::with_capacity(cell_count as usize * nb + 1);
    let mut ids = Vec::with_capacity(entries as usize);
    let mut cells = Vec::with_capacity(cell_count as usize);
    let mut cell0 = 0usize;
    for o in &outs {
        let base = ids.len() as u32;
        offsets.extend(o.offsets[..o.offsets.len() - 1].iter().map(|&x| x + base));
        ids.extend_from_slice(&o.ids);
        for (b, c) in bounds[cell0..cell0 + o.cells.len()]
            .iter_mut()
            .zip(&o.cells)
        {
            *b = [c.zmin, c.zmax];
        }
        cells.extend_from_slice(&o.cells);
        cell0 += o.cells.len();
    }
    offsets.push(ids.len() as u32);
    drop(outs);
    let assemble_ms = ms(t_asm);

    // 4. Mipmap Depth.
    let t_mip = Instant::now();
    mip::build_chain(&levels, &mut bounds);
    let recip_bounds = mip::reciprocal(&bounds);
    let mip_ms = ms(t_mip);

    let nonempty_cells = bounds[..cell_count as usize]
        .iter()
        .filter(|z| z[0].is_finite())
        .count() as u64;
    let mut cap = DirtCapture {
        view: view.clone(),
        opts: *opts,
        cells_x,
        cells_y,
        offsets,
        ids,
        levels,
        bounds,
        recip_bounds,
        cells,
        stats: DirtStats {
            width: view.width,
            height: view.height,
            tile_size: s,
            buckets: opts.buckets,
            cells_x,
            cells_y,
            triangles: ntri as u64,
            triangles_in_view: in_view,
            fragments,
            entries,
            nonempty_cells,
            bytes: 0,
            setup_ms,
            fill_ms,
            assemble_ms,
            mip_ms,
            total_ms: 0.0,
        },
    };
    cap.stats.bytes = cap.bytes();
    cap.stats.total_ms = setup_before + ms(t_start);
    Ok(cap)
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
