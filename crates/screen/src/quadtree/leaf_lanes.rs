//! The leaf of one pixel (Widmer et al. 2015, §3.2; `build.rs`, "Leaves") with its
//! arithmetic in SSE2 lanes: the cube covector's `x` and `y` in the two f64 lanes of one
//! register, the two gradient divisions as one `divpd`, the two f32 slopes clamped and
//! encoded to f16 in the lanes of one register. Every lane does exactly the scalar
//! definition's operations (`map_gradient` in `build.rs`, [`Node::plane_with_gradient`]) in
//! its order — IEEE products, sums, divisions and the f64 -> f32 rounding are correctly
//! rounded per lane, there is no fused multiply-add — so the nodes are the same bits
//! (`tests/quadtree_build.rs` compares whole trees with the reference build, which runs the
//! scalar code):
//!
//! - `q = M^T (n, -n·p)` as glam's `DMat4 * DVec4` computes it, `((X n.x + Y n.y) + Z n.z)
//!   + W w` per component, and `|q.xyz|^2` as `(q.x^2 + q.y^2) + q.z^2`;
//! - the slopes `q.x / -q.z`, `q.y / -q.z`, `None` if either is NaN, rounded to f32;
//! - [`Node::plane`]: the slopes times `1 / W`, `1 / H` (level 0), clamped to `±65504`
//!   (`maxps` / `minps` are `clamp` for non-NaN values, signed zeros included) and encoded
//!   by [`super::node::f32_to_f16_bits`]'s three cases selected by masks.

use core::arch::x86_64::*;

use glam::{DMat4, Vec3};

use super::node::{FLAG_CRACK, FLAG_UNSAFE, Node};

/// Largest finite f16.
const F16_MAX: f32 = 65504.0;

/// The constants of the leaf map of one layer.
pub(super) struct LeafMap {
    /// Per column of `M^T` (`x_axis` .. `w_axis`), its `x` and `y` entries.
    xy: [__m128d; 4],
    /// Per column of `M^T`, its `z` entry.
    z: [f64; 4],
    /// `(1 / W, 1 / H, 0, 0)` in f32: [`Node::plane_with_gradient`]'s scale at level 0.
    scale: __m128,
}

// SAFETY (all `unsafe` blocks below): SSE and SSE2 are part of the x86_64 baseline.

impl LeafMap {
    /// The map of the transposed inverse cube map `mt` for a `wf x hf` layer.
    pub(super) fn new(mt: &DMat4, wf: f32, hf: f32) -> Self {
        let cols = [mt.x_axis, mt.y_axis, mt.z_axis, mt.w_axis];
        let size = 1.0f32;
        Self {
            xy: cols.map(|c| unsafe { _mm_setr_pd(c.x, c.y) }),
            z: cols.map(|c| c.z),
            scale: unsafe { _mm_setr_ps(size / wf, size / hf, 0.0, 0.0) },
        }
    }

    /// The level-0 plane node of the world plane through `p` with normal `n`, cube `z`
    /// `zc`, `flags`; [`Node::EMPTY`] when the map is degenerate or `zc` invalid (module
    /// docs).
    #[inline(always)]
    pub(super) fn leaf(&self, p: Vec3, n: Vec3, zc: f32, flags: u32) -> Node {
        let (px, py, pz) = (p.x as f64, p.y as f64, p.z as f64);
        let (nx, ny, nz) = (n.x as f64, n.y as f64, n.z as f64);
        // `n.extend(-n.dot(p))`.
        let w = -((nx * px + ny * py) + nz * pz);
        let [x, y, z, ww] = self.z;
        let qz = ((x * nx + y * ny) + z * nz) + ww * w;
        unsafe {
            let [cx, cy, cz, cw] = self.xy;
            let qxy = _mm_add_pd(
                _mm_add_pd(
                    _mm_add_pd(
                        _mm_mul_pd(cx, _mm_set1_pd(nx)),
                        _mm_mul_pd(cy, _mm_set1_pd(ny)),
                    ),
                    _mm_mul_pd(cz, _mm_set1_pd(nz)),
                ),
                _mm_mul_pd(cw, _mm_set1_pd(w)),
            );
            let sq = _mm_mul_pd(qxy, qxy);
            let len2 = (_mm_cvtsd_f64(sq) + _mm_cvtsd_f64(_mm_unpackhi_pd(sq, sq))) + qz * qz;
            if !(len2.is_finite() && len2 > 0.0) {
                return Node::EMPTY;
            }
            let g = _mm_div_pd(qxy, _mm_set1_pd(-qz));
            if _mm_movemask_pd(_mm_cmpunord_pd(g, g)) != 0 {
                return Node::EMPTY;
            }
            // `Node::plane`: `z_c` finite and `>= 0` (the slopes are not NaN: an infinite
            // gradient times the scale stays infinite and is clamped).
            if !(zc.is_finite() && zc >= 0.0) {
                return Node::EMPTY;
            }
            let e = _mm_mul_ps(_mm_cvtpd_ps(g), self.scale);
            let e = _mm_min_ps(_mm_max_ps(e, _mm_set1_ps(-F16_MAX)), _mm_set1_ps(F16_MAX));
            let h = f16x4_encode(e);
            let (hx, hy) = (
                _mm_cvtsi128_si32(h) as u32,
                _mm_cvtsi128_si32(_mm_srli_si128(h, 4)) as u32,
            );
            let bits = (zc.to_bits() + 2) & !3;
            Node {
                a: 0x8000_0000 | bits | (flags & (FLAG_CRACK | FLAG_UNSAFE)),
                b: (hx & 0xffff) | (hy << 16),
            }
        }
    }
}

