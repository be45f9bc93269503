//! The set-up of a full 16-ray packet in lanes (`packet8.rs`, `Packet::init`): the rays' fields
//! loaded into lanes ([`Lanes16::load_rays`]), their validity, the common axis permutation of
//! the watertight test and whether they share one origin, with the comparisons of the scalar
//! code (`Ray::is_valid`, `watertight_code` in `packet8.rs`) lane for lane, so the packet is
//! the same as the one the scalar loop builds.
//!
//! **Invariant:** `valid` bit `i` is `rays[i].is_valid() && rays[i].t_min <= rays[i].t_max`;
//! `code` is `Some(c)` exactly when every valid ray's `watertight_code` is `c` (and some ray is
//! valid); `same_org` is true when every valid ray's origin equals `o0` bit for bit.

use parallax_core::Ray;

use crate::lanes16::Lanes16;

/// The lanes of 16 rays and what the packet set-up needs of them.
pub(crate) struct RayLanes<V> {
    pub valid: u32,
    /// origin x, y, z, direction x, y, z, `t_min`, `t_max` (invalid lanes: anything).
    pub f: [V; 8],
    pub code: Option<u32>,
    /// The first valid ray's origin (zero without one).
    pub o0: [f32; 3],
    pub same_org: bool,
}

/// Module docs.
#[inline(always)]
pub(crate) fn rays16<L: Lanes16>(l: L, rays: &[Ray; 16]) -> RayLanes<L::V> {
    let f = l.load_rays(rays);
    let (zero, inf) = (l.splat(0.0), l.splat(f32::INFINITY));
    // `is_finite`: `|x| < inf` (false for NaN).
    let mut valid = 0xFFFF;
    for v in &f[..6] {
        valid &= l.lt(l.abs(*v), inf);
    }
    // glam's `length_squared`: `(x * x + y * y) + z * z`.
    let len2 = l.add(
        l.add(l.mul(f[3], f[3]), l.mul(f[4], f[4])),
        l.mul(f[5], f[5]),
    );
    valid &= l.gt(len2, zero) & l.le(f[6], f[7]);
    // `watertight_code`: `kz` the dominant axis by `>` on `|d|`, swapped when `d[kz] < 0`.
    let (ax, ay, az) = (l.abs(f[3]), l.abs(f[4]), l.abs(f[5]));
    let (xy, xz, yz) = (l.gt(ax, ay), l.gt(ax, az), l.gt(ay, az));
    let k0 = xy & xz & valid;
    let k1 = !xy & yz & valid;
    let k2 = valid & !k0 & !k1;
    let kz = if valid == 0 {
        None
    } else if k0 == valid {
        Some(0)
    } else if k1 == valid {
        Some(1)
    } else if k2 == valid {
        Some(2)
    } else {
        None
    };
    let code = match kz {
        Some(kz) => {
            let neg = l.lt(f[3 + kz], zero) & valid;
            if neg == 0 {
                Some(2 * kz as u32)
            } else if neg == valid {
                Some(2 * kz as u32 + 1)
            } else {
                None
            }
        }
        None => None,
    };
    let mut o0 = [0.0; 3];
    let mut same_org = true;
    if valid != 0 {
        o0 = rays[valid.trailing_zeros() as usize].origin.to_array();
        for a in 0..3 {
            same_org &= l.eq_bits(f[a], l.splat(o0[a])) & valid == valid;
        }
    }
    RayLanes {
        valid,
        f,
        code,
        o0,
        same_org,
    }
}
