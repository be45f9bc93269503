//! Packet traversal of the 4-wide tree (the predecessor of `packet8.rs`, kept as its twin and
//! for comparison in `bench rays`): up to 16 rays walk the tree together, SIMD
//! over the rays at inner nodes (Wald, Slusallek, Benthin & Wagner 2001, "Interactive Rendering
//! with Coherent Ray Tracing"; the wide-node form of Embree's `rtcIntersect16`, Wald et al.
//! 2014, §4.2).
//!
//! - **Inner nodes**: each of the node's (up to four) child boxes is tested against the active
//!   rays, four rays per SSE `Vec4` (four groups for 16 rays; a group without active rays is
//!   skipped). The test is the single-ray slab test of `traverse.rs` lane for lane: the near /
//!   far plane is selected per ray by the sign of its direction (`select`, instead of the
//!   single ray's plane index), then the same `max_or_rhs` / `min_or_rhs` chain and the same
//!   robust far scaling (Ize 2013), so each ray gets bit-identical entry / exit distances.
//! - **Order**: the children hit by at least one ray are visited near-to-far by the smallest
//!   entry distance over their rays; the others are pushed with their ray mask and that
//!   distance, and on pop the mask is narrowed to the rays whose closest hit is not nearer.
//! - **Leaves**: each active ray runs the single-ray 4-triangle watertight test (`tri4.rs`),
//!   with its own axis permutation, so mixed permutations within a packet need no special case.
//!
//! **Invariant:** every ray's answer equals [`Bvh::closest_hit`] exactly (prim, t, u, v): both
//! return the lexicographic minimum of `(t, primitive id)` over the hits (ties at `t` are kept
//! for the tie-break by inclusive culling), and a ray's box tests here are conservative exactly
//! when its single-ray box tests are. `tests/packets.rs` checks it.
//!
//! **Measured / what we tried**: `docs/notes/bvh.md`.

use std::mem::MaybeUninit;

use glam::Vec4;
use parallax_core::Ray;
use parallax_core::math::{ROBUST_FAR_SCALE, WatertightRay};

use crate::bvh::Bvh;
use crate::hit::Hit;
use crate::node::{is_leaf, leaf_count, leaf_first};
use crate::stats::NoStats;
use crate::traverse::{Best, STACK_SIZE};
use crate::tri4::Tri4Ray;
use parallax_core::simd::{max_or_rhs, min_or_rhs};

/// Rays per packet traversal ([`Bvh::closest_hit_packet4`] splits longer slices).
const PACKET_SIZE: usize = 16;
const GROUPS: usize = PACKET_SIZE / 4;

#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    mask: u32,
    t: f32,
}

/// One value per ray of a packet, aligned for 256-bit loads.
#[derive(Clone, Copy)]
#[repr(C, align(64))]
struct Lanes([f32; PACKET_SIZE]);

impl Lanes {
    #[inline(always)]
    fn group(&self, g: usize) -> Vec4 {
        Vec4::from_slice(&self.0[4 * g..4 * g + 4])
    }
}

/// The rays of a packet in SoA form for the slab test.
struct PacketBoxes {
    org: [Lanes; 3],
    /// `1 / dir`; its sign bit says the near plane is the box's max (also the AVX2 blend mask).
    inv: [Lanes; 3],
    t_min: Lanes,
    /// Per ray: the closest hit so far (or the ray's `t_max`).
    t_max: Lanes,
}

impl PacketBoxes {
    fn new(rays: &[Ray], valid: u32) -> Self {
        let mut pb = PacketBoxes {
            org: [Lanes([0.0; PACKET_SIZE]); 3],
            inv: [Lanes([1.0; PACKET_SIZE]); 3],
            t_min: Lanes([0.0; PACKET_SIZE]),
            t_max: Lanes([f32::NEG_INFINITY; PACKET_SIZE]),
        };
        for (i, r) in rays.iter().enumerate() {
            if valid >> i & 1 == 0 {
                continue;
            }
            let iv = r.dir.recip();
            for a in 0..3 {
                pb.org[a].0[i] = r.origin[a];
                pb.inv[a].0[i] = iv[a];
            }
            pb.t_min.0[i] = r.t_min;
            pb.t_max.0[i] = r.t_max;
        }
        pb
    }

    /// Rays of `mask` that have not yet found a hit nearer than `t`.
    #[inline(always)]
    fn not_beyond(&self, mask: u32, t: f32) -> u32 {
        let t = Vec4::splat(t);
        let mut m = 0;
        for g in 0..GROUPS {
            if mask >> (4 * g) & 0xF != 0 {
                // Against the scaled closest hit, as the single-ray pop (`traverse.rs`).
                let bound = self.t_max.group(g) * ROBUST_FAR_SCALE;
                m |= t.cmple(bound).bitmask() << (4 * g);
            }
        }
        mask & m
    }

