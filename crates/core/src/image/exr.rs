//! OpenEXR IO with arbitrary named `f32` channels (linear values, no tonemap), through the
//! `exr` crate's `AnyChannels` API.
//!
//! Channel names follow the EXR layer convention (`"R"`, `"depth"`, `"normal.X"`,
//! `"albedo.R"`, ...). EXR stores channels sorted by name, so [`read_exr`] returns them in
//! alphabetical order whatever the order they were written in. Files are written as ZIP
//! scan lines (lossless). Reading takes the first valid layer at its largest resolution and
//! converts `f16`/`u32` samples to `f32`.

use std::path::Path;

use ::exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image as ExrFile, Layer, LayerAttributes,
    ReadChannels, ReadLayers, SmallVec, Text, WritableImage,
};

use super::buffer::check_size;
use crate::{CoreError, Result};

/// At most this many channels are written or read (keeps allocations bounded).
pub const MAX_EXR_CHANNELS: usize = 1024;

/// A decoded EXR layer: size and its channels as planar row-major `f32` data.
#[derive(Clone, Debug, PartialEq)]
pub struct ExrImage {
    pub width: u32,
    pub height: u32,
    /// `(name, width * height samples)`, sorted by name.
    pub channels: Vec<(String, Vec<f32>)>,
}

impl ExrImage {
    /// The samples of channel `name`, if present.
    pub fn channel(&self, name: &str) -> Option<&[f32]> {
        self.channels
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, d)| d.as_slice())
    }

    /// Channel names in file order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.channels.iter().map(|(n, _)| n.as_str())
    }
}

fn io_err(path: &Path, message: impl Into<String>) -> CoreError {
    CoreError::ImageIo {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

fn format_err(path: &Path, message: impl Into<String>) -> CoreError {
    CoreError::Format {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Writes a single-layer EXR with the given `f32` channels, each `width * height` samples in
/// row-major order. Errors (naming the path) on an invalid size, a wrong channel length, an
/// empty, duplicate or non-Latin-1 name, no channels, or a failed write.
pub fn write_exr(
    path: impl AsRef<Path>,
    width: u32,
    height: u32,
    channels: &[(&str, &[f32])],
) -> Result<()> {
    let path = path.as_ref();
    check_size(width, height)?;
    if channels.is_empty() || channels.len() > MAX_EXR_CHANNELS {
        return Err(format_err(path, "EXR needs 1..=1024 channels"));
    }
    let n = width as usize * height as usize;
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (i, (name, data)) in channels.iter().enumerate() {
        if name.is_empty() || name.len() > 255 {
            return Err(format_err(
                path,
                format!("channel name {name:?}: 1..=255 bytes"),
            ));
        }
        if channels[..i].iter().any(|(other, _)| other == name) {
            return Err(format_err(path, format!("duplicate channel {name:?}")));
        }
        if data.len() != n {
            return Err(format_err(
                path,
                format!(
                    "channel {name:?} has {} samples, expected {width}x{height} = {n}",
                    data.len()
                ),
            ));
        }
        let text = Text::new_or_none(name)
            .ok_or_else(|| format_err(path, format!("channel name {name:?} is not Latin-1")))?;
        list.push(AnyChannel::new(text, FlatSamples::F32(data.to_vec())));
    }
    let layer = Layer::new(
        (width as usize, height as usize),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    ExrFile::from_layer(layer)
        .write()
        .to_file(path)
        .map_err(|e| io_err(path, format!("writing EXR: {e}")))
}

/// Largest accepted ratio of decoded (2-byte) samples to file bytes in [`read_exr`].
pub const MAX_EXR_RATIO: u64 = 2048;

/// Reads the first valid layer of an EXR file. The header is checked before any pixel is
/// decoded: size (at most [`super::MAX_IMAGE_PIXELS`]), channel count, no deep data, and
/// no more samples than the file can hold at [`MAX_EXR_RATIO`] : 1.
pub fn read_exr(path: impl AsRef<Path>) -> Result<ExrImage> {
    let path = path.as_ref();
    let meta = ::exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| io_err(path, format!("reading EXR header: {e}")))?;
    let header = meta
        .headers
        .iter()
        .find(|h| !h.deep)
        .ok_or_else(|| format_err(path, "no flat (non-deep) layer"))?;
    let (w, h) = (header.layer_size.0, header.layer_size.1);
    let (width, height) = match (u32::try_from(w), u32::try_from(h)) {
        (Ok(w), Ok(h)) => (w, h),
        _ => return Err(format_err(path, format!("layer size {w}x{h} is too large"))),
    };
    check_size(width, height).map_err(|e| format_err(path, e.to_string()))?;
    let channel_count = header.channels.list.len();
    if channel_count == 0 || channel_count > MAX_EXR_CHANNELS {
        return Err(format_err(
            path,
            format!("{channel_count} channels (1..=1024 supported)"),
        ));
    }
    let total = width as u64 * height as u64 * channel_count as u64;
    if total > super::MAX_IMAGE_PIXELS {
        return Err(format_err(path, "channels * pixels exceeds 2^28 samples"));
    }
    // A decompression-bomb guard (found by parallax-fuzz: a 493-byte file whose header asks
    // for 2^28 samples made the decoder allocate 2 GiB before reading a pixel): EXR's
    // codecs stay far below MAX_EXR_RATIO : 1 (zlib's own limit is 1032 : 1), so a header
    // that needs more samples than the file can hold at that ratio is rejected first.
    let file_len = std::fs::metadata(path)
        .map_err(|e| io_err(path, format!("reading EXR: {e}")))?
        .len();
    if total * 2 > file_len.saturating_mul(MAX_EXR_RATIO) {
        return Err(format_err(
            path,
            format!(
                "header claims {w}x{h} x {channel_count} channels but the file has {file_len} bytes (over {MAX_EXR_RATIO}:1): truncated or malformed"
            ),
        ));
    }

    let image = ::exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| io_err(path, format!("reading EXR: {e}")))?;
    let layer = image.layer_data;
    let (lw, lh) = (layer.size.0, layer.size.1);
    if lw != w || lh != h {
        return Err(format_err(path, "layer size differs from the header"));
    }
    let n = w * h;
    let mut channels = Vec::with_capacity(layer.channel_data.list.len());
    for ch in &layer.channel_data.list {
        let name = ch.name.to_string();
        let data: Vec<f32> = match &ch.sample_data {
            FlatSamples::F32(v) => v.clone(),
            other => other.values_as_f32().collect(),
        };
        if data.len() != n {
            return Err(format_err(path, format!("channel {name:?} is subsampled")));
        }
        channels.push((name, data));
    }
    Ok(ExrImage {
        width,
        height,
        channels,
    })
}
