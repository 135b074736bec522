//! Tests: the render pipeline end to end on small scenes built here, against
//! hand-computed radiometry (blackbody and grey planes, a specular plate),
//! the line scanner's geometry, thread-count independence and tiling.

use glam::Vec3;
use irsig::Location;
use irsig::atmosphere::Atmosphere;
use irsig::geometry::{Instance, SceneGeometry, TriangleMesh};
use irsig::material::Material;
use irsig::progress::{Progress, Stage};
use irsig::radiometry::Band;
use irsig::radiometry::Emissivity;
use irsig::render::image::{StageTimes, finish, render_rows};
use irsig::render::session::{RunOptions, Session};
use irsig::render::tile::{TileInfo, assemble, read_tile, tile_rows, write_tile};
use irsig::render::{
    Conditions, Finished, SceneOptics, ShadeOptions, Shader, Sky, SunInput, SurfaceState,
    sensor_bands,
};
use irsig::sensor::Geometry;
use irsig::sensor::{Sensor, SensorConfig};
use irsig::trace::{self, Backend};
use serde_json::json;

/// A grey, opaque material.
fn material(name: &str, id: u32, emissivity: f64, specular: f64) -> Material {
    Material {
        id,
        name: name.into(),
        specific_heat_j_kg_k: 900.0,
        conductivity_w_m_k: 1.0,
        density_kg_m3: 2000.0,
        thickness_m: 0.1,
        solar_absorptivity: 0.5,
        thermal_emissivity: emissivity,
        exposed_area: 1.0,
        self_power_w_m2: 0.0,
        specular_fraction: specular,
        specular_roughness: None,
        transmissivity: 0.0,
        emissivity_curve: None,
        double_sided: false,
        surface_energy: None,
        convection: Default::default(),
        layers: Vec::new(),
        back: None,
    }
}

/// A quad `a b c d` (counter-clockwise seen from its front) as two triangles.
fn quad(name: &str, p: [Vec3; 4]) -> TriangleMesh {
    TriangleMesh {
        name: name.into(),
        positions: p.to_vec(),
        indices: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// A horizontal square of half-size `h` at height `z`, facing up.
fn ground(name: &str, cx: f32, cy: f32, h: f32, z: f32) -> TriangleMesh {
    quad(
        name,
        [
            Vec3::new(cx - h, cy - h, z),
            Vec3::new(cx + h, cy - h, z),
            Vec3::new(cx + h, cy + h, z),
            Vec3::new(cx - h, cy + h, z),
        ],
    )
}

fn geometry(meshes: Vec<TriangleMesh>) -> SceneGeometry {
    let instances = (0..meshes.len())
        .map(|mesh| Instance {
            mesh,
            world_from_object: glam::Affine3A::IDENTITY,
        })
        .collect();
    SceneGeometry { meshes, instances }
}

fn sensor(cfg: serde_json::Value) -> Sensor {
    let c: SensorConfig = serde_json::from_value(cfg).expect("sensor config");
    Sensor::from_config(&c, &Location::file("test.json").with_field("sensors[0]")).unwrap()
}

/// Per facet: material index and object index = mesh index.
fn optics(geom: &SceneGeometry, materials: Vec<Material>, mesh_material: &[u32]) -> SceneOptics {
    let mut facet_material = Vec::new();
    let mut facet_object = Vec::new();
    for inst in &geom.instances {
        let n = geom.meshes[inst.mesh].triangle_count();
        facet_material.extend(std::iter::repeat_n(mesh_material[inst.mesh], n));
        facet_object.extend(std::iter::repeat_n(inst.mesh as u32, n));
    }
    SceneOptics {
        materials,
        facet_material,
        facet_object,
    }
}

/// Per-facet state from per-mesh temperatures.
fn state(geom: &SceneGeometry, mesh_t: &[f32]) -> SurfaceState {
    let mut s = SurfaceState::uniform(geom.facet_count(), 300.0);
    let mut f = 0;
    for inst in &geom.instances {
        for _ in 0..geom.meshes[inst.mesh].triangle_count() {
            s.temperature_k[f] = mesh_t[inst.mesh];
            s.background_k[f] = mesh_t[inst.mesh];
            f += 1;
        }
    }
    s
}

const OPTS: ShadeOptions = ShadeOptions {
    max_bounces: 2,
    offset_m: 1e-3,
};

/// Render a whole image in one piece.
fn render(
    geom: &SceneGeometry,
    optics: &SceneOptics,
    cond: &Conditions,
    sensor: &Sensor,
    backend: Backend,
) -> (Vec<Band>, Finished) {
    let tracer = trace::build(geom, backend).unwrap();
    let bands = sensor_bands(sensor, std::path::Path::new("."), 0.1, &Location::file("t")).unwrap();
    let shader = Shader::new(tracer.as_ref(), geom, optics, cond, &bands, OPTS).unwrap();
    let times = StageTimes::default();
    let rows = render_rows(&shader, sensor, 0..sensor.height(), &times, &|_| {}).unwrap();
    let f = finish(rows, sensor, &bands, sensor.effects.seed).unwrap();
    (bands, f)
}

fn layer<'a>(f: &'a Finished, name: &str) -> &'a [f32] {
    &f.stack
        .layer(name)
        .unwrap_or_else(|| panic!("layer {name}"))
        .data
}

fn nadir_camera(width: usize, height: usize, fov: f64, n: usize) -> serde_json::Value {
    json!({"type": "frame", "name": "cam", "width": width, "height": height,
           "fov_deg": fov, "position": [0.0, 0.0, 100.0], "look_at": [0.0, 0.0, 0.0],
           "up": [0.0, 1.0, 0.0], "oversample": n,
           "bands": [{"name": "LWIR", "response": [8.0, 12.0]},
                     {"name": "MWIR", "response": [3.0, 5.0]}]})
}

#[test]
fn blackbody_plane_reads_its_temperature_in_every_pixel() {
    let geom = geometry(vec![ground("plane", 0.0, 0.0, 1000.0, 0.0)]);
    let optics = optics(&geom, vec![material("black", 7, 1.0, 0.0)], &[0]);
    let cond = Conditions {
        surface: state(&geom, &[300.0]),
        sky: Sky::Blackbody {
            temperature_k: 230.0,
        },
        sun: None,
        ground_temperature_k: 280.0,
        atmosphere: Atmosphere::None,
        per_hit: None,
        wind_speed_m_s: 0.0,
    };
    let s = sensor(nadir_camera(32, 24, 40.0, 2));
    let (_, f) = render(&geom, &optics, &cond, &s, Backend::Embree);
    for name in ["apparent_temperature", "MWIR_apparent_temperature"] {
        for &t in layer(&f, name) {
            assert!((t - 300.0).abs() < 0.01, "{name}: {t} K, expected 300 K");
        }
    }
    // Truth layers: the plane's temperature, ids, and the slant range.
    assert!(layer(&f, "surface_temperature").iter().all(|&t| t == 300.0));
    assert!(layer(&f, "material_id").iter().all(|&m| m == 7.0));
    assert!(layer(&f, "object_id").iter().all(|&m| m == 0.0));
    let d = layer(&f, "depth");
    let centre = d[12 * 32 + 16];
    assert!((centre - 100.0).abs() < 0.5, "centre depth {centre}");
    assert!(
        d.iter()
            .all(|&v| (99.99..=100.0 / (20f32.to_radians().cos() * 0.9)).contains(&v))
    );
}

#[test]
fn grey_plane_matches_the_hand_computed_big_equation() {
    // ε = 0.5 at 310 K; F = 0.6 of a 250 K sky, the rest a 290 K background;
    // the facet sunlit (fraction 0.8) at cos σ = 0.7 under DNI 800 W/m²:
    // its sample points disagree, so each hit traces its own shadow ray,
    // which finds the sun (nothing shades the plane): fraction 1.
    let geom = geometry(vec![ground("plane", 0.0, 0.0, 1000.0, 0.0)]);
    let optics = optics(&geom, vec![material("grey", 3, 0.5, 0.0)], &[0]);
    let mut surface = state(&geom, &[310.0]);
    surface.shape_factor.fill(0.6);
    surface.background_k.fill(290.0);
    surface.sun_fraction.fill(0.8);
    surface.cos_sun.fill(0.7);
    let (dni, t_sky) = (800.0, 250.0);
    let cond = Conditions {
        surface,
        sky: Sky::Blackbody {
            temperature_k: t_sky,
        },
        sun: Some(SunInput {
            direction: Vec3::new(0.0, -0.714, 0.7).normalize(),
            direct_normal_w_m2: dni,
        }),
        ground_temperature_k: 280.0,
        atmosphere: Atmosphere::None,
        per_hit: None,
        wind_speed_m_s: 0.0,
    };
    let s = sensor(nadir_camera(8, 8, 10.0, 1));
    let (bands, f) = render(&geom, &optics, &cond, &s, Backend::Embree);
    let eps_of = Emissivity::from_material(&optics.materials[0]).unwrap();
    for (band, name) in bands.iter().zip(["LWIR", "MWIR"]) {
        // Hand computation with band integrals of blackbodies:
        // L = ε B(T) + (1−ε)[E_s cos σ/π + F L_sky + (1−F) B(T_bg)], the
        // sun a 5772 K blackbody scaled to the DNI, ε = ε(θ) of the pixel's
        // view zenith (grey, Fresnel fall-off).
        let b = |t: f64| band.blackbody_radiance(t);
        let sigma = 5.670374419e-8;
        let e_sun = dni * std::f64::consts::PI * b(5772.0) / (sigma * 5772f64.powi(4));
        for (i, &l) in layer(&f, &format!("{name}_radiance")).iter().enumerate() {
            let eps = eps_of.eval(10.0, view_zenith_deg(&s, i % 8, i / 8));
            let expected = eps * b(310.0)
                + (1.0 - eps)
                    * (e_sun * 0.7 / std::f64::consts::PI + 0.6 * b(t_sky) + 0.4 * b(290.0));
            let rel = (l as f64 - expected).abs() / expected;
            assert!(rel < 2e-5, "{name}: {l} vs {expected} (rel {rel:e})");
        }
    }
    // The sun matters in the MWIR band, so the check above covers its term.
    let mwir = &bands[1];
    assert!(
        mwir.blackbody_radiance(5772.0) * 800.0 / (5.67e-8 * 5772f64.powi(4))
            > 0.01 * mwir.blackbody_radiance(310.0)
    );
}

/// View zenith (degrees) at a horizontal surface of the centre ray of
/// pixel `(col, row)` of a frame camera.
fn view_zenith_deg(s: &Sensor, col: usize, row: usize) -> f64 {
    let Geometry::Frame(c) = &s.geometry else {
        panic!("frame camera expected")
    };
    let d = c.direction(col as f64 + 0.5, row as f64 + 0.5).normalize();
    (-d.z).clamp(-1.0, 1.0).acos().to_degrees()
}

/// A specular plate (z = 0) in front of a vertical wall at y = 60 facing
/// the camera; the camera looks down at 45° so the plate mirrors the wall.
fn plate_and_wall(wall_k: f32) -> (SceneGeometry, SceneOptics, Conditions) {
    let plate = ground("plate", 0.0, 0.0, 30.0, 0.0);
    let wall = quad(
        "wall",
        [
            Vec3::new(-400.0, 60.0, -1.0),
            Vec3::new(-400.0, 60.0, 400.0),
            Vec3::new(400.0, 60.0, 400.0),
            Vec3::new(400.0, 60.0, -1.0),
        ],
    );
    let geom = geometry(vec![plate, wall]);
    let optics = optics(
        &geom,
        vec![
            material("plate", 1, 0.2, 1.0),
            material("wall", 2, 1.0, 0.0),
        ],
        &[0, 1],
    );
    let cond = Conditions {
        surface: state(&geom, &[300.0, wall_k]),
        sky: Sky::Blackbody {
            temperature_k: 240.0,
        },
        sun: None,
        ground_temperature_k: 280.0,
        atmosphere: Atmosphere::None,
        per_hit: None,
        wind_speed_m_s: 0.0,
    };
    (geom, optics, cond)
}

#[test]
fn specular_plate_shows_the_hot_block_scaled_by_one_minus_epsilon() {
    let cam = json!({"type": "frame", "name": "cam", "width": 16, "height": 16,
           "fov_deg": 8.0, "position": [0.0, -20.0, 20.0], "look_at": [0.0, 0.0, 0.0],
           "up": [0.0, 0.0, 1.0], "oversample": 1,
           "bands": [{"name": "LWIR", "response": [8.0, 12.0]}]});
    let s = sensor(cam);
    let (hot_g, hot_o, hot_c) = plate_and_wall(400.0);
    let (_, hot) = render(&hot_g, &hot_o, &hot_c, &s, Backend::Embree);
    let (cold_g, cold_o, cold_c) = plate_and_wall(250.0);
    let (bands, cold) = render(&cold_g, &cold_o, &cold_c, &s, Backend::Embree);
    let b = |t: f64| bands[0].blackbody_radiance(t);
    let ids = layer(&hot, "material_id");
    assert!(
        ids.iter().all(|&m| m == 1.0),
        "every centre ray hits the plate"
    );
    let eps_of = Emissivity::from_material(&hot_o.materials[0]).unwrap();
    let eps = |i: usize| eps_of.eval(10.0, view_zenith_deg(&s, i % 16, i / 16));
    for (i, (&lh, &lc)) in layer(&hot, "LWIR_radiance")
        .iter()
        .zip(layer(&cold, "LWIR_radiance"))
        .enumerate()
    {
        // L = ε B(T_plate) + (1 − ε) B(T_wall), mirror reflection only,
        // ε = ε(θ) ≈ ε(45°) of the plate.
        let e = eps(i);
        let expected = e * b(300.0) + (1.0 - e) * b(400.0);
        assert!(
            ((lh as f64 - expected) / expected).abs() < 1e-4,
            "{lh} vs {expected}"
        );
        let diff = (lh - lc) as f64;
        let expected_diff = (1.0 - e) * (b(400.0) - b(250.0));
        assert!(((diff - expected_diff) / expected_diff).abs() < 1e-4);
    }
    // With no bounces the plate reflects the diffuse environment instead.
    let tracer = trace::build(&hot_g, Backend::Embree).unwrap();
    let shader = Shader::new(
        tracer.as_ref(),
        &hot_g,
        &hot_o,
        &hot_c,
        &bands,
        ShadeOptions {
            max_bounces: 0,
            offset_m: 1e-3,
        },
    )
    .unwrap();
    let rows = render_rows(&shader, &s, 0..16, &StageTimes::default(), &|_| {}).unwrap();
    for (i, &l) in rows.radiance()[0].iter().enumerate() {
        let e = eps(i);
        let expected = e * b(300.0) + (1.0 - e) * b(240.0); // F = 1: all sky
        assert!(((l as f64 - expected) / expected).abs() < 1e-4);
    }
}

