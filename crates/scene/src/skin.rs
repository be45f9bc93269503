//! glTF node animation and skinning (glTF 2.0 spec §3.5 "Nodes", §3.7.3 "Skins", §3.11
//! "Animations"): the paper's per-frame vertex transform of animated, skinned characters
//! (Hunt et al. 2018, §5.2 stage 1), posing a [`TriangleMesh`] at time `t` from a stored rest
//! pose so that the BVH can be refit (`Bvh::refit`).
//!
//! Per frame: every node's local transform is its rest TRS with the animated components
//! replaced by the active clip's samplers ([`crate::keyframes`]) at `t` modulo the clip
//! duration; world matrices follow the hierarchy (parents first). Then
//! - a mesh instance without skin whose node (or an ancestor) moves is transformed rigidly by
//!   its node's world matrix (normals by its inverse transpose);
//! - a skinned instance is posed by linear blend skinning: with the spec's joint matrix
//!   `J_j = inverse(G_mesh) * G_joint_j * IBM_j` and the mesh node's `G_mesh` applied after it,
//!   the world-space blend is `M = Σ_i w_i G_joint_i IBM_i` (so the mesh node's own transform is
//!   ignored, as the spec requires); `p' = M p`, `n' = normalize(cof(M) n)` (the cofactor matrix
//!   is `det(M)` times the inverse transpose; the sign of `det` is kept, so mirroring blends flip
//!   normals like the loader does).
//!
//! Simplified: morph targets (`weights` channels) are not applied; one clip plays at a time
//! ([`GltfAnimation::clip`], default the first); a winding flip that an animated negative scale
//! would need is not applied (the loader's rest-pose winding is kept; for a skinned mesh that
//! winding follows its node's transform, which skinning otherwise ignores). Single-threaded
//! (`examples/skin_speed.rs`: about 25 ns per 4-influence vertex).

use glam::{Affine3A, Mat3, Mat4, Quat, Vec3, Vec3A, Vec4};

use crate::TriangleMesh;
use crate::error::AnimationError;
use crate::keyframes::Sampler;

/// A node's rest local transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LocalTransform {
    /// A `matrix` node (glTF forbids animating it).
    Matrix(Mat4),
    /// Translation, rotation, scale: `T * R * S`.
    Trs {
        translation: Vec3,
        rotation: Quat,
        scale: Vec3,
    },
}

/// One glTF node of the hierarchy.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    pub parent: Option<u32>,
    pub rest: LocalTransform,
}

/// Which TRS component a channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TargetPath {
    Translation,
    Rotation,
    Scale,
}

/// A sampler driving one component of one node.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    pub node: u32,
    pub path: TargetPath,
    pub sampler: Sampler,
}

/// One glTF animation: channels played together over `[0, duration]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    pub name: String,
    pub channels: Vec<Channel>,
    /// The last keyframe time over all channels (s); time loops over it.
    pub duration: f32,
}

/// A glTF skin: joint nodes and their inverse bind matrices.
#[derive(Clone, Debug, PartialEq)]
pub struct Skin {
    pub name: String,
    pub joints: Vec<u32>,
    /// One per joint (identity when the file gives none).
    pub inverse_bind: Vec<Mat4>,
    /// The skeleton root the file names, if any (informational).
    pub skeleton: Option<u32>,
}

/// Per-vertex skin weights of an instance: `influences` (joint, weight) pairs per vertex,
/// weights non-negative and summing to 1, joints indexing [`Skin::joints`].
#[derive(Clone, Debug, PartialEq)]
pub struct SkinBinding {
    pub skin: u32,
    pub influences: usize,
    pub joints: Vec<u16>,
    pub weights: Vec<f32>,
}

/// A mesh primitive instance whose vertices move: vertices `first_vertex..+local_positions.len()`
/// of the scene mesh, in the node's local space.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// Index into `mesh.objects`.
    pub object: usize,
    pub node: u32,
    pub first_vertex: u32,
    pub local_positions: Vec<Vec3>,
    /// Zero where the file gives no (or a non-finite) normal.
    pub local_normals: Vec<Vec3>,
    pub skin: Option<SkinBinding>,
}

