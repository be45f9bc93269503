//! Stereo and temporal sample reprojection (Mäkitalo et al. 2019) on real scenes, small films:
//! the paper's sample is the path tracer's, zero limits re-trace everything, a moving object's
//! disocclusions show in the discard mask, frames and scores do not depend on the thread
//! count, bad options are clear errors.

use glam::Vec3;
use parallax_core::WorldTracer;
use parallax_path::reproject::dataset::{Dataset, FrameWorld, Variant};
use parallax_path::reproject::footprint::Outcome;
use parallax_path::reproject::isa::Isa;
use parallax_path::reproject::method::{Method, MethodState};
use parallax_path::reproject::reference::{ReferenceCache, ReferenceSpec};
use parallax_path::reproject::sampler::PaperSampler;
use parallax_path::reproject::sequence::{RunOptions, eye_pinhole, run};
use parallax_path::reproject::{EvalOptions, EyeView, evaluate};
use parallax_path::{PathTracer, reproject};
use parallax_render::bsdf::MaterialMode;
use parallax_scene::animation::Animation;
use parallax_scene::camera::{Camera, CameraModel, Eye};
use parallax_scene::{CameraDesc, Scene};

fn opts(w: u32, h: u32, frames: u32) -> RunOptions {
    RunOptions {
        width: w,
        height: h,
        ipd: 0.065,
        frames,
        seed: 3,
        materials: MaterialMode::AsIs,
        max_position: None,
        max_normal_deg: None,
    }
}

fn atrium(variant: Variant) -> Dataset {
    Dataset::new(Scene::load("atrium").unwrap(), variant).unwrap()
}

/// Every frame's images and outcomes of every method and mode, as bits.
fn sequence_bits(world: &mut dyn FrameWorld, o: &RunOptions) -> Vec<Vec<u32>> {
    sequence_bits_of(world, o, &[Method::paper(), Method::ours()], Isa::detect())
}

/// [`sequence_bits`] of the given methods, their passes run in the build of `isa`.
fn sequence_bits_of(
    world: &mut dyn FrameWorld,
    o: &RunOptions,
    methods: &[Method],
    isa: Isa,
) -> Vec<Vec<u32>> {
    let mut states: Vec<MethodState> = methods
        .iter()
        .map(|m| MethodState::new(m.clone()).with_isa(isa))
        .collect();
    let mut out = Vec::new();
    run(world, o, &mut states, &mut |f, _| {
        for m in f.methods {
            for mf in [&m.stereo, &m.temporal, &m.combined] {
                out.push(
                    mf.image
                        .iter()
                        .flat_map(|c| c.to_array().map(f32::to_bits))
                        .chain(mf.outcomes.iter().map(|o| *o as u32))
                        .collect(),
                );
            }
        }
        Ok(())
    })
    .unwrap();
    out
}

#[test]
fn paper_sample_is_the_path_tracers_first_sample() {
    let world = atrium(Variant::Base);
    let head = world.head(0);
    let cam = eye_pinhole(&head, 0.065, Eye::Right, 24, 16).unwrap();
    let sampler = PaperSampler::new(world.scene(), world.tracer(), MaterialMode::AsIs);
    let mut view = EyeView::new(cam.clone());
    let mut radiance = vec![Vec3::ZERO; view.len()];
    sampler.trace_eye(11, &mut view, &mut radiance);
    let opts = PaperSampler::path_options(MaterialMode::AsIs, 1, 11);
    let camera = Camera::Pinhole(cam);
    let pt = PathTracer::new(world.scene(), &camera, world.tracer(), opts).unwrap();
    let mut film = pt.film();
    pt.render_samples(&mut film, 0..1, false, &|_| {});
    assert_eq!(film.mean().into_vec(), radiance);
    assert!(radiance.iter().any(|c| c.max_element() > 0.0));
}

/// Not a test: prints a hash of every frame, method and mode of a 4-frame atrium sequence at
/// 80x48 (still and with moving props), to compare outputs before and after a change to the
/// passes: `cargo test -p parallax-path --test reproject -- --ignored --nocapture output_hash`.
#[test]
#[ignore]
fn output_hash() {
    let methods: Vec<Method> = Method::NAMES
        .iter()
        .map(|n| Method::named(n).unwrap())
        .collect();
    for variant in [Variant::Base, Variant::MovingObjects] {
        let bits = sequence_bits_of(
            &mut atrium(variant),
            &opts(80, 48, 4),
            &methods,
            Isa::detect(),
        );
        // FNV-1a over every word, in order.
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        for w in bits.iter().flatten() {
            h = (h ^ *w as u64).wrapping_mul(0x100_0000_01b3);
        }
        println!("output hash {variant:?}: {h:016x} ({} outputs)", bits.len());
    }
}

