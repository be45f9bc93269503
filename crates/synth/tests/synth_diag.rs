//! Diagnostics of stereo-warp quality (ignored; run in release):
//! `SYNTH_DIAG_SCENE=atrium SYNTH_DIAG_OUT=/tmp/x cargo test --release -p parallax-render
//! --test synth_diag -- --ignored --nocapture`. For every method x layers x resampling it prints
//! the PSNR and splits the squared error (display values) of the left eye by answer kind and by
//! whether the answer is the BVH's surface (hit within 1% of the BVH hit's depth). It also
//! prints the PSNR of the BVH truth shaded with the *reference* eye's view direction (the cost
//! of view-dependent shading that any reuse of reference shading pays) and writes error heat
//! maps to `SYNTH_DIAG_OUT` when set.

use glam::{Vec2, Vec3};
use parallax_bvh::{Bvh, Hit};
use parallax_core::image::png::{ToneMapping, Tonemap, tonemap_image, write_png};
use parallax_core::{Image, Ray, Rgb};
use parallax_render::reference::render_gbuffer;
use parallax_render::reference::shade::Shader;
use parallax_render::score::{SCORE_TONEMAP, ground_truth};
use parallax_scene::camera::{Camera, CameraModel, Pinhole};
use parallax_scene::{CameraDesc, Scene};
use parallax_screen::TraceResult;
use parallax_synth::method::{Method, MethodOptions, build_tracer};
use parallax_synth::stereo::stereo_eyes;
use parallax_synth::warp::{HitKind, Resample, WarpOptions, warp_view_with};
use parallax_synth::{Shading, capture_reference, score};

fn setup() -> (Scene, CameraDesc, u32, u32) {
    let name = std::env::var("SYNTH_DIAG_SCENE").unwrap_or_else(|_| "atrium".into());
    let w: u32 = std::env::var("SYNTH_DIAG_W").map_or(1600, |s| s.parse().unwrap());
    let h: u32 = std::env::var("SYNTH_DIAG_H").map_or(900, |s| s.parse().unwrap());
    let scene = Scene::load(&name).unwrap();
    let desc = if name.contains("sponza") {
        CameraDesc::new(
            Vec3::new(-9.0, 3.5, 0.0),
            Vec3::new(8.0, 5.0, 0.0),
            Vec3::Y,
            60.0,
        )
    } else {
        scene.camera(None).unwrap()
    };
    (scene, desc, w, h)
}

/// The truth shaded with the reference eye's view direction at the eye's BVH hit.
fn truth_ref_dir(scene: &Scene, bvh: &Bvh, eye: &Pinhole, ref_pos: Vec3) -> Image<Rgb> {
    let shader = Shader::new(scene, bvh);
    let (w, h) = (eye.width, eye.height);
    let mut out = vec![scene.environment; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let cr = eye.generate_ray(film, Vec2::splat(0.5), 1).unwrap();
            let Some(hit) = bvh.closest_hit(&cr.ray) else {
                continue;
            };
            let p = cr.ray.origin + cr.ray.dir * hit.t;
            let d = p - ref_pos;
            let ray = Ray::new(ref_pos, d.normalize());
            let hit2 = Hit {
                t: d.length(),
                ..hit
            };
            let mut rng = Shading::Fixed.rng(0, x, y, 0);
            let mut rays = 0;
            out[(y * w + x) as usize] = shader.radiance_from_hit(ray, hit2, &mut rng, &mut rays);
        }
    }
    Image::from_vec(w, h, out).unwrap()
}

