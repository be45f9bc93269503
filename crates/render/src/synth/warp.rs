//! Warping a reference into a target pinhole view by tracing one ray per target pixel
//! (Widmer et al. 2015, §5.1): the colour of a pixel is the colour of the layer pixel its ray
//! hits; a miss takes the environment colour; an occlusion-volume crossing takes the colour of
//! the crossed layer pixel (the single-layer inpainting of §4.1) or, with
//! [`OcclusionFill::NearestBackground`], the nearest background pixel (Fig. 6e, below).
//!
//! **Colour resampling** ([`Resample`], default [`Resample::Bilinear`], the same for every
//! tracer): a hit lies at a sub-pixel position of the reference image, so its colour is
//! reconstructed there rather than taken from the nearest pixel centre. The hit position is
//! projected into the reference film ([`parallax_screen::UnitCube`]) and the 2x2 pixel centres
//! around it of the hit's layer are blended bilinearly, keeping only the neighbours that are
//! covered and lie on the hit pixel's surface (within [`SAME_SURFACE_PX`] pixel footprints of
//! the hit sample's tangent plane, normals within 60°), with the weights renormalised — the
//! depth-aware ("cross-bilateral") reconstruction filter of image-based rendering, e.g. Mark,
//! McMillan & Bishop 1997, "Post-Rendering 3D Warping", §4 (reconstruction), and Shade et al.
//! 1998, "Layered Depth Images", §4 (splatting with depth discontinuity handling), which do
//! not blend across depth discontinuities. Widmer et al. 2015 do not specify their colour
//! lookup; nearest is kept as [`Resample::Nearest`] for comparison. Occlusion-volume answers
//! keep the crossed pixel's colour (nearest).
//!
//! **Visible samples first** (bilinear only): a hit in layer 1 or deeper blends, instead of
//! its own layer's samples, the layer-0 samples of the 2x2 that lie on its surface when there
//! are any. Next to a contact edge (floor meeting a column, wall behind attached trim) the
//! layer-1 sample at a pixel centre lies inside or under the occluder and shades black,
//! while the eye's ray meets the visible part of the same surface in that pixel's footprint,
//! which layer 0's neighbours hold. Measured on atrium (800x450, ipd 0.065, quad-tree):
//! before this, such pixels (0.07% of the image) added more squared error than all layer-1
//! disocclusion answers removed, and 2 layers scored below 1 layer + background fill.
//!
//! **Layer-0 guard** (default on, the same for every tracer; only with 2+ layers): an answer
//! from layer 1 or deeper is re-checked against layer 0, in two separately switchable parts,
//! [`WarpOptions::side_entry_guard`] (a) and [`WarpOptions::dda_recheck`] (b).
//! (a) A ray that enters the reference frustum through a side face (not the near plane)
//! already more than 1% behind layer 0's depth at the entry pixel has its true surface outside
//! the captured view (the strip of an eye that the cyclopean reference does not see); a deeper
//! layer there is a wrong guess, so the answer becomes layer 0's occlusion volume at the entry
//! pixel (the single-layer inpainting). Measured on Sponza (1600x900, ipd 0.065, brute force):
//! without it the right eye's last ~100 columns carried 45% of its squared error with 2 layers
//! (right eye 29.3 dB against 31.7 dB with 1 layer). (b) A hit in a deeper layer is replaced
//! by layer 0's hit when a one-layer DDA (McGuire & Mara 2014 thin shell, 0.1 m,
//! [`DdaTracer`]) hits layer 0 earlier: rays slipping through the cracks between the per-pixel
//! planes of a layer-0 surface (which a single layer reports as an occlusion volume and
//! inpaints) otherwise land on the surface behind it (atrium: +0.35 dB with 2 layers). The
//! guard is our addition, not in Widmer et al. 2015; its DDA work is counted in the stats.
//! (c) With (b) on, a deeper-layer hit is rejected when its reference view depth is more
//! than 0.1% in front of layer 0's depth at the same pixel (a layer-k plane extrapolated in
//! front of layer 0: at 1600x900 on atrium such hits landed up to 10x nearer than their
//! sample) or when its sample lies less than 1% behind layer 0 there (a contact surface:
//! floor under a column base, wall behind attached trim, a face buried in another; such
//! samples lie inside or under the occluder, shade black, and a ray meeting their plane
//! meets the visible surface beside it in truth). The answer becomes the layer-0 DDA hit if
//! there is one, else layer 0's occlusion volume at that pixel (then filled). Part (b) is the special case Widmer's own crack handling (flag `O` + crack dilation,
//! §3.2) should cover; with G-buffer normals we now derive `O` from the planes
//! ([`parallax_screen::planes::crack_flags`]), but measured on atrium at 1600x900 (ipd
//! 0.065, quad-tree, 2 layers) (a) + crack dilation scores 29.09-29.47 dB against 29.67 dB for
//! (a) alone and 30.07 dB for (a) + (b) (none: 29.64 dB), so (b) stays.
//!
//! (d) [`WarpOptions::silhouette_check`] (with 2+ layers, after (a)-(c)): a deeper-layer hit is
//! kept only when the ray reached it by passing behind a layer-0 *silhouette*. The ray's
//! screen path in the reference is walked back from the hit while the ray lies behind layer
//! 0; if it comes out in front of layer 0 (or leaves the image) without any layer-0 depth
//! discontinuity (> 5% between neighbours, [`EDGE_REL`]) in the 3x3 around the walked pixels,
//! the ray went behind a continuous surface — it entered behind it from outside the captured
//! view or slipped through it beyond the DDA's reach — and the reference knows nothing of what
//! lies between layer 0 and the deeper layer there; the answer becomes layer 0's occlusion
//! volume (then filled). Measured (quad-tree, ipd 0.065, per-pixel 2-layer vs 1-layer error,
//! `tests/synth_diag.rs` `diagnose_worse_pixels`): on Sponza at 1600x900 the wrong layer-1
//! answers behind smooth layer-0 neighbourhoods (27 pixels, mostly black samples of walls
//! hidden behind pillars, where the truth is an intermediate surface the layers do not hold)
//! added more squared error than all correct layer-1 answers removed; with (d) Sponza 2 layers
//! go from 31.94 to 31.97 dB (1 layer: 31.96). Ours, not in Widmer et al. 2015.
//!
//! (e) [`WarpOptions::nearer_neighbour_check`] (with 2+ layers, after (d)): a deeper-layer hit
//! is rejected (layer 0's occlusion volume, then filled) when a layer-0 sample of its bilinear
//! cell (the 2x2 around the hit's projected position, the footprint the resampling reads)
//! is visible background nearer than the hit — more than 5% behind layer 0 at the hit pixel,
//! more than 1% in front of the hit — not on the hit sample's surface, and the ray meets
//! that sample's tangent plane before the hit within one pixel of the sample's centre (its
//! surface extended half a pixel beyond its footprint, into the hit pixel). Such a neighbour
//! shows a surface passing in front of the deeper sample just beside the occluder's edge; a ray
//! passing the edge there meets that surface (or one the layers do not hold, between the two)
//! before the deeper sample. Measured (quad-tree, ipd 0.065): at 1600x900 atrium 2 layers go
//! from 30.43 to 30.45 dB (the silhouette pixels of the atrium's columns, where the eye ray at
//! a sub-pixel position met a column side seen edge-on by the reference and the layer-1 sample
//! was a dark wall behind), Sponza 31.967 -> 31.971 dB; at 800x450 atrium it costs 0.002 dB
//! (27.881 -> 27.879); at 160x120, ipd 0.26 (`tests/synth.rs`) 0.03 dB (21.185 -> 21.152;
//! without the plane-crossing condition 0.05 dB). Ours, not in Widmer et al. 2015.
//!
//! **Occlusion-volume fill** ([`WarpOptions::fill`]). Fig. 6e fills single-layer misses and
//! occlusion-volume answers "with the nearest background pixels". [`OcclusionFill::Crossed`]
//! takes the colour of the pixel the tracer reports (for cascade-mode answers the pixel whose
//! plane the ray passed behind: the occluder's edge, a foreground colour).
//! [`OcclusionFill::NearestBackground`] ([`background_fill`], the default; Fig. 6e shows it
//! for single-layer references, we also apply it to the occlusion-volume answers left with
//! 2 layers: +0.08 dB on atrium and Sponza at 1600x900, -0.00..0.17 dB at 160x120 in
//! `tests/synth.rs`) walks from that pixel back along
//! the ray's screen direction in the reference (the epipolar line: the ray came from in front
//! of the background on that side of the silhouette) to the first pixel deeper than the
//! occluder edge by 1% (or uncovered: the environment), at most [`BACKGROUND_SEARCH_PX`]
//! pixels, else keeps the crossed pixel. An occlusion volume of layer 1 or deeper (the ray
//! passed behind that layer too; the per-pixel tracers min-max, Hi-Z and DDA report them) is
//! filled from layer 0's nearest background first (the visible background a single layer
//! would give), from its own layer only when layer 0 has none: hidden-layer samples next to
//! their own silhouettes are often dark contact or enclosed surfaces. Measured at 800x450,
//! ipd 0.065 (2 layers): min-max atrium 27.875 -> 27.929 dB, Sponza 29.689 -> 29.760 dB; DDA
//! 27.843 -> 27.901, 29.606 -> 29.646 dB (quad-tree and brute force report none). Ours.
//! Misses keep the environment colour (our misses are
//! rays that never pass behind a layer: sky, or outside the reference frustum).
//!
//! Besides colour, every pixel records what its ray found ([`HitKind`], shown like Fig. 6d:
//! misses red, occlusion volumes blue) and its intersection-test count (box + plane tests, or
//! steps for structures without tests — Fig. 1c's heatmap). Rows run in parallel (rayon), each
//! with its own [`TraceStats`], summed at the end.

