//! Sample testing four subsample rays at a time (Hunt et al. 2018, §5.5, "threads are mapped 1:1
//! with pixels or subpixels": SIMD lanes over rays instead of GPU threads).
//!
//! A packet is four consecutive subsample rays of a tile. Rays are generated in SIMD for the
//! pinhole and stereo models (the f32 operations of `Pinhole::generate_ray`, lane by lane:
//! bit-identical rays) and per lane otherwise. If the four rays share the permutation of the
//! watertight test (dominant axis and its sign, Woop et al. 2013 §3) — all but a few packets on
//! the diagonals of the image — each triangle is tested against the four rays with the exact f32
//! operations of `WatertightRay::intersect_within` per lane (vertex coordinates splatted, ray
//! constants per lane; exactly-zero edge functions fall back to the scalar test), so every hit
//! equals the per-ray BVH answer. Otherwise the packet's rays take the one-ray path
//! ([`super::intersect`]).
//!
//! Per leaf (near-depth order), the four rays first run the robust slab test of the BVH on the
//! leaf's box (Ize 2013 far scaling; lanes already holding a closer hit skip it), and the packet
//! stops once every ray has a hit nearer than the next leaf's near depth along the beam axis.

use glam::{Vec2, Vec3, Vec4};
use parallax_bvh::Tri4;
use parallax_bvh::node::{leaf_count, leaf_first};
use parallax_core::Ray;
use parallax_core::math::{PreparedBeam, ROBUST_FAR_SCALE, WatertightRay};
use parallax_scene::camera::{Camera, Pinhole};

use super::SampleSet;
use super::intersect::LeafBox;

/// `a > b ? a : b` per lane (NaN in `a` gives `b`).
#[inline(always)]
fn max_or_rhs(a: Vec4, b: Vec4) -> Vec4 {
    Vec4::select(a.cmpgt(b), a, b)
}

/// `a < b ? a : b` per lane (NaN in `a` gives `b`).
#[inline(always)]
fn min_or_rhs(a: Vec4, b: Vec4) -> Vec4 {
    Vec4::select(a.cmplt(b), a, b)
}

/// Four rays in SoA lanes.
#[derive(Clone, Copy, Debug)]
pub struct Rays4 {
    pub o: [Vec4; 3],
    pub d: [Vec4; 3],
    /// Lanes holding a valid ray.
    pub valid: u32,
}

impl Rays4 {
    pub fn lane(&self, l: usize) -> Ray {
        Ray::new(
            Vec3::new(self.o[0][l], self.o[1][l], self.o[2][l]),
            Vec3::new(self.d[0][l], self.d[1][l], self.d[2][l]),
        )
    }
}

/// `Pinhole::generate_ray` on four film positions (lane-wise the same f32 operations:
/// `camera_dir`, `Vec3::length`, `d / len`, `Mat3 * Vec3`).
#[inline(always)]
fn pinhole4(p: &Pinhole, fx: Vec4, fy: Vec4) -> ([Vec4; 3], [Vec4; 3]) {
    let w = Vec4::splat(p.width as f32);
    let h = Vec4::splat(p.height as f32);
    let ndc_x = Vec4::splat(2.0) * fx / w - Vec4::ONE;
    let ndc_y = Vec4::ONE - Vec4::splat(2.0) * fy / h;
    let x = (ndc_x + Vec4::splat(p.shift.x)) * Vec4::splat(p.tan_half_x());
    let y = (ndc_y + Vec4::splat(p.shift.y)) * Vec4::splat(p.tan_half_y);
    let z = Vec4::splat(-1.0);
    let len = Vec4::from_array((x * x + y * y + z * z).to_array().map(f32::sqrt));
    let (x, y, z) = (x / len, y / len, z / len);
    let m = &p.frame.basis;
    let col = |c: Vec3, i: usize| Vec4::splat(c[i]);
    let mut d = [Vec4::ZERO; 3];
    for (i, di) in d.iter_mut().enumerate() {
        *di = col(m.x_axis, i) * x + col(m.y_axis, i) * y + col(m.z_axis, i) * z;
    }
    let o = p.frame.position;
    ([Vec4::splat(o.x), Vec4::splat(o.y), Vec4::splat(o.z)], d)
}

