//! Why the layered depth cube answers a ray differently from the BVH: every disagreement of
//! [`super::replay`]'s ray-for-ray comparison put in one class, looked up in the cube's
//! samples and the scene's triangles (a measurement tool for `bench ldc`; Bürger et al. 2007,
//! §3, attribute their differences to sampling without counting them).
//!
//! **Classes** (the first that applies, in this order):
//!
//! | class | the ray | meaning |
//! |---|---|---|
//! | `truncated` | a traversal loop hit its step bound | the step bounds cut the walk |
//! | `outside` | the BVH's (first) hit is outside the cube's box | region-of-interest exit |
//! | `near` | both hit, positions within one LDI pixel (but not within the agreement tolerance) | sampling resolution: the LDC's hit is on a neighbouring sample of the same surface or of a surface within a pixel |
//! | `overhang` | the LDC hit first, more than `eps` off its sample's triangle | a splat covers its whole pixel and sticks out past its triangle's edge (silhouettes, thin parts) |
//! | `early` | the LDC hit first, on its sample's triangle | a surface the BVH passes (eps-thick plane test on a nearby surface, precision) |
//! | `skipped` | the BVH's hit is nearer than the LDC's skip distance | the LDC ignores hits within `skip` pixels of the origin by design |
//! | `uncaptured` | no sample of the BVH's triangle within one pixel of its hit in the triangle's LDI | the triangle is thinner than a pixel there: the rasterization left it out |
//! | `grazing` | the ray is within 10° of the BVH's surface | the ray runs along the splats of that surface and slips between them |
//! | `edge` | the BVH's triangle has samples around its hit but not in the hit's own pixel | that pixel's splat is a neighbouring triangle's plane (a crease, a triangle or LDI seam): the ray crosses it outside the pixel, and misses the neighbours' splats too |
//! | `gap` | otherwise (the hit's own pixel holds a sample of its triangle) | the walk or the sample test missed a sample whose plane is the triangle's |
//!
//! Layer truncation is not a class: a cube whose depth complexity exceeds the layer limit is a
//! build error ([`parallax_raster::ldc::LdcOptions::max_layers`]), so no layer is ever dropped.
//!
//! **Invariant:** the classes of a set sum to its disagreements
//! (`rays - agree` of [`super::Agreement`]) with the same tolerance.

use glam::Vec3;
use parallax_core::math::floor_i64;
use parallax_core::{Ray, WorldHit, WorldStats, WorldTracer};
use parallax_raster::ldc::image_axes;
use parallax_scene::Scene;
use parallax_screen::ldc::LdcTracer;
use rayon::prelude::*;
use serde::Serialize;

use super::render::Answers;

/// Disagreements per class (module table).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Disagreements {
    pub truncated: u64,
    pub outside: u64,
    pub near: u64,
    pub overhang: u64,
    pub early: u64,
    pub skipped: u64,
    pub uncaptured: u64,
    pub grazing: u64,
    pub edge: u64,
    pub gap: u64,
}

impl Disagreements {
    /// All classes.
    pub fn total(&self) -> u64 {
        self.truncated
            + self.outside
            + self.near
            + self.overhang
            + self.early
            + self.skipped
            + self.uncaptured
            + self.grazing
            + self.edge
            + self.gap
    }

    fn add(&mut self, c: Class) {
        match c {
            Class::Truncated => self.truncated += 1,
            Class::Outside => self.outside += 1,
            Class::Near => self.near += 1,
            Class::Overhang => self.overhang += 1,
            Class::Early => self.early += 1,
            Class::Skipped => self.skipped += 1,
            Class::Uncaptured => self.uncaptured += 1,
            Class::Grazing => self.grazing += 1,
            Class::Edge => self.edge += 1,
            Class::Gap => self.gap += 1,
        }
    }
}

impl std::ops::AddAssign for Disagreements {
    fn add_assign(&mut self, o: Self) {
        self.truncated += o.truncated;
        self.outside += o.outside;
        self.near += o.near;
        self.overhang += o.overhang;
        self.early += o.early;
        self.skipped += o.skipped;
        self.uncaptured += o.uncaptured;
        self.grazing += o.grazing;
        self.edge += o.edge;
        self.gap += o.gap;
    }
}

/// Where a triangle's samples are around a point ([`Classifier::captured`]).
enum Capture {
    Own,
    Neighbour,
    None,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Class {
    Truncated,
    Outside,
    Near,
    Overhang,
    Early,
    Skipped,
    Uncaptured,
    Grazing,
    Edge,
    Gap,
}

/// `sin(10°)`: a ray closer than this to its surface's plane is grazing.
const GRAZING_SIN: f32 = 0.173_648_18;

/// The closest point of triangle `[a, b, c]` to `p` (Ericson, Real-Time Collision Detection,
/// §5.1.5; written out because no dependency of this crate has it).
fn closest_on_triangle(p: Vec3, [a, b, c]: [Vec3; 3]) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if !(denom.abs() > 0.0) {
        return a;
    }
    a + ab * (vb / denom) + ac * (vc / denom)
}

/// The classifier of one cube against the scene (module docs).
pub struct Classifier<'a> {
    pub scene: &'a Scene,
    pub ldc: &'a LdcTracer,
    pub bvh: &'a dyn WorldTracer,
}

