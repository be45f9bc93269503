//! Precision of the quad-tree's 64-bit plane nodes in the fitted and the camera-near unit
//! cube (Widmer et al. 2015, §3.2 / §3.4): per-ray comparison of the lossless quad-tree, brute
//! force over the exact f32 planes ([`LayerPlanes::build`], what the bench's `brute` traces),
//! brute force over the tree's decoded planes, and an f64 brute force over the f64 planes;
//! and the encoding error of every decoded pixel plane against the exact plane.
//!
//! `cd crates/screen && cargo run --release --example quadtree_precision -- [W H] [--scene S
//! --eye x,y,z --target x,y,z --fov-y deg] [--near M]` (default atrium 800x450, the fitted
//! cube and the camera cube `M` = 0.1 m). Sponza: `--scene
//! ../../../shared/scenes/sponza_dabrovic/sponza_dabrovic.glb --eye -9,3.5,0 --target 8,5,0`.
//!
//! Measured (atrium 800x450, 720,000 stereo rays; rays whose answer differs in kind / in
//! pixel from brute force over the exact f32 planes):
//!
//! | node | fitted cube | camera cube 0.1 m | decoded planes vertical in the cube |
//! |---|---|---|---|
//! | paper's f16 `N.x, N.y`, implied `N.z` | 9 / 117 | 103 (99 miss -> hit) / 358 | 10 / 2 |
//! | f16 slopes ([`parallax_screen::quadtree::node`]) | 0 / 0 | 2 / 8 | 0 / 0 |
//!
//! (Brute force over the exact f32 planes itself equals an f64 brute force over f64
//! planes on every ray here.)

use glam::{DVec3, UVec2, Vec2, Vec3};
use parallax_core::Ray;
use parallax_raster::{RasterOptions, View, capture_layers};
use parallax_scene::camera::{Eye, Pinhole, StereoRig};
use parallax_scene::{CameraDesc, Scene};
use parallax_screen::{
    BruteForcePlanes, CubeNear, LayerPlanes, NormalSource, QuadTreeOptions, QuadTreeTracer,
    ScreenTracer, TraceResult, TraceStats, UnitCube,
};
use rayon::prelude::*;

fn v3(s: &str) -> anyhow::Result<Vec3> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse())
        .collect::<Result<_, _>>()?;
    anyhow::ensure!(v.len() == 3, "need x,y,z");
    Ok(Vec3::new(v[0], v[1], v[2]))
}

/// f64 brute force over f64 planes: closest crossing (segment parameter, pixel) or first
/// occlusion entry, same rules as [`BruteForcePlanes`].
fn brute64(cube: &UnitCube, planes: &[(DVec3, f64)], ray: &Ray) -> TraceResult {
    let Some(seg) = cube.clip_ray(ray) else {
        return TraceResult::Miss;
    };
    let (w, h) = (cube.camera.width, cube.camera.height);
    let p0 = seg.p0.as_dvec3();
    let d = seg.p1.as_dvec3() - p0;
    let lo = seg.p0.min(seg.p1);
    let hi = seg.p0.max(seg.p1);
    let ix = |v: f32, n: u32| ((v * n as f32).floor().max(0.0) as u32).min(n - 1);
    let (mut best, mut occ) = ((f64::INFINITY, UVec2::ZERO), (f64::INFINITY, UVec2::ZERO));
    for j in ix(lo.y, h)..=ix(hi.y, h) {
        for i in ix(lo.x, w)..=ix(hi.x, w) {
            let (n, c) = planes[(j * w + i) as usize];
            if n == DVec3::ZERO {
                continue;
            }
            let (mut sa, mut sb) = (0.0f64, 1.0f64);
            let mut ok = true;
            for (o, dd, r0, r1) in [
                (p0.x, d.x, i as f64 / w as f64, (i + 1) as f64 / w as f64),
                (p0.y, d.y, j as f64 / h as f64, (j + 1) as f64 / h as f64),
            ] {
                if dd == 0.0 {
                    ok &= o >= r0 && o <= r1;
                } else {
                    let (t0, t1) = ((r0 - o) / dd, (r1 - o) / dd);
                    sa = sa.max(t0.min(t1));
                    sb = sb.min(t0.max(t1));
                }
            }
            if !ok || sa > sb {
                continue;
            }
            let f0 = n.dot(p0) - c;
            let fd = n.dot(d);
            let (fa, fb) = (f0 + fd * sa, f0 + fd * sb);
            if (fa <= 0.0) != (fb <= 0.0) || fa == 0.0 || fb == 0.0 {
                let s = if fd != 0.0 {
                    (-f0 / fd).clamp(sa, sb)
                } else {
                    sa
                };
                if s < best.0 {
                    best = (s, UVec2::new(i, j));
                }
            } else if fa < 0.0 && sa < occ.0 {
                occ = (sa, UVec2::new(i, j));
            }
        }
    }
    if best.0.is_finite() {
        let t = seg.world_t(best.0 as f32);
        TraceResult::Hit {
            layer: 0,
            pixel: best.1,
            position: ray.at(t),
            t,
        }
    } else if occ.0.is_finite() {
        TraceResult::OcclusionVolume {
            layer: 0,
            pixel: occ.1,
            t: seg.world_t(occ.0 as f32),
        }
    } else {
        TraceResult::Miss
    }
}