    /// Slab test of child box `(lo, hi)` against the rays of `mask`, four at a time (SSE, or
    /// glam's scalar fallback): the rays that hit, and the smallest entry distance among them.
    #[inline(always)]
    fn test_child(&self, lo: [f32; 3], hi: [f32; 3], mask: u32) -> (u32, f32) {
        let lo = lo.map(Vec4::splat);
        let hi = hi.map(Vec4::splat);
        let scale = Vec4::splat(ROBUST_FAR_SCALE);
        let mut hits = 0u32;
        let mut t_first = Vec4::INFINITY;
        for g in 0..GROUPS {
            if mask >> (4 * g) & 0xF == 0 {
                continue;
            }
            let mut t_near = self.t_min.group(g);
            let mut t_far = Vec4::INFINITY;
            for a in 0..3 {
                let (o, inv) = (self.org[a].group(g), self.inv[a].group(g));
                let t0 = (lo[a] - o) * inv;
                let t1 = (hi[a] - o) * inv;
                // `inv` is never zero or NaN for a valid ray (padding lanes hold 1).
                let neg = inv.cmplt(Vec4::ZERO);
                t_near = max_or_rhs(Vec4::select(neg, t1, t0), t_near);
                t_far = min_or_rhs(Vec4::select(neg, t0, t1), t_far);
            }
            // `t_max` scaled too, as in the single-ray slab test (`traverse.rs`).
            let t_far = min_or_rhs(t_far, self.t_max.group(g)) * scale;
            let hit = t_near.cmple(t_far);
            let m = hit.bitmask() & (mask >> (4 * g));
            if m != 0 {
                hits |= m << (4 * g);
                t_first = t_first.min(Vec4::select(hit, t_near, Vec4::INFINITY));
            }
        }
        (hits, t_first.min_element())
    }

    /// [`Self::test_child`] eight rays at a time with AVX (same operations lane for lane:
    /// `vmaxps` / `vminps` return the second operand on NaN exactly as `maxps` / `minps`).
    ///
    /// # Safety
    /// The CPU must support AVX2 (the caller checks with `is_x86_feature_detected!`).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn test_child_avx2(&self, lo: [f32; 3], hi: [f32; 3], mask: u32) -> (u32, f32) {
        use std::arch::x86_64::*;
        // SAFETY: AVX2 is available (caller), loads are from 64-byte aligned `Lanes`.
        unsafe {
            let scale = _mm256_set1_ps(ROBUST_FAR_SCALE);
            let inf = _mm256_set1_ps(f32::INFINITY);
            let mut hits = 0u32;
            let mut t_first = inf;
            for h in 0..PACKET_SIZE / 8 {
                if mask >> (8 * h) & 0xFF == 0 {
                    continue;
                }
                let ld = |l: &Lanes| _mm256_load_ps(l.0.as_ptr().add(8 * h));
                let mut t_near = ld(&self.t_min);
                let mut t_far = inf;
                for a in 0..3 {
                    let (o, inv) = (ld(&self.org[a]), ld(&self.inv[a]));
                    let t0 = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(lo[a]), o), inv);
                    let t1 = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(hi[a]), o), inv);
                    // blendv takes the second operand where the mask's sign bit is set.
                    t_near = _mm256_max_ps(_mm256_blendv_ps(t0, t1, inv), t_near);
                    t_far = _mm256_min_ps(_mm256_blendv_ps(t1, t0, inv), t_far);
                }
                let t_far = _mm256_mul_ps(_mm256_min_ps(t_far, ld(&self.t_max)), scale);
                let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far);
                let m = _mm256_movemask_ps(hit) as u32 & (mask >> (8 * h)) & 0xFF;
                if m != 0 {
                    hits |= m << (8 * h);
                    t_first = _mm256_min_ps(t_first, _mm256_blendv_ps(inf, t_near, hit));
                }
            }
            let m = _mm_min_ps(
                _mm256_castps256_ps128(t_first),
                _mm256_extractf128_ps::<1>(t_first),
            );
            (hits, Vec4::from(m).min_element())
        }
    }
}

impl Bvh {
    /// The packet traversal of the 4-wide tree (the predecessor of [`Bvh::closest_hit_packet`],
    /// kept as its twin): up to 16 coherent rays traced together (longer slices are
    /// split into packets of 16); `out[i]` is exactly [`Bvh::closest_hit`] of
    /// `rays[i]`. Fast when the rays are coherent (e.g. the primary rays of a 4x4 pixel tile);
    /// incoherent rays are better traced one by one. Panics if `out` is shorter than `rays`.
    pub fn closest_hit_packet4(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        assert!(out.len() >= rays.len(), "closest_hit_packet: out too short");
        for (r, o) in rays.chunks(PACKET_SIZE).zip(out.chunks_mut(PACKET_SIZE)) {
            self.packet16(r, o);
        }
    }

