//! Per-tile triangle set-up and the set-up sample test (Hunt et al. 2018, §5.5, "triangle
//! setup ... tile-corner classification"): for a tile whose subsample rays share one origin `o`
//! (pinhole, stereo eye, lens-distorted, foveated, fisheye / wide-FoV models — everything but
//! the thin lens), every triangle of the tile's list is set up once relative to `o`, so that a
//! ray-triangle test is a few multiply-adds on the ray direction `d` alone:
//!
//! - **Edge covectors** `n_i = a_i x (a_{i+1} - a_i)` (`= a_i x a_{i+1}` exactly; `a_i = v_i - o`
//!   rounded, the very `a_i` of the watertight test's projection), `i = 0..2`, oriented by the
//!   sign of `D = N . a_0` (`N = (a_1 - a_0) x (a_2 - a_0)`): the ray `o + t d, t > 0` passes
//!   through the triangle iff `e_i(d) = n_i . d >= 0` for the three edges (for `d = p - o` with
//!   `p` of barycentrics `b`, `n_i . d = b_{i+2} D`). The short-edge form keeps the rounding
//!   error relative to `|a_i| |a_{i+1} - a_i|` instead of `|a_i|^2` (HVVR's `a_i x a_{i+1}`
//!   cancels for distant triangles). Watertightness no longer rests on bit-negated covectors
//!   but on the exact band below.
//! - **Inverse-distance covector** `g = N / D`, so `1/t = g . d` for any direction (`t` in
//!   units of `|d|`, the per-ray baseline's units since the rays are the same float rays). The
//!   closest hit is the largest positive `g . d` (rays of every camera have `t_min = 0,
//!   t_max = inf`).
//! - **Tile-corner classification** (§5.5): `n_i . d` is linear in `d`, and the tile beam
//!   ([`Beam`]) is the cone spanned by its four corner directions `c_k = s e_a + u e_b + v e_c`
//!   (every subsample ray of the tile satisfies `d / |d_a| = sum_k w_k c_k`, `w_k >= 0`,
//!   `sum w_k = 1`; the beam's slope bounds are rounded outwards, property-tested in
//!   tests/beams.rs). With `tol_i = bound cm + 3.1 U sum_j |n_ij| max_k |c_kj|` (`cm` the
//!   largest corner coordinate, `bound` the edge band below, `U = 2^-24`): if for some edge
//!   every corner has `n_i . c_k < -tol_i`, every ray of the tile has a real edge value below
//!   minus the watertight test's error — **all-out**, dropped; if every corner has
//!   `n_i . c_k > tol_i` for all three edges, every ray is certainly inside — **all-in**, only
//!   `g . d` is evaluated. Otherwise partial. So an all-in / all-out classification implies
//!   the per-ray band decision, which implies the watertight test's (tests/tile_setup.rs
//!   checks both against the watertight test on random beams and triangles).
//!
//! **Beyond HVVR: the exact band.** HVVR's set-up test decides with float signs, so it
//! disagrees with a per-ray watertight test on edges, leaks at shared vertices, and orders
//! overlapping coplanar faces by rounding noise. Ours uses the set-up values as a fast filter
//! with a conservative uncertainty band and decides everything inside the band with the BVH's
//! own watertight test (`WatertightRay::intersect_within`, Woop et al. 2013), so every hit
//! and `t` equal per-ray traversal bit for bit ([`SetupExactness::Full`]; the default
//! [`SetupExactness::Edges`] keeps only the edge band, below):
//!
//! - **Edge band** `bound |d|_inf` per triangle and tile (`TriSetup::bound`): forward error
//!   analysis of (1) our `fl(n_i . d)` against the real `e_i(d)` of the rounded `a_i`:
//!   `6.1 U |a_i|_1 |a_{i+1} - a_i|_1 |d|_inf` (edge subtraction, two products and a
//!   difference, the dot product); (2) the watertight test's edge function `u_i` (in `e`
//!   units: `e = |d_kz| u` exactly, the shear has determinant `1 / d_kz`) against `e_i(d)`:
//!   its projected coordinates are bounded by `psi = sqrt 3 (|a x c| + |a| r)` for every ray
//!   of the tile's cone (centre `c`, chord radius `r`, [`Cone`]), each carries
//!   `U (2.02 |a|_inf + 1.01 psi)` of error (shear product, rounded `d_kx / d_kz`,
//!   subtraction), and `u = c'x b'y - c'y b'x` adds `4.04 U psi_b psi_c`. Doubled for
//!   second-order terms. A ray with every edge value above the band is certainly inside
//!   (the watertight test sees three same-sign edge functions, and `t > 0`: all real values
//!   positive means the plane is crossed at `t > 0`), one edge below minus the band is
//!   certainly outside; otherwise the watertight test decides.
//! - **Depth band** `rho` (`TriSetup::rho`, relative): `g . d` loses `~14 U sigma kappa`
//!   (`kappa = |N| max |a| / |D|` = 1 / sine of the grazing angle for every ray through the
//!   triangle, `sigma` the sliver factor of `N`), the watertight `t = sum u_i z_i / sum u_i`
//!   moves by at most `sqrt 3 Lambda sum |du_i| / |D|` (`Lambda` the longest edge) plus `7U`.
//!   First order, doubled. A certain-inside candidate replaces the best only if `g . d` is
//!   above the best's band (`1.5 (rho_best + rho_cand)`); inside that band both watertight
//!   `t` are compared with the BVH's rule (`t` smaller, or equal and lower triangle index).
//!   Triangles with `rho > 0.05` (seen nearly edge-on, or their plane nearly through `o`)
//!   always take the watertight test.
//! - The winner's `t` is always the watertight test's (lane-wise in one pass per packet,
//!   `setup_full::final_t_lanes`), so the same triangle gives the same `t` bit for bit. A winner the
//!   watertight test rejects (a violated bound; never observed) sends the ray through an exact
//!   scan of the tile's list (`CastStats::setup_rescues`, asserted 0 in the tests).
//! - The early exit and the leaf box test use the upper bound `1 / (g . d (1 - rho))` of the
//!   best's watertight `t`.
//!
//! Caveat: the band analysis is first-order forward error analysis with a factor 2, not a
//! machine-checked proof; the tests compare every subsample of every scheme with per-ray
//! traversal and assert that no certain decision is ever contradicted (`setup_rescues`, the
//! fan and property tests). A camera exactly on a triangle's plane (`D = 0`: dropped here)
//! could get a `t ~ 0` hit from the watertight test.
//! - Triangles with `D = 0` (the plane holds `o`: seen edge-on, never hit by a ray from `o`)
//!   or a non-finite `g` are dropped.
//!
//! The sample test then runs packets of 4 (SSE) or 8 (AVX2) rays over the set-up list in the
//! tile list's near-depth order, leaf by leaf; a triangle whose `g . d` is below every lane's
//! best so far costs one 3-term dot product; the packet stops once every ray has a hit nearer
//! than the next leaf's near depth (as the watertight kernel). Beyond the paper (its GPU threads
//! test every triangle of the tile): before a leaf's set-up triangles, the packet runs the
//! BVH's robust slab test on the box of the leaf's *kept* triangles and skips the leaf if no
//! ray can reach it before its closest hit so far (this cut the triangle tests per ray from ~60
//! to ~1.2 on atrium at 96 x 64).
//!
//! **Watertightness at vertices.** With float signs alone, rays exactly through a shared
//! vertex leaked (all spoke values rounding noise of one sign: 32 of 800 fan-centre rays with
//! HVVR's covectors, 19 with ours); with the band they are decided by the watertight test,
//! which gives the vertex to exactly one triangle of the fan (tests/tile_setup.rs asserts
//! it for every ray).
//!
//! **Two settings, [`SetupExactness`]** (in [`crate::CastOptions`]; CLI `--visibility beam`
//! vs `beam-exact`):
//!
//! - **`Edges` (default)**: the edge band only (`cast/setup/edges.rs`): coverage is exact (no
//!   vertex hole, shared edges decided by the watertight test), depth is HVVR's largest
//!   `1/t = g . d` with `t = 1 / (g . d)` for the winner. Differences from per-ray traversal
//!   are depth ties only (`t` equal within ~1e-5 relative, never hit vs miss): 0 on atrium in
//!   every test, 47 of 213,385 subsamples on cornell (coplanar overlapping faces).
//! - **`Full`**: the edge band, the depth band and the winner's watertight `t` (below):
//!   bit-identical to per-ray traversal.
//!
//! Edges is the default because Full's extra cost buys only the order of depth ties at equal
//! `t` (within float tolerance, which the done-when allows) and bit-exact `t`, while
//! it costs up to ~25% more beam-cast time (measured below; classroom ~3%); Edges keeps
//! most of the speed of the kernel without any band (~6-12% slower on atrium, up to ~15% on
//! the other scenes in these noisy runs).
//!
//! **Cost of exactness** (`cargo run --release -p parallax-render --example vr_cast_cpu --
//! SCENE 540 600 16 3 MODE`: stereo 1080 x 600 film, spp 16, one thread, thread CPU time,
//! best of 3; runs of the pre-band binary (commit fd42ce8, the same example) and of this one,
//! alternating, two rounds each, on the loaded 2-core VM; beam Mrays/s and beam / per-ray
//! ratio, best round):
//!
//! | scene (`SCENE`)  | pre-band (fd42ce8)   | Edges (default)      | Full                 |
//! |------------------|----------------------|----------------------|----------------------|
//! | atrium           | 18.2 Mrays/s, 4.19x  | 18.7 Mrays/s, 4.20x  | 15.5 Mrays/s, 3.47x  |
//! | Sponza           | 43.2 Mrays/s, 5.24x  | 37.2 Mrays/s, 4.58x  | 31.5 Mrays/s, 3.83x  |
//! | classroom        | 36.9 Mrays/s, 2.61x  | 31.9 Mrays/s, 2.17x  | 30.8 Mrays/s, 2.09x  |
//!
//! (Sponza: `../shared/scenes/sponza_dabrovic/sponza_dabrovic.glb`, classroom:
//! `../shared/scenes/japanese_classroom/japanese_classroom.glb`, from the repository root,
//! each with `Scene::camera(None)`; `MODE` = `edges` or `full`, the pre-band binary ignores
//! it.) The machine's load rose during this run (atrium pre-band 569-597 ms, against 461-476
//! ms an hour earlier), so single figures swing ~10%: an earlier, quieter run of the
//! eager-band Edges kernel gave atrium 4.78-4.80x pre-band, 4.32-4.37x Edges, 3.37-3.45x Full;
//! Sponza 5.12-5.45x, 4.45-4.53x, 3.17-3.78x; classroom 2.43x, 2.10x, 2.06x. perf samples of
//! the lazy Edges kernel against the pre-band one on classroom at 1080 x 300 (6 rounds)
//! found no difference beyond noise (sample stage 4134 vs 4226 samples, set-up 348 vs 389).
//! Watertight fallbacks (of the ray-triangle tests): Edges 0.12% (atrium, classroom) and
//! 0.03% (Sponza), all edge band; Full 2.27% / 0.05% / 0.31% plus the winners' `t` (0.89 /
//! 0.42 / 0.06 tests per ray). A later, quieter atrium run (load ~3, the final code, same
//! command, pre-band / Edges alternating twice, then Full and pre-band once): pre-band
//! 460-493 ms (21.0-22.5 Mrays/s, 4.63-4.95x), Edges 521-524 ms (19.8-19.9 Mrays/s,
//! 4.31-4.39x), Full 658 ms (15.8 Mrays/s, 3.41x): Edges costs ~6-12% on atrium, Full ~40%.
//! The lead re-measures on the idle machine.
//!
//! Where Edges' extra time over the pre-band kernel goes (perf samples, atrium 1080 x 300):
//! more than half was the band analysis in `TriSetup::new` (per triangle and tile: replacing
//! it by constants saved ~10 ms of ~205 ms at 1080 x 300), so Edges sets triangles up
//! lazily: the corner classification uses a crude conservative band (from `max |a_i|_1`
//! alone, a few flops) and the full band is computed when a packet first reaches the
//! triangle (`TileTris::refine`; all-out and unreached triangles never pay it); the rest is
//! spread over the kernel (a second compare for packets with a candidate lane not certainly
//! inside, the larger `TriSetup`). The edge band's watertight tests themselves (0.12% of the
//! ray-triangle tests on atrium) are negligible. Full adds the winners' watertight `t` (0.89
//! tests per ray, one lane-wise test per packet) and the depth band's scalar watertight tests
//! (2.3% of the ray-triangle tests on atrium, ~60% of them overlapping coplanar faces with
//! bit-identical `g` that no float filter can order). Not done: a cheaper exact `t` for Full
//! (e.g. deferred to the consumers of the buffer), a vectorised band analysis.
//!
//! **Measured before the exact band** (`cargo run --release -p parallax-render --example vr_speed -- atrium 540 600
//! 1,8,16,32 4 setup`, then `... 4 watertight`; stereo 540 x 600 per eye, 2 threads on the 2-core
//! VM at load average 13-15 from other jobs, so wall times swing ~1.5x; speed-up = beam wall time
//! vs per-ray `trace_per_ray` wall time in the same process, best of 3 / best of 2):
//!
//! | spp | set-up kernel (default) | watertight kernel |
//! |-----|-------------------------|-------------------|
//! | 1   | 2.03x (4.8 Mrays/s)     | 1.86x (3.1)       |
//! | 8   | 3.82x (7.9)             | 2.37x (3.5)       |
//! | 16  | 5.02x (7.3)             | 2.53x (5.3)       |
//! | 32  | 3.86x (7.3)             | 2.30x (5.6)       |
//!
//! Interleaved spp-16-only runs at load 7-8: set-up 3.95x (10.4 Mrays/s), watertight 2.10x
//! (5.7), set-up 4.37x (13.0): the set-up kernel casts 1.8-2.3x faster than the watertight one.
//! (A spp-16-only pair of runs gave 4.05x for the 4-lane and 3.81x for the 8-lane set-up kernel,
//! and 3.43x / 4.70x in another pair: the AVX2 8-lane build is no faster — LLVM leaves most of
//! its `[f32; 8]` lane loops scalar (objdump: ~5x more xmm than ymm instructions), so 4 lanes
//! is the default.) The 5x aim at spp 16 is reached in one of these loaded runs, not
//! reliably; the full 2160 x 1200 table needs the idle machine. Per 4-ray packet the kernel
//! does ~1.2 triangle tests per ray (set-up on atrium at 96 x 64); the set-up itself is
//! counted in the caster's tile-cull time. At 96 x 64 tiles are large: 1-6% of a tile's
//! triangles are all-out, < 1% all-in, the rest partial (the tile cull's leaf boxes already
//! hug the beam) — the classification pays more at VR resolutions. Not done: the affine
//! film-position form of `n . d` for pinhole tiles (the ray generation still normalises every
//! direction), 4/8 triangles per SIMD op, a vectorised 8-lane build.
//!
//! **Exactness.** `Full`: same triangle and bit-identical `t` as per-ray traversal on every
//! subsample of every scheme tested (tests/cast.rs: 0 differences in 426,770 subsamples at
//! 96 x 64 and in 307,200 at 240 x 160). `Edges` (default): the same tests find 0
//! differences on atrium (96 x 64 and 240 x 160) and 47 of 213,385 on cornell, all depth
//! ties (both hit, `t` within 1e-5 relative; `t` itself within ~1e-5 of the watertight `t`). Tiles without a shared origin (thin lens) take the
//! exact watertight kernel ([`crate::cast::intersect`]).

