//! Tests: reliability. Output file permissions, Embree errors surfacing as
//! `Error::Embree`, and property tests that the thermal solver and the
//! radiometry give finite values for any valid input.

use chrono::{DateTime, FixedOffset, TimeDelta};
use proptest::prelude::*;

use irsig::material::Material;
use irsig::output::write_atomic;
use irsig::radiometry::band::Band;
use irsig::radiometry::equation::{SurfaceInputs, at_sensor, leaving_radiance};
use irsig::thermal::{self, FacetInputs, Forcing, SlabProperties, SolveOptions, Spinup};
use irsig::weather::WeatherRecord;
use irsig::weather::physics::relative_humidity_from_dew_point;

/// Issue 8: `write_atomic` gives its file the permissions `File::create`
/// would (0666 minus the umask), not tempfile's private 0600.
#[cfg(unix)]
#[test]
fn r8_atomic_write_has_normal_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let d = tempfile::tempdir().unwrap();
    // The reference: a file created the ordinary way under this umask.
    let plain = d.path().join("plain");
    std::fs::File::create(&plain).unwrap();
    let want = std::fs::metadata(&plain).unwrap().permissions().mode() & 0o777;
    let p = d.path().join("out.bin");
    write_atomic(&p, |w| {
        w.write_all(b"data")
            .map_err(|e| irsig::Error::io("out.bin", e))
    })
    .unwrap();
    let got = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
    assert_eq!(got, want, "mode {got:o}, expected {want:o}");
    // Group/other can read whenever the umask lets them (the usual 022).
    assert_ne!(got, 0o600, "still tempfile's private mode");
}

/// Issue 8: an error Embree reports through its device error callback comes
/// back as `Error::Embree` with the library's message (here: two geometries
/// attached under the same id, which Embree refuses).
#[test]
fn r8_embree_device_error_becomes_error_embree() {
    use irsig::trace::embree::{Device, Geometry, Scene, VertexBuffer};
    let device = Device::new().unwrap();
    let vb = VertexBuffer::new([glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y].into_iter());
    let g1 = Geometry::triangles(&device, &vb, &[[0, 1, 2]]).unwrap();
    let g2 = Geometry::triangles(&device, &vb, &[[0, 2, 1]]).unwrap();
    let mut scene = Scene::new(&device).unwrap();
    scene.attach(&g1, 7).unwrap();
    let err = scene.attach(&g2, 7).unwrap_err();
    match &err {
        irsig::Error::Embree(m) => assert!(!m.is_empty(), "empty Embree message"),
        other => panic!("expected Error::Embree, got {other:?}"),
    }
    assert!(err.to_string().starts_with("Embree: "), "{err}");
    // The device is usable afterwards: the error was taken, not sticky.
    device.check().unwrap();
    scene.commit().unwrap();
}

/// Indices beyond the vertex buffer are refused before Embree sees them.
#[test]
fn r8_embree_bad_indices_are_an_error_not_a_crash() {
    use irsig::trace::embree::{Device, Geometry, VertexBuffer};
    let device = Device::new().unwrap();
    let vb = VertexBuffer::new([glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y].into_iter());
    let err = Geometry::triangles(&device, &vb, &[[0, 1, 3]])
        .err()
        .expect("out-of-range index accepted");
    let msg = err.to_string();
    assert!(
        msg.contains("out of range") && msg.contains("3 vertices"),
        "{msg}"
    );
}

fn t0() -> DateTime<FixedOffset> {
    DateTime::parse_from_rfc3339("2025-06-21T00:00:00-04:00").unwrap()
}

/// A valid material from ranges wide enough to cover real ones (foams to
/// metals, foil to thick slabs).
fn material() -> impl Strategy<Value = Material> {
    (
        (
            100.0..3000.0f64,
            0.02..400.0f64,
            10.0..9000.0f64,
            0.001..1.0f64,
        ),
        (0.0..=1.0f64, 0.0..=1.0f64, -1.0..=1.0f64, 0.0..300.0f64),
        (0.0..=1.0f64, 0.0..=0.5f64),
    )
        .prop_map(|((c, k, rho, d), (a, e, exposed, p), (s, t))| Material {
            id: 1,
            name: "random".into(),
            specific_heat_j_kg_k: c,
            conductivity_w_m_k: k,
            density_kg_m3: rho,
            thickness_m: d,
            solar_absorptivity: a,
            thermal_emissivity: e,
            exposed_area: exposed,
            self_power_w_m2: p,
            specular_fraction: s,
            transmissivity: t,
            emissivity_curve: None,
            double_sided: false,
        })
}

