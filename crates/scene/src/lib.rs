//! parallax-scene: what is rendered and from where.
//!
//! Triangle meshes in world space ([`TriangleMesh`]), materials, textures, lights, camera models
//! ([`camera`]), keyframed camera paths, loaders for glTF 2.0, OBJ+MTL and PLY ([`load`]), and the
//! built-in procedural scenes ([`builtin`]).
//!
//! **Invariant:** a [`Scene`] that a loader or a built-in returns is valid: every index is in
//! range, every position finite, every material id names a material. Later layers rely on it.

pub mod animation;
pub mod builtin;
pub mod camera;
pub mod camera_desc;
pub mod error;
pub mod keyframes;
pub mod light;
pub mod load;
pub mod material;
pub mod mesh;
pub mod path;
pub mod scene;
pub mod skin;
pub mod texture;

pub use camera_desc::{CameraDesc, NamedCamera};
pub use error::{Result, SceneError};
pub use light::Light;
pub use material::{AlphaMode, Material, MaterialKind};
pub use mesh::{ObjectRange, TriangleMesh};
pub use path::{CameraKey, CameraPath};
pub use scene::{AnimationInfo, Scene};
pub use texture::{Texture, WrapMode};
