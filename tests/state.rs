//! Tests: the per-facet state split across processes (issue 23) —
//! `irsig thermal-scene --state DIR [--pass 1|2 --shard K/N]` and
//! `irsig render --state DIR`: shards merge to the unsplit state exactly,
//! a render from a state equals the render in one piece bit for bit (with
//! and without tiles, and through `scripts/slurm-render.sh` run locally),
//! pass 2 refuses to start with a pass-1 shard missing, a killed shard
//! leaves no file under its final name, and a state from another scene or
//! other times is refused.

use std::path::{Path, PathBuf};
use std::process::Command;

use irsig::render::session::Session;
use irsig::render::state::{self, FacetStates};
use irsig::trace::Backend;
use serde_json::json;

use crate::util::{irsig_bin, repo_path};

/// A scene in `dir` with enough facets for several batches of the rays
/// (a 200 m ground of `edge_m` triangles, two sheds, one with a glass
/// roof) and a small noisy frame camera.
fn write_scene(dir: &Path, edge_m: f64, ground: &str) -> PathBuf {
    let scene = json!({
        "site": {"latitude_deg": 43.16, "longitude_deg": -77.61, "altitude_m": 160.0,
                 "utc_offset_hours": -4.0},
        "time": "2025-06-21T14:00:00-04:00",
        "weather": {"file": repo_path("scenes/town/weather.csv")},
        "materials": [repo_path("scenes/materials.json")],
        "objects": [
            {"name": "ground", "material": ground,
             "shapes": [{"plane": {"size": [200.0, 200.0], "max_edge_m": edge_m}}]},
            {"name": "shed", "parts": [{"name": "top", "material": "glass"},
                                       {"name": "sides", "material": "brick"}],
             "shapes": [{"box": {"size": [20.0, 12.0, 6.0], "bottom": false}}],
             "instances": [{"translate": [-20.0, 10.0, 0.0]},
                           {"translate": [25.0, -5.0, 0.0], "rotate_deg": [0.0, 0.0, 30.0]}]}
        ],
        "sensors": [{"type": "frame", "name": "cam", "width": 24, "height": 18,
                     "fov_deg": 60.0, "position": [0.0, -120.0, 80.0],
                     "look_at": [0.0, 0.0, 0.0], "oversample": 2,
                     "psf": {"type": "gaussian", "sigma_px": 0.5},
                     "nedt_k": 0.05, "bits": 12, "gain": 100.0, "seed": 7,
                     "bands": [{"name": "LWIR", "response": [8.0, 12.0]}]}]
    });
    let path = dir.join("scene.json");
    std::fs::write(&path, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    path
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
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

/// `irsig ARGS` that must fail; its stderr.
fn irsig_fails(args: &[&str]) -> String {
    let out = Command::new(irsig_bin()).args(args).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "irsig {args:?} succeeded");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    err
}

/// The four image files of `cam` in `a` and `b` are the same bytes.
fn same_images(a: &Path, b: &Path) {
    for ext in ["exr", "img", "hdr", "png"] {
        let (x, y) = (
            std::fs::read(a.join(format!("cam.{ext}"))).unwrap(),
            std::fs::read(b.join(format!("cam.{ext}"))).unwrap(),
        );
        assert!(
            x == y,
            "cam.{ext} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
}

fn read(scene: &Path, dir: &Path) -> FacetStates {
    let session = Session::open(scene, Backend::Embree).unwrap();
    state::read_states(&session, dir, &[]).unwrap()
}

#[test]
fn shard_ranges_are_whole_batches_covering_every_facet_once() {
    for (facets, n) in [
        (0, 1),
        (1, 3),
        (5000, 3),
        (5120, 10),
        (100_000, 7),
        (513, 2),
    ] {
        let mut next = 0;
        for k in 1..=n {
            let r = state::shard_range(k, n, facets, 512);
            assert_eq!(r.start, next, "{facets} facets, {k}/{n}");
            assert!(r.start.is_multiple_of(512) || r.start == facets);
            next = r.end;
        }
        assert_eq!(next, facets);
    }
}

#[test]
fn split_state_equals_the_unsplit_one_and_renders_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 2 × 50² ground triangles + the sheds: 10 batches of 512 facets.
    let scene = write_scene(d, 4.0, "asphalt");
    let facets = Session::open(&scene, Backend::Embree)
        .unwrap()
        .scene
        .geometry
        .facet_count();
    assert!(facets > 4 * 512, "{facets} facets");
    let (one, whole, split) = (d.join("one"), d.join("whole"), d.join("split"));
    irsig(&["render", s(&scene), "-o", s(&one), "--quiet"]);

    // In one process.
    irsig(&["thermal-scene", s(&scene), "--state", s(&whole), "--quiet"]);
    assert!(whole.join("state-1-of-1.arrow").exists());
    let out = d.join("from_whole");
    irsig(&[
        "render",
        s(&scene),
        "--state",
        s(&whole),
        "-o",
        s(&out),
        "--quiet",
    ]);
    same_images(&one, &out);

    // Pass 1 in three shards, out of order; pass 2 in two.
    for k in [2, 3, 1] {
        let shard = format!("{k}/3");
        let a = [
            "thermal-scene",
            s(&scene),
            "--state",
            s(&split),
            "--pass",
            "1",
        ];
        irsig(&[&a[..], &["--shard", &shard, "--quiet"]].concat());
    }
    for k in [2, 1] {
        let shard = format!("{k}/2");
        let a = [
            "thermal-scene",
            s(&scene),
            "--state",
            s(&split),
            "--pass",
            "2",
        ];
        irsig(&[&a[..], &["--shard", &shard, "--quiet"]].concat());
    }
    let (w, p) = (read(&scene, &whole), read(&scene, &split));
    assert_eq!(w.len(), facets);
    // Bit for bit (f32 equality would pass -0.0 == 0.0; the bits do not).
    let bits = |v: &FacetStates| -> Vec<u32> {
        let mut out: Vec<u32> = v.shape_factor.iter().map(|x| x.to_bits()).collect();
        for a in &v.at {
            for q in [
                &a.temperature_k,
                &a.sun_fraction,
                &a.cos_sun,
                &a.background_k,
            ] {
                out.extend(q.iter().map(|x| x.to_bits()));
            }
        }
        out
    };
    assert!(
        bits(&w) == bits(&p),
        "the split state differs from the unsplit one"
    );
    assert_eq!(w, p);

    // Rendered from the split state: whole, and in tiles merged.
    let out = d.join("from_split");
    irsig(&[
        "render",
        s(&scene),
        "--state",
        s(&split),
        "-o",
        s(&out),
        "--quiet",
    ]);
    same_images(&one, &out);
    let tiles = d.join("tiles");
    for k in [1, 2] {
        let tile = format!("{k}/2");
        let a = ["render", s(&scene), "--state", s(&split), "-o", s(&tiles)];
        irsig(&[&a[..], &["--tile", &tile, "--quiet"]].concat());
    }
    let merged = d.join("merged");
    irsig(&[
        "merge",
        s(&tiles.join("cam.tile1-of-2.exr")),
        s(&tiles.join("cam.tile2-of-2.exr")),
        "-o",
        s(&merged),
        "--quiet",
    ]);
    same_images(&one, &merged);

    // A shard already complete is skipped, its file untouched.
    let f = split.join("rays-2-of-3.arrow");
    let before = std::fs::metadata(&f).unwrap().modified().unwrap();
    let out = irsig(&[
        "thermal-scene",
        s(&scene),
        "--state",
        s(&split),
        "--pass",
        "1",
        "--shard",
        "2/3",
    ]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("already complete"));
    assert_eq!(std::fs::metadata(&f).unwrap().modified().unwrap(), before);
}

#[test]
fn pass_2_refuses_to_start_with_a_pass_1_shard_missing() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), 4.0, "asphalt");
    let st = dir.path().join("st");
    let base = ["thermal-scene", s(&scene), "--state", s(&st), "--quiet"];
    irsig(&[&base[..], &["--pass", "1", "--shard", "1/3"]].concat());
    irsig(&[&base[..], &["--pass", "1", "--shard", "3/3"]].concat());
    let err = irsig_fails(&[&base[..], &["--pass", "2"]].concat());
    assert!(err.contains("missing"), "{err}");
    assert!(err.contains(s(&st.join("rays-2-of-3.arrow"))), "{err}");
    assert!(
        !err.contains("rays-1-of-3") && !err.contains("rays-3-of-3"),
        "{err}"
    );
    assert!(!st.join("state-1-of-1.arrow").exists());
    // Another split into the same folder is refused, naming the one there.
    let err = irsig_fails(&[&base[..], &["--pass", "1", "--shard", "2/4"]].concat());
    assert!(err.contains("--shard") && err.contains("3 shards"), "{err}");
    // A render before pass 2 is told so.
    let err = irsig_fails(&[
        "render",
        s(&scene),
        "--state",
        s(&st),
        "-o",
        s(&dir.path().join("o")),
    ]);
    assert!(err.contains("--state") && err.contains("pass 2"), "{err}");
}

