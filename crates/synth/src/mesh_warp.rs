//! Mesh-based forward warping, the non-tracing baseline of Widmer et al. 2015, §5.1 ("the
//! reference view as a regular grid mesh ... with one vertex per input image pixel", after
//! Didyk et al. 2010 / Bowles et al. 2012).
//!
//! **Mesh.** Vertex `y W + x` is layer 0's world position at pixel `(x, y)` with that pixel's
//! colour. Each 2x2 block of pixel centres gives two triangles (`(x,y) (x,y+1) (x+1,y)` and
//! `(x+1,y) (x,y+1) (x+1,y+1)`); a triangle is dropped when a corner saw no surface, or when
//! its corners' view depths differ by more than `max_rel_jump` times the smallest
//! (`max d / min d - 1 > max_rel_jump`). With the default `max_rel_jump = inf` no triangle is
//! split at depth jumps and disocclusions are filled by stretched triangles, as in the paper's
//! Fig. 6b / 7a; a finite threshold tears the mesh there and the holes show the environment.
//! Only layer 0 is used (the paper's mesh warping is single-layer).
//!
//! **Warp.** The mesh is rasterized into the target view with [`parallax_raster::rasterize`]
//! (one layer, nearest fragment); a pixel's colour interpolates its triangle's vertex colours
//! with the fragment's perspective-correct barycentrics. Uncovered pixels are misses (the
//! environment colour; a colour + depth input's by direction, [`crate::environment`]).

use std::sync::Arc;
use std::time::Instant;

use glam::{Vec2, Vec3};
use parallax_core::{Image, Rgb};
use parallax_raster::{RasterOptions, View, rasterize};
use parallax_scene::TriangleMesh;
use parallax_scene::camera::Pinhole;
use parallax_screen::TraceStats;
use rayon::prelude::*;

use crate::SynthError;
use crate::environment::Environment;
use crate::layers::Reference;
use crate::warp::{HitKind, WarpedView};

/// The grid mesh of a reference's layer 0 with per-vertex colours.
#[derive(Clone, Debug)]
pub struct GridMesh {
    pub mesh: TriangleMesh,
    pub colors: Vec<Rgb>,
    pub background: Rgb,
    /// The input's environment by direction (misses), as in [`crate::warp`].
    pub environment: Option<Arc<Environment>>,
}

impl GridMesh {
    /// Builds the mesh (module docs); `max_rel_jump` must be >= 0 (inf = never split).
    pub fn build(reference: &Reference, max_rel_jump: f32) -> Result<Self, SynthError> {
        if !(max_rel_jump >= 0.0) {
            return Err(SynthError::Invalid(format!(
                "mesh max_rel_jump must be >= 0, got {max_rel_jump}"
            )));
        }
        let g = &reference.layers[0];
        let (w, h) = (reference.width() as usize, reference.height() as usize);
        let covered = |i: usize| g.depth[i].is_finite() && g.depth[i] > 0.0;
        let positions: Vec<Vec3> = (0..w * h)
            .map(|i| {
                if covered(i) {
                    g.position[i]
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        let keep = |t: [usize; 3]| {
            if !t.iter().all(|&i| covered(i)) {
                return false;
            }
            let d = t.map(|i| g.depth[i]);
            let (lo, hi) = (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]));
            hi / lo - 1.0 <= max_rel_jump
        };
        let indices: Vec<[u32; 3]> = (0..h.saturating_sub(1))
            .into_par_iter()
            .flat_map_iter(|y| {
                (0..w.saturating_sub(1)).flat_map(move |x| {
                    let a = y * w + x;
                    let (b, c, d) = (a + 1, a + w, a + w + 1);
                    [[a, c, b], [b, c, d]]
                        .into_iter()
                        .filter(move |&t| keep(t))
                        .map(|t| t.map(|i| i as u32))
                })
            })
            .collect();
        let n = indices.len();
        let mesh = TriangleMesh {
            positions,
            indices,
            material_ids: vec![0; n],
            ..TriangleMesh::default()
        };
        Ok(Self {
            mesh,
            colors: reference.colors[0].data().to_vec(),
            background: reference.background,
            environment: reference.environment.clone(),
        })
    }

    /// Rasterizes the mesh into `target`.
    pub fn warp(&self, target: &Pinhole) -> Result<WarpedView, SynthError> {
        let start = Instant::now();
        let view = View::from_pinhole(target)?;
        let (frags, _) = rasterize(&self.mesh, &view, &RasterOptions::layers(1), None)?;
        let (w, h) = (target.width, target.height);
        let px: Vec<(Rgb, HitKind)> = (0..w * h)
            .into_par_iter()
            .map(|i| {
                let f = frags.get(i % w, i / w, 0);
                if f.is_empty() {
                    let c = match &self.environment {
                        Some(env) => {
                            let film = Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
                            env.lookup(target.frame.dir_to_world(target.camera_dir(film)))
                        }
                        None => self.background,
                    };
                    return (c, HitKind::Miss);
                }
                let [a, b, c] = self.mesh.indices[f.prim as usize];
                let col = self.colors[a as usize] * (1.0 - f.b1 - f.b2)
                    + self.colors[b as usize] * f.b1
                    + self.colors[c as usize] * f.b2;
                (col, HitKind::Hit(0))
            })
            .collect();
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let (image, kinds): (Vec<Rgb>, Vec<HitKind>) = px.into_iter().unzip();
        Ok(WarpedView {
            image: Image::from_vec(w, h, image)?,
            kinds,
            work: vec![0; (w * h) as usize],
            stats: TraceStats::default(),
            ms,
        })
    }
}
