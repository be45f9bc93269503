//! Reading glTF animation data into a [`GltfAnimation`]: the node hierarchy with rest TRS,
//! animation clips (glTF 2.0 spec §3.11), skins (§3.7.3: joints, inverse bind matrices) and the
//! per-vertex `JOINTS_n` / `WEIGHTS_n` of skinned primitives, plus the local-space vertices of
//! every primitive instance that moves.
//!
//! Malformed data is an error naming the element: joint index out of range, negative or
//! non-finite weights, weights summing to zero, a skinned primitive without `JOINTS_0` /
//! `WEIGHTS_0`, inverse bind matrices missing or non-finite, sampler times not increasing,
//! output counts that do not match, an animated `matrix` node. Weights that do not sum to 1 are
//! renormalised. Morph-target (`weights`) channels are skipped.

use glam::{Mat4, Quat, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::animation::{Interpolation as GInterp, Property};
use gltf::mesh::Semantic;

use super::gltf_accessor::{read_floats, read_uvec4, read_vec};
use crate::keyframes::{Interpolation, Sampler};
use crate::skin::{
    Channel, Clip, GltfAnimation, Instance, LocalTransform, Node, Skin, SkinBinding, TargetPath,
};

/// A primitive instance the loader emitted: `mesh.objects[object]` came from primitive `prim`
/// of mesh `mesh` at node `node`, vertices `first_vertex..+vertex_count`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PrimInstance {
    pub node: usize,
    pub mesh: usize,
    pub prim: usize,
    pub object: usize,
    pub first_vertex: u32,
    pub vertex_count: u32,
}

/// Most `JOINTS_n` / `WEIGHTS_n` sets read per primitive (32 influences).
const MAX_SKIN_SETS: u32 = 8;

/// Builds the animation of `doc`, or `None` when it has no clip and no skinned instance.
pub(crate) fn load_animation(
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    instances: &[PrimInstance],
    vertex_count: usize,
) -> Result<Option<GltfAnimation>, String> {
    if doc.animations().len() == 0 && doc.skins().len() == 0 {
        return Ok(None);
    }
    let (nodes, order) = hierarchy(doc)?;
    let clips = clips(doc, buffers, &nodes)?;
    let skins = skins(doc, buffers)?;
    // Nodes whose world transform can change: targeted ones and their descendants.
    let mut moving = vec![false; nodes.len()];
    for c in &clips {
        for ch in &c.channels {
            moving[ch.node as usize] = true;
        }
    }
    for &i in &order {
        if let Some(p) = nodes[i as usize].parent {
            moving[i as usize] |= moving[p as usize];
        }
    }
    let mut out = Vec::new();
    for pi in instances {
        let node = doc.nodes().nth(pi.node).ok_or("node out of range")?;
        let skin = node.skin();
        if skin.is_none() && !moving[pi.node] {
            continue;
        }
        let prim = doc
            .meshes()
            .nth(pi.mesh)
            .and_then(|m| m.primitives().nth(pi.prim))
            .ok_or("primitive out of range")?;
        let what = format!("mesh {} primitive {} at node {}", pi.mesh, pi.prim, pi.node);
        let n = pi.vertex_count as usize;
        let pos_acc = prim
            .get(&Semantic::Positions)
            .ok_or_else(|| format!("{what}: no POSITION"))?;
        let local_positions: Vec<Vec3> = read_vec::<3>(&pos_acc, buffers, false)
            .map_err(|m| format!("{what}: {m}"))?
            .into_iter()
            .map(Vec3::from)
            .collect();
        let local_normals: Vec<Vec3> = match prim.get(&Semantic::Normals) {
            Some(acc) => read_vec::<3>(&acc, buffers, false)
                .map_err(|m| format!("{what}: {m}"))?
                .into_iter()
                .map(Vec3::from)
                .map(|v| if v.is_finite() { v } else { Vec3::ZERO })
                .collect(),
            None => vec![Vec3::ZERO; n],
        };
        if local_positions.len() != n || local_normals.len() != n {
            return Err(format!("{what}: vertex count changed between reads"));
        }
        let skin = match skin {
            Some(s) => Some(binding(&prim, buffers, s.index() as u32, &skins, n, &what)?),
            None => None,
        };
        out.push(Instance {
            object: pi.object,
            node: pi.node as u32,
            first_vertex: pi.first_vertex,
            local_positions,
            local_normals,
            skin,
        });
    }
    if clips.is_empty() && out.is_empty() {
        return Ok(None);
    }
    Ok(Some(GltfAnimation {
        nodes,
        order,
        clips,
        skins,
        instances: out,
        clip: 0,
        vertex_count,
    }))
}

