//! Georeferenced outputs: ENVI map info and GeoTIFF of nadir images put a
//! known ground point at its pixel; geolocation truth layers; north-up
//! line scanners; tiles carry the hit points.

use std::path::{Path, PathBuf};

use glam::DVec3;
use irsig::geodesy::{UtmZone, geodetic_from_enu, utm_from_geodetic};
use irsig::output::{ImageStack, read_exr};
use irsig::render::session::{RunOptions, Session};
use irsig::sun::Site;
use irsig::trace::Backend;
use serde_json::{Value, json};
use tiff::decoder::{Decoder, DecodingResult};
use tiff::tags::Tag;

use crate::util::repo_path;

/// Centre of the marker block, scene metres (top at z = 1 m).
const MARKER: [f64; 3] = [37.0, -23.0, 1.0];

fn site() -> Site {
    Site::new(43.16, -77.61, 160.0).unwrap()
}

/// A 240 m ground square with a 12 m marker block at [`MARKER`], seen by
/// `sensors`.
fn write_scene(dir: &Path, sensors: Value, render: Value) -> PathBuf {
    let scene = json!({
        "site": {"latitude_deg": 43.16, "longitude_deg": -77.61, "altitude_m": 160.0,
                 "utc_offset_hours": -4.0},
        "time": "2025-06-21T14:00:00-04:00",
        "weather": {"file": repo_path("scenes/town/weather.csv")},
        "materials": [repo_path("scenes/materials.json")],
        "objects": [
            {"name": "ground", "material": "asphalt",
             "shapes": [{"plane": {"size": [240.0, 240.0], "max_edge_m": 40.0}}]},
            {"name": "marker", "material": "brick",
             "shapes": [{"box": {"size": [12.0, 12.0, 1.0]}}],
             "instances": [{"translate": [MARKER[0], MARKER[1], 0.0]}]}
        ],
        "sensors": sensors,
        "render": render,
    });
    let path = dir.join("scene.json");
    std::fs::write(&path, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    path
}

fn nadir(name: &str, yaw_deg: f64) -> Value {
    json!({"type": "frame", "name": name, "width": 90, "height": 70, "fov_deg": 40.0,
           "position": [5.0, -10.0, 400.0], "yaw_deg": yaw_deg, "pitch_deg": -90.0,
           "bands": [{"name": "LWIR", "response": [8.0, 12.0]}],
           "truth_layers": ["latitude", "longitude", "x", "y", "z"]})
}

fn render(scene: &Path, out: &Path, options: &RunOptions) -> Session {
    let mut session = Session::open(scene, Backend::Embree).unwrap();
    session.run(out, options).unwrap();
    session
}

/// The `map info` of an ENVI header as GDAL reads it: geotransform (GDAL
/// order), UTM zone and hemisphere.
fn map_info(hdr: &Path) -> Option<([f64; 6], u8, bool)> {
    let text = std::fs::read_to_string(hdr).unwrap();
    let line = text.lines().find(|l| l.starts_with("map info"))?;
    let inner = line.split_once('{').unwrap().1.trim_end_matches('}');
    let f: Vec<&str> = inner.split(',').map(str::trim).collect();
    assert_eq!(f[0], "UTM", "{line}");
    let num = |i: usize| f[i].parse::<f64>().unwrap();
    let (px_ref, py_ref, e, n, px, py) = (num(1), num(2), num(3), num(4), num(5), num(6));
    let rot = f
        .iter()
        .find_map(|s| s.strip_prefix("rotation="))
        .map_or(0.0, |r| r.parse::<f64>().unwrap())
        .to_radians();
    let (s, c) = rot.sin_cos();
    // As GDAL's ENVI driver reads it (GDAL 3.6): GT = [px·cos, px·sin;
    // py·sin, −py·cos]; the tie point is the upper-left corner of 1-based
    // pixel (px_ref, py_ref).
    let (a, b, cc, d) = (c * px, s * px, s * py, -c * py);
    let x0 = e - (px_ref - 1.0) * a - (py_ref - 1.0) * b;
    let y0 = n - (px_ref - 1.0) * cc - (py_ref - 1.0) * d;
    Some((
        [x0, a, b, y0, cc, d],
        f[7].parse().unwrap(),
        f[8] == "North",
    ))
}

fn pixel_of(t: &[f64; 6], x: f64, y: f64) -> (f64, f64) {
    let det = t[1] * t[5] - t[2] * t[4];
    let (dx, dy) = (x - t[0], y - t[3]);
    ((t[5] * dx - t[2] * dy) / det, (t[1] * dy - t[4] * dx) / det)
}

/// Mean continuous pixel coordinates (centres at +½) of the pixels whose
/// `object_id` is `id`.
fn centroid(stack: &ImageStack, id: f32) -> (f64, f64, usize) {
    let ids = &stack.layer("object_id").unwrap().data;
    let (mut su, mut sv, mut n) = (0.0, 0.0, 0);
    for (k, &v) in ids.iter().enumerate() {
        if v == id {
            su += (k % stack.width) as f64 + 0.5;
            sv += (k / stack.width) as f64 + 0.5;
            n += 1;
        }
    }
    (su / n as f64, sv / n as f64, n)
}

fn layer<'a>(stack: &'a ImageStack, name: &str) -> &'a [f32] {
    &stack
        .layer(name)
        .unwrap_or_else(|| panic!("no layer {name}"))
        .data
}

