//! The beam-culled ray caster (Hunt et al. 2018, §5.3-5.5): per block, block cull (64 entry
//! points), then per tile, tile cull (leaf list in near-depth order) and sample testing; parallel
//! over blocks with rayon, with per-thread scratch (no allocation in the hot loop once the
//! scratch vectors have grown).
//!
//! HVVR runs the culling on the CPU and sample testing on the GPU; here all three stages run on
//! the CPU threads, block after block.
//!
//! A tile whose rays share an origin (every model but the thin lens) takes the per-tile
//! triangle set-up and its sample test (`setup`); a thin-lens tile at more than one subsample
//! is culled once with its whole beam, then set up and tested once per lens point, on the rays
//! that start there (`Hierarchy::lens_beams`); other tiles (or [`SampleTest::Watertight`]) take
//! the watertight kernel over the tile's leaves.

pub mod intersect;
pub mod isa;
pub mod lanes16;
pub(crate) mod lanes256;
pub(crate) mod lanes512;
pub mod leaves;
pub mod packet;
pub(crate) mod packet_kernel;
pub mod setup;
pub mod stored;

use std::time::{Duration, Instant};

use crate::beam::{BLOCK_ENTRIES, CullScratch, SimdBeam, block_cull, tile_cull};
use crate::beam::{Beam, PreparedBeam};
use parallax_bvh::Bvh;
use rayon::prelude::*;

use crate::cast::intersect::test_tile;
pub use crate::cast::isa::Isa;
use crate::cast::leaves::{LeafBox, LeafGroup, group_leaves};
use crate::cast::setup::{
    SampleTest, SetupCounts, SetupExactness, SetupWork, TileTris, setup_tile_with, shared_origin,
    test_tile_setup,
};
use crate::cast::stored::RayBuffer;
use crate::{Hierarchy, SampleSet, VisibilityBuffer};

/// Per-stage times (summed over threads: CPU time, not wall time) and work counts of a cast.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CastStats {
    pub block_cull: Duration,
    pub tile_cull: Duration,
    pub sample_test: Duration,
    /// Wall time of the whole cast.
    pub wall: Duration,
    pub blocks: u64,
    pub tiles: u64,
    /// Entry points handed from block cull to tile cull (summed over blocks).
    pub entry_points: u64,
    /// Leaves in the tiles' lists (summed over tiles).
    pub tile_leaves: u64,
    /// Four-leaf-box slab tests of the sample stage.
    pub group_tests: u64,
    /// Leaf (4-triangle block) tests of the sample stage.
    pub leaf_tests: u64,
    /// Valid subsample rays cast.
    pub rays: u64,
    /// Tiles run through the set-up kernel ([`SampleTest::TileSetup`], shared origin).
    pub setup_tiles: u64,
    /// Packet-triangle tests of the set-up kernel (one per packet and set-up triangle reached).
    pub tri_tests: u64,
    /// Corner classification of the set-up tiles' triangles (§5.5): dropped (all-out or
    /// edge-on), partial, all-in.
    pub tris_all_out: u64,
    pub tris_partial: u64,
    pub tris_all_in: u64,
    /// Entries of the set-up tiles' lists dropped as repeats of a triangle kept earlier in the
    /// list (a triangle the SBVH put in several leaves; `cast/setup/rows.rs`).
    pub tris_repeated: u64,
    /// Ray-triangle tests of the set-up kernel (valid rays of its packet-triangle tests).
    pub setup_pair_tests: u64,
    /// Watertight tests the set-up kernel ran inside its uncertainty band (edge value within
    /// the bound, or `1/t` within the depth band of the best so far), per ray and triangle.
    pub setup_exact_tests: u64,
    /// Watertight tests of the set-up kernel's winners (one per hit ray whose winner was not
    /// already decided exactly), for their bit-exact `t`.
    pub setup_final_tests: u64,
    /// Rays re-decided by an exact scan of the tile's list because the watertight test
    /// contradicted a certain decision (a bound violation; expected 0).
    pub setup_rescues: u64,
    /// Of `setup_exact_tests`: those for an edge value within the band (the rest are depth
    /// comparisons within the depth band, including the best's own watertight `t`).
    pub setup_edge_band: u64,
    /// Packet-triangle tests decided for the whole packet by the affine packet test
    /// (`cast/setup/affine.rs`): every ray certainly outside / certainly inside.
    pub setup_packet_out: u64,
    pub setup_packet_in: u64,
    /// Set-up tiles swept (`cast/setup/sweep.rs`: [`CastOptions::sweep`]) instead of walked.
    pub setup_swept_tiles: u64,
}

