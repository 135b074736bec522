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
#[ignore = "needs ../shared/data"]
fn every_tape7_file_parses() {
    let dir = util::shared_data("modtran");
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
#[ignore = "needs ../shared/data"]
fn tape7_blank_column_and_two_line_header() {
    let dir = util::shared_data("modtran");
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
#[ignore = "needs ../shared/data"]
fn tape7_lwir_band_integrals_match_direct_trapezoid() {
    let dir = util::shared_data("modtran");
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

mod builtin {
    use super::*;
    use irsig::atmosphere::{
        Atmosphere, BuiltinAtmosphere, PathGeometry, SkyConditions, SurfaceMet,
    };
    use irsig::radiometry::SpectralGrid;

    fn met(rh: f64) -> SurfaceMet {
        SurfaceMet {
            air_temperature_k: 295.0,
            relative_humidity: rh,
            pressure_pa: 101_325.0,
            ground_altitude_m: 100.0,
        }
    }

    fn band_values(a: &Atmosphere, g: &PathGeometry, band: &Band) -> (f64, f64) {
        let p = a.path(g, band.grid()).unwrap();
        (
            band.mean(&p.transmittance),
            band.integrate(&p.path_radiance),
        )
    }

    #[test]
    fn monotone_in_range_and_water_vapour_with_zero_range_limit() {
        for (lo, hi) in [(8.0, 14.0), (3.0, 5.0)] {
            let band = Band::flat(lo, hi, 0.02).unwrap();
            let atmos = |rh| Atmosphere::Builtin(BuiltinAtmosphere::new(met(rh)).unwrap());
            // Zero range: τ = 1 and L_u = 0 exactly; 1 cm: close to it, and
            // 1 mm closer (the CO₂ 4.3 µm band centre absorbs measurably even
            // over 1 cm, and LOWTRAN 7's band models, exp(−(CW)^a) with
            // a ≈ 0.55 for water, lose ~0.1 % of 3–5 µm there: the power
            // law's slope is infinite at W = 0).
            let a = atmos(0.6);
            let g0 = PathGeometry {
                sensor_altitude_m: 101.5,
                target_altitude_m: 101.5,
                range_m: 0.0,
            };
            assert_eq!(band_values(&a, &g0, &band), (1.0, 0.0));
            let g1 = PathGeometry {
                range_m: 0.01,
                ..g0
            };
            let (t, l) = band_values(&a, &g1, &band);
            assert!(
                t > 0.998 && l < 2e-3 * band.blackbody_radiance(295.0),
                "{t} {l}"
            );
            let (t_mm, l_mm) = band_values(
                &a,
                &PathGeometry {
                    range_m: 0.001,
                    ..g0
                },
                &band,
            );
            assert!(t_mm > t && l_mm < l, "{t_mm} {l_mm} vs {t} {l}");
            // Range: horizontal near the ground, and slant down from 2 km.
            for slant in [false, true] {
                let mut last = (1.0, 0.0);
                for r in [10.0, 100.0, 500.0, 1000.0, 2000.0, 2500.0, 5000.0, 20_000.0] {
                    let g = if slant {
                        // Sensor at 2.1 km looking down 60° off nadir, growing range.
                        PathGeometry {
                            sensor_altitude_m: 2100.0,
                            target_altitude_m: 2100.0 - 0.5 * r,
                            range_m: r,
                        }
                    } else {
                        PathGeometry { range_m: r, ..g0 }
                    };
                    if g.target_altitude_m < 100.0 {
                        continue;
                    }
                    let (t, l) = band_values(&a, &g, &band);
                    assert!(
                        t < last.0 && l > last.1,
                        "{lo}-{hi} µm slant={slant} r={r}: τ {t} L_u {l} after {last:?}"
                    );
                    assert!((0.0..=1.0).contains(&t));
                    last = (t, l);
                }
            }
            // Water vapour at 1 km horizontal.
            let g = PathGeometry {
                range_m: 1000.0,
                ..g0
            };
            let mut last = (1.1, -1.0);
            for rh in [0.0, 0.2, 0.5, 0.8, 1.0] {
                let (t, l) = band_values(&atmos(rh), &g, &band);
                assert!(
                    t < last.0 && l > last.1,
                    "{lo}-{hi} µm rh {rh}: τ {t} L_u {l}"
                );
                last = (t, l);
            }
        }
    }

    #[test]
    fn long_opaque_path_radiates_like_a_blackbody_at_air_temperature() {
        // 50 km horizontal in humid air: the 13.5–14 µm CO₂/H₂O region is
        // opaque, so L_u → B(T_air) there (Kirchhoff for an isothermal path).
        let a = BuiltinAtmosphere::new(SurfaceMet {
            relative_humidity: 0.9,
            ..met(0.9)
        })
        .unwrap();
        let band = Band::flat(13.5, 14.0, 0.01).unwrap();
        let p = a.path(100.0, 100.0, 50_000.0, band.grid()).unwrap();
        let t_air = a.state(100.0).temperature_k;
        assert!((t_air - 295.0).abs() < 1e-9);
        assert!(band.mean(&p.transmittance) < 1e-3);
        assert!(
            rel(
                band.integrate(&p.path_radiance),
                band.blackbody_radiance(t_air)
            ) < 1e-3
        );
    }

    #[test]
    #[ignore = "needs ../shared/data"]
    fn zenith_path_compares_with_modtran_tropical() {
        // tape7.LWIRSun: MODTRAN tropical model, ground to space at zenith,
        // 4.11 g/cm² water. The built-in model with the same surface state
        // (299.7 K, 81 % RH → 4.06 g/cm²) is within 0.1 in band-mean
        // transmittance and 20 % in path radiance over 8–12 µm (it lacks
        // ozone, which MODTRAN has at 9.6 µm).
        let dir = util::shared_data("modtran");
        let t = Tape7::read(dir.join("tape7.LWIRSun")).unwrap();
        let band = Band::flat(8.0, 12.0, 0.01).unwrap();
        let g = band.grid();
        let (wl, tau) = t.transmittance_um();
        let tau_m = band.mean(&g.resample_mean(&wl, &tau, 0.02).unwrap());
        let (wl, lu) = t.path_radiance_um().unwrap();
        let lu_m = band.integrate(&g.resample_mean(&wl, &lu, 0.02).unwrap());
        let a = BuiltinAtmosphere::new(SurfaceMet {
            air_temperature_k: 299.7,
            relative_humidity: 0.81,
            pressure_pa: 101_300.0,
            ground_altitude_m: 0.0,
        })
        .unwrap();
        assert!((a.water_column_g_cm2() - 4.11).abs() < 0.1);
        let p = a.path_to_space(0.0, g).unwrap();
        let (tau_b, lu_b) = (
            band.mean(&p.transmittance),
            band.integrate(&p.path_radiance),
        );
        println!(
            "8–12 µm zenith: MODTRAN τ̄ {tau_m:.3} L_u {lu_m:.2}; built-in τ̄ {tau_b:.3} L_u {lu_b:.2}"
        );
        assert!((tau_b - tau_m).abs() < 0.1);
        assert!(rel(lu_b, lu_m) < 0.2);
    }

    #[test]
    fn sky_radiance_matches_weather_longwave() {
        let a = BuiltinAtmosphere::new(met(0.6)).unwrap();
        // Integrated over 3–100 µm (with a Rayleigh–Jeans tail) the scaled sky
        // radiance equals E_sky/π.
        let g = SpectralGrid::uniform(3.0, 100.0, 0.02).unwrap();
        let e_sky = 350.0;
        let l = a.sky_radiance(e_sky, &g).unwrap();
        let c = irsig::radiometry::Constants::CODATA_2018;
        let t = 295.0;
        let scale = l[l.len() - 1] / irsig::radiometry::planck_radiance(100.0, t);
        let tail = scale * c.c1l_w_um4_m2_sr() * t / (3.0 * c.c2_um_k() * 100f64.powi(3));
        let total = g.integrate(&l) + tail;
        assert!(rel(total, e_sky / std::f64::consts::PI) < 2e-3, "{total}");
        // The window is darker than the opaque bands (relative to B(T_air)).
        let p = irsig::radiometry::Planck::default();
        let i10 = g.wavelengths_um().iter().position(|&x| x >= 10.0).unwrap();
        let i20 = g.wavelengths_um().iter().position(|&x| x >= 20.0).unwrap();
        assert!(l[i10] / p.radiance(10.0, t) < 0.7 * l[i20] / p.radiance(20.0, t));
        // Through the Atmosphere enum; None gives a grey body of the same flux.
        let sky = SkyConditions {
            air_temperature_k: t,
            sky_longwave_w_m2: e_sky,
        };
        let none = Atmosphere::None.sky_radiance(&sky, &g).unwrap();
        let eps = e_sky / (c.stefan_boltzmann_w_m2_k4() * t.powi(4));
        assert!(rel(none[i10], eps * p.radiance(10.0, t)) < 1e-12);
        // Solar transmittance: 1 with no atmosphere, 0 below the horizon,
        // lower at a lower sun.
        let b = Atmosphere::Builtin(a);
        let g = SpectralGrid::uniform(3.0, 5.0, 0.02).unwrap();
        let m = |v: Vec<f64>| v.iter().sum::<f64>() / v.len() as f64;
        assert_eq!(
            m(Atmosphere::None.solar_transmittance(30.0, &g).unwrap()),
            1.0
        );
        assert_eq!(m(b.solar_transmittance(95.0, &g).unwrap()), 0.0);
        let t30 = m(b.solar_transmittance(30.0, &g).unwrap());
        let t70 = m(b.solar_transmittance(70.0, &g).unwrap());
        assert!(t30 > t70 && t70 > 0.0 && t30 < 1.0, "{t30} {t70}");
    }

    #[test]
    fn rejects_bad_conditions() {
        let e = BuiltinAtmosphere::new(SurfaceMet {
            relative_humidity: 1.5,
            ..met(0.5)
        })
        .unwrap_err();
        assert!(e.to_string().contains("relative_humidity"));
        let a = BuiltinAtmosphere::new(met(0.5)).unwrap();
        let g = SpectralGrid::uniform(8.0, 9.0, 0.1).unwrap();
        assert!(a.path(1000.0, 0.0, 500.0, &g).is_err()); // range shorter than the drop
        assert!(a.path(0.0, 0.0, -1.0, &g).is_err());
    }
}

mod lut {
    use super::*;
    use irsig::atmosphere::{Atmosphere, PathGeometry, SkyConditions, Tape7Lut};
    use std::fmt::Write;

    /// A radiance-mode tape7 text with constant τ and path radiance L_ν
    /// (W cm⁻² sr⁻¹ / cm⁻¹) over 700–1300 cm⁻¹.
    fn tape7_text(tau: f64, l_nu: f64) -> String {
        let mut s = String::from(
            "synthetic\n    FREQ  TOT_TRANS  PTH_THRML  THRML_SCT  SURF_EMIS   SOL_SCAT  TOTAL_RAD\n",
        );
        for nu in (700..=1300).step_by(5) {
            writeln!(
                s,
                "{:8.2}{:11.8}{:11.4E}{:11}{:11.4E}{:11.4E}{:11.4E}",
                nu as f64, tau, l_nu, "", 0.0, 0.0, l_nu
            )
            .unwrap();
        }
        s.push_str(" -9999.\n");
        s
    }

    #[test]
    fn interpolates_in_range_and_zenith_with_zero_range_limit() {
        let dir = tempfile::tempdir().unwrap();
        let w = |name: &str, tau: f64, l: f64| {
            std::fs::write(dir.path().join(name), tape7_text(tau, l)).unwrap()
        };
        w("z0_1k", 0.8, 1e-7);
        w("z0_2k", 0.6, 2e-7);
        w("z60_1k", 0.7, 1.5e-7);
        w("z60_2k", 0.5, 3e-7);
        let index = dir.path().join("atm.json");
        std::fs::write(
            &index,
            r#"{"path": [
                {"file": "z0_1k", "view_zenith_deg": 0, "range_m": 1000},
                {"file": "z0_2k", "view_zenith_deg": 0, "range_m": 2000},
                {"file": "z60_1k", "view_zenith_deg": 60, "range_m": 1000},
                {"file": "z60_2k", "view_zenith_deg": 60, "range_m": 2000}]}"#,
        )
        .unwrap();
        let lut = Tape7Lut::read_index(&index).unwrap();
        let a = Atmosphere::Tape7Lut(lut);
        let band = Band::flat(8.0, 12.0, 0.01).unwrap();
        let at = |zen_deg: f64, r: f64| {
            let h = r * zen_deg.to_radians().cos();
            band_values(
                &a,
                &PathGeometry {
                    sensor_altitude_m: h,
                    target_altitude_m: 0.0,
                    range_m: r,
                },
                &band,
            )
        };
        // L_ν constant → L_λ = L_ν ν², ∫ over 8–12 µm = 1e4 ∫ L_ν dν = 1e4 L_ν (1250 − 833.33).
        let lu = |l_nu: f64| 1e4 * l_nu * (1250.0 - 1e4 / 12.0);
        // (1e-4: L_λ ∝ ν² is resampled as piecewise linear in λ between 5 cm⁻¹ rows.)
        let (t, l) = at(0.0, 1500.0);
        assert!(
            (t - 0.7).abs() < 1e-9 && rel(l, lu(1.5e-7)) < 1e-4,
            "{t} {l}"
        );
        let (t, l) = at(0.0, 500.0);
        assert!(
            (t - 0.9).abs() < 1e-9 && rel(l, lu(0.5e-7)) < 1e-4,
            "{t} {l}"
        );
        let (t, l) = at(0.0, 0.0);
        assert!(t == 1.0 && l == 0.0);
        let (t, l) = at(30.0, 2000.0);
        assert!(
            (t - 0.55).abs() < 1e-6 && rel(l, lu(2.5e-7)) < 1e-4,
            "{t} {l}"
        );
        let (t, _) = at(0.0, 9000.0); // held beyond the longest run
        assert!((t - 0.6).abs() < 1e-9);
        // No sky runs: solar transmittance is an error, the sky a grey body.
        assert!(a.solar_transmittance(30.0, band.grid()).is_err());
        let sky = SkyConditions {
            air_temperature_k: 290.0,
            sky_longwave_w_m2: 300.0,
        };
        assert!(a.sky_radiance(&sky, band.grid()).is_ok());
        // A band outside the runs' coverage is an error naming the file.
        let mw = Band::flat(3.0, 5.0, 0.01).unwrap();
        let e = a
            .path(
                &PathGeometry {
                    sensor_altitude_m: 1000.0,
                    target_altitude_m: 0.0,
                    range_m: 1000.0,
                },
                mw.grid(),
            )
            .unwrap_err()
            .to_string();
        assert!(e.contains("z0_1k") && e.contains("µm"), "{e}");
    }

    #[test]
    #[ignore = "needs ../shared/data"]
    fn sky_runs_from_real_tape7_and_index_errors() {
        let data = util::shared_data("modtran");
        let dir = tempfile::tempdir().unwrap();
        let index = dir.path().join("atm.json");
        let lw = data.join("tape7.LWIRSun");
        std::fs::write(
            &index,
            format!(
                r#"{{"sky": [{{"file": "{}", "zenith_deg": 0}}]}}"#,
                lw.display()
            ),
        )
        .unwrap();
        let a = Atmosphere::Tape7Lut(Tape7Lut::read_index(&index).unwrap());
        let band = Band::flat(8.0, 12.0, 0.01).unwrap();
        let t7 = Tape7::read(&lw).unwrap();
        let (wl, lu) = t7.path_radiance_um().unwrap();
        let direct = band.integrate(&band.grid().resample_mean(&wl, &lu, 0.02).unwrap());
        let sky = SkyConditions {
            air_temperature_k: 299.7,
            sky_longwave_w_m2: 400.0,
        };
        let l = band.integrate(&a.sky_radiance(&sky, band.grid()).unwrap());
        assert!(rel(l, direct) < 1e-12);
        let tau = band.mean(&a.solar_transmittance(10.0, band.grid()).unwrap());
        assert!(tau > 0.3 && tau < 0.9);
        // Errors name the index file and field.
        for (json, what) in [
            (
                r#"{"sky": [{"file": "nope", "zenith_deg": 0}]}"#,
                "sky[0].file",
            ),
            (
                r#"{"path": [{"file": "x", "view_zenith_deg": 95, "range_m": 1}]}"#,
                "path[0].view_zenith_deg",
            ),
            (
                r#"{"path": [{"file": "x", "view_zenith_deg": 0, "range_m": -1}]}"#,
                "path[0].range_m",
            ),
            ("{\n\"path\": 3}", "atm.json:line 2"),
            (r#"{}"#, "no `path` or `sky`"),
        ] {
            std::fs::write(&index, json).unwrap();
            let e = Tape7Lut::read_index(&index).unwrap_err().to_string();
            assert!(e.contains("atm.json") && e.contains(what), "{json}: {e}");
        }
        let tb = data.join("tape7-01b");
        std::fs::write(
            &index,
            format!(
                r#"{{"sky": [{{"file": "{}", "zenith_deg": 0}}]}}"#,
                tb.display()
            ),
        )
        .unwrap();
        let e = Tape7Lut::read_index(&index).unwrap_err().to_string();
        assert!(e.contains("radiance-mode"), "{e}");
    }

    fn band_values(a: &Atmosphere, g: &PathGeometry, band: &Band) -> (f64, f64) {
        let p = a.path(g, band.grid()).unwrap();
        (
            band.mean(&p.transmittance),
            band.integrate(&p.path_radiance),
        )
    }
}

mod table {
    use super::*;
    use irsig::atmosphere::{
        Atmosphere, BuiltinAtmosphere, PathGeometry, PathSpectra, PathTable, SurfaceMet,
    };

    #[test]
    fn table_reproduces_direct_paths() {
        let a = Atmosphere::Builtin(
            BuiltinAtmosphere::new(SurfaceMet {
                air_temperature_k: 290.0,
                relative_humidity: 0.7,
                pressure_pa: 100_000.0,
                ground_altitude_m: 0.0,
            })
            .unwrap(),
        );
        let band = Band::flat(8.0, 14.0, 0.05).unwrap();
        let g = band.grid();
        // 48 geometric ranges (×1.22 per step): linear interpolation error < 1 %.
        let table = PathTable::new(&a, 1500.0, 70.0, 8, 5000.0, 48, g).unwrap();
        let mut out = PathSpectra {
            transmittance: vec![],
            path_radiance: vec![],
        };
        // Zero range: exact limit.
        table.lookup(1500.0, 0.0, &mut out);
        assert!(out.transmittance.iter().all(|&t| t == 1.0));
        assert!(out.path_radiance.iter().all(|&l| l == 0.0));
        // Off-node paths agree with the direct integration to 1 %.
        for (zen, r) in [
            (0.0, 1500.0),
            (20.0, 1200.0),
            (45.0, 2000.0),
            (63.0, 3000.0),
        ] {
            let c: f64 = f64::to_radians(zen).cos();
            let geom = PathGeometry {
                sensor_altitude_m: 1500.0,
                target_altitude_m: 1500.0 - r * c,
                range_m: r,
            };
            let direct = a.path(&geom, g).unwrap();
            table.lookup(geom.target_altitude_m, r, &mut out);
            let (td, ld) = (
                band.mean(&direct.transmittance),
                band.integrate(&direct.path_radiance),
            );
            let (tt, lt) = (
                band.mean(&out.transmittance),
                band.integrate(&out.path_radiance),
            );
            assert!(
                rel(tt, td) < 0.01 && rel(lt, ld) < 0.01,
                "θ {zen} R {r}: τ {tt} vs {td}, L_u {lt} vs {ld}"
            );
        }
        // Monotone in range through the table.
        let mut last = 1.0;
        for r in [10.0, 100.0, 400.0, 1000.0, 1600.0] {
            table.lookup(1500.0 - r, r, &mut out);
            let t = band.mean(&out.transmittance);
            assert!(t < last);
            last = t;
        }
    }
}

/// Issue 17: the AFGL model atmospheres in the built-in model, the
/// directional sky, and the published values they are checked against.
mod standard {
    use super::*;
    use irsig::atmosphere::aerosol::Season;
    use irsig::atmosphere::builtin::DIFFUSIVITY_ZENITH_DEG;
    use irsig::atmosphere::{
        Aerosol, AerosolModel, Atmosphere, BuiltinAtmosphere, BuiltinParams, PathGeometry, Profile,
        SkyConditions, SurfaceMet,
    };

    fn model(p: Profile, met: Option<SurfaceMet>) -> BuiltinAtmosphere {
        BuiltinAtmosphere::with_params(
            met.unwrap_or_else(|| SurfaceMet::of_profile(p, 0.0)),
            BuiltinParams {
                profile: Some(p),
                ..BuiltinParams::default()
            },
        )
        .unwrap()
    }

    /// The built-in model on profile `p` as tabulated, clear air (no
    /// aerosol): what RRTMG's clear-sky runs compute.
    fn clear(p: Profile) -> BuiltinAtmosphere {
        BuiltinAtmosphere::with_params(
            SurfaceMet::of_profile(p, 0.0),
            BuiltinParams {
                profile: Some(p),
                aerosol: None,
                ..BuiltinParams::default()
            },
        )
        .unwrap()
    }

    #[test]
    fn profiles_by_name_and_by_site() {
        for p in Profile::ALL {
            assert_eq!(Profile::from_name(p.name()).unwrap(), p);
        }
        let e = Profile::from_name("arctic").unwrap_err().to_string();
        assert!(
            e.contains("`arctic`") && Profile::ALL.iter().all(|p| e.contains(p.name())),
            "{e}"
        );
        assert_eq!(Profile::for_site(5.0, 1), Profile::Tropical);
        assert_eq!(Profile::for_site(-15.0, 7), Profile::Tropical);
        assert_eq!(Profile::for_site(45.0, 7), Profile::MidLatitudeSummer);
        assert_eq!(Profile::for_site(45.0, 1), Profile::MidLatitudeWinter);
        assert_eq!(Profile::for_site(-45.0, 1), Profile::MidLatitudeSummer);
        assert_eq!(Profile::for_site(65.0, 6), Profile::SubArcticSummer);
        assert_eq!(Profile::for_site(65.0, 12), Profile::SubArcticWinter);
    }

    #[test]
    fn water_and_ozone_columns_match_modtran_model_atmospheres() {
        // Column water vapour (g/cm²) of MODTRAN's six model atmospheres
        // (the MODTRAN user's manual; tape7.LWIRSun's header gives the
        // tropical 4.114728), and the AFGL ozone columns in atm-cm
        // (Anderson et al. 1986: tropical 0.277 — tape7 0.000594 g/cm² —,
        // US Standard 0.343). The model integrates the tabulated profiles
        // from the ground to 50 km.
        for (p, w) in [
            (Profile::Tropical, 4.11),
            (Profile::MidLatitudeSummer, 2.92),
            (Profile::MidLatitudeWinter, 0.85),
            (Profile::SubArcticSummer, 2.08),
            (Profile::SubArcticWinter, 0.42),
            (Profile::UsStandard, 1.42),
        ] {
            let a = model(p, None);
            let got = a.water_column_g_cm2();
            println!("{p}: water column {got:.3} g/cm² (MODTRAN {w})");
            assert!(rel(got, w) < 0.05, "{p}: {got} g/cm², expected {w}");
        }
        for (p, o3) in [(Profile::Tropical, 0.277), (Profile::UsStandard, 0.343)] {
            let a = model(p, None);
            let n = 5000;
            let dz = 50_000.0 / n as f64;
            let g_cm2: f64 = (0..n)
                .map(|i| a.state((i as f64 + 0.5) * dz).o3_g_m3 * dz * 1e-4)
                .sum();
            // 1 atm-cm of O₃ = 2.687e19 molecules/cm² = 2.142e-3 g/cm².
            let atm_cm = g_cm2 / 2.142e-3;
            println!("{p}: ozone column {atm_cm:.3} atm-cm (AFGL {o3})");
            assert!(rel(atm_cm, o3) < 0.1, "{p}: {atm_cm} atm-cm");
        }
    }

    #[test]
    fn weather_blends_into_the_lowest_two_kilometres_only() {
        let p = Profile::MidLatitudeSummer;
        let own = model(p, None);
        // The profile's own surface air: the profile exactly, at every height.
        for z in [0.0, 500.0, 1500.0, 5000.0, 20_000.0] {
            let (s, l) = (own.state(z), p.level(z));
            assert!((s.temperature_k - l.temperature_k).abs() < 1e-9, "{z}");
            assert!(rel(s.pressure_pa, l.pressure_pa) < 1e-12, "{z}");
            let x = s.water_pa / s.pressure_pa * 1e6;
            assert!(rel(x, l.h2o_ppmv) < 1e-9, "{z}: {x} ppmv vs {}", l.h2o_ppmv);
        }
        // A warmer, drier afternoon: changed near the ground, not above 2 km.
        let met = SurfaceMet {
            air_temperature_k: 303.0,
            relative_humidity: 0.3,
            pressure_pa: 100_000.0,
            ground_altitude_m: 0.0,
        };
        let hot = model(p, Some(met));
        let g = hot.state(0.0);
        assert!((g.temperature_k - 303.0).abs() < 1e-9);
        assert!(rel(g.pressure_pa, 100_000.0) < 1e-12);
        let rh = g.water_pa / irsig::atmosphere::builtin::saturation_vapour_pressure_pa(303.0);
        assert!((rh - 0.3).abs() < 1e-9, "{rh}");
        let mid = hot.state(1000.0);
        assert!(
            (mid.temperature_k - (p.level(1000.0).temperature_k + 0.5 * (303.0 - 294.2))).abs()
                < 1e-9
        );
        for z in [2000.0, 3000.0, 10_000.0] {
            let (s, l) = (hot.state(z), p.level(z));
            assert!((s.temperature_k - l.temperature_k).abs() < 1e-9, "{z}");
            let x = s.water_pa / s.pressure_pa * 1e6;
            assert!(rel(x, l.h2o_ppmv) < 1e-9, "{z}");
        }
    }

    #[test]
    fn isothermal_path_radiance_is_one_minus_tau_times_planck() {
        // A horizontal path at the ground of the analytic profile is
        // isothermal: L_u = (1 − τ)·B(T) at every wavelength (Schwarzschild).
        let a = BuiltinAtmosphere::new(SurfaceMet {
            air_temperature_k: 290.0,
            relative_humidity: 0.7,
            pressure_pa: 101_325.0,
            ground_altitude_m: 0.0,
        })
        .unwrap();
        let band = Band::flat(3.0, 14.0, 0.05).unwrap();
        let p = a.path(0.0, 0.0, 3000.0, band.grid()).unwrap();
        let planck = irsig::radiometry::Planck::default();
        for ((&l, &t), &lu) in band
            .wavelengths_um()
            .iter()
            .zip(&p.transmittance)
            .zip(&p.path_radiance)
        {
            let want = (1.0 - t) * planck.radiance(l, 290.0);
            assert!(
                (lu - want).abs() <= 1e-9 * planck.radiance(l, 290.0),
                "{l} µm: {lu} vs {want}"
            );
        }
    }

    #[test]
    fn sky_rises_from_zenith_to_horizon_toward_the_air_blackbody() {
        let band = Band::flat(8.0, 12.0, 0.02).unwrap();
        for p in Profile::ALL {
            let a = Atmosphere::standard(p, 0.0).unwrap();
            let t_air = p.level(0.0).temperature_k;
            let sky = SkyConditions {
                air_temperature_k: t_air,
                sky_longwave_w_m2: f64::NAN,
            };
            let b_air = band.blackbody_radiance(t_air);
            let mut last = 0.0;
            for z in [0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 80.0, 85.0, 88.0, 89.0] {
                let l = band.integrate(&a.sky_radiance_toward(&sky, z, band.grid()).unwrap());
                assert!(l > last, "{p}: sky at {z}° {l} not above {last}");
                assert!(l < b_air, "{p}: sky at {z}° {l} above B(T_air) {b_air}");
                last = l;
            }
            println!("{p}: 8–12 µm sky at 89° = {:.3} B(T_air)", last / b_air);
            // 0.75 for the dry sub-arctic winter (0.42 g/cm², a surface
            // inversion; τ = 0.19 along the 57 air masses at 89°).
            assert!(
                last > 0.7 * b_air,
                "{p}: horizon sky {last} vs B(T_air) {b_air}"
            );
        }
    }

    /// MODTRAN tape7 band values: (band-mean τ, ∫ L_u dλ).
    fn tape7_band(file: &str, band: &Band) -> (f64, f64) {
        let t = Tape7::read(util::shared_data("modtran").join(file)).unwrap();
        let g = band.grid();
        let (wl, tau) = t.transmittance_um();
        let tau = band.mean(&g.resample_mean(&wl, &tau, 0.02).unwrap());
        let (wl, lu) = t.path_radiance_um().unwrap();
        (
            tau,
            band.integrate(&g.resample_mean(&wl, &lu, 0.02).unwrap()),
        )
    }

    #[test]
    #[ignore = "needs ../shared/data"]
    fn tropical_zenith_compares_with_modtran() {
        // tape7.LWIRSun / tape7.MWIRSun: MODTRAN, tropical model atmosphere,
        // looking up from the ground at zenith (23 km rural aerosol, as the
        // built-in model's default). The built-in model on the same AFGL
        // tropical profile, without the weather: within the issue's goals,
        // 10 % in 8–12 µm and 15 % in 3.5–4.5 µm, in τ̄ and in the zenith
        // sky radiance (MODTRAN's includes scattered sunlight, 11 % of it in
        // 3.5–4.5 µm; the built-in `look_up` is thermal, its scattered
        // sunlight is `scattered::single_scattering_compares_with_modtran`).
        // Both with the rural 23 km aerosol (the built-in model's default,
        // LOWTRAN's).
        let a = Atmosphere::standard(Profile::Tropical, 0.0).unwrap();
        let sky = SkyConditions {
            air_temperature_k: 299.7,
            sky_longwave_w_m2: f64::NAN,
        };
        for (file, lo, hi, tol_tau, tol_l) in [
            ("tape7.LWIRSun", 8.0, 12.0, 0.10, 0.10),
            ("tape7.MWIRSun", 3.5, 4.5, 0.15, 0.15),
        ] {
            let band = Band::flat(lo, hi, 0.005).unwrap();
            let (tau_m, lu_m) = tape7_band(file, &band);
            let p = a.look_up(&sky, 0.0, band.grid()).unwrap();
            let (tau_b, lu_b) = (
                band.mean(&p.transmittance),
                band.integrate(&p.path_radiance),
            );
            println!(
                "{lo}–{hi} µm zenith: MODTRAN τ̄ {tau_m:.3} L {lu_m:.3}; built-in τ̄ {tau_b:.3} \
                 L {lu_b:.3} ({:+.1} %, {:+.1} %)",
                100.0 * (tau_b / tau_m - 1.0),
                100.0 * (lu_b / lu_m - 1.0)
            );
            assert!(rel(tau_b, tau_m) < tol_tau, "{file}: τ {tau_b} vs {tau_m}");
            assert!(rel(lu_b, lu_m) < tol_l, "{file}: L {lu_b} vs {lu_m}");
        }
        // Where the MWIR differences are: band-mean τ in sub-bands, each
        // within 0.1 of MODTRAN's, or within the issue's 15 % MWIR goal where
        // that is wider: 3.5–3.8 µm, 0.743, is 0.10 too opaque in the gases
        // of LOWTRAN 7's band model and continuum with the rural aerosol
        // both models have — LOWTRAN 7 itself gives 0.648 there
        // (docs/physics/atmosphere.md has the table).
        for (lo, hi) in [(3.5, 3.8), (3.8, 4.15), (4.15, 4.2), (4.2, 4.5)] {
            let band = Band::flat(lo, hi, 0.005).unwrap();
            let (tau_m, _) = tape7_band("tape7.MWIRSun", &band);
            let p = a.look_up(&sky, 0.0, band.grid()).unwrap();
            let tau_b = band.mean(&p.transmittance);
            println!("{lo}–{hi} µm: MODTRAN τ̄ {tau_m:.3}, built-in {tau_b:.3}");
            assert!(
                (tau_b - tau_m).abs() < 0.1f64.max(0.15 * tau_m),
                "{lo}–{hi} µm: τ {tau_b} vs {tau_m}"
            );
        }
    }

    #[test]
    #[ignore = "needs ../shared/data"]
    fn the_other_modtran_runs_compare_with_the_builtin_model() {
        // tape7-05: US Standard, ground to 100 km at 20° zenith, 2050–2100
        // cm⁻¹ (CO₂, CO, O₃ and H₂O lines of 4.8 µm); tape7-01b: tropical,
        // a 1 km horizontal path at the ground, 655–750 cm⁻¹ (the CO₂
        // 15 µm band's edge); tape7-02c: tropical, ground to 100 km at 89.5°,
        // 655–715 cm⁻¹ (opaque: the sky there is a blackbody at the air's
        // temperature). MODTRAN's L is PTH_THRML + SOL_SCAT.
        let cases: [(&str, Profile, f64, f64, f64); 2] = [
            ("tape7-05", Profile::UsStandard, 20.0, 2050.0, 2100.0),
            ("tape7-02c", Profile::Tropical, 89.5, 655.0, 715.0),
        ];
        for (file, profile, zenith, v1, v2) in cases {
            let a = Atmosphere::standard(profile, 0.0).unwrap();
            let t_air = profile.level(0.0).temperature_k;
            let sky = SkyConditions {
                air_temperature_k: t_air,
                sky_longwave_w_m2: f64::NAN,
            };
            let band = Band::flat(1e4 / v2, 1e4 / v1, 0.002).unwrap();
            let (tau_m, lu_m) = tape7_band(file, &band);
            let p = a.look_up(&sky, zenith, band.grid()).unwrap();
            let (tau_b, lu_b) = (
                band.mean(&p.transmittance),
                band.integrate(&p.path_radiance),
            );
            println!(
                "{file}: MODTRAN τ̄ {tau_m:.3} L {lu_m:.4}; built-in τ̄ {tau_b:.3} L {lu_b:.4} \
                 ({:+.1} %, {:+.1} %)",
                100.0 * (tau_b / tau_m - 1.0),
                100.0 * (lu_b / lu_m - 1.0)
            );
            assert!(
                (tau_b - tau_m).abs() < 0.15 * tau_m.max(0.05),
                "{file}: τ {tau_b} vs {tau_m}"
            );
            assert!(rel(lu_b, lu_m) < 0.15, "{file}: L {lu_b} vs {lu_m}");
        }
        // tape7-01b, transmittance mode: the 1 km horizontal path.
        let a = Atmosphere::standard(Profile::Tropical, 0.0).unwrap();
        let band = Band::flat(1e4 / 750.0, 1e4 / 655.0, 0.002).unwrap();
        let (tau_m, _) = {
            let t = Tape7::read(util::shared_data("modtran").join("tape7-01b")).unwrap();
            let (wl, tau) = t.transmittance_um();
            (
                band.mean(&band.grid().resample_mean(&wl, &tau, 0.02).unwrap()),
                (),
            )
        };
        let p = a
            .path(
                &PathGeometry {
                    sensor_altitude_m: 0.0,
                    target_altitude_m: 0.0,
                    range_m: 1000.0,
                },
                band.grid(),
            )
            .unwrap();
        let tau_b = band.mean(&p.transmittance);
        println!("tape7-01b: MODTRAN τ̄ {tau_m:.3}; built-in τ̄ {tau_b:.3}");
        assert!((tau_b - tau_m).abs() < 0.1, "τ {tau_b} vs {tau_m}");
    }

    /// Rows of a reference CSV in tests/data/atmosphere (comment lines
    /// start with `#`, then a header line).
    fn reference_rows(file: &str) -> Vec<Vec<String>> {
        let path = util::repo_path(&format!("tests/data/atmosphere/{file}"));
        let text =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let rows: Vec<Vec<String>> = text
            .lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
            .skip(1)
            .map(|l| l.split(',').map(|f| f.trim().to_string()).collect())
            .collect();
        assert!(!rows.is_empty(), "{}: no rows", path.display());
        rows
    }

    fn sky_of(p: Profile) -> SkyConditions {
        SkyConditions {
            air_temperature_k: p.level(0.0).temperature_k,
            sky_longwave_w_m2: f64::NAN,
        }
    }

    /// The aerosol of a LOWTRAN 7 reference row's label (`none`,
    /// `rural-23km`, `urban-5km`, …).
    fn aerosol_of(label: &str) -> Option<Aerosol> {
        let (model, vis) = label.split_once('-')?;
        let model = AerosolModel::from_name(model).unwrap().unwrap();
        let vis: f64 = vis.trim_end_matches("km").parse().unwrap();
        Some(Aerosol::new(model, vis).unwrap())
    }

    #[test]
    fn six_profiles_zenith_compare_with_lowtran7() {
        // LOWTRAN 7 (tests/data/atmosphere/lowtran7_zenith.csv: how it was
        // run is in the file) on its six model atmospheres, looking up from
        // the ground at zenith and 60°, without aerosol, with its rural
        // aerosol at 23 km (its default and MODTRAN's) and 5 km visibility,
        // and with its urban (5 km) and maritime (23 km) aerosols, against
        // the built-in model with the same aerosol on the same AFGL
        // profiles with LOWTRAN 7's CO₂ (330 ppmv): the issue's goals,
        // 10 % in τ̄ and L in 8–12 and 8–14 µm, 15 % in 3–5 and 3.5–4.5 µm.
        // The built-in model uses LOWTRAN 7's band models, continuum and
        // aerosol tables, so this checks the profiles, the aerosol's
        // vertical structure and humidity, the layering and the radiative
        // transfer on every profile; MODTRAN
        // (`tropical_zenith_compares_with_modtran`) and RRTMG
        // (`mid_latitude_summer_band_fluxes_compare_with_rrtmg`) are the
        // independent checks of the spectroscopy.
        let rows = reference_rows("lowtran7_zenith.csv");
        let mut checked = std::collections::BTreeMap::<String, usize>::new();
        let mut worst = std::collections::BTreeMap::<String, (f64, f64)>::new();
        // (profile, zenith, lo, hi) → (LOWTRAN τ̄, L; built-in τ̄, L) without aerosol.
        let mut clear_values = std::collections::BTreeMap::<String, [f64; 4]>::new();
        let mut worst_change = 0.0f64;
        for r in &rows {
            let p = Profile::from_name(&r[0]).unwrap();
            let zenith: f64 = r[2].parse().unwrap();
            let (lo, hi): (f64, f64) = (r[3].parse().unwrap(), r[4].parse().unwrap());
            let (tau_ref, l_ref): (f64, f64) = (r[5].parse().unwrap(), r[6].parse().unwrap());
            let a = Atmosphere::Builtin(
                BuiltinAtmosphere::with_params(
                    SurfaceMet::of_profile(p, 0.0),
                    BuiltinParams {
                        profile: Some(p),
                        co2_ppmv: 330.0,
                        aerosol: aerosol_of(&r[1]),
                        ..BuiltinParams::default()
                    },
                )
                .unwrap(),
            );
            let band = Band::flat(lo, hi, 0.01).unwrap();
            let up = a.look_up(&sky_of(p), zenith, band.grid()).unwrap();
            let (tau, l) = (
                band.mean(&up.transmittance),
                band.integrate(&up.path_radiance),
            );
            let tol = if hi <= 5.0 { 0.15 } else { 0.10 };
            println!(
                "{p} {} {zenith}° {lo}–{hi} µm: LOWTRAN 7 τ̄ {tau_ref:.3} L {l_ref:.3}; built-in τ̄ \
                 {tau:.3} L {l:.3} ({:+.1} %, {:+.1} %)",
                r[1],
                100.0 * (tau / tau_ref - 1.0),
                100.0 * (l / l_ref - 1.0)
            );
            assert!(
                rel(tau, tau_ref) < tol,
                "{p} {} {zenith}° {lo}–{hi} µm: τ {tau} vs {tau_ref}",
                r[1]
            );
            assert!(
                rel(l, l_ref) < tol,
                "{p} {} {zenith}° {lo}–{hi} µm: L {l} vs {l_ref}",
                r[1]
            );
            *checked.entry(r[1].clone()).or_default() += 1;
            // The aerosol's own change (with minus without, the rows sorted
            // "none" first): within 10 % of LOWTRAN 7's change where the
            // table's 4 decimals resolve it — τ̄ changing by more than 0.005,
            // L by more than 0.05 W m⁻² sr⁻¹ (8–12 and 8–14 µm; in 3–5 µm the
            // aerosol adds 0.001–0.02, a few units of the last decimal).
            let key = format!("{p} {zenith} {lo} {hi}");
            if r[1] == "none" {
                clear_values.insert(key, [tau_ref, l_ref, tau, l]);
            } else if let Some(&[t0_ref, l0_ref, t0, l0]) = clear_values.get(&key) {
                let (dt_ref, dl_ref, dt, dl) = (t0_ref - tau_ref, l_ref - l0_ref, t0 - tau, l - l0);
                println!(
                    "  aerosol's change: τ̄ −{dt:.4} (LOWTRAN −{dt_ref:.4}), L +{dl:.4} (LOWTRAN \
                     +{dl_ref:.4})"
                );
                if dt_ref > 0.005 {
                    assert!(
                        rel(dt, dt_ref) < 0.10,
                        "{key} {}: Δτ {dt} vs {dt_ref}",
                        r[1]
                    );
                }
                if dl_ref > 0.05 {
                    assert!(
                        rel(dl, dl_ref) < 0.10,
                        "{key} {}: ΔL {dl} vs {dl_ref}",
                        r[1]
                    );
                    worst_change = worst_change.max(rel(dl, dl_ref));
                }
            }
            let w = worst.entry(format!("{} {lo}–{hi} µm", r[1])).or_default();
            w.0 = w.0.max(rel(tau, tau_ref));
            w.1 = w.1.max(rel(l, l_ref));
        }
        for (k, (t, l)) in &worst {
            println!("worst {k}: τ̄ {:.1} %, L {:.1} %", 100.0 * t, 100.0 * l);
        }
        println!(
            "worst aerosol change in L (where > 0.05 W m⁻² sr⁻¹): {:.1} %",
            100.0 * worst_change
        );
        // Six profiles × (four bands at zenith + 8–12 µm at 60°) without
        // and with the rural 23 km aerosol; six × four at 5 km; two
        // profiles × four bands urban and maritime.
        let want = [
            ("none", 30),
            ("rural-23km", 30),
            ("rural-5km", 24),
            ("urban-5km", 8),
            ("maritime-23km", 8),
        ];
        assert_eq!(
            checked,
            want.iter().map(|&(k, n)| (k.to_string(), n)).collect(),
            "reference rows"
        );
    }

    /// A horizontal path at the ground of the analytic profile (isothermal,
    /// 70 % humidity), `range_m` long, with and without `aerosol`, on `band`.
    fn ground_path(aerosol: Option<Aerosol>, range_m: f64, band: &Band) -> (Vec<f64>, Vec<f64>) {
        let a = BuiltinAtmosphere::with_params(
            SurfaceMet {
                air_temperature_k: 290.0,
                relative_humidity: 0.7,
                pressure_pa: 101_325.0,
                ground_altitude_m: 0.0,
            },
            BuiltinParams {
                aerosol,
                ..BuiltinParams::default()
            },
        )
        .unwrap();
        let p = a.path(0.0, 0.0, range_m, band.grid()).unwrap();
        (p.transmittance, p.path_radiance)
    }

    #[test]
    fn aerosol_on_a_homogeneous_path_is_beer_lambert_and_emits_like_lowtran() {
        // A 2 km path at the ground in the boundary layer (rural, 23 km,
        // 70 % humidity): the aerosol multiplies the gases' τ by
        // exp(−β₀·k(λ)·L), β₀ the 0.55 µm extinction (Koschmieder's
        // 3.912/V less Rayleigh's 0.0116 km⁻¹), k LOWTRAN's RURE2 (70 %)
        // linear in wavelength; the path radiance is (1 − τ)·B(T) with the
        // whole extinction (LOWTRAN 7 without multiple scattering, IMULT = 0,
        // counts scattering as emission).
        let band = Band::flat(3.0, 14.0, 0.05).unwrap();
        let aer = Aerosol::default();
        let (t0, _) = ground_path(None, 2000.0, &band);
        let (t1, l1) = ground_path(Some(aer), 2000.0, &band);
        let beta0 = 3.912 / 23.0 - 0.0116;
        let beta = aer.extinction_055_km(Season::SpringSummer, 0.0)[0];
        assert!(rel(beta, beta0) < 0.005, "{beta} vs Koschmieder {beta0}");
        let planck = irsig::radiometry::Planck::default();
        for (i, &l) in band.wavelengths_um().iter().enumerate() {
            let (k, k_abs) = aer.boundary_coefficients(l, 70.0);
            let want = (-beta * k * 2.0).exp();
            assert!(
                rel(t1[i] / t0[i], want) < 1e-9,
                "{l} µm: {} vs {want}",
                t1[i] / t0[i]
            );
            let b = planck.radiance(l, 290.0);
            assert!((l1[i] - (1.0 - t1[i]) * b).abs() < 1e-9 * b, "{l} µm");
            assert!(k_abs < k, "{l} µm");
        }
        let (k10, a10) = aer.boundary_coefficients(10.0, 70.0);
        println!(
            "rural 23 km, 70 %: 10 µm k = {k10:.4} of 0.55 µm, absorbing {:.0} %",
            100.0 * a10 / k10
        );
    }

    #[test]
    fn halving_the_visibility_doubles_the_ground_extinction() {
        // Koschmieder: β(0.55 µm) = 3.912/V less Rayleigh's 0.0116 km⁻¹
        // (LOWTRAN's HZ2K at the ground), so halving V from 23 to 11.5 km
        // multiplies the aerosol optical depth of a path at the ground by
        // (3.912/11.5 − 0.0116)/(3.912/23 − 0.0116) = 2.07 at every
        // wavelength. (Aloft LOWTRAN's profile is not scaled: at 2 km the
        // boundary layer is 0.0621 km⁻¹ for every V ≤ 23 km.)
        let band = Band::flat(8.0, 12.0, 0.05).unwrap();
        let (t0, _) = ground_path(None, 1000.0, &band);
        let depth = |v: f64| -> Vec<f64> {
            let (t, _) = ground_path(
                Some(Aerosol::new(AerosolModel::Rural, v).unwrap()),
                1000.0,
                &band,
            );
            t.iter().zip(&t0).map(|(a, b)| (b / a).ln()).collect()
        };
        let (d23, d11) = (depth(23.0), depth(11.5));
        let want = (3.912 / 11.5 - 0.0116) / (3.912 / 23.0 - 0.0116);
        for (a, b) in d23.iter().zip(&d11) {
            assert!(rel(b / a, want) < 0.01, "{} vs {want}", b / a);
            assert!((b / a - 2.0).abs() < 0.1);
        }
        // Above the ground the slant column grows too, less than twice.
        let col = |v: f64| -> f64 {
            let a = Aerosol::new(AerosolModel::Rural, v).unwrap();
            (0..2000)
                .map(|i| {
                    a.extinction_055_km(Season::SpringSummer, (i as f64 + 0.5) * 1e-3)[0] * 1e-3
                })
                .sum()
        };
        let (c23, c11) = (col(23.0), col(11.5));
        println!("0–2 km column at 0.55 µm: {c23:.4} (23 km), {c11:.4} (11.5 km)");
        assert!(c11 > 1.5 * c23 && c11 < 3.0 * c23);
    }

    #[test]
    fn aerosol_columns_match_lowtran7_regions() {
        // LOWTRAN 7's printed 0.55 µm optical depths of its four aerosol
        // regions on the vertical path 0–100 km, rural 23 km (TAPE6 of the
        // runs of lowtran7_zenith.csv, "AER 1–3"): boundary layer 0.2365
        // (every profile), troposphere 0.08102 (spring–summer) and 0.05139
        // (fall–winter, the two winter profiles), stratosphere 0.007198 and
        // 0.007623 — against the profile here integrated from 0 to 50 km.
        let a = Aerosol::default();
        for (season, want) in [
            (Season::SpringSummer, [0.2365, 0.08102, 0.007198]),
            (Season::FallWinter, [0.2365, 0.05139, 0.007623]),
        ] {
            let mut got = [0.0; 3];
            let dz = 1e-3;
            for i in 0..50_000 {
                let b = a.extinction_055_km(season, (i as f64 + 0.5) * dz);
                for r in 0..3 {
                    got[r] += b[r] * dz;
                }
            }
            println!("{season:?}: {got:?} (LOWTRAN 7 {want:?})");
            for r in 0..3 {
                // The stratosphere's top: LOWTRAN's levels at 30 and 32.5 km,
                // here the profile's nodes at 30 and 35 km (+0.6 %).
                assert!(
                    rel(got[r], want[r]) < 0.01,
                    "{season:?} region {r}: {} vs {}",
                    got[r],
                    want[r]
                );
            }
        }
    }

    #[test]
    fn mid_latitude_summer_band_fluxes_compare_with_rrtmg() {
        // RRTMG_LW's clear-sky downward flux at the surface per band on the
        // mid-latitude summer atmosphere (tests/data/atmosphere/
        // rrtmg_lw_surface_flux.csv; LBLRTM's spectroscopy, independent of
        // LOWTRAN) against π × the built-in sky at the diffusivity angle
        // (sec θ = 1.66, RRTMG's own flux approximation): each band from
        // 700 to 1390 cm⁻¹ within 10 %, the window 820–1180 cm⁻¹
        // (8.5–12.2 µm) within 10 % and 2080–3250 cm⁻¹ (3.1–4.8 µm) within
        // 15 %. Clear sky on both sides (the built-in model without aerosol).
        let p = Profile::MidLatitudeSummer;
        let a = Atmosphere::Builtin(clear(p));
        let flux = |v1: f64, v2: f64| {
            let band = Band::flat(1e4 / v2, 1e4 / v1, 0.005).unwrap();
            let sky = a
                .look_up(&sky_of(p), DIFFUSIVITY_ZENITH_DEG, band.grid())
                .unwrap();
            std::f64::consts::PI * band.integrate(&sky.path_radiance)
        };
        let rows = reference_rows("rrtmg_lw_surface_flux.csv");
        let (mut window, mut window_ref, mut mwir, mut mwir_ref) = (0.0, 0.0, 0.0, 0.0);
        for r in rows.iter().filter(|r| r[0] == p.name() && r[1] != "10") {
            let (v1, v2): (f64, f64) = (r[1].parse().unwrap(), r[2].parse().unwrap());
            let f_ref: f64 = r[3].parse().unwrap();
            let f = flux(v1, v2);
            println!(
                "{v1}–{v2} cm⁻¹: RRTMG {f_ref:.2} W/m², built-in {f:.2} ({:+.1} %)",
                100.0 * (f / f_ref - 1.0)
            );
            if v2 <= 1390.0 {
                assert!(rel(f, f_ref) < 0.10, "{v1}–{v2} cm⁻¹: {f} vs {f_ref}");
            }
            if (820.0..1180.0).contains(&v1) {
                window += f;
                window_ref += f_ref;
            }
            if v1 >= 2080.0 {
                mwir += f;
                mwir_ref += f_ref;
            }
        }
        println!("820–1180 cm⁻¹: RRTMG {window_ref:.2}, built-in {window:.2}");
        println!("2080–3250 cm⁻¹: RRTMG {mwir_ref:.3}, built-in {mwir:.3}");
        assert!(window_ref > 40.0 && rel(window, window_ref) < 0.10);
        assert!(mwir_ref > 2.0 && rel(mwir, mwir_ref) < 0.15);
    }

    #[test]
    fn downward_longwave_compares_with_rrtmg() {
        // Broadband (10–3250 cm⁻¹) downward flux at the surface of RRTMG_LW
        // on four AFGL atmospheres against the built-in model's unscaled
        // isotropic-equivalent sky (3–16 µm from the model, a blackbody at
        // the air temperature beyond 16 µm): 1/sky_scale(1 W/m²). Within
        // 10 %; the blackbody beyond 16 µm makes the dry atmospheres too
        // bright (the 16–25 µm water band is not opaque there), by 8 % for
        // the sub-arctic winter. Clear sky on both sides.
        let rows = reference_rows("rrtmg_lw_surface_flux.csv");
        let mut checked = 0;
        for r in rows.iter().filter(|r| r[1] == "10") {
            let p = Profile::from_name(&r[0]).unwrap();
            let f_ref: f64 = r[3].parse().unwrap();
            let f = 1.0 / clear(p).sky_scale(1.0).unwrap();
            println!(
                "{p}: RRTMG {f_ref:.1} W/m², built-in {f:.1} ({:+.1} %)",
                100.0 * (f / f_ref - 1.0)
            );
            assert!(rel(f, f_ref) < 0.10, "{p}: {f} vs {f_ref}");
            checked += 1;
        }
        assert_eq!(checked, 4);
    }

    #[test]
    fn look_up_and_paths_for_any_geometry() {
        let band = Band::flat(8.0, 12.0, 0.05).unwrap();
        let a = Atmosphere::standard(Profile::UsStandard, 0.0).unwrap();
        let sky = SkyConditions {
            air_temperature_k: 288.2,
            sky_longwave_w_m2: f64::NAN,
        };
        // Looking up: the path radiance is the sky radiance toward that zenith.
        let up = a.look_up(&sky, 30.0, band.grid()).unwrap();
        assert_eq!(
            up.path_radiance,
            a.sky_radiance_toward(&sky, 30.0, band.grid()).unwrap()
        );
        assert!(a.look_up(&sky, 95.0, band.grid()).is_err());
        // A rooftop at 30 m seen from 1 km is a shorter, thinner path than
        // the ground at the same zenith.
        let path = |ht: f64| {
            let g = PathGeometry {
                sensor_altitude_m: 1000.0,
                target_altitude_m: ht,
                range_m: (1000.0 - ht) / 30f64.to_radians().cos(),
            };
            let p = a.path(&g, band.grid()).unwrap();
            (
                band.mean(&p.transmittance),
                band.integrate(&p.path_radiance),
            )
        };
        let (t0, l0) = path(0.0);
        let (t30, l30) = path(30.0);
        assert!(t30 > t0 && l30 < l0, "{t30} {l30} vs {t0} {l0}");
        // The vacuum: τ = 1 and no path radiance on any path.
        let p = Atmosphere::None
            .path(
                &PathGeometry {
                    sensor_altitude_m: 1000.0,
                    target_altitude_m: 0.0,
                    range_m: 1200.0,
                },
                band.grid(),
            )
            .unwrap();
        assert!(p.transmittance.iter().all(|&t| t == 1.0));
        assert!(p.path_radiance.iter().all(|&l| l == 0.0));
    }
}

/// Issue 17: where the scene's built-in atmosphere names no `visibility_km`, the
/// weather's visibility at the image time sets the aerosol's (an EPW's field 25),
/// clamped to LOWTRAN 7's table (2–50 km); a missing visibility (9999) keeps the
/// model's default (rural 23 km, urban 5 km); a scene's `visibility_km` always wins;
/// `"aerosol": "none"` stays clear air. The bundled town's weather has no visibility:
/// its renders keep rural 23 km.
#[test]
fn weather_visibility_sets_the_aerosol_unless_the_scene_names_one() {
    use irsig::atmosphere::{Aerosol, AerosolModel};
    use irsig::render::session::AtmosphereConfig;
    let config = |v: serde_json::Value| serde_json::from_value::<AtmosphereConfig>(v).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut vis = [8.0; 24];
    vis[17..].copy_from_slice(&[9999.0; 7]); // hour-ending 18:00..24:00 missing
    let p = dir.path().join("vis.epw");
    std::fs::write(&p, crate::weather::epw_visibility_day(&vis)).unwrap();
    let h = irsig::weather::load(&p).unwrap();
    let time = |s: &str| chrono::DateTime::parse_from_rfc3339(s).unwrap();
    let day = h.at(time("1990-06-21T10:00:00-05:00")).unwrap();
    let night = h.at(time("1990-06-21T21:00:00-05:00")).unwrap();
    assert_eq!(night.visibility_km, None);
    let rural = |v: f64| Some(Aerosol::new(AerosolModel::Rural, v).unwrap());

    for c in [
        AtmosphereConfig::default(),
        config(serde_json::json!("builtin")),
        config(serde_json::json!("tropical")),
        config(serde_json::json!({"model": "standard"})),
        config(serde_json::json!({"model": "builtin", "aerosol": "rural"})),
    ] {
        assert_eq!(c.aerosol_at(&day), (rural(8.0), None), "{c:?}");
        assert_eq!(c.aerosol_at(&night), (rural(23.0), None), "{c:?}");
    }
    // The model's own default where the weather has none.
    let urban = config(serde_json::json!({"model": "standard", "aerosol": "urban"}));
    let u = |v: f64| Some(Aerosol::new(AerosolModel::Urban, v).unwrap());
    assert_eq!(urban.aerosol_at(&day), (u(8.0), None));
    assert_eq!(urban.aerosol_at(&night), (u(5.0), None));
    // An explicit visibility wins, also outside the table.
    for v in [40.0, 60.0] {
        let c = config(serde_json::json!({"model": "standard", "visibility_km": v}));
        assert_eq!(c.aerosol_at(&day), (rural(v), None));
        assert_eq!(c.aerosol_at(&night), (rural(v), None));
    }
    let none = config(serde_json::json!({"model": "builtin", "aerosol": "none"}));
    assert_eq!(none.aerosol_at(&day), (None, None));
    assert_eq!(
        config(serde_json::json!("none")).aerosol_at(&day),
        (None, None)
    );
    // Observed visibilities beyond LOWTRAN's table are clamped, and say so.
    let std = AtmosphereConfig::default();
    for (v, used) in [(0.0, 2.0), (0.5, 2.0), (80.0, 50.0)] {
        let r = irsig::weather::WeatherRecord {
            visibility_km: Some(v),
            ..day
        };
        assert_eq!(std.aerosol_at(&r), (rural(used), Some(v)));
    }

    // The town: a CSV without visibility, rural 23 km at every record.
    let town = irsig::weather::load(&util::repo_path("scenes/town/weather.csv")).unwrap();
    for r in town.records() {
        assert_eq!(std.aerosol_at(r), (rural(23.0), None));
    }
}

/// Issue 17: a render whose weather gives a visibility outside LOWTRAN's table (here
/// 0.5 km at every record, the town's weather with a `visibility_km` column) gets one
/// `warning:` naming the weather file, the visibility and the 2 km the aerosol takes;
/// the town's own weather (no visibility) and a scene's explicit `visibility_km` get
/// none.
#[test]
fn weather_visibility_outside_the_table_warns_once_for_the_render() {
    use irsig::render::session::{Session, visibility_warnings};
    let dir = tempfile::tempdir().unwrap();
    let town = std::fs::read_to_string(util::repo_path("scenes/town/weather.csv")).unwrap();
    let mut header_seen = false;
    let foggy: String = town
        .lines()
        .map(|l| {
            if l.starts_with('#') || l.trim().is_empty() {
                format!("{l}\n")
            } else if !header_seen {
                header_seen = true;
                format!("{l},visibility_km\n")
            } else {
                format!("{l},0.5\n")
            }
        })
        .collect();
    let foggy_path = dir.path().join("foggy.csv");
    std::fs::write(&foggy_path, foggy).unwrap();
    let scene = |weather: &std::path::Path, atmosphere: serde_json::Value| {
        let s = serde_json::json!({
            "site": {"latitude_deg": 43.16, "longitude_deg": -77.61, "altitude_m": 160.0,
                     "utc_offset_hours": -4.0},
            "time": "2025-06-20T14:00:00-04:00",
            "weather": {"file": weather},
            "materials": [util::repo_path("scenes/materials.json")],
            "atmosphere": atmosphere,
            "objects": [{"name": "ground", "material": "asphalt",
                         "shapes": [{"plane": {"size": [50.0, 50.0]}}]}],
            "sensors": [{"type": "frame", "name": "cam", "width": 4, "height": 4,
                         "fov_deg": 30.0, "position": [0.0, -40.0, 40.0],
                         "look_at": [0.0, 0.0, 0.0],
                         "bands": [{"name": "LWIR", "response": [8.0, 12.0]}]}]
        });
        let p = dir.path().join("scene.json");
        std::fs::write(&p, serde_json::to_string(&s).unwrap()).unwrap();
        Session::open(&p, irsig::trace::Backend::Embree).unwrap()
    };
    let std = serde_json::json!("standard");
    let s = scene(&foggy_path, std.clone());
    let w = visibility_warnings(&s, &[]);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("foggy.csv") && w[0].contains("0.5 km") && w[0].contains("2 km"),
        "{w:?}"
    );
    // `scene check` shows what `render` would warn.
    let check = std::process::Command::new(env!("CARGO_BIN_EXE_irsig"))
        .args(["scene", "check"])
        .arg(dir.path().join("scene.json"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&check.stderr);
    assert!(check.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("warning: {}", w[0])),
        "scene check did not warn: {stderr}"
    );
    let times: Vec<_> = (12..15)
        .map(|h| {
            chrono::DateTime::parse_from_rfc3339(&format!("2025-06-20T{h}:00:00-04:00")).unwrap()
        })
        .collect();
    let w = visibility_warnings(&s, &times);
    assert!(w.len() == 1 && w[0].contains("2 more image times"), "{w:?}");
    let explicit = serde_json::json!({"model": "standard", "visibility_km": 10.0});
    assert!(visibility_warnings(&scene(&foggy_path, explicit), &[]).is_empty());
    let town = util::repo_path("scenes/town/weather.csv");
    assert!(visibility_warnings(&scene(&town, std), &[]).is_empty());
}

/// Single-scattered sunlight of the built-in model (`atmosphere::scatter`).
mod scattered {
    use super::*;
    use irsig::atmosphere::aerosol::Season;
    use irsig::atmosphere::scatter::{
        henyey_greenstein, rayleigh_cross_section_m2, rayleigh_phase, rayleigh_scattering_per_m,
    };
    use irsig::atmosphere::{
        Aerosol, Atmosphere, BuiltinAtmosphere, BuiltinParams, PathGeometry, Profile, Sun,
        SurfaceMet,
    };
    use irsig::radiometry::SpectralGrid;
    use irsig::radiometry::solar::solar_irradiance_toa_at;

    /// (1/4π)∫P dΩ and the mean cosine (1/4π)∫P cos Θ dΩ, midpoint rule in
    /// cos Θ.
    fn moments(p: impl Fn(f64) -> f64) -> (f64, f64) {
        let n = 400_000;
        let (mut m0, mut m1) = (0.0, 0.0);
        for k in 0..n {
            let mu = -1.0 + 2.0 * (k as f64 + 0.5) / n as f64;
            let v = p(mu) * 2.0 / n as f64 * 0.5;
            m0 += v;
            m1 += v * mu;
        }
        (m0, m1)
    }

    #[test]
    fn phase_functions_are_normalised() {
        for g in [-0.6, 0.0, 0.3, 0.7, 0.9] {
            let (m0, m1) = moments(|mu| henyey_greenstein(g, mu));
            assert!((m0 - 1.0).abs() < 1e-5, "g {g}: ∫P dΩ/4π = {m0}");
            assert!((m1 - g).abs() < 1e-5, "g {g}: ⟨cos Θ⟩ = {m1}");
        }
        assert_eq!(henyey_greenstein(0.0, 0.3), 1.0);
        let (m0, m1) = moments(rayleigh_phase);
        assert!((m0 - 1.0).abs() < 1e-6 && m1.abs() < 1e-9, "{m0} {m1}");
        // Without depolarisation it would be 3/4(1 + cos²Θ): 0.75 at 90°,
        // 1.5 at 0°; the depolarisation (ρ = 0.0279) raises 90° and lowers
        // 0° by ~1.5 %.
        assert!(rayleigh_phase(0.0) > 0.75 && rayleigh_phase(0.0) < 0.77);
        assert!(rayleigh_phase(1.0) > 1.47 && rayleigh_phase(1.0) < 1.5);
    }

    #[test]
    fn rayleigh_scattering_falls_as_the_inverse_fourth_power() {
        for (a, b) in [(3.0, 6.0), (4.0, 8.0), (6.0, 12.0)] {
            let r = rayleigh_cross_section_m2(a) / rayleigh_cross_section_m2(b);
            assert!((r / 16.0 - 1.0).abs() < 0.02, "σ({a})/σ({b}) = {r}");
        }
        // At sea level (288.15 K, 1013.25 hPa) and 0.55 µm: LOWTRAN 7's
        // 0.0116 km⁻¹ (the Rayleigh extinction its HZ2K table subtracts
        // from Koschmieder's 3.912/V).
        let b = rayleigh_scattering_per_m(0.55, 101_325.0, 288.15) * 1e3;
        assert!((b / 0.0116 - 1.0).abs() < 0.02, "{b} km⁻¹");
    }

    fn analytic_atmosphere() -> Atmosphere {
        Atmosphere::Builtin(
            BuiltinAtmosphere::new(SurfaceMet {
                air_temperature_k: 300.0,
                relative_humidity: 0.5,
                pressure_pa: 101_325.0,
                ground_altitude_m: 0.0,
            })
            .unwrap(),
        )
    }

    #[test]
    fn thin_layer_has_the_analytic_single_scattering() {
        // A path of a few metres in the air at the ground: optically thin
        // (τ_ext ≈ 10⁻⁴), homogeneous, so L = E₀·τ_sun·ω·τ_ext·P(Θ)/(4π μ)
        // per species, τ_ext = β_ext·Δz the vertical optical depth and μ
        // the cosine of the line of sight's zenith. The aerosol's ω·β_ext
        // and g from LOWTRAN 7's boundary-layer tables at 50 % humidity,
        // Rayleigh from Bucholtz, τ_sun from the model's own solar
        // transmittance to the ground.
        let a = analytic_atmosphere();
        let grid = SpectralGrid::uniform(3.6, 4.0, 0.1).unwrap();
        let sun = Sun::new(30.0, 0.0, 1.0).unwrap();
        let tau_sun = a.solar_transmittance(30.0, &grid).unwrap();
        let aer = Aerosol::default();
        let beta055 = aer.extinction_055_km(Season::SpringSummer, 0.0)[0] * 1e-3;
        let dz = 2.0;
        // (range, cos Θ): straight down (Θ = 150°) and at 60° (Θ = 90°).
        for (range, cos_theta) in [(dz, -(30f64.to_radians().cos())), (2.0 * dz, 0.0)] {
            let mu = dz / range;
            let geom = PathGeometry {
                sensor_altitude_m: dz,
                target_altitude_m: 0.0,
                range_m: range,
            };
            assert!(
                (sun.cos_scattering_angle(geom.line_of_sight_zenith_deg()) - cos_theta).abs()
                    < 1e-12
            );
            let l = a.scattered_solar(&geom, &sun, &grid).unwrap();
            for (i, &wl) in grid.wavelengths_um().iter().enumerate() {
                let (e, ab) = aer.boundary_coefficients(wl, 50.0);
                let g = aer.boundary_asymmetry(wl, 50.0);
                let (omega, tau_ext) = ((e - ab) / e, beta055 * e * dz);
                let aer_term = omega * tau_ext * henyey_greenstein(g, cos_theta);
                let ray_term = rayleigh_scattering_per_m(wl, 101_325.0, 300.0)
                    * dz
                    * rayleigh_phase(cos_theta);
                let want = solar_irradiance_toa_at(wl) * tau_sun[i] * (aer_term + ray_term)
                    / (4.0 * std::f64::consts::PI * mu);
                assert!(
                    rel(l[i], want) < 0.01,
                    "μ {mu}, {wl} µm: {} vs {want}",
                    l[i]
                );
            }
        }
    }

    #[test]
    fn no_scattered_sunlight_at_night_or_without_an_atmosphere() {
        let a = analytic_atmosphere();
        let grid = SpectralGrid::uniform(3.5, 4.5, 0.05).unwrap();
        let geom = PathGeometry {
            sensor_altitude_m: 1000.0,
            target_altitude_m: 0.0,
            range_m: 1500.0,
        };
        for z in [90.0, 100.0, 180.0] {
            let sun = Sun::new(z, 40.0, 1.0).unwrap();
            assert!(
                a.scattered_solar(&geom, &sun, &grid)
                    .unwrap()
                    .iter()
                    .all(|&x| x == 0.0)
            );
            assert!(
                a.scattered_solar_up(10.0, &sun, &grid)
                    .unwrap()
                    .iter()
                    .all(|&x| x == 0.0)
            );
            let p = a.prepare(&grid);
            assert!(p.sun_column(&sun).unwrap().is_none());
        }
        let day = Sun::new(40.0, 0.0, 1.0).unwrap();
        assert!(
            Atmosphere::None
                .scattered_solar(&geom, &day, &grid)
                .unwrap()
                .iter()
                .all(|&x| x == 0.0)
        );
        // By day: positive, and the sunlit path is the thermal path plus
        // the scattered part, from one march.
        let p = a.prepare(&grid);
        let col = p.sun_column(&day).unwrap().expect("the sun is up");
        let ss = p.scattered(&geom, Some(&col)).unwrap();
        assert!(ss.iter().all(|&x| x > 0.0), "{ss:?}");
        let thermal = p.path(&geom).unwrap();
        let lit = p.path_sunlit(&geom, Some(&col)).unwrap();
        assert_eq!(lit.transmittance, thermal.transmittance);
        for ((l, t), s) in lit
            .path_radiance
            .iter()
            .zip(&thermal.path_radiance)
            .zip(&ss)
        {
            assert!((l - t - s).abs() < 1e-12 * l, "{l} vs {t} + {s}");
        }
        // Bad suns are errors naming the field.
        for (z, az, d, field) in [
            (-1.0, 0.0, 1.0, "sun_zenith_deg"),
            (181.0, 0.0, 1.0, "sun_zenith_deg"),
            (f64::NAN, 0.0, 1.0, "sun_zenith_deg"),
            (30.0, f64::INFINITY, 1.0, "sun_azimuth_deg"),
            (30.0, 0.0, 0.0, "distance_au"),
        ] {
            let e = Sun::new(z, az, d).unwrap_err().to_string();
            assert!(e.contains(field), "{e}");
        }
    }

    #[test]
    fn a_dimmed_beam_scatters_in_proportion() {
        // The weather's attenuation of the direct beam (clouds, haze) scales
        // the scattered sunlight linearly: half the beam, half the light;
        // none, none. Values outside 0–1 are errors naming the field.
        let a = analytic_atmosphere();
        let grid = SpectralGrid::uniform(3.5, 4.5, 0.05).unwrap();
        let clear = Sun::new(35.0, 60.0, 1.0).unwrap();
        let l = |s: &Sun| a.scattered_solar_up(20.0, s, &grid).unwrap();
        let full = l(&clear);
        for c in [0.5, 0.0] {
            let dim = l(&clear.with_attenuation(c).unwrap());
            for (d, f) in dim.iter().zip(&full) {
                assert!(*f > 0.0 && (d - c * f).abs() <= 1e-12 * f, "{d} vs {c}·{f}");
            }
        }
        for bad in [-0.1, 1.1, f64::NAN] {
            let e = clear.with_attenuation(bad).unwrap_err().to_string();
            assert!(e.contains("attenuation"), "{e}");
        }
    }

    #[test]
    fn forward_scattering_is_brighter_than_back_scattering() {
        // Aerosol scattering peaks forward (g ≈ 0.7 at 4 µm): the sky
        // looking 30° from the sun outshines the sky 150° away.
        let a = analytic_atmosphere();
        let band = Band::flat(3.5, 4.1, 0.01).unwrap();
        let toward = Sun::new(30.0, 0.0, 1.0).unwrap();
        let away = Sun::new(30.0, 180.0, 1.0).unwrap();
        let l = |s: &Sun, z: f64| band.integrate(&a.scattered_solar_up(z, s, band.grid()).unwrap());
        let (fwd, back) = (l(&toward, 60.0), l(&away, 60.0));
        assert!(fwd > 2.0 * back && back > 0.0, "{fwd} vs {back}");
    }

    /// ∫ SING_SCAT (or another radiance column) dν over the whole file, W m⁻² sr⁻¹.
    fn tape7_integral(file: &str, column: &str) -> f64 {
        let t = Tape7::read(util::shared_data("modtran").join(file)).unwrap();
        let nu = &t.wavenumber_cm;
        let c = t.column(column).unwrap();
        (1..nu.len())
            .map(|k| 0.5 * (c[k] + c[k - 1]) * (nu[k] - nu[k - 1]))
            .sum::<f64>()
            * 1e4
    }

    /// Issue 17: the sky's scattered sunlight as the renderer tabulates it
    /// (`Atmosphere::scattered_sky`, every scattering-angle node in one
    /// march): nothing at night, with the sun's beam all gone, or with no
    /// atmosphere; by day at each node the single-scattering integral of
    /// that look-up path (`scattered_solar_up` with the relative azimuth
    /// that gives the node's angle), between nodes within the
    /// interpolation's error, falling away from the sun (the aerosol's
    /// forward peak), brighter toward the sun than away from it at the
    /// same zenith.
    #[test]
    fn the_scattered_sky_is_the_single_scattering_integral_at_every_angle() {
        use irsig::atmosphere::{ANGLE_NODES, angle_node, angle_node_cos};
        let a = Atmosphere::standard(Profile::MidLatitudeSummer, 0.0).unwrap();
        let band = Band::flat(3.5, 4.5, 0.02).unwrap();
        let grid = band.grid();
        let cos: Vec<f64> = (0..ANGLE_NODES).map(angle_node_cos).collect();
        let (sun_zenith, zenith) = (40.0f64, 30.0f64);
        let day = Sun::new(sun_zenith, 0.0, 1.0).unwrap();
        // None at night, in vacuum, with no beam.
        for z in [90.0, 120.0] {
            let night = Sun::new(z, 0.0, 1.0).unwrap();
            assert!(
                a.scattered_sky(&[zenith], &night, &cos, grid)
                    .unwrap()
                    .is_none()
            );
        }
        assert!(
            Atmosphere::None
                .scattered_sky(&[zenith], &day, &cos, grid)
                .unwrap()
                .is_none()
        );
        let dark = a
            .scattered_sky(&[zenith], &day.with_attenuation(0.0).unwrap(), &cos, grid)
            .unwrap()
            .unwrap();
        assert!(dark.iter().flatten().flatten().all(|&x| x == 0.0));
        // Bad zeniths are errors.
        assert!(a.scattered_sky(&[90.0], &day, &cos, grid).is_err());
        let table = a
            .scattered_sky(&[zenith], &day, &cos, grid)
            .unwrap()
            .unwrap();
        let l: Vec<f64> = table[0].iter().map(|s| band.integrate(s)).collect();
        // The exact integral at the scattering angle of a relative azimuth.
        let (ts, tl) = (sun_zenith.to_radians(), zenith.to_radians());
        let exact_at = |cos_theta: f64| {
            let c = ((cos_theta - ts.cos() * tl.cos()) / (ts.sin() * tl.sin())).clamp(-1.0, 1.0);
            let sun = Sun::new(sun_zenith, c.acos().to_degrees(), 1.0).unwrap();
            band.integrate(&a.scattered_solar_up(zenith, &sun, grid).unwrap())
        };
        // Reachable angles at this zenith: |θ_s − θ| to θ_s + θ.
        let (lo, hi) = ((ts + tl).cos(), (ts - tl).cos());
        let mut nodes = 0;
        for (k, &c) in cos.iter().enumerate() {
            if c > lo && c < hi {
                let e = exact_at(c);
                assert!(rel(l[k], e) < 1e-9, "node {k}: {} vs {e}", l[k]);
                nodes += 1;
            }
        }
        assert!(nodes >= 4, "{nodes} nodes reachable");
        // Between nodes: the table linear in sin(Θ/2).
        let mut worst = 0.0f64;
        for j in 0..=200 {
            let c = lo + (hi - lo) * j as f64 / 200.0;
            let (k, f) = angle_node(c);
            let got = l[k] + f * (l[k + 1] - l[k]);
            worst = worst.max(rel(got, exact_at(c)));
        }
        println!("scattered sky at {zenith}° zenith: worst interpolation error {worst:.2e}");
        // 33 nodes uniform in sin(Θ/2): 1.2 % at the aerosol's forward
        // peak (measured), well inside the issue's 15 % MWIR goal.
        assert!(worst < 0.015, "{worst}");
        // Falling away from the sun; toward it (Θ = 10°) brighter than away
        // (Θ = 70°).
        assert!(l.windows(2).all(|w| w[1] <= w[0]), "{l:?}");
        assert!(exact_at(10f64.to_radians().cos()) > 2.0 * exact_at(70f64.to_radians().cos()));
    }

    /// Issue 17: the zenith sky as a render sees it by day — the thermal
    /// sky (`look_up`) plus the scattered sunlight at the ray's own
    /// scattering angle, interpolated in the renderer's angle table —
    /// against MODTRAN's total sky radiance PTH_THRML + SOL_SCAT of
    /// tape7.MWIRSun (tropical, rural 23 km, the sun at 23.08° zenith,
    /// 0.9833 AU) in 3.5–4.5 µm: within the issue's 15 % MWIR goal, and
    /// the scattered part within 10 % of MODTRAN's SING_SCAT.
    #[test]
    #[ignore = "needs ../shared/data"]
    fn the_renderers_zenith_sky_by_day_compares_with_modtran() {
        use irsig::atmosphere::{ANGLE_NODES, SkyConditions, angle_node, angle_node_cos};
        let a = Atmosphere::standard(Profile::Tropical, 0.0).unwrap();
        let band = Band::flat(1e4 / 2857.0, 1e4 / 2222.0, 0.002).unwrap();
        let d = 1.0 / 1.034f64.sqrt();
        let zen = (23.07f64.to_radians().cos() * 0.8075f64.to_radians().cos())
            .acos()
            .to_degrees();
        let sun = Sun::new(zen, 0.0, d).unwrap();
        let sky = SkyConditions {
            air_temperature_k: 299.7,
            sky_longwave_w_m2: f64::NAN,
        };
        let thermal = band.integrate(&a.look_up(&sky, 0.0, band.grid()).unwrap().path_radiance);
        let cos: Vec<f64> = (0..ANGLE_NODES).map(angle_node_cos).collect();
        let table = a
            .scattered_sky(&[0.0], &sun, &cos, band.grid())
            .unwrap()
            .unwrap();
        // Looking at the zenith: Θ = the sun's zenith.
        let (k, f) = angle_node(zen.to_radians().cos());
        let (s0, s1) = (
            band.integrate(&table[0][k]),
            band.integrate(&table[0][k + 1]),
        );
        let scattered = s0 + f * (s1 - s0);
        let total = thermal + scattered;
        let m_total = tape7_integral("tape7.MWIRSun", "PTH_THRML")
            + tape7_integral("tape7.MWIRSun", "SOL_SCAT");
        let m_single = tape7_integral("tape7.MWIRSun", "SING_SCAT");
        println!(
            "zenith sky 3.5–4.5 µm by day: built-in {thermal:.4} + {scattered:.4} = {total:.4}, \
             MODTRAN {m_total:.4} ({:+.1} %); scattered vs SING_SCAT {m_single:.4} ({:+.1} %)",
            100.0 * (total / m_total - 1.0),
            100.0 * (scattered / m_single - 1.0)
        );
        assert!(rel(total, m_total) < 0.15, "{total} vs {m_total}");
        assert!(rel(scattered, m_single) < 0.10, "{scattered} vs {m_single}");
    }

    #[test]
    #[ignore = "needs ../shared/data"]
    fn single_scattering_compares_with_modtran() {
        // Solar geometry from the runs' cards 3A1/3A2 (IPARM, IPH, IDAY):
        // tape7.MWIRSun / LWIRSun: IPARM = 1, IDAY = 1, 12:00 UT, observer
        // at 0° N 0° E, the sun (as MODTRAN echoes it) at 23.07° S,
        // 359.19° W — solar zenith 23.08°, looking at the zenith: Θ =
        // 23.08°; IPH = 2 (Mie phase functions; here Henyey–Greenstein with
        // LOWTRAN 7's g). tape7-05: IPARM = 0, observer and sun both at
        // 0° N 0° E (solar zenith 0°), line of sight at 20° zenith: Θ =
        // 20°; IPH = 0 with G = 0 (an isotropic aerosol phase function).
        // IDAY = 1: sun–earth distance 0.9833 AU (LOWTRAN's 1/d² = 1.034).
        let d = 1.0 / 1.034f64.sqrt();
        let zen = (23.07f64.to_radians().cos() * 0.8075f64.to_radians().cos())
            .acos()
            .to_degrees();
        let tropical = Atmosphere::standard(Profile::Tropical, 0.0).unwrap();
        let us_iso = Atmosphere::Builtin(
            BuiltinAtmosphere::with_params(
                SurfaceMet::of_profile(Profile::UsStandard, 0.0),
                BuiltinParams {
                    profile: Some(Profile::UsStandard),
                    aerosol_asymmetry: Some(0.0),
                    ..BuiltinParams::default()
                },
            )
            .unwrap(),
        );
        // Tolerances: 10 % in the windows, where the Henyey–Greenstein
        // phase function (against MODTRAN's Mie) and the solar spectrum
        // (E490 against MODTRAN's) dominate; 25 % in the 4.8 µm lines of
        // tape7-05, where τ_sun·τ_view, a product of band-model
        // transmittances, is too opaque — the two paths see the same lines
        // (module docs of `atmosphere::scatter`).
        for (file, a, lo, hi, sun_zenith, los_zenith, tol) in [
            (
                "tape7.MWIRSun",
                &tropical,
                1e4 / 2857.0,
                1e4 / 2222.0,
                zen,
                0.0,
                0.10,
            ),
            (
                "tape7.LWIRSun",
                &tropical,
                1e4 / 1250.0,
                1e4 / 833.0,
                zen,
                0.0,
                0.10,
            ),
            (
                "tape7-05",
                &us_iso,
                1e4 / 2100.0,
                1e4 / 2050.0,
                0.0,
                20.0,
                0.25,
            ),
        ] {
            let band = Band::flat(lo, hi, 0.002).unwrap();
            let sun = Sun::new(sun_zenith, 0.0, d).unwrap();
            let l = band.integrate(&a.scattered_solar_up(los_zenith, &sun, band.grid()).unwrap());
            let single = tape7_integral(file, "SING_SCAT");
            let all = tape7_integral(file, "SOL_SCAT");
            println!(
                "{file}: built-in {l:.4e}, MODTRAN SING_SCAT {single:.4e} ({:+.1} %), \
                 SOL_SCAT/SING_SCAT {:.4}",
                100.0 * (l / single - 1.0),
                all / single
            );
            assert!(rel(l, single) < tol, "{file}: {l} vs {single}");
        }
    }
}

#[test]
fn atmosphere_cli_reports_the_scattered_sunlight() {
    let run = |sun_zenith: &str| -> serde_json::Value {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_irsig"))
            .args([
                "atmosphere",
                "--profile",
                "tropical",
                "--band",
                "3.5-4.5",
                "--look",
                "up",
                "--zenith",
                "0",
                "--sun-zenith",
                sun_zenith,
                "--sun-azimuth",
                "180",
                "--json",
            ])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let day = run("23.08");
    let (lu, ss, total) = (
        day["path_radiance_w_m2_sr"].as_f64().unwrap(),
        day["scattered_radiance_w_m2_sr"].as_f64().unwrap(),
        day["total_path_radiance_w_m2_sr"].as_f64().unwrap(),
    );
    // Looking at the zenith with the sun 23° from it: Θ = 23°; the scattered
    // sunlight a tenth of the thermal sky in 3.5–4.5 µm, as in MODTRAN.
    assert!((total - lu - ss).abs() < 1e-12 * total, "{day}");
    assert!(ss > 0.02 * lu && ss < lu, "{day}");
    let theta = day["sun"]["scattering_angle_deg"].as_f64().unwrap();
    assert!((theta - 23.08).abs() < 1e-6, "{day}");
    let night = run("95");
    assert_eq!(night["scattered_radiance_w_m2_sr"].as_f64(), Some(0.0));
    assert_eq!(night["path_radiance_w_m2_sr"].as_f64(), Some(lu));
}