#[test]
fn map_info_of_a_nadir_image_puts_the_marker_at_its_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(
        dir.path(),
        json!([nadir("north", 0.0), nadir("turned", 30.0)]),
        json!({"geotiff": true}),
    );
    let out = dir.path().join("out");
    render(&scene, &out, &RunOptions::default());
    let site = site();
    let (lat, lon, _) = geodetic_from_enu(&site, DVec3::from_array(MARKER));
    let zone = UtmZone::of(site.latitude_deg, site.longitude_deg).unwrap();
    let (e, n) = utm_from_geodetic(zone, lat, lon).unwrap();
    for name in ["north", "turned"] {
        let (t, zn, north) = map_info(&out.join(format!("{name}.hdr"))).expect("map info");
        assert_eq!((zn, north), (18, true));
        let stack = read_exr(out.join(format!("{name}.exr"))).unwrap();
        let (cu, cv, count) = centroid(&stack, 1.0);
        assert!(count > 10, "{name}: marker seen in {count} pixels");
        let (u, v) = pixel_of(&t, e, n);
        assert!(
            (u - cu).abs() <= 0.5 && (v - cv).abs() <= 0.5,
            "{name}: map info puts the marker at ({u:.2}, {v:.2}), the image shows it at ({cu:.2}, {cv:.2})"
        );
        // The truth layers at the marker's pixel.
        let k = cv.floor() as usize * stack.width + cu.floor() as usize;
        let (x, y, z) = (
            layer(&stack, "x")[k] as f64,
            layer(&stack, "y")[k] as f64,
            layer(&stack, "z")[k] as f64,
        );
        let pix = t[1].hypot(t[4]);
        assert!(
            (x - MARKER[0]).abs() < pix && (y - MARKER[1]).abs() < pix,
            "{x} {y}"
        );
        assert!((z - MARKER[2]).abs() < 1e-3, "{z}");
        let (plat, plon, _) = geodetic_from_enu(&site, DVec3::new(x, y, z));
        assert!((layer(&stack, "latitude")[k] as f64 - plat).abs() < 1e-5);
        assert!((layer(&stack, "longitude")[k] as f64 - plon).abs() < 1e-5);
        // Pixels past the ground square see nothing: NaN hit points.
        assert!(layer(&stack, "x")[0].is_nan() && layer(&stack, "latitude")[0].is_nan());
        assert_eq!(layer(&stack, "object_id")[0], -1.0);
    }
    // The turned camera's header states the rotation; the grid is turned
    // clockwise by the yaw plus the meridian convergence (2.6° west of zone
    // 18's central meridian, true north is 1.78° clockwise from grid north:
    // PROJ's `cs2cs` puts a step along the parallel at −1.78°).
    let text = std::fs::read_to_string(out.join("turned.hdr")).unwrap();
    assert!(text.contains("rotation="), "{text}");
    assert!(text.contains("coordinate system string = {PROJCS[\"WGS 84 / UTM zone 18N\""));
    let (t, ..) = map_info(&out.join("turned.hdr")).unwrap();
    let rot = t[4].atan2(t[1]).to_degrees();
    assert!((rot + 30.0 + 1.78).abs() < 0.05, "rotation {rot}");
}

