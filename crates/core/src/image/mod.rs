//! Images: [`Image<T>`], layered G-buffers, PNG and EXR IO.

mod buffer;

pub use buffer::{Image, MAX_IMAGE_PIXELS, Rgb, check_size};
