//! A small geometry builder for the built-in scenes: boxes, cylinders (cone frusta), UV spheres,
//! grids, thin closed sheets, extruded arches, tetrahedra and tapered strands, appended to a
//! [`TriangleMesh`] inside named [`ObjectRange`]s.
//!
//! Conventions (checked by the unit tests below and by `tests/builtin.rs`):
//! - Every triangle is counter-clockwise seen from outside: its right-hand normal
//!   `(b - a) x (c - a)` points out of the solid.
//! - The closed shapes ([`MeshBuilder::cuboid`], [`MeshBuilder::tiled_slab`], [`MeshBuilder::boxed`],
//!   [`MeshBuilder::cylinder`], [`MeshBuilder::sphere`], [`MeshBuilder::sheet`],
//!   [`MeshBuilder::arch`], [`MeshBuilder::tetra`], [`MeshBuilder::strand`]) are watertight:
//!   vertices are split where normals or uvs differ, but split copies carry bit-identical
//!   positions, so every edge is shared (by position) by exactly two triangles with opposite
//!   orientation.
//! - Curved surfaces carry smooth per-vertex normals; flat faces carry their face normal or zero
//!   (= "use the geometric normal").
//! - Texture coordinates are in metres along the surface for boxes, cylinders and arches (so a
//!   texture tiles once per metre) and in [0, 1] for spheres, grids and sheets.

use std::f32::consts::{PI, TAU};

use glam::{Affine3A, Vec2, Vec3};
use parallax_core::math::Frame;

use crate::{ObjectRange, TriangleMesh};

/// Wraps a parametric surface `P(u, v)` into `(P, N)` with `N = dP/du x dP/dv` (central
/// differences), the form [`MeshBuilder::grid`] and [`MeshBuilder::sheet`] take.
pub fn with_normals(p: impl Fn(f32, f32) -> Vec3) -> impl Fn(f32, f32) -> (Vec3, Vec3) {
    const E: f32 = 1e-3;
    move |u, v| {
        let du = p(u + E, v) - p(u - E, v);
        let dv = p(u, v + E) - p(u, v - E);
        (p(u, v), du.cross(dv).normalize_or_zero())
    }
}

/// Builds a [`TriangleMesh`] shape by shape.
#[derive(Debug, Default)]
pub struct MeshBuilder {
    mesh: TriangleMesh,
}

impl MeshBuilder {
    pub fn new() -> Self {
        Self::default()
    }

    /// Reserves room for `vertices` more vertices and `triangles` more triangles.
    pub fn reserve(&mut self, vertices: usize, triangles: usize) {
        let m = &mut self.mesh;
        m.positions.reserve(vertices);
        m.normals.reserve(vertices);
        m.uvs.reserve(vertices);
        m.indices.reserve(triangles);
        m.material_ids.reserve(triangles);
    }

    /// The finished mesh.
    pub fn finish(self) -> TriangleMesh {
        self.mesh
    }

    /// Triangles emitted so far.
    pub fn triangle_count(&self) -> usize {
        self.mesh.indices.len()
    }

    /// Runs `build` and records everything it appends as one object named `name`.
    pub fn object(&mut self, name: &str, build: impl FnOnce(&mut Self)) {
        let first_triangle = self.mesh.indices.len() as u32;
        let first_vertex = self.mesh.positions.len() as u32;
        build(self);
        self.mesh.objects.push(ObjectRange {
            name: name.to_string(),
            first_triangle,
            triangle_count: self.mesh.indices.len() as u32 - first_triangle,
            first_vertex,
            vertex_count: self.mesh.positions.len() as u32 - first_vertex,
        });
    }

    /// Appends a vertex and returns its index.
    pub fn vertex(&mut self, p: Vec3, n: Vec3, uv: Vec2) -> u32 {
        self.mesh.positions.push(p);
        self.mesh.normals.push(n);
        self.mesh.uvs.push(uv);
        self.mesh.positions.len() as u32 - 1
    }

    /// Appends triangle `(a, b, c)` (counter-clockwise seen from its front).
    pub fn tri(&mut self, a: u32, b: u32, c: u32, material: u32) {
        self.mesh.indices.push([a, b, c]);
        self.mesh.material_ids.push(material);
    }

