//! The per-tile triangle set-up of HVVR (Hunt et al. 2018, §5.5) for tiles whose rays share one
//! origin: per triangle, oriented edge covectors `n_i` and the inverse-distance covector `g`
//! (`1/t = g . d`), the tile-corner classification (all in / partial / all out) and the edge
//! uncertainty band `bound` and depth band `rho` that make the kernels exact (module docs of
//! [`super`]); the tile's list ([`TileTris`]) of set-up triangles in near-depth runs
//! ([`Segment`]), and the watertight fall-backs ([`exact_t`], [`exact_closest`]).
//!
//! **Invariant:** for every ray of the tile, `|fl(n_i . d) - e_i(d)| + |Woop's u_i - e_i(d)| <=
//! bound |d|_inf` and `|g . d - 1/t_woop| <= rho g . d`: a value outside the band decides the
//! ray exactly as the watertight test would.

use glam::{Vec3, Vec4};
use parallax_bvh::Tri4;
use parallax_core::Ray;
use parallax_core::math::{WatertightRay, shear_vertex, watertight_lanes};
use parallax_core::simd::Lanes;

use super::affine::{AffineTri, FilmFrame};
use super::rows::TileRows;
use super::tile_packets::TilePackets;
use crate::beam::Beam;
use crate::cast::packet::RaysN;

/// Unit roundoff of f32 (`2^-24`): `fl(x op y) = (x op y)(1 + δ)`, `|δ| <= U`.
pub(super) const U: f32 = f32::EPSILON * 0.5;
pub(super) const SQRT3: f32 = 1.732_051;
/// A triangle whose depth band [`TriSetup::rho`] exceeds this is ill-conditioned (seen almost
/// edge-on, or its plane passes near the origin): its depth is always decided exactly.
pub const RHO_MAX: f32 = 0.05;
/// Relative band of a best `1/t` that came from an exact Woop `t` (`fl(1/t)`: one rounding,
/// doubled).
pub(super) const RHO_EXACT: f32 = 2.0 * U;

/// A triangle set up for rays from one origin (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct TriSetup {
    /// Oriented edge covectors.
    pub n: [[f32; 3]; 3],
    /// Inverse-distance covector: `1/t = g . d`.
    pub g: [f32; 3],
    /// Index in `Bvh::triangles`.
    pub tri: u32,
    /// Where the vertices are: `4 * block + lane` in `Bvh::blocks` (the exact test reads them).
    pub src: u32,
    /// Edge uncertainty per unit `|d|_inf`: `|fl(n_i . d) - e_i(d)| + |Woop's u_i - e_i(d)|
    /// <= bound |d|_inf` for every ray of the tile (module docs, "exact band").
    pub bound: f32,
    /// Relative depth band: `|g . d - 1/t_woop| <= rho g . d` (first order, doubled).
    pub rho: f32,
    /// Every ray of the tile certainly passes the three edge tests.
    pub all_in: bool,
}

#[cfg(test)]
impl TriSetup {
    /// The fields as bits, for bit-for-bit comparisons in tests (`rho` may be NaN, so
    /// `PartialEq` would fail on equal set-ups).
    pub(crate) fn bits(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self.n.iter().flatten().map(|x| x.to_bits()).collect();
        v.extend(self.g.map(f32::to_bits));
        v.extend([
            self.tri,
            self.src,
            self.bound.to_bits(),
            self.rho.to_bits(),
            self.all_in as u32,
        ]);
        v
    }
}

/// `((a_x b_x + a_y b_y) + a_z b_z)` in f32 without contraction: the kernel's evaluation order.
#[inline(always)]
pub fn dot3(a: [f32; 3], d: Vec3) -> f32 {
    a[0] * d.x + a[1] * d.y + a[2] * d.z
}

/// `a x b` component by component, never contracted.
#[inline(always)]
fn cross(a: Vec3, b: Vec3) -> Vec3 {
    Vec3::new(
        a.y * b.z - a.z * b.y,
        a.z * b.x - a.x * b.z,
        a.x * b.y - a.y * b.x,
    )
}

