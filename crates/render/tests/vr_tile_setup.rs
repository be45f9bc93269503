//! HVVR's per-tile triangle set-up (§5.5, `vr::tile_setup`): the tile-corner classification
//! never changes the kernel's answer for a ray of the tile's beam (property test), and the
//! set-up edge test is watertight across the shared edges and the shared vertex of fans.

use glam::Vec3;
use parallax_core::Ray;
use parallax_core::math::BeamBuilder;
use parallax_render::vr::tile_setup::{BeamCorners, CornerClass, TriSetup, dot3};
use proptest::prelude::*;

/// Edge values of the kernel for direction `d`.
fn edges(s: &TriSetup, d: Vec3) -> [f32; 3] {
    s.n.map(|n| dot3(n, d))
}

fn unit(theta: f32, phi: f32) -> Vec3 {
    Vec3::new(phi.sin() * theta.cos(), phi.sin() * theta.sin(), phi.cos())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// A bundle of rays from one origin around a random axis (a tile's rays), its beam, and
    /// random triangles around the bundle: all-out triangles fail an edge test for every ray,
    /// all-in ones pass all three for every ray. Counts of each class are checked so the
    /// property is not vacuous.
    #[test]
    fn corner_classification_is_conservative(
        o in prop::array::uniform3(-50.0f32..50.0),
        axis in (0.0f32..6.28, 0.0f32..3.14),
        spread in 0.001f32..0.3,
        seed in any::<u64>(),
    ) {
        let o = Vec3::from_array(o);
        let mut rng = seed;
        let mut next = move || {
            rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((rng >> 40) as f32) / (1u64 << 24) as f32
        };
        let centre = unit(axis.0, axis.1);
        let (t1, t2) = (centre.any_orthonormal_pair().0, centre.any_orthonormal_pair().1);
        let mut rays = Vec::new();
        let mut b = BeamBuilder::new();
        for k in 0..200 {
            // Include the bundle's extreme corners exactly.
            let (x, y) = if k < 4 {
                ((k & 1) as f32 * 2.0 - 1.0, (k >> 1) as f32 * 2.0 - 1.0)
            } else {
                (next() * 2.0 - 1.0, next() * 2.0 - 1.0)
            };
            let d = (centre + spread * (x * t1 + y * t2)).normalize();
            let r = Ray::new(o, d);
            b.add(&r);
            rays.push(r);
        }
        let beam = b.finish().unwrap();
        let corners = BeamCorners::new(&beam).unwrap();
        let (mut outs, mut ins, mut partial) = (0, 0, 0);
        for _ in 0..60 {
            // Vertices at a random distance, in directions around the bundle (some inside,
            // some straddling its border, some outside).
            let dist = 0.1 + 30.0 * next();
            let v = [0; 3].map(|_| {
                let (x, y) = (next() * 6.0 - 3.0, next() * 6.0 - 3.0);
                let d = centre + spread * (x * t1 + y * t2);
                o + d * dist * (0.8 + 0.4 * next())
            });
            let Some(s) = TriSetup::new(v, o, 0) else { continue };
            let class = corners.classify(&s.n);
            match class {
                CornerClass::AllOut => outs += 1,
                CornerClass::AllIn => ins += 1,
                CornerClass::Partial => partial += 1,
            }
            for r in &rays {
                let e = edges(&s, r.dir);
                match class {
                    CornerClass::AllOut => prop_assert!(
                        e.iter().any(|&x| x < 0.0),
                        "all-out triangle passes every edge test of a ray of the beam: {e:?}"
                    ),
                    CornerClass::AllIn => prop_assert!(
                        e.iter().all(|&x| x >= 0.0),
                        "all-in triangle fails an edge test of a ray of the beam: {e:?}"
                    ),
                    CornerClass::Partial => {}
                }
            }
        }
        prop_assert!(outs + ins + partial > 30);
    }
}

/// The classes all occur on the property test's distribution (the test above is not vacuous):
/// a fixed bundle with a triangle covering it, one beside it and one across its border.
#[test]
fn classification_finds_all_three_classes() {
    let o = Vec3::new(1.0, 2.0, 3.0);
    let mut b = BeamBuilder::new();
    for (x, y) in [(-0.1, -0.1), (0.1, -0.1), (-0.1, 0.1), (0.1, 0.1)] {
        b.add(&Ray::new(o, Vec3::new(x, y, -1.0).normalize()));
    }
    let c = BeamCorners::new(&b.finish().unwrap()).unwrap();
    let tri = |pts: [(f32, f32); 3]| {
        let v = pts.map(|(x, y)| o + Vec3::new(x, y, -1.0) * 5.0);
        c.classify(&TriSetup::new(v, o, 0).unwrap().n)
    };
    assert_eq!(
        tri([(-1.0, -1.0), (1.0, -1.0), (0.0, 1.0)]),
        CornerClass::AllIn
    );
    assert_eq!(
        tri([(-1.0, -1.0), (0.0, 1.0), (1.0, -1.0)]),
        CornerClass::AllIn
    );
    assert_eq!(
        tri([(0.5, 0.5), (0.9, 0.5), (0.7, 0.9)]),
        CornerClass::AllOut
    );
    assert_eq!(
        tri([(0.0, -1.0), (1.0, -1.0), (0.0, 1.0)]),
        CornerClass::Partial
    );
    // The beam lies entirely left of the edge (0, -1) -> (0.5, 1).
    assert_eq!(
        tri([(0.0, -1.0), (1.0, -1.0), (0.5, 1.0)]),
        CornerClass::AllOut
    );
}

