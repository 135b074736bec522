//! Tests: atmosphere — MODTRAN tape7 import, the built-in atmosphere, the
//! tape7 lookup-table atmosphere.

use irsig::atmosphere::{Tape7, Tape7Mode};
use irsig::radiometry::Band;

use crate::util;

type Row = (f64, f64, f64, f64);

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn every_tape7_file_parses() {
    let Some(dir) = util::shared_data("modtran") else {
        return;
    };
    let expect = [
        ("tape7-01b", Tape7Mode::Transmittance, 655.0, 750.0),
        ("tape7-02c", Tape7Mode::Radiance, 655.0, 715.0),
        ("tape7-05", Tape7Mode::Radiance, 2050.0, 2100.0),
        ("tape7.LWIRSun", Tape7Mode::Radiance, 833.0, 1250.0),
        ("tape7.MWIRSun", Tape7Mode::Radiance, 2222.0, 2857.0),
    ];
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let p = entry.unwrap().path();
        let name = p.file_name().unwrap().to_str().unwrap().to_string();
        if !name.starts_with("tape7") {
            continue;
        }
        let t = Tape7::read(&p).unwrap_or_else(|e| panic!("{e}"));
        seen += 1;
        let &(_, mode, first, last) = expect.iter().find(|e| e.0 == name).unwrap();
        assert_eq!(t.mode, mode, "{name}");
        assert_eq!(t.wavenumber_cm[0], first);
        assert_eq!(*t.wavenumber_cm.last().unwrap(), last);
        let (_, tau) = t.transmittance_um();
        assert!(tau.iter().all(|&x| (0.0..=1.0).contains(&x)), "{name}");
        if mode == Tape7Mode::Radiance {
            // TOTAL_RAD = PTH_THRML + SURF_EMIS + SOL_SCAT + GRND_RFLT (to the
            // printed precision): checks the columns were cut right.
            let c = |n| t.column(n).unwrap();
            for i in 0..t.len() {
                let sum =
                    c("PTH_THRML")[i] + c("SURF_EMIS")[i] + c("SOL_SCAT")[i] + c("GRND_RFLT")[i];
                let tot = c("TOTAL_RAD")[i];
                assert!(
                    (sum - tot).abs() <= 1e-4 * tot,
                    "{name} row {i}: {sum} vs {tot}"
                );
            }
        }
    }
    assert_eq!(seen, expect.len());
}

#[test]
fn tape7_blank_column_and_two_line_header() {
    let Some(dir) = util::shared_data("modtran") else {
        return;
    };
    let t = Tape7::read(dir.join("tape7-02c")).unwrap();
    let sct = t.column("THRML_SCT").unwrap();
    assert!(
        sct.iter().all(|v| v.is_nan()),
        "THRML_SCT is blank in tape7-02c"
    );
    assert_eq!(t.column("SURF_EMIS").unwrap()[0], 0.0);
    assert_eq!(t.column("SOL_SCAT").unwrap()[0], 8.1174e-30);
    assert_eq!(t.column("BBODY_T[K]").unwrap()[0], 299.670);
    let t = Tape7::read(dir.join("tape7-01b")).unwrap();
    assert_eq!(t.columns.len(), 39);
    assert_eq!(t.column("H2O TRANS").unwrap()[0], 0.6119);
    assert_eq!(t.column("H2O CONT").unwrap()[0], 0.1949);
    assert_eq!(t.column("H2-CH4").unwrap()[0], 1.0);
    assert_eq!(t.column("CH4-CH4").unwrap()[0], 1.0);
    assert_eq!(t.column("-LOG").unwrap()[0], 15.344);
}