fn l1(v: Vec3) -> f32 {
    v.abs().element_sum()
}

/// Corner classification of a triangle against a tile beam (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CornerClass {
    AllOut,
    Partial,
    AllIn,
}

/// A cone of unit directions holding every ray of a tile: `|d/|d| - centre| <= radius`.
#[derive(Clone, Copy, Debug)]
pub struct Cone {
    pub centre: Vec3,
    pub radius: f32,
}

impl Cone {
    /// Every direction (`|d̂ - 0| = 1`; the vertex distance bound becomes `|a|`, module docs).
    pub const ANY: Cone = Cone {
        centre: Vec3::ZERO,
        radius: 1.0,
    };

    /// The cone of a beam's corners: centre = normalised sum of the unit corners, radius = the
    /// largest chord to a corner. Over a geodesically convex spherical quadrilateral within the
    /// hemisphere around the centre, the chord to the centre is largest at a corner; otherwise
    /// [`Cone::ANY`].
    pub fn of(corners: Option<&BeamCorners>) -> Cone {
        let Some(c) = corners else {
            return Cone::ANY;
        };
        let u = c.c.map(|x| x.normalize_or_zero());
        let centre = (u[0] + u[1] + u[2] + u[3]).normalize_or_zero();
        if centre == Vec3::ZERO || u.iter().any(|x| x.dot(centre) <= 0.1) {
            return Cone::ANY;
        }
        let r = u.iter().map(|x| (*x - centre).length()).fold(0.0, f32::max);
        Cone {
            centre,
            radius: r * 1.001 + 1e-6,
        }
    }
}

/// The four corner directions of a beam and the per-axis magnitude bound of its directions
/// (`None` for [`Beam::EVERYTHING`] or unbounded slopes: every triangle is partial).
#[derive(Clone, Copy, Debug)]
pub struct BeamCorners {
    pub c: [Vec3; 4],
    pub cmax: Vec3,
}

impl BeamCorners {
    pub fn new(beam: &Beam) -> Option<Self> {
        if beam.everything {
            return None;
        }
        let (a, (b, c)) = (beam.axis as usize, beam.side_axes());
        if !(beam.u.iter().chain(&beam.v).all(|x| x.is_finite())) {
            return None;
        }
        let mut cs = [Vec3::ZERO; 4];
        for (k, corner) in cs.iter_mut().enumerate() {
            corner[a] = beam.sign;
            corner[b] = beam.u[k & 1];
            corner[c] = beam.v[k >> 1];
        }
        let mut cmax = Vec3::ZERO;
        cmax[a] = 1.0;
        cmax[b] = beam.u[0].abs().max(beam.u[1].abs());
        cmax[c] = beam.v[0].abs().max(beam.v[1].abs());
        Some(BeamCorners { c: cs, cmax })
    }

    /// Classifies a set-up triangle (module docs): all-in only if every ray of the beam is
    /// certainly inside (edge values above the band), all-out only if one edge is certainly
    /// negative for every ray.
    #[inline(always)]
    pub fn classify(&self, s: &TriSetup) -> CornerClass {
        // Every ray satisfies d / |d_a| = sum_k w_k c_k, so |d|_inf <= |d_a| cm and the real
        // edge value is |d_a| sum_k w_k e(c_k); fl(n . c_k) is within the set-up part of the
        // band times cm plus its own dot rounding (3.1 U sum |n_j| cmax_j) of e(c_k).
        let cm = self.cmax.max_element();
        let mut all_in = true;
        for e in &s.n {
            let tol =
                s.bound * cm + 3.1 * U * dot3([e[0].abs(), e[1].abs(), e[2].abs()], self.cmax);
            let (mut out, mut inn) = (true, true);
            for c in &self.c {
                let v = dot3(*e, *c);
                out &= v < -tol;
                inn &= v > tol;
            }
            if out {
                return CornerClass::AllOut;
            }
            all_in &= inn;
        }
        if all_in {
            CornerClass::AllIn
        } else {
            CornerClass::Partial
        }
    }
}

