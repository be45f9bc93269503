//! What the secondary-ray renderer is asked for: the effects, the bounce limit, and its errors.

use serde::Serialize;

/// Largest `bounces`.
pub const MAX_BOUNCES: u32 = 16;

/// A kind of secondary ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum Effect {
    /// Mirror reflections (also the reflected part at glass, and total internal reflection).
    Reflect,
    /// Refraction through glass.
    Refract,
    /// Shadow rays to lights.
    Shadow,
}

impl Effect {
    pub const ALL: [Effect; 3] = [Effect::Reflect, Effect::Refract, Effect::Shadow];

    pub fn name(self) -> &'static str {
        match self {
            Effect::Reflect => "reflect",
            Effect::Refract => "refract",
            Effect::Shadow => "shadow",
        }
    }
}

/// Which effects are traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Effects {
    pub reflect: bool,
    pub refract: bool,
    pub shadow: bool,
}

impl Default for Effects {
    fn default() -> Self {
        Self {
            reflect: true,
            refract: true,
            shadow: true,
        }
    }
}

impl Effects {
    /// A comma list of `reflect`, `refract`, `shadow` (or `all`).
    pub fn parse(list: &str) -> Result<Self, SecondaryError> {
        let mut e = Self {
            reflect: false,
            refract: false,
            shadow: false,
        };
        for w in list.split(',').map(str::trim).filter(|w| !w.is_empty()) {
            match w {
                "reflect" => e.reflect = true,
                "refract" => e.refract = true,
                "shadow" => e.shadow = true,
                "all" => e = Self::default(),
                _ => {
                    return Err(SecondaryError::InvalidOptions(format!(
                        "unknown effect {w:?} (expected reflect, refract, shadow or all)"
                    )));
                }
            }
        }
        Ok(e)
    }

    pub fn has(&self, effect: Effect) -> bool {
        match effect {
            Effect::Reflect => self.reflect,
            Effect::Refract => self.refract,
            Effect::Shadow => self.shadow,
        }
    }
}

/// Renderer options (module table).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SecondaryOptions {
    pub effects: Effects,
    pub bounces: u32,
}

impl Default for SecondaryOptions {
    fn default() -> Self {
        Self {
            effects: Effects::default(),
            bounces: 4,
        }
    }
}

impl SecondaryOptions {
    pub fn validate(&self) -> Result<(), SecondaryError> {
        if self.bounces > MAX_BOUNCES {
            return Err(SecondaryError::InvalidOptions(format!(
                "bounces must be at most {MAX_BOUNCES}, got {}",
                self.bounces
            )));
        }
        Ok(())
    }
}

/// Errors of the secondary-ray renderer.
#[derive(Debug, thiserror::Error)]
pub enum SecondaryError {
    #[error("invalid secondary-ray options: {0}")]
    InvalidOptions(String),
    #[error("the secondary-ray renderer needs a pinhole camera (primary hits are rasterized)")]
    NotPinhole,
    #[error(transparent)]
    Raster(#[from] parallax_raster::RasterError),
    #[error(transparent)]
    Tracer(#[from] crate::PathError),
    #[error(transparent)]
    Core(#[from] parallax_core::CoreError),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn effects_parse() {
        let e = Effects::parse("reflect, shadow").unwrap();
        assert!(e.reflect && e.shadow && !e.refract);
        assert_eq!(Effects::parse("all").unwrap(), Effects::default());
        assert!(Effects::parse("glow").is_err());
        let bad = SecondaryOptions {
            bounces: MAX_BOUNCES + 1,
            ..SecondaryOptions::default()
        };
        assert!(bad.validate().is_err());
    }
}
