//! The public entry points of the packet traversals of the 8-wide tree ([`Bvh::closest_hit_packet`],
//! `packet8.rs`; [`Bvh::closest_hit_packet64`], `packet64.rs`) and their choice of lanes
//! ([`PacketLanes`]): the traversals are generic over [`Lanes16`], and each lane type runs in a
//! function compiled with its target features, chosen at run time: AVX-512 where the CPU has
//! it, else AVX2, else the portable twin (SSE2 on x86_64).
//!
//! **Invariant:** every lane type gives bit for bit the same answers (each ray's single-ray
//! closest hit); `tests/packets.rs` and `tests/simd_twins.rs` run every supported lane type
//! through [`Bvh::closest_hit_packet_with`] / [`Bvh::closest_hit_packet64_with`] and compare.
//!
//! | lanes | needs | 16 lanes as |
//! |---|---|---|
//! | [`PacketLanes::Avx512`] | AVX-512F, AVX2, POPCNT | one `__m512`, masks in `k` registers |
//! | [`PacketLanes::Avx2`] | AVX2, POPCNT | two `__m256`, masks by `movemask` (`lanes16/avx2.rs`) |
//! | [`PacketLanes::Portable`] | - | four glam `Vec4` |

use parallax_core::Ray;

use crate::bvh::Bvh;
use crate::hit::Hit;
#[cfg(target_arch = "x86_64")]
use crate::lanes16::{Avx2, Avx512};
use crate::lanes16::{Lanes16, Portable16};
use crate::packet8::PACKET_SIZE;
use crate::packet64::PACKET64_SIZE;

/// The SIMD lanes a packet traversal runs on (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PacketLanes {
    /// Four glam `Vec4` per 16 rays (SSE2 on x86_64, scalar elsewhere): runs everywhere.
    Portable,
    /// Two 256-bit registers per 16 rays.
    Avx2,
    /// One 512-bit register per 16 rays.
    Avx512,
}

impl PacketLanes {
    /// The fastest lanes the CPU supports (what [`Bvh::closest_hit_packet`] uses).
    pub fn detected() -> Self {
        [Self::Avx512, Self::Avx2]
            .into_iter()
            .find(|l| l.is_supported())
            .unwrap_or(Self::Portable)
    }

