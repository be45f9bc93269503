//! Light sampling for the reference renderer: analytic lights and emissive triangles.

use glam::{Vec2, Vec3};
use parallax_scene::{Light, Scene};

/// Emissive triangles with a CDF proportional to emitted power (area x luminance), for next-event
/// estimation.
#[derive(Clone, Debug, Default)]
pub struct EmitterSampler {
    /// Scene triangle index of each emitter.
    pub triangles: Vec<u32>,
    /// Inclusive prefix sums of power, normalised to end at 1.
    cdf: Vec<f32>,
    /// Probability of choosing each emitter.
    pmf: Vec<f32>,
    areas: Vec<f32>,
}

/// A point sampled on an emitter.
#[derive(Clone, Copy, Debug)]
pub struct EmitterSample {
    /// Scene triangle the point lies on.
    pub prim: u32,
    pub position: Vec3,
    pub normal: Vec3,
    pub radiance: Vec3,
    /// Probability density of the point per unit area.
    pub pdf_area: f32,
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

impl EmitterSampler {
    pub fn new(scene: &Scene) -> Self {
        let mesh = &scene.mesh;
        let mut s = Self::default();
        let mut total = 0.0f32;
        let mut weights = Vec::new();
        for (i, &m) in mesh.material_ids.iter().enumerate() {
            let mat = &scene.materials[m as usize];
            if !mat.is_emissive() {
                continue;
            }
            let [a, b, c] = mesh.triangle(i);
            let area = 0.5 * (b - a).cross(c - a).length();
            let w = area * luminance(mat.emissive);
            if w <= 0.0 || !w.is_finite() {
                continue;
            }
            s.triangles.push(i as u32);
            s.areas.push(area);
            weights.push(w);
            total += w;
        }
        let mut acc = 0.0;
        for w in weights {
            acc += w / total;
            s.cdf.push(acc);
            s.pmf.push(w / total);
        }
        if let Some(last) = s.cdf.last_mut() {
            *last = 1.0;
        }
        s
    }

    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The area density with which [`Self::sample`] picks a point on scene triangle `prim`
    /// (choice probability / area), `None` when `prim` is not an emitter. The MIS weight of a
    /// BSDF-sampled ray that hits an emitter needs it.
    pub fn pdf_area(&self, prim: u32) -> Option<f32> {
        // `triangles` is in increasing scene order (built by one pass over the triangles).
        let k = self.triangles.binary_search(&prim).ok()?;
        Some(self.pmf[k] / self.areas[k])
    }

    /// Picks an emitter by power and a uniform point on it (`u` in [0,1)^3).
    pub fn sample(&self, scene: &Scene, u_pick: f32, u_tri: Vec2) -> Option<EmitterSample> {
        if self.is_empty() {
            return None;
        }
        let k = self
            .cdf
            .partition_point(|&c| c <= u_pick)
            .min(self.cdf.len() - 1);
        let tri = self.triangles[k] as usize;
        let [a, b, c] = scene.mesh.triangle(tri);
        // Uniform barycentrics (Turk 1990): sqrt-warp.
        let su = u_tri.x.sqrt();
        let (b1, b2) = (1.0 - su, u_tri.y * su);
        let position = a * b1 + b * b2 + c * (1.0 - b1 - b2);
        let normal = scene.mesh.geometric_normal(tri);
        let radiance = scene.materials[scene.mesh.material_ids[tri] as usize].emissive;
        Some(EmitterSample {
            prim: tri as u32,
            position,
            normal,
            radiance,
            pdf_area: self.pmf[k] / self.areas[k],
        })
    }
}

/// Incident radiance-times-solid-angle from an analytic light at point `p`: the direction to
/// the light, the distance (inf for directional) and the irradiance arriving perpendicular to
/// that direction.
pub fn analytic_light_at(light: &Light, p: Vec3) -> Option<(Vec3, f32, Vec3)> {
    match *light {
        Light::Point {
            position,
            intensity,
        } => {
            let d = position - p;
            let dist2 = d.length_squared();
            (dist2 > 0.0).then(|| {
                let dist = dist2.sqrt();
                (d / dist, dist, intensity / dist2)
            })
        }
        Light::Spot {
            position,
            direction,
            intensity,
            inner_angle,
            outer_angle,
        } => {
            let d = position - p;
            let dist2 = d.length_squared();
            if dist2 <= 0.0 {
                return None;
            }
            let dist = dist2.sqrt();
            let wi = d / dist;
            // KHR_lights_punctual's smooth cone falloff.
            let cos = (-wi).dot(direction.normalize_or_zero());
            let (co, ci) = (outer_angle.cos(), inner_angle.cos());
            let t = ((cos - co) / (ci - co).max(1e-4)).clamp(0.0, 1.0);
            let falloff = t * t;
            (falloff > 0.0).then(|| (wi, dist, intensity * falloff / dist2))
        }
        Light::Directional {
            direction,
            irradiance,
        } => {
            let wi = -direction.normalize_or_zero();
            (wi != Vec3::ZERO).then_some((wi, f32::INFINITY, irradiance))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampled_points_report_the_area_pdf_of_their_triangle() {
        let scene = Scene::load("cornell").unwrap();
        let e = EmitterSampler::new(&scene);
        assert!(!e.is_empty());
        let mut total = 0.0;
        for &t in &e.triangles {
            let [a, b, c] = scene.mesh.triangle(t as usize);
            total += e.pdf_area(t).unwrap() * 0.5 * (b - a).cross(c - a).length();
        }
        assert!(
            (total - 1.0).abs() < 1e-5,
            "choice probabilities sum to {total}"
        );
        for i in 0..16 {
            let u = (i as f32 + 0.5) / 16.0;
            let s = e.sample(&scene, u, Vec2::new(u, 1.0 - u)).unwrap();
            assert_eq!(Some(s.pdf_area), e.pdf_area(s.prim));
        }
        let not_emitter = (0..scene.mesh.triangle_count() as u32)
            .find(|t| !e.triangles.contains(t))
            .unwrap();
        assert_eq!(e.pdf_area(not_emitter), None);
    }
}
