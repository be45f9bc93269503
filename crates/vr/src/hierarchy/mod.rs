//! The two-level sample hierarchy of HVVR (Hunt et al. 2018, §5, Fig. 4): samples grouped into
//! tiles of at most [`tile_samples`] samples (HVVR's [`TILE_SAMPLES`] = 128 from 8 spp up,
//! more at lower spp), tiles into blocks of at most
//! [`BLOCK_TILES`] = 64 tiles, each with a bounding beam over *every* subsample ray of its
//! samples (all `spp` footprint offsets and lens positions).
//!
//! **Grouping** (§5: "a top-down divisive algorithm", used by HVVR for foveated sets; we use it
//! for every set so that irregular sets work like grids): samples are first separated by colour
//! channel (§5: per-channel grids are "tiled and blocked separately") and by view (stereo eye,
//! cube face: a beam never spans two centres of projection). Each group is split recursively at
//! the median film position along x when the x extent is at least twice the y extent, else
//! along y, into blocks of at most 128 x 64 = 8192 samples, and each block likewise into tiles of
//! at most [`tile_samples`] samples; on a grid at 8 spp and more this gives 16 x 8 pixel tiles
//! and 128 x 64 pixel blocks (HVVR's sizes) wherever the film divides evenly (32 x 32 pixel
//! tiles at 1 spp).
//!
//! **Beams** ([`crate::beam::BeamBuilder`]): the dominant-axis beam of the tile's actual
//! subsample rays (generated once here, exactly as the caster generates them), so a beam holds
//! every ray the caster casts — a superset of HVVR's "entire footprint" bound only where it
//! matters. A block's beam bounds the union of its tiles' rays. A tile or block that no axis
//! bounds (directions over more than a hemisphere, e.g. a 210-degree fisheye block at the rim)
//! is split in two and retried; a single sample that cannot be bounded gets the safe
//! [`Beam::EVERYTHING`].
//!
//! **Lens beams** (thin lens, more than one subsample: [`Hierarchy::lens_beams`]). A tile's rays
//! start anywhere on the lens disc, so its beam has no single origin and the per-tile triangle
//! set-up (`cast/setup`) cannot use it. But the lens sample of subsample `k` is the same for
//! every sample (`SampleSet::lens`), so the tile's rays with lens sample `k` all start at one
//! point: per tile and `k` the beam of those rays alone, and the caster sets the tile up once
//! per lens point. Such tiles hold [`TILE_RAYS`] samples ([`tile_samples_of`]), so that each
//! of the `spp` set-ups serves as many rays as a 1-spp tile's. (HVVR §5 widens the tile beams
//! "to accommodate the distribution of ray origins" and tests every subsample on the GPU; its
//! Table 5 puts the thin-lens intersect at 2.8x the pinhole eyes' at 0.5 m focus.)

mod distorted_rect;
mod pose;

pub use pose::Rect;

use crate::beam::{Beam, BeamBuilder, LaneBeamBuilder};
use crate::cast::lanes16::V16;
#[cfg(target_arch = "x86_64")]
use crate::cast::lanes512::Z16;
use crate::cast::packet::{gen_n_film, sample_chunk_lens};
use parallax_core::Aabb;
use parallax_core::simd::Lanes;
use parallax_scene::camera::Camera;
use rayon::prelude::*;

use crate::SampleSet;

/// Most samples per tile (HVVR: 16 x 8 pixels).
pub const TILE_SAMPLES: usize = 128;
/// Most tiles per block (HVVR: 8 x 8 tiles).
pub const BLOCK_TILES: usize = 64;

/// Most samples per tile at `spp` subsamples: tiles of about [`TILE_RAYS`] rays, at least
/// [`TILE_SAMPLES`] (HVVR's 128) samples: 1024 samples at 1 spp, 512 at 2, 256 at 4, 128 from
/// 8 spp up. At low spp HVVR's 128-sample tiles leave the per-tile triangle set-up and tile
/// cull to few rays (measured at 1 spp: 128-sample tiles 812 instructions per ray, 1024-sample
/// tiles 497, `docs/notes/vr.md`). Blocks keep at most `TILE_SAMPLES * BLOCK_TILES` samples.
pub fn tile_samples(spp: u32) -> usize {
    (TILE_RAYS / spp.max(1) as usize).max(TILE_SAMPLES)
}

