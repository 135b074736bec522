//! Tests: weather (readers, filling, interpolation, the town history).

use std::path::{Path, PathBuf};

use chrono::{DateTime, FixedOffset, TimeDelta};
use irsig::sun::{self, Site};
use irsig::weather::{self, Format, LoadOptions, Timing, WeatherHistory, WeatherRecord, physics};

use crate::util;

fn t(s: &str) -> DateTime<FixedOffset> {
    DateTime::parse_from_rfc3339(s).unwrap()
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

fn write_tmp(dir: &tempfile::TempDir, name: &str, text: &str) -> PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const ROCHESTER: Site = Site {
    latitude_deg: 43.16,
    longitude_deg: -77.61,
    altitude_m: 170.0,
};

// ---------------------------------------------------------------- physics

/// Clark & Allen as in the EnergyPlus Engineering Reference, by hand:
/// T_db 18 °C, T_dp 12 °C, N = 3 tenths:
/// ε = (0.787 + 0.764 ln(285.15/273)) (1 + 0.0672 − 0.0315 + 0.00756) = 0.855752,
/// E = ε σ 291.15⁴ = 348.680 W/m².
#[test]
fn clark_allen_hand_values() {
    let eps = physics::clark_allen_sky_emissivity(285.15, 0.3);
    assert!(close(eps, 0.855_752, 1e-6), "{eps}");
    let e = physics::clark_allen_sky_longwave_w_m2(291.15, 285.15, 0.3);
    assert!(close(e, 348.680, 1e-3), "{e}");
    // Clear sky, cold: T_db −5.3 °C, T_dp −20 °C → ε = 0.729326, E = 212.863 W/m².
    let e = physics::clark_allen_sky_longwave_w_m2(267.85, 253.15, 0.0);
    assert!(close(e, 212.863, 1e-3), "{e}");
    // Overcast raises emissivity by the cubic cloud factor (N = 10: ×1.0940).
    let r = physics::clark_allen_sky_emissivity(285.15, 1.0)
        / physics::clark_allen_sky_emissivity(285.15, 0.0);
    assert!(close(r, 1.0 + 0.224 - 0.35 + 0.28, 1e-12), "{r}");
}

/// Erbs et al. (1982) diffuse fraction by hand, and the split's energy closure.
#[test]
fn erbs_hand_values_and_closure() {
    assert!(close(physics::erbs_diffuse_fraction(0.1), 0.991, 1e-12));
    assert!(close(physics::erbs_diffuse_fraction(0.5), 0.659_15, 1e-9));
    assert!(close(
        physics::erbs_diffuse_fraction(0.75),
        0.183_081_25,
        1e-9
    ));
    assert!(close(physics::erbs_diffuse_fraction(0.85), 0.165, 1e-12));
    // The published branches meet (nearly) at k_t = 0.22.
    let lo = 1.0 - 0.09 * 0.22;
    assert!(close(physics::erbs_diffuse_fraction(0.2200001), lo, 5e-4));
    // Split: GHI = DHI + DNI cos z.
    let (z, r) = (30.0f64, 1.0);
    let ghi = 0.6 * 1367.0 * z.to_radians().cos(); // k_t = 0.6
    let (dni, dhi) = physics::erbs_split(ghi, z, r);
    assert!(close(dhi + dni * z.to_radians().cos(), ghi, 1e-9));
    assert!(close(dhi / ghi, physics::erbs_diffuse_fraction(0.6), 1e-12));
    // Sun down: all diffuse / nothing.
    assert_eq!(physics::erbs_split(10.0, 95.0, 1.0), (0.0, 10.0));
}

/// Magnus (Alduchov & Eskridge 1996): e_s(20 °C) = 6.1094 exp(17.625·20/263.04) hPa
/// = 23.3344 hPa; RH(20 °C, T_d 10 °C) = 0.525413; dew point inverts RH exactly.
#[test]
fn magnus_hand_values_and_inverse() {
    assert!(close(
        physics::saturation_vapour_pressure_pa(293.15),
        2333.44,
        0.01
    ));
    let rh = physics::relative_humidity_from_dew_point(293.15, 283.15);
    assert!(close(rh, 0.525_413, 1e-6), "{rh}");
    for (tk, h) in [(253.0, 0.3), (283.0, 0.55), (303.0, 0.9), (300.0, 1.0)] {
        let td = physics::dew_point_from_relative_humidity(tk, h);
        assert!(close(
            physics::relative_humidity_from_dew_point(tk, td),
            h,
            1e-12
        ));
    }
    assert!(close(
        physics::dew_point_from_relative_humidity(300.0, 1.0),
        300.0,
        1e-9
    ));
}

// ---------------------------------------------------------------- DIRSIG .wth

#[test]
#[ignore = "needs ../shared/data"]
fn dirsig_wth_saw_reads_with_hand_conversions() {
    let dir = util::shared_data("dirsig");
    let path = dir.join("saw.wth");
    let opts = LoadOptions::default()
        .with_start(t("2025-01-15T00:00:00-05:00"))
        .with_site(ROCHESTER);
    let h = weather::load_with(&path, &opts).unwrap();
    assert_eq!(h.format(), Some(Format::DirsigWth));
    assert_eq!(h.records().len(), 193);
    assert_eq!(h.step(), TimeDelta::minutes(15));
    assert!(h.is_uniform());
    assert_eq!(h.start(), t("2025-01-15T00:00:00-05:00"));
    assert_eq!(h.end(), t("2025-01-17T00:00:00-05:00"));
    // Row `12.00 -5.30 1000.00  0.31-20.00   5.00    98.02     5.17 1.00  0  0   0.00  0.00`
    let r = &h.records()[48];
    assert_eq!(r.time, t("2025-01-15T12:00:00-05:00"));
    assert!(close(r.air_temperature_k, 267.85, 1e-9));
    assert!(close(r.pressure_pa, 100_000.0, 1e-9));
    assert!(close(r.relative_humidity, 0.31, 1e-12));
    assert!(close(r.dew_point_k, 253.15, 1e-9));
    assert!(close(r.wind_speed_m_s, 5.0, 1e-12));
    // 98.02 L/h × 41840 J/m² / 3600 s = 1139.2102 W/m²; 5.17 L/h = 60.0869 W/m².
    assert!(close(r.direct_normal_w_m2, 1139.2102, 1e-3));
    assert!(close(r.diffuse_horizontal_w_m2, 60.0869, 1e-3));
    assert_eq!(r.total_sky_cover, 0.0);
    // Filled: GHI = DHI + DNI cos z (Sun at Rochester), sky longwave by Clark & Allen.
    let p = sun::position_standard(&ROCHESTER, r.time).unwrap();
    let ghi =
        r.diffuse_horizontal_w_m2 + r.direct_normal_w_m2 * p.apparent_zenith_deg.to_radians().cos();
    assert!(close(r.global_horizontal_w_m2, ghi, 1e-6));
    assert!(close(r.sky_longwave_w_m2, 212.863, 1e-3));
    assert!(h.filled(48).contains(&"global_horizontal_w_m2"));
    assert!(h.filled(48).contains(&"sky_longwave_w_m2"));
    // Columns that run together: row 1 `0.00-15.00 …` is hour 0, −15 °C.
    assert!(close(h.records()[0].air_temperature_k, 258.15, 1e-9));
    assert!(close(h.records()[192].air_temperature_k, 258.15, 1e-9));
}

#[test]
#[ignore = "needs ../shared/data"]
fn dirsig_wth_needs_start_and_site() {
    let dir = util::shared_data("dirsig");
    let path = dir.join("saw.wth");
    let e = weather::load(&path).unwrap_err().to_string();
    assert!(e.contains("saw.wth") && e.contains("start"), "{e}");
    let opts = LoadOptions::default().with_start(t("2025-01-15T00:00:00-05:00"));
    let e = weather::load_with(&path, &opts).unwrap_err().to_string();
    assert!(e.contains("site"), "{e}");
}

#[test]
fn dirsig_wth_bad_rows_name_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let good = "0.00-15.00 1000.00  0.68-20.00   5.00     0.00     0.00 1.00  0  0   0.00  0.00";
    let row2 = "0.25-15.00 1000.00  0.68-20.00   5.00    -1.00     0.00 1.00  0  0   0.00  0.00";
    let p = write_tmp(&dir, "neg.wth", &format!("2 0.25\n{good}\n{row2}\n"));
    let opts = LoadOptions::default()
        .with_start(t("2025-01-15T00:00:00-05:00"))
        .with_site(ROCHESTER);
    let e = weather::load_with(&p, &opts).unwrap_err().to_string();
    assert!(
        e.contains("neg.wth:line 3") && e.contains("negative irradiance"),
        "{e}"
    );
    let row2 = "0.25-15.00 1000.00  1.68-20.00   5.00     0.00     0.00 1.00  0  0   0.00  0.00";
    let p = write_tmp(&dir, "rh.wth", &format!("2 0.25\n{good}\n{row2}\n"));
    let e = weather::load_with(&p, &opts).unwrap_err().to_string();
    assert!(
        e.contains("rh.wth:line 3") && e.contains("relative_humidity"),
        "{e}"
    );
    let p = write_tmp(
        &dir,
        "short.wth",
        &format!("2 0.25\n{good}\n0.25-15.00 1000.00\n"),
    );
    let e = weather::load_with(&p, &opts).unwrap_err().to_string();
    assert!(
        e.contains("short.wth:line 3") && e.contains("columns"),
        "{e}"
    );
    let p = write_tmp(&dir, "count.wth", &format!("3 0.25\n{good}\n{good}\n"));
    let e = weather::load_with(&p, &opts).unwrap_err().to_string();
    assert!(e.contains("count.wth:line 3") && e.contains("hour"), "{e}");
}

