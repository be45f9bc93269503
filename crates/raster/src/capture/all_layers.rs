//! The "all layers" capture of one view: every fragment of every (filtered) triangle at every
//! pixel centre, kept and sorted front to back per pixel — a layered depth image with its full
//! depth complexity (Shade et al. 1998; the LDIs of the layered depth cube, Lischinski &
//! Rappoport 1998, built on the GPU by depth peeling in Bürger et al. 2007, "Layered depth
//! cubes for GPU ray tracing", §1.2 / §2.1, where the number of passes is the depth complexity
//! counted in a first pass).
//!
//! Instead of `N` peeling passes it takes two passes of the shared rasterizer
//! ([`crate::raster`]: same setup, fixed point, top-left rule and attribute solve):
//! 1. **count** the fragments of each pixel, then an exclusive prefix sum turns the counts into
//!    CSR `offsets` (`width * height + 1`, u32);
//! 2. **fill** each pixel's fragments into its slice of one flat array and sort the slice by
//!    `(depth, primitive id)` (the rasterizer's total order), then resolve every fragment into
//!    the sample channels (structure of arrays).
//!
//! Screen bands of [`TILE`] rows are processed in parallel, each owning its pixels' counts and
//! its contiguous run of samples, so the result does not depend on the thread count. Nothing is
//! allocated per pixel.
//!
//! **Sample channels:** view depth (f32), shading normal (facing the viewer, as in the
//! G-buffer, [`resolve_fragment`]), albedo (base colour x texture) and primitive id.

use std::ops::Range;
use std::time::Instant;

use glam::Vec3;
use parallax_scene::Scene;
use rayon::prelude::*;
use serde::Serialize;

use super::resolve_fragment;
use crate::raster::tile::{self, Rect};
use crate::raster::{
    Bins, Fragment, RasterError, RasterStats, TILE, TriangleFilter, View, check_mesh, ms, setup_all,
};

/// Default bound on the samples of one capture (the build fails instead of allocating more).
pub const DEFAULT_MAX_SAMPLES: u64 = 1 << 28;

/// Sizes, work and per-stage times of an all-layers capture.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct AllLayersStats {
    pub width: u32,
    pub height: u32,
    /// Samples kept (= fragments).
    pub samples: usize,
    /// Largest number of samples of one pixel.
    pub max_depth_complexity: u32,
    /// Pixels with at least one sample.
    pub covered_pixels: usize,
    /// Bytes of the result ([`AllLayersCapture::bytes`]).
    pub bytes: usize,
    /// Setup and binning; `raster.raster_ms` is the count pass.
    pub raster: RasterStats,
    /// Prefix sum of the counts.
    pub offsets_ms: f64,
    /// Fill and per-pixel sort.
    pub fill_ms: f64,
    pub resolve_ms: f64,
    pub total_ms: f64,
}

/// All surfaces through every pixel centre of one view, front to back, in flat CSR arrays:
/// the samples of pixel `(x, y)` are `offsets[i]..offsets[i + 1]` with `i = y * width + x`.
#[derive(Clone, Debug)]
pub struct AllLayersCapture {
    pub view: View,
    pub offsets: Vec<u32>,
    pub depth: Vec<f32>,
    pub primitive_id: Vec<u32>,
    pub normal: Vec<Vec3>,
    pub albedo: Vec<Vec3>,
    pub stats: AllLayersStats,
}

impl AllLayersCapture {
    pub fn width(&self) -> u32 {
        self.view.width
    }

    pub fn height(&self) -> u32 {
        self.view.height
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.depth.len()
    }

    pub fn is_empty(&self) -> bool {
        self.depth.is_empty()
    }

    /// Sample index range of pixel `(x, y)`, nearest first.
    #[inline]
    pub fn range(&self, x: u32, y: u32) -> Range<usize> {
        let i = y as usize * self.view.width as usize + x as usize;
        self.offsets[i] as usize..self.offsets[i + 1] as usize
    }

    /// Depths of pixel `(x, y)`, nearest first.
    #[inline]
    pub fn depths(&self, x: u32, y: u32) -> &[f32] {
        &self.depth[self.range(x, y)]
    }

    /// Number of samples of pixel `(x, y)`.
    #[inline]
    pub fn depth_complexity(&self, x: u32, y: u32) -> u32 {
        let i = y as usize * self.view.width as usize + x as usize;
        self.offsets[i + 1] - self.offsets[i]
    }

    /// Bytes held by the offsets and the sample channels.
    pub fn bytes(&self) -> usize {
        self.offsets.len() * size_of::<u32>()
            + self.depth.len() * size_of::<f32>()
            + self.primitive_id.len() * size_of::<u32>()
            + (self.normal.len() + self.albedo.len()) * size_of::<Vec3>()
    }
}

/// Calls `f(band_row, x, y_in_band)` for each fragment of the tile row `ty` (rows
/// `ty * TILE..`), tile by tile, each tile's triangles in triangle order.
fn for_each_band_fragment(
    tris: &[crate::raster::RasterTri],
    bins: &Bins,
    view: &View,
    ty: u32,
    mut f: impl FnMut(u32, u32, Fragment),
) {
    let far = view.far as f64;
    for tx in 0..bins.tiles_x {
        let rect = Rect {
            x0: tx * TILE,
            y0: ty * TILE,
            x1: ((tx + 1) * TILE).min(view.width),
            y1: ((ty + 1) * TILE).min(view.height),
        };
        let items = bins.tile((ty * bins.tiles_x + tx) as usize);
        tile::for_each_fragment(tris, items, rect, far, |x, y, frag| f(x + rect.x0, y, frag));
    }
}