/// Nodes with parents and rest transforms, and a parents-first order. A node with two parents or
/// a cycle is an error.
fn hierarchy(doc: &gltf::Document) -> Result<(Vec<Node>, Vec<u32>), String> {
    let count = doc.nodes().len();
    let mut nodes = Vec::with_capacity(count);
    for n in doc.nodes() {
        let rest = match n.transform() {
            gltf::scene::Transform::Matrix { matrix } => {
                LocalTransform::Matrix(Mat4::from_cols_array_2d(&matrix))
            }
            gltf::scene::Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => LocalTransform::Trs {
                translation: Vec3::from(translation),
                rotation: Quat::from_array(rotation).normalize(),
                scale: Vec3::from(scale),
            },
        };
        let finite = match rest {
            LocalTransform::Matrix(m) => m.is_finite(),
            LocalTransform::Trs {
                translation,
                rotation,
                scale,
            } => translation.is_finite() && rotation.is_finite() && scale.is_finite(),
        };
        if !finite {
            return Err(format!("node {} has a non-finite transform", n.index()));
        }
        nodes.push(Node { parent: None, rest });
    }
    for n in doc.nodes() {
        for c in n.children() {
            let slot = &mut nodes[c.index()].parent;
            if slot.is_some() || c.index() == n.index() {
                return Err(format!(
                    "node {} has two parents or is its own parent",
                    c.index()
                ));
            }
            *slot = Some(n.index() as u32);
        }
    }
    let mut order = Vec::with_capacity(count);
    let mut stack: Vec<usize> = (0..count).filter(|&i| nodes[i].parent.is_none()).collect();
    while let Some(i) = stack.pop() {
        order.push(i as u32);
        if let Some(n) = doc.nodes().nth(i) {
            stack.extend(n.children().map(|c| c.index()));
        }
    }
    if order.len() != count {
        return Err("the node hierarchy has a cycle".into());
    }
    Ok((nodes, order))
}

fn clips(doc: &gltf::Document, buffers: &[Vec<u8>], nodes: &[Node]) -> Result<Vec<Clip>, String> {
    let mut clips = Vec::new();
    for a in doc.animations() {
        let mut channels = Vec::new();
        for (ci, ch) in a.channels().enumerate() {
            let what = format!("animation {} channel {ci}", a.index());
            let path = match ch.target().property() {
                Property::Translation => TargetPath::Translation,
                Property::Rotation => TargetPath::Rotation,
                Property::Scale => TargetPath::Scale,
                Property::MorphTargetWeights => continue,
            };
            let node = ch.target().node().index();
            if matches!(nodes[node].rest, LocalTransform::Matrix(_)) {
                return Err(format!(
                    "{what}: node {node} has a matrix and cannot be animated (glTF 2.0 §3.11)"
                ));
            }
            let s = ch.sampler();
            let times = read_floats(&s.input(), buffers, Dimensions::Scalar, |ty, _| {
                ty == DataType::F32
            })
            .map_err(|m| format!("{what}: input: {m}"))?;
            let values: Vec<Vec4> = if path == TargetPath::Rotation {
                read_floats(&s.output(), buffers, Dimensions::Vec4, |ty, norm| {
                    ty == DataType::F32 || (norm && ty != DataType::U32)
                })
                .map_err(|m| format!("{what}: output: {m}"))?
                .chunks_exact(4)
                .map(Vec4::from_slice)
                .collect()
            } else {
                read_floats(&s.output(), buffers, Dimensions::Vec3, |ty, _| {
                    ty == DataType::F32
                })
                .map_err(|m| format!("{what}: output: {m}"))?
                .chunks_exact(3)
                .map(|c| Vec4::new(c[0], c[1], c[2], 0.0))
                .collect()
            };
            let interpolation = match s.interpolation() {
                GInterp::Step => Interpolation::Step,
                GInterp::Linear => Interpolation::Linear,
                GInterp::CubicSpline => Interpolation::CubicSpline,
            };
            let sampler = Sampler::new(interpolation, times, values, path == TargetPath::Rotation)
                .map_err(|e| format!("{what}: sampler {}: {e}", s.index()))?;
            channels.push(Channel {
                node: node as u32,
                path,
                sampler,
            });
        }
        let duration = channels
            .iter()
            .map(|c| c.sampler.end())
            .fold(0.0f32, f32::max);
        clips.push(Clip {
            name: a.name().unwrap_or("").to_string(),
            channels,
            duration,
        });
    }
    Ok(clips)
}

