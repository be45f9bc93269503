//! Coherent ray packets: primary rays grouped by screen tiles (4x2 pixels for 8-wide packets,
//! 4x4 for 16-wide), the grouping Embree's packet kernels are designed for.

use glam::Vec2;
use parallax_core::Ray;
use parallax_scene::camera::{Camera, CameraModel};

/// Rays stored packet after packet; packet `k` is `rays[start..start + len]` of `packets[k]`.
#[derive(Clone, Debug, Default)]
pub struct Packets {
    pub rays: Vec<Ray>,
    /// `(start, len)` of each packet, `len <= tile_w * tile_h`.
    pub packets: Vec<(u32, u32)>,
}

impl Packets {
    /// The rays of packet `k`.
    #[inline]
    pub fn packet(&self, k: usize) -> &[Ray] {
        let (s, n) = self.packets[k];
        &self.rays[s as usize..(s + n) as usize]
    }
}

/// Primary rays through pixel centres (the same calls as
/// `parallax_render::bench::rays::make_rays`), grouped into `tile_w x tile_h` pixel tiles,
/// tiles in scanline order. Pixels without a ray (outside a fisheye's circle) are skipped.
pub fn primary_packets(camera: &Camera, tile_w: u32, tile_h: u32) -> Packets {
    let (w, h) = (camera.width(), camera.height());
    let mut out = Packets::default();
    for ty in (0..h).step_by(tile_h as usize) {
        for tx in (0..w).step_by(tile_w as usize) {
            let start = out.rays.len() as u32;
            for y in ty..(ty + tile_h).min(h) {
                for x in tx..(tx + tile_w).min(w) {
                    let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    if let Some(r) = camera.generate_ray(film, Vec2::splat(0.5), 1) {
                        out.rays.push(r.ray);
                    }
                }
            }
            let len = out.rays.len() as u32 - start;
            if len > 0 {
                out.packets.push((start, len));
            }
        }
    }
    out
}

/// Consecutive groups of `width` rays (for incoherent rays, where no tiling helps).
pub fn chunked(rays: &[Ray], width: usize) -> Packets {
    let packets = (0..rays.len())
        .step_by(width)
        .map(|s| (s as u32, width.min(rays.len() - s) as u32))
        .collect();
    Packets {
        rays: rays.to_vec(),
        packets,
    }
}
