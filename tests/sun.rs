//! Tests: sun (NREL SPA through `irsig::sun`).

use chrono::{DateTime, FixedOffset, TimeDelta, Utc};
use irsig::sun::{self, Site};

use crate::util;

fn t(s: &str) -> DateTime<FixedOffset> {
    DateTime::parse_from_rfc3339(s).unwrap()
}

/// Reda & Andreas (2004), NREL/TP-560-34302, Table A5.1 worked example:
/// 2003-10-17 12:30:30 UTC−7, ΔT 67 s, lat 39.742476, lon −105.1786, 1830.14 m,
/// 820 mbar, 11 °C.
fn spa_example() -> (Site, DateTime<FixedOffset>) {
    (
        Site::new(39.742476, -105.1786, 1830.14).unwrap(),
        t("2003-10-17T12:30:30-07:00"),
    )
}

#[test]
fn spa_worked_example_reda_andreas_2004() {
    let (site, time) = spa_example();
    let p = sun::position(&site, time, 67.0, 820.0, 11.0).unwrap();
    // Paper: topocentric zenith θ = 50.11162° (with refraction), azimuth Φ = 194.34024°.
    assert!((p.apparent_zenith_deg - 50.11162).abs() < 1e-5, "{p:?}");
    assert!((p.azimuth_deg - 194.34024).abs() < 1e-5, "{p:?}");
    // Paper: topocentric elevation without refraction e0 = 39.872046° → zenith 50.127954°.
    assert!((p.zenith_deg - (90.0 - 39.872046)).abs() < 1e-6, "{p:?}");
    // Paper: Earth radius vector R = 0.9965422974 AU.
    assert!((p.distance_au - 0.9965422974).abs() < 1e-10, "{p:?}");
    // Refraction lifts the Sun: Δe = 0.016332° in the paper.
    assert!(((p.zenith_deg - p.apparent_zenith_deg) - 0.016332).abs() < 1e-6);
}

#[test]
fn spa_worked_example_intermediate_values() {
    use solar_positioning::{SolarPositions, time::JulianDate};
    // 12:30:30 UTC−7 = 19:30:30 UTC.
    let jd = JulianDate::from_utc(2003, 10, 17, 19, 30, 30.0, 67.0).unwrap();
    // Table A5.1: JD = 2452930.312847, JDE from ΔT = 67 s.
    assert!((jd.julian_date() - 2_452_930.312_847).abs() < 1e-6);
    assert!((jd.julian_ephemeris_day() - (2_452_930.312_847 + 67.0 / 86_400.0)).abs() < 1e-6);
    let prepared = SolarPositions::new().for_time_from_julian(jd).unwrap();
    // α = 202.22741°, δ = −9.31434°, R = 0.9965422974 AU.
    assert!((prepared.right_ascension() - 202.22741).abs() < 1e-5);
    assert!((prepared.declination() - (-9.31434)).abs() < 1e-5);
    assert!((prepared.earth_radius_vector().unwrap() - 0.996_542_297_4).abs() < 1e-10);
}

/// NREL spa.c reference positions (1910, 2010, 2110, 2210; 512 rows over the globe):
/// irsig's positions must be within the 0.001° target (SPA claims 0.0003°).
#[test]
fn spa_matches_nrel_spa_c_reference_table() {
    let text =
        std::fs::read_to_string(util::repo_path("tests/data/sun/spa_reference.csv")).unwrap();
    let (mut n, mut max_az, mut max_zen) = (0, 0.0f64, 0.0f64);
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
    {
        let f: Vec<&str> = line.split(',').collect();
        let time: DateTime<Utc> = f[0].parse().unwrap();
        let lat: f64 = f[1].parse().unwrap();
        let lon: f64 = f[2].parse().unwrap();
        let az: f64 = f[3].parse().unwrap();
        let zen: f64 = f[4].parse().unwrap();
        let site = Site::new(lat, lon, 0.0).unwrap();
        let p = sun::position(&site, time, 0.0, 1000.0, 10.0).unwrap();
        let daz = (p.azimuth_deg - az + 540.0).rem_euclid(360.0) - 180.0;
        max_az = max_az.max(daz.abs());
        max_zen = max_zen.max((p.apparent_zenith_deg - zen).abs());
        n += 1;
    }
    eprintln!("SPA vs spa.c: {n} rows, max |Δazimuth| {max_az:.2e}°, max |Δzenith| {max_zen:.2e}°");
    assert_eq!(n, 512);
    assert!(max_az < 1e-3 && max_zen < 1e-3, "{max_az} {max_zen}");
}

/// Physics cross-check: at the summer solstice the minimum geometric zenith at latitude
/// φ is φ − ε (ε ≈ 23.44°, the obliquity), reached at solar noon with the Sun due south.
/// Rochester (77.61° W, UTC−4): solar noon ≈ 13:12 EDT (10 min for longitude,
/// −1.7 min equation of time).
#[test]
fn solstice_noon_at_rochester() {
    let site = Site::new(43.16, -77.61, 170.0).unwrap();
    let start = t("2025-06-21T12:30:00-04:00");
    let (mut best_zen, mut best) = (f64::MAX, None);
    for k in 0..=90 {
        let time = start + TimeDelta::minutes(k);
        let p = sun::position(&site, time, 69.0, 1000.0, 20.0).unwrap();
        if p.zenith_deg < best_zen {
            best_zen = p.zenith_deg;
            best = Some((time, p));
        }
    }
    let (time, p) = best.unwrap();
    assert!((p.zenith_deg - (43.16 - 23.44)).abs() < 0.02, "{p:?}");
    assert!((p.azimuth_deg - 180.0).abs() < 0.5, "{p:?}");
    let noon = t("2025-06-21T13:12:00-04:00");
    assert!(
        (time - noon).num_minutes().abs() <= 2,
        "solar noon at {time}"
    );
}

