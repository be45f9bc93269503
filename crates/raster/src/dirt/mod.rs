//! DIRT capture (in progress).
