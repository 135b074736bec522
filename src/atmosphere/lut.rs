//! A lookup-table atmosphere from a set of MODTRAN tape7 runs, in the manner
//! of DIRSIG's atmospheric database.
//!
//! The index is a small JSON file; tape7 paths are relative to it:
//!
//! ```json
//! {
//!   "path": [ {"file": "nadir_1km.tp7", "view_zenith_deg": 0, "range_m": 1000},
//!             {"file": "nadir_3km.tp7", "view_zenith_deg": 0, "range_m": 3000},
//!             {"file": "oblique_3km.tp7", "view_zenith_deg": 45, "range_m": 3000} ],
//!   "sky":  [ {"file": "tape7.LWIRSun", "zenith_deg": 0} ]
//! }
//! ```
//!
//! `path` runs (radiance mode) are surface-to-sensor paths at a view zenith
//! (at the surface) and range: `TOT_TRANS` gives τ₂ and `PTH_THRML +
//! SOL_SCAT` gives L_u. They are interpolated linearly in range within each
//! zenith (with the exact zero-range point τ = 1, L_u = 0 added, so short
//! paths tend to the right limit; beyond the longest range the longest run is
//! used) and then linearly in zenith between the two nearest zeniths
//! (clamped outside). `sky` runs look up from the ground to space at a zenith
//! angle: `PTH_THRML + SOL_SCAT` is the sky radiance in that direction and
//! `TOT_TRANS` the solar transmittance τ₁ for the sun at that zenith; both
//! are interpolated linearly in zenith (clamped). Every spectrum is resampled
//! onto the caller's grid conservatively; a grid outside a run's spectral
//! coverage is an error naming the file.
//!
//! Owns the index format and the interpolation between runs (brackets and
//! lerps by [`crate::math`]). Takes an index path and a spectral grid; gives
//! [`PathSpectra`]. Must not know rays, pixels or the renderer.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::PathSpectra;
use super::tape7::{Tape7, Tape7Mode};
use crate::math::{bracket, lerp};
use crate::radiometry::SpectralGrid;
use crate::{Error, Location, Result};

/// Spectral tolerance at a grid's ends when resampling tape7 data, µm
/// (half a 1–2 cm⁻¹ MODTRAN step at 12 µm).
const EDGE_TOLERANCE_UM: f64 = 0.02;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct IndexFile {
    #[serde(default)]
    path: Vec<PathEntry>,
    #[serde(default)]
    sky: Vec<SkyEntry>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PathEntry {
    file: String,
    view_zenith_deg: f64,
    range_m: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SkyEntry {
    file: String,
    zenith_deg: f64,
}

/// One tape7 run of the table.
#[derive(Debug, Clone, PartialEq)]
pub struct Tape7Run {
    /// The file it came from.
    pub file: PathBuf,
    /// View zenith (path runs) or look zenith (sky runs), degrees.
    pub zenith_deg: f64,
    /// Range, m (0 for sky runs).
    pub range_m: f64,
    /// The parsed file.
    pub tape7: Tape7,
}

/// A lookup-table atmosphere of tape7 runs (see the module docs).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Tape7Lut {
    /// Surface-to-sensor runs.
    pub path_runs: Vec<Tape7Run>,
    /// Ground-to-space (looking up) runs.
    pub sky_runs: Vec<Tape7Run>,
}

fn resample(run: &Tape7Run, grid: &SpectralGrid) -> Result<PathSpectra> {
    let err = |e: Error| Error::parse(Location::file(&run.file), format!("{e}"));
    let (wl, tau) = run.tape7.transmittance_um();
    let transmittance = grid
        .resample_mean(&wl, &tau, EDGE_TOLERANCE_UM)
        .map_err(err)?;
    let (wl, lu) = run.tape7.path_radiance_um().ok_or_else(|| {
        Error::parse(
            Location::file(&run.file),
            "a transmittance-mode tape7 has no path radiance; the LUT needs radiance-mode runs",
        )
    })?;
    let path_radiance = grid
        .resample_mean(&wl, &lu, EDGE_TOLERANCE_UM)
        .map_err(err)?;
    Ok(PathSpectra {
        transmittance,
        path_radiance,
    })
}

fn lerp_spectra(a: &PathSpectra, b: &PathSpectra, t: f64) -> PathSpectra {
    let mix = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(&p, &q)| lerp(p, q, t)).collect();
    PathSpectra {
        transmittance: mix(&a.transmittance, &b.transmittance),
        path_radiance: mix(&a.path_radiance, &b.path_radiance),
    }
}