#[test]
fn line_scanner_images_ground_points_where_its_geometry_predicts() {
    // Cold ground with small hot squares at known points.
    let points = [
        Vec3::new(0.0, 20.0, 0.0),
        Vec3::new(-60.0, 40.0, 0.0),
        Vec3::new(80.0, 70.0, 0.0),
        Vec3::new(30.0, 100.0, 0.0),
    ];
    let mut meshes = vec![ground("ground", 0.0, 60.0, 2000.0, 0.0)];
    for (i, p) in points.iter().enumerate() {
        meshes.push(ground(&format!("hot{i}"), p.x, p.y, 1.5, 0.05));
    }
    let geom = geometry(meshes);
    let mats = vec![
        material("ground", 1, 1.0, 0.0),
        material("hot", 2, 1.0, 0.0),
    ];
    let mut mm = vec![0u32];
    mm.extend(std::iter::repeat_n(1, points.len()));
    let optics = optics(&geom, mats, &mm);
    let mut temps = vec![280.0f32];
    temps.extend(std::iter::repeat_n(400.0, points.len()));
    let cond = Conditions {
        surface: state(&geom, &temps),
        sky: Sky::Blackbody {
            temperature_k: 240.0,
        },
        sun: None,
        ground_temperature_k: 280.0,
        atmosphere: Atmosphere::None,
        per_hit: None,
        wind_speed_m_s: 0.0,
    };
    let s = sensor(
        json!({"type": "line_scanner", "name": "scan", "ifov_rad": 0.003,
        "scan_angle_deg": 40.0, "samples_per_line": 160, "lines": 140,
        "scan_rate_hz": 10.0, "altitude_m": 300.0, "ground_speed_m_s": 10.0,
        "heading_deg": 0.0, "start": [0.0, 0.0], "oversample": 1,
        "bands": [{"name": "LWIR", "response": [8.0, 14.0]}]}),
    );
    let (_, f) = render(&geom, &optics, &cond, &s, Backend::Embree);
    let t = layer(&f, "apparent_temperature");
    let w = s.width();
    for p in points {
        // Where the written (north-up by default) image shows the point.
        let uv = s.project_written(p.as_dvec3()).expect("point is imaged");
        let (col, row) = (uv.x.floor() as usize, uv.y.floor() as usize);
        assert!(col < w && row < s.height(), "{p} → {uv}");
        assert!(
            t[row * w + col] > 390.0,
            "{p} at ({col}, {row}): {} K",
            t[row * w + col]
        );
        // Ten pixels away the ground is cold.
        assert!(t[row * w + col + 10] < 285.0);
        assert!(t[(row + 10) * w + col] < 285.0);
    }
}

/// A scene with everything on: specular and transmissive facets, sun,
/// Gaussian PSF, MTF, noise and quantisation.
fn busy_scene() -> (SceneGeometry, SceneOptics, Conditions, Sensor) {
    let mut meshes = vec![ground("ground", 0.0, 0.0, 500.0, 0.0)];
    for i in 0..6 {
        let x = -40.0 + 16.0 * i as f32;
        meshes.push(ground(
            &format!("roof{i}"),
            x,
            5.0 * i as f32,
            4.0,
            3.0 + i as f32,
        ));
    }
    let geom = geometry(meshes);
    let mut glass = material("glass", 4, 0.3, 0.5);
    glass.transmissivity = 0.3;
    let mats = vec![
        material("soil", 1, 0.95, 0.0),
        material("metal", 2, 0.1, 0.9),
        glass,
    ];
    let mm = [0, 1, 2, 1, 2, 1, 2];
    let optics = optics(&geom, mats, &mm);
    let mut surface = state(&geom, &[295.0, 320.0, 305.0, 330.0, 300.0, 310.0, 290.0]);
    for (i, f) in surface.shape_factor.iter_mut().enumerate() {
        *f = 0.5 + 0.05 * (i % 10) as f32;
    }
    surface.sun_fraction.fill(1.0);
    surface.cos_sun.fill(0.6);
    let cond = Conditions {
        surface,
        sky: Sky::Blackbody {
            temperature_k: 250.0,
        },
        sun: Some(SunInput {
            direction: Vec3::new(0.3, -0.5, 0.8).normalize(),
            direct_normal_w_m2: 700.0,
        }),
        ground_temperature_k: 285.0,
        atmosphere: Atmosphere::None,
        per_hit: None,
        wind_speed_m_s: 0.0,
    };
    let s = sensor(
        json!({"type": "frame", "name": "busy", "width": 48, "height": 37,
           "fov_deg": 50.0, "position": [10.0, -90.0, 60.0], "look_at": [0.0, 0.0, 0.0],
           "up": [0.0, 0.0, 1.0], "oversample": 2,
           "psf": {"type": "gaussian", "sigma_px": 0.6},
           "mtf": {"aperture_diameter_m": 0.02, "wavelength_um": 10.0, "fill_factor": 0.9},
           "nedt_k": 0.05, "bits": 14, "gain": 500.0, "seed": 42,
           "bands": [{"name": "LWIR", "response": [8.0, 12.0]},
                     {"name": "MWIR", "response": [3.0, 5.0]}]}),
    );
    (geom, optics, cond, s)
}

fn bits_equal(a: &Finished, b: &Finished) -> bool {
    a.stack.layers.len() == b.stack.layers.len()
        && a.stack.layers.iter().zip(&b.stack.layers).all(|(x, y)| {
            x.name == y.name
                && x.data.len() == y.data.len()
                && x.data
                    .iter()
                    .zip(&y.data)
                    .all(|(p, q)| p.to_bits() == q.to_bits())
        })
}

#[test]
fn one_and_two_threads_give_bit_identical_images() {
    let (geom, optics, cond, s) = busy_scene();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render(&geom, &optics, &cond, &s, Backend::Embree).1)
    };
    let (a, b) = (run(1), run(2));
    assert!(bits_equal(&a, &b));
    // And the image is not trivial: the roofs stand out, no NaN anywhere.
    let t = layer(&a, "apparent_temperature");
    let (lo, hi) = t
        .iter()
        .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
    assert!(hi - lo > 5.0, "{lo}..{hi}");
    assert!(
        a.stack
            .layers
            .iter()
            .all(|l| l.data.iter().all(|v| v.is_finite()))
    );
}

#[test]
fn tiles_merge_bit_for_bit_into_the_single_render() {
    let (geom, optics, cond, s) = busy_scene();
    let (bands, whole) = render(&geom, &optics, &cond, &s, Backend::Embree);
    let tracer = trace::build(&geom, Backend::Embree).unwrap();
    let shader = Shader::new(tracer.as_ref(), &geom, &optics, &cond, &bands, OPTS).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let n = 4;
    let mut parts = Vec::new();
    for k in (1..=n).rev() {
        let rows = tile_rows(k, n, s.height());
        let band = render_rows(&shader, &s, rows.clone(), &StageTimes::default(), &|_| {}).unwrap();
        let info = TileInfo {
            version: 1,
            scene_hash: "abc".into(),
            scene_file_hash: "0123".into(),
            scene: "scene.json".into(),
            sensor: s.name.clone(),
            stem: s.name.clone(),
            time: "2025-06-21T14:00:00-04:00".into(),
            tile: k,
            tiles: n,
            width: s.width(),
            height: s.height(),
            row_start: rows.start,
            row_end: rows.end,
            bands: vec!["LWIR".into(), "MWIR".into()],
            seed: 42,
            backend: "embree".into(),
        };
        let path = dir.path().join(format!("busy.tile{k}-of-{n}.exr"));
        write_tile(&path, &info, &band).unwrap();
        let (info2, band2) = read_tile(&path).unwrap();
        assert_eq!(info2, info);
        parts.push((path, info2, band2));
    }
    let (_, full) = assemble(&parts).unwrap();
    let merged = finish(full, &s, &bands, 42).unwrap();
    assert!(bits_equal(&merged, &whole));
    // A missing tile is named.
    let err = assemble(&parts[1..]).unwrap_err().to_string();
    assert!(err.contains("missing tile(s) 4/4"), "{err}");
    // A tile of another image is refused.
    let mut other = parts.clone();
    other[0].1.scene_hash = "def".into();
    let err = assemble(&other).unwrap_err().to_string();
    assert!(err.contains("does not belong to the same image"), "{err}");
}

#[test]
fn embree_and_obvhs_render_the_same_image() {
    let (geom, optics, cond, s) = busy_scene();
    let (_, a) = render(&geom, &optics, &cond, &s, Backend::Embree);
    let (_, b) = render(&geom, &optics, &cond, &s, Backend::Obvhs);
    let (ta, tb) = (
        layer(&a, "apparent_temperature"),
        layer(&b, "apparent_temperature"),
    );
    let differ = ta
        .iter()
        .zip(tb)
        .filter(|(x, y)| (*x - *y).abs() > 0.01)
        .count();
    assert!(differ == 0, "{differ} pixels differ by more than 0.01 K");
}

// ---------------------------------------------------------------------------
// The command line: `irsig render` / `irsig merge` on a small scene file.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

use crate::util::{irsig_bin, repo_path};

/// A small scene file in `dir`: ground, two buildings (one with a glass
/// roof), the bundled materials and weather; one frame camera with noise,
/// a Gaussian PSF and an MTF, `width × height` pixels.
fn write_scene(dir: &Path, width: usize, height: usize, oversample: usize) -> PathBuf {
    let scene = json!({
        "site": {"latitude_deg": 43.16, "longitude_deg": -77.61, "altitude_m": 160.0,
                 "utc_offset_hours": -4.0},
        "time": "2025-06-21T14:00:00-04:00",
        "weather": {"file": repo_path("scenes/town/weather.csv")},
        "materials": [repo_path("scenes/materials.json")],
        "objects": [
            {"name": "ground", "material": "asphalt",
             "shapes": [{"plane": {"size": [200.0, 200.0], "max_edge_m": 20.0}}]},
            {"name": "shed", "parts": [{"name": "top", "material": "glass"},
                                       {"name": "sides", "material": "brick"}],
             "shapes": [{"box": {"size": [20.0, 12.0, 6.0], "bottom": false}}],
             "instances": [{"translate": [-20.0, 10.0, 0.0]},
                           {"translate": [25.0, -5.0, 0.0], "rotate_deg": [0.0, 0.0, 30.0]}]}
        ],
        "sensors": [{"type": "frame", "name": "cam", "width": width, "height": height,
                     "fov_deg": 60.0, "position": [0.0, -120.0, 80.0],
                     "look_at": [0.0, 0.0, 0.0], "oversample": oversample,
                     "psf": {"type": "gaussian", "sigma_px": 0.5},
                     "mtf": {"aperture_diameter_m": 0.01, "wavelength_um": 10.0},
                     "nedt_k": 0.05, "bits": 12, "gain": 100.0, "seed": 7,
                     "bands": [{"name": "LWIR", "response": [8.0, 12.0]},
                               {"name": "MWIR", "response": [3.0, 5.0]}]}]
    });
    let path = dir.join("scene.json");
    std::fs::write(&path, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    path
}

fn irsig(args: &[&str]) -> std::process::Output {
    let out = Command::new(irsig_bin()).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "irsig {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn same_bytes(a: &Path, b: &Path) {
    let (x, y) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(x == y, "{} and {} differ", a.display(), b.display());
}

#[test]
fn cli_render_is_identical_for_1_and_2_threads_and_tiles_merge_to_it() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), 40, 30, 2);
    let (d1, d2, dt, dm) = (
        dir.path().join("t1"),
        dir.path().join("t2"),
        dir.path().join("tiles"),
        dir.path().join("merged"),
    );
    irsig(&[
        "--threads",
        "1",
        "render",
        s(&scene),
        "-o",
        s(&d1),
        "--quiet",
    ]);
    irsig(&[
        "--threads",
        "2",
        "render",
        s(&scene),
        "-o",
        s(&d2),
        "--quiet",
    ]);
    for ext in ["exr", "img", "hdr", "png"] {
        same_bytes(
            &d1.join(format!("cam.{ext}")),
            &d2.join(format!("cam.{ext}")),
        );
    }
    // The image is sane: every layer finite, the scene in view.
    let img = irsig::output::read_exr(d1.join("cam.exr")).unwrap();
    for l in &img.layers {
        assert!(l.data.iter().all(|v| v.is_finite()), "layer {}", l.name);
    }
    let t = img.layer("apparent_temperature").unwrap();
    assert!(t.data.iter().all(|&v| (200.0..400.0).contains(&v)));
    let ids = &img.layer("material_id").unwrap().data;
    assert!(ids.iter().any(|&m| m >= 0.0) && ids.iter().any(|&m| m != ids[0]));
    // Three tiles, in any order, merged: the same files.
    for k in [2, 3, 1] {
        irsig(&[
            "render",
            s(&scene),
            "-o",
            s(&dt),
            "--tile",
            &format!("{k}/3"),
            "--quiet",
        ]);
    }
    let tile1 = dt.join("cam.tile1-of-3.exr");
    let before = std::fs::metadata(&tile1).unwrap().modified().unwrap();
    // A complete tile is skipped when rerun.
    irsig(&[
        "render",
        s(&scene),
        "-o",
        s(&dt),
        "--tile",
        "1/3",
        "--quiet",
    ]);
    assert_eq!(
        std::fs::metadata(&tile1).unwrap().modified().unwrap(),
        before
    );
    let tiles: Vec<PathBuf> = (1..=3)
        .map(|k| dt.join(format!("cam.tile{k}-of-3.exr")))
        .collect();
    let mut args = vec!["merge"];
    args.extend(tiles.iter().map(|p| s(p)));
    args.extend(["-o", s(&dm), "--quiet"]);
    irsig(&args);
    for ext in ["exr", "img", "hdr", "png"] {
        same_bytes(
            &d1.join(format!("cam.{ext}")),
            &dm.join(format!("cam.{ext}")),
        );
    }
    // A missing tile is an error naming it.
    let out = Command::new(irsig_bin())
        .args(["merge", s(&tiles[0]), s(&tiles[2]), "-o", s(&dm)])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("missing tile(s) 2/3"), "{err}");
}

