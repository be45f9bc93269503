//! The affine packet test (`cast/setup/affine.rs`): its whole-packet decisions never contradict
//! the watertight test (adversarial rays: subsamples exactly on edges, shared edges, shared
//! vertices, grazing and tiny triangles, near and far), and casts with it equal casts without
//! it bit for bit (every lane width, 1 to 32 spp, pinhole, stereo and foveated sets).

use glam::{Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_core::Ray;
use parallax_core::math::WatertightRay;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_scene::{CameraDesc, Scene};
use parallax_vr::cast::setup::affine::{CLASS_IN, CLASS_OUT, FilmFrame, PacketBox, PacketClass};
use parallax_vr::cast::setup::{Cone, TriSetup};
use parallax_vr::{CastOptions, Hierarchy, Isa, SampleSet, VisibilityBuffer, cast_opts};

fn camera(scene: &Scene, kind: ModelKind, w: u32, h: u32) -> Camera {
    let desc = scene.camera(None).unwrap();
    Camera::new(kind, &desc, w, h, &CameraOptions::default()).unwrap()
}

/// Casts `set` with and without the affine packet test for every lane width (and the portable
/// 16-lane twin): the buffers are equal bit for bit. Returns the packet-triangle tests the
/// packet test decided and all of them.
fn same_with_and_without(bvh: &Bvh, set: &SampleSet, label: &str) -> (u64, u64) {
    let h = Hierarchy::build(set).unwrap();
    let plain = CastOptions {
        affine: false,
        ..CastOptions::default()
    };
    let mut reference = VisibilityBuffer::new(set);
    cast_opts(bvh, set, &h, &mut reference, plain);
    let (mut decided, mut tests) = (0, 0);
    for (lanes, isa) in [
        (4, Isa::Sse),
        (8, Isa::Sse),
        (8, Isa::Avx2),
        (16, Isa::Sse),
        (16, Isa::Avx2),
        (16, Isa::Avx512),
    ] {
        if isa.available() != isa {
            eprintln!("{label}: {isa:?} not detected, not compared");
            continue;
        }
        // The AVX-512 kernel, and the AVX2 16-lane kernel at 1 spp, take the packet test only
        // when asked (`affine_always`).
        let opts = CastOptions {
            lanes,
            isa,
            affine_always: true,
            ..CastOptions::default()
        };
        assert!(opts.affine);
        let mut with = VisibilityBuffer::new(set);
        let st = cast_opts(bvh, set, &h, &mut with, opts);
        assert_eq!(st.setup_rescues, 0, "{label}");
        let diff = with
            .prim
            .iter()
            .zip(&reference.prim)
            .zip(with.t.iter().zip(&reference.t))
            .filter(|((p, q), (s, u))| p != q || s.to_bits() != u.to_bits())
            .count();
        assert_eq!(
            diff, 0,
            "{label}: {lanes} lanes ({isa:?}): {diff} entries differ"
        );
        decided += st.setup_packet_out + st.setup_packet_in;
        tests += st.tri_tests;
    }
    (decided, tests)
}

/// Casts with the affine packet test equal casts without it, bit for bit: atrium and cornell,
/// pinhole grid, stereo and foveated sets, 1, 4, 16 and 32 spp (and Sponza at 16 spp when the
/// shared scenes are present).
#[test]
fn affine_packet_test_leaves_the_buffer_unchanged() {
    for name in ["atrium", "cornell"] {
        let scene = Scene::load(name).unwrap();
        let bvh = Bvh::build(&scene.mesh);
        for spp in [1, 4, 16, 32] {
            let sets = [
                (
                    "grid",
                    SampleSet::grid(camera(&scene, ModelKind::Pinhole, 64, 48), spp),
                ),
                (
                    "stereo",
                    SampleSet::grid(camera(&scene, ModelKind::Stereo, 40, 40), spp),
                ),
                (
                    "foveated",
                    SampleSet::foveated(
                        camera(&scene, ModelKind::Pinhole, 64, 48),
                        Vec2::new(30.0, 20.0),
                        8.0,
                        0.15,
                        spp,
                    )
                    .unwrap(),
                ),
            ];
            for (scheme, set) in sets {
                let label = format!("{name} {scheme} spp {spp}");
                let (decided, tests) = same_with_and_without(&bvh, &set, &label);
                eprintln!(
                    "{label}: packet test decided {decided} of {tests} packet-triangle tests"
                );
                assert!(decided > 0, "{label}: the packet test never decided");
            }
        }
    }
    let sponza = "../../../shared/scenes/sponza_dabrovic/sponza_dabrovic.glb";
    if std::path::Path::new(sponza).exists() {
        let scene = Scene::load(sponza).unwrap();
        let bvh = Bvh::build(&scene.mesh);
        let desc = CameraDesc::new(
            Vec3::new(-9.0, 3.5, 0.0),
            Vec3::new(8.0, 5.0, 0.0),
            Vec3::Y,
            60.0,
        );
        let cam = Camera::new(ModelKind::Stereo, &desc, 48, 40, &CameraOptions::default());
        let set = SampleSet::grid(cam.unwrap(), 16);
        let (decided, tests) = same_with_and_without(&bvh, &set, "sponza stereo spp 16");
        eprintln!("sponza: packet test decided {decided} of {tests}");
    }
}

/// A small deterministic generator in `[0, 1)`.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
}