#[test]
fn geotiff_reads_back_with_its_geokeys_and_layers() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), json!([nadir("cam", 30.0)]), json!({}));
    let out = dir.path().join("out");
    let mut session = Session::open(&scene, Backend::Embree).unwrap();
    session.config.geotiff = true;
    session.run(&out, &RunOptions::default()).unwrap();
    let stack = read_exr(out.join("cam.exr")).unwrap();
    let mut d = Decoder::new(std::fs::File::open(out.join("cam.tif")).unwrap()).unwrap();
    assert_eq!(d.dimensions().unwrap(), (90, 70));
    let keys = d.get_tag_u16_vec(Tag::GeoKeyDirectoryTag).unwrap();
    let key = |id: u16| {
        keys[4..]
            .chunks(4)
            .find(|k| k[0] == id)
            .map(|k| k[3])
            .unwrap_or_else(|| panic!("GeoKey {id} missing: {keys:?}"))
    };
    assert_eq!(key(1024), 1, "GTModelType projected");
    assert_eq!(key(1025), 1, "GTRasterType PixelIsArea");
    assert_eq!(key(3072), 32618, "ProjectedCSType WGS 84 / UTM 18N");
    assert_eq!(key(3076), 9001, "linear unit metre");
    // The transform agrees with the ENVI header's.
    let m = d.get_tag_f64_vec(Tag::ModelTransformationTag).unwrap();
    let (t, ..) = map_info(&out.join("cam.hdr")).unwrap();
    for (a, b) in [m[3], m[0], m[1], m[7], m[4], m[5]].iter().zip(t) {
        assert!((a - b).abs() < 1e-6 * b.abs().max(1.0), "{m:?} vs {t:?}");
    }
    assert_eq!(
        d.get_tag_u32(Tag::SamplesPerPixel).unwrap() as usize,
        stack.layers.len()
    );
    let meta = d.get_tag_ascii_string(Tag::Unknown(42112)).unwrap();
    assert!(meta.contains(">apparent_temperature<") && meta.contains(">latitude<"));
    // Every layer, pixel-interleaved float32, as in the EXR (NaN included).
    let DecodingResult::F32(v) = d.read_image().unwrap() else {
        panic!("expected float samples");
    };
    let n = stack.layers.len();
    for (i, l) in stack.layers.iter().enumerate() {
        for (k, &x) in l.data.iter().enumerate() {
            assert_eq!(
                v[k * n + i].to_bits(),
                x.to_bits(),
                "layer {} pixel {k}",
                l.name
            );
        }
    }
}

fn scanner(name: &str, heading: f64, start: [f64; 2], orientation: &str) -> Value {
    json!({"type": "line_scanner", "name": name, "ifov_rad": 0.002,
           "scan_angle_deg": 40.0 * 0.002f64.to_degrees(), "samples_per_line": 40, "lines": 30,
           "scan_rate_hz": 20.0, "altitude_m": 300.0, "ground_speed_m_s": 60.0,
           "heading_deg": heading, "start": start, "orientation": orientation,
           "bands": [{"name": "LWIR", "response": [8.0, 12.0]}],
           "truth_layers": ["x", "y"]})
}

