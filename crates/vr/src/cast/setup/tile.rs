//! The per-tile set-up of a tile's triangle list (HVVR, Hunt et al. 2018, §5.5: "triangle setup
//! ... tile-corner classification", module docs of [`super`]) `L::N` triangles at a time: the
//! tile's triangles, in list order and each once (a triangle in several leaves at its first
//! entry), are gathered from the BVH's leaf blocks ([`Tri4`]) as one row per value
//! (`cast/setup/rows.rs`) and loaded in packs of `L::N` consecutive ones
//! (across blocks and leaves: Sponza's leaf blocks hold ~2.2 triangles on average), set up
//! together in lanes ([`LazySetupN`], `cast/setup/lazy.rs`: 16
//! AVX-512 lanes where the CPU has them, else 8 AVX lanes where it has AVX2, else 4 SSE lanes;
//! `cast/isa.rs`), classified against the tile's
//! corners in the same registers, and the kept triangles appended to the tile's list in order
//! (one row per triangle from a transpose of the pack's registers, `LaneReduce::transpose8`),
//! each leaf's run closed after its last triangle ([`setup_tile`]). Runs' full bands are
//! computed four triangles at a time in SSE lanes (`cast/setup/bands.rs`).
//!
//! **Invariant: the same bits as the scalar set-up**, for every lane type. Every lane runs
//! exactly the operations of [`TriSetup::new_with`] (lazy band) and [`BeamCorners::classify`]
//! (and [`TriSetup::new`]'s band in `bands.rs`) in the same order: IEEE single-precision
//! `+ - * /` per lane, never contracted into FMAs (Rust does not contract), constants folded
//! the same way, negation and `|x|` as sign-bit operations or their equivalents on every
//! value a kept lane sees (`cast/setup/lazy.rs`), `max` only where no operand can be NaN. The
//! rejection tests are equivalent decisions (`D = 0` or not finite, `g` or the nine covector
//! entries not finite). So the list, its bands and its classification equal the scalar
//! twin's ([`setup_tile_scalar`]) bit for bit, and the run boxes ([`Segment`]) are equal
//! (taken per triangle before the run: a `0` and `-0` may swap, which no slab-test comparison
//! sees); the tests below compare both, for each lane type the CPU runs, on random and
//! adversarial triangles. The non-lazy set-up ([`crate::SetupExactness::Full`]) stays scalar.
//!
//! | name | value | meaning |
//! |---|---|---|
//! | `isa` | [`Isa::available`] | lanes of the lazy set-up: 16 AVX-512, 8 AVX, 4 SSE (`Isa::Sse`: the portable twin) |

use glam::{Vec3, Vec4};
use parallax_bvh::Tri4;
use parallax_bvh::node::{leaf_count, leaf_first};
use parallax_core::Aabb;
use parallax_core::math::watertight_permutation;

use super::lazy::{LazySetupN, PACK};
use super::rows::PAD;
use super::tri::{
    BeamCorners, Cone, CornerClass, RHO_MAX, RunBoxes16, Segment, TileTris, TriSetup,
};
use crate::beam::{Beam, LeafRef};
use crate::cast::isa::Isa;
use crate::cast::lanes16::LaneReduce;
#[cfg(target_arch = "x86_64")]
use crate::cast::lanes256::Y8;
#[cfg(target_arch = "x86_64")]
use crate::cast::lanes512::Z16;

/// Lane `l` of [`LazySetupN::arrays`] as a [`TriSetup`] (lazy: `rho` NaN): the tests' form.
#[cfg(test)]
fn lane_of(x: &[[f32; PACK]; 13], l: usize, tri: u32, src: u32, all_in: bool) -> TriSetup {
    TriSetup {
        n: [
            [x[0][l], x[1][l], x[2][l]],
            [x[3][l], x[4][l], x[5][l]],
            [x[6][l], x[7][l], x[8][l]],
        ],
        g: [x[9][l], x[10][l], x[11][l]],
        tri,
        src,
        bound: x[12][l],
        rho: f32::NAN,
        all_in,
    }
}

// A pack's loads stay inside the gathered rows.
const _: () = assert!(PAD >= PACK);

