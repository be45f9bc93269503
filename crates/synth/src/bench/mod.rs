//! Benchmarks behind `parallax bench warp | upsample | compression | dof | reflect | quadtree-build`: each reproduces a table or
//! figure of Widmer et al. 2015 on any scene and view and returns rows that the CLI prints as a
//! Markdown table and JSON (field names shared with `parallax_render::bench`).

use crate::method::{Method, MethodOptions};

pub mod build;
pub mod compression;
pub mod dof;
pub mod dof_equal;
pub mod input;
pub mod reflect;
pub mod trace;
pub mod upsample;
pub mod warp;

/// The layer count at which the mesh warp (layer 0 only) gets its one row: 1 if measured, else
/// the first layer count asked for.
pub(crate) fn mesh_layers(layers: &[usize]) -> usize {
    if layers.contains(&1) { 1 } else { layers[0] }
}

/// The `(method, options)` entries measured at `n` layers: every method once with `opts`, the
/// DDA once per value of `dda_steps` (when given), the mesh warp only at `mesh_layers`.
pub(crate) fn method_entries(
    methods: &[Method],
    n: usize,
    mesh_layers: usize,
    opts: &MethodOptions,
    dda_steps: &[u32],
) -> Vec<(Method, MethodOptions)> {
    let mut entries = Vec::new();
    for &m in methods {
        if m == Method::Mesh && n != mesh_layers {
            continue;
        }
        let steps = match m {
            Method::Dda if !dda_steps.is_empty() => dda_steps.to_vec(),
            _ => vec![opts.dda_max_steps],
        };
        for st in steps {
            let o = MethodOptions {
                dda_max_steps: st,
                ..*opts
            };
            entries.push((m, o));
        }
    }
    entries
}
