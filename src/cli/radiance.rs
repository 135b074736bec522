//! `irsig radiance`: Planck band radiance and its inverse.

use anyhow::Context;
use irsig::radiometry::{Band, Constants, Planck};

/// Arguments of `irsig radiance`.
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("input").required(true).args(["temperature", "radiance"])))]
pub struct Args {
    /// The band.
    #[command(flatten)]
    pub band: super::args::BandArgs,
    /// Blackbody temperature, K: print the band radiance ∫ R·B(λ,T) dλ.
    #[arg(long, value_name = "K")]
    pub temperature: Option<f64>,
    /// Band radiance, W/m²/sr: print the brightness temperature.
    #[arg(long, value_name = "W/m2/sr")]
    pub radiance: Option<f64>,
    /// Physical constants: CODATA `2018` (exact SI, default) or `2010`.
    #[arg(long, value_name = "YEAR", default_value_t = 2018)]
    pub codata: u32,
    /// Print JSON (`{"radiance_w_m2_sr": …}` or `{"temperature_k": …}`).
    #[arg(long)]
    pub json: bool,
}

/// The band the arguments describe, with their Planck constants.
fn band(args: &Args) -> anyhow::Result<Band> {
    let constants = match args.codata {
        2018 => Constants::CODATA_2018,
        2010 => Constants::CODATA_2010,
        y => anyhow::bail!("--codata: expected 2018 or 2010, got {y}"),
    };
    Ok(args.band.band()?.with_planck(Planck::new(constants)))
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