#[test]
fn north_up_scanner_images_have_the_northernmost_line_first_and_are_not_mirrored() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(
        dir.path(),
        json!([
            scanner("flown_n", 0.0, [37.0, -60.0], "as_flown"),
            scanner("up_n", 0.0, [37.0, -60.0], "north_up"),
            scanner("up_s", 180.0, [37.0, 30.0], "north_up"),
        ]),
        json!({}),
    );
    let out = dir.path().join("out");
    let session = render(&scene, &out, &RunOptions::default());
    let read = |n: &str| read_exr(out.join(format!("{n}.exr"))).unwrap();
    let at = |s: &ImageStack, l: &str, c: usize, r: usize| layer(s, l)[r * s.width + c];
    let flown = read("flown_n");
    // As flown northward: rows go north, columns east (a mirror image).
    assert!(at(&flown, "y", 20, 0) < at(&flown, "y", 20, 29));
    for name in ["up_n", "up_s"] {
        let s = read(name);
        let (w, h) = (s.width - 1, s.height - 1);
        assert!(
            at(&s, "y", 20, 0) > at(&s, "y", 20, h),
            "{name}: first row northernmost"
        );
        assert!(
            at(&s, "x", 0, 15) < at(&s, "x", w, 15),
            "{name}: west on the left"
        );
        // A narrow scan is affine to 0.1 px: north up, not mirrored. Its
        // oblong pixels (0.6 × 3 m) turned by the meridian convergence are
        // beyond ENVI map info (the GeoTIFF has them).
        let i = session.sensor_index(name).unwrap();
        let g = irsig::sensor::georef::georeference(&session.sensors[i], &site())
            .expect("georeferenced");
        let t = g.transform;
        assert!(
            t[5] < 0.0 && t[1] > 0.0 && t[1] * t[5] - t[2] * t[4] < 0.0,
            "{t:?}"
        );
        let text = std::fs::read_to_string(out.join(format!("{name}.hdr"))).unwrap();
        assert!(
            text.contains("; no map info: ENVI map info cannot state"),
            "{text}"
        );
        // The marker: map info, the projection into the written image and
        // the image itself agree.
        let (cu, cv, count) = centroid(&s, 1.0);
        assert!(count > 10, "{name}: {count}");
        let uv = session.sensors[i]
            .project_written(DVec3::from_array(MARKER))
            .unwrap();
        assert!(
            (uv.x - cu).abs() <= 0.5 && (uv.y - cv).abs() <= 0.5,
            "{name}: projected ({}, {}), seen ({cu}, {cv})",
            uv.x,
            uv.y
        );
    }
    // As flown the grid is mirrored: no ENVI map info, said so.
    let text = std::fs::read_to_string(out.join("flown_n.hdr")).unwrap();
    assert!(
        !text.contains("map info =") && text.contains("; no map info"),
        "{text}"
    );
}

#[test]
fn tiles_carry_the_hit_points_into_the_merged_image() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), json!([nadir("cam", 10.0)]), json!({}));
    let (whole, tiles, merged) = (
        dir.path().join("whole"),
        dir.path().join("tiles"),
        dir.path().join("merged"),
    );
    let mut session = Session::open(&scene, Backend::Embree).unwrap();
    session.run(&whole, &RunOptions::default()).unwrap();
    let mut parts = Vec::new();
    for k in 1..=2 {
        let options = RunOptions {
            tile: Some((k, 2)),
            ..RunOptions::default()
        };
        session.run(&tiles, &options).unwrap();
        parts.push(tiles.join(format!("cam.tile{k}-of-2.exr")));
    }
    irsig::render::tile::merge_tiles_with(&parts, &merged, true).unwrap();
    let a = read_exr(whole.join("cam.exr")).unwrap();
    let b = read_exr(merged.join("cam.exr")).unwrap();
    assert_eq!(a.layers.len(), b.layers.len());
    for (x, y) in a.layers.iter().zip(&b.layers) {
        assert_eq!(x.name, y.name);
        assert!(
            x.data
                .iter()
                .zip(&y.data)
                .all(|(p, q)| p.to_bits() == q.to_bits()),
            "layer {}",
            x.name
        );
    }
    assert_eq!(
        std::fs::read_to_string(whole.join("cam.hdr")).unwrap(),
        std::fs::read_to_string(merged.join("cam.hdr")).unwrap()
    );
    assert!(merged.join("cam.tif").exists() && !whole.join("cam.tif").exists());
}