#[test]
fn a_killed_render_leaves_no_file_under_a_final_name() {
    let dir = tempfile::tempdir().unwrap();
    // Cheap to trace, slow to write: a big image of a simple scene.
    let scene = write_scene(dir.path(), 1600, 1200, 1);
    let out = dir.path().join("out");
    let mut child = Command::new(irsig_bin())
        .args(["render", s(&scene), "-o", s(&out), "--quiet"])
        .spawn()
        .unwrap();
    // Wait for the EXR's temporary file to appear, then kill.
    let start = std::time::Instant::now();
    let mut tmp = None;
    while start.elapsed() < std::time::Duration::from_secs(120) {
        if let Some(st) = child.try_wait().unwrap() {
            panic!("the render ended ({st}) before it could be killed");
        }
        tmp = std::fs::read_dir(&out).ok().and_then(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .find(|n| n.ends_with(".tmp"))
        });
        if tmp.is_some() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    // `.cam.exr.XXXXXX.tmp` is being written: `cam.exr` must not exist.
    let tmp = tmp.expect("no temporary output file appeared");
    let name = tmp.trim_start_matches('.');
    let final_name = &name[..name.find('.').unwrap() + 4];
    assert!(
        !out.join(final_name).exists(),
        "{final_name} exists after the kill"
    );
    // Files written before it are complete; EXR first, so none here when
    // the EXR was the one cut short.
    if final_name == "cam.exr" {
        for ext in ["exr", "img", "hdr", "png"] {
            let p = out.join(format!("cam.{ext}"));
            assert!(!p.exists(), "{} exists after the kill", p.display());
        }
    }
}

#[test]
fn cli_render_errors_name_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), 8, 6, 1);
    let cases: [(&[&str], &str); 4] = [
        (
            &["render", "no/such/scene.json", "-o", "x"],
            "no/such/scene.json",
        ),
        (&["render", s(&scene), "-o", "x", "--tile", "4/3"], "--tile"),
        (
            &[
                "render",
                s(&scene),
                "-o",
                "x",
                "--times",
                "2025-06-21T14:00:00-04:00/2025-06-21T15:00:00-04:00/0s",
            ],
            "--times",
        ),
        (
            &["render", s(&scene), "-o", "x", "--sensor", "nope"],
            "`nope`: no such sensor",
        ),
    ];
    for (args, needle) in cases {
        let out = Command::new(irsig_bin()).args(args).output().unwrap();
        assert!(!out.status.success(), "{args:?} succeeded");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

/// Records every call of the [`Progress`] observer.
#[derive(Default)]
struct Calls {
    log: std::sync::Mutex<Vec<String>>,
    advanced: std::sync::atomic::AtomicU64,
}

impl Progress for Calls {
    fn start(&self, stage: Stage, total: u64) {
        self.advanced.store(0, std::sync::atomic::Ordering::SeqCst);
        self.log
            .lock()
            .unwrap()
            .push(format!("start {stage:?} {total}"));
    }
    fn item(&self, name: &str) {
        self.log.lock().unwrap().push(format!("item {name}"));
    }
    fn advance(&self, n: u64) {
        self.advanced
            .fetch_add(n, std::sync::atomic::Ordering::SeqCst);
    }
    fn finish(&self) {
        let n = self.advanced.load(std::sync::atomic::Ordering::SeqCst);
        self.log.lock().unwrap().push(format!("finish after {n}"));
    }
}

#[test]
fn session_run_reports_the_rays_the_thermal_passes_and_every_row_to_its_observer() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), 8, 6, 1);
    let mut session = Session::open(&scene, Backend::Embree).unwrap();
    let facets = session.scene.geometry.facet_count();
    let calls = Arc::new(Calls::default());
    let times = ["2025-06-21T14:00:00-04:00", "2025-06-21T15:00:00-04:00"]
        .map(|t| irsig::sun::parse_time(t).unwrap());
    let options = RunOptions {
        times: times.to_vec(),
        progress: Some(calls.clone()),
        ..RunOptions::default()
    };
    let stems = session.run(&dir.path().join("out"), &options).unwrap();
    assert_eq!(stems, ["cam_20250621T140000", "cam_20250621T150000"]);
    let log = calls.log.lock().unwrap().clone();
    assert_eq!(
        log,
        [
            format!("start Exposure {}", 2 * facets),
            "item solar history and sky view".to_string(),
            "item ground test".to_string(),
            format!("finish after {}", 2 * facets),
            format!("start Thermal {facets}"),
            "item reflected shortwave".to_string(),
            "item thermal solve".to_string(),
            format!("finish after {facets}"),
            "start Rows 12".to_string(),
            "item cam_20250621T140000".to_string(),
            "item cam_20250621T150000".to_string(),
            "finish after 12".to_string(),
        ]
    );
    // An unknown sensor is named by the library's field, not a flag.
    let options = RunOptions {
        sensors: vec!["nope".into()],
        ..RunOptions::default()
    };
    let e = session.run(&dir.path().join("out"), &options).unwrap_err();
    assert!(
        matches!(&e, irsig::Error::Invalid { field, .. } if field == "sensor"),
        "{e}"
    );
}

#[test]
fn opening_a_session_reports_loading_and_the_bvh_to_its_observer() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), 8, 6, 1);
    let calls = Calls::default();
    Session::open_observed(&scene, Backend::Embree, &calls).unwrap();
    let log = calls.log.lock().unwrap().clone();
    assert_eq!(
        log,
        [
            "start Load 0",
            "finish after 0",
            "start Bvh 0",
            "finish after 0"
        ]
    );
    // A scene that cannot load still finishes its stage.
    let calls = Calls::default();
    assert!(
        Session::open_observed(&dir.path().join("none.json"), Backend::Embree, &calls).is_err()
    );
    assert_eq!(
        calls.log.lock().unwrap().clone(),
        ["start Load 0", "finish after 0"]
    );
}

#[test]
fn slurm_script_submits_a_tile_array_and_a_dependent_merge() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), 8, 6, 1);
    // A stand-in `sbatch` recording its arguments.
    let bin = dir.path().join("bin");
    std::fs::create_dir(&bin).unwrap();
    let log = dir.path().join("sbatch.log");
    let fake = format!(
        "#!/bin/sh\necho \"$@\" >> {}\nn=$(wc -l < {})\necho \"$((1000 + n))\"\n",
        log.display(),
        log.display()
    );
    let sb = bin.join("sbatch");
    std::fs::write(&sb, fake).unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&sb, std::fs::Permissions::from_mode(0o755)).unwrap();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap());
    let out = Command::new("bash")
        .arg(repo_path("scripts/slurm-render.sh"))
        .args([
            s(&scene),
            s(&dir.path().join("out")),
            "4",
            "--seed",
            "3",
            "--times",
            "2025-06-21T15:00:00-04:00",
        ])
        .env("PATH", path)
        .env("IRSIG", irsig_bin())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let calls = std::fs::read_to_string(&log).unwrap();
    let lines: Vec<&str> = calls.lines().collect();
    assert_eq!(lines.len(), 4, "{calls}");
    // Pass 1: four shards of the rays; the render-only --seed stays out,
    // --times goes to every step.
    assert!(lines[0].contains("--array=1-4"), "{}", lines[0]);
    assert!(
        lines[0].contains("thermal-scene")
            && lines[0].contains("--pass 1 --shard ${SLURM_ARRAY_TASK_ID}/4"),
        "{}",
        lines[0]
    );
    assert!(!lines[0].contains("--dependency"), "{}", lines[0]);
    assert!(!lines[0].contains("--seed"), "{}", lines[0]);
    assert!(
        lines[0].contains("--times 2025-06-21T15:00:00-04:00"),
        "{}",
        lines[0]
    );
    // Pass 2 after every pass-1 task.
    assert!(lines[1].contains("--array=1-1"), "{}", lines[1]);
    assert!(
        lines[1].contains("--dependency=afterok:1001"),
        "{}",
        lines[1]
    );
    assert!(
        lines[1].contains("--pass 2 --shard ${SLURM_ARRAY_TASK_ID}/1"),
        "{}",
        lines[1]
    );
    // The tiles from the state, after pass 2.
    assert!(lines[2].contains("--array=1-4"), "{}", lines[2]);
    assert!(
        lines[2].contains("--dependency=afterok:1002"),
        "{}",
        lines[2]
    );
    assert!(
        lines[2].contains(" render ")
            && lines[2].contains("--state ")
            && lines[2].contains("--tile ${SLURM_ARRAY_TASK_ID}/4"),
        "{}",
        lines[2]
    );
    assert!(lines[2].contains("--seed 3"), "{}", lines[2]);
    // The merge after every tile.
    assert!(!lines[3].contains("--array"), "{}", lines[3]);
    assert!(
        lines[3].contains("--dependency=afterok:1003"),
        "{}",
        lines[3]
    );
    assert!(lines[3].contains(" merge "), "{}", lines[3]);
}

#[test]
fn cli_bench_render_reports_every_stage_and_the_bare_trace() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), 16, 12, 2);
    let out = irsig(&["bench", "render", s(&scene), "--json"]);
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["sensor"], "cam");
    assert_eq!(r["backend"], "embree");
    // Every pixel's N² sub-pixel rays, and the bare trace traced the same number.
    assert_eq!(r["primary_rays"], 16 * 12 * 4);
    let num = |k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k} missing: {r}"));
    let stages = [
        "load_s",
        "bvh_build_s",
        "rays_thermal_s",
        "radiometry_setup_s",
        "ray_generation_s",
        "primary_trace_s",
        "radiometry_s",
        "secondary_s",
        "sensor_s",
        "output_s",
    ];
    for k in stages {
        assert!(num(k) >= 0.0, "{k} = {}", num(k));
    }
    let sum: f64 = stages.iter().map(|k| num(k)).sum();
    assert!((sum - num("total_s")).abs() < 1e-6 * sum.max(1.0), "{r}");
    // The thermal passes are part of the per-facet stage, and took time.
    let solve = num("thermal_solve_s");
    assert!(solve > 0.0 && solve <= num("rays_thermal_s"), "{r}");
    assert!(num("bare_trace_s") > 0.0 && num("facets") > 0.0, "{r}");
    let pipeline =
        num("ray_generation_s") + num("primary_trace_s") + num("radiometry_s") + num("sensor_s");
    let ratio = num("pipeline_over_bare");
    assert!((ratio - pipeline / num("bare_trace_s")).abs() <= 1e-9 * ratio.max(1.0));
    let given = (pipeline - num("ray_generation_s")) / num("bare_trace_s");
    assert!((num("given_rays_over_bare") - given).abs() <= 1e-9 * given.max(1.0));
    let with = (pipeline + num("secondary_s")) / num("bare_trace_s");
    assert!((num("with_secondary_over_bare") - with).abs() <= 1e-9 * with.max(1.0));
    assert!(num("secondary_hits") <= num("primary_rays"), "{r}");
    // Outputs go to a temporary folder, not next to the scene.
    assert!(!dir.path().join("cam.exr").exists());

    let bad = Command::new(irsig_bin())
        .args(["bench", "render", s(&scene), "--sensor", "nope"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        !bad.status.success() && err.contains("nope") && err.contains("cam"),
        "{err}"
    );
}

/// A spectral, angle-dependent emissivity: rows at 0°, 40°, 70°, 90°
/// over 3–14 µm, falling with angle and with structure in both bands.
fn spectral_material(name: &str, id: u32, scale: f64) -> Material {
    use irsig::material::EmissivityCurve;
    let wl = vec![3.0, 3.7, 4.4, 5.0, 8.0, 9.2, 10.5, 12.0, 14.0];
    let normal = [0.82, 0.90, 0.75, 0.93, 0.96, 0.70, 0.91, 0.97, 0.94];
    let angles = vec![0.0, 40.0, 70.0, 90.0];
    let fall = [1.0, 0.97, 0.8, 0.0];
    let mut m = material(name, id, 0.9, 0.0);
    m.emissivity_curve = Some(EmissivityCurve {
        wavelengths_um: wl,
        emissivity: fall
            .iter()
            .map(|f| normal.iter().map(|e| e * f * scale).collect())
            .collect(),
        angles_deg: angles,
    });
    m
}

