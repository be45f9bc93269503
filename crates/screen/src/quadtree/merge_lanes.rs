//! One pruning step (Widmer et al. 2015, §3.3) with the four children in the lanes of
//! `Vec4`s: their gradients, normals (square root and division), footprint centres
//! (divisions), corner projections and conservative `z` ranges (divisions) one lane per
//! child. Every lane does exactly the operations of the scalar definition in
//! [`super::merge`], in its order (IEEE square root, division, products and sums are
//! correctly rounded per lane; no fused multiply-add), and what the definition folds over
//! the children (sums, minima) is folded in the same order from the lanes, so the nodes are
//! the same bits (`tests/quadtree_build.rs` compares whole trees with the reference build,
//! which runs the scalar definition).

use glam::{Vec3, Vec4};

use super::merge::{MergeCtx, plane_range, union};
use super::node::{FLAG_CRACK, Node};

/// `Vec4` from four values computed per child.
#[inline(always)]
fn lanes(f: impl Fn(usize) -> f32) -> Vec4 {
    Vec4::new(f(0), f(1), f(2), f(3))
}

impl MergeCtx {
    /// [`MergeCtx::parent`] in lanes (module docs).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub(crate) fn parent_lanes(
        &self,
        l: u32,
        qx: u32,
        qy: u32,
        cl: u32,
        kids: &[Node; 4],
        pos: &[(u32, u32); 4],
        allow_merge: bool,
    ) -> Node {
        // The gradients as `Node::gradient` computes them (garbage in lanes of AABB children,
        // which nothing below reads).
        let (ws, hs) = (
            f32::from_bits(self.wf.to_bits() - (cl << 23)),
            f32::from_bits(self.hf.to_bits() - (cl << 23)),
        );
        let (mut ex, mut ey) = ([0.0f32; 4], [0.0f32; 4]);
        for (i, k) in kids.iter().enumerate() {
            (ex[i], ey[i]) = k.increments();
        }
        let gx = Vec4::from(ex) * Vec4::splat(ws);
        let gy = Vec4::from(ey) * Vec4::splat(hs);
        let planes = kids.iter().all(|k| k.is_plane());
        if !self.never
            && allow_merge
            && planes
            && let Some(p) = self.merge_lanes(l, qx, qy, cl, kids, pos, gx, gy)
        {
            return p;
        }
        // `MergeCtx::zrange` per child: the spread's divisions in lanes.
        let size = (1u32 << cl) as f32;
        let half = lanes(|i| {
            let dil = if kids[i].flags() & FLAG_CRACK != 0 {
                self.crack_px
            } else {
                0.0
            };
            0.5 * size + dil
        });
        let spread = ((gx.abs() * half) / Vec4::splat(self.wf)
            + (gy.abs() * half) / Vec4::splat(self.hf))
        .to_array();
        union(kids.iter().zip(spread).map(|(k, s)| {
            if k.is_plane() {
                plane_range(k.zc(), s)
            } else {
                k.zrange()
            }
        }))
    }

    /// `MergeCtx::merge` in lanes; `gx`, `gy`: the children's decoded gradients.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn merge_lanes(
        &self,
        l: u32,
        qx: u32,
        qy: u32,
        cl: u32,
        kids: &[Node; 4],
        pos: &[(u32, u32); 4],
        gx: Vec4,
        gy: Vec4,
    ) -> Option<Node> {
        let s = Vec4::splat;
        // `Node::normal`: (g_x, g_y, -1) / sqrt(1 + g_x^2 + g_y^2).
        let mut q = (s(1.0) + gx * gx + gy * gy).to_array();
        for v in &mut q {
            *v = v.sqrt();
        }
        let r = s(1.0) / Vec4::from(q);
        let (nx, ny, nz) = ((gx * r).to_array(), (gy * r).to_array(), (-r).to_array());
        let mut sum = Vec3::ZERO;
        let mut flags = 0;
        for (i, k) in kids.iter().enumerate() {
            sum += Vec3::new(nx[i], ny[i], nz[i]);
            flags |= k.flags() & FLAG_CRACK;
        }
        let nn = sum.normalize_or_zero();
        if !(nn.z < -1e-6) {
            return None;
        }
        let (vx, vy, vz) = (Vec4::from(nx), Vec4::from(ny), Vec4::from(nz));
        let cos = (vx * s(nn.x) + vy * s(nn.y) + vz * s(nn.z)).to_array();
        let min_cos = cos.into_iter().fold(f32::INFINITY, f32::min);
        if !(min_cos > self.loosest_cos()) {
            return None;
        }
        // `node_centre` per child and the 16 corner projections, one corner per step.
        let size = (1u32 << cl) as f32;
        let xc = ((lanes(|i| pos[i].0 as f32) + s(0.5)) * s(size)) / s(self.wf);
        let yc = ((lanes(|i| pos[i].1 as f32) + s(0.5)) * s(size)) / s(self.hf);
        let zc = lanes(|i| kids[i].zc());
        let half = 0.5 * size;
        let (hx, hy) = (half / self.wf, half / self.hf);
        let mut proj = [0.0f32; 16];
        for (m, (sx, sy)) in [(-1.0f32, -1.0f32), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)]
            .into_iter()
            .enumerate()
        {
            let (dx, dy) = (sx * hx, sy * hy);
            let (px, py, pz) = (xc + s(dx), yc + s(dy), zc + gx * s(dx) + gy * s(dy));
            let p = (s(nn.x) * px + s(nn.y) * py + s(nn.z) * pz).to_array();
            for (i, v) in p.into_iter().enumerate() {
                proj[4 * i + m] = v;
            }
        }
        self.proxy(l, qx, qy, nn, min_cos, &proj, flags)
    }
}