#[test]
#[ignore]
fn diagnose_stereo_warp() {
    let (scene, desc, w, h) = setup();
    let bvh = Bvh::try_build(&scene.mesh).unwrap();
    let ipd = 0.065;
    let eyes = stereo_eyes(&desc, w, h, ipd).unwrap();
    let truths: Vec<_> = eyes
        .iter()
        .map(|e| ground_truth(&scene, &bvh, e, Shading::Fixed, 0))
        .collect();
    let out = std::env::var("SYNTH_DIAG_OUT").ok();
    let cam = Pinhole::new(&desc, w, h).unwrap();
    if std::env::var("SYNTH_DIAG_VIEWDEP").is_ok() {
        let t = truth_ref_dir(&scene, &bvh, &eyes[0], cam.frame.position);
        eprintln!(
            "view-dependent shading: truth vs truth shaded from the reference eye: {:.2} dB",
            score(&t, &truths[0]).unwrap().psnr
        );
    }
    let ei: usize = std::env::var("SYNTH_DIAG_EYE").map_or(0, |s| s.parse().unwrap());
    let g = render_gbuffer(&scene, &bvh, &Camera::Pinhole(eyes[ei].clone()));
    let tm_truth = tonemap_image(&truths[ei], &SCORE_TONEMAP);
    let methods: Vec<Method> = std::env::var("SYNTH_DIAG_METHODS")
        .map(|s| Method::parse_list(&s).unwrap())
        .unwrap_or(vec![Method::QuadTree, Method::Brute, Method::Dda]);
    for layers in [1usize, 2] {
        let r = capture_reference(&scene, &bvh, &cam, layers, Shading::Fixed, 0).unwrap();
        for &m in &methods {
            let tracer = build_tracer(m, &r.cube, &r.layers, &MethodOptions::default()).unwrap();
            let variants = [
                (Resample::Nearest, false),
                (Resample::Bilinear, false),
                (Resample::Bilinear, true),
            ];
            for (rs, guard) in variants {
                if guard && layers == 1 {
                    continue;
                }
                let wo = WarpOptions {
                    resample: rs,
                    ..WarpOptions::default()
                }
                .with_layer0_guard(guard);
                let views: Vec<_> = eyes
                    .iter()
                    .map(|e| warp_view_with(tracer.as_ref(), &r, e, &wo))
                    .collect();
                let pe: Vec<f64> = views
                    .iter()
                    .zip(&truths)
                    .map(|(v, t)| score(&v.image, t).unwrap().psnr)
                    .collect();
                let p = (pe[0] + pe[1]) / 2.0;
                // Error split of the left eye.
                let v = &views[ei];
                let tm = tonemap_image(&v.image, &SCORE_TONEMAP);
                // classes: hit L0 right, hit L0 wrong, hit L1 right, hit L1 wrong, occl, miss
                let mut se = [0f64; 6];
                let (mut hx, mut hy) = ([0f64; 16], [0f64; 9]);
                let mut cnt = [0usize; 6];
                let mut heat = vec![Vec3::ZERO; (w * h) as usize];
                for y in 0..h {
                    for x in 0..w {
                        let i = (y * w + x) as usize;
                        let e = (tm.data()[i] - tm_truth.data()[i]).abs();
                        let e2 = e.length_squared() as f64 / 3.0;
                        heat[i] = e;
                        let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                        let cr = eyes[ei].generate_ray(film, Vec2::splat(0.5), 1).unwrap();
                        let c = match tracer.trace(&cr.ray, &mut Default::default()) {
                            TraceResult::Hit {
                                layer, position, ..
                            } => {
                                let s = g.get(x, y);
                                let ok = s.is_hit()
                                    && (position - s.position).length()
                                        < 0.01 * (s.position - cr.ray.origin).length();
                                (layer.min(1) * 2) as usize + (!ok) as usize
                            }
                            TraceResult::OcclusionVolume { .. } => 4,
                            TraceResult::Miss => 5,
                        };
                        debug_assert!(matches!(v.kinds[i], HitKind::Hit(_)) == (c < 4));
                        if c == 3 {
                            hx[(x * 16 / w) as usize] += e2;
                            hy[(y * 9 / h) as usize] += e2;
                        }
                        se[c] += e2;
                        cnt[c] += 1;
                    }
                }
                let n = (w * h) as f64;
                let total: f64 = se.iter().sum();
                let names = ["L0ok", "L0bad", "L1ok", "L1bad", "occ", "miss"];
                let split: Vec<String> = (0..6)
                    .map(|k| {
                        format!(
                            "{} {:.2}%px {:.1}%err",
                            names[k],
                            100.0 * cnt[k] as f64 / n,
                            100.0 * se[k] / total
                        )
                    })
                    .collect();
                eprintln!(
                    "{m} {layers}L {rs:?} guard {guard}: {p:.2} dB (L {:.2} R {:.2}) | left MSE {:.5} | {}",
                    pe[0],
                    pe[1],
                    total / n,
                    split.join(", ")
                );
                let nrm = |v: &[f64]| -> Vec<u32> {
                    v.iter().map(|e| (100.0 * e / total) as u32).collect()
                };
                eprintln!(
                    "  L1bad err% by x/16: {:?} by y/9: {:?}",
                    nrm(&hx),
                    nrm(&hy)
                );
                if let Some(dir) = &out {
                    let img =
                        Image::from_vec(w, h, heat.iter().map(|e| *e * 4.0).collect()).unwrap();
                    let path = format!(
                        "{dir}/{}_{m}_{layers}L_{rs:?}_{guard}_eye{ei}_err.png",
                        scene.name
                    );
                    let lin = ToneMapping {
                        exposure: 0.0,
                        tonemap: Tonemap::Clamp,
                    };
                    let _ = write_png(&path, &img, &lin);
                }
            }
        }
    }
}

