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

use crate::util;

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
    let mut scene = Scene::new(&device, irsig::trace::Watertight::Yes).unwrap();
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
            specular_roughness: None,
            transmissivity: t,
            emissivity_curve: None,
            double_sided: false,
            surface_energy: None,
            convection: Default::default(),
            layers: Vec::new(),
            back: None,
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
                    precipitation_mm: 0.0,
                    visibility_km: None,
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
            blackbody: &band.grid().blackbody(band.planck(), temperature_k),
            emissivity: &emissivity,
            specular_fraction: m.specular_fraction,
            transmissivity: m.transmissivity,
            shape_factor,
            sky_radiance: &sky,
            background_radiance: &background,
            solar_irradiance: Some(&solar),
            cos_sun,
            specular_radiance: None,
            glint_sr: 0.0,
            transmitted_radiance: None,
        };
        let mut out = vec![0.0; n];
        leaving_radiance(&inputs, &mut out);
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

// ------------------------------------------------ whole chain, random scenes

/// The bundled material library's names (scenes/materials.json).
const MATERIAL_NAMES: [&str; 17] = [
    "asphalt",
    "concrete",
    "grass",
    "bare_soil",
    "asphalt_shingle_roof",
    "tar_gravel_roof",
    "brick",
    "wood_siding",
    "aluminium_siding",
    "glass",
    "painted_steel",
    "water",
    "deciduous_canopy",
    "coniferous_canopy",
    "sand",
    "tree_bark",
    "rubber_tire",
];

/// A random small scene: a ground plane, boxes and a sphere on it.
#[derive(Debug, Clone)]
struct RandomScene {
    /// Latitude, longitude (degrees), altitude (m).
    site: (f64, f64, f64),
    /// Day of 2025 (0-based), hour, minute of the image (local time).
    when: (i64, i64, i64),
    /// Ground plane: side (m), material.
    ground: (f64, usize),
    /// Boxes: size x, y, z (m), position x, y (fraction of the ground's
    /// half-size), rotation about z (degrees), material.
    boxes: Vec<([f64; 3], [f64; 2], f64, usize)>,
    /// A sphere: radius (m), height of its centre (m), material.
    sphere: Option<(f64, f64, usize)>,
    /// A glTF model (`util::gltf_doc` as GLB: cubes of painted steel and a
    /// glass panel): scale, position x, y (fraction of the ground's
    /// half-size), rotation about z (degrees).
    model: Option<(f64, [f64; 2], f64)>,
    /// Hourly weather rows: air temperature (K), dew-point depression (K),
    /// pressure (Pa), wind speed (m/s), wind direction (deg), direct normal
    /// and diffuse horizontal irradiance (W/m²), sky longwave (W/m²),
    /// cloud cover (0–1).
    weather: Vec<[f64; 9]>,
    /// Frame camera: azimuth, elevation (deg) and distance (ground sides)
    /// of its position, field of view (deg), oversample, NEdT (K, or none),
    /// quantisation bits (or none).
    camera: (f64, f64, f64, f64, usize, Option<f64>, Option<u32>),
    /// Add a 16 × 12 line scanner flying over the scene.
    scanner: Option<(f64, f64)>,
    /// Atmosphere: builtin (true) or none.
    builtin_atmosphere: bool,
    /// Render: most bounces, spectral step (µm).
    render: (u32, f64),
    /// Tracing backend: obvhs (true) or Embree.
    obvhs: bool,
}

/// Hours of weather before the image time: the render's history window
/// (24 h, see `exposure::HistoryWindow`) plus a margin; one more row after.
const WEATHER_HOURS_BEFORE: i64 = 25;

