//! Where the error of cube-map reflections (Widmer et al. 2015, §5.4) comes from, over the
//! reflective pixels whose reflected surface the cube map's centre sees: an *oracle* reflector
//! traces every ray exactly with the BVH and colours its hit by the cube map's colour lookup
//! at the exact hit point. Truth `T` vs oracle `O` is the colour reconstruction from the
//! faces' samples (the face resolution); oracle vs cube map `C` is where the traced answer
//! differs from the exact one (and the extra samples' plane lookups). A test checks the
//! optional thickness of the cube map's surfaces on `mirrors-open` and `mirrors`.

use std::sync::atomic::{AtomicU64, Ordering};

use glam::{UVec2, Vec3};
use parallax_bvh::Bvh;
use parallax_core::{Ray, WorldStats};
use parallax_render::brdf;
use parallax_render::score::Shading;
use parallax_scene::camera::{CameraModel, CubeMap, Pinhole};
use parallax_scene::{CameraDesc, Scene};
use parallax_synth::dof::truth::masked_psnr;
use parallax_synth::lightfield::{spp_side, supersampled};
use parallax_synth::reflect::{
    BvhReflector, CubeReflector, ReflectOptions, ReflectionCube, Reflector, SurfaceHit,
    render_reflections,
};
use parallax_synth::{Method, MethodOptions, capture_reference};

/// Exact hits, coloured by the cube map's lookup at the exact point where a face layer holds
/// the hit surface (else by the truth's colour: such rays add no error here).
struct Oracle<'a> {
    exact: BvhReflector<'a>,
    cube: &'a CubeReflector<'a>,
}

impl Oracle<'_> {
    /// The face, layer and pixel of the cube map's sample of the surface at `p`.
    fn sample_of(&self, p: Vec3) -> Option<(u8, u8, UVec2)> {
        let c = self.cube.cube;
        let d = p - c.cube.eye;
        let f = CubeMap::face_of(d);
        let face = &c.faces[f];
        let film = face.camera.project(p, 0)?;
        let s = c.cube.face as f32;
        if !(film.x >= 0.0 && film.y >= 0.0 && film.x < s && film.y < s) {
            return None;
        }
        let q = UVec2::new(film.x as u32, film.y as u32);
        let layer = face.layers.iter().position(|g| {
            let i = g.index(q.x, q.y);
            g.depth[i].is_finite() && (g.position[i] - p).length() <= 0.01 * d.length()
        })?;
        Some((f as u8, layer as u8, q))
    }
}

impl Reflector for Oracle<'_> {
    fn name(&self) -> String {
        "oracle".into()
    }

    fn scene(&self) -> &Scene {
        self.exact.scene()
    }

    fn trace(&self, ray: &Ray, stats: &mut WorldStats) -> Option<SurfaceHit> {
        let mut h = self.exact.trace(ray, stats)?;
        h.sample = self.sample_of(h.position);
        Some(h)
    }

    fn colour(&self, ray: &Ray, hit: &SurfaceHit) -> Vec3 {
        match hit.sample {
            Some(_) => self.cube.colour(ray, hit),
            None => self.exact.colour(ray, hit),
        }
    }

    fn traces_extras(&self) -> bool {
        true
    }

    fn plane_sample(&self, hit: &SurfaceHit, ray: &Ray, _: f32) -> (Vec3, f32) {
        (self.colour(ray, hit), 1.0)
    }
}

/// The cube map's answers where they agree with the exact hit (within 5% of its distance),
/// the oracle's elsewhere: what the disagreeing traced rays cost.
struct AgreeingOnly<'a> {
    oracle: &'a Oracle<'a>,
    rays: AtomicU64,
    disagree: AtomicU64,
    /// Disagreeing rays by (cube answer: hit, occlusion volume, miss) x (exact: hit, miss).
    kinds: [[AtomicU64; 2]; 3],
}

