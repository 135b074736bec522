//! Values the command line parses that the library takes typed: times and
//! time lists, durations, tiles, sites; and the flag context of library
//! errors.
//!
//! The library names a bad value by its field or parameter (`sensor`,
//! `layer`, `tilt_deg`); [`FlagContext`] adds the flag the user typed, so
//! the message says both (`--sensor: sensor: …`).

use anyhow::Context;
use chrono::{DateTime, FixedOffset, TimeDelta};
use irsig::sun::Site;

/// Most image times a `START/END/STEP` list may expand to.
const MAX_TIMES: usize = 10_000;

/// An RFC 3339 time given with `flag`.
pub(crate) fn parse_time(flag: &str, s: &str) -> anyhow::Result<DateTime<FixedOffset>> {
    irsig::sun::parse_time(s).with_context(|| flag.to_string())
}

/// A site `LAT,LON[,ALT]` given with `--site`.
pub(crate) fn parse_site(s: &str) -> anyhow::Result<Site> {
    s.parse::<Site>().context("--site")
}

/// `--times`: a comma-separated list of RFC 3339 times, or `START/END/STEP`
/// with STEP a duration like `30s`, `15min`, `1h` (at least 1 s; at most
/// 10000 times).
pub(crate) fn parse_times(s: &str) -> anyhow::Result<Vec<DateTime<FixedOffset>>> {
    let time = |t: &str| parse_time("--times", t);
    let parts: Vec<&str> = s.split('/').collect();
    match parts.as_slice() {
        [start, end, step] => {
            let (a, b) = (time(start)?, time(end)?);
            let step = parse_step(step).context("--times")?;
            anyhow::ensure!(b >= a, "--times: `{s}`: the end is before the start");
            let mut out = Vec::new();
            let mut t = a;
            while t <= b {
                out.push(t);
                anyhow::ensure!(
                    out.len() <= MAX_TIMES,
                    "--times: `{s}`: more than {MAX_TIMES} times"
                );
                t += step;
            }
            Ok(out)
        }
        [_] => s.split(',').map(time).collect(),
        _ => anyhow::bail!("--times: `{s}`: expected T1,T2,… or START/END/STEP"),
    }
}

/// A step of a time list: a duration of at least 1 s, in humantime's units
/// (`30s`, `15min`, `15m`, `1h`, `1h30m`) or a decimal number of one unit
/// (`1.5h`), rounded to the millisecond.
fn parse_step(s: &str) -> anyhow::Result<TimeDelta> {
    let s = s.trim();
    let bad = || format!("step `{s}`: expected a positive duration like 30s, 15min or 1h");
    let secs = match humantime::parse_duration(s) {
        Ok(d) => d.as_secs_f64(),
        Err(e) => {
            // humantime takes integers only: `1.5h` is 1.5 × `1h`.
            let split = s
                .find(|c: char| !(c.is_ascii_digit() || c == '.'))
                .with_context(|| format!("{e}"))
                .with_context(bad)?;
            let (num, unit) = s.split_at(split);
            let v: f64 = num.parse().with_context(bad)?;
            let one = humantime::parse_duration(&format!("1{unit}")).with_context(bad)?;
            v * one.as_secs_f64()
        }
    };
    anyhow::ensure!(secs.is_finite() && secs >= 1.0, bad());
    Ok(TimeDelta::milliseconds((secs * 1000.0).round() as i64))
}

/// `--tile K/N` (1 ≤ K ≤ N).
pub(crate) fn parse_tile(s: &str) -> anyhow::Result<(usize, usize)> {
    parse_k_of_n("--tile", s)
}

/// `K/N` (1 ≤ K ≤ N) given with `flag` (`--tile`, `--shard`).
pub(crate) fn parse_k_of_n(flag: &str, s: &str) -> anyhow::Result<(usize, usize)> {
    let bad = || anyhow::anyhow!("{flag}: `{s}`: expected K/N with 1 ≤ K ≤ N, e.g. 3/8");
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let k: usize = k.trim().parse().map_err(|_| bad())?;
    let n: usize = n.trim().parse().map_err(|_| bad())?;
    if k == 0 || n == 0 || k > n {
        return Err(bad());
    }
    Ok((k, n))
}

/// Adds the command-line flag to a library error about a field.
pub(crate) trait FlagContext<T> {
    /// When the error is about one of `fields` (pairs of the library's
    /// field name and the flag that sets it), give it the flag as context;
    /// other errors pass unchanged.
    fn for_flags(self, fields: &[(&str, &str)]) -> anyhow::Result<T>;
}