#[test]
fn a_state_from_another_scene_or_other_times_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    std::fs::create_dir_all(&a).unwrap();
    std::fs::create_dir_all(&b).unwrap();
    let scene = write_scene(&a, 20.0, "asphalt");
    let other = write_scene(&b, 20.0, "concrete");
    let st = dir.path().join("st");
    irsig(&["thermal-scene", s(&scene), "--state", s(&st), "--quiet"]);
    let out = dir.path().join("out");
    // Another material on the ground: another scene.
    let err = irsig_fails(&["render", s(&other), "--state", s(&st), "-o", s(&out)]);
    assert!(err.contains("another scene"), "{err}");
    // Other settings of the rays.
    let err = irsig_fails(&[
        "render",
        s(&scene),
        "--state",
        s(&st),
        "-o",
        s(&out),
        "--facet-samples",
        "3",
    ]);
    assert!(err.contains("another scene or other settings"), "{err}");
    // Other times.
    let err = irsig_fails(&[
        "render",
        s(&scene),
        "--state",
        s(&st),
        "-o",
        s(&out),
        "--times",
        "2025-06-21T15:00:00-04:00",
    ]);
    assert!(
        err.contains("holds the times 2025-06-21T14:00:00-04:00"),
        "{err}"
    );
    // Pass 1 of another scene into the folder is refused too.
    let err = irsig_fails(&["thermal-scene", s(&other), "--state", s(&st), "--pass", "1"]);
    assert!(err.contains("another scene"), "{err}");
    assert!(!out.join("cam.exr").exists());
}

