//! Per-frame vertex animation (Hunt et al. 2018, §5.2 stage 1 "transform vertices"): rigid
//! motion of whole objects ([`ObjectRange`]s) of a [`TriangleMesh`], applied in place to
//! positions and normals from a stored rest pose, so that the BVH can be refit (not rebuilt)
//! every frame (`Bvh::refit`, §5.2 stages 2-4).
//!
//! What moves ([`RigidAnimation::for_scene`]): the "props" of a scene — built-in objects whose
//! name marks them as movable (spheres, boxes, crates, banners, shrubs, planters), or, for scene
//! files, the objects whose bounds are small against the scene (diagonal under 10 % of the
//! scene's, at most [`MAX_DEFAULT_TRACKS`]). Each selected object `k` spins about the vertical
//! axis through its rest-pose centre at `SPIN_RAD_PER_S * (1 + 0.25 k mod 3)` rad/s and bobs
//! vertically with amplitude `BOB_FRACTION` of its size at `BOB_HZ` Hz, phase-shifted by
//! object. Motion is a function of time `t` (seconds), not of the previous frame: frame `t` is
//! always rest pose × transform(t), so errors never accumulate.
//!
//! glTF files with animation clips are posed by their own animation instead
//! ([`crate::skin::GltfAnimation`]: node TRS channels, rigid node motion and linear blend
//! skinning, the paper's animated characters). [`Animation`] is the choice between the two
//! ([`Animation::for_scene`]), applied the same way ([`Animate`]).

use std::sync::Arc;

use glam::{Affine3A, Mat3, Vec3};

use crate::skin::GltfAnimation;
use crate::{ObjectRange, Scene, TriangleMesh};

/// Something that poses a mesh at time `t` (seconds) from its rest pose.
pub trait Animate {
    fn apply(&self, mesh: &mut TriangleMesh, t: f32) -> Result<(), AnimationError>;
}

/// The animation of a scene: its glTF clips and skins when the file has any that move
/// geometry, else the rigid props animation.
#[derive(Clone, Debug)]
pub enum Animation {
    Rigid(RigidAnimation),
    Gltf(Arc<GltfAnimation>),
}

impl Animation {
    /// glTF animation when the scene carries one that moves vertices
    /// ([`GltfAnimation::is_animated`]), else [`RigidAnimation::for_scene`].
    pub fn for_scene(scene: &Scene) -> Self {
        match &scene.gltf_animation {
            Some(g) if g.is_animated() => Animation::Gltf(g.clone()),
            _ => Animation::Rigid(RigidAnimation::for_scene(scene)),
        }
    }

    /// Poses `mesh` at time `t` from the rest pose.
    pub fn apply(&self, mesh: &mut TriangleMesh, t: f32) -> Result<(), AnimationError> {
        match self {
            Animation::Rigid(a) => a.apply(mesh, t),
            Animation::Gltf(a) => a.apply(mesh, t),
        }
    }

    /// Moving objects: rigid tracks, or glTF instances that move.
    pub fn moving_objects(&self) -> usize {
        match self {
            Animation::Rigid(a) => a.tracks.len(),
            Animation::Gltf(a) => a.instances.len(),
        }
    }

    /// Number of vertices written per frame.
    pub fn moving_vertices(&self, mesh: &TriangleMesh) -> usize {
        match self {
            Animation::Rigid(a) => a.moving_vertices(mesh),
            Animation::Gltf(a) => a.moving_vertices(),
        }
    }

    /// "rigid" or "gltf".
    pub fn kind(&self) -> &'static str {
        match self {
            Animation::Rigid(_) => "rigid",
            Animation::Gltf(_) => "gltf",
        }
    }
}

impl Animate for Animation {
    fn apply(&self, mesh: &mut TriangleMesh, t: f32) -> Result<(), AnimationError> {
        Animation::apply(self, mesh, t)
    }
}

impl Animate for RigidAnimation {
    fn apply(&self, mesh: &mut TriangleMesh, t: f32) -> Result<(), AnimationError> {
        RigidAnimation::apply(self, mesh, t)
    }
}

