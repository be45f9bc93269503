//! Building a layered depth cube: validate, fit the box, assign triangles to axes, capture the
//! three all-layers LDIs, orient their normals and reduce their coarse grids (stages of the
//! module docs, each timed).

use std::time::Instant;

use glam::Vec3;
use parallax_core::math::Aabb;
use parallax_scene::Scene;
use rayon::prelude::*;

use super::{
    CoarseGrid, LayeredDepthCube, LdcOptions, LdcStats, Ldi, LdiStats, MAX_RESOLUTION,
    dominant_axis, ldi_view,
};
use crate::capture::{AllLayersCapture, capture_all_layers};
use crate::raster::{RasterError, ms};

fn invalid(msg: String) -> RasterError {
    RasterError::InvalidOptions(msg)
}

/// Checks the options (see the module table).
fn validate(resolution: u32, opts: &LdcOptions) -> Result<(), RasterError> {
    if resolution == 0 || resolution > MAX_RESOLUTION {
        return Err(invalid(format!(
            "LDC resolution must be in 1..={MAX_RESOLUTION}, got {resolution}"
        )));
    }
    if opts.block == 0 || opts.block > MAX_RESOLUTION {
        return Err(invalid(format!(
            "block must be in 1..={MAX_RESOLUTION}, got {}",
            opts.block
        )));
    }
    if !(opts.padding.is_finite() && opts.padding >= 0.0 && opts.padding <= 1.0) {
        return Err(invalid(format!(
            "padding must be in [0, 1], got {}",
            opts.padding
        )));
    }
    if opts.max_layers == 0 {
        return Err(invalid("max_layers must be at least 1".into()));
    }
    if let Some([lo, hi]) = opts.roi
        && !(lo.is_finite() && hi.is_finite() && lo.cmplt(hi).all())
    {
        return Err(invalid(format!(
            "the region of interest needs finite min < max on every axis, got {lo} .. {hi}"
        )));
    }
    Ok(())
}

/// The padded box of `scene` (fitted to `opts.roi`).
fn fit_box(scene: &Scene, opts: &LdcOptions) -> Result<Aabb, RasterError> {
    let raw = scene.mesh.bounds();
    if raw.is_empty() || !(raw.min.is_finite() && raw.max.is_finite()) {
        return Err(RasterError::InvalidMesh(
            "the scene has no finite bounding box".into(),
        ));
    }
    let raw = match opts.roi {
        None => raw,
        Some([lo, hi]) => {
            let b = Aabb::new(raw.min.max(lo), raw.max.min(hi));
            if !b.min.cmple(b.max).all() {
                return Err(invalid(format!(
                    "the region of interest {lo} .. {hi} misses the scene bounds {} .. {}",
                    raw.min, raw.max
                )));
            }
            b
        }
    };
    // Padding keeps surfaces off the image plane (depth > 0) and gives flat scenes depth.
    let longest = raw.extent().max_element();
    let pad = (opts.padding * longest).max(1e-6 * (1.0 + raw.max.abs().max_element()));
    Ok(Aabb::new(raw.min - pad, raw.max + pad))
}

/// Turns the capture's normals (flipped towards the LDI's viewer, looking along `+axis`) back
/// to the winding of their triangles — the resolve flipped them exactly when the geometric
/// normal's `axis` component is `>= 0` — and returns each sample's geometric normal.
fn orient_to_winding(scene: &Scene, cap: &mut AllLayersCapture, axis: usize) -> Vec<Vec3> {
    let mesh = &scene.mesh;
    cap.normal
        .par_iter_mut()
        .zip(cap.primitive_id.par_iter())
        .map(|(n, &p)| {
            let ng = mesh.geometric_normal(p as usize);
            if ng[axis] >= 0.0 {
                *n = -*n;
            }
            ng
        })
        .collect()
}