#[test]
fn fast_radiometry_matches_the_spectral_reference_on_every_hit() {
    use irsig::atmosphere::{BuiltinAtmosphere, SkyConditions, SurfaceMet};
    use irsig::render::FastMiss;
    use irsig::render::path::PathTables;
    use irsig::trace::{Coherence, Ray};
    // Ground, tilted panels at many view angles, a double-sided fin seen
    // from both faces.
    let mut meshes = vec![ground("ground", 0.0, 0.0, 200.0, 0.0)];
    for i in 0..8 {
        let x = -70.0 + 20.0 * i as f32;
        let tilt = 10.0 * i as f32;
        let (s, c) = tilt.to_radians().sin_cos();
        meshes.push(quad(
            &format!("panel{i}"),
            [
                Vec3::new(x - 6.0, -6.0 * c, 6.0 + 6.0 * s),
                Vec3::new(x + 6.0, -6.0 * c, 6.0 + 6.0 * s),
                Vec3::new(x + 6.0, 6.0 * c, 6.0 - 6.0 * s),
                Vec3::new(x - 6.0, 6.0 * c, 6.0 - 6.0 * s),
            ],
        ));
    }
    meshes.push(quad(
        "fin",
        [
            Vec3::new(-30.0, 40.0, 0.0),
            Vec3::new(30.0, 40.0, 0.0),
            Vec3::new(30.0, 40.0, 25.0),
            Vec3::new(-30.0, 40.0, 25.0),
        ],
    ));
    let geom = geometry(meshes);
    // Spectral + angular; spectral normal-only (Fresnel fall-off); grey,
    // specular and transmissive, double-sided.
    let mut fresnel = spectral_material("fresnel", 2, 0.95);
    if let Some(c) = &mut fresnel.emissivity_curve {
        c.emissivity.truncate(1);
        c.angles_deg.clear();
    }
    let mut window = material("window", 3, 0.6, 0.4);
    window.transmissivity = 0.25;
    window.double_sided = true;
    let mats = vec![
        spectral_material("paint", 1, 1.0),
        fresnel,
        window,
        material("soil", 4, 0.93, 0.0),
    ];
    let mm = [3, 1, 0, 1, 2, 0, 3, 0, 1, 2];
    let optics = optics(&geom, mats, &mm);
    let mut surface = state(
        &geom,
        &[
            292.0, 301.5, 318.2, 276.9, 333.3, 299.9, 288.1, 310.7, 305.0, 340.2,
        ],
    );
    for (i, f) in (0..surface.len()).zip(0..) {
        surface.shape_factor[i] = 0.4 + 0.06 * (f % 10) as f32;
        surface.sun_fraction[i] = if f % 3 == 0 { 0.0 } else { 0.7 };
        surface.cos_sun[i] = 0.2 + 0.07 * (f % 11) as f32;
        surface.background_k[i] = 280.0 + 2.5 * (f % 13) as f32;
    }
    let met = SurfaceMet {
        air_temperature_k: 296.0,
        relative_humidity: 0.7,
        pressure_pa: 100_500.0,
        ground_altitude_m: 150.0,
    };
    let atmosphere = Atmosphere::Builtin(BuiltinAtmosphere::new(met).unwrap());
    let cond = Conditions {
        surface,
        sky: Sky::Atmosphere(SkyConditions {
            air_temperature_k: 296.0,
            sky_longwave_w_m2: 360.0,
        }),
        sun: Some(SunInput {
            direction: Vec3::new(0.4, -0.3, 0.85).normalize(),
            direct_normal_w_m2: 800.0,
        }),
        ground_temperature_k: 290.0,
        atmosphere,
        per_hit: None,
        wind_speed_m_s: 0.0,
    };
    let s = sensor(
        json!({"type": "frame", "name": "cam", "width": 64, "height": 48,
           "fov_deg": 70.0, "position": [20.0, -160.0, 90.0], "look_at": [0.0, 10.0, 0.0],
           "up": [0.0, 0.0, 1.0], "oversample": 2,
           "bands": [{"name": "LWIR", "response": [8.0, 12.0]},
                     {"name": "MWIR", "response": [3.0, 5.0]}]}),
    );
    let bands = sensor_bands(&s, std::path::Path::new("."), 0.1, &Location::file("t")).unwrap();
    // As a render builds them: by day, with the scattered sunlight.
    let sun = irsig::render::path::PathSun::for_scene(cond.sun.as_ref());
    let paths = PathTables::new(
        &cond.atmosphere,
        &s,
        &bands,
        150.0,
        400.0,
        (0.0, 30.0),
        sun.as_ref(),
    )
    .unwrap()
    .expect("a path atmosphere");
    let tracer = trace::build(&geom, Backend::Embree).unwrap();
    let mut rays: Vec<Ray> = Vec::new();
    for row in 0..s.height() {
        s.rays_for_row(row, &mut rays);
    }
    let hits = trace::intersect_all(tracer.as_ref(), &rays, Coherence::Coherent);
    // With and without the sensor path (grey materials take per-facet
    // terms without it), with and without secondary rays.
    for (bounces, path) in [(0, true), (2, true), (0, false), (2, false)] {
        let opts = ShadeOptions {
            max_bounces: bounces,
            offset_m: 1e-3,
        };
        let shader = Shader::new(tracer.as_ref(), &geom, &optics, &cond, &bands, opts)
            .unwrap()
            .with_path(path.then(|| paths.clone()));
        let nl = shader.spectrum_len();
        let mut spectra = vec![0.0; rays.len() * nl];
        shader.shade_primary(&rays, &hits, &mut spectra);
        let (mut fast, mut secondary, mut misses, mut glint) = (0, 0, 0, 0);
        let mut worst = 0.0f64;
        let mut out = [0f32; 2];
        let mut angles = std::collections::BTreeSet::new();
        for (i, (ray, hit)) in rays.iter().zip(&hits).enumerate() {
            match hit {
                None => {
                    shader.fast_miss(ray, &mut out);
                    misses += 1;
                }
                Some(h) => match shader.fast_primary(ray, h, &mut out) {
                    Ok(()) => {
                        fast += 1;
                        let n = h.ng.normalize();
                        angles.insert((ray.dir.dot(n).abs().acos().to_degrees() / 10.0) as u32);
                    }
                    Err(FastMiss::Secondary) => {
                        secondary += 1;
                        continue;
                    }
                    Err(FastMiss::Glint) => {
                        glint += 1;
                        continue;
                    }
                    Err(e) => panic!("ray {i}: {e:?}"),
                },
            }
            for (b, &v) in out.iter().enumerate() {
                let r = shader.band_radiance(b, &spectra[i * nl..(i + 1) * nl]);
                assert!(r > 0.0);
                let rel = (v as f64 - r).abs() / r;
                worst = worst.max(rel);
                assert!(rel <= 1e-5, "ray {i} band {b}: fast {v}, reference {r}");
            }
        }
        // The batched form (what the renderer runs on each row) gives the
        // same values bit for bit and leaves the same hits to the reference.
        let nb = shader.band_count();
        let mut batch = vec![0f32; nb * rays.len()];
        let mut slow = Vec::new();
        // Truth of every third ray from ray 1, written as the batch is read.
        let cols = (rays.len() - 1).div_ceil(3);
        let mut truth = vec![vec![f32::NAN; cols]; irsig::render::TRUTH_LAYERS.len()];
        let mut layers: Vec<&mut [f32]> = truth.iter_mut().map(|v| v.as_mut_slice()).collect();
        shader.shade_fast(
            &rays,
            &hits,
            &mut batch,
            &mut slow,
            &mut irsig::render::FastScratch::default(),
            Some(irsig::render::TruthOut {
                first: 1,
                stride: 3,
                layers: &mut layers,
            }),
        );
        assert_eq!(slow.len(), secondary + glint);
        for c in 0..cols {
            let i = 1 + 3 * c;
            let want = match &hits[i] {
                None => irsig::render::MISS_TRUTH,
                Some(h) => shader.truth_of(&rays[i], h),
            };
            for (l, w) in truth.iter().zip(want) {
                assert_eq!(l[c].to_bits(), w.to_bits(), "truth of ray {i}");
            }
        }
        for (i, (ray, hit)) in rays.iter().zip(&hits).enumerate() {
            if slow.contains(&i) {
                continue;
            }
            match hit {
                None => shader.fast_miss(ray, &mut out),
                Some(h) => shader.fast_primary(ray, h, &mut out).unwrap(),
            }
            for (b, &v) in out.iter().enumerate() {
                assert_eq!(
                    batch[b * rays.len() + i].to_bits(),
                    v.to_bits(),
                    "ray {i} band {b}"
                );
            }
        }
        // Every kind of hit was compared: fast hits over many view angles
        // (the fin and window are specular only when bounces remain).
        assert!(fast > 4000 && misses > 0, "{fast} fast, {misses} misses");
        assert!(angles.len() >= 6, "view angles (10° bins) {angles:?}");
        // (Without bounces the window still glints: the reference.)
        if bounces == 0 {
            assert_eq!(secondary, 0);
            assert!(glint > 100, "{glint}");
        } else {
            assert!(secondary > 100, "{secondary}");
        }
        eprintln!("max bounces {bounces}, path {path}: worst relative difference {worst:.2e}");
    }
}

#[test]
fn tabulated_apparent_temperatures_match_the_exact_inversion() {
    use irsig::render::image::{apparent_temperature, apparent_temperatures};
    // Radiances of 200–400 K blackbodies in an MWIR and an LWIR band, plus
    // values in between, against the exact per-pixel inversion.
    // 200–400 K (radiances over decades: Hermite per pixel) and 270–330 K
    // (a scene's range: the uniform radiance table).
    for (band, t0, dt) in [
        (Band::flat(3.0, 5.0, 0.1).unwrap(), 200.0, 0.05),
        (Band::flat(8.0, 14.0, 0.1).unwrap(), 200.0, 0.05),
        (Band::flat(3.0, 5.0, 0.1).unwrap(), 270.0, 0.015),
        (Band::flat(8.0, 14.0, 0.1).unwrap(), 270.0, 0.015),
    ] {
        let radiance: Vec<f32> = (0..4000)
            .map(|i| band.blackbody_radiance(t0 + dt * i as f64 + 0.0123) as f32)
            .chain([0.0, -1.0, f32::NAN])
            .collect();
        let t = apparent_temperatures(&band, &radiance);
        let mut worst = 0.0f32;
        for (&l, &ti) in radiance.iter().zip(&t) {
            let exact = apparent_temperature(&band, l);
            worst = worst.max((ti - exact).abs());
        }
        // f32 resolves 3·10⁻⁵ K at 400 K; the table adds < 10⁻⁶ K.
        eprintln!("worst difference from the exact inversion: {worst} K");
        assert!(worst < 1e-4, "worst {worst} K");
        assert_eq!(&t[4000..], &[0.0, 0.0, 0.0]);
    }
}

#[test]
fn row_bands_refuse_a_non_finite_value_and_name_the_layer_row_and_column() {
    use irsig::render::{RowBand, TRUTH_LAYERS};
    let s = sensor(nadir_camera(8, 6, 20.0, 1));
    let bands = sensor_bands(&s, std::path::Path::new("."), 0.1, &Location::file("t")).unwrap();
    let radiance = vec![vec![9.0f32; 8 * 4]; bands.len()];
    let mut truth = vec![vec![0.0f32; 8 * 4]; TRUTH_LAYERS.len()];
    let make = |r: &Vec<Vec<f32>>, t: &Vec<Vec<f32>>| {
        RowBand::new("tile.exr", 8, 6, 2..6, r.clone(), t.clone())
    };
    let ok = make(&radiance, &truth).unwrap();
    assert_eq!((ok.width(), ok.height(), ok.rows()), (8, 6, 2..6));
    // Rows 2..6: index 3·8 + 7 is image row 5, column 7.
    truth[5][3 * 8 + 7] = f32::INFINITY;
    let e = make(&radiance, &truth).unwrap_err().to_string();
    assert!(
        e.contains("tile.exr") && e.contains("`depth`") && e.contains("inf"),
        "{e}"
    );
    assert!(e.contains("row 5") && e.contains("column 7"), "{e}");
    truth[5][3 * 8 + 7] = 0.0;
    let mut bad = radiance.clone();
    bad[0][9] = f32::NAN;
    let e = make(&bad, &truth).unwrap_err().to_string();
    assert!(
        e.contains("radiance") && e.contains("NaN") && e.contains("row 3"),
        "{e}"
    );
    // Wrong sizes are refused too.
    bad[0] = vec![9.0; 31];
    let e = make(&bad, &truth).unwrap_err().to_string();
    assert!(e.contains("31 values") && e.contains("expected 32"), "{e}");
    assert!(RowBand::new("t", 8, 6, 2..6, radiance, truth[..5].to_vec()).is_err());
    // A finished image of a finite band is finite in every layer.
    let full = RowBand::new(
        "t",
        8,
        6,
        0..6,
        vec![vec![9.0; 48]; bands.len()],
        vec![vec![0.0; 48]; TRUTH_LAYERS.len()],
    )
    .unwrap();
    let f = finish(full, &s, &bands, 1).unwrap();
    for l in &f.stack.layers {
        assert!(l.data.iter().all(|v| v.is_finite()), "{}", l.name);
    }
}

