//! The traversal of §1.4 (module docs of [`super`]): per direction a coarse DDA over the
//! `n x n` blocks, a fine DDA over a block's pixels where the ray's depth span meets the
//! block's `[min, max]`, and the sample test at every pixel. Nothing is allocated; every loop
//! has a step bound.

use parallax_core::math::floor_i64;
use parallax_core::{Ray, WorldStats};

use super::{LdcTracer, LdiTrace, SampleTest};

/// The ray in an LDI's frame: pixel coordinates `x(t) = ox + t dx`, `y(t) = oy + t dy` and the
/// depth from the box face `z(t) = oz + t dz` (world units); `uo, vo` are the origin's image
/// coordinates in world units from the box corner, `du, dv` the direction's.
struct LdiRay {
    ox: f32,
    oy: f32,
    dx: f32,
    dy: f32,
    oz: f32,
    dz: f32,
    uo: f32,
    vo: f32,
    du: f32,
    dv: f32,
    t_min: f32,
    /// Hits nearer than this are the surface the ray leaves (`t_min` + the skip distance).
    t_skip: f32,
}

/// One axis of a 2D DDA (Amanatides & Woo 1987) over cells of `size` units: the current cell,
/// its step, the `t` of the next cell boundary and the `t` between boundaries.
#[derive(Clone, Copy)]
struct DdaAxis {
    cell: i64,
    step: i64,
    t_next: f32,
    t_delta: f32,
}

impl DdaAxis {
    /// The axis at parameter `t` of `o + t d`, its cell clamped to `lo..=hi`.
    #[inline]
    fn new(o: f32, d: f32, t: f32, size: f32, lo: i64, hi: i64) -> Self {
        let cell = floor_i64((o + t * d) / size).clamp(lo, hi);
        if d > 0.0 {
            Self {
                cell,
                step: 1,
                t_next: ((cell + 1) as f32 * size - o) / d,
                t_delta: size / d,
            }
        } else if d < 0.0 {
            Self {
                cell,
                step: -1,
                t_next: (cell as f32 * size - o) / d,
                t_delta: -size / d,
            }
        } else {
            Self {
                cell,
                step: 0,
                t_next: f32::INFINITY,
                t_delta: f32::INFINITY,
            }
        }
    }
}

/// Advances the DDA to the next cell: returns the `t` where it is entered.
#[inline]
fn advance(x: &mut DdaAxis, y: &mut DdaAxis) -> f32 {
    if x.t_next < y.t_next {
        x.cell += x.step;
        let t = x.t_next;
        x.t_next += x.t_delta;
        t
    } else {
        y.cell += y.step;
        let t = y.t_next;
        y.t_next += y.t_delta;
        t
    }
}

/// The closest hit of a direction so far: sample index and `t`.
type Found = Option<(usize, f32)>;

impl LdcTracer {
    /// The closest hit `(axis, sample index, t)` of `ray` over the three directions, or the
    /// first one found when `any`.
    pub(super) fn trace(
        &self,
        ray: &Ray,
        any: bool,
        stats: &mut WorldStats,
    ) -> Option<(usize, usize, f32)> {
        // NaN parameters fail the comparison.
        if !ray.is_valid() || !(ray.t_min < ray.t_max) {
            return None;
        }
        let (t0, t1) = self.ldc.bounds.intersect(ray, ray.dir.recip())?;
        if !(t0.is_finite() && t1.is_finite()) {
            return None;
        }
        // The most ray-aligned direction first: it crosses the fewest pixels, and its hits
        // shorten the others.
        let a = ray.dir.abs();
        let order = if a.x >= a.y && a.x >= a.z {
            if a.y >= a.z { [0, 1, 2] } else { [0, 2, 1] }
        } else if a.y >= a.z {
            if a.x >= a.z { [1, 0, 2] } else { [1, 2, 0] }
        } else if a.x >= a.y {
            [2, 0, 1]
        } else {
            [2, 1, 0]
        };
        let mut best = None;
        let mut t_end = t1;
        let mut truncated = false;
        for axis in order {
            if let Some((i, t)) =
                self.trace_ldi(&self.ldis[axis], ray, t0, t_end, &mut truncated, stats)
            {
                best = Some((axis, i, t));
                t_end = t;
                if any {
                    break;
                }
            }
        }
        stats.truncated += truncated as u64;
        best
    }

