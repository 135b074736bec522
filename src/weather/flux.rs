//! Measured surface-energy-balance data from flux towers: the forcing a
//! thermal model runs on and the surface temperature and fluxes it is judged
//! against.
//!
//! **Reads** the two 30-min datasets of the project's validation data
//! (`../shared/data/flux/`, each folder with a README giving source, licence,
//! units and checks):
//!
//! | [`FluxSite`] | surface temperature | forcing wind | heights |
//! |---|---|---|---|
//! | `Bondville1998` (NOAA/ARL, = AmeriFlux US-Bo1, soybean) | infrared radiometer (`surface_temperature_c`) | `wind_speed_10m_m_s` (propeller, complete) | air 3 m, wind 10 m |
//! | `UsCrt2011` (AmeriFlux US-CRT, soybean, doi:10.17190/AMF/1246156) | from LW↑ and LW↓ (below) | `wind_speed_m_s` (sonic, 20 % gaps in summer) | not documented |
//!
//! Times in the files are UTC at the **start** of each 30-min averaging
//! interval; every value is a mean over its interval and a gap is an empty
//! cell. The reader keeps the gaps ([`FluxRecord`]'s fields are `Option`)
//! and checks that rows are contiguous 30-min steps.
//!
//! **Gives** (a) [`FluxDataset::weather`]: irsig weather records, each placed
//! at the **middle** of its interval (in the site's local standard time), the
//! global shortwave split into direct and diffuse by Erbs et al. (1982)
//! ([`crate::weather::physics::erbs_split`]) with the sun at that mid-interval
//! instant, the measured sky longwave, dew point from relative humidity
//! (clamped at 100 %: Bondville's hygrometer reads up to 109 % in fog),
//! negative wind read as calm, and gaps in wind and pressure filled by linear
//! interpolation in time between the neighbouring measurements (held at the
//! ends); air temperature, humidity and radiation are never filled: a gap is
//! an error naming file, line and column. (b) the measured series: surface
//! temperature, H, LE, G (positive: up, up, into the soil) and net radiation,
//! and [`FluxDataset::energy_balance_closure`].
//!
//! **Surface temperature of US-CRT** from the 4-component radiometer:
//! T_s = ((LW↑ − (1 − ε) LW↓) / (ε σ))^¼ with ε = [`CROP_EMISSIVITY`] = 0.98:
//! the broadband emissivity of a closed green crop canopy (0.97–0.99 in
//! measured vegetation spectra, e.g. the ASTER/ECOSTRESS spectral library),
//! and the value the dataset README's own consistency check uses. Bondville's
//! radiometer temperature is taken as reported (no emissivity correction is
//! documented).
//!
//! **Must not know** thermal models or scenes.

use std::io::Read;
use std::ops::Range;
use std::path::{Path, PathBuf};

use chrono::{DateTime, FixedOffset, TimeDelta, Utc};

use crate::error::{Error, Location, Result};
use crate::sun::{self, Site};
use crate::weather::physics::{
    STEFAN_BOLTZMANN_W_M2_K4, dew_point_from_relative_humidity, erbs_split,
};
use crate::weather::{WeatherHistory, WeatherRecord};

const ZERO_C_K: f64 = 273.15;

/// Broadband thermal emissivity used to turn US-CRT's LW↑ into a surface
/// temperature (module docs).
pub const CROP_EMISSIVITY: f64 = 0.98;

/// Length of every averaging interval, s.
pub const INTERVAL_S: i64 = 1800;

/// Which flux-tower dataset a file is (told apart by its header).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum FluxSite {
    /// Bondville, Illinois, 1998 (NOAA/ARL; AmeriFlux US-Bo1), no-till soybean.
    Bondville1998,
    /// Curtice, Ohio, 2011 (AmeriFlux US-CRT), soybean.
    UsCrt2011,
}

