//! Shared checks of the `bench warp` / `bench upsample` tests.

/// Asserts the row order of `run` over methods brute, mesh, dda, minmax at 1 and 2 layers
/// with a DDA sweep of `steps`: per layer count the methods in order, the DDA once per
/// sweep value, the mesh warp only with one layer. `rows` are `(method, layers, dda steps)`.
pub fn assert_sweep_order(rows: &[(&str, usize, Option<u32>)], steps: [u32; 2]) {
    let [a, b] = steps;
    assert_eq!(
        rows,
        [
            ("brute", 1, None),
            ("mesh", 1, None),
            ("dda", 1, Some(a)),
            ("dda", 1, Some(b)),
            ("minmax", 1, None),
            ("brute", 2, None),
            ("dda", 2, Some(a)),
            ("dda", 2, Some(b)),
            ("minmax", 2, None),
        ]
    );
}
