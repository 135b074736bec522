//! Image outputs: a stack of named float layers ([`ImageStack`]) and its
//! writers/readers, every file written atomically ([`atomic`]).
//!
//! - [`write_exr`] / [`read_exr`]: OpenEXR, one `f32` channel per layer (the
//!   DIRSIG-style "debug images": `band0_radiance`, `apparent_temperature`,
//!   `surface_temperature`, `material_id`, `object_id`, `shape_factor`,
//!   `sun_fraction`, `depth`, ...).
//! - [`write_envi`] / [`read_envi`]: ENVI `NAME.img` + `NAME.hdr`,
//!   band-sequential little-endian float32 with band names and wavelengths.
//! - [`write_quicklook_png`]: PNG quick-look of apparent temperature with a
//!   colour map and a scale bar in K.
//! - [`read_image`]: read an EXR or ENVI file by its extension.
//! - [`georef`]: an image's georeference ([`Georef`]: map system and
//!   pixel → map transform), written into the ENVI header (`map info`) and
//!   as a GeoTIFF ([`write_geotiff`]).
//!
//! Takes named layers; gives files (and reads them back). It must not know
//! how the layers were computed: no scene, sensor or physics.

pub mod atomic;
mod envi;
pub mod exr_io;
pub mod georef;
mod quicklook;

use std::path::{Path, PathBuf};

pub use atomic::{AtomicFile, WriteSeek, write_atomic};
pub use envi::{EnviImage, envi_paths, read_envi, write_envi, write_envi_georef};
pub use exr_io::{read_exr, write_exr};
pub use georef::{Georef, MapSystem, write_geotiff};

pub use quicklook::{
    BAR_AREA_HEIGHT, MIN_CANVAS_WIDTH, RgbImage, auto_range, inferno, render_quicklook,
    write_quicklook_png,
};

use crate::{Error, Location, Result};

/// One named float layer, row-major, `width × height` values.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// Layer name (`apparent_temperature`, `band0_radiance`, ...).
    pub name: String,
    /// Row-major values, row 0 at the top.
    pub data: Vec<f32>,
}

/// A multi-layer float image.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ImageStack {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// The layers, each `width * height` long.
    pub layers: Vec<Layer>,
}

/// Statistics of one layer over its non-NaN values (`irsig info`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LayerStats {
    /// Layer name.
    pub name: String,
    /// Smallest non-NaN value (`None` if every value is NaN).
    pub min: Option<f64>,
    /// Largest non-NaN value.
    pub max: Option<f64>,
    /// Mean of the non-NaN values.
    pub mean: Option<f64>,
    /// Number of NaN values.
    pub nan_count: usize,
}

impl Layer {
    /// Statistics over the non-NaN values (infinities included).
    pub fn stats(&self) -> LayerStats {
        let (mut lo, mut hi, mut sum, mut n, mut nan) =
            (f64::INFINITY, f64::NEG_INFINITY, 0.0f64, 0usize, 0usize);
        for &v in &self.data {
            if v.is_nan() {
                nan += 1;
                continue;
            }
            let v = v as f64;
            lo = lo.min(v);
            hi = hi.max(v);
            sum += v;
            n += 1;
        }
        let some = |v: f64| (n > 0).then_some(v);
        LayerStats {
            name: self.name.clone(),
            min: some(lo),
            max: some(hi),
            mean: some(sum / n.max(1) as f64),
            nan_count: nan,
        }
    }
}

impl ImageStack {
    /// An image with no layers yet.
    pub fn new(width: usize, height: usize) -> Self {
        ImageStack {
            width,
            height,
            layers: Vec::new(),
        }
    }

    /// The layer called `name`, if present.
    pub fn layer(&self, name: &str) -> Option<&Layer> {
        self.layers.iter().find(|l| l.name == name)
    }

    /// Append a layer, checking its size and that its name is new.
    pub fn push(&mut self, name: impl Into<String>, data: Vec<f32>) -> Result<()> {
        let name = name.into();
        if data.len() != self.width * self.height {
            return Err(Error::invalid(
                format!("layer `{name}`"),
                format!(
                    "{} values: expected {}×{} = {}",
                    data.len(),
                    self.width,
                    self.height,
                    self.width * self.height
                ),
            ));
        }
        if self.layer(&name).is_some() {
            return Err(Error::invalid(
                format!("layer `{name}`"),
                "duplicate layer name",
            ));
        }
        self.layers.push(Layer { name, data });
        Ok(())
    }