/// [`super::node::f32_to_f16_bits`] per lane (values not NaN, at most 65504 in magnitude):
/// the same three cases, selected by the same conditions; the half in each lane's low 16
/// bits.
#[inline(always)]
fn f16x4_encode(v: __m128) -> __m128i {
    unsafe {
        let x = _mm_castps_si128(v);
        let sign = _mm_and_si128(_mm_srli_epi32(x, 16), _mm_set1_epi32(0x8000));
        let a = _mm_and_si128(x, _mm_set1_epi32(0x7fff_ffff));
        let magic_bits = ((127 - 15) + (23 - 10) + 1) << 23;
        let magic = _mm_castsi128_ps(_mm_set1_epi32(magic_bits));
        let sub = _mm_sub_epi32(
            _mm_castps_si128(_mm_add_ps(_mm_castsi128_ps(a), magic)),
            _mm_set1_epi32(magic_bits),
        );
        let odd = _mm_and_si128(_mm_srli_epi32(a, 13), _mm_set1_epi32(1));
        let bias = ((15u32.wrapping_sub(127)) << 23).wrapping_add(0xfff) as i32;
        let normal = _mm_srli_epi32(
            _mm_add_epi32(_mm_add_epi32(a, _mm_set1_epi32(bias)), odd),
            13,
        );
        // `a` is below 2^31, so the signed compares are the unsigned ones.
        let is_inf = _mm_cmpgt_epi32(a, _mm_set1_epi32(0x477f_ffff));
        let is_sub = _mm_cmplt_epi32(a, _mm_set1_epi32(0x3880_0000));
        let h = _mm_or_si128(
            _mm_or_si128(
                _mm_and_si128(_mm_set1_epi32(0x7c00), is_inf),
                _mm_and_si128(sub, is_sub),
            ),
            _mm_andnot_si128(_mm_or_si128(is_sub, is_inf), normal),
        );
        _mm_or_si128(sign, h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadtree::node::f32_to_f16_bits;

    /// The lane encode equals the scalar one on a spread of values in its domain.
    #[test]
    fn lane_encode_matches_scalar() {
        let mut vals: Vec<f32> = (0..(1u32 << 20))
            .map(|k| f32::from_bits(k.wrapping_mul(4099)))
            .filter(|v| !v.is_nan() && v.abs() <= F16_MAX)
            .collect();
        vals.extend([0.0, -0.0, F16_MAX, -F16_MAX, 6.1e-5, 6.0e-5, -2.9802322e-8]);
        for c in vals.chunks(4) {
            let mut l = [0.0f32; 4];
            l[..c.len()].copy_from_slice(c);
            let mut out = [0u32; 4];
            unsafe {
                let h = f16x4_encode(_mm_loadu_ps(l.as_ptr()));
                _mm_storeu_si128(out.as_mut_ptr() as *mut __m128i, h);
            }
            for (v, o) in l.iter().zip(out) {
                assert_eq!(o, f32_to_f16_bits(*v) as u32, "{v:e}");
            }
        }
    }
}