impl FluxSite {
    /// The tower's location. Bondville's elevation is not in its source; the
    /// SURFRAD Bondville station a few km away is at 213 m, consistent with
    /// the file's mean pressure (README).
    pub fn site(&self) -> Site {
        match self {
            FluxSite::Bondville1998 => Site {
                latitude_deg: 40.01,
                longitude_deg: -88.37,
                altitude_m: 213.0,
            },
            FluxSite::UsCrt2011 => Site {
                latitude_deg: 41.628495,
                longitude_deg: -83.347086,
                altitude_m: 180.0,
            },
        }
    }

    /// Local standard time of the site (UTC−6 Bondville, UTC−5 US-CRT; the
    /// sources' own stamps, no daylight saving).
    pub fn local_standard_time(&self) -> FixedOffset {
        let hours = match self {
            FluxSite::Bondville1998 => -6,
            FluxSite::UsCrt2011 => -5,
        };
        FixedOffset::east_opt(hours * 3600).expect("a whole-hour offset is valid")
    }

    /// Height of the air temperature and humidity sensor, m, where documented.
    pub fn air_height_m(&self) -> Option<f64> {
        match self {
            FluxSite::Bondville1998 => Some(3.0),
            FluxSite::UsCrt2011 => None,
        }
    }

    /// Height of the forcing wind measurement, m, where documented.
    pub fn wind_height_m(&self) -> Option<f64> {
        match self {
            FluxSite::Bondville1998 => Some(10.0),
            FluxSite::UsCrt2011 => None,
        }
    }

    /// How the measured surface temperature is obtained.
    pub fn surface_temperature_source(&self) -> &'static str {
        match self {
            FluxSite::Bondville1998 => "infrared radiometer (surface_temperature_c)",
            FluxSite::UsCrt2011 => "LW↑ and LW↓ with emissivity (lw_up_w_m2, lw_down_w_m2)",
        }
    }

    /// Column names: (forcing wind, ground heat flux columns, site-specific
    /// required columns).
    fn columns(&self) -> SiteColumns {
        match self {
            FluxSite::Bondville1998 => SiteColumns {
                wind: "wind_speed_10m_m_s",
                ground: &["ground_heat_w_m2"],
                surface_c: Some("surface_temperature_c"),
                lw_up: None,
                friction_velocity: None,
            },
            FluxSite::UsCrt2011 => SiteColumns {
                wind: "wind_speed_m_s",
                ground: &["ground_heat_w_m2_plate1", "ground_heat_w_m2_plate2"],
                surface_c: None,
                lw_up: Some("lw_up_w_m2"),
                friction_velocity: Some("friction_velocity_m_s"),
            },
        }
    }

    fn detect(headers: &csv::StringRecord) -> Option<FluxSite> {
        let has = |name: &str| headers.iter().any(|h| h == name);
        if has("surface_temperature_c") && has("wind_speed_10m_m_s") {
            Some(FluxSite::Bondville1998)
        } else if has("lw_up_w_m2") && has("ground_heat_w_m2_plate1") {
            Some(FluxSite::UsCrt2011)
        } else {
            None
        }
    }
}

struct SiteColumns {
    wind: &'static str,
    ground: &'static [&'static str],
    surface_c: Option<&'static str>,
    lw_up: Option<&'static str>,
    friction_velocity: Option<&'static str>,
}

/// Columns common to both datasets.
const COMMON: [&str; 8] = [
    "time_utc",
    "air_temperature_c",
    "relative_humidity_pct",
    "pressure_hpa",
    "sw_down_w_m2",
    "lw_down_w_m2",
    "net_radiation_w_m2",
    "precipitation_mm",
];

