//! Shared checks of the `bench warp` / `bench upsample` tests.

use parallax_synth::method::Method;

/// The methods of the sweep tests, in the order [`assert_sweep_order`] expects.
pub const SWEEP_METHODS: [Method; 4] = [Method::Brute, Method::Mesh, Method::Dda, Method::MinMax];

/// Asserts the row order of `run` over [`SWEEP_METHODS`] at 1 and 2 layers
/// with a DDA sweep of `steps`: per layer count the methods in order, the DDA once per
/// sweep value, the mesh warp only with one layer. `rows` are `(method, layers, dda steps)`.
pub fn assert_sweep_order<'a>(
    rows: impl IntoIterator<Item = (&'a str, usize, Option<u32>)>,
    steps: [u32; 2],
) {
    let [a, b] = steps;
    let rows: Vec<_> = rows.into_iter().collect();
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