/// Ray-triangle decision of the set-up edge test for one direction (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EdgeClass {
    /// Every edge value above the band: the watertight test certainly finds the ray inside.
    In,
    /// An edge value below minus the band: the watertight test certainly rejects the ray.
    Out,
    /// Within the band: decide with the watertight test.
    Unsure,
}

impl TriSetup {
    /// Sets up triangle `(v0, v1, v2)` (at `src` = `4 * block + lane`) for rays from `o` within
    /// `cone`; `None` if no ray from `o` can hit it (`D = 0`, non-finite values).
    #[inline(always)]
    pub fn new(v: [Vec3; 3], o: Vec3, tri: u32, src: u32, cone: &Cone) -> Option<Self> {
        Self::new_with(v, o, tri, src, cone, false)
    }

    /// [`TriSetup::new`], or with `lazy` a cheap set-up for [`crate::SetupExactness::Edges`]: a
    /// crude edge band `bound >= ` the one of `new` (from `max |a_i|_1` alone: enough for a
    /// conservative corner classification) and `rho = NaN`, to be replaced by `new`'s band
    /// when a packet first reaches the triangle (`TileTris::refine`), so triangles dropped
    /// by the classification or never reached skip the band analysis.
    #[inline(always)]
    pub fn new_with(
        v: [Vec3; 3],
        o: Vec3,
        tri: u32,
        src: u32,
        cone: &Cone,
        lazy: bool,
    ) -> Option<Self> {
        // The same rounded `a_i = v_i - o` as the watertight test's projection.
        let a = [v[0] - o, v[1] - o, v[2] - o];
        // Edges of the rounded triangle: e_i = fl(a_{i+1} - a_i) (relative error U each).
        let e = [a[1] - a[0], a[2] - a[1], a[0] - a[2]];
        let nrm = cross(e[0], -e[2]);
        let d = nrm.dot(a[0]);
        if d == 0.0 || !d.is_finite() {
            return None;
        }
        let g = nrm / d;
        if !g.is_finite() {
            return None;
        }
        let s = if d > 0.0 { 1.0 } else { -1.0 };
        // n_i = a_i x (a_{i+1} - a_i) = a_i x a_{i+1} in exact arithmetic; the short edge
        // keeps the rounding error relative to |a| |e_i| instead of |a|^2.
        let n = [
            (cross(a[0], e[0]) * s).to_array(),
            (cross(a[1], e[1]) * s).to_array(),
            (cross(a[2], e[2]) * s).to_array(),
        ];
        // All nine finite iff the sum of the `x - x` is 0 (+0 for finite `x`, NaN otherwise).
        #[allow(clippy::eq_op)] // `x - x` is the finiteness test, not a mistake
        let z: f32 = n.iter().flatten().map(|&x| x - x).sum();
        if z != 0.0 {
            return None;
        }
        let (bound, rho) = if lazy {
            // psi_i <= sqrt 3 sqrt 2 |a_i| sqrt(1 + r^2) <= 2.45 (1 + r) A (A = max |a_i|_1,
            // |c| = 1), amax_i <= A, |e_i|_1 <= 2A: every term of the band below at most.
            let aa = l1(a[0]).max(l1(a[1])).max(l1(a[2]));
            let pp = SQRT3 * 1.4143 * aa * (1.0 + cone.radius) * 1.01;
            let ep = U * (2.02 * aa + 1.01 * pp);
            let w = 2.0 * (2.0 * ep * pp) + 4.04 * U * pp * pp;
            let p = 6.1 * U * aa * (2.0 * aa) * 1.01;
            (2.0 * (w + p) * 1.01, f32::NAN)
        } else {
            // Distance of each vertex from any ray of the cone (module docs) and the bound on the
            // watertight test's projected coordinates |x'|, |y'| <= sqrt 3 dist.
            // (x + y <= sqrt(2 (x^2 + y^2)): one square root per vertex instead of two.)
            let psi_of = |ai: Vec3| {
                let (x, y) = (cross(ai, cone.centre), ai * cone.radius);
                SQRT3 * (2.0 * (x.length_squared() + y.length_squared())).sqrt() * 1.001
            };
            let psi = [psi_of(a[0]), psi_of(a[1]), psi_of(a[2])];
            let amax = [
                a[0].abs().max_element(),
                a[1].abs().max_element(),
                a[2].abs().max_element(),
            ];
            // Error of a projected coordinate: U |sx a_kz| (product) + U |sx| |a_kz| (sx itself)
            // + U |x'| (subtraction), |sx| <= 1.
            let ep_of = |i: usize| U * (2.02 * amax[i] + 1.01 * psi[i]);
            let ep = [ep_of(0), ep_of(1), ep_of(2)];
            let mut bound = 0.0f32;
            let mut wsum = 0.0f32;
            for i in 0..3 {
                let (b, c) = (i, (i + 1) % 3);
                // Watertight edge function u = c'x b'y - c'y b'x: input errors plus three
                // roundings, in u units; times |d_kz| = |d|_inf in e units.
                let w = 2.0 * (ep[c] * psi[b] + ep[b] * psi[c]) + 4.04 * U * psi[b] * psi[c];
                // Set-up value: n from e_i (U), two products and a difference (about 3U of
                // |a| (x) |e|), the dot product (3U): 6.1 U |a_i|_1 |e_i|_1 |d|_inf.
                let p = 6.1 * U * l1(a[i]) * l1(e[i]);
                bound = bound.max(w + p);
                wsum += w;
            }
            // Safety factor 2 over the first-order analysis (second-order terms, the 1.01s).
            let bound = 2.0 * bound;
            // Depth band. g . d: D and N . d lose U |N| |a| / |D| (kappa: 1 / sine of the grazing
            // angle, for every ray through the triangle) each, N itself 3U sigma (sigma = sliver
            // factor |e0| |e2| / |N|). Woop's t = sum u_i z_i / sum u_i moves by
            // sqrt 3 Lambda sum |du_i| / |D| (Lambda = longest edge) plus 7U of rounding.
            // (sigma kappa = max |a| |e0| |e2| / |D|: two square roots in all.)
            let amax_sq = a.iter().map(|x| x.length_squared()).fold(0.0, f32::max);
            let sigma_kappa =
                (amax_sq * e[0].length_squared() * e[2].length_squared()).sqrt() * 1.001 / d.abs();
            let lambda = e
                .iter()
                .map(|x| x.length_squared())
                .fold(0.0, f32::max)
                .sqrt()
                * 1.001;
            let rho = 2.0 * (SQRT3 * lambda * wsum / d.abs() + 14.0 * U * sigma_kappa + 11.0 * U);
            let rho = if rho.is_finite() && rho <= RHO_MAX {
                rho
            } else {
                f32::INFINITY
            };
            (bound, rho)
        };
        Some(TriSetup {
            n,
            g: g.to_array(),
            tri,
            src,
            bound: if bound.is_finite() {
                bound
            } else {
                f32::INFINITY
            },
            rho,
            all_in: false,
        })
    }

