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

/// Quoted cells (RFC 4180) may hold commas and quotes; counts and line
/// numbers are unchanged around them.
#[test]
fn points_csv_quoted_cells_keep_commas() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("pts.csv");
    std::fs::write(
        &p,
        "id,x,y,value,material\r\n\"P1, north\",0.5,0.5,299,\"grass, \"\"wet\"\"\"\r\n  \"P2\" , 1 , 0 , 300.5 , asphalt\r\n",
    )
    .unwrap();
    let pts = csv::read_truth_points(&p).unwrap();
    assert_eq!(pts.len(), 2);
    assert_eq!(pts[0].id, "P1, north");
    assert_eq!(pts[0].material.as_deref(), Some("grass, \"wet\""));
    assert_eq!((pts[1].id.as_str(), pts[1].line), ("P2", 3));
    assert_eq!(pts[1].value, Some(300.5));
    // An unquoted comma is still a separator, and the error names the line.
    std::fs::write(&p, "id,x,y,value\n\"a,b\",0,0,300\nc,d,0,0,300\n").unwrap();
    let e = csv::read_truth_points(&p).unwrap_err().to_string();
    assert!(e.contains("pts.csv:line 3") && e.contains("found 5"), "{e}");
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

#[test]
fn exr_synthetic_with_material_layer_compares_per_material() {
    let dir = tempfile::tempdir().unwrap();
    let synth = stack(
        4,
        1,
        &[
            ("apparent_temperature", vec![300.0, 302.0, 310.0, 312.0]),
            ("material_id", vec![1.0, 1.0, 2.0, 2.0]),
        ],
    );
    let sp = dir.path().join("s.exr");
    irsig::output::write_exr(&sp, &synth).unwrap();
    let tp = dir.path().join("t.tif");
    write_tiff_f32(&tp, 4, 1, &[301.0, 303.0, 309.0, 311.0]);
    let s = image::read_image(&sp).unwrap();
    let t = image::read_image(&tp).unwrap();
    let c = compare::compare_images(&s, &t, &CompareOptions::default()).unwrap();
    assert_close!(c.overall.bias, 0.0, 1e-6);
    assert_close!(c.overall.rmse, 1.0, 1e-6);
    let b: Vec<f64> = c.per_material.iter().map(|m| m.agreement.bias).collect();
    assert_eq!(b, vec![-1.0, 1.0]);
}

// ---- sensitivity engines on analytic models ---------------------------

use irsig::analysis::calibrate::{self, CalibrationOptions};
use irsig::analysis::diurnal;
use irsig::analysis::params::ParamSet;
use irsig::analysis::sensitivity::{self, Factor, MorrisOptions};

fn factor(name: &str, nominal: f64, low: f64, high: f64, u: f64) -> Factor {
    Factor {
        name: name.into(),
        nominal,
        low,
        high,
        uncertainty: u,
    }
}

/// y0 = 3·a + 0.5·b² (+ 0·c), y1 = a·b.
fn analytic(x: &[f64]) -> irsig::Result<Vec<f64>> {
    Ok(vec![3.0 * x[0] + 0.5 * x[1] * x[1], x[0] * x[1]])
}

fn analytic_factors() -> Vec<Factor> {
    vec![
        factor("a", 1.0, 0.0, 2.0, 0.1),
        factor("b", 2.0, 0.0, 4.0, 0.2),
        factor("unused", 0.0, -1.0, 1.0, 0.5),
    ]
}

#[test]
fn oat_exact_on_analytic_model_and_unused_parameter_has_no_effect() {
    let f = analytic_factors();
    let out = vec!["y0".to_string(), "y1".to_string()];
    let oat = sensitivity::one_at_a_time(&f, &out, &analytic).unwrap();
    assert_eq!(oat.evaluations, 7);
    assert_eq!(oat.nominal_outputs, vec![5.0, 2.0]);
    let e = &oat.effects[0];
    assert_eq!((e[0].at_low, e[0].at_high, e[0].per_unit), (-3.0, 3.0, 3.0));
    // b: 0.5·(0−4) = −2, 0.5·(16−4) = 6, secant (8 − 0)/4 = 2.
    assert_eq!((e[1].at_low, e[1].at_high, e[1].per_unit), (-2.0, 6.0, 2.0));
    assert_eq!((e[2].at_low, e[2].at_high, e[2].per_unit), (0.0, 0.0, 0.0));
    assert_eq!(oat.ranking(0), vec![1, 0, 2]);
    // Error budget: linear propagation u·|∂y/∂x|, root-sum-square:
    // y0: 0.1·3 = 0.3, 0.2·2 = 0.4 → 0.5.
    let s: Vec<Vec<f64>> = oat
        .effects
        .iter()
        .map(|o| o.iter().map(|e| e.per_unit).collect())
        .collect();
    let b = sensitivity::error_budget(&f, &out, &s);
    assert_close!(b[0].combined, 0.5, 1e-12);
    assert_eq!(b[0].lines[0].name, "b");
    assert_close!(b[0].lines[0].variance_fraction, 0.64, 1e-12);
    assert_eq!(b[0].lines[2].contribution, 0.0);
}

#[test]
fn morris_statistics_on_analytic_model() {
    let f = analytic_factors();
    let out = vec!["y0".to_string(), "y1".to_string()];
    let opts = MorrisOptions {
        trajectories: 30,
        levels: 4,
        seed: 7,
    };
    let m = sensitivity::morris(&f, &out, &analytic, opts).unwrap();
    assert_eq!(m.evaluations, 30 * 4);
    assert_close!(m.delta, 2.0 / 3.0, 1e-15);
    // Linear in a: every elementary effect is 3 × range 2 = 6, σ = 0.
    let a = &m.effects[0][0];
    assert_close!(a.mu, 6.0, 1e-12);
    assert_close!(a.mu_star, 6.0, 1e-12);
    assert_close!(a.sigma, 0.0, 1e-12);
    assert_close!(a.mu_star_per_unit, 3.0, 1e-12);
    // Quadratic in b: with b = 4u, EE = 8(u₁ + u₂) ∈ {16/3, 32/3}: mean
    // between them, σ > 0 (non-linearity shows).
    let b = &m.effects[0][1];
    assert!(
        b.mu_star > 16.0 / 3.0 - 1e-9 && b.mu_star < 32.0 / 3.0 + 1e-9,
        "{b:?}"
    );
    assert!(b.sigma > 1.0, "{b:?}");
    // The unused parameter: exactly zero.
    let c = &m.effects[0][2];
    assert_eq!((c.mu, c.mu_star, c.sigma), (0.0, 0.0, 0.0));
    // Interaction term y1 = a·b: both effects vary (σ > 0), same seed → same result.
    assert!(m.effects[1][0].sigma > 0.0 && m.effects[1][1].sigma > 0.0);
    let again = sensitivity::morris(&f, &out, &analytic, opts).unwrap();
    assert_eq!(again.effects[1][1], m.effects[1][1]);
    assert_eq!(m.ranking(0)[2], 2);
    assert!(sensitivity::morris(&f, &out, &analytic, MorrisOptions { levels: 3, ..opts }).is_err());
}

#[test]
fn finite_difference_jacobian_matches_derivatives() {
    let f = analytic_factors();
    let j = sensitivity::finite_difference_jacobian(&f, &[1.0, 2.0, 0.0], 1e-4, &analytic).unwrap();
    assert_close!(j[0][0], 3.0, 1e-9);
    assert_close!(j[0][1], 2.0, 1e-9);
    assert_close!(j[1][0], 2.0, 1e-9);
    assert_close!(j[1][1], 1.0, 1e-9);
    assert_eq!(j[0][2], 0.0);
    // At a bound: one-sided, still right for a linear term.
    let j = sensitivity::finite_difference_jacobian(&f, &[2.0, 0.0, 1.0], 1e-4, &analytic).unwrap();
    assert_close!(j[0][0], 3.0, 1e-9);
}

/// Standard normal deviates (Box–Muller) from a seeded generator.
fn normals(seed: u64, n: usize) -> Vec<f64> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let u1: f64 = rng.random_range(f64::EPSILON..1.0);
            let u2: f64 = rng.random();
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        })
        .collect()
}

/// A diurnal surface-temperature curve T(h) = mean + amp·sin(2π(h − lag)/24).
fn diurnal_curve(x: &[f64], hours: &[f64]) -> Vec<f64> {
    hours
        .iter()
        .map(|h| x[0] + x[1] * (2.0 * std::f64::consts::PI * (h - x[2]) / 24.0).sin())
        .collect()
}

#[test]
fn calibration_recovers_known_parameters_within_intervals() {
    let hours: Vec<f64> = (0..48).map(|i| i as f64 * 0.5).collect();
    let true_x = [296.0, 12.0, 8.5];
    let f = vec![
        factor("mean_k", 290.0, 280.0, 320.0, 1.0),
        factor("amplitude_k", 5.0, 0.0, 25.0, 1.0),
        factor("lag_h", 6.0, 3.0, 12.0, 1.0),
    ];
    let sigma = 0.4;
    let mut covered = [0usize; 3];
    let runs = 30;
    for seed in 0..runs {
        let noise = normals(seed, hours.len());
        let truth: Vec<f64> = diurnal_curve(&true_x, &hours)
            .iter()
            .zip(&noise)
            .map(|(t, e)| t + sigma * e)
            .collect();
        let model = |x: &[f64]| Ok(diurnal_curve(x, &hours));
        let c = calibrate::calibrate(&f, &truth, &model, CalibrationOptions::default()).unwrap();
        assert_eq!((c.n_obs, c.dof), (48, 45));
        assert!(c.fitted.rmse < c.initial.rmse);
        // The residual RMSE approaches the noise level (within sampling spread).
        assert!((c.fitted.rmse - sigma).abs() < 0.15, "{}", c.fitted.rmse);
        for (i, p) in c.params.iter().enumerate() {
            let se = p.std_error.unwrap();
            assert!(se.is_finite() && se > 0.0);
            let (lo, hi) = (p.ci_low.unwrap(), p.ci_high.unwrap());
            if lo <= true_x[i] && true_x[i] <= hi {
                covered[i] += 1;
            }
        }
        if seed == 0 {
            // Linearised standard errors for a sinusoid fit (n samples over
            // whole periods): se(mean) = σ/√n, se(amp) = σ·√(2/n).
            assert_close!(
                c.params[0].std_error.unwrap(),
                c.fitted.residual_std * (48.0f64).sqrt().recip(),
                0.01
            );
            assert_close!(
                c.params[1].std_error.unwrap(),
                c.fitted.residual_std * (2.0f64 / 48.0).sqrt(),
                0.01
            );
            assert!(c.fitted.spearman > 0.99);
        }
    }
    // 95 % intervals: expect ~28.5 of 30 covering; allow sampling spread.
    for (i, n) in covered.iter().enumerate() {
        assert!(*n >= 25, "parameter {i} covered in only {n}/{runs} runs");
    }
}