/// The glTF animation of a scene file: nodes, clips, skins and the instances they move.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfAnimation {
    pub nodes: Vec<Node>,
    /// Node indices, parents before children.
    pub order: Vec<u32>,
    pub clips: Vec<Clip>,
    pub skins: Vec<Skin>,
    pub instances: Vec<Instance>,
    /// The clip that plays.
    pub clip: usize,
    /// Vertex count of the mesh this was made for.
    pub vertex_count: usize,
}

fn trs_matrix(t: Vec3, r: Quat, s: Vec3) -> Mat4 {
    Mat4::from_scale_rotation_translation(s, r, t)
}

/// Cofactor matrix of `m` (columns `c1×c2, c2×c0, c0×c1`): `det(m) * inverse(m)^T`, defined for
/// singular `m` too.
fn cofactor(m: Mat3) -> Mat3 {
    Mat3::from_cols(
        m.y_axis.cross(m.z_axis),
        m.z_axis.cross(m.x_axis),
        m.x_axis.cross(m.y_axis),
    )
}

impl GltfAnimation {
    /// True when some clip has a channel and some instance can move (the scene has motion to
    /// play).
    pub fn is_animated(&self) -> bool {
        !self.instances.is_empty() && self.clips.iter().any(|c| !c.channels.is_empty())
    }

    /// The active clip's duration (0 without clips).
    pub fn duration(&self) -> f32 {
        self.clips.get(self.clip).map_or(0.0, |c| c.duration)
    }

    /// Number of vertices that [`Self::apply`] writes.
    pub fn moving_vertices(&self) -> usize {
        self.instances.iter().map(|i| i.local_positions.len()).sum()
    }

    /// World matrices of every node at time `t` of the active clip (looping over its
    /// duration); the rest pose when `t` is `None` or there is no clip.
    pub fn node_worlds(&self, t: Option<f32>) -> Vec<Mat4> {
        let clip = t.and_then(|t| self.clips.get(self.clip).map(|c| (c, t)));
        // Local TRS per node, overridden by the channels.
        let mut local: Vec<LocalTransform> = self.nodes.iter().map(|n| n.rest).collect();
        if let Some((clip, t)) = clip {
            let tc = if clip.duration > 0.0 && t.is_finite() {
                t.rem_euclid(clip.duration)
            } else {
                0.0
            };
            for ch in &clip.channels {
                if let Some(LocalTransform::Trs {
                    translation,
                    rotation,
                    scale,
                }) = local.get_mut(ch.node as usize)
                {
                    match ch.path {
                        TargetPath::Translation => {
                            *translation = ch.sampler.sample_vec(tc).truncate()
                        }
                        TargetPath::Rotation => *rotation = ch.sampler.sample_rotation(tc),
                        TargetPath::Scale => *scale = ch.sampler.sample_vec(tc).truncate(),
                    }
                }
            }
        }
        let mut world = vec![Mat4::IDENTITY; self.nodes.len()];
        for &i in &self.order {
            let i = i as usize;
            let m = match local[i] {
                LocalTransform::Matrix(m) => m,
                LocalTransform::Trs {
                    translation,
                    rotation,
                    scale,
                } => trs_matrix(translation, rotation, scale),
            };
            world[i] = match self.nodes[i].parent {
                Some(p) => world[p as usize] * m,
                None => m,
            };
        }
        world
    }

    /// Poses `mesh` at time `t` (seconds, looping over the active clip). `mesh` must be the mesh
    /// this animation was loaded with (same vertex count). A pose that overflows to a
    /// non-finite vertex is an error ([`AnimationError::NonFinite`]; the mesh is then partly
    /// posed and must be re-posed before use).
    pub fn apply(&self, mesh: &mut TriangleMesh, t: f32) -> Result<(), AnimationError> {
        self.pose(mesh, Some(t))
    }

    /// Poses `mesh` at the nodes' rest transforms (no clip): skinned instances in their rest
    /// skeleton pose.
    pub fn apply_rest(&self, mesh: &mut TriangleMesh) -> Result<(), AnimationError> {
        self.pose(mesh, None)
    }