/// The set-up triangle whose fields in `TriSetup`'s order are `a` (`n[0]`, `n[1]`,
/// `n[2][0..2]`) and `b` (`n[2][2]`, `g`, `tri` and `src` as f32 bits, `bound`, `rho`): a
/// lane of the pack's rows after [`LaneReduce::transpose8`].
#[inline(always)]
fn from_rows(a: &[f32; 8], b: &[f32; 8], all_in: bool) -> TriSetup {
    TriSetup {
        n: [[a[0], a[1], a[2]], [a[3], a[4], a[5]], [a[6], a[7], b[0]]],
        g: [b[1], b[2], b[3]],
        tri: b[4].to_bits(),
        src: b[5].to_bits(),
        bound: b[6],
        rho: b[7],
        all_in,
    }
}

/// The state `setup_tile` starts from: the beam's corners, cone and watertight permutation.
fn begin(beam: &Beam, origin: Vec3, out: &mut TileTris) -> Option<BeamCorners> {
    out.origin = origin;
    out.frame = None;
    out.tris.clear();
    out.segs.clear();
    out.runs16.clear();
    out.rho_max = 0.0;
    let corners = BeamCorners::new(beam);
    let cone = Cone::of(corners.as_ref());
    out.cone = cone;
    out.perm = corners.and_then(|c| {
        // Float division is monotone and x / x = 1: slopes below 1 mean |d_b| < |d_a|.
        let (a, (b, cc)) = (beam.axis as usize, beam.side_axes());
        (c.cmax[b] < 1.0 && c.cmax[cc] < 1.0).then(|| {
            let mut d = Vec3::ZERO;
            d[a] = beam.sign;
            watertight_permutation(d)
        })
    });
    corners
}

/// Appends the run of leaf `r` (its kept triangles `tris[previous end..]`, box `bx`).
#[inline(always)]
fn end_run(out: &mut TileTris, r: &LeafRef, bx: Aabb) {
    let end = out.tris.len() as u32;
    if out.segs.last().map_or(0, |s| s.end) < end {
        let (lo, hi) = (bx.min - out.origin, bx.max - out.origin);
        let k = out.segs.len();
        out.segs.push(Segment {
            end,
            near: r.near,
            lo: lo.extend(0.0),
            hi: hi.extend(0.0),
        });
        if k.is_multiple_of(16) {
            out.runs16.push(RunBoxes16::default());
        }
        let rb = out.runs16.last_mut().expect("pushed above");
        for a in 0..3 {
            rb.lo[a][k % 16] = lo[a];
            rb.hi[a][k % 16] = hi[a];
        }
    }
}

/// Sets up every triangle of the tile list `leaves` (near-depth order) for rays from `origin`
/// within `beam`, dropping all-out triangles (module docs of [`super`]); the lazy set-up
/// `L::N` triangles at a time in the widest lanes the CPU has (`LazySetupN`,
/// `cast/setup/lazy.rs`), the full one scalar.
pub fn setup_tile(
    blocks: &[Tri4],
    copies: &[u8],
    leaves: &[LeafRef],
    beam: &Beam,
    origin: Vec3,
    lazy: bool,
    out: &mut TileTris,
) {
    setup_tile_with(
        Isa::Avx512.available(),
        blocks,
        copies,
        leaves,
        beam,
        origin,
        lazy,
        out,
    );
}

/// [`setup_tile`] in the lanes of the tier `isa` (one the CPU has, [`Isa::available`]): 16
/// AVX-512 lanes, 8 AVX lanes or 4 SSE lanes (the portable twin). Every tier gives the same
/// list.
#[allow(clippy::too_many_arguments)]
pub fn setup_tile_with(
    isa: Isa,
    blocks: &[Tri4],
    copies: &[u8],
    leaves: &[LeafRef],
    beam: &Beam,
    origin: Vec3,
    lazy: bool,
    out: &mut TileTris,
) {
    if !lazy {
        return setup_tile_scalar(blocks, copies, leaves, beam, origin, lazy, out);
    }
    debug_assert!(isa <= isa.available(), "{isa:?} not detected");
    #[cfg(target_arch = "x86_64")]
    match isa {
        // SAFETY: the caller's `isa` is available: the AVX-512 tier detected (`avx512_detected`).
        Isa::Avx512 => {
            return unsafe { setup_tile_avx512(blocks, copies, leaves, beam, origin, out) };
        }
        // SAFETY: the caller's `isa` is available: AVX2 (and the bit instructions) detected.
        Isa::Avx2 => return unsafe { setup_tile_avx2(blocks, copies, leaves, beam, origin, out) },
        Isa::Sse => {}
    }
    setup_tile_lanes::<Vec4>(blocks, copies, leaves, beam, origin, out)
}

