//! The DIRT build (§4.1): triangle setup and binning to screen bands, then per band (in
//! parallel, each band owning its cell rows) the per-cell clipping (Fig. 6a), Fill Depth
//! (§4.1.1), and the two-pass count / prefix-sum / fill of the buckets (§4.1.2, eq. 1);
//! finally the bands are concatenated into the flat CSR arrays and the mip chain is built.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use glam::{DVec3, Vec3};
use parallax_scene::TriangleMesh;
use parallax_scene::camera::Pinhole;
use rayon::prelude::*;

use super::clip::Poly;
use super::mip;
use super::{
    DirtCapture, DirtError, DirtOptions, DirtStats, FILM_MARGIN_PX, MAX_BUCKETS, MAX_CELL_BUCKETS,
    MAX_TILE_SIZE, bucket_index, bucket_scale,
};

/// Guard band (pixels) around the film: triangles are clipped to it in camera space before
/// projection, so projected coordinates stay small (well conditioned) whatever the near plane.
const GUARD_PX: f64 = 2.0;
/// Relative margin on a clipped depth range.
const DEPTH_REL_MARGIN: f64 = 1.0 / 65536.0;
/// Absolute depth margin, in units of f32::EPSILON times the triangle's coordinate scale.
const DEPTH_ABS_ULPS: f64 = 32.0;
/// Target number of screen bands (a band = whole cell rows, so bands concatenate in order).
const TARGET_BANDS: u32 = 64;

/// The view in f64: rotation rows (camera space = R (p - eye)), projection constants and the
/// near + guard clip planes (camera space, `n . q + d >= 0` inside).
struct ViewXf {
    rows: [DVec3; 3],
    eye: DVec3,
    eye_mag: f64,
    tx: f64,
    ty: f64,
    shift: (f64, f64),
    w: f64,
    h: f64,
    planes: [(DVec3, f64); 5],
}

impl ViewXf {
    fn new(view: &Pinhole, near: f64) -> ViewXf {
        let b = view.frame.basis;
        let (w, h) = (view.width as f64, view.height as f64);
        // The same f32 constants the pinhole's ray generation uses.
        let tx = view.tan_half_x() as f64;
        let ty = view.tan_half_y as f64;
        let (sx, sy) = (view.shift.x as f64, view.shift.y as f64);
        // film x >= -g  <=>  q.x / -q.z >= (ndc_lo + sx) tx  <=>  q.x + a q.z >= 0, and so on.
        let (gx, gy) = (2.0 * GUARD_PX / w, 2.0 * GUARD_PX / h);
        let ax_lo = (-1.0 - gx + sx) * tx;
        let ax_hi = (1.0 + gx + sx) * tx;
        // film y grows down: film y >= -g <=> ndc y <= 1 + gy; film y <= h + g <=> ndc y >= -1 - gy.
        let ay_hi = (1.0 + gy + sy) * ty;
        let ay_lo = (-1.0 - gy + sy) * ty;
        let eye = view.frame.position.as_dvec3();
        ViewXf {
            rows: [
                b.x_axis.as_dvec3(),
                b.y_axis.as_dvec3(),
                b.z_axis.as_dvec3(),
            ],
            eye,
            eye_mag: eye.abs().max_element(),
            tx,
            ty,
            shift: (sx, sy),
            w,
            h,
            planes: [
                (DVec3::new(0.0, 0.0, -1.0), -near),
                (DVec3::new(1.0, 0.0, ax_lo), 0.0),
                (DVec3::new(-1.0, 0.0, -ax_hi), 0.0),
                (DVec3::new(0.0, 1.0, ay_lo), 0.0),
                (DVec3::new(0.0, -1.0, -ay_hi), 0.0),
            ],
        }
    }

    #[inline]
    fn to_camera(&self, p: Vec3) -> DVec3 {
        let d = p.as_dvec3() - self.eye;
        DVec3::new(
            self.rows[0].dot(d),
            self.rows[1].dot(d),
            self.rows[2].dot(d),
        )
    }

    /// Camera point (in front) -> (film x, film y, 1 / view depth); inverse of
    /// `Pinhole::camera_dir`.
    #[inline]
    fn project(&self, q: DVec3) -> DVec3 {
        let inv = 1.0 / -q.z;
        let nx = q.x * inv / self.tx - self.shift.0;
        let ny = q.y * inv / self.ty - self.shift.1;
        DVec3::new((nx + 1.0) * 0.5 * self.w, (1.0 - ny) * 0.5 * self.h, inv)
    }

