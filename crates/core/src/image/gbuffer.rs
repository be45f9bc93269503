//! G-buffers: per-pixel surface attributes of one view, stored as planar channels
//! (structure of arrays), and stacks of them for k depth layers (depth peeling, Everitt 2001).

use glam::{Vec2, Vec3};

use super::buffer::{Image, check_size};
use crate::{CoreError, Result};

/// Id value meaning "no material / no primitive".
pub const NO_ID: u32 = u32::MAX;

/// The attributes of one G-buffer pixel, gathered from the planar channels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GSample {
    /// View depth: positive distance along the view axis; `+inf` for a miss.
    pub depth: f32,
    /// World-space position.
    pub position: Vec3,
    /// World-space shading normal (unit length).
    pub normal: Vec3,
    /// Linear RGB albedo.
    pub albedo: Vec3,
    /// Material id, [`NO_ID`] if none.
    pub material_id: u32,
    /// Primitive (triangle) id, [`NO_ID`] if none.
    pub primitive_id: u32,
    /// Barycentrics `(b1, b2)` of the hit on the primitive (`b0 = 1 - b1 - b2`).
    pub barycentrics: Vec2,
}

impl GSample {
    /// The value of a pixel that saw no surface.
    pub const MISS: Self = Self {
        depth: f32::INFINITY,
        position: Vec3::ZERO,
        normal: Vec3::ZERO,
        albedo: Vec3::ZERO,
        material_id: NO_ID,
        primitive_id: NO_ID,
        barycentrics: Vec2::ZERO,
    };

    /// True when this sample holds a surface (finite depth).
    #[inline]
    pub fn is_hit(&self) -> bool {
        self.depth.is_finite()
    }
}

/// A G-buffer of one view: one flat row-major `Vec` per channel (structure of arrays,
/// index `y * width + x`). A miss has `depth = +inf` and ids [`NO_ID`].
///
/// **Invariant:** every channel holds exactly `width * height` values; the fields are public
/// for direct slice access by rasterizers and tracers, which must not resize them.
#[derive(Clone, Debug, PartialEq)]
pub struct GBuffer {
    width: u32,
    height: u32,
    pub depth: Vec<f32>,
    pub position: Vec<Vec3>,
    pub normal: Vec<Vec3>,
    pub albedo: Vec<Vec3>,
    pub material_id: Vec<u32>,
    pub primitive_id: Vec<u32>,
    pub barycentrics: Vec<Vec2>,
}

impl GBuffer {
    /// An empty (all-miss) G-buffer. Errors on a zero or too large size.
    pub fn new(width: u32, height: u32) -> Result<Self> {
        check_size(width, height)?;
        let n = width as usize * height as usize;
        Ok(Self {
            width,
            height,
            depth: vec![f32::INFINITY; n],
            position: vec![Vec3::ZERO; n],
            normal: vec![Vec3::ZERO; n],
            albedo: vec![Vec3::ZERO; n],
            material_id: vec![NO_ID; n],
            primitive_id: vec![NO_ID; n],
            barycentrics: vec![Vec2::ZERO; n],
        })
    }

    #[inline]
    pub fn width(&self) -> u32 {
        self.width
    }

    #[inline]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Number of pixels.
    #[inline]
    pub fn len(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Always false: sizes are at least 1x1.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Row-major index of pixel `(x, y)`.
    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        debug_assert!(x < self.width && y < self.height);
        y as usize * self.width as usize + x as usize
    }

    /// True when pixel `(x, y)` saw a surface (finite depth).
    #[inline]
    pub fn is_hit(&self, x: u32, y: u32) -> bool {
        self.depth[self.index(x, y)].is_finite()
    }

    /// All attributes of pixel `(x, y)`.
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> GSample {
        self.sample_at(self.index(x, y))
    }

    /// All attributes of the pixel with row-major index `i`.
    #[inline]
    pub fn sample_at(&self, i: usize) -> GSample {
        GSample {
            depth: self.depth[i],
            position: self.position[i],
            normal: self.normal[i],
            albedo: self.albedo[i],
            material_id: self.material_id[i],
            primitive_id: self.primitive_id[i],
            barycentrics: self.barycentrics[i],
        }
    }

    /// Writes all attributes of pixel `(x, y)`.
    #[inline]
    pub fn set(&mut self, x: u32, y: u32, s: GSample) {
        let i = self.index(x, y);
        self.set_at(i, s);
    }

