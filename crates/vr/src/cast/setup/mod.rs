//! Per-tile triangle set-up and the set-up sample test (Hunt et al. 2018, §5.5, "triangle
//! setup ... tile-corner classification"): for a tile whose subsample rays share one origin `o`
//! (pinhole, stereo eye, lens-distorted, foveated, fisheye / wide-FoV models; a thin lens's
//! tile one lens point at a time, `lens_k` of [`test_tile_setup`]), every triangle of the tile's list is set up once relative to `o`, so that a
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
//! **The affine packet test** ([`affine`], `Edges` only, pinhole and stereo tiles): before a
//! packet's per-lane edge test, the edge functions' affine form in the film position decides
//! the whole packet (one pixel at 16 spp) against the triangle — every lane certainly out or
//! certainly in, with a rigorous error bound — or leaves it to the per-lane test; the buffer is
//! the same bit for bit (`tests/affine.rs`).
//!
//! **Set-up in lanes** (`cast/setup/tile.rs`, `cast/setup/lazy.rs`): the `Edges` set-up (lazy
//! band, classification) runs sixteen consecutive triangles of the tile list at once in one
//! AVX-512 register per value where the CPU has AVX-512F, eight in one AVX register where it
//! has AVX2, four in SSE registers elsewhere or with `CastOptions::isa` at [`Isa::Sse`]
//! (`cast/isa.rs`), and the full
//! bands of a run's triangles four at a time when a packet first enters the run; per lane the
//! scalar operations in the scalar order, so the list is bit-identical to the scalar twin's
//! (tested there). `Full` sets up one triangle at a time.
//!
//! The sample test then runs packets of 4 (SSE), 8 (AVX2) or 16 (one AVX-512, two AVX or four
//! SSE registers) rays over the set-up list in the
//! tile list's near-depth order, leaf by leaf; a triangle whose `g . d` is below every lane's
//! best so far costs one 3-term dot product; the packet stops once every ray has a hit nearer
//! than the next leaf's near depth (as the watertight kernel). Beyond the paper (its GPU threads
//! test every triangle of the tile): before a leaf's set-up triangles, the packet runs the
//! BVH's robust slab test on the box of the leaf's *kept* triangles and skips the leaf if no
//! ray can reach it before its closest hit so far.
//!
//! **The sweep** (`cast/setup/sweep.rs`, [`crate::CastOptions::sweep`]): where every 16-lane
//! packet of a tile is one sample's chunk of 16 subsamples (pinhole and stereo eyes at 16 and
//! 32 spp, `Edges`), the tile's packets are generated once and each set-up triangle is swept
//! over all of them, its affine packet test on 16 packets per register; the same per-packet
//! test and the same buffer as the walk above, without the walk's per-packet set-up.
//!
//! **Each triangle once** (`cast/setup/rows.rs`): a triangle split by the BVH's spatial splits
//! (the SBVH, the default build) sits in several leaves, and a tile's list often reaches it
//! twice. The gather keeps its first entry (the leaf of smallest near depth) and drops the
//! others before the set-up (`CastStats::tris_repeated`): set up twice, a triangle tied with
//! itself at the same `1/t` and `Full` sent every such tie to the watertight test (atrium,
//! distorted, 4 spp: 5.9% of the ray-triangle tests in the band with the repeats, 0.79%
//! without, 0.82% on the object-split tree; `docs/notes/bvh.md`).
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
//! `Edges` is the default: `Full`'s extra cost buys only the order of depth ties at equal `t`
//! (within float tolerance) and a bit-exact `t`.
//!
//! **Exactness** (tested in `tests/cast.rs` on every scheme): `Full` gives the same triangle and
//! a bit-identical `t` as per-ray traversal for every subsample; `Edges` differs only in depth
//! ties (both hit, `t` within 1e-5 relative). Tiles without a shared origin (orthographic
//! cameras, a thin-lens tile with a lens point's rays that no beam bounds) take the exact
//! watertight kernel ([`crate::cast::intersect`]).
//!
//! **Parameters** (of [`test_tile_setup`], set through [`crate::CastOptions`]):
//!
//! | name | type | default | meaning |
//! |---|---|---|---|
//! | `exactness` | [`SetupExactness`] | `Edges` | which bands decide by the watertight test |
//! | `lanes` | usize | 16 | rays per packet: 4 (SSE), 8 (AVX2 if detected and allowed, else 4) or 16 |
//! | `isa` | [`Isa`] | the widest detected | lanes of 16-ray packets: one AVX-512 register, two AVX registers, four SSE registers ([`crate::cast::lanes16`], the portable twin) |
//! | [`RHO_MAX`] | f32 | 0.05 | depth band above which a triangle always takes the watertight test |
//! | `affine` | bool | true | the affine packet test ([`affine`]) before the per-lane edge test (`Edges` only) |
//! | `affine_always` | bool | false | the affine packet test on the AVX-512 kernel and the AVX2 16-lane kernel at 1 spp too (slower there, `docs/notes/vr.md`) |
//! | `sweep` | bool | true | the sweep (above) where it applies |
//!
//! Measurements (speed of `Edges` and `Full` against the kernel without a band, 4 vs 8 lanes,
//! where the time goes): `docs/notes/vr.md`.