fn random_scene() -> impl Strategy<Value = RandomScene> {
    let m = 0..MATERIAL_NAMES.len();
    let row = (
        (
            235.0..320.0f64,
            0.0..25.0f64,
            60_000.0..105_000.0f64,
            0.0..20.0f64,
        ),
        (
            0.0..360.0f64,
            0.0..950.0f64,
            0.0..350.0f64,
            150.0..450.0f64,
            0.0..=1.0f64,
        ),
    )
        .prop_map(|((a, d, p, w), (wd, dni, dhi, lw, c))| [a, d, p, w, wd, dni, dhi, lw, c]);
    (
        (
            (-70.0..70.0f64, -180.0..180.0f64, 0.0..3000.0f64),
            (0..365i64, 0..24i64, 0..60i64),
            (20.0..200.0f64, m.clone()),
            proptest::collection::vec(
                (
                    [1.0..30.0f64, 1.0..30.0f64, 1.0..25.0f64],
                    [-0.8..0.8f64, -0.8..0.8f64],
                    0.0..360.0f64,
                    m.clone(),
                ),
                0..4,
            ),
            proptest::option::of((0.5..10.0f64, -2.0..12.0f64, m)),
            proptest::option::of((0.2..3.0f64, [-0.8..0.8f64, -0.8..0.8f64], 0.0..360.0f64)),
        ),
        (
            proptest::collection::vec(row, (WEATHER_HOURS_BEFORE + 2) as usize),
            (
                0.0..360.0f64,
                10.0..89.0f64,
                0.6..3.0f64,
                15.0..70.0f64,
                1..=2usize,
                proptest::option::of(0.02..0.3f64),
                proptest::option::of(10..=16u32),
            ),
            proptest::option::of((0.0..360.0f64, 100.0..1500.0f64)),
            any::<bool>(),
            (0..=2u32, 0.1..0.4f64),
            any::<bool>(),
        ),
    )
        .prop_map(
            |(
                (site, when, ground, boxes, sphere, model),
                (weather, camera, scanner, builtin_atmosphere, render, obvhs),
            )| RandomScene {
                site,
                when,
                ground,
                boxes,
                sphere,
                model,
                weather,
                camera,
                scanner,
                builtin_atmosphere,
                render,
                obvhs,
            },
        )
}