/// One 30-min interval as measured; `None` is a gap in the file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FluxRecord {
    /// Start of the averaging interval, UTC.
    pub start: DateTime<Utc>,
    /// 1-based line of the record in its file.
    pub line: usize,
    /// Air temperature, K.
    pub air_temperature_k: Option<f64>,
    /// Relative humidity as measured, fraction (may exceed 1, README).
    pub relative_humidity: Option<f64>,
    /// Station pressure, Pa.
    pub pressure_pa: Option<f64>,
    /// Forcing wind speed, m s⁻¹ ([`FluxSite::wind_height_m`]).
    pub wind_speed_m_s: Option<f64>,
    /// Friction velocity u* from the eddy covariance, m s⁻¹ (US-CRT only).
    pub friction_velocity_m_s: Option<f64>,
    /// Global horizontal shortwave irradiance, W m⁻².
    pub global_horizontal_w_m2: Option<f64>,
    /// Downwelling longwave irradiance, W m⁻².
    pub sky_longwave_w_m2: Option<f64>,
    /// Upwelling longwave irradiance (US-CRT only), W m⁻².
    pub longwave_up_w_m2: Option<f64>,
    /// Net all-wave radiation, W m⁻² (positive: down).
    pub net_radiation_w_m2: Option<f64>,
    /// Measured surface temperature, K (module docs for its source).
    pub surface_temperature_k: Option<f64>,
    /// Sensible heat flux H, W m⁻² (positive: upward).
    pub sensible_heat_w_m2: Option<f64>,
    /// Latent heat flux LE, W m⁻² (positive: upward).
    pub latent_heat_w_m2: Option<f64>,
    /// Ground heat flux G, W m⁻² (positive: into the soil; US-CRT: the mean
    /// of the plates present).
    pub ground_heat_w_m2: Option<f64>,
    /// Precipitation over the interval, mm.
    pub precipitation_mm: Option<f64>,
}

impl FluxRecord {
    /// Rn − G − H − LE, W m⁻²: the energy-balance residual, when all four
    /// terms are present.
    pub fn residual_w_m2(&self) -> Option<f64> {
        Some(
            self.net_radiation_w_m2?
                - self.ground_heat_w_m2?
                - self.sensible_heat_w_m2?
                - self.latent_heat_w_m2?,
        )
    }
}

/// A flux-tower file, read.
#[derive(Debug, Clone, PartialEq)]
pub struct FluxDataset {
    path: PathBuf,
    site: FluxSite,
    emissivity: f64,
    records: Vec<FluxRecord>,
}

/// Energy-balance closure over a set of records (those with Rn, G, H and LE
/// all present).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnergyBalanceClosure {
    /// Records used.
    pub records: usize,
    /// Σ(H + LE) / Σ(Rn − G).
    pub ratio_of_sums: f64,
    /// Least-squares slope of H + LE against Rn − G.
    pub slope: f64,
    /// Least-squares intercept, W m⁻².
    pub intercept_w_m2: f64,
    /// Mean of Rn − G − H − LE, W m⁻².
    pub mean_residual_w_m2: f64,
}

/// How many values [`FluxDataset::weather`] filled or adjusted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ForcingFills {
    /// Wind speeds interpolated across gaps.
    pub wind_interpolated: usize,
    /// Pressures interpolated across gaps.
    pub pressure_interpolated: usize,
    /// Negative wind speeds read as calm.
    pub wind_negative_to_calm: usize,
    /// Relative humidities above 100 % clamped to 100 %.
    pub humidity_clamped: usize,
}

/// Read a flux-tower CSV file (either dataset; told apart by its header),
/// with US-CRT's surface temperature from [`CROP_EMISSIVITY`].
///
/// # Errors
/// I/O errors; a header that is neither dataset's; a cell that is not a
/// number, a time that is not RFC 3339 or not 30 min after the previous row
/// (each naming file, line and column).
pub fn load(path: &Path) -> Result<FluxDataset> {
    load_with_emissivity(path, CROP_EMISSIVITY)
}

/// As [`load`], with the emissivity `emissivity` (0 < ε ≤ 1) for a surface
/// temperature derived from longwave (US-CRT; unused for Bondville).
///
/// # Errors
/// As [`load`]; an emissivity outside (0, 1].
pub fn load_with_emissivity(path: &Path, emissivity: f64) -> Result<FluxDataset> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    from_reader(file, path, emissivity)
}