pub mod edges;
pub mod full;

use crate::beam::Beam;
use crate::beam::LeafRef;
use glam::{Vec3, Vec4};
use parallax_bvh::Tri4;
use parallax_bvh::node::{leaf_count, leaf_first};
use parallax_core::math::{ROBUST_FAR_SCALE, WatertightRay};
use parallax_core::{Aabb, NO_ID, Ray};

use crate::SampleSet;
use crate::cast::packet::{Lanes, for_each_packet, max_or_rhs, min_or_rhs, permutation};

/// Which sample test the caster runs (module docs of `cast/setup/mod.rs` and `intersect.rs`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SampleTest {
    /// The BVH's watertight test per ray (Woop et al. 2013), bit-identical to per-ray traversal.
    Watertight,
    /// HVVR's per-tile triangle set-up with tile-corner classification (this module), exact
    /// through its uncertainty band; tiles without a shared ray origin (thin lens) fall back
    /// to [`SampleTest::Watertight`].
    #[default]
    TileSetup,
}

/// How exactly the set-up kernel ([`SampleTest::TileSetup`]) reproduces per-ray traversal
/// (module docs, "cost of exactness").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SetupExactness {
    /// Exact coverage (the edge band: no vertex hole, shared edges decided by the watertight
    /// test), depth by the largest `1/t = g . d` with `t = 1 / (g . d)` (HVVR §5.5): equal to
    /// per-ray traversal up to depth ties within float tolerance (`cast/setup/edges.rs`). The
    /// default: it keeps the set-up kernel's speed (module docs).
    #[default]
    Edges,
    /// Edge and depth bands, the winner's `t` by the watertight test: the same triangle and
    /// `t`, bit for bit, as per-ray traversal (module docs, "exact band"), ~1.5x slower.
    Full,
}