pub mod affine;
mod bands;
pub mod edges;
pub mod full;
mod kernel;
mod lazy;
mod out;
mod rows;
mod sweep;
mod tile;
mod tile_packets;
mod tri;

use glam::{Vec2, Vec4};
use parallax_bvh::Tri4;

use crate::SampleSet;
use crate::beam::Beam;
use crate::cast::isa::Isa;
use crate::cast::lanes16::{LaneReduce, V16};
#[cfg(target_arch = "x86_64")]
use crate::cast::lanes256::{Y8, Y16};
#[cfg(target_arch = "x86_64")]
use crate::cast::lanes512::Z16;
use crate::cast::packet::{
    MAX_LANES, RaysN, gen_n_film, gen_samples, sample_chunk, sample_chunk_lens,
};
use crate::cast::stored::RayBuffer;
use crate::samples::MAX_SPP;
use affine::{FilmFrame, PacketBox};
use out::Out;
use parallax_scene::camera::Camera;

pub use kernel::SetupWork;
pub use tile::{setup_tile, setup_tile_scalar, setup_tile_with};
pub use tri::{
    BeamCorners, Cone, CornerClass, EdgeClass, RHO_MAX, Segment, SetupCounts, TileTris, TriSetup,
    dot3, exact_closest, exact_t, shared_origin,
};

/// Which sample test the caster runs (module docs of `cast/setup/mod.rs` and `intersect.rs`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SampleTest {
    /// The BVH's watertight test per ray (Woop et al. 2013), bit-identical to per-ray traversal.
    Watertight,
    /// HVVR's per-tile triangle set-up with tile-corner classification (this module), exact
    /// through its uncertainty band; a thin lens's tiles are set up per lens point
    /// (`Hierarchy::lens_beams`); tiles without a shared ray origin otherwise fall back to
    /// [`SampleTest::Watertight`].
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