    fn pose(&self, mesh: &mut TriangleMesh, t: Option<f32>) -> Result<(), AnimationError> {
        if mesh.positions.len() != self.vertex_count || mesh.normals.len() != self.vertex_count {
            return Err(AnimationError::WrongMesh {
                expected: self.vertex_count,
                given: mesh.positions.len(),
            });
        }
        let world = self.node_worlds(t);
        // World-space skinning matrices G_joint * IBM per skin.
        let skin_mats: Vec<Vec<Affine3A>> = self
            .skins
            .iter()
            .map(|s| {
                s.joints
                    .iter()
                    .zip(&s.inverse_bind)
                    .map(|(&j, ibm)| Affine3A::from_mat4(world[j as usize] * *ibm))
                    .collect()
            })
            .collect();
        for inst in &self.instances {
            let r =
                inst.first_vertex as usize..inst.first_vertex as usize + inst.local_positions.len();
            let (pos, nrm) = (&mut mesh.positions[r.clone()], &mut mesh.normals[r]);
            match &inst.skin {
                None => {
                    let m = Affine3A::from_mat4(world[inst.node as usize]);
                    let lin = Mat3::from(m.matrix3);
                    let c = cofactor(lin) * lin.determinant().signum();
                    for (p, l) in pos.iter_mut().zip(&inst.local_positions) {
                        *p = m.transform_point3(*l);
                    }
                    for (n, l) in nrm.iter_mut().zip(&inst.local_normals) {
                        *n = (c * *l).normalize_or_zero();
                    }
                }
                Some(b) => {
                    let mats = &skin_mats[b.skin as usize];
                    let k = b.influences;
                    for (v, ((p, n), (lp, ln))) in pos
                        .iter_mut()
                        .zip(nrm.iter_mut())
                        .zip(inst.local_positions.iter().zip(&inst.local_normals))
                        .enumerate()
                    {
                        let mut x = Vec3A::ZERO;
                        let mut y = Vec3A::ZERO;
                        let mut z = Vec3A::ZERO;
                        let mut w = Vec3A::ZERO;
                        for i in v * k..(v + 1) * k {
                            let wt = b.weights[i];
                            if wt != 0.0 {
                                let m = &mats[b.joints[i] as usize];
                                x += m.matrix3.x_axis * wt;
                                y += m.matrix3.y_axis * wt;
                                z += m.matrix3.z_axis * wt;
                                w += m.translation * wt;
                            }
                        }
                        let lp = Vec3A::from(*lp);
                        *p = Vec3::from(x * lp.x + y * lp.y + z * lp.z + w);
                        let lin = Mat3::from_cols(x.into(), y.into(), z.into());
                        let c = cofactor(lin) * lin.determinant().signum();
                        *n = (c * *ln).normalize_or_zero();
                    }
                }
            }
            // Extreme but finite keyframes or matrices can overflow: never hand a non-finite
            // vertex to the BVH refit.
            if let Some(i) = pos.iter().position(|p| !p.is_finite()) {
                return Err(AnimationError::NonFinite {
                    t: t.unwrap_or(0.0),
                    vertex: inst.first_vertex as usize + i,
                });
            }
        }
        Ok(())
    }

    /// The transform from the rest pose to time `t` is not rigid for skins; this evaluates one
    /// vertex of instance `instance` (for tests and debugging): its world position at `t`.
    pub fn vertex_at(&self, instance: usize, vertex: usize, t: f32) -> Option<Vec3> {
        let inst = self.instances.get(instance)?;
        let lp = *inst.local_positions.get(vertex)?;
        let world = self.node_worlds(Some(t));
        Some(match &inst.skin {
            None => world[inst.node as usize].transform_point3(lp),
            Some(b) => {
                let s = &self.skins[b.skin as usize];
                let mut m = Mat4::ZERO;
                for i in vertex * b.influences..(vertex + 1) * b.influences {
                    let j = b.joints[i] as usize;
                    m += world[s.joints[j] as usize] * s.inverse_bind[j] * b.weights[i];
                }
                (m * Vec4::from((lp, 1.0))).truncate()
            }
        })
    }
}