impl Reflector for AgreeingOnly<'_> {
    fn name(&self) -> String {
        "agreeing".into()
    }

    fn scene(&self) -> &Scene {
        self.oracle.scene()
    }

    fn trace(&self, ray: &Ray, stats: &mut WorldStats) -> Option<SurfaceHit> {
        let c = self.oracle.cube.trace(ray, stats);
        let e = self.oracle.trace(ray, &mut WorldStats::default());
        let agree = match (c, e) {
            (Some(a), Some(b)) => {
                (a.position - b.position).length() <= 0.05 * (b.position - ray.origin).length()
            }
            (None, None) => true,
            _ => false,
        };
        self.rays.fetch_add(1, Ordering::Relaxed);
        if agree {
            c
        } else {
            self.disagree.fetch_add(1, Ordering::Relaxed);
            let ck = match c {
                Some(h) if h.occlusion => 1,
                Some(_) => 0,
                None => 2,
            };
            let n = self.kinds[ck][e.is_none() as usize].fetch_add(1, Ordering::Relaxed);
            if std::env::var("REFLECT_SPLIT_EXAMPLES").is_ok() && n < 6 {
                let name = |h: &Option<SurfaceHit>| {
                    h.map(|h| {
                        let m = &self.scene().materials[h.material_id as usize].name;
                        format!(
                            "{m} at {:.2} (t {:.2}, sample {:?})",
                            h.position, h.t, h.sample
                        )
                    })
                };
                eprintln!(
                    "ray {:.3} -> {:.3} (t_min {:.3}): cube {:?}, exact {:?}",
                    ray.origin,
                    ray.dir,
                    ray.t_min,
                    name(&c),
                    name(&e)
                );
            }
            e
        }
    }

    fn colour(&self, ray: &Ray, hit: &SurfaceHit) -> Vec3 {
        self.oracle.colour(ray, hit)
    }

    fn plane_sample(&self, hit: &SurfaceHit, ray: &Ray, sigma: f32) -> (Vec3, f32) {
        match hit.sample {
            Some(_) => self.oracle.cube.plane_sample(hit, ray, sigma),
            None => (Vec3::ZERO, 0.0),
        }
    }
}

/// The share of mirror pixels' reflection rays (1/0/1 paths, first segments) whose cube-map
/// hit lies within 5% of the BVH hit's distance (both missing counts as agreement).
fn agreement(
    scene: &Scene,
    bvh: &Bvh,
    r: &dyn Reflector,
    reference: &parallax_synth::Reference,
) -> f64 {
    let eye = reference.camera.frame.position;
    let truth = BvhReflector::new(scene, bvh, eye, 0);
    let g = &reference.layers[0];
    let (mut agree, mut n) = (0u32, 0u32);
    for i in 0..g.len() {
        let mirror = scene.materials.get(g.material_id[i] as usize);
        if !g.depth[i].is_finite() || mirror.is_none_or(|m| m.name != "mirror") {
            continue;
        }
        let p = g.position[i];
        let dir = brdf::reflect((eye - p).normalize(), g.normal[i]);
        let t_min = 1.5 * 2.0 * (p - eye).abs().max_element() / FACE as f32;
        let ray = Ray::segment(p + g.normal[i] * 1e-4, dir, t_min, f32::INFINITY);
        let mut st = WorldStats::default();
        let a = r.trace(&ray, &mut st).map(|h| h.position);
        let b = truth.trace(&ray, &mut st).map(|h| h.position);
        n += 1;
        agree += match (a, b) {
            (Some(a), Some(b)) => (a - b).length() <= 0.05 * (b - ray.origin).length(),
            (None, None) => true,
            _ => false,
        } as u32;
    }
    agree as f64 / n.max(1) as f64
}

/// Face size of the agreement test.
const FACE: u32 = 192;

/// `mirrors-open` (192x108, 192^2 faces, 2 layers): giving the cube map's surfaces a
/// thickness (`CubeMapTracer::thickness`) lets rays that pass behind the pillars and boxes
/// (as the eye sees them) go on to the sky and ground the BVH finds, where occlusion volumes
/// end them; and it changes nothing on a ray that never enters one (the `mirrors` room's
/// answers barely move).
#[test]
fn thickness_lets_rays_pass_behind_thin_occluders() {
    let mut measured = Vec::new();
    for name in ["mirrors-open", "mirrors"] {
        let scene = Scene::load(name).unwrap();
        let bvh = Bvh::build(&scene.mesh);
        let camera = Pinhole::new(&scene.camera(None).unwrap(), 192, 108).unwrap();
        let reference = capture_reference(&scene, &bvh, &camera, 1, Shading::Fixed, 0).unwrap();
        let eye = camera.frame.position;
        let desc = CameraDesc::new(eye, eye - Vec3::Z, Vec3::Y, 90.0);
        let cube = ReflectionCube::capture(&scene, &bvh, &desc, FACE, 2, 0).unwrap();
        let mut r =
            CubeReflector::build(&scene, &cube, Method::QuadTree, &MethodOptions::default())
                .unwrap();
        let plain = agreement(&scene, &bvh, &r, &reference);
        r.tracer.thickness = Some(0.1);
        let thick = agreement(&scene, &bvh, &r, &reference);
        println!(
            "{name}: mirror hit agreement {plain:.3} with occlusion volumes, {thick:.3} with thickness 0.1"
        );
        measured.push((plain, thick));
    }
    let (open, room) = (measured[0], measured[1]);
    assert!(open.1 > open.0 + 0.05, "mirrors-open: {open:?}");
    assert!(open.1 > 0.9, "mirrors-open: {open:?}");
    assert!((room.1 - room.0).abs() < 0.02, "mirrors: {room:?}");
}

