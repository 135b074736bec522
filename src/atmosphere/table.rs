//! A precomputed table of path spectra for one sensor position, so the
//! render integrator can look paths up per hit instead of integrating the
//! atmosphere per pixel.
//!
//! For a sensor at a fixed altitude, a straight path is fixed by its view
//! zenith at the target θ and its range R (target altitude = sensor altitude
//! − R cos θ). The table samples cos θ uniformly and R on a geometric grid
//! starting at the exact R = 0 limit (τ = 1, L_u = 0); lookups interpolate
//! bilinearly in (cos θ, R), clamped to the table. Linear interpolation keeps
//! the monotonicity in range of the underlying model; L_u is concave in R,
//! so ~50 ranges (a ×1.2 step) keep the interpolation error below 1 %.
//!
//! Owns the table and its lookups (brackets by [`crate::math`]). Takes an
//! [`Atmosphere`] and the sensor altitude; gives [`PathSpectra`] by target
//! altitude and range. Must not know rays, pixels or where the sensor points.

use super::{Atmosphere, PathGeometry, PathSpectra};
use crate::math::bracket;
use crate::radiometry::SpectralGrid;
use crate::{Error, Result};

/// Path spectra tabulated over view zenith and range (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct PathTable {
    sensor_altitude_m: f64,
    cos_zenith: Vec<f64>,
    ranges_m: Vec<f64>,
    /// [zenith][range] spectra.
    spectra: Vec<Vec<PathSpectra>>,
    n: usize,
}

impl PathTable {
    /// Tabulate `atmosphere` for a sensor at `sensor_altitude_m`, view
    /// zeniths from 0 to `max_zenith_deg` (`n_zenith` ≥ 1 values of cos θ),
    /// ranges up to `max_range_m` (`n_range` ≥ 2 values, geometric from
    /// `max_range_m`/10⁴, plus R = 0), on `grid`. Paths whose target would
    /// lie above the sensor are not needed (θ < 90° looks down) and zeniths
    /// must be below 90°.
    pub fn new(
        atmosphere: &Atmosphere,
        sensor_altitude_m: f64,
        max_zenith_deg: f64,
        n_zenith: usize,
        max_range_m: f64,
        n_range: usize,
        grid: &SpectralGrid,
    ) -> Result<Self> {
        if !(0.0..90.0).contains(&max_zenith_deg) || n_zenith == 0 {
            return Err(Error::invalid(
                "max_zenith_deg",
                format!("expected 0 ≤ zenith < 90° and at least one zenith, got {max_zenith_deg}"),
            ));
        }
        if !(max_range_m.is_finite() && max_range_m > 0.0) || n_range < 2 {
            return Err(Error::invalid(
                "max_range_m",
                format!("expected a positive range and ≥ 2 ranges, got {max_range_m} m"),
            ));
        }
        let cmin = max_zenith_deg.to_radians().cos();
        let cos_zenith: Vec<f64> = if n_zenith == 1 {
            vec![1.0]
        } else {
            (0..n_zenith)
                .map(|i| cmin + (1.0 - cmin) * i as f64 / (n_zenith - 1) as f64)
                .collect()
        };
        let r0 = max_range_m * 1e-4;
        let mut ranges_m = vec![0.0];
        ranges_m.extend(
            (0..n_range).map(|i| r0 * (max_range_m / r0).powf(i as f64 / (n_range - 1) as f64)),
        );
        let n = grid.len();
        let mut spectra = Vec::with_capacity(cos_zenith.len());
        for &c in &cos_zenith {
            let mut row = Vec::with_capacity(ranges_m.len());
            for &r in &ranges_m {
                let geom = PathGeometry {
                    sensor_altitude_m,
                    target_altitude_m: sensor_altitude_m - r * c,
                    range_m: r,
                };
                row.push(atmosphere.path(&geom, grid)?);
            }
            spectra.push(row);
        }
        Ok(PathTable {
            sensor_altitude_m,
            cos_zenith,
            ranges_m,
            spectra,
            n,
        })
    }

    /// The sensor altitude the table was built for, m.
    pub fn sensor_altitude_m(&self) -> f64 {
        self.sensor_altitude_m
    }

    /// Interpolated τ₂ and L_u for a path of `range_m` whose target is
    /// `sensor_altitude_m − target_altitude_m` below the sensor, written into
    /// `out` (resized to the grid).
    pub fn lookup(&self, target_altitude_m: f64, range_m: f64, out: &mut PathSpectra) {
        let c = if range_m > 0.0 {
            ((self.sensor_altitude_m - target_altitude_m) / range_m).clamp(-1.0, 1.0)
        } else {
            1.0
        };
        let (i0, i1, tz) = bracket(&self.cos_zenith, c);
        let (j0, j1, tr) = bracket(&self.ranges_m, range_m.max(0.0));
        out.transmittance.resize(self.n, 0.0);
        out.path_radiance.resize(self.n, 0.0);
        let w = [
            ((i0, j0), (1.0 - tz) * (1.0 - tr)),
            ((i0, j1), (1.0 - tz) * tr),
            ((i1, j0), tz * (1.0 - tr)),
            ((i1, j1), tz * tr),
        ];
        out.transmittance.iter_mut().for_each(|v| *v = 0.0);
        out.path_radiance.iter_mut().for_each(|v| *v = 0.0);
        for ((i, j), wt) in w {
            if wt == 0.0 {
                continue;
            }
            let s = &self.spectra[i][j];
            for k in 0..self.n {
                out.transmittance[k] += wt * s.transmittance[k];
                out.path_radiance[k] += wt * s.path_radiance[k];
            }
        }
    }
}