#[test]
fn calibration_flags_unidentifiable_parameter() {
    let hours: Vec<f64> = (0..24).map(|i| i as f64).collect();
    let truth = diurnal_curve(&[300.0, 10.0, 9.0], &hours);
    let f = vec![
        factor("mean_k", 295.0, 280.0, 320.0, 1.0),
        factor("unused", 0.5, 0.0, 1.0, 0.1),
    ];
    let model = |x: &[f64]| Ok(diurnal_curve(&[x[0], 10.0, 9.0], &hours));
    let c = calibrate::calibrate(&f, &truth, &model, CalibrationOptions::default()).unwrap();
    assert_close!(c.params[0].fitted, 300.0, 1e-4);
    assert!(c.params[1].std_error.unwrap().is_infinite());
    // The identifiable parameter keeps its finite interval.
    assert!(c.params[0].std_error.unwrap().is_finite());
    let e =
        calibrate::calibrate(&f, &truth[..2], &model, CalibrationOptions::default()).unwrap_err();
    assert!(e.to_string().contains("2 truth values"), "{e}");
}

/// NIST StRD nonlinear least-squares dataset Misra1a (Misra 1978, dental
/// research monomolecular adsorption; NIST "lower difficulty"):
/// `y = b1 (1 − exp(−b2 x))`, 14 observations, and NIST's certified values
/// (https://www.itl.nist.gov/div898/strd/nls/data/misra1a.shtml).
const MISRA1A_X: [f64; 14] = [
    77.6, 114.9, 141.1, 190.8, 239.9, 289.0, 332.8, 378.4, 434.8, 477.3, 536.8, 593.1, 689.1, 760.0,
];
const MISRA1A_Y: [f64; 14] = [
    10.07, 14.73, 17.94, 23.93, 29.61, 35.18, 40.02, 44.82, 50.76, 55.05, 61.01, 66.40, 75.47,
    81.78,
];

#[test]
fn levenberg_marquardt_reaches_the_nist_misra1a_certified_values() {
    use irsig::analysis::calibrate::Method;
    let model = |b: &[f64]| -> irsig::Result<Vec<f64>> {
        Ok(MISRA1A_X
            .iter()
            .map(|x| b[0] * (1.0 - (-b[1] * x).exp()))
            .collect())
    };
    // NIST's first (distant) start, b1 = 500, b2 = 1e-4, inside wide bounds.
    let f = vec![
        factor("b1", 500.0, 1.0, 1000.0, 1.0),
        factor("b2", 1e-4, 1e-6, 1e-2, 1e-5),
    ];
    let run = |method| {
        calibrate::calibrate(
            &f,
            &MISRA1A_Y,
            &model,
            CalibrationOptions {
                method,
                ..CalibrationOptions::default()
            },
        )
        .unwrap()
    };
    let lm = run(Method::LevenbergMarquardt);
    let ssr = |c: &calibrate::Calibration| c.fitted.rmse.powi(2) * 14.0;
    // Certified: b1 = 2.3894212918E+02 ± 2.7070075241E+00,
    // b2 = 5.5015643181E-04 ± 7.2668688436E-06, SSR 1.2455138894E-01.
    assert_close!(lm.params[0].fitted, 2.3894212918E+02, 1e-6 * 238.9);
    assert_close!(lm.params[1].fitted, 5.5015643181E-04, 1e-6 * 5.5e-4);
    assert_close!(ssr(&lm), 1.2455138894E-01, 1e-8);
    // Standard errors through the finite-difference Jacobian: 4 digits.
    assert_close!(lm.params[0].std_error.unwrap(), 2.7070075241, 1e-3 * 2.707);
    assert_close!(
        lm.params[1].std_error.unwrap(),
        7.2668688436E-06,
        1e-3 * 7.27e-6
    );
    assert_eq!((lm.dof, lm.params[0].at_bound), (12, None));
    // The simplex gets there too, with many more model evaluations.
    let nm = run(Method::NelderMead);
    eprintln!(
        "Misra1a: LM {} evaluations ({} Jacobians), SSR {:.10e}; Nelder–Mead {} evaluations, SSR {:.10e}",
        lm.evaluations,
        lm.iterations,
        ssr(&lm),
        nm.evaluations,
        ssr(&nm)
    );
    assert!(ssr(&nm) >= ssr(&lm) * (1.0 - 1e-9));
    assert!(lm.evaluations * 3 < nm.evaluations);
}

#[test]
fn a_parameter_at_its_bound_is_reported_there_and_the_others_keep_finite_intervals() {
    use irsig::analysis::calibrate::{Bound, Method};
    let hours: Vec<f64> = (0..48).map(|i| i as f64 * 0.5).collect();
    let noise = normals(7, hours.len());
    let truth: Vec<f64> = diurnal_curve(&[296.0, 12.0, 8.5], &hours)
        .iter()
        .zip(&noise)
        .map(|(t, e)| t + 0.4 * e)
        .collect();
    // The amplitude's upper bound (10 K) is below the truth's 12 K.
    let f = vec![
        factor("mean_k", 290.0, 280.0, 320.0, 1.0),
        factor("amplitude_k", 5.0, 0.0, 10.0, 1.0),
        factor("lag_h", 6.0, 3.0, 12.0, 1.0),
    ];
    let model = |x: &[f64]| Ok(diurnal_curve(x, &hours));
    for method in [Method::LevenbergMarquardt, Method::NelderMead] {
        let c = calibrate::calibrate(
            &f,
            &truth,
            &model,
            CalibrationOptions {
                method,
                ..CalibrationOptions::default()
            },
        )
        .unwrap();
        let a = &c.params[1];
        assert_eq!(a.at_bound, Some(Bound::High), "{method:?}: {a:?}");
        assert_close!(a.fitted, 10.0, 1e-3);
        assert_eq!((a.std_error, a.ci_low, a.ci_high), (None, None, None));
        // The bound parameter is held: n − 2 degrees of freedom.
        assert_eq!(c.dof, 46);
        for i in [0, 2] {
            let p = &c.params[i];
            assert_eq!(p.at_bound, None, "{method:?}: {p:?}");
            let se = p.std_error.unwrap();
            let (lo, hi) = (p.ci_low.unwrap(), p.ci_high.unwrap());
            assert!(se.is_finite() && se > 0.0, "{method:?}: {p:?}");
            assert!(lo < p.fitted && p.fitted < hi && hi - lo < 2.0, "{p:?}");
        }
        assert!(c.covariance[1].iter().all(|&v| v == 0.0));
        assert_close!(c.params[0].fitted, 296.0, 0.3);
        assert_close!(c.params[2].fitted, 8.5, 0.2);
    }
}

#[test]
fn diurnal_contrast_maximum_and_crossovers() {
    use chrono::{DateTime, Duration};
    let t0 = DateTime::parse_from_rfc3339("2024-06-21T00:00:00-04:00").unwrap();
    let times: Vec<_> = (0..=96).map(|i| t0 + Duration::minutes(15 * i)).collect();
    let h: Vec<f64> = (0..=96).map(|i| i as f64 * 0.25).collect();
    // target − background = −5 + 10 sin(2π(h − 9)/24): zero at 11:00 and
    // 19:00, largest |contrast| 15 at 03:00.
    let target = diurnal_curve(&[295.0, 10.0, 9.0], &h);
    let background = vec![300.0; h.len()];
    let s = diurnal::contrast_series("temperature", "K", &times, &target, &background).unwrap();
    assert_eq!(s.crossovers.len(), 2);
    for (c, want) in s.crossovers.iter().zip([11, 19]) {
        let err = (*c - (t0 + Duration::hours(want))).num_seconds().abs();
        assert!(err < 60, "crossover {c} vs {want}:00 ({err} s)");
    }
    assert_eq!(s.time_of_max, t0 + Duration::hours(3));
    assert_close!(s.max_contrast_signed, -15.0, 1e-9);
}

fn test_material(name: &str) -> irsig::material::Material {
    let db = irsig::material::MaterialDb::load(&crate::util::repo_path("scenes/materials.json"))
        .unwrap();
    let mut m = db.materials()[0].clone();
    m.name = name.into();
    m
}

#[test]
fn params_file_parses_applies_and_reports_errors() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("params.json");
    let asphalt = test_material("asphalt");
    let mats = vec![asphalt.clone()];
    std::fs::write(
        &p,
        r#"{"params": [
          {"kind": "weather", "property": "air_temperature_offset_k", "low": -2, "high": 2, "uncertainty": 0.5},
          {"kind": "weather", "property": "relative_humidity_offset", "low": -0.2, "high": 0.2},
          {"kind": "material", "material": "asphalt", "property": "thermal_emissivity", "low": 0.85, "high": 0.98}
        ]}"#,
    )
    .unwrap();
    let ps = ParamSet::load(&p, &mats).unwrap();
    assert_eq!(ps.params[0].name, "weather.air_temperature_offset_k");
    assert_eq!(ps.params[2].name, "asphalt.thermal_emissivity");
    assert_eq!(ps.nominal(), vec![0.0, 0.0, asphalt.thermal_emissivity]);
    assert_close!(ps.params[1].uncertainty, 0.4 / 12f64.sqrt(), 1e-15);
    let m = ps.apply_materials(&[0.0, 0.0, 0.9], &mats).unwrap();
    assert_eq!(m[0].thermal_emissivity, 0.9);
    // Air temperature +2 K at fixed dew point: humidity falls by the ratio
    // of saturation vapour pressures (≈ 6.2 % per K near 20 °C).
    let rec = irsig::weather::WeatherRecord {
        time: chrono::DateTime::parse_from_rfc3339("2024-06-21T12:00:00-04:00").unwrap(),
        air_temperature_k: 293.15,
        dew_point_k: 283.15,
        relative_humidity: 0.526,
        pressure_pa: 101325.0,
        wind_speed_m_s: 2.0,
        wind_direction_deg: 180.0,
        direct_normal_w_m2: 800.0,
        diffuse_horizontal_w_m2: 100.0,
        global_horizontal_w_m2: 700.0,
        sky_longwave_w_m2: 330.0,
        total_sky_cover: 0.2,
        opaque_sky_cover: 0.1,
        precipitation_mm: 0.0,
        visibility_km: None,
    };
    let w = ps.apply_weather(&[2.0, 0.0, 0.9], &[rec]).unwrap();
    assert_eq!(w[0].air_temperature_k, 295.15);
    assert_eq!(w[0].dew_point_k, 283.15);
    let es = irsig::analysis::params::saturation_vapour_pressure_pa;
    assert_close!(
        w[0].relative_humidity,
        0.526 * es(293.15) / es(295.15),
        1e-12
    );
    assert!(w[0].relative_humidity < 0.526 * 0.9);
    // Zero offsets leave the record exactly as it was.
    assert_eq!(ps.apply_weather(&[0.0, 0.0, 0.9], &[rec]).unwrap()[0], rec);
    // Magnus at 20 °C vs 2338.8 Pa (Hyland–Wexler / WMO tables), within
    // the form's stated 0.4 %.
    assert_close!(es(293.15), 2338.8, 0.004 * 2338.8);
    let w = ps.apply_weather(&[0.0, 0.2, 0.9], &[rec]).unwrap();
    assert_close!(w[0].relative_humidity, 0.726, 1e-12);
    let dp = irsig::analysis::params::dew_point_k;
    assert_close!(
        w[0].dew_point_k - 283.15,
        dp(293.15, 0.726) - dp(293.15, 0.526),
        1e-12
    );
    assert_close!(es(dp(293.15, 0.726)) / es(293.15), 0.726, 1e-12);
    // Errors name the file and the field.
    for (text, want) in [
        (
            r#"[{"kind":"weather","property":"wind","low":0,"high":1}]"#,
            "params[0].property",
        ),
        (
            r#"[{"kind":"material","material":"brick","property":"density","low":1,"high":2}]"#,
            "params[0].material",
        ),
        (
            r#"[{"kind":"material","material":"asphalt","property":"solar_absorptivity","low":0.5,"high":1.2}]"#,
            "params[0].low",
        ),
        (
            r#"[{"kind":"material","material":"asphalt","property":"density","low":1,"high":2}]"#,
            "params[0].nominal",
        ),
        (
            r#"[{"kind":"weather","property":"insolation_scale","low":0.5,"high":1.5,"colour":1}]"#,
            "params[0]",
        ),
        ("[\n{\"kind\": }", "line 2"),
    ] {
        std::fs::write(&p, text).unwrap();
        let e = ParamSet::load(&p, &mats).unwrap_err().to_string();
        assert!(e.contains("params.json") && e.contains(want), "{text}: {e}");
    }
}

