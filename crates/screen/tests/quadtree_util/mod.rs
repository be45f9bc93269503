//! Shared helpers of the quad-tree tests: synthetic height fields, ray sets, and the
//! comparison of two trace results.
#![allow(dead_code)]

use glam::{Vec2, Vec3};
use parallax_core::{GBuffer, Ray, Rng};
use parallax_scene::{CameraDesc, camera::Pinhole};
use parallax_screen::{
    BruteForcePlanes, QuadTreeOptions, QuadTreeTracer, ScreenTracer, TraceResult, TraceStats,
    UnitCube,
};

/// A pinhole looking down -Z from the origin.
pub fn camera(w: u32, h: u32) -> Pinhole {
    let desc = CameraDesc::new(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), Vec3::Y, 60.0);
    Pinhole::new(&desc, w, h).unwrap()
}

/// A random height field: smooth patches with depth steps, random tilted normals (facing the
/// camera), some empty pixels.
pub fn height_field(cam: &Pinhole, seed: u64, empty_frac: f32) -> GBuffer {
    let (w, h) = (cam.width, cam.height);
    let mut g = GBuffer::new(w, h).unwrap();
    let mut rng = Rng::new(seed, 7);
    let patches: Vec<(f32, f32, f32, f32, Vec3)> = (0..6)
        .map(|_| {
            let tilt = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, 0.0) * 1.6;
            (
                rng.next_f32() * w as f32,
                rng.next_f32() * h as f32,
                1.5 + 6.0 * rng.next_f32(),
                0.02 * (rng.next_f32() - 0.5),
                (Vec3::Z + tilt).normalize(),
            )
        })
        .collect();
    for j in 0..h {
        for i in 0..w {
            let k = (j * w + i) as usize;
            if rng.next_f32() < empty_frac {
                continue;
            }
            // Nearest patch centre decides the surface (Voronoi cells: depth steps).
            let p = patches
                .iter()
                .min_by(|a, b| {
                    let da = (a.0 - i as f32).powi(2) + (a.1 - j as f32).powi(2);
                    let db = (b.0 - i as f32).powi(2) + (b.1 - j as f32).powi(2);
                    da.total_cmp(&db)
                })
                .unwrap();
            let d = p.2 * (1.0 + p.3 * (i as f32 - p.0)) + 0.05 * rng.next_f32();
            let jitter = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, 0.0) * 0.3;
            g.depth[k] = d.max(0.5);
            g.normal[k] = (p.4 + jitter).normalize();
        }
    }
    g
}

/// World direction through film position `film`.
pub fn film_dir(cam: &Pinhole, film: Vec2) -> Vec3 {
    cam.frame.dir_to_world(cam.camera_dir(film)).normalize()
}

/// Random rays: from eyes displaced up to `spread` metres towards random captured points
/// (and a few fully random ones).
pub fn rays(cam: &Pinhole, g: &GBuffer, n: usize, spread: f32, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed, 11);
    let (w, h) = (cam.width, cam.height);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let film = Vec2::new(rng.next_f32() * w as f32, rng.next_f32() * h as f32);
        let k = ((film.y as u32).min(h - 1) * w + (film.x as u32).min(w - 1)) as usize;
        let d = if g.depth[k].is_finite() {
            g.depth[k] * (0.8 + 0.4 * rng.next_f32())
        } else {
            5.0 * rng.next_f32() + 0.5
        };
        let target = cam.frame.position
            + film_dir(cam, film) * d / film_dir(cam, film).dot(cam.frame.forward()).max(1e-3);
        let r = Vec3::new(
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
        );
        let origin = cam.frame.position + cam.frame.dir_to_world(r * 2.0 * spread);
        let dir = target - origin;
        if dir.length() > 1e-4 {
            out.push(Ray::new(origin, dir.normalize()));
        }
        if out.len() % 16 == 0 {
            // A fully random ray from inside the frustum.
            let film = Vec2::new(rng.next_f32() * w as f32, rng.next_f32() * h as f32);
            let o = cam.frame.position + film_dir(cam, film) * (0.5 + 4.0 * rng.next_f32());
            let dir = Vec3::new(
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
            );
            if dir.length() > 1e-3 {
                out.push(Ray::new(o, dir.normalize()));
            }
        }
    }
    out
}

