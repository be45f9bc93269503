//! Refit after the vertices moved (topology unchanged).
//!
//! HVVR §5.2: gather the moved vertices into the BVH's triangle array, recompute leaf bounds,
//! then propagate bounds upwards. Because nodes are in depth-first preorder (every child has a
//! larger index than its parent), one reverse sweep over the node array visits children before
//! parents: no recursion, no parent pointers. The triangle gather and the leaf-lane bounds (the
//! bulk of the work, touching every triangle) run in parallel; the inner-lane sweep is a short
//! sequential pass over the nodes.

use std::time::{Duration, Instant};

use parallax_core::Aabb;
use parallax_scene::TriangleMesh;
use rayon::prelude::*;

use crate::bvh::Bvh;
use crate::node::{ChildRef, EMPTY};
use crate::options::BvhError;
use crate::tri::Tri;

impl Bvh {
    /// Updates the BVH to the mesh's current vertex positions, keeping its topology (the mesh
    /// must have the same triangles, with the same indices, as the one it was built from).
    /// Returns the time taken. Quality degrades when triangles move far relative to each other;
    /// rebuild then.
    pub fn refit(&mut self, mesh: &TriangleMesh) -> Result<Duration, BvhError> {
        let start = Instant::now();
        if mesh.triangle_count() != self.prim_count {
            return Err(BvhError::TopologyChanged {
                built: self.prim_count,
                given: mesh.triangle_count(),
            });
        }
        let nv = mesh.positions.len();
        if let Some(t) = mesh
            .indices
            .par_iter()
            .position_any(|t| t.iter().any(|&i| i as usize >= nv))
        {
            return Err(BvhError::IndexOutOfRange { triangle: t });
        }
        self.tris
            .par_iter_mut()
            .zip(self.prim_ids.par_iter())
            .with_min_len(1024)
            .for_each(|(tri, &id)| *tri = Tri::new(mesh.triangle(id as usize)));
        let tris = &self.tris;
        self.blocks
            .par_iter_mut()
            .zip(self.block_tris.par_iter())
            .with_min_len(1024)
            .for_each(|(b, &start)| {
                for l in 0..4 {
                    if b.tri[l] != u32::MAX {
                        b.set(l, &tris[start as usize + l], b.tri[l]);
                    }
                }
            });

        // Leaf lanes, in parallel over nodes.
        let block_tris = &self.block_tris;
        let leaf_bounds = |first: u32, count: u32| {
            let start = block_tris[first as usize] as usize;
            tris[start..start + count as usize]
                .iter()
                .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()))
        };
        self.nodes
            .par_iter_mut()
            .with_min_len(256)
            .for_each(|node| {
                for lane in 0..4 {
                    let c = node.child[lane];
                    if c == EMPTY {
                        continue;
                    }
                    if let ChildRef::Leaf { first, count } = ChildRef::decode(c) {
                        node.set_child_bounds(lane, leaf_bounds(first, count));
                    }
                }
            });
        // Inner lanes, children before parents.
        for i in (0..self.nodes.len()).rev() {
            let (head, tail) = self.nodes.split_at_mut(i + 1);
            let node = &mut head[i];
            for lane in 0..4 {
                if let ChildRef::Inner(c) = ChildRef::decode(node.child[lane]) {
                    node.set_child_bounds(lane, tail[c as usize - i - 1].bounds());
                }
            }
        }
        // The 8-wide tree: the same two passes.
        self.nodes8
            .par_iter_mut()
            .with_min_len(128)
            .for_each(|node| {
                for lane in 0..8 {
                    let c = node.child[lane];
                    if c == EMPTY {
                        continue;
                    }
                    if let ChildRef::Leaf { first, count } = ChildRef::decode(c) {
                        node.set_child_bounds(lane, leaf_bounds(first, count));
                    }
                }
            });
        for i in (0..self.nodes8.len()).rev() {
            let (head, tail) = self.nodes8.split_at_mut(i + 1);
            let node = &mut head[i];
            for lane in 0..8 {
                if let ChildRef::Inner(c) = ChildRef::decode(node.child[lane]) {
                    node.set_child_bounds(lane, tail[c as usize - i - 1].bounds());
                }
            }
        }
        self.bounds = self.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds());
        Ok(start.elapsed())
    }
}
