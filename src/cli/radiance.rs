//! `irsig radiance`: Planck band radiance and its inverse.

use std::path::PathBuf;

use anyhow::Context;
use irsig::radiometry::{Band, Constants, DEFAULT_STEP_UM, Planck, SpectralResponse};

/// Arguments of `irsig radiance`.
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("input").required(true).args(["temperature", "radiance"])))]
pub struct Args {
    /// Spectral band in µm, `LO-HI` (e.g. `8-14`). With `--response`, the
    /// response is cut to this range; without it the response is flat.
    #[arg(long, value_name = "LO-HI")]
    pub band: Option<String>,
    /// Blackbody temperature, K: print the band radiance ∫ R·B(λ,T) dλ.
    #[arg(long, value_name = "K")]
    pub temperature: Option<f64>,
    /// Band radiance, W/m²/sr: print the brightness temperature.
    #[arg(long, value_name = "W/m2/sr")]
    pub radiance: Option<f64>,
    /// Relative spectral response CSV (`wavelength_um, response` per line).
    #[arg(long, value_name = "FILE")]
    pub response: Option<PathBuf>,
    /// Largest spectral step of the integration grid, µm.
    #[arg(long, value_name = "UM", default_value_t = DEFAULT_STEP_UM)]
    pub step: f64,
    /// Physical constants: CODATA `2018` (exact SI, default) or `2010`.
    #[arg(long, value_name = "YEAR", default_value_t = 2018)]
    pub codata: u32,
    /// Print JSON (`{"radiance_w_m2_sr": …}` or `{"temperature_k": …}`).
    #[arg(long)]
    pub json: bool,
}

/// Parse `LO-HI` (µm).
pub(super) fn parse_band(s: &str) -> anyhow::Result<(f64, f64)> {
    let bad = || anyhow::anyhow!("--band: expected `LO-HI` in µm (e.g. `8-14`), got `{s}`");
    let (a, b) = s.split_once('-').ok_or_else(bad)?;
    let lo: f64 = a.trim().parse().map_err(|_| bad())?;
    let hi: f64 = b.trim().parse().map_err(|_| bad())?;
    anyhow::ensure!(
        lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo,
        "--band: expected 0 < LO < HI in µm, got `{s}`"
    );
    Ok((lo, hi))
}

/// The band the arguments describe.
fn band(args: &Args) -> anyhow::Result<Band> {
    let range = args.band.as_deref().map(parse_band).transpose()?;
    anyhow::ensure!(
        args.step.is_finite() && args.step > 0.0,
        "--step: expected a positive step in µm, got {}",
        args.step
    );
    let constants = match args.codata {
        2018 => Constants::CODATA_2018,
        2010 => Constants::CODATA_2010,
        y => anyhow::bail!("--codata: expected 2018 or 2010, got {y}"),
    };
    let band = match (&args.response, range) {
        (None, None) => anyhow::bail!("give --band LO-HI (µm), --response FILE, or both"),
        (None, Some((lo, hi))) => Band::flat(lo, hi, args.step)?,
        (Some(path), range) => {
            let resp = irsig::radiometry::read_response_csv(path)?;
            for w in resp.warnings() {
                eprintln!("warning: {w}");
            }
            let resp = match range {
                None => resp,
                Some((lo, hi)) => clip(&resp, lo, hi).with_context(|| {
                    format!("--band {lo}-{hi} with response {}", path.display())
                })?,
            };
            Band::from_response(&resp, args.step)?
        }
    };
    Ok(band.with_planck(Planck::new(constants)))
}

/// The response restricted to [lo, hi] (interpolated at the cut points).
pub(super) fn clip(resp: &SpectralResponse, lo: f64, hi: f64) -> anyhow::Result<SpectralResponse> {
    let mut wl = vec![lo];
    let mut r = vec![resp.at(lo)];
    for (&l, &v) in resp.wavelengths_um().iter().zip(resp.response()) {
        if l > lo && l < hi {
            wl.push(l);
            r.push(v);
        }
    }
    wl.push(hi);
    r.push(resp.at(hi));
    SpectralResponse::new(wl, r).map_err(|e| {
        anyhow::anyhow!("{e}: the response has no sensitivity inside the band {lo}–{hi} µm")
    })
}

/// Run `irsig radiance`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let band = band(&args)?;
    let wl = band.wavelengths_um();
    let (lo, hi) = (wl[0], wl[wl.len() - 1]);
    if let Some(t) = args.temperature {
        anyhow::ensure!(
            t.is_finite() && t > 0.0,
            "--temperature: expected a positive temperature in K, got {t}"
        );
        let l = band.blackbody_radiance(t);
        if args.json {
            outln!("{}", serde_json::json!({ "radiance_w_m2_sr": l }));
        } else {
            outln!("band {lo}–{hi} µm, T = {t} K: band radiance {l:.9} W/m²/sr");
        }
    } else if let Some(l) = args.radiance {
        let t = band
            .brightness_temperature(l)
            .context("--radiance: no brightness temperature")?;
        if args.json {
            outln!("{}", serde_json::json!({ "temperature_k": t }));
        } else {
            outln!("band {lo}–{hi} µm, L = {l} W/m²/sr: brightness temperature {t:.6} K");
        }
    }
    Ok(())
}
