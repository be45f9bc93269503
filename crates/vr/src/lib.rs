//! parallax-vr: HVVR (Hunt et al. 2018, "Hierarchical Visibility for Virtual Reality") —
//! primary visibility for headsets by ray casting that shares traversal across thousands of
//! coherent rays, then resolve, shading and reconstruction of the frame.
//!
//! **Where things are** (one frame, [`frame`], top to bottom):
//!
//! | stage | module | paper |
//! |---|---|---|
//! | headset presets and eye cameras | [`presets`] | §2, Table 5 |
//! | sample sets: every sample's `spp` subsample rays, just in time | [`samples`], [`patterns`] (grid, per-channel distortion, foveated, wide FoV, depth of field) | §2, §5.1 |
//! | tiles (<= 128 samples) and blocks (<= 64 tiles) with bounding beams | [`hierarchy`] | §5, Fig. 4 |
//! | the beam, its box test, block cull and tile cull over the BVH | [`beam`] | §5.3-5.4 |
//! | sample tests: per-tile triangle set-up (default) or the watertight kernels | [`cast`](mod@cast) ([`cast::setup`], [`cast::packet`], [`cast::intersect`]) | §5.5 |
//! | the visibility buffer, and the per-ray BVH baseline that fills the same buffer | [`visibility`] | §5.5 |
//! | MSAA / SSAA resolve, shading, reconstruction onto the display grid | [`resolve`], [`shade`], [`reconstruct`] | §5.6, §2.1-2.3 |
//! | scene update (animation + BVH refit) and one frame | [`frame`] | §5.2 |
//! | `parallax bench vr` (Tables 1-6) | [`bench`](mod@bench) | §6 |
//!
//! **The seam:** every visibility method fills a [`VisibilityBuffer`] (the closest triangle
//! of every subsample ray); the beam caster ([`cast()`]) and the per-ray BVH traversal
//! ([`trace_per_ray`]) fill the same buffer from the same rays, so they are compared
//! subsample by subsample, and resolve and shading consume either.
//!
//! **Invariants.**
//! - The watertight kernels ([`SampleTest::Watertight`]) perform, per subsample ray, the f32
//!   operations of the BVH's own leaf test with the same tie-break, on rays bit-identical to
//!   [`SampleSet::subsample_ray`], and the culling is conservative: their buffer equals
//!   [`trace_per_ray`]'s, subsample for subsample (`tests/cast.rs`).
//! - The set-up kernel ([`SampleTest::TileSetup`], the default for tiles with a shared ray
//!   origin) decides everything inside a conservative uncertainty band with the same
//!   watertight test ([`cast::setup`], "exact band"): with [`SetupExactness::Edges`] (default)
//!   the coverage is exact and the only differences from per-ray traversal are depth ties
//!   within float tolerance; with [`SetupExactness::Full`] (`--visibility beam-exact`) the
//!   buffer is bit-identical.
//! - Images do not depend on the thread count (tiles write only their own samples).
//!
//! **Parameters** ([`CastOptions`]):
//!
//! | name | type | default | meaning |
//! |---|---|---|---|
//! | `test` | [`SampleTest`] | `TileSetup` | the sample test (tiles without a shared origin, e.g. thin lens, always take the watertight kernel) |
//! | `lanes` | usize | 16 | rays per SIMD packet: 4 (SSE), 8 (AVX2 if detected), 16 (set-up kernel: one AVX-512 or four SSE registers, one pixel at 16 spp), 1 (one ray against four leaf boxes) |
//! | `exactness` | [`SetupExactness`] | `Edges` | how exactly the set-up kernel reproduces per-ray traversal |
//! | `isa` | [`Isa`] | `Avx512` | the widest instruction-set tier of the set-up kernel's 16-lane packets and the per-tile set-up: one AVX-512 register where the CPU has AVX-512F, else two AVX registers where it has AVX2, else four SSE registers (`Isa::Sse`: the portable twin); the same buffer |
//! | `affine` | bool | true | the affine packet test before the set-up kernel's per-lane edge test (`Edges`, pinhole and stereo tiles; [`cast::setup::affine`]): decides whole packets against a triangle with a rigorous error bound; the same buffer; not on the AVX-512 kernel, nor on the AVX2 16-lane kernel at 1 spp, unless `affine_always` |
//! | `affine_always` | bool | false | the affine packet test on the AVX-512 kernel and on the AVX2 16-lane kernel at 1 spp too (there it costs more than it saves, `docs/notes/vr.md`) |
//! | `sweep` | bool | true | the set-up test with the tile's triangles outside and its packets inside ([`cast::setup`]'s `sweep.rs`) where a tile's 16-lane packets are whole 16-subsample chunks of pinhole or stereo samples (`Edges`); the same buffer |
//!
//! Measurements and what was tried: `docs/notes/vr.md`.

pub mod beam;
pub mod bench;
pub mod cast;
pub mod frame;
pub mod hierarchy;
pub mod patterns;
pub mod presets;
pub mod reconstruct;
pub mod resolve;
pub mod samples;
pub mod shade;
#[cfg(test)]
mod test_streams;
pub mod visibility;

pub use cast::setup::{SampleTest, SetupExactness};
pub use cast::stored::RayBuffer;
pub use cast::{CastOptions, CastStats, Isa, cast, cast_opts, cast_stored, cast_with};
pub use hierarchy::{Block, Hierarchy, HierarchyError, Tile};
pub use patterns::PatternError;
pub use samples::{Sample, SampleSet};
pub use visibility::{VisibilityBuffer, trace_per_ray};
