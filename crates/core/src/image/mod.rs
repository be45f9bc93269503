//! Images: [`Image<T>`], layered G-buffers, PNG and EXR IO.

mod buffer;

pub use buffer::{Image, MAX_IMAGE_PIXELS, Rgb, check_size};
pub mod exr;
mod gbuffer;
pub mod png;

pub use self::exr::{ExrImage, read_exr, write_exr};
pub use gbuffer::{GBuffer, GSample, LayeredGBuffer, MAX_LAYERS, NO_ID};