// ---------------------------------------------------------------- EPW

#[test]
fn epw_fixture_reads_site_times_and_fills_longwave() {
    let path = util::repo_path("tests/data/weather/rochester_sample.epw");
    let h = weather::load(&path).unwrap();
    assert_eq!(h.format(), Some(Format::Epw));
    let s = h.site().unwrap();
    assert_eq!(
        (s.latitude_deg, s.longitude_deg, s.altitude_m),
        (43.12, -77.68, 169.0)
    );
    assert_eq!(h.records().len(), 6);
    assert_eq!(h.timing(), Timing::SolarMeanEnding { interval_s: 3600 });
    // Hour 5 is hour-ending 05:00 local standard time (UTC−5); its solar values are the
    // mean of 04:00–05:00, so the record is placed at 04:30 (issue 16 item 3).
    assert_eq!(h.start(), t("1990-06-21T04:30:00-05:00"));
    assert_eq!(h.end(), t("1990-06-21T09:30:00-05:00"));
    // Hour 7 (16.7 °C, 12.0 °C, 74 %, 99 700 Pa, 220° 2.1 m/s, 3/2 tenths) and hour 8
    // (18.0 °C, 12.0 °C, 68 %, 99 700 Pa, 230° 2.6 m/s, 4/3 tenths, IR 9999): the
    // readings at the stamps are interpolated to 07:30, the irradiances are hour 8's.
    let r = &h.records()[3];
    assert_eq!(r.time, t("1990-06-21T07:30:00-05:00"));
    assert!(close(r.air_temperature_k, 290.5, 1e-9));
    assert!(close(r.dew_point_k, 285.15, 1e-9));
    assert!(close(r.relative_humidity, 0.71, 1e-12));
    assert!(close(r.pressure_pa, 99_700.0, 1e-9));
    assert_eq!(
        (
            r.global_horizontal_w_m2,
            r.direct_normal_w_m2,
            r.diffuse_horizontal_w_m2
        ),
        (402.0, 655.0, 88.0)
    );
    assert!(close(r.wind_direction_deg, 225.0, 1e-9) && close(r.wind_speed_m_s, 2.35, 1e-12));
    assert!(close(r.total_sky_cover, 0.35, 1e-12) && close(r.opaque_sky_cover, 0.25, 1e-12));
    // Clark & Allen at the mid-interval readings.
    let lw = physics::clark_allen_sky_longwave_w_m2(290.5, 285.15, 0.25);
    assert!(
        close(r.sky_longwave_w_m2, lw, 1e-9),
        "{}",
        r.sky_longwave_w_m2
    );
    assert_eq!(h.filled(3), &["sky_longwave_w_m2"]);
    // The first record has no earlier stamp: it keeps its own readings (hour 5: 14.4 °C).
    assert!(close(h.records()[0].air_temperature_k, 287.55, 1e-9));
    assert_eq!(h.records()[2].sky_longwave_w_m2, 340.0);
    assert!(h.filled(2).is_empty());
}

#[test]
fn epw_bad_rows_name_file_line_and_field() {
    let text = std::fs::read_to_string(util::repo_path("tests/data/weather/rochester_sample.epw"))
        .unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let dir = tempfile::tempdir().unwrap();
    // RH 150 % at line 11.
    let mut bad: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
    bad[10] = bad[10].replacen(",16.7,12.0,74,", ",16.7,12.0,150,", 1);
    let p = write_tmp(&dir, "rh.epw", &bad.join("\n"));
    let e = weather::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("rh.epw:line 11") && e.contains("relative_humidity"),
        "{e}"
    );
    // Truncated row at line 12.
    let mut bad: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
    bad[11] = bad[11].split(',').take(15).collect::<Vec<_>>().join(",");
    let p = write_tmp(&dir, "short.epw", &bad.join("\n"));
    let e = weather::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("short.epw:line 12") && e.contains("diffuse horizontal"),
        "{e}"
    );
    // NaN dry bulb at line 9.
    let mut bad: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
    bad[8] = bad[8].replacen(",14.4,", ",NaN,", 1);
    let p = write_tmp(&dir, "nan.epw", &bad.join("\n"));
    let e = weather::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("nan.epw:line 9") && e.contains("dry bulb"),
        "{e}"
    );
}

/// Quoted fields (RFC 4180, blanks before the opening quote allowed) may hold
/// commas: an EPW city "Rochester, NY" and a TMY3 station name read as the
/// fixtures do, with CRLF line ends.
#[test]
fn epw_and_tmy3_quoted_fields_with_commas() {
    let dir = tempfile::tempdir().unwrap();
    let epw = std::fs::read_to_string(util::repo_path("tests/data/weather/rochester_sample.epw"))
        .unwrap();
    let quoted = epw
        .replacen(
            "LOCATION,Rochester Greater Rochester Intl AP,NY,",
            "LOCATION, \"Rochester, Greater Rochester Intl AP\",\"NY\",",
            1,
        )
        .replace('\n', "\r\n");
    assert_ne!(quoted, epw);
    let p = write_tmp(&dir, "q.epw", &quoted);
    let (a, b) = (
        weather::load(&util::repo_path("tests/data/weather/rochester_sample.epw")).unwrap(),
        weather::load(&p).unwrap(),
    );
    assert_eq!(a.site(), b.site());
    assert_eq!(a.records(), b.records());

    let tmy = std::fs::read_to_string(util::repo_path(
        "tests/data/weather/rochester_sample_tmy3.csv",
    ))
    .unwrap();
    let quoted = tmy.replacen(
        "\"ROCHESTER GREATER ROCHESTER INT\"",
        "\"ROCHESTER, GREATER \"\"INT\"\"\"",
        1,
    );
    assert_ne!(quoted, tmy);
    let p = write_tmp(&dir, "q_tmy3.csv", &quoted);
    let (a, b) = (
        weather::load(&util::repo_path(
            "tests/data/weather/rochester_sample_tmy3.csv",
        ))
        .unwrap(),
        weather::load(&p).unwrap(),
    );
    assert_eq!(a.site(), b.site());
    assert_eq!(a.records(), b.records());
}

