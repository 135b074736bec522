//! Tests: analysis — statistics against hand-computed and textbook values,
//! image/point comparison, geometric accuracy, sensitivity, calibration.

use irsig::analysis::compare::{self, CompareOptions};
use irsig::analysis::csv;
use irsig::analysis::image;
use irsig::analysis::stats::{self, Agreement, Histogram};
use irsig::output::{ImageStack, Layer};

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

macro_rules! assert_close {
    ($a:expr, $b:expr, $tol:expr) => {{
        let (a, b, t) = ($a as f64, $b as f64, $tol as f64);
        assert!(
            close(a, b, t),
            "{} = {a} but expected {b} ± {t}",
            stringify!($a)
        );
    }};
}

// ---- statistics ---------------------------------------------------------

#[test]
fn rmse_bias_mae_hand_computed() {
    // residuals: +1, −2, +3, 0 → bias 0.5, MAE 1.5, RMSE sqrt(14/4)
    let p = [11.0, 18.0, 33.0, 40.0];
    let t = [10.0, 20.0, 30.0, 40.0];
    assert_close!(stats::bias(&p, &t).unwrap(), 0.5, 1e-15);
    assert_close!(stats::mae(&p, &t).unwrap(), 1.5, 1e-15);
    assert_close!(stats::rmse(&p, &t).unwrap(), (14.0f64 / 4.0).sqrt(), 1e-15);
    assert!(stats::rmse(&p, &t[..3]).is_err());
    assert!(stats::rmse(&[], &[]).is_err());
}

#[test]
fn pearson_anscombe_quartet_set_one() {
    // Anscombe (1973), data set I: r = 0.816 (0.81642).
    let x = [10.0, 8.0, 13.0, 9.0, 11.0, 14.0, 6.0, 4.0, 12.0, 7.0, 5.0];
    let y = [
        8.04, 6.95, 7.58, 8.81, 8.33, 9.96, 7.24, 4.26, 10.84, 4.82, 5.68,
    ];
    assert_close!(stats::pearson(&x, &y).unwrap(), 0.81642, 5e-5);
}

#[test]
fn spearman_textbook_iq_vs_television() {
    // Wikipedia, "Spearman's rank correlation coefficient", worked example
    // (IQ vs hours of TV per week, no ties): Σd² = 194, ρ = 1 − 6·194/(10·99) = −29/165.
    let iq = [
        106.0, 100.0, 86.0, 101.0, 99.0, 103.0, 97.0, 113.0, 112.0, 110.0,
    ];
    let tv = [7.0, 27.0, 2.0, 50.0, 28.0, 29.0, 20.0, 12.0, 6.0, 17.0];
    assert_close!(stats::spearman(&iq, &tv).unwrap(), -29.0 / 165.0, 1e-12);
}

#[test]
fn average_ranks_share_ties() {
    assert_eq!(
        stats::average_ranks(&[3.0, 1.0, 4.0, 1.0, 5.0, 9.0, 2.0, 6.0, 5.0]),
        vec![4.0, 1.5, 5.0, 1.5, 6.5, 9.0, 3.0, 8.0, 6.5]
    );
    assert_eq!(stats::average_ranks(&[7.0, 7.0, 7.0]), vec![2.0, 2.0, 2.0]);
}