use std::time::Instant;

use glam::{UVec2, Vec2, Vec3};
use parallax_core::{Image, Rgb};
use parallax_scene::camera::{CameraModel, Pinhole};
use parallax_screen::{DdaOptions, DdaTracer, ScreenTracer, TraceResult, TraceStats};
use rayon::prelude::*;

use super::layers::Reference;

/// How a hit's colour is read from its layer (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum Resample {
    /// The hit pixel's colour.
    Nearest,
    /// Depth-aware bilinear interpolation at the hit's sub-pixel position (same layer, same
    /// surface neighbours only, weights renormalised).
    #[default]
    Bilinear,
}

/// Neighbours farther than this many pixel footprints (at the hit's depth) from the hit
/// sample's tangent plane are another surface and are not blended.
pub const SAME_SURFACE_PX: f32 = 1.0;

/// What a target pixel's ray found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HitKind {
    /// A captured surface of this layer.
    Hit(u8),
    /// Nothing: left the reference frustum (environment colour).
    Miss,
    /// An occlusion volume of this layer (inpainted).
    Occlusion(u8),
}

impl HitKind {
    /// The layer the answer came from (`None` for a miss).
    pub fn layer(self) -> Option<u8> {
        match self {
            HitKind::Hit(l) | HitKind::Occlusion(l) => Some(l),
            HitKind::Miss => None,
        }
    }
}