    /// Appends the quad `a b c d` (counter-clockwise) as triangles `a b c` and `a c d`.
    pub fn quad(&mut self, [a, b, c, d]: [u32; 4], material: u32) {
        self.tri(a, b, c, material);
        self.tri(a, c, d, material);
    }

    /// A flat quad with corners `p` (counter-clockwise seen from the front), face normal and uvs.
    pub fn flat_quad(&mut self, p: [Vec3; 4], uv: [Vec2; 4], material: u32) {
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let i = std::array::from_fn(|k| self.vertex(p[k], n, uv[k]));
        self.quad(i, material);
    }

    /// An axis-aligned box from `min` to `max` (closed).
    pub fn cuboid(&mut self, min: Vec3, max: Vec3, material: u32) {
        let c = 0.5 * (min + max);
        self.boxed(Affine3A::from_translation(c), 0.5 * (max - min), material);
    }

    /// A closed axis-aligned slab from `y0` to `y1` over the grid lines `xs` x `zs`
    /// (increasing): its top is one quad per grid cell with material `top(i, k)` (cell `i`
    /// between `xs[i]` and `xs[i + 1]`), its bottom and sides are split at the same lines in
    /// `side`. Unlike a row of [`Self::cuboid`]s it has no inner faces: adjacent boxes leave
    /// coincident walls between them, which no ray can reach but which hidden depth layers
    /// capture as surfaces behind the top. Uvs in metres, as boxes.
    pub fn tiled_slab(
        &mut self,
        xs: &[f32],
        zs: &[f32],
        [y0, y1]: [f32; 2],
        top: impl Fn(usize, usize) -> u32,
        side: u32,
    ) {
        let (nx, nz) = (xs.len().saturating_sub(1), zs.len().saturating_sub(1));
        if nx == 0 || nz == 0 {
            return;
        }
        let uv = |a: f32, b: f32| Vec2::new(a, b);
        for i in 0..nx {
            let (x0, x1) = (xs[i], xs[i + 1]);
            for k in 0..nz {
                let (z0, z1) = (zs[k], zs[k + 1]);
                self.flat_quad(
                    [
                        Vec3::new(x0, y1, z0),
                        Vec3::new(x0, y1, z1),
                        Vec3::new(x1, y1, z1),
                        Vec3::new(x1, y1, z0),
                    ],
                    [uv(x0, z0), uv(x0, z1), uv(x1, z1), uv(x1, z0)],
                    top(i, k),
                );
                self.flat_quad(
                    [
                        Vec3::new(x0, y0, z0),
                        Vec3::new(x1, y0, z0),
                        Vec3::new(x1, y0, z1),
                        Vec3::new(x0, y0, z1),
                    ],
                    [uv(x0, z0), uv(x1, z0), uv(x1, z1), uv(x0, z1)],
                    side,
                );
            }
        }
        // The four sides, one quad per grid segment `a0 -> a1` along the side:
        // `[P(a0, y0), P(a1, y0), P(a1, y1), P(a0, y1)]` faces -x on an x side and +z on a z side
        // for increasing `a`, so the +x and -z sides walk their lines backwards.
        let x_side = |x: f32| move |a: f32, y: f32| Vec3::new(x, y, a);
        let z_side = |z: f32| move |a: f32, y: f32| Vec3::new(a, y, z);
        #[allow(clippy::type_complexity)] // a one-off local: (lines, point at (a, y), backwards)
        let sides: [(&[f32], &dyn Fn(f32, f32) -> Vec3, bool); 4] = [
            (zs, &x_side(xs[0]), false),
            (zs, &x_side(xs[nx]), true),
            (xs, &z_side(zs[0]), true),
            (xs, &z_side(zs[nz]), false),
        ];
        for (lines, at, backwards) in sides {
            for w in lines.windows(2) {
                let (a0, a1) = if backwards {
                    (w[1], w[0])
                } else {
                    (w[0], w[1])
                };
                self.flat_quad(
                    [at(a0, y0), at(a1, y0), at(a1, y1), at(a0, y1)],
                    [uv(a0, 0.0), uv(a1, 0.0), uv(a1, y1 - y0), uv(a0, y1 - y0)],
                    side,
                );
            }
        }
    }

