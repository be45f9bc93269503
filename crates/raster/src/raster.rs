//! The triangle rasterizer (in progress).