/// Runs every subsample ray `0..samples.len() * spp` of a tile (`pair(j)` = its `(sample, k)`) through the
/// set-up kernel with `L::N` lanes; the results go to `out`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn run_setup<L: LaneReduce, const FULL: bool>(
    set: &SampleSet,
    stored: Option<&RayBuffer>,
    blocks: &[Tri4],
    tt: &mut TileTris,
    axis: usize,
    sign: f32,
    slack: f32,
    samples: &[u32],
    film: Option<[&[f32]; 3]>,
    lens_k: Option<u32>,
    sweep: bool,
    pair: impl Fn(usize) -> (u32, u32),
    out: Out,
) -> SetupWork {
    let total = samples.len() * set.spp as usize;
    let mut work = SetupWork::default();
    // The packet loop of `for_each_packet`, written out: the kernel must not sit in a closure
    // (no target features there: the AVX-512 lanes would be out-of-line calls, measured 3x
    // slower; `cast/lanes512.rs`).
    let mut rays_n = 0u64;
    let mut pairs = [(0u32, 0u32); MAX_LANES];
    // The affine packet test (`affine.rs`): per chunk of `L::N` subsamples the range of their
    // offsets (one-sample packets take their film box from it).
    let frame = if FULL { None } else { tt.frame };
    let spp = set.spp as usize;
    let chunked = spp.is_multiple_of(L::N);
    let mut ranges = [(Vec2::ZERO, Vec2::ZERO); MAX_SPP as usize / 4];
    // One sample's chunk of `L::N` subsamples: its offsets in lanes, kept for the tile (the
    // ray generator's `gen_one_sample` builds them per packet).
    let zero = L::splat(0.0);
    let mut lanes = [(zero, zero); MAX_SPP as usize / 4];
    if chunked {
        for c in 0..spp / L::N {
            let o = &set.offsets[c * L::N..(c + 1) * L::N];
            ranges[c] = o
                .iter()
                .fold((o[0], o[0]), |(a, b), &x| (a.min(x), b.max(x)));
            lanes[c] = (L::from_fn(|l| o[l].x), L::from_fn(|l| o[l].y));
        }
    }
    // The set-up kernel on a packet (`rays`, `pbox`).
    macro_rules! closest {
        ($rays:expr, $pbox:expr, $first:expr) => {
            if FULL {
                full::closest_full($rays, blocks, &*tt, axis, sign, slack, &mut work)
            } else {
                edges::closest_edges(
                    $rays, blocks, tt, axis, sign, slack, $pbox, $first, &mut work,
                )
            }
        };
    }
    if let Some(k) = lens_k {
        // One lens sample `k` of every sample (a thin-lens tile's rays from one lens point):
        // packets of `L::N` consecutive samples, neighbours on the film, as at 1 spp (edges
        // first).
        let mut j = 0;
        while j < samples.len() {
            let n = (samples.len() - j).min(L::N);
            for (p, &i) in pairs.iter_mut().zip(&samples[j..j + n]) {
                *p = (i, k);
            }
            j += n;
            let batch = &pairs[..n];
            let (mut rays, _) = gen_n_film::<L>(set, stored, batch);
            rays_n += clear_invalid(&mut rays, n);
            let c = closest!(&rays, None, true);
            for (l, &p) in batch.iter().enumerate() {
                // SAFETY: as below.
                unsafe { out.one(p, c.t[l], c.tri[l]) };
            }
        }
        work.rays = rays_n;
        return work;
    }
    let lens_chunk = matches!(set.camera, Camera::Distorted(_) | Camera::Fisheye(_));
    // The sweep (`sweep.rs`): whole tiles of 16-subsample chunks with affine boxes.
    if !FULL && sweep && chunked && L::N == MAX_LANES && !lens_chunk && stored.is_none() {
        let c = spp / L::N;
        let (ch, rg) = (&lanes[..c], &ranges[..c]);
        let swept = sweep::sweep_edges(
            set, blocks, tt, axis, sign, slack, samples, ch, rg, out, &mut work,
        );
        if swept {
            return work;
        }
    }
    // Packets of whole samples (`gen_samples`: pinhole and stereo cameras, below `L::N`
    // subsamples; one sample's packets take the chunk path below) and the lanes' offsets
    // `offsets[l % spp]`.
    let whole_samples = L::N.is_multiple_of(spp)
        && spp < L::N
        && matches!(set.camera, Camera::Pinhole(_) | Camera::Stereo(_));
    let shift = spp.trailing_zeros();
    let whole_off = if whole_samples {
        (
            L::from_fn(|l| set.offsets[l % spp].x),
            L::from_fn(|l| set.offsets[l % spp].y),
        )
    } else {
        (zero, zero)
    };
    let mut j = 0;
    while j < total {
        let n = (total - j).min(L::N);
        // One subsample per sample: the packet's samples are `samples[j..j + n]`, its rays
        // from their film positions in lanes (`gen_samples`), no `(sample, k)` pairs.
        let spp1 = if spp == 1 && n == L::N && stored.is_none() {
            let f = film.map(|f| f.map(|v| &v[j..j + n]));
            let o = set.offsets[0];
            let off = (L::splat(o.x), L::splat(o.y));
            gen_samples::<L>(set, f, &samples[j..j + n], 0, off)
        } else {
            None
        };
        if let Some((rays, (lo, hi))) = spp1 {
            let pbox = frame.and_then(|fr| PacketBox::new(&fr, lo.x, hi.x, lo.y, hi.y));
            rays_n += n as u64;
            // (Edges first: `edges.rs`; the other packets keep the depth test first.)
            let c = closest!(&rays, pbox.as_ref(), true);
            // SAFETY: as below.
            unsafe { out.spp1(&samples[j..j + n], &c) };
            j += n;
            continue;
        }
        // Several whole samples (`spp` dividing `L::N`, below it; `j` is then a multiple of
        // `spp`): the packet's samples are `samples[j / spp..(j + n) / spp]`, its rays from
        // their film positions in lanes (`gen_samples`), no `(sample, k)` pairs.
        let whole = if whole_samples && n == L::N && stored.is_none() {
            let idx = &samples[j >> shift..(j + n) >> shift];
            gen_samples::<L>(set, None, idx, shift, whole_off).map(|r| (r, idx))
        } else {
            None
        };
        if let Some(((rays, (lo, hi)), idx)) = whole {
            let pbox = frame.and_then(|fr| PacketBox::new(&fr, lo.x, hi.x, lo.y, hi.y));
            rays_n += n as u64;
            let c = closest!(&rays, pbox.as_ref(), false);
            // SAFETY: as below.
            unsafe { out.samples(idx, &c) };
            j += n;
            continue;
        }
        // `j` is a multiple of `L::N`: with `chunked` (`spp % L::N == 0`) a full packet is one
        // sample's aligned chunk `k0..k0 + L::N` (`pair(j) = (samples[j / spp], j % spp)`).
        let chunk = chunked && n == L::N;
        let (i0, k0) = pair(j);
        let c = k0 as usize / L::N;
        let chunk_rays = if chunk && stored.is_none() {
            let ((ox, oy), (a, b)) = (lanes[c], ranges[c]);
            if lens_chunk {
                sample_chunk_lens::<L>(set, i0, ox, oy)
            } else {
                sample_chunk::<L>(set, i0, ox, oy, a.x, b.x)
            }
        } else {
            None
        };
        // The lanes' `(sample, k)` pairs, unless the chunk's rays and box need none.
        if !chunk || chunk_rays.is_none() {
            for (l, p) in pairs.iter_mut().enumerate().take(n) {
                *p = pair(j + l);
            }
        }
        j += n;
        let batch = &pairs[..n];
        let (mut rays, film) = match chunk_rays {
            Some(r) => (r, None),
            None => gen_n_film::<L>(set, stored, batch),
        };
        let pbox = match (&frame, film) {
            (None, _) => None,
            // The generator's film box of the lanes.
            (Some(fr), Some((lo, hi))) => PacketBox::new(fr, lo.x, hi.x, lo.y, hi.y),
            (Some(fr), None) => packet_box(fr, set, i0, batch, chunk.then(|| ranges[c])),
        };
        rays_n += clear_invalid(&mut rays, n);
        let c = closest!(&rays, pbox.as_ref(), false);
        // One sample's consecutive subsamples: `pair` maps consecutive `j` to `(sample, j % spp)`
        // (`test_tile_setup`), so a last lane at `k0 + n - 1` of the first lane's sample means
        // no wrap to the next sample in between.
        let run = chunk || batch[n - 1] == (batch[0].0, batch[0].1 + n as u32 - 1);
        // SAFETY: the caller of `test_tile_setup` guarantees exclusive access to these
        // samples' entries.
        unsafe {
            if run && n == MAX_LANES {
                out.run_streamed((i0, k0), &c);
            } else if run {
                out.run((i0, k0), &c, n);
            } else {
                for (l, &p) in batch.iter().enumerate() {
                    out.one(p, c.t[l], c.tri[l]);
                }
            }
        }
    }
    out.fence();
    work.rays = rays_n;
    work
}