/// A synthesised view.
#[derive(Clone, Debug)]
pub struct WarpedView {
    pub image: Image<Rgb>,
    /// Per pixel, row-major.
    pub kinds: Vec<HitKind>,
    /// Intersection tests per pixel (0 for the mesh warp).
    pub work: Vec<u32>,
    pub stats: TraceStats,
    /// Wall-clock milliseconds of the synthesis (tracing + colour fetch).
    pub ms: f64,
}

impl WarpedView {
    /// Fraction of pixels whose answer came from layer 1 or deeper (the paper's "rays into
    /// the second layer", measured on the final answer).
    pub fn frac_deep(&self) -> f64 {
        let n = self
            .kinds
            .iter()
            .filter(|k| k.layer().is_some_and(|l| l >= 1))
            .count();
        n as f64 / self.kinds.len().max(1) as f64
    }

    /// Fractions of (hits, misses, occlusion volumes).
    pub fn kind_fractions(&self) -> (f64, f64, f64) {
        let n = self.kinds.len().max(1) as f64;
        let c = |f: fn(&HitKind) -> bool| self.kinds.iter().filter(|k| f(k)).count() as f64 / n;
        (
            c(|k| matches!(k, HitKind::Hit(_))),
            c(|k| matches!(k, HitKind::Miss)),
            c(|k| matches!(k, HitKind::Occlusion(_))),
        )
    }

    /// Fig. 6d: hits keep their colour, misses red, occlusion-volume crossings blue.
    pub fn hit_type_image(&self) -> Image<Rgb> {
        let data = self
            .image
            .data()
            .iter()
            .zip(&self.kinds)
            .map(|(c, k)| match k {
                HitKind::Hit(_) => *c,
                HitKind::Miss => Vec3::new(1.0, 0.0, 0.0),
                HitKind::Occlusion(_) => Vec3::new(0.0, 0.0, 1.0),
            })
            .collect();
        Image::from_vec(self.image.width(), self.image.height(), data).expect("same size")
    }

    /// Fig. 1c: intersection tests per ray, black = 0, white = `max` (the largest count when
    /// `None`). Returns the image and the scale used.
    pub fn heatmap(&self, max: Option<u32>) -> (Image<Rgb>, u32) {
        let m = max
            .unwrap_or_else(|| self.work.iter().copied().max().unwrap_or(0))
            .max(1);
        let data = self
            .work
            .iter()
            .map(|&w| Vec3::splat((w as f32 / m as f32).min(1.0)))
            .collect();
        let img = Image::from_vec(self.image.width(), self.image.height(), data).expect("size");
        (img, m)
    }

    /// Mean intersection tests (box + plane) per ray.
    pub fn tests_per_ray(&self) -> f64 {
        let s = &self.stats;
        (s.box_tests + s.plane_tests) as f64 / s.rays.max(1) as f64
    }

    /// Mean hierarchy nodes visited per ray (steps for flat structures).
    pub fn nodes_per_ray(&self) -> f64 {
        let s = &self.stats;
        let n = if s.nodes_visited > 0 {
            s.nodes_visited
        } else {
            s.steps
        };
        n as f64 / s.rays.max(1) as f64
    }
}

/// Traces every pixel-centre ray of `target` with `tracer` (built over `reference`'s layers)
/// and fetches colours from `reference` with [`Resample::default`].
pub fn warp_view(tracer: &dyn ScreenTracer, reference: &Reference, target: &Pinhole) -> WarpedView {
    warp_view_with(tracer, reference, target, &WarpOptions::default())
}

/// How an occlusion-volume answer is coloured (module docs, "Occlusion-volume fill").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum OcclusionFill {
    /// The colour of the pixel the tracer reports (the crossed pixel).
    Crossed,
    /// The nearest background pixel along the ray's epipolar line (Fig. 6e).
    #[default]
    NearestBackground,
}