/// Diagnostic (`cargo test --release -p parallax-synth --test reflect_split -- --ignored
/// --nocapture`; `REFLECT_SPLIT_SCENE` (default `mirrors`), `REFLECT_SPLIT_FACES` (default
/// `512,1024`), `REFLECT_SPLIT_SIZE` (default `480,270`), `REFLECT_SPLIT_THICKNESS` (default
/// none), `REFLECT_SPLIT_LAYERS` (default 1), `REFLECT_SPLIT_SPP` (default 1: rays per pixel,
/// `s x s` box-filtered on every side), `REFLECT_SPLIT_CONFIGS` (default `1/0/1,1/8/1`),
/// `REFLECT_SPLIT_TRACE_BELOW` (default 0, `ReflectOptions::trace_below`),
/// `REFLECT_SPLIT_METHOD` (`quadtree` or `dda` at the face size's steps),
/// `REFLECT_SPLIT_HIDDEN` (set: the not-seen pixels split by surface, [`hidden_split`])): per
/// face size, PSNR of `C` and `O` against `T` and of `C` against `O` over the reflective pixels whose BVH reflection hit the eye sees (antialiased: every reflecting ray
/// of the pixel's), and of `C` over all reflective pixels.
#[test]
#[ignore]
fn reflection_error_split() {
    let env = |k: &str, d: &str| std::env::var(k).unwrap_or_else(|_| d.into());
    let scene = Scene::load(&env("REFLECT_SPLIT_SCENE", "mirrors")).unwrap();
    let nums = |s: String| -> Vec<u32> { s.split(',').map(|v| v.parse().unwrap()).collect() };
    let faces = nums(env("REFLECT_SPLIT_FACES", "512,1024"));
    let size = nums(env("REFLECT_SPLIT_SIZE", "480,270"));
    let bvh = Bvh::build(&scene.mesh);
    let side = spp_side(env("REFLECT_SPLIT_SPP", "1").parse().unwrap()).unwrap();
    let configs: Vec<Vec<u32>> = env("REFLECT_SPLIT_CONFIGS", "1/0/1,1/8/1")
        .split(',')
        .map(|c| c.split('/').map(|v| v.parse().unwrap()).collect())
        .collect();
    let view = Pinhole::new(&scene.camera(None).unwrap(), size[0], size[1]).unwrap();
    let camera = supersampled(&view, side);
    let reference = capture_reference(&scene, &bvh, &camera, 1, Shading::Fixed, 0).unwrap();
    let eye = camera.frame.position;
    let g = &reference.layers[0];
    let sees = |q: Vec3| {
        let d = q - eye;
        let r = Ray::segment(eye, d.normalize(), 0.0, d.length() * (1.0 - 1e-3));
        bvh.closest_hit(&r).is_none()
    };
    for face in faces {
        let desc = CameraDesc::new(eye, eye - Vec3::Z, Vec3::Y, 90.0);
        let layers: usize = env("REFLECT_SPLIT_LAYERS", "1").parse().unwrap();
        let cube = ReflectionCube::capture(&scene, &bvh, &desc, face, layers, 0).unwrap();
        let method = match env("REFLECT_SPLIT_METHOD", "quadtree").as_str() {
            "dda" => Method::Dda,
            _ => Method::QuadTree,
        };
        let mopts = MethodOptions {
            dda_max_steps: face,
            ..MethodOptions::default()
        };
        let mut c = CubeReflector::build(&scene, &cube, method, &mopts).unwrap();
        c.tracer.thickness = std::env::var("REFLECT_SPLIT_THICKNESS")
            .ok()
            .map(|t| t.parse().unwrap());
        let truth = BvhReflector::new(&scene, &bvh, eye, 0);
        let oracle = Oracle {
            exact: BvhReflector::new(&scene, &bvh, eye, 0),
            cube: &c,
        };
        for cfg in &configs {
            let (n_p, n_s, n_b) = (cfg[0], cfg[1], cfg[2]);
            let o = ReflectOptions {
                n_p,
                n_s,
                n_b,
                trace_below: env("REFLECT_SPLIT_TRACE_BELOW", "0").parse().unwrap(),
                ..ReflectOptions::default()
            };
            let render = |r: &dyn Reflector| {
                render_reflections(r, &reference, eye, face, &o)
                    .unwrap()
                    .box_filtered(side)
                    .unwrap()
            };
            let fine_mask = render_reflections(&truth, &reference, eye, face, &o)
                .unwrap()
                .mask;
            let t = render(&truth);
            let ci = render(&c);
            let oi = render(&oracle);
            let agreeing = AgreeingOnly {
                oracle: &oracle,
                rays: AtomicU64::new(0),
                disagree: AtomicU64::new(0),
                kinds: Default::default(),
            };
            let ai = render(&agreeing);
            let disagree = agreeing.disagree.load(Ordering::Relaxed) as f64
                / agreeing.rays.load(Ordering::Relaxed).max(1) as f64;
            let mut seen_fine = vec![false; g.len()];
            for i in 0..g.len() {
                if !fine_mask[i] {
                    continue;
                }
                let p = g.position[i];
                let dir = brdf::reflect((eye - p).normalize(), g.normal[i]);
                let ray = Ray::segment(p + g.normal[i] * 1e-4, dir, 1e-3, f32::INFINITY);
                let mut st = WorldStats::default();
                // A miss sees the environment, which the cube map holds by direction.
                seen_fine[i] = truth.trace(&ray, &mut st).is_none_or(|h| sees(h.position));
            }
            if std::env::var("REFLECT_SPLIT_HIDDEN").is_ok() {
                hidden_split(
                    &scene,
                    &reference,
                    (&truth, &c),
                    face,
                    &o,
                    &fine_mask,
                    &seen_fine,
                );
            }
            // A filtered pixel is seen when every reflecting ray of it is.
            let (w, fw, sd) = (view.width as usize, camera.width as usize, side as usize);
            let seen: Vec<bool> = (0..t.mask.len())
                .map(|i| {
                    let (x, y) = (i % w * sd, i / w * sd);
                    t.mask[i]
                        && (0..sd * sd).all(|k| {
                            let f = (y + k / sd) * fw + x + k % sd;
                            !fine_mask[f] || seen_fine[f]
                        })
                })
                .collect();
            let share = seen.iter().filter(|s| **s).count() as f64
                / t.mask.iter().filter(|m| **m).count().max(1) as f64;
            let m = |a: &parallax_core::Image<parallax_core::Rgb>,
                     b: &parallax_core::Image<parallax_core::Rgb>| {
                masked_psnr(a, b, &seen).unwrap()
            };
            println!(
                "{} face {face} {n_p}/{n_s}/{n_b} {} spp: C-T {:.2} dB over all reflective pixels; over the {:.1}% seen: C-T {:.2}, O-T (colour reconstruction) {:.2}, C-O (traced answer) {:.2}; A-T {:.2} where the {:.2}% of traced rays that miss the exact hit by > 5% take the oracle's answer",
                scene.name,
                side * side,
                masked_psnr(&ci.image, &t.image, &t.mask).unwrap(),
                100.0 * share,
                m(&ci.image, &t.image),
                m(&oi.image, &t.image),
                m(&ci.image, &oi.image),
                m(&ai.image, &t.image),
                100.0 * disagree,
            );
            let k = |c: usize, e: usize| agreeing.kinds[c][e].load(Ordering::Relaxed);
            println!(
                "  disagreeing rays, cube answer / exact: hit/hit {} hit/miss {} occlusion/hit {} occlusion/miss {} miss/hit {}",
                k(0, 0),
                k(0, 1),
                k(1, 0),
                k(1, 1),
                k(2, 0)
            );
        }
    }
}