// ---------------------------------------------------------------- TMY3

#[test]
fn tmy3_fixture_reads_and_splits_missing_beam_by_erbs() {
    let path = util::repo_path("tests/data/weather/rochester_sample_tmy3.csv");
    let h = weather::load(&path).unwrap();
    assert_eq!(h.format(), Some(Format::Tmy3));
    let s = *h.site().unwrap();
    assert_eq!(
        (s.latitude_deg, s.longitude_deg, s.altitude_m),
        (43.117, -77.683, 169.0)
    );
    // Hour-ending 11:00 holds the mean of 10:00–11:00: placed at 10:30.
    assert_eq!(h.start(), t("1988-06-21T10:30:00-05:00"));
    // The first record keeps its readings (no earlier stamp): 11:00's row as written.
    let r0 = &h.records()[0];
    let r = &h.records()[1]; // 12:00: 23.9 °C, 12.8 °C, 50 %, 996 mbar, 250°, 4.6 m/s
    assert_eq!(r.time, t("1988-06-21T11:30:00-05:00"));
    // Readings at 11:30: halfway between the 11:00 and 12:00 rows.
    assert!(close(
        r.air_temperature_k,
        0.5 * (r0.air_temperature_k + 297.05),
        1e-9
    ));
    assert!(close(
        r.pressure_pa,
        0.5 * (r0.pressure_pa + 99_600.0),
        1e-9
    ));
    assert_eq!(
        (
            r.global_horizontal_w_m2,
            r.direct_normal_w_m2,
            r.diffuse_horizontal_w_m2
        ),
        (842.0, 768.0, 157.0)
    );
    // 13:00 has DNI and DHI −9900 (missing): Erbs split of GHI 760 with the Sun at 12:30 LST,
    // the record's own (mid-interval) time.
    let r = &h.records()[2];
    assert_eq!(r.time, t("1988-06-21T12:30:00-05:00"));
    let p = sun::position_standard(&s, t("1988-06-21T12:30:00-05:00")).unwrap();
    let (dni, dhi) = physics::erbs_split(760.0, p.apparent_zenith_deg, p.distance_au);
    assert!(close(r.direct_normal_w_m2, dni, 1e-9) && close(r.diffuse_horizontal_w_m2, dhi, 1e-9));
    let kt = 760.0 / (1367.0 / p.distance_au.powi(2) * p.apparent_zenith_deg.to_radians().cos());
    assert!((0.6..0.75).contains(&kt), "k_t {kt}");
    assert!(close(dhi, 760.0 * physics::erbs_diffuse_fraction(kt), 1e-6));
    assert!(h.filled(2).contains(&"direct_normal_w_m2"));
    // Sky longwave filled by Clark & Allen with the mid-interval readings.
    let lw = physics::clark_allen_sky_longwave_w_m2(
        r.air_temperature_k,
        r.dew_point_k,
        r.opaque_sky_cover,
    );
    assert!(close(r.sky_longwave_w_m2, lw, 1e-9));
}

// ---------------------------------------------------------------- irsig CSV/JSON

fn sample_history() -> WeatherHistory {
    let rec = |time: &str, air: f64, dir: f64, dni: f64| WeatherRecord {
        time: t(time),
        air_temperature_k: air,
        dew_point_k: 283.15,
        relative_humidity: physics::relative_humidity_from_dew_point(air, 283.15),
        pressure_pa: 100_000.0,
        wind_speed_m_s: 2.0,
        wind_direction_deg: dir,
        direct_normal_w_m2: dni,
        diffuse_horizontal_w_m2: 100.0,
        global_horizontal_w_m2: 100.0 + 0.5 * dni,
        sky_longwave_w_m2: 330.0,
        total_sky_cover: 0.2,
        opaque_sky_cover: 0.1,
        precipitation_mm: 0.0,
        visibility_km: None,
    };
    WeatherHistory::new(
        vec![
            rec("2025-06-21T12:00:00-04:00", 293.15, 350.0, 800.0),
            rec("2025-06-21T13:00:00-04:00", 295.15, 10.0, 700.0),
            rec("2025-06-21T14:00:00-04:00", 296.15, 20.0, 600.0),
        ],
        Some(ROCHESTER),
    )
    .unwrap()
}

#[test]
fn interpolation_is_linear_and_bounded() {
    let h = sample_history();
    let r = h.at(t("2025-06-21T12:30:00-04:00")).unwrap();
    assert!(close(r.air_temperature_k, 294.15, 1e-9));
    assert!(close(r.direct_normal_w_m2, 750.0, 1e-9));
    // Wind direction along the short arc: 350° → 10° passes through 0°.
    assert!(close(r.wind_direction_deg, 0.0, 1e-9) || close(r.wind_direction_deg, 360.0, 1e-9));
    // Same instant in UTC gives the same answer; time keeps the history's offset.
    let ru = h.at(t("2025-06-21T16:30:00Z")).unwrap();
    assert_eq!(ru, r);
    assert_eq!(r.time.to_rfc3339(), "2025-06-21T12:30:00-04:00");
    // At a record: that record.
    assert_eq!(
        h.at(t("2025-06-21T13:00:00-04:00")).unwrap(),
        h.records()[1]
    );
    assert_eq!(h.at(h.end()).unwrap(), h.records()[2]);
    // Outside: an error naming the time and the span.
    let e = h
        .at(t("2025-06-21T14:00:01-04:00"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("2025-06-21T14:00:01-04:00") && e.contains("outside"),
        "{e}"
    );
    assert!(h.at(t("2025-06-21T11:59:59-04:00")).is_err());
}

#[test]
fn irsig_csv_round_trip_and_json() {
    let h = sample_history();
    let mut buf = Vec::new();
    weather::write_csv(&h, &["test"], &mut buf).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("w.csv");
    std::fs::write(&p, &buf).unwrap();
    let back = weather::load(&p).unwrap();
    assert_eq!(back.format(), Some(Format::IrsigCsv));
    assert_eq!(back.site(), Some(&ROCHESTER));
    for (a, b) in h.records().iter().zip(back.records()) {
        assert_eq!(a.time, b.time);
        assert!(close(a.air_temperature_k, b.air_temperature_k, 1e-3));
        assert!(close(a.relative_humidity, b.relative_humidity, 1e-4));
        assert!(close(a.direct_normal_w_m2, b.direct_normal_w_m2, 1e-2));
    }
    // JSON with the same records (serde of WeatherRecord) reads back identically.
    let json = serde_json::json!({"site": ROCHESTER, "records": h.records()});
    let pj = dir.path().join("w.json");
    std::fs::write(&pj, json.to_string()).unwrap();
    let hj = weather::load(&pj).unwrap();
    assert_eq!(hj.records(), h.records());
    // Unknown JSON field → error naming it.
    std::fs::write(
        &pj,
        r#"{"records": [{"time": "2025-06-21T12:00:00Z", "air_temp": 3}]}"#,
    )
    .unwrap();
    let e = weather::load(&pj).unwrap_err().to_string();
    assert!(e.contains("w.json") && e.contains("air_temp"), "{e}");
}

/// irsig CSV cells may be quoted (as spreadsheets write them); a bad
/// quoted cell still names its line and column.
#[test]
fn irsig_csv_quoted_cells() {
    let dir = tempfile::tempdir().unwrap();
    let plain = "time,air_temperature_k,relative_humidity,wind_speed_m_s,global_horizontal_w_m2,opaque_sky_cover\n\
                 2025-06-21T12:00:00-04:00,300,0.5,2,700,0.2\n\
                 2025-06-21T13:00:00-04:00,301,0.4,3,710,0.2\n";
    let quoted = "# site: latitude_deg=43.16 longitude_deg=-77.61 altitude_m=170\r\n\
                  \"time\", \"air_temperature_k\",relative_humidity,wind_speed_m_s,global_horizontal_w_m2,opaque_sky_cover\r\n\
                  \"2025-06-21T12:00:00-04:00\", \"300\" ,0.5,2,\"700\",0.2\r\n\
                  2025-06-21T13:00:00-04:00,\"301\",\"0.4\",\"3\",710,0.2\r\n";
    let opts = LoadOptions {
        site: Some(ROCHESTER),
        ..LoadOptions::default()
    };
    let a = weather::load_with(&write_tmp(&dir, "a.csv", plain), &opts).unwrap();
    let b = weather::load_with(&write_tmp(&dir, "b.csv", quoted), &opts).unwrap();
    assert_eq!(a.records(), b.records());
    let bad = quoted.replace("\"301\"", "\"301,5\"");
    let e = weather::load_with(&write_tmp(&dir, "c.csv", &bad), &opts)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("c.csv:line 4") && e.contains("air_temperature_k") && e.contains("301,5"),
        "{e}"
    );
}