/// The subsample rays `(sample, k)` of `pairs` (up to four) into lanes.
pub fn gen4(set: &SampleSet, pairs: &[(u32, u32)]) -> Rays4 {
    let n = pairs.len();
    let mut film = [Vec2::ZERO; 4];
    for (l, &(i, k)) in pairs.iter().enumerate() {
        let s = &set.samples[i as usize];
        film[l] = s.film + set.offsets[k as usize] * s.footprint;
    }
    let f0 = film[0];
    for f in film.iter_mut().skip(n) {
        *f = f0;
    }
    let full = (1u32 << n) - 1;
    let fx = Vec4::new(film[0].x, film[1].x, film[2].x, film[3].x);
    let fy = Vec4::new(film[0].y, film[1].y, film[2].y, film[3].y);
    match &set.camera {
        Camera::Pinhole(p) => {
            let (o, d) = pinhole4(p, fx, fy);
            return Rays4 { o, d, valid: full };
        }
        Camera::Stereo(rig) => {
            let w = rig.eye_width() as f32;
            let inside = film[..n].iter().all(|f| f.x >= 0.0 && f.x <= 2.0 * w);
            let left = film[..n].iter().all(|f| f.x < w);
            let right = film[..n].iter().all(|f| f.x >= w);
            if inside && (left || right) {
                let (p, fx) = if left {
                    (&rig.eyes[0], fx)
                } else {
                    (&rig.eyes[1], fx - Vec4::splat(w))
                };
                let (o, d) = pinhole4(p, fx, fy);
                return Rays4 { o, d, valid: full };
            }
        }
        _ => {}
    }
    let mut r = Rays4 {
        o: [Vec4::ZERO; 3],
        d: [Vec4::ZERO; 3],
        valid: 0,
    };
    for (l, &(i, k)) in pairs.iter().enumerate() {
        if let Some(ray) = set.fast_subsample_ray(i as usize, k as usize) {
            for a in 0..3 {
                r.o[a][l] = ray.origin[a];
                r.d[a][l] = ray.dir[a];
            }
            r.valid |= 1 << l;
        }
    }
    r
}

/// The axis permutation of `WatertightRay::new`: dominant axis `kz`, `kx, ky` swapped when
/// `d[kz] < 0`.
#[inline(always)]
fn permutation(d: Vec3) -> (usize, usize, usize) {
    let a = d.abs();
    let kz = if a.x > a.y {
        if a.x > a.z { 0 } else { 2 }
    } else if a.y > a.z {
        1
    } else {
        2
    };
    let kx = (kz + 1) % 3;
    let ky = (kx + 1) % 3;
    if d[kz] < 0.0 {
        (ky, kx, kz)
    } else {
        (kx, ky, kz)
    }
}

/// Result of a packet: per lane the closest `(t, index in Bvh::triangles)` (`u32::MAX` = none).
#[derive(Clone, Copy, Debug)]
pub struct Closest4 {
    pub t: [f32; 4],
    pub tri: [u32; 4],
}

/// Work counters of a packet.
#[derive(Clone, Copy, Debug, Default)]
pub struct PacketWork {
    pub box_tests: u64,
    pub tri_tests: u64,
}

