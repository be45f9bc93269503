//! One DIRT view prepared for tracing: its projection as plane constants, and a world ray
//! expressed in the view (Vardis et al. 2017, §4.2.1 "Screen-space ray tracing": "rays are
//! clipped against the viewing frustum and subsequently traced ... up to the screen-space
//! projection of their clipped endpoint").
//!
//! A view is a pinhole with camera space `q = R (p - eye)` (looking down `-z`), view depth
//! `-q.z`, and film position `x = (u - a0) / ax`, `y = (b0 - v) / by` of the slopes
//! `u = q.x / depth`, `v = q.y / depth` — the projection of `DirtCapture`'s build. On a ray
//! `q(t) = o + t d` the depth `z(t) = z0 + t dz` is affine in `t`; the walk (`walk`) projects
//! the clipped segment's two ends and steps along its projection.

use glam::Vec3;
use parallax_raster::dirt::DirtCapture;

/// Mip levels a view can have: a grid of at most `2^31` cells a side.
pub(crate) const MAX_LEVELS: usize = 32;

/// The constants of one view.
#[derive(Clone, Debug)]
pub(crate) struct ViewConsts {
    pub eye: Vec3,
    /// Rows of `R` (the view's right, up and backward axes).
    pub rows: [Vec3; 3],
    pub near: f32,
    /// `u` of film column 0.
    pub a0: f32,
    /// `u` of the last film column (`a0 + W ax`, computed without rounding through `ax`).
    pub a_end: f32,
    /// `v` of film row 0.
    pub b0: f32,
    /// `v` of the last film row.
    pub b_end: f32,
    /// `1 / (ax * S)` and `1 / (by * S)`: cells per unit slope.
    pub cells_per_u: f32,
    pub cells_per_v: f32,
    pub cells_x: u32,
    pub cells_y: u32,
    pub buckets: u32,
    /// Index of the top mip level.
    pub top: usize,
    /// Per mip level, its first texel in the flat bounds array and its width.
    pub level_offset: [u32; MAX_LEVELS],
    pub level_width: [u32; MAX_LEVELS],
    /// Bound on loop iterations of one traversal of this view.
    pub max_steps: u32,
    /// The instruction set the walk of this view runs on.
    pub isa: Isa,
}

/// Which compiled copy of the tracer runs (`walk`): the same source and results on each.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
#[repr(u8)]
pub(crate) enum Isa {
    /// The build's baseline (the portable twin).
    Baseline = 0,
    /// x86-64-v3: AVX2, BMI1/2, LZCNT, POPCNT.
    X86V3 = 1,
    /// x86-64-v3 and AVX-512 F/VL/BW/DQ: 32 vector registers for the walk's float state.
    X86V4 = 2,
}

impl Isa {
    /// Every copy this CPU runs, the best last.
    pub fn available() -> Vec<Isa> {
        let mut v = vec![Isa::Baseline];
        if parallax_core::cpu::x86_64_v3() {
            v.push(Isa::X86V3);
            if parallax_core::cpu::x86_64_v4() {
                v.push(Isa::X86V4);
            }
        }
        v
    }

    /// The best copy this CPU runs.
    pub fn detect() -> Isa {
        *Isa::available().last().expect("baseline")
    }
}

impl ViewConsts {
    pub fn new(cap: &DirtCapture) -> ViewConsts {
        let view = cap.view();
        let b = view.frame.basis;
        let (w, h) = (view.width as f32, view.height as f32);
        let tx = view.tan_half_x();
        let ty = view.tan_half_y;
        let ax = 2.0 * tx / w;
        let by = 2.0 * ty / h;
        let s = cap.tile_size();
        let (cells_x, cells_y) = cap.cells();
        let top = cap.mip_levels() - 1;
        let (levels, bounds) = cap.mip_arrays();
        assert!(
            levels.len() <= MAX_LEVELS && bounds.len() <= u32::MAX as usize,
            "mip chain too large"
        );
        // Every iteration either descends a level or leaves a texel; leaving moves the cell
        // one step in x or y in the ray's (monotone) film direction, and at most `top` levels
        // are descended per move.
        let max_steps = (cells_x + cells_y + 4).saturating_mul(2 * top as u32 + 4);
        ViewConsts {
            eye: view.frame.position,
            rows: [b.x_axis, b.y_axis, b.z_axis],
            near: cap.options().near,
            a0: (view.shift.x - 1.0) * tx,
            a_end: (view.shift.x + 1.0) * tx,
            b0: (view.shift.y + 1.0) * ty,
            b_end: (view.shift.y - 1.0) * ty,
            cells_per_u: 1.0 / (ax * s as f32),
            cells_per_v: 1.0 / (by * s as f32),
            cells_x,
            cells_y,
            buckets: cap.buckets(),
            top,
            level_offset: std::array::from_fn(|k| levels.get(k).map_or(0, |l| l.offset as u32)),
            level_width: std::array::from_fn(|k| levels.get(k).map_or(0, |l| l.width)),
            max_steps,
            isa: Isa::detect(),
        }
    }

