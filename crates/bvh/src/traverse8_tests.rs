//! Unit tests of `traverse8.rs`'s ray preparation.

use glam::Vec3;
use parallax_core::Ray;

use super::RayBoxes8;

/// `RayBoxes8::new` (one 4-lane division, one sign mask) against the per-component
/// definition: `-1 / d` bit for bit and the plane offsets from each reciprocal's sign, on
/// zero, negative-zero, tiny, huge and ordinary components. Returns how many rays had each
/// axis's reciprocal negative.
fn check_boxes() -> [u32; 3] {
    let vals = [
        0.0f32, -0.0, 1.0, -1.0, 0.3, -7.5, 1e-38, -1e-38, 3e38, -3e38, 1e-45,
    ];
    let mut neg = [0u32; 3];
    for &x in &vals {
        for &y in &vals {
            for &z in &vals {
                let ray = Ray::new(Vec3::new(1.0, -2.0, 0.5), Vec3::new(x, y, z));
                let rb = RayBoxes8::new(&ray);
                for (a, d) in [x, y, z].into_iter().enumerate() {
                    let inv = 1.0 / d;
                    assert_eq!(rb.neg_inv[a].to_bits(), (-inv).to_bits(), "{d}");
                    let s = inv.is_sign_negative() as usize;
                    assert_eq!(rb.near[a], 32 * (2 * a + s), "{d}");
                    assert_eq!(rb.far[a], 32 * (2 * a + 1 - s), "{d}");
                    neg[a] += s as u32;
                }
                assert_eq!(rb.org, [1.0, -2.0, 0.5]);
            }
        }
    }
    neg
}

#[test]
fn ray_boxes_match_per_component_reference() {
    let neg = check_boxes();
    // 5 of the 11 values are negative (with -0.0): 5 * 11 * 11 rays per axis.
    assert_eq!(neg, [605; 3]);
}