#[test]
fn irsig_csv_optional_columns_are_filled() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_tmp(
        &dir,
        "min.csv",
        "# site: latitude_deg=43.16 longitude_deg=-77.61 altitude_m=170\n\
         time,air_temperature_k,relative_humidity,wind_speed_m_s,global_horizontal_w_m2,opaque_sky_cover\n\
         2025-06-21T12:00:00-04:00,293.15,0.5254132558,2,700,0.2\n\
         2025-06-21T12:15:00-04:00,293.65,,2,710,0.2\n",
    );
    let e = weather::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("min.csv:line 4") && e.contains("dew point"),
        "{e}"
    );
    std::fs::write(
        &p,
        "# site: latitude_deg=43.16 longitude_deg=-77.61 altitude_m=170\n\
         time,air_temperature_k,relative_humidity,wind_speed_m_s,global_horizontal_w_m2,opaque_sky_cover\n\
         2025-06-21T12:00:00-04:00,293.15,0.5254132558,2,700,0.2\n\
         2025-06-21T12:15:00-04:00,293.65,0.51,2,710,0.2\n",
    )
    .unwrap();
    let h = weather::load(&p).unwrap();
    let r = &h.records()[0];
    // Dew point by inverse Magnus: RH 0.525413 at 20 °C → 10 °C.
    assert!(close(r.dew_point_k, 283.15, 1e-6), "{}", r.dew_point_k);
    // Pressure: ICAO standard atmosphere at 170 m = 99 299 Pa.
    assert!(close(r.pressure_pa, 99_299.0, 2.0), "{}", r.pressure_pa);
    assert_eq!(r.wind_direction_deg, 180.0);
    assert_eq!(r.total_sky_cover, 0.2);
    // Erbs split closes on GHI.
    let p0 = sun::position_standard(&ROCHESTER, r.time).unwrap();
    let cz = p0.apparent_zenith_deg.to_radians().cos();
    assert!(close(
        r.diffuse_horizontal_w_m2 + r.direct_normal_w_m2 * cz,
        700.0,
        1e-6
    ));
    let f = h.filled(0);
    for name in [
        "dew_point_k",
        "pressure_pa",
        "wind_direction_deg",
        "direct_normal_w_m2",
        "sky_longwave_w_m2",
        "total_sky_cover",
    ] {
        assert!(f.contains(&name), "{name} not in {f:?}");
    }
}

#[test]
fn irsig_csv_bad_rows_name_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let head = format!("{}\n", weather::CSV_HEADER);
    let good =
        "2025-06-21T12:00:00-04:00,293.15,283.15,0.525,100000,2,180,700,100,600,330,0.1,0.1\n";
    let cases: [(&str, &str, &[&str]); 6] = [
        (
            "nan.csv",
            "2025-06-21T12:15:00-04:00,NaN,283.15,0.525,100000,2,180,700,100,600,330,0.1,0.1\n",
            &["nan.csv:line 3", "air_temperature_k"],
        ),
        (
            "rh.csv",
            "2025-06-21T12:15:00-04:00,293.15,283.15,1.5,100000,2,180,700,100,600,330,0.1,0.1\n",
            &["rh.csv:line 3", "relative_humidity", "1.5"],
        ),
        (
            "neg.csv",
            "2025-06-21T12:15:00-04:00,293.15,283.15,0.5,100000,2,180,-5,100,600,330,0.1,0.1\n",
            &[
                "neg.csv:line 3",
                "direct_normal_w_m2",
                "negative irradiance",
            ],
        ),
        (
            "cols.csv",
            "2025-06-21T12:15:00-04:00,293.15,283.15,0.5,100000,2,180,700\n",
            &[
                "cols.csv:line 3",
                "diffuse_horizontal_w_m2",
                "8 columns, expected 13",
            ],
        ),
        (
            "time.csv",
            "2025-06-21 12:15,293.15,283.15,0.5,100000,2,180,700,100,600,330,0.1,0.1\n",
            &["time.csv:line 3", "RFC 3339"],
        ),
        (
            "order.csv",
            "2025-06-21T11:15:00-04:00,293.15,283.15,0.5,100000,2,180,700,100,600,330,0.1,0.1\n",
            &["order.csv:line 3", "increasing"],
        ),
    ];
    for (name, row, needles) in cases {
        let p = write_tmp(&dir, name, &format!("{head}{good}{row}"));
        let e = weather::load(&p).unwrap_err().to_string();
        for n in needles {
            assert!(e.contains(n), "{name}: `{n}` not in `{e}`");
        }
    }
    let p = write_tmp(&dir, "hdr.csv", &format!("time,air_temp\n{good}"));
    let e = weather::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("hdr.csv:line 1") && e.contains("air_temp"),
        "{e}"
    );
}

// ---------------------------------------------------------------- town history