/// Gives the invalid lanes of `rays` (`n` lanes in use) `d = 0` (`g . d = 0` is never a
/// hit); returns the number of valid lanes.
#[inline(always)]
fn clear_invalid<L: LaneReduce>(rays: &mut RaysN<L>, n: usize) -> u64 {
    if rays.valid == (1 << n) - 1 {
        return n as u64;
    }
    for l in 0..n {
        if rays.valid >> l & 1 == 0 {
            for a in 0..3 {
                rays.d[a] = L::from_fn(|i| if i == l { 0.0 } else { rays.d[a].get(i) });
            }
        }
    }
    rays.valid.count_ones() as u64
}

/// The camera-space box of a packet's rays (`affine.rs`): its film box is the exact float
/// range of the lanes' `film + offset * footprint` — from `range` (the smallest and largest
/// offset of sample `i0`'s chunk; `x -> film + x * footprint` is monotone for
/// `footprint >= 0`), else lane by lane over `batch`.
#[inline(always)]
fn packet_box(
    fr: &FilmFrame,
    set: &SampleSet,
    i0: u32,
    batch: &[(u32, u32)],
    range: Option<(Vec2, Vec2)>,
) -> Option<PacketBox> {
    let s = &set.samples[i0 as usize];
    let (lo, hi) = if let Some((a, b)) = range
        && s.footprint >= 0.0
    {
        (s.film + a * s.footprint, s.film + b * s.footprint)
    } else {
        let mut lo = Vec2::splat(f32::INFINITY);
        let mut hi = Vec2::splat(f32::NEG_INFINITY);
        for &(i, k) in batch {
            let s = &set.samples[i as usize];
            let f = s.film + set.offsets[k as usize] * s.footprint;
            lo = lo.min(f);
            hi = hi.max(f);
        }
        (lo, hi)
    };
    PacketBox::new(fr, lo.x, hi.x, lo.y, hi.y)
}