#[test]
fn the_registry_lists_every_parameter_and_the_list_is_a_params_file() {
    use irsig::analysis::registry;
    let db = irsig::material::MaterialDb::load(&crate::util::repo_path("scenes/materials.json"))
        .unwrap();
    for m in db.materials() {
        let list = registry::list(m);
        // Every registered material row this material has, then the weather.
        let n_mat = registry::MATERIAL_PARAMETERS
            .iter()
            .filter(|p| (p.get)(m).is_some())
            .count();
        assert_eq!(list.len(), n_mat + registry::WEATHER_PARAMETERS.len());
        for p in &list {
            assert!(
                p.low < p.high && p.low <= p.value && p.value <= p.high,
                "{p:?}"
            );
        }
        // The printed list reads back as a PARAMS file with the same values.
        let text = registry::ParamsFile { params: &list }.to_json();
        let ps = ParamSet::parse(&text, std::path::Path::new("list.json"), db.materials()).unwrap();
        assert_eq!(ps.params.len(), list.len());
        assert_eq!(
            ps.nominal(),
            list.iter().map(|p| p.value).collect::<Vec<_>>()
        );
        // At those values nothing changes, and it lists back the same.
        let same = ps.apply_material(&ps.nominal(), m).unwrap();
        assert_eq!(&same, m);
        let back = ps.listing(&ps.nominal()).unwrap();
        assert_eq!(back, list);
    }
    // Rows: physical bounds inside the domain; set then get returns the value.
    let mut dry = db.get("asphalt").unwrap().clone();
    let mut wet = db.get("crop").unwrap().clone();
    // With kB⁻¹ from the canopy, so that its leaf width is a parameter.
    wet.surface_energy.as_mut().unwrap().heat_roughness = irsig::material::HeatRoughness::Su2001;
    // Leaves and soil apart, so that the clumping and the soil's porosity are parameters.
    wet.surface_energy.as_mut().unwrap().canopy = irsig::material::CanopyModel::TwoSource;
    for row in registry::MATERIAL_PARAMETERS {
        // The surface-energy rows on a material that has the block.
        let m = if row.name.starts_with("surface_energy.") {
            &mut wet
        } else {
            &mut dry
        };
        let (lo, hi, excl) = row.domain;
        assert!(
            (if excl { row.low > lo } else { row.low >= lo }) && row.high <= hi,
            "{}",
            row.name
        );
        let v = 0.5 * (row.low + row.high);
        (row.set)(m, v).unwrap();
        assert_eq!((row.get)(m), Some(v), "{}", row.name);
    }
    for row in registry::WEATHER_PARAMETERS {
        assert!(
            row.low <= row.identity && row.identity <= row.high,
            "{}",
            row.name
        );
    }
    // The older short names still read, under the JSON name.
    let mats = vec![test_material("asphalt")];
    let ps = ParamSet::parse(
        r#"[{"kind": "material", "material": "asphalt", "property": "conductivity", "low": 0.1, "high": 2, "value": 1.5}]"#,
        std::path::Path::new("p.json"),
        &mats,
    )
    .unwrap();
    assert_eq!(ps.params[0].name, "asphalt.conductivity_w_m_k");
    assert_eq!(ps.nominal(), vec![1.5]);
    // A wrong unit, or both value and nominal, are errors naming the field.
    for (text, want) in [
        (
            r#"[{"kind": "material", "material": "asphalt", "property": "conductivity_w_m_k", "unit": "K", "low": 0.1, "high": 2}]"#,
            "params[0].unit",
        ),
        (
            r#"[{"kind": "weather", "property": "wind_speed_scale", "value": 1, "nominal": 1, "low": 0.5, "high": 2}]"#,
            "params[0].value",
        ),
    ] {
        let e = ParamSet::parse(text, std::path::Path::new("p.json"), &mats)
            .unwrap_err()
            .to_string();
        assert!(e.contains("p.json") && e.contains(want), "{text}: {e}");
    }
}

/// Root-mean-square difference of an `irsig thermal --csv` output and a
/// `time,surface_temperature_k` series at the series' times.
/// `irsig thermal --csv` output as time → surface temperature.
fn thermal_csv_by_time(thermal_csv: &str) -> std::collections::HashMap<&str, f64> {
    thermal_csv
        .lines()
        .skip(1)
        .map(|l| {
            let (t, v) = l.split_once(',').unwrap();
            (t, v.parse::<f64>().unwrap())
        })
        .collect()
}

fn rmse_against_series(thermal_csv: &str, series: &[(String, f64)]) -> f64 {
    let model = thermal_csv_by_time(thermal_csv);
    let ss: f64 = series
        .iter()
        .map(|(t, v)| (model[t.as_str()] - v).powi(2))
        .sum();
    (ss / series.len() as f64).sqrt()
}

/// Issue 16: `calibrate --thermal -o` dropped the fitted weather parameters,
/// so `irsig thermal` with the fitted file missed the fit by kelvins. The
/// fitted outputs now carry every parameter and `irsig thermal` with the
/// same facet options reproduces the fit's RMSE.
#[test]
fn cli_fitted_outputs_reproduce_the_fit_in_irsig_thermal() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let weather = crate::util::repo_path("scenes/town/weather.csv");
    let materials = crate::util::repo_path("scenes/materials.json");
    let os = |s: &str| std::ffi::OsString::from(s);
    // Model options other than the defaults, shared by both commands.
    let facet: Vec<std::ffi::OsString> = [
        "--tilt",
        "20",
        "--azimuth",
        "200",
        "--back",
        "insulated",
        "--spinup-days",
        "2",
    ]
    .iter()
    .map(|s| os(s))
    .collect();
    let thermal = |extra: &[std::ffi::OsString]| {
        let mut a = vec![
            os("thermal"),
            os("--materials"),
            materials.clone().into(),
            os("--weather"),
            weather.clone().into(),
            os("--time"),
            os("2025-06-20T20:00:00-04:00"),
            os("--csv"),
        ];
        a.extend(facet.iter().cloned());
        a.extend(extra.iter().cloned());
        let r: Vec<&std::ffi::OsStr> = a.iter().map(|s| s.as_os_str()).collect();
        let (ok, out, err) = run_irsig(&r);
        assert!(ok, "{err}");
        out
    };
    // Truth: asphalt with α = 0.8 under 1.6× the wind, hourly, ±0.2 K noise.
    std::fs::write(
        p("truth_params.json"),
        r#"[{"kind": "material", "material": "asphalt", "property": "solar_absorptivity", "value": 0.8, "low": 0, "high": 1},
            {"kind": "weather", "property": "wind_speed_scale", "value": 1.6, "low": 0.2, "high": 5}]"#,
    )
    .unwrap();
    let truth_csv = thermal(&[
        os("--material"),
        os("asphalt"),
        os("--params"),
        p("truth_params.json").into(),
    ]);
    let series: Vec<(String, f64)> = truth_csv
        .lines()
        .skip(1)
        .step_by(4)
        .enumerate()
        .map(|(k, l)| {
            let (t, v) = l.split_once(',').unwrap();
            let e = if k % 2 == 0 { 0.2 } else { -0.2 };
            (t.to_string(), v.parse::<f64>().unwrap() + e)
        })
        .collect();
    let mut text = String::from("time,surface_temperature_k\n");
    for (t, v) in &series {
        text += &format!("{t},{v}\n");
    }
    std::fs::write(p("series.csv"), text).unwrap();
    std::fs::write(
        p("fit.json"),
        r#"[{"kind": "material", "material": "asphalt", "property": "solar_absorptivity", "low": 0.5, "high": 1.0},
            {"kind": "weather", "property": "wind_speed_scale", "low": 0.2, "high": 5}]"#,
    )
    .unwrap();
    let calibrate = |extra: &[&str]| {
        let mut a = vec![
            os("calibrate"),
            os("--thermal"),
            os("--material"),
            os("asphalt"),
            os("--materials"),
            materials.clone().into(),
            os("--weather"),
            weather.clone().into(),
            os("--truth"),
            p("series.csv").into(),
            os("--params"),
            p("fit.json").into(),
            os("-o"),
            p("fitted.json").into(),
        ];
        a.extend(facet.iter().cloned());
        a.extend(extra.iter().map(|s| os(s)));
        let r: Vec<&std::ffi::OsStr> = a.iter().map(|s| s.as_os_str()).collect();
        run_irsig(&r)
    };
    // A material file cannot carry the wind scale: refused, not dropped.
    let (ok, _, err) = calibrate(&[]);
    assert!(!ok);
    assert!(
        err.contains("weather.wind_speed_scale") && err.contains("--params-out"),
        "{err}"
    );
    assert!(!p("fitted.json").exists());
    let fp = p("fitted_params.json");
    let (ok, out, err) = calibrate(&["--params-out", fp.to_str().unwrap(), "--json"]);
    assert!(ok, "{err}");
    let fit: serde_json::Value = serde_json::from_str(&out).unwrap();
    let fit_rmse = fit["fitted"]["rmse"].as_f64().unwrap();
    let fitted: Vec<f64> = fit["params"]
        .as_array()
        .unwrap()
        .iter()
        .map(|q| q["fitted"].as_f64().unwrap())
        .collect();
    assert!((fit_rmse - 0.2).abs() < 0.05, "{out}");
    assert_close!(fitted[0], 0.8, 0.01);
    assert_close!(fitted[1], 1.6, 0.05);
    // irsig thermal with the fitted material and parameters, same options.
    let again = thermal(&[
        os("--material"),
        p("fitted.json").into(),
        os("--params"),
        fp.clone().into(),
    ]);
    let rmse = rmse_against_series(&again, &series);
    eprintln!("fit RMSE {fit_rmse:.5} K, irsig thermal with the fitted files {rmse:.5} K");
    assert!((rmse - fit_rmse).abs() < 0.01, "{rmse} vs {fit_rmse}");
    // The fitted material alone lacks the wind: it misses by far more.
    let without = rmse_against_series(
        &thermal(&[os("--material"), p("fitted.json").into()]),
        &series,
    );
    assert!(without > fit_rmse + 0.3, "{without}");
}