/// How two results compare.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Same kind, layer, pixel; `t` within tolerance.
    Equal,
    /// Same kind and layer, `t` within tolerance, pixels adjacent: the event lies on a
    /// shared footprint edge/corner where both answers are right.
    EdgeTie,
    Differ,
}

pub fn compare(a: &TraceResult, b: &TraceResult, rel: f32) -> Verdict {
    // Relative tolerance, absolute below t = 1 (unit-length directions: metres; segment
    // parameters of the two tracers differ by f32 rounding of the footprint bounds).
    let close = |x: f32, y: f32| (x - y).abs() <= rel * x.abs().max(y.abs()).max(1.0);
    let pix = |p: glam::UVec2, q: glam::UVec2| {
        if p == q {
            Verdict::Equal
        } else if p.x.abs_diff(q.x) <= 1 && p.y.abs_diff(q.y) <= 1 {
            Verdict::EdgeTie
        } else {
            Verdict::Differ
        }
    };
    match (*a, *b) {
        (TraceResult::Miss, TraceResult::Miss) => Verdict::Equal,
        (
            TraceResult::Hit {
                layer: l1,
                pixel: p1,
                t: t1,
                ..
            },
            TraceResult::Hit {
                layer: l2,
                pixel: p2,
                t: t2,
                ..
            },
        )
        | (
            TraceResult::OcclusionVolume {
                layer: l1,
                pixel: p1,
                t: t1,
            },
            TraceResult::OcclusionVolume {
                layer: l2,
                pixel: p2,
                t: t2,
            },
        ) if l1 == l2 && close(t1, t2) => pix(p1, p2),
        _ => Verdict::Differ,
    }
}

impl Verdict {
    /// An occlusion-volume answer's `t` is where the ray enters the pixel footprint, i.e.
    /// crosses a pixel boundary line. For a ray almost parallel to that line in screen
    /// space the crossing is ill-conditioned in `t` (a 1-ulp difference in the grid
    /// coordinate moves it far along the ray; found by proptest: a ray gaining 0.037 px in
    /// y over its whole segment, the two tracers' `t` 3e-4 apart). Two OV answers of the
    /// same layer and pixel whose entry points lie within 1e-3 px of each other *on the
    /// screen* are the same entry computed with different rounding: [`Verdict::EdgeTie`].
    pub fn or_same_entry(
        self,
        a: &TraceResult,
        b: &TraceResult,
        ray: &Ray,
        cube: &parallax_screen::UnitCube,
    ) -> Verdict {
        let (
            Verdict::Differ,
            TraceResult::OcclusionVolume {
                layer: l1,
                pixel: p1,
                t: t1,
            },
            TraceResult::OcclusionVolume {
                layer: l2,
                pixel: p2,
                t: t2,
            },
        ) = (self, *a, *b)
        else {
            return self;
        };
        let grid = |t: f32| {
            cube.to_cube(ray.at(t)).map(|c| {
                glam::Vec2::new(
                    c.x * cube.camera.width as f32,
                    c.y * cube.camera.height as f32,
                )
            })
        };
        match (grid(t1), grid(t2)) {
            (Some(g1), Some(g2)) if l1 == l2 && p1 == p2 && g1.distance(g2) <= 1e-3 => {
                Verdict::EdgeTie
            }
            _ => self,
        }
    }