    /// Triangle `t` clipped to the near plane and the guard band, on the film, with the
    /// absolute depth margin for it; `None` if nothing is left (or it is not finite).
    fn setup(&self, mesh: &TriangleMesh, t: usize) -> Option<(Poly, f64)> {
        let [a, b, c] = mesh.triangle(t);
        let q = [self.to_camera(a), self.to_camera(b), self.to_camera(c)];
        if !q.iter().all(|v| v.is_finite()) {
            return None;
        }
        let mut poly = Poly::from_triangle(q);
        for &(n, d) in &self.planes {
            poly = poly.clip_plane(n, d);
            if poly.n == 0 {
                return None;
            }
        }
        for v in &mut poly.v[..poly.n] {
            *v = self.project(*v);
        }
        let world_mag = a.abs().max(b.abs()).max(c.abs()).max_element() as f64;
        let dist = q.iter().map(|v| v.length()).fold(0.0, f64::max);
        let abs_margin = DEPTH_ABS_ULPS * f32::EPSILON as f64 * (dist + world_mag + self.eye_mag);
        Some((poly, abs_margin))
    }
}

/// One cell-triangle pair with the clipped (and widened) view-depth range.
#[derive(Clone, Copy)]
struct Fragment {
    cell: u32,
    tri: u32,
    zlo: f32,
    zhi: f32,
}

/// A band's share of the result.
struct BandOut {
    zmin: Vec<f32>,
    zmax: Vec<f32>,
    /// Local exclusive prefix sums, `cells * B + 1`.
    offsets: Vec<u32>,
    ids: Vec<u32>,
    fragments: u64,
}

struct Grid {
    s: u32,
    cells_x: u32,
    cells_y: u32,
    buckets: u32,
    band_rows: u32,
}

impl Grid {
    /// Cell rows a film-y interval (widened by the margin) can touch, clamped to `[lo, hi)`.
    #[inline]
    fn span(v0: f64, v1: f64, s: u32, lo: u32, hi: u32) -> Option<(u32, u32)> {
        let m = FILM_MARGIN_PX;
        let a = ((v0 - m) / s as f64).floor() - 1.0;
        let b = ((v1 + m) / s as f64).floor();
        let a = a.max(lo as f64);
        let b = b.min(hi as f64 - 1.0);
        (a <= b).then_some((a as u32, b as u32))
    }
}

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