/// Issue 17: a perfect horizontal mirror shows the sky radiance of the
/// mirrored direction (the directional sky of the atmosphere model), not
/// the isotropic sky.
#[test]
fn perfect_mirror_shows_the_sky_of_the_mirrored_direction() {
    use irsig::atmosphere::{Profile, SkyConditions};
    let geom = geometry(vec![ground("mirror", 0.0, 0.0, 5000.0, 0.0)]);
    let optics = optics(&geom, vec![material("mirror", 1, 0.0, 1.0)], &[0]);
    let atmosphere = Atmosphere::standard(Profile::MidLatitudeSummer, 0.0).unwrap();
    let sky_c = SkyConditions {
        air_temperature_k: 294.2,
        sky_longwave_w_m2: f64::NAN,
    };
    let cond = Conditions {
        surface: state(&geom, &[300.0]),
        sky: Sky::Atmosphere(sky_c),
        sun: None,
        ground_temperature_k: 294.2,
        atmosphere: atmosphere.clone(),
        per_hit: None,
        wind_speed_m_s: 0.0,
    };
    for zenith in [20.0f64, 45.0, 70.0] {
        // A narrow camera looking down at the origin from `zenith`.
        let (s, c) = zenith.to_radians().sin_cos();
        let cam = json!({"type": "frame", "name": "cam", "width": 3, "height": 3,
            "fov_deg": 0.05, "position": [0.0, -100.0 * s, 100.0 * c], "look_at": [0.0, 0.0, 0.0],
            "up": [0.0, 0.0, 1.0], "oversample": 1,
            "bands": [{"name": "LWIR", "response": [8.0, 12.0]}]});
        let (bands, f) = render(&geom, &optics, &cond, &sensor(cam), Backend::Embree);
        let got = layer(&f, "LWIR_radiance")[4] as f64;
        let want = bands[0].integrate(
            &atmosphere
                .sky_radiance_toward(&sky_c, zenith, bands[0].grid())
                .unwrap(),
        );
        let iso = bands[0].integrate(&atmosphere.sky_radiance(&sky_c, bands[0].grid()).unwrap());
        println!("mirror at {zenith}°: {got:.4} W/m²/sr, sky there {want:.4}, isotropic {iso:.4}");
        assert!(
            (got - want).abs() < 0.005 * want,
            "{zenith}°: {got} vs the sky there {want}"
        );
        assert!(
            (want - iso).abs() > 0.02 * iso,
            "{zenith}°: {want} vs {iso}"
        );
    }
}

/// Issue 17: spectral sunlight — the top-of-atmosphere spectrum integrates
/// to the solar constant, and with an atmosphere the sunlight at the ground
/// is that spectrum times τ₁ along the sun's path (nothing inside the CO₂
/// 4.3 µm band), scaled by the weather's DNI over the clear-sky DNI (at most
/// 1); with no
/// atmosphere, the DNI spread as a 5772 K blackbody as before.
#[test]
fn spectral_sunlight_follows_the_sun_path_transmittance() {
    use irsig::atmosphere::Profile;
    use irsig::radiometry::{Planck, SpectralGrid, solar_irradiance_toa};
    use irsig::render::shade::solar_spectrum;
    use irsig::render::{clear_sky_dni_w_m2, surface_solar_spectrum};
    let g = SpectralGrid::uniform(0.1, 200.0, 0.002).unwrap();
    let total = g.integrate(&solar_irradiance_toa(&g, 1.0));
    assert!((total - 1361.0).abs() < 0.005 * 1361.0, "{total} W/m²");

    let zenith = 30f64.to_radians();
    let dni = 0.8 * clear_sky_dni_w_m2(30.0);
    let sun = SunInput {
        direction: Vec3::new(0.0, zenith.sin() as f32, zenith.cos() as f32),
        direct_normal_w_m2: dni,
    };
    let band = Band::flat(3.0, 5.0, 0.01).unwrap();
    let planck = Planck::default();
    let vacuum = surface_solar_spectrum(&Atmosphere::None, &planck, &sun, band.grid()).unwrap();
    assert_eq!(vacuum, solar_spectrum(&planck, band.wavelengths_um(), dni));
    let a = Atmosphere::standard(Profile::MidLatitudeSummer, 0.0).unwrap();
    let s = surface_solar_spectrum(&a, &planck, &sun, band.grid()).unwrap();
    let toa = solar_irradiance_toa(band.grid(), 1.0);
    let d = sun.direction.normalize();
    let tau = a
        .solar_transmittance((d.z as f64).acos().to_degrees(), band.grid())
        .unwrap();
    for (i, &l) in band.wavelengths_um().iter().enumerate() {
        let want = toa[i] * tau[i] * 0.8;
        assert!(
            (s[i] - want).abs() <= 1e-6 * toa[i],
            "{l} µm: {} vs {want}",
            s[i]
        );
        // The band's core (its long-wave wing, 4.35–4.5 µm, is too
        // transparent in the built-in model: docs/physics/atmosphere.md).
        if (4.2..=4.31).contains(&l) {
            assert!(s[i] < 1e-2 * toa[i], "{l} µm: {} inside the CO₂ band", s[i]);
        }
    }
    // In the 3.8 µm window most of the sun gets through.
    let k = band
        .wavelengths_um()
        .iter()
        .position(|&l| l >= 3.8)
        .unwrap();
    assert!(tau[k] > 0.7, "{}", tau[k]);
}

/// A box of half-size `h` (x, y) from the ground to `top`, its five
/// visible faces facing out.
fn tower(h: f32, top: f32) -> Vec<TriangleMesh> {
    let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    vec![
        quad(
            "top",
            [p(-h, -h, top), p(h, -h, top), p(h, h, top), p(-h, h, top)],
        ),
        quad(
            "east",
            [p(h, -h, 0.0), p(h, h, 0.0), p(h, h, top), p(h, -h, top)],
        ),
        quad(
            "west",
            [p(-h, h, 0.0), p(-h, -h, 0.0), p(-h, -h, top), p(-h, h, top)],
        ),
        quad(
            "north",
            [p(h, h, 0.0), p(-h, h, 0.0), p(-h, h, top), p(h, h, top)],
        ),
        quad(
            "south",
            [p(-h, -h, 0.0), p(h, -h, 0.0), p(h, -h, top), p(-h, -h, top)],
        ),
    ]
}

#[test]
fn a_shadowed_point_reflects_no_sun_and_a_lit_one_all_of_it() {
    use irsig::trace::{Coherence, Ray};
    // A 40 m tower on a ground of ε = 0.5 (r = 0.5: the reflected sun is a
    // large part of its MWIR radiance), the sun 45° up in the east: the
    // tower's shadow covers x ∈ (−45, −5), |y| < 5. The ground facets'
    // sample points disagree (sunlit fraction 0.5), so each hit traces its
    // own shadow ray: a point in the shadow sees no sun (the render without
    // sun), one outside it all of it (the ground at fraction 1) — not half.
    let mut meshes = vec![ground("ground", 0.0, 0.0, 200.0, 0.0)];
    meshes.extend(tower(5.0, 40.0));
    let geom = geometry(meshes);
    let optics = optics(
        &geom,
        vec![
            material("ground", 1, 0.5, 0.0),
            material("tower", 2, 0.9, 0.0),
        ],
        &[0, 1, 1, 1, 1, 1],
    );
    let sun_dir = Vec3::new(1.0, 0.0, 1.0).normalize();
    let conditions = |fraction: f32, sun: bool| {
        let mut surface = state(&geom, &[305.0, 300.0, 300.0, 300.0, 300.0, 300.0]);
        for f in 0..2 {
            surface.sun_fraction[f] = fraction;
            surface.cos_sun[f] = sun_dir.z;
        }
        surface.background_k.fill(290.0);
        Conditions {
            surface,
            sky: Sky::Blackbody {
                temperature_k: 250.0,
            },
            sun: sun.then_some(SunInput {
                direction: sun_dir,
                direct_normal_w_m2: 800.0,
            }),
            ground_temperature_k: 290.0,
            atmosphere: Atmosphere::None,
            per_hit: None,
            wind_speed_m_s: 0.0,
        }
    };
    let s = sensor(nadir_camera(8, 8, 10.0, 1));
    let bands = sensor_bands(&s, std::path::Path::new("."), 0.1, &Location::file("t")).unwrap();
    let tracer = trace::build(&geom, Backend::Embree).unwrap();
    // Straight down onto the shadow (x = −25) and the lit ground (x = 25).
    let rays = [
        Ray::new(Vec3::new(-25.0, 0.0, 100.0), Vec3::NEG_Z),
        Ray::new(Vec3::new(25.0, 0.0, 100.0), Vec3::NEG_Z),
    ];
    let hits = trace::intersect_all(tracer.as_ref(), &rays, Coherence::Coherent);
    // Band radiances of both rays by the fast path and by the spectral
    // reference (they must agree), and the sun-fraction truth.
    let radiance = |c: &Conditions| -> Vec<[f64; 2]> {
        let shader = Shader::new(tracer.as_ref(), &geom, &optics, c, &bands, OPTS).unwrap();
        let nl = shader.spectrum_len();
        let mut spectra = vec![0.0; rays.len() * nl];
        shader.shade_primary(&rays, &hits, &mut spectra);
        (0..rays.len())
            .map(|i| {
                let h = hits[i].expect("the ground");
                let mut fast = [0f32; 2];
                shader.fast_primary(&rays[i], &h, &mut fast).unwrap();
                let mut v = [0.0; 2];
                for (b, v) in v.iter_mut().enumerate() {
                    *v = shader.band_radiance(b, &spectra[i * nl..(i + 1) * nl]);
                    let rel = (fast[b] as f64 - *v).abs() / *v;
                    assert!(rel < 1e-5, "ray {i} band {b}: fast {} vs {v}", fast[b]);
                }
                v
            })
            .collect()
    };
    let half = radiance(&conditions(0.5, true));
    let dark = radiance(&conditions(0.5, false));
    let full = radiance(&conditions(1.0, true));
    for b in 0..2 {
        let rel = |x: f64, y: f64| (x - y).abs() / y;
        assert!(
            rel(half[0][b], dark[0][b]) < 1e-9,
            "band {b}: shadowed point {} vs no sun {}",
            half[0][b],
            dark[0][b]
        );
        assert!(
            rel(half[1][b], full[1][b]) < 1e-9,
            "band {b}: lit point {} vs full sun {}",
            half[1][b],
            full[1][b]
        );
    }
    // The sun's term is large in the MWIR: the checks above can fail.
    assert!(
        half[1][1] > 1.2 * dark[1][1],
        "{:?} vs {:?}",
        half[1],
        dark[1]
    );
    // The truth layer reports the points' own visibility.
    let c = conditions(0.5, true);
    let shader = Shader::new(tracer.as_ref(), &geom, &optics, &c, &bands, OPTS).unwrap();
    assert_eq!(shader.truth_of(&rays[0], &hits[0].unwrap())[4], 0.0);
    assert_eq!(shader.truth_of(&rays[1], &hits[1].unwrap())[4], 1.0);
}

#[test]
fn glint_on_a_water_plane_lies_in_the_mirror_direction_of_the_computed_sun() {
    use irsig::material::SurfaceEnergySpec;
    use irsig::render::glint::{SUN_ANGULAR_RADIUS_RAD, cox_munk_slope_variance};
    use irsig::sun::{Site, parse_time, position_standard};
    use irsig::trace::{Coherence, Ray};
    // The sun of a June morning in Colorado (NREL SPA), a calm pond (ε 0.9
    // at normal view, all of its reflection specular) at 295 K under a
    // 250 K sky, a camera 100 m up looking near the mirror point.
    let site = Site::new(40.0, -105.0, 1600.0).unwrap();
    let time = parse_time("2024-06-21T09:30:00-06:00").unwrap();
    let sun = position_standard(&site, time).unwrap();
    let sd = sun.direction_enu().as_vec3();
    assert!(sd.z > 0.3, "sun up: {sd}");
    let mut water = material("water", 5, 0.9, 1.0);
    water.surface_energy = Some(serde_json::from_value(json!({"kind": "water"})).unwrap());
    let _: &Option<SurfaceEnergySpec> = &water.surface_energy;
    let geom = geometry(vec![ground("pond", 0.0, 0.0, 5000.0, 0.0)]);
    let optics = optics(&geom, vec![water], &[0]);
    let cond = Conditions {
        surface: state(&geom, &[295.0]),
        sky: Sky::Blackbody {
            temperature_k: 250.0,
        },
        sun: Some(SunInput {
            direction: sd,
            direct_normal_w_m2: 800.0,
        }),
        ground_temperature_k: 290.0,
        atmosphere: Atmosphere::None,
        per_hit: None,
        wind_speed_m_s: 0.0,
    };
    // The mirror point: where the view direction is the sun's reflected
    // about the vertical.
    let cam = Vec3::new(0.0, 0.0, 100.0);
    let v = Vec3::new(-sd.x, -sd.y, sd.z);
    let p = cam - v * (cam.z / v.z);
    // Look off the mirror point so the glint is not simply the centre.
    let look = p + Vec3::new(12.0, -8.0, 0.0);
    let s = sensor(
        json!({"type": "frame", "name": "cam", "width": 64, "height": 48,
        "fov_deg": 40.0, "position": [cam.x, cam.y, cam.z], "look_at": [look.x, look.y, 0.0],
        "up": [0.0, 0.0, 1.0], "oversample": 1,
        "bands": [{"name": "MWIR", "response": [3.0, 5.0]}]}),
    );
    let (bands, f) = render(&geom, &optics, &cond, &s, Backend::Embree);
    let img = layer(&f, "MWIR_radiance");
    let (w, h) = (s.width(), s.height());
    let brightest = (0..w * h)
        .max_by(|&a, &b| img[a].total_cmp(&img[b]))
        .unwrap();
    // The pixel whose centre ray meets the plane nearest the mirror point.
    let mut rays = Vec::new();
    let mut best = (f32::INFINITY, 0);
    for row in 0..h {
        s.rays_for_row(row, &mut rays);
        for (col, r) in rays.iter().enumerate() {
            if r.dir.z < 0.0 {
                let q = r.origin + r.dir * (-r.origin.z / r.dir.z);
                let d = (q - p).length();
                if d < best.0 {
                    best = (d, row * w + col);
                }
            }
        }
        rays.clear();
    }
    let (bc, br) = (brightest % w, brightest / w);
    let (ec, er) = (best.1 % w, best.1 / w);
    assert!(
        bc.abs_diff(ec) <= 1 && br.abs_diff(er) <= 1,
        "brightest pixel ({bc}, {br}), mirror point at ({ec}, {er})"
    );
    assert!((ec, er) != (w / 2, h / 2), "the mirror point is off centre");
    let mut sorted = img.to_vec();
    sorted.sort_by(f32::total_cmp);
    assert!(
        img[brightest] > 3.0 * sorted[sorted.len() / 2],
        "a bright glint"
    );

    // Its size: at the mirror point L = ε B(T) + (1 − ε)[L_sky + E_s·D/(4 cos θ_o)]
    // with D = 1/(π m²) (h = n), m² Cox–Munk's calm sea plus the sun's disc.
    let tracer = trace::build(&geom, Backend::Embree).unwrap();
    let shader = Shader::new(tracer.as_ref(), &geom, &optics, &cond, &bands, OPTS).unwrap();
    let ray = [Ray::new(cam, (p - cam).normalize())];
    let hit = trace::intersect_all(tracer.as_ref(), &ray, Coherence::Coherent);
    let mut spectrum = vec![0.0; shader.spectrum_len()];
    shader.shade_primary(&ray, &hit, &mut spectrum);
    let got = shader.band_radiance(0, &spectrum);
    let band = &bands[0];
    let cos_o = v.z as f64;
    let eps = Emissivity::from_material(&optics.materials[0])
        .unwrap()
        .eval(4.0, cos_o.acos().to_degrees());
    let m2 = cox_munk_slope_variance(0.0) + SUN_ANGULAR_RADIUS_RAD.powi(2) / 8.0;
    let lobe = 1.0 / (std::f64::consts::PI * m2 * 4.0 * cos_o);
    let sigma = 5.670374419e-8;
    let e_sun =
        800.0 * std::f64::consts::PI * band.blackbody_radiance(5772.0) / (sigma * 5772f64.powi(4));
    let expected = eps * band.blackbody_radiance(295.0)
        + (1.0 - eps) * (band.blackbody_radiance(250.0) + e_sun * lobe);
    let rel = (got - expected).abs() / expected;
    assert!(rel < 1e-3, "glint {got} vs {expected} W/m²/sr");
}