    /// A plane crossing exactly at a footprint boundary, classified differently by the two
    /// tracers. The footprint's entry and exit are computed with different f32 rounding
    /// (brute force: `(i / W - p0.x) / d.x` in cube units, `i / W` itself rounded; the
    /// traversal: `(i - o.x) r` in grid units with `r` the rounded reciprocal of the
    /// direction), so when the ray crosses a pixel's plane within ~1e-6 px of a footprint
    /// edge, one tracer sees the crossing inside (a **hit**) and the other just outside: at
    /// the entry the ray then enters **behind** the plane (an occlusion-volume entry), at the
    /// exit it leaves still in front (nothing at that pixel). Both are right up to rounding,
    /// and the difference can change the final answer entirely (a later hit elsewhere; in a
    /// cascade a deeper layer's crossing becomes the closest hit, or not). Found by
    /// proptest: cascade 24x45 (the plane root 1.0e-6 px outside the entry in f64, brute
    /// force's bound `27/45` rounded 1.07e-6 px further out: a hit), cascade 53x41 (layer
    /// 1's root 3.7e-7 px outside the entry, the traversal's entry one ulp earlier: a layer-1
    /// hit beating layer 0's), lossless 88x26 (the root 9.3e-7 px inside the exit, brute
    /// force's bound `37/88` rounded just before it: brute force's hit is a pixel later),
    /// lossless 72x17 (the root 6.4e-8 px inside the image's right edge, where the segment
    /// ends: brute force's `f(1)` is exactly 0, a hit; the traversal's footprint exit is
    /// one ulp earlier, a miss).
    ///
    /// Turns [`Verdict::Differ`] into [`Verdict::EdgeTie`] only when the answer of one
    /// tracer *is* the other's with that single crossing reclassified:
    /// - quad-tree `a` = Hit at `(layer, pixel, t)`, a crossing of that pixel's plane on its
    ///   footprint boundary ([`crossing_on_boundary`]), and brute force has no hit before
    ///   `t`: counted as a hit, brute force's closest hit is exactly `a`;
    /// - brute force `b` = such a Hit: brute force over the planes without that pixel's
    ///   plane, plus what the pixel contributes with the crossing just outside its footprint
    ///   ([`footprint_without_crossing`]: an occlusion entry or nothing), must equal `a`
    ///   ([`compare`] and [`Verdict::or_same_entry`]).
    pub fn or_boundary_crossing(
        self,
        a: &TraceResult,
        b: &TraceResult,
        ray: &Ray,
        bf: &BruteForcePlanes,
        rel: f32,
    ) -> Verdict {
        if self != Verdict::Differ {
            return self;
        }
        let detail = bf.trace_detailed(ray, &mut TraceStats::default());
        if let TraceResult::Hit {
            layer, pixel, t, ..
        } = *a
            && crossing_on_boundary(bf, ray, layer, pixel, t)
            && detail.hit.is_none_or(|h| h.t >= t)
        {
            return Verdict::EdgeTie;
        }
        if let TraceResult::Hit {
            layer, pixel, t, ..
        } = *b
            && crossing_on_boundary(bf, ray, layer, pixel, t)
        {
            let mut without = bf.clone();
            let k = (pixel.y * bf.cube.camera.width + pixel.x) as usize;
            without.layers[layer as usize].normal[k] = Vec3::ZERO;
            let r = without.trace_detailed(ray, &mut TraceStats::default());
            // The crossing just outside the footprint: inside it the ray is then wholly on
            // the side of the footprint's other end — behind the plane: an occlusion entry
            // at the footprint entry; in front: nothing.
            let ov = footprint_without_crossing(bf, ray, layer, pixel, t)
                .map(|t_entry| (t_entry, layer, pixel));
            let first_ov = match (r.occlusion.map(|o| (o.t, o.layer, o.pixel)), ov) {
                (Some(x), Some(y)) => Some(if (x.0, x.1) <= (y.0, y.1) { x } else { y }),
                (x, y) => x.or(y),
            };
            let expected = match (r.hit, first_ov) {
                (Some(h), _) => TraceResult::Hit {
                    layer: h.layer,
                    pixel: h.pixel,
                    position: ray.at(h.t),
                    t: h.t,
                },
                (None, Some((t, layer, pixel))) => TraceResult::OcclusionVolume { layer, pixel, t },
                (None, None) => TraceResult::Miss,
            };
            if compare(a, &expected, rel).or_same_entry(a, &expected, ray, &bf.cube)
                != Verdict::Differ
            {
                return Verdict::EdgeTie;
            }
        }
        self
    }
}

