//! The cascade trigger depths ([`super::cascade`], `pixel_trigger`) of four neighbouring
//! pixels of a row at once, one pixel per lane (x86_64 SSE2): the fast path of
//! `fixpoint::pixel_triggers_row` (each pixel against its own leaf's plane) and of
//! `fixpoint::merged_triggers` (against a merged node's plane: one node's run of four
//! pixels, or two level-1 runs of two).
//!
//! Every lane does exactly the scalar definition's operations in its order, so the trigger
//! depths are the same bits (`tests/quadtree_build.rs` compares whole trees, trigger depths
//! included, with the reference build, which runs the definition):
//!
//! - a pixel's own leaf's plane as [`super::node::decode_plane_at`] at level 0: the f16 slopes
//!   decoded by `f16_bits_to_f32`'s integer operations, the gradient, the power-of-two
//!   scale of [`Node::test_normal`] from the exponent bits (`maxps` is its compare-select),
//!   `c = (n.x x_c + n.y y_c) + n.z z_c`; computed for every lane, used only where a deeper
//!   plane needs it (the definition decodes lazily; the decode has no side effect);
//! - per deeper layer in order, the lanes it covers (`normal != 0`); an edge-on deeper plane
//!   (`!(n.z < -1e-6)`) makes the lane unsafe with `front = 0`; otherwise per footprint
//!   corner, in the definition's corner order, the deeper plane's `z = ((c_j - n_j.x x) -
//!   n_j.y y) / n_j.z`, the running minimum `front` by the same compare-select (so the same
//!   value, signed zeros included), and the own plane's `f = ((n.x x + n.y y) + n.z z) - c`,
//!   unsafe unless `f <= -SAFE_MARGIN` (or when the pixel has no plane);
//! - the trigger depth `max(front - margin, +0)` of unsafe lanes, `+inf` elsewhere.
//!
//! The deeper layers' normals are read as four consecutive `Vec3`s (no per-lane arrays
//! written and read back).

use core::arch::x86_64::*;

use glam::Vec4;

use super::cascade::SAFE_MARGIN;
use super::node::Node;
use crate::LayerPlanes;

// SAFETY (all `unsafe` blocks below): SSE and SSE2 are part of the x86_64 baseline; the
// unaligned loads read four consecutive, bounds-checked elements.

/// [`super::node::f16_bits_to_f32`] of the low 16 bits of each lane (the same integer
/// operations, the subnormal case by the same exact conversion and product).
#[inline(always)]
pub(super) fn f16x4(h: __m128i) -> Vec4 {
    // SAFETY: SSE2 is part of the x86_64 baseline.
    unsafe {
        let mag = _mm_and_si128(h, _mm_set1_epi32(0x7fff));
        let normal = _mm_add_epi32(_mm_slli_epi32(mag, 13), _mm_set1_epi32(0x3800_0000));
        let sub = _mm_castps_si128(_mm_mul_ps(
            _mm_cvtepi32_ps(mag),
            _mm_castsi128_ps(_mm_set1_epi32(0x3380_0000)),
        ));
        let is_sub = _mm_cmplt_epi32(mag, _mm_set1_epi32(0x400));
        let v = _mm_or_si128(_mm_and_si128(sub, is_sub), _mm_andnot_si128(is_sub, normal));
        let sign = _mm_slli_epi32(_mm_and_si128(h, _mm_set1_epi32(0x8000)), 16);
        Vec4::from(_mm_castsi128_ps(_mm_or_si128(v, sign)))
    }
}

/// `select(m, a, b)` per lane.
#[inline(always)]
fn sel(m: __m128, a: Vec4, b: Vec4) -> Vec4 {
    unsafe {
        Vec4::from(_mm_or_ps(
            _mm_and_ps(m, a.into()),
            _mm_andnot_ps(m, b.into()),
        ))
    }
}