/// The caster's sample-test choice: the kernel and the SIMD width of its ray packets (`4` SSE,
/// `8` AVX2 when detected (else 4), `16` in the widest lanes `isa` allows and the CPU has —
/// one AVX-512 register, two AVX registers or four SSE registers — set-up kernel only, the
/// watertight kernel treats it as `4`; `1` one ray at a time — watertight kernel only; the
/// set-up kernel treats `1` as `4`). Every width and tier gives the same buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CastOptions {
    pub test: SampleTest,
    pub lanes: usize,
    /// How exactly the set-up kernel reproduces per-ray traversal (ignored by the watertight
    /// kernel, which is always exact).
    pub exactness: SetupExactness,
    /// The widest instruction-set tier of the set-up kernel's 16-lane packets and of the
    /// per-tile triangle set-up ([`Isa`], `cast/isa.rs`): the widest the CPU has at or below it
    /// runs ([`Isa::available`]); [`Isa::Sse`] selects the portable twin (four SSE registers,
    /// 4-lane set-up). Every tier gives the same buffer bit for bit.
    pub isa: Isa,
    /// Run the affine packet test (`cast/setup/affine.rs`) before the per-lane edge test of
    /// the set-up kernel with [`SetupExactness::Edges`] (pinhole and stereo tiles): the same
    /// buffer bit for bit, fewer instructions — on the SSE, AVX2 and 16-lane twin kernels; the
    /// AVX-512 kernel, and the AVX2 16-lane kernel at 1 spp, take it only with `affine_always`.
    pub affine: bool,
    /// Run the affine packet test (with `affine`) on the AVX-512 kernel and on the AVX2 16-lane
    /// kernel at 1 spp too. Off by default: on AVX-512 a packet's per-lane edge test is one
    /// register per edge, and at 1 spp an AVX2 packet is a 4 x 4-pixel block that the packet
    /// test rarely decides whole: there it costs more than it saves (`docs/notes/vr.md`); the
    /// buffer is the same.
    pub affine_always: bool,
    /// Sweep each tile's set-up triangles over all its packets (`cast/setup/sweep.rs`) instead
    /// of walking the tile's runs once per packet, where a tile's packets are whole 16-subsample
    /// chunks of pinhole or stereo samples ([`SetupExactness::Edges`]): the same buffer bit for
    /// bit.
    pub sweep: bool,
}

impl Default for CastOptions {
    /// The set-up kernel on 16-lane packets (one pixel at 16 spp; 1.3-1.9x the 4-lane
    /// kernel's speed on Sponza, AVX-512 a further ~1.3x, `docs/notes/vr.md`; the 8-lane AVX2
    /// build is slower).
    fn default() -> Self {
        CastOptions {
            test: SampleTest::TileSetup,
            lanes: 16,
            exactness: SetupExactness::Edges,
            isa: Isa::Avx512,
            affine: true,
            affine_always: false,
            sweep: true,
        }
    }
}

/// Shared output pointers (each sample is written by exactly one tile).
#[derive(Clone, Copy)]
struct OutPtr {
    prim: *mut u32,
    t: *mut f32,
}
// SAFETY: the hierarchy's `order` is a permutation (checked in `cast`), so tiles write disjoint
// entries.
unsafe impl Send for OutPtr {}
unsafe impl Sync for OutPtr {}

/// The magnitude bound of the beam tests' rounding slack: the scene's and the camera's
/// coordinates.
fn scene_scale(bvh: &Bvh, h: &Hierarchy) -> f32 {
    let b = bvh.bounds();
    let mut m = if b.is_empty() {
        0.0
    } else {
        b.min.abs().max(b.max.abs()).max_element()
    };
    for blk in &h.blocks {
        if !blk.beam.everything && !blk.beam.origin.is_empty() {
            let o = blk.beam.origin;
            m = m.max(o.min.abs().max(o.max.abs()).max_element());
        }
    }
    m
}

