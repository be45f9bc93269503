//! [`QuadTreeTracer`]: the quad-trees of all layers of one reference view and the
//! occlusion-aware multi-layer traversal of Widmer et al. 2015, §4.1.
//!
//! # What is computed
//!
//! The result equals [`crate::BruteForcePlanes`] over the trees' decoded planes
//! ([`QuadTree::effective_planes`]): the closest plane hit over all layers (ties: lower
//! layer); if there is none, the first occlusion-volume entry over all layers (ties: lower
//! layer); else `Miss`. With lossless settings and G-buffer normals this is brute force over
//! the quantised per-pixel planes (tests `quadtree_lossless.rs`, `quadtree_cascade.rs`).
//!
//! # Cascading (§4.1) and why it is exact
//!
//! The paper traces layer `k + 1` only for rays that "hit an occlusion volume" of layer `k`,
//! arguing that occluded geometry lies behind layer `k`. For the *planes* that is not
//! automatic: a deeper layer's plane at pixel `p` is behind layer `k`'s plane at the pixel
//! centre (depth peeling), but a tilted plane can come in front of it elsewhere in the
//! footprint, and a layer can be empty where a deeper one is not. The supplement is not
//! public; we close the gap as follows.
//!
//! **Trigger region.** For layer `k` and pixel `p` with footprint column `C_p`, let
//! `f_k(X) = N_k·X - c_k` (positive in front). Pixel `p` is *safe* when for every deeper
//! layer `j > k` with a plane at `p`, layer `k` has a plane at `p` and at all four footprint
//! corners `(x, y)` the point `X_j = (x, y, z_j(x, y))` of plane `j` satisfies
//! `f_k(X_j) <= -1e-6` (a margin above f32 rounding). Otherwise `p` is *unsafe*
//! ([`super::node::FLAG_UNSAFE`]) with *trigger depth* `tz_p` = the minimum over deeper
//! planes of their corner `z`, minus the margin (0 if a deeper plane is seen edge-on,
//! `N_j.z ≈ 0`). The trigger region is `T_k ∩ C_p = {f_k(X) < 0}` for safe `p` and
//! `{f_k(X) < 0} ∪ {z >= tz_p}` for unsafe `p` (`{z >= tz_p}` alone where layer `k` is
//! empty). Storage: `tz` lives in a per-pixel side array read only at unsafe leaves; an
//! unsafe empty pixel becomes the AABB leaf `(tz, -inf)`; every AABB above lowers its
//! `min z` to the smallest `tz` below it. Layers are built deepest first; layer `k`'s
//! trigger depths are computed from its *effective* planes against the deeper layers' final
//! effective planes, and pruning never merges a node containing an unsafe pixel, so the
//! plane the analysis used is the plane the traversal tests. (A merged proxy plane deviates
//! from its pixels' planes by up to `gamma_dist`, so a pixel safe against its own plane can
//! be unsafe against the proxy: the build blocks such pixels from merging and rebuilds, to
//! a fixed point, [`QuadTree::build`](super::QuadTree).) (A merged plane node flagged
//! unsafe would trigger on footprint entry; with this rule none occurs.)
//!
//! **Lemma 1.** Every point `X` of a deeper plane `j > k` in `C_p`, and every point behind
//! it, lies in `T_k` or on layer `k`'s plane. *Proof.* Unsafe: plane `j` is affine over the
//! footprint square, so its `z` there is at least its smallest corner `z >= tz_p`, and points
//! behind it have larger `z`. Safe: `f_k` is affine, so on the footprint square
//! `g(x, y) = f_k(x, y, z_j(x, y))` is affine and its maximum is at a corner,
//! `<= -1e-6 < 0`; `N_k.z <= 0` makes `f_k` non-increasing in `z`, so points behind plane
//! `j` have `f_k` smaller still. ∎
//!
//! **Lemma 2.** If the ray enters `T_k` first at `s_k` (its first point in `T_k`), then no
//! plane of a layer `j > k` is hit, and no occlusion volume of such a layer is entered,
//! before `s_k`. *Proof.* A hit at `s` is a point of plane `j`; a brute-force occlusion
//! entry at `s` is the footprint entry point `P(s)` lying behind plane `j`. By Lemma 1 both
//! are in `T_k` (or on plane `k`, which is then a layer-`k` hit at `s`, and lower layers win
//! ties), so `s >= s_k`. ∎
//!
//! **Algorithm.** With the window `[s_lo, s_hi] = [0, 1]`, for `k = 0, 1, ...`: traverse
//! layer `k` over the window, stopping at its first hit; record its first trigger entry, its
//! first occlusion entry and its hit. A hit lowers `s_hi` (deeper layers must beat it
//! strictly). If `k` is the last layer or the ray never entered `T_k`, stop; else
//! `s_lo := s_k`. By Lemma 2 (applied to every `k' < j`, since unsafe flags of layer `k`
//! are computed against *all* deeper layers) every hit and occlusion entry of deeper layers
//! lies in the window that is traced, so the closest hit and the first occlusion entry over
//! all layers are found — the brute-force answer. The traversal of layer `k` detects `T_k`
//! through the extruded boxes (`[min z, 1]`, `min z = 0` above unsafe pixels) while a trigger
//! or occlusion entry is still wanted, and plain boxes afterwards.
//!
//! Almost all rays of small reprojections hit layer 0 before entering `T_0`, so layer 1 is
//! traced for few rays (the examples measure the fraction).
//!
//! **Inpaint mode** ([`super::LayerMode::Inpaint`]): on the last layer the traversal stops at
//! the first occlusion-volume entry `s_o` and returns it moved back by
//! [`super::INPAINT_DILATION_PX`] pixels of ray travel (not before the window start) — the
//! dilated occlusion volume of §4.1 — with the pixel under that point, which is the pixel the
//! ray crossed just before passing behind the silhouette (the background side).
//!
//! **Crack dilation** (flag `O`: depth normals or `NormalSource::GBufferFlagged`) intersects flagged planes slightly
//! outside their footprints; it is a deliberate deviation from the brute-force planes (set
//! `crack_dilation = 0` for exact agreement), and Lemma 1 does not account for it.

