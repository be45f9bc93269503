//! An optional record of every ray a render traced, bounce by bounce: what the structures
//! behind the tracer interface are compared on (same rays, same primitive?) and what benches
//! replay.
//!
//! **Invariant:** the order is deterministic: tile by tile in film order, then sample, bounce,
//! and the wavefront's path order (pixel order, channel order), so two renders of the same
//! scene, camera and options give records that can be compared entry by entry as long as their
//! hits agree.

use parallax_core::Ray;

/// One closest-hit ray and its answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayRecord {
    pub sample: u32,
    pub bounce: u32,
    /// Image pixel.
    pub x: u32,
    pub y: u32,
    pub channel: u8,
    pub ray: Ray,
    /// Primitive hit, [`parallax_core::NO_ID`] for a miss or an unknown primitive.
    pub prim: u32,
    /// Ray parameter of the hit, infinite for a miss.
    pub t: f32,
}

/// One shadow ray and its answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowRecord {
    pub sample: u32,
    /// Bounce of the vertex the shadow ray leaves.
    pub bounce: u32,
    pub x: u32,
    pub y: u32,
    pub ray: Ray,
    pub occluded: bool,
}

/// Every ray of a render.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PathRecord {
    pub rays: Vec<RayRecord>,
    pub shadows: Vec<ShadowRecord>,
}

impl PathRecord {
    pub fn append(&mut self, mut o: PathRecord) {
        self.rays.append(&mut o.rays);
        self.shadows.append(&mut o.shadows);
    }

    /// The closest-hit rays of bounce `b`.
    pub fn bounce(&self, b: u32) -> impl Iterator<Item = &RayRecord> {
        self.rays.iter().filter(move |r| r.bounce == b)
    }
}
