//! Large packets for coherent primary rays: up to [`PACKET64_SIZE`] = 64 rays (an 8x8 pixel
//! tile, as four 16-ray groups of 4x4 pixels) walk the 8-wide tree together with one stack, in
//! the manner of the large-packet tracers of Reshetov, Soupikov & Hurley 2005 (MLRTA) and
//! Wald, Boulos & Shirley 2007 ("Ray tracing deformable scenes using dynamic bounding volume
//! hierarchies": 8x8 packets over a BVH with whole-packet culling, SIMD over the rays still
//! active), on the node and leaf kernels of the 16-ray packets (`packet8.rs`, `lanes16.rs`).
//!
//! - **Two-level interval culling**: at each node one 8-lane test of the whole packet's
//!   interval bounds (`packet_interval.rs`, the union of the four groups' ranges) rejects the
//!   children no ray can enter; each surviving child is then tested against the interval
//!   bounds of each active group (one 8-lane test per group and node), and a child is entered
//!   with the rays of the groups that pass. The node's load, the child ordering (near bound of
//!   the whole packet) and the stack are paid once per 64 rays instead of once per 16.
//! - **Per group at the leaves and pops**: each active group runs the 16-lane SIMD triangle
//!   test (or its rays' 4-triangle test when few are active), and a popped entry keeps the rays
//!   of each group whose closest hit is not nearer than that group's entry bound.
//! - **Hybrid**: a subtree entered by at most `SINGLE_RAYS_BELOW` rays is finished ray by ray.
//! - **Fallback**: when the groups do not share the direction signs, or some group has no
//!   interval bounds (a zero direction component, mixed signs inside it), each group is traced
//!   as its own 16-ray packet ([`Bvh::closest_hit_packet`]); slices of at most 16 rays too.
//!
//! | parameter | value | meaning |
//! |---|---|---|
//! | [`PACKET64_SIZE`] | 64 | rays per packet (longer slices are split) |
//! | `GROUPS` | 4 | 16-ray groups per packet (ray `i` is lane `i % 16` of group `i / 16`) |
//! | `GROUP_TESTS` | true | test each group's interval against the surviving children |
//!
//! **Invariant:** every ray's answer equals [`Bvh::closest_hit`] exactly (prim, t, u, v): both
//! interval tests only cull children that the ray's own slab test culls (their ranges contain
//! the ray's origin, `1 / dir`, `t_min` and current `t_max`), the pops only drop rays with a
//! closer hit, and each ray keeps the lexicographic minimum of `(t, primitive id)` over the
//! hits it finds. `tests/packets.rs` checks it for every lane type the CPU supports (AVX-512,
//! AVX2) and the portable twin.

use std::mem::MaybeUninit;

use parallax_core::Ray;

use crate::bvh::Bvh;
use crate::hit::Hit;
use crate::lanes16::Lanes16;
use crate::node::{is_leaf, leaf_count, leaf_first};
use crate::node8::Node8;
use crate::packet_interval::Interval;
use crate::packet8::{PACKET_SIZE, Packet, SINGLE_RAYS_BELOW, sorted_keys};
use crate::traverse8::STACK8_SIZE;

/// Rays per large packet ([`Bvh::closest_hit_packet64`] splits longer slices).
pub const PACKET64_SIZE: usize = 64;
/// 16-ray groups per packet.
const GROUPS: usize = PACKET64_SIZE / PACKET_SIZE;
/// Test each active group's interval bounds against the children that pass the packet's.
const GROUP_TESTS: bool = true;

#[derive(Clone, Copy)]
struct Entry64 {
    child: u32,
    /// Bit `i` = ray `i` of the packet.
    mask: u64,
    /// Per group, a lower bound of its rays' entry distances.
    t: [f32; GROUPS],
}

/// Group `g`'s rays (empty past the end of the slice).
#[inline(always)]
fn group(rays: &[Ray], g: usize) -> &[Ray] {
    let n = rays.len();
    &rays[(PACKET_SIZE * g).min(n)..(PACKET_SIZE * (g + 1)).min(n)]
}