/// The reflective pixels (one ray each, unfiltered) split by what their centre reflection ray
/// reaches: seen by the cube map's centre, or not seen — the side it hits faces away from the
/// centre (no layer can hold it) or faces it but is occluded — and by material: share of the
/// pixels, PSNR of `C` against `T`, share of the squared error (`REFLECT_SPLIT_HIDDEN=1`).
fn hidden_split(
    scene: &Scene,
    reference: &parallax_synth::Reference,
    (truth, c): (&BvhReflector, &CubeReflector),
    face: u32,
    o: &ReflectOptions,
    mask: &[bool],
    seen: &[bool],
) {
    let eye = reference.camera.frame.position;
    let t = render_reflections(truth, reference, eye, face, o).unwrap();
    let ci = render_reflections(c, reference, eye, face, o).unwrap();
    let along = render_reflections(&AlongTheRay(truth), reference, eye, face, o).unwrap();
    println!(
        "  truth colouring hits whose seen side faces away from the centre by their radiance along the reflection ray: C-T {:.2} dB over all reflective pixels",
        masked_psnr(&ci.image, &along.image, mask).unwrap()
    );
    let g = &reference.layers[0];
    let mut classes: std::collections::BTreeMap<String, Vec<bool>> = Default::default();
    for i in 0..g.len() {
        if !mask[i] {
            continue;
        }
        let key = if seen[i] {
            "seen".to_string()
        } else {
            let p = g.position[i];
            let dir = brdf::reflect((eye - p).normalize(), g.normal[i]);
            let ray = Ray::segment(p + g.normal[i] * 1e-4, dir, 1e-3, f32::INFINITY);
            let h = truth.trace(&ray, &mut WorldStats::default()).unwrap();
            let m = &scene.materials[h.material_id as usize].name;
            let facing = h.normal.dot(eye - h.position) > 0.0;
            let side = if facing { "occluded" } else { "back-facing" };
            format!("not seen, {side}, {m}")
        };
        classes.entry(key).or_insert_with(|| vec![false; g.len()])[i] = true;
    }
    let n_all = mask.iter().filter(|m| **m).count() as f64;
    let rows: Vec<(String, f64, f64, f64)> = classes
        .into_iter()
        .map(|(k, m)| {
            let n = m.iter().filter(|v| **v).count() as f64;
            let p = masked_psnr(&ci.image, &t.image, &m).unwrap();
            (k, n, p, n * 10f64.powf(-p / 10.0))
        })
        .collect();
    let se: f64 = rows.iter().map(|r| r.3).sum();
    println!(
        "  1 ray per pixel: C-T {:.2} dB over all reflective pixels",
        masked_psnr(&ci.image, &t.image, mask).unwrap()
    );
    for (k, n, p, e) in rows {
        println!(
            "  {k}: {:.2}% of the pixels, C-T {p:.2} dB, {:.1}% of the squared error",
            100.0 * n / n_all,
            100.0 * e / se
        );
    }
}