    /// The box `[-half, half]` placed by `xf` (closed; any invertible affine map).
    pub fn boxed(&mut self, xf: Affine3A, half: Vec3, material: u32) {
        // Corner k has coordinate sign bit 0 -> x, 1 -> y, 2 -> z.
        let local = |k: usize| {
            Vec3::new(
                if k & 1 != 0 { half.x } else { -half.x },
                if k & 2 != 0 { half.y } else { -half.y },
                if k & 4 != 0 { half.z } else { -half.z },
            )
        };
        let corners: [Vec3; 8] = std::array::from_fn(|k| xf.transform_point3(local(k)));
        let normal_xf = xf.matrix3.inverse().transpose();
        let mirrored = xf.matrix3.determinant() < 0.0;
        // Faces as corner lists, counter-clockwise seen from outside (in local space), with the
        // local axes spanned by the uv (u along the first edge, v along the last).
        const FACES: [([usize; 4], Vec3); 6] = [
            ([1, 3, 7, 5], Vec3::X),
            ([0, 4, 6, 2], Vec3::NEG_X),
            ([2, 6, 7, 3], Vec3::Y),
            ([0, 1, 5, 4], Vec3::NEG_Y),
            ([4, 5, 7, 6], Vec3::Z),
            ([0, 2, 3, 1], Vec3::NEG_Z),
        ];
        for (quad, n_local) in FACES {
            let n = (normal_xf * n_local).normalize_or_zero();
            let (e_u, e_v) = (
                corners[quad[1]] - corners[quad[0]],
                corners[quad[3]] - corners[quad[0]],
            );
            let (lu, lv) = (e_u.length(), e_v.length());
            let uv = [
                Vec2::ZERO,
                Vec2::new(lu, 0.0),
                Vec2::new(lu, lv),
                Vec2::new(0.0, lv),
            ];
            let idx: [u32; 4] = std::array::from_fn(|k| self.vertex(corners[quad[k]], n, uv[k]));
            if mirrored {
                self.quad([idx[0], idx[3], idx[2], idx[1]], material);
            } else {
                self.quad(idx, material);
            }
        }
    }

    /// A closed cone frustum from `base` (radius `r0`) to `top` (radius `r1`) with `segments`
    /// sides, smooth side normals and flat caps. Both radii must be positive and `base != top`
    /// (otherwise nothing is emitted; [`Self::strand`] makes pointed tips).
    pub fn cylinder(&mut self, base: Vec3, top: Vec3, r0: f32, r1: f32, segments: u32, m: u32) {
        let segments = segments.max(3) as usize;
        let axis_v = top - base;
        let h = axis_v.length();
        if !(h > 0.0 && r0 > 0.0 && r1 > 0.0 && h.is_finite()) {
            return;
        }
        let axis = axis_v / h;
        let f = Frame::from_normal(axis);
        let dirs: Vec<Vec3> = (0..segments)
            .map(|i| {
                let a = TAU * i as f32 / segments as f32;
                f.x * a.cos() + f.y * a.sin()
            })
            .collect();
        let ring0: Vec<Vec3> = dirs.iter().map(|d| base + *d * r0).collect();
        let ring1: Vec<Vec3> = dirs.iter().map(|d| top + *d * r1).collect();
        // Side: normal of a cone frustum tilts towards the narrow end by (r0 - r1) / h.
        let mean_circ = PI * (r0 + r1);
        let first = self.mesh.positions.len() as u32;
        for i in 0..=segments {
            let d = dirs[i % segments];
            let n = (d * h + axis * (r0 - r1)).normalize_or_zero();
            let u = mean_circ * i as f32 / segments as f32;
            self.vertex(ring0[i % segments], n, Vec2::new(u, 0.0));
            self.vertex(ring1[i % segments], n, Vec2::new(u, h));
        }
        for i in 0..segments as u32 {
            let (a, b) = (first + 2 * i, first + 2 * i + 2);
            // (bottom i, bottom i+1, top i+1, top i): counter-clockwise seen from outside
            // because the ring runs counter-clockwise around `axis`.
            self.quad([a, b, b + 1, a + 1], m);
        }
        self.cap(base, &ring0, -axis, r0, m, true);
        self.cap(top, &ring1, axis, r1, m, false);
    }

