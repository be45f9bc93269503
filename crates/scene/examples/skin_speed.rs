//! Per-vertex cost of the per-frame vertex transform (HVVR §5.2 stage 1): linear blend skinning
//! with 4 influences ([`GltfAnimation::apply`]) against the rigid props transform, on 2^20
//! vertices, single thread. Thread CPU time (`/proc/thread-self/schedstat`), best of 7.
//!
//! `cargo run --release -p parallax-scene --example skin_speed`

use glam::{Quat, Vec3, Vec4};
use parallax_scene::animation::RigidAnimation;
use parallax_scene::keyframes::{Interpolation, Sampler};
use parallax_scene::skin::{
    Channel, Clip, GltfAnimation, Instance, LocalTransform, Node, Skin, SkinBinding, TargetPath,
};
use parallax_scene::{ObjectRange, TriangleMesh};

fn cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

fn best_ns(mut f: impl FnMut()) -> f64 {
    (0..7)
        .map(|_| {
            let t = cpu_ns();
            f();
            (cpu_ns() - t) as f64
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let n = 1usize << 20;
    let joints = 64u32;
    let mut seed = 1u32;
    let mut rnd = move || {
        seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
        (seed >> 8) as f32 / (1u32 << 24) as f32
    };
    let local: Vec<Vec3> = (0..n)
        .map(|_| Vec3::new(6.4 * rnd(), rnd() - 0.5, rnd() - 0.5))
        .collect();
    let normals: Vec<Vec3> = (0..n).map(|_| Vec3::Y).collect();
    let nodes: Vec<Node> = (0..joints)
        .map(|j| Node {
            parent: j.checked_sub(1),
            rest: LocalTransform::Trs {
                translation: if j == 0 { Vec3::ZERO } else { Vec3::X * 0.1 },
                rotation: Quat::IDENTITY,
                scale: Vec3::ONE,
            },
        })
        .collect();
    let q = |a: f32| Vec4::from(Quat::from_rotation_z(a));
    let channels = (0..joints)
        .map(|j| Channel {
            node: j,
            path: TargetPath::Rotation,
            sampler: Sampler::new(
                Interpolation::Linear,
                vec![0.0, 1.0, 2.0],
                vec![q(0.0), q(0.05), q(0.0)],
                true,
            )
            .unwrap(),
        })
        .collect();
    let (mut js, mut ws) = (Vec::new(), Vec::new());
    for p in &local {
        let j = ((p.x * 10.0) as u16).min(joints as u16 - 4);
        js.extend([j, j + 1, j + 2, j + 3]);
        ws.extend([0.4, 0.3, 0.2, 0.1]);
    }
    let anim = GltfAnimation {
        nodes,
        order: (0..joints).collect(),
        clips: vec![Clip {
            name: "wave".into(),
            channels,
            duration: 2.0,
        }],
        skins: vec![Skin {
            name: "chain".into(),
            joints: (0..joints).collect(),
            inverse_bind: (0..joints)
                .map(|j| glam::Mat4::from_translation(-Vec3::X * 0.1 * j as f32))
                .collect(),
            skeleton: Some(0),
        }],
        instances: vec![Instance {
            object: 0,
            node: 0,
            first_vertex: 0,
            local_positions: local.clone(),
            local_normals: normals.clone(),
            skin: Some(SkinBinding {
                skin: 0,
                influences: 4,
                joints: js,
                weights: ws,
            }),
        }],
        clip: 0,
        vertex_count: n,
    };
    let mut mesh = TriangleMesh {
        positions: local,
        normals,
        objects: vec![ObjectRange {
            name: "sphere".into(),
            first_triangle: 0,
            triangle_count: 0,
            first_vertex: 0,
            vertex_count: n as u32,
        }],
        ..Default::default()
    };
    let rigid = RigidAnimation::new(&mesh, &[0]).unwrap();
    let mut t = 0.0;
    let skin = best_ns(|| {
        t += 0.1;
        anim.apply(&mut mesh, t).unwrap();
    });
    let rig = best_ns(|| {
        t += 0.1;
        rigid.apply(&mut mesh, t).unwrap();
    });
    println!(
        "{n} vertices, one thread: skinning (4 influences, {joints} joints) {:.2} ms = {:.2} ns/vertex; rigid {:.2} ms = {:.2} ns/vertex",
        skin * 1e-6,
        skin / n as f64,
        rig * 1e-6,
        rig / n as f64
    );
}
