//! `embree-baseline`: parallax's BVH against Embree 3 on identical rays, in one process.
//!
//! ```text
//! cargo run --release -- --scene S [--width 1280 --height 720]
//!     [--camera NAME | --eye x,y,z --target x,y,z [--fov-y DEG]]
//!     [--repeats 3] [--quality low|medium|high] [--robust] [--no-single-thread]
//! ```
//!
//! `S` is a built-in scene (`atrium`, ...), a scene file (.glb/.gltf/.obj/.ply), or a
//! procedural mesh: `procedural:sphere` (a 400x800 UV sphere) or `procedural:random[:N]`
//! (N random triangles, default 200k).
//!
//! Rays: "primary" = one pinhole ray per pixel centre, "random" = cosine bounce rays from the
//! primary hits (both from `parallax_render::bench::rays::make_rays`, as `parallax bench rays`
//! uses). Each method is timed best-of-`repeats` over rayon chunks on all threads, then on one.

use std::process::ExitCode;
use std::time::Instant;

use glam::Vec3;
use parallax_bvh::Bvh;
use parallax_core::Ray;
use parallax_embree_baseline::packets::{Packets, chunked, primary_packets};
use parallax_embree_baseline::{
    BuildOptions, EmbreeScene, PrimHit, Quality, cputime, hits_agree, procedural,
};
use parallax_render::bench::rays::make_rays;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_scene::{CameraDesc, Scene};
use rayon::prelude::*;

const USAGE: &str = "usage: embree-baseline --scene S [--width W --height H] \
[--camera NAME | --eye x,y,z --target x,y,z [--fov-y DEG]] [--repeats N] \
[--quality low|medium|high] [--robust] [--no-single-thread]";

/// Fraction of rays on which Embree and the parallax BVH must agree.
const MIN_AGREEMENT: f64 = 0.999;

struct Args {
    scene: String,
    width: u32,
    height: u32,
    camera: Option<String>,
    eye: Option<Vec3>,
    target: Option<Vec3>,
    fov_y: Option<f32>,
    repeats: u32,
    quality: Quality,
    robust: bool,
    single_thread: bool,
}

fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("bad vector {s:?}: {e}"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(x, y, z)),
        _ => Err(format!("expected three finite numbers x,y,z, got {s:?}")),
    }
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        scene: String::new(),
        width: 1280,
        height: 720,
        camera: None,
        eye: None,
        target: None,
        fov_y: None,
        repeats: 3,
        quality: Quality::Medium,
        robust: false,
        single_thread: true,
    };
    // `--flag=value` is split into `--flag value` (a value may start with '-', e.g. -9,3.5,0).
    let mut it = std::env::args()
        .skip(1)
        .flat_map(|a| match a.split_once('=') {
            Some((f, v)) if f.starts_with("--") => vec![f.to_string(), v.to_string()],
            _ => vec![a],
        });
    while let Some(flag) = it.next() {
        let mut val = || it.next().ok_or_else(|| format!("{flag} needs a value"));
        let num = |s: String| s.parse::<u32>().map_err(|e| format!("{flag}: {e}"));
        match flag.as_str() {
            "--scene" => a.scene = val()?,
            "--width" => a.width = num(val()?)?,
            "--height" => a.height = num(val()?)?,
            "--camera" => a.camera = Some(val()?),
            "--eye" => a.eye = Some(parse_vec3(&val()?)?),
            "--target" => a.target = Some(parse_vec3(&val()?)?),
            "--fov-y" => {
                a.fov_y = Some(val()?.parse().map_err(|e| format!("--fov-y: {e}"))?);
            }
            "--repeats" => a.repeats = num(val()?)?.clamp(1, 100),
            "--quality" => {
                a.quality = match val()?.as_str() {
                    "low" => Quality::Low,
                    "medium" => Quality::Medium,
                    "high" => Quality::High,
                    q => return Err(format!("--quality: unknown {q:?} (low|medium|high)")),
                }
            }
            "--robust" => a.robust = true,
            "--no-single-thread" => a.single_thread = false,
            "-h" | "--help" => return Err(USAGE.to_string()),
            f => return Err(format!("unknown argument {f:?}\n{USAGE}")),
        }
    }
    if a.scene.is_empty() {
        return Err(format!("--scene is required\n{USAGE}"));
    }
    if a.eye.is_some() != a.target.is_some() {
        return Err("--eye and --target go together".into());
    }
    Ok(a)
}