    fn ldi_ray(&self, l: &LdiTrace, ray: &Ray) -> LdiRay {
        let lo = self.ldc.bounds.min;
        let inv_s = 1.0 / self.ldc.pixel_size;
        let (uo, vo) = (ray.origin[l.u] - lo[l.u], ray.origin[l.v] - lo[l.v]);
        let (du, dv) = (ray.dir[l.u], ray.dir[l.v]);
        LdiRay {
            ox: uo * inv_s,
            oy: vo * inv_s,
            dx: du * inv_s,
            dy: dv * inv_s,
            oz: ray.origin[l.axis] - lo[l.axis],
            dz: ray.dir[l.axis],
            uo,
            vo,
            du,
            dv,
            t_min: ray.t_min,
            t_skip: ray.t_min + self.opts.skip * self.ldc.pixel_size / ray.dir.length(),
        }
    }

    /// The coarse DDA of one direction over `[ta, tb]` (`tb` exclusive for hits).
    fn trace_ldi(
        &self,
        l: &LdiTrace,
        ray: &Ray,
        ta: f32,
        tb: f32,
        truncated: &mut bool,
        stats: &mut WorldStats,
    ) -> Found {
        if !(ta <= tb) {
            return None;
        }
        let r = self.ldi_ray(l, ray);
        let grid = &l.layout.bounds;
        let m = l.layout.intervals;
        let n = l.block as f32;
        let (bxn, byn) = (l.blocks_x as i64, l.blocks_y as i64);
        let mut x = DdaAxis::new(r.ox, r.dx, ta, n, 0, bxn - 1);
        let mut y = DdaAxis::new(r.oy, r.dy, ta, n, 0, byn - 1);
        let pad = self.opts.eps + l.margin;
        let mut t = ta;
        for _ in 0..(bxn + byn + 2) {
            let t_exit = x.t_next.min(y.t_next).min(tb).max(t);
            stats.nodes += 1;
            let b = (y.cell * bxn + x.cell) as usize;
            let (z0, z1) = (r.oz + t * r.dz, r.oz + t_exit * r.dz);
            let (lo, hi) = (z0.min(z1) - pad, z0.max(z1) + pad);
            // Empty slots are [+inf, -inf] and never overlap.
            if grid[b * m..(b + 1) * m]
                .iter()
                .any(|&[bmin, bmax]| hi >= bmin && lo <= bmax)
            {
                let found = self.walk_block(l, &r, [x.cell, y.cell], t, t_exit, tb, stats);
                if found.is_some() {
                    return found;
                }
            }
            if t_exit >= tb {
                return None;
            }
            t = advance(&mut x, &mut y);
            if x.cell < 0 || x.cell >= bxn || y.cell < 0 || y.cell >= byn {
                return None;
            }
        }
        *truncated = true;
        None
    }

    /// The fine DDA over the pixels of block `b` between `t0` and `t1`.
    #[allow(clippy::too_many_arguments)]
    fn walk_block(
        &self,
        l: &LdiTrace,
        r: &LdiRay,
        b: [i64; 2],
        t0: f32,
        t1: f32,
        t_end: f32,
        stats: &mut WorldStats,
    ) -> Found {
        let n = l.block as i64;
        let (x_lo, y_lo) = (b[0] * n, b[1] * n);
        let x_hi = ((b[0] + 1) * n).min(l.width as i64) - 1;
        let y_hi = ((b[1] + 1) * n).min(l.height as i64) - 1;
        let mut x = DdaAxis::new(r.ox, r.dx, t0, 1.0, x_lo, x_hi);
        let mut y = DdaAxis::new(r.oy, r.dy, t0, 1.0, y_lo, y_hi);
        let base = ((b[1] * l.blocks_x as i64 + b[0]) * n * n) as usize;
        let mut t = t0;
        for _ in 0..(2 * n + 2) {
            let t_out = x.t_next.min(y.t_next).min(t1).max(t);
            stats.steps += 1;
            let cell = base + ((y.cell - y_lo) * n + (x.cell - x_lo)) as usize;
            let pixel = [x.cell as u32, y.cell as u32];
            let found = self.test_pixel(l, r, cell, pixel, t, t_out, t_end, stats);
            if found.is_some() {
                return found;
            }
            if t_out >= t1 {
                return None;
            }
            t = advance(&mut x, &mut y);
            if x.cell < x_lo || x.cell > x_hi || y.cell < y_lo || y.cell > y_hi {
                return None;
            }
        }
        // The block's pixels are at most 2n apart along a monotone path: not reached.
        None
    }