/// Options of [`warp_view_with`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct WarpOptions {
    pub resample: Resample,
    /// Layer-0 guard part (a) (module docs): an answer from layer 1.. for a ray entering the
    /// reference frustum through a side face behind layer 0 becomes layer 0's occlusion
    /// volume.
    pub side_entry_guard: bool,
    /// Layer-0 guard part (b) (module docs): a hit in layer 1.. is replaced by layer 0's
    /// thin-shell DDA hit when that comes first (rays slipping through layer-0 cracks).
    pub dda_recheck: bool,
    /// Colour of occlusion-volume answers (any layer count).
    pub fill: OcclusionFill,
    /// Layer-0 guard part (d) (module docs): a hit in layer 1.. is kept only when the ray
    /// passed behind a layer-0 silhouette to reach it.
    pub silhouette_check: bool,
    /// Layer-0 guard part (e) (module docs): a hit in layer 1.. is rejected when a layer-0
    /// sample of another surface in its bilinear cell lies between layer 0 and the hit.
    pub nearer_neighbour_check: bool,
}

impl WarpOptions {
    /// Both parts of the layer-0 guard on or off.
    pub fn with_layer0_guard(self, on: bool) -> Self {
        Self {
            side_entry_guard: on,
            dda_recheck: on,
            silhouette_check: on,
            nearer_neighbour_check: on,
            ..self
        }
    }
}

impl Default for WarpOptions {
    fn default() -> Self {
        Self {
            resample: Resample::default(),
            side_entry_guard: true,
            dda_recheck: true,
            fill: OcclusionFill::default(),
            silhouette_check: true,
            nearer_neighbour_check: true,
        }
    }
}

/// [`warp_view`] with a choice of colour resampling and crack guard.
pub fn warp_view_with(
    tracer: &dyn ScreenTracer,
    reference: &Reference,
    target: &Pinhole,
    opts: &WarpOptions,
) -> WarpedView {
    let resample = opts.resample;
    let deep = reference.layers.len() > 1;
    // The background fill of Fig. 6e, for every layer count (module docs).
    let fill_bg = opts.fill == OcclusionFill::NearestBackground;
    let side_guard = opts.side_entry_guard && deep;
    let silhouette = opts.silhouette_check && deep;
    let nearer = opts.nearer_neighbour_check && deep;
    let guard = (opts.dda_recheck && deep)
        .then(|| {
            let o = DdaOptions {
                layers: 1,
                ..DdaOptions::default()
            };
            DdaTracer::new(&reference.cube, &reference.layers[..1], &o).ok()
        })
        .flatten();
    let (w, h) = (target.width, target.height);
    let n = w as usize * h as usize;
    let mut image = vec![Vec3::ZERO; n];
    let mut kinds = vec![HitKind::Miss; n];
    let mut work = vec![0u32; n];
    let start = Instant::now();
    let stats = image
        .par_chunks_mut(w as usize)
        .zip(kinds.par_chunks_mut(w as usize))
        .zip(work.par_chunks_mut(w as usize))
        .enumerate()
        .map(|(y, ((img, kind), wk))| {
            let mut total = TraceStats::default();
            for x in 0..w as usize {
                let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let Some(cr) = target.generate_ray(film, Vec2::splat(0.5), 1) else {
                    img[x] = reference.background;
                    continue;
                };
                let mut s = TraceStats::default();
                let mut r = tracer.trace(&cr.ray, &mut s);
                if side_guard || guard.is_some() {
                    r = guard_deep(reference, side_guard, guard.as_ref(), &cr.ray, r, &mut s);
                }
                if silhouette {
                    r = silhouette_guard(reference, &cr.ray, r);
                }
                if nearer {
                    r = nearer_neighbour_guard(reference, &cr.ray, r);
                }
                let tests = s.box_tests + s.plane_tests;
                wk[x] = (if tests > 0 { tests } else { s.steps }).min(u32::MAX as u64) as u32;
                total += s;
                (img[x], kind[x]) = resolve(reference, r, resample);
                if let (true, HitKind::Occlusion(l)) = (fill_bg, kind[x])
                    && let TraceResult::OcclusionVolume { pixel, .. } = r
                    && let Some(c) = background_fill(reference, 0, pixel, &cr.ray)
                        .or_else(|| background_fill(reference, l as u32, pixel, &cr.ray))
                {
                    img[x] = c;
                }
            }
            total
        })
        .reduce(TraceStats::default, |a, b| a + b);
    let ms = start.elapsed().as_secs_f64() * 1e3;
    WarpedView {
        image: Image::from_vec(w, h, image).expect("camera size is valid"),
        kinds,
        work,
        stats,
        ms,
    }
}

