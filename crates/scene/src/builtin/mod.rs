//! Built-in procedural scenes, chosen for the papers' workloads.

use crate::Scene;

/// Names of the built-in scenes.
pub const NAMES: [&str; 0] = [];

/// A built-in scene by name.
pub fn by_name(name: &str) -> Option<Scene> {
    let _ = name;
    None
}
