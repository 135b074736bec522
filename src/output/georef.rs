//! The georeference of an image grid ([`Georef`]): a map coordinate system
//! and the affine map from pixel to map coordinates; its ENVI header lines
//! ([`Georef::envi_lines`]) and the GeoTIFF writer ([`write_geotiff`]).
//!
//! Pixel coordinates are continuous, `(column, row)`, with `(0, 0)` the
//! upper-left *corner* of the first pixel (pixel centres at `+½`): GDAL's
//! geotransform convention, GeoTIFF's `PixelIsArea` raster space, and
//! ENVI's `map info` tie point at pixel `(1, 1)` (1-based, its upper-left
//! corner). Map coordinates are easting, northing in metres.
//!
//! Takes a georeference worked out elsewhere (the sensor and the site, see
//! `sensor::georef`); gives header text and files. Knows nothing of
//! sensors or scenes.

use std::path::Path;

use tiff::encoder::TiffEncoder;
use tiff::tags::Tag;

use super::ImageStack;
use super::atomic::write_atomic;
use crate::geodesy::UtmZone;
use crate::{Error, Result};

/// The map coordinate system of a [`Georef`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MapSystem {
    /// WGS 84 / UTM (EPSG 326zz north, 327zz south), metres.
    Utm(UtmZone),
    /// The scene's own east-north-up plane, metres from the site (used
    /// where UTM does not reach: beyond 84°N and 80°S).
    LocalEnu {
        /// Site latitude, degrees.
        latitude_deg: f64,
        /// Site longitude, degrees.
        longitude_deg: f64,
    },
}

/// Largest shift (pixels) at an image corner between its affine transform
/// and the grid written as ENVI `map info` ([`Georef::envi_rotation`]).
pub const ROTATION_TOLERANCE_PX: f64 = 0.01;

/// Pixel → map affine transform of an image and its map system.
#[derive(Debug, Clone, PartialEq)]
pub struct Georef {
    /// The map coordinate system.
    pub system: MapSystem,
    /// GDAL-order geotransform: `X = t[0] + t[1]·col + t[2]·row`,
    /// `Y = t[3] + t[4]·col + t[5]·row` (map metres; pixel corner
    /// coordinates, see the module docs).
    pub transform: [f64; 6],
    /// Largest distance between the affine transform and the exact
    /// projection over the image, pixels (what the transform is good to).
    pub max_error_px: f64,
    /// Image size `(width, height)`, pixels.
    pub size: (usize, usize),
    /// Free text for the headers (what surface the grid refers to, the
    /// image orientation).
    pub note: String,
}

impl Georef {
    /// Map coordinates of continuous pixel point `(col, row)`.
    pub fn map_of_pixel(&self, col: f64, row: f64) -> (f64, f64) {
        let t = &self.transform;
        (
            t[0] + t[1] * col + t[2] * row,
            t[3] + t[4] * col + t[5] * row,
        )
    }

    /// Continuous pixel coordinates `(col, row)` of map point `(x, y)`, or
    /// `None` for a singular transform.
    pub fn pixel_of_map(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let t = &self.transform;
        let det = t[1] * t[5] - t[2] * t[4];
        if det.abs() < 1e-300 || !det.is_finite() {
            return None;
        }
        let (dx, dy) = (x - t[0], y - t[3]);
        Some(((t[5] * dx - t[2] * dy) / det, (t[1] * dy - t[4] * dx) / det))
    }

    /// The ENVI `map info` of the grid, if it can state it: pixel sizes
    /// `(x, y)` (m) and the rotation θ (degrees, counter-clockwise).
    ///
    /// GDAL's ENVI driver (checked with `gdalinfo`, GDAL 3.6) reads
    /// `rotation=θ` with pixel sizes `x`, `y` as the geotransform
    /// `[x cos θ, x sin θ; y sin θ, −y cos θ]`: the rotation applied before
    /// the scaling, which for pixels that are not square is not a turned
    /// grid. So map info is given only where that reading and the turned
    /// grid (column step `x·(cos θ, sin θ)`, row step `y·(sin θ, −cos θ)`)
    /// both put every image corner within [`ROTATION_TOLERANCE_PX`] of this
    /// transform: a north-up grid (θ = 0) of any pixel shape, or a turned
    /// grid of square pixels. `None` otherwise (skewed or mirrored grids,
    /// turned grids of oblong pixels): the GeoTIFF states those exactly.
    pub fn envi_rotation(&self) -> Option<(f64, f64, f64)> {
        let t = &self.transform;
        let px = t[1].hypot(t[4]);
        let py = t[2].hypot(t[5]);
        if !(px > 0.0 && py > 0.0) {
            return None;
        }
        let theta = t[4].atan2(t[1]);
        let (s, c) = theta.sin_cos();
        let (w, h) = (self.size.0.max(1) as f64, self.size.1.max(1) as f64);
        // Largest corner shift (pixels) of a model [t1, t2, t4, t5].
        let shift = |m: [f64; 4]| {
            let d = [t[1] - m[0], t[2] - m[1], t[4] - m[2], t[5] - m[3]];
            [(w, 0.0), (0.0, h), (w, h)]
                .iter()
                .map(|&(u, v)| (d[0] * u + d[1] * v).hypot(d[2] * u + d[3] * v))
                .fold(0.0f64, f64::max)
                / px.min(py)
        };
        let turned = shift([px * c, py * s, px * s, -py * c]);
        let gdal = shift([px * c, px * s, py * s, -py * c]);
        if turned.is_nan()
            || gdal.is_nan()
            || turned > ROTATION_TOLERANCE_PX
            || gdal > ROTATION_TOLERANCE_PX
        {
            return None;
        }
        Some((px, py, theta.to_degrees()))
    }