/// The issue-16 case on measured forcing: stock grass calibrated with a
/// weather scaling on the first half of the Bondville 1998 subset (its
/// forcing written as irsig CSV, its radiometric surface temperature as the
/// truth series). `irsig thermal` with both fitted files reproduces the
/// fit's RMSE; parameters at a bound are reported there, the others keep
/// finite intervals.
#[test]
#[ignore = "needs ../shared/data"]
fn cli_fitted_grass_on_measured_forcing_reproduces_in_irsig_thermal() {
    let d = irsig::weather::flux::load(
        &crate::util::shared_data("flux").join("bondville_1998/bondville_1998_aug01-sep11.csv"),
    )
    .unwrap();
    let first = d.first_half();
    let (history, _) = d.weather(first.clone()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let mut w = Vec::new();
    irsig::weather::write_csv(&history, &["Bondville 1998, first half"], &mut w).unwrap();
    std::fs::write(p("weather.csv"), w).unwrap();
    // Read back, so the truth times are the loaded records' own.
    let loaded = irsig::weather::load(&p("weather.csv")).unwrap();
    let mut series = Vec::new();
    for (k, i) in first.enumerate() {
        if let Some(t) = d.records()[i].surface_temperature_k {
            series.push((loaded.records()[k].time.to_rfc3339(), t));
        }
    }
    let mut text = String::from("time,surface_temperature_k\n");
    for (t, v) in &series {
        text += &format!("{t},{v}\n");
    }
    std::fs::write(p("series.csv"), text).unwrap();
    std::fs::write(
        p("fit.json"),
        r#"[{"kind": "material", "material": "grass", "property": "solar_absorptivity", "low": 0.5, "high": 0.95},
            {"kind": "material", "material": "grass", "property": "conductivity_w_m_k", "low": 0.2, "high": 2.5},
            {"kind": "material", "material": "grass", "property": "thickness_m", "low": 0.05, "high": 1.0},
            {"kind": "weather", "property": "wind_speed_scale", "low": 0.2, "high": 5}]"#,
    )
    .unwrap();
    let materials = crate::util::repo_path("scenes/materials.json");
    let common = |cmd: &str| -> Vec<std::ffi::OsString> {
        vec![
            cmd.into(),
            "--materials".into(),
            materials.clone().into(),
            "--weather".into(),
            p("weather.csv").into(),
        ]
    };
    let mut a = common("calibrate");
    for s in ["--thermal", "--material", "grass", "--json"] {
        a.push(s.into());
    }
    for (f, v) in [
        ("--truth", p("series.csv")),
        ("--params", p("fit.json")),
        ("-o", p("fitted.json")),
        ("--params-out", p("fitted_params.json")),
    ] {
        a.push(f.into());
        a.push(v.into());
    }
    let r: Vec<&std::ffi::OsStr> = a.iter().map(|s| s.as_os_str()).collect();
    let (ok, out, err) = run_irsig(&r);
    assert!(ok, "{err}");
    let fit: serde_json::Value = serde_json::from_str(&out).unwrap();
    let fit_rmse = fit["fitted"]["rmse"].as_f64().unwrap();
    for q in fit["params"].as_array().unwrap() {
        eprintln!(
            "{}: {} -> {} (std error {}, at bound {})",
            q["name"], q["initial"], q["fitted"], q["std_error"], q["at_bound"]
        );
        if q["at_bound"].is_null() {
            assert!(q["std_error"].as_f64().is_some_and(f64::is_finite), "{q}");
        } else {
            assert!(q["std_error"].is_null() && q["ci_low"].is_null(), "{q}");
        }
    }
    let mut a = common("thermal");
    for s in ["--csv", "--material"] {
        a.push(s.into());
    }
    a.push(p("fitted.json").into());
    a.push("--params".into());
    a.push(p("fitted_params.json").into());
    a.push("--time".into());
    a.push(series.last().unwrap().0.clone().into());
    let r: Vec<&std::ffi::OsStr> = a.iter().map(|s| s.as_os_str()).collect();
    let (ok, out, err) = run_irsig(&r);
    assert!(ok, "{err}");
    let rmse = rmse_against_series(&out, &series);
    eprintln!(
        "Bondville first half, grass: initial RMSE {:.3} K, fit {fit_rmse:.4} K, irsig thermal with the fitted files {rmse:.4} K",
        fit["initial"]["rmse"].as_f64().unwrap()
    );
    assert!(fit_rmse < fit["initial"]["rmse"].as_f64().unwrap());
    assert!((rmse - fit_rmse).abs() < 0.01, "{rmse} vs {fit_rmse}");
}

#[test]
fn cli_list_params_is_a_params_file_for_sensitivity() {
    let dir = tempfile::tempdir().unwrap();
    let materials = crate::util::repo_path("scenes/materials.json");
    let (ok, out, err) = run_irsig(&[
        "calibrate".as_ref(),
        "--thermal".as_ref(),
        "--material".as_ref(),
        "asphalt".as_ref(),
        "--materials".as_ref(),
        materials.as_os_str(),
        "--list-params".as_ref(),
        "--json".as_ref(),
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let list = v["params"].as_array().unwrap();
    let k = list
        .iter()
        .find(|q| q["property"] == "conductivity_w_m_k")
        .unwrap();
    assert_eq!(
        (&k["kind"], &k["material"], k["value"].as_f64(), &k["unit"]),
        (
            &serde_json::json!("material"),
            &serde_json::json!("asphalt"),
            Some(0.75),
            &serde_json::json!("W/(m·K)")
        )
    );
    assert!(list.iter().any(|q| q["property"] == "wind_speed_scale"));
    let pfile = dir.path().join("all.json");
    std::fs::write(&pfile, &out).unwrap();
    let (ok, out, err) = run_irsig(&[
        "sensitivity".as_ref(),
        "--thermal".as_ref(),
        "--material".as_ref(),
        "asphalt".as_ref(),
        "--materials".as_ref(),
        materials.as_os_str(),
        "--weather".as_ref(),
        crate::util::repo_path("scenes/town/weather.csv").as_os_str(),
        "--time".as_ref(),
        "2025-06-20T14:00:00-04:00".as_ref(),
        "--params".as_ref(),
        pfile.as_os_str(),
        "--json".as_ref(),
    ]);
    assert!(ok, "{err}");
    let r: serde_json::Value = serde_json::from_str(&out).unwrap();
    let effects = r["oat"]["effects"][0].as_array().unwrap();
    assert_eq!(effects.len(), list.len());
}

// ---- one-facet studies ---------------------------------------------------

use irsig::analysis::facet::{self, FacetSpec, OneFacet};
use irsig::analysis::study::MaterialStudy;

/// Asphalt and concrete on a horizontal facet under the town's weather
/// (19–20 June 2025, Rochester NY) up to 20 June 14:00, default solver.
fn town_study(params: &str) -> MaterialStudy {
    town_study_at("2025-06-20T14:00:00-04:00", params)
}

/// [`town_study`] at another image time.
fn town_study_at(time: &str, params: &str) -> MaterialStudy {
    let h = irsig::weather::load(&crate::util::repo_path("scenes/town/weather.csv")).unwrap();
    let until = chrono::DateTime::parse_from_rfc3339(time).unwrap();
    let records = facet::records_until(&h, until).unwrap();
    let site = *h.site().unwrap();
    let opts = irsig::thermal::SolveOptions::default();
    let f = OneFacet::new(
        records,
        &site,
        &FacetSpec::default(),
        opts,
        facet::lwir_band().unwrap(),
    )
    .unwrap();
    let db = irsig::material::MaterialDb::load(&crate::util::repo_path("scenes/materials.json"))
        .unwrap();
    let materials = vec![
        db.get("asphalt").unwrap().clone(),
        db.get("concrete").unwrap().clone(),
    ];
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("params.json");
    std::fs::write(&p, params).unwrap();
    let params = ParamSet::load(&p, &materials).unwrap();
    let time_index = f.index_at(until).unwrap();
    MaterialStudy {
        facet: f,
        materials,
        params,
        time_index,
    }
}

const FACET_PARAMS: &str = r#"[
  {"kind": "weather", "property": "insolation_scale", "low": 0.8, "high": 1.2, "uncertainty": 0.05},
  {"kind": "weather", "property": "air_temperature_offset_k", "low": -2, "high": 2, "uncertainty": 0.5},
  {"kind": "material", "material": "asphalt", "property": "conductivity", "low": 0.5, "high": 1.0},
  {"kind": "material", "material": "concrete", "property": "solar_absorptivity", "low": 0.5, "high": 0.8}
]"#;

#[test]
fn one_facet_oat_and_morris_rank_like_finite_differences() {
    let study = town_study(FACET_PARAMS);
    let f = study.params.factors();
    let out = study.output_names();
    assert_eq!(out[0], "asphalt.surface_temperature_k");
    let model = |x: &[f64]| study.evaluate(x);
    let oat = sensitivity::one_at_a_time(&f, &out, &model).unwrap();
    let m = sensitivity::morris(
        &f,
        &out,
        &model,
        MorrisOptions {
            trajectories: 8,
            levels: 4,
            seed: 3,
        },
    )
    .unwrap();
    let jac =
        sensitivity::finite_difference_jacobian(&f, &study.params.nominal(), 1e-3, &model).unwrap();
    // Asphalt surface temperature (output 0): rank by |∂T/∂x|·(high − low).
    let scaled: Vec<f64> = f
        .iter()
        .zip(&jac[0])
        .map(|(f, d)| (d * (f.high - f.low)).abs())
        .collect();
    let mut fd_rank: Vec<usize> = (0..f.len()).collect();
    fd_rank.sort_by(|&a, &b| scaled[b].total_cmp(&scaled[a]));
    assert_eq!(
        oat.ranking(0),
        fd_rank,
        "OAT {:?} vs FD {scaled:?}",
        oat.effects[0]
    );
    assert_eq!(
        m.ranking(0),
        fd_rank,
        "Morris {:?} vs FD {scaled:?}",
        m.effects[0]
    );
    // Physics signs: more sun and warmer air warm the asphalt at 14:00.
    assert!(jac[0][0] > 0.0 && jac[0][1] > 0.0);
    // The concrete parameter does not enter the asphalt outputs: exactly zero.
    for o in [0, 1] {
        assert_eq!(oat.effects[o][3].swing(), 0.0);
        assert_eq!((m.effects[o][3].mu_star, m.effects[o][3].sigma), (0.0, 0.0));
        assert_eq!(jac[o][3], 0.0);
    }
    // …and asphalt's conductivity none on concrete (outputs 2, 3).
    assert_eq!(oat.effects[2][2].swing(), 0.0);
    assert!(oat.effects[2][3].swing() > 0.1);
    // A +1 K air offset raises the surface by less than 1 K (the surface
    // also exchanges with sun, sky and ground), but by a good part of it.
    assert!(
        oat.effects[0][1].per_unit > 0.3 && oat.effects[0][1].per_unit < 1.0,
        "{:?}",
        oat.effects[0][1]
    );
}

#[test]
fn one_facet_calibration_recovers_known_material_within_intervals() {
    let params = r#"[
      {"kind": "material", "material": "asphalt", "property": "solar_absorptivity", "low": 0.7, "high": 0.98},
      {"kind": "material", "material": "asphalt", "property": "conductivity", "low": 0.4, "high": 2.0}
    ]"#;
    let study = town_study(params);
    let true_x = [0.82, 1.3];
    // Truth: irsig's own series with the known values, hourly, plus seeded noise.
    let every = 4; // 15-min records → hourly
    let clean = study.temperature_series(&true_x, 0).unwrap();
    let idx: Vec<usize> = (0..clean.len()).step_by(every).collect();
    let mut covered = [0usize; 2];
    let seeds = 8;
    for seed in 0..seeds {
        let noise = normals(100 + seed, idx.len());
        let truth: Vec<f64> = idx
            .iter()
            .zip(&noise)
            .map(|(&i, e)| clean[i] + 0.3 * e)
            .collect();
        let model = |x: &[f64]| -> irsig::Result<Vec<f64>> {
            let t = study.temperature_series(x, 0)?;
            Ok(idx.iter().map(|&i| t[i]).collect())
        };
        let c = calibrate::calibrate(
            &study.params.factors(),
            &truth,
            &model,
            CalibrationOptions::default(),
        )
        .unwrap();
        assert!(
            c.initial.rmse > 1.0,
            "nominal asphalt should misfit: {}",
            c.initial.rmse
        );
        assert!((c.fitted.rmse - 0.3).abs() < 0.1, "{}", c.fitted.rmse);
        for (k, (p, t)) in c.params.iter().zip(true_x).enumerate() {
            eprintln!(
                "seed {seed}: {} = {:.4} ± {:.4} (true {t})",
                p.name,
                p.fitted,
                p.std_error.unwrap()
            );
            let (lo, hi) = (p.ci_low.unwrap(), p.ci_high.unwrap());
            assert!(
                (p.fitted - t).abs() < 4.0 * p.std_error.unwrap(),
                "{p:?} vs {t}"
            );
            assert!(hi - lo < 0.2 * (p.bounds[1] - p.bounds[0]), "{p:?}");
            if lo <= t && t <= hi {
                covered[k] += 1;
            }
        }
    }
    // 95 % intervals over 8 noise draws: at least 6 should cover (P ≈ 0.99).
    assert!(
        covered.iter().all(|&n| n >= 6),
        "covered {covered:?} of {seeds}"
    );
}

