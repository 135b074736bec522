//! `irsig atmosphere`: the transmittance and path radiance a render uses,
//! for one path and band — looking up (the sky) or between a sensor and a
//! target.

use std::path::PathBuf;

use anyhow::Context;
use irsig::atmosphere::{
    Aerosol, AerosolModel, Atmosphere, BuiltinAtmosphere, BuiltinParams, PathGeometry, Profile,
    SkyConditions, Sun, SurfaceMet,
};

use super::args::{parse_site, parse_time};

/// Which way the path looks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Look {
    /// From the ground to space: τ to space and the sky radiance.
    Up,
    /// From the sensor down to the target.
    Down,
}

/// The boundary-layer aerosol of the built-in model (LOWTRAN 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum AerosolArg {
    /// Continental air away from towns and industry (LOWTRAN's default;
    /// 23 km visibility unless given).
    Rural,
    /// Rural air with 20 % soot-like particles (5 km unless given).
    Urban,
    /// Sea salt over a continental background (23 km unless given).
    Maritime,
    /// No aerosol: gases only (clear air).
    None,
}

impl AerosolArg {
    fn model(self) -> Option<AerosolModel> {
        match self {
            AerosolArg::Rural => Some(AerosolModel::Rural),
            AerosolArg::Urban => Some(AerosolModel::Urban),
            AerosolArg::Maritime => Some(AerosolModel::Maritime),
            AerosolArg::None => None,
        }
    }
}

/// Arguments of `irsig atmosphere`.
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("model").required(true).multiple(true).args(["profile", "weather", "tape7_index"])))]
pub struct Args {
    /// AFGL model atmosphere: tropical, mid-latitude-summer,
    /// mid-latitude-winter, sub-arctic-summer, sub-arctic-winter,
    /// us-standard. With --weather, the profile under the weather (default:
    /// chosen by the site's latitude and the month).
    #[arg(long, value_name = "NAME")]
    pub profile: Option<String>,
    /// Weather file: its record at --time drives the built-in model as in a
    /// render (surface air blended into the profile, sky scaled to the
    /// record's sky longwave).
    #[arg(
        long,
        value_name = "FILE",
        requires = "time",
        conflicts_with = "tape7_index"
    )]
    pub weather: Option<PathBuf>,
    /// Time of the weather record (RFC 3339).
    #[arg(long, value_name = "RFC3339", requires = "weather")]
    pub time: Option<String>,
    /// Site `LAT,LON[,ALT]` for a weather file that carries none.
    #[arg(long, value_name = "LAT,LON[,ALT]", requires = "weather")]
    pub site: Option<String>,
    /// A MODTRAN tape7 table (index JSON, see docs/formats.md).
    #[arg(long, value_name = "FILE", conflicts_with = "profile")]
    pub tape7_index: Option<PathBuf>,
    /// LOWTRAN 7's boundary-layer aerosol of the built-in model (as a
    /// scene's `"aerosol"`; see docs/physics/atmosphere.md). Not for
    /// --tape7-index, whose MODTRAN runs carry their own.
    #[arg(
        long,
        value_enum,
        value_name = "MODEL",
        default_value_t = AerosolArg::Rural,
        conflicts_with = "tape7_index"
    )]
    pub aerosol: AerosolArg,
    /// Visibility (meteorological range) at the ground, km, > 0: sets the
    /// aerosol's amount (as a scene's `"visibility_km"`). Default: the
    /// weather record's visibility with --weather where the file has one
    /// (clamped to LOWTRAN's table, 2–50 km), else the model's (23 km;
    /// urban 5 km).
    #[arg(
        long,
        value_name = "KM",
        conflicts_with = "tape7_index",
        allow_negative_numbers = true
    )]
    pub visibility_km: Option<f64>,
    /// The band.
    #[command(flatten)]
    pub band: super::args::BandArgs,
    /// `up`: ground to space; `down`: sensor to target.
    #[arg(long, value_enum, default_value_t = Look::Down)]
    pub look: Look,
    /// Zenith angle, degrees (0–180): looking up, of the line of sight;
    /// looking down, of the direction from the target to the sensor.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub zenith: f64,
    /// Sensor altitude above the ground, m.
    #[arg(
        long,
        value_name = "M",
        default_value_t = 1000.0,
        allow_negative_numbers = true
    )]
    pub sensor_altitude: f64,
    /// Target altitude above the ground, m.
    #[arg(
        long,
        value_name = "M",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub target_altitude: f64,
    /// Slant range, m (needed for a horizontal path; otherwise from the
    /// altitudes and the zenith).
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    pub range: Option<f64>,
    /// The sun's zenith angle, degrees (0–180; 90 and beyond: night), for
    /// the single-scattered sunlight of the built-in model (with
    /// --sun-azimuth). Default with --weather: the sun at --time.
    #[arg(
        long,
        value_name = "DEG",
        requires = "sun_azimuth",
        conflicts_with = "tape7_index",
        allow_negative_numbers = true
    )]
    pub sun_zenith: Option<f64>,
    /// The sun's azimuth, degrees clockwise from north (0–360).
    #[arg(
        long,
        value_name = "DEG",
        requires = "sun_zenith",
        allow_negative_numbers = true
    )]
    pub sun_azimuth: Option<f64>,
    /// Azimuth of the line of sight (from the sensor toward where it
    /// looks), degrees clockwise from north (0–360): with the sun's, sets
    /// the scattering angle.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub view_azimuth: f64,
    /// Print JSON: `{"transmittance": …, "path_radiance_w_m2_sr": …,
    /// "aerosol": {"model": …, "visibility_km": …} | null}`; with a sun
    /// also `"scattered_radiance_w_m2_sr"` (single-scattered sunlight,
    /// not part of the thermal `path_radiance_w_m2_sr`),
    /// `"total_path_radiance_w_m2_sr"` and `"sun": {"zenith_deg",
    /// "azimuth_deg", "scattering_angle_deg"}`.
    #[arg(long)]
    pub json: bool,
}