/// Screen distance (px) of a crossing from a footprint boundary for
/// [`Verdict::or_boundary_crossing`].
pub const BOUNDARY_TIE_PX: f32 = 1e-3;

/// For a crossing of pixel `pixel`'s plane at world `t` on its footprint boundary
/// ([`crossing_on_boundary`]), moved just outside the footprint: the occlusion entry the
/// pixel then contributes (world `t` of the footprint entry, the same slab test as
/// [`BruteForcePlanes`]) when the ray is behind the plane at the footprint's other end,
/// else `None`.
pub fn footprint_without_crossing(
    bf: &BruteForcePlanes,
    ray: &Ray,
    layer: u32,
    pixel: glam::UVec2,
    t: f32,
) -> Option<f32> {
    let seg = bf.cube.clip_ray(ray)?;
    let x = bf.cube.to_cube(ray.at(t))?;
    let (wf, hf) = (bf.cube.camera.width as f32, bf.cube.camera.height as f32);
    let d = seg.p1 - seg.p0;
    let (mut sa, mut sb) = (0.0f32, 1.0f32);
    for (o, dd, lo, hi) in [
        (
            seg.p0.x,
            d.x,
            pixel.x as f32 / wf,
            (pixel.x + 1) as f32 / wf,
        ),
        (
            seg.p0.y,
            d.y,
            pixel.y as f32 / hf,
            (pixel.y + 1) as f32 / hf,
        ),
    ] {
        if dd != 0.0 {
            let (t0, t1) = ((lo - o) / dd, (hi - o) / dd);
            sa = sa.max(t0.min(t1));
            sb = sb.min(t0.max(t1));
        }
    }
    let sc = (x - seg.p0).dot(d) / d.dot(d);
    let far = if (sc - sa).abs() < (sc - sb).abs() {
        sb
    } else {
        sa
    };
    let k = (pixel.y * bf.cube.camera.width + pixel.x) as usize;
    (bf.layers[layer as usize].side(k, seg.at(far)) < 0.0).then(|| seg.world_t(sa))
}

/// True when the ray at `t` lies within [`BOUNDARY_TIE_PX`] of the footprint boundary of
/// `pixel` (inside or out) and on that pixel's plane of `layer` (`|N·X - c| <= 1e-5 |N|`,
/// cube units: the world-to-cube round trip of the point).
pub fn crossing_on_boundary(
    bf: &BruteForcePlanes,
    ray: &Ray,
    layer: u32,
    pixel: glam::UVec2,
    t: f32,
) -> bool {
    let cam = &bf.cube.camera;
    let Some(x) = bf.cube.to_cube(ray.at(t)) else {
        return false;
    };
    let Some(planes) = bf.layers.get(layer as usize) else {
        return false;
    };
    let g = Vec2::new(x.x * cam.width as f32, x.y * cam.height as f32);
    let p = pixel.as_vec2();
    // Signed distance to the footprint's edges: the smallest of the four margins.
    let on_edge = (g - p).min(p + 1.0 - g).min_element().abs() <= BOUNDARY_TIE_PX;
    let k = (pixel.y * cam.width + pixel.x) as usize;
    on_edge && planes.covered(k) && planes.side(k, x).abs() <= 1e-5 * planes.normal[k].length()
}

/// Counts of a comparison run.
#[derive(Clone, Copy, Debug, Default)]
pub struct Tally {
    pub equal: usize,
    pub edge: usize,
    pub differ: usize,
    pub hits: usize,
    pub ovs: usize,
}