/// The passes' AVX build (chosen where the CPU has AVX) and the baseline build give the same
/// frames and outcomes bit for bit, for every method, still and with moving props.
#[test]
fn avx_and_baseline_builds_give_the_same_frames() {
    let methods: Vec<Method> = Method::NAMES
        .iter()
        .map(|n| Method::named(n).unwrap())
        .collect();
    if !Isa::detect().is_avx() {
        eprintln!("no AVX on this CPU: only the baseline build is compared with itself");
    }
    for variant in [Variant::Base, Variant::MovingObjects] {
        let o = opts(40, 24, 4);
        let bits = |isa| sequence_bits_of(&mut atrium(variant), &o, &methods, isa);
        let (base, detected) = (bits(Isa::BASELINE), bits(Isa::detect()));
        assert_eq!(base.len(), detected.len());
        for (k, (a, b)) in base.iter().zip(&detected).enumerate() {
            assert!(a == b, "{variant:?}: output {k} differs between the builds");
        }
    }
}

#[test]
fn one_and_two_threads_give_the_same_frames_and_scores() {
    let o = opts(40, 24, 3);
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    };
    let frames = |n: usize| pool(n).install(|| sequence_bits(&mut atrium(Variant::Base), &o));
    assert_eq!(frames(1), frames(2));
    let eval = EvalOptions {
        run: o.clone(),
        reference: ReferenceSpec {
            spp: 12,
            curve_spp: 4,
        },
        cache: ReferenceCache::default(),
    };
    let score = |n: usize| {
        pool(n).install(|| {
            let e = evaluate(
                &mut atrium(Variant::Base),
                &eval,
                &[Method::paper()],
                &|_| {},
            )
            .unwrap();
            e.series
                .iter()
                .flat_map(|s| {
                    s.frames
                        .iter()
                        .map(|f| (f.effective_spp.to_bits(), f.rmse.to_bits()))
                })
                .collect::<Vec<_>>()
        })
    };
    assert_eq!(score(1), score(2));
}

#[test]
fn zero_limits_retrace_every_pixel() {
    let mut o = opts(32, 20, 2);
    o.max_position = Some(0.0);
    o.max_normal_deg = Some(0.0);
    let mut world = atrium(Variant::Base);
    let mut states = vec![MethodState::new(Method::paper())];
    run(&mut world, &o, &mut states, &mut |f, w| {
        let m = &f.methods[0];
        // The left eye's own 1-spp samples, traced in full.
        let sampler = PaperSampler::new(w.scene(), w.tracer(), o.materials);
        let mut left = EyeView::new(f.left.camera.clone());
        let mut own = vec![Vec3::ZERO; left.len()];
        sampler.trace_eye(f.left_seed, &mut left, &mut own);
        let mut hits = 0;
        for (i, t) in f.left.texels.iter().enumerate() {
            if t.is_hit() {
                hits += 1;
                assert!(m.stereo.outcomes[i].is_discarded(), "left pixel {i} kept");
                assert_eq!(
                    m.stereo.image[i], own[i],
                    "left pixel {i} is not its own sample"
                );
            } else {
                assert_eq!(m.stereo.outcomes[i], Outcome::Background);
            }
        }
        assert!(hits > 0);
        assert_eq!(m.stereo.discarded(), hits);
        assert_eq!(m.left_traced.samples as usize, hits);
        let right_hits = f.right.texels.iter().filter(|t| t.is_hit()).count();
        // No history survives: the temporal frame is the new 1-spp sample (on the first frame
        // there is no history at all, sky pixels included).
        let expect = if f.index == 0 {
            f.right.len()
        } else {
            right_hits
        };
        assert_eq!(m.temporal.discarded(), expect);
        assert_eq!(m.temporal.image, f.right_radiance);
        Ok(())
    })
    .unwrap();
}

/// Frames of the dataset this far apart (the props move slowly at 30 fps).
const STRIDE: u32 = 8;

/// A dataset whose head stays at its first pose (only the scene moves), every STRIDE-th frame.
struct FixedHead(Dataset, CameraDesc);

impl FrameWorld for FixedHead {
    fn frames(&self) -> u32 {
        self.0.frames() / STRIDE
    }
    fn pose(&mut self, f: u32) -> reproject::Result<()> {
        self.0.pose(f * STRIDE)
    }
    fn scene(&self) -> &Scene {
        self.0.scene()
    }
    fn tracer(&self) -> &dyn WorldTracer {
        self.0.tracer()
    }
    fn head(&self, _: u32) -> CameraDesc {
        self.1
    }
    fn geometry_moves(&self) -> bool {
        self.0.geometry_moves()
    }
    fn label(&self) -> String {
        self.0.label()
    }
}