/// Checks every packet (one pixel's 16 subsamples, and 4 x 4-pixel blocks at 1 spp) of a
/// pinhole around pixel `(px, py)` against `tri`: an `Out` packet has no lane the watertight
/// test hits, an `In` packet has every lane hit, an edge skipped for a partial packet
/// (`classify_edges`) is positive on every lane. Counts `(out, in, partial, skipped edges)`.
fn check_tri(set16: &SampleSet, set1: &SampleSet, tri: [Vec3; 3], counts: &mut [u64; 4]) {
    let Camera::Pinhole(p) = &set16.camera else {
        unreachable!()
    };
    let o = p.frame.position;
    let w = p.width;
    for (set, block) in [(set16, 1u32), (set1, 4u32)] {
        let fr = FilmFrame::of(set, o, 0.5).unwrap();
        let spp = set.spp as usize;
        for by in (0..p.height).step_by(block as usize) {
            for bx in (0..w).step_by(block as usize) {
                // The packet's rays and film box.
                let mut rays = Vec::new();
                let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
                for y in by..by + block {
                    for x in bx..bx + block {
                        let i = (y * w + x) as usize;
                        for k in 0..spp {
                            let s = &set.samples[i];
                            let f = s.film + set.offsets[k] * s.footprint;
                            lo = lo.min(f);
                            hi = hi.max(f);
                            rays.push(set.fast_subsample_ray(i, k).unwrap());
                        }
                    }
                }
                let Some(pb) = PacketBox::new(&fr, lo.x, hi.x, lo.y, hi.y) else {
                    continue;
                };
                // The packet's cone (as a tile's: centre and largest chord, widened).
                let c = rays.iter().map(|r| r.dir).sum::<Vec3>().normalize();
                let r = rays
                    .iter()
                    .map(|r| (r.dir - c).length())
                    .fold(0.0, f32::max);
                let cone = Cone {
                    centre: c,
                    radius: r * 1.001 + 1e-6,
                };
                let Some(ts) = TriSetup::new(tri, o, 0, 0, &cone) else {
                    continue;
                };
                let (class, inside) = pb.classify_edges(&fr.affine(&ts.n), ts.bound);
                assert_eq!(class, pb.classify(&fr.affine(&ts.n), ts.bound));
                // The branch-free word of the run walk: the same class and skip bits.
                let code = pb.classify_bits(&fr.affine(&ts.n), ts.bound);
                let word = match class {
                    PacketClass::Out => CLASS_OUT,
                    PacketClass::In => CLASS_IN,
                    PacketClass::Partial => inside,
                };
                assert_eq!(code, word, "{tri:?}");
                // An edge certainly inside for the packet is positive (in f64) on every ray.
                for e in (0..3).filter(|e| inside >> e & 1 != 0) {
                    assert_eq!(class, PacketClass::Partial);
                    counts[3] += 1;
                    for r in &rays {
                        let v: f64 = (0..3).map(|k| ts.n[e][k] as f64 * r.dir[k] as f64).sum();
                        assert!(v > 0.0, "edge {e} of {tri:?} skipped, value {v}");
                    }
                }
                let hits = rays
                    .iter()
                    .filter(|r: &&Ray| {
                        WatertightRay::new(r)
                            .intersect(tri[0], tri[1], tri[2])
                            .is_some()
                    })
                    .count();
                match class {
                    PacketClass::Out => {
                        assert_eq!(hits, 0, "Out packet ({bx}, {by}) with {hits} hits: {tri:?}");
                        counts[0] += 1;
                    }
                    PacketClass::In => {
                        assert_eq!(hits, rays.len(), "In packet ({bx}, {by}): {tri:?}");
                        counts[1] += 1;
                    }
                    PacketClass::Partial => counts[2] += 1,
                }
            }
        }
    }
}

