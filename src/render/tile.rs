//! Tiles: a render split into `N` bands of image rows (tile `K` of `N`,
//! [`RunOptions::tile`](super::session::RunOptions::tile)), each written to
//! a partial file and assembled by [`merge_tiles`].
//!
//! A tile file `NAME.tileK-of-N.exr` is an OpenEXR image of the tile's rows
//! holding, per band, the radiance after the PSF reduction but before the
//! image-wide effects (`NAME_radiance`), and the truth layers; its part
//! attribute `irsigTile` is a JSON [`TileInfo`]: which image it belongs to
//! (scene hash, sensor, time), the full size and its row range. Merging
//! checks every tile of `1..=N` is present exactly once and that they agree,
//! pastes the rows and runs the image-wide effects once
//! ([`super::image::finish`]), so the result is bit-identical to a render in
//! one piece. Tiles are written atomically: a tile file that exists is
//! complete, and a rerun skips it ([`tile_is_complete`]).

use std::path::{Path, PathBuf};

use exr::prelude::{self as x};
use serde::{Deserialize, Serialize};

use super::image::{POINT_LAYERS, RowBand, TRUTH_LAYERS};
use crate::output::exr_io::{flat_exr_layer, read_flat_exr, write_flat_exr};
use crate::{Error, Location, Result};

/// Name of the EXR attribute holding the [`TileInfo`] JSON.
pub const TILE_ATTRIBUTE: &str = "irsigTile";

/// Which tile of which image a tile file holds.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct TileInfo {
    /// Format version (1).
    pub version: u32,
    /// Hash of everything the image depends on (scene, weather, materials,
    /// sensor, time, seed, options), hex.
    pub scene_hash: String,
    /// Hash of the scene file alone (checked by `irsig merge`, which reads
    /// the sensor settings from it), hex.
    pub scene_file_hash: String,
    /// The scene file, as given on the command line (absolute).
    pub scene: PathBuf,
    /// Sensor name.
    pub sensor: String,
    /// Output file stem (sensor name, plus the time for a series).
    pub stem: String,
    /// Image time, RFC 3339.
    pub time: String,
    /// Tile index `K` (1-based).
    pub tile: usize,
    /// Tile count `N`.
    pub tiles: usize,
    /// Full image width, pixels.
    pub width: usize,
    /// Full image height, pixels.
    pub height: usize,
    /// First row held.
    pub row_start: usize,
    /// One past the last row held.
    pub row_end: usize,
    /// Band names, in order.
    pub bands: Vec<String>,
    /// Noise seed used by the finishing step.
    pub seed: u64,
    /// Tracing backend.
    pub backend: String,
}

/// Rows `[start, end)` of tile `k` (1-based) of `n` for an image of
/// `height` rows: as equal as possible, the first `height mod n` tiles one
/// row longer.
pub fn tile_rows(k: usize, n: usize, height: usize) -> std::ops::Range<usize> {
    let base = height / n;
    let extra = height % n;
    let start = (k - 1) * base + (k - 1).min(extra);
    let len = base + usize::from(k - 1 < extra);
    start..start + len
}

/// The tile file of `stem` in `dir`: `dir/STEM.tileK-of-N.exr`.
pub fn tile_path(dir: &Path, stem: &str, k: usize, n: usize) -> PathBuf {
    dir.join(format!("{stem}.tile{k}-of-{n}.exr"))
}

/// JSON with every non-ASCII character escaped (EXR text is Latin-1).
fn ascii_json<T: Serialize>(v: &T) -> Result<String> {
    let s = serde_json::to_string(v).map_err(|e| Error::Other(format!("tile metadata: {e}")))?;
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if c.is_ascii() {
            out.push(c);
        } else {
            let mut buf = [0u16; 2];
            for u in c.encode_utf16(&mut buf) {
                out.push_str(&format!("\\u{u:04x}"));
            }
        }
    }
    Ok(out)
}