#[test]
fn a_killed_shard_leaves_no_file_under_its_final_name() {
    let dir = tempfile::tempdir().unwrap();
    // Fine ground and two days of history: a pass-1 file of some MB.
    let scene = write_scene(dir.path(), 2.0, "asphalt");
    let st = dir.path().join("st");
    let times = "2025-06-20T14:00:00-04:00,2025-06-21T14:00:00-04:00";
    let args = [
        "thermal-scene",
        s(&scene),
        "--state",
        s(&st),
        "--times",
        times,
        "--pass",
        "1",
        "--quiet",
    ];
    let mut child = Command::new(irsig_bin()).args(args).spawn().unwrap();
    let start = std::time::Instant::now();
    let mut tmp = None;
    while start.elapsed() < std::time::Duration::from_secs(300) {
        if let Some(st) = child.try_wait().unwrap() {
            panic!("pass 1 ended ({st}) before it could be killed");
        }
        tmp = std::fs::read_dir(&st).ok().and_then(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .find(|n| n.starts_with(".rays-") && n.ends_with(".tmp"))
        });
        if tmp.is_some() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_micros(200));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(tmp.is_some(), "no temporary pass-1 file appeared");
    assert!(
        !st.join("rays-1-of-1.arrow").exists(),
        "rays-1-of-1.arrow exists after the kill"
    );
    // Pass 2 names the shard the kill lost; rerunning pass 1 completes it.
    let err = irsig_fails(&[
        "thermal-scene",
        s(&scene),
        "--state",
        s(&st),
        "--times",
        times,
        "--pass",
        "2",
    ]);
    assert!(err.contains("rays-1-of-1.arrow"), "{err}");
    irsig(&args);
    irsig(&[
        "thermal-scene",
        s(&scene),
        "--state",
        s(&st),
        "--times",
        times,
        "--pass",
        "2",
        "--quiet",
    ]);
    assert!(st.join("state-1-of-1.arrow").exists());
}

