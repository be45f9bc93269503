//! The Hi-Z walk's descent by child scans (Vardis et al. 2017, §4.2.1 and Algorithm 1 lines
//! 1-6, the hierarchical traversal of the min-max mips): when a texel at level `L >= 1`
//! overlaps the ray, its children (at most three of its 2x2) that the ray passes through are
//! tested in ray order, each over its own `λ` interval, without going back up to the texel
//! between them; the walk (`walk`) goes on at the first that overlaps, or, when none does,
//! leaves the texel as after a skip (staying at level `L`).
//!
//! **Why it is the walk's own step.** Each child is tested over exactly the interval the walk
//! at level `L - 1` would test it over: its exit crossings are those of the walk (the middle
//! boundary's `k inv + c` on an axis where the ray starts in the near child, the texel's own
//! exit crossing on the other; `λ_exit = max(min(λ_col, λ_row, 1), λ)`), its `w` range the
//! walk's `w_at` at both ends, its bounds and slab test the walk's. The moves between
//! children are the walk's moves at level `L - 1` (`next_cell` across a middle boundary, which
//! lies on the grid: a scan whose far child would be off the grid returns [`Scan::Edge`] and
//! the walk takes the plain one-level step; a tie of the two crossings moves diagonally; the
//! other axis is `refine`d at the move's `λ`). The `refine` is deferred to the child the scan
//! returns: it keeps the cell inside the child's texel, so the texels tested in between do not
//! depend on it. So the walk traces the same kind of sequence of cells over intervals that
//! share their computed end points, and `walk`'s exactness argument holds unchanged; only the
//! parent texel's re-tests between its children (the classic Hi-Z "up one level after a
//! skip, down again") are gone. The hits are the same; the cells traced can differ from the
//! plain walk's by cells touched within rounding of a corner (the moves out of a skipped
//! texel `refine` at its level).
//!
//! | parameter | value | meaning |
//! |---|---|---|
//! | children per scan | at most 3 | of the 2x2: the ray's film path is monotone in x and y |
//! | levels | `L >= 1` | a level-1 scan tests level-0 cells (bounds and slabs; the records follow) |

use super::segment::{Axis, Segment, fmax, fmin, refine};

/// A texel known to overlap the ray, whose children a scan tests.
pub(super) struct Parent {
    pub(super) tx: u32,
    pub(super) ty: u32,
    pub(super) level: usize,
    /// Its exit column and row boundaries (in cells) and `λ` of their crossings.
    pub(super) kx: u32,
    pub(super) ky: u32,
    pub(super) l_col: f32,
    pub(super) l_row: f32,
}

/// The first child of a scan that overlaps, with the walk's state at its entry.
pub(super) struct Child {
    pub(super) cx: u32,
    pub(super) cy: u32,
    pub(super) l: f32,
    pub(super) w: f32,
    pub(super) l_col: f32,
    pub(super) l_row: f32,
    pub(super) l_exit: f32,
    pub(super) w_exit: f32,
    /// Its exit column and row boundaries (in cells).
    pub(super) kx: u32,
    pub(super) ky: u32,
}

pub(super) enum Scan {
    Child(Child),
    /// No child along the ray overlaps: the texel is skipped as a whole.
    None,
    /// A child the ray may cross into lies off the grid: the plain one-level step instead.
    Edge,
}

