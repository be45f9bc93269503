//! G-buffer captures, depth layers, cube maps, orthographic views (in progress).