/// Four consecutive `f32`s as lanes.
#[inline(always)]
fn load4(v: &[f32]) -> Vec4 {
    let v = &v[..4];
    unsafe { Vec4::from(_mm_loadu_ps(v.as_ptr())) }
}

/// The trigger depths of the pixels `k .. k + 4` (row `j`, columns `i .. i + 4`) from their
/// leaves `nodes` (4), the footprint edges `xe[i .. i + 5]` (`x / W`), the pixel centres
/// `xc[i .. i + 4]`, the row's edges `y0`, `y1` and centre `yc` (module docs); and the
/// pixels' deeper fronts ([`super::cascade::deeper_front`], same bits).
#[allow(clippy::too_many_arguments)]
#[inline]
pub(super) fn pixel_triggers4(
    k: usize,
    nodes: &[Node],
    xe: &[f32],
    xc: &[f32],
    (y0, y1, yc): (f32, f32, f32),
    (wf, hf): (f32, f32),
    deeper: &[LayerPlanes],
) -> (Vec4, Vec4) {
    let s = Vec4::splat;
    let nodes = &nodes[..4];
    // The own planes (`decode_plane_at`, level 0: the scale `w 2^-0` is `w`).
    let (a, b) = unsafe {
        let lo = _mm_loadu_ps(nodes.as_ptr() as *const f32);
        let hi = _mm_loadu_ps(nodes[2..].as_ptr() as *const f32);
        (
            _mm_castps_si128(_mm_shuffle_ps(lo, hi, 0b10_00_10_00)),
            _mm_castps_si128(_mm_shuffle_ps(lo, hi, 0b11_01_11_01)),
        )
    };
    let gx = f16x4(b) * s(wf);
    let gy = unsafe { f16x4(_mm_srli_epi32(b, 16)) } * s(hf);
    let (pnx, pny, pnz, pc, plane) = unsafe {
        let m = _mm_max_ps(gx.abs().into(), gy.abs().into());
        let m = _mm_max_ps(m, _mm_set1_ps(1.0));
        let e = _mm_and_si128(_mm_castps_si128(m), _mm_set1_epi32(0x7f80_0000));
        let sc = Vec4::from(_mm_castsi128_ps(_mm_sub_epi32(
            _mm_set1_epi32(0x7f00_0000),
            e,
        )));
        let (nx, ny, nz) = (gx * sc, gy * sc, -sc);
        let zc = Vec4::from(_mm_castsi128_ps(_mm_and_si128(
            a,
            _mm_set1_epi32(0x7fff_fffc),
        )));
        let c = nx * load4(xc) + ny * s(yc) + nz * zc;
        // Plane leaves: the tag in the sign bit of `a`.
        (nx, ny, nz, c, _mm_castsi128_ps(_mm_srai_epi32(a, 31)))
    };
    triggers4(k, (pnx, pny, pnz, pc, plane), xe, (y0, y1), deeper)
}

/// The trigger depths of the pixels `k .. k + 4` of one merged node's run: its plane `(n,
/// c)` in every lane.
#[inline]
pub(super) fn merged_triggers4(
    k: usize,
    (n, c): (glam::Vec3, f32),
    xe: &[f32],
    y: (f32, f32),
    deeper: &[LayerPlanes],
) -> Vec4 {
    let s = Vec4::splat;
    let all = unsafe { _mm_castsi128_ps(_mm_set1_epi32(-1)) };
    triggers4(k, (s(n.x), s(n.y), s(n.z), s(c), all), xe, y, deeper).0
}