use std::time::Instant;

use glam::{UVec2, Vec3, Vec4};
use parallax_core::cpu_time::{ms_between, process_cpu_ns};
use parallax_core::{GBuffer, Ray};
use rayon::prelude::*;

use super::node::plane_z;
use super::traverse::{LayerEvents, Query, RaySetup};
use super::tree::QuadTree;
use super::{INPAINT_DILATION_PX, LayerMode, QuadTreeOptions};
use crate::depth_layers::{Clip, PixelRay};
use crate::{
    CubeSegment, LayerPlanes, ScreenError, ScreenTracer, TraceResult, TraceStats, UnitCube,
};

/// Margin of the safety test (in `f` units).
pub(super) const SAFE_MARGIN: f32 = 1e-6;

/// The quad-trees of all layers of one reference view (§3-§4.1).
#[derive(Clone, Debug)]
pub struct QuadTreeTracer {
    pub cube: UnitCube,
    pub trees: Vec<QuadTree>,
    pub opts: QuadTreeOptions,
    build_ms: Vec<f64>,
    build_cpu_ms: Vec<f64>,
    unsafe_pixels: Vec<usize>,
    /// The f32 cube clip shared with the baselines ([`Self::with_f32_clip`]).
    clip: Clip,
    pub(super) f32_clip: bool,
}

impl QuadTreeTracer {
    /// Builds one tree per layer (layer 0 first) and the cascade flags.
    pub fn build(
        cube: &UnitCube,
        layers: &[GBuffer],
        opts: &QuadTreeOptions,
    ) -> Result<Self, ScreenError> {
        Self::build_impl(cube, layers, opts, false)
    }

