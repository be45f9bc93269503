use super::*;
use glam::Vec2;
use parallax_scene::CameraDesc;
use parallax_scene::camera::{CameraModel, Pinhole};

/// A view of the plane z = -d, every texel on it, facing +z.
fn plane_view(eye: Vec3, d: f32, w: u32, h: u32) -> EyeView {
    let desc = CameraDesc::new(eye, eye - Vec3::Z, Vec3::Y, 60.0);
    let cam = Pinhole::new(&desc, w, h).unwrap();
    let mut v = EyeView::new(cam.clone());
    for y in 0..h {
        for x in 0..w {
            let r = cam
                .generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), Vec2::ZERO, 0)
                .unwrap();
            let t = (eye.z + d) / -r.ray.dir.z;
            v.texels[(y * w + x) as usize] = Texel {
                position: r.ray.at(t),
                depth: d,
                normal: Vec3::Z,
                albedo: Vec3::ONE,
            };
        }
    }
    v
}

const LOOSE: Tests = Tests {
    position: 1.0,
    normal_deg: 30.0,
    plane: false,
};

#[test]
fn same_view_reuses_each_pixel_with_its_own_value() {
    let v = plane_view(Vec3::ZERO, 5.0, 16, 12);
    let values: Vec<Vec3> = (0..v.len()).map(|i| Vec3::splat(i as f32)).collect();
    for (i, t) in v.texels.iter().enumerate() {
        let fp = footprint(&v, t, Kernel::BILINEAR, LOOSE);
        assert_eq!(fp.outcome, Outcome::Reused);
        let g = fp.gather(Kernel::BILINEAR, &values, 16);
        assert!((g.x - i as f32).abs() < 1e-3, "{i}: {g}");
    }
}

#[test]
fn bilinear_weights_interpolate_a_linear_ramp_and_sum_to_one() {
    let src = plane_view(Vec3::ZERO, 5.0, 32, 24);
    // Shifted eye: positions land between source pixel centres.
    let dst = plane_view(Vec3::new(0.013, 0.021, 0.0), 5.0, 32, 24);
    let ramp: Vec<Vec3> = (0..src.len())
        .map(|i| Vec3::new((i % 32) as f32, (i / 32) as f32, 1.0))
        .collect();
    for kernel in [Kernel::BILINEAR, Kernel { radius: 2.0 }] {
        for t in dst.texels.iter().skip(32 * 3).take(32 * 18) {
            let fp = footprint(&src, t, kernel, LOOSE);
            if fp.outcome != Outcome::Reused || fp.mask.count_ones() < 4 {
                continue;
            }
            let f = src.camera.project(t.position, 0).unwrap() - Vec2::splat(0.5);
            if f.x < 2.0 || f.x > 29.0 {
                continue;
            }
            let g = fp.gather(kernel, &ramp, 32);
            assert!((g.z - 1.0).abs() < 1e-5, "weights sum to {}", g.z);
            assert!(
                (g.x - f.x).abs() < 1e-3 && (g.y - f.y).abs() < 1e-3,
                "{f} {g}"
            );
        }
    }
}

#[test]
fn tests_discard_far_positions_turned_normals_and_everything_at_zero() {
    let src = plane_view(Vec3::ZERO, 5.0, 16, 12);
    let t = src.texels[5 * 16 + 7];
    let far = Texel {
        position: t.position + Vec3::Z * 2.0,
        ..t
    };
    assert_eq!(
        footprint(&src, &far, Kernel::BILINEAR, LOOSE).outcome,
        Outcome::Position
    );
    let turned = Texel {
        normal: Vec3::X,
        ..t
    };
    assert_eq!(
        footprint(&src, &turned, Kernel::BILINEAR, LOOSE).outcome,
        Outcome::Normal
    );
    let zero = Tests {
        position: 0.0,
        normal_deg: 0.0,
        plane: true,
    };
    for t in &src.texels {
        assert!(
            footprint(&src, t, Kernel::BILINEAR, zero)
                .outcome
                .is_discarded()
        );
    }
    let behind = Texel {
        position: Vec3::new(0.0, 0.0, 3.0),
        ..t
    };
    assert_eq!(
        footprint(&src, &behind, Kernel::BILINEAR, LOOSE).outcome,
        Outcome::Outside
    );
    assert_eq!(
        footprint(&src, &Texel::MISS, Kernel::BILINEAR, LOOSE).outcome,
        Outcome::Background
    );
}