#[test]
fn tape7_lwir_band_integrals_match_direct_trapezoid() {
    let Some(dir) = util::shared_data("modtran") else {
        return;
    };
    let path = dir.join("tape7.LWIRSun");
    let t = Tape7::read(&path).unwrap();
    // Independent computation straight from the text columns: trapezoid
    // sums in the wavenumber domain over 8–12 µm = 833.33–1250 cm⁻¹.
    let text = std::fs::read_to_string(&path).unwrap();
    // ν, τ, PTH_THRML, SOL_SCAT per row.
    let mut rows: Vec<Row> = Vec::new();
    let mut on = false;
    for line in text.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.first() == Some(&"FREQ") {
            on = true;
            continue;
        }
        if !on {
            continue;
        }
        if f[0].starts_with("-9999") {
            break;
        }
        let v = |i: usize| f[i].parse::<f64>().unwrap();
        rows.push((v(0), v(1), v(2), v(5)));
    }
    let (nu_lo, nu_hi) = (1e4 / 12.0, 1e4 / 8.0);
    // ∫ f dν on [nu_lo, nu_hi] of the piecewise-linear f(ν).
    let integrate_nu = |f: &dyn Fn(&Row) -> f64| -> f64 {
        let mut s = 0.0;
        for w in rows.windows(2) {
            let (a, b) = (w[0].0, w[1].0);
            let (fa, fb) = (f(&w[0]), f(&w[1]));
            let (x0, x1) = (a.max(nu_lo), b.min(nu_hi));
            if x1 <= x0 {
                continue;
            }
            let at = |x: f64| fa + (fb - fa) * (x - a) / (b - a);
            s += 0.5 * (at(x0) + at(x1)) * (x1 - x0);
        }
        s
    };
    // L_λ dλ = L_ν dν: in-band radiance in W m⁻² sr⁻¹ = 1e4 ∫ L_ν dν.
    let l_direct = 1e4 * integrate_nu(&|r| r.2 + r.3);
    // Band-mean transmittance over 8–12 µm: ∫ τ dλ / 4 µm, dλ = 1e4/ν² dν.
    let tau_direct = integrate_nu(&|r| r.1 * 1e4 / (r.0 * r.0)) / 4.0;

    let band = Band::flat(8.0, 12.0, 0.005).unwrap();
    let g = band.grid();
    let (wl, tau) = t.transmittance_um();
    let tau_g = g.resample_mean(&wl, &tau, 0.01).unwrap();
    let (wl, lu) = t.path_radiance_um().unwrap();
    let lu_g = g.resample_mean(&wl, &lu, 0.01).unwrap();
    let tau_band = band.mean(&tau_g);
    let l_band = band.integrate(&lu_g);
    println!(
        "tape7.LWIRSun 8–12 µm: τ̄ = {tau_band:.6} (direct {tau_direct:.6}), L_u = {l_band:.6} W/m²/sr (direct {l_direct:.6})"
    );
    // Different discretisations (linear in λ vs in ν, 1 cm⁻¹ rows): ~1e-6 apart.
    assert!(
        rel(tau_band, tau_direct) < 1e-5,
        "{tau_band} vs {tau_direct}"
    );
    assert!(rel(l_band, l_direct) < 1e-5, "{l_band} vs {l_direct}");
    // Sanity: a tropical zenith path in the 8–12 µm window.
    assert!(tau_band > 0.3 && tau_band < 0.9);
}

#[test]
fn tape7_errors_name_file_and_line() {
    let good = "header\n    FREQ  TOT_TRANS  PTH_THRML   SOL_SCAT\n  833.00 0.43711221 6.6340E-06 2.4683E-10\n  834.00 0.43369895 6.6668E-06 2.4625E-10\n  835.00 0.41594598 6.8788E-06 2.3742E-10\n -9999.\n";
    let t = Tape7::parse(good, "t7").unwrap();
    assert_eq!(t.len(), 3);
    let e = Tape7::parse(&good.replace("6.6668E-06", "6.66x8E-06"), "t7")
        .unwrap_err()
        .to_string();
    assert!(e.contains("t7:line 4") && e.contains("PTH_THRML"), "{e}");
    let e = Tape7::parse(&good.replace(" -9999.\n", ""), "t7")
        .unwrap_err()
        .to_string();
    assert!(e.contains("-9999"), "{e}");
    let e = Tape7::parse("just text\n", "t7").unwrap_err().to_string();
    assert!(e.contains("t7") && e.contains("FREQ"), "{e}");
    let e = Tape7::parse(&good.replace("835.00", "834.00"), "t7")
        .unwrap_err()
        .to_string();
    assert!(e.contains("t7:line 5") && e.contains("monotonic"), "{e}");
    let e = Tape7::parse(&good.replace("6.6340E-06", "          "), "t7")
        .unwrap_err()
        .to_string();
    assert!(e.contains("t7:line 3") && e.contains("blank"), "{e}");
}
