//! Tests: sensor geometry, sensor effects, and image outputs.

use irsig::output::{
    self, ImageStack, Layer, read_envi, read_exr, read_image, render_quicklook, write_atomic,
    write_envi, write_exr, write_quicklook_png,
};

use crate::util;

/// A test image with distinctive values: a gradient, NaNs, negative zero,
/// tiny and huge values, integer ids.
fn sample_stack(w: usize, h: usize) -> ImageStack {
    let mut s = ImageStack::new(w, h);
    // Names deliberately not in alphabetical order.
    let rad: Vec<f32> = (0..w * h).map(|i| 8.5 + 0.013 * i as f32).collect();
    let mut temp: Vec<f32> = (0..w * h).map(|i| 280.0 + (i % w) as f32 * 0.37).collect();
    temp[3] = f32::NAN;
    temp[5] = -0.0;
    temp[7] = 1e-38;
    temp[8] = 3.4e38;
    let ids: Vec<f32> = (0..w * h).map(|i| (i / 7) as f32).collect();
    s.push("band0_radiance", rad).unwrap();
    s.push("apparent_temperature", temp).unwrap();
    s.push("material_id", ids).unwrap();
    s
}

fn assert_bit_identical(a: &ImageStack, b: &ImageStack) {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let names = |s: &ImageStack| s.layers.iter().map(|l| l.name.clone()).collect::<Vec<_>>();
    assert_eq!(names(a), names(b));
    for (la, lb) in a.layers.iter().zip(&b.layers) {
        let bits = |l: &Layer| l.data.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(la), bits(lb), "layer {}", la.name);
    }
}

/// Files in `dir`, sorted.
fn listing(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn exr_round_trip_is_bit_exact_and_keeps_layer_order() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("scene.exr");
    let s = sample_stack(37, 23);
    write_exr(&p, &s).unwrap();
    let back = read_exr(&p).unwrap();
    assert_bit_identical(&s, &back);
    let back2 = read_image(&p).unwrap();
    assert_bit_identical(&s, &back2);
    assert_eq!(listing(dir.path()), vec!["scene.exr"]);
}

/// EXR blocks are compressed on as many threads as the caller's rayon pool
/// has, and written in line order: the file is the same, byte for byte, for
/// one and for three threads, and reads back exactly (an image of many
/// 16-line blocks, so that the threads do overlap).
#[test]
fn exr_written_on_any_thread_count_is_byte_identical() {
    let dir = tempfile::tempdir().unwrap();
    let s = sample_stack(301, 257);
    let write = |threads: usize| {
        let p = dir.path().join(format!("t{threads}.exr"));
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| write_exr(&p, &s))
            .unwrap();
        (std::fs::read(&p).unwrap(), p)
    };
    let ((one, p1), (three, _)) = (write(1), write(3));
    assert!(one == three, "1 and 3 threads wrote different files");
    assert_bit_identical(&s, &read_exr(&p1).unwrap());
}

#[test]
fn envi_round_trip_and_header_fields() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = ImageStack::new(11, 5);
    s.push(
        "band0_radiance",
        (0..55).map(|i| i as f32 * 0.25 - 3.0).collect(),
    )
    .unwrap();
    s.push(
        "band1_radiance",
        (0..55).map(|i| (i as f32).sqrt()).collect(),
    )
    .unwrap();
    write_envi(
        dir.path().join("cube"),
        &s,
        Some(&[3.75, 10.5]),
        "irsig test",
    )
    .unwrap();
    assert_eq!(listing(dir.path()), vec!["cube.hdr", "cube.img"]);
    let hdr = std::fs::read_to_string(dir.path().join("cube.hdr")).unwrap();
    for field in [
        "samples = 11",
        "lines = 5",
        "bands = 2",
        "data type = 4",
        "interleave = bsq",
        "byte order = 0",
        "header offset = 0",
        "wavelength units = Micrometers",
        "band names = {band0_radiance, band1_radiance}",
        "wavelength = {3.75, 10.5}",
    ] {
        assert!(
            hdr.lines().any(|l| l == field),
            "{field} missing in:\n{hdr}"
        );
    }
    assert!(hdr.starts_with("ENVI\n"));
    // Band-sequential little-endian float32: size, and the first values of
    // band 0 and band 1.
    let raw = std::fs::read(dir.path().join("cube.img")).unwrap();
    assert_eq!(raw.len(), 2 * 55 * 4);
    assert_eq!(f32::from_le_bytes(raw[220..224].try_into().unwrap()), 0.0);
    assert_eq!(f32::from_le_bytes(raw[4..8].try_into().unwrap()), -2.75);
    for p in ["cube.img", "cube.hdr", "cube"] {
        let back = read_envi(dir.path().join(p)).unwrap();
        assert_bit_identical(&s, &back.stack);
        assert_eq!(back.wavelengths, Some(vec![3.75, 10.5]));
        assert_eq!(back.wavelength_units.as_deref(), Some("Micrometers"));
    }
    assert_bit_identical(&s, &read_image(dir.path().join("cube.hdr")).unwrap());
}

