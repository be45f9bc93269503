//! Building a [`Bvh`]: validation, the binned-SAH binary build (`build.rs`), and the two
//! collapses into 4-wide (`collapse.rs`) and 8-wide (`collapse8.rs`) nodes over the same leaves.

use std::sync::OnceLock;
use std::time::Instant;

use glam::Vec3;
use parallax_core::Aabb;
use parallax_scene::TriangleMesh;
use rayon::prelude::*;

use crate::bvh::Bvh;
use crate::options::{BuildOptions, BvhError};
use crate::{build, collapse, collapse8, node, traverse, traverse8};
use parallax_core::huge_pages::HugeBuf;

impl Bvh {
    /// Builds with the default [`BuildOptions`]. Panics only where [`Bvh::try_build_with`]
    /// returns an error (an invalid mesh; loaders validate meshes, so this is a bug upstream).
    pub fn build(mesh: &TriangleMesh) -> Bvh {
        Self::build_with(mesh, &BuildOptions::default())
    }

    /// Builds with the default options, or explains why the mesh cannot be indexed.
    pub fn try_build(mesh: &TriangleMesh) -> Result<Bvh, BvhError> {
        Self::try_build_with(mesh, &BuildOptions::default())
    }

    /// Builds with explicit options; panics as [`Bvh::build`].
    pub fn build_with(mesh: &TriangleMesh, opts: &BuildOptions) -> Bvh {
        Self::try_build_with(mesh, opts).unwrap_or_else(|e| panic!("BVH build: {e}"))
    }

    /// Builds, or explains why the mesh cannot be indexed. An empty mesh gives an empty BVH
    /// that every ray misses. Degenerate triangles are kept (the triangle test never hits them).
    pub fn try_build_with(mesh: &TriangleMesh, opts: &BuildOptions) -> Result<Bvh, BvhError> {
        let start = Instant::now();
        let opts = opts.sanitized();
        let n = mesh.triangle_count();
        if n > node::MAX_TRIANGLES {
            return Err(BvhError::TooManyTriangles { count: n });
        }
        let nv = mesh.positions.len();
        if let Some(t) = mesh
            .indices
            .par_iter()
            .position_any(|t| t.iter().any(|&i| i as usize >= nv))
        {
            return Err(BvhError::IndexOutOfRange { triangle: t });
        }
        if n == 0 {
            return Ok(Bvh {
                nodes: Vec::new(),
                nodes8: Vec::new(),
                tris: Vec::new(),
                prim_ids: Vec::new(),
                blocks: Vec::new(),
                block_tris: Vec::new(),
                bounds: Aabb::EMPTY,
                depth: 0,
                prim_count: 0,
                build_time: start.elapsed(),
                block_copies: OnceLock::new(),
            });
        }
        // Room for the spatial splits' duplicates from the start (no reallocation later).
        let cap = if opts.spatial_splits {
            build::reference_capacity(n, &opts)
        } else {
            n
        };
        let mut refs = HugeBuf::new(cap, build::PrimRef::new(Vec3::ZERO, Vec3::ZERO, 0));
        refs[..n]
            .par_chunks_mut(4096)
            .enumerate()
            .for_each(|(k, chunk)| {
                for (i, r) in (k * 4096..).zip(chunk) {
                    let [a, b, c] = mesh.triangle(i);
                    *r = build::PrimRef::new(a.min(b).min(c), a.max(b).max(c), i as u32);
                }
            });
        let tree = if opts.spatial_splits {
            build::build_binary_spatial(&mut refs, n, &|id| mesh.triangle(id as usize), &opts)
        } else {
            build::build_binary(&mut refs, &opts)
        };
        // Both collapses only read the binary tree: the 8-wide one runs next to the 4-wide
        // one and then points its leaves at the blocks the 4-wide one laid out.
        let (c, mut c8) = rayon::join(
            || collapse::collapse(&tree, &refs, n / 6 + 1, |id| mesh.triangle(id as usize)),
            || collapse8::collapse8(&tree, n / 6 + 1),
        );
        c8.point_leaves_at_blocks(&c.leaf_blocks);
        // The binary tree is freed here, inside the timed build.
        drop(tree);
        assert!(
            3 * c.depth as usize + 1 < traverse::STACK_SIZE
                && 7 * c8.depth as usize + 1 < traverse8::STACK8_SIZE,
            "BVH depth {} / {} exceeds the traversal stack",
            c.depth,
            c8.depth
        );
        let bounds = c.nodes[0].bounds();
        Ok(Bvh {
            nodes: c.nodes,
            nodes8: c8.nodes,
            tris: c.tris,
            prim_ids: c.prim_ids,
            blocks: c.blocks,
            block_tris: c.block_tris,
            bounds,
            depth: c.depth,
            prim_count: n,
            build_time: start.elapsed(),
            block_copies: OnceLock::new(),
        })
    }
}
