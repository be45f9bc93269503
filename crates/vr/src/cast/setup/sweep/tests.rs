//! Tests of `sweep.rs`.

use crate::test_streams::uniform;
use glam::Vec4;

use super::super::kernel::PacketSlab;
use super::super::tri::Segment;
use super::{intervals_of_row, run_reaches};
use crate::cast::lanes16::LaneReduce;
use crate::cast::lanes16::V16;
use parallax_core::simd::Lanes;

/// The run-box test of sixteen packets at once decides every packet as the walk's interval
/// test of that packet alone (`PacketSlab::interval_reaches`, every box reached where the
/// packet has no interval), on packets of nearby directions (random signs, near-axis
/// components that straddle 0, so some packets have no interval), boxes from tiny to huge
/// straddling the origin's planes, and per-packet limits from 0 to infinity.
#[test]
fn run_reaches_equals_the_walks_interval_test() {
    let mut f = uniform(0x5851_f42d_4c95_7f2d);
    let (mut tested, mut reached, mut without) = (0u32, 0u32, 0u32);
    for _ in 0..400 {
        let mut iv = [[0.0f32; 16]; 6];
        let mut lim = [0.0f32; 16];
        let mut slabs = Vec::new();
        for k in 0..16 {
            let base = [f() - 0.5, f() - 0.5, f() - 0.5]
                .map(|c| if c.abs() < 0.05 { c * 1e-3 } else { c });
            let spread = 10f32.powi(-(((f() * 5.0) as i32) + 1));
            let d = [0, 1, 2].map(|a| V16::from_fn(|_| base[a] + (f() - 0.5) * spread));
            let [x, y, z] = d;
            let (lo, hi) = (V16::hmin4([x, y, z, z]), V16::hmax4([x, y, z, z]));
            for a in 0..3 {
                iv[a][k] = hi[a];
                iv[3 + a][k] = lo[a];
            }
            lim[k] = [f32::INFINITY, 0.0, f() * 10.0, f() * 1e4][(f() * 4.0) as usize % 4];
            slabs.push(PacketSlab::<V16>::with_interval(d));
        }
        intervals_of_row::<V16>(&mut iv);
        for _ in 0..8 {
            let s = 10f32.powi((f() * 8.0) as i32 - 3);
            let c = [f() - 0.5, f() - 0.5, f() - 0.5].map(|v| v * 4.0 * s);
            let h = [f(), f(), f()].map(|v| v * s);
            let seg = Segment {
                end: 0,
                near: 0.0,
                lo: Vec4::new(c[0] - h[0], c[1] - h[1], c[2] - h[2], 0.0),
                hi: Vec4::new(c[0] + h[0], c[1] + h[1], c[2] + h[2], 0.0),
            };
            let bits = run_reaches::<V16>(&seg, &iv, &lim);
            for (k, p) in slabs.iter().enumerate() {
                let one = !p.has_interval() || p.interval_reaches(&seg, lim[k]);
                assert_eq!(bits >> k & 1 != 0, one, "packet {k}: {seg:?} {}", lim[k]);
                tested += 1;
                reached += one as u32;
                without += !p.has_interval() as u32;
            }
        }
    }
    assert!(
        reached > tested / 50 && reached < tested * 49 / 50,
        "{reached} {tested}"
    );
    assert!(
        without > tested / 100,
        "{without} of {tested} without an interval"
    );
}