#[test]
fn envi_reader_handles_bil_big_endian_and_reports_bad_headers() {
    let dir = tempfile::tempdir().unwrap();
    // 2 samples × 1 line × 2 bands, BIL, big-endian int16, multi-line braces.
    std::fs::write(
        dir.path().join("b.hdr"),
        "ENVI\nsamples = 2\nlines = 1\nbands = 2\ndata type = 2\ninterleave = bil\n\
         byte order = 1\nband names = {\n a,\n b}\n",
    )
    .unwrap();
    let vals: [i16; 4] = [1, -2, 300, 4];
    let raw: Vec<u8> = vals.iter().flat_map(|v| v.to_be_bytes()).collect();
    std::fs::write(dir.path().join("b.img"), raw).unwrap();
    let e = read_envi(dir.path().join("b.img")).unwrap();
    assert_eq!(e.stack.layers[0].name, "a");
    assert_eq!(e.stack.layers[0].data, vec![1.0, -2.0]);
    assert_eq!(e.stack.layers[1].data, vec![300.0, 4.0]);

    std::fs::write(
        dir.path().join("c.hdr"),
        "ENVI\nsamples = 2\nlines = x3\nbands = 1\ndata type = 4\n",
    )
    .unwrap();
    let msg = read_envi(dir.path().join("c.hdr")).unwrap_err().to_string();
    assert!(
        msg.contains("c.hdr") && msg.contains("line 3") && msg.contains("lines"),
        "{msg}"
    );
    std::fs::write(dir.path().join("c.img"), [0u8; 4]).unwrap();
    std::fs::write(
        dir.path().join("c.hdr"),
        "ENVI\nsamples = 2\nlines = 1\nbands = 1\ndata type = 4\n",
    )
    .unwrap();
    let msg = read_envi(dir.path().join("c.hdr")).unwrap_err().to_string();
    assert!(msg.contains("c.img") && msg.contains("needs 8"), "{msg}");
    let msg = read_image(dir.path().join("x.tif"))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("x.tif") && msg.contains(".exr"), "{msg}");
}

#[test]
fn atomic_write_leaves_nothing_on_error_and_keeps_the_old_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("out.exr");
    let r: irsig::Result<()> = write_atomic(&p, |w| {
        w.write_all(&[0u8; 10_000]).unwrap();
        Err(irsig::Error::Other("simulated failure half-way".into()))
    });
    assert!(r.is_err());
    assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));

    std::fs::write(&p, b"old").unwrap();
    let r: irsig::Result<()> = write_atomic(&p, |w| {
        w.write_all(b"new, but incomplete").unwrap();
        Err(irsig::Error::Other("fail".into()))
    });
    assert!(r.is_err());
    assert_eq!(std::fs::read(&p).unwrap(), b"old");
    assert_eq!(listing(dir.path()), vec!["out.exr"]);

    write_atomic(&p, |w| {
        w.write_all(b"new").map_err(|e| irsig::Error::io("x", e))
    })
    .unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), b"new");
    assert_eq!(listing(dir.path()), vec!["out.exr"]);

    // An invalid image is refused before anything is written.
    let mut bad = sample_stack(4, 4);
    bad.layers[1].data.pop();
    assert!(write_exr(dir.path().join("bad.exr"), &bad).is_err());
    assert!(write_envi(dir.path().join("bad"), &bad, None, "").is_err());
    assert_eq!(listing(dir.path()), vec!["out.exr"]);
}

#[test]
fn inferno_runs_dark_to_bright_monotonically() {
    // Endpoints of matplotlib's inferno table: (0.001462, 0.000466, 0.013866)
    // and (0.988362, 0.998364, 0.644924).
    let lo = output::inferno(0.0);
    let hi = output::inferno(1.0);
    assert!(lo.iter().all(|&c| c <= 3), "{lo:?}");
    for (c, r) in hi.iter().zip([252.0, 255.0, 164.0]) {
        assert!((*c as f64 - r).abs() <= 5.0, "{hi:?}");
    }
    let luma = |c: [u8; 3]| 0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64;
    let mut prev = -1.0;
    for i in 0..=100 {
        let l = luma(output::inferno(i as f32 / 100.0));
        assert!(l >= prev - 0.5, "lightness not monotonic at {i}");
        prev = l;
    }
}

#[test]
fn quicklook_png_decodes_with_the_right_size_and_colours() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64, 48);
    let mut t: Vec<f32> = (0..w * h)
        .map(|i| 290.0 + (i % w) as f32 / 63.0 * 20.0)
        .collect();
    t[0] = f32::NAN;
    let p = dir.path().join("q.png");
    let range = write_quicklook_png(&p, w, h, &t, None).unwrap();
    assert_eq!(range, (290.0, 310.0));
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&p).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let cw = w.max(output::MIN_CANVAS_WIDTH);
    assert_eq!(
        (info.width as usize, info.height as usize),
        (cw, h + output::BAR_AREA_HEIGHT)
    );
    let px = |x: usize, y: usize| {
        let i = 3 * (y * cw + x);
        [buf[i], buf[i + 1], buf[i + 2]]
    };
    assert_eq!(px(w - 1, 5), output::inferno(1.0));
    assert_eq!(px(0, 5), output::inferno(0.0));
    assert_eq!(px(0, 0), [128, 128, 128]);
    // The same pixels as the in-memory rendering, and the bar area holds
    // light text pixels (the labels).
    let img = render_quicklook(w, h, &t, Some(range)).unwrap();
    assert_eq!(img.pixels, buf[..img.pixels.len()]);
    let text_px = (h + 20..h + output::BAR_AREA_HEIGHT)
        .flat_map(|y| (0..cw).map(move |x| (x, y)))
        .filter(|&(x, y)| img.get(x, y) == [235, 235, 235])
        .count();
    assert!(text_px > 100, "{text_px} label pixels");
}

