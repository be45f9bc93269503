//! Sampling: seeded per-pixel random streams, low-discrepancy points, warps.
