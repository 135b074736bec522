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