/// Casts every subsample ray of `set` (tiles and blocks of `hierarchy`, built for `set`) and
/// writes the closest hits to `out` with the default [`CastOptions`]: for each subsample the
/// closest triangle of [`crate::trace_per_ray`] up to depth ties within float tolerance, and
/// its `t` within ~1e-5 relative (the set-up kernel with [`SetupExactness::Edges`], module
/// docs of `cast/setup/mod.rs`; [`SetupExactness::Full`] is bit-identical). Panics if `hierarchy`
/// or `out` was made for another set, or `hierarchy` for another camera pose (a
/// programming error).
pub fn cast(
    bvh: &Bvh,
    set: &SampleSet,
    hierarchy: &Hierarchy,
    out: &mut VisibilityBuffer,
) -> CastStats {
    cast_opts(bvh, set, hierarchy, out, CastOptions::default())
}

/// [`cast`] with the exact watertight sample test ([`SampleTest::Watertight`]: the same triangle
/// and `t`, bit for bit, as [`crate::trace_per_ray`], module docs of `cast/intersect.rs`) and the
/// choice of its kernel: `lanes = 4` tests four rays at a time on
/// SSE (`packet.rs`), `8` eight rays at a time on AVX2 (four without AVX2), `1` one
/// ray at a time against groups of four leaf boxes (`intersect.rs`); all give the same buffer.
/// The 8-lane kernel is slower than the 4-lane one (`docs/notes/vr.md`).
pub fn cast_with(
    bvh: &Bvh,
    set: &SampleSet,
    hierarchy: &Hierarchy,
    out: &mut VisibilityBuffer,
    lanes: usize,
) -> CastStats {
    cast_opts(
        bvh,
        set,
        hierarchy,
        out,
        CastOptions {
            test: SampleTest::Watertight,
            lanes,
            exactness: SetupExactness::Full,
            isa: Isa::Avx512,
            affine: false,
            affine_always: false,
            sweep: true,
        },
    )
}

/// [`cast`] with explicit [`CastOptions`].
pub fn cast_opts(
    bvh: &Bvh,
    set: &SampleSet,
    hierarchy: &Hierarchy,
    out: &mut VisibilityBuffer,
    opts: CastOptions,
) -> CastStats {
    cast_from(bvh, set, None, hierarchy, out, opts)
}

/// [`cast_opts`] reading the subsample rays from `stored` (made from `set`: HVVR Table 3's
/// high-resolution ray buffer, `cast/stored.rs`) instead of generating them: the same buffer.
/// Panics if `stored` holds another number of rays (a programming error).
pub fn cast_stored(
    bvh: &Bvh,
    set: &SampleSet,
    stored: &RayBuffer,
    hierarchy: &Hierarchy,
    out: &mut VisibilityBuffer,
    opts: CastOptions,
) -> CastStats {
    assert_eq!(
        stored.rays.len(),
        set.ray_count(),
        "ray buffer of another set"
    );
    cast_from(bvh, set, Some(stored), hierarchy, out, opts)
}