/// The packet test never contradicts the watertight test, on triangles built to be hard:
/// edges through subsample rays (and their mirror images: shared edges), fans around a vertex
/// on a subsample ray, grazing (nearly edge-on) triangles, sub-pixel and huge triangles, at
/// distances from 1e-2 to 1e4; every class occurs.
#[test]
fn packet_classification_never_contradicts_the_watertight_test() {
    let desc = CameraDesc::new(
        Vec3::new(0.3, -1.2, 2.0),
        Vec3::new(1.0, 0.5, -3.0),
        Vec3::Y,
        50.0,
    );
    let (w, h) = (12, 12);
    let cam = Camera::new(ModelKind::Pinhole, &desc, w, h, &CameraOptions::default()).unwrap();
    let set16 = SampleSet::grid(cam.clone(), 16);
    let set1 = SampleSet::grid(cam, 1);
    let o = match &set16.camera {
        Camera::Pinhole(p) => p.frame.position,
        _ => unreachable!(),
    };
    let mut rng = Rng(7);
    let mut counts = [0u64; 4];
    let sub = |rng: &mut Rng| {
        let i = (rng.next() * (w * h) as f32) as usize;
        let k = (rng.next() * 16.0) as usize;
        set16.fast_subsample_ray(i, k).unwrap().dir
    };
    for case in 0..160 {
        let dist = 10f32.powf(rng.next() * 6.0 - 2.0);
        let (d1, d2) = (sub(&mut rng), sub(&mut rng));
        let (p1, p2) = (o + d1 * dist, o + d2 * dist * (0.5 + rng.next()));
        let side = (d1.cross(d2)).normalize_or_zero() * dist * (0.01 + rng.next());
        let tris: Vec<[Vec3; 3]> = match case % 4 {
            // An edge through two subsample rays, and its mirror (a shared edge).
            0 => {
                let mid = (p1 + p2) * 0.5;
                vec![[p1, p2, mid + side], [p2, p1, mid - side]]
            }
            // A fan of four triangles around a vertex on a subsample ray.
            1 => {
                let (a, b) = d1.any_orthonormal_pair();
                let s = dist * (0.002 + 0.05 * rng.next());
                let ring = [a, b, -a, -b].map(|x| p1 + x * s);
                (0..4).map(|q| [p1, ring[q], ring[(q + 1) % 4]]).collect()
            }
            // Grazing: nearly containing a subsample ray.
            2 => {
                let far = o + d1 * dist * 2.0;
                let eps = dist * 1e-4 * rng.next();
                vec![[p1, far, p1 + side * 1e-3 + d2 * eps], [p1, far + side, p2]]
            }
            // Sub-pixel to huge, random.
            _ => {
                let s = dist * 10f32.powf(rng.next() * 4.0 - 4.0);
                let j = |rng: &mut Rng| Vec3::new(rng.next(), rng.next(), rng.next()) - 0.5;
                vec![[
                    p1 + j(&mut rng) * s,
                    p1 + j(&mut rng) * s,
                    p1 + j(&mut rng) * s,
                ]]
            }
        };
        for t in tris {
            check_tri(&set16, &set1, t, &mut counts);
        }
    }
    eprintln!(
        "packets out {} in {} partial {} (edges skipped {})",
        counts[0], counts[1], counts[2], counts[3]
    );
    assert!(counts.iter().all(|&c| c > 100), "{counts:?}");
}

/// `PacketBox::new` (the film rectangle's packets in one register) equals the scalar
/// `PacketBox::new_general` field for field, bit for bit, on both eyes of a stereo rig and on a
/// pinhole: random pixel-sized to half-eye boxes inside, across and outside the eye's
/// rectangle, boxes on its borders, empty and non-finite ones.
#[test]
fn packet_box_equals_the_scalar_form() {
    let scene = Scene::load("atrium").unwrap();
    let mut rng = Rng(11);
    let (mut region, mut other, mut none) = (0u32, 0u32, 0u32);
    for kind in [ModelKind::Stereo, ModelKind::Pinhole] {
        let set = SampleSet::grid(camera(&scene, kind, 40, 30), 16);
        let (eyes, ew, h) = match &set.camera {
            Camera::Stereo(rig) => (2, rig.eye_width() as f32, 30.0),
            Camera::Pinhole(p) => (1, p.width as f32, p.height as f32),
            _ => unreachable!(),
        };
        for e in 0..eyes {
            let x0 = e as f32 * ew;
            let origin = match &set.camera {
                Camera::Stereo(rig) => rig.eyes[e].frame.position,
                Camera::Pinhole(p) => p.frame.position,
                _ => unreachable!(),
            };
            let fr = FilmFrame::of(&set, origin, x0 + 0.5).unwrap();
            let mut boxes = vec![
                (x0, x0 + ew, 0.0, h),
                (x0, x0, 0.0, 0.0),
                (x0 + ew, x0 + ew, h, h),
                (x0 - 1e-3, x0 + 1.0, 0.0, 1.0),
                (x0 + 1.0, x0 + 0.5, 0.0, 1.0),
                (f32::NAN, x0 + 1.0, 0.0, 1.0),
                (x0, x0 + 1.0, -f32::INFINITY, 1.0),
            ];
            for _ in 0..4000 {
                let size = [0.9, 3.9, ew * 0.5][(rng.next() * 3.0) as usize];
                let fx = x0 - 2.0 + rng.next() * (ew + 4.0);
                let fy = -2.0 + rng.next() * (h + 4.0);
                let (sx, sy) = (rng.next() * size, rng.next() * size);
                boxes.push((fx, fx + sx, fy, fy + sy));
            }
            for (a, b, c, d) in boxes {
                let fast = PacketBox::new(&fr, a, b, c, d);
                let slow = PacketBox::new_general(&fr, a, b, c, d);
                match (&fast, &slow) {
                    (Some(f), Some(s)) => {
                        // Bit for bit (`==` would equate signed zeros).
                        assert_eq!(format!("{f:?}"), format!("{s:?}"), "{a} {b} {c} {d}");
                        let inside = a >= x0 && b <= x0 + ew && c >= 0.0 && d <= h;
                        if inside { region += 1 } else { other += 1 }
                    }
                    (None, None) => none += 1,
                    _ => panic!("{a} {b} {c} {d}: {fast:?} vs {slow:?}"),
                }
            }
        }
    }
    eprintln!("packet boxes: region {region}, other {other}, none {none}");
    assert!(
        region > 1000 && other > 100 && none > 100,
        "{region} {other} {none}"
    );
}

