//! The scene as another renderer reads it, for cross-checks: [`mitsuba`] writes meshes,
//! textures, camera, lights and materials for Mitsuba 3 (`tools/mitsuba_check.py`).

pub mod mitsuba;