/// The layer-0 guard of an answer `r` from layer 1 or deeper (module docs): layer 0's
/// occlusion volume at the entry pixel when the ray enters the reference frustum through a
/// side face already behind layer 0 (its true surface lies outside the captured view); for a
/// hit, layer 0's thin-shell hit when the DDA over layer 0 finds one before it; else `r`.
fn guard_deep(
    reference: &Reference,
    side_entry: bool,
    guard: Option<&DdaTracer>,
    ray: &parallax_core::Ray,
    r: TraceResult,
    stats: &mut TraceStats,
) -> TraceResult {
    let deep = match r {
        TraceResult::Hit { layer, .. } | TraceResult::OcclusionVolume { layer, .. } => layer >= 1,
        TraceResult::Miss => false,
    };
    if !deep {
        return r;
    }
    if side_entry
        && let Some(seg) = reference.cube.clip_ray(ray)
        && seg.p0.z > 1e-4
    {
        let g0 = &reference.layers[0];
        let (w, h) = (g0.width(), g0.height());
        let px = ((seg.p0.x * w as f32) as u32).min(w - 1);
        let py = ((seg.p0.y * h as f32) as u32).min(h - 1);
        let d0 = g0.depth[g0.index(px, py)];
        if d0.is_finite() && d0 > 0.0 && seg.w0 as f32 > d0 * (1.0 + ENTRY_BEHIND_REL) {
            return TraceResult::OcclusionVolume {
                layer: 0,
                pixel: UVec2::new(px, py),
                t: seg.t0,
            };
        }
    }
    let (Some(guard), Some(t)) = (guard, r.hit_t()) else {
        return r;
    };
    // (c) A deeper layer's plane met in front of layer 0's depth at the same pixel is an
    // extrapolation, not a surface (layer k lies behind layer 0 in every pixel).
    let in_front = match r {
        TraceResult::Hit {
            layer,
            pixel,
            position,
            ..
        } if layer >= 1 => {
            let g0 = &reference.layers[0];
            let d0 = g0.depth[g0.index(pixel.x, pixel.y)];
            let dh = reference.cube.homogeneous(position).w as f32;
            let gk = &reference.layers[layer as usize];
            let dk = gk.depth[gk.index(pixel.x, pixel.y)];
            d0.is_finite()
                && d0 > 0.0
                && (dh < d0 * (1.0 - IN_FRONT_REL) || dk < d0 * (1.0 + CONTACT_REL))
        }
        _ => false,
    };
    let r0 = guard.trace(ray, stats);
    match (r0, r) {
        (TraceResult::Hit { t: t0, pixel, .. }, _) if t0 < t && interior(reference, pixel) => r0,
        (TraceResult::Hit { .. }, _) if in_front => r0,
        (_, TraceResult::Hit { pixel, t, .. }) if in_front => {
            TraceResult::OcclusionVolume { layer: 0, pixel, t }
        }
        _ => r,
    }
}

/// True when the 4-neighbours of layer-0 `pixel` are covered and lie on its surface (the
/// same-surface test of [`bilinear`]): a ray meeting layer 0 there slipped through a crack
/// between pixel planes; at a depth edge it may pass legitimately behind the edge pixel.
fn interior(reference: &Reference, pixel: UVec2) -> bool {
    let g = &reference.layers[0];
    let (w, h) = (g.width(), g.height());
    let (x, y) = (pixel.x, pixel.y);
    if x == 0 || y == 0 || x + 1 >= w || y + 1 >= h {
        return false;
    }
    let i = g.index(x, y);
    let (p, n, d) = (g.position[i], g.normal[i], g.depth[i]);
    let tol = same_surface_tol(reference, d);
    [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)]
        .into_iter()
        .all(|(a, b)| same_surface(g, g.index(a, b), p, n, tol))
}

/// Distance from a tangent plane under which a neighbour at view depth `depth` is the same
/// surface ([`SAME_SURFACE_PX`] pixel footprints + 0.01% of the depth).
#[inline]
fn same_surface_tol(reference: &Reference, depth: f32) -> f32 {
    let footprint = depth * 2.0 * reference.camera.tan_half_y / reference.height() as f32;
    SAME_SURFACE_PX * footprint + 1e-4 * depth
}

/// True when sample `i` of `g` is covered and lies on the surface through `p` with normal `n`
/// (within `tol` of the plane, normals within 60°).
#[inline]
fn same_surface(g: &parallax_core::GBuffer, i: usize, p: Vec3, n: Vec3, tol: f32) -> bool {
    g.depth[i].is_finite()
        && g.depth[i] > 0.0
        && n.dot(g.normal[i]) > 0.5
        && n.dot(g.position[i] - p).abs() <= tol
}

/// A deeper-layer hit more than this fraction of layer 0's depth in front of layer 0 (same
/// pixel) is rejected by the DDA recheck (guard part c, module docs).
const IN_FRONT_REL: f32 = 0.001;

/// A deeper-layer sample less than this fraction of layer 0's depth behind layer 0 is a
/// contact surface (guard part c, module docs).
const CONTACT_REL: f32 = 0.01;

/// A ray entering the cube through a side face more than this fraction of layer 0's depth
/// behind layer 0 entered from behind it.
const ENTRY_BEHIND_REL: f32 = 0.01;