#[test]
fn info_json_reports_layer_statistics() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("i.exr");
    let mut s = ImageStack::new(4, 2);
    s.push("a", vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0])
        .unwrap();
    s.push("b", vec![f32::NAN, -1.0, 0.5, 0.5, 0.5, 0.5, 0.5, 3.0])
        .unwrap();
    s.push("c", vec![f32::NAN; 8]).unwrap();
    write_exr(&p, &s).unwrap();
    let out = std::process::Command::new(util::irsig_bin())
        .args(["info", "--json"])
        .arg(&p)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["width"], 4);
    assert_eq!(v["height"], 2);
    let l = v["layers"].as_array().unwrap();
    assert_eq!(l.len(), 3);
    assert_eq!(l[0]["name"], "a");
    assert_eq!(l[0]["min"], 1.0);
    assert_eq!(l[0]["max"], 8.0);
    assert_eq!(l[0]["mean"], 4.5);
    assert_eq!(l[0]["nan_count"], 0);
    assert_eq!(l[1]["min"], -1.0);
    assert_eq!(l[1]["max"], 3.0);
    assert_eq!(l[1]["mean"], 4.5 / 7.0);
    assert_eq!(l[1]["nan_count"], 1);
    assert!(l[2]["mean"].is_null());
    assert_eq!(l[2]["nan_count"], 8);
    let keys: Vec<&String> = l[0].as_object().unwrap().keys().collect();
    assert_eq!(keys.len(), 5);

    // Human-readable form, and a clear error for a missing file.
    let out = std::process::Command::new(util::irsig_bin())
        .arg("info")
        .arg(&p)
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&out.stdout).contains("width  4"));
    let out = std::process::Command::new(util::irsig_bin())
        .args(["info"])
        .arg(dir.path().join("missing.exr"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.exr"));
}

// ---------------------------------------------------------------------------
// Sensor geometry
// ---------------------------------------------------------------------------

use glam::{DVec2, DVec3};
use irsig::Location;
use irsig::sensor::effects::{self, Mtf, Psf};
use irsig::sensor::{Geometry, LineScanner, Sensor, SensorConfig};

fn sensor_from_json(json: &str) -> irsig::Result<Sensor> {
    let cfg: SensorConfig = serde_json::from_str(json).expect("valid sensor JSON");
    Sensor::from_config(&cfg, &Location::file("scene.json").with_field("sensors[0]"))
}

fn frame(json_extra: &str) -> Sensor {
    sensor_from_json(&format!(
        r#"{{"type": "frame", "name": "cam", "width": 64, "height": 48,
            "position": [10, -20, 30], "look_at": [40, 60, 2], "up": [0, 0, 1],
            "bands": [{{"name": "lwir", "response": [8.0, 12.0]}}] {json_extra}}}"#
    ))
    .unwrap()
}

fn camera(s: &Sensor) -> &irsig::sensor::FrameCamera {
    match &s.geometry {
        Geometry::Frame(c) => c,
        _ => panic!("not a frame camera"),
    }
}

fn scanner(s: &Sensor) -> &LineScanner {
    match &s.geometry {
        Geometry::LineScanner(c) => c,
        _ => panic!("not a line scanner"),
    }
}

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).length() <= tol
}

#[test]
fn camera_centre_looks_at_target_and_fov_edges_are_at_half_fov() {
    let s = frame(r#", "focal_length_m": 0.05, "pixel_pitch_m": 25e-6, "oversample": 3"#);
    let c = camera(&s);
    let pos = DVec3::new(10.0, -20.0, 30.0);
    let target = DVec3::new(40.0, 60.0, 2.0);
    let axis = (target - pos).normalize();
    // The array centre (W/2, H/2) looks along the optical axis at the target.
    assert!(close(c.direction(32.0, 24.0), axis, 1e-12));
    let p = c.project(target).unwrap();
    assert!((p - DVec2::new(32.0, 24.0)).length() < 1e-9, "{p}");
    // f/p = 2000 px: the column edge u = 0 is atan(32/2000) off axis.
    assert!((c.focal_px - 2000.0).abs() < 1e-9);
    let edge = c.direction(0.0, 24.0).angle_between(axis);
    assert!((edge - (32.0f64 / 2000.0).atan()).abs() < 1e-12);

    // Field of view given directly: edges at ±fov/2, left edge to the west
    // for a camera looking north with z up.
    let s = sensor_from_json(
        r#"{"type": "frame", "name": "c2", "width": 101, "height": 51, "fov_deg": 40,
            "position": [0, 0, 5], "look_at": [0, 100, 5],
            "bands": [{"name": "b", "response": [8, 12]}]}"#,
    )
    .unwrap();
    let c = camera(&s);
    let fwd = DVec3::Y;
    for u in [0.0, 101.0] {
        let a = c.direction(u, 25.5).angle_between(fwd);
        assert!((a.to_degrees() - 20.0).abs() < 1e-9, "{}", a.to_degrees());
    }
    assert!(c.direction(0.0, 25.5).x < 0.0 && c.direction(101.0, 25.5).x > 0.0);
    // Row 0 is at the top of the image: it looks up.
    assert!(c.direction(50.5, 0.0).z > 0.0);
    assert!((c.horizontal_fov().to_degrees() - 40.0).abs() < 1e-9);
}

