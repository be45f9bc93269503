//! The DIRT build (§4.1): triangle setup and binning to screen bands, then per band (in
//! parallel, each band owning its cell rows) the conservative rasterization with per-cell
//! depth ranges (Fig. 6a), Fill Depth (§4.1.1) and the count / prefix-sum / fill of the
//! buckets (§4.1.2, eq. 1) (`fill`); finally the bands are copied into the flat CSR arrays
//! and the mip chain is built. Several views of one mesh (the camera view and the cube
//! faces of [`super::DirtViews`]) share one setup pass over the mesh ([`build_views`]); a
//! view's set-up triangles stay in the chunks the parallel setup made them in.
//!
//! **Parallel shape.** No stage runs view by view: binning is parallel over the views, the
//! fill over every band of every view in one loop, the assembly (the bands' arrays
//! concatenated) and the mip chain over the views, so a view's serial work overlaps the
//! others'. A band's
//! output does not depend on which thread fills it or when, so the capture is bit for bit the
//! same at any thread count.

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
    let caps = finish_views(
        mesh,
        std::slice::from_ref(view),
        opts,
        vec![grid],
        std::slice::from_ref(&xf),
        vec![setups],
        t_start,
    )?;
    Ok(caps.into_iter().next().expect("one view"))
}

/// The captures of several views of one mesh (the camera view and the cube map's faces),
/// with the triangle setup done in one pass over the mesh for all of them
/// ([`ViewXf::setup_all_views`]) and every later stage parallel over all views at once
/// ([`finish_views`]); `opts.max_entries` bounds the entries of all views together.
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
    finish_views(mesh, views, opts, grids, &xfs, setups, t_start)
}

/// One view's set-up triangles binned to its screen bands: band `b`'s keys (ascending, so
/// in triangle order) are `entries[band_start[b]..band_start[b + 1]]`.
struct Bins {
    band_start: Vec<u32>,
    entries: Vec<u32>,
    /// Set-up triangles whose clipped projection touches a cell row of the view.
    in_view: u64,
}

impl Bins {
    fn bands(&self) -> u32 {
        self.band_start.len() as u32 - 1
    }

    fn band(&self, b: u32) -> &[u32] {
        &self.entries
            [self.band_start[b as usize] as usize..self.band_start[b as usize + 1] as usize]
    }
}

/// Which bands each set-up triangle's clipped projection touches.
fn bin(setups: &Setups, grid: &Grid) -> Bins {
    let (s, cells_y, band_rows) = (grid.s, grid.cells_y, grid.band_rows);
    let bands = cells_y.div_ceil(band_rows);
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
    let mut entries = vec![0u32; band_start[bands as usize] as usize];
    let mut cursor = band_start.clone();
    for &(key, b0, b1) in &spans {
        for b in b0..=b1 {
            entries[cursor[b as usize] as usize] = key;
            cursor[b as usize] += 1;
        }
    }
    Bins {
        band_start,
        entries,
        in_view,
    }
}

/// `wall` ms split over the views in proportion to their measured `work` (evenly if none).
fn shares(wall: f64, work: &[f64]) -> Vec<f64> {
    let total: f64 = work.iter().sum();
    work.iter()
        .map(|&w| {
            if total > 0.0 {
                wall * w / total
            } else {
                wall / work.len() as f64
            }
        })
        .collect()
}

