//! The options of the warp (the module docs of [`super`] say what each does).

use super::hit::Resample;

/// How an occlusion-volume answer is coloured (module docs, "Occlusion-volume fill").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum OcclusionFill {
    /// The colour of the pixel the tracer reports (the crossed pixel).
    Crossed,
    /// The nearest background pixel along the ray's epipolar line (Fig. 6e).
    #[default]
    NearestBackground,
}

/// Options of [`super::warp_view_with`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct WarpOptions {
    pub resample: Resample,
    /// Layer-0 guard part (a) (module docs): an answer from layer 1.. for a ray entering the
    /// reference frustum through a side face behind layer 0 becomes layer 0's occlusion
    /// volume.
    pub side_entry_guard: bool,
    /// Layer-0 guard part (b) (module docs): a hit in layer 1.. is replaced by layer 0's
    /// thin-shell DDA hit when that comes first (rays slipping through layer-0 cracks).
    pub dda_recheck: bool,
    /// Colour of occlusion-volume answers (any layer count).
    pub fill: OcclusionFill,
    /// Layer-0 guard part (d) (module docs): a hit in layer 1.. is kept only when the ray
    /// passed behind a layer-0 silhouette to reach it.
    pub silhouette_check: bool,
    /// Layer-0 guard part (e) (module docs): a hit in layer 1.. is rejected when a layer-0
    /// sample of another surface in its bilinear cell lies between layer 0 and the hit.
    pub nearer_neighbour_check: bool,
}

impl WarpOptions {
    /// Both parts of the layer-0 guard on or off.
    pub fn with_layer0_guard(self, on: bool) -> Self {
        Self {
            side_entry_guard: on,
            dda_recheck: on,
            silhouette_check: on,
            nearer_neighbour_check: on,
            ..self
        }
    }
}

impl Default for WarpOptions {
    fn default() -> Self {
        Self {
            resample: Resample::default(),
            side_entry_guard: true,
            dda_recheck: true,
            fill: OcclusionFill::default(),
            silhouette_check: true,
            nearer_neighbour_check: true,
        }
    }
}
