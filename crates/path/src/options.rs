//! Options of a path-traced render.
//!
//! | name | type | default | meaning |
//! |---|---|---|---|
//! | `spp` | u32 | 16 | samples (paths) per pixel; with a time budget, the most that are taken |
//! | `time_budget` | `Option<f64>` | none | seconds: one more sample of every pixel while, at the rate measured so far, it ends within the budget ([`crate::schedule`]) |
//! | `seed` | u64 | 0 | seed of the per-pixel random streams |
//! | `max_depth` | u32 | 16 | longest path in segments, as Mitsuba 3's `max_depth` (1 = emitters seen directly, 2 = direct light) |
//! | `rr_depth` | u32 | 5 | depth from which Russian roulette may end a path (Mitsuba 3's `rr_depth`) |
//! | `materials` | [`MaterialMode`] | `AsIs` | the scene's materials, or every opaque surface Lambertian |
//! | `env_nee` | f32 | 0 | probability that a vertex connects to the constant environment ([`crate::light_sampler`]) |
//! | `tile` | u32 | 32 | edge of the square pixel tiles one wavefront covers |
//! | `final_nee` | bool | false | the last smooth vertex a path can reach connects to the lights with full weight and ends, instead of sampling a last segment for emission only (same expectation; one closest-hit ray fewer per path: `max_depth` 3 is Mäkitalo et al.'s 1-bounce sample) |

use parallax_render::bsdf::MaterialMode;

use crate::error::{PathError, Result};

/// Most samples per pixel one render takes.
pub const MAX_SPP: u32 = 1 << 20;
/// Longest path (segments) accepted by `max_depth`.
pub const MAX_DEPTH: u32 = 1024;
/// Tile edges accepted (pixels).
pub const TILE_RANGE: std::ops::RangeInclusive<u32> = 1..=256;

/// See the module table.
#[derive(Clone, Debug, PartialEq)]
pub struct PathOptions {
    pub spp: u32,
    pub time_budget: Option<f64>,
    pub seed: u64,
    pub max_depth: u32,
    pub rr_depth: u32,
    pub materials: MaterialMode,
    pub env_nee: f32,
    pub tile: u32,
    pub final_nee: bool,
}

impl Default for PathOptions {
    fn default() -> Self {
        Self {
            spp: 16,
            time_budget: None,
            seed: 0,
            max_depth: 16,
            rr_depth: 5,
            materials: MaterialMode::AsIs,
            env_nee: crate::light_sampler::DEFAULT_ENV_NEE,
            tile: 32,
            final_nee: false,
        }
    }
}

impl PathOptions {
    /// Checks every range; the message names the CLI flag.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(PathError::Option(m));
        if !(1..=MAX_SPP).contains(&self.spp) {
            return bad(format!("--spp must be in 1..={MAX_SPP}, got {}", self.spp));
        }
        if let Some(t) = self.time_budget
            && !(t.is_finite() && t > 0.0)
        {
            return bad(format!(
                "--time-budget must be a positive number of seconds, got {t}"
            ));
        }
        if !(1..=MAX_DEPTH).contains(&self.max_depth) {
            return bad(format!(
                "--max-depth must be in 1..={MAX_DEPTH}, got {}",
                self.max_depth
            ));
        }
        if !(0.0..=1.0).contains(&self.env_nee) {
            return bad(format!("--env-nee must be in [0, 1], got {}", self.env_nee));
        }
        if self.rr_depth == 0 {
            return bad("--rr-depth must be at least 1".into());
        }
        if !TILE_RANGE.contains(&self.tile) {
            return bad(format!(
                "tile edge must be in {}..={}, got {}",
                TILE_RANGE.start(),
                TILE_RANGE.end(),
                self.tile
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_checked_with_the_flag_named() {
        assert!(PathOptions::default().validate().is_ok());
        let err = |o: PathOptions| o.validate().unwrap_err().to_string();
        assert!(
            err(PathOptions {
                spp: 0,
                ..Default::default()
            })
            .contains("--spp")
        );
        assert!(
            err(PathOptions {
                time_budget: Some(0.0),
                ..Default::default()
            })
            .contains("--time-budget")
        );
        assert!(
            err(PathOptions {
                time_budget: Some(f64::NAN),
                ..Default::default()
            })
            .contains("--time-budget")
        );
        assert!(
            err(PathOptions {
                max_depth: 0,
                ..Default::default()
            })
            .contains("--max-depth")
        );
        assert!(
            err(PathOptions {
                rr_depth: 0,
                ..Default::default()
            })
            .contains("--rr-depth")
        );
        assert!(
            err(PathOptions {
                tile: 0,
                ..Default::default()
            })
            .contains("tile")
        );
    }
}