/// `FilmFrame::dir_rows` (the sweep's direction bounds of sixteen packets from their boxes)
/// holds every lane's float ray, as the per-ray generator makes it, on both eyes of a stereo
/// rig and on pinholes of narrow and wide fields of view in random poses: random packets from a
/// point to several pixels inside the eye's film rectangle, their lanes at random points of
/// the box and at its corners.
#[test]
fn direction_bounds_hold_every_float_ray() {
    use parallax_scene::camera::CameraModel;
    let mut rng = Rng(23);
    let (mut packets, mut points) = (0u64, 0u64);
    for case in 0..12 {
        let kind = if case % 3 == 0 {
            ModelKind::Stereo
        } else {
            ModelKind::Pinhole
        };
        let mut r3 = || Vec3::new(rng.next(), rng.next(), rng.next()) * 20.0 - 10.0;
        let (eye, target) = (r3(), r3());
        let fov = [20.0, 60.0, 110.0, 150.0][case % 4];
        let desc = CameraDesc::new(eye, target, Vec3::Y, fov);
        let (w, h) = (64, 48);
        let cam = Camera::new(kind, &desc, w, h, &CameraOptions::default()).unwrap();
        let set = SampleSet::grid(cam, 16);
        let eyes: Vec<(f32, f32, Vec3)> = match &set.camera {
            Camera::Stereo(rig) => {
                let ew = rig.eye_width() as f32;
                (0..2)
                    .map(|e| (e as f32 * ew, ew, rig.eyes[e].frame.position))
                    .collect()
            }
            Camera::Pinhole(p) => vec![(0.0, p.width as f32, p.frame.position)],
            _ => unreachable!(),
        };
        for (x0, ew, origin) in eyes {
            let fr = FilmFrame::of(&set, origin, x0 + 0.5).unwrap();
            for _ in 0..200 {
                // A packet: a film box inside the eye's rectangle, its lanes.
                let size = [0.0, 1e-3, 1.0, 4.0][(rng.next() * 4.0) as usize];
                let fx0 = x0 + rng.next() * (ew - size);
                let fy0 = rng.next() * (h as f32 - size);
                let (fx1, fy1) = (fx0 + size, fy0 + size);
                assert!(fr.in_region(fx0, fx1, fy0, fy1));
                let [xc, yc, rx, ry, _, _] =
                    PacketBox::new(&fr, fx0, fx1, fy0, fy1).unwrap().scalars();
                // (One lane: the same float operations as each lane of sixteen.)
                let (lo, hi) = fr.dir_rows::<f32>([xc, yc, rx, ry]);
                let mut pts = vec![(fx0, fy0), (fx1, fy1), (fx0, fy1), (fx1, fy0)];
                for _ in 0..12 {
                    pts.push((fx0 + rng.next() * size, fy0 + rng.next() * size));
                }
                for (fx, fy) in pts {
                    let r = set
                        .camera
                        .generate_ray(Vec2::new(fx, fy), Vec2::ZERO, 0)
                        .unwrap()
                        .ray;
                    for a in 0..3 {
                        assert!(
                            lo[a] <= r.dir[a] && r.dir[a] <= hi[a],
                            "case {case} axis {a}: {} not in [{}, {}] at ({fx}, {fy})",
                            r.dir[a],
                            lo[a],
                            hi[a]
                        );
                    }
                    points += 1;
                }
                packets += 1;
            }
        }
    }
    assert!(points > 1_000, "{points} rays in {packets} packets");
}
