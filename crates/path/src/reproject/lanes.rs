//! The bilinear footprint's four taps tested in the lanes of SSE vectors (x86-64), for
//! [`super::footprint`]: the source texels' positions and normals are loaded 16 bytes at a
//! time and transposed so that one vector holds one component of all four taps.
//!
//! **Invariants:** the result is the scalar tap loop's bit for bit (every lane does the
//! scalar operations in the same order; tested in `footprint`'s tests against the scalar and
//! general kernels); the caller guarantees that all four taps lie inside the source.
//!
//! | parameter | type | meaning |
//! |---|---|---|
//! | `wt` | Vec4 | the four taps' weights, row-major from `(x0, y0)` |
//! | `pos2`, `nrm2` | f32 | squared position limit and squared normal chord |
//! | `plane` | bool | position measured against the target's tangent plane |

use std::arch::x86_64::*;

use glam::Vec4;

use super::buffers::{EyeView, Texel};

/// The four taps of a bilinear footprint, all inside the source, tested in the lanes of SSE
/// vectors (lane = tap, row-major from `(x0, y0)`): every lane does the operations of the
/// scalar tap loop of `footprint::footprint_in` in the same order (differences, products
/// summed as glam's `dot`, strict compares), and the kept weights are summed lane by lane in tap order (a
/// dropped tap adds +0, which leaves a sum of non-negative weights unchanged), so the result
/// is the scalar loop's bit for bit. `wt` are the taps' weights (the products of the tent
/// weights of their column and row, in tap order); `pos2`, `nrm2` the squared limits, `plane` the
/// tangent-plane test. Returns `(mask, sum, inside, near, kept)`, `kept` the weights with the
/// dropped taps' lanes +0.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn bilinear_taps_x4(
    source: &EyeView,
    t: &Texel,
    x0: i32,
    y0: i32,
    wt: Vec4,
    pos2: f32,
    nrm2: f32,
    plane: bool,
) -> (u16, f32, bool, bool, Vec4) {
    let w = source.width() as usize;
    let i0 = y0 as usize * w + x0 as usize;
    // Both rows in one range check (the indices below are within `w + 2`).
    let r = &source.texels[i0..i0 + w + 2];
    let s = [&r[0], &r[1], &r[w], &r[w + 1]];
    // SAFETY: SSE2 is part of x86-64; `Texel` is `repr(C)`, so 16 bytes from `position` are
    // the position and depth and 16 bytes from `normal` are the normal and albedo.x, all
    // inside the texel.
    unsafe {
        let pd = s.map(|s| _mm_loadu_ps(&s.position.x));
        let na = s.map(|s| _mm_loadu_ps(&s.normal.x));
        // 4x4 transposes: per-tap vectors -> per-component vectors over the taps.
        let transpose = |v: [__m128; 4]| {
            let (a, b) = (_mm_unpacklo_ps(v[0], v[1]), _mm_unpacklo_ps(v[2], v[3]));
            let (c, d) = (_mm_unpackhi_ps(v[0], v[1]), _mm_unpackhi_ps(v[2], v[3]));
            [
                _mm_movelh_ps(a, b),
                _mm_movehl_ps(b, a),
                _mm_movelh_ps(c, d),
                _mm_movehl_ps(d, c),
            ]
        };
        let [px, py, pz, depth] = transpose(pd);
        let [nx, ny, nz, _] = transpose(na);
        let splat = _mm_set1_ps;
        let (dx, dy, dz) = (
            _mm_sub_ps(px, splat(t.position.x)),
            _mm_sub_ps(py, splat(t.position.y)),
            _mm_sub_ps(pz, splat(t.position.z)),
        );
        let dot = |ax, ay, az, bx, by, bz| {
            _mm_add_ps(
                _mm_add_ps(_mm_mul_ps(ax, bx), _mm_mul_ps(ay, by)),
                _mm_mul_ps(az, bz),
            )
        };
        let (tnx, tny, tnz) = (splat(t.normal.x), splat(t.normal.y), splat(t.normal.z));
        let d2 = if plane {
            let h = dot(dx, dy, dz, tnx, tny, tnz);
            _mm_mul_ps(h, h)
        } else {
            dot(dx, dy, dz, dx, dy, dz)
        };
        let (ex, ey, ez) = (
            _mm_sub_ps(nx, tnx),
            _mm_sub_ps(ny, tny),
            _mm_sub_ps(nz, tnz),
        );
        let n2 = dot(ex, ey, ez, ex, ey, ez);
        let wt: __m128 = wt.into();
        let valid = _mm_cmpgt_ps(wt, _mm_setzero_ps());
        // `is_finite`: |depth| < inf (false for NaN).
        let abs = _mm_andnot_ps(splat(-0.0), depth);
        let hit = _mm_cmplt_ps(abs, splat(f32::INFINITY));
        let near = _mm_and_ps(_mm_and_ps(valid, hit), _mm_cmplt_ps(d2, splat(pos2)));
        let keep = _mm_and_ps(near, _mm_cmplt_ps(n2, splat(nrm2)));
        let kept_lanes = _mm_and_ps(keep, wt);
        let mut kept = [0.0f32; 4];
        _mm_storeu_ps(kept.as_mut_ptr(), kept_lanes);
        let sum = 0.0 + kept[0] + kept[1] + kept[2] + kept[3];
        (
            _mm_movemask_ps(keep) as u16,
            sum,
            _mm_movemask_ps(valid) != 0,
            _mm_movemask_ps(near) != 0,
            kept_lanes.into(),
        )
    }
}