pub(super) fn build(
    mesh: &TriangleMesh,
    view: &Pinhole,
    opts: &DirtOptions,
) -> Result<DirtCapture, DirtError> {
    let t_start = Instant::now();
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
    let band_rows = cells_y.div_ceil(TARGET_BANDS).max(1);
    let grid = Grid {
        s,
        cells_x,
        cells_y,
        buckets: opts.buckets,
        band_rows,
    };
    let bands = cells_y.div_ceil(band_rows);
    let xf = ViewXf::new(view, opts.near as f64);
    let ntri = mesh.triangle_count();

    // 1. Setup + binning: which bands each triangle's clipped projection can touch.
    let spans: Vec<(u32, u32)> = (0..ntri)
        .into_par_iter()
        .with_min_len(1024)
        .map(|t| {
            xf.setup(mesh, t)
                .and_then(|(p, _)| p.range(1))
                .and_then(|(y0, y1)| Grid::span(y0, y1, s, 0, cells_y))
                .map_or((1, 0), |(r0, r1)| (r0 / band_rows, r1 / band_rows))
        })
        .collect();
    let mut band_start = vec![0u32; bands as usize + 1];
    let mut in_view = 0u64;
    for &(b0, b1) in &spans {
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
    let mut band_tris = vec![0u32; band_start[bands as usize] as usize];
    let mut cursor = band_start.clone();
    for (t, &(b0, b1)) in spans.iter().enumerate() {
        for b in b0..=b1 {
            band_tris[cursor[b as usize] as usize] = t as u32;
            cursor[b as usize] += 1;
        }
    }
    drop(spans);
    let setup_ms = ms(t_start);

    // 2. Per band: clip, Fill Depth, count / prefix / fill.
    let t_fill = Instant::now();
    let budget = AtomicU64::new(0);
    let outs: Vec<Result<BandOut, DirtError>> = (0..bands)
        .into_par_iter()
        .map_init(Vec::new, |frags, band| {
            let tris = &band_tris
                [band_start[band as usize] as usize..band_start[band as usize + 1] as usize];
            fill_band(mesh, &xf, &grid, opts, band, tris, frags, &budget)
        })
        .collect();
    let outs: Vec<BandOut> = outs.into_iter().collect::<Result<_, _>>()?;
    let fill_ms = ms(t_fill);

    // 3. Assemble the flat arrays.
    let t_asm = Instant::now();
    let entries: u64 = outs.iter().map(|o| o.ids.len() as u64).sum();
    let fragments: u64 = outs.iter().map(|o| o.fragments).sum();
    let (levels, texels) = mip::layout(cells_x, cells_y);
    let mut mip_min = vec![f32::INFINITY; texels];
    let mut mip_max = vec![f32::NEG_INFINITY; texels];
    let nb = opts.buckets as usize;
    let mut offsets = Vec::with_capacity(cell_count as usize * nb + 1);
    let mut ids = Vec::with_capacity(entries as usize);
    let mut cell0 = 0usize;
    for o in &outs {
        let base = ids.len() as u32;
        offsets.extend(o.offsets[..o.offsets.len() - 1].iter().map(|&x| x + base));
        ids.extend_from_slice(&o.ids);
        mip_min[cell0..cell0 + o.zmin.len()].copy_from_slice(&o.zmin);
        mip_max[cell0..cell0 + o.zmax.len()].copy_from_slice(&o.zmax);
        cell0 += o.zmin.len();
    }
    offsets.push(ids.len() as u32);
    drop(outs);
    let assemble_ms = ms(t_asm);

    // 4. Mipmap Depth.
    let t_mip = Instant::now();
    mip::build_chain(&levels, &mut mip_min, &mut mip_max);
    let mip_ms = ms(t_mip);

    let nonempty_cells = mip_min[..cell_count as usize]
        .iter()
        .filter(|z| z.is_finite())
        .count() as u64;
    let mut cap = DirtCapture {
        view: view.clone(),
        opts: *opts,
        cells_x,
        cells_y,
        offsets,
        ids,
        levels,
        mip_min,
        mip_max,
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
    cap.stats.total_ms = ms(t_start);
    Ok(cap)
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
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

/// Rasterizes the band's triangles (ascending ids) into its cells.
#[allow(clippy::too_many_arguments)]
fn fill_band(
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
    for &t in tris {
        let Some((poly, abs_margin)) = xf.setup(mesh, t as usize) else {
            continue;
        };
        let before = frags.len();
        let Some((y0, y1)) = poly.range(1) else {
            continue;
        };
        let Some((r0, r1)) = Grid::span(y0, y1, g.s, row0, row1) else {
            continue;
        };
        for r in r0..=r1 {
            let top = r as f64 * s - m;
            let bottom = ((r as f64 + 1.0) * s).min(xf.h) + m;
            let rp = poly.clip_axis(1, top, 1.0).clip_axis(1, bottom, -1.0);
            let Some((x0, x1)) = rp.range(0) else {
                continue;
            };
            let Some((c0, c1)) = Grid::span(x0, x1, g.s, 0, g.cells_x) else {
                continue;
            };
            for c in c0..=c1 {
                let left = c as f64 * s - m;
                let right = ((c as f64 + 1.0) * s).min(xf.w) + m;
                // = rp.clip_axis(0, left, 1.0).clip_axis(0, right, -1.0).range(2); measured
                // 1.6-2x faster in the fill stage than the two clips (no polygon copies).
                let Some((wlo, whi)) = rp.z_range_in_strip(left, right) else {
                    continue;
                };
                // w = 1 / depth > 0 after the near clip.
                let (zlo, zhi) = widen(1.0 / whi, 1.0 / wlo, abs_margin);
                frags.push(Fragment {
                    cell: (r - row0) * g.cells_x + c,
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

    // Fill Depth (§4.1.1).
    let mut zmin = vec![f32::INFINITY; ncells];
    let mut zmax = vec![f32::NEG_INFINITY; ncells];
    for f in frags.iter() {
        let c = f.cell as usize;
        zmin[c] = zmin[c].min(f.zlo);
        zmax[c] = zmax[c].max(f.zhi);
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
        for b in b0..=b1 {
            offsets[base + b + 1] += 1;
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
    for k in 0..ncells * nb {
        offsets[k + 1] += offsets[k];
    }
    let mut cursor = offsets.clone();
    let mut ids = vec![0u32; total as usize];
    for f in frags.iter() {
        let (b0, b1) = brange(f);
        let base = f.cell as usize * nb;
        for b in b0..=b1 {
            ids[cursor[base + b] as usize] = f.tri;
            cursor[base + b] += 1;
        }
    }
    Ok(BandOut {
        zmin,
        zmax,
        offsets,
        ids,
        fragments: frags.len() as u64,
    })
}