fn cast_from(
    bvh: &Bvh,
    set: &SampleSet,
    stored: Option<&RayBuffer>,
    hierarchy: &Hierarchy,
    out: &mut VisibilityBuffer,
    opts: CastOptions,
) -> CastStats {
    let lanes = opts.lanes;
    // The tier that runs (one detection per cast).
    let isa = opts.isa.available();
    let wall = Instant::now();
    assert!(
        hierarchy.sample_count == set.samples.len()
            && hierarchy.spp == set.spp
            && hierarchy.order.len() == set.samples.len(),
        "hierarchy built for another sample set"
    );
    assert!(
        hierarchy.camera == set.camera,
        "hierarchy built for another camera or pose (`Hierarchy::repose` moves it)"
    );
    assert!(
        out.prim.len() == set.ray_count() && out.t.len() == set.ray_count() && out.spp == set.spp,
        "visibility buffer made for another sample set"
    );
    // No clearing pass over the buffer (at 16 spp and 2160 x 1200 it is 330 MB of writes):
    // every sample lies in exactly one tile (`order` is a permutation), and every tile writes
    // all of its samples' entries, empty tiles and blocks included (`clear_samples`).
    let scale = scene_scale(bvh, hierarchy);
    let ptr = OutPtr {
        prim: out.prim.as_mut_ptr(),
        t: out.t.as_mut_ptr(),
    };
    let blocks_ = bvh.blocks();
    // The lanes whose triangle sits in several leaves (the SBVH's split triangles).
    let copies = bvh.block_copies();
    let tally = hierarchy.blocks.par_iter().map_init(
        || {
            (
                CullScratch::default(),
                Vec::<LeafGroup>::new(),
                Vec::<LeafBox>::new(),
                TileTris::default(),
            )
        },
        |(scratch, groups, boxes, tt), block| {
            // Capture the whole (Send) struct, not its raw-pointer fields.
            #[allow(clippy::redundant_locals)]
            let ptr = ptr;
            let mut tally = Tally::default();
            if block.rays == 0 {
                let tiles = &hierarchy.tiles
                    [block.first_tile as usize..(block.first_tile + block.tile_count) as usize];
                for tile in tiles {
                    // SAFETY: as below (this tile's entries only).
                    unsafe { clear_samples(hierarchy, tile, set.spp as usize, ptr) };
                }
                return tally;
            }
            let t0 = Instant::now();
            let bb = PreparedBeam::new(&block.beam, scale);
            block_cull(bvh, &SimdBeam::new(&bb), BLOCK_ENTRIES, scratch);
            let entries = std::mem::take(&mut scratch.entries);
            let t1 = Instant::now();
            tally.block_ns = (t1 - t0).as_nanos() as u64;
            tally.entry_points = entries.len() as u64;
            tt.counts = Default::default();
            let tiles = &hierarchy.tiles
                [block.first_tile as usize..(block.first_tile + block.tile_count) as usize];
            for (ti, tile) in tiles.iter().enumerate() {
                if tile.rays == 0 {
                    // SAFETY: as below (this tile's entries only).
                    unsafe { clear_samples(hierarchy, tile, set.spp as usize, ptr) };
                    continue;
                }
                let a = Instant::now();
                let tb = PreparedBeam::new(&tile.beam, scale);
                tile_cull(bvh, &SimdBeam::new(&tb), &entries, scratch);
                let range = tile.start as usize..(tile.start + tile.len) as usize;
                let samples = &hierarchy.order[range.clone()];
                // The ray bundles of the tile that share an origin: the tile itself, or (a thin
                // lens) its rays through each lens point (`Hierarchy::lens_beams`), each set up
                // and tested as a pinhole tile; none: the watertight kernel.
                let origin = match opts.test {
                    SampleTest::TileSetup => shared_origin(&tile.beam),
                    SampleTest::Watertight => None,
                };
                let lens = match opts.test {
                    SampleTest::TileSetup if origin.is_none() => {
                        lens_bundles(hierarchy, block.first_tile as usize + ti)
                    }
                    _ => None,
                };
                let bundles = if origin.is_some() {
                    1
                } else {
                    lens.map_or(0, <[Beam]>::len)
                };
                if bundles > 0 {
                    let lazy = opts.exactness == SetupExactness::Edges;
                    // The 1-spp film lanes of these samples (`Hierarchy::film`).
                    let film = (hierarchy.film[0].len() == set.samples.len())
                        .then(|| hierarchy.film.each_ref().map(|v| &v[range.clone()]));
                    let mut mark = a;
                    for q in 0..bundles {
                        let (beam, o, lens_k) = match (origin, lens) {
                            (Some(o), _) => (&tile.beam, o, None),
                            (None, Some(lb)) => (&lb[q], lb[q].origin.min, Some(q as u32)),
                            (None, None) => unreachable!("bundles == 0"),
                        };
                        // The set-up's lanes follow the kernel's tier: the same list either way.
                        setup_tile_with(isa, blocks_, copies, &scratch.leaves, beam, o, lazy, tt);
                        let b = Instant::now();
                        // SAFETY: as below.
                        let w = unsafe {
                            test_tile_setup(
                                set,
                                stored,
                                blocks_,
                                samples,
                                film,
                                lens_k,
                                tt,
                                beam,
                                scale,
                                lanes,
                                isa,
                                opts.exactness,
                                opts.affine,
                                opts.affine_always,
                                opts.sweep,
                                ptr.prim,
                                ptr.t,
                            )
                        };
                        let c = Instant::now();
                        tally.tile_ns += (b - mark).as_nanos() as u64;
                        tally.test_ns += (c - b).as_nanos() as u64;
                        mark = c;
                        tally.rays += w.rays;
                        tally.setup.add(&w);
                        tally.setup_tiles += 1;
                    }
                    tally.tile_leaves += scratch.leaves.len() as u64;
                    continue;
                }
                group_leaves(bvh, &scratch.leaves, groups, boxes);
                let b = Instant::now();
                // SAFETY: `order` is a permutation of the samples (built by `Hierarchy::build`,
                // sizes checked above), so this tile's entries are written by no other tile.
                let w = unsafe {
                    test_tile(
                        set, blocks_, samples, groups, boxes, &tb, scale, lanes, ptr.prim, ptr.t,
                    )
                };
                let c = Instant::now();
                tally.tile_ns += (b - a).as_nanos() as u64;
                tally.test_ns += (c - b).as_nanos() as u64;
                tally.tile_leaves += scratch.leaves.len() as u64;
                tally.leaf_tests += w.leaf_tests;
                tally.group_tests += w.group_tests;
                tally.rays += w.rays;
            }
            scratch.entries = entries;
            tally.tiles = tiles.len() as u64;
            tally.corners = tt.counts;
            tally
        },
    );
    let t = tally.reduce(Tally::default, Tally::sum);
    CastStats {
        block_cull: Duration::from_nanos(t.block_ns),
        tile_cull: Duration::from_nanos(t.tile_ns),
        sample_test: Duration::from_nanos(t.test_ns),
        wall: wall.elapsed(),
        blocks: hierarchy.blocks.len() as u64,
        tiles: t.tiles,
        entry_points: t.entry_points,
        tile_leaves: t.tile_leaves,
        leaf_tests: t.leaf_tests,
        group_tests: t.group_tests,
        rays: t.rays,
        setup_tiles: t.setup_tiles,
        tri_tests: t.setup.tri_tests,
        tris_all_out: t.corners.all_out,
        tris_partial: t.corners.partial,
        tris_all_in: t.corners.all_in,
        tris_repeated: t.corners.repeated,
        setup_pair_tests: t.setup.pair_tests,
        setup_exact_tests: t.setup.exact_tests,
        setup_final_tests: t.setup.final_tests,
        setup_rescues: t.setup.rescues,
        setup_edge_band: t.setup.edge_band,
        setup_swept_tiles: t.setup.swept,
        setup_packet_out: t.setup.packet_out,
        setup_packet_in: t.setup.packet_in,
    }
}