    /// The nearest splat of layout cell `cell` (pixel `(px, py)`) that the ray hits while it
    /// crosses the pixel's column in `[t_in, t_out]`.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn test_pixel(
        &self,
        l: &LdiTrace,
        r: &LdiRay,
        cell: usize,
        [px, py]: [u32; 2],
        t_in: f32,
        t_out: f32,
        t_end: f32,
        stats: &mut WorldStats,
    ) -> Found {
        let cells = &l.layout.cells;
        let c = cells[cell];
        let eps = self.opts.eps;
        let pad = eps + l.margin;
        let (z_in, z_out) = (r.oz + t_in * r.dz, r.oz + t_out * r.dz);
        let (z_lo, z_hi) = (z_in.min(z_out), z_in.max(z_out));
        // Empty pixels have lo = +inf > hi = -inf and fail too.
        if c.lo > z_hi + pad || c.hi < z_lo - pad {
            return None;
        }
        let (k0, k1) = (c.start as usize, cells[cell + 1].start as usize);
        // A pixel of one or two samples holds just `lo` and `hi`: reject it without reading
        // its splats when neither is near the ray's span.
        let near = |d: f32| d >= z_lo - pad && d <= z_hi + pad;
        if k1 - k0 <= 2 && !near(c.lo) && !near(c.hi) {
            return None;
        }
        let s = self.ldc.pixel_size;
        let half = (0.5 + self.opts.overlap) * s;
        let eps2 = eps * eps;
        // The ray relative to the pixel centre (world units).
        let cu = r.uo - (px as f32 + 0.5) * s;
        let cv = r.vo - (py as f32 + 0.5) * s;
        let mut best: Option<(usize, f32, f32)> = None;
        for (k, &[d, gu, gv]) in l.layout.splats[k0..k1].iter().enumerate() {
            // Samples are sorted by depth: skip those below the ray's span, stop above it.
            if d < z_lo - pad {
                continue;
            }
            if d > z_hi + pad {
                break;
            }
            stats.tests += 1;
            // Signed depth of the ray above the sample's tangent plane: h(t) = h0 + h1 t.
            let h0 = r.oz - d - gu * cu - gv * cv;
            let h1 = r.dz - gu * r.du - gv * r.dv;
            if h1 == 0.0 {
                continue;
            }
            let t_cross = -h0 / h1;
            // A ray leaving the sample's surface recedes from its tangent plane.
            if !(t_cross > r.t_min) {
                continue;
            }
            // The hit's parameter (`t_hit`) and its order within the direction (`key`, inside
            // the pixel's interval, so pixels visited later never hold an earlier key).
            let (key, t_hit) = match self.opts.test {
                SampleTest::Plane => {
                    // Where the ray crosses the tangent plane, relative to the pixel centre:
                    // inside the pixel's square grown by `overlap` (the splat) or within eps
                    // of the sample point.
                    let (du, dv) = (cu + t_cross * r.du, cv + t_cross * r.dv);
                    let inside = du.abs() <= half && dv.abs() <= half;
                    if !inside {
                        let dz = gu * du + gv * dv;
                        if du * du + dv * dv + dz * dz >= eps2 {
                            continue;
                        }
                    }
                    (t_cross.clamp(t_in, t_out), t_cross)
                }
                SampleTest::Depth => {
                    // The paper's: the ray's depth within eps of the sample's over the pixel.
                    let h0 = r.oz - d;
                    let (ha, hb) = (h0 + r.dz * t_in, h0 + r.dz * t_out);
                    if ha.max(hb) <= -eps || ha.min(hb) >= eps {
                        continue;
                    }
                    let t = if r.dz != 0.0 { -h0 / r.dz } else { t_in };
                    let key = t.clamp(t_in, t_out);
                    (key, key)
                }
            };
            if t_hit > r.t_skip && t_hit < t_end && best.is_none_or(|(_, bk, _)| key < bk) {
                best = Some((k0 + k, key, t_hit));
            }
        }
        best.map(|(k, _, t)| (k, t))
    }
}