    /// Check every layer has `width · height` values and names are unique.
    pub fn validate(&self) -> Result<()> {
        let n = self.width * self.height;
        for (i, l) in self.layers.iter().enumerate() {
            if l.data.len() != n {
                return Err(Error::invalid(
                    format!("layer `{}`", l.name),
                    format!(
                        "{} values: expected {}×{} = {n}",
                        l.data.len(),
                        self.width,
                        self.height
                    ),
                ));
            }
            if self.layers[..i].iter().any(|o| o.name == l.name) {
                return Err(Error::invalid(
                    format!("layer `{}`", l.name),
                    "duplicate layer name",
                ));
            }
        }
        Ok(())
    }

    /// Per-layer statistics, in layer order.
    pub fn stats(&self) -> Vec<LayerStats> {
        self.layers.iter().map(Layer::stats).collect()
    }
}

/// The files of one rendered image set (see [`write_image_set`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ImageSetPaths {
    /// `NAME.exr`: every layer.
    pub exr: PathBuf,
    /// `NAME.img` and `NAME.hdr`: the spectral layers, if any were named.
    pub envi: Option<(PathBuf, PathBuf)>,
    /// `NAME.png`: quick-look of `apparent_temperature`, if that layer exists.
    pub png: Option<PathBuf>,
    /// `NAME.tif`: every layer as a GeoTIFF, if asked for.
    pub geotiff: Option<PathBuf>,
}

/// The georeferenced outputs of an image set (see [`write_image_set_geo`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GeoOutputs {
    /// The image's georeference, written into the ENVI header.
    pub georef: Option<Georef>,
    /// Also write `NAME.tif`, a GeoTIFF of every layer (needs `georef`).
    pub geotiff: bool,
}

/// Write the standard image set of a render into `dir`: `NAME.exr` (all
/// layers), `NAME.img` + `NAME.hdr` (the layers named in `spectral`, in that
/// order, each with its band-centre wavelength in µm) and `NAME.png` (the
/// quick-look of the `apparent_temperature` layer). Each file is written
/// atomically; the image is validated before any file is written.
pub fn write_image_set(
    dir: impl AsRef<Path>,
    name: &str,
    stack: &ImageStack,
    spectral: &[(&str, f64)],
    description: &str,
) -> Result<ImageSetPaths> {
    write_image_set_geo(
        dir,
        name,
        stack,
        spectral,
        description,
        &GeoOutputs::default(),
    )
}

/// [`write_image_set`] with a georeference: the ENVI header carries it,
/// and with `geo.geotiff` every layer is also written to `NAME.tif`
/// ([`write_geotiff`]). Errors if a GeoTIFF is asked for without a
/// georeference.
pub fn write_image_set_geo(
    dir: impl AsRef<Path>,
    name: &str,
    stack: &ImageStack,
    spectral: &[(&str, f64)],
    description: &str,
    geo: &GeoOutputs,
) -> Result<ImageSetPaths> {
    let dir = dir.as_ref();
    stack.validate()?;
    if geo.geotiff && geo.georef.is_none() {
        return Err(Error::invalid(
            "geotiff",
            format!("image `{name}` has no georeference to write a GeoTIFF with"),
        ));
    }
    let mut envi_stack = ImageStack::new(stack.width, stack.height);
    for (layer, _) in spectral {
        let l = stack.layer(layer).ok_or_else(|| {
            Error::invalid(
                "spectral layers",
                format!("no layer `{layer}` in the image to write to ENVI"),
            )
        })?;
        envi_stack.push(l.name.clone(), l.data.clone())?;
    }
    let exr = dir.join(format!("{name}.exr"));
    write_exr(&exr, stack)?;
    let envi = if spectral.is_empty() {
        None
    } else {
        let w: Vec<f64> = spectral.iter().map(|(_, w)| *w).collect();
        let base = dir.join(name);
        write_envi_georef(
            &base,
            &envi_stack,
            Some(&w),
            description,
            geo.georef.as_ref(),
        )?;
        Some(envi_paths(&base))
    };
    let png = match stack.layer("apparent_temperature") {
        Some(t) => {
            let p = dir.join(format!("{name}.png"));
            write_quicklook_png(&p, stack.width, stack.height, &t.data, None)?;
            Some(p)
        }
        None => None,
    };
    let geotiff = match (&geo.georef, geo.geotiff) {
        (Some(g), true) => {
            let p = dir.join(format!("{name}.tif"));
            write_geotiff(&p, stack, g)?;
            Some(p)
        }
        _ => None,
    };
    Ok(ImageSetPaths {
        exr,
        envi,
        png,
        geotiff,
    })
}

/// Read an image file into an [`ImageStack`], choosing the format by the
/// extension: `.exr` (OpenEXR), `.hdr` / `.img` (ENVI).
pub fn read_image(path: impl AsRef<Path>) -> Result<ImageStack> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("exr") => read_exr(path),
        Some("hdr") | Some("img") => Ok(read_envi(path)?.stack),
        _ => Err(Error::parse(
            Location::file(path),
            "unknown image format: expected a `.exr`, `.hdr` or `.img` file",
        )),
    }
}