impl Animate for GltfAnimation {
    fn apply(&self, mesh: &mut TriangleMesh, t: f32) -> Result<(), AnimationError> {
        GltfAnimation::apply(self, mesh, t)
    }
}

pub use crate::error::AnimationError;

/// Base spin rate of an animated object (rad/s).
pub const SPIN_RAD_PER_S: f32 = 0.8;
/// Vertical bob amplitude as a fraction of the object's bounding-box diagonal.
pub const BOB_FRACTION: f32 = 0.1;
/// Vertical bob frequency (Hz).
pub const BOB_HZ: f32 = 0.5;
/// Most objects the default selection of a scene file animates.
pub const MAX_DEFAULT_TRACKS: usize = 16;
/// Name fragments of built-in objects that move.
pub const MOVABLE_NAMES: &[&str] = &[
    "sphere",
    "tall_box",
    "short_box",
    "crate",
    "banner",
    "shrub",
    "planter",
];

/// The motion of one object: spin about the vertical axis through `pivot`, and bob.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObjectTrack {
    /// Index into `mesh.objects`.
    pub object: usize,
    /// Rest-pose centre of the object (the spin axis passes through it).
    pub pivot: Vec3,
    /// Spin rate (rad/s) about +Y.
    pub spin: f32,
    /// Vertical bob amplitude (m).
    pub bob: f32,
    /// Bob phase (rad).
    pub phase: f32,
}

impl ObjectTrack {
    /// The object's transform at time `t` (seconds) relative to its rest pose.
    pub fn transform(&self, t: f32) -> Affine3A {
        let rot = Mat3::from_rotation_y(self.spin * t);
        // Zero at t = 0 whatever the phase: frame 0 is the rest pose.
        let w = std::f32::consts::TAU * BOB_HZ * t;
        let lift = Vec3::Y * (self.bob * ((w + self.phase).sin() - self.phase.sin()));
        // p' = R (p - pivot) + pivot + lift
        Affine3A::from_mat3_translation(rot, self.pivot + lift - rot * self.pivot)
    }
}

/// Rigid animation of selected objects of a mesh, with the rest pose it started from.
#[derive(Clone, Debug)]
pub struct RigidAnimation {
    pub tracks: Vec<ObjectTrack>,
    rest_positions: Vec<Vec3>,
    rest_normals: Vec<Vec3>,
}

fn object_bounds(mesh: &TriangleMesh, o: &ObjectRange) -> parallax_core::Aabb {
    let r = o.first_vertex as usize..(o.first_vertex + o.vertex_count) as usize;
    parallax_core::Aabb::from_points(mesh.positions[r].iter().copied())
}

impl RigidAnimation {
    /// Animates the objects `objects` (indices into `mesh.objects`) of `mesh` with the default
    /// motion (module docs). Errors on an out-of-range object or an object whose vertex range
    /// exceeds the mesh.
    pub fn new(mesh: &TriangleMesh, objects: &[usize]) -> Result<Self, AnimationError> {
        let mut tracks = Vec::with_capacity(objects.len());
        for (k, &i) in objects.iter().enumerate() {
            let o = mesh.objects.get(i).ok_or(AnimationError::NoSuchObject {
                index: i,
                count: mesh.objects.len(),
            })?;
            if (o.first_vertex as usize + o.vertex_count as usize) > mesh.positions.len() {
                return Err(AnimationError::VerticesOutOfRange(o.name.clone()));
            }
            let b = object_bounds(mesh, o);
            let (pivot, size) = if b.is_empty() {
                (Vec3::ZERO, 0.0)
            } else {
                (b.center(), b.extent().length())
            };
            tracks.push(ObjectTrack {
                object: i,
                pivot,
                spin: SPIN_RAD_PER_S * (1.0 + 0.25 * (k % 3) as f32),
                bob: BOB_FRACTION * size,
                phase: k as f32 * 1.3,
            });
        }
        Ok(Self {
            tracks,
            rest_positions: mesh.positions.clone(),
            rest_normals: mesh.normals.clone(),
        })
    }