#[test]
fn slurm_chain_run_locally_equals_the_render_in_one_piece() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = write_scene(d, 4.0, "asphalt");
    let one = d.join("one");
    irsig(&["render", s(&scene), "-o", s(&one), "--quiet", "--seed", "3"]);
    let out = d.join("cluster");
    let run = || {
        let o = Command::new("bash")
            .arg(repo_path("scripts/slurm-render.sh"))
            .args([s(&scene), s(&out), "3", "--seed", "3"])
            .env("IRSIG", irsig_bin())
            .env("SLURM_LOCAL", "1")
            .env("SLURM_PASS2_SHARDS", "2")
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    run();
    same_images(&one, &out);
    for f in [
        "rays-1-of-3.arrow",
        "rays-3-of-3.arrow",
        "state-2-of-2.arrow",
    ] {
        assert!(out.join("state").join(f).exists(), "{f}");
    }
    // Resubmitted after a lost pass-1 shard and tile: only those are redone.
    let kept = out.join("state/rays-1-of-3.arrow");
    let before = std::fs::metadata(&kept).unwrap().modified().unwrap();
    std::fs::remove_file(out.join("state/rays-2-of-3.arrow")).unwrap();
    std::fs::remove_file(out.join("cam.tile2-of-3.exr")).unwrap();
    run();
    assert_eq!(
        std::fs::metadata(&kept).unwrap().modified().unwrap(),
        before
    );
    assert!(out.join("state/rays-2-of-3.arrow").exists());
    same_images(&one, &out);
}

#[test]
fn cli_bench_facets_reports_the_stages_facets_per_second_and_peak_memory() {
    let out = irsig(&["bench", "facets", "--facets", "3000", "--json"]);
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let num = |k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k} missing: {r}"));
    let facets = num("facets");
    assert!((facets - 3000.0).abs() <= 60.0, "{r}");
    for k in ["load_s", "bvh_build_s", "rays_s", "thermal_s"] {
        assert!(num(k) >= 0.0, "{k}: {r}");
    }
    assert!(num("thermal_s") > 0.0 && num("rays_s") > 0.0, "{r}");
    // The reflected shortwave is part of the thermal passes' time.
    assert!(
        num("reflected_s") > 0.0 && num("reflected_s") < num("thermal_s"),
        "{r}"
    );
    let per_s = facets / (num("rays_s") + num("thermal_s"));
    assert!((num("facets_per_s") - per_s).abs() <= 1e-6 * per_s, "{r}");
    // Linux reports the peak resident set; it is the process's whole.
    let peak = num("peak_rss_bytes");
    assert!(peak > 1e6, "{r}");
    assert!(
        (num("peak_bytes_per_facet") - peak / facets).abs() <= 1e-6 * peak,
        "{r}"
    );
}