/// The atmosphere the arguments describe, with the sky conditions, the
/// ground altitude (m above sea level), a description and the built-in
/// model's aerosol (`None`: clear air or a tape7 table).
struct Model {
    atmosphere: Atmosphere,
    sky: SkyConditions,
    ground_m: f64,
    what: String,
    aerosol: Option<Aerosol>,
    /// The weather's sun at --time: (zenith, azimuth, distance AU).
    sun: Option<(f64, f64, f64)>,
}

/// The aerosol `--aerosol` and `--visibility-km` ask for, before any
/// weather (`None`: clear air).
fn aerosol_arg(args: &Args) -> anyhow::Result<Option<Aerosol>> {
    let Some(m) = args.aerosol.model() else {
        anyhow::ensure!(
            args.visibility_km.is_none(),
            "--visibility-km: a visibility needs an aerosol, not --aerosol none"
        );
        return Ok(None);
    };
    let v = args.visibility_km.unwrap_or(m.default_visibility_km());
    anyhow::ensure!(
        v.is_finite() && v > 0.0,
        "--visibility-km: expected a visibility > 0 km, got {v}"
    );
    Ok(Some(Aerosol::new(m, v)?))
}

fn model(args: &Args) -> anyhow::Result<Model> {
    let profile = args
        .profile
        .as_deref()
        .map(Profile::from_name)
        .transpose()
        .context("--profile")?;
    if let Some(index) = &args.tape7_index {
        let a = Atmosphere::tape7_index(index).context("--tape7-index")?;
        let sky = SkyConditions {
            air_temperature_k: 288.15,
            sky_longwave_w_m2: f64::NAN,
        };
        return Ok(Model {
            atmosphere: a,
            sky,
            ground_m: 0.0,
            what: format!("tape7 table {}", index.display()),
            aerosol: None,
            sun: None,
        });
    }
    let aerosol = aerosol_arg(args)?;
    if let Some(file) = &args.weather {
        let time = parse_time("--time", args.time.as_deref().unwrap_or_default())?;
        let mut opts = irsig::weather::LoadOptions::default();
        if let Some(s) = &args.site {
            opts = opts.with_site(parse_site(s)?);
        }
        let history = irsig::weather::load_with(file, &opts)
            .with_context(|| format!("--weather {}", file.display()))?;
        let site = *history.site().context(
            "--weather: the file carries no site: give --site LAT,LON[,ALT] (the profile \
             is chosen by latitude, the ground altitude is the site's)",
        )?;
        let rec = history.at(time).context("--time")?;
        let sp = history.sun_position(time).context("--time")?;
        let profile = profile.unwrap_or_else(|| {
            use chrono::Datelike;
            Profile::for_site(site.latitude_deg, rec.time.month())
        });
        // As in a render: the record's visibility unless one is given.
        let aerosol = match aerosol {
            Some(a) if args.visibility_km.is_none() => {
                let (a, clamped) = a.with_observed_visibility(rec.visibility_km);
                if let Some(v) = clamped {
                    let (lo, hi) = irsig::atmosphere::aerosol::VISIBILITY_TABLE_KM;
                    eprintln!(
                        "warning: {}: visibility {v} km at {} is outside LOWTRAN 7's aerosol \
                         table ({lo}–{hi} km): the aerosol takes {} km",
                        file.display(),
                        rec.time.to_rfc3339(),
                        a.visibility_km
                    );
                }
                Some(a)
            }
            a => a,
        };
        let a = Atmosphere::Builtin(BuiltinAtmosphere::with_params(
            SurfaceMet::from_weather(&rec, site.altitude_m),
            BuiltinParams {
                profile: Some(profile),
                aerosol,
                ..BuiltinParams::default()
            },
        )?);
        let sky = SkyConditions {
            air_temperature_k: rec.air_temperature_k,
            sky_longwave_w_m2: rec.sky_longwave_w_m2,
        };
        return Ok(Model {
            atmosphere: a,
            sky,
            ground_m: site.altitude_m,
            what: format!("{profile} under {}", file.display()),
            aerosol,
            sun: Some((sp.zenith_deg, sp.azimuth_deg, sp.distance_au)),
        });
    }
    let profile = profile.context("give --profile, --weather or --tape7-index")?;
    let a = Atmosphere::Builtin(BuiltinAtmosphere::with_params(
        SurfaceMet::of_profile(profile, 0.0),
        BuiltinParams {
            profile: Some(profile),
            aerosol,
            ..BuiltinParams::default()
        },
    )?);
    let t = profile.level(0.0).temperature_k;
    let sky = SkyConditions {
        air_temperature_k: t,
        sky_longwave_w_m2: f64::NAN,
    };
    Ok(Model {
        atmosphere: a,
        sky,
        ground_m: 0.0,
        what: profile.to_string(),
        aerosol,
        sun: None,
    })
}