/// Group `g`'s bits of a packet mask.
#[inline(always)]
fn gbits(m: u64, g: usize) -> u32 {
    (m >> (PACKET_SIZE * g)) as u32 & 0xFFFF
}

/// The interval test with 256-bit registers where the lanes prove AVX2.
#[inline(always)]
fn test<L: Lanes16>(iv: &Interval, node: &Node8) -> (u32, [f32; 8]) {
    #[cfg(target_arch = "x86_64")]
    if L::AVX2 {
        // SAFETY: `L::AVX2` holds only for lanes made after detecting AVX2.
        return unsafe { iv.test_avx2(node) };
    }
    iv.test(node)
}

impl Bvh {
    /// Each group as its own 16-ray packet.
    #[inline(always)]
    fn packet64_by_groups<L: Lanes16>(&self, l: L, rays: &[Ray], out: &mut [Option<Hit>]) {
        for g in 0..GROUPS {
            let r = group(rays, g);
            if !r.is_empty() {
                let o0 = PACKET_SIZE * g;
                self.packet8(l, r, &mut out[o0..o0 + r.len()]);
            }
        }
    }

    /// The 64-ray traversal of up to [`PACKET64_SIZE`] rays on lanes `l` (module docs; the
    /// entry points and the choice of lanes are in `packet_lanes.rs`).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // the loop index addresses several arrays in step
    pub(crate) fn packet64<L: Lanes16>(&self, l: L, rays: &[Ray], out: &mut [Option<Hit>]) {
        if rays.len() <= PACKET_SIZE || self.nodes8.is_empty() {
            return self.packet64_by_groups(l, rays, out);
        }
        for o in out.iter_mut().take(rays.len()) {
            *o = None;
        }
        // One loop, not four inlined set-ups (code size), and no closures over the lanes
        // (they would not inherit the target features).
        // Built in place: moving the four packets (~5.6 kB) cost two copies per packet.
        let mut slots = [const { MaybeUninit::<Packet>::uninit() }; GROUPS];
        for (g, p) in slots.iter_mut().enumerate() {
            Packet::init(p, l, group(rays, g));
        }
        // SAFETY: every element was written by the loop above, and `MaybeUninit<Packet>` has
        // the layout of `Packet`.
        let ps = unsafe { &mut *(slots.as_mut_ptr() as *mut [Packet; GROUPS]) };
        let mut valid = 0u64;
        for (g, p) in ps.iter().enumerate() {
            valid |= (p.valid as u64) << (PACKET_SIZE * g);
        }
        if valid == 0 {
            return;
        }
        // The whole packet's interval: the union of the groups' ranges, if they share signs.
        let (mut lo, mut hi) = ([f32::INFINITY; 6], [f32::NEG_INFINITY; 6]);
        let (mut t_lo, mut t_hi) = (f32::INFINITY, f32::NEG_INFINITY);
        let mut signs = None;
        let mut coherent = true;
        let mut first = 0;
        for g in (0..GROUPS).rev() {
            let p = &ps[g];
            if p.valid == 0 {
                continue;
            }
            first = g;
            let s = p.sign_code();
            coherent &= p.interval.is_some() && *signs.get_or_insert(s) == s;
            for a in 0..6 {
                lo[a] = lo[a].min(p.lo[a]);
                hi[a] = hi[a].max(p.hi[a]);
            }
            t_lo = t_lo.min(p.t_range.0);
            t_hi = t_hi.max(p.t_range.1);
        }
        if !coherent {
            return self.packet64_by_groups(l, rays, out);
        }
        let mut big = ps[first].interval(lo, hi, t_lo, t_hi);
        let mut stack = [MaybeUninit::<Entry64>::uninit(); STACK8_SIZE];
        let mut sp = 0usize;
        let mut cur = 0u32;
        let mut mask = valid;
        loop {
            if mask.count_ones() <= SINGLE_RAYS_BELOW {
                let mut m = mask;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let g = i / PACKET_SIZE;
                    ps[g].single_ray(self, l, group(rays, g), i % PACKET_SIZE, cur);
                    ps[g].refresh_interval(l);
                }
                big.t_max = max_t(ps);
            } else if !is_leaf(cur) {
                let node = &self.nodes8[cur as usize];
                let (cand, t_ia) = test::<L>(&big, node);
                let mut kid = [Entry64 {
                    child: 0,
                    mask: 0,
                    t: [0.0; GROUPS],
                }; 8];
                // The children some group enters, by lane, then ordered by the whole packet's
                // entry bound (keys and sorting networks of `packet8.rs`).
                let mut entered = 0u32;
                if cand != 0 {
                    let mut gc = [0u32; GROUPS];
                    let mut gt = [t_ia; GROUPS];
                    for g in 0..GROUPS {
                        if gbits(mask, g) == 0 {
                            continue;
                        }
                        match &ps[g].interval {
                            Some(iv) if GROUP_TESTS => (gc[g], gt[g]) = test::<L>(iv, node),
                            _ => gc[g] = cand,
                        }
                    }
                    let mut m = cand;
                    while m != 0 {
                        let c = m.trailing_zeros() as usize;
                        m &= m - 1;
                        let mut hits = 0u64;
                        let mut t = [f32::INFINITY; GROUPS];
                        for g in 0..GROUPS {
                            if gc[g] >> c & 1 != 0 {
                                hits |= mask & (0xFFFF << (PACKET_SIZE * g));
                                t[g] = gt[g][c];
                            }
                        }
                        if hits != 0 {
                            kid[c] = Entry64 {
                                child: node.child[c],
                                mask: hits,
                                t,
                            };
                            entered |= 1 << c;
                        }
                    }
                }
                if entered != 0 {
                    let first = if entered & (entered - 1) == 0 {
                        entered.trailing_zeros() as usize
                    } else {
                        let ks = sorted_keys(entered, &t_ia);
                        let n = entered.count_ones() as usize;
                        for &k in ks[1..n].iter().rev() {
                            // `7 * depth8 < STACK8_SIZE` (checked at build): at most 7 per level.
                            stack[sp] = MaybeUninit::new(kid[(k & 7) as usize]);
                            sp += 1;
                        }
                        (ks[0] & 7) as usize
                    };
                    cur = kid[first].child;
                    mask = kid[first].mask;
                    continue;
                }
            } else {
                for g in 0..GROUPS {
                    let gm = gbits(mask, g);
                    if gm != 0 {
                        let (first, count) = (leaf_first(cur), leaf_count(cur));
                        self.packet_leaf(l, &mut ps[g], group(rays, g), first, count, gm);
                        ps[g].refresh_interval(l);
                    }
                }
                big.t_max = max_t(ps);
            }
            loop {
                if sp == 0 {
                    for (i, o) in out.iter_mut().enumerate().take(rays.len()) {
                        *o = ps[i / PACKET_SIZE].best(i % PACKET_SIZE).hit();
                    }
                    return;
                }
                sp -= 1;
                // SAFETY: entries below `sp` were written by the pushes above.
                let e = unsafe { stack[sp].assume_init() };
                let mut m = 0u64;
                for g in 0..GROUPS {
                    let gm = gbits(e.mask, g);
                    if gm != 0 {
                        let keep = ps[g].not_beyond(l, gm, e.t[g]);
                        m |= (keep as u64) << (PACKET_SIZE * g);
                    }
                }
                if m != 0 {
                    cur = e.child;
                    mask = m;
                    break;
                }
            }
        }
    }
}

/// The largest current `t_max` over the groups' intervals (groups without rays: -inf).
#[inline(always)]
fn max_t(ps: &[Packet; GROUPS]) -> f32 {
    let mut t = f32::NEG_INFINITY;
    for p in ps {
        if let Some(iv) = &p.interval {
            t = t.max(iv.t_max);
        }
    }
    t
}