/// Issue 17: each pixel adds the sunlight scattered into its own path at
/// its own scattering angle. An oblique camera 1500 m up over a 100°-wide
/// field of view, 3.5–4.5 µm, rural aerosol, the sun 40° from the zenith:
/// rays toward and away from the sun's azimuth at the same zenith see very
/// different scattered sunlight, and the table's value at each ray's
/// (range, height, Θ) is the exact single-scattering integral of that
/// path (`Atmosphere::scattered_solar` with the ray's own relative
/// azimuth) within the tabulation's error.
#[test]
fn each_pixel_adds_the_scattered_sunlight_of_its_own_scattering_angle() {
    use irsig::atmosphere::{PathGeometry, Profile, Sun};
    use irsig::render::path::{PathSun, PathTables};
    let atmosphere = Atmosphere::standard(Profile::MidLatitudeSummer, 0.0).unwrap();
    let s = sensor(
        json!({"type": "frame", "name": "cam", "width": 16, "height": 16,
        "fov_deg": 100.0, "position": [0.0, -1500.0, 1500.0], "look_at": [0.0, 0.0, 0.0],
        "up": [0.0, 0.0, 1.0], "bands": [{"name": "MWIR", "response": [3.5, 4.5]}]}),
    );
    let bands = sensor_bands(&s, std::path::Path::new("."), 0.1, &Location::file("t")).unwrap();
    let band = &bands[0];
    // The sun 40° from the zenith toward the south-east (azimuth 135°).
    let (sz, saz) = (40f64.to_radians(), 135f64.to_radians());
    let dir = glam::DVec3::new(sz.sin() * saz.sin(), sz.sin() * saz.cos(), sz.cos());
    let path_sun = PathSun::new(dir).unwrap();
    let t = PathTables::new(
        &atmosphere,
        &s,
        &bands,
        0.0,
        2000.0,
        (0.0, 40.0),
        Some(&path_sun),
    )
    .unwrap()
    .expect("a path atmosphere");
    let sc = t.scatter.as_ref().expect("scattered sunlight by day");
    let sensor_at = glam::DVec3::new(0.0, -1500.0, 1500.0);
    // Targets over the frame, on the ground and on roofs.
    let mut worst = 0.0f64;
    let mut by_target = Vec::new();
    for (x, y, z) in [
        (-1500.0, 0.0, 0.0),
        (1500.0, 0.0, 0.0),
        (-700.0, -900.0, 20.0),
        (700.0, -900.0, 20.0),
        (0.0, 300.0, 33.0),
        (1200.0, 900.0, 7.0),
        (-1200.0, 900.0, 7.0),
        (0.0, -1200.0, 0.0),
    ] {
        let target = glam::DVec3::new(x, y, z);
        let d = target - sensor_at;
        let range = d.length();
        let cos = sc.cos_theta(d.to_array());
        let (_, total) = t.at(0, range, z, cos);
        let (_, thermal) = {
            let night = PathTables {
                scatter: None,
                ..t.clone()
            };
            night.at(0, range, z, cos)
        };
        let table = band.integrate(&total) - band.integrate(&thermal);
        // The exact integral along this ray, its relative azimuth its own.
        let rel_az = saz.to_degrees() - d.x.atan2(d.y).to_degrees();
        let sun = Sun::new(40.0, rel_az, 1.0).unwrap();
        let geom = PathGeometry {
            sensor_altitude_m: 1500.0,
            target_altitude_m: z,
            range_m: range,
        };
        let exact = band.integrate(
            &atmosphere
                .scattered_solar(&geom, &sun, band.grid())
                .unwrap(),
        );
        let r = (table - exact).abs() / exact;
        worst = worst.max(r);
        eprintln!(
            "target ({x}, {y}, {z}): Θ {:.1}°, table {table:.5e}, exact {exact:.5e} ({:+.2} %)",
            cos.acos().to_degrees(),
            100.0 * (table / exact - 1.0)
        );
        by_target.push(exact);
        assert!(r < 0.02, "({x}, {y}, {z}): {table} vs {exact}");
    }
    eprintln!("worst relative difference {worst:.2e}");
    // East (toward the sun's side) and west at the same range and zenith:
    // the forward-scattering side is much brighter.
    assert!(by_target[1] > 1.3 * by_target[0], "{by_target:?}");
}

#[test]
fn a_rooftop_gets_the_path_to_its_own_height_as_irsig_atmosphere_prints_it() {
    use irsig::atmosphere::Profile;
    use irsig::render::path::PathTables;
    // A nadir camera 1000 m up (US Standard atmosphere, 8–12 µm): a roof
    // 50 m up, straight below, is 950 m away; the ground 1000 m.
    let atmosphere = Atmosphere::standard(Profile::UsStandard, 0.0).unwrap();
    let band = Band::flat(8.0, 12.0, irsig::radiometry::DEFAULT_STEP_UM).unwrap();
    let cam = |kind: &str| {
        let mut c = json!({"type": kind, "name": "cam", "width": 16, "height": 16,
            "fov_deg": 20.0, "position": [0.0, 0.0, 1000.0], "look_at": [0.0, 0.0, 0.0],
            "up": [0.0, 1.0, 0.0], "bands": [{"name": "LWIR", "response": [8.0, 12.0]}]});
        if kind == "line_scanner" {
            c = json!({"type": "line_scanner", "name": "scan", "ifov_rad": 0.003,
                "scan_angle_deg": 40.0, "samples_per_line": 16, "lines": 4,
                "scan_rate_hz": 10.0, "altitude_m": 1000.0, "ground_speed_m_s": 50.0,
                "heading_deg": 0.0, "start": [0.0, 0.0], "oversample": 1,
                "bands": [{"name": "LWIR", "response": [8.0, 12.0]}]});
        }
        sensor(c)
    };
    let cli = |target: &str| -> (f64, f64) {
        let out = irsig(&[
            "atmosphere",
            "--profile",
            "us-standard",
            "--band",
            "8-12",
            "--sensor-altitude",
            "1000",
            "--target-altitude",
            target,
            "--zenith",
            "0",
            "--json",
        ]);
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        (
            v["transmittance"].as_f64().unwrap(),
            v["path_radiance_w_m2_sr"].as_f64().unwrap(),
        )
    };
    let (roof_tau, roof_lu) = cli("50");
    let (ground_tau, _) = cli("0");
    assert!(roof_tau > ground_tau, "{roof_tau} vs {ground_tau}");
    for kind in ["frame", "line_scanner"] {
        let s = cam(kind);
        let t = PathTables::new(
            &atmosphere,
            &s,
            std::slice::from_ref(&band),
            0.0,
            300.0,
            (0.0, 60.0),
            None,
        )
        .unwrap()
        .expect("a path atmosphere");
        assert!(t.heights_m.len() >= 3, "{:?}", t.heights_m);
        let (tau, lu) = t.at(0, 950.0, 50.0, 1.0);
        let (tau, lu) = (band.mean(&tau), band.integrate(&lu));
        let rel = |a: f64, b: f64| (a - b).abs() / b;
        assert!(rel(tau, roof_tau) < 1e-3, "{kind}: τ {tau} vs {roof_tau}");
        assert!(rel(lu, roof_lu) < 1e-3, "{kind}: L_u {lu} vs {roof_lu}");
        // The ground below keeps its own (longer, more opaque) path.
        let (g, _) = t.at(0, 1000.0, 0.0, 1.0);
        assert!(rel(band.mean(&g), ground_tau) < 1e-3);
    }
}

/// SplitMix64 (Steele, Lea & Flood 2014): a seeded generator for the
/// random-input comparisons, the same cases on every run.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    fn f(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in 0..n.
    fn u(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    /// A unit vector at most `max_zenith_deg` from +z.
    fn up(&mut self, max_zenith_deg: f64) -> Vec3 {
        let z = self.f(max_zenith_deg.to_radians().cos(), 1.0);
        let phi = self.f(0.0, std::f64::consts::TAU);
        let s = (1.0 - z * z).sqrt();
        Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32)
    }
}

/// Issue 17: the diffusely reflected sky of the renderer — the exact
/// integrals of the directional sky on the tilt nodes, linear between
/// them — is within 10⁻³ of the exact integral at every tilt, in the
/// band, for the built-in model on the six AFGL atmospheres in 8–12 and
/// 3–5 µm; and a wall reflects more sky than a roof in 8–12 µm, where the
/// sky brightens toward the horizon.
#[test]
fn reflected_sky_tilt_table_is_within_1e_3_of_the_integral_for_every_profile() {
    use irsig::atmosphere::{Profile, SkyConditions};
    use irsig::render::shade::{reflected_sky, sky_node_zeniths_deg, sky_tilt_weights};
    let zen = sky_node_zeniths_deg();
    let unscaled = SkyConditions {
        air_temperature_k: f64::NAN,
        sky_longwave_w_m2: f64::NAN,
    };
    let (mut worst, mut at) = (0.0f64, String::new());
    for profile in [
        Profile::Tropical,
        Profile::MidLatitudeSummer,
        Profile::MidLatitudeWinter,
        Profile::SubArcticSummer,
        Profile::SubArcticWinter,
        Profile::UsStandard,
    ] {
        let atm = Atmosphere::standard(profile, 0.0).unwrap();
        for (lwir, band) in [
            (true, Band::flat(8.0, 12.0, 0.05).unwrap()),
            (false, Band::flat(3.0, 5.0, 0.02).unwrap()),
        ] {
            let sky = atm
                .sky_radiances_toward(&unscaled, &zen, band.grid())
                .unwrap();
            let nodes: Vec<f64> = sky.iter().map(|s| band.integrate(s)).collect();
            let exact = |c: f64| -> f64 {
                sky_tilt_weights(c)
                    .iter()
                    .zip(&nodes)
                    .map(|(a, b)| a * b)
                    .sum()
            };
            for i in 0..=400 {
                let c = 1.0 - 2.0 * i as f64 / 400.0;
                let model = band.integrate(&reflected_sky(&sky, c));
                let want = exact(c);
                let rel = (model - want).abs() / want;
                if rel > worst {
                    worst = rel;
                    at = format!(
                        "{profile:?}, {} µm, cos β {c}",
                        band.grid().wavelengths_um()[0]
                    );
                }
            }
            if lwir {
                assert!(
                    exact(0.0) > exact(1.0) * 1.02,
                    "{profile:?}: wall {} roof {}",
                    exact(0.0),
                    exact(1.0)
                );
            }
        }
    }
    eprintln!("reflected sky: worst relative interpolation error {worst:.2e} ({at})");
    assert!(worst <= 1e-3, "worst {worst:.2e} at {at}");
}

