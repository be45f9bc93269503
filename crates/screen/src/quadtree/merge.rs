//! Bottom-up pruning of one quad-tree level (Widmer et al. 2015, §3.3): the proxy plane of
//! four plane children under the three conditions, or the conservative AABB (see
//! [`super::build`] for the definitions).

use glam::Vec3;

use super::node::{FLAG_CRACK, Node, node_centre, plane_z};
use super::tree::Z_EPS;

/// Merge settings of one build.
pub(crate) struct MergeCtx {
    pub(crate) wf: f32,
    pub(crate) hf: f32,
    pub(crate) cos_norm: f32,
    pub(crate) gamma_dist: f32,
    pub(crate) adaptive: bool,
    pub(crate) near: f64,
    pub(crate) far: f64,
    pub(crate) crack_px: f32,
    pub(crate) never: bool,
    /// Evaluate the four children in lanes ([`Self::parent_lanes`], same bits); `false`:
    /// the scalar definition (the reference build).
    pub(crate) lanes: bool,
}

#[cfg(test)]
impl MergeCtx {
    /// Settings of the lane kernels' twin tests, varied by `case`: the three fixed threshold
    /// pairs, fixed and adaptive thresholds, crack dilation 0 / 0.5 / 1 px, and every
    /// sixteenth case a build that never merges; evaluated in lanes, at 1600x900.
    pub(crate) fn test_case(case: u32) -> Self {
        MergeCtx {
            wf: 1600.0,
            hf: 900.0,
            cos_norm: [0.99, 0.9995, 0.95][case as usize % 3],
            gamma_dist: [1e-3, 1e-4, 1e-2][case as usize % 3],
            adaptive: case % 2 == 1,
            near: 0.1,
            far: 100.0,
            crack_px: 0.5 * (case % 3) as f32,
            never: case % 16 == 15,
            lanes: true,
        }
    }
}

impl MergeCtx {
    /// Conservative `[zmin, zmax]` of a node over its footprint.
    pub(crate) fn zrange(&self, node: Node, level: u32) -> (f32, f32) {
        if !node.is_plane() {
            return node.zrange();
        }
        // A plane is affine over the footprint: its range is z_c ± (|dz/dx| hx + |dz/dy| hy)
        // around the footprint centre (where the node stores z_c), hx, hy = half extents.
        let (gx, gy) = node.gradient(level, self.wf, self.hf);
        let dil = if node.flags() & FLAG_CRACK != 0 {
            self.crack_px
        } else {
            0.0
        };
        let half = 0.5 * (1u32 << level) as f32 + dil;
        let spread = gx.abs() * half / self.wf + gy.abs() * half / self.hf;
        plane_range(node.zc(), spread)
    }

    /// The threshold of the early reject on the smallest child-normal cosine: the loosest
    /// this node could get.
    pub(super) fn loosest_cos(&self) -> f32 {
        if self.adaptive {
            self.cos_thr(1.0)
        } else {
            self.cos_norm
        }
    }

