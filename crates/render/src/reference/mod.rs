//! The reference renderer: exact BVH ray tracing, the ground truth of every technique.
//!
//! - [`gbuffer`]: primary visibility for any camera model (view depth, position, shading
//!   normal, albedo, material, primitive, barycentrics at the pixel centre);
//! - [`shade`]: direct lighting with shadow rays (analytic lights, emissive triangles by
//!   next-event estimation, the constant environment by cosine-sampled visibility), GGX
//!   specular, and mirror / glass chains;
//! - [`render()`]: both, over screen tiles with rayon; images are bit-identical for any thread
//!   count because every pixel draws from its own seeded random stream.

pub mod gbuffer;
pub mod render;
pub mod shade;
pub mod surface;

pub use gbuffer::render_gbuffer;
pub use render::{RenderOptions, RenderOutput, render};
