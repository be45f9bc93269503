//! The DIRT build (§4.1): each triangle is set up (transform, near / guard clip,
//! projection, `w` plane: `setup`) and rasterized right after, while the set-up triangle is
//! in registers (conservative rasterization with per-cell depth ranges, Fig. 6a: `fill`),
//! in parallel chunks of the mesh, each chunk's fragments kept per view and per screen band;
//! then per band (in parallel, each band owning its cell rows, reading its fragments chunk
//! by chunk) Fill Depth (§4.1.1) and the count / prefix-sum / fill of the buckets (§4.1.2,
//! eq. 1); finally the bands are copied into the flat CSR arrays and the mip chain is
//! built. Several views of one mesh (the camera view and the cube faces of
//! [`super::DirtViews`]) share one setup pass over the mesh ([`build_views`]).
//!
//! **Parallel shape.** No stage runs view by view: the setup and rasterization are parallel
//! over chunks of the mesh (every view of a triangle in turn), the band fill over every band
//! of every view in one loop, the assembly (the bands' arrays concatenated) and the mip chain
//! over the views, so a view's serial work overlaps the others'. Within a band the fragments
//! are in triangle order (chunks in mesh order, each chunk's in triangle order), as a serial
//! build makes them, so a band's output does not depend on which thread fills it or when:
//! the capture is bit for bit the same at any thread count.

use std::sync::atomic::AtomicU64;
use std::time::Instant;

use parallax_scene::TriangleMesh;
use parallax_scene::camera::Pinhole;
use rayon::prelude::*;

use super::capture::{
    DirtCapture, DirtError, DirtOptions, DirtStats, MAX_BUCKETS, MAX_CELL_BUCKETS, MAX_TILE_SIZE,
};
use super::cull::FaceCull;
use super::fill::{
    BILL_EVERY, BandOut, FillJob, Grid, RawFrag, ViewFrags, bill, fill_band, raster,
};
use super::mip;
use super::setup::{SETUP_CHUNK, ViewXf};

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
    let caps = build_views(mesh, std::slice::from_ref(view), opts, &[opts.tile_size])?;
    Ok(caps.into_iter().next().expect("one view"))
}

/// The captures of several views of one mesh (the camera view and the cube map's faces):
/// the triangle setup and rasterization in one pass over the mesh for all of them
/// ([`setup_and_raster`]), then every later stage parallel over all views at once;
/// `opts.max_entries` bounds the entries of all views together. View `k` is built with tile
/// size `tiles[k]` (the other options are `opts`' for every view).
pub(super) fn build_views(
    mesh: &TriangleMesh,
    views: &[Pinhole],
    opts: &DirtOptions,
    tiles: &[u32],
) -> Result<Vec<DirtCapture>, DirtError> {
    build_views_isa(mesh, views, opts, tiles, wide_available())
}

/// Whether the CPU runs the build's AVX-512 copies ([`parallax_core::cpu::x86_64_v4`]): the
/// setup and rasterization of a chunk ([`chunk_frags_v4`]) and the fill of a band
/// ([`super::fill::fill_band_v4`]) compiled a second time with the x86-64-v4 features. Same
/// captures bit for bit: the same IEEE operations (Rust contracts nothing into FMA); what
/// changes is the instructions, e.g. one `vcvttss2usi` for a float-to-unsigned cast. Tested
/// by `wide_build_equals_the_baseline`; measured in `docs/notes/dirt.md` (2026-12-06).
pub(super) fn wide_available() -> bool {
    parallax_core::cpu::x86_64_v4()
}

