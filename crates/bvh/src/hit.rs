//! The answer of a ray query: which triangle, where along the ray, where on the triangle.

/// A ray-triangle hit: the scene's triangle index, the ray parameter and the barycentrics of the
/// triangle's vertices 1 and 2 (`P = (1 - u - v) * p0 + u * p1 + v * p2`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub prim: u32,
    pub t: f32,
    pub u: f32,
    pub v: f32,
}
