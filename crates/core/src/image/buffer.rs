//! The image container.

use glam::Vec3;

use crate::{CoreError, Result};

/// Linear-light RGB.
pub type Rgb = Vec3;

/// The largest image parallax allocates: 2^28 pixels (16384 x 16384). Larger requests are
/// rejected up front instead of failing inside an allocation.
pub const MAX_IMAGE_PIXELS: u64 = 1 << 28;

/// A row-major 2-D image; pixel `(x, y)` has its centre at `(x + 0.5, y + 0.5)` and `y` grows
/// downward.
#[derive(Clone, Debug, PartialEq)]
pub struct Image<T> {
    width: u32,
    height: u32,
    data: Vec<T>,
}

impl<T: Clone> Image<T> {
    /// A `width x height` image filled with `value`. Errors on a zero or absurd size.
    pub fn new(width: u32, height: u32, value: T) -> Result<Self> {
        check_size(width, height)?;
        Ok(Self {
            width,
            height,
            data: vec![value; width as usize * height as usize],
        })
    }
}

impl<T> Image<T> {
    /// Wraps row-major data; errors when the length does not match or the size is invalid.
    pub fn from_vec(width: u32, height: u32, data: Vec<T>) -> Result<Self> {
        check_size(width, height)?;
        if data.len() != width as usize * height as usize {
            return Err(CoreError::InvalidSize {
                width: width as u64,
                height: height as u64,
                reason: "data length does not match width * height",
            });
        }
        Ok(Self {
            width,
            height,
            data,
        })
    }

    /// Builds an image by calling `f(x, y)` for every pixel.
    pub fn from_fn(width: u32, height: u32, mut f: impl FnMut(u32, u32) -> T) -> Result<Self> {
        check_size(width, height)?;
        let mut data = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height {
            for x in 0..width {
                data.push(f(x, y));
            }
        }
        Ok(Self {
            width,
            height,
            data,
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
    #[inline]
    pub fn len(&self) -> usize {
        self.data.len()
    }
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        debug_assert!(x < self.width && y < self.height);
        y as usize * self.width as usize + x as usize
    }
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> &T {
        &self.data[self.index(x, y)]
    }
    #[inline]
    pub fn get_mut(&mut self, x: u32, y: u32) -> &mut T {
        let i = self.index(x, y);
        &mut self.data[i]
    }
    #[inline]
    pub fn set(&mut self, x: u32, y: u32, v: T) {
        let i = self.index(x, y);
        self.data[i] = v;
    }
    #[inline]
    pub fn data(&self) -> &[T] {
        &self.data
    }
    #[inline]
    pub fn data_mut(&mut self) -> &mut [T] {
        &mut self.data
    }
    pub fn into_vec(self) -> Vec<T> {
        self.data
    }
    /// Rows as mutable slices (for splitting work over threads).
    pub fn rows_mut(&mut self) -> std::slice::ChunksExactMut<'_, T> {
        self.data.chunks_exact_mut(self.width as usize)
    }
    /// A new image with `f` applied to every pixel.
    pub fn map<U>(&self, f: impl FnMut(&T) -> U) -> Image<U> {
        Image {
            width: self.width,
            height: self.height,
            data: self.data.iter().map(f).collect(),
        }
    }
}

/// Validates an image size: non-zero and at most [`MAX_IMAGE_PIXELS`].
pub fn check_size(width: u32, height: u32) -> Result<()> {
    let (w, h) = (width as u64, height as u64);
    if w == 0 || h == 0 {
        return Err(CoreError::InvalidSize {
            width: w,
            height: h,
            reason: "width and height must be at least 1",
        });
    }
    if w * h > MAX_IMAGE_PIXELS {
        return Err(CoreError::InvalidSize {
            width: w,
            height: h,
            reason: "more than 2^28 pixels (16384 x 16384)",
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_zero_and_absurd_sizes() {
        assert!(Image::new(0, 10, 0u8).is_err());
        assert!(Image::new(10, 0, 0u8).is_err());
        assert!(Image::new(1 << 20, 1 << 20, 0u8).is_err());
        let img = Image::from_fn(3, 2, |x, y| x + 10 * y).unwrap();
        assert_eq!(*img.get(2, 1), 12);
        assert!(Image::from_vec(2, 2, vec![0; 3]).is_err());
    }
}