/// `unsafe fn $name<const FULL: bool>(...)`: [`run_setup`] with lanes `$lanes` compiled for the
/// target feature `$feature`.
///
/// # Safety (of the generated function)
/// The CPU must support `$feature` (checked by the caller with `is_x86_feature_detected!`).
macro_rules! isa_entry {
    ($(#[$doc:meta])* $name:ident, $feature:literal, $lanes:ty) => {
        $(#[$doc])*
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $feature)]
        #[allow(clippy::too_many_arguments)]
        unsafe fn $name<const FULL: bool>(
            set: &SampleSet,
            stored: Option<&RayBuffer>,
            blocks: &[Tri4],
            tt: &mut TileTris,
            axis: usize,
            sign: f32,
            slack: f32,
            samples: &[u32],
            film: Option<[&[f32]; 3]>,
            lens_k: Option<u32>,
            sweep: bool,
            pair: impl Fn(usize) -> (u32, u32),
            out: Out,
        ) -> SetupWork {
            run_setup::<$lanes, FULL>(
                set, stored, blocks, tt, axis, sign, slack, samples, film, lens_k, sweep, pair, out,
            )
        }
    };
}
isa_entry!(
    /// [`run_setup`] with eight AVX2 lanes ([`Y8`], one register per packet).
    run_setup_avx2,
    "avx2,bmi1,bmi2,lzcnt,popcnt",
    Y8
);
isa_entry!(
    /// [`run_setup`] with sixteen AVX2 lanes ([`Y16`], two registers per packet).
    run_setup_avx2_16,
    "avx2,bmi1,bmi2,lzcnt,popcnt",
    Y16
);
isa_entry!(
    /// [`run_setup`] with sixteen AVX-512 lanes ([`Z16`], one register per packet).
    run_setup_avx512,
    "avx512f,avx512vl,avx512bw,avx512dq,avx2,bmi1,bmi2,lzcnt,popcnt",
    Z16
);

