//! DIRT's deferred path tracer against the reference (Vardis et al. 2017, §4.2 and §5.1
//! "identical results with the reference images"): the same wavefront path tracer
//! ([`PathTracer`]: trace pass -> hit buffer, fetch pass, shade pass per bounce) rendered twice
//! with the same seed, once with the BVH and once with DIRT behind the tracer interface, every
//! ray recorded. Rays are matched by (sample, bounce, pixel, channel): once a path's hits
//! differ it takes other rays, which are then matched only where both renders traced them.
//!
//! Per bounce: rays matched, same primitive (or both miss), ties (different primitives at
//! exactly the same `t`: coplanar overlapping triangles, where the BVH keeps the lower index in
//! its leaf order and DIRT the lower triangle id), and for the shadow rays the same occlusion
//! answer; and the PSNR of the two images.

use std::collections::HashMap;
use std::time::Instant;

use parallax_core::NO_ID;
use parallax_core::metrics::psnr_rgb;
use parallax_scene::Scene;
use parallax_scene::camera::Camera;
use serde::Serialize;

use crate::error::Result;
use crate::options::PathOptions;
use crate::record::PathRecord;
use crate::render::{PathOutput, PathTracer};
use crate::tracers::{TracerKind, TracerOptions, build_tracer};

/// Agreement of one bounce.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BounceAgreement {
    pub bounce: u32,
    /// Closest-hit rays traced by both renders.
    pub rays: u64,
    /// Same primitive, or both miss.
    pub same: u64,
    /// Different primitives at the same `t`.
    pub ties: u64,
    /// Rays only one of the renders traced (their paths diverged before).
    pub unmatched: u64,
    pub shadow_rays: u64,
    pub shadow_same: u64,
}

impl BounceAgreement {
    /// Fraction of matched rays with the same primitive.
    pub fn same_fraction(&self) -> f64 {
        self.same as f64 / self.rays.max(1) as f64
    }

    /// Fraction of matched rays with the same primitive or a tie.
    pub fn same_or_tie_fraction(&self) -> f64 {
        (self.same + self.ties) as f64 / self.rays.max(1) as f64
    }
}

/// Per-bounce agreement of two records of the same render settings.
pub fn compare_records(reference: &PathRecord, other: &PathRecord) -> Vec<BounceAgreement> {
    let key = |s: u32, b: u32, x: u32, y: u32, c: u8| (s, b, x, y, c);
    let rays: HashMap<_, _> = reference
        .rays
        .iter()
        .map(|r| (key(r.sample, r.bounce, r.x, r.y, r.channel), (r.prim, r.t)))
        .collect();
    let depth = reference
        .rays
        .iter()
        .chain(&other.rays)
        .map(|r| r.bounce + 1)
        .max()
        .unwrap_or(0);
    let mut out: Vec<BounceAgreement> = (0..depth)
        .map(|bounce| BounceAgreement {
            bounce,
            ..BounceAgreement::default()
        })
        .collect();
    for r in &other.rays {
        let a = &mut out[r.bounce as usize];
        match rays.get(&key(r.sample, r.bounce, r.x, r.y, r.channel)) {
            Some(&(prim, t)) => {
                a.rays += 1;
                if prim == r.prim {
                    a.same += 1;
                } else if prim != NO_ID && r.prim != NO_ID && t == r.t {
                    a.ties += 1;
                }
            }
            None => a.unmatched += 1,
        }
    }
    // Reference rays without a partner.
    for a in &mut out {
        let in_ref = reference.bounce(a.bounce).count() as u64;
        a.unmatched += in_ref - a.rays;
    }
    // Shadow rays: keyed by the vertex they leave and their rank among that vertex's shadow
    // rays in record order (a vertex may cast several: one per light sample).
    let keyed = |rec: &PathRecord| -> HashMap<(u32, u32, u32, u32, u32), bool> {
        let mut rank: HashMap<(u32, u32, u32, u32), u32> = HashMap::new();
        rec.shadows
            .iter()
            .map(|s| {
                let v = (s.sample, s.bounce, s.x, s.y);
                let k = rank.entry(v).or_insert(0);
                *k += 1;
                ((v.0, v.1, v.2, v.3, *k), s.occluded)
            })
            .collect()
    };
    let shadows = keyed(reference);
    for (k, occluded) in keyed(other) {
        if let (Some(&occ), Some(a)) = (shadows.get(&k), out.get_mut(k.1 as usize)) {
            a.shadow_rays += 1;
            a.shadow_same += (occ == occluded) as u64;
        }
    }
    out
}

/// The BVH and DIRT renders of one scene and camera with the same options.
#[derive(Clone, Debug, Serialize)]
pub struct PathAgreement {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub bounces: Vec<BounceAgreement>,
    /// PSNR (peak 1) of DIRT's image against the BVH's; infinite when bit-identical.
    pub psnr: f64,
    /// Pixels whose value differs at all.
    pub pixels_differ: u64,
    pub ms_build_bvh: f64,
    pub ms_build_dirt: f64,
    pub ms_render_bvh: f64,
    pub ms_render_dirt: f64,
}

/// Renders `scene` through `camera` with the BVH and with DIRT (`tracer_opts.dirt`), every ray
/// recorded, and compares them; also returns the two renders (BVH, DIRT).
pub fn path_agreement(
    scene: &Scene,
    camera: &Camera,
    opts: &PathOptions,
    tracer_opts: &TracerOptions,
) -> Result<(PathAgreement, PathOutput, PathOutput)> {
    let run = |kind| -> Result<(PathOutput, PathRecord, f64, f64)> {
        let built = build_tracer(kind, scene, camera, tracer_opts)?;
        let pt = PathTracer::new(scene, camera, built.tracer.as_ref(), opts.clone())?;
        let t = Instant::now();
        let (out, rec) = pt.render_recorded(&|_| {});
        Ok((out, rec, built.build_ms, t.elapsed().as_secs_f64() * 1e3))
    };
    let (bvh_out, bvh_rec, bvh_build, bvh_ms) = run(TracerKind::Bvh)?;
    let (dirt_out, dirt_rec, dirt_build, dirt_ms) = run(TracerKind::Dirt)?;
    let pixels_differ = bvh_out
        .image
        .data()
        .iter()
        .zip(dirt_out.image.data())
        .filter(|(a, b)| a != b)
        .count() as u64;
    let agreement = PathAgreement {
        scene: scene.name.clone(),
        width: bvh_out.image.width(),
        height: bvh_out.image.height(),
        spp: bvh_out.spp,
        max_depth: opts.max_depth,
        bounces: compare_records(&bvh_rec, &dirt_rec),
        psnr: psnr_rgb(&bvh_out.image, &dirt_out.image, 1.0)?,
        pixels_differ,
        ms_build_bvh: bvh_build,
        ms_build_dirt: dirt_build,
        ms_render_bvh: bvh_ms,
        ms_render_dirt: dirt_ms,
    };
    Ok((agreement, bvh_out, dirt_out))
}