/// [`build_views`] with the AVX-512 copies of the hot stages (`wide`, only where
/// [`wide_available`]) or without.
fn build_views_isa(
    mesh: &TriangleMesh,
    views: &[Pinhole],
    opts: &DirtOptions,
    tiles: &[u32],
    wide: bool,
) -> Result<Vec<DirtCapture>, DirtError> {
    debug_assert!(!wide || wide_available());
    let t_start = Instant::now();
    assert_eq!(views.len(), tiles.len(), "one tile size per view");
    let grids = views
        .iter()
        .zip(tiles)
        .map(|(v, &s)| {
            grid(
                v,
                &DirtOptions {
                    tile_size: s,
                    ..*opts
                },
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    let xfs: Vec<ViewXf> = views
        .iter()
        .map(|v| ViewXf::new(v, opts.near as f64))
        .collect();
    let budget = AtomicU64::new(0);
    let frags = setup_and_raster(mesh, &xfs, &grids, opts, &budget, wide)?;
    finish_views(mesh, views, opts, &grids, frags, &budget, t_start, wide)
}

thread_local! {
    /// Each worker's per-view, per-band fragment buffers of a chunk (no allocation once warm).
    static RAW: std::cell::RefCell<Vec<Vec<Vec<RawFrag>>>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// Every triangle of `mesh` set up and rasterized for each view right after its setup (the
/// set-up triangle never leaves the registers and the stack), in parallel chunks of
/// [`SETUP_CHUNK`] triangles; per view, its chunks' fragments grouped by band
/// (`out[view][chunk]`). The fragments are billed to `budget` as they are made.
fn setup_and_raster(
    mesh: &TriangleMesh,
    xfs: &[ViewXf],
    grids: &[Grid],
    opts: &DirtOptions,
    budget: &AtomicU64,
    wide: bool,
) -> Result<Vec<Vec<ViewFrags>>, DirtError> {
    let n = mesh.triangle_count();
    let same_eye = ViewXf::same_eyes(xfs);
    let cull = FaceCull::new(&xfs.iter().map(ViewXf::axis_view).collect::<Vec<_>>());
    let ctx = ChunkCtx {
        mesh,
        xfs,
        same_eye: &same_eye,
        cull: cull.as_ref(),
        grids,
        opts,
        budget,
    };
    let chunks: Vec<Result<Vec<ViewFrags>, DirtError>> = (0..n.div_ceil(SETUP_CHUNK))
        .into_par_iter()
        .map(|c| {
            #[cfg(target_arch = "x86_64")]
            if wide {
                // SAFETY: `wide` only where the CPU has the features (`build_views_isa`).
                return unsafe { chunk_frags_v4(&ctx, c) };
            }
            let _ = wide;
            chunk_frags(&ctx, c)
        })
        .collect();
    let mut per_view: Vec<Vec<ViewFrags>> = xfs.iter().map(|_| Vec::new()).collect();
    for chunk in chunks {
        for (v, f) in per_view.iter_mut().zip(chunk?) {
            v.push(f);
        }
    }
    Ok(per_view)
}

/// What every chunk of [`setup_and_raster`] reads.
struct ChunkCtx<'a> {
    mesh: &'a TriangleMesh,
    xfs: &'a [ViewXf],
    same_eye: &'a [bool],
    cull: Option<&'a FaceCull>,
    grids: &'a [Grid],
    opts: &'a DirtOptions,
    budget: &'a AtomicU64,
}

/// The body of [`chunk_frags`] and [`chunk_frags_v4`]: a macro, so that its closures (the
/// rasterization callback holds the hot code) are written inside each function and the
/// AVX-512 copy's closures inherit its target features (a closure written in a function
/// without them would stay one shared, baseline copy).
macro_rules! chunk_frags_body {
    ($x:ident, $c:ident) => {{
        let x: &ChunkCtx = $x;
        let c: usize = $c;
        let (xfs, grids, opts) = (x.xfs, x.grids, x.opts);
        let n = x.mesh.triangle_count();
        RAW.with_borrow_mut(|raw| {
            raw.resize_with(xfs.len(), Vec::new);
            for (r, g) in raw.iter_mut().zip(grids) {
                r.resize_with(g.bands() as usize, Vec::new);
                r.iter_mut().for_each(Vec::clear);
            }
            let mut in_view = vec![0u64; xfs.len()];
            let mut unbilled = 0u64;
            let range = c * SETUP_CHUNK..((c + 1) * SETUP_CHUNK).min(n);
            ViewXf::setup_range(xfs, x.same_eye, x.cull, x.mesh, range, |v, e, poly| {
                let out = &mut raw[v];
                if let Some(n) = raster(e, poly, &grids[v], &xfs[v], opts.cell_depth, out) {
                    in_view[v] += 1;
                    unbilled += n as u64;
                }
                if unbilled >= BILL_EVERY {
                    bill(x.budget, &mut unbilled, opts.max_entries)?;
                }
                Ok(())
            })?;
            bill(x.budget, &mut unbilled, opts.max_entries)?;
            Ok(raw
                .iter()
                .zip(grids)
                .zip(in_view)
                .map(|((r, _), iv)| ViewFrags::concat(&r[..], iv))
                .collect())
        })
    }};
}

/// The fragments of chunk `c` ([`SETUP_CHUNK`] triangles) for every view, grouped by band.
fn chunk_frags(x: &ChunkCtx, c: usize) -> Result<Vec<ViewFrags>, DirtError> {
    chunk_frags_body!(x, c)
}

/// [`chunk_frags`] compiled with the x86-64-v4 features ([`wide_available`]).
///
/// # Safety
/// The CPU must have them ([`wide_available`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(
    enable = "avx512f,avx512vl,avx512bw,avx512dq,avx2,fma,bmi1,bmi2,lzcnt,popcnt,f16c"
)]
unsafe fn chunk_frags_v4(x: &ChunkCtx, c: usize) -> Result<Vec<ViewFrags>, DirtError> {
    chunk_frags_body!(x, c)
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

/// Fill and assembly of every view from its rasterized fragments (the setup and
/// rasterization started at `t_start`). The fill is one parallel loop over every band of
/// every view (the camera view's bands first: they are the largest), the assembly and the
/// mip chain run over the views in parallel. Each stage's wall time is split over the views
/// in proportion to their work in it (the setup and rasterization's by the views' fragments),
/// so the views' `total_ms` add up to the build's.
#[allow(clippy::too_many_arguments)]
fn finish_views(
    mesh: &TriangleMesh,
    views: &[Pinhole],
    opts: &DirtOptions,
    grids: &[Grid],
    frags: Vec<Vec<ViewFrags>>,
    budget: &AtomicU64,
    t_start: Instant,
    wide: bool,
) -> Result<Vec<DirtCapture>, DirtError> {
    let nv = views.len();
    let setup_ms = ms(t_start);

    // Per band of every view: Fill Depth, count / prefix / fill.
    let t_fill = Instant::now();
    let jobs: Vec<(usize, u32)> = grids
        .iter()
        .enumerate()
        .flat_map(|(v, g)| (0..g.bands()).map(move |band| (v, band)))
        .collect();
    let outs: Vec<Result<(BandOut, f64), DirtError>> = jobs
        .par_iter()
        .map(|&(v, band)| {
            let t = Instant::now();
            let job = FillJob {
                chunks: &frags[v],
                grid: &grids[v],
                opts,
                budget,
            };
            #[cfg(target_arch = "x86_64")]
            if wide {
                // SAFETY: `wide` only where the CPU has the features (`build_views_isa`).
                return unsafe { super::fill::fill_band_v4(&job, band) }.map(|o| (o, ms(t)));
            }
            fill_band(&job, band).map(|o| (o, ms(t)))
        })
        .collect();
    let outs: Vec<(BandOut, f64)> = outs.into_iter().collect::<Result<_, _>>()?;
    let fill_wall = ms(t_fill);
    let in_view: Vec<u64> = frags
        .iter()
        .map(|v| v.iter().map(|c| c.in_view).sum())
        .collect();
    // The setup and rasterization ran for all views at once: their wall time split by each
    // view's fragments (the rasterization's output, most of its work).
    let frag_work: Vec<f64> = frags
        .iter()
        .map(|v| v.iter().map(|c| c.frags.len() as f64).sum())
        .collect();
    let setup_ms = shares(setup_ms, &frag_work);
    drop(frags);

    // Per view (views in parallel): assemble the flat arrays, Mipmap Depth.
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
        .zip(grids)
        .zip(&in_view)
        .map(|(((outs, view), g), &in_view)| {
            let opts = DirtOptions {
                tile_size: g.s,
                ..*opts
            };
            assemble_view(outs, view, g, &opts, in_view, ntri)
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
            st.setup_ms = setup_ms[v];
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

#[cfg(test)]
mod tests {
    use parallax_scene::Scene;
    use parallax_scene::camera::CubeMap;

    use super::*;

    /// The captures' arrays, as text (f32 `Debug` round-trips every value, NaN included).
    fn arrays(caps: &[DirtCapture]) -> Vec<String> {
        caps.iter()
            .map(|c| {
                format!(
                    "{} {} {:?} {:?} {:?} {:?} {:?} {:?}",
                    c.cells_x,
                    c.cells_y,
                    c.offsets,
                    c.ids,
                    c.levels,
                    c.bounds,
                    c.recip_bounds,
                    c.cells
                )
            })
            .collect()
    }

    /// The build with the AVX-512 copies of its hot stages (where the CPU has them) makes the
    /// same captures as the build without: the camera view and the six cube faces of the
    /// atrium and of the foliage scene (thin, slanted triangles), two tile sizes.
    #[test]
    fn wide_build_equals_the_baseline() {
        if !wide_available() {
            eprintln!("no AVX-512: nothing to compare");
            return;
        }
        let mut entries = 0;
        for name in ["atrium", "foliage"] {
            let scene = Scene::load(name).unwrap();
            let desc = scene.camera(None).unwrap();
            let cube = CubeMap::new(&desc, 48).unwrap();
            let mut views = vec![Pinhole::new(&desc, 160, 96).unwrap()];
            views.extend((0..6).map(|i| cube.face_camera(i)));
            for tile in [1, 4] {
                let opts = DirtOptions {
                    tile_size: tile,
                    buckets: 8,
                    ..DirtOptions::default()
                };
                let tiles = vec![tile; views.len()];
                let base = build_views_isa(&scene.mesh, &views, &opts, &tiles, false).unwrap();
                let wide = build_views_isa(&scene.mesh, &views, &opts, &tiles, true).unwrap();
                assert_eq!(arrays(&base), arrays(&wide), "{name}, S = {tile}");
                entries += base.iter().map(|c| c.ids.len()).sum::<usize>();
            }
        }
        assert!(entries > 10_000, "{entries} list entries compared");
    }
}
