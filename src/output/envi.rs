//! ENVI raster: a raw binary file `NAME.img` plus a text header `NAME.hdr`.
//!
//! irsig writes band-sequential (`interleave = bsq`) little-endian
//! (`byte order = 0`) 32-bit floats (`data type = 4`), one band per layer,
//! with `band names` and, for spectral bands, `wavelength` (band centres)
//! in `wavelength units = Micrometers`. The reader also accepts `bil`/`bip`,
//! big-endian data, data types 1, 2, 3, 4, 5, 12, 13 and a header offset.
//! Format reference: the ENVI header file documentation (NV5 Geospatial,
//! "ENVI Header Files").

use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use super::atomic::AtomicFile;
use super::georef::Georef;
use super::{ImageStack, Layer};
use crate::{Error, Location, Result};

/// An ENVI image as read: the bands, and the header's wavelengths if any.
#[derive(Debug, Clone, PartialEq)]
pub struct EnviImage {
    /// The bands, as layers named from `band names` (or `band_1`, ...).
    pub stack: ImageStack,
    /// `wavelength` values, one per band, in `wavelength_units`.
    pub wavelengths: Option<Vec<f64>>,
    /// `wavelength units` (e.g. `Micrometers`), if given.
    pub wavelength_units: Option<String>,
    /// `description`, if given.
    pub description: Option<String>,
}

/// The `(NAME.img, NAME.hdr)` pair for a path given as `NAME`, `NAME.img` or
/// `NAME.hdr`.
pub fn envi_paths(path: impl AsRef<Path>) -> (PathBuf, PathBuf) {
    let p = path.as_ref();
    let base = match p.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("img") || e.eq_ignore_ascii_case("hdr") => {
            p.with_extension("")
        }
        _ => p.to_path_buf(),
    };
    let mut img = base.clone().into_os_string();
    img.push(".img");
    let mut hdr = base.into_os_string();
    hdr.push(".hdr");
    (PathBuf::from(img), PathBuf::from(hdr))
}

/// Write `stack` as ENVI (`NAME.img` + `NAME.hdr`, see [`envi_paths`]),
/// atomically: both files are written under temporary names, then the data
/// file and last the header are renamed into place. `wavelengths_um`, when
/// given, must hold one band-centre wavelength (µm) per layer.
pub fn write_envi(
    path: impl AsRef<Path>,
    stack: &ImageStack,
    wavelengths_um: Option<&[f64]>,
    description: &str,
) -> Result<()> {
    write_envi_georef(path, stack, wavelengths_um, description, None)
}

/// [`write_envi`] with the image's georeference in the header (`map info`,
/// `coordinate system string`: see [`Georef::envi_lines`]).
pub fn write_envi_georef(
    path: impl AsRef<Path>,
    stack: &ImageStack,
    wavelengths_um: Option<&[f64]>,
    description: &str,
    georef: Option<&Georef>,
) -> Result<()> {
    stack.validate()?;
    let (img_path, hdr_path) = envi_paths(&path);
    if stack.layers.is_empty() {
        return Err(Error::invalid(
            "image",
            format!(
                "cannot write an ENVI file with no bands to {}",
                img_path.display()
            ),
        ));
    }
    if let Some(w) = wavelengths_um {
        if w.len() != stack.layers.len() {
            return Err(Error::invalid(
                "wavelengths",
                format!(
                    "{} wavelengths for {} bands: expected one per band",
                    w.len(),
                    stack.layers.len()
                ),
            ));
        }
    }
    for l in &stack.layers {
        if l.name.contains([',', '{', '}', '\n']) {
            return Err(Error::invalid(
                "layer name",
                format!(
                    "`{}`: ENVI band names cannot contain `,`, `{{`, `}}` or newlines",
                    l.name
                ),
            ));
        }
    }
    let mut img = AtomicFile::create(&img_path)?;
    {
        let w = img.writer();
        let mut buf = Vec::with_capacity(stack.width * 4);
        for l in &stack.layers {
            for row in l.data.chunks(stack.width.max(1)) {
                buf.clear();
                for v in row {
                    buf.extend_from_slice(&v.to_le_bytes());
                }
                w.write_all(&buf).map_err(|e| Error::io(&img_path, e))?;
            }
        }
    }
    let mut hdr = AtomicFile::create(&hdr_path)?;
    let mut text = header_text(stack, wavelengths_um, description);
    if let Some(g) = georef {
        text.push_str(&g.envi_lines());
    }
    hdr.writer()
        .write_all(text.as_bytes())
        .map_err(|e| Error::io(&hdr_path, e))?;
    img.commit()?;
    hdr.commit()
}

