//! The per-eye, per-frame G-buffer of the reprojection (Mäkitalo et al. 2019, §4.1: "we do
//! assume that we have access to the depth and shading normal buffers of both eyes"): per pixel
//! the world position, shading normal, view depth and albedo of the primary hit of the pixel's
//! sample, and the pinhole camera that saw it.
//!
//! **Invariants:** the texel of pixel `(x, y)` is at `y * width + x`; a miss has an infinite
//! depth (its other fields are zero); `position` is the hit of the sample's own (jittered)
//! primary ray, so it lies inside the pixel's footprint, and `normal` is unit length and faces
//! that ray.

use glam::{Vec3, Vec3A, Vec4};
use parallax_scene::camera::Pinhole;

/// One pixel of a G-buffer. `repr(C)`: the footprint's SSE path loads the position with the
/// depth and the normal with the albedo's first channel as 16 bytes each.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Texel {
    /// World position of the primary hit.
    pub position: Vec3,
    /// View depth (distance along the camera's forward axis); infinite for a miss.
    pub depth: f32,
    /// Unit shading normal, facing the primary ray.
    pub normal: Vec3,
    /// Linear RGB albedo (base colour times texture) of the hit.
    pub albedo: Vec3,
}

impl Texel {
    /// A pixel whose primary ray left the scene.
    pub const MISS: Texel = Texel {
        position: Vec3::ZERO,
        depth: f32::INFINITY,
        normal: Vec3::ZERO,
        albedo: Vec3::ZERO,
    };

    /// The world position in the lanes of one vector (on x86-64 one 16-byte load of the
    /// position and the depth, which `repr(C)` places after it).
    #[inline(always)]
    pub fn position_lanes(&self) -> Vec3A {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: SSE2 is part of x86-64; the 16 bytes from `position` are the position and
        // the depth, inside the texel.
        unsafe {
            Vec3A::from(std::arch::x86_64::_mm_loadu_ps(&self.position.x))
        }
        #[cfg(not(target_arch = "x86_64"))]
        Vec3A::from(self.position)
    }

    /// True when the primary ray hit a surface.
    #[inline]
    pub fn is_hit(&self) -> bool {
        self.depth.is_finite()
    }

    /// Albedo factor of demodulation: the albedo where a channel has one, else 1 (so black
    /// and sky texels pass radiance through).
    #[inline]
    pub fn albedo_factor(&self) -> Vec3 {
        self.albedo_factor_lanes().into()
    }

    /// [`Self::albedo_factor`] in the lanes of one vector.
    #[inline(always)]
    fn albedo_factor_lanes(&self) -> Vec3A {
        let a = Vec3A::from(self.albedo);
        Vec3A::select(a.cmpgt(Vec3A::splat(1e-3)), a, Vec3A::ONE)
    }

    /// `v` divided by the albedo factor when `on` (radiance as demodulated values carry it).
    /// The three channels are divided in the lanes of one vector (each lane's division is
    /// the scalar one, correctly rounded).
    #[inline]
    pub fn demodulate(&self, v: Vec3, on: bool) -> Vec3 {
        if on {
            (Vec3A::from(v) / self.albedo_factor_lanes()).into()
        } else {
            v
        }
    }

    /// [`Self::demodulate`] into lanes x, y, z of a vector (w is 0).
    #[inline]
    pub fn demodulate_lanes(&self, v: Vec3, on: bool) -> Vec4 {
        let v = Vec3A::from(v);
        if on {
            (v / self.albedo_factor_lanes()).extend(0.0)
        } else {
            v.extend(0.0)
        }
    }

    /// [`Self::remodulate`] of lanes x, y, z of `v`.
    #[inline]
    pub fn remodulate_lanes(&self, v: Vec4, on: bool) -> Vec3 {
        let v = Vec3A::from_vec4(v);
        if on {
            (v * self.albedo_factor_lanes()).into()
        } else {
            v.into()
        }
    }

    /// `v` times the albedo factor when `on` (an image value of demodulated radiance).
    #[inline]
    pub fn remodulate(&self, v: Vec3, on: bool) -> Vec3 {
        if on {
            (Vec3A::from(v) * self.albedo_factor_lanes()).into()
        } else {
            v
        }
    }
}

/// The G-buffer of one eye at one frame.
#[derive(Clone, Debug)]
pub struct EyeView {
    pub camera: Pinhole,
    /// Row-major, `width * height` texels.
    pub texels: Vec<Texel>,
}

impl EyeView {
    /// An all-miss G-buffer of `camera`'s size.
    pub fn new(camera: Pinhole) -> Self {
        let n = camera.width as usize * camera.height as usize;
        Self {
            camera,
            texels: vec![Texel::MISS; n],
        }
    }

    #[inline]
    pub fn width(&self) -> u32 {
        self.camera.width
    }

    #[inline]
    pub fn height(&self) -> u32 {
        self.camera.height
    }

    /// Pixels.
    #[inline]
    pub fn len(&self) -> usize {
        self.texels.len()
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.texels.is_empty()
    }
}
