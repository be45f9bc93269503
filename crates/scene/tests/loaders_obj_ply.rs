//! The OBJ and PLY loaders against small files written to a temporary folder (materials and
//! textures from an MTL file, polygons as triangle fans, and one test per error case, each
//! asserting that the message names the problem). glTF and the real models: `loaders.rs`.

use glam::Vec3;
use parallax_scene::texture::srgb_to_linear;
use parallax_scene::{MaterialKind, SceneError};

#[path = "common/files.rs"]
mod files;
use files::{load, load_err, tmp, write};

// ---- OBJ ----

#[test]
fn obj_with_mtl_materials_and_texture() {
    let folder = tmp("obj");
    let d = folder.path();
    let mut img = image::RgbImage::new(2, 1);
    img.put_pixel(0, 0, image::Rgb([255, 128, 0]));
    img.save(d.join("tex.png")).unwrap();
    write(
        d,
        "m.mtl",
        "newmtl red\nKd 1 0 0\nNs 98\nKe 0 0 2\n\
         newmtl mirror\nillum 5\nKd 0.2 0.2 0.2\nKs 0.9 0.9 0.9\n\
         newmtl glass\nillum 7\nNi 1.33\n\
         newmtl tex\nKd 1 1 1\nmap_Kd tex.png\n",
    );
    let obj = "mtllib m.mtl\n\
        v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 2\n\
        o quad\nusemtl tex\nf 1/1/1 2/2/1 3/3/1 4/4/1\n\
        o tri\nusemtl red\nf 1 2 3\nusemtl mirror\nf 1 3 4\nusemtl glass\nf 1 2 4\n";
    let s = load(&write(d, "scene.obj", obj));
    assert_eq!(s.name, "scene");
    assert_eq!(s.mesh.triangle_count(), 5);
    assert_eq!(s.materials.len(), 4);
    let by = |n: &str| s.materials.iter().find(|m| m.name == n).unwrap();
    let red = by("red");
    assert_eq!(
        (red.base_color, red.emissive),
        (Vec3::X, Vec3::new(0.0, 0.0, 2.0))
    );
    assert!((red.roughness - 0.02f32.powf(0.25)).abs() < 1e-6);
    assert_eq!(by("mirror").kind, MaterialKind::Mirror);
    assert_eq!(by("mirror").base_color, Vec3::splat(0.9));
    assert_eq!(by("glass").kind, MaterialKind::Dielectric { ior: 1.33 });
    let t = &s.textures[by("tex").base_color_texture.unwrap() as usize];
    assert_eq!((t.width, t.height), (2, 1));
    assert_eq!(
        t.texels[0],
        Vec3::new(1.0, srgb_to_linear(128.0 / 255.0), 0.0)
    );
    // The quad (first object) is textured, uses vt flipped to v-down, normals normalised.
    let q = &s.mesh.objects[0];
    assert_eq!((q.name.as_str(), q.triangle_count), ("quad", 2));
    assert_eq!(s.mesh.uvs[0], glam::Vec2::new(0.0, 1.0));
    assert_eq!(s.mesh.normals[0], Vec3::Z);
    assert_eq!(s.materials[s.mesh.material_ids[0] as usize].name, "tex");
}

#[test]
fn obj_without_its_mtl_uses_the_default_material() {
    let folder = tmp("obj-nomtl");
    let d = folder.path();
    let s = load(&write(
        d,
        "a.obj",
        "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl x\nf 1 2 3\n",
    ));
    assert_eq!((s.mesh.triangle_count(), s.materials.len()), (1, 1));
    assert_eq!(s.materials[0].name, "default");
}

#[test]
fn obj_mtl_outside_the_folder_is_refused() {
    let folder = tmp("obj-escape");
    let d = folder.path();
    write(d, "evil.mtl", "newmtl a\nKd 1 1 1\n");
    std::fs::create_dir_all(d.join("in")).unwrap();
    let p = write(
        &d.join("in"),
        "a.obj",
        "mtllib ../evil.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let (e, msg) = load_err(&p);
    assert!(matches!(e, SceneError::BadReference { .. }), "{msg}");
    assert!(msg.contains("../evil.mtl"), "{msg}");
}

#[test]
fn malformed_obj_is_a_parse_error() {
    let folder = tmp("obj-bad");
    let d = folder.path();
    let (e, msg) = load_err(&write(
        d,
        "bad.obj",
        "v 0 0 zero\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    ));
    assert!(matches!(e, SceneError::Parse { .. }), "{msg}");
    assert!(
        msg.contains("malformed OBJ") && msg.contains("bad.obj"),
        "{msg}"
    );
    let (e, msg) = load_err(&write(
        d,
        "range.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
    ));
    assert!(
        matches!(e, SceneError::Parse { .. } | SceneError::Invalid { .. }),
        "{msg}"
    );
}

// ---- PLY ----

const PLY_HEAD: &str = "ply\nformat ascii 1.0\ncomment test\nelement vertex 5\n\
    property double x\nproperty double y\nproperty double z\n\
    property float nx\nproperty float ny\nproperty float nz\nproperty float confidence\n\
    element face 2\nproperty list uchar int vertex_indices\n\
    element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";

#[test]
fn ply_polygons_become_triangle_fans() {
    let folder = tmp("ply");
    let d = folder.path();
    let body = "0 0 0 0 0 2 1\n1 0 0 0 0 2 1\n1 1 0 0 0 2 1\n0 1 0 0 0 2 1\n0 0 1 0 0 2 1\n\
                4 0 1 2 3\n3 0 1 4\n0 1\n";
    let s = load(&write(d, "quad.ply", format!("{PLY_HEAD}{body}")));
    assert_eq!(s.mesh.indices, vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]]);
    assert_eq!(s.mesh.normals, vec![Vec3::Z; 5]);
    assert_eq!(s.mesh.positions[4], Vec3::Z);
    assert_eq!((s.materials.len(), s.mesh.objects.len()), (1, 1));
}

#[test]
fn malformed_ply_is_a_parse_error() {
    let folder = tmp("ply-bad");
    let d = folder.path();
    let body = "0 0 0 0 0 1 1\n1 0 zero 0 0 1 1\n";
    let (e, msg) = load_err(&write(d, "bad.ply", format!("{PLY_HEAD}{body}")));
    assert!(matches!(e, SceneError::Parse { .. }), "{msg}");
    assert!(
        msg.contains("malformed PLY") && msg.contains("vertex"),
        "{msg}"
    );
    let (e, msg) = load_err(&write(d, "notply.ply", "hello\n"));
    assert!(matches!(e, SceneError::Parse { .. }), "{msg}");
    let body = "0 0 0 0 0 1 1\n1 0 0 0 0 1 1\n1 1 0 0 0 1 1\n0 1 0 0 0 1 1\n0 0 1 0 0 1 1\n\
                3 0 1 9\n3 0 1 2\n0 1\n";
    let (e, msg) = load_err(&write(d, "range.ply", format!("{PLY_HEAD}{body}")));
    assert!(matches!(e, SceneError::Invalid { .. }), "{msg}");
    assert!(msg.contains("face 0 uses vertex 9"), "{msg}");
}