/// Issue 17 item 6: every fast path the renderer takes for a primary hit —
/// the grey path with per-facet terms (no sensor path) and with the path
/// tables, the fused single-precision spectral sum, grey integrals in a
/// band where a spectral material is flat — and the spectral path it
/// leaves glint hits to, give the band radiance of the reference big
/// equation ([`irsig::radiometry::leaving_radiance`] with exact Planck
/// radiances, then [`irsig::radiometry::at_sensor`] through the path's
/// τ₂ and L_u at the hit) to 10⁻⁵ relative, on 200 random cases:
/// temperatures, emissivities (grey, spectral, angular), specular and
/// transmitted fractions, one- or two-sided facets, sky, sun and glint,
/// background, shape factor and sunlit fraction, view angles, ranges,
/// heights and random path tables. What the renderer calls is what runs:
/// [`Shader::shade_fast`] on the batch, [`Shader::shade_primary`] and
/// [`Shader::band_radiance`] for the hits it leaves. The one documented
/// approximation the reference is handed is ε linear between the 1° angle
/// rows (exact for curves with knots on whole degrees; see
/// docs/physics/radiometry.md); the tabulated Planck function (≤ 2·10⁻⁶)
/// and single precision (≈ 10⁻⁶) lie inside the tolerance.
#[test]
fn every_fast_path_equals_the_reference_big_equation_on_random_inputs() {
    use irsig::atmosphere::{BuiltinAtmosphere, SkyConditions, SurfaceMet};
    use irsig::material::EmissivityCurve;
    use irsig::radiometry::{Planck, SurfaceInputs, at_sensor, leaving_radiance};
    use irsig::render::glint::{glint_lobe_sr, lobe_slope_variance};
    use irsig::render::path::PathTables;
    use irsig::render::shade::{reflected_sky, sky_node_zeniths_deg};
    use irsig::render::{FastScratch, surface_solar_spectrum};
    use irsig::trace::{Coherence, Ray};
    let mut rng = SplitMix(17);
    let planck = Planck::default();
    let (mut compared, mut fast_hits, mut slow_hits, mut glinting) = (0, 0, 0, 0);
    let mut worst = 0.0f64;
    for case in 0..200 {
        // The material.
        let mut m = material("m", 1, rng.f(0.02, 0.99), 0.0);
        let wl = vec![3.0, 3.6, 4.2, 5.0, 8.0, 9.5, 11.0, 12.5, 14.0];
        match rng.u(4) {
            0 => {} // grey, Fresnel fall-off
            kind => {
                // Spectral: with angles on whole degrees (kind 1), normal
                // only with the Fresnel fall-off (2), or flat in 3–5 µm
                // (3: grey integrals in that band, the fused sum in the other).
                let angles = if kind == 1 {
                    let a = 1 + rng.u(40);
                    vec![0.0, a as f64, (a + 1 + rng.u(40)) as f64, 90.0]
                } else {
                    vec![]
                };
                let rows = angles.len().max(1);
                let flat = rng.f(0.05, 0.99);
                let emissivity = (0..rows)
                    .map(|_| {
                        wl.iter()
                            .map(|&l| {
                                if kind == 3 && l <= 5.0 {
                                    flat
                                } else {
                                    rng.f(0.05, 0.99)
                                }
                            })
                            .collect()
                    })
                    .collect();
                m.emissivity_curve = Some(EmissivityCurve {
                    wavelengths_um: wl.clone(),
                    emissivity,
                    angles_deg: if kind == 3 { vec![] } else { angles },
                });
            }
        }
        if rng.u(2) == 0 {
            m.specular_fraction = rng.f(0.0, 1.0);
        }
        if rng.u(3) == 0 {
            m.transmissivity = rng.f(0.0, 0.5);
        }
        m.double_sided = rng.u(2) == 0;
        // A 20 m square tilted up to 80°, through the origin.
        let n = rng.up(80.0);
        let u = n.cross(Vec3::X).try_normalize().unwrap_or(Vec3::Y);
        let v = n.cross(u);
        let c = [(-10.0, -10.0), (10.0, -10.0), (10.0, 10.0), (-10.0, 10.0)];
        let geom = geometry(vec![quad("q", c.map(|(a, b)| u * a + v * b))]);
        let optics = optics(&geom, vec![m.clone()], &[0]);
        // The sun, the sky, the atmosphere.
        let sun = (rng.u(4) != 0).then(|| SunInput {
            direction: rng.up(85.0),
            direct_normal_w_m2: rng.f(50.0, 1000.0),
        });
        let air = rng.f(250.0, 310.0);
        let atmosphere = if rng.u(2) == 0 {
            Atmosphere::None
        } else {
            Atmosphere::Builtin(
                BuiltinAtmosphere::new(SurfaceMet {
                    air_temperature_k: air,
                    relative_humidity: rng.f(0.1, 0.95),
                    pressure_pa: rng.f(90_000.0, 103_000.0),
                    ground_altitude_m: rng.f(0.0, 1500.0),
                })
                .unwrap(),
            )
        };
        let sky = if rng.u(2) == 0 {
            Sky::Blackbody {
                temperature_k: rng.f(200.0, 290.0),
            }
        } else {
            Sky::Atmosphere(SkyConditions {
                air_temperature_k: air,
                sky_longwave_w_m2: rng.f(200.0, 420.0),
            })
        };
        // The facets' state: cos σ of the front face, sunlit fraction
        // none, all or part.
        let mut surface = SurfaceState::uniform(geom.facet_count(), 300.0);
        let (t_s, t_bg) = (rng.f(230.0, 345.0), rng.f(230.0, 345.0));
        let (big_f, frac) = (rng.f(0.0, 1.0), [0.0, 1.0, rng.f(0.01, 0.99)][rng.u(3)]);
        let cos_sun = sun.map_or(0.0, |s| n.dot(s.direction).max(0.0));
        // A double-sided square's back face with its own sky view (in half
        // of those cases), which its back-face hits reflect.
        let back_f = (m.double_sided && rng.u(2) == 0).then(|| rng.f(0.0, 1.0));
        for f in 0..surface.len() {
            surface.temperature_k[f] = t_s as f32;
            surface.background_k[f] = t_bg as f32;
            surface.shape_factor[f] = big_f as f32;
            surface.back_shape_factor[f] = back_f.map(|b| b as f32);
            surface.sun_fraction[f] = frac as f32;
            surface.cos_sun[f] = cos_sun;
        }
        let cond = Conditions {
            surface,
            sky,
            sun,
            ground_temperature_k: rng.f(250.0, 320.0),
            atmosphere,
            per_hit: None,
            wind_speed_m_s: rng.f(0.0, 12.0),
        };
        // One, two or three bands (the grey pass has its own loops for one
        // and two, and a general one).
        let bands: Vec<Band> = match rng.u(4) {
            0 => vec![Band::flat(8.0, 12.0, 0.1).unwrap()],
            1 => vec![Band::flat(3.0, 5.0, 0.05).unwrap()],
            2 => vec![
                Band::flat(3.0, 5.0, 0.05).unwrap(),
                Band::flat(7.5, 13.5, 0.1).unwrap(),
            ],
            _ => vec![
                Band::flat(3.0, 5.0, 0.05).unwrap(),
                Band::flat(8.0, 10.0, 0.1).unwrap(),
                Band::flat(10.0, 12.0, 0.1).unwrap(),
            ],
        };
        // A random sensor path: τ₂ and L_u per band, range node and height
        // node (one, or three spanning the square's heights).
        let path = (rng.u(3) != 0).then(|| {
            let mut ranges_m = vec![0.0];
            for _ in 0..rng.u(4) + 2 {
                let last = *ranges_m.last().unwrap();
                ranges_m.push(last + rng.f(50.0, 600.0));
            }
            let heights_m = if rng.u(2) == 0 {
                vec![0.0]
            } else {
                vec![-12.0, rng.f(-5.0, 5.0), 12.0]
            };
            let nodes = ranges_m.len() * heights_m.len();
            let path_bands: Vec<Vec<(Vec<f64>, Vec<f64>)>> = bands
                .iter()
                .map(|b| {
                    (0..nodes)
                        .map(|_| {
                            let tau = (0..b.len()).map(|_| rng.f(0.3, 1.0)).collect();
                            let lu = (0..b.len()).map(|_| rng.f(0.0, 4.0)).collect();
                            (tau, lu)
                        })
                        .collect()
                })
                .collect();
            // By day (half the cases), random scattered sunlight per node
            // and scattering-angle node, toward a random sun.
            let scatter = (rng.u(2) == 0).then(|| {
                let z = rng.f(0.1, 1.0);
                let (s, c) = rng.f(0.0, std::f64::consts::TAU).sin_cos();
                let h = (1.0 - z * z).sqrt();
                irsig::render::path::PathScatter {
                    sun_direction: [h * c, h * s, z],
                    bands: bands
                        .iter()
                        .map(|b| {
                            (0..nodes)
                                .map(|_| {
                                    (0..irsig::atmosphere::ANGLE_NODES)
                                        .map(|_| (0..b.len()).map(|_| rng.f(0.0, 2.0)).collect())
                                        .collect()
                                })
                                .collect()
                        })
                        .collect(),
                }
            });
            PathTables {
                ranges_m,
                heights_m,
                bands: path_bands,
                scatter,
            }
        });
        // Rays at the square from all around (both faces), unit directions.
        let far = path
            .as_ref()
            .map_or(1500.0, |p| p.ranges_m.last().unwrap() * 1.1);
        let rays: Vec<Ray> = (0..48)
            .map(|_| {
                let target = u * rng.f(-8.0, 8.0) as f32 + v * rng.f(-8.0, 8.0) as f32;
                let mut from = rng.up(88.0);
                if rng.u(4) == 0 {
                    from = -from;
                }
                let r = rng.f(5.0, far) as f32;
                Ray::new(target + from * r, -from)
            })
            .collect();
        let tracer = trace::build(&geom, Backend::Embree).unwrap();
        let hits = trace::intersect_all(tracer.as_ref(), &rays, Coherence::Coherent);
        let opts = ShadeOptions {
            max_bounces: 0,
            offset_m: 1e-3,
        };
        let shader = Shader::new(tracer.as_ref(), &geom, &optics, &cond, &bands, opts)
            .unwrap()
            .with_path(path.clone());
        // What the renderer runs on a row.
        let nb = bands.len();
        let mut got = vec![0f32; nb * rays.len()];
        let mut slow = Vec::new();
        shader.shade_fast(
            &rays,
            &hits,
            &mut got,
            &mut slow,
            &mut FastScratch::default(),
            None,
        );
        if !slow.is_empty() {
            let nl = shader.spectrum_len();
            let sr: Vec<Ray> = slow.iter().map(|&i| rays[i]).collect();
            let sh: Vec<_> = slow.iter().map(|&i| hits[i]).collect();
            let mut spectra = vec![0.0; sr.len() * nl];
            shader.shade_primary(&sr, &sh, &mut spectra);
            for (&i, s) in slow.iter().zip(spectra.chunks_exact(nl)) {
                for b in 0..nb {
                    got[b * rays.len() + i] = shader.band_radiance(b, s) as f32;
                }
            }
        }
        // The reference, from the scene's inputs.
        let em = Emissivity::from_material(&m).unwrap();
        let sun_dir = sun.map(|s| s.direction.normalize());
        // Per band: L_sky, E_s, B(T), B(T_bg), exact.
        let sources: Vec<_> = bands
            .iter()
            .map(|band| {
                let grid = band.grid();
                // The directional sky at the sky nodes, reflected by the
                // square's tilt (β: n·z).
                let sky_dir = match &cond.sky {
                    Sky::Blackbody { temperature_k } => {
                        vec![grid.blackbody(&planck, *temperature_k); sky_node_zeniths_deg().len()]
                    }
                    Sky::Atmosphere(c) => cond
                        .atmosphere
                        .sky_radiances_toward(c, &sky_node_zeniths_deg(), grid)
                        .unwrap(),
                };
                // By day, with the azimuthal mean of its scattered sunlight.
                let sky_dir = match irsig::render::shade::scattered_sky_nodes(&cond, grid).unwrap()
                {
                    Some(t) => {
                        let z = sun.map_or(0.0, |s| {
                            (s.direction.normalize().z as f64).acos().to_degrees()
                        });
                        let mean = irsig::render::shade::scattered_sky_azimuth_mean(&t, z);
                        sky_dir
                            .iter()
                            .zip(&mean)
                            .map(|(a, b)| a.iter().zip(b).map(|(x, y)| x + y).collect())
                            .collect()
                    }
                    None => sky_dir,
                };
                let sky_l = reflected_sky(&sky_dir, n.z as f64);
                // The back face's: tilt 180° − β.
                let sky_back = reflected_sky(&sky_dir, -n.z as f64);
                let e_s = match sun {
                    Some(s) => surface_solar_spectrum(&cond.atmosphere, &planck, &s, grid).unwrap(),
                    None => vec![0.0; band.len()],
                };
                let (b_t, b_bg) = (grid.blackbody(&planck, t_s), grid.blackbody(&planck, t_bg));
                (sky_l, sky_back, e_s, b_t, b_bg)
            })
            .collect();
        // The glint lobe's m² while the sun lights any band.
        let sun_up = sources
            .iter()
            .any(|(_, _, e_s, _, _)| e_s.iter().any(|&e| e > 0.0));
        let m2 = if sun_up && m.specular_fraction > 0.0 {
            lobe_slope_variance(&m, cond.wind_speed_m_s)
        } else {
            0.0
        };
        for (i, (ray, hit)) in rays.iter().zip(&hits).enumerate() {
            let Some(h) = hit else { continue };
            let f = shader.facet_of(h);
            let mut nrm = h.ng.normalize();
            let front = nrm.dot(ray.dir) < 0.0;
            if !front {
                nrm = -nrm;
            }
            let theta = (-(ray.dir.dot(nrm)) as f64)
                .clamp(0.0, 1.0)
                .acos()
                .to_degrees();
            let a0 = (theta.floor() as usize).min(89);
            // The hit's sunlit fraction: its own shadow ray (nothing
            // occludes a lone square) or the facet's.
            let f_sun = if shader.traces_sun_ray(f) { 1.0 } else { frac };
            let sun_seen = sun_dir.is_some_and(|s| s.dot(nrm) > 0.0);
            // The sun lights a single-sided facet's front only, and the
            // face of a double-sided one on its side only.
            let lit_face = if m.double_sided {
                sun_dir.is_none() || sun_seen
            } else {
                front
            };
            let range = (h.t * ray.dir.length()) as f64;
            let z = (ray.origin.z + ray.dir.z * h.t) as f64;
            for (b, band) in bands.iter().enumerate() {
                let eps: Vec<f64> = band
                    .wavelengths_um()
                    .iter()
                    .map(|&l| {
                        let (e0, e1) = (em.eval(l, a0 as f64), em.eval(l, a0 as f64 + 1.0));
                        e0 + (theta - a0 as f64) * (e1 - e0)
                    })
                    .collect();
                let (sky_front, sky_back, e_s, b_t, b_bg) = &sources[b];
                // The seen face's sky view: a back face with its own.
                let (big_f, sky_l) = match back_f {
                    Some(fb) if !front => (fb, sky_back),
                    _ => (big_f, sky_front),
                };
                let glint_sr = match sun_dir {
                    Some(s) if m2 > 0.0 && sun_seen => glint_lobe_sr(m2, nrm, -ray.dir, s),
                    _ => 0.0,
                };
                if glint_sr > 0.0 {
                    glinting += 1;
                }
                let inputs = SurfaceInputs {
                    blackbody: b_t,
                    emissivity: &eps,
                    specular_fraction: m.specular_fraction,
                    transmissivity: m.transmissivity,
                    shape_factor: big_f,
                    sky_radiance: sky_l,
                    background_radiance: b_bg,
                    solar_irradiance: Some(e_s),
                    cos_sun: if lit_face {
                        cos_sun as f64 * f_sun
                    } else {
                        0.0
                    },
                    glint_sr,
                    specular_radiance: None,
                    transmitted_radiance: None,
                };
                let mut leaving = vec![0.0; band.len()];
                leaving_radiance(&inputs, &mut leaving);
                let want = match &path {
                    Some(p) => {
                        let (tau, lu) =
                            p.at(b, range, z, p.cos_theta(ray.dir.as_dvec3().to_array()));
                        at_sensor(&leaving, &tau, &lu, band)
                    }
                    None => band.integrate(&leaving),
                };
                let v = got[b * rays.len() + i] as f64;
                let rel = (v - want).abs() / want;
                worst = worst.max(rel);
                assert!(
                    rel <= 1e-5,
                    "case {case} ray {i} band {b}: renderer {v}, reference {want} \
                     (material {m:?}, slow {})",
                    slow.contains(&i)
                );
                compared += 1;
            }
            if slow.contains(&i) {
                slow_hits += 1;
            } else {
                fast_hits += 1;
            }
        }
    }
    eprintln!(
        "{compared} band values ({fast_hits} fast hits, {slow_hits} spectral, \
         {glinting} glinting): worst relative difference {worst:.2e}"
    );
    // Every path was exercised.
    assert!(fast_hits > 2500 && slow_hits > 500 && glinting > 100);
}