/// Subsample rays per tile of the pinhole and stereo sets from 16 spp ([`tile_samples_of`]).
pub const SWEEP_TILE_RAYS: usize = 4096;

/// Most samples per tile of `set`: [`tile_samples`], except for a thin lens at more than one
/// subsample, whose tiles are cast one lens point at a time ([`Hierarchy::lens_beams`]): there
/// [`TILE_RAYS`] samples, so that each of a tile's per-lens-point set-ups serves as many rays
/// as a 1-spp tile's (measured in `docs/notes/vr.md`). Pinhole and stereo sets from 16 spp,
/// whose tiles the caster sweeps
/// (`cast/setup/sweep.rs`), hold [`SWEEP_TILE_RAYS`] rays (256 samples at 16 spp, 128 at 32):
/// the sweep's cost per packet stays at 256 packets per tile while the per-tile set-up's
/// share halves; at 512 packets its sample test doubles (`docs/notes/vr.md`).
pub fn tile_samples_of(set: &SampleSet) -> usize {
    let swept = matches!(set.camera, Camera::Pinhole(_) | Camera::Stereo(_));
    if lens_bundles(set) {
        TILE_RAYS
    } else if swept && set.spp >= 16 {
        (SWEEP_TILE_RAYS / set.spp as usize).max(1)
    } else {
        tile_samples(set.spp)
    }
}

/// Whether `set`'s tiles are cast one lens sample at a time (a thin lens, more than one
/// subsample: the rays of one lens sample share the lens point as their origin).
fn lens_bundles(set: &SampleSet) -> bool {
    matches!(set.camera, Camera::ThinLens(_)) && set.spp > 1
}

/// Subsample rays per tile aimed at by [`tile_samples`].
pub const TILE_RAYS: usize = 1024;

/// Why a hierarchy could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum HierarchyError {
    #[error("sample set has {0} samples; the hierarchy indexes at most 2^31")]
    TooManySamples(usize),
    #[error("sample set has spp {spp} but {offsets} offsets and {lens} lens samples")]
    BadTables {
        spp: u32,
        offsets: usize,
        lens: usize,
    },
    #[error("sample {index} has a non-finite film position or footprint")]
    BadSample { index: usize },
    #[error(
        "hierarchy built for {built} samples at spp {built_spp}, moved to a set of {samples} \
         samples at spp {spp}: build a new one for another sample set"
    )]
    OtherSet {
        built: usize,
        built_spp: u32,
        samples: usize,
        spp: u32,
    },
}

/// A tile: `len` samples `order[start..start + len]`, `rays` valid subsample rays among them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tile {
    pub start: u32,
    pub len: u32,
    pub rays: u32,
    pub beam: Beam,
}

/// A block: tiles `first_tile..first_tile + tile_count`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Block {
    pub first_tile: u32,
    pub tile_count: u32,
    pub rays: u32,
    pub beam: Beam,
}

/// Tiles and blocks of a [`SampleSet`] (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Hierarchy {
    /// A permutation of the sample indices, tile after tile.
    pub order: Vec<u32>,
    pub tiles: Vec<Tile>,
    pub blocks: Vec<Block>,
    /// The set it was built for: sample count and spp (checked by the caster).
    pub sample_count: usize,
    pub spp: u32,
    /// At one subsample per sample: every sample's film position and footprint in `order`
    /// (`film[0][p]`, `film[1][p]`, `film[2][p]` = x, y, footprint of sample `order[p]`), so
    /// that the caster's 1-spp packets (sixteen consecutive samples of a tile) load their
    /// film lanes contiguously instead of gathering them through `order`; empty at other spp.
    pub film: [Vec<f32>; 3],
    /// For a thin lens at more than one subsample: per tile and lens sample (`tile * spp +
    /// k`) the beam of the tile's rays with lens sample `k` alone. They share one origin, the
    /// lens point, so the caster sets the tile's triangles up once per lens sample and tests
    /// each such ray bundle as a pinhole tile (`cast/mod.rs`); [`Beam::EVERYTHING`] where no
    /// axis bounds the bundle. Empty for every other set.
    pub lens_beams: Vec<Beam>,
    /// The camera (with its pose) the beams are for: the caster refuses another
    /// ([`Hierarchy::repose`] moves them).
    pub camera: Camera,
    /// For the models `Hierarchy::repose` moves (pinhole, stereo rig, distorted eye, fisheye,
    /// thin lens): the pose-free camera-space rectangle of every tile's rays, then of every
    /// block's, then for a thin lens of every tile's per lens sample (`hierarchy/pose.rs`).
    /// Computed on the first move; empty until then and for other models.
    pub rects: Vec<Rect>,
}

