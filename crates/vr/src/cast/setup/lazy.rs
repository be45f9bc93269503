//! The lazy per-tile triangle set-up (HVVR, Hunt et al. 2018, §5.5: "triangle setup ...
//! tile-corner classification"; module docs of [`super`]) of `L::N` triangles at once, one
//! triangle per lane: [`LazySetupN`] runs [`TriSetup::new_with`] (lazy band) and
//! [`BeamCorners::classify`] lane by lane, for any lane type: `setup_tile`
//! (`cast/setup/tile.rs`) runs 16 AVX-512 lanes (`Z16`, only inside an AVX-512F entry point:
//! `cast/lanes512.rs`) where the CPU has them, else 4 SSE lanes (glam `Vec4`, the portable
//! twin).
//!
//! **Invariant: the same bits as the scalar set-up, for every lane type.** Every lane runs
//! exactly the operations of the scalar code in the same order: IEEE single-precision
//! `+ - * /` per lane, never contracted into FMAs, constants folded the same way. `-x` is
//! `x * -1` (equal to the sign flip for every non-NaN `x`; a NaN lane is rejected), `|x|` is
//! `max(x, 0 - x)` with `maxps`' rule (`+0` for both zeros, `|x|` otherwise, NaN only for a
//! NaN, whose lane is rejected), `max` only where no kept lane has a NaN operand, and the
//! finiteness test is `x - x == 0`. So a kept lane's covectors, band and classification are
//! the scalar twin's bit for bit (tested in `cast/setup/tile.rs` for every lane type on random
//! and adversarial triangles).
//!
//! No closures call lane operations here: inside an AVX-512 entry point a closure's body would
//! call the lane intrinsics out of line (closures have no target features).
//!
//! | name | value | meaning |
//! |---|---|---|
//! | `L::N` | 4, 16 | triangles per set-up pack |
//! | [`PACK`] | 16 | the largest `L::N` (array sizes) |

use glam::Vec3;
use parallax_core::simd::Lanes;

use super::kernel::finite;
use super::tri::{BeamCorners, SQRT3, U};
use crate::cast::lanes16::LaneReduce;

/// The largest pack ([`LazySetupN`] lanes).
pub const PACK: usize = 16;

