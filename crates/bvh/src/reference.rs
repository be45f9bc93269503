//! Brute-force reference queries: every triangle, the same watertight test. The slow twin that
//! the tests hold the BVH against (DESIGN.md, "keep every fast path's slow twin alive").

use parallax_core::Ray;
use parallax_core::math::WatertightRay;
use parallax_scene::TriangleMesh;

use crate::hit::Hit;
use crate::traverse::sort_hits;

/// The closest hit over all triangles of `mesh` (the first in index order on exact ties).
pub fn brute_force_closest(mesh: &TriangleMesh, ray: &Ray) -> Option<Hit> {
    let wt = WatertightRay::new(ray);
    let mut best: Option<Hit> = None;
    let mut t_max = ray.t_max;
    for i in 0..mesh.triangle_count() {
        let [a, b, c] = mesh.triangle(i);
        if let Some(h) = wt.intersect_within(a, b, c, t_max) {
            t_max = h.t;
            best = Some(Hit {
                prim: i as u32,
                t: h.t,
                u: h.u,
                v: h.v,
            });
        }
    }
    best
}

/// Every hit over all triangles of `mesh`, sorted by `t` then primitive; `out` is cleared first.
pub fn brute_force_all(mesh: &TriangleMesh, ray: &Ray, out: &mut Vec<Hit>) {
    out.clear();
    let wt = WatertightRay::new(ray);
    for i in 0..mesh.triangle_count() {
        let [a, b, c] = mesh.triangle(i);
        if let Some(h) = wt.intersect(a, b, c) {
            out.push(Hit {
                prim: i as u32,
                t: h.t,
                u: h.u,
                v: h.v,
            });
        }
    }
    sort_hits(out);
}