    /// The set-up edge test of one ray direction `d` with the band (module docs).
    #[inline]
    pub fn edge_class(&self, d: Vec3) -> EdgeClass {
        if self.all_in {
            return EdgeClass::In;
        }
        let b = self.bound * d.abs().max_element();
        let m = self
            .n
            .iter()
            .map(|n| dot3(*n, d))
            .fold(f32::INFINITY, f32::min);
        if m > b {
            EdgeClass::In
        } else if m < -b {
            EdgeClass::Out
        } else {
            EdgeClass::Unsure
        }
    }
}

/// The watertight test (the BVH's, `WatertightRay::intersect_within`) of set-up triangle `src`.
#[inline(never)]
pub fn exact_t(wt: &WatertightRay, blocks: &[Tri4], src: u32) -> Option<f32> {
    let b = &blocks[(src >> 2) as usize];
    let ln = (src & 3) as usize;
    wt.intersect_within(
        b.vertex(ln, 0),
        b.vertex(ln, 1),
        b.vertex(ln, 2),
        f32::INFINITY,
    )
    .map(|h| h.t)
}

/// [`exact_t`] on every lane of `rays` at once, for rays that all have the watertight
/// permutation `perm` (`TileTris::perm`) and the triangle `p[vertex][axis]` (per lane):
/// lane-wise exactly the f32 operations of `WatertightRay::new` and `intersect_within` (the
/// shear constants divided lane-wise; `t` in `(0, inf)`, the rays' `t_min` and `t_max`).
/// Returns `(zero, hit, t)`: the lanes with an exactly-zero edge function, which only the
/// scalar test decides (its f64 branch, Woop et al. 2013, §4.1); the other lanes whose ray
/// the test accepts; and `t`, meaningful on `hit`.
#[inline(always)]
pub(super) fn exact_t_lanes<L: Lanes>(
    rays: &RaysN<L>,
    perm: [usize; 3],
    p: &[[L; 3]; 3],
) -> (u32, u32, L) {
    let [kx, ky, kz] = perm;
    let dkz = rays.d[kz];
    let shear = [rays.d[kx] / dkz, rays.d[ky] / dkz, L::splat(1.0) / dkz];
    let o = [rays.o[kx], rays.o[ky], rays.o[kz]];
    // Not a closure (lane intrinsics would not inline into it, `cast/lanes512.rs`).
    let va = shear_vertex([p[0][kx], p[0][ky], p[0][kz]], o, shear);
    let vb = shear_vertex([p[1][kx], p[1][ky], p[1][kz]], o, shear);
    let vc = shear_vertex([p[2][kx], p[2][ky], p[2][kz]], o, shear);
    let r = watertight_lanes(va, vb, vc);
    let d = r.distance(va[2], vb[2], vc[2]);
    let ok = r.same_sign
        & d.nonzero
        & L::bits(d.t.gt(L::splat(0.0)))
        & L::bits(d.t.lt(L::splat(f32::INFINITY)));
    (r.exact, ok & !r.exact, d.t)
}