    /// The header lines for ENVI: `map info` (and `coordinate system
    /// string` for UTM) where the grid is a rotation of the map axes;
    /// otherwise a comment giving the geotransform. Comment lines (`;`)
    /// state the note and the accuracy.
    pub fn envi_lines(&self) -> String {
        let mut s = String::new();
        let t = &self.transform;
        match self.envi_rotation() {
            Some((px, py, rot)) => {
                let rotation = if rot.abs() < 1e-9 {
                    String::new()
                } else {
                    format!(", rotation={}", fmt_num(rot))
                };
                match self.system {
                    MapSystem::Utm(z) => {
                        s.push_str(&format!(
                            "map info = {{UTM, 1, 1, {}, {}, {}, {}, {}, {}, WGS-84, units=Meters{rotation}}}\n",
                            fmt_num(t[0]),
                            fmt_num(t[3]),
                            fmt_num(px),
                            fmt_num(py),
                            z.number,
                            if z.north { "North" } else { "South" }
                        ));
                        s.push_str(&format!("coordinate system string = {{{}}}\n", z.wkt()));
                    }
                    MapSystem::LocalEnu { .. } => {
                        s.push_str(&format!(
                            "map info = {{Arbitrary, 1, 1, {}, {}, {}, {}, 0, North, units=Meters{rotation}}}\n",
                            fmt_num(t[0]),
                            fmt_num(t[3]),
                            fmt_num(px),
                            fmt_num(py)
                        ));
                    }
                }
            }
            None => s.push_str(&format!(
                "; no map info: ENVI map info cannot state this grid (skewed, mirrored, or turned \
                 with oblong pixels; the GeoTIFF can); geotransform (GDAL order) = {}\n",
                t.map(fmt_num).join(", ")
            )),
        }
        match self.system {
            MapSystem::Utm(z) => s.push_str(&format!(
                "; map: WGS 84 / UTM zone {} (EPSG:{}), pixel (1,1) upper-left corner\n",
                z.name(),
                z.epsg()
            )),
            MapSystem::LocalEnu {
                latitude_deg,
                longitude_deg,
            } => s.push_str(&format!(
                "; map: local east-north-up plane, metres from the scene site \
                 ({latitude_deg}°, {longitude_deg}°, WGS-84), pixel (1,1) upper-left corner\n"
            )),
        }
        s.push_str(&format!(
            "; georeference good to {:.3} pixel; {}\n",
            self.max_error_px, self.note
        ));
        s
    }
}