/// 1 layer + background fill against 2 layers (defaults), per pixel of the left eye: the
/// squared-error difference (2L - 1L, tone-mapped display values) summed by the class of the
/// 2-layer answer (raw tracer answer -> final answer after the layer-0 guard) and the 1-layer
/// answer. Same env vars as [`diagnose_stereo_warp`].
#[test]
#[ignore]
fn diagnose_one_vs_two_layers() {
    use std::collections::BTreeMap;
    let (scene, desc, w, h) = setup();
    let bvh = Bvh::try_build(&scene.mesh).unwrap();
    let eyes = stereo_eyes(&desc, w, h, 0.065).unwrap();
    let cam = Pinhole::new(&desc, w, h).unwrap();
    let m = Method::QuadTree;
    let r1 = capture_reference(&scene, &bvh, &cam, 1, Shading::Fixed, 0).unwrap();
    let r2 = capture_reference(&scene, &bvh, &cam, 2, Shading::Fixed, 0).unwrap();
    let t1 = build_tracer(m, &r1.cube, &r1.layers, &MethodOptions::default()).unwrap();
    let t2 = build_tracer(m, &r2.cube, &r2.layers, &MethodOptions::default()).unwrap();
    let wo = WarpOptions::default();
    let name = |k: HitKind| match k {
        HitKind::Hit(l) => format!("H{l}"),
        HitKind::Occlusion(l) => format!("O{l}"),
        HitKind::Miss => "M".into(),
    };
    let raw = |r: TraceResult| match r {
        TraceResult::Hit { layer, .. } => format!("H{layer}"),
        TraceResult::OcclusionVolume { layer, .. } => format!("O{layer}"),
        TraceResult::Miss => "M".into(),
    };
    for (ei, eye) in eyes.iter().enumerate() {
        let truth = ground_truth(&scene, &bvh, eye, Shading::Fixed, 0);
        let g = render_gbuffer(&scene, &bvh, &Camera::Pinhole(eye.clone()));
        let v1 = warp_view_with(t1.as_ref(), &r1, eye, &wo);
        let v2 = warp_view_with(t2.as_ref(), &r2, eye, &wo);
        let p1 = score(&v1.image, &truth).unwrap().psnr;
        let p2 = score(&v2.image, &truth).unwrap().psnr;
        let tt = tonemap_image(&truth, &SCORE_TONEMAP);
        let a = tonemap_image(&v1.image, &SCORE_TONEMAP);
        let b = tonemap_image(&v2.image, &SCORE_TONEMAP);
        // class -> (count, se1, se2)
        let mut cls: BTreeMap<String, (usize, f64, f64)> = BTreeMap::new();
        let (mut s1, mut s2) = (0f64, 0f64);
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let e1 = (a.data()[i] - tt.data()[i]).length_squared() as f64 / 3.0;
                let e2 = (b.data()[i] - tt.data()[i]).length_squared() as f64 / 3.0;
                s1 += e1;
                s2 += e2;
                let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let cr = eye.generate_ray(film, Vec2::splat(0.5), 1).unwrap();
                let rr = t2.trace(&cr.ray, &mut Default::default());
                let mut ok = String::new();
                if let TraceResult::Hit { position, .. } = rr {
                    let s = g.get(x, y);
                    let good = s.is_hit()
                        && (position - s.position).length()
                            < 0.01 * (s.position - cr.ray.origin).length();
                    ok = if good { "+" } else { "-" }.into();
                }
                let key = format!(
                    "2L {}{ok}->{} | 1L {}",
                    raw(rr),
                    name(v2.kinds[i]),
                    name(v1.kinds[i])
                );
                if std::env::var("SYNTH_DIAG_DUMP").is_ok()
                    && key.starts_with(&std::env::var("SYNTH_DIAG_DUMP").unwrap())
                    && e2 > 0.05
                    && (x + y) % 7 == 0
                {
                    let r1r = t1.trace(&cr.ray, &mut Default::default());
                    let s = g.get(x, y);
                    if let TraceResult::Hit {
                        pixel, position, ..
                    } = rr
                    {
                        let l1 = r2.layers[1].get(pixel.x, pixel.y);
                        let l0 = r2.layers[0].get(pixel.x, pixel.y);
                        eprintln!(
                            "   hitdepth {:.3} px {x},{y} truth {:?} 1L {:?} 2L {:?} | L1 px {pixel} prim {} d {:.3} c {:?} | L0 there prim {} d {:.3} c {:?} | bvh prim {} | 2Lpos {position} bvh {} | 1L {:?}",
                            r2.cube.homogeneous(position).w,
                            tt.data()[i],
                            a.data()[i],
                            b.data()[i],
                            l1.primitive_id,
                            l1.depth,
                            r2.colors[1].get(pixel.x, pixel.y),
                            l0.primitive_id,
                            l0.depth,
                            r2.colors[0].get(pixel.x, pixel.y),
                            s.primitive_id,
                            s.position,
                            r1r
                        );
                    }
                }
                let e = cls.entry(key).or_default();
                e.0 += 1;
                e.1 += e1;
                e.2 += e2;
            }
        }
        let n = (w * h) as f64;
        eprintln!(
            "eye {ei}: 1L+fill {p1:.2} dB, 2L {p2:.2} dB; MSE 1L {:.6} 2L {:.6} (diff {:.6})",
            s1 / n,
            s2 / n,
            (s2 - s1) / n
        );
        let mut rows: Vec<_> = cls.into_iter().collect();
        rows.sort_by(|x, y| ((y.1.2 - y.1.1).abs()).total_cmp(&(x.1.2 - x.1.1).abs()));
        for (k, (c, e1, e2)) in rows.iter().take(18) {
            eprintln!(
                "  {k:28} {:6.2}%px  se1 {:9.2} se2 {:9.2}  d {:+9.2} ({:+.1}% of total diff)",
                100.0 * *c as f64 / n,
                e1,
                e2,
                e2 - e1,
                100.0 * (e2 - e1) / (s2 - s1)
            );
        }
    }
}