    /// Dispatch: the AVX2 node test where the CPU has it (checked once per call, cached by
    /// std), else the SSE / portable one.
    fn packet16(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        #[cfg(target_arch = "x86_64")]
        if use_avx2() {
            // SAFETY: AVX2 was detected.
            return unsafe { self.packet16_avx2(rays, out) };
        }
        self.packet16_impl::<false>(rays, out)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn packet16_avx2(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        self.packet16_impl::<true>(rays, out)
    }

    /// [`Self::closest_hit_packet4`] with the portable (SSE / scalar) node test even where AVX2
    /// exists: the twin the tests hold the AVX2 path against.
    pub fn closest_hit_packet4_portable(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        assert!(out.len() >= rays.len(), "closest_hit_packet: out too short");
        for (r, o) in rays.chunks(PACKET_SIZE).zip(out.chunks_mut(PACKET_SIZE)) {
            self.packet16_impl::<false>(r, o);
        }
    }

    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // the loop index addresses several arrays in step
    fn packet16_impl<const AVX2: bool>(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        let mut valid = 0u32;
        for (i, r) in rays.iter().enumerate() {
            out[i] = None;
            if r.is_valid() && r.t_min <= r.t_max {
                valid |= 1 << i;
            }
        }
        if self.nodes.is_empty() || valid == 0 {
            return;
        }
        let mut pb = PacketBoxes::new(rays, valid);
        let mut r4: [MaybeUninit<Tri4Ray>; PACKET_SIZE] = [MaybeUninit::uninit(); PACKET_SIZE];
        let mut best = [Best::new(); PACKET_SIZE];
        for (i, r) in rays.iter().enumerate() {
            if valid >> i & 1 != 0 {
                r4[i] = MaybeUninit::new(Tri4Ray::new(WatertightRay::new(r)));
            }
        }
        let mut stack = [MaybeUninit::<Entry>::uninit(); STACK_SIZE];
        let mut sp = 0usize;
        let mut cur = 0u32;
        let mut mask = valid;
        loop {
            if !is_leaf(cur) {
                let node = &self.nodes[cur as usize];
                let b = &node.bounds;
                let mut kid = [Entry {
                    child: 0,
                    mask: 0,
                    t: 0.0,
                }; 4];
                let mut n = 0;
                for c in 0..node.num_children as usize {
                    let lo = [b[0][c], b[2][c], b[4][c]];
                    let hi = [b[1][c], b[3][c], b[5][c]];
                    #[cfg(target_arch = "x86_64")]
                    let (hits, t) = if AVX2 {
                        // SAFETY: `AVX2` is only set after runtime detection.
                        unsafe { pb.test_child_avx2(lo, hi, mask) }
                    } else {
                        pb.test_child(lo, hi, mask)
                    };
                    #[cfg(not(target_arch = "x86_64"))]
                    let (hits, t) = pb.test_child(lo, hi, mask);
                    if hits != 0 {
                        kid[n] = Entry {
                            child: node.child[c],
                            mask: hits,
                            t,
                        };
                        n += 1;
                    }
                }
                if n != 0 {
                    // Sort far-to-near (insertion sort of at most four), push all but the
                    // nearest, continue with the nearest.
                    for i in 1..n {
                        let x = kid[i];
                        let mut j = i;
                        while j > 0 && kid[j - 1].t < x.t {
                            kid[j] = kid[j - 1];
                            j -= 1;
                        }
                        kid[j] = x;
                    }
                    for e in &kid[..n - 1] {
                        stack[sp] = MaybeUninit::new(*e);
                        sp += 1;
                    }
                    cur = kid[n - 1].child;
                    mask = kid[n - 1].mask;
                    continue;
                }
            } else {
                let (first, count) = (leaf_first(cur), leaf_count(cur));
                let mut m = mask;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let mut t_max = pb.t_max.0[i];
                    // SAFETY: rays of the mask are valid, and valid rays were initialised.
                    let r = unsafe { r4[i].assume_init_ref() };
                    self.leaf_closest(r, first, count, &mut t_max, &mut best[i], &mut NoStats);
                    pb.t_max.0[i] = t_max;
                }
            }
            // Pop the next entry that some ray can still use.
            loop {
                if sp == 0 {
                    for (i, o) in out.iter_mut().enumerate().take(rays.len()) {
                        *o = best[i].hit();
                    }
                    return;
                }
                sp -= 1;
                // SAFETY: entries below `sp` were written by the pushes above.
                let e = unsafe { stack[sp].assume_init() };
                let m = pb.not_beyond(e.mask, e.t);
                if m != 0 {
                    cur = e.child;
                    mask = m;
                    break;
                }
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[inline]
fn use_avx2() -> bool {
    std::is_x86_feature_detected!("avx2")
}
