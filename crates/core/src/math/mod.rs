//! Geometry on glam: rays, boxes, planes, frusta and the watertight ray-triangle test; an
//! exact integer floor; sine and cosine with bit-identical SIMD twins.

mod aabb;
mod floor;
mod frame;
mod frustum;
mod plane;
mod ray;
mod triangle;
mod trig;

pub use aabb::{Aabb, ROBUST_FAR_SCALE};
pub use floor::{FLOOR_EXACT, floor_i32, floor_i64};
pub use frame::Frame;
pub use frustum::{Containment, Frustum};
pub use plane::Plane;
pub use ray::{Ray, RayDifferential};
pub use triangle::{
    LaneDistance, TriangleHit, WatertightLanes, WatertightRay, dominant_axis, edge_functions,
    intersect_triangle_moller, scaled_distance, shear_vertex, watertight_lanes,
    watertight_permutation,
};
pub use trig::sin_cos_0_pi;
