//! Rasterizing one tile: edge functions stepped over the pixel centres (Pineda 1988, "A
//! parallel algorithm for polygon rasterization"), exact in i64 on the snapped vertices with the
//! top-left rule, and the two ways of keeping `N` depth layers per pixel:
//!
//! - **k-buffer** (Bavoil et al. 2007, "Multi-fragment effects on the GPU using the k-buffer"):
//!   one pass, each fragment insertion-sorted into the pixel's `N` nearest, keyed by
//!   `(depth, primitive id)` so the result does not depend on fragment order;
//! - **depth peeling** (Everitt 2001, "Interactive order-independent transparency"): `N` passes,
//!   pass `k` keeping the nearest fragment behind layer `k - 1`; with a minimum separation `Δ`
//!   "behind" means at least `Δ` farther (the deep G-buffer's layer rule, Mara, McGuire,
//!   Nowrouzezahrai & Luebke 2016 / 2013 tech report "Fast global illumination approximations on
//!   deep G-buffers", §3). With `Δ = 0` both give the same layers (tested).

use super::setup::{ONE, RasterTri, edge};

/// One fragment: a surface seen through a pixel centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fragment {
    /// View depth (`+inf` = empty).
    pub depth: f32,
    /// Primitive (mesh triangle) id, `NO_ID` = empty.
    pub prim: u32,
    /// Perspective-correct barycentrics of mesh vertices 1 and 2.
    pub b1: f32,
    pub b2: f32,
}

impl Fragment {
    pub const EMPTY: Self = Self {
        depth: f32::INFINITY,
        prim: parallax_core::NO_ID,
        b1: 0.0,
        b2: 0.0,
    };

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.prim == parallax_core::NO_ID
    }

    /// The total order of fragments: nearer first, ties by primitive id.
    #[inline]
    pub fn before(&self, o: &Fragment) -> bool {
        self.depth < o.depth || (self.depth == o.depth && self.prim < o.prim)
    }
}

/// A tile's pixel rectangle `[x0, x1) x [y0, y1)`.
#[derive(Clone, Copy, Debug)]
pub struct Rect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

/// Calls `f(local_x, local_y, fragment)` for every pixel centre of `rect` covered by each of
/// `items` (in order). Depths outside `(0, far]` are dropped (snapping can move a clipped
/// polygon's edge a fraction of a pixel past the near plane).
#[inline]
pub fn for_each_fragment(
    tris: &[RasterTri],
    items: &[u32],
    rect: Rect,
    far: f64,
    mut f: impl FnMut(u32, u32, Fragment),
) {
    for &i in items {
        let t = &tris[i as usize];
        let (x0, y0) = (t.x0.max(rect.x0), t.y0.max(rect.y0));
        let (x1, y1) = (t.x1.min(rect.x1 - 1), t.y1.min(rect.y1 - 1));
        if x0 > x1 || y0 > y1 {
            continue;
        }
        let e = [
            edge(t.v[1], t.v[2]),
            edge(t.v[2], t.v[0]),
            edge(t.v[0], t.v[1]),
        ];
        let px0 = x0 as i64 * ONE + ONE / 2;
        for y in y0..=y1 {
            let py = y as i64 * ONE + ONE / 2;
            // E - bias >= 0 <=> covered (top-left rule folded into the bias).
            let mut w = e.map(|(a, b, c, bias)| a * px0 + b * py + c - bias);
            let step = e.map(|(a, _, _, _)| a * ONE);
            for x in x0..=x1 {
                if (w[0] | w[1] | w[2]) >= 0
                    && let Some((b, d)) = t.interpolate(x as f64 + 0.5, y as f64 + 0.5)
                    && d > 0.0
                    && d <= far
                {
                    let frag = Fragment {
                        depth: d as f32,
                        prim: t.prim,
                        b1: b[1] as f32,
                        b2: b[2] as f32,
                    };
                    f(x - rect.x0, y - rect.y0, frag);
                }
                w[0] += step[0];
                w[1] += step[1];
                w[2] += step[2];
            }
        }
    }
}

/// Inserts `f` into the sorted `slots` (k-buffer), dropping the farthest when full.
#[inline]
pub fn kbuffer_insert(slots: &mut [Fragment], f: Fragment) {
    let n = slots.len();
    if !f.before(&slots[n - 1]) {
        return;
    }
    let mut i = n - 1;
    while i > 0 && f.before(&slots[i - 1]) {
        slots[i] = slots[i - 1];
        i -= 1;
    }
    slots[i] = f;
}

/// Fills `slots` (`layers` per pixel, pixel-major over the tile rows of width `pitch`) by
/// depth peeling with minimum separation `delta` (see the module docs).
#[allow(clippy::too_many_arguments)]
pub fn peel(
    tris: &[RasterTri],
    items: &[u32],
    rect: Rect,
    far: f64,
    pitch: usize,
    layers: usize,
    delta: f32,
    slots: &mut [Fragment],
) {
    for k in 0..layers {
        let mut any = false;
        for_each_fragment(tris, items, rect, far, |x, y, f| {
            let base = (y as usize * pitch + x as usize) * layers;
            if k > 0 {
                let prev = slots[base + k - 1];
                let behind = if delta > 0.0 {
                    f.depth >= prev.depth + delta
                } else {
                    prev.before(&f)
                };
                if prev.is_empty() || !behind {
                    return;
                }
            }
            if f.before(&slots[base + k]) {
                slots[base + k] = f;
                any = true;
            }
        });
        if !any {
            break;
        }
    }
}