/// Hourly weather rows with physically valid values.
fn weather(hours: usize) -> impl Strategy<Value = Vec<WeatherRecord>> {
    proptest::collection::vec(
        (
            (
                230.0..325.0f64,
                0.0..30.0f64,
                50_000.0..106_000.0f64,
                0.0..25.0f64,
            ),
            (0.0..1000.0f64, 0.0..400.0f64, 150.0..480.0f64, 0.0..=1.0f64),
        ),
        hours,
    )
    .prop_map(|rows| {
        rows.into_iter()
            .enumerate()
            .map(|(i, ((air, dep, p, wind), (dni, dhi, lw, cover)))| {
                let dew = air - dep;
                WeatherRecord {
                    time: t0() + TimeDelta::hours(i as i64),
                    air_temperature_k: air,
                    dew_point_k: dew,
                    relative_humidity: relative_humidity_from_dew_point(air, dew),
                    pressure_pa: p,
                    wind_speed_m_s: wind,
                    wind_direction_deg: 180.0,
                    direct_normal_w_m2: dni,
                    diffuse_horizontal_w_m2: dhi,
                    global_horizontal_w_m2: dhi + 0.5 * dni,
                    sky_longwave_w_m2: lw,
                    total_sky_cover: cover,
                    opaque_sky_cover: cover,
                }
            })
            .collect()
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, failure_persistence: None, ..ProptestConfig::default() })]

    /// Issue 8: the thermal solver returns finite temperatures and fluxes for
    /// any valid material, weather and facet inputs.
    #[test]
    fn r8_thermal_solver_output_is_finite(
        m in material(),
        records in weather(13),
        lit in proptest::collection::vec((any::<bool>(), 0.0..=1.0f32), 13),
        shape_factor in 0.0..=1.0f64,
    ) {
        let props = SlabProperties::from_material(&m).unwrap();
        let forcing = Forcing::from_records(&records).unwrap();
        let sun: Vec<f32> = lit.iter().map(|&(l, _)| if l { 1.0 } else { 0.0 }).collect();
        let cos: Vec<f32> = lit.iter().map(|&(_, c)| c).collect();
        let inputs = FacetInputs::new(&sun, &cos, shape_factor);
        let opts = SolveOptions { spinup: Spinup::none(), ..SolveOptions::fast() };
        let sol = thermal::solve(&props, &forcing, &inputs, &opts).unwrap();
        prop_assert_eq!(sol.surface_temperature_k.len(), records.len());
        for (i, &t) in sol.surface_temperature_k.iter().enumerate() {
            // Finite, and physically plausible: a slab in weather of
            // 200–330 K air cannot leave a few hundred kelvin of it.
            prop_assert!(t.is_finite() && t > 100.0 && t < 700.0, "T_s[{}] = {}", i, t);
        }
        for &t in &sol.back_temperature_k {
            prop_assert!(t.is_finite());
        }
        for &q in &sol.net_front_flux_w_m2 {
            prop_assert!(q.is_finite());
        }
    }

    /// Issue 8: the leaving and at-sensor band radiance are finite and
    /// non-negative, and the brightness temperature inverts, for any valid
    /// surface, environment and path.
    #[test]
    fn r8_radiometry_output_is_finite(
        m in material(),
        temperature_k in 150.0..1500.0f64,
        shape_factor in 0.0..=1.0f64,
        cos_sun in -1.0..=1.0f64,
        env in (0.0..20.0f64, 0.0..20.0f64, 0.0..2000.0f64),
        path in (0.0..=1.0f64, 0.0..10.0f64),
        lo in 3.0..10.0f64,
        width in 0.2..6.0f64,
    ) {
        let band = Band::flat(lo, lo + width, 0.05).unwrap();
        let wl = band.wavelengths_um().to_vec();
        let n = wl.len();
        let emissivity: Vec<f64> = wl.iter().map(|&w| m.emissivity_at(w, 30.0)).collect();
        let sky = vec![env.0; n];
        let background = vec![env.1; n];
        let solar = vec![env.2; n];
        let inputs = SurfaceInputs {
            temperature_k,
            emissivity: &emissivity,
            specular_fraction: m.specular_fraction,
            transmissivity: m.transmissivity,
            shape_factor,
            sky_radiance: &sky,
            background_radiance: &background,
            solar_irradiance: Some(&solar),
            cos_sun,
            specular_radiance: None,
        };
        let mut out = vec![0.0; n];
        leaving_radiance(&inputs, &band, &mut out);
        for (i, &l) in out.iter().enumerate() {
            prop_assert!(l.is_finite() && l >= 0.0, "L({}) = {}", wl[i], l);
        }
        let tau = vec![path.0; n];
        let lu = vec![path.1; n];
        let l = at_sensor(&out, &tau, &lu, &band);
        prop_assert!(l.is_finite() && l >= 0.0, "at-sensor {}", l);
        // Blackbody round trip through the band's inverse.
        let lb = band.blackbody_radiance(temperature_k);
        prop_assert!(lb.is_finite() && lb > 0.0);
        let tb = band.brightness_temperature(lb).unwrap();
        prop_assert!((tb - temperature_k).abs() < 1e-6 * temperature_k, "{} vs {}", tb, temperature_k);
    }
}

/// Issue 8, found by `scripts/fuzz` (target `obj`): a relative texture or
/// normal index beyond those defined overflowed inside tobj
/// (`vt * 2`, a panic with overflow checks); now the pre-scan reports it
/// with its line.
#[test]
fn r8_obj_out_of_range_texture_and_normal_indices() {
    use irsig::scene::obj::load_obj_str;
    let head = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";
    let p = std::path::Path::new("t.obj");
    for (face, what, idx) in [
        ("f 1/1 2/-8 3/1\n", "texture", "-8"),
        ("f 1/2 2/1 3/1\n", "texture", "2"),
        ("f 1//1 2//-2 3//1\n", "normal", "-2"),
        ("f 1/1/1 2/1/9 3/1/1\n", "normal", "9"),
    ] {
        let e = load_obj_str(&format!("{head}{face}"), p)
            .err()
            .unwrap_or_else(|| panic!("{face} accepted"));
        let m = e.to_string();
        assert!(
            m.contains("t.obj:line 6") && m.contains(&format!("{what} index {idx}")),
            "{m}"
        );
    }
    // In range, all three forms load.
    let ok = format!("{head}f 1/1/1 2/1/1 3/-1/-1\nf 1//1 2//1 3//1\nf 1/1 2/1 3/1\n");
    let groups = load_obj_str(&ok, p).unwrap();
    assert_eq!(
        groups.iter().map(|g| g.mesh.indices.len()).sum::<usize>(),
        3
    );
    // `vt` with one number is refused (tobj needs u and v).
    let e = load_obj_str("v 0 0 0\nvt 0.5\n", p)
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 2") && e.contains("vt"), "{e}");
}