    /// The parent of `kids` (children at level `cl`, positions `pos`, in order
    /// (0,0), (1,0), (0,1), (1,1)); the parent is `(qx, qy)` at level `l`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn parent(
        &self,
        l: u32,
        qx: u32,
        qy: u32,
        cl: u32,
        kids: &[Node; 4],
        pos: &[(u32, u32); 4],
        allow_merge: bool,
    ) -> Node {
        if self.lanes {
            return self.parent_lanes(l, qx, qy, cl, kids, pos, allow_merge);
        }
        if !self.never
            && allow_merge
            && kids.iter().all(|k| k.is_plane())
            && let Some(p) = self.merge(l, qx, qy, cl, kids, pos)
        {
            return p;
        }
        union(kids.iter().map(|k| self.zrange(*k, cl)))
    }

    /// §3.3: the proxy plane of four plane children, if the three conditions hold.
    fn merge(
        &self,
        l: u32,
        qx: u32,
        qy: u32,
        cl: u32,
        kids: &[Node; 4],
        pos: &[(u32, u32); 4],
    ) -> Option<Node> {
        let mut planes = [(Vec3::ZERO, 0.0f32); 4];
        let mut sum = Vec3::ZERO;
        let mut flags = 0;
        for (i, k) in kids.iter().enumerate() {
            planes[i] = (k.normal(cl, self.wf, self.hf), 0.0);
            sum += planes[i].0;
            flags |= k.flags() & FLAG_CRACK;
        }
        let nn = sum.normalize_or_zero();
        if !(nn.z < -1e-6) {
            return None;
        }
        let min_cos = planes
            .iter()
            .map(|p| p.0.dot(nn))
            .fold(f32::INFINITY, f32::min);
        // Cheap early reject with the loosest threshold this node could get.
        if !(min_cos > self.loosest_cos()) {
            return None;
        }
        // Child corners from the stored centre z and the decoded plane gradient:
        // z = z_c + g_x (x - x_c) + g_y (y - y_c).
        let mut proj = [0.0f32; 16];
        let half = 0.5 * (1u32 << cl) as f32;
        let (hx, hy) = (half / self.wf, half / self.hf);
        for (i, (k, &(cx, cy))) in kids.iter().zip(pos).enumerate() {
            let (gx, gy) = k.gradient(cl, self.wf, self.hf);
            let (xc, yc) = node_centre(cl, cx, cy, self.wf, self.hf);
            let zc = k.zc();
            for (m, (sx, sy)) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)]
                .into_iter()
                .enumerate()
            {
                let (dx, dy) = (sx * hx, sy * hy);
                let p = Vec3::new(xc + dx, yc + dy, zc + gx * dx + gy * dy);
                proj[4 * i + m] = nn.dot(p);
            }
        }
        self.proxy(l, qx, qy, nn, min_cos, &proj, flags)
    }

    /// The proxy plane of a merge (§3.3) from its normal `nn`, the smallest cosine
    /// `min_cos` of a child normal to it and the projections `proj` of the 16 child corners
    /// on `nn`, if conditions 2 and 3 hold.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn proxy(
        &self,
        l: u32,
        qx: u32,
        qy: u32,
        nn: Vec3,
        min_cos: f32,
        proj: &[f32; 16],
        flags: u32,
    ) -> Option<Node> {
        let c = proj.iter().sum::<f32>() / 16.0;
        // The largest `|p - c|` by compare-select (`maxss`), not `f32::max`'s NaN handling:
        // the values are `+0` or positive, or NaN, which both skip, so the same value.
        let dmax = proj
            .iter()
            .map(|p| (p - c).abs())
            .fold(0.0f32, |m, d| if d > m { d } else { m })
            / -nn.z;
        let (xc, yc) = node_centre(l, qx, qy, self.wf, self.hf);
        let zc = plane_z(nn, c, xc, yc);
        let u = if self.adaptive {
            self.depth_fraction(zc)
        } else {
            0.0
        };
        if min_cos > self.cos_thr(u) && dmax < self.dist_thr(u) {
            let inv = -1.0 / nn.z; // nn.z < -1e-6 (checked above)
            Node::plane_with_gradient(zc, nn.x * inv, nn.y * inv, l, self.wf, self.hf, flags)
        } else {
            None
        }
    }

    /// Linear depth fraction `(d - near) / (far - near)` of cube `z`, in `[0, 1]`.
    pub(super) fn depth_fraction(&self, z: f32) -> f32 {
        let (n, f) = (self.near, self.far);
        let inv_d = 1.0 / n - z as f64 * (1.0 / n - 1.0 / f);
        if !(inv_d > 0.0) {
            return 1.0;
        }
        (((1.0 / inv_d) - n) / (f - n)).clamp(0.0, 1.0) as f32
    }

    pub(super) fn cos_thr(&self, u: f32) -> f32 {
        if !self.adaptive || self.cos_norm >= 1.0 {
            return self.cos_norm;
        }
        let a0 = self.cos_norm.clamp(-1.0, 1.0).acos();
        let cap = 25f32.to_radians().max(a0);
        (a0 * (1.0 + (super::ADAPTIVE_SCALE - 1.0) * u))
            .min(cap)
            .cos()
    }

    pub(super) fn dist_thr(&self, u: f32) -> f32 {
        if !self.adaptive {
            return self.gamma_dist;
        }
        let cap = 0.1f32.max(self.gamma_dist);
        (self.gamma_dist * (1.0 + (super::ADAPTIVE_SCALE - 1.0) * u)).min(cap)
    }
}

/// The range `z_c ± spread` of a plane over its footprint, widened by [`Z_EPS`] and clamped
/// to `[0, 1]`; `[0, 1]` for an infinite or NaN spread.
#[inline]
pub(super) fn plane_range(zc: f32, spread: f32) -> (f32, f32) {
    if !spread.is_finite() {
        return (0.0, 1.0);
    }
    let (lo, hi) = (zc - spread, zc + spread);
    ((lo - Z_EPS).clamp(0.0, 1.0), (hi + Z_EPS).clamp(0.0, 1.0))
}

/// The AABB node of the union of the children's ranges, in order (empty if none).
#[inline]
pub(super) fn union(ranges: impl Iterator<Item = (f32, f32)>) -> Node {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for (a, b) in ranges {
        lo = lo.min(a);
        hi = hi.max(b);
    }
    if lo > hi {
        Node::EMPTY
    } else {
        Node::aabb(lo, hi)
    }
}