    /// [`Self::build`] by the definitions: the slow twin of the tests, equal bit for bit
    /// (`tests/quadtree_build.rs`). It prunes the whole tree on every iteration of the
    /// cascade's fixed point and computes every trigger depth from full per-pixel plane
    /// arrays, one footprint corner at a time.
    pub fn build_reference(
        cube: &UnitCube,
        layers: &[GBuffer],
        opts: &QuadTreeOptions,
    ) -> Result<Self, ScreenError> {
        Self::build_impl(cube, layers, opts, true)
    }

    fn build_impl(
        cube: &UnitCube,
        layers: &[GBuffer],
        opts: &QuadTreeOptions,
        reference: bool,
    ) -> Result<Self, ScreenError> {
        if layers.is_empty() {
            return Err(ScreenError::Mismatch("no layers".into()));
        }
        // Deepest layer first: each layer's cascade flags need the deeper layers' final
        // effective planes.
        let nl = layers.len();
        let mut trees: Vec<Option<QuadTree>> = vec![None; nl];
        let mut build_ms = vec![0.0; nl];
        let mut build_cpu_ms = vec![0.0; nl];
        let mut unsafe_pixels = vec![0; nl];
        let mut eff: Vec<LayerPlanes> = Vec::new(); // layers k+1.. in order
        for k in (0..nl).rev() {
            let (t, c) = (Instant::now(), process_cpu_ns());
            let tree = QuadTree::build_cascaded(cube, &layers[k], opts, &eff, reference)?;
            if k > 0 {
                eff.insert(0, tree.effective_planes());
            }
            build_ms[k] = t.elapsed().as_secs_f64() * 1e3;
            build_cpu_ms[k] = ms_between(c, process_cpu_ns());
            unsafe_pixels[k] = tree.unsafe_count;
            trees[k] = Some(tree);
        }
        let trees: Vec<QuadTree> = trees.into_iter().map(|t| t.unwrap()).collect();
        Ok(Self {
            cube: cube.clone(),
            trees,
            opts: *opts,
            build_ms,
            build_cpu_ms,
            unsafe_pixels,
            clip: Clip::new(cube),
            f32_clip: false,
        })
    }

    /// Clip rays to the cube with the baselines' f32 clip instead of the f64
    /// [`UnitCube::clip_ray`] (default off). **Not exact**: a ray lying exactly on a pixel
    /// boundary (test `quadtree_edge.rs`, a ray in the plane `y = 1/2`) can land on the other
    /// side of it after f32 rounding and hit a different plane than
    /// [`crate::BruteForcePlanes`], which clips in f64; and no measurable gain
    /// (`docs/notes/quadtree.md`, "what we tried first").
    pub fn with_f32_clip(mut self, on: bool) -> Self {
        self.f32_clip = on;
        self
    }

    /// Build time per layer in ms (tree construction incl. its per-pixel planes, plus that
    /// layer's share of the cascade flags), measured inside [`Self::build`].
    pub fn build_ms(&self) -> Vec<f64> {
        self.build_ms.clone()
    }

    /// Process CPU time per layer in ms (all threads, rayon's idle spinning included; NaN
    /// where the clock is unavailable), over the same span as [`Self::build_ms`]: less
    /// sensitive than wall time to other jobs on the machine.
    pub fn build_cpu_ms(&self) -> Vec<f64> {
        self.build_cpu_ms.clone()
    }

    /// Bytes of all trees' node arrays.
    pub fn bytes(&self) -> usize {
        self.trees.iter().map(|t| t.bytes()).sum()
    }

    /// Pixels per layer marked unsafe for cascading (0 for the last layer).
    /// See the module docs.
    pub fn unsafe_pixels(&self) -> &[usize] {
        &self.unsafe_pixels
    }
}

