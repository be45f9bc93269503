//! DIRT's capture: per-pixel (or per `S x S` tile) lists of the ids of the triangles whose
//! pixel-frustum-clipped part overlaps the cell, with per-cell depth bounds, uniform depth
//! buckets and the min-max mip chain of the bounds — the build stage of Vardis et al. 2017,
//! "DIRT: Deferred Image-based Ray Tracing" (§4.1).
//!
//! | option | type | default | meaning |
//! |---|---|---|---|
//! | `tile_size` | u32 | 1 | `S = 2^m`: one list per `S x S` pixel tile (conservative rasterization, "ADS downscaling", §4.1); 1 = per pixel |
//! | `buckets` | u32 | 8 | `B` uniform depth buckets per cell over `[zmin, zmax]` (§4.1.2, eq. 1) |
//! | `near` | f32 | 1e-4 | near plane (view depth); surface closer than this is not captured |
//! | `max_entries` | u64 | 2^28 | bound on list entries (of all views built together): the build fails instead of allocating more (the rasterization checks it every 4096 fragments, so each worker holds at most that many more before it fails) |
//! | `cell_depth` | [`CellDepth`] | `Corners` | how a triangle's depth range in a cell is bounded |
//!
//! **What a cell holds.** Each triangle is clipped against the near plane, projected, and
//! listed in every cell its projection overlaps (conservative rasterization: row slab, then
//! column, of the clipped polygon) with the view-depth range of its part inside the cell (DIRT
//! Fig. 6a): by default the range of its depth plane over the cell's corners cut to its range
//! in the cell row (exact inside the triangle), or, the slow twin, the exact range of the
//! triangle clipped against the cell's frustum (Sutherland & Hodgman 1974, in 2-D with
//! `1 / depth` interpolated perspective-correctly) as the paper's fragment shader does. "Fill
//! Depth" (§4.1.1) takes the min/max over a cell's triangles; "Fill Primitives" (§4.1.2) appends each triangle to every bucket `[b_min, b_max]`
//! its range overlaps (eq. 1a/1b, Fig. 6b), computed by [`bucket_index`] — the same monotone
//! function the tracer uses for a ray depth, so a hit at depth `d` on a triangle always lies
//! in a bucket that lists the triangle.
//!
//! **Conservative under rounding.** Cells are expanded by [`FILM_MARGIN_PX`] on every side
//! (f32 ray generation and the watertight triangle test stray by ~1e-4 px at 1280 px), and each
//! clipped depth range by a relative `2^-16` plus an absolute `32 * f32::EPSILON * scale`, with
//! `scale` = the triangle's farthest vertex from the eye plus the magnitudes of the eye and the
//! vertices (the absolute error of an f32 ray-triangle `t`). Clipping is done in f64.
//!
//! **Layout** (DIRT Table 3, with flat arrays instead of linked lists): `offsets` (CSR, one per
//! cell-bucket, `cells * B + 1` u32), `ids` (u32 triangle indices into the "vertex buffer",
//! [`DirtTriangles`], which holds the mesh's triangles in mesh order; [`DirtViews`] bundles it
//! with the camera view and the cube map the tracer reads), the mip chain (`[min, max]` f32
//! per texel over all levels; level 0 = the depth bounds) and per cell a [`CellRecord`]
//! (bounds, bucket scale and the mask of its non-empty buckets, what the tracer reads of a
//! cell in one load). Within a bucket, ids ascend. The result
//! is bit-identical whatever the thread count (screen bands are processed in parallel, each
//! owning its cells).
//!
//! Empty cells have bounds `(+inf, -inf)` and no entries.

mod build;
mod capture;
pub mod clip;
mod cube;
mod cull;
mod fill;
pub mod mip;
mod setup;
mod triangles;
mod views;

pub use capture::{
    CellDepth, CellRecord, DirtCapture, DirtError, DirtOptions, DirtStats, FILM_MARGIN_PX,
    MAX_BUCKETS, MAX_CELL_BUCKETS, MAX_TILE_SIZE, bucket_index, bucket_mask, bucket_scale,
};
pub use cube::DirtCube;
pub use mip::{LevelInfo, MipLevel};
pub use triangles::{DirtTri, DirtTriangles};
pub use views::{DirtViews, DirtViewsOptions, DirtViewsStats, MAX_FACE_SIZE};