#[test]
fn direction_enu_is_unit_and_matches_angles() {
    let site = Site::new(43.16, -77.61, 170.0).unwrap();
    // Morning: Sun in the east-north-east, above the horizon.
    let p = sun::position_standard(&site, t("2025-06-21T08:00:00-04:00")).unwrap();
    let d = p.direction_enu();
    assert!((d.length() - 1.0).abs() < 1e-12);
    assert!(d.x > 0.0 && d.z > 0.0, "{d:?}");
    assert!((d.z - p.apparent_zenith_deg.to_radians().cos()).abs() < 1e-12);
    assert!((d.x.atan2(d.y).to_degrees().rem_euclid(360.0) - p.azimuth_deg).abs() < 1e-9);
    // Night: below the horizon.
    let night = sun::position_standard(&site, t("2025-06-21T01:00:00-04:00")).unwrap();
    assert!(!night.is_up() && night.direction_enu().z < 0.0);
}

#[test]
fn invalid_inputs_are_named_errors() {
    let time = t("2025-06-21T14:00:00-04:00");
    let e = Site::new(95.0, 0.0, 0.0).unwrap_err().to_string();
    assert!(e.contains("latitude") && e.contains("95"), "{e}");
    let e = Site::new(10.0, 200.0, 0.0).unwrap_err().to_string();
    assert!(e.contains("longitude"), "{e}");
    let bad = Site {
        latitude_deg: f64::NAN,
        longitude_deg: 0.0,
        altitude_m: 0.0,
    };
    let e = sun::position(&bad, time, 69.0, 1000.0, 10.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("latitude"), "{e}");
    let site = Site::new(43.16, -77.61, 170.0).unwrap();
    let e = sun::position(&site, time, 69.0, 0.0, 10.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("pressure"), "{e}");
    let e = sun::position(&site, time, f64::INFINITY, 1000.0, 10.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("delta_t"), "{e}");
}

#[test]
fn cli_sun_json() {
    let out = std::process::Command::new(util::irsig_bin())
        .args([
            "sun",
            "--lat",
            "39.742476",
            "--lon",
            "-105.1786",
            "--alt",
            "1830.14",
            "--time",
            "2003-10-17T12:30:30-07:00",
            "--delta-t",
            "67",
            "--pressure",
            "820",
            "--temperature",
            "11",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!((v["apparent_zenith_deg"].as_f64().unwrap() - 50.11162).abs() < 1e-5);
    assert!((v["azimuth_deg"].as_f64().unwrap() - 194.34024).abs() < 1e-5);
    assert!((v["zenith_deg"].as_f64().unwrap() - 50.127954).abs() < 1e-5);
    assert!(v["distance_au"].as_f64().is_some());

    let out = std::process::Command::new(util::irsig_bin())
        .args([
            "sun",
            "--lat",
            "91",
            "--lon",
            "0",
            "--time",
            "2025-06-21T14:00:00Z",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("latitude"), "{err}");
}

/// Independent implementation: 400 random instants 1950–2050 (random sites, elevation,
/// pressure, temperature, ΔT) from pvlib-python's `spa.py` (NumPy SPA). The issue's
/// target is 0.001° for any date 1950–2050.
#[test]
fn spa_matches_pvlib_1950_2050() {
    let text =
        std::fs::read_to_string(util::repo_path("tests/data/sun/pvlib_spa_1950_2050.csv")).unwrap();
    let (mut n, mut max_z0, mut max_z, mut max_az, mut max_r) = (0, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
    {
        let f: Vec<&str> = line.split(',').collect();
        let time: DateTime<Utc> = f[0].parse().unwrap();
        let v: Vec<f64> = f[1..].iter().map(|s| s.parse().unwrap()).collect();
        let site = Site::new(v[0], v[1], v[2]).unwrap();
        let p = sun::position(&site, time, v[5], v[3], v[4]).unwrap();
        max_z0 = max_z0.max((p.zenith_deg - v[6]).abs());
        max_z = max_z.max((p.apparent_zenith_deg - v[7]).abs());
        let daz = (p.azimuth_deg - v[8] + 540.0).rem_euclid(360.0) - 180.0;
        max_az = max_az.max(daz.abs());
        max_r = max_r.max((p.distance_au - v[9]).abs());
        n += 1;
    }
    eprintln!(
        "SPA vs pvlib 1950-2050: {n} rows, max |Δzenith| {max_z0:.2e}°, |Δapparent| {max_z:.2e}°, |Δazimuth| {max_az:.2e}°, |ΔR| {max_r:.2e} AU"
    );
    assert_eq!(n, 400);
    assert!(
        max_z0 < 1e-3 && max_z < 1e-3 && max_az < 1e-3,
        "{max_z0} {max_z} {max_az}"
    );
    assert!(max_r < 1e-8, "{max_r}");
}
