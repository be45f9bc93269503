//! Decoding base-colour textures (PNG, JPEG) into linear [`Texture`]s.

use std::io::Cursor;

use glam::Vec3;

use crate::texture::srgb_to_linear;
use crate::{Texture, WrapMode};

/// Largest texture side accepted (a bigger image is a decoding error, not an allocation).
pub(crate) const MAX_TEXTURE_SIDE: u32 = 8192;

/// Most texels all textures of one scene may hold together (12 bytes each once decoded): a
/// small, highly compressed image can declare a large size, so the total is bounded too.
pub(crate) const MAX_SCENE_TEXELS: u64 = 1 << 27;

/// Decodes an encoded image (format guessed from its bytes) into a linear-light texture,
/// charging its texels to `budget` (an error once [`MAX_SCENE_TEXELS`] is exceeded).
/// The 8-bit sRGB values are linearised through a 256-entry table.
pub(crate) fn decode_texture(
    bytes: &[u8],
    name: &str,
    wrap_s: WrapMode,
    wrap_t: WrapMode,
    budget: &mut u64,
) -> Result<Texture, String> {
    let mut reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot read image {name:?}: {e}"))?;
    let mut limits = image::Limits::default(); // max_alloc 512 MiB
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    reader.limits(limits);
    let img = reader
        .decode()
        .map_err(|e| format!("cannot decode image {name:?}: {e}"))?
        .to_rgb8();
    let (width, height) = img.dimensions();
    if width == 0 || height == 0 {
        return Err(format!("image {name:?} is empty"));
    }
    *budget += width as u64 * height as u64;
    if *budget > MAX_SCENE_TEXELS {
        return Err(format!(
            "image {name:?}: the scene's textures exceed {MAX_SCENE_TEXELS} texels"
        ));
    }
    let lut: Vec<f32> = (0..256).map(|v| srgb_to_linear(v as f32 / 255.0)).collect();
    let texels = img
        .pixels()
        .map(|p| Vec3::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]))
        .collect();
    Ok(Texture {
        name: name.to_string(),
        width,
        height,
        texels,
        wrap_s,
        wrap_t,
    })
}