/// Read a flux-tower CSV from `reader`; `path` is used in messages.
///
/// # Errors
/// As [`load_with_emissivity`].
pub fn from_reader(reader: impl Read, path: &Path, emissivity: f64) -> Result<FluxDataset> {
    if !(emissivity > 0.0 && emissivity <= 1.0) {
        return Err(Error::invalid(
            "emissivity",
            format!("{emissivity} is outside (0, 1]"),
        ));
    }
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(reader);
    let csv_err = |e: csv::Error| {
        let mut loc = Location::file(path);
        if let Some(p) = e.position() {
            loc = loc.at_line(p.line() as usize);
        }
        Error::parse(loc, e.to_string())
    };
    let headers = rdr.headers().map_err(csv_err)?.clone();
    let site = FluxSite::detect(&headers).ok_or_else(|| {
        Error::parse(
            Location::file(path).at_line(1),
            "the header is neither the Bondville 1998 nor the US-CRT 2011 flux dataset's \
             (expected `surface_temperature_c` and `wind_speed_10m_m_s`, or `lw_up_w_m2` and \
             `ground_heat_w_m2_plate1`)",
        )
    })?;
    let cols = site.columns();
    let column = |name: &'static str| -> Result<usize> {
        headers.iter().position(|h| h == name).ok_or_else(|| {
            Error::parse(
                Location::file(path).at_line(1).with_field(name),
                format!("column `{name}` is missing from the header"),
            )
        })
    };
    let mut idx = std::collections::HashMap::new();
    let site_cols = [
        Some(cols.wind),
        cols.surface_c,
        cols.lw_up,
        cols.friction_velocity,
        Some("sensible_heat_w_m2"),
        Some("latent_heat_w_m2"),
    ];
    for name in COMMON
        .iter()
        .copied()
        .chain(site_cols.into_iter().flatten())
        .chain(cols.ground.iter().copied())
    {
        idx.insert(name, column(name)?);
    }

    let mut records: Vec<FluxRecord> = Vec::new();
    for row in rdr.records() {
        let row = row.map_err(csv_err)?;
        let line = row.position().map_or(0, |p| p.line() as usize);
        let loc = |field: &str| Location::file(path).at_line(line).with_field(field);
        let num = |name: &'static str| -> Result<Option<f64>> {
            let cell = row.get(idx[name]).unwrap_or("").trim();
            if cell.is_empty() {
                return Ok(None);
            }
            let v: f64 = cell
                .parse()
                .map_err(|_| Error::parse(loc(name), format!("`{cell}` is not a number")))?;
            if v.is_finite() {
                Ok(Some(v))
            } else {
                Err(Error::parse(loc(name), format!("`{cell}` is not finite")))
            }
        };
        let time_cell = row.get(idx["time_utc"]).unwrap_or("").trim();
        let start = DateTime::parse_from_rfc3339(time_cell)
            .map_err(|e| {
                Error::parse(
                    loc("time_utc"),
                    format!("`{time_cell}` is not an RFC 3339 time ({e})"),
                )
            })?
            .with_timezone(&Utc);
        if let Some(prev) = records.last() {
            let step = start - prev.start;
            if step != TimeDelta::seconds(INTERVAL_S) {
                return Err(Error::parse(
                    loc("time_utc"),
                    format!(
                        "{start} is {} s after the previous row ({}); expected contiguous \
                         {INTERVAL_S} s steps",
                        step.num_seconds(),
                        prev.start
                    ),
                ));
            }
        }
        let lw_down = num("lw_down_w_m2")?;
        let lw_up = match cols.lw_up {
            Some(c) => num(c)?,
            None => None,
        };
        let surface_temperature_k = match (cols.surface_c, lw_up, lw_down) {
            (Some(c), _, _) => num(c)?.map(|t| t + ZERO_C_K),
            (None, Some(up), Some(down)) => {
                surface_temperature_from_longwave_k(up, down, emissivity)
            }
            _ => None,
        };
        let mut g_sum = 0.0;
        let mut g_n = 0;
        for c in cols.ground {
            if let Some(g) = num(c)? {
                g_sum += g;
                g_n += 1;
            }
        }
        records.push(FluxRecord {
            start,
            line,
            air_temperature_k: num("air_temperature_c")?.map(|t| t + ZERO_C_K),
            relative_humidity: num("relative_humidity_pct")?.map(|r| r / 100.0),
            pressure_pa: num("pressure_hpa")?.map(|p| p * 100.0),
            wind_speed_m_s: num(cols.wind)?,
            friction_velocity_m_s: match cols.friction_velocity {
                Some(c) => num(c)?,
                None => None,
            },
            global_horizontal_w_m2: num("sw_down_w_m2")?,
            sky_longwave_w_m2: lw_down,
            longwave_up_w_m2: lw_up,
            net_radiation_w_m2: num("net_radiation_w_m2")?,
            surface_temperature_k,
            sensible_heat_w_m2: num("sensible_heat_w_m2")?,
            latent_heat_w_m2: num("latent_heat_w_m2")?,
            ground_heat_w_m2: (g_n > 0).then(|| g_sum / g_n as f64),
            precipitation_mm: num("precipitation_mm")?,
        });
    }
    if records.len() < 2 {
        return Err(Error::parse(
            Location::file(path),
            format!("{} data rows; expected at least 2", records.len()),
        ));
    }
    Ok(FluxDataset {
        path: path.to_path_buf(),
        site,
        emissivity,
        records,
    })
}

