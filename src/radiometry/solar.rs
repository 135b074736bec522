//! The solar spectrum at the top of the atmosphere: the ASTM E490-00a
//! zero-air-mass table (`data/astm_e490_am0.csv`, its source, licence and
//! resampling in the file's header), rescaled to the solar constant.
//!
//! Between tabulated points the spectrum is linear in wavelength. Below the
//! first point (0.2025 µm) it is 0 (the E490 table carries 0.1 W/m² below
//! 0.2 µm, 0.007 % of the total). Beyond the last (1000 µm) it falls as
//! λ⁻⁴, the Rayleigh–Jeans tail of a blackbody. The table integrates to
//! 1366.0 W/m² (the standard's own solar constant, 1366.1 W/m², from older
//! radiometry); it is scaled by S₀/1366.0 to irsig's solar constant
//! S₀ = [`SOLAR_CONSTANT_W_M2`] (Kopp & Lean 2011), a 0.4 % change that keeps
//! the spectral shape. Units: µm, W·m⁻²·µm⁻¹.

use super::band::SpectralGrid;
use super::equation::SOLAR_CONSTANT_W_M2;
use std::sync::OnceLock;

const TABLE: &str = include_str!("data/astm_e490_am0.csv");

/// The parsed table: wavelengths (µm), irradiance (W·m⁻²·µm⁻¹) already
/// scaled to the solar constant.
struct SolarTable {
    wavelength_um: Vec<f64>,
    irradiance: Vec<f64>,
}

fn parse(text: &str) -> std::result::Result<(Vec<f64>, Vec<f64>), String> {
    let mut wl = Vec::new();
    let mut e = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') || line.starts_with("wavelength") {
            continue;
        }
        let mut f = line.split(',').map(|s| s.trim().parse::<f64>());
        match (f.next(), f.next(), f.next()) {
            (Some(Ok(l)), Some(Ok(v)), None) if l > 0.0 && v >= 0.0 => {
                if wl.last().is_some_and(|&p| l <= p) {
                    return Err(format!("line {}: wavelength {l} not increasing", i + 1));
                }
                wl.push(l);
                e.push(v);
            }
            _ => return Err(format!("line {}: expected `wavelength,irradiance`", i + 1)),
        }
    }
    if wl.len() < 2 {
        return Err("fewer than two rows".into());
    }
    Ok((wl, e))
}

/// Trapezoid integral of the table plus its λ⁻⁴ tail, W/m².
fn table_integral(wl: &[f64], e: &[f64]) -> f64 {
    let body: f64 = wl
        .windows(2)
        .zip(e.windows(2))
        .map(|(w, v)| 0.5 * (w[1] - w[0]) * (v[0] + v[1]))
        .sum();
    // ∫_{λn}^∞ E_n (λn/λ)⁴ dλ = E_n λn / 3.
    body + e[e.len() - 1] * wl[wl.len() - 1] / 3.0
}

fn table() -> &'static SolarTable {
    static T: OnceLock<SolarTable> = OnceLock::new();
    T.get_or_init(|| {
        // The file is compiled in and checked by the tests; a parse failure
        // is a build defect, not bad user input.
        let (wl, e) = parse(TABLE).expect("src/radiometry/data/astm_e490_am0.csv is malformed");
        let scale = SOLAR_CONSTANT_W_M2 / table_integral(&wl, &e);
        SolarTable {
            irradiance: e.iter().map(|v| v * scale).collect(),
            wavelength_um: wl,
        }
    })
}

/// The solar constant the unscaled table integrates to, W/m² (0.2–∞ µm).
pub fn e490_table_integral_w_m2() -> f64 {
    let (wl, e) = parse(TABLE).expect("src/radiometry/data/astm_e490_am0.csv is malformed");
    table_integral(&wl, &e)
}

/// Solar spectral irradiance at the top of the atmosphere at one wavelength
/// `wavelength_um` (µm), 1 AU, W·m⁻²·µm⁻¹ (see the module docs).
pub fn solar_irradiance_toa_at(wavelength_um: f64) -> f64 {
    let t = table();
    let (wl, e) = (&t.wavelength_um, &t.irradiance);
    let n = wl.len();
    // Below the table, or NaN: no sunlight.
    if wavelength_um.is_nan() || wavelength_um < wl[0] {
        return 0.0;
    }
    if wavelength_um >= wl[n - 1] {
        return e[n - 1] * (wl[n - 1] / wavelength_um).powi(4);
    }
    let i = wl.partition_point(|&x| x <= wavelength_um) - 1;
    let f = (wavelength_um - wl[i]) / (wl[i + 1] - wl[i]);
    e[i] + f * (e[i + 1] - e[i])
}

/// Solar spectral irradiance at the top of the atmosphere on a surface normal
/// to the sun, W·m⁻²·µm⁻¹, on `grid`, the sun–earth distance `distance_au`
/// AU away (E ∝ 1/d²): the ASTM E490 spectrum of the module docs.
pub fn solar_irradiance_toa(grid: &SpectralGrid, distance_au: f64) -> Vec<f64> {
    let inv_d2 = 1.0 / (distance_au * distance_au);
    grid.wavelengths_um()
        .iter()
        .map(|&l| solar_irradiance_toa_at(l) * inv_d2)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_errors_name_the_line() {
        assert!(parse("# c\n1,2\n0.5,3\n").unwrap_err().contains("line 3"));
        assert!(parse("1,2\nx,3\n").unwrap_err().contains("line 2"));
        assert!(parse("1,2\n").is_err());
    }

    #[test]
    fn interpolates_and_extends() {
        let t = table();
        let (wl, e) = (&t.wavelength_um, &t.irradiance);
        assert_eq!(solar_irradiance_toa_at(wl[3]), e[3]);
        let mid = 0.5 * (wl[3] + wl[4]);
        assert!((solar_irradiance_toa_at(mid) - 0.5 * (e[3] + e[4])).abs() < 1e-9 * e[3]);
        assert_eq!(solar_irradiance_toa_at(0.1), 0.0);
        let last = *wl.last().unwrap();
        let r = solar_irradiance_toa_at(2.0 * last) / solar_irradiance_toa_at(last);
        assert!((r - 1.0 / 16.0).abs() < 1e-12);
    }
}