/// Unit roundoff of f32 (`2^-24`): `fl(x op y) = (x op y)(1 + δ)`, `|δ| <= U`.
pub(super) const U: f32 = f32::EPSILON * 0.5;
const SQRT3: f32 = 1.732_051;
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

    /// [`TriSetup::new`], or with `lazy` a cheap set-up for [`SetupExactness::Edges`]: a
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
        if !n.iter().flatten().all(|x| x.is_finite()) {
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
    /// Box of the run's triangles relative to the origin (`min - o`, `max - o`).
    pub lo: Vec3,
    pub hi: Vec3,
}

/// Counts of the corner classification.
#[derive(Clone, Copy, Debug, Default)]
pub struct SetupCounts {
    pub all_out: u64,
    pub partial: u64,
    pub all_in: u64,
}

/// The set-up triangle list of a tile (per-thread scratch, reused).
#[derive(Clone, Debug, Default)]
pub struct TileTris {
    pub origin: Vec3,
    pub tris: Vec<TriSetup>,
    pub segs: Vec<Segment>,
    pub counts: SetupCounts,
    /// The largest depth band `rho` of the list's well-conditioned triangles.
    pub rho_max: f32,
    /// The watertight permutation `(kx, ky, kz)` shared by every ray of the tile, when the
    /// beam's slopes are below 1 (`|d_a|` strictly dominant, sign fixed).
    pub perm: Option<(usize, usize, usize)>,
    /// The cone of the tile's rays (for the lazy band, [`TileTris::refine`]).
    pub cone: Cone,
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

/// Sets up every triangle of the tile list `leaves` (near-depth order) for rays from `origin`
/// within `beam`, dropping all-out triangles (module docs).
pub fn setup_tile(
    blocks: &[Tri4],
    leaves: &[LeafRef],
    beam: &Beam,
    origin: Vec3,
    lazy: bool,
    out: &mut TileTris,
) {
    out.origin = origin;
    out.tris.clear();
    out.segs.clear();
    out.rho_max = 0.0;
    let corners = BeamCorners::new(beam);
    let cone = Cone::of(corners.as_ref());
    out.cone = cone;
    out.perm = corners.and_then(|c| {
        // Float division is monotone and x / x = 1: slopes below 1 mean |d_b| < |d_a|.
        let (a, (b, cc)) = (beam.axis as usize, beam.side_axes());
        (c.cmax[b] < 1.0 && c.cmax[cc] < 1.0).then(|| {
            let mut d = Vec3::ZERO;
            d[a] = beam.sign;
            permutation(d)
        })
    });
    for r in leaves {
        let mut bx = Aabb::EMPTY;
        let (first, count) = (leaf_first(r.leaf), leaf_count(r.leaf));
        for j in 0..count {
            let bi = first + j / 4;
            let b = &blocks[bi as usize];
            let ln = (j % 4) as usize;
            if b.tri[ln] == u32::MAX {
                continue;
            }
            let v = [b.vertex(ln, 0), b.vertex(ln, 1), b.vertex(ln, 2)];
            let Some(mut s) =
                TriSetup::new_with(v, origin, b.tri[ln], 4 * bi + ln as u32, &cone, lazy)
            else {
                out.counts.all_out += 1;
                continue;
            };
            match corners.map_or(CornerClass::Partial, |c| c.classify(&s)) {
                CornerClass::AllOut => {
                    out.counts.all_out += 1;
                    continue;
                }
                CornerClass::AllIn => {
                    out.counts.all_in += 1;
                    s.all_in = true;
                }
                CornerClass::Partial => out.counts.partial += 1,
            }
            if s.rho <= RHO_MAX {
                out.rho_max = out.rho_max.max(s.rho);
            }
            out.tris.push(s);
            bx = bx.grow(v[0]).grow(v[1]).grow(v[2]);
        }
        let end = out.tris.len() as u32;
        if out.segs.last().map_or(0, |s| s.end) < end {
            out.segs.push(Segment {
                end,
                near: r.near,
                lo: bx.min - origin,
                hi: bx.max - origin,
            });
        }
    }
}

/// `n . d` per lane in the scalar order of [`dot3`] (no FMA: plain functions, not closures,
/// so they are compiled inside the AVX2 entry point).
#[inline(always)]
pub(super) fn dot_n<L: Lanes>(n: [f32; 3], dx: L, dy: L, dz: L) -> L {
    L::splat(n[0]) * dx + L::splat(n[1]) * dy + L::splat(n[2]) * dz
}

/// Entry and exit `t` of one slab (`lo`, `hi` relative to the origin).
#[inline(always)]
pub(super) fn slab<L: Lanes>(lo: f32, hi: f32, inv: L, neg: L::M) -> (L, L) {
    let t0 = L::splat(lo) * inv;
    let t1 = L::splat(hi) * inv;
    (L::select(neg, t1, t0), L::select(neg, t0, t1))
}

/// Per-packet constants of the set-up kernels (`cast/setup/edges.rs`, `cast/setup/full.rs`): reciprocal
/// directions and their signs for the BVH's robust slab test, and the packet's largest
/// `|d|_inf` over its lanes (the scale of the edge band; invalid lanes have `d = 0`).
pub(super) struct PacketSlab<L: Lanes> {
    inv: [L; 3],
    neg: [L::M; 3],
    pub dinf: f32,
}

impl<L: Lanes> PacketSlab<L> {
    #[inline(always)]
    pub(super) fn new([dx, dy, dz]: [L; 3]) -> Self {
        let (zero, one) = (L::splat(0.0), L::splat(1.0));
        let inv = [one / dx, one / dy, one / dz];
        let neg = [inv[0].lt(zero), inv[1].lt(zero), inv[2].lt(zero)];
        let abs = |x: L| L::select(x.lt(zero), zero - x, x);
        let dinf_l = max_or_rhs(abs(dx), max_or_rhs(abs(dy), abs(dz)));
        let mut dinf = 0.0f32;
        for l in 0..L::N {
            dinf = dinf.max(dinf_l.get(l));
        }
        Self { inv, neg, dinf }
    }

