//! Content addresses for the reference cache: a stable 128-bit hash of what a reference image
//! depends on (geometry, materials, textures, lights, camera, frame, sample count, seed and
//! the estimator's options), so that a cached reference is reused exactly when it would be
//! rendered the same.
//!
//! The hash is two SplitMix64 lanes (Steele et al. 2014, the mixer of
//! [`parallax_core::sampling::rng::splitmix64`]) fed 64-bit words; it is not cryptographic
//! (nothing here is adversarial) but it is stable across runs, platforms and compiler
//! versions, which `std`'s `DefaultHasher` does not promise.

use glam::{Vec2, Vec3};
use parallax_core::sampling::rng::splitmix64;
use parallax_scene::{Light, Scene};

/// A 128-bit content hash under construction.
#[derive(Clone, Copy, Debug)]
pub struct Fingerprint {
    a: u64,
    b: u64,
}

impl Default for Fingerprint {
    fn default() -> Self {
        Self::new()
    }
}

impl Fingerprint {
    pub fn new() -> Self {
        Self {
            a: 0x243F_6A88_85A3_08D3,
            b: 0x1319_8A2E_0370_7344,
        }
    }

    #[inline]
    pub fn u64(&mut self, v: u64) -> &mut Self {
        self.a = splitmix64(self.a ^ v);
        self.b = splitmix64(self.b.rotate_left(23) ^ v ^ 0xA076_1D64_78BD_642F);
        self
    }

    #[inline]
    pub fn f32(&mut self, v: f32) -> &mut Self {
        self.u64(v.to_bits() as u64)
    }

    pub fn vec3(&mut self, v: Vec3) -> &mut Self {
        self.u64((v.x.to_bits() as u64) << 32 | v.y.to_bits() as u64)
            .f32(v.z)
    }

    pub fn vec2(&mut self, v: Vec2) -> &mut Self {
        self.u64((v.x.to_bits() as u64) << 32 | v.y.to_bits() as u64)
    }

    pub fn str(&mut self, s: &str) -> &mut Self {
        self.u64(s.len() as u64);
        for chunk in s.as_bytes().chunks(8) {
            let mut w = [0u8; 8];
            w[..chunk.len()].copy_from_slice(chunk);
            self.u64(u64::from_le_bytes(w));
        }
        self
    }

    /// The geometry, materials and textures of `scene` (not its lights: see [`Self::lights`]).
    pub fn scene_content(&mut self, scene: &Scene) -> &mut Self {
        let m = &scene.mesh;
        self.u64(m.positions.len() as u64);
        for &p in &m.positions {
            self.vec3(p);
        }
        for &n in &m.normals {
            self.vec3(n);
        }
        for &uv in &m.uvs {
            self.vec2(uv);
        }
        self.u64(m.indices.len() as u64);
        for (t, id) in m.indices.iter().zip(&m.material_ids) {
            self.u64((t[0] as u64) << 32 | t[1] as u64)
                .u64((t[2] as u64) << 32 | *id as u64);
        }
        for mat in &scene.materials {
            // Every field, through its debug form (new fields change the hash, as they should).
            self.str(&format!("{mat:?}"));
        }
        for tex in &scene.textures {
            self.u64((tex.width as u64) << 32 | tex.height as u64)
                .str(&format!("{:?}{:?}", tex.wrap_s, tex.wrap_t));
            for &t in &tex.texels {
                self.vec3(t);
            }
        }
        self
    }

    /// The analytic lights and the environment of `scene`.
    pub fn lights(&mut self, scene: &Scene) -> &mut Self {
        self.vec3(scene.environment);
        for l in &scene.lights {
            match *l {
                Light::Point {
                    position,
                    intensity,
                } => self.u64(1).vec3(position).vec3(intensity),
                Light::Spot {
                    position,
                    direction,
                    intensity,
                    inner_angle,
                    outer_angle,
                } => self
                    .u64(2)
                    .vec3(position)
                    .vec3(direction)
                    .vec3(intensity)
                    .f32(inner_angle)
                    .f32(outer_angle),
                Light::Directional {
                    direction,
                    irradiance,
                } => self.u64(3).vec3(direction).vec3(irradiance),
            };
        }
        self
    }

    /// The 128-bit value as 32 hex digits.
    pub fn hex(&self) -> String {
        format!("{:016x}{:016x}", self.a, self.b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_content_equal_hash_any_change_another() {
        let s = Scene::load("cornell").unwrap();
        let h = |s: &Scene| Fingerprint::new().scene_content(s).lights(s).hex();
        assert_eq!(h(&s), h(&s.clone()));
        let mut moved = s.clone();
        moved.mesh.positions[0].x += 1e-6;
        assert_ne!(h(&s), h(&moved));
        let mut lit = s.clone();
        lit.environment.y += 0.01;
        assert_ne!(h(&s), h(&lit));
        assert_ne!(
            Fingerprint::new().str("ab").hex(),
            Fingerprint::new().str("ba").hex()
        );
        assert_eq!(h(&s).len(), 32);
    }
}
