//! The thin-lens view of a depth-of-field run and its reference: the pinhole at the lens
//! centre, widened by a guard band so that lens rays near the image border stay inside the
//! captured frustum (Widmer et al. 2015, §5.2 traces lens rays through the reference's layers;
//! how far they stray is the circle of confusion).
//!
//! The guard band is the circle of confusion's largest radius over the scene's depths
//! ([`crate::margin`] with the aperture radius as the baseline and the focus distance as the
//! focal plane). User colour + depth input has no guard band: lens rays leaving it take the
//! environment.

use parallax_bvh::Bvh;
use parallax_scene::Scene;
use parallax_scene::camera::{Pinhole, ThinLens};

use crate::SynthError;
use crate::layers::{Reference, capture_reference};
use crate::margin::{margin_px, widened};
use parallax_render::score::Shading;

/// A thin-lens view and the guard band of its reference.
#[derive(Clone, Debug)]
pub struct DofSetup {
    pub lens: ThinLens,
    /// Pixels added on every side of the reference.
    pub guard: u32,
}

impl DofSetup {
    /// The pinhole at the lens centre with `guard` more pixels on each side: same frame, same
    /// pixel size, same centre. Pixel `(x, y)` of the lens view is `(x + guard, y + guard)`
    /// of this camera.
    pub fn reference_camera(&self) -> Pinhole {
        widened(&self.lens.pinhole, self.guard, self.guard)
    }
}

/// The guard band of `lens` over the scene of `bvh`: its largest circle of confusion
/// ([`margin_px`]).
pub fn guard_px(bvh: &Bvh, lens: &ThinLens) -> u32 {
    margin_px(
        bvh,
        &lens.pinhole,
        lens.aperture_radius,
        lens.focus_distance,
    )
}

/// The guarded reference of `setup` with `layers` layers (`T_ref` in its times).
pub fn capture_dof_reference(
    scene: &Scene,
    bvh: &Bvh,
    setup: &DofSetup,
    layers: usize,
    shading: Shading,
    seed: u64,
) -> Result<Reference, SynthError> {
    if !(1..=8).contains(&layers) {
        return Err(SynthError::Invalid(format!(
            "layers must be in 1..=8, got {layers}"
        )));
    }
    capture_reference(scene, bvh, &setup.reference_camera(), layers, shading, seed)
}
