//! Tests: radiometry — Planck's law, band integrals and their inverse,
//! spectral response files, emissivity, the per-hit radiance equation.

use irsig::radiometry::{Band, Constants, Planck, SpectralGrid, planck_radiance};

use crate::util;

/// Composite Simpson's rule with `n` (even) intervals: brute-force quadrature.
fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    assert!(n % 2 == 0);
    let h = (b - a) / n as f64;
    let mut s = f(a) + f(b);
    for i in 1..n {
        s += f(a + h * i as f64) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn planck_matches_pyspectral_reference_with_codata_2010() {
    // pyspectral's test value: B(11 µm, 300 K) = 9.573176935 W m⁻² sr⁻¹ µm⁻¹.
    let b = Planck::new(Constants::CODATA_2010).radiance(11.0, 300.0);
    assert!(rel(b, 9.573176935) < 1e-9, "B = {b}");
    // The default (CODATA 2018) differs by 3.4e-7 relative, no more.
    let b18 = planck_radiance(11.0, 300.0);
    assert!(rel(b18, 9.573180197) < 1e-9, "B = {b18}");
    assert!(rel(b18, b) > 1e-7 && rel(b18, b) < 1e-6);
}

#[test]
fn planck_integrates_to_stefan_boltzmann_and_peaks_at_wien() {
    let p = Planck::default();
    let t = 300.0;
    // ∫ B dλ = σT⁴/π: Simpson over 0.5–1000 µm (below 0.5 µm is < 1e-30 of
    // the total) plus the Rayleigh–Jeans tail beyond 1000 µm,
    // ∫ c₁L T/(c₂ λ⁴) dλ = c₁L T / (3 c₂ λ³).
    let c = Constants::CODATA_2018;
    let tail = c.c1l_w_um4_m2_sr() * t / (3.0 * c.c2_um_k() * 1000f64.powi(3));
    let total = simpson(|l| p.radiance(l, t), 0.5, 1000.0, 400_000) + tail;
    let sigma = Constants::CODATA_2018.stefan_boltzmann_w_m2_k4();
    assert!(rel(sigma, 5.670374419e-8) < 1e-9, "σ = {sigma}");
    let expected = sigma * t.powi(4) / std::f64::consts::PI;
    assert!(rel(total, expected) < 2e-6, "{total} vs {expected}");
    // Wien: λ_max T = 2897.771955 µm·K.
    let lmax = 2897.771955 / t;
    for d in [-0.01, 0.01] {
        assert!(p.radiance(lmax, t) > p.radiance(lmax + d, t));
    }
}

#[test]
fn planck_derivative_matches_finite_difference() {
    let p = Planck::default();
    for (l, t) in [(4.0, 250.0), (10.0, 300.0), (12.0, 350.0)] {
        let h = 1e-3;
        let fd = (p.radiance(l, t + h) - p.radiance(l, t - h)) / (2.0 * h);
        assert!(rel(p.radiance_derivative(l, t), fd) < 1e-7);
    }
}

#[test]
fn band_integral_matches_brute_force_quadrature() {
    let p = Planck::default();
    for (lo, hi, t) in [
        (8.0, 14.0, 300.0),
        (3.0, 5.0, 300.0),
        (8.0, 12.0, 250.0),
        (3.5, 4.1, 1000.0),
    ] {
        let brute = simpson(|l| p.radiance(l, t), lo, hi, 20_000);
        // Trapezoid error ∝ step²: 2e-5 at the default 0.01 µm (steep MWIR
        // Wien side), 1e-6 at 0.002 µm.
        let coarse = Band::flat(lo, hi, 0.01).unwrap().blackbody_radiance(t);
        assert!(
            rel(coarse, brute) < 2e-5,
            "{lo}-{hi} µm {t} K: {coarse} vs {brute}"
        );
        let band = Band::flat(lo, hi, 0.002).unwrap();
        let got = band.blackbody_radiance(t);
        assert!(
            rel(got, brute) < 1e-6,
            "{lo}-{hi} µm {t} K: {got} vs {brute}"
        );
        // Grid integration of the sampled spectrum gives the same number.
        let spec = band.grid().blackbody(&p, t);
        assert!(rel(band.integrate(&spec), got) < 1e-13);
        // Mean spectral radiance × width = integral for a flat band.
        assert!(rel(band.mean(&spec) * (hi - lo), got) < 1e-12);
    }
    // The reference number the CLI test uses: 8–14 µm at 300 K.
    let l = Band::flat(8.0, 14.0, 0.01)
        .unwrap()
        .blackbody_radiance(300.0);
    assert!(rel(l, 54.93346137684) < 1e-6, "{l}");
}

#[test]
fn brightness_temperature_round_trips() {
    for (lo, hi) in [(8.0, 14.0), (3.0, 5.0), (10.5, 11.5)] {
        let band = Band::flat(lo, hi, 0.01).unwrap();
        for t in [150.0, 220.0, 273.15, 300.0, 333.3, 600.0, 1500.0] {
            let l = band.blackbody_radiance(t);
            let back = band.brightness_temperature(l).unwrap();
            assert!(
                (back - t).abs() < 1e-7 * t,
                "{lo}-{hi}: {t} -> {l} -> {back}"
            );
        }
    }
    let band = Band::flat(8.0, 14.0, 0.01).unwrap();
    assert!(band.brightness_temperature(0.0).is_err());
    assert!(band.brightness_temperature(-1.0).is_err());
    assert!(band.brightness_temperature(f64::NAN).is_err());
    assert!(band.brightness_temperature(1e30).is_err());
}

#[test]
fn spectral_grid_validates_and_resamples_conservatively() {
    assert!(SpectralGrid::new(vec![]).is_err());
    assert!(SpectralGrid::new(vec![8.0, 8.0]).is_err());
    assert!(SpectralGrid::new(vec![8.0, -1.0]).is_err());
    assert!(Band::flat(14.0, 8.0, 0.01).is_err());
    let g = SpectralGrid::uniform(8.0, 12.0, 0.05).unwrap();
    assert!(rel(g.weights_um().iter().sum::<f64>(), 4.0) < 1e-14);
    // A finely tabulated spectrum with structure: the resampled values
    // integrate to the exact piecewise-linear integral.
    let src_wl: Vec<f64> = (0..=1000).map(|i| 7.9 + 0.0043 * i as f64).collect();
    let src: Vec<f64> = src_wl.iter().map(|l| 1.0 + (l * 37.0).sin()).collect();
    let exact: f64 = {
        // Trapezoid on the source points clipped to [8, 12].
        let f = |x: f64| {
            let j = src_wl
                .partition_point(|&w| w <= x)
                .clamp(1, src_wl.len() - 1);
            let t = (x - src_wl[j - 1]) / (src_wl[j] - src_wl[j - 1]);
            src[j - 1] + t * (src[j] - src[j - 1])
        };
        let mut pts = vec![8.0];
        pts.extend(src_wl.iter().copied().filter(|&w| w > 8.0 && w < 12.0));
        pts.push(12.0);
        pts.windows(2)
            .map(|w| 0.5 * (f(w[0]) + f(w[1])) * (w[1] - w[0]))
            .sum()
    };
    let out = g.resample_mean(&src_wl, &src, 0.0).unwrap();
    assert!(rel(g.integrate(&out), exact) < 1e-12);
    // Outside the data: an error naming both ranges.
    let err = SpectralGrid::uniform(7.0, 12.0, 0.05)
        .unwrap()
        .resample_mean(&src_wl, &src, 0.0)
        .unwrap_err()
        .to_string();
    assert!(err.contains("7.0000") && err.contains("7.9000"), "{err}");
}

mod response {
    use super::*;
    use irsig::radiometry::response::parse_response_csv;

    #[test]
    fn reads_with_and_without_header_and_weights_the_band() {
        let a =
            parse_response_csv("wavelength_um,response\n8,0\n9,1\n13,1\n14,0\n", "a.csv").unwrap();
        let b = parse_response_csv("# comment\n8 0\n9\t1\n\n13;1 # x\n14,0\n", "b.csv").unwrap();
        assert_eq!(a, b);
        assert_eq!(a.at(8.5), 0.5);
        assert_eq!(a.at(7.0), 0.0);
        assert_eq!(a.at(14.5), 0.0);
        // Trapezoid response: ∫R B dλ vs brute force.
        let band = Band::from_response(&a, 0.01).unwrap();
        let p = Planck::default();
        let brute = simpson(|l| a.at(l) * p.radiance(l, 300.0), 8.0, 14.0, 60_000);
        assert!(rel(band.blackbody_radiance(300.0), brute) < 1e-6);
        assert!(rel(band.equivalent_width_um(), 5.0) < 1e-12);
        // Scaling the response does not change the result (peak-normalised).
        let c = parse_response_csv("8,0\n9,50\n13,50\n14,0\n", "c.csv").unwrap();
        let bc = Band::from_response(&c, 0.01).unwrap();
        assert!(rel(bc.blackbody_radiance(300.0), band.blackbody_radiance(300.0)) < 1e-14);
    }

    #[test]
    fn errors_name_file_and_line() {
        let cases = [
            ("w,r\n8,0\n9,x\n", "bad.csv:line 3", "response"),
            ("8,0\n9,1\n8.5,1\n", "bad.csv:line 3", "increase"),
            ("8,0\n9,1,2\n", "bad.csv:line 2", "two fields"),
            ("8,0\n9,-1\n", "bad.csv:line 2", "≥ 0"),
            ("8000,1\n9000,1\n", "bad.csv:line 1", "µm"),
            ("8,1\n", "bad.csv", "at least two"),
            ("8,0\n9,0\n", "bad.csv", "zero"),
        ];
        for (text, loc, what) in cases {
            let e = parse_response_csv(text, "bad.csv").unwrap_err().to_string();
            assert!(e.contains(loc) && e.contains(what), "{text:?}: {e}");
        }
        let e = irsig::radiometry::read_response_csv("/nonexistent/r.csv").unwrap_err();
        assert!(e.to_string().contains("/nonexistent/r.csv"));
    }
}

mod cli {
    use super::*;
    use std::process::Command;

    fn run(args: &[&str]) -> (bool, String, String) {
        let out = Command::new(util::irsig_bin()).args(args).output().unwrap();
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    }

    #[test]
    fn radiance_and_inverse() {
        let (ok, out, err) = run(&[
            "radiance",
            "--band",
            "8-14",
            "--temperature",
            "300",
            "--json",
        ]);
        assert!(ok, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        let l = v["radiance_w_m2_sr"].as_f64().unwrap();
        let brute = simpson(|x| planck_radiance(x, 300.0), 8.0, 14.0, 20_000);
        assert!(rel(l, brute) < 1e-6, "{l} vs {brute}");
        let (ok, out, err) = run(&[
            "radiance",
            "--band",
            "8-14",
            "--radiance",
            &l.to_string(),
            "--json",
        ]);
        assert!(ok, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert!((v["temperature_k"].as_f64().unwrap() - 300.0).abs() < 1e-6);
        // CODATA 2010 reproduces the published monochromatic-ish value.
        let (ok, out, _) = run(&[
            "radiance",
            "--band",
            "10.999-11.001",
            "--temperature",
            "300",
            "--codata",
            "2010",
            "--json",
        ]);
        assert!(ok);
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert!(rel(v["radiance_w_m2_sr"].as_f64().unwrap() / 0.002, 9.573176935) < 1e-6);
    }

    #[test]
    fn response_file_and_errors() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("r.csv");
        std::fs::write(&f, "wavelength_um,response\n7,1\n15,1\n").unwrap();
        let fs = f.to_str().unwrap();
        // A flat response cut to 8–14 equals the flat band.
        let (ok, out, err) = run(&[
            "radiance",
            "--band",
            "8-14",
            "--response",
            fs,
            "--temperature",
            "300",
            "--json",
        ]);
        assert!(ok, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert!(rel(v["radiance_w_m2_sr"].as_f64().unwrap(), 54.93346137684) < 1e-6);
        std::fs::write(&f, "7,1\n8,oops\n").unwrap();
        let (ok, _, err) = run(&["radiance", "--response", fs, "--temperature", "300"]);
        assert!(!ok && err.contains("r.csv:line 2"), "{err}");
        let (ok, _, err) = run(&["radiance", "--band", "14-8", "--temperature", "300"]);
        assert!(!ok && err.contains("--band"), "{err}");
        let (ok, _, _) = run(&["radiance", "--band", "8-14"]);
        assert!(!ok);
        let (ok, _, _) = run(&[
            "radiance",
            "--band",
            "8-14",
            "--temperature",
            "300",
            "--radiance",
            "3",
        ]);
        assert!(!ok);
    }
}