    /// A fan cap over `ring` (counter-clockwise around the axis); `reverse` for the bottom cap.
    /// uv = planar offset from the centre in metres.
    fn cap(&mut self, centre: Vec3, ring: &[Vec3], n: Vec3, r: f32, m: u32, reverse: bool) {
        let c = self.vertex(centre, n, Vec2::ZERO);
        let first = self.mesh.positions.len() as u32;
        for (i, &p) in ring.iter().enumerate() {
            let a = TAU * i as f32 / ring.len() as f32;
            self.vertex(p, n, Vec2::new(a.cos(), a.sin()) * r);
        }
        let k = ring.len() as u32;
        for i in 0..k {
            let (a, b) = (first + i, first + (i + 1) % k);
            if reverse {
                self.tri(c, b, a, m);
            } else {
                self.tri(c, a, b, m);
            }
        }
    }

    /// A closed UV sphere with `slices` around +Y and `stacks` from pole to pole, smooth
    /// normals, uv = (longitude, latitude) in [0, 1].
    pub fn sphere(&mut self, centre: Vec3, radius: f32, slices: u32, stacks: u32, m: u32) {
        let (slices, stacks) = (slices.max(3) as usize, stacks.max(2) as usize);
        // Unit directions of the interior rings, computed once so seam copies are bit-identical.
        let rings: Vec<Vec<Vec3>> = (1..stacks)
            .map(|j| {
                let theta = PI * j as f32 / stacks as f32;
                (0..slices)
                    .map(|i| {
                        let phi = TAU * i as f32 / slices as f32;
                        Vec3::new(
                            theta.sin() * phi.cos(),
                            theta.cos(),
                            -theta.sin() * phi.sin(),
                        )
                    })
                    .collect()
            })
            .collect();
        let grid_first = self.mesh.positions.len() as u32;
        let row = slices as u32 + 1;
        for (j, ring) in rings.iter().enumerate() {
            for i in 0..=slices {
                let d = ring[i % slices];
                let uv = Vec2::new(i as f32 / slices as f32, (j + 1) as f32 / stacks as f32);
                self.vertex(centre + d * radius, d, uv);
            }
        }
        let at = |j: usize, i: usize| grid_first + j as u32 * row + i as u32;
        // Longitude runs counter-clockwise seen from +Y; latitude downwards.
        for j in 0..stacks - 2 {
            for i in 0..slices {
                self.quad([at(j, i), at(j + 1, i), at(j + 1, i + 1), at(j, i + 1)], m);
            }
        }
        let north = centre + Vec3::Y * radius;
        let south = centre - Vec3::Y * radius;
        for i in 0..slices {
            let u = (i as f32 + 0.5) / slices as f32;
            let n = self.vertex(north, Vec3::Y, Vec2::new(u, 0.0));
            self.tri(n, at(0, i), at(0, i + 1), m);
            let s = self.vertex(south, Vec3::NEG_Y, Vec2::new(u, 1.0));
            self.tri(s, at(stacks - 2, i + 1), at(stacks - 2, i), m);
        }
    }

    /// An open `nu x nv` grid over `f(u, v) -> (position, normal)`, `u, v` in [0, 1]; the
    /// front is the side of `dP/du x dP/dv`.
    pub fn grid(&mut self, nu: u32, nv: u32, m: u32, f: impl Fn(f32, f32) -> (Vec3, Vec3)) {
        let first = self.mesh.positions.len() as u32;
        for j in 0..=nv {
            for i in 0..=nu {
                let uv = Vec2::new(i as f32 / nu as f32, j as f32 / nv as f32);
                let (p, n) = f(uv.x, uv.y);
                self.vertex(p, n, uv);
            }
        }
        self.grid_triangles(first, nu, nv, m, false);
    }

    fn grid_triangles(&mut self, first: u32, nu: u32, nv: u32, m: u32, flip: bool) {
        let at = |i: u32, j: u32| first + j * (nu + 1) + i;
        for j in 0..nv {
            for i in 0..nu {
                let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                if flip {
                    self.quad([q[0], q[3], q[2], q[1]], m);
                } else {
                    self.quad(q, m);
                }
            }
        }
    }