    /// The default selection of a scene (module docs): movable built-in objects by name, else
    /// small objects.
    pub fn for_scene(scene: &Scene) -> Self {
        let mesh = &scene.mesh;
        let mut objects: Vec<usize> = mesh
            .objects
            .iter()
            .enumerate()
            .filter(|(_, o)| MOVABLE_NAMES.iter().any(|n| o.name.contains(n)))
            .map(|(i, _)| i)
            .collect();
        if objects.is_empty() {
            let diag = mesh.bounds().extent().length();
            objects = mesh
                .objects
                .iter()
                .enumerate()
                .filter(|(_, o)| {
                    o.vertex_count > 0 && object_bounds(mesh, o).extent().length() < 0.1 * diag
                })
                .map(|(i, _)| i)
                .take(MAX_DEFAULT_TRACKS)
                .collect();
        }
        Self::new(mesh, &objects).expect("selected objects are in range")
    }

    /// Number of vertices that move.
    pub fn moving_vertices(&self, mesh: &TriangleMesh) -> usize {
        self.tracks
            .iter()
            .map(|t| mesh.objects[t.object].vertex_count as usize)
            .sum()
    }

    /// Poses `mesh` at time `t`: every animated object's positions and normals become its rest
    /// pose under its transform. `mesh` must be the mesh the animation was made from (same
    /// vertex count); errors otherwise.
    pub fn apply(&self, mesh: &mut TriangleMesh, t: f32) -> Result<(), AnimationError> {
        if mesh.positions.len() != self.rest_positions.len()
            || mesh.normals.len() != self.rest_normals.len()
        {
            return Err(AnimationError::WrongMesh {
                expected: self.rest_positions.len(),
                given: mesh.positions.len(),
            });
        }
        for track in &self.tracks {
            let o = &mesh.objects[track.object];
            let r = o.first_vertex as usize..(o.first_vertex + o.vertex_count) as usize;
            let m = track.transform(t);
            for (p, rest) in mesh.positions[r.clone()]
                .iter_mut()
                .zip(&self.rest_positions[r.clone()])
            {
                *p = m.transform_point3(*rest);
            }
            // Rotation only: normals stay unit (a zero normal stays zero).
            for (n, rest) in mesh.normals[r.clone()]
                .iter_mut()
                .zip(&self.rest_normals[r])
            {
                *n = m.transform_vector3(*rest);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_select_their_props_and_time_zero_is_the_rest_pose() {
        for name in ["cornell", "atrium"] {
            let scene = crate::builtin::by_name(name).unwrap();
            let anim = RigidAnimation::for_scene(&scene);
            assert!(!anim.tracks.is_empty(), "{name}");
            let mut mesh = scene.mesh.clone();
            anim.apply(&mut mesh, 0.0).unwrap();
            for (a, b) in mesh.positions.iter().zip(&scene.mesh.positions) {
                assert!((*a - *b).length() < 1e-4, "{name}: {a} vs {b}");
            }
            anim.apply(&mut mesh, 1.0).unwrap();
            let moved = mesh
                .positions
                .iter()
                .zip(&scene.mesh.positions)
                .filter(|(a, b)| (**a - **b).length() > 1e-3)
                .count();
            assert!(moved > 0 && moved <= anim.moving_vertices(&mesh), "{name}");
            assert!(mesh.validate(scene.materials.len()).is_ok());
        }
    }

    #[test]
    fn motion_is_rigid() {
        let scene = crate::builtin::by_name("cornell").unwrap();
        let anim = RigidAnimation::for_scene(&scene);
        let mut mesh = scene.mesh.clone();
        anim.apply(&mut mesh, 2.3).unwrap();
        for track in &anim.tracks {
            let o = &mesh.objects[track.object];
            let a = o.first_vertex as usize;
            let b = a + o.vertex_count as usize - 1;
            let d0 = (scene.mesh.positions[a] - scene.mesh.positions[b]).length();
            let d1 = (mesh.positions[a] - mesh.positions[b]).length();
            assert!((d0 - d1).abs() < 1e-4, "{}: {d0} vs {d1}", o.name);
        }
        let mut other = TriangleMesh::default();
        assert!(anim.apply(&mut other, 0.0).is_err());
    }
}