/// [`merged_triggers4`] of two runs of two pixels: plane `a` in the first two lanes, `b`
/// in the last two.
#[inline]
pub(super) fn merged_pair_triggers4(
    k: usize,
    (a, ca): (glam::Vec3, f32),
    (b, cb): (glam::Vec3, f32),
    xe: &[f32],
    y: (f32, f32),
    deeper: &[LayerPlanes],
) -> Vec4 {
    let all = unsafe { _mm_castsi128_ps(_mm_set1_epi32(-1)) };
    let two = |u: f32, v: f32| Vec4::new(u, u, v, v);
    let planes = (
        two(a.x, b.x),
        two(a.y, b.y),
        two(a.z, b.z),
        two(ca, cb),
        all,
    );
    triggers4(k, planes, xe, y, deeper).0
}

/// The trigger depths of the pixels `k .. k + 4` with their own planes `(n.x, n.y, n.z, c)`
/// per lane and a lane mask of the pixels that have one, the footprint edges `xe[i .. i +
/// 5]` and the row's edges `y0`, `y1` (module docs); and the pixels' deeper fronts
/// ([`super::cascade::deeper_front`]: `front`, or `-inf` where a deeper plane is edge-on or
/// a corner `z` is NaN).
#[inline(always)]
fn triggers4(
    k: usize,
    (pnx, pny, pnz, pc, plane): (Vec4, Vec4, Vec4, Vec4, __m128),
    xe: &[f32],
    (y0, y1): (f32, f32),
    deeper: &[LayerPlanes],
) -> (Vec4, Vec4) {
    let s = Vec4::splat;
    let (x0, x1) = (load4(&xe[..4]), load4(&xe[1..5]));
    let corners = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)];
    let mut front = s(f32::INFINITY);
    let mut bad = unsafe { _mm_setzero_ps() };
    // Lanes with an edge-on deeper plane or a NaN corner `z`: deeper front `-inf`.
    let mut void = unsafe { _mm_setzero_ps() };
    for pj in deeper {
        let n = &pj.normal[k..k + 4];
        let (nx, ny, nz) = (
            Vec4::new(n[0].x, n[1].x, n[2].x, n[3].x),
            Vec4::new(n[0].y, n[1].y, n[2].y, n[3].y),
            Vec4::new(n[0].z, n[1].z, n[2].z, n[3].z),
        );
        let cj = load4(&pj.offset[k..]);
        unsafe {
            // `covered`: `normal != Vec3::ZERO`.
            let z0 = _mm_setzero_ps();
            let covered = _mm_or_ps(
                _mm_or_ps(_mm_cmpneq_ps(nx.into(), z0), _mm_cmpneq_ps(ny.into(), z0)),
                _mm_cmpneq_ps(nz.into(), z0),
            );
            // `!(nj.z < -1e-6)`: unsafe, `front = 0`.
            let edge = _mm_andnot_ps(_mm_cmplt_ps(nz.into(), _mm_set1_ps(-1e-6)), covered);
            bad = _mm_or_ps(bad, edge);
            void = _mm_or_ps(void, edge);
            front = sel(edge, Vec4::ZERO, front);
            let live = _mm_andnot_ps(edge, covered);
            if _mm_movemask_ps(live) == 0 {
                continue;
            }
            for &(x, y) in &corners {
                let z = (cj - nx * x - ny * s(y)) / nz;
                void = _mm_or_ps(void, _mm_and_ps(live, _mm_cmpunord_ps(z.into(), z.into())));
                let lower = _mm_and_ps(live, _mm_cmplt_ps(z.into(), front.into()));
                front = sel(lower, z, front);
                let f = pnx * x + pny * s(y) + pnz * z - pc;
                let safe = _mm_and_ps(_mm_cmple_ps(f.into(), _mm_set1_ps(-SAFE_MARGIN)), plane);
                bad = _mm_or_ps(bad, _mm_andnot_ps(safe, live));
            }
        }
    }
    let t = front - s(SAFE_MARGIN);
    let t = unsafe { sel(_mm_cmpgt_ps(t.into(), _mm_setzero_ps()), t, Vec4::ZERO) };
    (
        sel(bad, t, s(f32::INFINITY)),
        sel(void, s(f32::NEG_INFINITY), front),
    )
}