/// The vertices of set-up triangle `src` in every lane (`p[vertex][axis]`, [`exact_t_lanes`]).
#[inline(always)]
pub(super) fn splat_vertices<L: Lanes>(blocks: &[Tri4], src: u32) -> [[L; 3]; 3] {
    let b = &blocks[(src >> 2) as usize];
    let ln = (src & 3) as usize;
    // Loops, not `map` closures (lane intrinsics would not inline into a closure).
    let mut p = [[L::splat(0.0); 3]; 3];
    for (v, pv) in p.iter_mut().enumerate() {
        for (k, pk) in pv.iter_mut().enumerate() {
            *pk = L::splat(b.p[v][k][ln]);
        }
    }
    p
}

/// The closest hit `(t, set-up index)` of `ray` over every triangle of `tris` with the
/// watertight test alone, the BVH's tie-break (the rescue path; also the tests' reference).
pub fn exact_closest(ray: &Ray, blocks: &[Tri4], tris: &[TriSetup]) -> (f32, u32) {
    let wt = WatertightRay::new(ray);
    let (mut bt, mut bi) = (f32::INFINITY, u32::MAX);
    for (i, tr) in tris.iter().enumerate() {
        if let Some(t) = exact_t(&wt, blocks, tr.src)
            && (bi == u32::MAX || t < bt || (t == bt && tr.tri < tris[bi as usize].tri))
        {
            (bt, bi) = (t, i as u32);
        }
    }
    (bt, bi)
}