/// The children of texel `p` (level `L >= 1`, overlapping the ray over `[l, λ_exit]`) the ray
/// passes through, in ray order, each tested over its own `λ` interval as the walk at level
/// `L - 1` would (the same crossings, exits and `w`, the same moves between them: `next_cell`
/// across a middle boundary, `refine` on the other axis), without going back up to `p`
/// between them. The first that overlaps is returned with the walk's state at its entry; the
/// walk goes on there at level `L - 1`. The middle column's crossing is computed only when
/// the ray starts in the near column (likewise rows); the far side's exit is `p`'s. `cells`:
/// the grid's size.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn scan_children<const UX: bool, const UY: bool>(
    cells: (u32, u32),
    seg: &Segment,
    xs: &Axis,
    ys: &Axis,
    p: &Parent,
    mut cx: u32,
    mut cy: u32,
    l: f32,
    w_l: f32,
    test: &impl Fn(u32, u32, usize, f32, f32) -> bool,
) -> (Scan, u64) {
    let m = p.level - 1;
    // The middle boundaries of `p` (in cells), and whether the ray starts before them.
    let (kmx, kmy) = (((p.tx << 1) + 1) << m, ((p.ty << 1) + 1) << m);
    let mut near_x = ((cx >> m) & 1) == (!UX) as u32;
    let mut near_y = ((cy >> m) & 1) == (!UY) as u32;
    // Towards higher indices the far child must be on the grid (towards lower ones the near
    // child is the odd one, so the far one exists).
    if (UX && near_x && kmx >= cells.0) || (UY && near_y && kmy >= cells.1) {
        return (Scan::Edge, 0);
    }
    let mut lc = if near_x { xs.cross(kmx) } else { p.l_col };
    let mut lr = if near_y { ys.cross(kmy) } else { p.l_row };
    let (mut lam, mut w) = (l, w_l);
    let mut tested = 0;
    // The `refine` of the axis the last move did not cross, at that move's `λ` (`None`: no
    // move, or a diagonal one). Deferred to the child the scan returns: it keeps the cell
    // inside its child texel, so the texels tested before do not depend on it.
    let mut pending: Option<(bool, f32)> = None;
    // At most three children: each move crosses a middle boundary not crossed before.
    for _ in 0..3 {
        let l_exit = fmax(fmin(fmin(lc, lr), 1.0), lam);
        let w_exit = seg.w_at(l_exit);
        tested += 1;
        if test(cx, cy, m, w, w_exit) {
            match pending {
                Some((true, at)) if m > 0 => {
                    let y = seg.y + at * seg.dy;
                    cy = refine::<UY>(cy, cy >> m, m as u32, y, cells.1);
                }
                Some((false, at)) if m > 0 => {
                    let x = seg.x + at * seg.dx;
                    cx = refine::<UX>(cx, cx >> m, m as u32, x, cells.0);
                }
                _ => {}
            }
            return (
                Scan::Child(Child {
                    cx,
                    cy,
                    l: lam,
                    w,
                    l_col: lc,
                    l_row: lr,
                    l_exit,
                    w_exit,
                    kx: if near_x { kmx } else { p.kx },
                    ky: if near_y { kmy } else { p.ky },
                }),
                tested,
            );
        }
        if l_exit >= 1.0 {
            break;
        }
        // The move of the walk at level `m` (as in `walk_body`); leaving `p` ends the scan.
        if lc <= lr {
            if !near_x || (lc == lr && !near_y) {
                break;
            }
            cx = if UX { kmx } else { kmx - 1 };
            near_x = false;
            if lc == lr {
                cy = if UY { kmy } else { kmy - 1 };
                near_y = false;
                lr = p.l_row;
                pending = None;
            } else {
                pending = Some((true, l_exit));
            }
            lc = p.l_col;
        } else {
            if !near_y {
                break;
            }
            cy = if UY { kmy } else { kmy - 1 };
            near_y = false;
            pending = Some((false, l_exit));
            lr = p.l_row;
        }
        lam = l_exit;
        w = w_exit;
    }
    (Scan::None, tested)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dirt::segment::next_cell;

    /// The plain walk at level `m` from `(cx, cy)` over the children of the level-`m + 1`
    /// texel it starts in: each child's crossings recomputed, each move's `refine` done at once,
    /// the first child `test` accepts returned (the walk's steps before child scans).
    #[allow(clippy::too_many_arguments)]
    fn plain<const UX: bool, const UY: bool>(
        seg: &Segment,
        mut xs: Axis,
        mut ys: Axis,
        cells: (u32, u32),
        m: usize,
        (mut cx, mut cy): (u32, u32),
        (mut l, mut w): (f32, f32),
        test: &impl Fn(u32, u32, usize, f32, f32) -> bool,
    ) -> Option<[u32; 4]> {
        let parent = (cx >> (m + 1), cy >> (m + 1));
        loop {
            let (tx, ty) = (cx >> m, cy >> m);
            let (kx, ky) = ((tx + UX as u32) << m, (ty + UY as u32) << m);
            let (lc, lr) = (xs.cross(kx), ys.cross(ky));
            let l_exit = fmax(fmin(fmin(lc, lr), 1.0), l);
            let w_exit = seg.w_at(l_exit);
            if test(cx, cy, m, w, w_exit) {
                return Some([cx, cy, l.to_bits(), l_exit.to_bits()]);
            }
            if l_exit >= 1.0 {
                return None;
            }
            if lc <= lr {
                cx = next_cell::<UX>(cx, kx, &mut xs, cells.0);
                if lr == lc {
                    cy = next_cell::<UY>(cy, ky, &mut ys, cells.1);
                } else if m > 0 {
                    let y = seg.y + l_exit * seg.dy;
                    cy = refine::<UY>(cy, ty, m as u32, y, cells.1);
                }
            } else {
                cy = next_cell::<UY>(cy, ky, &mut ys, cells.1);
                if m > 0 {
                    let x = seg.x + l_exit * seg.dx;
                    cx = refine::<UX>(cx, tx, m as u32, x, cells.0);
                }
            }
            if (cx >> (m + 1), cy >> (m + 1)) != parent {
                return None;
            }
            (l, w) = (l_exit, w_exit);
        }
    }

    /// A scan returns the child the plain walk at the level below finds first, with the same
    /// cell, entry and exit `λ` (bits), on random segments, levels and overlap patterns
    /// (every direction; ties of the two crossings included by segments through corners).
    fn scan_is_the_plain_walk<const UX: bool, const UY: bool>(seed: u64) -> (u32, u32) {
        let mut state = seed;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as u32
        };
        let cells = (37u32, 29u32);
        let (mut compared, mut found) = (0, 0);
        for case in 0..20_000 {
            let m = (next() % 4) as usize;
            // A start inside the grid, a film direction of the given signs (whole cells for a
            // quarter of the cases: crossings that tie).
            let snap = case % 4 == 0;
            let f = |v: u32, n: u32| {
                if snap {
                    (v % n) as f32
                } else {
                    (v % (n * 1024)) as f32 / 1024.0
                }
            };
            let (x, y) = (f(next(), cells.0), f(next(), cells.1));
            let span = |up: bool, v: u32| {
                let d = if snap {
                    (v % 16) as f32
                } else {
                    (v % 16384) as f32 / 1024.0
                };
                if up { d } else { -d }
            };
            let (dx, dy) = (span(UX, next()), span(UY, next()));
            let (x1, y1) = (x + dx, y + dy);
            // Inside the grid to the end (the walk's interval is clipped to the view).
            if x1 <= 0.0 || y1 <= 0.0 || x1 >= cells.0 as f32 || y1 >= cells.1 as f32 {
                continue;
            }
            let seg = Segment::from_parts(x, y, dx, dy, 0.5, -0.25);
            let ((xs, _), (ys, _)) = (Axis::new(x, x1), Axis::new(y, y1));
            let (cx, cy) = ((x as u32).min(cells.0 - 1), (y as u32).min(cells.1 - 1));
            let salt = next();
            let test = |cx: u32, cy: u32, m: usize, _: f32, _: f32| {
                ((cx >> m).wrapping_mul(73) ^ (cy >> m).wrapping_mul(151) ^ salt) % 3 == 0
            };
            let (tx, ty) = (cx >> (m + 1), cy >> (m + 1));
            let (kx, ky) = ((tx + UX as u32) << (m + 1), (ty + UY as u32) << (m + 1));
            let p = Parent {
                tx,
                ty,
                level: m + 1,
                kx,
                ky,
                l_col: xs.cross(kx),
                l_row: ys.cross(ky),
            };
            let want = plain::<UX, UY>(&seg, xs, ys, cells, m, (cx, cy), (0.0, 0.5), &test);
            let got =
                match scan_children::<UX, UY>(cells, &seg, &xs, &ys, &p, cx, cy, 0.0, 0.5, &test).0
                {
                    Scan::Edge => continue,
                    Scan::None => None,
                    Scan::Child(c) => {
                        assert_eq!(
                            (c.kx, c.ky),
                            (
                                ((c.cx >> m) + UX as u32) << m,
                                ((c.cy >> m) + UY as u32) << m
                            )
                        );
                        assert_eq!(
                            (c.l_col.to_bits(), c.l_row.to_bits()),
                            (xs.cross(c.kx).to_bits(), ys.cross(c.ky).to_bits())
                        );
                        assert_eq!(c.w_exit.to_bits(), seg.w_at(c.l_exit).to_bits());
                        Some([c.cx, c.cy, c.l.to_bits(), c.l_exit.to_bits()])
                    }
                };
            assert_eq!(
                got, want,
                "case {case}: m {m}, start ({x}, {y}), span ({dx}, {dy})"
            );
            compared += 1;
            found += got.is_some() as u32;
        }
        (compared, found)
    }

    #[test]
    fn scans_equal_the_plain_walk() {
        for (k, (compared, found)) in [
            scan_is_the_plain_walk::<false, false>(1),
            scan_is_the_plain_walk::<false, true>(2),
            scan_is_the_plain_walk::<true, false>(3),
            scan_is_the_plain_walk::<true, true>(4),
        ]
        .into_iter()
        .enumerate()
        {
            // Enough cases of both outcomes in every direction.
            assert!(
                compared > 5_000 && found > 1_000 && compared - found > 1_000,
                "direction {k}: {compared} compared, {found} found"
            );
        }
    }
}