#[test]
fn camera_projection_inverts_ray_generation() {
    let s = frame(r#", "fov_deg": 55, "oversample": 2"#);
    let c = camera(&s);
    for (u, v) in [(0.5, 0.5), (63.5, 47.5), (17.25, 40.75), (32.0, 3.0)] {
        let d = c.direction(u, v);
        for dist in [1.0, 37.0, 2500.0] {
            let p = c.position() + d * dist;
            let back = c.project(p).unwrap();
            assert!(
                (back - DVec2::new(u, v)).length() < 1e-8,
                "{u},{v} → {back}"
            );
        }
    }
    // Points behind the camera are not seen.
    let behind = c.position() - c.direction(32.0, 24.0) * 10.0;
    assert!(c.project(behind).is_none());
    // Oversampled row layout: N sub-rows of W·N rays, stratified.
    let mut rays = Vec::new();
    s.rays_for_row(5, &mut rays);
    assert_eq!(rays.len(), 64 * 4);
    assert_eq!(rays.len(), s.rays_per_row());
    let expect = |u: f64, v: f64| c.direction(u, v).as_vec3();
    assert!((rays[0].dir - expect(0.25, 5.25)).length() < 1e-6);
    assert!((rays[1].dir - expect(0.75, 5.25)).length() < 1e-6);
    assert!((rays[128].dir - expect(0.25, 5.75)).length() < 1e-6);
    assert!((rays[255].dir - expect(63.75, 5.75)).length() < 1e-6);
    assert!(rays.iter().all(|r| (r.dir.length() - 1.0).abs() < 1e-6));
    // Every ray of the row is `FrameCamera::ray` at its point, bit for bit.
    for (i, r) in rays.iter().enumerate() {
        let (j, k) = (i / 128, i % 128);
        assert_eq!(
            *r,
            c.ray((k as f64 + 0.5) / 2.0, 5.0 + (j as f64 + 0.5) / 2.0)
        );
    }
}

/// A row's rays, made from the camera's table of per-column terms, are the
/// rays `FrameCamera::ray` gives at the same points, bit for bit — also
/// after the public fields the table depends on changed.
#[test]
fn camera_tabulated_row_equals_per_ray_geometry() {
    let s = frame(r#", "fov_deg": 55, "oversample": 3"#);
    let mut c = camera(&s).clone();
    for change in 0..4 {
        match change {
            1 => c.width = 37,
            2 => c.focal_px *= 1.7,
            3 => {
                c.oversample = 2;
                c.world_from_camera.matrix3 =
                    glam::DMat3::from_rotation_z(0.3) * c.world_from_camera.matrix3;
            }
            _ => {}
        }
        let n = c.oversample;
        for row in [0usize, 7, 23] {
            let mut rays = Vec::new();
            c.rays_for_row(row, &mut rays);
            assert_eq!(rays.len(), c.width * n * n, "change {change}");
            for (i, r) in rays.iter().enumerate() {
                let (j, k) = (i / (c.width * n), i % (c.width * n));
                let want = c.ray(
                    (k as f64 + 0.5) / n as f64,
                    row as f64 + (j as f64 + 0.5) / n as f64,
                );
                assert_eq!(*r, want, "change {change}, row {row}, ray {i}");
            }
        }
    }
}

#[test]
fn sensor_config_errors_name_the_field() {
    let e = sensor_from_json(
        r#"{"type": "frame", "name": "c", "width": 4, "height": 4, "position": [0,0,1],
            "look_at": [0,1,1], "bands": [{"name": "b", "response": [8, 12]}]}"#,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("scene.json") && e.contains("sensors[0].focal_length_m"),
        "{e}"
    );
    let e = sensor_from_json(
        r#"{"type": "frame", "name": "c", "width": 4, "height": 4, "fov_deg": 30,
            "position": [0,0,1], "look_at": [0,0,1], "bands": [{"name": "b", "response": [8, 12]}]}"#,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("sensors[0].look_at"), "{e}");
    let e = sensor_from_json(
        r#"{"type": "line_scanner", "name": "s", "ifov_rad": 0.002, "scan_angle_deg": 200,
            "samples_per_line": 10, "lines": 5, "scan_rate_hz": 10, "altitude_m": 500,
            "ground_speed_m_s": 60, "heading_deg": 0, "start": [0, 0],
            "bands": [{"name": "b", "response": [8, 12]}]}"#,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("sensors[0].scan_angle_deg") && e.contains("180"),
        "{e}"
    );
    let e = sensor_from_json(
        r#"{"type": "frame", "name": "c", "width": 4, "height": 4, "fov_deg": 30,
            "position": [0,0,1], "look_at": [0,1,1], "bands": [{"name": "b", "response": [12, 8]}]}"#,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("sensors[0].bands") && e.contains("lo < hi"),
        "{e}"
    );
    // Unknown keys are rejected, not ignored.
    let r: Result<SensorConfig, _> = serde_json::from_str(
        r#"{"type": "frame", "name": "c", "width": 4, "height": 4, "fov_deg": 30, "colour": 1,
            "position": [0,0,1], "look_at": [0,1,1], "bands": []}"#,
    );
    assert!(r.unwrap_err().to_string().contains("colour"));
    // A response given as a file name.
    let cfg: SensorConfig = serde_json::from_str(
        r#"{"type": "frame", "name": "c", "width": 4, "height": 4, "fov_deg": 30,
            "position": [0,0,1], "look_at": [0,1,1],
            "bands": [{"name": "b", "response": "resp/lwir.csv"}]}"#,
    )
    .unwrap();
    let SensorConfig::Frame(f) = cfg else {
        panic!()
    };
    assert_eq!(
        f.bands[0].response,
        irsig::sensor::ResponseSpec::File("resp/lwir.csv".into())
    );
}