/// Trigger depths of a layer's pixel planes `pk` against all `deeper` layers' effective
/// planes (module docs, "Trigger region"): `+inf` for safe pixels, else the minimum over
/// deeper planes of their footprint-corner `z` minus [`SAFE_MARGIN`] (0 for a deeper plane
/// seen edge-on). The definition: one corner at a time ([`pixel_trigger`]); the build's
/// fast path evaluates the four corners in lanes ([`pixel_trigger_lanes`], same bits).
pub(crate) fn trigger_depths(pk: &LayerPlanes, deeper: &[LayerPlanes]) -> Vec<f32> {
    let (w, h) = (pk.width, pk.height);
    let (wf, hf) = (w as f32, h as f32);
    let mut tz = vec![f32::INFINITY; (w * h) as usize];
    tz.par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(j, row)| {
            let j = j as u32;
            let (y0, y1) = (j as f32 / hf, (j + 1) as f32 / hf);
            for i in 0..w {
                let idx = (j * w + i) as usize;
                let (x0, x1) = (i as f32 / wf, (i + 1) as f32 / wf);
                let plane = pk.covered(idx).then(|| (pk.normal[idx], pk.offset[idx]));
                row[i as usize] = pixel_trigger(idx, (x0, x1, y0, y1), plane, deeper);
            }
        });
    tz
}

/// The trigger depth of pixel `idx` with footprint `(x0, x1, y0, y1)` (cube units) and
/// plane `plane` (`N·P = c`, `None`: empty) against the `deeper` layers ([`trigger_depths`]).
fn pixel_trigger(
    idx: usize,
    (x0, x1, y0, y1): (f32, f32, f32, f32),
    plane: Option<(Vec3, f32)>,
    deeper: &[LayerPlanes],
) -> f32 {
    trigger_over(idx, deeper, |nj, cj, front| {
        let mut bad = false;
        for (x, y) in [(x0, y0), (x1, y0), (x0, y1), (x1, y1)] {
            let z = plane_z(nj, cj, x, y);
            *front = front.min(z);
            let f = match plane {
                Some((n, c)) => n.dot(Vec3::new(x, y, z)) - c,
                None => f32::NAN,
            };
            if !(f <= -SAFE_MARGIN) {
                bad = true;
            }
        }
        bad
    })
}

/// The *deeper front* of pixel `idx` with footprint `(x0, x1, y0, y1)`: the smallest
/// footprint-corner `z` of the `deeper` layers' planes there, computed as
/// [`pixel_trigger`] computes them (`plane_z`), `+inf` where no deeper layer has a plane,
/// `-inf` where a deeper plane is edge-on (`!(n.z < -1e-6)`) or a corner `z` is NaN. It does
/// not depend on this layer's plane: the leaf pass stores it so that the fixed point can
/// certify pixels safe against a merged proxy plane without their corners
/// ([`proxy_safe_front`]).
pub(crate) fn deeper_front(
    idx: usize,
    (x0, x1, y0, y1): (f32, f32, f32, f32),
    deeper: &[LayerPlanes],
) -> f32 {
    let mut front = f32::INFINITY;
    for pj in deeper {
        if !pj.covered(idx) {
            continue;
        }
        let (nj, cj) = (pj.normal[idx], pj.offset[idx]);
        // Edge-on: `!(nj.z < -1e-6)`.
        if nj.z >= -1e-6 || nj.z.is_nan() {
            return f32::NEG_INFINITY;
        }
        for (x, y) in [(x0, y0), (x1, y0), (x0, y1), (x1, y1)] {
            let z = plane_z(nj, cj, x, y);
            if z.is_nan() {
                return f32::NEG_INFINITY;
            }
            if z < front {
                front = z;
            }
        }
    }
    front
}