/// Tests the packet against the near-sorted `leaves`; `None` when the rays do not share one
/// watertight permutation (the caller then takes the one-ray path).
#[inline(never)]
pub fn closest4(
    rays: &Rays4,
    blocks: &[Tri4],
    leaves: &[LeafBox],
    beam: &PreparedBeam,
    slack: f32,
    work: &mut PacketWork,
) -> Option<Closest4> {
    // Per-lane watertight set-up (Woop et al. 2013, §3, as `WatertightRay::new`); all lanes
    // must share (kx, ky, kz). The shear constants are divided lane-wise (the same IEEE
    // divisions); a scalar `WatertightRay` is only built for the exact-fallback lanes.
    let valid = rays.valid;
    let mut out = Closest4 {
        t: [f32::INFINITY; 4],
        tri: [u32::MAX; 4],
    };
    let mut perm = None;
    for l in 0..4 {
        if valid >> l & 1 == 0 {
            continue;
        }
        let ray = rays.lane(l);
        // The packet kernel assumes `Ray::new`'s interval (0, inf); anything else takes the
        // one-ray path.
        if !(ray.is_valid() && ray.t_min == 0.0 && ray.t_max == f32::INFINITY) {
            return None;
        }
        let p = permutation(ray.dir);
        if *perm.get_or_insert(p) != p {
            return None;
        }
    }
    let Some((kx, ky, kz)) = perm else {
        return Some(out);
    };
    let dkz = rays.d[kz];
    let sx = rays.d[kx] / dkz;
    let sy = rays.d[ky] / dkz;
    let sz = Vec4::ONE / dkz;
    // `Ray::new`: t in (0, inf) for every ray the generators make.
    let t_min = Vec4::ZERO;
    let ok_ = rays.o;
    let (okx, oky, okz) = (ok_[kx], ok_[ky], ok_[kz]);
    let inv = [rays.d[0].recip(), rays.d[1].recip(), rays.d[2].recip()];
    let neg = [
        inv[0].cmplt(Vec4::ZERO),
        inv[1].cmplt(Vec4::ZERO),
        inv[2].cmplt(Vec4::ZERO),
    ];
    let a = beam.axis;
    let (oa, da) = (rays.o[a], rays.d[a]);
    let s = Vec4::splat(beam.sign);
    let ordered = !beam.everything;
    // Per lane: the slab limit (closest t so far) and the triangle limit (next float above it).
    let mut box_lim = Vec4::INFINITY;
    let mut tri_lim = Vec4::INFINITY;
    let mut exit_depth = f32::INFINITY;
    let mut hit_lanes = 0u32;
    for lb in leaves {
        if ordered && hit_lanes == valid && lb.near > exit_depth + slack {
            break;
        }
        work.box_tests += 1;
        let b = &lb.bounds;
        let slab = |lo: f32, hi: f32, ax: usize| {
            let t0 = (Vec4::splat(lo) - rays.o[ax]) * inv[ax];
            let t1 = (Vec4::splat(hi) - rays.o[ax]) * inv[ax];
            (Vec4::select(neg[ax], t1, t0), Vec4::select(neg[ax], t0, t1))
        };
        let (tnx, tfx) = slab(b.min.x, b.max.x, 0);
        let (tny, tfy) = slab(b.min.y, b.max.y, 1);
        let (tnz, tfz) = slab(b.min.z, b.max.z, 2);
        let t_near = max_or_rhs(tnz, max_or_rhs(tny, max_or_rhs(tnx, t_min)));
        let t_far = min_or_rhs(tfz, min_or_rhs(tfy, min_or_rhs(tfx, box_lim)));
        let m = t_near.cmple(t_far * ROBUST_FAR_SCALE).bitmask() & valid;
        if m == 0 {
            continue;
        }
        let (first, count) = (leaf_first(lb.leaf), leaf_count(lb.leaf));
        let mut changed = false;
        for j in 0..count {
            let blk = &blocks[(first + j / 4) as usize];
            let ln = (j % 4) as usize;
            let tri = blk.tri[ln];
            work.tri_tests += 1;
            let proj = |v: usize| {
                let p = &blk.p[v];
                let az = Vec4::splat(p[kz][ln]) - okz;
                let x = (Vec4::splat(p[kx][ln]) - okx) - sx * az;
                let y = (Vec4::splat(p[ky][ln]) - oky) - sy * az;
                (x, y, sz * az)
            };
            let (ax, ay, az) = proj(0);
            let (bx, by, bz) = proj(1);
            let (cx, cy, cz) = proj(2);
            let u = cx * by - cy * bx;
            let v = ax * cy - ay * cx;
            let w = bx * ay - by * ax;
            let zero = Vec4::ZERO;
            let exact = (u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero)).bitmask() & m;
            let negm = u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero);
            let posm = u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero);
            let det = u + v + w;
            let t_scaled = u * az + v * bz + w * cz;
            let t = t_scaled * (Vec4::ONE / det);
            let ok = (negm & posm).bitmask() ^ 0xF;
            let nz = det.cmpne(zero).bitmask();
            let in_range = (t.cmpgt(t_min) & t.cmplt(tri_lim)).bitmask();
            let hit = ok & nz & in_range & m & !exact;
            let mut offer = |l: usize, tl: f32| {
                if out.tri[l] == u32::MAX || tl < out.t[l] || (tl == out.t[l] && tri < out.tri[l]) {
                    out.t[l] = tl;
                    out.tri[l] = tri;
                    changed = true;
                }
            };
            let mut hm = hit;
            while hm != 0 {
                let l = hm.trailing_zeros() as usize;
                hm &= hm - 1;
                offer(l, t[l]);
            }
            let mut em = exact;
            while em != 0 {
                let l = em.trailing_zeros() as usize;
                em &= em - 1;
                let wt = WatertightRay::new(&rays.lane(l));
                let vtx = |q: usize| blk.vertex(ln, q);
                if let Some(hh) = wt.intersect_within(vtx(0), vtx(1), vtx(2), tri_lim[l]) {
                    offer(l, hh.t);
                }
            }
            if changed {
                for l in 0..4 {
                    if out.tri[l] != u32::MAX {
                        tri_lim[l] = out.t[l].next_up();
                        box_lim[l] = out.t[l];
                    }
                }
            }
        }
        if changed {
            hit_lanes = 0;
            let bt = Vec4::from_array(out.t);
            let depth = (s * (oa + bt * da)).to_array();
            exit_depth = f32::NEG_INFINITY;
            for l in 0..4 {
                if valid >> l & 1 != 0 {
                    if out.tri[l] != u32::MAX {
                        hit_lanes |= 1 << l;
                    }
                    exit_depth = exit_depth.max(depth[l]);
                }
            }
        }
    }
    Some(out)
}
