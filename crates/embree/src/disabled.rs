//! The API of [`EmbreeScene`] in a build without the `embree` feature: the constructor fails
//! with [`EmbreeError::NotEnabled`] (its message says how to enable Embree), so no value of the
//! type can exist and the query methods are statically unreachable.

use std::convert::Infallible;

use parallax_core::Ray;
use parallax_scene::TriangleMesh;

use crate::{EmbreeError, EmbreeHit, Options};

/// Embree scene (this build has no Embree: see [`crate::ENABLE_HINT`]).
pub struct EmbreeScene {
    never: Infallible,
}

impl EmbreeScene {
    /// Always [`EmbreeError::NotEnabled`] (after the same mesh checks as the real build).
    pub fn new(mesh: &TriangleMesh, _opts: Options) -> Result<Self, EmbreeError> {
        crate::validate(mesh)?;
        Err(EmbreeError::NotEnabled)
    }

    pub fn native_packets(&self) -> [bool; 3] {
        match self.never {}
    }

    pub fn closest_hits(&self, _rays: &[Ray], _out: &mut [Option<EmbreeHit>]) {
        match self.never {}
    }

    pub fn occluded(&self, _rays: &[Ray], _out: &mut [bool]) {
        match self.never {}
    }

    pub fn closest_hit_packets(&self, _rays: &[Ray], _w: usize, _out: &mut [Option<EmbreeHit>]) {
        match self.never {}
    }

    pub fn closest_hit_stream(&self, _r: &[Ray], _c: bool, _out: &mut [Option<EmbreeHit>]) {
        match self.never {}
    }
}
