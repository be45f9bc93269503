//! Sampling: seeded per-pixel random streams, low-discrepancy points, warps.
//!
//! * [`rng`]: PCG32 streams keyed by `(seed, x, y, sample_index)` — bit-identical images
//!   whatever the thread count.
//! * [`lowdisc`]: Halton, Owen-scrambled Sobol (0,2)-sequence, R2, Cranley-Patterson.
//! * [`warp`]: square -> disk / hemisphere / sphere / triangle / Phong lobe / GGX visible
//!   normals, each with its pdf (local frame, `z` up).

pub mod lowdisc;
pub mod rng;
pub mod warp;

pub use lowdisc::{
    cranley_patterson, halton, halton_2d, owen_scramble_bits, r2, radical_inverse, sobol_2d,
    sobol_2d_unscrambled,
};
pub use rng::{ONE_MINUS_EPSILON, Rng, pcg_hash, splitmix64};
pub use warp::{
    Ggx, UNIFORM_HEMISPHERE_PDF, UNIFORM_SPHERE_PDF, blinn_phong_d, concentric_disk,
    concentric_disk_inverse, cosine_hemisphere, cosine_hemisphere_around, cosine_hemisphere_pdf,
    ggx_d, phong_exponent_from_roughness, phong_lobe, phong_lobe_pdf, reflect, smith_g1, smith_g2,
    uniform_hemisphere, uniform_sphere, uniform_triangle,
};