/// The colour and kind of one trace result.
#[inline]
fn resolve(reference: &Reference, r: TraceResult, resample: Resample) -> (Rgb, HitKind) {
    match r {
        TraceResult::Hit {
            layer,
            pixel,
            position,
            ..
        } => {
            let c = match resample {
                Resample::Nearest => fetch(reference, layer, pixel),
                Resample::Bilinear => bilinear(reference, layer, pixel, position)
                    .unwrap_or_else(|| fetch(reference, layer, pixel)),
            };
            (c, HitKind::Hit(layer as u8))
        }
        TraceResult::Miss => (reference.background, HitKind::Miss),
        TraceResult::OcclusionVolume { layer, pixel, .. } => (
            fetch(reference, layer, pixel),
            HitKind::Occlusion(layer as u8),
        ),
    }
}

/// The colour of one layer pixel (the background outside the image).
#[inline]
fn fetch(reference: &Reference, layer: u32, p: UVec2) -> Rgb {
    reference
        .colors
        .get(layer as usize)
        .filter(|c| p.x < c.width() && p.y < c.height())
        .map(|c| *c.get(p.x, p.y))
        .unwrap_or(reference.background)
}

/// Depth-aware bilinear colour of a hit at world `position` answered by `pixel` of `layer`
/// (module docs). `None` when the hit pixel is not one of the four neighbours of the
/// projected position (then the caller takes the nearest colour).
fn bilinear(reference: &Reference, layer: u32, pixel: UVec2, position: Vec3) -> Option<Rgb> {
    let g = reference.layers.get(layer as usize)?;
    let colors = reference.colors.get(layer as usize)?;
    let (w, h) = (g.width(), g.height());
    if pixel.x >= w || pixel.y >= h {
        return None;
    }
    let hc = reference.cube.homogeneous(position);
    if !(hc.w > 0.0) {
        return None;
    }
    let depth = hc.w as f32;
    // Film position minus the pixel-centre offset: integer values are pixel centres.
    let fx = (hc.x / hc.w) as f32 * w as f32 - 0.5;
    let fy = (hc.y / hc.w) as f32 * h as f32 - 0.5;
    if !(fx.is_finite() && fy.is_finite()) {
        return None;
    }
    let (x0, y0) = (fx.floor(), fy.floor());
    let (tx, ty) = (fx - x0, fy - y0);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let (px, py) = (pixel.x as i64, pixel.y as i64);
    if !(x0..=x0 + 1).contains(&px) || !(y0..=y0 + 1).contains(&py) {
        return None;
    }
    let hi = g.index(pixel.x, pixel.y);
    let (p_hit, n_hit) = (g.position[hi], g.normal[hi]);
    let tol = same_surface_tol(reference, depth);
    // A deeper layer's hit blends the layer-0 samples of its surface when there are any
    // (module docs, "Visible samples first").
    if layer >= 1 {
        let g0 = &reference.layers[0];
        let c0 = &reference.colors[0];
        let mut sum = Vec3::ZERO;
        let mut wsum = 0.0f32;
        for (dy, wy) in [(0, 1.0 - ty), (1, ty)] {
            for (dx, wx) in [(0, 1.0 - tx), (1, tx)] {
                let (x, y) = (x0 + dx, y0 + dy);
                if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                    continue;
                }
                let (x, y) = (x as u32, y as u32);
                let wgt = wx * wy;
                if wgt > 0.0 && same_surface(g0, g0.index(x, y), p_hit, n_hit, tol) {
                    sum += *c0.get(x, y) * wgt;
                    wsum += wgt;
                }
            }
        }
        if wsum > 1e-6 {
            return Some(sum / wsum);
        }
    }
    let mut sum = Vec3::ZERO;
    let mut wsum = 0.0f32;
    for (dy, wy) in [(0, 1.0 - ty), (1, ty)] {
        for (dx, wx) in [(0, 1.0 - tx), (1, tx)] {
            let (x, y) = (x0 + dx, y0 + dy);
            if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                continue;
            }
            let (x, y) = (x as u32, y as u32);
            let i = g.index(x, y);
            let same = i == hi || same_surface(g, i, p_hit, n_hit, tol);
            let wgt = wx * wy;
            if same && wgt > 0.0 {
                sum += *colors.get(x, y) * wgt;
                wsum += wgt;
            }
        }
    }
    (wsum > 1e-6).then(|| sum / wsum)
}

/// Steps of the background search of [`background_fill`] (pixels along the epipolar line).
pub const BACKGROUND_SEARCH_PX: u32 = 8;

/// A pixel deeper than the occluder edge by more than this fraction of its depth is
/// background for [`background_fill`].
const BACKGROUND_REL: f32 = 0.01;