#[test]
fn humidity_and_cloud_act_through_sky_longwave_and_insolation() {
    let params = r#"[
      {"kind": "weather", "property": "relative_humidity_offset", "low": -0.2, "high": 0.2},
      {"kind": "weather", "property": "cloud_cover_offset", "low": -0.3, "high": 0.5},
      {"kind": "material", "material": "concrete", "property": "density", "low": 1800, "high": 2600}
    ]"#;
    // Night (04:00): more humidity or cloud, more sky longwave, a warmer surface.
    let night = town_study_at("2025-06-20T04:00:00-04:00", params);
    let f = night.params.factors();
    let out = night.output_names();
    let oat = sensitivity::one_at_a_time(&f, &out, &|x: &[f64]| night.evaluate(x)).unwrap();
    let (hum, cloud) = (&oat.effects[0][0], &oat.effects[0][1]);
    assert!(hum.at_low < -0.05 && hum.at_high > 0.05, "{hum:?}");
    // (Less cloud acts both ways at night: a colder sky now, but more sun
    // stored the day before; more cloud is clearly warmer.)
    assert!(cloud.at_high > 0.2, "{cloud:?}");
    // The concrete parameter does not enter asphalt: exactly zero.
    assert_eq!(oat.effects[0][2].swing(), 0.0);
    // Sky longwave follows the Clark & Allen ratio, and the insolation the
    // Kasten & Czeplak one (with the Erbs re-split at the site).
    let rec = night.facet.records[night.time_index - 56]; // 14:00 the day before
    assert!(rec.global_horizontal_w_m2 > 100.0);
    let site = night.facet.site;
    let w = night
        .params
        .apply_weather_at(&[0.1, 0.3, 2300.0], &[rec], Some(&site))
        .unwrap()[0];
    let eps = irsig::weather::physics::clark_allen_sky_emissivity;
    let want = rec.sky_longwave_w_m2 * eps(w.dew_point_k, w.opaque_sky_cover)
        / eps(rec.dew_point_k, rec.opaque_sky_cover);
    assert_close!(w.sky_longwave_w_m2, want, 1e-9 * want);
    assert!(w.sky_longwave_w_m2 > rec.sky_longwave_w_m2);
    let kc = irsig::analysis::params::kasten_czeplak_cloud_ratio;
    assert_close!(
        w.global_horizontal_w_m2,
        rec.global_horizontal_w_m2 * kc(w.total_sky_cover) / kc(rec.total_sky_cover),
        1e-9
    );
    assert!(w.direct_normal_w_m2 < rec.direct_normal_w_m2);
    // Zero offsets: the record unchanged.
    let same = night
        .params
        .apply_weather_at(&[0.0, 0.0, 2300.0], &[rec], Some(&site))
        .unwrap()[0];
    assert_eq!(same, rec);
    // Kasten & Czeplak: overcast passes 25 % of the clear-sky global.
    assert_close!(kc(1.0), 0.25, 1e-15);
    assert_close!(kc(0.0), 1.0, 1e-15);
    // Day (14:00): more cloud, less sun, a cooler asphalt.
    let day = town_study(params);
    let oat = sensitivity::one_at_a_time(
        &day.params.factors(),
        &day.output_names(),
        &|x: &[f64]| day.evaluate(x),
    )
    .unwrap();
    assert!(oat.effects[0][1].at_high < -0.5, "{:?}", oat.effects[0][1]);
}

// ---- scene studies ----------------------------------------------------------

use irsig::analysis::geo;
use irsig::analysis::scene::{PixelPoint, SceneStudy};
use irsig::render::session::Session;

/// A tiny scene in `dir`: a 120 m asphalt plane and a concrete block
/// (20 × 12 × 6 m), the town's weather, one 24×16 frame camera looking down
/// at 45° with 2×2 sub-rays, a box PSF and no noise.
fn tiny_scene(dir: &std::path::Path, atmosphere: Option<serde_json::Value>) -> std::path::PathBuf {
    let mut scene = serde_json::json!({
        "site": {"latitude_deg": 43.16, "longitude_deg": -77.61, "altitude_m": 160.0,
                 "utc_offset_hours": -4.0},
        "time": "2025-06-20T14:00:00-04:00",
        "weather": {"file": crate::util::repo_path("scenes/town/weather.csv")},
        "materials": [crate::util::repo_path("scenes/materials.json")],
        "objects": [
            {"name": "ground", "material": "asphalt",
             "shapes": [{"plane": {"size": [120.0, 120.0], "max_edge_m": 30.0}}]},
            {"name": "block", "material": "concrete",
             "shapes": [{"box": {"size": [20.0, 12.0, 6.0], "bottom": false}}],
             "instances": [{"translate": [0.0, 5.0, 0.0]}]}
        ],
        "sensors": [{"type": "frame", "name": "cam", "width": 24, "height": 16,
                     "fov_deg": 60.0, "position": [0.0, -60.0, 60.0],
                     "look_at": [0.0, 0.0, 0.0], "oversample": 2,
                     "bands": [{"name": "LWIR", "response": [8.0, 12.0]}]}]
    });
    if let Some(a) = atmosphere {
        scene["atmosphere"] = a;
    }
    let path = dir.join("scene.json");
    std::fs::write(&path, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    path
}

fn write_params(dir: &std::path::Path, text: &str) -> std::path::PathBuf {
    let p = dir.join("params.json");
    std::fs::write(&p, text).unwrap();
    p
}

fn tiny_study(dir: &std::path::Path, params: &str, points: Vec<PixelPoint>) -> SceneStudy {
    let session = Session::open(&tiny_scene(dir, None), irsig::trace::Backend::Embree).unwrap();
    let time = session.scene.time;
    let ps = ParamSet::load(
        write_params(dir, params),
        session.scene.materials.materials(),
    )
    .unwrap();
    SceneStudy::new(session, 0, time, ps, points, Vec::new()).unwrap()
}

fn px(label: &str, x: f64, y: f64) -> PixelPoint {
    PixelPoint {
        label: label.into(),
        x,
        y,
    }
}

#[test]
fn scene_study_reproduces_the_render_and_responds_like_physics() {
    let dir = tempfile::tempdir().unwrap();
    let params = r#"[
      {"kind": "material", "material": "asphalt", "property": "solar_absorptivity", "low": 0.8, "high": 0.98},
      {"kind": "material", "material": "asphalt", "property": "thermal_emissivity", "low": 0.85, "high": 0.98},
      {"kind": "weather", "property": "cloud_cover_offset", "low": -0.2, "high": 0.4},
      {"kind": "material", "material": "glass", "property": "density", "low": 2000, "high": 3000}
    ]"#;
    // Bottom rows see the open ground, the middle the block's roof or face.
    let points = vec![px("ground", 3.5, 14.5), px("block", 12.5, 8.5)];
    let mut study = tiny_study(dir.path(), params, points);
    eprintln!("{study:?}");
    let (sampled, neighbours) = study.facet_counts();
    assert!(sampled >= 2 && neighbours >= 1, "{sampled} {neighbours}");
    let x0 = study.params.nominal();
    let nominal = study.pixels(&x0).unwrap();
    // At the nominal parameters the pixels are the render's: same radiance
    // as the renderer's own rows (box PSF, no noise).
    let time = study.time;
    let states = study.session.thermal(&[time]).unwrap();
    let band = study
        .session
        .render_rows(0, &states.conditions[0], 0..16, &|_| {})
        .unwrap();
    for (p, v) in study.points.iter().zip(&nominal) {
        let k = p.y as usize * 24 + p.x as usize;
        let rendered = band.radiance()[0][k] as f64;
        assert_close!(v.band_radiance_w_m2_sr, rendered, 1e-5 * rendered);
        assert!(v.apparent_temperature_k > 280.0 && v.apparent_temperature_k < 340.0);
    }
    // The re-solved facets reproduce the scene-wide solve (its dedup
    // merging error aside): the per-facet inputs are the scene's.
    let res = study.resolve_residuals_k();
    assert!(res.iter().all(|r| r.abs() < 0.5), "{res:?}");
    let y0 = study.evaluate(&x0).unwrap();
    assert_close!(y0[0], nominal[0].surface_temperature_k, 1e-9);
    // Physics: more solar absorptivity warms the ground at 14:00; higher
    // emissivity cools it (and raises its emission); glass is not in the
    // scene: exactly no effect.
    let names = study.output_names();
    assert_eq!(names[1], "ground.apparent_temperature_k");
    let oat = sensitivity::one_at_a_time(&study.params.factors(), &names, &|x: &[f64]| {
        study.evaluate(x)
    })
    .unwrap();
    let ground_t = &oat.effects[0];
    assert!(
        ground_t[0].at_high > 0.2 && ground_t[0].at_low < -0.2,
        "{:?}",
        ground_t[0]
    );
    assert!(ground_t[1].at_high < 0.0, "{:?}", ground_t[1]);
    assert!(
        oat.effects[0][2].swing() > 0.05,
        "cloud {:?}",
        oat.effects[0][2]
    );
    for (name, effects) in names.iter().zip(&oat.effects) {
        assert_eq!(effects[3].swing(), 0.0, "{name}");
    }
}