#[test]
fn spearman_with_ties_hand_computed() {
    // y = [5,6,7,8,7] → ranks [1,2,3.5,5,3.5]; x ranks 1..5.
    // Σdx·dy = 8, Σdx² = 10, Σdy² = 9.5 → ρ = 8/√95 = 0.8207826816681233
    // (also SciPy's documented spearmanr([1,2,3,4,5],[5,6,7,8,7])).
    let x = [1.0, 2.0, 3.0, 4.0, 5.0];
    let y = [5.0, 6.0, 7.0, 8.0, 7.0];
    assert_close!(stats::spearman(&x, &y).unwrap(), 8.0 / 95f64.sqrt(), 1e-14);
    assert_close!(stats::spearman(&x, &y).unwrap(), 0.8207826816681233, 1e-14);
    // Ties in both: x ranks [1,2.5,2.5,4], y ranks [1,3,2,4] → ρ = 4.5/√22.5 = 3/√10.
    let x = [1.0, 2.0, 2.0, 3.0];
    let y = [1.0, 3.0, 2.0, 4.0];
    assert_close!(stats::spearman(&x, &y).unwrap(), 3.0 / 10f64.sqrt(), 1e-14);
    // With ties the 1 − 6Σd²/(n(n²−1)) shortcut is wrong; ours is not that:
    // Σd² = 0.25·2 = 0.5 → shortcut 0.95 ≠ 0.948683.
    assert!((stats::spearman(&x, &y).unwrap() - 0.95).abs() > 1e-3);
    // Monotone but non-linear → ρ = 1; a constant sample → undefined (NaN).
    let z: Vec<f64> = x.iter().map(|v: &f64| v.powi(3)).collect();
    assert_close!(stats::spearman(&x, &z).unwrap(), 1.0, 1e-15);
    assert!(stats::spearman(&x, &[1.0; 4]).unwrap().is_nan());
    assert!(stats::spearman(&[1.0, f64::NAN], &[1.0, 2.0]).is_err());
}

#[test]
fn agreement_skips_non_finite_pairs_and_histogram_counts() {
    let p = [1.0, f64::NAN, 3.0, 4.0];
    let t = [1.0, 2.0, f64::INFINITY, 5.0];
    let a = Agreement::of(&p, &t).unwrap();
    assert_eq!(a.n, 2);
    assert_close!(a.bias, -0.5, 1e-15);
    assert!(Agreement::of(&[f64::NAN], &[1.0]).is_err());
    let h = Histogram::new([0.0, 0.5, 1.0, 1.5, 2.0, 3.0, -1.0, f64::NAN], 0.0, 2.0, 4).unwrap();
    assert_eq!(h.counts, vec![1, 1, 1, 2]);
    assert_eq!((h.below, h.above, h.total()), (1, 1, 5));
    assert_close!(h.bin_centre(1), 0.75, 1e-15);
}

// ---- comparison ------------------------------------------------------------

fn stack(w: usize, h: usize, layers: &[(&str, Vec<f32>)]) -> ImageStack {
    ImageStack {
        width: w,
        height: h,
        layers: layers
            .iter()
            .map(|(n, d)| Layer {
                name: n.to_string(),
                data: d.clone(),
            })
            .collect(),
    }
}

#[test]
fn image_comparison_overall_and_per_material() {
    // 3×2 image, materials 0 (left column pair) and 7; background NaN id.
    let synth = stack(
        3,
        2,
        &[
            (
                "apparent_temperature",
                vec![300.0, 301.0, 302.0, 310.0, 311.0, 312.0],
            ),
            ("material_id", vec![0.0, 0.0, 7.0, 7.0, 7.0, f32::NAN]),
        ],
    );
    let truth = stack(
        3,
        2,
        &[("value", vec![299.0, 300.0, 303.0, 309.0, 312.0, 312.0])],
    );
    let c = compare::compare_images(&synth, &truth, &CompareOptions::default()).unwrap();
    assert_eq!(c.layer, "apparent_temperature");
    assert_eq!(c.unit, "K");
    // residuals +1 +1 −1 +1 −1 0 → bias 1/6, RMSE sqrt(5/6)
    assert_close!(c.overall.bias, 1.0 / 6.0, 1e-6);
    assert_close!(c.overall.rmse, (5.0f64 / 6.0).sqrt(), 1e-6);
    assert_eq!(c.per_material.len(), 2);
    let m0 = &c.per_material[0];
    assert_eq!((m0.material.as_str(), m0.agreement.n), ("0", 2));
    assert_close!(m0.agreement.bias, 1.0, 1e-6);
    let m7 = &c.per_material[1];
    assert_eq!((m7.material.as_str(), m7.agreement.n), ("7", 3));
    assert_close!(m7.agreement.bias, -1.0 / 3.0, 1e-6);
    assert_eq!(c.synth_histogram.total(), 6);
    assert_eq!(c.truth_histogram.total(), 6);
    // Size mismatch is an error naming both sizes.
    let small = stack(2, 2, &[("value", vec![0.0; 4])]);
    let e = compare::compare_images(&synth, &small, &CompareOptions::default()).unwrap_err();
    assert!(e.to_string().contains("2×2"), "{e}");
}