/// The pose-free rectangles of a [`pose::movable`] camera's set (`hierarchy/pose.rs`): every
/// tile's, then every block's, then for a thin lens cast one lens sample at a time every
/// tile's per lens sample ([`Hierarchy::rects`]).
fn pose_rects(set: &SampleSet, order: &[u32], tiles: &[Tile], blocks: &[Block]) -> Vec<Rect> {
    let tile_rects: Vec<Rect> = tiles
        .par_iter()
        .map(|t| {
            let idx = &order[t.start as usize..(t.start + t.len) as usize];
            // (Never `None`: called for a movable camera only.)
            pose::rect_of(set, idx).expect("a movable camera's rectangle")
        })
        .collect();
    let from_rays = pose::block_rect_from_rays(&set.camera);
    let block_rects: Vec<Rect> = blocks
        .par_iter()
        .map(|b| {
            let ts = &tiles[b.first_tile as usize..][..b.tile_count as usize];
            if from_rays {
                // A block's tiles are consecutive in `order`.
                let (first, last) = (&ts[0], &ts[ts.len() - 1]);
                let idx = &order[first.start as usize..(last.start + last.len) as usize];
                return pose::rect_of(set, idx).expect("a movable camera's rectangle");
            }
            let t = &tile_rects[b.first_tile as usize..][..b.tile_count as usize];
            t.iter().skip(1).fold(t[0], |a, r| a.union(*r))
        })
        .collect();
    // A thin lens cast one lens sample at a time: per tile and lens sample the
    // rectangle of those rays alone (the lens beams').
    let lens_rects: Vec<Rect> = match &set.camera {
        Camera::ThinLens(c) if lens_bundles(set) => tiles
            .par_iter()
            .flat_map_iter(|t| {
                let idx = &order[t.start as usize..(t.start + t.len) as usize];
                (0..set.spp as usize).map(move |k| pose::lens_rect(set, c, idx, k..k + 1))
            })
            .collect(),
        _ => Vec::new(),
    };
    [tile_rects, block_rects, lens_rects].concat()
}

/// The view (stereo eye, cube face) a film position belongs to.
fn view_of(camera: &Camera, x: f32) -> u32 {
    match camera {
        Camera::Stereo(r) => (x >= r.eye_width() as f32) as u32,
        Camera::Cube(c) => ((x / c.face_size() as f32).floor().max(0.0) as u32).min(5),
        _ => 0,
    }
}

/// Splits `idx` at its median along the wider film axis (x if `ext_x >= 2 ext_y`); returns the
/// split point.
fn median_split(set: &SampleSet, idx: &mut [u32]) -> usize {
    let (mut lo, mut hi) = (glam::Vec2::INFINITY, glam::Vec2::NEG_INFINITY);
    for &i in idx.iter() {
        let f = set.samples[i as usize].film;
        lo = lo.min(f);
        hi = hi.max(f);
    }
    let e = hi - lo;
    let axis = if e.x >= 2.0 * e.y { 0 } else { 1 };
    let mid = idx.len() / 2;
    // The order `(film[axis], film[other])` by `total_cmp`, then the index, as one integer key
    // per sample: the selection compares keys in one array instead of film positions gathered
    // through `idx`. The two halves are the same sets either way (the order is total).
    let mut keyed: Vec<(u64, u32)> = idx
        .iter()
        .map(|&i| {
            let f = set.samples[i as usize].film;
            let key = (total_order_key(f[axis]) as u64) << 32 | total_order_key(f[1 - axis]) as u64;
            (key, i)
        })
        .collect();
    keyed.select_nth_unstable(mid);
    for (d, &(_, i)) in idx.iter_mut().zip(&keyed) {
        *d = i;
    }
    mid
}