#[test]
fn oblique_and_polar_images_get_no_utm_map_info() {
    let dir = tempfile::tempdir().unwrap();
    let oblique = json!({"type": "frame", "name": "oblique", "width": 40, "height": 30,
        "fov_deg": 40.0, "position": [0.0, -300.0, 200.0], "look_at": [0.0, 0.0, 0.0],
        "bands": [{"name": "LWIR", "response": [8.0, 12.0]}]});
    let scene = write_scene(dir.path(), json!([oblique]), json!({}));
    let out = dir.path().join("out");
    render(&scene, &out, &RunOptions::default());
    let text = std::fs::read_to_string(out.join("oblique.hdr")).unwrap();
    assert!(
        !text.contains("map info") && !text.contains("; map:"),
        "{text}"
    );
    // Beyond UTM's latitudes: a local east-north-up grid.
    let s = irsig::sensor::Sensor::from_config(
        &serde_json::from_value::<irsig::sensor::SensorConfig>(nadir("polar", 0.0)).unwrap(),
        &irsig::Location::file("t"),
    )
    .unwrap();
    let g = irsig::sensor::georef::georeference(&s, &Site::new(86.0, 10.0, 0.0).unwrap())
        .expect("a nadir camera is georeferenced");
    assert!(matches!(
        g.system,
        irsig::output::MapSystem::LocalEnu { .. }
    ));
    let lines = g.envi_lines();
    assert!(lines.contains("map info = {Arbitrary, 1, 1,"), "{lines}");
    // Corner (0, 0) is the ground point of the upper-left image corner.
    let p = s.ground_point(0.0, 0.0, 0.0).unwrap();
    let (x, y) = g.map_of_pixel(0.0, 0.0);
    assert!((x - p.x).abs() < 1e-6 && (y - p.y).abs() < 1e-6);
}

#[test]
fn compare_places_latlon_points_by_the_images_latitude_longitude_layers() {
    use irsig::analysis::compare::locate_by_latlon_layers;
    use irsig::analysis::csv::{PointPosition, TruthPoint};
    let (w, h) = (4, 3);
    let mut st = ImageStack::new(w, h);
    let mut lat = Vec::new();
    let mut lon = Vec::new();
    for r in 0..h {
        for c in 0..w {
            lat.push(43.0 - 0.001 * r as f32);
            lon.push(-77.0 + 0.001 * c as f32);
        }
    }
    lat[2 * w + 3] = f32::NAN;
    lon[2 * w + 3] = f32::NAN;
    st.push("latitude", lat).unwrap();
    st.push("longitude", lon).unwrap();
    let pt = |line: usize, position: PointPosition| TruthPoint {
        id: format!("p{line}"),
        position,
        value: Some(300.0),
        material: None,
        line,
    };
    let file = Path::new("points.csv");
    let got = locate_by_latlon_layers(
        &st,
        &[
            pt(
                2,
                PointPosition::LatLon {
                    lat: 42.9991,
                    lon: -76.9979,
                },
            ),
            pt(3, PointPosition::Pixel { x: 0.2, y: 0.7 }),
        ],
        file,
    )
    .unwrap();
    assert_eq!(got[0].position, PointPosition::Pixel { x: 2.5, y: 1.5 });
    assert_eq!(got[1].position, PointPosition::Pixel { x: 0.2, y: 0.7 });
    // Off the image: a kilometre south, or 300 m east.
    for (lat, lon) in [(42.99, -76.998), (42.999, -76.993)] {
        let e = locate_by_latlon_layers(&st, &[pt(5, PointPosition::LatLon { lat, lon })], file)
            .unwrap_err()
            .to_string();
        assert!(e.contains("points.csv") && e.contains("line 5"), "{e}");
    }
}