    /// A thin closed sheet (cloth, banner, leaf blade): the surface `f(u, v) -> (position,
    /// normal)` offset by `+-thickness / 2` along the normal, with the rim closed. The normal
    /// must point along `dP/du x dP/dv`.
    pub fn sheet(
        &mut self,
        nu: u32,
        nv: u32,
        thickness: f32,
        m: u32,
        f: impl Fn(f32, f32) -> (Vec3, Vec3),
    ) {
        let (nu, nv) = (nu.max(1), nv.max(1));
        let cols = nu + 1;
        let mut front = Vec::with_capacity(((nu + 1) * (nv + 1)) as usize);
        let mut back = Vec::with_capacity(front.capacity());
        let mut normals = Vec::with_capacity(front.capacity());
        for j in 0..=nv {
            for i in 0..=nu {
                let (p, n) = f(i as f32 / nu as f32, j as f32 / nv as f32);
                let n = n.normalize_or_zero();
                front.push(p + n * (0.5 * thickness));
                back.push(p - n * (0.5 * thickness));
                normals.push(n);
            }
        }
        let uv = |k: usize| {
            Vec2::new(
                (k as u32 % cols) as f32 / nu as f32,
                (k as u32 / cols) as f32 / nv as f32,
            )
        };
        let f0 = self.mesh.positions.len() as u32;
        for k in 0..front.len() {
            self.vertex(front[k], normals[k], uv(k));
        }
        self.grid_triangles(f0, nu, nv, m, false);
        let b0 = self.mesh.positions.len() as u32;
        for k in 0..back.len() {
            self.vertex(back[k], -normals[k], uv(k));
        }
        self.grid_triangles(b0, nu, nv, m, true);
        // The front's boundary loop, counter-clockwise (the direction the front's triangles
        // run along it); for each boundary edge P -> Q the rim quad is (Q, P, P', Q').
        let mut rim: Vec<u32> = Vec::with_capacity(2 * (nu + nv) as usize + 1);
        rim.extend(0..nu);
        rim.extend((0..nv).map(|j| j * cols + nu));
        rim.extend((1..=nu).rev().map(|i| nv * cols + i));
        rim.extend((1..=nv).rev().map(|j| j * cols));
        rim.push(0);
        for w in rim.windows(2) {
            let (p, q) = (w[0] as usize, w[1] as usize);
            let pts = [front[q], front[p], back[p], back[q]];
            let t = (front[q] - front[p]).length();
            let uvs = [
                Vec2::new(t, 0.0),
                Vec2::ZERO,
                Vec2::new(0.0, thickness),
                Vec2::new(t, thickness),
            ];
            let idx = std::array::from_fn(|k| self.vertex(pts[k], Vec3::ZERO, uvs[k]));
            self.quad(idx, m);
        }
    }