/// Write a tile file atomically.
pub fn write_tile(path: &Path, info: &TileInfo, band: &RowBand) -> Result<()> {
    if band.rows() != (info.row_start..info.row_end) || band.radiance().len() != info.bands.len() {
        return Err(Error::invalid(
            "tile",
            format!(
                "rows {:?} with {} bands do not match the tile metadata",
                band.rows(),
                band.radiance().len()
            ),
        ));
    }
    let point_names = if band.points().is_empty() {
        &[][..]
    } else {
        &POINT_LAYERS[..]
    };
    let names: Vec<String> = info
        .bands
        .iter()
        .map(|b| format!("{b}_radiance"))
        .chain(TRUTH_LAYERS.iter().map(|s| s.to_string()))
        .chain(point_names.iter().map(|s| s.to_string()))
        .collect();
    let data: Vec<&Vec<f32>> = band
        .radiance()
        .iter()
        .chain(band.truth())
        .chain(band.points())
        .collect();
    let mut attributes = x::LayerAttributes::named("irsig-tile");
    attributes.other.insert(
        x::Text::from(TILE_ATTRIBUTE),
        x::AttributeValue::Text(x::Text::from(ascii_json(info)?.as_str())),
    );
    let layer = flat_exr_layer(
        (band.width(), band.rows().len()),
        attributes,
        names.iter().map(String::as_str).zip(data),
    );
    write_flat_exr(path, layer, "tile")
}

/// Read a tile file: its metadata and rows.
pub fn read_tile(path: &Path) -> Result<(TileInfo, RowBand)> {
    let bad = |m: String| Error::parse(Location::file(path), m);
    let layer = read_flat_exr(path, "OpenEXR tile")?;
    let info: TileInfo = match layer.attributes.other.get(&x::Text::from(TILE_ATTRIBUTE)) {
        Some(x::AttributeValue::Text(t)) => serde_json::from_str(&t.to_string())
            .map_err(|e| bad(format!("attribute `{TILE_ATTRIBUTE}`: {e}")))?,
        _ => {
            return Err(bad(format!(
                "no `{TILE_ATTRIBUTE}` attribute: expected a tile file of a render split into tiles"
            )));
        }
    };
    let (w, h) = (layer.size.width(), layer.size.height());
    if w != info.width
        || info.row_end < info.row_start
        || h != info.row_end - info.row_start
        || info.row_end > info.height
        || info.tile == 0
        || info.tile > info.tiles
    {
        return Err(bad(format!(
            "size {w}×{h} does not match its metadata (width {}, rows {}..{} of {}, tile {}/{})",
            info.width, info.row_start, info.row_end, info.height, info.tile, info.tiles
        )));
    }
    let get = |name: &str| -> Result<Vec<f32>> {
        let c = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)
            .ok_or_else(|| bad(format!("missing layer `{name}`")))?;
        match &c.sample_data {
            x::FlatSamples::F32(v) => Ok(v.clone()),
            _ => Err(bad(format!(
                "layer `{name}`: expected 32-bit float samples"
            ))),
        }
    };
    let radiance = info
        .bands
        .iter()
        .map(|b| get(&format!("{b}_radiance")))
        .collect::<Result<Vec<_>>>()?;
    let truth = TRUTH_LAYERS
        .iter()
        .map(|n| get(n))
        .collect::<Result<Vec<_>>>()?;
    let band = RowBand::new(
        &path.display().to_string(),
        w,
        info.height,
        info.row_start..info.row_end,
        radiance,
        truth,
    )?;
    // The hit points, where the sensor asked for geolocation layers.
    let has_points = layer
        .channel_data
        .list
        .iter()
        .any(|c| c.name.to_string() == POINT_LAYERS[0]);
    let band = if has_points {
        let points = POINT_LAYERS
            .iter()
            .map(|n| get(n))
            .collect::<Result<Vec<_>>>()?;
        band.with_points(points)?
    } else {
        band
    };
    Ok((info, band))
}

/// Whether `path` holds a complete tile matching `expected` (same image and
/// rows). Files are written atomically, so a readable one is complete.
pub fn tile_is_complete(path: &Path, expected: &TileInfo) -> bool {
    match read_tile(path) {
        Ok((info, _)) => &info == expected,
        Err(_) => false,
    }
}

