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
use super::view::ViewConsts;

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
/// the ray starts in the near column (likewise rows); the far side's exit is `p`'s.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn scan_children<const UX: bool, const UY: bool>(
    vc: &ViewConsts,
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
    if (UX && near_x && kmx >= vc.cells_x) || (UY && near_y && kmy >= vc.cells_y) {
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
                    cy = refine::<UY>(cy, cy >> m, m as u32, y, vc.cells_y);
                }
                Some((false, at)) if m > 0 => {
                    let x = seg.x + at * seg.dx;
                    cx = refine::<UX>(cx, cx >> m, m as u32, x, vc.cells_x);
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
