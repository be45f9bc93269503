//! Built-in procedural scenes, chosen for the papers' workloads.
//!
//! | name      | what it stresses                                                     | triangles |
//! |-----------|----------------------------------------------------------------------|-----------|
//! | `atrium`  | depth discontinuities and disocclusions (columns, arches, banners)   | ~49k      |
//! | `cornell` | global illumination, a mirror and a glass sphere (reflection papers) | ~2.3k     |
//! | `foliage` | depth complexity (leaves, grass, fence slats: 8-20+ layers per ray)  | ~132k     |
//! | `mirrors` | reflections: a closed room with convex, concave and glossy mirrors   | ~9k       |
//! | `mirrors-open` | reflections of what the camera sees: curved mirrors in the open (Widmer Fig. 11) | ~12k |
//!
//! `room:<file>` (and `room-mirror:<file>`, `room-glass:<file>`) stages a model file in a small
//! room with a mirror, a glass sphere and shadow-casting lights ([`room`]).
//!
//! Every scene is generated deterministically (same triangles on every call), is valid
//! ([`Scene::validate`]), has lights, an environment, named cameras and a 60-frame camera path.
//! Objects named `solid:...` are closed, outward-oriented solids (every edge shared by exactly
//! two triangles with opposite orientation); other objects (light quads) are open surfaces.

mod atrium;
mod cameras;
mod cornell;
mod foliage;
mod mirrors;
mod mirrors_open;
pub mod room;
pub mod shapes;

use crate::Scene;

/// Names of the built-in scenes.
pub const NAMES: &[&str] = &["atrium", "cornell", "foliage", "mirrors", "mirrors-open"];

/// A built-in scene by name.
pub fn by_name(name: &str) -> Option<Scene> {
    match name {
        "atrium" => Some(atrium::build()),
        "cornell" => Some(cornell::build()),
        "foliage" => Some(foliage::build()),
        "mirrors" => Some(mirrors::build()),
        "mirrors-open" => Some(mirrors_open::build()),
        _ => None,
    }
}

/// One-line description of a built-in scene (empty for unknown names).
pub fn describe(name: &str) -> &'static str {
    match name {
        "atrium" => {
            "Sponza-like courtyard: two storeys of arcades, banners, open sky (depth discontinuities)"
        }
        "cornell" => "Cornell box with an area light, a mirror box and a glass sphere",
        "foliage" => {
            "trees, grass and a slatted fence: many thin occluders (depth complexity 8-20+)"
        }
        "mirrors" => "a closed room with a convex mirror ball, a concave mirror and a glossy ball",
        "mirrors-open" => {
            "curved mirrors in the open reflecting surroundings the camera sees (Widmer Fig. 11 set-up)"
        }
        _ => "",
    }
}