impl<T> FlagContext<T> for irsig::Result<T> {
    fn for_flags(self, fields: &[(&str, &str)]) -> anyhow::Result<T> {
        self.map_err(|err| {
            let field = match &err {
                irsig::Error::Invalid { field, .. } => Some(field.as_str()),
                _ => None,
            };
            match field.and_then(|f| fields.iter().find(|(name, _)| *name == f)) {
                Some((_, flag)) => anyhow::Error::new(err).context(flag.to_string()),
                None => err.into(),
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_keep_the_forms_accepted_before() {
        let secs = |s: &str| parse_step(s).unwrap().num_milliseconds() as f64 / 1000.0;
        assert_eq!(secs("30s"), 30.0);
        assert_eq!(secs("15min"), 900.0);
        assert_eq!(secs("15m"), 900.0);
        assert_eq!(secs("1h"), 3600.0);
        assert_eq!(secs(" 1h "), 3600.0);
        assert_eq!(secs("1.5h"), 5400.0);
        assert_eq!(secs("0.5m"), 30.0);
        assert_eq!(secs("1h30m"), 5400.0);
        for bad in ["0s", "0.5s", "500ms", "30", "", "h", "-1h", "1x", "1.2.3h"] {
            assert!(parse_step(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn time_lists() {
        let t = parse_times("2025-06-21T10:00:00-04:00/2025-06-21T11:00:00-04:00/15min").unwrap();
        assert_eq!(t.len(), 5);
        let t = parse_times("2025-06-21T10:00:00-04:00, 2025-06-21T12:00:00Z").unwrap();
        assert_eq!(t.len(), 2);
        let e = parse_times("2025-06-21T11:00:00-04:00/2025-06-21T10:00:00-04:00/1h");
        assert!(format!("{:#}", e.unwrap_err()).contains("before the start"));
        let e = parse_times("2025-06-21T00:00:00Z/2025-06-22T00:00:00Z/1s").unwrap_err();
        assert!(format!("{e:#}").contains("more than 10000"), "{e:#}");
        let e = parse_times("2025-06-21 10:00").unwrap_err();
        assert!(format!("{e:#}").starts_with("--times: "), "{e:#}");
    }

    #[test]
    fn tiles() {
        assert_eq!(parse_tile("3/8").unwrap(), (3, 8));
        for bad in ["0/3", "4/3", "3", "a/b", "1/0"] {
            let e = parse_tile(bad).unwrap_err();
            assert!(format!("{e:#}").contains("--tile"), "{bad}");
        }
    }

    #[test]
    fn library_errors_get_their_flag() {
        let e: irsig::Result<()> = Err(irsig::Error::invalid("layer", "no layer `x`"));
        let e = e.for_flags(&[("layer", "--layer")]).unwrap_err();
        assert_eq!(format!("{e:#}"), "--layer: layer: no layer `x`");
        let e: irsig::Result<()> = Err(irsig::Error::invalid("other", "bad"));
        let e = e.for_flags(&[("layer", "--layer")]).unwrap_err();
        assert_eq!(format!("{e:#}"), "other: bad");
    }
}

/// The spectral band options shared by `irsig radiance` and `irsig
/// atmosphere`: `--band LO-HI`, `--response FILE`, `--step UM`.
#[derive(Debug, clap::Args)]
pub struct BandArgs {
    /// Spectral band in µm, `LO-HI` (e.g. `8-14`). With `--response`, the
    /// response is cut to this range; without it the response is flat.
    #[arg(long, value_name = "LO-HI")]
    pub band: Option<String>,
    /// Relative spectral response CSV (`wavelength_um, response` per line).
    #[arg(long, value_name = "FILE")]
    pub response: Option<std::path::PathBuf>,
    /// Largest spectral step of the integration grid, µm.
    #[arg(long, value_name = "UM", default_value_t = irsig::radiometry::DEFAULT_STEP_UM)]
    pub step: f64,
}

impl BandArgs {
    /// The band the options describe (response warnings printed as
    /// `warning:` lines).
    pub fn band(&self) -> anyhow::Result<irsig::radiometry::Band> {
        use irsig::radiometry::Band;
        let range = self.band.as_deref().map(parse_band).transpose()?;
        anyhow::ensure!(
            self.step.is_finite() && self.step > 0.0,
            "--step: expected a positive step in µm, got {}",
            self.step
        );
        Ok(match (&self.response, range) {
            (None, None) => anyhow::bail!("give --band LO-HI (µm), --response FILE, or both"),
            (None, Some((lo, hi))) => Band::flat(lo, hi, self.step)?,
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
                Band::from_response(&resp, self.step)?
            }
        })
    }
}

/// Parse `LO-HI` (µm).
pub(crate) fn parse_band(s: &str) -> anyhow::Result<(f64, f64)> {
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

/// The response restricted to [lo, hi] (interpolated at the cut points).
fn clip(
    resp: &irsig::radiometry::SpectralResponse,
    lo: f64,
    hi: f64,
) -> anyhow::Result<irsig::radiometry::SpectralResponse> {
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
    irsig::radiometry::SpectralResponse::new(wl, r).map_err(|e| {
        anyhow::anyhow!("{e}: the response has no sensitivity inside the band {lo}–{hi} µm")
    })
}