impl Classifier<'_> {
    /// Where the cube holds samples of triangle `prim` near `p`, in the LDI the triangle was
    /// assigned to: in `p`'s own pixel, only in one of the 8 around it, or in neither.
    fn captured(&self, prim: u32, p: Vec3) -> Capture {
        let cube = self.ldc.cube();
        let axis = parallax_raster::ldc::dominant_axis(&self.scene.mesh, prim as usize);
        let cap = &cube.ldis[axis].capture;
        let (u, v) = image_axes(axis);
        let s = cube.pixel_size;
        let x = floor_i64((p[u] - cube.bounds.min[u]) / s);
        let y = floor_i64((p[v] - cube.bounds.min[v]) / s);
        let holds = |xx: i64, yy: i64| {
            xx >= 0
                && yy >= 0
                && xx < cap.width() as i64
                && yy < cap.height() as i64
                && cap
                    .range(xx as u32, yy as u32)
                    .any(|i| cap.primitive_id[i] == prim)
        };
        if holds(x, y) {
            return Capture::Own;
        }
        for yy in (y - 1)..=(y + 1) {
            for xx in (x - 1)..=(x + 1) {
                if holds(xx, yy) {
                    return Capture::Neighbour;
                }
            }
        }
        Capture::None
    }

    /// The class of a ray the two tracers answer differently (`bvh`, `ldc`: their closest
    /// hits on it).
    fn class(&self, ray: &Ray, bvh: Option<&WorldHit>, ldc: Option<&WorldHit>) -> Class {
        let cube = self.ldc.cube();
        let mut stats = WorldStats::default();
        self.ldc.closest_hit(ray, &mut stats);
        if stats.truncated > 0 {
            return Class::Truncated;
        }
        let s = cube.pixel_size;
        let eps = self.ldc.options().eps;
        let outside = match bvh {
            Some(h) => !cube.bounds.contains(h.position),
            None => false,
        };
        if outside {
            return Class::Outside;
        }
        if let (Some(b), Some(l)) = (bvh, ldc)
            && b.position.distance(l.position) < s
        {
            return Class::Near;
        }
        let ldc_first = match (bvh, ldc) {
            (_, None) => false,
            (None, Some(_)) => true,
            (Some(b), Some(l)) => l.t < b.t,
        };
        if ldc_first {
            let l = ldc.expect("the LDC hit");
            let tri = self.scene.mesh.triangle(l.prim as usize);
            return if closest_on_triangle(l.position, tri).distance(l.position) > eps {
                Class::Overhang
            } else {
                Class::Early
            };
        }
        let b = bvh.expect("the BVH hit (the LDC's is later or missing)");
        let skip = self.ldc.options().skip * s / ray.dir.length();
        if b.t < ray.t_min + skip {
            return Class::Skipped;
        }
        let n = self.scene.mesh.geometric_normal(b.prim as usize);
        match self.captured(b.prim, b.position) {
            Capture::None => Class::Uncaptured,
            _ if n.dot(ray.dir.normalize()).abs() < GRAZING_SIN => Class::Grazing,
            Capture::Neighbour => Class::Edge,
            Capture::Own => Class::Gap,
        }
    }

    /// The classes of the rays of `rays` on which the LDC (traced here) and `reference` (the
    /// BVH's answers) disagree with agreement distance `tolerance` (the replay's rule).
    pub fn classify(&self, rays: &[Ray], reference: &Answers, tolerance: f32) -> Disagreements {
        let one = |i: usize| -> Option<Class> {
            let ray = &rays[i];
            let mut st = WorldStats::default();
            match reference {
                Answers::Closest(r) => {
                    let o = self.ldc.closest_hit(ray, &mut st);
                    let (r, o) = (r[i].as_ref(), o.as_ref());
                    let agree = match (r, o) {
                        (None, None) => true,
                        (Some(r), Some(o)) => {
                            r.prim == o.prim || r.position.distance(o.position) < tolerance
                        }
                        _ => false,
                    };
                    (!agree).then(|| self.class(ray, r, o))
                }
                Answers::Occluded(r) => {
                    if r[i] == self.ldc.occluded(ray, &mut st) {
                        return None;
                    }
                    let b = self.bvh.closest_hit(ray, &mut st);
                    let l = self.ldc.closest_hit(ray, &mut st);
                    Some(self.class(ray, b.as_ref(), l.as_ref()))
                }
            }
        };
        (0..rays.len())
            .into_par_iter()
            .filter_map(one)
            .fold(Disagreements::default, |mut d, c| {
                d.add(c);
                d
            })
            .reduce(Disagreements::default, |mut a, b| {
                a += b;
                a
            })
    }
}

#[cfg(test)]
mod tests {
    use super::closest_on_triangle;
    use glam::Vec3;

    #[test]
    fn closest_point_on_a_triangle_in_each_region() {
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        // Within float rounding of the exact answer (the projection's arithmetic rounds
        // differently with and without FMA contraction).
        let near = |p: Vec3, want: Vec3| {
            let got = closest_on_triangle(p, t);
            assert!((got - want).length() < 1e-6, "{p}: {got} != {want}");
        };
        near(Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.2, 0.2, 0.0));
        near(Vec3::new(-1.0, -1.0, 0.0), Vec3::ZERO);
        near(Vec3::new(2.0, -0.5, 0.0), Vec3::X);
        near(Vec3::new(0.5, -1.0, 3.0), Vec3::new(0.5, 0.0, 0.0));
        near(Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.5, 0.5, 0.0));
    }
}