/// A threshold `T` for plane `(n, c)` (`N·P = c`, as the trigger tests evaluate it) over the
/// footprint rectangle `[x_lo, x_hi] x [y_lo, y_hi]` (`0 <= x, y <= 1`): every pixel in it
/// whose [`deeper_front`] is `>= T` has an infinite trigger depth against this plane
/// (`+inf` when `n.z >= 0` or a value is not finite: no pixel is certified).
///
/// *Proof.* The trigger test evaluates `f = ((n.x x + n.y y) + n.z z) - c` in f32 at a
/// corner `(x, y)` of the footprint with a deeper plane's corner `z >= front >= T >= 0`; it
/// is safe iff `f <= -SAFE_MARGIN`. Three products and three sums, no fused operations:
/// `|f - f_exact| <= g (|n.x| + |n.y| + |n.z| z + |c|)` with `g = 1e-6` (above `4 u / (1 - 4
/// u)`, `u = 2^-24`). With `n.z < 0`, `f_exact = n.x x + n.y y + n.z z - c <= M - |n.z| z`,
/// `M = max(n.x x_lo, n.x x_hi) + max(n.y y_lo, n.y y_hi) - c`. So `f <= M + g A - |n.z| (1 -
/// g) z` (`A = |n.x| + |n.y| + |c|`), decreasing in `z`; at `z = T = (M + g A + 2e-6) /
/// (|n.z| (1 - g))` it is `-2e-6 < -SAFE_MARGIN`. `T` is computed in f64 (exact products of
/// f32 values, sums with errors ~1e-16 far inside the 1e-6 of slack) and rounded up to
/// f32; it is clamped to `>= 0` (the error bound used `z >= 0`). A NaN corner `z` or an
/// edge-on deeper plane gives `front = -inf`, never certified; an overflowing `n.z z` gives
/// `f = -inf`, safe.
pub(crate) fn proxy_safe_front(
    (n, c): (Vec3, f32),
    (x_lo, x_hi): (f32, f32),
    (y_lo, y_hi): (f32, f32),
) -> f32 {
    const G: f64 = 1e-6;
    let (nx, ny, nz, c) = (n.x as f64, n.y as f64, n.z as f64, c as f64);
    if nz >= 0.0 || nz.is_nan() {
        return f32::INFINITY;
    }
    let m = (nx * x_lo as f64).max(nx * x_hi as f64) + (ny * y_lo as f64).max(ny * y_hi as f64) - c;
    let a = nx.abs() + ny.abs() + c.abs();
    let t = (m + G * a + 2e-6) / (-nz * (1.0 - G));
    if !t.is_finite() {
        return f32::INFINITY;
    }
    // Rounded up: a relative 1e-6 above any f32 rounding of a positive value.
    let t = (t.max(0.0) * (1.0 + 1e-6) + 1e-30) as f32;
    if t.is_finite() { t } else { f32::INFINITY }
}

/// [`pixel_trigger`] with the four footprint corners in the lanes of `xs`, `ys`
/// (`(x0, x1, x0, x1)`, `(y0, y0, y1, y1)`) and the pixel's plane computed by `plane` only
/// where a deeper plane needs it (at most once): every lane does the scalar definition's
/// operations in its order (`plane_z`, the `Vec3` dot left to right; no fused multiply-add),
/// so the result is the same bits (`tests/quadtree_build.rs` compares whole trees with the
/// definition's build).
#[inline]
pub(crate) fn pixel_trigger_lanes(
    idx: usize,
    xs: Vec4,
    ys: Vec4,
    mut plane: impl FnMut() -> Option<(Vec3, f32)>,
    deeper: &[LayerPlanes],
) -> f32 {
    let s = Vec4::splat;
    let mut decoded: Option<Option<(Vec3, f32)>> = None;
    trigger_over(idx, deeper, |nj, cj, front| {
        let z = (s(cj) - s(nj.x) * xs - s(nj.y) * ys) / s(nj.z);
        // `front.min(zc)` of the definition as one `minss` each: `front` is never NaN and a
        // NaN corner is skipped as there; at a tie of `+0` and `-0` the sign may differ,
        // which the trigger depth `max(front - margin, +0)` does not see (`±0 - margin` is
        // the same value).
        for zc in z.to_array() {
            *front = if zc < *front { zc } else { *front };
        }
        match *decoded.get_or_insert_with(&mut plane) {
            Some((n, c)) => {
                let f = s(n.x) * xs + s(n.y) * ys + s(n.z) * z - s(c);
                !f.cmple(s(-SAFE_MARGIN)).all()
            }
            None => true,
        }
    })
}