/// Surface temperature from upwelling and downwelling longwave, K:
/// T = ((LW↑ − (1 − ε) LW↓) / (ε σ))^¼ (the emitted part of LW↑ after the
/// reflected sky is removed). `None` when the emitted part is not positive.
pub fn surface_temperature_from_longwave_k(
    lw_up_w_m2: f64,
    lw_down_w_m2: f64,
    emissivity: f64,
) -> Option<f64> {
    let emitted = lw_up_w_m2 - (1.0 - emissivity) * lw_down_w_m2;
    (emitted > 0.0).then(|| (emitted / (emissivity * STEFAN_BOLTZMANN_W_M2_K4)).powf(0.25))
}

impl FluxDataset {
    /// The file read.
    pub fn path(&self) -> &Path {
        &self.path
    }
    /// Which dataset it is.
    pub fn site(&self) -> FluxSite {
        self.site
    }
    /// The emissivity used for a longwave-derived surface temperature.
    pub fn emissivity(&self) -> f64 {
        self.emissivity
    }
    /// The records, contiguous 30-min intervals.
    pub fn records(&self) -> &[FluxRecord] {
        &self.records
    }
    /// Number of records.
    pub fn len(&self) -> usize {
        self.records.len()
    }
    /// Whether there are no records (never, for a loaded file).
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }
    /// The first half of the records (calibration).
    pub fn first_half(&self) -> Range<usize> {
        0..self.records.len() / 2
    }
    /// The second half of the records (prediction).
    pub fn second_half(&self) -> Range<usize> {
        self.records.len() / 2..self.records.len()
    }
    /// Middle of interval `i` in the site's local standard time.
    pub fn mid_interval(&self, i: usize) -> DateTime<FixedOffset> {
        (self.records[i].start + TimeDelta::seconds(INTERVAL_S / 2))
            .with_timezone(&self.site.local_standard_time())
    }

    /// Number of records in `range` where `field` is a gap.
    pub fn gaps(&self, range: Range<usize>, field: impl Fn(&FluxRecord) -> Option<f64>) -> usize {
        self.records[range]
            .iter()
            .filter(|r| field(r).is_none())
            .count()
    }

    /// The forcing of records `range` as an irsig weather history (module
    /// docs), with the counts of what was filled or adjusted.
    ///
    /// # Errors
    /// [`Error::Parse`] naming file, line and column for a gap in air
    /// temperature, humidity, global shortwave or sky longwave, a humidity
    /// ≤ 0, or a column with no value at all in `range` for wind or
    /// pressure; fewer than 2 records; as [`WeatherHistory::new`].
    pub fn weather(&self, range: Range<usize>) -> Result<(WeatherHistory, ForcingFills)> {
        let recs = &self.records[range.clone()];
        let mut fills = ForcingFills::default();
        let cols = self.site.columns();
        // Interpolated up front, checked after the never-filled columns (so
        // that their gaps are reported first).
        let wind = interpolate_gaps(recs, |r| r.wind_speed_m_s);
        let pressure = interpolate_gaps(recs, |r| r.pressure_pa);
        fills.wind_interpolated = recs.iter().filter(|r| r.wind_speed_m_s.is_none()).count();
        fills.pressure_interpolated = recs.iter().filter(|r| r.pressure_pa.is_none()).count();
        let site = self.site.site();
        let mut out = Vec::with_capacity(recs.len());
        for (k, r) in recs.iter().enumerate() {
            let need = |v: Option<f64>, col: &str| -> Result<f64> {
                v.ok_or_else(|| {
                    Error::parse(
                        Location::file(&self.path).at_line(r.line).with_field(col),
                        "a gap in a forcing value that is never filled",
                    )
                })
            };
            let air = need(r.air_temperature_k, "air_temperature_c")?;
            let mut rh = need(r.relative_humidity, "relative_humidity_pct")?;
            if rh <= 0.0 {
                return Err(Error::parse(
                    Location::file(&self.path)
                        .at_line(r.line)
                        .with_field("relative_humidity_pct"),
                    format!("{} % is not a humidity; expected > 0", rh * 100.0),
                ));
            }
            if rh > 1.0 {
                rh = 1.0;
                fills.humidity_clamped += 1;
            }
            let ghi = need(r.global_horizontal_w_m2, "sw_down_w_m2")?.max(0.0);
            let sky = need(r.sky_longwave_w_m2, "lw_down_w_m2")?;
            let (Some(wind), Some(pressure)) = (&wind, &pressure) else {
                let col = if wind.is_none() {
                    cols.wind
                } else {
                    "pressure_hpa"
                };
                return Err(self.no_values(recs, col));
            };
            let mut u = wind[k];
            if u < 0.0 {
                u = 0.0;
                fills.wind_negative_to_calm += 1;
            }
            let time = self.mid_interval(range.start + k);
            let sun = sun::position_standard(&site, time).map_err(|e| {
                Error::parse(
                    Location::file(&self.path).at_line(r.line),
                    format!("solar position for the Erbs split: {e}"),
                )
            })?;
            let (dni, dhi) = erbs_split(ghi, sun.apparent_zenith_deg, sun.distance_au);
            out.push(WeatherRecord {
                time,
                air_temperature_k: air,
                dew_point_k: dew_point_from_relative_humidity(air, rh),
                relative_humidity: rh,
                pressure_pa: pressure[k],
                wind_speed_m_s: u,
                wind_direction_deg: 180.0,
                direct_normal_w_m2: dni,
                diffuse_horizontal_w_m2: dhi,
                global_horizontal_w_m2: ghi,
                sky_longwave_w_m2: sky,
                // Unknown; irsig uses sky cover only to fill a missing sky
                // longwave, which these files measure. EnergyPlus' default.
                total_sky_cover: 0.5,
                opaque_sky_cover: 0.5,
                precipitation_mm: r.precipitation_mm.unwrap_or(0.0).max(0.0),
                visibility_km: None,
            });
        }
        let history = WeatherHistory::new(out, Some(site))
            .map_err(|e| Error::parse(Location::file(&self.path), format!("as weather: {e}")))?;
        Ok((history, fills))
    }

    fn no_values(&self, recs: &[FluxRecord], col: &str) -> Error {
        let line = recs.first().map_or(0, |r| r.line);
        Error::parse(
            Location::file(&self.path).at_line(line).with_field(col),
            format!(
                "no `{col}` value at all in the {} records from this line; nothing to \
                 interpolate from",
                recs.len()
            ),
        )
    }

    /// The height of the wind measurement that the neutral logarithmic
    /// profile implies, m, where the site documents none (US-CRT): the
    /// median over the near-neutral records of `range` (|H| < 20 W m⁻²,
    /// U ≥ 2.5 m s⁻¹, u* ≥ 0.1 m s⁻¹) of
    /// `z = d + z_om exp(k U/u*)` (the log law `U = (u*/k) ln((z − d)/z_om)`
    /// solved for z; k = 0.41), with FAO-56's `d = 2/3 h`, `z_om = 0.123 h`
    /// (Allen et al. 1998, eq. 4) for the canopy height `h` that
    /// `canopy_height_m` gives at a record's start. None without measured
    /// friction velocity (Bondville) or without a near-neutral record.
    pub fn log_law_wind_height_m(
        &self,
        range: Range<usize>,
        canopy_height_m: impl Fn(DateTime<Utc>) -> f64,
    ) -> Option<f64> {
        const VON_KARMAN: f64 = 0.41;
        let mut z: Vec<f64> = self.records[range]
            .iter()
            .filter_map(|r| {
                let (u, us, h) = (
                    r.wind_speed_m_s?,
                    r.friction_velocity_m_s?,
                    r.sensible_heat_w_m2?,
                );
                (u >= 2.5 && us >= 0.1 && h.abs() < 20.0).then(|| {
                    let hc = canopy_height_m(r.start);
                    2.0 / 3.0 * hc + 0.123 * hc * (VON_KARMAN * u / us).exp()
                })
            })
            .filter(|z| z.is_finite())
            .collect();
        if z.is_empty() {
            return None;
        }
        z.sort_by(f64::total_cmp);
        let n = z.len();
        Some(if n % 2 == 1 {
            z[n / 2]
        } else {
            0.5 * (z[n / 2 - 1] + z[n / 2])
        })
    }

    /// Energy-balance closure over the records of `range` whose global
    /// shortwave exceeds `min_shortwave_w_m2` (e.g. 20 W m⁻² for daytime;
    /// −∞ for all) and whose Rn, G, H and LE are all present.
    pub fn energy_balance_closure(
        &self,
        range: Range<usize>,
        min_shortwave_w_m2: f64,
    ) -> EnergyBalanceClosure {
        let pairs: Vec<(f64, f64)> = self.records[range]
            .iter()
            .filter(|r| {
                r.global_horizontal_w_m2
                    .is_some_and(|s| s > min_shortwave_w_m2)
            })
            .filter_map(|r| {
                let avail = r.net_radiation_w_m2? - r.ground_heat_w_m2?;
                let turb = r.sensible_heat_w_m2? + r.latent_heat_w_m2?;
                Some((avail, turb))
            })
            .collect();
        let n = pairs.len() as f64;
        let (sx, sy) = pairs
            .iter()
            .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x, b + y));
        let (mx, my) = (sx / n, sy / n);
        let (sxy, sxx) = pairs.iter().fold((0.0, 0.0), |(a, b), &(x, y)| {
            (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
        });
        let slope = sxy / sxx;
        EnergyBalanceClosure {
            records: pairs.len(),
            ratio_of_sums: sy / sx,
            slope,
            intercept_w_m2: my - slope * mx,
            mean_residual_w_m2: mx - my,
        }
    }
}