/// Fig. 6e's "nearest background pixel" for an occlusion-volume answer at `pixel` of `layer`
/// (module docs): the occluder edge depth is the nearer of `pixel` and the next pixel along
/// the ray's screen direction in the reference; walking back from `pixel` against that
/// direction one pixel at a time (at most [`BACKGROUND_SEARCH_PX`] steps), the first pixel
/// that is uncovered or deeper than the edge by [`BACKGROUND_REL`] gives the colour. `None`
/// when there is none (the caller keeps the crossed pixel's colour).
fn background_fill(
    reference: &Reference,
    layer: u32,
    pixel: UVec2,
    ray: &parallax_core::Ray,
) -> Option<Rgb> {
    let g = reference.layers.get(layer as usize)?;
    let colors = reference.colors.get(layer as usize)?;
    let (w, h) = (g.width(), g.height());
    if pixel.x >= w || pixel.y >= h {
        return None;
    }
    let seg = reference.cube.clip_ray(ray)?;
    let d = seg.p1 - seg.p0;
    let dir = Vec2::new(d.x * w as f32, d.y * h as f32);
    let len = dir.x.abs().max(dir.y.abs());
    if !(len > 1e-6 && len.is_finite()) {
        return None;
    }
    // One pixel per step along the major axis.
    let step = dir / len;
    let centre = Vec2::new(pixel.x as f32 + 0.5, pixel.y as f32 + 0.5);
    let at = |p: Vec2| -> Option<usize> {
        (p.x >= 0.0 && p.y >= 0.0 && p.x < w as f32 && p.y < h as f32)
            .then(|| g.index(p.x as u32, p.y as u32))
    };
    let depth = |i: usize| {
        let d = g.depth[i];
        if d.is_finite() && d > 0.0 {
            d
        } else {
            f32::INFINITY
        }
    };
    let mut edge = depth(g.index(pixel.x, pixel.y));
    if let Some(i) = at(centre + step) {
        edge = edge.min(depth(i));
    }
    if !edge.is_finite() {
        return None;
    }
    let limit = edge * (1.0 + BACKGROUND_REL);
    for k in 0..=BACKGROUND_SEARCH_PX {
        let i = at(centre - step * k as f32)?;
        if depth(i) > limit {
            let (x, y) = (i as u32 % w, i as u32 / w);
            return Some(if g.depth[i].is_finite() && g.depth[i] > 0.0 {
                *colors.get(x, y)
            } else {
                reference.background
            });
        }
    }
    None
}

/// Layer-0 guard part (d) (module docs): a hit `r` in layer 1 or deeper is kept only when the
/// ray reached it by passing behind a layer-0 silhouette. The ray's screen path in the
/// reference is walked back from the hit, one pixel at a time, while the ray lies behind layer
/// 0: the hit is kept as soon as layer 0 shows a depth discontinuity (neighbouring depths
/// differing by more than [`EDGE_REL`], or an uncovered pixel) in the 3x3 around the walked
/// pixel, or when the ray's path is longer than [`SILHOUETTE_SEARCH_PX`]. It becomes layer 0's occlusion
/// volume at the hit pixel (then filled) when the walk reaches a pixel where the ray is in front
/// of layer 0, or leaves the image, without meeting a discontinuity: the ray went behind a
/// continuous surface (through it, or from outside the captured view), where the reference
/// knows nothing of what lies between layer 0 and the deeper layer.
fn silhouette_guard(
    reference: &Reference,
    ray: &parallax_core::Ray,
    r: TraceResult,
) -> TraceResult {
    let TraceResult::Hit {
        layer,
        pixel,
        position,
        t,
        ..
    } = r
    else {
        return r;
    };
    if layer == 0 {
        return r;
    }
    let Some(g0) = reference.layers.first() else {
        return r;
    };
    let Some(seg) = reference.cube.clip_ray(ray) else {
        return r;
    };
    let (w, h) = (g0.width(), g0.height());
    let (wf, hf) = (w as f32, h as f32);
    let s0 = Vec2::new(seg.p0.x * wf, seg.p0.y * hf);
    let s1 = Vec2::new(seg.p1.x * wf, seg.p1.y * hf);
    let hc = reference.cube.homogeneous(position);
    if !(hc.w > 0.0) {
        return r;
    }
    let sq = Vec2::new((hc.x / hc.w) as f32 * wf, (hc.y / hc.w) as f32 * hf);
    let d = s1 - s0;
    let len = d.x.abs().max(d.y.abs());
    if !(len > 1e-6 && len.is_finite() && sq.is_finite()) {
        return r;
    }
    let step = d / len;
    let depth0 = |x: i64, y: i64| -> Option<f32> {
        (x >= 0 && y >= 0 && x < w as i64 && y < h as i64).then(|| {
            let d = g0.depth[g0.index(x as u32, y as u32)];
            if d.is_finite() && d > 0.0 {
                d
            } else {
                f32::INFINITY
            }
        })
    };
    // A depth discontinuity of layer 0 in the 3x3 around (x, y).
    let edge_near = |x: i64, y: i64, dc: f32| -> bool {
        if !dc.is_finite() {
            return true;
        }
        (-1..=1).any(|dy| {
            (-1..=1).any(|dx| {
                depth0(x + dx, y + dy).is_some_and(|dn| !((dn - dc).abs() <= EDGE_REL * dn.min(dc)))
            })
        })
    };
    // Perspective-correct view depth of the ray at screen position `s` on the segment.
    let (iw0, iw1) = (1.0 / seg.w0 as f32, 1.0 / seg.w1 as f32);
    let ray_depth = |s: Vec2| -> f32 {
        let u = ((s - s0).dot(d) / d.length_squared()).clamp(0.0, 1.0);
        1.0 / (iw0 + (iw1 - iw0) * u)
    };
    let path = (sq - s0).abs().max_element().ceil() as u32;
    if path > SILHOUETTE_SEARCH_PX {
        return r;
    }
    for k in 0..=path {
        let s = sq - step * k as f32;
        let (x, y) = (s.x.floor() as i64, s.y.floor() as i64);
        let Some(dc) = depth0(x, y) else {
            break;
        };
        if edge_near(x, y, dc) {
            return r;
        }
        if k > 0 && ray_depth(s) < dc {
            break;
        }
    }
    TraceResult::OcclusionVolume { layer: 0, pixel, t }
}