/// The lens beams of tile `ti` ([`Hierarchy::lens_beams`]) when every one has a single origin
/// (the lens point) for the set-up kernel; `None` otherwise (no lens beams, or a bundle no axis
/// bounds).
fn lens_bundles(h: &Hierarchy, ti: usize) -> Option<&[Beam]> {
    let spp = h.spp as usize;
    let lb = h.lens_beams.get(ti * spp..(ti + 1) * spp)?;
    lb.iter().all(|b| shared_origin(b).is_some()).then_some(lb)
}

/// Writes "no hit" to every subsample entry of `tile`'s samples (a tile without rays).
///
/// # Safety
/// `ptr` points to buffers of `sample_count * spp` entries that no other thread writes for
/// this tile's samples (`order` is a permutation, checked by the caller).
unsafe fn clear_samples(h: &Hierarchy, tile: &crate::Tile, spp: usize, ptr: OutPtr) {
    for &i in &h.order[tile.start as usize..(tile.start + tile.len) as usize] {
        for k in 0..spp {
            let o = i as usize * spp + k;
            // SAFETY: the caller's.
            unsafe {
                *ptr.prim.add(o) = parallax_core::NO_ID;
                *ptr.t.add(o) = f32::INFINITY;
            }
        }
    }
}

/// One block's counters in [`cast_opts`], summed over blocks (rayon map / reduce).
#[derive(Clone, Copy, Default)]
struct Tally {
    block_ns: u64,
    tile_ns: u64,
    test_ns: u64,
    tiles: u64,
    entry_points: u64,
    tile_leaves: u64,
    leaf_tests: u64,
    group_tests: u64,
    rays: u64,
    setup_tiles: u64,
    setup: SetupWork,
    corners: SetupCounts,
}

impl Tally {
    fn sum(mut self, o: Self) -> Self {
        self.block_ns += o.block_ns;
        self.tile_ns += o.tile_ns;
        self.test_ns += o.test_ns;
        self.tiles += o.tiles;
        self.entry_points += o.entry_points;
        self.tile_leaves += o.tile_leaves;
        self.leaf_tests += o.leaf_tests;
        self.group_tests += o.group_tests;
        self.rays += o.rays;
        self.setup_tiles += o.setup_tiles;
        self.setup.add(&o.setup);
        self.corners.all_out += o.corners.all_out;
        self.corners.partial += o.corners.partial;
        self.corners.all_in += o.corners.all_in;
        self.corners.repeated += o.corners.repeated;
        self
    }
}