/// Rasterizes every fragment of the triangles of `scene` that `filter` accepts into `view`
/// (see the module docs). Errors on an invalid view or mesh, or when the capture would hold more
/// than `max_samples` (at most `u32::MAX`) samples.
pub fn capture_all_layers(
    scene: &Scene,
    view: &View,
    filter: Option<TriangleFilter>,
    max_samples: u64,
) -> Result<AllLayersCapture, RasterError> {
    let start = Instant::now();
    let mesh = &scene.mesh;
    parallax_core::image::check_size(view.width, view.height).map_err(RasterError::Size)?;
    check_mesh(mesh)?;
    let max_samples = max_samples.min(u32::MAX as u64);
    let (w, h) = (view.width as usize, view.height as usize);
    let npix = w * h;
    let band = TILE as usize * w;
    let mut raster = RasterStats {
        triangles: mesh.indices.len(),
        ..RasterStats::default()
    };

    let t = Instant::now();
    let tris = setup_all(mesh, view, filter, &mut raster);
    raster.raster_triangles = tris.len();
    raster.setup_ms = ms(t);
    let t = Instant::now();
    let bins = Bins::new(&tris, view.width, view.height);
    raster.bin_refs = bins.items.len();
    raster.bin_ms = ms(t);

    // Pass 1: count per pixel (offsets[i + 1] = count of pixel i).
    let t = Instant::now();
    let mut offsets = vec![0u32; npix + 1];
    offsets[1..]
        .par_chunks_mut(band)
        .enumerate()
        .for_each(|(ty, counts)| {
            for_each_band_fragment(&tris, &bins, view, ty as u32, |x, y, _| {
                counts[y as usize * w + x as usize] += 1;
            });
        });
    raster.raster_ms = ms(t);

    // Exclusive prefix sum (in place: offsets[i + 1] += offsets[i]).
    let t = Instant::now();
    let (mut total, mut max_dc, mut covered) = (0u64, 0u32, 0usize);
    for o in offsets[1..].iter_mut() {
        let c = *o;
        max_dc = max_dc.max(c);
        covered += (c > 0) as usize;
        total += c as u64;
        if total > max_samples {
            return Err(RasterError::InvalidOptions(format!(
                "all-layers capture of {}x{} exceeds {max_samples} samples",
                view.width, view.height
            )));
        }
        *o = total as u32;
    }
    let total = total as usize;
    let offsets_ms = ms(t);
    raster.fragments = total;

    // Pass 2: fill each band's contiguous run of fragments, then sort each pixel's slice.
    let t = Instant::now();
    let mut frags = vec![Fragment::EMPTY; total];
    let mut runs: Vec<&mut [Fragment]> = Vec::with_capacity(npix.div_ceil(band));
    let mut rest = frags.as_mut_slice();
    for b0 in (0..npix).step_by(band) {
        let b1 = (b0 + band).min(npix);
        let (run, r) = rest.split_at_mut((offsets[b1] - offsets[b0]) as usize);
        runs.push(run);
        rest = r;
    }
    runs.into_par_iter().enumerate().for_each(|(ty, run)| {
        let p0 = ty * band;
        let base = offsets[p0];
        let pix = &offsets[p0..(p0 + band).min(npix) + 1];
        // Write cursor of each pixel of the band (one array per band, none per pixel).
        let mut cursor: Vec<u32> = pix[..pix.len() - 1].iter().map(|&o| o - base).collect();
        for_each_band_fragment(&tris, &bins, view, ty as u32, |x, y, f| {
            let c = &mut cursor[y as usize * w + x as usize];
            run[*c as usize] = f;
            *c += 1;
        });
        for i in 0..pix.len() - 1 {
            let s = &mut run[(pix[i] - base) as usize..(pix[i + 1] - base) as usize];
            if s.len() > 1 {
                s.sort_unstable_by(|a, b| a.depth.total_cmp(&b.depth).then(a.prim.cmp(&b.prim)));
            }
        }
    });
    let fill_ms = ms(t);

    // Resolve into the sample channels.
    let t = Instant::now();
    let mut depth = vec![0f32; total];
    let mut primitive_id = vec![0u32; total];
    let mut normal = vec![Vec3::ZERO; total];
    let mut albedo = vec![Vec3::ZERO; total];
    const CHUNK: usize = 4096;
    depth
        .par_chunks_mut(CHUNK)
        .zip(primitive_id.par_chunks_mut(CHUNK))
        .zip(normal.par_chunks_mut(CHUNK))
        .zip(albedo.par_chunks_mut(CHUNK))
        .zip(frags.par_chunks(CHUNK))
        .for_each(|((((d, p), n), a), fr)| {
            for (k, f) in fr.iter().enumerate() {
                let s = resolve_fragment(scene, view, *f);
                d[k] = s.depth;
                p[k] = s.primitive_id;
                n[k] = s.normal;
                a[k] = s.albedo;
            }
        });
    let resolve_ms = ms(t);
    raster.scratch_bytes = tris.len() * size_of::<crate::raster::RasterTri>()
        + bins.bytes()
        + frags.len() * size_of::<Fragment>();
    drop(frags);

    let mut cap = AllLayersCapture {
        view: view.clone(),
        offsets,
        depth,
        primitive_id,
        normal,
        albedo,
        stats: AllLayersStats::default(),
    };
    cap.stats = AllLayersStats {
        width: view.width,
        height: view.height,
        samples: total,
        max_depth_complexity: max_dc,
        covered_pixels: covered,
        bytes: cap.bytes(),
        raster,
        offsets_ms,
        fill_ms,
        resolve_ms,
        total_ms: ms(start),
    };
    Ok(cap)
}