#[test]
fn points_csv_comparison_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("pts.csv");
    std::fs::write(&p, "# field radiometer\nx,y,value,material\n0.5,0.5,299,grass\n2.9,1.2,311,\n1,0,300.5,grass\n").unwrap();
    let synth = stack(
        3,
        2,
        &[
            (
                "apparent_temperature",
                vec![300.0, 301.0, 302.0, 310.0, 311.0, 312.0],
            ),
            ("material_id", vec![0.0, 0.0, 7.0, 7.0, 7.0, 7.0]),
        ],
    );
    let pts = csv::read_truth_points(&p).unwrap();
    assert_eq!(pts.len(), 3);
    let c = compare::compare_points(&synth, &pts, &p, &CompareOptions::default()).unwrap();
    let r: Vec<f64> = c.points.iter().map(|q| q.residual).collect();
    assert_eq!(r, vec![1.0, 1.0, 0.5]);
    assert_eq!(c.points[1].pixel, [2, 1]);
    // Unlabelled point takes the pixel's material id.
    assert_eq!(c.points[1].material.as_deref(), Some("7"));
    assert_eq!(c.per_material.len(), 2);
    // Errors name file and line.
    std::fs::write(&p, "x,y,value\n0,0,300\n5,0,300\n").unwrap();
    let pts = csv::read_truth_points(&p).unwrap();
    let e = compare::compare_points(&synth, &pts, &p, &CompareOptions::default()).unwrap_err();
    assert!(e.to_string().contains("pts.csv:line 3"), "{e}");
    std::fs::write(&p, "x,y,value\n0,zero,300\n").unwrap();
    let e = csv::read_truth_points(&p).unwrap_err().to_string();
    assert!(e.contains("line 2") && e.contains("`y`"), "{e}");
    std::fs::write(&p, "x,y,value,colour\n0,0,300,red\n").unwrap();
    let e = csv::read_truth_points(&p).unwrap_err().to_string();
    assert!(e.contains("colour"), "{e}");
}

#[test]
fn geometric_accuracy_pixels_and_metres() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("gcp.csv");
    // offsets (truth − synth): (1, 0), (−1, 2), (3, 1), (1, 1)
    std::fs::write(
        &p,
        "synth_x,synth_y,truth_x,truth_y\n10,10,11,10\n20,5,19,7\n0,0,3,1\n7,7,8,8\n",
    )
    .unwrap();
    let g = compare::geometric_accuracy(&csv::read_control_points(&p).unwrap(), Some(0.5)).unwrap();
    assert_eq!(g.n, 4);
    assert_close!(g.bias_px[0], 1.0, 1e-12);
    assert_close!(g.bias_px[1], 1.0, 1e-12);
    assert_close!(g.rmse_px[0], 3f64.sqrt(), 1e-12); // sqrt((1+1+9+1)/4)
    assert_close!(g.rmse_px[1], 1.5f64.sqrt(), 1e-12); // sqrt((0+4+1+1)/4)
    assert_close!(g.rmse_radial_px, 4.5f64.sqrt(), 1e-12);
    assert_close!(g.rmse_m.unwrap()[0], 0.5 * 3f64.sqrt(), 1e-12);
    assert_close!(g.bias_m.unwrap()[1], 0.5, 1e-12);
}