/// Issue 18: a hit on the back face of a double-sided facet reflects the
/// sky that face sees. A double-sided fence (vertical, front facing −y
/// onto open ground: F = 0.5) with a wall 2 m behind it (its back face's
/// F = 0.1) under a cold blackbody sky, everything else at 300 K: viewed
/// normally, a face leaves `B(T) − r·F·(B(T) − B(T_sky))`, r = 1 − ε(0°),
/// with the F of the face seen — on the fast path and in the spectral
/// reference. Front-face hits are the same whether the back face's view
/// is known or not.
#[test]
fn r18_a_double_sided_fence_reflects_the_sky_of_the_face_seen() {
    use irsig::radiometry::Planck;
    use irsig::trace::{Coherence, Ray};
    let mut fence = material("fence", 1, 0.6, 0.0);
    fence.double_sided = true;
    let wall = material("wall", 2, 0.9, 0.0);
    // Front normal −y: counter-clockwise seen from −y.
    let fence_q = quad(
        "fence",
        [
            Vec3::new(-5.0, 0.0, 0.0),
            Vec3::new(5.0, 0.0, 0.0),
            Vec3::new(5.0, 0.0, 2.0),
            Vec3::new(-5.0, 0.0, 2.0),
        ],
    );
    let wall_q = quad(
        "wall",
        [
            Vec3::new(-5.0, 2.0, 0.0),
            Vec3::new(-5.0, 2.0, 4.0),
            Vec3::new(5.0, 2.0, 4.0),
            Vec3::new(5.0, 2.0, 0.0),
        ],
    );
    let geom = geometry(vec![fence_q, wall_q]);
    let optics = optics(&geom, vec![fence.clone(), wall], &[0, 1]);
    let (f_front, f_back, t_sky) = (0.5f64, 0.1f64, 230.0);
    let conditions = |back: Option<f32>| {
        let mut surface = state(&geom, &[300.0, 300.0]);
        for f in 0..2 {
            surface.shape_factor[f] = f_front as f32;
            surface.back_shape_factor[f] = back;
        }
        Conditions {
            surface,
            sky: Sky::Blackbody {
                temperature_k: t_sky,
            },
            sun: None,
            ground_temperature_k: 300.0,
            atmosphere: Atmosphere::None,
            per_hit: None,
            wind_speed_m_s: 2.0,
        }
    };
    // Normal views of the front (from −y) and of the back (from between
    // the fence and the wall).
    let rays: Vec<Ray> = [-0.5f32, 0.5]
        .iter()
        .flat_map(|&x| {
            [
                Ray::new(Vec3::new(x, -20.0, 1.0), Vec3::Y),
                Ray::new(Vec3::new(x, 1.0, 1.0), -Vec3::Y),
            ]
        })
        .collect();
    let tracer = trace::build(&geom, Backend::Embree).unwrap();
    let hits = trace::intersect_all(tracer.as_ref(), &rays, Coherence::Coherent);
    assert!(
        hits.iter()
            .all(|h| h.is_some_and(|h| h.prim < 2 && h.instance == 0))
    );
    let bands = vec![Band::flat(8.0, 12.0, 0.1).unwrap()];
    let opts = ShadeOptions {
        max_bounces: 0,
        offset_m: 1e-3,
    };
    let shade = |cond: &Conditions| {
        let shader = Shader::new(tracer.as_ref(), &geom, &optics, cond, &bands, opts).unwrap();
        fast_and_reference(&shader, &rays, &hits)
    };
    let planck = Planck::default();
    let em = Emissivity::from_material(&fence).unwrap();
    let grid = bands[0].grid();
    let (b_t, b_sky) = (
        grid.blackbody(&planck, 300.0),
        grid.blackbody(&planck, t_sky),
    );
    let analytic = |big_f: f64| -> f64 {
        let l: Vec<f64> = bands[0]
            .wavelengths_um()
            .iter()
            .zip(b_t.iter().zip(&b_sky))
            .map(|(&lambda, (&bt, &bs))| {
                let r = 1.0 - em.eval(lambda, 0.0);
                bt - r * big_f * (bt - bs)
            })
            .collect();
        bands[0].integrate(&l)
    };
    let (own_fast, own_ref) = shade(&conditions(Some(f_back as f32)));
    let (old_fast, old_ref) = shade(&conditions(None));
    for (i, _) in rays.iter().enumerate() {
        let back = i % 2 == 1;
        let want = analytic(if back { f_back } else { f_front });
        for (what, v) in [("fast", own_fast[i]), ("reference", own_ref[i])] {
            assert!(
                (v - want).abs() <= 1e-5 * want,
                "ray {i} ({}): {what} {v}, analytic {want}",
                if back { "back" } else { "front" }
            );
        }
        if back {
            // Without its own view the back face took the front face's F:
            // brighter by r·(F − F_back)·(B(T) − B(T_sky)).
            let front_f = analytic(f_front);
            assert!((old_fast[i] - front_f).abs() <= 1e-5 * front_f);
            assert!(
                own_fast[i] > old_fast[i] + 0.1,
                "{} {}",
                own_fast[i],
                old_fast[i]
            );
        } else {
            assert_eq!(own_fast[i], old_fast[i]);
            assert_eq!(own_ref[i], old_ref[i]);
        }
    }
}

/// Per ray: the fast path's and the spectral reference's radiance in band
/// 0 (every hit must stay on the fast paths).
fn fast_and_reference(
    shader: &Shader,
    rays: &[irsig::trace::Ray],
    hits: &[Option<irsig::trace::Hit>],
) -> (Vec<f64>, Vec<f64>) {
    let mut fast = vec![0f32; rays.len()];
    let mut slow = Vec::new();
    shader.shade_fast(
        rays,
        hits,
        &mut fast,
        &mut slow,
        &mut irsig::render::FastScratch::default(),
        None,
    );
    assert!(slow.is_empty(), "{slow:?}");
    let nl = shader.spectrum_len();
    let mut spectra = vec![0.0; rays.len() * nl];
    shader.shade_primary(rays, hits, &mut spectra);
    let reference = spectra
        .chunks_exact(nl)
        .map(|s| shader.band_radiance(0, s))
        .collect();
    (fast.iter().map(|&v| v as f64).collect(), reference)
}

/// A lone double-sided plate (a leaf screen) in the sun, seen from both
/// sides: the face the sun falls on reflects it (fast path and reference
/// alike), the face turned from the sun reflects none — it renders exactly
/// as with no sun at all — though its facet's `cos_sun` is `|n·s|`, lit
/// on either side for the thermal model. Turning the sun to the other side
/// swaps the faces (issue 18).
#[test]
fn r18_a_double_sided_plate_reflects_the_sun_on_its_sunlit_face_only() {
    use irsig::trace::{Coherence, Ray};
    let mut plate = material("plate", 1, 0.7, 0.0);
    plate.double_sided = true;
    // Front normal −y: counter-clockwise seen from −y.
    let q = quad(
        "plate",
        [
            Vec3::new(-5.0, 0.0, 0.0),
            Vec3::new(5.0, 0.0, 0.0),
            Vec3::new(5.0, 0.0, 4.0),
            Vec3::new(-5.0, 0.0, 4.0),
        ],
    );
    let geom = geometry(vec![q]);
    let optics = optics(&geom, vec![plate], &[0]);
    // Rays 0, 2 see the front (from −y), 1, 3 the back (from +y).
    let rays: Vec<Ray> = [-0.5f32, 0.5]
        .iter()
        .flat_map(|&x| {
            [
                Ray::new(Vec3::new(x, -20.0, 2.0), Vec3::Y),
                Ray::new(Vec3::new(x, 20.0, 2.0), -Vec3::Y),
            ]
        })
        .collect();
    let tracer = trace::build(&geom, Backend::Embree).unwrap();
    let hits = trace::intersect_all(tracer.as_ref(), &rays, Coherence::Coherent);
    assert!(hits.iter().all(|h| h.is_some_and(|h| h.prim < 2)));
    let bands = vec![Band::flat(3.0, 5.0, 0.05).unwrap()];
    let opts = ShadeOptions {
        max_bounces: 0,
        offset_m: 1e-3,
    };
    let conditions = |sun: Option<Vec3>| {
        let mut surface = state(&geom, &[300.0]);
        for f in 0..2 {
            surface.shape_factor[f] = 0.5;
            surface.sun_fraction[f] = 1.0;
            // What the exposure gives a double-sided facet: |n·s|.
            surface.cos_sun[f] = sun.map_or(0.0, |s| s.dot(Vec3::NEG_Y).abs());
        }
        Conditions {
            surface,
            sky: Sky::Blackbody {
                temperature_k: 250.0,
            },
            sun: sun.map(|direction| SunInput {
                direction,
                direct_normal_w_m2: 800.0,
            }),
            ground_temperature_k: 300.0,
            atmosphere: Atmosphere::None,
            per_hit: None,
            wind_speed_m_s: 2.0,
        }
    };
    let shade = |cond: &Conditions| {
        let shader = Shader::new(tracer.as_ref(), &geom, &optics, cond, &bands, opts).unwrap();
        fast_and_reference(&shader, &rays, &hits)
    };
    let (dark_fast, dark_ref) = shade(&conditions(None));
    for (sun_side, sun) in [
        (-1.0f32, Vec3::new(0.2, -0.6, 0.7).normalize()),
        (1.0, Vec3::new(0.2, 0.6, 0.7).normalize()),
    ] {
        let (lit_fast, lit_ref) = shade(&conditions(Some(sun)));
        for i in 0..rays.len() {
            // The viewer's side: −y for the front rays.
            let viewer_side = if i % 2 == 0 { -1.0 } else { 1.0 };
            let (f, r) = (lit_fast[i], lit_ref[i]);
            assert!(
                (f - r).abs() <= 1e-5 * r,
                "ray {i}: fast {f}, reference {r}"
            );
            if viewer_side == sun_side {
                // r_d·E·cos σ/π in 3–5 µm: well above float rounding.
                assert!(
                    f > dark_fast[i] * 1.01,
                    "ray {i}: {f} vs dark {}",
                    dark_fast[i]
                );
            } else {
                assert_eq!(f, dark_fast[i], "ray {i}: the unlit face");
                assert!(
                    (r - dark_ref[i]).abs() <= 1e-12 * r,
                    "ray {i}: {r} vs {}",
                    dark_ref[i]
                );
            }
        }
    }
}