#[test]
fn town_weather_csv_is_reproduced_by_the_generator() {
    let path = util::repo_path("scenes/town/weather.csv");
    let committed = weather::load(&path).unwrap();
    let (generated, _) = weather::synth::town_history().unwrap();
    assert_eq!(committed.records().len(), generated.records().len());
    assert_eq!(committed.site(), Some(&weather::synth::TOWN_SITE));
    for (a, b) in committed.records().iter().zip(generated.records()) {
        assert_eq!(a.time, b.time);
        let pairs = [
            (a.air_temperature_k, b.air_temperature_k),
            (a.dew_point_k, b.dew_point_k),
            (a.relative_humidity, b.relative_humidity),
            (a.pressure_pa, b.pressure_pa),
            (a.wind_speed_m_s, b.wind_speed_m_s),
            (a.wind_direction_deg, b.wind_direction_deg),
            (a.direct_normal_w_m2, b.direct_normal_w_m2),
            (a.diffuse_horizontal_w_m2, b.diffuse_horizontal_w_m2),
            (a.global_horizontal_w_m2, b.global_horizontal_w_m2),
            (a.sky_longwave_w_m2, b.sky_longwave_w_m2),
            (a.total_sky_cover, b.total_sky_cover),
            (a.opaque_sky_cover, b.opaque_sky_cover),
        ];
        for (x, y) in pairs {
            assert!(close(x, y, 0.051), "{}: {x} vs {y}", a.time);
        }
    }
}

#[test]
fn town_weather_covers_the_image_time_with_plausible_physics() {
    let h = weather::load(&util::repo_path("scenes/town/weather.csv")).unwrap();
    assert_eq!(h.step(), TimeDelta::minutes(15));
    assert!(h.is_uniform());
    assert!(h.start() <= t("2025-06-19T14:00:00-04:00"));
    assert!(h.end() >= t("2025-06-21T14:00:00-04:00"));
    assert!(h.end() - h.start() >= TimeDelta::hours(48));
    let noon = h.at(t("2025-06-21T13:15:00-04:00")).unwrap();
    // Closure GHI = DHI + DNI cos z with the SPA Sun.
    let p = sun::position_standard(&ROCHESTER, noon.time).unwrap();
    let cz = p.apparent_zenith_deg.to_radians().cos();
    assert!(close(
        noon.global_horizontal_w_m2,
        noon.diffuse_horizontal_w_m2 + noon.direct_normal_w_m2 * cz,
        0.2
    ));
    // A turbid summer clear sky near the solstice noon: DNI 750–950, GHI 800–1000 W/m².
    assert!(
        (750.0..950.0).contains(&noon.direct_normal_w_m2),
        "{noon:?}"
    );
    assert!(
        (800.0..1000.0).contains(&noon.global_horizontal_w_m2),
        "{noon:?}"
    );
    // Night is dark; sky longwave 300–420 W/m² throughout; daytime warmer than night.
    let night = h.at(t("2025-06-21T02:00:00-04:00")).unwrap();
    assert_eq!(night.global_horizontal_w_m2, 0.0);
    assert!(noon.air_temperature_k > night.air_temperature_k + 5.0);
    for r in h.records() {
        assert!((300.0..420.0).contains(&r.sky_longwave_w_m2), "{r:?}");
        assert!(r.dew_point_k < r.air_temperature_k);
    }
    // The first afternoon is cloudier than the clear third one at the same hour.
    let c = h.at(t("2025-06-19T14:30:00-04:00")).unwrap();
    let k = h.at(t("2025-06-21T14:30:00-04:00")).unwrap();
    assert!(c.opaque_sky_cover > 0.5 && k.opaque_sky_cover == 0.0);
    assert!(c.direct_normal_w_m2 < 0.5 * k.direct_normal_w_m2);
    assert!(c.sky_longwave_w_m2 > k.sky_longwave_w_m2 - 5.0);
}

// ---------------------------------------------------------------- CLI

#[test]
fn cli_weather_show_json_shape() {
    let out = std::process::Command::new(util::irsig_bin())
        .args(["weather", "show", "--json"])
        .arg(util::repo_path("tests/data/weather/rochester_sample.epw"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let recs = v["records"].as_array().unwrap();
    assert_eq!(recs.len(), 6);
    let keys: Vec<&str> = recs[3]
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    let mut expected = vec![
        "time",
        "air_temperature_k",
        "dew_point_k",
        "relative_humidity",
        "pressure_pa",
        "wind_speed_m_s",
        "direct_normal_w_m2",
        "diffuse_horizontal_w_m2",
        "global_horizontal_w_m2",
        "sky_longwave_w_m2",
        "opaque_sky_cover",
    ];
    let mut got = keys.clone();
    got.sort_unstable();
    expected.sort_unstable();
    assert_eq!(got, expected);
    // Hour-ending 08:00, placed at mid-interval (see epw_fixture_reads_…).
    assert_eq!(recs[3]["time"], "1990-06-21T07:30:00-05:00");
    assert!(close(
        recs[3]["sky_longwave_w_m2"].as_f64().unwrap(),
        physics::clark_allen_sky_longwave_w_m2(290.5, 285.15, 0.25),
        1e-3
    ));
    assert!(close(
        recs[3]["opaque_sky_cover"].as_f64().unwrap(),
        0.25,
        1e-12
    ));
}

#[test]
#[ignore = "needs ../shared/data"]
fn cli_weather_show_wth_needs_start() {
    let dir = util::shared_data("dirsig");
    let wth: &Path = &dir.join("saw.wth");
    let out = std::process::Command::new(util::irsig_bin())
        .args(["weather", "show"])
        .arg(wth)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("start"));
    let out = std::process::Command::new(util::irsig_bin())
        .args([
            "weather",
            "show",
            "--start",
            "2025-01-15T00:00:00-05:00",
            "--lat",
            "43.16",
            "--lon",
            "-77.61",
        ])
        .arg(wth)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("2025-01-15T12:00:00-05:00"));
    assert_eq!(text.lines().filter(|l| l.starts_with("2025-")).count(), 193);
}

#[test]
fn epw_year_override_and_mixed_years_hint() {
    let path = util::repo_path("tests/data/weather/rochester_sample.epw");
    let h = weather::load_with(&path, &LoadOptions::default().with_year(2025)).unwrap();
    assert_eq!(h.start(), t("2025-06-21T04:30:00-05:00"));
    // The history's own site gives the Sun: Rochester, 21 June 09:30 EST, Sun up in the south-east.
    let p = h.sun_position(h.end()).unwrap();
    assert!(p.is_up() && (90.0..180.0).contains(&p.azimuth_deg), "{p:?}");
    // A typical-year file whose years go backwards: the error names the line and suggests --year.
    let text = std::fs::read_to_string(&path).unwrap();
    let bad = text.replacen("1990,6,21,9,", "1987,6,21,9,", 1);
    let dir = tempfile::tempdir().unwrap();
    let p = write_tmp(&dir, "mixed.epw", &bad);
    let e = weather::load(&p).unwrap_err().to_string();
    assert!(e.contains("mixed.epw:line 13") && e.contains("year"), "{e}");
    assert!(weather::load_with(&p, &LoadOptions::default().with_year(1990)).is_ok());
}