/// Write `case` as a scene file with its weather CSV into `dir`; returns
/// the scene path.
fn write_random_scene(case: &RandomScene, dir: &std::path::Path) -> std::path::PathBuf {
    use serde_json::json;
    let (lat, lon, alt) = case.site;
    // Local standard time of the site's zone.
    let offset_h = (lon / 15.0).round().clamp(-12.0, 14.0) as i32;
    let tz = FixedOffset::east_opt(offset_h * 3600).unwrap();
    let (day, hour, minute) = case.when;
    let time = DateTime::parse_from_rfc3339("2025-01-01T00:00:00Z")
        .unwrap()
        .with_timezone(&tz)
        + TimeDelta::days(day)
        + TimeDelta::hours(hour)
        + TimeDelta::minutes(minute);
    // Weather: hourly rows from before the history window to after the
    // image, on whole hours.
    let first = time - TimeDelta::minutes(minute) - TimeDelta::hours(WEATHER_HOURS_BEFORE);
    let mut csv = String::from(
        "time,air_temperature_k,dew_point_k,relative_humidity,pressure_pa,wind_speed_m_s,\
         wind_direction_deg,direct_normal_w_m2,diffuse_horizontal_w_m2,global_horizontal_w_m2,\
         sky_longwave_w_m2,total_sky_cover,opaque_sky_cover\n",
    );
    for (i, &[air, dep, p, wind, dir_deg, dni, dhi, lw, cover]) in case.weather.iter().enumerate() {
        let t = first + TimeDelta::hours(i as i64);
        let dew = air - dep;
        let rh = relative_humidity_from_dew_point(air, dew);
        csv += &format!(
            "{},{air},{dew},{rh},{p},{wind},{dir_deg},{dni},{dhi},{},{lw},{cover},{}\n",
            t.to_rfc3339(),
            dhi + 0.5 * dni,
            0.8 * cover
        );
    }
    std::fs::write(dir.join("weather.csv"), csv).unwrap();

    let name = |i: usize| MATERIAL_NAMES[i];
    let (side, ground_m) = case.ground;
    let mut objects = vec![json!({
        "name": "ground",
        "shapes": [{"plane": {"size": [side, side]}}],
        "material": name(ground_m),
    })];
    for (i, (size, pos, rot, mat)) in case.boxes.iter().enumerate() {
        objects.push(json!({
            "name": format!("box{i}"),
            "shapes": [{"box": {"size": size}}],
            "material": name(*mat),
            "transform": {"translate": [pos[0] * side / 2.0, pos[1] * side / 2.0, 0.0],
                          "rotate_deg": [0.0, 0.0, rot]},
        }));
    }
    if let Some((r, z, mat)) = case.sphere {
        objects.push(json!({
            "name": "ball",
            "shapes": [{"sphere": {"radius": r}}],
            "material": name(mat),
            "transform": {"translate": [0.0, 0.0, z]},
        }));
    }
    if let Some((scale, pos, rot)) = case.model {
        let (doc, bin) = util::gltf_doc();
        std::fs::write(dir.join("model.glb"), util::glb(&doc, &bin)).unwrap();
        objects.push(json!({
            "name": "model",
            "shapes": [{"gltf": "model.glb"}],
            "transform": {"translate": [pos[0] * side / 2.0, pos[1] * side / 2.0, 0.0],
                          "rotate_deg": [0.0, 0.0, rot], "scale": scale},
        }));
    }
    let bands = json!([{"name": "LWIR", "response": [8.0, 12.0]},
                       {"name": "MWIR", "response": [3.0, 5.0]}]);
    let (az, el, dist, fov, oversample, nedt, bits) = case.camera;
    let r = dist * side;
    let (az, el) = (az.to_radians(), el.to_radians());
    let mut camera = json!({
        "type": "frame", "name": "cam", "width": 16, "height": 12,
        "fov_deg": fov, "oversample": oversample,
        "position": [r * el.cos() * az.sin(), r * el.cos() * az.cos(), r * el.sin()],
        "look_at": [0.0, 0.0, 0.0],
        "bands": bands,
        "seed": 7,
    });
    if let Some(n) = nedt {
        camera["nedt_k"] = json!(n);
    }
    if let Some(b) = bits {
        camera["bits"] = json!(b);
        camera["gain"] = json!(50.0);
    }
    let mut sensors = vec![camera];
    if let Some((heading, altitude)) = case.scanner {
        // 16 samples across ±(scan angle / 2), 12 lines along the track,
        // centred on the scene.
        let speed = 50.0;
        let rate = 10.0;
        let (h, along) = (heading.to_radians(), 12.0 * speed / rate);
        sensors.push(json!({
            "type": "line_scanner", "name": "scan",
            "ifov_rad": 0.002, "scan_angle_deg": 60.0, "samples_per_line": 16, "lines": 12,
            "scan_rate_hz": rate, "altitude_m": altitude, "ground_speed_m_s": speed,
            "heading_deg": heading,
            "start": [-0.5 * along * h.sin(), -0.5 * along * h.cos()],
            "bands": [{"name": "LWIR", "response": [8.0, 14.0]}],
        }));
    }
    let (bounces, step) = case.render;
    let mut scene = json!({
        "site": {"latitude_deg": lat, "longitude_deg": lon, "altitude_m": alt,
                 "utc_offset_hours": offset_h},
        "time": time.to_rfc3339(),
        "materials": [util::repo_path("scenes/materials.json")],
        "weather": {"file": "weather.csv"},
        "objects": objects,
        "sensors": sensors,
        "render": {"max_bounces": bounces, "spectral_step_um": step},
    });
    if case.builtin_atmosphere {
        scene["atmosphere"] = json!({"model": "builtin"});
    }
    let path = dir.join("scene.json");
    std::fs::write(&path, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    path
}

/// Cases of [`r8_random_scenes_render_finite_plausible_layers`]: few (each
/// is a whole render with a 24 h thermal history); `PROPTEST_CASES`
/// overrides.
fn render_cases() -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(24)
}