/// The closest hit among `tris` along `d` (largest `1/t`), if any.
fn hits(tris: &[TriSetup], d: Vec3) -> usize {
    tris.iter().filter(|s| s.hit(d).is_some()).count()
}

/// A closed fan of `n` triangles around `c` (ring `ring`), consistently oriented.
fn fan(c: Vec3, ring: &[Vec3], o: Vec3) -> Vec<TriSetup> {
    (0..ring.len())
        .filter_map(|k| TriSetup::new([c, ring[k], ring[(k + 1) % ring.len()]], o, k as u32))
        .collect()
}

/// Rays exactly through points of the shared edges of random fans (non-planar, arbitrary float
/// coordinates) hit at least one of the fan's triangles; rays through the interior of a
/// triangle hit exactly one (the fan does not overlap itself). Rays exactly through the shared
/// vertex may leak (counted: see the assertion).
#[test]
fn set_up_edge_test_is_watertight_on_fans() {
    let mut rng = 0x1234_5678_9abc_def0u64;
    let mut next = move || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((rng >> 40) as f32) / (1u64 << 24) as f32
    };
    let (mut edge_rays, mut vertex_rays, mut vertex_leaks) = (0, 0, 0u32);
    for _ in 0..400 {
        let o = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 20.0;
        let dist = 0.5 + 50.0 * next();
        let dir = unit(next() * 6.28, next() * 3.14);
        let c = o + dir * dist;
        let (t1, t2) = dir.any_orthonormal_pair();
        let n = 3 + (next() * 6.0) as usize;
        let size = dist * (0.001 + 0.3 * next());
        let ring: Vec<Vec3> = (0..n)
            .map(|k| {
                let a = (k as f32 + 0.3 * next()) / n as f32 * std::f32::consts::TAU;
                let r = size * (0.5 + next());
                c + r * (a.cos() * t1 + a.sin() * t2) + dir * (size * 0.3 * (next() - 0.5))
            })
            .collect();
        let tris = fan(c, &ring, o);
        assert_eq!(tris.len(), n);
        // Through the shared vertex: unnormalised and normalised float directions.
        for d in [c - o, (c - o).normalize()] {
            vertex_rays += 1;
            vertex_leaks += (hits(&tris, d) == 0) as u32;
        }
        // Through points of the shared spokes.
        for r in &ring {
            for lambda in [0.5f32, 0.25, 0.9, next()] {
                let p = c + lambda * (*r - c);
                for d in [p - o, (p - o).normalize()] {
                    edge_rays += 1;
                    assert!(hits(&tris, d) >= 1, "ray through a shared edge leaks");
                }
            }
        }
        // Interior points: exactly one triangle.
        for k in 0..n {
            let (a, b) = (ring[k], ring[(k + 1) % n]);
            let p = (c + a + b) / 3.0;
            assert_eq!(
                hits(&tris, p - o),
                1,
                "interior ray hits {}",
                hits(&tris, p - o)
            );
        }
    }
    assert!(edge_rays > 1000 && vertex_rays > 100);
    // Exactly through the shared vertex, all spoke values are rounding noise around zero and
    // can share one strict sign: the set-up test is watertight on edges, not on vertices
    // (measured, reported, bounded here).
    eprintln!("rays exactly through a fan's vertex that leak: {vertex_leaks} / {vertex_rays}");
    assert!(
        vertex_leaks * 4 <= vertex_rays,
        "{vertex_leaks} / {vertex_rays}"
    );
}

/// Shared edges give exactly negated covectors (the watertightness argument of the module docs).
#[test]
fn shared_edges_have_negated_covectors() {
    let o = Vec3::new(0.3, -0.7, 1.1);
    let (a, b) = (Vec3::new(1.1, 2.3, -7.7), Vec3::new(-0.9, 2.9, -8.1));
    let (c, d) = (Vec3::new(0.4, -1.3, -6.9), Vec3::new(0.2, 5.1, -9.3));
    // (a, b, c) and (b, a, d): consistently oriented across edge ab.
    let s1 = TriSetup::new([a, b, c], o, 0).unwrap();
    let s2 = TriSetup::new([b, a, d], o, 1).unwrap();
    let e1 = s1.n[0];
    let e2 = s2.n[0];
    assert_eq!(e1.map(f32::to_bits), e2.map(|x| (-x).to_bits()));
}