/// Per frame `1..`: the right eye's temporally discarded pixels, and the screen boxes (two
/// pixels wider) of the moving objects at this and the previous frame.
fn temporal_discards(variant: Variant, frames: u32) -> Vec<(Vec<bool>, Vec<[f32; 4]>)> {
    let ds = atrium(variant);
    let head = ds.head(0);
    let anim = Animation::for_scene(&ds.scene);
    let objects: Vec<usize> = match &anim {
        Animation::Rigid(r) => r.tracks.iter().map(|t| t.object).collect(),
        Animation::Gltf(_) => unreachable!("the atrium has no glTF clips"),
    };
    assert!(!objects.is_empty());
    let o = opts(128, 80, frames);
    let mut world = FixedHead(ds, head);
    let mut states = vec![MethodState::new(Method::ours())];
    let mut out = Vec::new();
    let mut prev_boxes: Vec<[f32; 4]> = Vec::new();
    run(&mut world, &o, &mut states, &mut |f, w| {
        let mesh = &w.scene().mesh;
        let boxes: Vec<[f32; 4]> = objects
            .iter()
            .map(|&k| {
                let r = &mesh.objects[k];
                let mut b = [f32::MAX, f32::MAX, f32::MIN, f32::MIN];
                for p in &mesh.positions
                    [r.first_vertex as usize..(r.first_vertex + r.vertex_count) as usize]
                {
                    if let Some(q) = f.right.camera.project(*p, 0) {
                        b = [b[0].min(q.x), b[1].min(q.y), b[2].max(q.x), b[3].max(q.y)];
                    }
                }
                [b[0] - 2.0, b[1] - 2.0, b[2] + 2.0, b[3] + 2.0]
            })
            .collect();
        if f.index > 0 {
            let m = &f.methods[0];
            let mask = m
                .temporal
                .outcomes
                .iter()
                .map(|o| o.is_discarded())
                .collect();
            let mut both = boxes.clone();
            both.extend_from_slice(&prev_boxes);
            out.push((mask, both));
        }
        prev_boxes = boxes;
        Ok(())
    })
    .unwrap();
    out
}

#[test]
fn a_moving_objects_disocclusions_show_in_the_discard_mask() {
    let frames = 4;
    let still = temporal_discards(Variant::Base, frames);
    let moving = temporal_discards(Variant::MovingObjects, frames);
    let w = 128;
    for ((s, _), (m, boxes)) in still.iter().zip(&moving) {
        let (ns, nm) = (
            s.iter().filter(|&&d| d).count(),
            m.iter().filter(|&&d| d).count(),
        );
        // New discards where the objects moved: many more than camera jitter alone gives,
        let extra: Vec<usize> = (0..m.len()).filter(|&i| m[i] && !s[i]).collect();
        eprintln!("moving {nm} vs still {ns} discarded, {} new", extra.len());
        assert!(nm >= ns + 20, "moving {nm} vs still {ns} discarded");
        // and they lie where a moving object is or was.
        let inside = extra
            .iter()
            .filter(|&&i| {
                let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
                boxes
                    .iter()
                    .any(|b| x >= b[0] && y >= b[1] && x <= b[2] && y <= b[3])
            })
            .count();
        assert!(
            inside as f64 >= 0.95 * extra.len() as f64,
            "{inside} of {} new discards near the moving objects",
            extra.len()
        );
    }
}

#[test]
fn bad_options_are_clear_errors() {
    let err = |o: &RunOptions, methods: &[Method], spec: ReferenceSpec| {
        let eval = EvalOptions {
            run: o.clone(),
            reference: spec,
            cache: ReferenceCache::default(),
        };
        evaluate(&mut atrium(Variant::Base), &eval, methods, &|_| {})
            .unwrap_err()
            .to_string()
    };
    let spec = ReferenceSpec {
        spp: 8,
        curve_spp: 4,
    };
    let o = opts(16, 8, 2);
    for a in [0.0, -0.5, 1.5, f32::NAN] {
        let mut m = Method::paper();
        m.blend = reproject::Blend::Fixed(a);
        assert!(err(&o, &[m], spec).contains("--alpha"));
    }
    let mut neg = o.clone();
    neg.max_position = Some(-1.0);
    assert!(err(&neg, &[Method::paper()], spec).contains("--max-position"));
    neg.max_position = None;
    neg.max_normal_deg = Some(-3.0);
    assert!(err(&neg, &[Method::paper()], spec).contains("--max-normal-deg"));
    let short = opts(16, 8, 1);
    assert!(err(&short, &[Method::paper()], spec).contains("--frames"));
    let low = ReferenceSpec {
        spp: 4,
        curve_spp: 8,
    };
    assert!(err(&o, &[Method::paper()], low).contains("--reference-spp"));
    let zero = opts(0, 8, 2);
    assert!(err(&zero, &[Method::paper()], spec).contains("--width"));
    assert!(
        Method::named("nope")
            .unwrap_err()
            .to_string()
            .contains("paper")
    );
}
