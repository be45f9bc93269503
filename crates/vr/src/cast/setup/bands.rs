//! The full bands of a run's lazily set-up triangles (HVVR, Hunt et al. 2018, §5.5; the band
//! of [`TriSetup::new`], module docs of [`super`]), four triangles at a time in SSE lanes: the
//! edge kernel refines a run ([`refine_run`]) when a packet reaches it and some ray needs the
//! exact band.
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
/// time ([`bands4`]); the affine forms per triangle.
#[inline(never)]
#[allow(clippy::needless_range_loop)] // the index addresses several arrays in step
pub fn refine_run(tt: &mut TileTris, first: usize, end: usize, blocks: &[Tri4]) {
    let mut j = first;
    while j < end {
        let k = (end - j).min(4);
        let mut p = [[[0.0f32; 4]; 3]; 3];
        for l in 0..k {
            let src = tt.tris[j + l].src;
            let b = &blocks[(src >> 2) as usize];
            let ln = (src & 3) as usize;
            for v in 0..3 {
                for a in 0..3 {
                    p[v][a][l] = b.p[v][a].as_ref()[ln];
                }
            }
        }
        let (bound, rho) = bands4(&p.map(|v| v.map(Vec4::from_array)), tt.origin, &tt.cone);
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