/// Run `irsig atmosphere`.
pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.zenith.is_finite() && (0.0..=180.0).contains(&args.zenith),
        "--zenith: expected 0–180°, got {}",
        args.zenith
    );
    for (flag, v) in [
        ("--sensor-altitude", args.sensor_altitude),
        ("--target-altitude", args.target_altitude),
    ] {
        anyhow::ensure!(
            v.is_finite() && v >= 0.0,
            "{flag}: expected an altitude ≥ 0 m above the ground, got {v}"
        );
    }
    if let Some(r) = args.range {
        anyhow::ensure!(
            r.is_finite() && r >= 0.0,
            "--range: expected a range ≥ 0 m, got {r}"
        );
    }
    if let Some(z) = args.sun_zenith {
        anyhow::ensure!(
            z.is_finite() && (0.0..=180.0).contains(&z),
            "--sun-zenith: expected 0–180°, got {z}"
        );
    }
    for (flag, v) in [
        ("--sun-azimuth", args.sun_azimuth),
        ("--view-azimuth", Some(args.view_azimuth)),
    ] {
        if let Some(v) = v {
            anyhow::ensure!(
                v.is_finite() && (0.0..=360.0).contains(&v),
                "{flag}: expected 0–360° clockwise from north, got {v}"
            );
        }
    }
    let band = args.band.band()?;
    let Model {
        atmosphere: atmos,
        sky,
        ground_m,
        what,
        aerosol,
        sun: weather_sun,
    } = model(&args)?;
    // The sun: as given, else the weather's at --time (a render's).
    let sun = match (args.sun_zenith, args.sun_azimuth) {
        (Some(z), Some(a)) => Some((z, a, 1.0)),
        _ => weather_sun,
    };
    let sun = sun
        .map(|(z, a, d)| Sun::new(z, a - args.view_azimuth, d))
        .transpose()?;
    let wl = band.wavelengths_um();
    let (lo, hi) = (wl[0], wl[wl.len() - 1]);
    if let Some((a, b)) = atmos.spectral_range_um() {
        anyhow::ensure!(
            lo >= a - 1e-9 && hi <= b + 1e-9,
            "--band: {lo}–{hi} µm is outside the built-in model's spectral range {a}–{b} µm"
        );
    }
    let (p, scattered, los_zenith, geometry) = match args.look {
        Look::Up => {
            anyhow::ensure!(
                args.zenith < 90.0,
                "--zenith: looking up needs a zenith below 90°, got {}",
                args.zenith
            );
            let p = atmos.look_up(&sky, args.zenith, band.grid())?;
            let ss = sun
                .map(|s| atmos.scattered_solar_up(args.zenith, &s, band.grid()))
                .transpose()?;
            (
                p,
                ss,
                args.zenith,
                format!("looking up at zenith {}°", args.zenith),
            )
        }
        Look::Down => {
            let (hs, ht) = (args.sensor_altitude, args.target_altitude);
            let cos = args.zenith.to_radians().cos();
            let range = match args.range {
                Some(r) => r,
                None => {
                    anyhow::ensure!(
                        cos.abs() > 1e-9,
                        "--range: a horizontal path (zenith 90°) needs --range"
                    );
                    let r = (hs - ht) / cos;
                    anyhow::ensure!(
                        r >= 0.0,
                        "--zenith: at {}° the sensor ({hs} m) cannot be {} the target ({ht} m)",
                        args.zenith,
                        if hs > ht { "above" } else { "below" }
                    );
                    r
                }
            };
            let g = PathGeometry {
                sensor_altitude_m: ground_m + hs,
                target_altitude_m: ground_m + ht,
                range_m: range,
            };
            let p = atmos.path(&g, band.grid())?;
            let ss = sun
                .map(|s| atmos.scattered_solar(&g, &s, band.grid()))
                .transpose()?;
            (
                p,
                ss,
                g.line_of_sight_zenith_deg(),
                format!("sensor {hs} m, target {ht} m above the ground, range {range:.1} m"),
            )
        }
    };
    let tau = band.mean(&p.transmittance);
    let lu = band.integrate(&p.path_radiance);
    let ss = scattered.map(|s| band.integrate(&s));
    let builtin = matches!(atmos, Atmosphere::Builtin(_));
    let sun_json = sun.map(|s| {
        serde_json::json!({
            "zenith_deg": s.zenith_deg,
            "azimuth_deg": (s.relative_azimuth_deg + args.view_azimuth).rem_euclid(360.0),
            "scattering_angle_deg": s.cos_scattering_angle(los_zenith).acos().to_degrees(),
        })
    });
    if args.json {
        let aerosol_json = aerosol.map(
            |a| serde_json::json!({ "model": a.model.name(), "visibility_km": a.visibility_km }),
        );
        let mut j = serde_json::json!({
            "transmittance": tau,
            "path_radiance_w_m2_sr": lu,
            "aerosol": aerosol_json
        });
        if let Some(ss) = ss {
            j["scattered_radiance_w_m2_sr"] = ss.into();
            j["total_path_radiance_w_m2_sr"] = (lu + ss).into();
            j["sun"] = sun_json.unwrap_or_default();
        }
        outln!("{j}");
    } else {
        outln!("{what}, band {lo}–{hi} µm, {geometry}:");
        if builtin {
            match aerosol {
                Some(a) => outln!(
                    "  aerosol {} (LOWTRAN 7), visibility {} km",
                    a.model,
                    a.visibility_km
                ),
                None => outln!("  no aerosol (gases only)"),
            }
        }
        outln!("  band-mean transmittance {tau:.4}");
        let bt = band
            .brightness_temperature(lu)
            .map(|t| format!(" (brightness temperature {t:.2} K)"))
            .unwrap_or_default();
        outln!("  path radiance {lu:.4} W/m²/sr{bt}");
        if let (Some(ss), Some(s)) = (ss, sun) {
            let theta = s.cos_scattering_angle(los_zenith).acos().to_degrees();
            outln!(
                "  scattered sunlight {ss:.4} W/m²/sr (sun at zenith {:.2}°, scattering angle \
                 {theta:.1}°), total {:.4} W/m²/sr",
                s.zenith_deg,
                lu + ss
            );
        }
    }
    Ok(())
}