#[test]
fn bilinear_specialisation_equals_the_general_kernel_bit_for_bit() {
    let mut src = plane_view(Vec3::ZERO, 5.0, 24, 16);
    // Bumps and turned normals on the left half so that every outcome and partial masks
    // occur; the flat right half keeps all four taps.
    for (i, s) in src
        .texels
        .iter_mut()
        .enumerate()
        .filter(|(i, _)| i % 24 < 12)
    {
        let k = (i * 7919 % 13) as f32;
        s.position.z += 0.05 * (k - 6.0);
        if i % 5 == 0 {
            s.normal = Vec3::new(0.6, 0.0, 0.8);
        }
        if i % 11 == 0 {
            *s = Texel::MISS;
        }
    }
    let dst = plane_view(Vec3::new(0.37, -0.21, 0.4), 5.0, 24, 16);
    let values: Vec<Vec3> = (0..src.len())
        .map(|i| Vec3::new(i as f32, (i * i % 17) as f32, 1.0))
        .collect();
    let counts: Vec<f32> = (0..src.len()).map(|i| (i % 9) as f32 + 1.0).collect();
    let packed: Vec<Vec4> = values
        .iter()
        .zip(&counts)
        .map(|(v, c)| v.extend(*c))
        .collect();
    let (mut seen, mut full) = (std::collections::HashSet::new(), 0);
    let proj = Projector::new(&src.camera);
    for plane in [false, true] {
        let lim = Tests {
            position: 0.12,
            normal_deg: 25.0,
            plane,
        }
        .limits();
        for t in &dst.texels {
            let lanes = footprint_in::<true, true>(&src, &proj, t, Kernel::BILINEAR, lim);
            let fast = footprint_in::<true, false>(&src, &proj, t, Kernel::BILINEAR, lim);
            let slow = footprint_in::<false, false>(&src, &proj, t, Kernel::BILINEAR, lim);
            assert_eq!(fast, slow);
            assert_eq!(
                (lanes.mask, lanes.inv_weight.to_bits(), lanes.outcome),
                (slow.mask, slow.inv_weight.to_bits(), slow.outcome)
            );
            assert_eq!(lanes, slow);
            // The kept weights' positive lanes are the mask's bits (the Vec4 gather's lane
            // mask).
            let positive = slow.weights.cmpgt(Vec4::ZERO).bitmask() as u16;
            assert_eq!(positive, if slow.taps_inside { slow.mask } else { 0 });
            seen.insert(fast.outcome);
            full += usize::from(fast.mask == 0xF);
            let (a, b) = (
                fast.gather_in::<true, Vec3>(Kernel::BILINEAR, &values, 24),
                slow.gather_in::<false, Vec3>(Kernel::BILINEAR, &values, 24),
            );
            assert_eq!(
                a.to_array().map(f32::to_bits),
                b.to_array().map(f32::to_bits)
            );
            let n = fast.gather_in::<true, f32>(Kernel::BILINEAR, &counts, 24);
            assert_eq!(
                n.to_bits(),
                slow.gather_in::<false, f32>(Kernel::BILINEAR, &counts, 24)
                    .to_bits()
            );
            // A colour and a count gathered together (SIMD lanes) equal both gathered
            // apart.
            let both = fast.gather_in::<true, Vec4>(Kernel::BILINEAR, &packed, 24);
            assert_eq!(
                both.to_array().map(f32::to_bits),
                [a.x, a.y, a.z, n].map(f32::to_bits)
            );
        }
    }
    assert!(seen.len() >= 3, "outcomes seen: {seen:?}");
    assert!(full > 0, "no footprint kept all four taps");
}