/// Assemble tiles into the full image, checking they all belong to one
/// image (same hash, sensor, time, size, band names, tile count) and that
/// tiles `1..=N` are each present exactly once.
pub fn assemble(parts: &[(PathBuf, TileInfo, RowBand)]) -> Result<(TileInfo, RowBand)> {
    let Some((p0, first, _)) = parts.first() else {
        return Err(Error::invalid("merge", "no tile files given"));
    };
    let n = first.tiles;
    let mut seen: Vec<Option<&Path>> = vec![None; n];
    for (p, info, _) in parts {
        let same = info.scene_hash == first.scene_hash
            && info.sensor == first.sensor
            && info.stem == first.stem
            && info.time == first.time
            && info.width == first.width
            && info.height == first.height
            && info.bands == first.bands
            && info.tiles == first.tiles
            && info.seed == first.seed;
        if !same {
            return Err(Error::parse(
                Location::file(p),
                format!(
                    "tile {}/{} of `{}` (scene hash {}, {}×{}) does not belong to the same image as {} (`{}`, scene hash {}, {}×{}, {} tiles)",
                    info.tile,
                    info.tiles,
                    info.stem,
                    info.scene_hash,
                    info.width,
                    info.height,
                    p0.display(),
                    first.stem,
                    first.scene_hash,
                    first.width,
                    first.height,
                    first.tiles
                ),
            ));
        }
        if (info.row_start..info.row_end) != tile_rows(info.tile, n, info.height) {
            return Err(Error::parse(
                Location::file(p),
                format!(
                    "tile {}/{} holds rows {}..{}: expected {:?}",
                    info.tile,
                    n,
                    info.row_start,
                    info.row_end,
                    tile_rows(info.tile, n, info.height)
                ),
            ));
        }
        if let Some(other) = seen[info.tile - 1] {
            return Err(Error::parse(
                Location::file(p),
                format!(
                    "tile {}/{} given twice (also {})",
                    info.tile,
                    n,
                    other.display()
                ),
            ));
        }
        seen[info.tile - 1] = Some(p);
    }
    let missing: Vec<String> = seen
        .iter()
        .enumerate()
        .filter(|(_, s)| s.is_none())
        .map(|(k, _)| format!("{}/{n}", k + 1))
        .collect();
    if !missing.is_empty() {
        return Err(Error::invalid(
            "merge",
            format!(
                "`{}`: missing tile(s) {}: expected all {n} tiles (`{}.tileK-of-{n}.exr`)",
                first.stem,
                missing.join(", "),
                first.stem
            ),
        ));
    }
    let mut full = RowBand::empty_with(
        first.width,
        first.height,
        0..first.height,
        first.bands.len(),
        parts.iter().any(|(_, _, b)| !b.points().is_empty()),
    );
    for (_, _, band) in parts {
        full.paste(band)?;
    }
    let mut info = first.clone();
    info.tile = 1;
    info.tiles = 1;
    info.row_start = 0;
    info.row_end = first.height;
    Ok((info, full))
}

/// The sensor `name` of the scene file `scene` and its bands, read from the
/// file's JSON alone (no geometry), for finishing merged tiles. Errors when
/// the file's hash is not `expected_file_hash` (the scene changed since the
/// tiles were rendered).
pub fn sensor_from_scene_file(
    scene: &Path,
    name: &str,
    expected_file_hash: &str,
) -> Result<(crate::sensor::Sensor, Vec<crate::radiometry::Band>)> {
    let (sensor, bands, _) = scene_sensor(scene, name, expected_file_hash)?;
    Ok((sensor, bands))
}

/// What merging tiles of a sensor needs from the scene file.
struct SceneSensor {
    /// The scene's site (for the georeference and latitude/longitude).
    site: crate::sun::Site,
    /// The scene's `render.geotiff`.
    geotiff: bool,
}