#[test]
fn scene_calibration_recovers_absorptivity_within_its_interval() {
    let dir = tempfile::tempdir().unwrap();
    let params = r#"[
      {"kind": "material", "material": "asphalt", "property": "solar_absorptivity", "low": 0.7, "high": 0.98, "nominal": 0.95}
    ]"#;
    let points: Vec<PixelPoint> = (0..6)
        .map(|i| {
            px(
                &format!("p{i}"),
                1.5 + 4.0 * i as f64,
                14.5 - (i % 2) as f64,
            )
        })
        .collect();
    let study = tiny_study(dir.path(), params, points);
    let true_x = [0.82];
    let clean: Vec<f64> = study
        .pixels(&true_x)
        .unwrap()
        .iter()
        .map(|v| v.apparent_temperature_k)
        .collect();
    let noise = normals(7, clean.len());
    let truth: Vec<f64> = clean.iter().zip(&noise).map(|(c, e)| c + 0.2 * e).collect();
    let model = |x: &[f64]| -> irsig::Result<Vec<f64>> {
        Ok(study
            .pixels(x)?
            .iter()
            .map(|v| v.apparent_temperature_k)
            .collect())
    };
    let c = calibrate::calibrate(
        &study.params.factors(),
        &truth,
        &model,
        CalibrationOptions {
            restarts: 1,
            ..CalibrationOptions::default()
        },
    )
    .unwrap();
    let p = &c.params[0];
    assert!(c.initial.rmse > 1.0, "{}", c.initial.rmse);
    let (lo, hi) = (p.ci_low.unwrap(), p.ci_high.unwrap());
    assert!(lo <= 0.82 && 0.82 <= hi, "{p:?}");
    assert!(hi - lo < 0.1, "{p:?}");
}

#[test]
fn geodetic_to_enu_matches_the_ellipsoid_radii() {
    let site = irsig::sun::Site::new(43.16, -77.61, 160.0).unwrap();
    // A small step north is the meridian radius M = a(1−e²)/(1−e² sin²φ)^{3/2}
    // times Δφ; a step east the prime-vertical radius N cos φ times Δλ.
    let (a, f) = (geo::WGS84_A_M, geo::WGS84_F);
    let e2 = f * (2.0 - f);
    let s2 = 43.16f64.to_radians().sin().powi(2);
    let m = a * (1.0 - e2) / (1.0 - e2 * s2).powf(1.5);
    let n = a / (1.0 - e2 * s2).sqrt();
    let d = 1e-4f64;
    let north = geo::enu_from_geodetic(&site, 43.16 + d, -77.61, 160.0);
    assert_close!(north.y, (m + 160.0) * d.to_radians(), 1e-3);
    assert_close!(north.x, 0.0, 1e-6);
    let east = geo::enu_from_geodetic(&site, 43.16, -77.61 + d, 160.0);
    assert_close!(
        east.x,
        (n + 160.0) * 43.16f64.to_radians().cos() * d.to_radians(),
        1e-3
    );
    // Up: the site itself is the origin; 10 m above it is z = 10.
    assert_close!(
        geo::enu_from_geodetic(&site, 43.16, -77.61, 170.0).z,
        10.0,
        1e-6
    );
    // Earth curvature: 1 km east drops below the tangent plane by ≈ d²/2R.
    let km = 1000.0 / ((n + 160.0) * 43.16f64.to_radians().cos());
    let p = geo::enu_from_geodetic(&site, 43.16, -77.61 + km.to_degrees(), 160.0);
    assert_close!(p.z, -1000.0f64.powi(2) / (2.0 * n), 2e-3);
}

#[test]
fn latlon_points_land_on_their_pixel_or_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let session =
        Session::open(&tiny_scene(dir.path(), None), irsig::trace::Backend::Embree).unwrap();
    let site = session.scene.site;
    // The block's roof centre, (0, 5, 6) m ENU: invert the small-offset
    // relation to lat/lon, then the point must project where the sensor
    // projects the roof point.
    let e2 = geo::WGS84_F * (2.0 - geo::WGS84_F);
    let s2 = site.latitude_deg.to_radians().sin().powi(2);
    let m = geo::WGS84_A_M * (1.0 - e2) / (1.0 - e2 * s2).powf(1.5) + site.altitude_m;
    let lat = site.latitude_deg + (5.0 / m).to_degrees();
    let at = irsig::Location::file("pts.csv").at_line(2);
    let uv = geo::pixel_of_latlon(&session, 0, lat, site.longitude_deg, &at).unwrap();
    let want = session.sensors[0]
        .project(glam::DVec3::new(0.0, 5.0, 6.0))
        .unwrap();
    assert!((uv - want).length() < 0.01, "{uv} vs {want}");
    // Ground 3 m north of the block is hidden from the camera (south of it,
    // looking down at 45°): refused, not silently given the block's pixel.
    let hidden = site.latitude_deg + (14.0 / m).to_degrees();
    let e = geo::pixel_of_latlon(&session, 0, hidden, site.longitude_deg, &at)
        .unwrap_err()
        .to_string();
    assert!(e.contains("hidden") && e.contains("pts.csv"), "{e}");
    // …while ground south of the block is seen.
    let open = site.latitude_deg + (-20.0 / m).to_degrees();
    geo::pixel_of_latlon(&session, 0, open, site.longitude_deg, &at).unwrap();
    // Through the CSV path: a point 1 km away falls outside the image.
    let csvp = dir.path().join("pts.csv");
    std::fs::write(
        &csvp,
        format!(
            "id,lat,lon,value\nroof,{lat},{},300\nfar,{},{},300\n",
            site.longitude_deg,
            site.latitude_deg + 0.01,
            site.longitude_deg
        ),
    )
    .unwrap();
    let pts = csv::read_truth_points(&csvp).unwrap();
    let e = geo::points_to_pixels(&session, 0, &pts, &csvp)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("pts.csv") && e.contains("line 3") && e.contains("outside"),
        "{e}"
    );
    let ok = geo::points_to_pixels(&session, 0, &pts[..1], &csvp).unwrap();
    assert_eq!(
        ok[0].position,
        csv::PointPosition::Pixel { x: uv.x, y: uv.y }
    );
}