/// A real NSRDB TMY3 file (Greensboro NC, 723170TYA.CSV as shipped in pvlib-python's data;
/// public-domain NREL data): header and the 24 rows of 21 June.
#[test]
fn tmy3_real_file_reads_and_closes_irradiance() {
    let path = util::repo_path("tests/data/weather/723170TYA_jun21.csv");
    let h = weather::load(&path).unwrap();
    let s = *h.site().unwrap();
    assert_eq!(
        (s.latitude_deg, s.longitude_deg, s.altitude_m),
        (36.1, -79.95, 273.0)
    );
    assert_eq!(h.records().len(), 24);
    // Hour-ending rows placed at mid-interval.
    assert_eq!(h.start(), t("1989-06-21T00:30:00-05:00"));
    assert_eq!(h.end(), t("1989-06-21T23:30:00-05:00"));
    // `06/21/1989,12:00,…,702,…,395,…,324,…,6,A,7,6,A,7,25.0,A,7,21.1,A,7,79,A,7,990,A,7,260,A,7,2.6,…`
    // `06/21/1989,11:00,…,7,A,7,7,A,7,24.4,A,7,21.1,A,7,82,A,7,990,A,7,230,A,7,4.1,…`
    // The 12:00 row is placed at 11:30 with readings halfway from the 11:00 row's.
    let r = &h.records()[11];
    assert_eq!(r.time, t("1989-06-21T11:30:00-05:00"));
    assert!(close(r.air_temperature_k, 297.85, 1e-9) && close(r.dew_point_k, 294.25, 1e-9));
    assert!(close(r.relative_humidity, 0.805, 1e-12) && close(r.pressure_pa, 99_000.0, 1e-9));
    assert!(close(r.wind_direction_deg, 245.0, 1e-9) && close(r.wind_speed_m_s, 3.35, 1e-12));
    assert_eq!(
        (
            r.global_horizontal_w_m2,
            r.direct_normal_w_m2,
            r.diffuse_horizontal_w_m2
        ),
        (702.0, 395.0, 324.0)
    );
    assert!(close(r.opaque_sky_cover, 0.65, 1e-12));
    let lw = physics::clark_allen_sky_longwave_w_m2(297.85, 294.25, 0.65);
    assert!(close(r.sky_longwave_w_m2, lw, 1e-9));
    assert_eq!(h.filled(11), &["sky_longwave_w_m2"]);
    // Hour-ending means: the measured components close on GHI with the Sun at mid-hour,
    // the record's placed time (GHI = DHI + DNI cos z), far better than with the Sun at
    // the stamped hour end.
    let (mut err_mid, mut err_end) = (0.0, 0.0);
    for r in h
        .records()
        .iter()
        .filter(|r| r.global_horizontal_w_m2 > 200.0)
    {
        let closure = |tt| {
            let p = h.sun_position(tt).unwrap();
            (r.diffuse_horizontal_w_m2
                + r.direct_normal_w_m2 * p.apparent_zenith_deg.to_radians().cos()
                - r.global_horizontal_w_m2)
                .abs()
        };
        err_mid += closure(r.time);
        err_end += closure(r.time + TimeDelta::minutes(30));
    }
    eprintln!(
        "TMY3 closure |DHI + DNI cos z − GHI| summed: mid-hour {err_mid:.0}, hour end {err_end:.0} W/m²"
    );
    assert!(err_mid < 0.1 * err_end, "{err_mid} {err_end}");
}

// ---------------------------------------------------------------- typical years (issue 20)

/// EPW text: the Rochester fixture's header, then hourly rows (hour-ending 1..24) for
/// each `(year, month, day)`, air temperature = day of month °C so rows can be told apart.
fn epw_days(days: &[(i32, u32, u32)]) -> String {
    let fixture =
        std::fs::read_to_string(util::repo_path("tests/data/weather/rochester_sample.epw"))
            .unwrap();
    let mut out: String = fixture.lines().take(8).map(|l| format!("{l}\n")).collect();
    for &(y, m, d) in days {
        for h in 1..=24 {
            out.push_str(&format!(
                "{y},{m},{d},{h},60,?9?9?9?9E0?9?9?9?9?9?9?9?9?9?9?9?9?9?9?9*9*9?9?9?9,{d}.0,-5.0,50,99800,0,1321,300,0,0,0,0,0,0,0,200,1.5,2,1,16.1,77777,9,999999999,25,0.1,0,88,0.0,0.0,0.0\n"
            ));
        }
    }
    out
}

/// A typical-year EPW (February from 2003, March from 1999: months from different years)
/// reads without a year when the image time's year is given, and 29 February follows that
/// year: repeated from 28 February in 2024, absent in 2025.
#[test]
fn typical_year_epw_takes_the_image_year_and_handles_29_february() {
    let dir = tempfile::tempdir().unwrap();
    let text = epw_days(&[(2003, 2, 27), (2003, 2, 28), (1999, 3, 1), (1999, 3, 2)]);
    let p = write_tmp(&dir, "tmy.epw", &text);
    // Without a year: an error naming the line where the year jumps, saying what to give.
    let e = weather::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("tmy.epw:line 57") && e.contains("typical-year") && e.contains("2003"),
        "{e}"
    );
    // 2025, a common year: 96 rows, 28 Feb 24:00 then 1 Mar 01:00 (placed at mid-hour).
    let h = weather::load_with(&p, &LoadOptions::default().with_typical_year(2025)).unwrap();
    assert_eq!(h.records().len(), 96);
    assert_eq!(h.start(), t("2025-02-27T00:30:00-05:00"));
    assert_eq!(h.end(), t("2025-03-02T23:30:00-05:00"));
    let r = h.at(t("2025-03-01T12:30:00-05:00")).unwrap();
    assert!(close(r.air_temperature_k, 274.15, 1e-9), "{r:?}");
    // 2024, a leap year: 28 February's 24 rows repeated as 29 February.
    let h = weather::load_with(&p, &LoadOptions::default().with_typical_year(2024)).unwrap();
    assert_eq!(h.records().len(), 120);
    let r = h.at(t("2024-02-29T12:30:00-05:00")).unwrap();
    assert!(close(r.air_temperature_k, 301.15, 1e-9), "{r:?}");
    assert_eq!(h.end(), t("2024-03-02T23:30:00-05:00"));
    // An explicit year wins over the image year.
    let h = weather::load_with(
        &p,
        &LoadOptions::default()
            .with_typical_year(2024)
            .with_year(2021),
    )
    .unwrap();
    assert_eq!(h.start(), t("2021-02-27T00:30:00-05:00"));
    // A file whose February comes from a leap year (2004) has 29 February rows: kept in a
    // leap year, dropped in a common one.
    let text = epw_days(&[(2004, 2, 28), (2004, 2, 29), (1999, 3, 1)]);
    let p = write_tmp(&dir, "leap.epw", &text);
    let h = weather::load_with(&p, &LoadOptions::default().with_typical_year(2025)).unwrap();
    assert_eq!(h.records().len(), 48);
    let h = weather::load_with(&p, &LoadOptions::default().with_typical_year(2028)).unwrap();
    assert_eq!(h.records().len(), 72);
    // A file in time order keeps its own years (the image year applies to typical years only).
    let text = epw_days(&[(2019, 12, 31), (2020, 1, 1)]);
    let p = write_tmp(&dir, "actual.epw", &text);
    let h = weather::load_with(&p, &LoadOptions::default().with_typical_year(2025)).unwrap();
    assert_eq!(h.start(), t("2019-12-31T00:30:00-05:00"));
}

/// TMY3 rows from different years, as NSRDB ships them, read as one year.
#[test]
fn typical_year_tmy3_takes_the_image_year() {
    let text =
        std::fs::read_to_string(util::repo_path("tests/data/weather/723170TYA_jun21.csv")).unwrap();
    // 30 June from 1989 and 1 July from 1977, as NSRDB picks months.
    let mut lines = text.lines();
    let head: Vec<&str> = lines.by_ref().take(2).collect();
    let rows: Vec<&str> = lines.collect();
    let mut mixed = head.join("\n") + "\n";
    for r in &rows {
        mixed += &(r.replace("06/21/1989", "06/30/1989") + "\n");
    }
    for r in &rows {
        mixed += &(r.replace("06/21/1989", "07/01/1977") + "\n");
    }
    let dir = tempfile::tempdir().unwrap();
    let p = write_tmp(&dir, "tmy3.csv", &mixed);
    assert!(
        weather::load(&p)
            .unwrap_err()
            .to_string()
            .contains("typical-year")
    );
    let h = weather::load_with(&p, &LoadOptions::default().with_typical_year(2025)).unwrap();
    assert_eq!(h.start(), t("2025-06-30T00:30:00-05:00"));
    assert_eq!(h.end(), t("2025-07-01T23:30:00-05:00"));
    assert_eq!(h.records().len(), 48);
}

