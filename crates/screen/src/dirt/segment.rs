//! A ray's clipped segment projected onto a DIRT view's cell grid, and the walk's moves from
//! cell to cell (Vardis et al. 2017, §4.2.1 "Screen-space ray tracing"; the walk and why its
//! rounding keeps the answer exact: `walk`'s module docs). Film position (in cells) and
//! reciprocal view depth `w = 1 / depth` are affine in one screen-space parameter
//! `λ in [0, 1]`: a boundary crossing and the ray's `w` there are a multiply-add each.
//!
//! | item | meaning |
//! |---|---|
//! | `Axis` | one film axis: boundary `k` crossed at `λ = k inv + c` |
//! | `Segment` | the projected segment: film position and `w` at `λ = 0`, their spans |
//! | `next_cell`, `refine` | the cell after leaving a texel: across the boundary, and on the other axis |

use super::view::{ViewConsts, ViewRay};

/// One film axis of the projected segment: boundary `k` (in cells) is crossed at
/// `λ = k inv + c` (`inv = 1 / (x_b - x_a)`, `c = -x_a inv`); an axis the ray does not move
/// along has `inv = 0`, `c = +inf`, so every crossing is at `+inf` and the walk never steps
/// it (a step needs a crossing before the segment's end, `λ < 1`). The direction (`up`) is
/// not stored: the walk is specialised on it.
#[derive(Clone, Copy)]
pub(super) struct Axis {
    inv: f32,
    c: f32,
}

impl Axis {
    /// An axis the ray does not move along.
    pub(super) const STILL: Axis = Axis {
        inv: 0.0,
        c: f32::INFINITY,
    };

    /// The axis of a segment from `a` to `b` (cells), and whether the ray moves towards
    /// higher cell indices. Below `MIN_SPAN` cells the axis does not move (its film span is
    /// far inside the capture's film margin, and `1 / span` stays finite with room for
    /// `k inv`).
    #[inline(always)]
    pub(super) fn new(a: f32, b: f32) -> (Axis, bool) {
        const MIN_SPAN: f32 = 1e-30;
        let span = b - a;
        if span.abs() <= MIN_SPAN || span.is_nan() {
            return (Axis::STILL, span > 0.0);
        }
        let inv = 1.0 / span;
        (Axis { inv, c: -a * inv }, span > 0.0)
    }

    /// `λ` of the crossing of boundary `k`.
    #[inline(always)]
    pub(super) fn cross(&self, k: u32) -> f32 {
        k as f32 * self.inv + self.c
    }
}

/// The ray's clipped segment `[t_a, t_b]` projected onto the view's cell grid: film position
/// (in cells) and reciprocal view depth `w = 1 / depth` are affine in the screen-space
/// parameter `λ in [0, 1]` (module docs).
pub(super) struct Segment {
    pub(super) x: f32,
    pub(super) y: f32,
    pub(super) dx: f32,
    pub(super) dy: f32,
    pub(super) w: f32,
    pub(super) dw: f32,
    /// The ends in `t`, `t_b - t_a` and the depth at `t_b`, to map a hit's `t` to `λ`.
    t_a: f32,
    t_b: f32,
    dt: f32,
    z_b: f32,
}

impl Segment {
    #[inline(always)]
    pub(super) fn new(vc: &ViewConsts, r: &ViewRay, t_a: f32, t_b: f32) -> Segment {
        let (z_a, z_b) = (r.depth(t_a), r.depth(t_b));
        let (w_a, w_b) = (1.0 / z_a, 1.0 / z_b);
        let film = |t: f32, w: f32| {
            let (u, v) = ((r.o.x + t * r.d.x) * w, (r.o.y + t * r.d.y) * w);
            ((u - vc.a0) * vc.cells_per_u, (vc.b0 - v) * vc.cells_per_v)
        };
        let (x_a, y_a) = film(t_a, w_a);
        let (x_b, y_b) = film(t_b, w_b);
        Segment {
            x: x_a,
            y: y_a,
            dx: x_b - x_a,
            dy: y_b - y_a,
            w: w_a,
            dw: w_b - w_a,
            t_a,
            t_b,
            dt: t_b - t_a,
            z_b,
        }
    }

    /// A segment from its film start, film span, `w` at the start and `w` span (the `t`
    /// mapping left empty: for tests of the walk's steps).
    #[cfg(test)]
    pub(super) fn from_parts(x: f32, y: f32, dx: f32, dy: f32, w: f32, dw: f32) -> Segment {
        Segment {
            x,
            y,
            dx,
            dy,
            w,
            dw,
            t_a: 0.0,
            t_b: 0.0,
            dt: 0.0,
            z_b: 0.0,
        }
    }

    /// Reciprocal depth at `λ` (monotone in `λ`).
    #[inline(always)]
    pub(super) fn w_at(&self, l: f32) -> f32 {
        self.w + l * self.dw
    }

    /// `λ` of the ray point at `t`: `(t - t_a) z_b / ((t_b - t_a) z(t))` inside the segment
    /// (at most 1), 0 before it, `+inf` after it.
    #[inline]
    pub(super) fn lambda_of(&self, r: &ViewRay, t: f32) -> f32 {
        if t <= self.t_a {
            0.0
        } else if t <= self.t_b {
            fmin((t - self.t_a) * self.z_b / (self.dt * r.depth(t)), 1.0)
        } else {
            f32::INFINITY
        }
    }
}

/// `min` and `max` of two finite-or-infinite, non-NaN floats (plain comparisons; `f32::min`
/// pays for NaN handling the walk never needs).
#[inline(always)]
pub(super) fn fmin(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

#[inline(always)]
pub(super) fn fmax(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// `floor(f)` clamped to `[0, n)`.
#[inline(always)]
pub(super) fn cell_index(f: f32, n: u32) -> u32 {
    if f > 0.0 { (f as u32).min(n - 1) } else { 0 }
}

/// The cell across boundary `k` (in cells) in the ray's direction along the axis (`UP`:
/// towards higher indices). Only called for an axis whose crossing comes before the
/// segment's end, so a moving one. Off the grid before the end of the walk's interval
/// (clipped to the frustum), the ray runs along the film's edge within rounding of it (its
/// film direction is numerically undecided): it stays in the edge cells and the axis stops
/// stepping.
#[inline(always)]
pub(super) fn next_cell<const UP: bool>(c: u32, k: u32, axis: &mut Axis, n: u32) -> u32 {
    if UP {
        if k < n {
            return k;
        }
    } else if k > 0 {
        return k - 1;
    }
    *axis = Axis::STILL;
    c
}

/// The cell coordinate (along the axis the ray did not leave through) at the exit of texel `t`
/// at `level`: `floor(f)` kept inside the texel and never behind `c` in the ray's direction
/// (`UP`). The same on an axis that does not step (`Axis::STILL`): `f` is the ray's film
/// position there as on a moving axis (on an axis still from the start it floors to the start
/// cell; on one stopped at the grid's edge it is within rounding of that edge).
#[inline(always)]
pub(super) fn refine<const UP: bool>(c: u32, t: u32, level: u32, f: f32, n: u32) -> u32 {
    let lo = t << level;
    let hi = (((t + 1) << level) - 1).min(n - 1);
    let f = if f > 0.0 { f as u32 } else { 0 };
    let f = f.clamp(lo, hi);
    if UP { f.max(c) } else { f.min(c) }
}