#[test]
fn cli_scene_sensitivity_and_diurnal_run() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path(), Some(serde_json::json!({"model": "builtin"})));
    let params = write_params(
        dir.path(),
        r#"[{"kind": "weather", "property": "relative_humidity_offset", "low": -0.2, "high": 0.2},
            {"kind": "material", "material": "concrete", "property": "solar_absorptivity", "low": 0.5, "high": 0.8}]"#,
    );
    let plot = dir.path().join("tornado.png");
    let (ok, out, err) = run_irsig(&[
        "sensitivity".as_ref(),
        scene.as_os_str(),
        "--params".as_ref(),
        params.as_os_str(),
        "--per-material".as_ref(),
        "2".as_ref(),
        "--json".as_ref(),
        "--plot".as_ref(),
        plot.as_os_str(),
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let outputs: Vec<String> = serde_json::from_value(v["outputs"].clone()).unwrap();
    assert!(
        outputs.contains(&"asphalt.apparent_temperature_k".to_string()),
        "{outputs:?}"
    );
    assert!(
        outputs.contains(&"concrete.apparent_temperature_k".to_string()),
        "{outputs:?}"
    );
    assert!(std::fs::metadata(&plot).unwrap().len() > 1000);
    // Morris screening on the scene, text report.
    let (ok, out, err) = run_irsig(&[
        "sensitivity".as_ref(),
        scene.as_os_str(),
        "--params".as_ref(),
        params.as_os_str(),
        "--per-material".as_ref(),
        "1".as_ref(),
        "--method".as_ref(),
        "morris".as_ref(),
        "--trajectories".as_ref(),
        "3".as_ref(),
    ]);
    assert!(ok, "{err}");
    assert!(
        out.contains("scene study: ") && out.contains("mu*"),
        "{out}"
    );
    let (ok, out, err) = run_irsig(&[
        "diurnal".as_ref(),
        scene.as_os_str(),
        "--target".as_ref(),
        "block".as_ref(),
        "--background".as_ref(),
        "asphalt".as_ref(),
        "--step".as_ref(),
        "60".as_ref(),
        "--samples".as_ref(),
        "3".as_ref(),
        "--json".as_ref(),
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["times"].as_array().unwrap().len(), 25);
    assert!(
        v["apparent_temperature"]["max_abs_contrast"]
            .as_f64()
            .unwrap()
            > 0.5
    );
    // An unknown target is named in the error.
    let (ok, _, err) = run_irsig(&[
        "diurnal".as_ref(),
        scene.as_os_str(),
        "--target".as_ref(),
        "tower".as_ref(),
        "--background".as_ref(),
        "asphalt".as_ref(),
    ]);
    assert!(!ok && err.contains("`tower`"), "{err}");
}

#[test]
fn cli_compare_latlon_points_against_a_render() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path(), None);
    // The check is of `compare`'s lat/lon → pixel mapping, whose premise is
    // a uniform ground around each point (a point on a pixel edge may take
    // the neighbour pixel). The shortwave reflected from the block and the
    // wind at each facet (issue 19) make the ground triangles by the block
    // differ by a few hundredths of a kelvin, so they are off here.
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&scene).unwrap()).unwrap();
    v["render"] = serde_json::json!({"thermal": {"reflected_bounces": 0, "facet_wind": false}});
    std::fs::write(&scene, v.to_string()).unwrap();
    let out = dir.path().join("out");
    let (ok, _, err) = run_irsig(&[
        "render".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(ok, "{err}");
    let exr = out.join("cam.exr");
    let synth = image::read_image(&exr).unwrap();
    let at = synth.layer("apparent_temperature").unwrap();
    // Two points: the block's roof centre and a ground point 30 m south of
    // the site, as lat/lon; truth = the rendered pixel + 1 K.
    let session = Session::open(&scene, irsig::trace::Backend::Embree).unwrap();
    let site = session.scene.site;
    let e2 = geo::WGS84_F * (2.0 - geo::WGS84_F);
    let s2 = site.latitude_deg.to_radians().sin().powi(2);
    let m = geo::WGS84_A_M * (1.0 - e2) / (1.0 - e2 * s2).powf(1.5) + site.altitude_m;
    let mut rows = String::from("id,lat,lon,value\n");
    for (id, north, z) in [("roof", 5.0, 6.0), ("road", -30.0, 0.0)] {
        let uv = session.sensors[0]
            .project(glam::DVec3::new(0.0, north, z))
            .unwrap();
        let k = uv.y as usize * synth.width + uv.x as usize;
        let lat = site.latitude_deg + (north / m).to_degrees();
        rows += &format!(
            "{id},{lat},{},{}\n",
            site.longitude_deg,
            at.data[k] as f64 + 1.0
        );
    }
    let pts = dir.path().join("pts.csv");
    std::fs::write(&pts, rows).unwrap();
    let (ok, _, err) = run_irsig(&["compare".as_ref(), exr.as_os_str(), pts.as_os_str()]);
    assert!(!ok && err.contains("--scene"), "{err}");
    let (ok, out, err) = run_irsig(&[
        "compare".as_ref(),
        exr.as_os_str(),
        pts.as_os_str(),
        "--scene".as_ref(),
        scene.as_os_str(),
        "--json".as_ref(),
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let o = &v["points"]["overall"];
    // (a point within a hair of a pixel edge may take the neighbour pixel)
    assert_close!(o["bias"].as_f64().unwrap(), -1.0, 0.01);
    assert_close!(o["rmse"].as_f64().unwrap(), 1.0, 0.01);
    assert_eq!(v["points"]["points"].as_array().unwrap().len(), 2);
}

/// Brightness temperatures (8–12 µm, K) at `points` of a full render (scene-wide
/// solve, render) of the tiny scene in `dir` whose `asphalt` takes `edits`
/// (material fields), through its own materials file.
fn full_render_of_perturbed_asphalt(
    dir: &std::path::Path,
    edits: &[(&str, f64)],
    points: &[PixelPoint],
) -> Vec<f64> {
    let mut db: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(crate::util::repo_path("scenes/materials.json")).unwrap(),
    )
    .unwrap();
    for m in db["materials"].as_array_mut().unwrap() {
        if m["name"] == "asphalt" {
            for &(k, v) in edits {
                m[k] = v.into();
            }
        }
    }
    let mats = dir.join("materials_truth.json");
    std::fs::write(&mats, db.to_string()).unwrap();
    let mut scene: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("scene.json")).unwrap()).unwrap();
    scene["materials"] = serde_json::json!([mats]);
    let truth_path = dir.join("truth.json");
    std::fs::write(&truth_path, scene.to_string()).unwrap();
    let mut truth = Session::open(&truth_path, irsig::trace::Backend::Embree).unwrap();
    let t = truth.scene.time;
    let states = truth.thermal(&[t]).unwrap();
    let band = truth
        .render_rows(0, &states.conditions[0], 0..16, &|_| {})
        .unwrap();
    points
        .iter()
        .map(|p| band_bt(band.radiance()[0][p.y as usize * 24 + p.x as usize] as f64))
        .collect()
}

/// 8–12 µm brightness temperature (K) of a band radiance (W m⁻² sr⁻¹).
fn band_bt(l: f64) -> f64 {
    irsig::radiometry::Band::flat(8.0, 12.0, 0.01)
        .unwrap()
        .brightness_temperature(l)
        .unwrap()
}

#[test]
fn scene_model_matches_a_full_render_of_the_perturbed_scene() {
    // Fixed-geometry model at asphalt α = 0.78, k = 1.2 vs the whole chain
    // (scene-wide solve, render) of a scene whose materials say so.
    let dir = tempfile::tempdir().unwrap();
    let params = r#"[
      {"kind": "material", "material": "asphalt", "property": "solar_absorptivity", "low": 0.7, "high": 0.98},
      {"kind": "material", "material": "asphalt", "property": "conductivity", "low": 0.4, "high": 2.0}
    ]"#;
    let points: Vec<PixelPoint> = [(2.5, 15.5), (20.5, 14.5), (12.5, 12.5), (12.5, 8.5)]
        .iter()
        .enumerate()
        .map(|(i, &(x, y))| px(&format!("p{i}"), x, y))
        .collect();
    let study = tiny_study(dir.path(), params, points.clone());
    let x = [0.78, 1.2];
    let model = study.pixels(&x).unwrap();
    let nominal = study.pixels(&study.params.nominal()).unwrap();
    // The perturbed scene: its own materials file.
    let fulls = full_render_of_perturbed_asphalt(
        dir.path(),
        &[("solar_absorptivity", 0.78), ("conductivity_w_m_k", 1.2)],
        &points,
    );
    for (((p, m), n), &full) in points.iter().zip(&model).zip(&nominal).zip(&fulls) {
        let (mt, nt) = (
            band_bt(m.band_radiance_w_m2_sr),
            band_bt(n.band_radiance_w_m2_sr),
        );
        eprintln!(
            "{}: nominal {nt:.3} K, model {mt:.3} K, full render {full:.3} K",
            p.label
        );
        // The change is captured to within a few per cent of itself
        // (and ≤ 0.1 K).
        assert!(
            (mt - full).abs() <= 0.1_f64.min(0.05 * (full - nt).abs()).max(0.01),
            "{}: model {mt} vs full {full} (nominal {nt})",
            p.label
        );
    }
}

/// A brighter road sends more sunlight onto the block beside it: the model
/// recomputes the reflected shortwave at the perturbed albedos, so the
/// block's pixels follow a full render of the perturbed scene.
#[test]
fn scene_model_follows_the_sunlight_a_brighter_road_reflects() {
    let dir = tempfile::tempdir().unwrap();
    let params = r#"[
      {"kind": "material", "material": "asphalt", "property": "solar_absorptivity", "low": 0.3, "high": 0.98}
    ]"#;
    let points: Vec<PixelPoint> = [(12.5, 7.5), (10.5, 7.5), (12.5, 6.5), (14.5, 6.5)]
        .iter()
        .enumerate()
        .map(|(i, &(x, y))| px(&format!("p{i}"), x, y))
        .collect();
    let study = tiny_study(dir.path(), params, points.clone());
    let x = [0.4];
    let model = study.pixels(&x).unwrap();
    let nominal = study.pixels(&study.params.nominal()).unwrap();
    let fulls =
        full_render_of_perturbed_asphalt(dir.path(), &[("solar_absorptivity", 0.4)], &points);
    let mut changes = Vec::new();
    for (((p, m), n), &full) in points.iter().zip(&model).zip(&nominal).zip(&fulls) {
        let (mt, nt) = (
            band_bt(m.band_radiance_w_m2_sr),
            band_bt(n.band_radiance_w_m2_sr),
        );
        eprintln!(
            "{}: nominal {nt:.3} K, model {mt:.3} K, full render {full:.3} K",
            p.label
        );
        changes.push(full - nt);
        // Within a tenth of the change: the facets farther away keep their
        // rendered temperatures. With the reflected shortwave of the
        // nominal albedos the block's face went the wrong way (−2.8 K
        // against the full render's +1.7 K).
        assert!(
            (mt - full).abs() <= 0.1 * (full - nt).abs() + 0.01,
            "{}: model {mt} vs full {full} (nominal {nt})",
            p.label
        );
    }
    // The block's sunlit south face (the first two points) warms with the
    // road's albedo: what the road reflects onto it outweighs the cooler
    // road in its background.
    assert!(changes[0] > 1.0 && changes[1] > 1.0, "{changes:?}");
}