/// An unsigned key whose order is `f32::total_cmp`'s.
fn total_order_key(x: f32) -> u32 {
    let b = x.to_bits();
    if b >> 31 == 1 { !b } else { b | 1 << 31 }
}

/// Morton (Z-order) code of the pixel containing a film position (16 bits per axis).
fn morton(f: glam::Vec2) -> u32 {
    let spread = |v: f32| {
        let mut x = (v.max(0.0) as u32) & 0xFFFF;
        x = (x | (x << 8)) & 0x00FF_00FF;
        x = (x | (x << 4)) & 0x0F0F_0F0F;
        x = (x | (x << 2)) & 0x3333_3333;
        (x | (x << 1)) & 0x5555_5555
    };
    spread(f.x) | (spread(f.y) << 1)
}

/// The beam accumulator of the subsample rays of `idx`, and for a set cast one lens sample at
/// a time ([`lens_bundles`]) the beams of each lens sample's rays ([`Hierarchy::lens_beams`];
/// the accumulator is then their union). Every ray is generated once, sixteen at a time by the
/// caster's own generator (`cast/packet.rs`: the rays it casts, bit for bit), and accumulated
/// in lanes ([`LaneBeamBuilder`]).
fn rays_of(set: &SampleSet, idx: &[u32]) -> (BeamBuilder, Vec<Beam>) {
    #[cfg(target_arch = "x86_64")]
    if crate::cast::isa::avx512_detected() {
        // SAFETY: the AVX-512 tier detected.
        return unsafe { rays_of_avx512(set, idx) };
    }
    rays_of_lanes::<V16>(set, idx)
}

/// [`rays_of`] in sixteen AVX-512 lanes ([`Z16`]: one register per value; the same bits as the
/// portable [`V16`], which runs four SSE registers).
///
/// # Safety
/// The CPU must have the AVX-512 tier (`crate::cast::isa::avx512_detected`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512bw,avx512dq,avx2,bmi1,bmi2,lzcnt,popcnt")]
unsafe fn rays_of_avx512(set: &SampleSet, idx: &[u32]) -> (BeamBuilder, Vec<Beam>) {
    rays_of_lanes::<Z16>(set, idx)
}

/// [`rays_of`] with the lanes `L` (sixteen of them).
#[inline(always)]
fn rays_of_lanes<L: Lanes>(set: &SampleSet, idx: &[u32]) -> (BeamBuilder, Vec<Beam>) {
    debug_assert_eq!(L::N, 16);
    let spp = set.spp as usize;
    let mut pairs = [(0u32, 0u32); 16];
    if !lens_bundles(set) {
        // `(sample, k)` in order, sixteen at a time (one sample's subsamples from 16 spp up).
        let mut acc = LaneBeamBuilder::<L>::default();
        let total = idx.len() * spp;
        // A lens-distorted or fisheye camera's one-sample packets by `sample_chunk_lens` (the
        // kernel's own one-sample path for them).
        let lens_chunks = spp.is_multiple_of(16)
            && matches!(set.camera, Camera::Distorted(_) | Camera::Fisheye(_));
        let mut j = 0;
        while j < total {
            let n = (total - j).min(16);
            if lens_chunks {
                let (i, k0) = (idx[j / spp], j % spp);
                let o = &set.offsets[k0..k0 + 16];
                let (ox, oy) = (L::from_fn(|l| o[l].x), L::from_fn(|l| o[l].y));
                if let Some(r) = sample_chunk_lens::<L>(set, i, ox, oy) {
                    acc.add(r.o, r.d, r.valid);
                    j += n;
                    continue;
                }
            }
            for (l, p) in pairs[..n].iter_mut().enumerate() {
                *p = (idx[(j + l) / spp], ((j + l) % spp) as u32);
            }
            let (r, _) = gen_n_film::<L>(set, None, &pairs[..n]);
            acc.add(r.o, r.d, r.valid & ((1u32 << n) - 1));
            j += n;
        }
        return (acc.fold(), Vec::new());
    }
    let mut all = BeamBuilder::new();
    let mut beams = Vec::with_capacity(spp);
    for k in 0..spp as u32 {
        let mut acc = LaneBeamBuilder::<L>::default();
        for chunk in idx.chunks(16) {
            for (p, &i) in pairs.iter_mut().zip(chunk) {
                *p = (i, k);
            }
            let n = chunk.len();
            let (r, _) = gen_n_film::<L>(set, None, &pairs[..n]);
            acc.add(r.o, r.d, r.valid & ((1u32 << n) - 1));
        }
        let b = acc.fold();
        all.merge(&b);
        beams.push(b.finish().unwrap_or(Beam::EVERYTHING));
    }
    (all, beams)
}

