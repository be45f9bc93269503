//! The full bands of a run's lazily set-up triangles (HVVR, Hunt et al. 2018, §5.5; the band
//! of [`TriSetup::new`], module docs of [`super`]), four triangles at a time in SSE lanes: the
//! edge kernel refines a run ([`refine_run`]) when a packet reaches it and some ray needs the
//! exact band. The AVX2 walks call [`refine_run_avx2`], the same code compiled for AVX2 with
//! the four triangles' vertices gathered per coordinate (`vgatherdps`).
//!
//! **Invariant: the same bits as the scalar set-up**: [`bands4`] runs the operations of
//! [`TriSetup::new`]'s band per lane in the same order (IEEE single precision, no FMA), so a
//! refined triangle equals the one the non-lazy set-up makes (the tests of `tile.rs`).

use glam::{Vec3, Vec4};
use parallax_bvh::Tri4;
use parallax_core::simd::Lanes;

use super::lazy::{cross, dot, sub3};
#[cfg(doc)]
use super::tri::TriSetup;
use super::tri::{Cone, RHO_MAX, SQRT3, TileTris, U};

/// `(|x| + |y|) + |z|` per lane.
#[inline(always)]
fn l1_4(a: [Vec4; 3]) -> Vec4 {
    a[0].abs() + a[1].abs() + a[2].abs()
}

/// `|v|^2 = (x x + y y) + z z` per lane (`Vec3::length_squared`).
#[inline(always)]
fn lsq4(v: [Vec4; 3]) -> Vec4 {
    dot(v, v)
}

/// `f32::max(acc, x)` for `acc` never NaN (`maxps(x, acc)`: `x` if `x > acc`, else `acc`).
#[inline(always)]
fn fmax4(acc: Vec4, x: Vec4) -> Vec4 {
    x.max(acc)
}

/// The full bands of four triangles (`p[vertex][axis]`, lane = triangle) for rays from `o`
/// within `cone`: per lane `(bound, rho)` of [`TriSetup::new`] (the non-lazy branch of
/// [`TriSetup::new_with`]), operation by operation.
#[inline(always)]
pub fn bands4(p: &[[Vec4; 3]; 3], o: Vec3, cone: &Cone) -> (Vec4, Vec4) {
    let sp = Vec4::splat;
    let os = [sp(o.x), sp(o.y), sp(o.z)];
    let a = [sub3(p[0], os), sub3(p[1], os), sub3(p[2], os)];
    let e = [sub3(a[1], a[0]), sub3(a[2], a[1]), sub3(a[0], a[2])];
    let nrm = cross(e[0], [-e[2][0], -e[2][1], -e[2][2]]);
    let d = dot(nrm, a[0]);
    let c = [sp(cone.centre.x), sp(cone.centre.y), sp(cone.centre.z)];
    let r = sp(cone.radius);
    let psi_of = |ai: [Vec4; 3]| {
        let (x, y) = (cross(ai, c), [ai[0] * r, ai[1] * r, ai[2] * r]);
        sp(SQRT3) * Lanes::sqrt(sp(2.0) * (lsq4(x) + lsq4(y))) * sp(1.001)
    };
    let psi = [psi_of(a[0]), psi_of(a[1]), psi_of(a[2])];
    let amax = a.map(|x| x[0].abs().max(x[1].abs().max(x[2].abs())));
    let ep = [0, 1, 2].map(|i| sp(U) * (sp(2.02) * amax[i] + sp(1.01) * psi[i]));
    let (mut bound, mut wsum) = (Vec4::ZERO, Vec4::ZERO);
    for i in 0..3 {
        let (b, cc) = (i, (i + 1) % 3);
        let w = sp(2.0) * (ep[cc] * psi[b] + ep[b] * psi[cc]) + sp(4.04 * U) * psi[b] * psi[cc];
        let pr = sp(6.1 * U) * l1_4(a[i]) * l1_4(e[i]);
        bound = fmax4(bound, w + pr);
        wsum += w;
    }
    let bound = sp(2.0) * bound;
    let amax_sq = fmax4(fmax4(fmax4(Vec4::ZERO, lsq4(a[0])), lsq4(a[1])), lsq4(a[2]));
    let dabs = d.abs();
    let sigma_kappa = Lanes::sqrt(amax_sq * lsq4(e[0]) * lsq4(e[2])) * sp(1.001) / dabs;
    let lsq_e = fmax4(fmax4(fmax4(Vec4::ZERO, lsq4(e[0])), lsq4(e[1])), lsq4(e[2]));
    let lambda = Lanes::sqrt(lsq_e) * sp(1.001);
    let rho =
        sp(2.0) * (sp(SQRT3) * lambda * wsum / dabs + sp(14.0 * U) * sigma_kappa + sp(11.0 * U));
    let rho = Vec4::select(
        rho.is_finite_mask() & rho.cmple(sp(RHO_MAX)),
        rho,
        Vec4::INFINITY,
    );
    let bound = Vec4::select(bound.is_finite_mask(), bound, Vec4::INFINITY);
    (bound, rho)
}