    /// Writes all attributes of the pixel with row-major index `i`.
    #[inline]
    pub fn set_at(&mut self, i: usize, s: GSample) {
        self.depth[i] = s.depth;
        self.position[i] = s.position;
        self.normal[i] = s.normal;
        self.albedo[i] = s.albedo;
        self.material_id[i] = s.material_id;
        self.primitive_id[i] = s.primitive_id;
        self.barycentrics[i] = s.barycentrics;
    }

    /// A copy of the depth channel as an [`Image`] (e.g. for [`super::png::write_depth_png`]);
    /// errors only if a caller broke the channel-length invariant.
    pub fn depth_image(&self) -> Result<Image<f32>> {
        Image::from_vec(self.width, self.height, self.depth.clone())
    }

    /// Resets every pixel to a miss, keeping the allocation.
    pub fn clear(&mut self) {
        self.depth.fill(f32::INFINITY);
        self.position.fill(Vec3::ZERO);
        self.normal.fill(Vec3::ZERO);
        self.albedo.fill(Vec3::ZERO);
        self.material_id.fill(NO_ID);
        self.primitive_id.fill(NO_ID);
        self.barycentrics.fill(Vec2::ZERO);
    }

    /// Number of pixels that saw a surface.
    pub fn hit_count(&self) -> usize {
        self.depth.iter().filter(|d| d.is_finite()).count()
    }

    /// Bytes held by the channel data (not counting the struct itself).
    pub fn bytes(&self) -> usize {
        Self::bytes_per_pixel() * self.len()
    }

    /// Bytes per pixel over all channels (4 + 3·12 + 2·4 + 8 = 56).
    pub const fn bytes_per_pixel() -> usize {
        size_of::<f32>() + 3 * size_of::<Vec3>() + 2 * size_of::<u32>() + size_of::<Vec2>()
    }

    /// Writes all channels to a linear EXR (see [`crate::image::exr`]): `depth`,
    /// `P.X/Y/Z`, `N.X/Y/Z`, `albedo.R/G/B`, `materialId`, `primitiveId` (ids as f32, exact
    /// below 2^24; [`NO_ID`] is written as -1) and `bary.U/V`.
    pub fn write_exr(&self, path: impl AsRef<std::path::Path>) -> Result<()> {
        let split3 = |d: &[Vec3]| -> [Vec<f32>; 3] {
            [
                d.iter().map(|v| v.x).collect(),
                d.iter().map(|v| v.y).collect(),
                d.iter().map(|v| v.z).collect(),
            ]
        };
        let id = |d: &[u32]| -> Vec<f32> {
            let f = |&v: &u32| if v == NO_ID { -1.0 } else { v as f32 };
            d.iter().map(f).collect()
        };
        let [px, py, pz] = split3(&self.position);
        let [nx, ny, nz] = split3(&self.normal);
        let [ar, ag, ab] = split3(&self.albedo);
        let mat = id(&self.material_id);
        let prim = id(&self.primitive_id);
        let bu: Vec<f32> = self.barycentrics.iter().map(|b| b.x).collect();
        let bv: Vec<f32> = self.barycentrics.iter().map(|b| b.y).collect();
        super::exr::write_exr(
            path,
            self.width(),
            self.height(),
            &[
                ("depth", &self.depth),
                ("P.X", &px),
                ("P.Y", &py),
                ("P.Z", &pz),
                ("N.X", &nx),
                ("N.Y", &ny),
                ("N.Z", &nz),
                ("albedo.R", &ar),
                ("albedo.G", &ag),
                ("albedo.B", &ab),
                ("materialId", &mat),
                ("primitiveId", &prim),
                ("bary.U", &bu),
                ("bary.V", &bv),
            ],
        )
    }
}

/// The largest number of layers a [`LayeredGBuffer`] accepts.
pub const MAX_LAYERS: usize = 64;

/// `k` G-buffers of the same view, layer 0 nearest (filled by depth peeling: layer `i`
/// holds, per pixel, the `i`-th surface along the view ray).
#[derive(Clone, Debug, PartialEq)]
pub struct LayeredGBuffer {
    pub layers: Vec<GBuffer>,
}