/// The trigger depth of pixel `idx` from its deeper planes: `corners(N_j, c_j, front)`
/// lowers `front` to the plane's corner `z` and answers whether a corner is not safely
/// behind this layer's plane; a plane seen edge-on is unsafe with `front = 0`.
#[inline(always)]
fn trigger_over(
    idx: usize,
    deeper: &[LayerPlanes],
    mut corners: impl FnMut(Vec3, f32, &mut f32) -> bool,
) -> f32 {
    let mut bad = false;
    let mut front = f32::INFINITY;
    for pj in deeper {
        if !pj.covered(idx) {
            continue;
        }
        let (nj, cj) = (pj.normal[idx], pj.offset[idx]);
        if !(nj.z < -1e-6) {
            bad = true;
            front = 0.0;
            continue;
        }
        if corners(nj, cj, &mut front) {
            bad = true;
        }
    }
    if bad {
        let t = front - SAFE_MARGIN;
        if t > 0.0 { t } else { 0.0 }
    } else {
        f32::INFINITY
    }
}

impl QuadTreeTracer {
    /// Traces `ray` through the layers; see the module docs for the semantics.
    pub fn trace_ray(&self, ray: &Ray, stats: &mut TraceStats) -> TraceResult {
        self.trace_layers(ray, stats).0
    }

    /// [`Self::trace_ray`] and the number of layers the ray was traversed in (0 when it
    /// misses the cube, 1 when layer 0 settled it, ...).
    pub fn trace_layers(&self, ray: &Ray, stats: &mut TraceStats) -> (TraceResult, usize) {
        self.trace_impl(ray, stats)
    }

    /// [`Self::trace_layers`], inlined into [`ScreenTracer::trace`] too (no call and no
    /// copy of the returned pair per ray).
    #[inline(always)]
    fn trace_impl(&self, ray: &Ray, stats: &mut TraceStats) -> (TraceResult, usize) {
        let seg = if self.f32_clip {
            // f32 rounding can lose a segment that only grazes a face, so when the f32 clip
            // finds nothing the f64 clip decides.
            match PixelRay::new(&self.clip, ray, f32::INFINITY) {
                Some(p) => Some(p.seg),
                None => self.cube.clip_ray(ray),
            }
        } else {
            self.cube.clip_ray(ray)
        };
        let Some(seg) = seg else {
            return (TraceResult::Miss, 0);
        };
        // The f64 clip clamps its end points to [0, 1] (NaN to 0), so they are finite; only
        // the opt-in f32 clip's need the check (a per-ray saving of ~40 instructions).
        debug_assert!(self.f32_clip || (seg.p0.is_finite() && seg.p1.is_finite()));
        if self.f32_clip && !(seg.p0.is_finite() && seg.p1.is_finite()) {
            return (TraceResult::Miss, 0);
        }
        let t0 = &self.trees[0];
        let rs = RaySetup::new(&seg, t0.wf, t0.hf);
        self.trace_segment(ray, &seg, &rs, stats)
    }