impl LayeredDepthCube {
    /// Builds the LDC of `scene` with `resolution` pixels along the padded box's longest side.
    /// Errors on an empty or non-finite scene, a resolution outside `1..=2^14`, invalid options,
    /// a region of interest that misses the scene, an LDI exceeding `opts.max_samples`, or a
    /// pixel deeper than `opts.max_layers` layers.
    pub fn build(scene: &Scene, resolution: u32, opts: &LdcOptions) -> Result<Self, RasterError> {
        let start = Instant::now();
        let mesh = &scene.mesh;
        validate(resolution, opts)?;
        crate::raster::check_mesh(mesh)?;
        let padded = fit_box(scene, opts)?;
        let s = padded.extent().max_element() / resolution as f32;
        // The box grows to whole pixels on every axis: its faces are the LDI image edges.
        let cells = (padded.extent() / s).ceil().max(glam::Vec3::ONE);
        let bounds = Aabb::new(padded.min, padded.min + cells * s);

        let t = Instant::now();
        let axis_of: Vec<u8> = (0..mesh.indices.len())
            .into_par_iter()
            .map(|i| dominant_axis(mesh, i) as u8)
            .collect();
        let mut counts = [0usize; 3];
        for &a in &axis_of {
            counts[a as usize] += 1;
        }
        let assign_ms = ms(t);

        let mut captures = Vec::with_capacity(3);
        let t = Instant::now();
        for axis in 0..3 {
            let view = ldi_view(&bounds, s, axis)?;
            let filter = |p: u32| axis_of[p as usize] as usize == axis;
            let cap = capture_all_layers(scene, &view, Some(&filter), opts.max_samples)?;
            if cap.stats.max_depth_complexity > opts.max_layers {
                return Err(invalid(format!(
                    "the LDI along {} needs {} layers (depth complexity) at {}x{}, more than \
                     the limit of {}: raise the layer limit or fit the cube to a region of \
                     interest",
                    ["x", "y", "z"][axis],
                    cap.stats.max_depth_complexity,
                    cap.width(),
                    cap.height(),
                    opts.max_layers
                )));
            }
            captures.push(cap);
        }
        let peel_ms = ms(t);

        let t = Instant::now();
        let geometric: Vec<Vec<Vec3>> = captures
            .iter_mut()
            .enumerate()
            .map(|(axis, cap)| orient_to_winding(scene, cap, axis))
            .collect();
        let orient_ms = ms(t);

        let t = Instant::now();
        let mut ldi_stats = [LdiStats::default(); 3];
        let mut ldis = Vec::with_capacity(3);
        for (axis, (capture, geometric_normal)) in captures.into_iter().zip(geometric).enumerate() {
            let t = Instant::now();
            let coarse = CoarseGrid::build(&capture, opts.block);
            ldi_stats[axis] = LdiStats {
                axis,
                triangles: counts[axis],
                capture: capture.stats,
                coarse_bytes: coarse.bytes(),
                coarse_ms: ms(t),
            };
            ldis.push(Ldi {
                axis,
                capture,
                geometric_normal,
                coarse,
            });
        }
        let grid_ms = ms(t);
        let ldis: [Ldi; 3] = ldis.try_into().expect("three LDIs");
        let stats = LdcStats {
            resolution,
            block: opts.block,
            box_min: bounds.min,
            box_max: bounds.max,
            roi: opts.roi.is_some(),
            pixel_size: s,
            triangles: mesh.indices.len(),
            samples: ldis.iter().map(|l| l.capture.len()).sum(),
            max_depth_complexity: ldis
                .iter()
                .map(|l| l.capture.stats.max_depth_complexity)
                .max()
                .unwrap_or(0),
            bytes: ldis.iter().map(Ldi::bytes).sum(),
            assign_ms,
            peel_ms,
            orient_ms,
            grid_ms,
            ldis: ldi_stats,
            total_ms: ms(start),
        };
        Ok(Self {
            bounds,
            pixel_size: s,
            ldis,
            stats,
        })
    }
}