    /// The world ray `origin + t dir` in this view.
    #[inline(always)]
    pub fn ray(&self, origin: Vec3, dir: Vec3) -> ViewRay {
        let p = origin - self.eye;
        let o = Vec3::new(
            self.rows[0].dot(p),
            self.rows[1].dot(p),
            self.rows[2].dot(p),
        );
        let d = Vec3::new(
            self.rows[0].dot(dir),
            self.rows[1].dot(dir),
            self.rows[2].dot(dir),
        );
        ViewRay {
            o,
            d,
            z0: -o.z,
            dz: -d.z,
        }
    }

    /// The part of `[t0, t1]` where the ray is inside the view's frustum: depth at least
    /// `near`, film position inside `[0, W] x [0, H]`. Each bound is a half-space
    /// `f0 + t f1 >= 0` in `t`. Neighbouring cube faces share their side planes, and the
    /// constants of a face are exactly `±1` (90-degree faces), so the two faces compute
    /// bit-identical crossing parameters and their intervals meet without a gap.
    #[inline(always)]
    pub fn clip(&self, r: &ViewRay, t0: f32, t1: f32) -> Option<(f32, f32)> {
        self.clip_exit(r, t0, t1).map(|(lo, hi, _)| (lo, hi))
    }

    /// [`Self::clip`], and which bound ends the interval: [`Exit::End`] (`t1`), the near plane
    /// or a film edge.
    #[inline(always)]
    pub fn clip_exit(&self, r: &ViewRay, t0: f32, t1: f32) -> Option<(f32, f32, Exit)> {
        let (uw, vh) = (self.a_end, self.b_end);
        let (a0, b0) = (self.a0, self.b0);
        let halfspaces = [
            (r.z0 - self.near, r.dz, Exit::Near),
            (r.o.x - a0 * r.z0, r.d.x - a0 * r.dz, Exit::Left),
            (uw * r.z0 - r.o.x, uw * r.dz - r.d.x, Exit::Right),
            (b0 * r.z0 - r.o.y, b0 * r.dz - r.d.y, Exit::Top),
            (r.o.y - vh * r.z0, r.d.y - vh * r.dz, Exit::Bottom),
        ];
        let (mut lo, mut hi, mut exit) = (t0, t1, Exit::End);
        for (f0, f1, side) in halfspaces {
            if f1 > 0.0 {
                lo = lo.max(-f0 / f1);
            } else if f1 < 0.0 {
                let t = -f0 / f1;
                if t < hi {
                    hi = t;
                    exit = side;
                }
            } else if f0 < 0.0 || f0.is_nan() {
                return None;
            }
        }
        (lo < hi).then_some((lo, hi, exit))
    }
}

/// Which bound of a view's frustum ends a ray's interval in it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Exit {
    /// The end of the interval asked for.
    End,
    Near,
    /// Film x = 0, x = W, y = 0, y = H.
    Left,
    Right,
    Top,
    Bottom,
}

/// A world ray in one view (see the module docs).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ViewRay {
    pub o: Vec3,
    pub d: Vec3,
    pub z0: f32,
    pub dz: f32,
}

impl ViewRay {
    /// View depth at `t`.
    #[inline(always)]
    pub fn depth(&self, t: f32) -> f32 {
        self.z0 + t * self.dz
    }
}