/// A leaf's run of set-up triangles: `tris[previous end..end]`, and its near depth.
#[derive(Clone, Copy, Debug)]
pub struct Segment {
    pub end: u32,
    pub near: f32,
    /// Box of the run's triangles relative to the origin (`min - o`, `max - o`; `w` = 0).
    pub lo: Vec4,
    pub hi: Vec4,
}

/// The boxes of sixteen consecutive runs `segs[16k..16k + 16]` ([`Segment::lo`],
/// [`Segment::hi`]), per axis one lane per run: the packet's interval test of sixteen runs in
/// one AVX-512 register per axis and bound (`PacketSlab::interval_reaches16` in
/// `cast/setup/kernel.rs`), or of each quarter's four runs in one SSE register
/// (`PacketSlab::interval_reaches4`). Lanes past the last run are 0.
#[derive(Clone, Copy, Debug)]
pub struct RunBoxes16 {
    pub lo: [[f32; 16]; 3],
    pub hi: [[f32; 16]; 3],
}

impl Default for RunBoxes16 {
    fn default() -> Self {
        RunBoxes16 {
            lo: [[0.0; 16]; 3],
            hi: [[0.0; 16]; 3],
        }
    }
}

/// Counts of the corner classification.
#[derive(Clone, Copy, Debug, Default)]
pub struct SetupCounts {
    pub all_out: u64,
    pub partial: u64,
    pub all_in: u64,
    /// Entries of the tile lists dropped as repeats of a triangle kept earlier in the list
    /// (a triangle in several leaves: spatial splits; `cast/setup/rows.rs`), not set up.
    pub repeated: u64,
}

/// The set-up triangle list of a tile (per-thread scratch, reused).
#[derive(Clone, Debug, Default)]
pub struct TileTris {
    pub origin: Vec3,
    pub tris: Vec<TriSetup>,
    pub segs: Vec<Segment>,
    /// `runs16[k]`: the boxes of `segs[16k..16k + 16]`.
    pub runs16: Vec<RunBoxes16>,
    pub counts: SetupCounts,
    /// The largest depth band `rho` of the list's well-conditioned triangles.
    pub rho_max: f32,
    /// The watertight permutation `[kx, ky, kz]` shared by every ray of the tile, when the
    /// beam's slopes are below 1 (`|d_a|` strictly dominant, sign fixed).
    pub perm: Option<[usize; 3]>,
    /// The cone of the tile's rays (for the lazy band, [`TileTris::refine`]).
    pub cone: Cone,
    /// The film frame of the tile's eye when the affine packet test runs
    /// (`cast/setup/affine.rs`), and `aff[j]`, the affine form of `tris[j]` (filled by
    /// [`TileTris::refine`]).
    pub frame: Option<FilmFrame>,
    pub aff: Vec<AffineTri>,
    /// Scratch of `setup_tile` (`cast/setup/tile.rs`): the tile's triangles in list order
    /// (`cast/setup/rows.rs`) and each leaf's end in that list.
    pub rows: TileRows,
    pub ends: Vec<u32>,
    /// Scratch of the sweep (`cast/setup/sweep.rs`): the tile's packets side by side.
    pub packets: TilePackets,
}

impl Default for Cone {
    fn default() -> Self {
        Cone::ANY
    }
}

impl TileTris {
    /// Replaces the lazy set-up `tris[j]` (`rho` NaN, [`TriSetup::new_with`]) by the band of
    /// [`TriSetup::new`] (the same `n`, `g`: the same arithmetic), keeping its classification.
    #[inline(never)]
    pub fn refine(&mut self, j: usize, blocks: &[Tri4]) {
        let s = &mut self.tris[j];
        let b = &blocks[(s.src >> 2) as usize];
        let ln = (s.src & 3) as usize;
        let v = [b.vertex(ln, 0), b.vertex(ln, 1), b.vertex(ln, 2)];
        match TriSetup::new(v, self.origin, s.tri, s.src, &self.cone) {
            Some(e) => {
                s.bound = e.bound;
                s.rho = e.rho;
                if let (Some(fr), Some(a)) = (&self.frame, self.aff.get_mut(j)) {
                    *a = fr.affine(&s.n);
                }
            }
            // (Never: the same checks passed in the lazy set-up.)
            None => s.rho = f32::INFINITY,
        }
    }
}