fn header_text(stack: &ImageStack, wavelengths_um: Option<&[f64]>, description: &str) -> String {
    let desc = description.replace(['{', '}'], "");
    let names: Vec<&str> = stack.layers.iter().map(|l| l.name.as_str()).collect();
    let mut s = format!(
        "ENVI\ndescription = {{{desc}}}\nsamples = {}\nlines = {}\nbands = {}\n\
         header offset = 0\nfile type = ENVI Standard\ndata type = 4\ninterleave = bsq\n\
         byte order = 0\nband names = {{{}}}\n",
        stack.width,
        stack.height,
        stack.layers.len(),
        names.join(", ")
    );
    if let Some(w) = wavelengths_um {
        let w: Vec<String> = w.iter().map(|v| format!("{v}")).collect();
        s.push_str(&format!(
            "wavelength units = Micrometers\nwavelength = {{{}}}\n",
            w.join(", ")
        ));
    }
    s
}

/// Parse an ENVI header: `key = value` lines, values in `{…}` may span lines.
/// Keys are lower-cased; returns each key with its value and 1-based line.
fn parse_header(path: &Path, text: &str) -> Result<HashMap<String, (String, usize)>> {
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, first)) if first.trim() == "ENVI" => {}
        _ => {
            return Err(Error::parse(
                Location::file(path).at_line(1),
                "not an ENVI header: expected the first line to be `ENVI`",
            ));
        }
    }
    let mut map = HashMap::new();
    while let Some((i, line)) = lines.next() {
        let line_no = i + 1;
        if line.trim().is_empty() || line.trim_start().starts_with(';') {
            continue;
        }
        let Some((k, v)) = line.split_once('=') else {
            return Err(Error::parse(
                Location::file(path).at_line(line_no),
                format!("expected `key = value`, found `{}`", line.trim()),
            ));
        };
        let mut value = v.trim().to_string();
        if value.starts_with('{') {
            while !value.contains('}') {
                let Some((_, more)) = lines.next() else {
                    return Err(Error::parse(
                        Location::file(path).at_line(line_no).with_field(k.trim()),
                        "unterminated `{`: expected a closing `}`",
                    ));
                };
                value.push(' ');
                value.push_str(more.trim());
            }
            let end = value.rfind('}').unwrap_or(value.len());
            value = value[1..end].trim().to_string();
        }
        map.insert(k.trim().to_ascii_lowercase(), (value, line_no));
    }
    Ok(map)
}