fn kind(r: &TraceResult) -> &'static str {
    match r {
        TraceResult::Hit { .. } => "hit",
        TraceResult::OcclusionVolume { .. } => "ov",
        TraceResult::Miss => "miss",
    }
}

fn t_of(r: &TraceResult) -> Option<(f32, UVec2)> {
    match *r {
        TraceResult::Hit { t, pixel, .. } => Some((t, pixel)),
        TraceResult::OcclusionVolume { t, pixel, .. } => Some((t, pixel)),
        _ => None,
    }
}

/// Differences of `b` against the reference `a`: (kind differs, same kind but another
/// pixel, same pixel but |dt|/t > 1e-4); plus examples.
fn compare(name: &str, a: &[TraceResult], b: &[TraceResult], w: u32) {
    let (mut kinds, mut pix, mut tdiff) = (0usize, 0usize, 0usize);
    let mut max_rel = 0.0f32;
    let mut pairs = std::collections::BTreeMap::<(&str, &str), usize>::new();
    let mut shown = 0;
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        if kind(x) != kind(y) {
            kinds += 1;
            *pairs.entry((kind(x), kind(y))).or_default() += 1;
            if shown < 6 {
                shown += 1;
                println!(
                    "    ray px ({}, {}): {:?} vs {:?}",
                    k as u32 % w,
                    k as u32 / w,
                    t_of(x),
                    t_of(y)
                );
            }
            continue;
        }
        if let (Some((ta, pa)), Some((tb, pb))) = (t_of(x), t_of(y)) {
            if pa != pb {
                pix += 1;
                if shown < 6 {
                    shown += 1;
                    println!(
                        "    ray px ({}, {}) {}: {:?} vs {:?}",
                        k as u32 % w,
                        k as u32 / w,
                        kind(x),
                        (ta, pa),
                        (tb, pb)
                    );
                }
            } else {
                let rel = (ta - tb).abs() / ta.abs().max(1e-6);
                max_rel = max_rel.max(rel);
                if rel > 1e-4 {
                    tdiff += 1;
                }
            }
        }
    }
    println!(
        "  {name}: {kinds} rays of another kind {pairs:?}, {pix} another pixel, {tdiff} same pixel with |dt|/t > 1e-4 (max rel dt on same pixel {max_rel:.2e})"
    );
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (mut w, mut h) = (800u32, 450u32);
    let mut scene_name = "atrium".to_string();
    let (mut eye, mut target, mut fov) = (None, None, 60.0f32);
    let mut nears = vec![CubeNear::Fitted, CubeNear::Camera(0.1)];
    let mut nums = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--scene" => scene_name = it.next().unwrap().clone(),
            "--eye" => eye = Some(v3(it.next().unwrap())?),
            "--target" => target = Some(v3(it.next().unwrap())?),
            "--fov-y" => fov = it.next().unwrap().parse()?,
            "--near" => {
                nears = vec![
                    CubeNear::Fitted,
                    CubeNear::Camera(it.next().unwrap().parse()?),
                ]
            }
            v => nums.push(v.parse::<u32>()?),
        }
    }
    if nums.len() == 2 {
        (w, h) = (nums[0], nums[1]);
    }
    let scene = Scene::load(&scene_name)?;
    let desc = match (eye, target) {
        (Some(e), Some(t)) => CameraDesc::new(e, t, Vec3::Y, fov),
        _ => scene.camera(None)?,
    };
    let cam = Pinhole::new(&desc, w, h)?;
    let cap = capture_layers(
        &scene,
        &View::from_pinhole(&cam)?,
        &RasterOptions::layers(1),
    )?;
    let layer = &cap.layers.layers[0];
    let rig = StereoRig::new(&desc, w, h, 0.065)?;
    let mut rays = Vec::new();
    for e in [Eye::Left, Eye::Right] {
        let ec = rig.eye(e);
        for y in 0..h {
            for x in 0..w {
                let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                rays.push(Ray::new(
                    ec.frame.position,
                    ec.frame.dir_to_world(ec.camera_dir(film)).normalize(),
                ));
            }
        }
    }
    println!(
        "{scene_name} {w}x{h}, 1 layer, {} stereo rays (both eyes, ipd 0.065)",
        rays.len()
    );
    for near in nears {
        let cube = UnitCube::fit(&cam, [&layer.depth[..]], near)?;
        let kk = 1.0 / cube.near as f64 - 1.0 / cube.far as f64;
        println!(
            "\n## cube {near:?}: near {} far {}, K = 1/near - 1/far = {kk:.4}",
            cube.near, cube.far
        );
        let exact = LayerPlanes::build(&cube, layer, NormalSource::GBuffer)?;
        // f64 planes: the world plane through the pixel sample, mapped in f64 (map_plane
        // without the final f32 rounding).
        let mut p64 = vec![(DVec3::ZERO, 0.0f64); (w * h) as usize];
        let mut zrange = (f32::INFINITY, f32::NEG_INFINITY);
        for j in 0..h {
            for i in 0..w {
                let k = (j * w + i) as usize;
                let d = layer.depth[k];
                if !(d.is_finite() && d > 0.0) || layer.normal[k] == Vec3::ZERO {
                    continue;
                }
                let z = cube.z_of_depth(d);
                zrange = (zrange.0.min(z), zrange.1.max(z));
                let film = Vec2::new(i as f32 + 0.5, j as f32 + 0.5);
                let p = cam.frame.position + cam.frame.dir_to_world(cam.camera_dir(film)) * d;
                let n = layer.normal[k].as_dvec3();
                let pi = n.extend(-n.dot(p.as_dvec3()));
                let q = cube.cube_to_world.transpose() * pi;
                let mut q = q / q.truncate().length();
                if q.z > 0.0 {
                    q = -q;
                }
                p64[k] = (q.truncate(), -q.w);
            }
        }
        println!("  captured z range [{:.6}, {:.6}]", zrange.0, zrange.1);
        let qt = QuadTreeTracer::build(
            &cube,
            std::slice::from_ref(layer),
            &QuadTreeOptions::lossless(),
        )?;
        let decoded = qt.trees[0].effective_planes();
        // Encoding error at the footprint corners: decoded vs f64 plane, in cube z, and as
        // a disparity error in pixels of the eye (`|dz| K f_px b`, b = ipd / 2).
        let fpx = w as f64 / (2.0 * (cam.tan_half_y as f64 * w as f64 / h as f64));
        let b = 0.0325f64;
        let zat = |n: DVec3, c: f64, x: f64, y: f64| (c - n.x * x - n.y * y) / n.z;
        let mut errs: Vec<(f64, f64, usize)> = Vec::new(); // (|dz| decoded, |dz| exact f32, k)
        for j in 0..h {
            for i in 0..w {
                let k = (j * w + i) as usize;
                let (n, c) = p64[k];
                if n == DVec3::ZERO || !decoded.covered(k) || !exact.covered(k) {
                    continue;
                }
                let (nd, cd) = (decoded.normal[k].as_dvec3(), decoded.offset[k] as f64);
                let (ne, ce) = (exact.normal[k].as_dvec3(), exact.offset[k] as f64);
                let (mut ed, mut ee) = (0.0f64, 0.0f64);
                for (x, y) in [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)] {
                    let (x, y) = (x as f64 / w as f64, y as f64 / h as f64);
                    let z = zat(n, c, x, y);
                    ed = ed.max((zat(nd, cd, x, y) - z).abs());
                    ee = ee.max((zat(ne, ce, x, y) - z).abs());
                }
                errs.push((ed, ee, k));
            }
        }
        let pct = |v: &mut Vec<f64>, q: f64| {
            v.sort_by(f64::total_cmp);
            v[((v.len() - 1) as f64 * q) as usize]
        };
        let mut ed: Vec<f64> = errs.iter().map(|e| e.0).collect();
        let mut ee: Vec<f64> = errs.iter().map(|e| e.1).collect();
        for (name, v) in [("decoded (node)", &mut ed), ("exact f32 planes", &mut ee)] {
            let (p50, p99, p999, max) = (pct(v, 0.5), pct(v, 0.99), pct(v, 0.999), pct(v, 1.0));
            println!(
                "  plane z error at footprint corners, {name}: median {p50:.2e}, p99 {p99:.2e}, p99.9 {p999:.2e}, max {max:.2e} cube z; max as disparity {:.2e} px",
                max * kk * fpx * b
            );
        }
        for thr in [1e-6, 1e-5, 1e-3] {
            let n = errs.iter().filter(|e| e.0 > thr).count();
            let ne = errs.iter().filter(|e| e.1 > thr).count();
            println!(
                "  planes with corner z error > {thr:e}: decoded {n}, exact f32 {ne} (of {})",
                errs.len()
            );
        }
        let nz0 = (0..(w * h) as usize)
            .filter(|&k| decoded.covered(k) && decoded.normal[k].z == 0.0)
            .count();
        println!("  decoded planes with N.z == 0 (vertical in the cube): {nz0}");
        let worst = errs.iter().max_by(|a, b| a.0.total_cmp(&b.0)).unwrap();
        let k = worst.2;
        println!(
            "  worst decoded pixel ({}, {}): depth {} m, exact normal {:?}, decoded {:?}",
            k as u32 % w,
            k as u32 / w,
            layer.depth[k],
            p64[k].0,
            decoded.normal[k]
        );

        let bf_exact = BruteForcePlanes {
            cube: cube.clone(),
            layers: vec![exact.clone()],
        };
        let bf_dec = BruteForcePlanes {
            cube: cube.clone(),
            layers: vec![decoded.clone()],
        };
        let trace = |t: &(dyn ScreenTracer + Sync)| -> Vec<TraceResult> {
            rays.par_iter()
                .map(|r| t.trace(r, &mut TraceStats::default()))
                .collect()
        };
        let r_qt = trace(&qt);
        let r_ex = trace(&bf_exact);
        let r_dec = trace(&bf_dec);
        let r_64: Vec<TraceResult> = rays.par_iter().map(|r| brute64(&cube, &p64, r)).collect();
        compare("quadtree vs brute(decoded planes)", &r_dec, &r_qt, w);
        compare("quadtree vs brute(exact f32 planes)", &r_ex, &r_qt, w);
        compare("brute(exact f32) vs brute64", &r_64, &r_ex, w);
        compare("quadtree vs brute64", &r_64, &r_qt, w);
    }
    Ok(())
}