/// Tests every subsample ray of the tile `samples` against the set-up list `tt` (built from
/// `blocks`) and writes the closest hits, packets of 16 rays (`lanes == 16`: one AVX-512
/// register if `isa` is [`Isa::Avx512`], two AVX registers if [`Isa::Avx2`], else four SSE
/// registers), 8 (`lanes == 8` and `isa` at least [`Isa::Avx2`]: one AVX register) or 4. `isa`
/// must be a tier the CPU has ([`Isa::available`]). Every choice gives the same buffer. `affine`: the affine packet test
/// (`Edges`), on the AVX-512 kernel and on the AVX2 16-lane kernel at 1 spp only with
/// `affine_always`. `film`: the samples' film lanes
/// at 1 spp ([`crate::Hierarchy::film`], `[x, y, footprint]` in `samples` order), read by
/// the 1-spp packets instead of a gather through `samples`; `None` gathers. `lens_k`: only
/// subsample `k` of every sample (a thin-lens tile's rays through lens point `k`, which `tt`
/// and `beam` were set up for: `Hierarchy::lens_beams`), else every subsample.
/// `sweep`: the sweep (`sweep.rs`) on tiles of 16-subsample chunks (module docs).
///
/// # Safety
/// As [`crate::cast::intersect::test_tile`]: `prim` and `t` valid for `set.ray_count()` elements,
/// written for these samples by this call only.
#[allow(clippy::too_many_arguments)]
pub unsafe fn test_tile_setup(
    set: &SampleSet,
    stored: Option<&RayBuffer>,
    blocks: &[Tri4],
    samples: &[u32],
    film: Option<[&[f32]; 3]>,
    lens_k: Option<u32>,
    tt: &mut TileTris,
    beam: &Beam,
    scale: f32,
    lanes: usize,
    isa: Isa,
    exactness: SetupExactness,
    affine: bool,
    affine_always: bool,
    sweep: bool,
    prim: *mut u32,
    t: *mut f32,
) -> SetupWork {
    let spp = set.spp as usize;
    debug_assert!(isa <= isa.available(), "{isa:?} not detected");
    let z16 = lanes == 16 && isa == Isa::Avx512;
    // The AVX-512 kernel's per-lane edge test is one register per edge, and the AVX2 16-lane
    // kernel's 1-spp packets (4 x 4-pixel blocks) are rarely decided whole: the affine packet
    // test pays there only when asked for (`CastOptions::affine_always`).
    let y16_spp1 = lanes == 16 && isa == Isa::Avx2 && spp == 1;
    let affine = affine && ((!z16 && !y16_spp1) || affine_always);
    // The sweep (`sweep.rs`) on 16-lane packets of whole chunks; it needs the film frame.
    let sweep = sweep
        && exactness == SetupExactness::Edges
        && lanes == 16
        && lens_k.is_none()
        && stored.is_none()
        && spp.is_multiple_of(16);
    tt.frame = None;
    if (affine || sweep) && exactness == SetupExactness::Edges && !samples.is_empty() {
        let film_x = set.samples[samples[0] as usize].film.x;
        tt.frame = FilmFrame::of(set, tt.origin, film_x);
        if tt.frame.is_some() {
            // Grown only: `refine_run` writes `aff[j]` before any read of it in this tile
            // (every triangle of the lazy set-up is refined before its first test).
            if tt.aff.len() < tt.tris.len() {
                tt.aff.resize(tt.tris.len(), Default::default());
            }
        }
    }
    let slack = 1e-5 * (scale.abs() + 1.0);
    // Power-of-two spp (every preset) without an integer division per ray.
    let (shift, pow2) = (spp.trailing_zeros(), spp.is_power_of_two());
    let pair = |j: usize| {
        if pow2 {
            (samples[j >> shift], (j & (spp - 1)) as u32)
        } else {
            (samples[j / spp], (j % spp) as u32)
        }
    };
    let out = Out { prim, t, spp };
    let (axis, sign) = (beam.axis as usize, beam.sign);
    // `run!(f)` / `run!(f, L)`: `f` (with lane type `L`) for the chosen exactness.
    macro_rules! run {
        ($f:ident $(, $l:ty)?) => {
            match exactness {
                SetupExactness::Edges => {
                    $f::<$($l,)? false>(set, stored, blocks, tt, axis, sign, slack, samples, film, lens_k, sweep, pair, out)
                }
                SetupExactness::Full => {
                    $f::<$($l,)? true>(set, stored, blocks, tt, axis, sign, slack, samples, film, lens_k, sweep, pair, out)
                }
            }
        };
    }
    #[cfg(target_arch = "x86_64")]
    if lanes == 8 && isa >= Isa::Avx2 {
        // SAFETY: the caller's `isa` is available: AVX2 (and the bit instructions) detected.
        return unsafe { run!(run_setup_avx2) };
    }
    #[cfg(target_arch = "x86_64")]
    if z16 {
        // SAFETY: the caller's `isa` is available: the AVX-512 tier detected (`avx512_detected`).
        return unsafe { run!(run_setup_avx512) };
    }
    #[cfg(target_arch = "x86_64")]
    if lanes == 16 && isa == Isa::Avx2 {
        // SAFETY: the caller's `isa` is available: AVX2 (and the bit instructions) detected.
        return unsafe { run!(run_setup_avx2_16) };
    }
    if lanes == 16 {
        return run!(run_setup, V16);
    }
    run!(run_setup, Vec4)
}