/// Render every sensor of `case` through the whole chain (scene file →
/// exposure → thermal → render → sensor effects) and check the layers:
/// every value finite, facet temperatures within 150–450 K, the first
/// band's (LWIR) apparent temperatures, without noise, within 80–450 K (a
/// cold clear sky's window to the hottest surface: the driest sky the
/// strategy draws — 235 K air, 25 K dew-point depression, 60 kPa, 150 W·m⁻²
/// sky longwave — reads ≈ 101 K seen directly), with noise the exact
/// inversion of each pixel's radiance, and the frame camera, aimed at the
/// ground's centre, sees the scene. Returns the number of facets.
fn render_random_scene(case: &RandomScene) -> Result<usize, TestCaseError> {
    use irsig::render::session::Session;
    use irsig::trace::Backend;
    let dir = tempfile::tempdir().unwrap();
    let path = write_random_scene(case, dir.path());
    let backend = if case.obvhs {
        Backend::Obvhs
    } else {
        Backend::Embree
    };
    let mut session =
        Session::open(&path, backend).unwrap_or_else(|e| panic!("valid scene refused: {e}"));
    let time = session.scene.time;
    let states = session
        .thermal(&[time])
        .unwrap_or_else(|e| panic!("thermal: {e}"));
    let cond = &states.conditions[0];
    for (f, &t) in cond.surface.temperature_k.iter().enumerate() {
        prop_assert!((150.0..450.0).contains(&t), "facet {} at {} K", f, t);
    }
    for (f, &t) in cond.surface.background_k.iter().enumerate() {
        prop_assert!(
            (100.0..450.0).contains(&t),
            "facet {} background {} K",
            f,
            t
        );
    }
    for s in 0..session.sensors.len() {
        let h = session.sensors[s].height();
        let band = session
            .render_rows(s, cond, 0..h, &|_| {})
            .unwrap_or_else(|e| panic!("sensor {s}: {e}"));
        let out = session
            .finish(s, band, 11)
            .unwrap_or_else(|e| panic!("sensor {s}: {e}"));
        let stack = &out.stack;
        for layer in &stack.layers {
            for (i, v) in layer.data.iter().enumerate() {
                prop_assert!(
                    v.is_finite(),
                    "sensor {} layer {} pixel {}: {}",
                    s,
                    layer.name,
                    i,
                    v
                );
            }
        }
        let get = |name: &str| &stack.layers.iter().find(|l| l.name == name).unwrap().data;
        let material = get("material_id");
        if s == 0 {
            prop_assert!(
                material.iter().any(|&m| m >= 0.0),
                "the camera sees nothing"
            );
        }
        for (i, &t) in get("surface_temperature").iter().enumerate() {
            if material[i] >= 0.0 {
                prop_assert!(
                    (150.0..450.0).contains(&t),
                    "sensor {} pixel {}: surface {} K",
                    s,
                    i,
                    t
                );
            }
        }
        let apparent = get("apparent_temperature");
        if session.sensors[s].effects.nedt_k.is_none() {
            for (i, &t) in apparent.iter().enumerate() {
                prop_assert!(
                    (80.0..450.0).contains(&t),
                    "sensor {} pixel {}: apparent {} K",
                    s,
                    i,
                    t
                );
            }
        } else {
            // An NEdT is a radiance σ at its reference temperature (300 K):
            // on a cold sky (≈ 0.07 W·m⁻²·sr⁻¹ in 8–12 µm at 127 K) that is
            // tens of kelvin, and a sample may fall to ≤ 0 W·m⁻²·sr⁻¹, which
            // reads 0 K by the documented sentinel. What must hold is the
            // inversion: 0 K exactly for a non-positive radiance, otherwise
            // the temperature whose band radiance is the pixel's.
            let band = &session.bands[s][0];
            let radiance = &stack.layers[0].data;
            prop_assert!(stack.layers[0].name.ends_with("_radiance"));
            for (i, (&t, &l)) in apparent.iter().zip(radiance).enumerate() {
                if l <= 0.0 {
                    prop_assert_eq!(t, 0.0, "sensor {} pixel {}: radiance {}", s, i, l);
                } else {
                    let back = band.blackbody_radiance(t as f64);
                    prop_assert!(
                        (0.0..500.0).contains(&t)
                            && (back - l as f64).abs() <= 1e-4 * l as f64 + 1e-9,
                        "sensor {} pixel {}: apparent {} K is radiance {}, pixel {}",
                        s,
                        i,
                        t,
                        back,
                        l
                    );
                }
            }
        }
        if session.sensors[s].effects.nedt_k.is_none() {
            for layer in &stack.layers {
                if layer.name.ends_with("_radiance") {
                    prop_assert!(
                        layer.data.iter().all(|&v| v >= 0.0),
                        "negative radiance in {}",
                        layer.name
                    );
                }
            }
        }
    }
    Ok(session.scene.geometry.facet_count())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: render_cases(), failure_persistence: None, ..ProptestConfig::default() })]

    /// Issue 8: for any valid small scene — a plane, boxes, a sphere and a
    /// glTF model of the bundled materials anywhere on Earth at any time of
    /// year, random physical weather with a 24 h history, with or without the built-in
    /// atmosphere, a frame camera (oversampled, with or without noise and
    /// quantisation) and a line scanner, either backend — every output
    /// layer is finite and the temperatures plausible
    /// ([`render_random_scene`]).
    #[test]
    fn r8_random_scenes_render_finite_plausible_layers(case in random_scene()) {
        render_random_scene(&case)?;
    }
}