/// [`setup_tile_lanes`] with eight AVX lanes.
///
/// # Safety
/// The CPU must support the AVX2 tier ([`crate::cast::isa::avx2_detected`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
unsafe fn setup_tile_avx2(
    blocks: &[Tri4],
    copies: &[u8],
    leaves: &[LeafRef],
    beam: &Beam,
    origin: Vec3,
    out: &mut TileTris,
) {
    setup_tile_lanes::<Y8>(blocks, copies, leaves, beam, origin, out)
}

/// [`setup_tile_lanes`] with sixteen AVX-512 lanes.
///
/// # Safety
/// The CPU must support the AVX-512 tier (`crate::cast::isa::avx512_detected`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512bw,avx512dq,avx2,bmi1,bmi2,lzcnt,popcnt")]
unsafe fn setup_tile_avx512(
    blocks: &[Tri4],
    copies: &[u8],
    leaves: &[LeafRef],
    beam: &Beam,
    origin: Vec3,
    out: &mut TileTris,
) {
    setup_tile_lanes::<Z16>(blocks, copies, leaves, beam, origin, out)
}

/// The lazy [`setup_tile`] in lanes `L`: packs of `L::N` consecutive triangles of the tile
/// list (across blocks and leaves) set up and classified together ([`LazySetupN`]), the kept
/// ones appended in list order, each leaf's run closed after its last triangle. (No closure
/// calls a lane operation: module docs of `cast/setup/lazy.rs`.)
#[inline(always)]
fn setup_tile_lanes<L: LaneReduce>(
    blocks: &[Tri4],
    copies: &[u8],
    leaves: &[LeafRef],
    beam: &Beam,
    origin: Vec3,
    out: &mut TileTris,
) {
    let corners = begin(beam, origin, out);
    let radius = out.cone.radius;
    // The tile's triangles in list order, as rows (`cast/setup/rows.rs`), and each leaf's end.
    let (mut rows, mut ends) = (std::mem::take(&mut out.rows), std::mem::take(&mut out.ends));
    rows.gather(blocks, copies, leaves, L::AVX2, &mut ends);
    out.counts.repeated += rows.repeated;
    let mut li = 0usize;
    let mut bx = Aabb::EMPTY;
    let mut mn = [[0.0f32; PACK]; 3];
    let mut mx = [[0.0f32; PACK]; 3];
    // The kept lanes' rows (`from_rows`).
    let (mut ta, mut tb) = ([[0.0f32; 8]; PACK], [[0.0f32; 8]; PACK]);
    for pi in 0..rows.len.div_ceil(L::N) {
        let base = L::N * pi;
        let len = (rows.len - base).min(L::N);
        let r = &rows.rows;
        let mut p = [[L::splat(0.0); 3]; 3];
        for v in 0..3 {
            for a in 0..3 {
                p[v][a] = L::load_n(&r[3 * v + a][base..]);
            }
        }
        let (tri_l, src_l) = (L::load_n(&r[9][base..]), L::load_n(&r[10][base..]));
        let s = LazySetupN::new(&p, origin, radius);
        let (outm, inm) = match &corners {
            Some(c) => s.classify(c),
            None => (0, 0),
        };
        let valid = (1u32 << len) - 1;
        let keep = valid & s.ok & !outm;
        out.counts.all_out += (valid & !keep).count_ones() as u64;
        out.counts.all_in += (keep & inm).count_ones() as u64;
        out.counts.partial += (keep & !inm).count_ones() as u64;
        if keep != 0 {
            let n = &s.n;
            L::transpose8(
                [
                    n[0][0], n[0][1], n[0][2], n[1][0], n[1][1], n[1][2], n[2][0], n[2][1],
                ],
                &mut ta,
            );
            L::transpose8(
                [
                    n[2][2],
                    s.g[0],
                    s.g[1],
                    s.g[2],
                    tri_l,
                    src_l,
                    s.bound,
                    L::splat(f32::NAN),
                ],
                &mut tb,
            );
            // Per lane the triangle's box (`Aabb::grow`'s `min` / `max` of its vertices).
            for a in 0..3 {
                p[0][a]
                    .min_or_rhs(p[1][a])
                    .min_or_rhs(p[2][a])
                    .write(&mut mn[a]);
                p[0][a]
                    .max_or_rhs(p[1][a])
                    .max_or_rhs(p[2][a])
                    .write(&mut mx[a]);
            }
        }
        for l in 0..len {
            let q = (L::N * pi + l) as u32;
            while ends[li] == q {
                end_run(out, &leaves[li], bx);
                bx = Aabb::EMPTY;
                li += 1;
            }
            if keep >> l & 1 != 0 {
                out.tris.push(from_rows(&ta[l], &tb[l], inm >> l & 1 != 0));
                bx.min = bx.min.min(Vec3::new(mn[0][l], mn[1][l], mn[2][l]));
                bx.max = bx.max.max(Vec3::new(mx[0][l], mx[1][l], mx[2][l]));
            }
        }
    }
    while li < leaves.len() {
        end_run(out, &leaves[li], bx);
        bx = Aabb::EMPTY;
        li += 1;
    }
    (out.rows, out.ends) = (rows, ends);
}

