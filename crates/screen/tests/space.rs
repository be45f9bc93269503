//! The unit cube is a projective map: round trips, lines stay lines, planes stay planes.

use glam::{Vec2, Vec3};
use parallax_scene::{CameraDesc, camera::Pinhole};
use parallax_screen::UnitCube;
use proptest::prelude::*;

fn cube() -> UnitCube {
    let desc = CameraDesc::new(
        Vec3::new(0.3, 1.0, 4.0),
        Vec3::new(0.0, 0.8, 0.0),
        Vec3::Y,
        60.0,
    );
    let cam = Pinhole::new(&desc, 40, 30)
        .unwrap()
        .with_shift(Vec2::new(0.1, -0.05));
    UnitCube::new(&cam, 0.5, 12.0).unwrap()
}

/// A world point in the frustum from film fractions and a depth.
fn point(c: &UnitCube, fx: f32, fy: f32, d: f32) -> Vec3 {
    let cam = &c.camera;
    let film = Vec2::new(fx * cam.width as f32, fy * cam.height as f32);
    cam.frame.position + cam.frame.dir_to_world(cam.camera_dir(film)) * d
}

proptest! {
    #[test]
    fn round_trip(fx in 0.0f32..1.0, fy in 0.0f32..1.0, d in 0.5f32..12.0) {
        let c = cube();
        let p = point(&c, fx, fy, d);
        let u = c.to_cube(p).unwrap();
        prop_assert!(u.cmpge(Vec3::splat(-1e-5)).all() && u.cmple(Vec3::splat(1.0 + 1e-5)).all());
        prop_assert!((u.x - fx).abs() < 1e-5 && (u.y - fy).abs() < 1e-5);
        prop_assert!((c.to_world(u) - p).length() < 1e-5 * d.max(1.0) * 10.0);
    }

    #[test]
    fn lines_stay_lines(a in prop::array::uniform3(0.0f32..1.0), b in prop::array::uniform3(0.0f32..1.0),
                        s in prop::array::uniform3(0.0f32..1.0)) {
        let c = cube();
        let pa = point(&c, a[0], a[1], 0.6 + 11.0 * a[2]);
        let pb = point(&c, b[0], b[1], 0.6 + 11.0 * b[2]);
        // The points of the smallest and largest parameter span the chord; the middle one must
        // lie on it. (Measuring the angle between two chords instead is ill-conditioned when two
        // samples nearly coincide: proptest found such a case.)
        let mut s = s;
        s.sort_by(f32::total_cmp);
        let u: Vec<Vec3> = s.iter().map(|&t| c.to_cube(pa.lerp(pb, t)).unwrap()).collect();
        let chord = u[2] - u[0];
        prop_assume!(chord.length() > 1e-3);
        let dist = (u[1] - u[0]).cross(chord).length() / chord.length();
        prop_assert!(dist < 1e-5, "{:?}: {}", u, dist);
    }

    #[test]
    fn planes_stay_planes(p in prop::array::uniform3(0.1f32..0.9), n in prop::array::uniform3(-1.0f32..1.0),
                          uv in prop::array::uniform4(-0.5f32..0.5)) {
        let c = cube();
        let n = Vec3::from(n);
        prop_assume!(n.length() > 0.1);
        let n = n.normalize();
        let origin = point(&c, p[0], p[1], 1.0 + 8.0 * p[2]);
        let t1 = n.any_orthonormal_vector();
        let t2 = n.cross(t1);
        let pts = [Vec3::ZERO, Vec3::new(uv[0], uv[1], 0.0), Vec3::new(uv[2], uv[3], 0.0), Vec3::new(uv[1], uv[2], 0.0)]
            .map(|q| origin + t1 * q.x + t2 * q.y);
        // Points in front of the eye only.
        let us: Vec<Vec3> = pts.iter().filter_map(|&q| {
            let d = -c.camera.frame.to_camera(q).z;
            (d > 0.3).then(|| c.to_cube(q).unwrap())
        }).collect();
        prop_assume!(us.len() == 4);
        let (e1, e2, e3) = (us[1] - us[0], us[2] - us[0], us[3] - us[0]);
        let nrm = e1.cross(e2);
        prop_assume!(nrm.length() > 1e-5 && e3.length() > 1e-4);
        prop_assert!((nrm.normalize().dot(e3) / e3.length()).abs() < 2e-3);
        // And the covector-mapped plane contains all four.
        let (cn, off) = c.map_plane(origin, n).unwrap();
        for u in &us {
            prop_assert!((cn.dot(*u) - off).abs() < 1e-4, "{}", cn.dot(*u) - off);
        }
    }
}