/// Found by `r8_random_scenes_render_finite_plausible_layers`: with the
/// built-in atmosphere every render failed (`a 0 m path cannot span the
/// altitudes …`): the sensor-path table's first node asked for a 0 m path
/// from the sensor's height. A fixed case: both backends, both sensors.
#[test]
fn r8_builtin_atmosphere_renders_from_above_the_ground() {
    let case = RandomScene {
        site: (43.16, -77.61, 160.0),
        when: (171, 14, 0),
        ground: (60.0, 0),
        boxes: vec![([10.0, 8.0, 6.0], [0.3, -0.2], 30.0, 5)],
        sphere: Some((3.0, 4.0, 10)),
        model: Some((1.5, [-0.4, 0.3], 45.0)),
        weather: (0..WEATHER_HOURS_BEFORE + 2)
            .map(|i| {
                let day = (std::f64::consts::TAU * (i as f64 - 20.0) / 24.0).cos();
                [
                    293.0 + 6.0 * day,
                    8.0,
                    99_000.0,
                    3.0,
                    200.0,
                    (700.0 * day).max(0.0),
                    (100.0 * day).max(0.0),
                    330.0,
                    0.2,
                ]
            })
            .collect(),
        camera: (200.0, 35.0, 1.5, 40.0, 2, Some(0.05), Some(14)),
        scanner: Some((30.0, 400.0)),
        builtin_atmosphere: true,
        render: (2, 0.1),
        obvhs: false,
    };
    let facets = render_random_scene(&case).unwrap();
    assert!(facets > 20, "{facets} facets");
    render_random_scene(&RandomScene {
        obvhs: true,
        ..case
    })
    .unwrap();
}

/// Issue 8, found by `scripts/fuzz` (target `weather`): an EPW row of year
/// 0 whose missing global irradiance is filled from the solar position (ΔT
/// of year 0 exceeds SPA's ±10⁴ s) failed with an error naming neither the
/// file nor the row; now it names both and what needed the sun.
#[test]
fn r8_weather_fill_solar_position_error_names_file_and_line() {
    use irsig::weather::{LoadOptions, detect_format, load_str};
    let text = "LOCATION,,,,,,4,8,5,1\n\n\n\n\n\n\n\n\
                0,6,2,8,0,,1,1,6,99700,,,4,1,9999,4,,,,,0,0,6,0\n\
                1,6,2,1,0,,1,0,0,0,,,6,5,3,1,,,,,8,8,0,1";
    let p = std::path::Path::new("year0.epw");
    let format = detect_format(p, text).unwrap();
    let e = load_str(text, p, format, &LoadOptions::default())
        .expect_err("year 0 accepted")
        .to_string();
    assert!(
        e.contains("year0.epw:line 9") && e.contains("solar position") && e.contains("delta_t"),
        "{e}"
    );
}

/// Issue 8, found by `scripts/fuzz` (target `tape7`): a first spectral row
/// at wavenumber 0 was accepted (only later rows were checked), giving an
/// infinite wavelength; now it is an error naming the file, line and FREQ.
#[test]
fn r8_tape7_zero_first_wavenumber_is_an_error() {
    let p = std::path::Path::new("zero.tape7");
    let text =
        "M F00\n    FREQ COMBIN    H2CH4\n 0.0000  1.010000\n  705.0  1.0000 1.0000\n -9999.\n";
    let e = irsig::atmosphere::Tape7::parse(text, p)
        .expect_err("wavenumber 0 accepted")
        .to_string();
    assert!(
        e.contains("zero.tape7:line 3") && e.contains("FREQ") && e.contains("positive"),
        "{e}"
    );
}