/// The scalar twin of [`setup_tile`]: one triangle at a time ([`TriSetup::new_with`],
/// [`BeamCorners::classify`]); the reference of the lane set-up's tests.
pub fn setup_tile_scalar(
    blocks: &[Tri4],
    copies: &[u8],
    leaves: &[LeafRef],
    beam: &Beam,
    origin: Vec3,
    lazy: bool,
    out: &mut TileTris,
) {
    let corners = begin(beam, origin, out);
    let cone = out.cone;
    // Each triangle once, at its first entry in list order (as the gather, `rows.rs`): only
    // the triangles in several leaves (`copies`) can repeat.
    let dedup = !copies.is_empty();
    if dedup {
        out.rows
            .seen
            .begin(leaves.iter().map(|r| leaf_count(r.leaf) as usize).sum());
    }
    for r in leaves {
        let mut bx = Aabb::EMPTY;
        let (first, count) = (leaf_first(r.leaf), leaf_count(r.leaf));
        for j in 0..count {
            let bi = first + j / 4;
            let b = &blocks[bi as usize];
            let ln = (j % 4) as usize;
            if b.tri[ln] == u32::MAX {
                continue;
            }
            if dedup && copies[bi as usize] >> ln & 1 != 0 && !out.rows.seen.insert(b.tri[ln]) {
                out.counts.repeated += 1;
                continue;
            }
            let v = [b.vertex(ln, 0), b.vertex(ln, 1), b.vertex(ln, 2)];
            let Some(mut s) =
                TriSetup::new_with(v, origin, b.tri[ln], 4 * bi + ln as u32, &cone, lazy)
            else {
                out.counts.all_out += 1;
                continue;
            };
            match corners.map_or(CornerClass::Partial, |c| c.classify(&s)) {
                CornerClass::AllOut => {
                    out.counts.all_out += 1;
                    continue;
                }
                CornerClass::AllIn => {
                    out.counts.all_in += 1;
                    s.all_in = true;
                }
                CornerClass::Partial => out.counts.partial += 1,
            }
            if s.rho <= RHO_MAX {
                out.rho_max = out.rho_max.max(s.rho);
            }
            out.tris.push(s);
            bx = bx.grow(v[0]).grow(v[1]).grow(v[2]);
        }
        end_run(out, r, bx);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cast::setup::bands::refine_run;
    use parallax_bvh::node::ChildRef;

    /// xorshift64*, deterministic.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
        }
        fn f(&mut self) -> f32 {
            (self.next() >> 40) as f32 / (1u64 << 24) as f32
        }
        fn v(&mut self, s: f32) -> Vec3 {
            Vec3::new(self.f() - 0.5, self.f() - 0.5, self.f() - 0.5) * s
        }
    }

    /// Random and adversarial triangles around `o`: every scale from 1e-30 to 1e30, degenerate
    /// and collinear ones, a vertex at the origin, planes through the origin, shared edges,
    /// non-finite vertices.
    fn triangles(rng: &mut Rng, o: Vec3) -> Vec<[Vec3; 3]> {
        let mut t = Vec::new();
        for _ in 0..4000 {
            let scale = 10f32.powi((rng.next() % 61) as i32 - 30);
            let c = o + rng.v(2.0 * scale);
            let sz = scale * 10f32.powi(-((rng.next() % 8) as i32));
            let v = [c + rng.v(sz), c + rng.v(sz), c + rng.v(sz)];
            t.push(v);
            match rng.next() % 10 {
                0 => t.push([v[0], v[1], v[0] + (v[1] - v[0]) * 0.5]),
                1 => t.push([o, v[1], v[2]]),
                2 => t.push([v[0], v[0], v[2]]),
                3 => t.push([o + (v[0] - o) * 2.0, v[0], v[1]]),
                4 => t.push([v[1], v[0], c + rng.v(sz)]),
                5 => t.push([v[0], Vec3::new(f32::INFINITY, 0.0, 1.0), v[2]]),
                6 => t.push([v[0], Vec3::new(f32::NAN, 0.0, 1.0), v[2]]),
                7 => t.push([v[0] * 1e30, v[1] * 1e30, v[2] * -1e30]),
                8 => t.push([v[0], v[1] + Vec3::splat(f32::MIN_POSITIVE), v[1]]),
                _ => t.push([v[0].to_array().map(|x| x * 1e-38).into(), v[1], v[2]]),
            }
        }
        t
    }

    fn blocks_of(tris: &[[Vec3; 3]]) -> Vec<Tri4> {
        tris.chunks(4)
            .enumerate()
            .map(|(k, ch)| {
                let mut b = Tri4::EMPTY;
                for (l, t) in ch.iter().enumerate() {
                    for (v, p) in t.iter().enumerate() {
                        for a in 0..3 {
                            b.p[v][a][l] = p[a];
                        }
                    }
                    // Some padding lanes inside a block.
                    b.tri[l] = if (k + l) % 13 == 5 {
                        u32::MAX
                    } else {
                        (4 * k + l) as u32
                    };
                }
                b
            })
            .collect()
    }

    fn beam(rng: &mut Rng, o: Vec3) -> Beam {
        let (u0, v0) = (rng.f() * 1.6 - 0.8, rng.f() * 1.6 - 0.8);
        let (du, dv) = (rng.f() * 0.3, rng.f() * 0.3);
        Beam {
            axis: (rng.next() % 3) as u8,
            sign: if rng.next().is_multiple_of(2) {
                1.0
            } else {
                -1.0
            },
            u: [u0, u0 + du],
            v: [v0, v0 + dv],
            origin: Aabb::EMPTY.grow(o),
            everything: false,
        }
    }

    #[test]
    fn lane_setup_equals_scalar_bit_for_bit() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let (mut kept, mut lanes) = (0, 0);
        for round in 0..6 {
            let o = if round == 0 { Vec3::ZERO } else { rng.v(100.0) };
            let tris = triangles(&mut rng, o);
            let blocks = blocks_of(&tris);
            let bm = beam(&mut rng, o);
            let corners = BeamCorners::new(&bm).unwrap();
            let cone = if round == 1 {
                Cone::ANY
            } else {
                Cone::of(Some(&corners))
            };
            for (bi, b) in blocks.iter().enumerate() {
                let s4 = LazySetupN::<Vec4>::new(&b.p, o, cone.radius);
                let (outm, inm) = s4.classify(&corners);
                let mut x = [[0.0f32; PACK]; 13];
                s4.arrays(&mut x);
                for l in 0..4 {
                    lanes += 1;
                    let v = [b.vertex(l, 0), b.vertex(l, 1), b.vertex(l, 2)];
                    let src = 4 * bi as u32 + l as u32;
                    let s = TriSetup::new_with(v, o, 7, src, &cone, true);
                    assert_eq!(s.is_some(), s4.ok >> l & 1 != 0, "{v:?} {o:?}");
                    let Some(mut s) = s else { continue };
                    kept += 1;
                    let class = corners.classify(&s);
                    assert_eq!(class == CornerClass::AllOut, outm >> l & 1 != 0, "{v:?}");
                    assert_eq!(class == CornerClass::AllIn, inm >> l & 1 != 0, "{v:?}");
                    s.all_in = class == CornerClass::AllIn;
                    let t = lane_of(&x, l, 7, src, s.all_in);
                    assert_eq!(s.bits(), t.bits(), "{v:?} {o:?}");
                }
            }
        }
        assert!(kept > lanes / 10, "{kept} of {lanes}");
    }

    #[test]
    fn setup_tile_equals_scalar_twin() {
        let mut rng = Rng(0x1234_5678_9abc_def1);
        for _ in 0..20 {
            let o = rng.v(10.0);
            let tris = triangles(&mut rng, o);
            let blocks = blocks_of(&tris[..tris.len() / 4 * 4]);
            // Leaves of 1 to 16 triangles (whole blocks, the last one partly filled).
            let mut leaves = Vec::new();
            let mut first = 0u32;
            while (first as usize) < blocks.len() {
                let nb = (1 + rng.next() % 4).min((blocks.len() - first as usize) as u64) as u32;
                let count = (4 * nb - (rng.next() % 4) as u32).min(15);
                let leaf = ChildRef::Leaf { first, count }.encode();
                leaves.push(LeafRef {
                    leaf,
                    near: first as f32,
                });
                first += nb;
            }
            let bm = if rng.next().is_multiple_of(5) {
                Beam::EVERYTHING
            } else {
                beam(&mut rng, o)
            };
            let mut b = TileTris::default();
            setup_tile_scalar(&blocks, &[], &leaves, &bm, o, true, &mut b);
            // Every lane marked as a triangle in several leaves: the look-ups find no repeat
            // (every id once here) and change nothing.
            let all = vec![15u8; blocks.len()];
            // Every tier this CPU has (the AVX ones only where detected).
            for isa in [Isa::Sse, Isa::Avx2, Isa::Avx512] {
                if isa.available() != isa {
                    eprintln!("{isa:?} not detected: its set-up lanes are not tested here");
                    continue;
                }
                for copies in [&[][..], &all[..]] {
                    let mut a = TileTris::default();
                    setup_tile_with(isa, &blocks, copies, &leaves, &bm, o, true, &mut a);
                    same_lists(&a, &b);
                }
            }
        }
    }

    /// `a` and `b` hold the same list: bit for bit, run boxes equal as values.
    fn same_lists(a: &TileTris, b: &TileTris) {
        {
            assert_eq!(a.tris.len(), b.tris.len());
            for (x, y) in a.tris.iter().zip(&b.tris) {
                assert_eq!(x.bits(), y.bits());
            }
            assert_eq!(a.segs.len(), b.segs.len());
            for (x, y) in a.segs.iter().zip(&b.segs) {
                assert_eq!(x.end, y.end);
                assert_eq!(x.near.to_bits(), y.near.to_bits());
                // Equal values (the sign of a zero may differ: no comparison sees it).
                assert_eq!((x.lo, x.hi), (y.lo, y.hi));
            }
            let c = |t: &TileTris| (t.counts.all_out, t.counts.partial, t.counts.all_in);
            assert_eq!(c(a), c(b));
            assert_eq!(a.runs16.len(), a.segs.len().div_ceil(16));
            for (k, x) in a.segs.iter().enumerate() {
                let rb16 = &a.runs16[k / 16];
                for ax in 0..3 {
                    assert_eq!(rb16.lo[ax][k % 16].to_bits(), x.lo[ax].to_bits());
                    assert_eq!(rb16.hi[ax][k % 16].to_bits(), x.hi[ax].to_bits());
                }
            }
            assert_eq!((a.perm, a.rho_max.to_bits()), (b.perm, b.rho_max.to_bits()));
        }
    }

    #[test]
    fn run_refine_equals_scalar_refine() {
        let mut rng = Rng(0x5151_7e57_c0ff_ee01);
        let mut refined = 0;
        for _ in 0..20 {
            let o = rng.v(10.0);
            let tris = triangles(&mut rng, o);
            let blocks = blocks_of(&tris[..tris.len() / 4 * 4]);
            let leaves: Vec<LeafRef> = (0..blocks.len() as u32)
                .map(|first| LeafRef {
                    leaf: ChildRef::Leaf { first, count: 4 }.encode(),
                    near: first as f32,
                })
                .collect();
            let bm = beam(&mut rng, o);
            let mut a = TileTris::default();
            setup_tile(&blocks, &[], &leaves, &bm, o, true, &mut a);
            let mut b = a.clone();
            let mut first = 0;
            for seg in a.segs.clone() {
                refine_run(&mut a, first, seg.end as usize, &blocks);
                first = seg.end as usize;
            }
            for j in 0..b.tris.len() {
                b.refine(j, &blocks);
            }
            for (x, y) in a.tris.iter().zip(&b.tris) {
                assert_eq!(x.bits(), y.bits(), "{x:?} {y:?}");
                refined += 1;
            }
        }
        assert!(refined > 1000, "{refined}");
    }
}
