//! parallax-path: light transport written once over the world-space tracer interface
//! ([`parallax_core::WorldTracer`]): the reference path tracer (the BVH behind the interface),
//! DIRT's deferred image-based path tracer (Vardis et al. 2017: the same estimator with DIRT's
//! per-pixel primitive lists behind it), and the secondary-ray renderer of the layered depth
//! cube paper (reflections, refractions and shadows from a rasterized primary view).
//!
//! **Invariant:** nothing here knows which structure answers its rays; every structure is
//! compared on identical rays.