/// A double-sided fence whose back face the camera sees (issue 18): the
/// state folder keeps each double-sided facet's back-face shape factor
/// (`back_shape_factor`, null for the single-sided ones), so a render from
/// the state equals the render in one piece bit for bit — before the
/// column, the back face took the front face's `F` there. A state file
/// without the column (written before it existed) still reads, with the
/// back faces' view unknown.
#[test]
fn a_state_keeps_the_back_faces_sky_view_of_double_sided_facets() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = write_scene(d, 20.0, "asphalt");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&scene).unwrap()).unwrap();
    // A 30 × 4 m leaf screen across the camera's view, its front (the
    // plane's +z) turned to +y, away from the camera at y = −120, and 1 m
    // from a 10 m brick wall: the camera sees the back face, open to the
    // sky, and a render from the state must give it its own view.
    json["objects"].as_array_mut().unwrap().push(json!({
        "name": "fence", "material": "deciduous_canopy",
        "shapes": [{"plane": {"size": [30.0, 4.0]},
                    "transform": {"rotate_deg": [-90.0, 0.0, 0.0],
                                  "translate": [0.0, -30.0, 2.0]}}]
    }));
    json["objects"].as_array_mut().unwrap().push(json!({
        "name": "wall", "material": "brick",
        "shapes": [{"box": {"size": [40.0, 1.0, 10.0]},
                    "transform": {"translate": [0.0, -28.5, 0.0]}}]
    }));
    std::fs::write(&scene, serde_json::to_string_pretty(&json).unwrap()).unwrap();
    let (one, st, from) = (d.join("one"), d.join("st"), d.join("from"));
    irsig(&["render", s(&scene), "-o", s(&one), "--quiet"]);
    irsig(&["thermal-scene", s(&scene), "--state", s(&st), "--quiet"]);
    irsig(&[
        "render",
        s(&scene),
        "--state",
        s(&st),
        "-o",
        s(&from),
        "--quiet",
    ]);
    same_images(&one, &from);

    let session = Session::open(&scene, Backend::Embree).unwrap();
    let states = state::read_states(&session, &st, &[]).unwrap();
    assert_eq!(states.back_shape_factor.len(), states.len());
    let fence: Vec<usize> = (0..states.len())
        .filter(|&f| states.back_shape_factor[f].is_some())
        .collect();
    // The plane's two triangles, and only they.
    assert_eq!(fence.len(), 2, "{:?}", states.back_shape_factor);
    for &f in &fence {
        let (front, back) = (states.shape_factor[f], states.back_shape_factor[f].unwrap());
        // The back sees half the sky. The front, 1 m from the wall along
        // its length, sees the sky above the wall's top only: (1 − sin α)/2
        // with α that top's elevation, 0.007 at the fence's top (sin α =
        // 6/√37) and less below, plus the slot's ends.
        assert!((0.45..=0.52).contains(&back), "F_back {back}");
        assert!(front < 0.1, "F {front}");
    }

    // The render from the state shades the back face the camera sees
    // with that face's own view: the truth layer `shape_factor` of the
    // fence's pixels (object 2) is the back face's, not the front's.
    let stack = irsig::output::read_exr(from.join("cam.exr")).unwrap();
    let layer = |name: &str| {
        &stack
            .layers
            .iter()
            .find(|l| l.name == name)
            .unwrap_or_else(|| panic!("no layer {name}"))
            .data
    };
    let seen: Vec<f32> = layer("object_id")
        .iter()
        .zip(layer("shape_factor"))
        .filter(|(o, _)| **o == 2.0)
        .map(|(_, f)| *f)
        .collect();
    assert!(!seen.is_empty(), "the camera sees no fence");
    assert!(seen.iter().all(|&f| f >= 0.45), "fence pixels' F {seen:?}");

    // A state file without the column: written from the same states with
    // the back faces' view unknown, it reads back unknown.
    let key = state::StateKey::of(&session, &[]).unwrap();
    let mut old = states.clone();
    old.back_shape_factor.clear();
    let p = d.join("old.arrow");
    state::write_states(&p, &key, (1, 1), &old).unwrap();
    let back = state::read_state_file(&p, &key, (1, 1), 0..states.len()).unwrap();
    assert!(back.back_shape_factor.is_empty());
    assert_eq!(back.shape_factor, states.shape_factor);
}