#[test]
fn scene_model_of_humidity_and_cloud_matches_a_render_with_that_weather() {
    // With the built-in atmosphere (sky radiance and sensor path from the
    // weather): the model at RH +0.15 and cloud +0.3 vs a full render with a
    // weather file holding those records.
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path(), Some(serde_json::json!({"model": "builtin"})));
    let session = Session::open(&scene, irsig::trace::Backend::Embree).unwrap();
    let time = session.scene.time;
    let ps = ParamSet::load(
        write_params(
            dir.path(),
            r#"[{"kind": "weather", "property": "relative_humidity_offset", "low": -0.3, "high": 0.3},
                {"kind": "weather", "property": "cloud_cover_offset", "low": 0, "high": 0.5}]"#,
        ),
        session.scene.materials.materials(),
    )
    .unwrap();
    let site = session.scene.site;
    let x = [0.15, 0.3];
    let records = ps
        .apply_weather_at(&x, session.weather.records(), Some(&site))
        .unwrap();
    let history = irsig::weather::WeatherHistory::new(records, Some(site)).unwrap();
    let wpath = dir.path().join("weather_truth.csv");
    let mut f = std::fs::File::create(&wpath).unwrap();
    irsig::weather::write_csv(&history, &[], &mut f).unwrap();
    drop(f);
    let points = vec![
        px("ground", 3.5, 14.5),
        px("far", 20.5, 2.5),
        px("mid", 12.5, 8.5),
    ];
    let study = SceneStudy::new(session, 0, time, ps, points.clone(), Vec::new()).unwrap();
    let model = study.pixels(&x).unwrap();
    let nominal = study.pixels(&study.params.nominal()).unwrap();
    let mut s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&scene).unwrap()).unwrap();
    s["weather"] = serde_json::json!({"file": wpath});
    let truth_path = dir.path().join("truth.json");
    std::fs::write(&truth_path, s.to_string()).unwrap();
    let mut truth = Session::open(&truth_path, irsig::trace::Backend::Embree).unwrap();
    let states = truth.thermal(&[time]).unwrap();
    let band = truth
        .render_rows(0, &states.conditions[0], 0..16, &|_| {})
        .unwrap();
    for ((p, m), n) in points.iter().zip(&model).zip(&nominal) {
        let full = band_bt(band.radiance()[0][p.y as usize * 24 + p.x as usize] as f64);
        let (mt, nt) = (
            band_bt(m.band_radiance_w_m2_sr),
            band_bt(n.band_radiance_w_m2_sr),
        );
        eprintln!(
            "{}: nominal {nt:.3} K, model {mt:.3} K, full render {full:.3} K",
            p.label
        );
        assert!((full - nt).abs() > 0.1, "the weather change should show");
        assert!(
            (mt - full).abs() <= 0.1_f64.min(0.05 * (full - nt).abs()).max(0.01),
            "{}: model {mt} vs full {full} (nominal {nt})",
            p.label
        );
    }
}

/// Issue 16's validation as a user would run it, on both flux-tower sites:
/// calibrate the stock `crop` (leaf area, stomatal resistance, soil
/// moisture, canopy–soil conductance, solar absorptivity) with `irsig
/// calibrate --thermal` on the first half of the 42-day subset, then run
/// `irsig thermal` with the fitted files over the whole subset and score
/// the second half against the measured surface temperature. At US-CRT the
/// soybean grows from 0.15 m to about 1 m between the halves (its README):
/// the crop is given those heights, its leaves grow with them (LAI =
/// min(a·h, LAI)) and the fit takes the growth `a` instead of a constant
/// LAI, which fitted to the sparse first half would mispredict the closed
/// second (2.01 K). Issue 16's goal, RMSE ≤ 1.5 K and Spearman ≥ 0.97 on
/// the second half, is asserted at both (measured: Bondville 1.24 K,
/// 0.982; US-CRT 1.36 K, 0.988, the fitted `a` 6.4 m⁻¹ against METRIC's
/// 6.8 for field crops).
#[test]
#[ignore = "needs ../shared/data"]
fn calibrated_crop_predicts_the_second_half_of_both_flux_sites() {
    use irsig::analysis::stats;
    // US-CRT twice: with a constant LAI fitted (the canopy as if it did
    // not grow) and with the growth fitted.
    let mut constant_lai_rmse = None;
    for (file, growing) in [
        ("bondville_1998/bondville_1998_aug01-sep11.csv", false),
        ("us-crt_2011/us-crt_2011_jul06-aug16.csv", false),
        ("us-crt_2011/us-crt_2011_jul06-aug16.csv", true),
    ] {
        let d = irsig::weather::flux::load(&crate::util::shared_data("flux").join(file)).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let p = |name: &str| dir.path().join(name);
        let write_weather = |range: std::ops::Range<usize>, name: &str| {
            let (history, _) = d.weather(range).unwrap();
            let mut w = Vec::new();
            irsig::weather::write_csv(&history, &[file], &mut w).unwrap();
            std::fs::write(p(name), w).unwrap();
            irsig::weather::load(&p(name)).unwrap()
        };
        let first = d.first_half();
        let first_w = write_weather(first.clone(), "first.csv");
        let all_w = write_weather(0..d.len(), "all.csv");
        let series =
            |range: std::ops::Range<usize>, w: &irsig::weather::WeatherHistory, off: usize| {
                range
                    .filter_map(|i| {
                        d.records()[i]
                            .surface_temperature_k
                            .map(|t| (w.records()[i - off].time.to_rfc3339(), t))
                    })
                    .collect::<Vec<_>>()
            };
        let truth_first = series(first.clone(), &first_w, first.start);
        let truth_second = series(d.second_half(), &all_w, 0);
        let mut text = String::from("time,surface_temperature_k\n");
        for (t, v) in &truth_first {
            text += &format!("{t},{v}\n");
        }
        std::fs::write(p("truth.csv"), text).unwrap();
        // US-CRT's soybean grows (its README's heights): the user gives the
        // crop those heights and leaves that grow with them (LAI =
        // min(a·h, LAI), METRIC's field-crop a = 6.8 m⁻¹), and fits the
        // growth `a` instead of a fixed LAI. Bondville's heights are not
        // documented: its crop keeps a constant LAI, fitted.
        let mut db: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(crate::util::repo_path("scenes/materials.json")).unwrap(),
        )
        .unwrap();
        let crop = db["materials"]
            .as_array_mut()
            .unwrap()
            .iter_mut()
            .find(|m| m["name"] == "crop")
            .unwrap();
        let se = &mut crop["surface_energy"];
        // US-CRT's wind and air height, which its metadata does not give:
        // the neutral log law on its wind and u* over the README's canopy
        // heights (linear between 0.15 m on 5 Jul, 0.45 m on 26 Jul and
        // 0.975 m on 19 Aug).
        if let Some(z) = d.log_law_wind_height_m(0..d.len(), |t| {
            let day = (t.timestamp() as f64 - 1_309_824_000.0) / 86_400.0;
            if day < 21.0 {
                0.15 + 0.30 * day / 21.0
            } else {
                0.45 + 0.525 * ((day - 21.0) / 24.0).min(1.0)
            }
        }) {
            se["measurement_height_m"] = serde_json::json!(z);
        }
        if growing {
            se["phenology"] = serde_json::json!([
                {"date": "2011-07-05", "canopy_height_m": 0.15},
                {"date": "2011-07-26", "canopy_height_m": 0.45},
                {"date": "2011-08-19", "canopy_height_m": 0.975}
            ]);
            se["leaf_area_per_height_per_m"] = serde_json::json!(6.8);
        }
        std::fs::write(p("materials.json"), db.to_string()).unwrap();
        let leaves = if growing {
            r#"{"kind": "material", "material": "crop", "property": "surface_energy.leaf_area_per_height_per_m", "low": 1, "high": 30}"#
        } else {
            r#"{"kind": "material", "material": "crop", "property": "surface_energy.leaf_area_index", "low": 0.5, "high": 7}"#
        };
        std::fs::write(
            p("fit.json"),
            format!(r#"[{leaves},
                {{"kind": "material", "material": "crop", "property": "surface_energy.min_stomatal_resistance_s_m", "low": 30, "high": 400}},
                {{"kind": "material", "material": "crop", "property": "surface_energy.soil_moisture_m3_m3", "low": 0.13, "high": 0.32}},
                {{"kind": "material", "material": "crop", "property": "surface_energy.skin_conductance_w_m2_k", "low": 3, "high": 50}},
                {{"kind": "material", "material": "crop", "property": "solar_absorptivity", "low": 0.7, "high": 0.9}}]"#),
        )
        .unwrap();
        let materials = p("materials.json");
        let os = |v: &[&dyn AsRef<std::ffi::OsStr>]| -> Vec<std::ffi::OsString> {
            v.iter().map(|s| s.as_ref().to_os_string()).collect()
        };
        let args = os(&[
            &"calibrate",
            &"--thermal",
            &"--material",
            &"crop",
            &"--materials",
            &materials,
            &"--weather",
            &p("first.csv"),
            &"--truth",
            &p("truth.csv"),
            &"--params",
            &p("fit.json"),
            &"-o",
            &p("fitted.json"),
            &"--params-out",
            &p("fitted_params.json"),
            &"--json",
        ]);
        let r: Vec<&std::ffi::OsStr> = args.iter().map(|s| s.as_os_str()).collect();
        let (ok, out, err) = run_irsig(&r);
        assert!(ok, "{err}");
        let fit: serde_json::Value = serde_json::from_str(&out).unwrap();
        let last = all_w.records().last().unwrap().time.to_rfc3339();
        let args = os(&[
            &"thermal",
            &"--csv",
            &"--material",
            &p("fitted.json"),
            &"--params",
            &p("fitted_params.json"),
            &"--weather",
            &p("all.csv"),
            &"--time",
            &last,
        ]);
        let r: Vec<&std::ffi::OsStr> = args.iter().map(|s| s.as_os_str()).collect();
        let (ok, out, err) = run_irsig(&r);
        assert!(ok, "{err}");
        let model = thermal_csv_by_time(&out);
        let (m, t): (Vec<f64>, Vec<f64>) = truth_second
            .iter()
            .map(|(time, v)| (model[time.as_str()], *v))
            .unzip();
        let rmse = stats::rmse(&m, &t).unwrap();
        let rho = stats::spearman(&m, &t).unwrap();
        let bias = stats::bias(&m, &t).unwrap();
        let fitted: Vec<String> = fit["params"]
            .as_array()
            .unwrap()
            .iter()
            .map(|q| format!("{} = {:.3}", q["name"], q["fitted"]))
            .collect();
        eprintln!(
            "{file}{}: crop fitted on the first half (RMSE {:.2} → {:.2} K: {}); second half: \
             RMSE {rmse:.2} K, bias {bias:+.2} K, Spearman {rho:.3} (n = {})",
            if growing { ", growing" } else { "" },
            fit["initial"]["rmse"].as_f64().unwrap(),
            fit["fitted"]["rmse"].as_f64().unwrap(),
            fitted.join(", "),
            m.len()
        );
        if file.starts_with("us-crt") && !growing {
            // A constant LAI fitted to the sparse first half: a bound that
            // catches a broken fit; the growing canopy must do better.
            assert!(rmse <= 3.0, "{file}: second-half RMSE {rmse}");
            constant_lai_rmse = Some(rmse);
            continue;
        }
        assert!(rho >= 0.97, "{file}: second-half Spearman {rho}");
        assert!(rmse <= 1.5, "{file}: second-half RMSE {rmse}");
        if growing {
            let c = constant_lai_rmse.unwrap();
            assert!(
                rmse < c - 0.2,
                "{file}: growing {rmse} K, constant LAI {c} K"
            );
        }
    }
}
