//! PNG quick-look of an apparent-temperature layer: the image through the
//! *inferno* colour map (perceptually uniform, monotonic lightness; van der
//! Walt & Smith, matplotlib 1.5, 2015), with a scale bar under it labelled
//! in kelvin. Digits are drawn with an embedded 3×5 bitmap font, so no font
//! file is needed. NaN / infinite pixels are drawn mid-grey.
//!
//! Layout: the image at the top-left of a canvas at least
//! [`MIN_CANVAS_WIDTH`] pixels wide; below it a [`BAR_AREA_HEIGHT`]-pixel
//! strip with a horizontal colour ramp from the lowest to the highest
//! temperature, tick marks at both ends and the middle, and their values
//! (`287.3 K`) printed under the ticks.

use std::path::Path;

use super::atomic::write_atomic;
use crate::{Error, Result};

/// Smallest canvas width, so the scale bar labels fit under tiny images.
pub const MIN_CANVAS_WIDTH: usize = 200;
/// Height of the scale-bar strip under the image, pixels.
pub const BAR_AREA_HEIGHT: usize = 40;
const MARGIN: usize = 8;
const BAR_TOP: usize = 6;
const BAR_HEIGHT: usize = 12;
const TEXT_TOP: usize = BAR_TOP + BAR_HEIGHT + 6;
const FONT_SCALE: usize = 2;
const GLYPH_ADVANCE: usize = 4 * FONT_SCALE;
const BACKGROUND: [u8; 3] = [32, 32, 32];
const FOREGROUND: [u8; 3] = [235, 235, 235];
const NAN_COLOUR: [u8; 3] = [128, 128, 128];

/// The *inferno* colour map at `t ∈ [0, 1]` (clamped), as 8-bit sRGB.
/// Sixth-order polynomial fit of matplotlib's table (Matt Zucconi, 2019,
/// public domain); within about 5/255 of the table.
pub fn inferno(t: f32) -> [u8; 3] {
    const C: [[f64; 3]; 7] = [
        [
            0.000_218_940_369_119_226_5,
            0.001_651_004_631_001_012,
            -0.019_480_898_437_091_84,
        ],
        [
            0.106_513_419_485_611_6,
            0.563_956_436_788_409_1,
            3.932_712_388_889_277,
        ],
        [
            11.602_493_082_471_87,
            -3.972_853_965_665_698,
            -15.942_394_106_291_4,
        ],
        [
            -41.703_996_131_394_59,
            17.436_398_882_053_13,
            44.354_145_198_728_13,
        ],
        [
            77.162_935_699_427,
            -33.402_358_942_100_92,
            -81.807_309_257_389_93,
        ],
        [
            -71.319_428_244_992_14,
            32.626_064_263_977_23,
            73.209_519_858_032_02,
        ],
        [
            25.131_126_224_773_41,
            -12.242_668_952_385_67,
            -23.070_325_002_871_72,
        ],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0) as f64
    } else {
        0.0
    };
    let mut out = [0u8; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let v = C.iter().rev().fold(0.0, |acc, c| acc * t + c[k]);
        *o = (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    }
    out
}

/// 3×5 glyphs, one row per byte, bit 2 = left column.
fn glyph(c: char) -> Option<[u8; 5]> {
    Some(match c {
        '0' => [0b111, 0b101, 0b101, 0b101, 0b111],
        '1' => [0b010, 0b110, 0b010, 0b010, 0b111],
        '2' => [0b111, 0b001, 0b111, 0b100, 0b111],
        '3' => [0b111, 0b001, 0b111, 0b001, 0b111],
        '4' => [0b101, 0b101, 0b111, 0b001, 0b001],
        '5' => [0b111, 0b100, 0b111, 0b001, 0b111],
        '6' => [0b111, 0b100, 0b111, 0b101, 0b111],
        '7' => [0b111, 0b001, 0b001, 0b001, 0b001],
        '8' => [0b111, 0b101, 0b111, 0b101, 0b111],
        '9' => [0b111, 0b101, 0b111, 0b001, 0b111],
        '.' => [0b000, 0b000, 0b000, 0b000, 0b010],
        '-' => [0b000, 0b000, 0b111, 0b000, 0b000],
        'K' => [0b101, 0b101, 0b110, 0b101, 0b101],
        ' ' => [0; 5],
        _ => return None,
    })
}

/// An 8-bit RGB raster, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbImage {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// `3 · width · height` bytes, RGB.
    pub pixels: Vec<u8>,
}