/// A number with enough digits for millimetres and micro-degrees, without
/// trailing zeros.
fn fmt_num(v: f64) -> String {
    let s = format!("{v:.9}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

/// GeoKey ids and values (GeoTIFF 1.0, OGC 19-008r4, §7 and Annex C).
mod key {
    pub const GT_MODEL_TYPE: u16 = 1024;
    pub const GT_RASTER_TYPE: u16 = 1025;
    pub const GT_CITATION: u16 = 1026;
    pub const PROJECTED_CS_TYPE: u16 = 3072;
    pub const PROJ_LINEAR_UNITS: u16 = 3076;
    pub const MODEL_TYPE_PROJECTED: u16 = 1;
    pub const RASTER_PIXEL_IS_AREA: u16 = 1;
    pub const USER_DEFINED: u16 = 32767;
    pub const LINEAR_METER: u16 = 9001;
    /// The GeoAsciiParamsTag, which holds the citation strings.
    pub const GEO_ASCII_PARAMS_TAG: u16 = 34737;
    /// GDAL's metadata tag (band descriptions), an XML string.
    pub const GDAL_METADATA_TAG: u16 = 42112;
}

/// Write `stack` as a GeoTIFF at `path`, atomically: one image of
/// `SamplesPerPixel` = one sample per layer, 32-bit IEEE float
/// (`SampleFormat` 3), pixel-interleaved, uncompressed, in strips; the
/// layer names as GDAL band descriptions (tag 42112); and the georeference:
/// `ModelPixelScale` (33550) + `ModelTiepoint` (33922) for a north-up grid,
/// `ModelTransformation` (34264) otherwise, and the `GeoKeyDirectory`
/// (34735) with `GTModelType` projected, `GTRasterType` PixelIsArea and
/// `ProjectedCSType` EPSG 326zz/327zz (UTM) or user-defined with a
/// citation (local grid).
pub fn write_geotiff(path: impl AsRef<Path>, stack: &ImageStack, georef: &Georef) -> Result<()> {
    let path = path.as_ref();
    stack.validate()?;
    let n = stack.layers.len();
    if n == 0 || stack.width == 0 || stack.height == 0 {
        return Err(Error::invalid(
            "image",
            format!("cannot write an empty GeoTIFF to {}", path.display()),
        ));
    }
    let samples = u16::try_from(n)
        .map_err(|_| Error::invalid("image", format!("{n} layers: a TIFF holds at most 65535")))?;
    let (w, h) = (stack.width, stack.height);
    let tiff_err = |e: tiff::TiffError| Error::Other(format!("{}: {e}", path.display()));
    write_atomic(path, |out| {
        let mut enc = TiffEncoder::new(out).map_err(tiff_err)?;
        let mut dir = enc.image_directory().map_err(tiff_err)?;
        // Strips of whole rows, about 256 KiB each.
        let row_bytes = w * n * 4;
        let rows_per_strip = (256 * 1024 / row_bytes.max(1)).clamp(1, h);
        let mut offsets = Vec::new();
        let mut counts = Vec::new();
        let mut buf: Vec<f32> = Vec::with_capacity(rows_per_strip * w * n);
        for r0 in (0..h).step_by(rows_per_strip) {
            buf.clear();
            for r in r0..(r0 + rows_per_strip).min(h) {
                for c in 0..w {
                    buf.extend(stack.layers.iter().map(|l| l.data[r * w + c]));
                }
            }
            let off = dir.write_data(buf.as_slice()).map_err(tiff_err)?;
            offsets.push(u32::try_from(off).map_err(|_| {
                Error::invalid("image", "larger than 4 GiB: too big for a classic TIFF")
            })?);
            counts.push((buf.len() * 4) as u32);
        }
        let u32_of = |v: usize| v as u32;
        dir.write_tag(Tag::ImageWidth, u32_of(w))
            .map_err(tiff_err)?;
        dir.write_tag(Tag::ImageLength, u32_of(h))
            .map_err(tiff_err)?;
        dir.write_tag(Tag::BitsPerSample, &vec![32u16; n][..])
            .map_err(tiff_err)?;
        dir.write_tag(Tag::Compression, 1u16).map_err(tiff_err)?;
        dir.write_tag(Tag::PhotometricInterpretation, 1u16)
            .map_err(tiff_err)?;
        dir.write_tag(Tag::StripOffsets, offsets.as_slice())
            .map_err(tiff_err)?;
        dir.write_tag(Tag::SamplesPerPixel, samples)
            .map_err(tiff_err)?;
        dir.write_tag(Tag::RowsPerStrip, u32_of(rows_per_strip))
            .map_err(tiff_err)?;
        dir.write_tag(Tag::StripByteCounts, counts.as_slice())
            .map_err(tiff_err)?;
        dir.write_tag(Tag::PlanarConfiguration, 1u16)
            .map_err(tiff_err)?;
        if n > 1 {
            // The samples past the first are "unspecified" extra samples.
            dir.write_tag(Tag::ExtraSamples, &vec![0u16; n - 1][..])
                .map_err(tiff_err)?;
        }
        dir.write_tag(Tag::SampleFormat, &vec![3u16; n][..])
            .map_err(tiff_err)?;
        // Georeference.
        let t = georef.transform;
        let square = 1e-12 * t[1].abs().max(t[5].abs());
        if t[2].abs() <= square && t[4].abs() <= square && t[1] > 0.0 && t[5] < 0.0 {
            dir.write_tag(Tag::ModelPixelScaleTag, &[t[1], -t[5], 0.0][..])
                .map_err(tiff_err)?;
            dir.write_tag(Tag::ModelTiepointTag, &[0.0, 0.0, 0.0, t[0], t[3], 0.0][..])
                .map_err(tiff_err)?;
        } else {
            let m = [
                t[1], t[2], 0.0, t[0], t[4], t[5], 0.0, t[3], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                1.0,
            ];
            dir.write_tag(Tag::ModelTransformationTag, &m[..])
                .map_err(tiff_err)?;
        }
        let (citation, pcs) = match georef.system {
            MapSystem::Utm(z) => (format!("WGS 84 / UTM zone {}|", z.name()), z.epsg()),
            MapSystem::LocalEnu {
                latitude_deg,
                longitude_deg,
            } => (
                format!(
                    "irsig local east-north-up plane at {latitude_deg} {longitude_deg} (WGS 84), metres|"
                ),
                key::USER_DEFINED,
            ),
        };
        let keys: Vec<[u16; 4]> = vec![
            [key::GT_MODEL_TYPE, 0, 1, key::MODEL_TYPE_PROJECTED],
            [key::GT_RASTER_TYPE, 0, 1, key::RASTER_PIXEL_IS_AREA],
            [
                key::GT_CITATION,
                key::GEO_ASCII_PARAMS_TAG,
                citation.len() as u16,
                0,
            ],
            [key::PROJECTED_CS_TYPE, 0, 1, pcs],
            [key::PROJ_LINEAR_UNITS, 0, 1, key::LINEAR_METER],
        ];
        let mut dirkeys = vec![1u16, 1, 0, keys.len() as u16];
        dirkeys.extend(keys.iter().flatten());
        dir.write_tag(Tag::GeoKeyDirectoryTag, dirkeys.as_slice())
            .map_err(tiff_err)?;
        dir.write_tag(Tag::Unknown(key::GEO_ASCII_PARAMS_TAG), citation.as_str())
            .map_err(tiff_err)?;
        let mut meta = String::from("<GDALMetadata>");
        for (i, l) in stack.layers.iter().enumerate() {
            meta.push_str(&format!(
                "<Item name=\"DESCRIPTION\" sample=\"{i}\" role=\"description\">{}</Item>",
                xml_escape(&l.name)
            ));
        }
        meta.push_str(&format!(
            "<Item name=\"IRSIG_GEOREFERENCE\">{}</Item></GDALMetadata>",
            xml_escape(&georef.note)
        ));
        dir.write_tag(Tag::Unknown(key::GDAL_METADATA_TAG), meta.as_str())
            .map_err(tiff_err)?;
        dir.finish().map_err(tiff_err)?;
        Ok(())
    })?;
    Ok(())
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn georef(transform: [f64; 6]) -> Georef {
        Georef {
            system: MapSystem::Utm(UtmZone {
                number: 18,
                north: true,
            }),
            transform,
            max_error_px: 0.0,
            size: (100, 80),
            note: String::new(),
        }
    }

    #[test]
    fn envi_map_info_only_for_grids_it_states_unambiguously() {
        let (s, c) = 30f64.to_radians().sin_cos();
        // Square pixels turned 30°: column step 2·(cos, sin), row 2·(sin, −cos).
        let g = georef([1000.0, 2.0 * c, 2.0 * s, 5000.0, 2.0 * s, -2.0 * c]);
        let (px, py, rot) = g.envi_rotation().unwrap();
        assert!((px - 2.0).abs() < 1e-12 && (py - 2.0).abs() < 1e-12 && (rot - 30.0).abs() < 1e-9);
        let lines = g.envi_lines();
        assert!(
            lines.starts_with("map info = {UTM, 1, 1, 1000, 5000, 2, 2, 18, North, WGS-84, units=Meters, rotation=30}\n"),
            "{lines}"
        );
        assert!(lines.contains("coordinate system string = {PROJCS[\"WGS 84 / UTM zone 18N\""));
        // North-up oblong pixels: no rotation written.
        let g = georef([1000.0, 0.5, 0.0, 5000.0, 0.0, -3.0]);
        assert_eq!(g.envi_rotation(), Some((0.5, 3.0, 0.0)));
        assert!(
            g.envi_lines()
                .contains("0.5, 3, 18, North, WGS-84, units=Meters}")
        );
        // Oblong pixels turned, a mirror, a skew: none.
        for t in [
            [1000.0, 0.5 * c, 3.0 * s, 5000.0, 0.5 * s, -3.0 * c],
            [1000.0, 2.0, 0.0, 5000.0, 0.0, 2.0],
            [1000.0, 2.0, 0.5, 5000.0, 0.0, -2.0],
        ] {
            let g = georef(t);
            assert_eq!(g.envi_rotation(), None, "{t:?}");
            assert!(g.envi_lines().starts_with("; no map info"));
        }
        // Pixel and map coordinates invert each other.
        let g = georef([1000.0, 2.0 * c, 2.0 * s, 5000.0, 2.0 * s, -2.0 * c]);
        let (x, y) = g.map_of_pixel(12.5, 40.25);
        let (u, v) = g.pixel_of_map(x, y).unwrap();
        assert!((u - 12.5).abs() < 1e-9 && (v - 40.25).abs() < 1e-9);
    }
}