impl LayeredGBuffer {
    /// `k` empty layers of `width x height`. Errors when `k` is 0 or above [`MAX_LAYERS`], or
    /// when the total pixel count exceeds [`super::MAX_IMAGE_PIXELS`].
    pub fn new(width: u32, height: u32, k: usize) -> Result<Self> {
        check_size(width, height)?;
        let total = width as u64 * height as u64 * k as u64;
        if k == 0 || k > MAX_LAYERS || total > super::MAX_IMAGE_PIXELS {
            return Err(CoreError::InvalidSize {
                width: width as u64,
                height: height as u64,
                reason: "layer count must be 1..=64 and layers * pixels at most 2^28",
            });
        }
        let layers = (0..k)
            .map(|_| GBuffer::new(width, height))
            .collect::<Result<Vec<_>>>()?;
        Ok(Self { layers })
    }

    /// Number of layers.
    #[inline]
    pub fn len(&self) -> usize {
        self.layers.len()
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.layers.is_empty()
    }

    #[inline]
    pub fn width(&self) -> u32 {
        self.layers.first().map_or(0, GBuffer::width)
    }

    #[inline]
    pub fn height(&self) -> u32 {
        self.layers.first().map_or(0, GBuffer::height)
    }

    /// Layer `i` (0 = nearest).
    #[inline]
    pub fn layer(&self, i: usize) -> &GBuffer {
        &self.layers[i]
    }

    #[inline]
    pub fn layer_mut(&mut self, i: usize) -> &mut GBuffer {
        &mut self.layers[i]
    }

    /// Number of layers holding a surface at pixel `(x, y)`.
    pub fn depth_complexity(&self, x: u32, y: u32) -> usize {
        self.layers.iter().filter(|l| l.is_hit(x, y)).count()
    }

    /// Resets every layer to misses.
    pub fn clear(&mut self) {
        self.layers.iter_mut().for_each(GBuffer::clear);
    }

    /// Bytes held by all layers' channel data.
    pub fn bytes(&self) -> usize {
        self.layers.iter().map(GBuffer::bytes).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn new_is_all_miss_and_set_get_round_trips() {
        let mut g = GBuffer::new(4, 3).unwrap();
        assert_eq!((g.width(), g.height(), g.len()), (4, 3, 12));
        assert_eq!(g.hit_count(), 0);
        assert!(!g.is_hit(3, 2));
        assert_eq!(g.get(1, 1), GSample::MISS);
        let s = GSample {
            depth: 2.5,
            position: Vec3::new(1.0, 2.0, -2.5),
            normal: Vec3::Z,
            albedo: Vec3::splat(0.5),
            material_id: 3,
            primitive_id: 77,
            barycentrics: Vec2::new(0.25, 0.5),
        };
        g.set(3, 2, s);
        assert!(g.is_hit(3, 2) && !g.is_hit(2, 2));
        assert_eq!(g.get(3, 2), s);
        assert_eq!(g.primitive_id[g.index(3, 2)], 77);
        assert_eq!(g.depth_image().unwrap().get(3, 2), &2.5);
        assert_eq!(g.hit_count(), 1);
        g.clear();
        assert_eq!(g.hit_count(), 0);
        assert_eq!(g.get(3, 2), GSample::MISS);
    }

    #[test]
    fn bytes_counts_all_channels() {
        let g = GBuffer::new(10, 10).unwrap();
        assert_eq!(GBuffer::bytes_per_pixel(), 56);
        assert_eq!(g.bytes(), 5600);
        let l = LayeredGBuffer::new(10, 10, 4).unwrap();
        assert_eq!(l.bytes(), 4 * 5600);
        assert_eq!((l.len(), l.width(), l.height()), (4, 10, 10));
    }

    #[test]
    fn layered_rejects_bad_sizes() {
        assert!(LayeredGBuffer::new(10, 10, 0).is_err());
        assert!(LayeredGBuffer::new(10, 10, MAX_LAYERS + 1).is_err());
        assert!(LayeredGBuffer::new(16384, 16384, 2).is_err());
        assert!(GBuffer::new(0, 5).is_err());
    }

    #[test]
    fn depth_complexity_counts_hit_layers() {
        let mut l = LayeredGBuffer::new(2, 2, 3).unwrap();
        let hit = GSample {
            depth: 1.0,
            ..GSample::MISS
        };
        l.layer_mut(0).set(1, 0, hit);
        l.layer_mut(1).set(1, 0, GSample { depth: 2.0, ..hit });
        assert_eq!(l.depth_complexity(1, 0), 2);
        assert_eq!(l.depth_complexity(0, 0), 0);
    }
}