#[inline(always)]
pub(super) fn sub3<L: Lanes>(a: [L; 3], b: [L; 3]) -> [L; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a x b` per lane, component by component as the scalar `cross`.
#[inline(always)]
pub(super) fn cross<L: Lanes>(a: [L; 3], b: [L; 3]) -> [L; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `((a_x b_x + a_y b_y) + a_z b_z)` per lane (the scalar `dot3` / `Vec3::dot` order).
#[inline(always)]
pub(super) fn dot<L: Lanes>(a: [L; 3], b: [L; 3]) -> L {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `|x|` per lane (module docs).
#[inline(always)]
fn abs<L: Lanes>(x: L) -> L {
    x.max_or_rhs(L::splat(0.0) - x)
}

/// `(|x| + |y|) + |z|` per lane.
#[inline(always)]
fn l1<L: Lanes>(a: [L; 3]) -> L {
    abs(a[0]) + abs(a[1]) + abs(a[2])
}

#[inline(always)]
fn finite3<L: Lanes>(a: [L; 3]) -> L::M {
    L::and(L::and(finite(a[0]), finite(a[1])), finite(a[2]))
}

#[inline(always)]
fn scale3<L: Lanes>(c: [L; 3], s: L) -> [L; 3] {
    [c[0] * s, c[1] * s, c[2] * s]
}

/// The lazy set-up of `L::N` triangles, one per lane ([`TriSetup::new_with`] with `lazy`).
#[derive(Clone, Copy, Debug)]
pub struct LazySetupN<L: Lanes> {
    /// `n[i][axis]`: edge covector `i`.
    pub n: [[L; 3]; 3],
    pub g: [L; 3],
    pub bound: L,
    /// Lanes the scalar set-up keeps (`Some`).
    pub ok: u32,
}

impl<L: LaneReduce> LazySetupN<L> {
    /// The lanes of `p` (`p[vertex][axis]`, lane = triangle) set up for rays from `o` within
    /// a cone of chord radius `radius`.
    #[inline(always)]
    pub fn new(p: &[[L; 3]; 3], o: Vec3, radius: f32) -> Self {
        let sp = L::splat;
        let os = [sp(o.x), sp(o.y), sp(o.z)];
        let a = [sub3(p[0], os), sub3(p[1], os), sub3(p[2], os)];
        let e = [sub3(a[1], a[0]), sub3(a[2], a[1]), sub3(a[0], a[2])];
        let nrm = cross(e[0], scale3(e[2], sp(-1.0)));
        let d = dot(nrm, a[0]);
        let mut ok = L::and(d.ne(sp(0.0)), finite(d));
        let g = [nrm[0] / d, nrm[1] / d, nrm[2] / d];
        ok = L::and(ok, finite3(g));
        let s = L::select(d.gt(sp(0.0)), sp(1.0), sp(-1.0));
        let n = [
            scale3(cross(a[0], e[0]), s),
            scale3(cross(a[1], e[1]), s),
            scale3(cross(a[2], e[2]), s),
        ];
        ok = L::and(
            ok,
            L::and(finite3(n[0]), L::and(finite3(n[1]), finite3(n[2]))),
        );
        // The lazy band of `TriSetup::new_with`, term by term (`max` of the 1-norms: no NaN
        // in a kept lane, whose `a_i` are finite).
        let aa = l1(a[0]).max_or_rhs(l1(a[1])).max_or_rhs(l1(a[2]));
        let pp = sp(SQRT3 * 1.4143) * aa * sp(1.0 + radius) * sp(1.01);
        let ep = sp(U) * (sp(2.02) * aa + sp(1.01) * pp);
        let w = sp(2.0) * (sp(2.0) * ep * pp) + sp(4.04 * U) * pp * pp;
        let pr = sp(6.1 * U) * aa * (sp(2.0) * aa) * sp(1.01);
        let bound = sp(2.0) * (w + pr) * sp(1.01);
        let bound = L::select(finite(bound), bound, sp(f32::INFINITY));
        LazySetupN {
            n,
            g,
            bound,
            ok: L::bits(ok),
        }
    }

    /// [`BeamCorners::classify`] per lane: the masks of the lanes all out and all in.
    #[inline(always)]
    pub fn classify(&self, c: &BeamCorners) -> (u32, u32) {
        let sp = L::splat;
        let cm = sp(c.cmax.max_element());
        let cmax = [sp(c.cmax.x), sp(c.cmax.y), sp(c.cmax.z)];
        let mut out_any = 0u32;
        let mut all_in = u32::MAX;
        for e in &self.n {
            let tol = self.bound * cm + sp(3.1 * U) * dot([abs(e[0]), abs(e[1]), abs(e[2])], cmax);
            let ntol = tol * sp(-1.0);
            let (mut out, mut inn) = (u32::MAX, u32::MAX);
            for x in &c.c {
                let v = dot(*e, [sp(x.x), sp(x.y), sp(x.z)]);
                out &= L::bits(v.lt(ntol));
                inn &= L::bits(v.gt(tol));
            }
            out_any |= out;
            all_in &= inn;
        }
        (out_any, all_in & !out_any)
    }

    /// The lanes as arrays: `[n_0 x, y, z, n_1 .., n_2 .., g x, y, z, bound][lane]` (lanes
    /// `0..L::N`): the tests' form of the lanes.
    #[cfg(test)]
    pub fn arrays(&self, x: &mut [[f32; PACK]; 13]) {
        let n = &self.n;
        let v = [
            n[0][0], n[0][1], n[0][2], n[1][0], n[1][1], n[1][2], n[2][0], n[2][1], n[2][2],
            self.g[0], self.g[1], self.g[2], self.bound,
        ];
        for (r, v) in x.iter_mut().zip(v) {
            v.write(r);
        }
    }
}