/// Latin-1 bytes (Windows-1252 `é`, 0xE9) in EPW header lines are read as Latin-1; in a
/// data row they are an error naming the line and column.
#[test]
fn epw_latin1_header_bytes_are_accepted() {
    let text = std::fs::read_to_string(util::repo_path("tests/data/weather/rochester_sample.epw"))
        .unwrap();
    let mut bytes = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let mut l = line.as_bytes().to_vec();
        if i == 0 {
            l = line
                .replacen("Rochester", "Rochester Montr\u{1}al", 1)
                .into_bytes();
        } else if i == 5 {
            l = line.replacen("irsig", "irsig caf\u{1}", 1).into_bytes();
        }
        for b in &mut l {
            if *b == 1 {
                *b = 0xE9;
            }
        }
        bytes.extend(l);
        bytes.push(b'\n');
    }
    assert!(std::str::from_utf8(&bytes).is_err());
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("latin1.epw");
    std::fs::write(&p, &bytes).unwrap();
    let h = weather::load(&p).unwrap();
    assert_eq!(
        h.records(),
        weather::load(&util::repo_path("tests/data/weather/rochester_sample.epw"))
            .unwrap()
            .records()
    );
    // In a data row: an error naming line and column.
    let mut bad = bytes.clone();
    let row = bad
        .split(|&b| b == b'\n')
        .take(9)
        .map(|l| l.len() + 1)
        .sum::<usize>();
    bad[row + 2] = 0xE9;
    std::fs::write(&p, &bad).unwrap();
    let e = weather::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("latin1.epw:line 10") && e.contains("0xE9"),
        "{e}"
    );
}

// ---------------------------------------------------------------- timing (issue 16 item 3)

/// irsig CSV/JSON declare their timing per file: instant by default; `interval-mean N min`
/// places every record N/2 minutes before its stamp (all fields are means).
#[test]
fn irsig_timing_setting_places_interval_means_mid_interval() {
    let h = sample_history();
    let mut buf = Vec::new();
    weather::write_csv(&h, &["timing: interval-mean 60 min"], &mut buf).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let p = write_tmp(&dir, "mean.csv", std::str::from_utf8(&buf).unwrap());
    let back = weather::load(&p).unwrap();
    assert_eq!(back.timing(), Timing::MeanEnding { interval_s: 3600 });
    for (a, b) in h.records().iter().zip(back.records()) {
        assert_eq!(b.time, a.time - TimeDelta::minutes(30));
        assert!(close(a.air_temperature_k, b.air_temperature_k, 1e-3));
        assert!(close(a.direct_normal_w_m2, b.direct_normal_w_m2, 1e-2));
    }
    // Default: instant.
    let mut buf = Vec::new();
    weather::write_csv(&h, &[], &mut buf).unwrap();
    let p = write_tmp(&dir, "inst.csv", std::str::from_utf8(&buf).unwrap());
    let back = weather::load(&p).unwrap();
    assert_eq!(back.timing(), Timing::Instant);
    assert_eq!(back.start(), h.start());
    // JSON: the same setting as a key.
    let json = r#"{"site": null, "timing": "interval-mean 15 min", "records": [
        {"time": "2025-06-21T12:00:00-04:00", "air_temperature_k": 300, "dew_point_k": 290,
         "wind_speed_m_s": 2, "direct_normal_w_m2": 0, "diffuse_horizontal_w_m2": 0,
         "global_horizontal_w_m2": 0},
        {"time": "2025-06-21T12:15:00-04:00", "air_temperature_k": 301, "dew_point_k": 290,
         "wind_speed_m_s": 2, "direct_normal_w_m2": 0, "diffuse_horizontal_w_m2": 0,
         "global_horizontal_w_m2": 0}]}"#;
    let p = write_tmp(&dir, "w.json", json);
    let back = weather::load(&p).unwrap();
    assert_eq!(back.start(), t("2025-06-21T11:52:30-04:00"));
    // A bad setting names the file, line and field.
    let p = write_tmp(
        &dir,
        "bad.csv",
        "# timing: hourly\ntime,air_temperature_k\n",
    );
    let e = weather::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("bad.csv:line 1") && e.contains("timing") && e.contains("interval-mean"),
        "{e}"
    );
}

/// Rain: EPW field 34 (liquid precipitation depth, mm) is read into
/// `precipitation_mm` (999 = missing = none), and the irsig CSV carries an
/// optional `precipitation_mm` column that `write_csv` writes only when a
/// history has rain, reading back to the same values.
#[test]
fn precipitation_from_epw_and_through_irsig_csv() {
    let text = std::fs::read_to_string(util::repo_path("tests/data/weather/rochester_sample.epw"))
        .unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    // Row at line 11: 2.5 mm of rain in its hour (field 34 of 35).
    let mut f: Vec<String> = lines[10].split(',').map(str::to_string).collect();
    f[33] = "2.5".into();
    lines[10] = f.join(",");
    let dir = tempfile::tempdir().unwrap();
    let p = write_tmp(&dir, "rain.epw", &lines.join("\n"));
    let h = weather::load(&p).unwrap();
    let rain: Vec<f64> = h.records().iter().map(|r| r.precipitation_mm).collect();
    assert_eq!(rain.iter().filter(|&&v| v > 0.0).count(), 1, "{rain:?}");
    assert_eq!(rain.iter().sum::<f64>(), 2.5);
    // Through irsig CSV and back.
    let mut w = Vec::new();
    weather::write_csv(&h, &[], &mut w).unwrap();
    let csv = String::from_utf8(w).unwrap();
    assert!(csv.contains(",precipitation_mm"), "{csv}");
    let back = weather::load(&write_tmp(&dir, "rain.csv", &csv)).unwrap();
    let again: Vec<f64> = back.records().iter().map(|r| r.precipitation_mm).collect();
    assert_eq!(again, rain);
    // A dry history writes the plain header.
    let dry = weather::load(&util::repo_path("tests/data/weather/rochester_sample.epw")).unwrap();
    let mut w = Vec::new();
    weather::write_csv(&dry, &[], &mut w).unwrap();
    assert!(!String::from_utf8(w).unwrap().contains("precipitation"));
}