/// `field` of every record, gaps filled by linear interpolation in time
/// between the nearest values either side (held constant before the first
/// and after the last). `None` when there is no value at all.
fn interpolate_gaps(
    recs: &[FluxRecord],
    field: impl Fn(&FluxRecord) -> Option<f64>,
) -> Option<Vec<f64>> {
    let (xs, ys): (Vec<f64>, Vec<f64>) = recs
        .iter()
        .enumerate()
        .filter_map(|(i, r)| field(r).map(|v| (i as f64, v)))
        .unzip();
    if xs.is_empty() {
        return None;
    }
    let out = (0..recs.len())
        .map(|i| crate::math::interp1d(&xs, &ys, i as f64))
        .collect();
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(i: usize, v: Option<f64>) -> FluxRecord {
        FluxRecord {
            start: DateTime::from_timestamp(i as i64 * INTERVAL_S, 0).unwrap(),
            line: i + 2,
            air_temperature_k: None,
            relative_humidity: None,
            pressure_pa: None,
            wind_speed_m_s: v,
            friction_velocity_m_s: None,
            global_horizontal_w_m2: None,
            sky_longwave_w_m2: None,
            longwave_up_w_m2: None,
            net_radiation_w_m2: None,
            surface_temperature_k: None,
            sensible_heat_w_m2: None,
            latent_heat_w_m2: None,
            ground_heat_w_m2: None,
            precipitation_mm: None,
        }
    }

    #[test]
    fn the_log_law_recovers_the_wind_height() {
        // Winds at 2.5 m over a 0.6 m canopy, each with the u* of the
        // neutral log law (d = 0.4 m, z_om = 0.0738 m); records that are not
        // near-neutral, too calm or without u* do not count.
        let (z, h): (f64, f64) = (2.5, 0.6);
        let ln = ((z - 2.0 / 3.0 * h) / (0.123 * h)).ln();
        let mut records: Vec<FluxRecord> = [2.5, 3.0, 4.0, 5.5, 7.0]
            .iter()
            .enumerate()
            .map(|(i, &u)| FluxRecord {
                friction_velocity_m_s: Some(0.41 * u / ln),
                sensible_heat_w_m2: Some(5.0),
                ..rec(i, Some(u))
            })
            .collect();
        let wrong = |i: usize, u: f64, us: Option<f64>, hf: f64| FluxRecord {
            friction_velocity_m_s: us,
            sensible_heat_w_m2: Some(hf),
            ..rec(i, Some(u))
        };
        records.push(wrong(5, 3.0, Some(0.05), 5.0));
        records.push(wrong(6, 3.0, Some(0.9), 150.0));
        records.push(wrong(7, 1.0, Some(0.3), 5.0));
        records.push(wrong(8, 3.0, None, 5.0));
        let d = FluxDataset {
            path: PathBuf::from("x.csv"),
            site: FluxSite::UsCrt2011,
            emissivity: 0.98,
            records,
        };
        let est = d.log_law_wind_height_m(0..d.len(), |_| h).unwrap();
        assert!((est - z).abs() < 1e-9, "{est}");
        assert!(d.log_law_wind_height_m(5..9, |_| h).is_none());
    }

    #[test]
    fn gaps_are_interpolated_linearly_and_held_at_the_ends() {
        let vals = [None, Some(1.0), None, None, Some(4.0), None];
        let recs: Vec<_> = vals.iter().enumerate().map(|(i, v)| rec(i, *v)).collect();
        let out = interpolate_gaps(&recs, |r| r.wind_speed_m_s).unwrap();
        assert_eq!(out, vec![1.0, 1.0, 2.0, 3.0, 4.0, 4.0]);
        let none: Vec<_> = (0..3).map(|i| rec(i, None)).collect();
        assert!(interpolate_gaps(&none, |r| r.wind_speed_m_s).is_none());
    }

    #[test]
    fn longwave_surface_temperature_inverts_the_emission() {
        let (t, eps, down) = (300.0_f64, 0.98, 350.0);
        let up = eps * STEFAN_BOLTZMANN_W_M2_K4 * t.powi(4) + (1.0 - eps) * down;
        let back = surface_temperature_from_longwave_k(up, down, eps).unwrap();
        assert!((back - t).abs() < 1e-9, "{back}");
        assert!(surface_temperature_from_longwave_k(0.0, 300.0, 0.9).is_none());
    }
}