/// A tile, its rays' accumulator and its lens beams (`rays_of`).
type TileOut = (Tile, BeamBuilder, Vec<Beam>);

/// A block and its tiles with their lens beams.
type BlockOut = (Vec<(Tile, Vec<Beam>)>, Block);

/// Tiles of one block's samples (`idx`, at offset `base` of the order array).
fn build_tiles(set: &SampleSet, idx: &mut [u32], base: u32, out: &mut Vec<TileOut>) {
    if idx.len() > tile_samples_of(set) {
        let mid = median_split(set, idx);
        let (a, b) = idx.split_at_mut(mid);
        build_tiles(set, a, base, out);
        build_tiles(set, b, base + mid as u32, out);
        return;
    }
    // Z-order within the tile, so that consecutive samples (the caster's ray packets at low
    // spp) are neighbours on the film.
    // (The key computed once per sample: `morton << 32 | i`, the order of `(morton, i)`.)
    let mut keyed: Vec<u64> = idx
        .iter()
        .map(|&i| (morton(set.samples[i as usize].film) as u64) << 32 | i as u64)
        .collect();
    keyed.sort_unstable();
    for (d, &k) in idx.iter_mut().zip(&keyed) {
        *d = k as u32;
    }
    let (acc, lens) = rays_of(set, idx);
    let beam = match acc.finish() {
        Some(b) => b,
        None if acc.count() == 0 || idx.len() == 1 => Beam::EVERYTHING,
        None => {
            let mid = median_split(set, idx);
            let (a, b) = idx.split_at_mut(mid);
            build_tiles(set, a, base, out);
            build_tiles(set, b, base + mid as u32, out);
            return;
        }
    };
    out.push((
        Tile {
            start: base,
            len: idx.len() as u32,
            rays: acc.count(),
            beam,
        },
        acc,
        lens,
    ));
}

/// Blocks (each with its tiles) of `idx`: split further while a block has too many tiles or no
/// bounding beam.
fn build_blocks(set: &SampleSet, idx: &mut [u32], base: u32) -> Vec<BlockOut> {
    let mut tiles = Vec::new();
    if idx.len() <= TILE_SAMPLES * BLOCK_TILES {
        build_tiles(set, idx, base, &mut tiles);
        let mut acc = BeamBuilder::new();
        for (_, a, _) in &tiles {
            acc.merge(a);
        }
        let beam = acc.finish();
        if tiles.len() <= BLOCK_TILES && (beam.is_some() || tiles.len() == 1 || acc.count() == 0) {
            let block = Block {
                first_tile: 0,
                tile_count: tiles.len() as u32,
                rays: acc.count(),
                beam: beam.unwrap_or(Beam::EVERYTHING),
            };
            return vec![(tiles.into_iter().map(|(t, _, l)| (t, l)).collect(), block)];
        }
    }
    let mid = median_split(set, idx);
    let (a, b) = idx.split_at_mut(mid);
    let (mut x, y) = rayon::join(
        || build_blocks(set, a, base),
        || build_blocks(set, b, base + mid as u32),
    );
    x.extend(y);
    x
}

