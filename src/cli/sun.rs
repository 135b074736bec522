//! `irsig sun`: solar position (NREL SPA) for a place and time.

use std::io::Write;

use irsig::sun::{self, Site};

/// Arguments of `irsig sun`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Latitude, degrees, north positive (−90..90).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub lat: f64,
    /// Longitude, degrees, east positive (−180..180; Rochester NY is −77.61).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub lon: f64,
    /// Altitude above mean sea level, metres.
    #[arg(
        long,
        value_name = "M",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub alt: f64,
    /// Time, RFC 3339 with a UTC offset (e.g. 2025-06-21T14:00:00-04:00).
    #[arg(long, value_name = "RFC3339")]
    pub time: String,
    /// ΔT = TT − UT1 in seconds (default: Espenak & Meeus estimate for the date).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub delta_t: Option<f64>,
    /// Pressure for refraction, mbar (default: standard atmosphere at --alt).
    #[arg(long, value_name = "MBAR")]
    pub pressure: Option<f64>,
    /// Temperature for refraction, °C (default: standard atmosphere at --alt).
    #[arg(long, value_name = "C", allow_negative_numbers = true)]
    pub temperature: Option<f64>,
    /// Print JSON: {"zenith_deg", "apparent_zenith_deg", "azimuth_deg", "distance_au"}.
    #[arg(long)]
    pub json: bool,
}

/// Run `irsig sun`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let time = super::args::parse_time("--time", &args.time)?;
    let site = Site::new(args.lat, args.lon, args.alt)?;
    let delta_t = match args.delta_t {
        Some(d) => d,
        None => sun::delta_t_estimate_s(&time)?,
    };
    let pressure = args
        .pressure
        .unwrap_or_else(|| sun::standard_pressure_pa(site.altitude_m) / 100.0);
    let temperature = args
        .temperature
        .unwrap_or_else(|| sun::standard_temperature_c(site.altitude_m));
    let p = sun::position(&site, time, delta_t, pressure, temperature)?;
    let mut out = std::io::stdout().lock();
    if args.json {
        let v = serde_json::json!({
            "zenith_deg": p.zenith_deg,
            "apparent_zenith_deg": p.apparent_zenith_deg,
            "azimuth_deg": p.azimuth_deg,
            "distance_au": p.distance_au,
        });
        writeln!(out, "{v}")?;
    } else {
        writeln!(out, "time                 {}", time.to_rfc3339())?;
        writeln!(
            out,
            "site                 lat {:.6}°, lon {:.6}°, alt {:.1} m",
            site.latitude_deg, site.longitude_deg, site.altitude_m
        )?;
        writeln!(
            out,
            "delta_t              {delta_t:.2} s; refraction at {pressure:.2} mbar, {temperature:.2} °C"
        )?;
        writeln!(out, "zenith_deg           {:.6}", p.zenith_deg)?;
        writeln!(out, "apparent_zenith_deg  {:.6}", p.apparent_zenith_deg)?;
        writeln!(out, "azimuth_deg          {:.6}", p.azimuth_deg)?;
        writeln!(out, "distance_au          {:.10}", p.distance_au)?;
    }
    Ok(())
}