fn load_scene(name: &str) -> Result<Scene, String> {
    let mesh = match name.strip_prefix("procedural:") {
        None => return Scene::load(name).map_err(|e| format!("loading {name:?}: {e}")),
        Some("sphere") => procedural::uv_sphere(1.0, 400, 800),
        Some(r) if r == "random" || r.starts_with("random:") => {
            let n = match r.strip_prefix("random:") {
                Some(n) => n.parse::<usize>().map_err(|e| format!("{name}: {e}"))?,
                None => 200_000,
            };
            procedural::random_triangles(n.min(20_000_000), 0.02, 1)
        }
        Some(p) => {
            return Err(format!(
                "unknown procedural mesh {p:?} (sphere, random[:N])"
            ));
        }
    };
    Ok(Scene {
        name: name.to_string(),
        mesh,
        ..Default::default()
    })
}

/// Wall and process-CPU time (ms) of one run of `f`, and what `f` returned (hit count).
fn timed(f: impl Fn() -> u64) -> (f64, f64, u64) {
    let c = cputime::process_cpu_seconds();
    let t = Instant::now();
    let hits = f();
    let wall = t.elapsed().as_secs_f64() * 1e3;
    (wall, (cputime::process_cpu_seconds() - c) * 1e3, hits)
}

/// The methods compared; each returns the number of rays that hit.
enum Method<'a> {
    Parallax(&'a [Ray]),
    Embree1(&'a [Ray]),
    Embree8(&'a Packets),
    Embree16(&'a Packets),
    /// `Bvh::closest_hit_packet` on the same packets as `Embree16`.
    ParallaxPacket(&'a Packets),
}

impl Method<'_> {
    fn name(&self, coherent: bool) -> &'static str {
        match (self, coherent) {
            (Method::Parallax(_), _) => "parallax BVH, single rays",
            (Method::Embree1(_), _) => "Embree rtcIntersect1",
            (Method::Embree8(_), true) => "Embree rtcIntersect8, 4x2 tiles",
            (Method::Embree8(_), false) => "Embree rtcIntersect8, 8 in a row",
            (Method::Embree16(_), true) => "Embree rtcIntersect16, 4x4 tiles",
            (Method::Embree16(_), false) => "Embree rtcIntersect16, 16 in a row",
            (Method::ParallaxPacket(_), true) => "parallax BVH packets, 4x4 tiles",
            (Method::ParallaxPacket(_), false) => "parallax BVH packets, 16 in a row",
        }
    }

    fn rays(&self) -> usize {
        match self {
            Method::Parallax(r) | Method::Embree1(r) => r.len(),
            Method::Embree8(p) | Method::Embree16(p) | Method::ParallaxPacket(p) => p.rays.len(),
        }
    }

    fn trace(&self, bvh: &Bvh, emb: &EmbreeScene) -> u64 {
        let count = |n: usize| n as u64;
        match self {
            Method::Parallax(rays) => rays
                .par_chunks(1024)
                .map(|c| count(c.iter().filter(|r| bvh.closest_hit(r).is_some()).count()))
                .sum(),
            Method::Embree1(rays) => rays
                .par_chunks(1024)
                .map(|c| count(c.iter().filter(|r| emb.closest_hit(r).is_some()).count()))
                .sum(),
            Method::ParallaxPacket(p) => (0..p.packets.len())
                .into_par_iter()
                .with_min_len(64)
                .map(|k| {
                    let mut out = [None; parallax_bvh::PACKET_SIZE];
                    let rays = p.packet(k);
                    bvh.closest_hit_packet(rays, &mut out);
                    count(out[..rays.len()].iter().filter(|h| h.is_some()).count())
                })
                .sum(),
            Method::Embree8(p) | Method::Embree16(p) => {
                let wide = matches!(self, Method::Embree16(_));
                (0..p.packets.len())
                    .into_par_iter()
                    .with_min_len(64)
                    .map(|k| {
                        let mut out = [None; 16];
                        let rays = p.packet(k);
                        if wide {
                            emb.closest_hit_packet16(rays, &mut out);
                        } else {
                            emb.closest_hit_packet8(rays, &mut out);
                        }
                        count(out[..rays.len()].iter().filter(|h| h.is_some()).count())
                    })
                    .sum()
            }
        }
    }

    /// Embree's answers for every ray, in ray order (for the agreement check).
    fn answers(&self, emb: &EmbreeScene) -> Option<Vec<Option<PrimHit>>> {
        match self {
            Method::Parallax(_) | Method::ParallaxPacket(_) => None,
            Method::Embree1(rays) => Some(rays.par_iter().map(|r| emb.closest_hit(r)).collect()),
            Method::Embree8(p) | Method::Embree16(p) => {
                let wide = matches!(self, Method::Embree16(_));
                let per: Vec<Vec<Option<PrimHit>>> = (0..p.packets.len())
                    .into_par_iter()
                    .map(|k| {
                        let mut out = [None; 16];
                        let rays = p.packet(k);
                        if wide {
                            emb.closest_hit_packet16(rays, &mut out);
                        } else {
                            emb.closest_hit_packet8(rays, &mut out);
                        }
                        out[..rays.len()].to_vec()
                    })
                    .collect();
                Some(per.concat())
            }
        }
    }

    fn rays_in_order(&self) -> &[Ray] {
        match self {
            Method::Parallax(r) | Method::Embree1(r) => r,
            Method::Embree8(p) | Method::Embree16(p) | Method::ParallaxPacket(p) => &p.rays,
        }
    }
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<(), String> {
    let args = parse_args()?;
    let t = Instant::now();
    let scene = load_scene(&args.scene)?;
    eprintln!(
        "loaded {} ({} triangles) in {:.0} ms",
        scene.name,
        scene.mesh.triangle_count(),
        t.elapsed().as_secs_f64() * 1e3
    );
    let desc = match (args.eye, args.target) {
        (Some(eye), Some(target)) => {
            let fov = args.fov_y.unwrap_or(45.0);
            CameraDesc::new(eye, target, Vec3::Y, fov)
        }
        _ => {
            let mut d = scene
                .camera(args.camera.as_deref())
                .map_err(|e| e.to_string())?;
            if let Some(f) = args.fov_y {
                d.fov_y_deg = f;
            }
            d
        }
    };
    let camera = Camera::new(
        ModelKind::Pinhole,
        &desc,
        args.width,
        args.height,
        &CameraOptions::default(),
    )
    .map_err(|e| e.to_string())?;

    // Builds: each twice, the faster counts (the first Embree device also starts its threads).
    let mut bvh_ms = f64::INFINITY;
    let mut bvh = None;
    for _ in 0..2 {
        let t = Instant::now();
        bvh = Some(Bvh::build(&scene.mesh));
        bvh_ms = bvh_ms.min(t.elapsed().as_secs_f64() * 1e3);
    }
    let bvh = bvh.unwrap();
    let opts = BuildOptions {
        quality: args.quality,
        robust: args.robust,
    };
    let mut emb_ms = f64::INFINITY;
    let mut emb = None;
    for _ in 0..2 {
        drop(emb.take());
        let t = Instant::now();
        emb = Some(EmbreeScene::with_options(&scene.mesh, opts).map_err(|e| e.to_string())?);
        emb_ms = emb_ms.min(t.elapsed().as_secs_f64() * 1e3);
    }
    let emb = emb.unwrap();
    let (n8, n16) = emb.native_packets();
    eprintln!(
        "parallax BVH {bvh_ms:.1} ms, Embree ({:?}{}) {emb_ms:.1} ms; Embree native packets: \
         8-wide {n8}, 16-wide {n16}",
        args.quality,
        if args.robust { ", robust" } else { "" },
    );

    let (primary, random) = make_rays(&bvh, &scene, &camera);
    let b = scene.bounds();
    eprintln!(
        "bounds {:?}..{:?}; camera eye {:?} target {:?} fov-y {}; {} primary rays, {:.1}% hit",
        b.min,
        b.max,
        desc.eye,
        desc.target,
        desc.fov_y_deg,
        primary.len(),
        100.0 * random.len() as f64 / primary.len().max(1) as f64
    );
    let tiles8 = primary_packets(&camera, 4, 2);
    let tiles16 = primary_packets(&camera, 4, 4);
    let rows8 = chunked(&random, 8);
    let rows16 = chunked(&random, 16);
    let all = rayon::current_num_threads();
    let single = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| e.to_string())?;

    println!(
        "\n| scene | mode | method | rays | build ms | Mrays/s | Mrays/CPU-s | threads \
         | CPU-s vs parallax |\n|---|---|---|---:|---:|---:|---:|---:|---:|"
    );
    let mut agreement = Vec::new();
    let mut disagreeing = 0;
    for (mode, rays, p8, p16) in [
        ("primary", &primary, &tiles8, &tiles16),
        ("random", &random, &rows8, &rows16),
    ] {
        let coherent = mode == "primary";
        let methods = [
            Method::Parallax(rays),
            Method::Embree1(rays),
            Method::Embree8(p8),
            Method::Embree16(p16),
            Method::ParallaxPacket(p16),
        ];
        // Agreement of every Embree method with the parallax BVH on the same rays (the packet
        // traversal is tested to equal the single rays exactly in parallax-bvh's tests).
        for m in &methods[1..4] {
            let e = m.answers(&emb).unwrap();
            let ordered = m.rays_in_order();
            let ok = ordered
                .par_iter()
                .zip(&e)
                .filter(|(r, h)| hits_agree(**h, bvh.closest_hit(r).map(|h| (h.prim, h.t)), 1e-4))
                .count();
            let same_prim = ordered
                .par_iter()
                .zip(&e)
                .filter(|(r, h)| bvh.closest_hit(r).map(|h| h.prim) == h.map(|h| h.0))
                .count();
            let low = (ok as f64) < MIN_AGREEMENT * e.len() as f64;
            disagreeing += usize::from(low);
            agreement.push(format!(
                "{mode:7} {:36} agree {ok}/{} ({:.4}%), same triangle or both miss {:.4}%{}",
                m.name(coherent),
                e.len(),
                100.0 * ok as f64 / e.len().max(1) as f64,
                100.0 * same_prim as f64 / e.len().max(1) as f64,
                if low { "  <-- BELOW 99.9%" } else { "" },
            ));
        }
        let pools: Vec<(usize, Option<&rayon::ThreadPool>)> = if args.single_thread {
            vec![(all, None), (1, Some(&single))]
        } else {
            vec![(all, None)]
        };
        for (threads, pool) in pools {
            // Methods interleaved within each repeat, best run per method: a burst of load from
            // other processes then hurts one run of each method rather than all runs of one.
            let mut best = [(f64::INFINITY, f64::INFINITY); 5];
            for _ in 0..args.repeats {
                for (m, b) in methods.iter().zip(&mut best) {
                    let go = || timed(|| m.trace(&bvh, &emb));
                    let (wall, cpu, hits) = match pool {
                        Some(p) => p.install(go),
                        None => go(),
                    };
                    std::hint::black_box(hits);
                    *b = (b.0.min(wall), b.1.min(cpu));
                }
            }
            let base = methods[0].rays() as f64 / (best[0].1 * 1e3);
            for (m, (wall, cpu)) in methods.iter().zip(best) {
                let mrays = m.rays() as f64 / (wall * 1e3);
                let per_cpu = m.rays() as f64 / (cpu * 1e3);
                let build = if matches!(m, Method::Parallax(_) | Method::ParallaxPacket(_)) {
                    bvh_ms
                } else {
                    emb_ms
                };
                println!(
                    "| {} | {mode} | {} | {} | {build:.1} | {mrays:.2} | {per_cpu:.2} | {threads} \
                     | {:.2}x |",
                    scene.name,
                    m.name(coherent),
                    m.rays(),
                    per_cpu / base.max(1e-12),
                );
            }
        }
    }
    println!(
        "\n{} triangles, {}x{}, best of {} runs; machine: {} threads. Mrays/s is per wall \
         second, Mrays/CPU-s per second of CPU time this process used (robust to other load; \
         multiply by the threads for an unloaded machine). Agreement with the parallax BVH (same triangle, or t within 1e-4 relative):",
        scene.mesh.triangle_count(),
        args.width,
        args.height,
        args.repeats,
        all
    );
    for a in agreement {
        println!("    {a}");
    }
    if disagreeing > 0 {
        return Err(format!(
            "{disagreeing} method(s) agree with the parallax BVH on fewer than 99.9% of rays"
        ));
    }
    Ok(())
}