/// Rain from TMY3: `Lprecip depth (mm)` over `Lprecip quantity (hr)` hours ending at the
/// row. The real Greensboro day has hourly readings (quantity 1): each record carries its
/// row's depth. A depth over 3 h after two rows without readings is shared by the three.
#[test]
fn precipitation_from_tmy3_rows_and_accumulation_periods() {
    let path = util::repo_path("tests/data/weather/723170TYA_jun21.csv");
    let h = weather::load(&path).unwrap();
    let rain: Vec<f64> = h.records().iter().map(|r| r.precipitation_mm).collect();
    // The file's column (hours 01:00..24:00).
    let col = [
        76.0, 122.0, 5.0, 0.0, 0.0, 0.0, 0.0, 25.0, 0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 8.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 0.0, 0.0, 10.0, 15.0,
    ];
    assert_eq!(rain, col);
    // 01:00 and 02:00 missing (−9900), 03:00: 9 mm over 3 h.
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let names: Vec<&str> = lines[1].split(',').collect();
    let depth = names
        .iter()
        .position(|n| *n == "Lprecip depth (mm)")
        .unwrap();
    let hours = names
        .iter()
        .position(|n| *n == "Lprecip quantity (hr)")
        .unwrap();
    let edit = |line: &str, d: &str, q: &str| {
        let mut f: Vec<String> = line.split(',').map(str::to_string).collect();
        f[depth] = d.into();
        f[hours] = q.into();
        f.join(",")
    };
    lines[2] = edit(&lines[2], "-9900", "-9900");
    lines[3] = edit(&lines[3], "-9900", "-9900");
    lines[4] = edit(&lines[4], "9", "3");
    let dir = tempfile::tempdir().unwrap();
    let h = weather::load(&write_tmp(&dir, "acc.csv", &lines.join("\n"))).unwrap();
    let rain: Vec<f64> = h.records().iter().map(|r| r.precipitation_mm).collect();
    assert_eq!(&rain[..4], &[3.0, 3.0, 3.0, 0.0], "{rain:?}");
    // A negative depth is an error naming the line and the column.
    lines[6] = edit(&lines[6], "-2", "1");
    let e = weather::load(&write_tmp(&dir, "neg.csv", &lines.join("\n")))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("neg.csv:line 7") && e.contains("Lprecip depth (mm)"),
        "{e}"
    );
}

// ---------------------------------------------------------------- visibility (issue 17)

/// EPW text of one day, 1990-06-21, under the Rochester fixture's header: hour-ending
/// rows 1..24, the visibility of hour `h` being `vis[h - 1]` km in field 25 (9999 is
/// EPW's "missing").
pub(crate) fn epw_visibility_day(vis: &[f64; 24]) -> String {
    let fixture =
        std::fs::read_to_string(util::repo_path("tests/data/weather/rochester_sample.epw"))
            .unwrap();
    let mut out: String = fixture.lines().take(8).map(|l| format!("{l}\n")).collect();
    for (h, v) in (1..=24).zip(vis) {
        out.push_str(&format!(
            "1990,6,21,{h},60,?9?9?9?9E0?9?9?9?9?9?9?9?9?9?9?9?9?9?9?9*9*9?9?9?9,20.0,10.0,53,99800,0,1321,330,0,0,0,0,0,0,0,200,1.5,2,1,{v},77777,9,999999999,25,0.1,0,88,0.0,0.0,0.0\n"
        ));
    }
    out
}

/// EPW field 25 is the visibility in km, 9999 missing. EPW stamps readings at the hour's
/// end and irsig places the record at mid-hour: the visibility there is the two
/// readings' mean in extinction (1/V, as LOWTRAN interpolates), and a missing reading
/// leaves the nearer one's (missing at mid-hour after a missing stamp). TMY3's `Hvis (m)`
/// reads in km: the Rochester fixtures agree (16 100 m = 16.1 km).
#[test]
fn epw_visibility_is_field_25_and_9999_is_missing() {
    let dir = tempfile::tempdir().unwrap();
    let mut vis = [16.1; 24];
    vis[11] = 4.0; // hour-ending 12:00
    vis[12] = 9999.0; // 13:00
    vis[13] = 9999.0; // 14:00
    let p = write_tmp(&dir, "vis.epw", &epw_visibility_day(&vis));
    let h = weather::load(&p).unwrap();
    let at = |s: &str| h.at(t(s)).unwrap().visibility_km;
    // Far from the change: the readings' own value.
    assert!(close(at("1990-06-21T05:00:00-05:00").unwrap(), 16.1, 1e-12));
    // The record of hour-ending 12:00, at 11:30: mean extinction of 16.1 and 4 km.
    let mean = 1.0 / (0.5 / 16.1 + 0.5 / 4.0);
    assert!(close(at("1990-06-21T11:30:00-05:00").unwrap(), mean, 1e-12));
    assert!(mean < 0.5 * (16.1 + 4.0));
    // 12:30 (readings 4 km and missing) and 13:30 (both missing): no visibility.
    assert_eq!(at("1990-06-21T12:30:00-05:00"), None);
    assert_eq!(at("1990-06-21T13:30:00-05:00"), None);
    // Between 11:30 and 12:30: the nearer record's.
    assert!(close(at("1990-06-21T11:45:00-05:00").unwrap(), mean, 1e-12));
    assert_eq!(at("1990-06-21T12:15:00-05:00"), None);
    // After the gap, the reading again.
    assert!(close(at("1990-06-21T15:30:00-05:00").unwrap(), 16.1, 1e-12));

    let epw = weather::load(&util::repo_path("tests/data/weather/rochester_sample.epw")).unwrap();
    let tmy3 = weather::load(&util::repo_path(
        "tests/data/weather/rochester_sample_tmy3.csv",
    ))
    .unwrap();
    for r in epw.records().iter().chain(tmy3.records()) {
        assert!(close(r.visibility_km.unwrap(), 16.1, 1e-9), "{r:?}");
    }
}

/// irsig CSV takes an optional `visibility_km` column (empty cells missing) that
/// `write_csv` writes only where some record has a visibility, and reads back; a
/// negative visibility is an error naming the line and the column. The bundled town's
/// weather has none.
#[test]
fn irsig_csv_visibility_column_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let mut vis = [9999.0; 24];
    vis[..12].copy_from_slice(&[7.5; 12]);
    let p = write_tmp(&dir, "vis.epw", &epw_visibility_day(&vis));
    let h = weather::load(&p).unwrap();
    let mut out = Vec::new();
    weather::write_csv(&h, &[], &mut out).unwrap();
    let csv = String::from_utf8(out).unwrap();
    assert!(csv.lines().any(|l| l.ends_with(",visibility_km")), "{csv}");
    let q = write_tmp(&dir, "vis.csv", &csv);
    let back = weather::load(&q).unwrap();
    let a: Vec<Option<f64>> = h.records().iter().map(|r| r.visibility_km).collect();
    let b: Vec<Option<f64>> = back.records().iter().map(|r| r.visibility_km).collect();
    assert_eq!(a.iter().filter(|v| v.is_some()).count(), 12, "{a:?}");
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.is_some(), y.is_some(), "{a:?} {b:?}");
        if let (Some(x), Some(y)) = (x, y) {
            assert!(close(*x, *y, 1e-3), "{x} {y}");
        }
    }

    let bad = "time,air_temperature_k,dew_point_k,wind_speed_m_s,direct_normal_w_m2,\
               diffuse_horizontal_w_m2,global_horizontal_w_m2,visibility_km\n\
               2025-06-21T12:00:00-04:00,295,285,2,0,0,0,10\n\
               2025-06-21T13:00:00-04:00,295,285,2,0,0,0,-3\n";
    let e = weather::load(&write_tmp(&dir, "bad.csv", bad))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("bad.csv") && e.contains("line 3") && e.contains("visibility_km"),
        "{e}"
    );

    let town = weather::load(&util::repo_path("scenes/town/weather.csv")).unwrap();
    assert!(town.records().iter().all(|r| r.visibility_km.is_none()));
    let mut out = Vec::new();
    weather::write_csv(&town, &[], &mut out).unwrap();
    assert!(!String::from_utf8(out).unwrap().contains("visibility_km"));
}