/// The BVH reflector, except that a hit whose side the ray sees faces away from the cube
/// map's centre (no cube-map sample can hold it) is coloured by the radiance it sends back
/// along the ray (the physical reflection) instead of by the shading of that side seen
/// from the centre.
struct AlongTheRay<'a, 'b>(&'b BvhReflector<'a>);

impl Reflector for AlongTheRay<'_, '_> {
    fn name(&self) -> String {
        "bvh-along-the-ray".into()
    }

    fn scene(&self) -> &Scene {
        self.0.scene()
    }

    fn trace(&self, ray: &Ray, stats: &mut WorldStats) -> Option<SurfaceHit> {
        self.0.trace(ray, stats)
    }

    fn colour(&self, ray: &Ray, hit: &SurfaceHit) -> Vec3 {
        if hit.normal.dot(self.0.eye - hit.position) > 0.0 {
            return self.0.colour(ray, hit);
        }
        let h = parallax_bvh::Hit {
            prim: hit.prim,
            t: hit.t,
            u: hit.barycentrics.x,
            v: hit.barycentrics.y,
        };
        let mut rng = Shading::Fixed.rng(self.0.seed, 0, 0, 0);
        self.0.shader.radiance_from_hit(*ray, h, &mut rng, &mut 0)
    }

    fn traces_extras(&self) -> bool {
        true
    }

    fn plane_sample(&self, hit: &SurfaceHit, ray: &Ray, _: f32) -> (Vec3, f32) {
        (self.colour(ray, hit), 1.0)
    }
}