    /// [`Self::trace_impl`] after the clip and the set-up: `seg` is `ray`'s cube segment and
    /// `rs` its [`RaySetup`] (also the batches' last phase, `quadtree/batch.rs`).
    #[inline(always)]
    pub(super) fn trace_segment(
        &self,
        ray: &Ray,
        seg: &CubeSegment,
        rs: &RaySetup,
        stats: &mut TraceStats,
    ) -> (TraceResult, usize) {
        let t0 = &self.trees[0];
        let nl = self.trees.len();
        if nl == 1 && self.opts.mode == LayerMode::Cascade {
            // One layer without inpainting: the general loop below with its query fixed
            // (no trigger, no stop at occlusion), so the inlined traversal drops the cascade
            // bookkeeping. Same result.
            let q = Query::WHOLE;
            let ev = t0.trace_layer(rs, &q, stats);
            return (one_layer_result(ray, seg, &ev, stats), 1);
        }
        let mut q = Query::WHOLE;
        let mut best_hit: Option<(f32, UVec2, u32)> = None;
        let mut best_ov: Option<(f32, UVec2, u32)> = None;
        let mut inpainted = false;
        let mut reached = 0;
        for (k, tree) in self.trees.iter().enumerate() {
            reached = k + 1;
            let last = k + 1 == nl;
            q.want_trigger = !last;
            q.stop_at_ov = last && self.opts.mode == LayerMode::Inpaint;
            let ev = tree.trace_layer(rs, &q, stats);
            if let Some((s, px)) = ev.hit {
                best_hit = Some((s, px, k as u32));
                q.s_hi = s;
                q.hi_inclusive = false;
            }
            if let Some((s, px)) = ev.ov
                && best_ov.is_none_or(|b| s < b.0)
            {
                best_ov = Some((s, px, k as u32));
            }
            if q.stop_at_ov
                && ev.hit.is_none()
                && let Some((s, _)) = ev.ov
            {
                // Inpaint: the occlusion entry precedes any remaining hit of this layer.
                let sd = (s - INPAINT_DILATION_PX * rs.s_per_px).max(q.s_lo);
                let (w, h) = tree.size();
                let px = UVec2::new(
                    (rs.at(0, sd).floor().max(0.0) as u32).min(w - 1),
                    (rs.at(1, sd).floor().max(0.0) as u32).min(h - 1),
                );
                best_ov = Some((sd, px, k as u32));
                inpainted = true;
            }
            if last {
                break;
            }
            match ev.trigger {
                Some(s) if s < q.s_hi || (q.hi_inclusive && s <= q.s_hi) => q.s_lo = s,
                _ => break,
            }
        }
        if !inpainted && let Some((s, pixel, layer)) = best_hit {
            stats.hits += 1;
            let t = seg.world_t(s);
            let r = TraceResult::Hit {
                layer,
                pixel,
                position: ray.at(t),
                t,
            };
            return (r, reached);
        }
        if let Some((s, pixel, layer)) = best_ov {
            stats.occlusion_volumes += 1;
            let r = TraceResult::OcclusionVolume {
                layer,
                pixel,
                t: seg.world_t(s),
            };
            return (r, reached);
        }
        (TraceResult::Miss, reached)
    }
}

/// The answer of a single-layer cascade trace of `ray` (segment `seg`) from its layer-0
/// events, with the hit / occlusion counts.
#[inline(always)]
pub(super) fn one_layer_result(
    ray: &Ray,
    seg: &CubeSegment,
    ev: &LayerEvents,
    stats: &mut TraceStats,
) -> TraceResult {
    if let Some((s, pixel)) = ev.hit {
        stats.hits += 1;
        let t = seg.world_t(s);
        return TraceResult::Hit {
            layer: 0,
            pixel,
            position: ray.at(t),
            t,
        };
    }
    if let Some((s, pixel)) = ev.ov {
        stats.occlusion_volumes += 1;
        return TraceResult::OcclusionVolume {
            layer: 0,
            pixel,
            t: seg.world_t(s),
        };
    }
    TraceResult::Miss
}