/// Where 2 layers are worse (or better) than 1 layer, per pixel, for each method of
/// `SYNTH_DIAG_METHODS` (default quadtree,brute) on the fitted cube (as `bench warp`), ipd
/// `SYNTH_DIAG_IPD` (default 0.065). Each pixel whose 2-layer answer differs from its 1-layer
/// answer is classed by: final 2-layer kind, 1-layer kind, whether the 2-layer hit is the BVH
/// surface (`+`/`-`), the layer-1 sample's gap behind layer 0 at its pixel (`gap<1%`,
/// `gap<5%`, `gap>5%`), whether layer 0 has a depth edge (> 5%) in the 3x3 around that pixel (`L0edge`/`L0interior`),
/// and whether the 1-layer answer was already good (`1Lok`: squared error < 1e-3). Prints
/// the squared-error change per class (2L - 1L, summed over both eyes).
#[test]
#[ignore]
fn diagnose_worse_pixels() {
    use std::collections::BTreeMap;
    let (scene, desc, w, h) = setup();
    let bvh = Bvh::try_build(&scene.mesh).unwrap();
    let ipd: f32 = std::env::var("SYNTH_DIAG_IPD").map_or(0.065, |s| s.parse().unwrap());
    let eyes = stereo_eyes(&desc, w, h, ipd).unwrap();
    let cam = Pinhole::new(&desc, w, h).unwrap();
    let methods: Vec<Method> = std::env::var("SYNTH_DIAG_METHODS")
        .map(|s| Method::parse_list(&s).unwrap())
        .unwrap_or(vec![Method::QuadTree, Method::Brute]);
    let mo = MethodOptions::default();
    let mut r1 = capture_reference(&scene, &bvh, &cam, 1, Shading::Fixed, 0).unwrap();
    let mut r2 = capture_reference(&scene, &bvh, &cam, 2, Shading::Fixed, 0).unwrap();
    r1.fit_cube(mo.cube_near).unwrap();
    r2.fit_cube(mo.cube_near).unwrap();
    let truths: Vec<_> = eyes
        .iter()
        .map(|e| ground_truth(&scene, &bvh, e, Shading::Fixed, 0))
        .collect();
    let gts: Vec<_> = eyes
        .iter()
        .map(|e| render_gbuffer(&scene, &bvh, &Camera::Pinhole(e.clone())))
        .collect();
    let wo = mo.warp;
    let name = |k: HitKind| match k {
        HitKind::Hit(l) => format!("H{l}"),
        HitKind::Occlusion(l) => format!("O{l}"),
        HitKind::Miss => "M".into(),
    };
    let dump = std::env::var("SYNTH_DIAG_DUMP").ok();
    for &m in &methods {
        let t1 = build_tracer(m, &r1.cube, &r1.layers, &mo).unwrap();
        let t2 = build_tracer(m, &r2.cube, &r2.layers, &mo).unwrap();
        let mut cls: BTreeMap<String, (usize, f64, f64)> = BTreeMap::new();
        let (mut s1, mut s2, mut p) = (0f64, 0f64, [0f64; 4]);
        for (ei, eye) in eyes.iter().enumerate() {
            let v1 = warp_view_with(t1.as_ref(), &r1, eye, &wo);
            let v2 = warp_view_with(t2.as_ref(), &r2, eye, &wo);
            p[ei] = score(&v1.image, &truths[ei]).unwrap().psnr;
            p[2 + ei] = score(&v2.image, &truths[ei]).unwrap().psnr;
            let tt = tonemap_image(&truths[ei], &SCORE_TONEMAP);
            let a = tonemap_image(&v1.image, &SCORE_TONEMAP);
            let b = tonemap_image(&v2.image, &SCORE_TONEMAP);
            let org = eye.frame.position;
            for y in 0..h {
                for x in 0..w {
                    let i = (y * w + x) as usize;
                    let e1 = (a.data()[i] - tt.data()[i]).length_squared() as f64 / 3.0;
                    let e2 = (b.data()[i] - tt.data()[i]).length_squared() as f64 / 3.0;
                    s1 += e1;
                    s2 += e2;
                    if (e2 - e1).abs() < 1e-9 {
                        continue;
                    }
                    let mut key = format!("{} | 1L {}", name(v2.kinds[i]), name(v1.kinds[i]));
                    let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    let cr = eye.generate_ray(film, Vec2::splat(0.5), 1).unwrap();
                    let rr = t2.trace(&cr.ray, &mut Default::default());
                    if let (
                        HitKind::Hit(1),
                        TraceResult::Hit {
                            pixel, position, ..
                        },
                    ) = (v2.kinds[i], rr)
                    {
                        let s = gts[ei].get(x, y);
                        let good = s.is_hit()
                            && (position - s.position).length()
                                < 0.01 * (s.position - org).length();
                        let l0 = r2.layers[0].get(pixel.x, pixel.y);
                        let l1 = r2.layers[1].get(pixel.x, pixel.y);
                        let gap = (l1.depth - l0.depth) / l0.depth;
                        let dh = r2.cube.homogeneous(position).w as f32;
                        let mut mid0 = false;
                        let mut mid1 = false;
                        for dy in -1i32..=1 {
                            for dx in -1i32..=1 {
                                let (nx, ny) = (pixel.x as i32 + dx, pixel.y as i32 + dy);
                                if nx < 0 || ny < 0 || nx >= w as i32 || ny >= h as i32 {
                                    continue;
                                }
                                for (k, flag) in [(0usize, &mut mid0), (1, &mut mid1)] {
                                    let dn = r2.layers[k].get(nx as u32, ny as u32).depth;
                                    let _ = dh;
                                    if k == 0
                                        && !(dn.is_finite()
                                            && (dn - l0.depth).abs() < 0.05 * l0.depth)
                                    {
                                        *flag = true;
                                    }
                                }
                            }
                        }
                        key += &format!(
                            " {} {} {}",
                            if good { "+" } else { "-" },
                            if gap < 0.01 {
                                "gap<1%"
                            } else if gap < 0.05 {
                                "gap<5%"
                            } else {
                                "gap>5%"
                            },
                            if mid0 { "L0edge" } else { "L0interior" }
                        );
                        if let Some(d) = &dump
                            && key.contains(d.as_str())
                            && e2 - e1 > 0.02
                        {
                            eprintln!(
                                "   eye{ei} px {x},{y} truth {:.2?} 1L {:.2?} 2L {:.2?} | L1 px {pixel} d0 {:.3} d1 {:.3} prim {} c1 {:.2?} | bvh prim {} d {:.3} refcos {:.3} eyecos {:.3} | 1L {:?}",
                                tt.data()[i],
                                a.data()[i],
                                b.data()[i],
                                l0.depth,
                                l1.depth,
                                l1.primitive_id,
                                r2.colors[1].get(pixel.x, pixel.y),
                                s.primitive_id,
                                (s.position - org).length(),
                                scene
                                    .mesh
                                    .geometric_normal(s.primitive_id as usize)
                                    .dot((cam.frame.position - s.position).normalize()),
                                scene
                                    .mesh
                                    .geometric_normal(s.primitive_id as usize)
                                    .dot((org - s.position).normalize()),
                                v1.kinds[i]
                            );
                            let hc = r2.cube.homogeneous(position);
                            let fx = (hc.x / hc.w) as f32 * w as f32 - pixel.x as f32;
                            let fy = (hc.y / hc.w) as f32 * h as f32 - pixel.y as f32;
                            let nb: Vec<String> = [(-1i32, 0i32), (1, 0), (0, -1), (0, 1)]
                                .iter()
                                .map(|(dx, dy)| {
                                    let (nx, ny) = (
                                        (pixel.x as i32 + dx).clamp(0, w as i32 - 1) as u32,
                                        (pixel.y as i32 + dy).clamp(0, h as i32 - 1) as u32,
                                    );
                                    format!(
                                        "{:.2}/{:.2}",
                                        r2.layers[0].get(nx, ny).depth,
                                        r2.layers[1].get(nx, ny).depth
                                    )
                                })
                                .collect();
                            eprintln!(
                                "      sub ({fx:.2},{fy:.2}) hit d {:.3} nb d0/d1 L,R,U,D {nb:?}",
                                hc.w
                            );
                        }
                    }
                    key += if e1 < 1e-3 { " 1Lok" } else { " 1Lbad" };
                    let e = cls.entry(key).or_default();
                    e.0 += 1;
                    e.1 += e1;
                    e.2 += e2;
                }
            }
        }
        let n = 2.0 * (w * h) as f64;
        eprintln!(
            "{m} ipd {ipd} {w}x{h}: 1L {:.3}/{:.3} dB, 2L {:.3}/{:.3} dB; MSE diff {:+.3e}",
            p[0],
            p[1],
            p[2],
            p[3],
            (s2 - s1) / n
        );
        let mut rows: Vec<_> = cls.into_iter().collect();
        rows.sort_by(|x, y| ((y.1.2 - y.1.1).abs()).total_cmp(&(x.1.2 - x.1.1).abs()));
        let (gain, loss): (f64, f64) = rows.iter().fold((0.0, 0.0), |(g, l), r| {
            let d = r.1.2 - r.1.1;
            if d < 0.0 { (g + d, l) } else { (g, l + d) }
        });
        eprintln!("  classes: gains {gain:+.2}, losses {loss:+.2} (summed se)");
        for (k, (c, e1, e2)) in rows.iter().take(14) {
            eprintln!(
                "  {k:40} {:6} px  se1 {:8.2} se2 {:8.2}  d {:+8.2}",
                c,
                e1,
                e2,
                e2 - e1
            );
        }
    }
}