impl RgbImage {
    fn new(width: usize, height: usize, fill: [u8; 3]) -> Self {
        RgbImage {
            width,
            height,
            pixels: fill.repeat(width * height),
        }
    }
    /// Colour at `(x, y)`.
    pub fn get(&self, x: usize, y: usize) -> [u8; 3] {
        let i = 3 * (y * self.width + x);
        [self.pixels[i], self.pixels[i + 1], self.pixels[i + 2]]
    }
    fn set(&mut self, x: usize, y: usize, c: [u8; 3]) {
        if x < self.width && y < self.height {
            let i = 3 * (y * self.width + x);
            self.pixels[i..i + 3].copy_from_slice(&c);
        }
    }
    fn text(&mut self, x0: usize, y0: usize, s: &str, c: [u8; 3]) {
        for (k, ch) in s.chars().enumerate() {
            let Some(g) = glyph(ch) else { continue };
            for (row, bits) in g.iter().enumerate() {
                for col in 0..3 {
                    if bits & (0b100 >> col) != 0 {
                        for dy in 0..FONT_SCALE {
                            for dx in 0..FONT_SCALE {
                                self.set(
                                    x0 + k * GLYPH_ADVANCE + col * FONT_SCALE + dx,
                                    y0 + row * FONT_SCALE + dy,
                                    c,
                                );
                            }
                        }
                    }
                }
            }
        }
    }
}

fn text_width(s: &str) -> usize {
    s.chars().count() * GLYPH_ADVANCE - FONT_SCALE
}

/// The temperature range of the finite values of `t`, widened to at least
/// 1 K around its centre (a flat image still gets a readable bar).
pub fn auto_range(t: &[f32]) -> (f32, f32) {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for &v in t.iter().filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1.0 {
        let c = 0.5 * (lo + hi);
        return (c - 0.5, c + 0.5);
    }
    (lo, hi)
}

/// Draw the quick-look of a `width × height` temperature image (K) mapped
/// over `range_k` (default: [`auto_range`]).
pub fn render_quicklook(
    width: usize,
    height: usize,
    temperature_k: &[f32],
    range_k: Option<(f32, f32)>,
) -> Result<RgbImage> {
    if temperature_k.len() != width * height || width == 0 || height == 0 {
        return Err(Error::invalid(
            "quick-look",
            format!(
                "{} values for a {width}×{height} image: expected width·height > 0",
                temperature_k.len()
            ),
        ));
    }
    let (lo, hi) = range_k.unwrap_or_else(|| auto_range(temperature_k));
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Err(Error::invalid(
            "quick-look range",
            format!("[{lo}, {hi}] K: expected finite bounds with max > min"),
        ));
    }
    let cw = width.max(MIN_CANVAS_WIDTH);
    let mut img = RgbImage::new(cw, height + BAR_AREA_HEIGHT, BACKGROUND);
    for y in 0..height {
        for x in 0..width {
            let v = temperature_k[y * width + x];
            let c = if v.is_finite() {
                inferno((v - lo) / (hi - lo))
            } else {
                NAN_COLOUR
            };
            img.set(x, y, c);
        }
    }
    // Colour ramp.
    let (x0, x1) = (MARGIN, cw - MARGIN - 1);
    let top = height + BAR_TOP;
    for x in x0..=x1 {
        let c = inferno((x - x0) as f32 / (x1 - x0) as f32);
        for y in top..top + BAR_HEIGHT {
            img.set(x, y, c);
        }
    }
    // Ticks and labels at min, middle, max.
    let label = |v: f32| format!("{v:.1} K");
    let mid = 0.5 * (lo + hi);
    let xm = (x0 + x1) / 2;
    let ty = height + TEXT_TOP;
    for x in [x0, xm, x1] {
        for y in top + BAR_HEIGHT..top + BAR_HEIGHT + 4 {
            img.set(x, y, FOREGROUND);
        }
    }
    let (ll, lm, lh) = (label(lo), label(mid), label(hi));
    img.text(x0, ty, &ll, FOREGROUND);
    let hx = (x1 + 1).saturating_sub(text_width(&lh));
    img.text(hx, ty, &lh, FOREGROUND);
    let mx = xm.saturating_sub(text_width(&lm) / 2);
    if mx > x0 + text_width(&ll) + GLYPH_ADVANCE && mx + text_width(&lm) + GLYPH_ADVANCE < hx {
        img.text(mx, ty, &lm, FOREGROUND);
    }
    Ok(img)
}

/// Write the quick-look PNG of a temperature image (see [`render_quicklook`])
/// atomically. Returns the temperature range used, K.
pub fn write_quicklook_png(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    temperature_k: &[f32],
    range_k: Option<(f32, f32)>,
) -> Result<(f32, f32)> {
    let path = path.as_ref();
    let range = range_k.unwrap_or_else(|| auto_range(temperature_k));
    let img = render_quicklook(width, height, temperature_k, Some(range))?;
    write_atomic(path, |w| {
        let png_err =
            |e: png::EncodingError| Error::Other(format!("{}: writing PNG: {e}", path.display()));
        let mut enc = png::Encoder::new(w, img.width as u32, img.height as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        let mut writer = enc.write_header().map_err(png_err)?;
        writer.write_image_data(&img.pixels).map_err(png_err)?;
        writer.finish().map_err(png_err)
    })?;
    Ok(range)
}