    /// The BVH's robust slab test (Ize 2013 far scaling) of the packet on a run's box: true
    /// when a lane of `valid` reaches the box before `box_lim` (its closest hit so far).
    #[inline(always)]
    pub(super) fn reaches(&self, seg: &Segment, box_lim: L, valid: u32) -> bool {
        let (inv, neg) = (&self.inv, &self.neg);
        let (tnx, tfx) = slab(seg.lo.x, seg.hi.x, inv[0], neg[0]);
        let (tny, tfy) = slab(seg.lo.y, seg.hi.y, inv[1], neg[1]);
        let (tnz, tfz) = slab(seg.lo.z, seg.hi.z, inv[2], neg[2]);
        let t_near = max_or_rhs(tnz, max_or_rhs(tny, max_or_rhs(tnx, L::splat(0.0))));
        let t_far = min_or_rhs(tfz, min_or_rhs(tfy, min_or_rhs(tfx, box_lim)));
        L::bits(t_near.le(t_far * L::splat(ROBUST_FAR_SCALE))) & valid != 0
    }
}

/// Work counters of the set-up kernel.
#[derive(Clone, Copy, Debug, Default)]
pub struct SetupWork {
    pub rays: u64,
    /// Packet-triangle tests (one per packet of `lanes` rays and set-up triangle).
    pub tri_tests: u64,
    /// Ray-triangle tests (valid lanes of the packet-triangle tests).
    pub pair_tests: u64,
    /// Watertight tests run in the band (edge or depth uncertain), per ray and triangle.
    pub exact_tests: u64,
    /// Watertight tests of winners for their bit-exact `t`.
    pub final_tests: u64,
    /// Of `exact_tests`: edge value within the band (the rest: depth band).
    pub edge_band: u64,
    /// Rays re-decided by the exact scan (a certain decision contradicted; expected 0).
    pub rescues: u64,
}

impl SetupWork {
    /// Adds `o`'s counters to these.
    pub fn add(&mut self, o: &Self) {
        self.rays += o.rays;
        self.tri_tests += o.tri_tests;
        self.pair_tests += o.pair_tests;
        self.exact_tests += o.exact_tests;
        self.final_tests += o.final_tests;
        self.edge_band += o.edge_band;
        self.rescues += o.rescues;
    }
}

/// Runs every subsample ray `0..total` of a tile (`pair(j)` = its `(sample, k)`) through the
/// set-up kernel with `L::N` lanes; `write(pair, t, tri)` stores a result.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn run_setup<L: Lanes, const FULL: bool>(
    set: &SampleSet,
    blocks: &[Tri4],
    tt: &mut TileTris,
    axis: usize,
    sign: f32,
    slack: f32,
    total: usize,
    pair: impl Fn(usize) -> (u32, u32),
    mut write: impl FnMut((u32, u32), f32, u32),
) -> SetupWork {
    let mut work = SetupWork::default();
    let rays_n = for_each_packet::<L>(set, total, pair, |batch, rays| {
        let mut rays = *rays;
        // Invalid lanes get `d = 0`: `g . d = 0` is never a hit.
        for l in 0..batch.len() {
            if rays.valid >> l & 1 == 0 {
                for a in 0..3 {
                    rays.d[a] = L::from_fn(|i| if i == l { 0.0 } else { rays.d[a].get(i) });
                }
            }
        }
        let c = if FULL {
            crate::cast::setup::full::closest_full(
                &rays, blocks, &*tt, axis, sign, slack, &mut work,
            )
        } else {
            crate::cast::setup::edges::closest_edges(
                &rays, blocks, tt, axis, sign, slack, &mut work,
            )
        };
        for (l, &p) in batch.iter().enumerate() {
            write(p, c.t[l], c.tri[l]);
        }
    });
    work.rays = rays_n;
    work
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
unsafe fn run_setup_avx2<const FULL: bool>(
    set: &SampleSet,
    blocks: &[Tri4],
    tt: &mut TileTris,
    axis: usize,
    sign: f32,
    slack: f32,
    total: usize,
    pair: impl Fn(usize) -> (u32, u32),
    write: impl FnMut((u32, u32), f32, u32),
) -> SetupWork {
    run_setup::<crate::cast::packet::F8, FULL>(
        set, blocks, tt, axis, sign, slack, total, pair, write,
    )
}

/// Tests every subsample ray of the tile `samples` against the set-up list `tt` (built from
/// `blocks`) and writes the closest hits, packets of 8 rays (AVX2, if detected and
/// `lanes == 8`) or 4.
///
/// # Safety
/// As [`crate::cast::intersect::test_tile`]: `prim` and `t` valid for `set.ray_count()` elements,
/// written for these samples by this call only.
#[allow(clippy::too_many_arguments)]
pub unsafe fn test_tile_setup(
    set: &SampleSet,
    blocks: &[Tri4],
    prim_ids: &[u32],
    samples: &[u32],
    tt: &mut TileTris,
    beam: &Beam,
    scale: f32,
    lanes: usize,
    exactness: SetupExactness,
    prim: *mut u32,
    t: *mut f32,
) -> SetupWork {
    let spp = set.spp as usize;
    let slack = 1e-5 * (scale.abs() + 1.0);
    let total = samples.len() * spp;
    let pair = |j: usize| (samples[j / spp], (j % spp) as u32);
    let write = |(i, k): (u32, u32), bt: f32, tri: u32| {
        let o = i as usize * spp + k as usize;
        // SAFETY: the caller guarantees exclusive access to this sample's entries.
        unsafe {
            if tri == u32::MAX {
                *prim.add(o) = NO_ID;
                *t.add(o) = f32::INFINITY;
            } else {
                *prim.add(o) = prim_ids[tri as usize];
                *t.add(o) = bt;
            }
        }
    };
    let (axis, sign) = (beam.axis as usize, beam.sign);
    #[cfg(target_arch = "x86_64")]
    if lanes == 8 && std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 was detected.
        return unsafe {
            match exactness {
                SetupExactness::Edges => {
                    run_setup_avx2::<false>(set, blocks, tt, axis, sign, slack, total, pair, write)
                }
                SetupExactness::Full => {
                    run_setup_avx2::<true>(set, blocks, tt, axis, sign, slack, total, pair, write)
                }
            }
        };
    }
    match exactness {
        SetupExactness::Edges => {
            run_setup::<Vec4, false>(set, blocks, tt, axis, sign, slack, total, pair, write)
        }
        SetupExactness::Full => {
            run_setup::<Vec4, true>(set, blocks, tt, axis, sign, slack, total, pair, write)
        }
    }
}