impl ScreenTracer for QuadTreeTracer {
    fn trace(&self, ray: &Ray, stats: &mut TraceStats) -> TraceResult {
        stats.rays += 1;
        self.trace_impl(ray, stats).0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadtree::node::{Node, decode_plane};
    use crate::quadtree::test_rng::Rng;

    /// [`proxy_safe_front`] certifies only pixels the definition finds safe: random merged
    /// nodes (levels 1-5, random gentle slopes) over one or two deeper layers whose planes lie a
    /// little (down to 1e-7) or far behind the node's plane, cross it, or are edge-on or
    /// missing; every pixel whose [`deeper_front`] reaches the node's threshold has an
    /// infinite [`pixel_trigger`] against the node's decoded plane.
    #[test]
    fn certified_pixels_are_safe() {
        let (w, h) = (64u32, 48u32);
        let (wf, hf) = (w as f32, h as f32);
        let mut rng = Rng(0x5eed_0fc0_ffee);
        let (mut certified, mut total) = (0usize, 0usize);
        for case in 0..400u32 {
            let l = 1 + case % 5;
            let (qx, qy) = (rng.next() as u32 % (w >> l), rng.next() as u32 % (h >> l));
            let zc = rng.f(0.05, 0.95);
            let (gx, gy) = (rng.f(-0.1, 0.1), rng.f(-0.1, 0.1));
            let Some(node) = Node::plane_with_gradient(zc, gx, gy, l, wf, hf, 0) else {
                continue;
            };
            let (n, c) = decode_plane(node, l, qx, qy, wf, hf);
            let (x0, y0) = (qx << l, qy << l);
            let (x1, y1) = (((qx + 1) << l).min(w), ((qy + 1) << l).min(h));
            let n_px = (w * h) as usize;
            // Deeper planes: the node's plane pushed back by a random gap (some negative),
            // tilted a little.
            let deeper: Vec<LayerPlanes> = (0..1 + case % 2)
                .map(|_| {
                    let mut normal = vec![Vec3::ZERO; n_px];
                    let mut offset = vec![0.0f32; n_px];
                    for j in y0..y1 {
                        for i in x0..x1 {
                            let k = (j * w + i) as usize;
                            let gap = match rng.next() % 6 {
                                0 => -rng.f(0.0, 1e-3),
                                1 => rng.f(0.0, 1e-5),
                                2 => rng.f(0.0, 1e-7),
                                _ => rng.f(0.0, 0.2),
                            };
                            let nj = match rng.next() % 16 {
                                0 => Vec3::ZERO,
                                1 => Vec3::new(0.6, 0.8, -1e-7),
                                _ => (n + Vec3::new(rng.f(-1e-3, 1e-3), rng.f(-1e-3, 1e-3), 0.0))
                                    .normalize(),
                            };
                            let p = Vec3::new(i as f32 / wf, j as f32 / hf, 0.0);
                            let zp = plane_z(n, c, p.x, p.y) + gap;
                            normal[k] = nj;
                            offset[k] = nj.dot(Vec3::new(p.x, p.y, zp));
                        }
                    }
                    LayerPlanes {
                        width: w,
                        height: h,
                        normal,
                        offset,
                        flag: vec![false; n_px],
                    }
                })
                .collect();
            for j in y0..y1 {
                let (fy0, fy1) = (j as f32 / hf, (j + 1) as f32 / hf);
                let t = proxy_safe_front((n, c), (x0 as f32 / wf, x1 as f32 / wf), (fy0, fy1));
                for i in x0..x1 {
                    let k = (j * w + i) as usize;
                    let fp = (i as f32 / wf, (i + 1) as f32 / wf, fy0, fy1);
                    total += 1;
                    if deeper_front(k, fp, &deeper) >= t {
                        certified += 1;
                        let tz = pixel_trigger(k, fp, Some((n, c)), &deeper);
                        assert_eq!(tz, f32::INFINITY, "case {case} pixel ({i}, {j})");
                    }
                }
            }
        }
        assert!(
            certified > total / 8 && certified < total,
            "{certified} of {total} certified"
        );
    }
}