impl Tape7Lut {
    /// Read an index JSON file and every tape7 it lists.
    pub fn read_index(path: impl AsRef<Path>) -> Result<Tape7Lut> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let index: IndexFile = serde_json::from_str(&text).map_err(|e| {
            Error::parse(
                Location::file(path).at_line(e.line()),
                format!("invalid atmosphere index: {e}"),
            )
        })?;
        let base = path.parent().unwrap_or(Path::new("."));
        let mut lut = Tape7Lut::default();
        for (i, e) in index.path.iter().enumerate() {
            let field = |f: &str| Location::file(path).with_field(format!("path[{i}].{f}"));
            if !(0.0..90.0).contains(&e.view_zenith_deg) {
                return Err(Error::parse(
                    field("view_zenith_deg"),
                    format!("expected 0 ≤ zenith < 90°, got {}", e.view_zenith_deg),
                ));
            }
            if !(e.range_m.is_finite() && e.range_m > 0.0) {
                return Err(Error::parse(
                    field("range_m"),
                    format!("expected a positive range in m, got {}", e.range_m),
                ));
            }
            lut.path_runs.push(Self::load(
                base,
                &e.file,
                e.view_zenith_deg,
                e.range_m,
                field("file"),
            )?);
        }
        for (i, e) in index.sky.iter().enumerate() {
            let field = |f: &str| Location::file(path).with_field(format!("sky[{i}].{f}"));
            if !(0.0..90.0).contains(&e.zenith_deg) {
                return Err(Error::parse(
                    field("zenith_deg"),
                    format!("expected 0 ≤ zenith < 90°, got {}", e.zenith_deg),
                ));
            }
            lut.sky_runs
                .push(Self::load(base, &e.file, e.zenith_deg, 0.0, field("file"))?);
        }
        if lut.path_runs.is_empty() && lut.sky_runs.is_empty() {
            return Err(Error::parse(
                Location::file(path),
                "the atmosphere index lists no `path` or `sky` runs",
            ));
        }
        lut.validate()
            .map_err(|e| Error::parse(Location::file(path), e.to_string()))?;
        Ok(lut)
    }

    fn load(base: &Path, file: &str, zenith: f64, range: f64, loc: Location) -> Result<Tape7Run> {
        let p = base.join(file);
        let t = Tape7::read(&p).map_err(|e| Error::parse(loc.clone(), format!("{e}")))?;
        if t.mode != Tape7Mode::Radiance {
            return Err(Error::parse(
                loc,
                format!(
                    "{}: expected a radiance-mode tape7 (transmittance mode has no path radiance)",
                    p.display()
                ),
            ));
        }
        Ok(Tape7Run {
            file: p,
            zenith_deg: zenith,
            range_m: range,
            tape7: t,
        })
    }

    /// Check the runs: no two at the same (zenith, range).
    pub fn validate(&self) -> Result<()> {
        for runs in [&self.path_runs, &self.sky_runs] {
            for (i, a) in runs.iter().enumerate() {
                for b in &runs[..i] {
                    if a.zenith_deg == b.zenith_deg && a.range_m == b.range_m {
                        return Err(Error::invalid(
                            "runs",
                            format!(
                                "{} and {} are both at zenith {}° range {} m",
                                b.file.display(),
                                a.file.display(),
                                a.zenith_deg,
                                a.range_m
                            ),
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// Distinct zeniths of `runs`, sorted.
    fn zeniths(runs: &[Tape7Run]) -> Vec<f64> {
        let mut z: Vec<f64> = runs.iter().map(|r| r.zenith_deg).collect();
        z.sort_by(f64::total_cmp);
        z.dedup();
        z
    }

    /// Path spectra at `view_zenith_deg` and `range_m` on `grid`.
    pub fn path(
        &self,
        view_zenith_deg: f64,
        range_m: f64,
        grid: &SpectralGrid,
    ) -> Result<PathSpectra> {
        if self.path_runs.is_empty() {
            return Err(Error::invalid(
                "atmosphere",
                "the tape7 table has no `path` runs: it cannot give path transmittance",
            ));
        }
        let zs = Self::zeniths(&self.path_runs);
        let (i, j, t) = bracket(&zs, view_zenith_deg);
        let at_zenith = |z: f64| -> Result<PathSpectra> {
            let mut runs: Vec<&Tape7Run> = self
                .path_runs
                .iter()
                .filter(|r| r.zenith_deg == z)
                .collect();
            runs.sort_by(|a, b| a.range_m.total_cmp(&b.range_m));
            let mut ranges = vec![0.0];
            ranges.extend(runs.iter().map(|r| r.range_m));
            let (a, b, u) = bracket(&ranges, range_m.max(0.0));
            let get = |k: usize| -> Result<PathSpectra> {
                if k == 0 {
                    Ok(PathSpectra {
                        transmittance: vec![1.0; grid.len()],
                        path_radiance: vec![0.0; grid.len()],
                    })
                } else {
                    resample(runs[k - 1], grid)
                }
            };
            let sa = get(a)?;
            if a == b {
                return Ok(sa);
            }
            Ok(lerp_spectra(&sa, &get(b)?, u))
        };
        let si = at_zenith(zs[i])?;
        if i == j {
            return Ok(si);
        }
        Ok(lerp_spectra(&si, &at_zenith(zs[j])?, t))
    }

    /// Sky runs interpolated at `zenith_deg`: (τ to space, sky radiance).
    pub fn sky(&self, zenith_deg: f64, grid: &SpectralGrid) -> Result<PathSpectra> {
        if self.sky_runs.is_empty() {
            return Err(Error::invalid(
                "atmosphere",
                "the tape7 table has no `sky` runs: it cannot give sky radiance or solar \
                 transmittance",
            ));
        }
        let mut runs: Vec<&Tape7Run> = self.sky_runs.iter().collect();
        runs.sort_by(|a, b| a.zenith_deg.total_cmp(&b.zenith_deg));
        let zs: Vec<f64> = runs.iter().map(|r| r.zenith_deg).collect();
        let (i, j, t) = bracket(&zs, zenith_deg);
        let si = resample(runs[i], grid)?;
        if i == j {
            return Ok(si);
        }
        Ok(lerp_spectra(&si, &resample(runs[j], grid)?, t))
    }
}