/// [`TileTris::refine`] of every lazy triangle of `tt.tris[first..end]` (a run), four at a
/// time ([`bands4`]); the affine forms per triangle. The portable twin of
/// [`refine_run_avx2`].
#[inline(never)]
pub fn refine_run(tt: &mut TileTris, first: usize, end: usize, blocks: &[Tri4]) {
    refine_run_in::<false>(tt, first, end, blocks);
}

/// [`refine_run`] compiled for AVX2 (three-operand forms of the same operations), the
/// vertices of four triangles gathered per coordinate (`vgatherdps`): the same bits.
///
/// # Safety
/// The CPU must support AVX2 ([`crate::cast::isa::avx2_detected`]).
#[cfg(target_arch = "x86_64")]
#[inline(never)]
#[target_feature(enable = "avx2")]
pub unsafe fn refine_run_avx2(tt: &mut TileTris, first: usize, end: usize, blocks: &[Tri4]) {
    refine_run_in::<true>(tt, first, end, blocks);
}

/// f32s per [`Tri4`] (the stride of the vertex gather).
const TRI4_F32: usize = std::mem::size_of::<Tri4>() / 4;
const _: () = assert!(std::mem::offset_of!(Tri4, p) == 0 && TRI4_F32 == 40);

/// The body of [`refine_run`]; `GATHER`: the vertices by AVX2 gathers (only inside
/// [`refine_run_avx2`]).
#[inline(always)]
fn refine_run_in<const GATHER: bool>(tt: &mut TileTris, first: usize, end: usize, blocks: &[Tri4]) {
    // The vertices as f32 offsets in `blocks` fit in `i32` (the gather's indices).
    let gather = GATHER && blocks.len() <= i32::MAX as usize / TRI4_F32;
    let mut j = first;
    while j < end {
        let k = (end - j).min(4);
        let mut p = [[Vec4::ZERO; 3]; 3];
        if gather {
            gather4(&mut p, &tt.tris[j..j + k], blocks);
        } else {
            let mut pa = [[[0.0f32; 4]; 3]; 3];
            for l in 0..k {
                let src = tt.tris[j + l].src;
                let b = &blocks[(src >> 2) as usize];
                let ln = (src & 3) as usize;
                for v in 0..3 {
                    for a in 0..3 {
                        pa[v][a][l] = b.p[v][a].as_ref()[ln];
                    }
                }
            }
            p = pa.map(|v| v.map(Vec4::from_array));
        }
        let (bound, rho) = bands4(&p, tt.origin, &tt.cone);
        let (bound, rho) = (bound.to_array(), rho.to_array());
        for l in 0..k {
            let s = &mut tt.tris[j + l];
            if !s.rho.is_nan() {
                continue;
            }
            s.bound = bound[l];
            s.rho = rho[l];
            if let (Some(fr), Some(a)) = (&tt.frame, tt.aff.get_mut(j + l)) {
                *a = fr.affine(&s.n);
            }
        }
        j += k;
    }
}

/// `p[v][a]` lane `l` = vertex `v` axis `a` of `tris[l]` (`tris.len()` in `1..=4`; lanes past
/// it repeat lane 0), one `vgatherdps` per coordinate. Only inside AVX2 code, with
/// `blocks.len() * 40 <= i32::MAX`.
#[inline(always)]
fn gather4(p: &mut [[Vec4; 3]; 3], tris: &[super::tri::TriSetup], blocks: &[Tri4]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m128, _mm_i32gather_ps, _mm_loadu_si128};
        let mut idx = [0i32; 4];
        for (l, t) in tris.iter().enumerate() {
            // Bounds-checked here: the gather reads inside `blocks[src >> 2]`.
            let b = (t.src >> 2) as usize;
            assert!(b < blocks.len());
            idx[l] = (b * TRI4_F32 + (t.src & 3) as usize) as i32;
        }
        for l in tris.len()..4 {
            idx[l] = idx[0];
        }
        let base = blocks.as_ptr().cast::<f32>();
        for v in 0..3 {
            for a in 0..3 {
                // SAFETY: AVX2 code (caller); `Tri4` is `repr(C)` with `p` first, so lane
                // `ln` of `p[v][a]` of block `b` is f32 `40 b + 4 (3 v + a) + ln`, inside
                // `blocks` (checked above); the offsets fit in `i32` (caller).
                p[v][a] = Vec4::from(unsafe {
                    let i = _mm_loadu_si128(idx.as_ptr().cast());
                    _mm_i32gather_ps::<4>(base.add(4 * (3 * v + a)), i)
                } as __m128);
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (p, tris, blocks);
}