impl Tally {
    pub fn total(&self) -> usize {
        self.equal + self.edge + self.differ
    }
}

/// Traces `rays` with both tracers; returns the tally and the first difference.
pub fn run(
    qt: &QuadTreeTracer,
    bf: &BruteForcePlanes,
    rays: &[Ray],
    rel: f32,
) -> (Tally, Option<String>, TraceStats) {
    let mut tally = Tally::default();
    let mut first = None;
    let mut stats = TraceStats::default();
    let mut bstats = TraceStats::default();
    for (i, r) in rays.iter().enumerate() {
        let a = qt.trace(r, &mut stats);
        let b = bf.trace(r, &mut bstats);
        match a {
            TraceResult::Hit { .. } => tally.hits += 1,
            TraceResult::OcclusionVolume { .. } => tally.ovs += 1,
            _ => {}
        }
        match compare(&a, &b, rel)
            .or_same_entry(&a, &b, r, &bf.cube)
            .or_boundary_crossing(&a, &b, r, bf, rel)
        {
            Verdict::Equal => tally.equal += 1,
            Verdict::EdgeTie => tally.edge += 1,
            Verdict::Differ => {
                tally.differ += 1;
                if first.is_none() {
                    first = Some(format!("ray {i} {r:?}: quadtree {a:?} vs brute {b:?}"));
                }
            }
        }
    }
    (tally, first, stats)
}

/// Brute force over the tracer's decoded (effective) planes.
pub fn twin(qt: &QuadTreeTracer) -> BruteForcePlanes {
    BruteForcePlanes {
        cube: qt.cube.clone(),
        layers: qt.trees.iter().map(|t| t.effective_planes()).collect(),
    }
}

/// The fitted cube of some layers.
pub fn cube(cam: &Pinhole, layers: &[GBuffer]) -> UnitCube {
    UnitCube::fit_depths(cam, layers.iter().map(|g| &g.depth[..])).unwrap()
}

/// One ray per pixel of the reference camera moved by `shift` metres along its right axis
/// (a stereo eye for `shift = ipd / 2`).
pub fn stereo_rays(cam: &Pinhole, shift: f32) -> Vec<Ray> {
    let o = cam.frame.position + cam.frame.right() * shift;
    let mut out = Vec::with_capacity((cam.width * cam.height) as usize);
    for y in 0..cam.height {
        for x in 0..cam.width {
            out.push(Ray::new(
                o,
                film_dir(cam, Vec2::new(x as f32 + 0.5, y as f32 + 0.5)),
            ));
        }
    }
    out
}

/// `opts` without crack dilation: the brute-force twin ([`twin`]) tests every plane over its
/// own footprint only, so exact agreement needs `crack_dilation = 0` (G-buffer planes carry
/// the flag `O` at depth steps and cracks, [`parallax_screen::planes::crack_flags`]).
pub fn exact(opts: QuadTreeOptions) -> QuadTreeOptions {
    QuadTreeOptions {
        crack_dilation: 0.0,
        ..opts
    }
}

/// A second layer behind `g`: depth + random gap, unrelated random normals (so deeper planes
/// often poke in front of layer 0 inside footprints: unsafe pixels).
pub fn behind(g: &GBuffer, seed: u64) -> GBuffer {
    let mut rng = Rng::new(seed, 3);
    let mut b = g.clone();
    for k in 0..b.depth.len() {
        if !b.depth[k].is_finite() || rng.next_f32() < 0.2 {
            b.depth[k] = f32::INFINITY;
            b.normal[k] = Vec3::ZERO;
            continue;
        }
        b.depth[k] += 0.02 + 2.0 * rng.next_f32().powi(3);
        let t = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, 0.0) * 2.5;
        b.normal[k] = (Vec3::Z + t).normalize();
    }
    b
}