/// Read an ENVI image given as `NAME`, `NAME.img` or `NAME.hdr`.
pub fn read_envi(path: impl AsRef<Path>) -> Result<EnviImage> {
    let (img_path, hdr_path) = envi_paths(&path);
    let text = std::fs::read(&hdr_path).map_err(|e| Error::io(&hdr_path, e))?;
    let text = String::from_utf8_lossy(&text);
    let h = parse_header(&hdr_path, &text)?;
    let loc = |key: &str| {
        let l = Location::file(&hdr_path).with_field(key);
        match h.get(key) {
            Some((_, line)) => l.at_line(*line),
            None => l,
        }
    };
    let int = |key: &str, default: Option<usize>| -> Result<usize> {
        match h.get(key) {
            Some((v, _)) => v.parse::<usize>().map_err(|_| {
                Error::parse(
                    loc(key),
                    format!("expected a non-negative integer, found `{v}`"),
                )
            }),
            None => default.ok_or_else(|| Error::parse(loc(key), "missing required header field")),
        }
    };
    let width = int("samples", None)?;
    let height = int("lines", None)?;
    let bands = int("bands", None)?;
    let offset = int("header offset", Some(0))?;
    let dtype = int("data type", None)?;
    let byte_order = int("byte order", Some(0))?;
    if byte_order > 1 {
        return Err(Error::parse(
            loc("byte order"),
            "expected 0 (little-endian) or 1 (big-endian)",
        ));
    }
    let interleave = h
        .get("interleave")
        .map(|(v, _)| v.to_ascii_lowercase())
        .unwrap_or_else(|| "bsq".into());
    let size = match dtype {
        1 => 1,
        2 | 12 => 2,
        3 | 4 | 13 => 4,
        5 => 8,
        _ => {
            return Err(Error::parse(
                loc("data type"),
                format!("unsupported data type {dtype}: expected 1, 2, 3, 4, 5, 12 or 13"),
            ));
        }
    };
    let n = width
        .checked_mul(height)
        .and_then(|p| p.checked_mul(bands))
        .ok_or_else(|| Error::parse(loc("samples"), "image size overflows"))?;
    let raw = std::fs::read(&img_path).map_err(|e| Error::io(&img_path, e))?;
    let need = offset + n * size;
    if raw.len() < need {
        return Err(Error::parse(
            Location::file(&img_path),
            format!(
                "file holds {} bytes; the header ({width}×{height}×{bands}, data type {dtype}, \
                 header offset {offset}) needs {need}",
                raw.len()
            ),
        ));
    }
    let be = byte_order == 1;
    let value = |i: usize| -> f32 {
        let b = &raw[offset + i * size..offset + (i + 1) * size];
        macro_rules! num {
            ($t:ty) => {{
                let a = b.try_into().unwrap_or_default();
                if be {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }
            }};
        }
        match dtype {
            1 => b[0] as f32,
            2 => num!(i16) as f32,
            12 => num!(u16) as f32,
            3 => num!(i32) as f32,
            13 => num!(u32) as f32,
            4 => num!(f32),
            _ => num!(f64) as f32,
        }
    };
    let index = |band: usize, row: usize, col: usize| -> Result<usize> {
        Ok(match interleave.as_str() {
            "bsq" => (band * height + row) * width + col,
            "bil" => (row * bands + band) * width + col,
            "bip" => (row * width + col) * bands + band,
            other => {
                return Err(Error::parse(
                    loc("interleave"),
                    format!("unknown interleave `{other}`: expected bsq, bil or bip"),
                ));
            }
        })
    };
    index(0, 0, 0)?;
    let names: Vec<String> = match h.get("band names") {
        Some((v, _)) => v.split(',').map(|s| s.trim().to_string()).collect(),
        None => (1..=bands).map(|b| format!("band_{b}")).collect(),
    };
    if names.len() != bands {
        return Err(Error::parse(
            loc("band names"),
            format!(
                "{} band names for {bands} bands: expected one per band",
                names.len()
            ),
        ));
    }
    let mut layers = Vec::with_capacity(bands);
    for (b, name) in names.into_iter().enumerate() {
        let mut data = Vec::with_capacity(width * height);
        for r in 0..height {
            for c in 0..width {
                data.push(value(index(b, r, c)?));
            }
        }
        layers.push(Layer { name, data });
    }
    let wavelengths = match h.get("wavelength") {
        Some((v, _)) => {
            let w: std::result::Result<Vec<f64>, _> =
                v.split(',').map(|s| s.trim().parse::<f64>()).collect();
            let w = w.map_err(|_| Error::parse(loc("wavelength"), "expected a list of numbers"))?;
            if w.len() != bands {
                return Err(Error::parse(
                    loc("wavelength"),
                    format!(
                        "{} wavelengths for {bands} bands: expected one per band",
                        w.len()
                    ),
                ));
            }
            Some(w)
        }
        None => None,
    };
    Ok(EnviImage {
        stack: ImageStack {
            width,
            height,
            layers,
        },
        wavelengths,
        wavelength_units: h.get("wavelength units").map(|(v, _)| v.clone()),
        description: h.get("description").map(|(v, _)| v.clone()),
    })
}