/// Bound of the walk of [`silhouette_guard`] (pixels).
pub const SILHOUETTE_SEARCH_PX: u32 = 256;

/// Neighbouring layer-0 depths differing by more than this fraction are a silhouette for
/// [`silhouette_guard`].
const EDGE_REL: f32 = 0.05;

/// Layer-0 guard part (e) (module docs): a hit `r` in layer 1 or deeper becomes layer 0's
/// occlusion volume at the hit pixel when one of the four layer-0 samples around the hit's
/// projected position (its bilinear cell) is covered, lies more than [`EDGE_REL`] behind layer
/// 0 at the hit pixel and more than [`NEARER_REL`] in front of the hit, and is not on the hit
/// sample's surface (the same-surface test of the bilinear resampling, tolerance x
/// [`NEARER_SURFACE_TOL`]), and the ray meets that sample's tangent plane before the hit within
/// [`NEARER_EXTENT_PX`] of the sample's pixel centre; any other answer is returned unchanged.
fn nearer_neighbour_guard(
    reference: &Reference,
    ray: &parallax_core::Ray,
    r: TraceResult,
) -> TraceResult {
    let TraceResult::Hit {
        layer,
        pixel,
        position,
        t,
        ..
    } = r
    else {
        return r;
    };
    if layer == 0 {
        return r;
    }
    let g0 = &reference.layers[0];
    let (w, h) = (g0.width() as i64, g0.height() as i64);
    let d0 = g0.depth[g0.index(pixel.x, pixel.y)];
    let dh = reference.cube.homogeneous(position).w as f32;
    if !(d0.is_finite() && d0 > 0.0) {
        return r;
    }
    let lo = d0 * (1.0 + EDGE_REL);
    let hi = dh * (1.0 - NEARER_REL);
    let gk = &reference.layers[layer as usize];
    let hk = gk.index(pixel.x, pixel.y);
    let (p_hit, n_hit) = (gk.position[hk], gk.normal[hk]);
    let tol = same_surface_tol(reference, dh) * NEARER_SURFACE_TOL;
    let between = |x: i64, y: i64| -> bool {
        if x < 0 || y < 0 || x >= w || y >= h {
            return false;
        }
        let i = g0.index(x as u32, y as u32);
        let d = g0.depth[i];
        if !(d.is_finite() && d > lo && d < hi && !same_surface(g0, i, p_hit, n_hit, tol)) {
            return false;
        }
        // The ray meets the neighbour's tangent plane before the hit, within
        // `NEARER_EXTENT_PX` pixels of the neighbour's centre.
        let (pn, nn) = (g0.position[i], g0.normal[i]);
        let den = nn.dot(ray.dir);
        if den.abs() < 1e-8 {
            return false;
        }
        let tn = nn.dot(pn - ray.origin) / den;
        if !(tn > 0.0 && tn < t) {
            return false;
        }
        let q = reference.cube.homogeneous(ray.origin + ray.dir * tn);
        if !(q.w > 0.0) {
            return false;
        }
        let qx = (q.x / q.w) as f32 * w as f32 - 0.5 - x as f32;
        let qy = (q.y / q.w) as f32 * h as f32 - 0.5 - y as f32;
        qx.abs().max(qy.abs()) <= NEARER_EXTENT_PX
    };
    let hc = reference.cube.homogeneous(position);
    let fx = (hc.x / hc.w) as f32 * w as f32 - 0.5;
    let fy = (hc.y / hc.w) as f32 * h as f32 - 0.5;
    if !(fx.is_finite() && fy.is_finite()) {
        return r;
    }
    let (x0, y0) = (fx.floor() as i64, fy.floor() as i64);
    let found = [(0, 0), (1, 0), (0, 1), (1, 1)]
        .iter()
        .any(|(dx, dy)| between(x0 + dx, y0 + dy));
    if found {
        TraceResult::OcclusionVolume { layer: 0, pixel, t }
    } else {
        r
    }
}

/// A layer-0 neighbour must lie more than this fraction of the hit's depth in front of a
/// deeper-layer hit to reject it (guard part e).
const NEARER_REL: f32 = 0.01;

/// Same-surface tolerance of guard part (e), in units of the bilinear one.
const NEARER_SURFACE_TOL: f32 = 2.0;

/// Guard part (e): a neighbour's surface counts where the ray meets its tangent plane within
/// this many pixels (max norm) of the neighbour's centre (its own footprint and half a pixel
/// beyond).
const NEARER_EXTENT_PX: f32 = 1.0;