impl Hierarchy {
    /// Groups the samples of `set` into tiles and blocks with their beams (module docs). Works
    /// for every camera model (beams come from the rays themselves); errors on sets the caster
    /// cannot index.
    pub fn build(set: &SampleSet) -> Result<Self, HierarchyError> {
        let n = set.samples.len();
        if n >= 1 << 31 {
            return Err(HierarchyError::TooManySamples(n));
        }
        if set.spp == 0
            || set.offsets.len() != set.spp as usize
            || set.lens.len() != set.spp as usize
        {
            return Err(HierarchyError::BadTables {
                spp: set.spp,
                offsets: set.offsets.len(),
                lens: set.lens.len(),
            });
        }
        if let Some(index) = set
            .samples
            .iter()
            .position(|s| !(s.film.is_finite() && s.footprint.is_finite()))
        {
            return Err(HierarchyError::BadSample { index });
        }
        // Group by (channel, view), then split each group.
        let key = |i: u32| {
            let s = &set.samples[i as usize];
            s.channel as u32 * 8 + view_of(&set.camera, s.film.x)
        };
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.sort_by_key(|&i| key(i));
        let mut groups = Vec::new();
        let mut start = 0;
        while start < n {
            let k = key(order[start]);
            let mut end = start;
            while end < n && key(order[end]) == k {
                end += 1;
            }
            groups.push((start, end));
            start = end;
        }
        let mut slices: Vec<(u32, &mut [u32])> = Vec::new();
        let mut rest: &mut [u32] = &mut order;
        let mut done = 0;
        for &(s, e) in &groups {
            let (head, tail) = rest.split_at_mut(e - done);
            debug_assert_eq!(s, done);
            slices.push((s as u32, head));
            rest = tail;
            done = e;
        }
        let parts: Vec<Vec<BlockOut>> = slices
            .into_par_iter()
            .map(|(base, idx)| build_blocks(set, idx, base))
            .collect();
        let mut tiles = Vec::new();
        let mut blocks = Vec::new();
        let mut lens_beams = Vec::new();
        for (t, mut b) in parts.into_iter().flatten() {
            b.first_tile = tiles.len() as u32;
            for (tile, lens) in t {
                tiles.push(tile);
                lens_beams.extend(lens);
            }
            blocks.push(b);
        }
        let film = if set.spp == 1 {
            let at = |f: fn(&crate::samples::Sample) -> f32| {
                order.iter().map(|&i| f(&set.samples[i as usize])).collect()
            };
            [at(|s| s.film.x), at(|s| s.film.y), at(|s| s.footprint)]
        } else {
            Default::default()
        };
        Ok(Hierarchy {
            lens_beams,
            film,
            order,
            tiles,
            blocks,
            sample_count: n,
            spp: set.spp,
            camera: set.camera.clone(),
            rects: Vec::new(),
        })
    }

    /// Takes the pose-free rectangles ([`Hierarchy::rects`]) now, for the hierarchy's own set
    /// `set` (any pose), if its camera moves and they are not taken yet: a frame loop calls it
    /// after the build, so that its moves cost only the move. [`Hierarchy::repose`] takes them
    /// itself on the first move otherwise; a hierarchy never moved never pays for them.
    pub fn prepare_moves(&mut self, set: &SampleSet) {
        if self.rects.is_empty()
            && pose::movable(&set.camera)
            && set.samples.len() == self.sample_count
            && set.spp == self.spp
        {
            self.rects = pose_rects(set, &self.order, &self.tiles, &self.blocks);
        }
    }

