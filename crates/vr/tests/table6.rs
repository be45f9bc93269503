//! `bench vr`'s Table 6 (`parallax_vr::bench::table6`) on a tiny frame: every ray tracer answers
//! the beam caster's rays (same rays, same order of magnitude of agreement), the packet rows say
//! what a packet is, every round's time is kept with the per-round speed-ups, and without
//! Embree the report says how to enable it.

use parallax_bvh::Bvh;
use parallax_scene::Scene;
use parallax_vr::bench::table6::{Table6Options, run};

#[test]
fn table6_rows_agree_with_the_beam_caster() {
    let scene = Scene::load("atrium").unwrap();
    let bvh = Bvh::build(&scene.mesh);
    let head = scene.camera(None).unwrap();
    let opts = Table6Options {
        width: 64,
        height: 32,
        spp: vec![1, 16],
        repeats: 2,
    };
    let r = run(&scene, &bvh, &head, &opts).unwrap();
    assert_eq!(r.embree_missing.is_some(), !parallax_embree::ENABLED);
    let tracers = if parallax_embree::ENABLED { 5 } else { 3 };
    assert_eq!(r.rows.len(), 2 * tracers);
    for row in &r.rows {
        assert_eq!(row.rays, 64 * 32 * row.samples_per_pixel as u64, "{row:?}");
        assert!(row.mrays_per_s > 0.0 && row.beam_speedup > 0.0, "{row:?}");
        // The beam caster's default kernel differs from per-ray traversal only in depth ties.
        assert!(row.same_t >= 0.999, "{row:?}");
        assert!(row.same_prim >= 0.99, "{row:?}");
        // Every round is kept; the best is the least; per-round speed-ups are ordered.
        assert_eq!(row.ms_trace_rounds.len(), 2, "{row:?}");
        let least = row
            .ms_trace_rounds
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        assert_eq!(row.ms_trace, least, "{row:?}");
        let s = row.beam_speedup_rounds;
        assert!(
            s.min > 0.0 && s.min <= s.median && s.median <= s.max,
            "{row:?}"
        );
        if row.method == "beam" {
            assert_eq!((s.min, s.max), (1.0, 1.0), "{row:?}");
        }
    }
    let packet = |spp, m: &str| {
        r.rows
            .iter()
            .find(|x| x.samples_per_pixel == spp && x.method == m)
            .unwrap()
            .packet
            .clone()
    };
    assert_eq!(packet(1, "bvh packet16"), "4x4 pixels");
    assert_eq!(packet(16, "bvh packet16"), "1 pixel");
}