/// The shared origin of a tile's rays, if they have one (the beam's origin box is a point).
pub fn shared_origin(beam: &Beam) -> Option<Vec3> {
    (!beam.everything && !beam.origin.is_empty() && beam.origin.min == beam.origin.max)
        .then_some(beam.origin.min)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cast::lanes16::V16;
    use parallax_core::math::watertight_permutation;

    /// [`exact_t_lanes`] decides every lane without a zero edge function as [`exact_t`] does
    /// (hit or not, `t` bit for bit), on sixteen rays of one origin around a direction and
    /// triangles near, far, tiny, huge and degenerate (zero-area: its edge functions are often
    /// exactly zero, which the lanes leave to the scalar test).
    #[test]
    fn exact_t_lanes_equals_exact_t() {
        let mut f = crate::test_streams::uniform(0x853c_49e6_748f_ea9b);
        let mut v = |s: f32| Vec3::new(f() - 0.5, f() - 0.5, f() - 0.5) * s;
        let (mut hits, mut misses, mut zeros, mut cases) = (0, 0, 0, 0);
        for case in 0..6000 {
            let o = v(if case % 3 == 0 { 800.0 } else { 20.0 });
            let c = v(2.0).try_normalize().unwrap_or(Vec3::Z);
            let spread = [1e-4, 3e-3, 0.05, 0.3][case % 4];
            let d: Vec<Vec3> = (0..16).map(|_| c + v(spread)).collect();
            let perm = watertight_permutation(d[0]);
            if d.iter().any(|&di| watertight_permutation(di) != perm) {
                continue;
            }
            cases += 1;
            let dist = [0.05, 3.0, 400.0][case % 3];
            let size = [1e-3, 0.5, 50.0, 5e3][(case / 4) % 4];
            let centre = o + c * dist + v(size * 0.2);
            let mut p = [centre + v(size), centre + v(size), centre + v(size)];
            if case % 7 == 0 {
                // Degenerate: the third vertex on the first edge.
                p[2] = p[0] + (p[1] - p[0]) * 0.25;
            }
            if case % 11 == 0 {
                // A vertex at the origin: two edge functions exactly zero on every lane.
                p[0] = o;
            }
            let mut block = Tri4::EMPTY;
            for (vi, pv) in p.iter().enumerate() {
                for k in 0..3 {
                    block.p[vi][k].x = pv[k];
                }
            }
            let blocks = [block];
            let lanes = |k: usize| V16::from_fn(|l| d[l][k]);
            let rays = RaysN {
                o: [V16::splat(o.x), V16::splat(o.y), V16::splat(o.z)],
                d: [lanes(0), lanes(1), lanes(2)],
                valid: 0xffff,
            };
            let (zero, hit, t) = exact_t_lanes(&rays, perm, &splat_vertices::<V16>(&blocks, 0));
            for l in 0..16 {
                if zero >> l & 1 != 0 {
                    zeros += 1;
                    continue;
                }
                let scalar = exact_t(&WatertightRay::new(&rays.lane(l)), &blocks, 0);
                assert_eq!(hit >> l & 1 != 0, scalar.is_some(), "case {case} lane {l}");
                if let Some(ts) = scalar {
                    assert_eq!(ts.to_bits(), t.get(l).to_bits(), "case {case} lane {l}");
                    hits += 1;
                } else {
                    misses += 1;
                }
            }
        }
        assert!(cases > 4000 && hits > 5000 && misses > 30000 && zeros > 3000);
    }
}