/// Binning, fill and assembly of every view from its set-up triangles (the setup started at
/// `t_start`). Binning is parallel over the views, the fill over every band of every view in
/// one loop (the camera view's bands first: they are the largest), the assembly and the mip
/// chain over the views. Each stage's wall time is split over the views in proportion to
/// their work in it (the setup's evenly), so the views' `total_ms` add up to the build's.
fn finish_views(
    mesh: &TriangleMesh,
    views: &[Pinhole],
    opts: &DirtOptions,
    grids: Vec<Grid>,
    xfs: &[ViewXf],
    setups: Vec<Setups>,
    t_start: Instant,
) -> Result<Vec<DirtCapture>, DirtError> {
    let nv = views.len();
    let setup_ms = ms(t_start);

    // 1. Binning: which bands each set-up triangle's clipped projection touches.
    let t_bin = Instant::now();
    let bins: Vec<(Bins, f64)> = setups
        .par_iter()
        .zip(&grids)
        .map(|(s, g)| {
            let t = Instant::now();
            let b = bin(s, g);
            (b, ms(t))
        })
        .collect();
    let bin_ms = shares(ms(t_bin), &bins.iter().map(|b| b.1).collect::<Vec<_>>());

    // 2. Per band of every view: clip, Fill Depth, count / prefix / fill; one entry budget
    // for all views.
    let t_fill = Instant::now();
    let budget = AtomicU64::new(0);
    let jobs: Vec<(usize, u32)> = bins
        .iter()
        .enumerate()
        .flat_map(|(v, (b, _))| (0..b.bands()).map(move |band| (v, band)))
        .collect();
    let outs: Vec<Result<(BandOut, f64), DirtError>> = jobs
        .par_iter()
        .map(|&(v, band)| {
            let t = Instant::now();
            let job = FillJob {
                setups: &setups[v],
                xf: &xfs[v],
                grid: &grids[v],
                opts,
                budget: &budget,
            };
            fill_band(&job, band, bins[v].0.band(band)).map(|o| (o, ms(t)))
        })
        .collect();
    let outs: Vec<(BandOut, f64)> = outs.into_iter().collect::<Result<_, _>>()?;
    let fill_wall = ms(t_fill);
    drop(setups);

    // 3. Per view (views in parallel): assemble the flat arrays, Mipmap Depth.
    let t_asm = Instant::now();
    let mut fill_work = vec![0.0; nv];
    let mut per_view: Vec<Vec<BandOut>> = (0..nv).map(|_| Vec::new()).collect();
    for ((v, _), (o, t)) in jobs.iter().zip(outs) {
        fill_work[*v] += t;
        per_view[*v].push(o);
    }
    let fill_ms = shares(fill_wall, &fill_work);
    let ntri = mesh.triangle_count() as u64;
    let caps: Vec<(DirtCapture, f64, f64)> = per_view
        .into_par_iter()
        .zip(views)
        .zip(&grids)
        .zip(&bins)
        .map(|(((outs, view), g), (bins, _))| {
            assemble_view(outs, view, g, opts, bins.in_view, ntri)
        })
        .collect();
    // The assembly and the mips ran together: their wall time split by their work.
    let asm_wall = ms(t_asm);
    let work: Vec<f64> = caps.iter().flat_map(|c| [c.1, c.2]).collect();
    let split = shares(asm_wall, &work);
    Ok(caps
        .into_iter()
        .enumerate()
        .map(|(v, (mut cap, _, _))| {
            let st = &mut cap.stats;
            st.setup_ms = setup_ms / nv as f64 + bin_ms[v];
            st.fill_ms = fill_ms[v];
            st.assemble_ms = split[2 * v];
            st.mip_ms = split[2 * v + 1];
            st.total_ms = st.setup_ms + st.fill_ms + st.assemble_ms + st.mip_ms;
            cap
        })
        .collect())
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// One view's capture from its bands' outputs (in band order): the flat CSR arrays, the
/// depth bounds and their mip chain, the counters (times left zero); with the assembly's and
/// the mips' thread time.
fn assemble_view(
    outs: Vec<BandOut>,
    view: &Pinhole,
    g: &Grid,
    opts: &DirtOptions,
    in_view: u64,
    ntri: u64,
) -> (DirtCapture, f64, f64) {
    let t = Instant::now();
    let cell_count = g.cells_x as usize * g.cells_y as usize;
    let entries: usize = outs.iter().map(|o| o.ids.len()).sum();
    let fragments: u64 = outs.iter().map(|o| o.fragments).sum();
    let (levels, texels) = mip::layout(g.cells_x, g.cells_y);
    let mut bounds = vec![mip::EMPTY; texels];
    let mut offsets = Vec::with_capacity(cell_count * g.buckets as usize + 1);
    let mut ids = Vec::with_capacity(entries);
    let mut cells = Vec::with_capacity(cell_count);
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
    let assemble = ms(t);
    let t = Instant::now();
    mip::build_chain(&levels, &mut bounds);
    let recip_bounds = mip::reciprocal(&bounds);
    let nonempty_cells = bounds[..cell_count]
        .iter()
        .filter(|z| z[0].is_finite())
        .count() as u64;
    let mut cap = DirtCapture {
        view: view.clone(),
        opts: *opts,
        cells_x: g.cells_x,
        cells_y: g.cells_y,
        offsets,
        ids,
        levels,
        bounds,
        recip_bounds,
        cells,
        stats: DirtStats {
            width: view.width,
            height: view.height,
            tile_size: g.s,
            buckets: g.buckets,
            cells_x: g.cells_x,
            cells_y: g.cells_y,
            triangles: ntri,
            triangles_in_view: in_view,
            fragments,
            entries: entries as u64,
            nonempty_cells,
            bytes: 0,
            setup_ms: 0.0,
            fill_ms: 0.0,
            assemble_ms: 0.0,
            mip_ms: 0.0,
            total_ms: 0.0,
        },
    };
    cap.stats.bytes = cap.bytes();
    (cap, assemble, ms(t))
}