#[test]
fn sixteen_bit_png_and_tiff_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (5u32, 3u32);
    let dn: Vec<u16> = (0..w * h).map(|i| 1000 + 977 * i as u16).collect();
    // PNG, 16-bit greyscale (big-endian samples).
    let png_path = dir.path().join("t.png");
    {
        let f = std::fs::File::create(&png_path).unwrap();
        let mut enc = png::Encoder::new(std::io::BufWriter::new(f), w, h);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Sixteen);
        let bytes: Vec<u8> = dn.iter().flat_map(|v| v.to_be_bytes()).collect();
        enc.write_header()
            .unwrap()
            .write_image_data(&bytes)
            .unwrap();
    }
    // TIFF, 16-bit greyscale.
    let tif_path = dir.path().join("t.tif");
    {
        let f = std::fs::File::create(&tif_path).unwrap();
        let mut enc = tiff::encoder::TiffEncoder::new(f).unwrap();
        enc.write_image::<tiff::encoder::colortype::Gray16>(w, h, &dn)
            .unwrap();
    }
    for p in [&png_path, &tif_path] {
        let mut s = image::read_image(p).unwrap();
        assert_eq!((s.width, s.height), (5, 3));
        let want: Vec<f32> = dn.iter().map(|&v| v as f32).collect();
        assert_eq!(s.layers[0].data, want, "{}", p.display());
        image::Calibration {
            gain: 0.01,
            offset: 250.0,
        }
        .apply(&mut s);
        assert_close!(s.layers[0].data[1], 0.01 * 1977.0 + 250.0, 1e-4);
    }
    let e = image::read_image(dir.path().join("t.bmp"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("t.bmp"), "{e}");
}

fn write_tiff_f32(path: &std::path::Path, w: u32, h: u32, v: &[f32]) {
    let f = std::fs::File::create(path).unwrap();
    let mut enc = tiff::encoder::TiffEncoder::new(f).unwrap();
    enc.write_image::<tiff::encoder::colortype::Gray32Float>(w, h, v)
        .unwrap();
}

fn run_irsig(args: &[&std::ffi::OsStr]) -> (bool, String, String) {
    let out = std::process::Command::new(crate::util::irsig_bin())
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn cli_compare_images_json_and_histogram_plot() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16u32, 8u32);
    let synth: Vec<f32> = (0..w * h).map(|i| 290.0 + (i % 16) as f32).collect();
    // Truth DN with gain 0.01 K/DN, offset 200 K: truth = synth − 0.5 K.
    let dn: Vec<u16> = synth
        .iter()
        .map(|&t| ((t - 0.5 - 200.0) * 100.0).round() as u16)
        .collect();
    let sp = dir.path().join("synth.tif");
    write_tiff_f32(&sp, w, h, &synth);
    let tp = dir.path().join("truth.png");
    {
        let f = std::fs::File::create(&tp).unwrap();
        let mut enc = png::Encoder::new(f, w, h);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Sixteen);
        let b: Vec<u8> = dn.iter().flat_map(|v| v.to_be_bytes()).collect();
        enc.write_header().unwrap().write_image_data(&b).unwrap();
    }
    let plot = dir.path().join("hist.png");
    let (ok, out, err) = run_irsig(&[
        "compare".as_ref(),
        sp.as_os_str(),
        tp.as_os_str(),
        "--truth-gain=0.01".as_ref(),
        "--truth-offset=200".as_ref(),
        "--quantity=temperature".as_ref(),
        "--json".as_ref(),
        "--plot".as_ref(),
        plot.as_os_str(),
    ]);
    assert!(ok, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    let all = &j["image"]["overall"];
    assert_close!(all["bias"].as_f64().unwrap(), 0.5, 1e-3);
    assert_close!(all["rmse"].as_f64().unwrap(), 0.5, 1e-3);
    assert_close!(all["spearman"].as_f64().unwrap(), 1.0, 1e-12);
    assert_eq!(all["n"].as_u64(), Some(128));
    assert_eq!(j["image"]["unit"], "K");
    // The plot is a real PNG of the requested size.
    let s = image::read_png(&plot);
    assert!(s.is_err(), "an RGB plot is not a single-band image");
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&plot).unwrap()));
    let info = dec.read_info().unwrap();
    assert_eq!((info.info().width, info.info().height), (900, 560));
    // A bad points file fails with its name and line.
    let pp = dir.path().join("pts.csv");
    std::fs::write(&pp, "x,y\n1,1\n99,1\n").unwrap();
    let (ok, _, err) = run_irsig(&[
        "compare".as_ref(),
        sp.as_os_str(),
        tp.as_os_str(),
        "--points".as_ref(),
        pp.as_os_str(),
    ]);
    assert!(!ok);
    assert!(err.contains("pts.csv:line 3"), "{err}");
}
