//! Scattering functions for Monte Carlo light transport: evaluation, importance sampling and
//! the sampling pdf of every surface model, shared by every technique that traces paths
//! (the reference path tracer, DIRT's deferred path tracer, the secondary-ray renderer).
//!
//! | model | file | lobes | sampling |
//! |---|---|---|---|
//! | [`Bsdf::Lambert`] | [`lambert`] | diffuse | cosine hemisphere |
//! | [`Bsdf::MetallicRoughness`] | [`microfacet`] | diffuse + GGX reflection (glTF) | lobe mixture: cosine or GGX visible normals (Heitz 2018) |
//! | [`Bsdf::Mirror`] | [`specular`] | delta reflection | deterministic |
//! | [`Bsdf::Dielectric`] | [`specular`] | delta reflection + refraction | Fresnel-weighted choice |
//! | [`Bsdf::ThinDielectric`] | [`specular`] | delta reflection + straight transmission | Fresnel-weighted choice |
//!
//! **Conventions.** All directions are unit vectors in the local shading frame (`z` = shading
//! normal, see [`parallax_core::math::Frame`]) and point away from the surface: `wo` towards
//! the viewer (the previous path vertex), `wi` towards the light (the next vertex). The frame is
//! oriented so that `wo.z >= 0`: every model here is two-sided, and the dielectric is told which
//! side `wo` is on ([`Bsdf::from_surface`], [`Bsdf::flipped`]). Values are for radiance transport
//! (camera paths): refraction scales radiance by `1 / eta^2`.
//!
//! **Invariants** (the tests in `tests/bsdf.rs` check them):
//! - `eval(wo, wi)` is `f(wo, wi) |cos θ_i|`, zero for delta lobes and below the surface;
//! - `pdf(wo, wi)` is the solid-angle density with which `sample` produces `wi` through its
//!   non-delta lobes (it integrates to at most one; a chi-square test holds it against the
//!   histogram of `sample`);
//! - a non-delta sample has `weight == eval / pdf` and `pdf == pdf(wo, wi)`; a delta sample has
//!   `pdf` = the probability of the discrete lobe chosen (as Mitsuba 3 reports it) and `weight`
//!   = lobe value / that probability;
//! - every weight is finite and non-negative.

pub mod lambert;
pub mod microfacet;
pub mod sample;
pub mod specular;

use glam::{Vec2, Vec3};
use parallax_scene::{Material, MaterialKind};

pub use microfacet::MetallicRoughness;
pub use sample::{BsdfSample, luminance};

/// A surface's scattering function (see the module table).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    /// Two-sided Lambertian reflection of `albedo`.
    Lambert { albedo: Vec3 },
    /// glTF metallic-roughness: Lambert base + GGX specular reflection.
    MetallicRoughness(MetallicRoughness),
    /// A perfect mirror tinted by `tint`.
    Mirror { tint: Vec3 },
    /// A smooth interface; `eta` = index on the far side / index on `wo`'s side.
    Dielectric { eta: f32 },
    /// A thin slab of index `ior` in vacuum: reflection with the slab's summed inter-reflections,
    /// the rest passes straight through (Mitsuba 3's `thindielectric`).
    ThinDielectric { ior: f32 },
}

/// How a scene material is turned into a scattering function (`--materials`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MaterialMode {
    /// Each material's own model; glTF glass ([`Material::is_glass`]) as a thin dielectric.
    #[default]
    AsIs,
    /// Every opaque surface a two-sided Lambertian of its base colour (and texture); glass —
    /// dielectrics and glTF glass — a thin dielectric of index 1.5. The model both renderers of
    /// a cross-check can express exactly.
    Diffuse,
}

impl MaterialMode {
    pub const ALL: [MaterialMode; 2] = [MaterialMode::AsIs, MaterialMode::Diffuse];

    pub fn name(self) -> &'static str {
        match self {
            MaterialMode::AsIs => "as-is",
            MaterialMode::Diffuse => "diffuse",
        }
    }

    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == s)
    }
}

/// Index of refraction of the glass that [`MaterialMode::Diffuse`] and glTF glass use.
pub const GLASS_IOR: f32 = 1.5;

/// True when `m` is rendered as glass (a dielectric or glTF glass).
pub fn is_glass(m: &Material) -> bool {
    matches!(m.kind, MaterialKind::Dielectric { .. }) || m.is_glass()
}

impl Bsdf {
    /// The scattering function of material `m` with texture-modulated `albedo`, seen from the
    /// front (`front_face`: the side the triangle's winding calls the front) or the back.
    pub fn from_surface(m: &Material, albedo: Vec3, front_face: bool, mode: MaterialMode) -> Self {
        if mode == MaterialMode::Diffuse {
            return if is_glass(m) {
                Bsdf::ThinDielectric { ior: GLASS_IOR }
            } else {
                Bsdf::Lambert { albedo }
            };
        }
        match m.kind {
            MaterialKind::Dielectric { ior } => Bsdf::Dielectric {
                eta: if front_face { ior } else { 1.0 / ior },
            },
            _ if m.is_glass() => Bsdf::ThinDielectric { ior: GLASS_IOR },
            MaterialKind::Mirror => Bsdf::Mirror { tint: albedo },
            MaterialKind::Standard => {
                Bsdf::MetallicRoughness(MetallicRoughness::new(albedo, m.metallic, m.roughness))
            }
        }
    }

    /// True when the model has a smooth (non-delta) lobe: next-event estimation applies.
    pub fn has_smooth_lobe(&self) -> bool {
        matches!(self, Bsdf::Lambert { .. } | Bsdf::MetallicRoughness(_))
    }

    /// The model seen from the other side of its surface: the same for every two-sided model,
    /// the inverse index for the dielectric interface. Used when `wo` lies behind the shading
    /// normal (interpolated normals at silhouettes): the frame flips and the model with it,
    /// as Mitsuba 3 decides sides by the shading frame.
    pub fn flipped(self) -> Self {
        match self {
            Bsdf::Dielectric { eta } => Bsdf::Dielectric { eta: 1.0 / eta },
            other => other,
        }
    }

    /// `f(wo, wi) |cos θ_i|` of the smooth lobes.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        match self {
            Bsdf::Lambert { albedo } => lambert::eval(*albedo, wo, wi),
            Bsdf::MetallicRoughness(m) => m.eval(wo, wi),
            _ => Vec3::ZERO,
        }
    }

    /// Solid-angle pdf of sampling `wi` through the smooth lobes.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Bsdf::Lambert { .. } => lambert::pdf(wo, wi),
            Bsdf::MetallicRoughness(m) => m.pdf(wo, wi),
            _ => 0.0,
        }
    }

    /// Samples `wi` from `u_lobe` (lobe choice) and `u` (direction), both uniform in `[0, 1)`.
    /// `None` when the sample carries no energy (e.g. a reflection below the horizon).
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            Bsdf::Lambert { albedo } => lambert::sample(*albedo, wo, u),
            Bsdf::MetallicRoughness(m) => m.sample(wo, u_lobe, u),
            Bsdf::Mirror { tint } => specular::sample_mirror(*tint, wo),
            Bsdf::Dielectric { eta } => specular::sample_dielectric(*eta, wo, u_lobe),
            Bsdf::ThinDielectric { ior } => specular::sample_thin_dielectric(*ior, wo, u_lobe),
        }
    }
}