fn scanner_json(extra: &str) -> Sensor {
    sensor_from_json(&format!(
        r#"{{"type": "line_scanner", "name": "bendix", "ifov_rad": 0.0157079632679,
            "scan_angle_deg": 90, "samples_per_line": 100, "lines": 40, "scan_rate_hz": 10,
            "altitude_m": 1000, "ground_speed_m_s": 50, "start": [0, 0],
            "bands": [{{"name": "b", "response": [8, 14]}}] {extra}}}"#
    ))
    .unwrap()
}

/// Where a ray meets the ground plane z = 0.
fn ground(r: &irsig::trace::Ray) -> DVec3 {
    let (o, d) = (r.origin.as_dvec3(), r.dir.as_dvec3());
    o + d * (-o.z / d.z)
}

#[test]
fn line_scanner_nadir_edges_and_panoramic_geometry() {
    let s = scanner_json(r#", "heading_deg": 0"#);
    let sc = scanner(&s);
    // Line l is flown at y = v·l/rate = 5 m per line; the point straight
    // below lands on the middle of the line (sample S/2, line l + ½).
    for l in [0usize, 7, 39] {
        let below = DVec3::new(0.0, 5.0 * l as f64, 0.0);
        let p = sc.project(below).unwrap();
        assert!(
            (p - DVec2::new(l as f64 + 0.5, 50.0)).length() < 1e-9,
            "{p}"
        );
        let nadir = sc.ray(l, 50.0, 0.0);
        assert!(close(nadir.dir.as_dvec3(), -DVec3::Z, 1e-7));
        assert!(close(
            nadir.origin.as_dvec3(),
            DVec3::new(0.0, 5.0 * l as f64, 1000.0),
            1e-3
        ));
    }
    // Scan edges at ±45° from nadir; flying north, sample 0 looks west.
    let west = sc.ray(3, 0.0, 0.0).dir.as_dvec3();
    let east = sc.ray(3, 100.0, 0.0).dir.as_dvec3();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert!(close(west, DVec3::new(-h, 0.0, -h), 1e-7), "{west}");
    assert!(close(east, DVec3::new(h, 0.0, -h), 1e-7), "{east}");
    // Ground point 405 m east of track at line 12: θ = atan(405/1000) →
    // sample S/2 + θ/Δθ (Δθ = 0.9°).
    let p = sc.project(DVec3::new(405.0, 60.0, 0.0)).unwrap();
    let theta = (405.0f64 / 1000.0).atan().to_degrees();
    assert!((p.y - (50.0 + theta / 0.9)).abs() < 1e-9);
    assert!((p.x - 12.5).abs() < 1e-9);
    // Panoramic distortion: ground step between samples grows as 1/cos²θ.
    let step = |s0: f64| {
        let a = ground(&sc.ray(0, s0, 0.0));
        let b = ground(&sc.ray(0, s0 + 1.0, 0.0));
        (b - a).length()
    };
    let nadir_step = step(49.5);
    let theta_edge = sc.scan_angle(95.0);
    let ratio = step(94.5) / nadir_step;
    assert!(
        (ratio - 1.0 / theta_edge.cos().powi(2)).abs() < 2e-3,
        "{ratio}"
    );
    assert!((nadir_step - 1000.0 * 0.9f64.to_radians()).abs() < 0.01);
}

#[test]
fn line_scanner_heading_roll_and_mirror_sweep() {
    // Flying east: starboard is south, so a point north of track (left)
    // is at negative scan angle.
    let s = scanner_json(r#", "heading_deg": 90"#);
    let sc = scanner(&s);
    let p = sc.project(DVec3::new(50.0, 300.0, 0.0)).unwrap();
    let theta = -(300.0f64 / 1000.0).atan();
    assert!(
        (p.y - (50.0 + theta.to_degrees() / 0.9)).abs() < 1e-9,
        "{p}"
    );
    assert!((p.x - 10.5).abs() < 1e-9);

    // Roll 2° right wing down: the body's down axis tilts to port, so the
    // point straight below is seen 2° to starboard of the scan centre.
    let s = scanner_json(r#", "heading_deg": 0, "roll_deg": 2"#);
    let p = scanner(&s).project(DVec3::new(0.0, 100.0, 0.0)).unwrap();
    assert!((p.y - (50.0 + 2.0 / 0.9)).abs() < 1e-9, "{p}");

    // Mirror sweep: one revolution per line; the nadir sample comes
    // (A/2)/(2π) = 1/8 of a line period after the line start.
    let s = scanner_json(r#", "heading_deg": 0, "mirror_sweep": true"#);
    let p = scanner(&s).project(DVec3::new(0.0, 50.0, 0.0)).unwrap();
    assert!((p.x - (10.5 - 0.125)).abs() < 1e-9, "{p}");
    let r = scanner(&s).ray(10, 50.0, 0.0);
    assert!((r.origin.y as f64 - (50.0 + 5.0 / 8.0)).abs() < 1e-4);
}

#[test]
fn line_scanner_ground_points_land_on_predicted_pixels_with_attitude() {
    let s = scanner_json(
        r#", "heading_deg": 30, "roll_deg": 3, "pitch_deg": -2, "yaw_deg": 4,
           "mirror_sweep": true, "start_time": 12.5, "oversample": 3"#,
    );
    let sc = scanner(&s);
    for (l, smp) in [(0usize, 0usize), (5, 50), (17, 3), (39, 99), (22, 71)] {
        let r = sc.ray(l, smp as f64 + 0.5, 0.0);
        let g = ground(&r);
        let p = sc.project(g).unwrap();
        assert!(
            (p - DVec2::new(l as f64 + 0.5, smp as f64 + 0.5)).length() < 1e-4,
            "({l}, {smp}) → {p}"
        );
        // Sensor::project reports (column, row) = (sample, line).
        let q = s.project(g).unwrap();
        assert!((q - DVec2::new(p.y, p.x)).length() < 1e-12);
    }
    assert_eq!(s.row_time(4), 12.5 + 0.4);
    let mut rays = Vec::new();
    s.rays_for_row(2, &mut rays);
    assert_eq!(rays.len(), 100 * 9);
    // The middle sub-ray of sample 10 (sub-line 1, i = 1) is its centre ray.
    let centre = sc.ray(2, 10.5, 0.0);
    let mid = rays[300 + 10 * 3 + 1];
    assert!((mid.dir - centre.dir).length() < 1e-6);
    assert!((mid.origin - centre.origin).length() < 1e-3);
}

/// A scan line's rays, made from the scanner's table of scan angles, are
/// the rays `LineScanner::ray` gives at the same coordinates, bit for bit —
/// with and without the mirror sweep, and after public fields changed (scan
/// angles; attitude, scan rate and sweep).
#[test]
fn line_scanner_tabulated_line_equals_per_ray_geometry() {
    for extra in [
        r#", "heading_deg": 30, "roll_deg": 3, "pitch_deg": -2, "yaw_deg": 4, "oversample": 3"#,
        r#", "heading_deg": 200, "mirror_sweep": true, "start_time": 4.5, "oversample": 2"#,
    ] {
        let s = scanner_json(extra);
        let mut sc = scanner(&s).clone();
        for change in 0..3 {
            if change == 1 {
                // Fields the scan angles depend on, changed after `new`.
                sc.ifov_rad *= 1.5;
                sc.samples_per_line = 37;
            }
            if change == 2 {
                // Fields the directions and sweep delays depend on.
                sc.world_from_body = glam::DMat3::from_rotation_z(0.1) * sc.world_from_body;
                sc.scan_rate_hz *= 1.3;
                sc.mirror_sweep = !sc.mirror_sweep;
            }
            let n = sc.oversample;
            let step = sc.sample_step_rad();
            for line in [0usize, 13, 39] {
                let mut rays = Vec::new();
                sc.rays_for_line(line, &mut rays);
                assert_eq!(rays.len(), sc.samples_per_line * n * n);
                let mut k = 0;
                for j in 0..n {
                    let phi = ((j as f64 + 0.5) / n as f64 - 0.5) * sc.ifov_rad;
                    for smp in 0..sc.samples_per_line {
                        for i in 0..n {
                            let ds = ((i as f64 + 0.5) / n as f64 - 0.5) * sc.ifov_rad / step;
                            let want = sc.ray(line, smp as f64 + 0.5 + ds, phi);
                            assert_eq!(
                                rays[k], want,
                                "line {line}, sub-line {j}, sample {smp}.{i}"
                            );
                            k += 1;
                        }
                    }
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------
// Sensor effects
// ---------------------------------------------------------------------------

#[test]
fn psf_reduction_preserves_flat_fields_block_means_and_energy() {
    let (w, h, n) = (13, 9, 3);
    let flat = vec![7.25f32; w * n * h * n];
    for psf in [Psf::Box, Psf::Gaussian { sigma_px: 0.7 }] {
        let out = effects::reduce_oversampled(&flat, w, h, n, psf).unwrap();
        assert!(out.iter().all(|v| (v - 7.25).abs() < 1e-5), "{psf:?}");
    }
    // Box: the mean of each pixel's own N×N block.
    let ramp: Vec<f32> = (0..w * n * h * n).map(|i| (i % 97) as f32).collect();
    let out = effects::reduce_oversampled(&ramp, w, h, n, Psf::Box).unwrap();
    let (x, y) = (4, 6);
    let mut s = 0.0;
    for j in 0..n {
        for i in 0..n {
            s += ramp[(y * n + j) * w * n + x * n + i];
        }
    }
    assert!((out[y * w + x] - s / 9.0).abs() < 1e-4);
    // Energy: an interior impulse of E on the sub-sample grid spreads into
    // pixels summing to E/N² (the radiance of one sub-sample's share).
    let (w, h, n) = (21, 21, 4);
    let mut imp = vec![0f32; w * n * h * n];
    imp[(42) * w * n + 41] = 16.0;
    for psf in [Psf::Box, Psf::Gaussian { sigma_px: 0.8 }] {
        let out = effects::reduce_oversampled(&imp, w, h, n, psf).unwrap();
        let total: f64 = out.iter().map(|&v| v as f64).sum();
        assert!((total - 1.0).abs() < 1e-4, "{psf:?}: {total}");
        if let Psf::Gaussian { .. } = psf {
            // Spread over neighbours, peak at the impulse's pixel (10, 10).
            let peak = out.iter().cloned().fold(0f32, f32::max);
            assert_eq!(out[10 * w + 10], peak);
            assert!(out[10 * w + 11] > 0.0 && out[9 * w + 10] > 0.0);
        }
    }
    assert!(effects::reduce_oversampled(&imp[1..], w, h, n, Psf::Box).is_err());
}

#[test]
fn mtf_scales_a_cosine_by_the_transfer_at_its_frequency() {
    // Published point: diffraction MTF at half the cutoff = 0.3910.
    assert!((effects::diffraction_mtf(0.5) - 0.391_002).abs() < 1e-6);
    assert_eq!(effects::diffraction_mtf(0.0), 1.0);
    assert_eq!(effects::diffraction_mtf(1.2), 0.0);
    let (w, h) = (64, 8);
    let mtf = Mtf {
        optics_cutoff_cycles_per_px: Some(0.4),
        fill_factor: Some(0.8),
    };
    for k in [8usize, 16, 40] {
        let f = k as f64 / (2 * w) as f64;
        let pat: Vec<f64> = (0..w * h)
            .map(|i| (std::f64::consts::TAU * f * ((i % w) as f64 + 0.5)).cos())
            .collect();
        let mut img: Vec<f32> = pat.iter().map(|&c| (300.0 + 10.0 * c) as f32).collect();
        effects::apply_mtf(&mut img, w, h, &mtf).unwrap();
        let mean: f64 = img.iter().map(|&v| v as f64).sum::<f64>() / (w * h) as f64;
        let amp: f64 = img
            .iter()
            .zip(&pat)
            .map(|(&v, c)| (v as f64 - mean) * c)
            .sum::<f64>()
            / pat.iter().map(|c| c * c).sum::<f64>();
        let expect = 10.0 * effects::diffraction_mtf(f / 0.4) * effects::sinc(0.8 * f);
        assert!((mean - 300.0).abs() < 1e-4, "DC changed: {mean}");
        assert!((amp - expect).abs() < 2e-4, "k={k}: {amp} vs {expect}");
    }
}

/// Planck spectral radiance, W·m⁻²·sr⁻¹·m⁻¹ (λ in m, T in K).
fn planck(lambda: f64, t: f64) -> f64 {
    const H: f64 = 6.626_070_15e-34;
    const C: f64 = 299_792_458.0;
    const K: f64 = 1.380_649e-23;
    2.0 * H * C * C / lambda.powi(5) / ((H * C / (lambda * K * t)).exp() - 1.0)
}

#[test]
fn nedt_noise_has_the_predicted_sigma_and_is_deterministic() {
    let lambda = 10e-6;
    let t = 300.0;
    // dL/dT analytically: L·x·eˣ/((eˣ − 1)·T), x = hc/(λkT).
    let x = 6.626_070_15e-34 * 299_792_458.0 / (lambda * 1.380_649e-23 * t);
    let dldt = planck(lambda, t) * x * x.exp() / ((x.exp() - 1.0) * t);
    let sigma = effects::radiance_sigma_from_nedt(0.05, t, |tt| planck(lambda, tt) * 1e-6);
    assert!((sigma / (0.05 * dldt * 1e-6) - 1.0).abs() < 1e-6);

    let (w, h) = (256, 256);
    let base = vec![9.0f32; w * h];
    let mut img = base.clone();
    effects::add_noise(&mut img, w, 0, sigma, 42, 0);
    let n = (w * h) as f64;
    let mean = img.iter().map(|&v| v as f64).sum::<f64>() / n;
    let sd = (img.iter().map(|&v| (v as f64 - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    assert!((mean - 9.0).abs() < 4.0 * sigma / n.sqrt(), "{mean}");
    // Standard error of a sample σ is σ/√(2n) ≈ 0.28 %.
    assert!((sd / sigma - 1.0).abs() < 0.012, "{sd} vs {sigma}");

    // Bit-identical for 1 and 2 threads and for row-band tiling.
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut v = base.clone();
            effects::add_noise(&mut v, w, 0, sigma, 42, 0);
            v
        })
    };
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&run(1)), bits(&img));
    assert_eq!(bits(&run(2)), bits(&img));
    let mut tiled = base.clone();
    let (top, bottom) = tiled.split_at_mut(100 * w);
    effects::add_noise(top, w, 0, sigma, 42, 0);
    effects::add_noise(bottom, w, 100, sigma, 42, 0);
    assert_eq!(bits(&tiled), bits(&img));
    let mut other = base.clone();
    effects::add_noise(&mut other, w, 0, sigma, 43, 0);
    assert_ne!(bits(&other), bits(&img));
    let mut band1 = base;
    effects::add_noise(&mut band1, w, 0, sigma, 42, 1);
    assert_ne!(bits(&band1), bits(&img));
}

#[test]
fn quantisation_step_offset_and_saturation() {
    let (gain, offset) = (100.0, 10.0);
    let l: Vec<f32> = vec![0.5, 0.51, 0.52, -1.0, 2.44, 2.46, 50.0, f32::NAN];
    let c = effects::quantise(&l, 8, gain, offset);
    assert_eq!(&c[..7], &[60.0, 61.0, 62.0, 0.0, 254.0, 255.0, 255.0]);
    assert!(c[7].is_nan());
    // One count per 1/gain of radiance over the whole 12-bit range.
    let ramp: Vec<f32> = (0..4000).map(|i| i as f32 / 100.0).collect();
    let c = effects::quantise(&ramp, 12, gain, 0.0);
    for (i, v) in c.iter().enumerate() {
        assert_eq!(*v, (i as f32).min(4095.0));
    }
}

#[test]
fn effects_chain_from_config_is_deterministic() {
    let s = frame(
        r#", "fov_deg": 30, "oversample": 2, "psf": {"type": "gaussian", "sigma_px": 0.6},
           "mtf": {"aperture_diameter_m": 0.05, "fill_factor": 1.0},
           "nedt_k": 0.05, "bits": 14, "gain": 500, "offset": 100, "seed": 7"#,
    );
    let m = s.effects.mtf.unwrap().at(10.0);
    // Cutoff D/λ · (pixel angle): λ = 10 µm (band centre), pixel angle =
    // 1/focal_px.
    let c = camera(&s);
    let expect = 0.05 / 10e-6 / c.focal_px;
    assert!((m.optics_cutoff_cycles_per_px.unwrap() - expect).abs() < 1e-12);
    let bands = s
        .resolve_bands(
            std::path::Path::new("."),
            0.05,
            &Location::file("scene.json").with_field("sensors[0]"),
        )
        .unwrap();
    assert!((effects::band_centre_um(&bands[0]) - 10.0).abs() < 1e-9);
    // σ_L = NEdT·dL/dT, the analytic derivative against a central difference.
    let sigma = s.effects.noise_sigma(&bands[0]);
    let numeric =
        effects::radiance_sigma_from_nedt(0.05, 300.0, |t| bands[0].blackbody_radiance(t));
    assert!((sigma / numeric - 1.0).abs() < 1e-6, "{sigma} {numeric}");
    let (w, h, n) = (64, 48, 2);
    let over: Vec<f32> = (0..w * n * h * n)
        .map(|i| 8.0 + (i % 13) as f32 * 0.01)
        .collect();
    let a = s.effects.apply(&over, w, h, n, 0, &bands[0]).unwrap();
    let b = s.effects.apply(&over, w, h, n, 0, &bands[0]).unwrap();
    assert_eq!(a, b);
    let counts = a.counts.unwrap();
    assert!(
        counts
            .iter()
            .all(|&v| (0.0..=16383.0).contains(&v) && v.fract() == 0.0)
    );
    let mean: f64 = counts.iter().map(|&v| v as f64).sum::<f64>() / counts.len() as f64;
    assert!((mean - (500.0 * 8.06 + 100.0)).abs() < 2.0, "{mean}");
}

#[test]
fn band_responses_resolve_from_ranges_and_csv_files() {
    let dir = tempfile::tempdir().unwrap();
    // A symmetric triangular response: centre 10 µm.
    std::fs::write(
        dir.path().join("tri.csv"),
        "wavelength_um,response\n9.0,0\n10.0,1\n11.0,0\n",
    )
    .unwrap();
    let cfg: SensorConfig = serde_json::from_str(
        r#"{"type": "frame", "name": "c", "width": 4, "height": 4, "fov_deg": 30,
            "position": [0,0,1], "look_at": [0,1,1],
            "bands": [{"name": "tri", "response": "tri.csv"},
                      {"name": "mw", "response": [3.0, 5.0]}]}"#,
    )
    .unwrap();
    let loc = Location::file("scene.json").with_field("sensors[2]");
    let s = Sensor::from_config(&cfg, &loc).unwrap();
    let bands = s.resolve_bands(dir.path(), 0.01, &loc).unwrap();
    assert!((effects::band_centre_um(&bands[0]) - 10.0).abs() < 1e-9);
    assert!((bands[0].equivalent_width_um() - 1.0).abs() < 1e-9);
    assert!((effects::band_centre_um(&bands[1]) - 4.0).abs() < 1e-9);
    // A missing file is an error naming it.
    let e = s
        .resolve_bands(&dir.path().join("nowhere"), 0.01, &loc)
        .unwrap_err()
        .to_string();
    assert!(e.contains("tri.csv"), "{e}");
}

#[test]
fn image_set_writes_exr_envi_and_png() {
    let dir = tempfile::tempdir().unwrap();
    let s = sample_stack(12, 7);
    let paths =
        output::write_image_set(dir.path(), "cam", &s, &[("band0_radiance", 10.0)], "irsig")
            .unwrap();
    assert_eq!(
        listing(dir.path()),
        vec!["cam.exr", "cam.hdr", "cam.img", "cam.png"]
    );
    assert_bit_identical(&s, &read_exr(&paths.exr).unwrap());
    let e = read_envi(&paths.envi.unwrap().1).unwrap();
    assert_eq!(e.stack.layers.len(), 1);
    assert_eq!(e.stack.layers[0], s.layers[0]);
    assert_eq!(e.wavelengths, Some(vec![10.0]));
    assert!(paths.png.is_some());
    // A missing spectral layer fails before anything is written.
    let d2 = tempfile::tempdir().unwrap();
    assert!(output::write_image_set(d2.path(), "x", &s, &[("nope", 4.0)], "").is_err());
    assert!(listing(d2.path()).is_empty());
}

/// Issue 21: band limits given in nanometres (or otherwise outside
/// 0.2–100 µm) are an error naming the field, with the µm reading; response
/// files likewise, naming file, line and column.
#[test]
fn bands_in_nanometres_are_errors() {
    let e = sensor_from_json(
        r#"{"type": "frame", "name": "c", "width": 4, "height": 4, "fov_deg": 30,
            "position": [0,0,1], "look_at": [0,1,1], "bands": [{"name": "lwir", "response": [8000, 12000]}]}"#,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("sensors[0].bands")
            && e.contains("outside 0.2–100 µm")
            && e.contains("[8, 12] µm"),
        "{e}"
    );
    let e = sensor_from_json(
        r#"{"type": "frame", "name": "c", "width": 4, "height": 4, "fov_deg": 30,
            "position": [0,0,1], "look_at": [0,1,1], "bands": [{"name": "uv", "response": [0.1, 0.3]}]}"#,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("outside 0.2–100 µm"), "{e}");
    let e = irsig::radiometry::response::parse_response_csv(
        "wavelength_um,response\n7800,0\n8000,1\n",
        "nm.csv",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("nm.csv") && e.contains("line 2") && e.contains("outside 0.2–100 µm"),
        "{e}"
    );
}