    /// Moves the beams to the camera of `set`: the sample set the hierarchy was built for,
    /// with the camera moved (a new head pose). HVVR §5.1 computes the bounds once from the
    /// lens parameters and only moves them per frame; so does this for the pinhole, the stereo
    /// rig, the lens-distorted eye and the fisheye (`hierarchy/pose.rs`: per tile and block a
    /// few f64 operations, no ray). Any
    /// other camera change (intrinsics, another model) or model is built anew
    /// ([`Hierarchy::build`]). Errors on a set of another size; the samples themselves must be
    /// the build's (a foveated set whose gaze moved is another set: build it anew).
    pub fn repose(&mut self, set: &SampleSet) -> Result<(), HierarchyError> {
        if set.samples.len() != self.sample_count || set.spp != self.spp {
            return Err(HierarchyError::OtherSet {
                built: self.sample_count,
                built_spp: self.spp,
                samples: set.samples.len(),
                spp: set.spp,
            });
        }
        if self.camera == set.camera {
            return Ok(());
        }
        let moved = pose::with_frames_of(&self.camera, &set.camera);
        if moved.as_ref() != Some(&set.camera) {
            *self = Self::build(set)?;
            return Ok(());
        }
        // On the first move unless taken before ([`Hierarchy::prepare_moves`]): from `set`,
        // whose samples and intrinsics are the build's.
        self.prepare_moves(set);
        let (tile_rects, rest) = self.rects.split_at(self.tiles.len());
        let (block_rects, lens_rects) = rest.split_at(self.blocks.len());
        // The thin lens's ray origins at the new pose (one per lens sample), and their box:
        // the origin of its tiles' and blocks' beams.
        let origins = pose::lens_origins(set);
        let origin_box = origins
            .as_ref()
            .map(|o| o.iter().fold(Aabb::EMPTY, |b, p| b.grow(*p)));
        let beam_of = |r: &Rect| {
            pose::eye_frame(&set.camera, r.eye).map(|f| match origin_box {
                Some(ob) => pose::rect_beam_from(f, r, ob),
                None => pose::rect_beam(f, r),
            })
        };
        let order = &self.order;
        self.tiles
            .par_iter_mut()
            .zip(tile_rects)
            .for_each(|(t, r)| {
                t.beam = beam_of(r).unwrap_or_else(|| {
                    // A tile with rays of both eyes: the beam of its rays.
                    let idx = &order[t.start as usize..(t.start + t.len) as usize];
                    rays_of(set, idx).0.finish().unwrap_or(Beam::EVERYTHING)
                });
            });
        for (b, r) in self.blocks.iter_mut().zip(block_rects) {
            b.beam = beam_of(r).unwrap_or(Beam::EVERYTHING);
        }
        if let (Some(origins), Some(frame)) = (&origins, pose::eye_frame(&set.camera, 0)) {
            let spp = self.spp as usize;
            self.lens_beams
                .par_iter_mut()
                .zip(lens_rects)
                .enumerate()
                .for_each(|(j, (beam, r))| {
                    *beam = pose::rect_beam_from(frame, r, Aabb::EMPTY.grow(origins[j % spp]));
                });
        }
        self.camera = set.camera.clone();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use parallax_scene::CameraDesc;
    use parallax_scene::camera::{CameraOptions, ModelKind};

    /// The AVX-512 ray pass (where the CPU has it: the dispatch of `rays_of`) gives the same
    /// beams, bit for bit, as the portable sixteen lanes, on every camera model's sets.
    #[test]
    fn ray_pass_tiers_agree() {
        let desc = CameraDesc::new(Vec3::new(0.2, 1.0, 3.0), Vec3::ZERO, Vec3::Y, 60.0);
        for kind in [
            ModelKind::Pinhole,
            ModelKind::ThinLens,
            ModelKind::Fisheye,
            ModelKind::Distorted,
            ModelKind::Stereo,
        ] {
            let cam = Camera::new(kind, &desc, 40, 24, &CameraOptions::default()).unwrap();
            for spp in [1, 4, 16] {
                let set = SampleSet::grid(cam.clone(), spp);
                let idx: Vec<u32> = (0..set.samples.len() as u32).step_by(3).collect();
                let (a, la) = rays_of(&set, &idx);
                let (b, lb) = rays_of_lanes::<V16>(&set, &idx);
                assert_eq!(a.count(), b.count(), "{kind:?} {spp}");
                assert_eq!(a.finish(), b.finish(), "{kind:?} {spp}");
                assert_eq!(la, lb, "{kind:?} {spp}");
            }
        }
    }

    /// The median split's integer key orders floats as `f32::total_cmp` does: signed zeros,
    /// infinities, NaNs of both signs, subnormals and random values, pair by pair.
    #[test]
    fn total_order_key_is_total_cmp() {
        let mut v = vec![
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            1e-45,
            -1e-45,
            f32::MAX,
            f32::MIN,
        ];
        // Bit patterns spread over the whole u32 range (every sign and exponent).
        v.extend((0..200u32).map(|i| f32::from_bits(i.wrapping_mul(0x9E37_79B9))));
        for &a in &v {
            for &b in &v {
                assert_eq!(
                    total_order_key(a).cmp(&total_order_key(b)),
                    a.total_cmp(&b),
                    "{a} {b}"
                );
            }
        }
    }
}