    /// Whether the CPU can run these lanes (checked at run time).
    pub fn is_supported(self) -> bool {
        match self {
            Self::Portable => true,
            #[cfg(target_arch = "x86_64")]
            Self::Avx2 => crate::traverse8::use_avx2(),
            #[cfg(target_arch = "x86_64")]
            Self::Avx512 => {
                std::is_x86_feature_detected!("avx512f")
                    && std::is_x86_feature_detected!("avx2")
                    && std::is_x86_feature_detected!("popcnt")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// Every lane type the CPU supports, the portable twin first.
    pub fn supported() -> impl Iterator<Item = Self> {
        [Self::Portable, Self::Avx2, Self::Avx512]
            .into_iter()
            .filter(|l| l.is_supported())
    }
}

impl Bvh {
    /// Closest hits of up to [`PACKET_SIZE`] coherent rays traced together (longer slices are
    /// split into packets of [`PACKET_SIZE`]); `out[i]` is exactly [`Bvh::closest_hit`] of
    /// `rays[i]`. Fast when the rays are coherent (a pixel tile's or one pixel's camera rays);
    /// incoherent rays are better traced one by one. Uses the fastest lanes the CPU has
    /// ([`PacketLanes::detected`]). Panics if `out` is shorter than `rays`.
    pub fn closest_hit_packet(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        self.closest_hit_packet_with(PacketLanes::detected(), rays, out)
    }

    /// [`Self::closest_hit_packet`] with the portable lanes even where SIMD lanes exist: the
    /// twin the tests hold the SIMD lanes against.
    pub fn closest_hit_packet_portable(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        self.closest_hit_packet_with(PacketLanes::Portable, rays, out)
    }

    /// [`Self::closest_hit_packet`] on the given lanes. Panics if the CPU does not support
    /// them ([`PacketLanes::is_supported`]) or if `out` is shorter than `rays`.
    pub fn closest_hit_packet_with(
        &self,
        lanes: PacketLanes,
        rays: &[Ray],
        out: &mut [Option<Hit>],
    ) {
        assert!(out.len() >= rays.len(), "closest_hit_packet: out too short");
        self.dispatch::<false>(lanes, rays, out);
    }

    /// Closest hits of up to [`PACKET64_SIZE`] coherent rays traced together (longer slices
    /// are split into packets of 64); `out[i]` is exactly [`Bvh::closest_hit`] of `rays[i]`.
    /// Made for an 8x8 pixel tile's camera rays ordered as four 4x4 tiles of 16 consecutive
    /// rays (each 16 rays are one group); packets whose groups are not coherent fall back to
    /// [`Bvh::closest_hit_packet`] per group. Uses the fastest lanes the CPU has.
    /// Panics if `out` is shorter than `rays`.
    pub fn closest_hit_packet64(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        self.closest_hit_packet64_with(PacketLanes::detected(), rays, out)
    }

    /// [`Self::closest_hit_packet64`] with the portable lanes even where SIMD lanes exist: the
    /// twin the tests hold the SIMD lanes against.
    pub fn closest_hit_packet64_portable(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        self.closest_hit_packet64_with(PacketLanes::Portable, rays, out)
    }

    /// [`Self::closest_hit_packet64`] on the given lanes. Panics if the CPU does not support
    /// them or if `out` is shorter than `rays`.
    pub fn closest_hit_packet64_with(
        &self,
        lanes: PacketLanes,
        rays: &[Ray],
        out: &mut [Option<Hit>],
    ) {
        assert!(
            out.len() >= rays.len(),
            "closest_hit_packet64: out too short"
        );
        self.dispatch::<true>(lanes, rays, out);
    }

    /// Runs the 16-ray (`P64` false) or 64-ray kernel over `rays` on `lanes`, inside a
    /// function compiled for them (one per kernel and lane type).
    fn dispatch<const P64: bool>(&self, lanes: PacketLanes, rays: &[Ray], out: &mut [Option<Hit>]) {
        assert!(
            lanes.is_supported(),
            "{lanes:?} lanes: not supported by this CPU"
        );
        match lanes {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: AVX-512F and AVX2 were detected (`is_supported`).
            PacketLanes::Avx512 => unsafe { self.packets_avx512::<P64>(rays, out) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: AVX2 and POPCNT were detected (`is_supported`).
            PacketLanes::Avx2 => unsafe { self.packets_avx2::<P64>(rays, out) },
            _ => self.packets::<P64, _>(Portable16, rays, out),
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx2,popcnt")]
    unsafe fn packets_avx512<const P64: bool>(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        // SAFETY: AVX-512F, AVX2 and POPCNT are enabled for this function (the caller
        // detected them, `is_supported`).
        self.packets::<P64, _>(unsafe { Avx512::new() }, rays, out)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,popcnt")]
    unsafe fn packets_avx2<const P64: bool>(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        // SAFETY: AVX2 and POPCNT are enabled for this function (the caller detected them).
        self.packets::<P64, _>(unsafe { Avx2::new() }, rays, out)
    }

    /// `rays` in packets of the kernel's size, on lanes `l`.
    #[inline(always)]
    fn packets<const P64: bool, L: Lanes16>(&self, l: L, rays: &[Ray], out: &mut [Option<Hit>]) {
        if P64 {
            for (r, o) in rays
                .chunks(PACKET64_SIZE)
                .zip(out.chunks_mut(PACKET64_SIZE))
            {
                self.packet64(l, r, o);
            }
        } else {
            for (r, o) in rays.chunks(PACKET_SIZE).zip(out.chunks_mut(PACKET_SIZE)) {
                self.packet8(l, r, o);
            }
        }
    }
}