    /// An extruded arch block, closed, in the local frame `xf`: a semicircular opening of
    /// radius `r` centred on the origin (springing line y = 0), flat shoulders of width
    /// `shoulder` on both sides, the flat top at `y = height` (> r), extruded over
    /// `z in [-depth / 2, depth / 2]`. The intrados (underside of the arch) carries smooth normals
    /// pointing into the opening.
    #[allow(clippy::too_many_arguments)]
    pub fn arch(
        &mut self,
        xf: Affine3A,
        r: f32,
        shoulder: f32,
        height: f32,
        depth: f32,
        segments: u32,
        m: u32,
    ) {
        let segments = segments.max(2);
        // Bottom profile b_k (y-monotone in x) with per-vertex underside normals (2-D).
        let mut bottom: Vec<(Vec2, Vec2)> = Vec::with_capacity(segments as usize + 3);
        if shoulder > 0.0 {
            bottom.push((Vec2::new(-r - shoulder, 0.0), Vec2::NEG_Y));
        }
        for k in 0..=segments {
            let a = PI * (1.0 - k as f32 / segments as f32);
            let d = Vec2::new(a.cos(), a.sin());
            let mut p = d * r;
            if k == 0 {
                p = Vec2::new(-r, 0.0);
            } else if k == segments {
                p = Vec2::new(r, 0.0);
            }
            bottom.push((p, -d));
        }
        if shoulder > 0.0 {
            bottom.push((Vec2::new(r + shoulder, 0.0), Vec2::NEG_Y));
        }
        let hz = 0.5 * depth;
        let world = |p: Vec2, z: f32| xf.transform_point3(Vec3::new(p.x, p.y, z));
        let nrm = |n: Vec3| xf.matrix3.mul_vec3(n).normalize_or_zero();
        // Positions, computed once: bottom/top at the front (z = +hz) and the back.
        let bf: Vec<Vec3> = bottom.iter().map(|(p, _)| world(*p, hz)).collect();
        let bb: Vec<Vec3> = bottom.iter().map(|(p, _)| world(*p, -hz)).collect();
        let tf: Vec<Vec3> = bottom
            .iter()
            .map(|(p, _)| world(Vec2::new(p.x, height), hz))
            .collect();
        let tb: Vec<Vec3> = bottom
            .iter()
            .map(|(p, _)| world(Vec2::new(p.x, height), -hz))
            .collect();
        let count = bottom.len();
        // Front (+z) and back (-z) faces: vertical strips between the profile and the top.
        for (pts_b, pts_t, n, flip) in [(&bf, &tf, Vec3::Z, false), (&bb, &tb, Vec3::NEG_Z, true)] {
            let n = nrm(n);
            let first = self.mesh.positions.len() as u32;
            for k in 0..count {
                let x = bottom[k].0.x;
                self.vertex(pts_b[k], n, Vec2::new(x, bottom[k].0.y));
                self.vertex(pts_t[k], n, Vec2::new(x, height));
            }
            for k in 0..count as u32 - 1 {
                let (b0, t0, b1, t1) = (
                    first + 2 * k,
                    first + 2 * k + 1,
                    first + 2 * k + 2,
                    first + 2 * k + 3,
                );
                if flip {
                    self.quad([b0, t0, t1, b1], m);
                } else {
                    self.quad([b0, b1, t1, t0], m);
                }
            }
        }
        // Underside (intrados + shoulders) and top, as strips front-to-back. Each underside
        // quad gets its own vertices: shoulders are flat (-y), the intrados carries the smooth
        // radial normals (the spring vertices differ between the two).
        let mut arc = 0.0;
        for k in 0..count - 1 {
            let step = (bottom[k + 1].0 - bottom[k].0).length();
            let is_shoulder = bottom[k].0.y == 0.0 && bottom[k + 1].0.y == 0.0;
            let n2 = |q: usize| {
                if is_shoulder {
                    Vec2::NEG_Y
                } else {
                    bottom[q].1
                }
            };
            let (n0, n1) = (n2(k), n2(k + 1));
            let (n0, n1) = (
                nrm(Vec3::new(n0.x, n0.y, 0.0)),
                nrm(Vec3::new(n1.x, n1.y, 0.0)),
            );
            let f0 = self.vertex(bf[k], n0, Vec2::new(arc, depth));
            let b0 = self.vertex(bb[k], n0, Vec2::new(arc, 0.0));
            let f1 = self.vertex(bf[k + 1], n1, Vec2::new(arc + step, depth));
            let b1 = self.vertex(bb[k + 1], n1, Vec2::new(arc + step, 0.0));
            self.quad([f0, b0, b1, f1], m);
            arc += step;
        }
        let n_top = nrm(Vec3::Y);
        let first = self.mesh.positions.len() as u32;
        for k in 0..count {
            let x = bottom[k].0.x;
            self.vertex(tf[k], n_top, Vec2::new(x, depth));
            self.vertex(tb[k], n_top, Vec2::new(x, 0.0));
        }
        for k in 0..count as u32 - 1 {
            let (f0, b0, f1, b1) = (
                first + 2 * k,
                first + 2 * k + 1,
                first + 2 * k + 2,
                first + 2 * k + 3,
            );
            self.quad([f0, f1, b1, b0], m);
        }
        // End faces at the two ends of the profile.
        let (l, r_) = (0, count - 1);
        let h = height - bottom[l].0.y;
        self.flat_quad(
            [bb[l], bf[l], tf[l], tb[l]],
            [
                Vec2::ZERO,
                Vec2::new(depth, 0.0),
                Vec2::new(depth, h),
                Vec2::new(0.0, h),
            ],
            m,
        );
        let h = height - bottom[r_].0.y;
        self.flat_quad(
            [bf[r_], bb[r_], tb[r_], tf[r_]],
            [
                Vec2::ZERO,
                Vec2::new(depth, 0.0),
                Vec2::new(depth, h),
                Vec2::new(0.0, h),
            ],
            m,
        );
    }