fn skins(doc: &gltf::Document, buffers: &[Vec<u8>]) -> Result<Vec<Skin>, String> {
    let mut out = Vec::new();
    for s in doc.skins() {
        let what = format!("skin {}", s.index());
        let joints: Vec<u32> = s.joints().map(|j| j.index() as u32).collect();
        if joints.len() > u16::MAX as usize + 1 {
            return Err(format!("{what}: {} joints (at most 65536)", joints.len()));
        }
        let inverse_bind = match s.inverse_bind_matrices() {
            Some(acc) => {
                let m = read_floats(&acc, buffers, Dimensions::Mat4, |ty, _| ty == DataType::F32)
                    .map_err(|m| format!("{what}: inverse bind matrices: {m}"))?;
                if m.len() < joints.len() * 16 {
                    return Err(format!(
                        "{what}: {} inverse bind matrices for {} joints",
                        m.len() / 16,
                        joints.len()
                    ));
                }
                if m.iter().any(|v| !v.is_finite()) {
                    return Err(format!("{what}: a non-finite inverse bind matrix"));
                }
                m.chunks_exact(16)
                    .take(joints.len())
                    .map(Mat4::from_cols_slice)
                    .collect()
            }
            None => vec![Mat4::IDENTITY; joints.len()],
        };
        out.push(Skin {
            name: s.name().unwrap_or("").to_string(),
            joints,
            inverse_bind,
            skeleton: s.skeleton().map(|n| n.index() as u32),
        });
    }
    Ok(out)
}

/// Reads `JOINTS_n` / `WEIGHTS_n` (n = 0, 1, ...) of a skinned primitive with `n_vert` vertices.
fn binding(
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    skin: u32,
    skins: &[Skin],
    n_vert: usize,
    what: &str,
) -> Result<SkinBinding, String> {
    let joint_count = skins[skin as usize].joints.len();
    let mut sets = Vec::new();
    for set in 0..MAX_SKIN_SETS {
        match (
            prim.get(&Semantic::Joints(set)),
            prim.get(&Semantic::Weights(set)),
        ) {
            (None, None) => break,
            (Some(j), Some(w)) => {
                let j =
                    read_uvec4(&j, buffers).map_err(|m| format!("{what}: JOINTS_{set}: {m}"))?;
                let w = read_floats(&w, buffers, Dimensions::Vec4, |ty, norm| {
                    ty == DataType::F32 || (norm && matches!(ty, DataType::U8 | DataType::U16))
                })
                .map_err(|m| format!("{what}: WEIGHTS_{set}: {m}"))?;
                if j.len() != n_vert || w.len() != 4 * n_vert {
                    return Err(format!(
                        "{what}: JOINTS_{set} / WEIGHTS_{set} have {} / {} elements for {n_vert} vertices",
                        j.len(),
                        w.len() / 4
                    ));
                }
                sets.push((j, w));
            }
            _ => {
                return Err(format!(
                    "{what}: JOINTS_{set} and WEIGHTS_{set} must come together"
                ));
            }
        }
    }
    if sets.is_empty() {
        return Err(format!(
            "{what}: the node has skin {skin} but the primitive has no JOINTS_0 / WEIGHTS_0"
        ));
    }
    let k = 4 * sets.len();
    let mut joints = Vec::with_capacity(k * n_vert);
    let mut weights = Vec::with_capacity(k * n_vert);
    for v in 0..n_vert {
        let start = weights.len();
        for (j, w) in &sets {
            for c in 0..4 {
                let (ji, wi) = (j[v][c], w[4 * v + c]);
                if ji as usize >= joint_count {
                    return Err(format!(
                        "{what}: vertex {v} uses joint {ji} but skin {skin} has {joint_count} joints"
                    ));
                }
                if !wi.is_finite() || wi < 0.0 {
                    return Err(format!("{what}: vertex {v} has skin weight {wi}"));
                }
                joints.push(ji as u16);
                weights.push(wi);
            }
        }
        let sum: f32 = weights[start..].iter().sum();
        if sum.is_nan() || sum <= 0.0 || !sum.is_finite() {
            return Err(format!(
                "{what}: vertex {v} has skin weights summing to {sum}"
            ));
        }
        if (sum - 1.0).abs() > 1e-6 {
            weights[start..].iter_mut().for_each(|w| *w /= sum);
        }
    }
    Ok(SkinBinding {
        skin,
        influences: k,
        joints,
        weights,
    })
}
