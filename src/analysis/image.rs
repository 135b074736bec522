//! Reading images to compare: single-band 16-bit (or 8-bit, or float) TIFF
//! and 16-/8-bit greyscale PNG here; multi-layer EXR and ENVI through
//! [`crate::output`]. Every reader returns an [`ImageStack`].
//!
//! Truth imagery from a camera usually holds digital numbers; a linear
//! calibration `value = gain·DN + offset` ([`Calibration`]) turns them into
//! kelvin or radiance before comparison.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use crate::output::{ImageStack, Layer};
use crate::{Error, Location, Result};

/// A linear calibration of stored values: `value = gain·stored + offset`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// Multiplier.
    pub gain: f64,
    /// Additive offset (after the gain).
    pub offset: f64,
}

impl Default for Calibration {
    fn default() -> Self {
        Calibration {
            gain: 1.0,
            offset: 0.0,
        }
    }
}

impl Calibration {
    /// Apply the calibration to every value of every layer of `stack`.
    pub fn apply(&self, stack: &mut ImageStack) {
        if *self == Calibration::default() {
            return;
        }
        for l in &mut stack.layers {
            for v in &mut l.data {
                *v = (self.gain * *v as f64 + self.offset) as f32;
            }
        }
    }
}

/// Image file formats that [`read_image`] understands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFormat {
    /// PNG, greyscale 8 or 16 bit.
    Png,
    /// TIFF, one band (8/16/32-bit integer or 32/64-bit float).
    Tiff,
    /// OpenEXR or ENVI (multi-layer), read by [`crate::output`].
    Stack,
}

impl ImageFormat {
    /// The format by file extension (case-insensitive).
    pub fn from_path(path: &Path) -> Option<ImageFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "png" => Some(ImageFormat::Png),
            "tif" | "tiff" => Some(ImageFormat::Tiff),
            "exr" | "hdr" | "img" => Some(ImageFormat::Stack),
            _ => None,
        }
    }
}

/// Read any supported image into a layer stack. Single-band files give one
/// layer named `value`.
pub fn read_image(path: impl AsRef<Path>) -> Result<ImageStack> {
    let path = path.as_ref();
    match ImageFormat::from_path(path) {
        Some(ImageFormat::Png) => read_png(path),
        Some(ImageFormat::Tiff) => read_tiff(path),
        Some(ImageFormat::Stack) => read_stack(path),
        None => Err(Error::parse(
            Location::file(path),
            "unknown image type: expected a .exr, ENVI (.hdr/.img), .tif/.tiff or .png file",
        )),
    }
}

fn read_stack(path: &Path) -> Result<ImageStack> {
    crate::output::read_image(path)
}

fn single(width: usize, height: usize, data: Vec<f32>) -> ImageStack {
    ImageStack {
        width,
        height,
        layers: vec![Layer {
            name: "value".into(),
            data,
        }],
    }
}

/// Read a greyscale PNG (8- or 16-bit, no palette, alpha ignored) as stored
/// digital numbers.
pub fn read_png(path: impl AsRef<Path>) -> Result<ImageStack> {
    let path = path.as_ref();
    let bad = |m: String| Error::parse(Location::file(path), m);
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    let mut decoder = png::Decoder::new(BufReader::new(file));
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder
        .read_info()
        .map_err(|e| bad(format!("not a readable PNG: {e}")))?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| bad("PNG too large to decode".into()))?;
    let mut buf = vec![0u8; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| bad(format!("PNG decoding failed: {e}")))?;
    let (w, h) = (info.width as usize, info.height as usize);
    let channels = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        other => {
            return Err(bad(format!(
                "expected a single-band greyscale PNG, found colour type {other:?}"
            )));
        }
    };
    let data: Vec<f32> = match info.bit_depth {
        png::BitDepth::Sixteen => buf[..info.buffer_size()]
            .chunks_exact(2 * channels)
            .map(|c| u16::from_be_bytes([c[0], c[1]]) as f32)
            .collect(),
        png::BitDepth::Eight => buf[..info.buffer_size()]
            .chunks_exact(channels)
            .map(|c| c[0] as f32)
            .collect(),
        other => {
            return Err(bad(format!(
                "expected an 8- or 16-bit PNG, found bit depth {other:?}"
            )));
        }
    };
    if data.len() != w * h {
        return Err(bad(format!(
            "decoded {} values for a {w}×{h} image",
            data.len()
        )));
    }
    Ok(single(w, h, data))
}

/// Read a single-band TIFF (8/16/32-bit unsigned or signed integer, 32/64-bit
/// float; uncompressed, LZW or Deflate).
pub fn read_tiff(path: impl AsRef<Path>) -> Result<ImageStack> {
    let path = path.as_ref();
    let bad = |m: String| Error::parse(Location::file(path), m);
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    let mut dec = tiff::decoder::Decoder::new(BufReader::new(file))
        .map_err(|e| bad(format!("not a readable TIFF: {e}")))?;
    let (w, h) = dec
        .dimensions()
        .map_err(|e| bad(format!("TIFF without dimensions: {e}")))?;
    match dec.colortype() {
        Ok(tiff::ColorType::Gray(_)) => {}
        Ok(other) => {
            return Err(bad(format!(
                "expected a single-band (greyscale) TIFF, found {other:?}"
            )));
        }
        Err(e) => return Err(bad(format!("unsupported TIFF layout: {e}"))),
    }
    use tiff::decoder::DecodingResult as D;
    let img = dec
        .read_image()
        .map_err(|e| bad(format!("TIFF decoding failed: {e}")))?;
    let data: Vec<f32> = match img {
        D::U8(v) => v.into_iter().map(|x| x as f32).collect(),
        D::U16(v) => v.into_iter().map(|x| x as f32).collect(),
        D::U32(v) => v.into_iter().map(|x| x as f32).collect(),
        D::I8(v) => v.into_iter().map(|x| x as f32).collect(),
        D::I16(v) => v.into_iter().map(|x| x as f32).collect(),
        D::I32(v) => v.into_iter().map(|x| x as f32).collect(),
        D::F32(v) => v,
        D::F64(v) => v.into_iter().map(|x| x as f32).collect(),
        other => {
            return Err(bad(format!(
                "unsupported TIFF sample type ({})",
                match other {
                    D::U64(_) => "64-bit unsigned",
                    D::I64(_) => "64-bit signed",
                    D::F16(_) => "16-bit float",
                    _ => "unknown",
                }
            )));
        }
    };
    let (w, h) = (w as usize, h as usize);
    if data.len() != w * h {
        return Err(bad(format!(
            "decoded {} values for a {w}×{h} single-band image",
            data.len()
        )));
    }
    Ok(single(w, h, data))
}