    /// A closed tetrahedron over four points (any order; the winding is chosen so that the
    /// faces point outwards), flat shaded (zero normals), four shared vertices with uvs
    /// (0, .5), (1, .5), (.5, 1), (.5, 0) in input order: a rhombus for leaf-like input (midrib
    /// ends first). Degenerate (flat) input emits nothing.
    pub fn tetra(&mut self, p: [Vec3; 4], m: u32) {
        let vol = (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]);
        if vol == 0.0 || !vol.is_finite() {
            return;
        }
        const UV: [Vec2; 4] = [
            Vec2::new(0.0, 0.5),
            Vec2::new(1.0, 0.5),
            Vec2::new(0.5, 1.0),
            Vec2::new(0.5, 0.0),
        ];
        let i: [u32; 4] = std::array::from_fn(|k| self.vertex(p[k], Vec3::ZERO, UV[k]));
        // With positive volume, faces (0 2 1), (0 1 3), (1 2 3), (0 3 2) point outwards;
        // otherwise swap vertices 1 and 2.
        let i = if vol > 0.0 {
            i
        } else {
            [i[0], i[2], i[1], i[3]]
        };
        for [a, b, c] in [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]] {
            self.tri(i[a], i[b], i[c], m);
        }
    }

    /// A closed, flat-shaded tube along the polyline `path` with an elliptic cross-section of
    /// `sides` corners and half-axes `(width, thickness)` per path point along `(across, the
    /// third axis)`; a last point with zero width closes the tube in an apex (grass blades,
    /// twigs). The first point gets a flat cap.
    pub fn strand(
        &mut self,
        path: &[Vec3],
        radii: &[(f32, f32)],
        across: Vec3,
        sides: u32,
        m: u32,
    ) {
        let sides = sides.max(3) as usize;
        let n = path.len().min(radii.len());
        if n < 2 {
            return;
        }
        let apex = radii[n - 1].0 <= 0.0;
        let rings_n = if apex { n - 1 } else { n };
        let mut rings: Vec<Vec<Vec3>> = Vec::with_capacity(rings_n);
        for k in 0..rings_n {
            let t = if k + 1 < n {
                path[k + 1] - path[k]
            } else {
                path[k] - path[k - 1]
            };
            let t = t.normalize_or(Vec3::Y);
            let a = (across - t * across.dot(t)).normalize_or_zero();
            let a = if a == Vec3::ZERO {
                Frame::from_normal(t).x
            } else {
                a
            };
            let b = t.cross(a);
            rings.push(
                (0..sides)
                    .map(|i| {
                        let ang = TAU * i as f32 / sides as f32;
                        path[k] + a * (radii[k].0 * ang.cos()) + b * (radii[k].1 * ang.sin())
                    })
                    .collect(),
            );
        }
        let uv = |i: usize, k: usize| Vec2::new(i as f32 / sides as f32, k as f32 / (n - 1) as f32);
        // Each ring runs counter-clockwise around the tangent (a x b = t), so the side quads
        // (k i, k i+1, k+1 i+1, k+1 i) face outwards.
        for k in 0..rings_n - 1 {
            for i in 0..sides {
                let j = (i + 1) % sides;
                let pts = [rings[k][i], rings[k][j], rings[k + 1][j], rings[k + 1][i]];
                let uvs = [uv(i, k), uv(i + 1, k), uv(i + 1, k + 1), uv(i, k + 1)];
                let idx = std::array::from_fn(|q| self.vertex(pts[q], Vec3::ZERO, uvs[q]));
                self.quad(idx, m);
            }
        }
        let last = &rings[rings_n - 1];
        if apex {
            let tip = path[n - 1];
            for i in 0..sides {
                let j = (i + 1) % sides;
                let a = self.vertex(last[i], Vec3::ZERO, uv(i, n - 2));
                let b = self.vertex(last[j], Vec3::ZERO, uv(i + 1, n - 2));
                let c = self.vertex(tip, Vec3::ZERO, uv(i, n - 1));
                self.tri(a, b, c, m);
            }
        } else {
            let c = path[n - 1];
            let ci = self.vertex(c, Vec3::ZERO, Vec2::ONE);
            let first = self.mesh.positions.len() as u32;
            for (i, &p) in last.iter().enumerate() {
                self.vertex(p, Vec3::ZERO, uv(i, n - 1));
            }
            for i in 0..sides as u32 {
                self.tri(ci, first + i, first + (i + 1) % sides as u32, m);
            }
        }
        let c = self.vertex(path[0], Vec3::ZERO, Vec2::ZERO);
        let first = self.mesh.positions.len() as u32;
        for (i, &p) in rings[0].iter().enumerate() {
            self.vertex(p, Vec3::ZERO, uv(i, 0));
        }
        for i in 0..sides as u32 {
            self.tri(c, first + (i + 1) % sides as u32, first + i, m);
        }
    }
}