/// [`sensor_from_scene_file`], with the site and render settings.
fn scene_sensor(
    scene: &Path,
    name: &str,
    expected_file_hash: &str,
) -> Result<(
    crate::sensor::Sensor,
    Vec<crate::radiometry::Band>,
    SceneSensor,
)> {
    let bytes = std::fs::read(scene).map_err(|e| Error::io(scene, e))?;
    let mut h = super::Fnv::default();
    h.write(&bytes);
    let got = format!("{:016x}", h.finish());
    if got != expected_file_hash {
        return Err(Error::parse(
            Location::file(scene),
            format!(
                "the scene file changed since the tiles were rendered (hash {got}, tiles say {expected_file_hash}): re-render the tiles"
            ),
        ));
    }
    let file = Location::file(scene);
    let v: serde_json::Value = serde_json::from_slice(&bytes)
        .map_err(|e| Error::parse(file.clone().at_line(e.line()), format!("{e}")))?;
    let config = super::RenderConfig::from_json(v.get("render"), &file)?;
    let sensors = v.get("sensors").and_then(|s| s.as_array()).ok_or_else(|| {
        Error::parse(
            file.clone().with_field("sensors"),
            "missing: expected an array",
        )
    })?;
    for (i, s) in sensors.iter().enumerate() {
        if s.get("name").and_then(|n| n.as_str()) != Some(name) {
            continue;
        }
        let loc = file.clone().with_field(format!("sensors[{i}]"));
        let c: crate::sensor::SensorConfig = serde_json::from_value(s.clone())
            .map_err(|e| Error::parse(loc.clone(), e.to_string()))?;
        let sensor = crate::sensor::Sensor::from_config(&c, &loc)?;
        let base = scene.parent().unwrap_or(Path::new("."));
        let bands = super::sensor_bands(&sensor, base, config.spectral_step_um, &loc)?;
        let site_loc = file.clone().with_field("site");
        let spec: crate::scene::file::SiteSpec = v
            .get("site")
            .cloned()
            .ok_or_else(|| Error::parse(site_loc.clone(), "missing: expected an object"))
            .and_then(|s| {
                serde_json::from_value(s).map_err(|e| Error::parse(site_loc.clone(), e.to_string()))
            })?;
        let site = crate::sun::Site::new(spec.latitude_deg, spec.longitude_deg, spec.altitude_m)
            .map_err(|e| Error::parse(site_loc.clone(), e.to_string()))?;
        let extra = SceneSensor {
            site,
            geotiff: config.geotiff,
        };
        return Ok((sensor, bands, extra));
    }
    Err(Error::parse(
        file.with_field("sensors"),
        format!("no sensor named `{name}`"),
    ))
}

/// Merge tile files into finished images in `out_dir`: tiles are grouped by
/// image (file stem), each group checked and assembled ([`assemble`]),
/// finished with the sensor's effects read from the scene file, and written
/// ([`super::write_outputs`]). Returns the stems written.
pub fn merge_tiles(parts: &[PathBuf], out_dir: &Path) -> Result<Vec<String>> {
    merge_tiles_with(parts, out_dir, false)
}

/// [`merge_tiles`], also writing a GeoTIFF of each georeferenced image when
/// `geotiff` (or the scene's `render.geotiff`) says so.
pub fn merge_tiles_with(parts: &[PathBuf], out_dir: &Path, geotiff: bool) -> Result<Vec<String>> {
    let mut groups: std::collections::BTreeMap<String, Vec<(PathBuf, TileInfo, RowBand)>> =
        Default::default();
    for p in parts {
        let (info, band) = read_tile(p)?;
        groups
            .entry(info.stem.clone())
            .or_default()
            .push((p.clone(), info, band));
    }
    if groups.is_empty() {
        return Err(Error::invalid("merge", "no tile files given"));
    }
    std::fs::create_dir_all(out_dir).map_err(|e| Error::io(out_dir, e))?;
    let mut done = Vec::new();
    for (stem, group) in groups {
        let (info, full) = assemble(&group)?;
        let (sensor, bands, extra) =
            scene_sensor(&info.scene, &info.sensor, &info.scene_file_hash)?;
        if sensor.width() != info.width || sensor.height() != info.height {
            return Err(Error::parse(
                Location::file(&info.scene),
                format!(
                    "sensor `{}` is {}×{} but its tiles are {}×{}",
                    info.sensor,
                    sensor.width(),
                    sensor.height(),
                    info.width,
                    info.height
                ),
            ));
        }
        let finished = super::finish_at(full, &sensor, &bands, info.seed, Some(&extra.site))?;
        let desc = super::description(&info.scene, &info.backend, &info.sensor, &info.time);
        let geo = super::geo_outputs(&sensor, &extra.site, geotiff || extra.geotiff);
        super::write_outputs_geo(out_dir, &stem, &finished, &desc, &geo)?;
        done.push(stem);
    }
    Ok(done)
}
