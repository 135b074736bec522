//! Tests: `irsig scene check` agrees with `irsig render` (issue 21). Each
//! case edits one thing in a complete, renderable scene and runs the real
//! binary twice — `scene check` and `render` — and both must end the same
//! way: an error (exit ≠ 0, no panic) or success with a `warning:` line,
//! and both messages must contain the expected text (file, line, field,
//! what was expected, a "did you mean" where a key or name is misspelt).
//! Together with the malformed-input table in `tests/cli.rs` these are the
//! ≥ 80 malformed-input cases the issue asks for.

use std::process::Command;

use crate::util::irsig_bin;

/// A valid one-material database.
const MATS: &str = r#"{"materials": [
  {"name": "slab", "id": 7, "density_kg_m3": 2300, "specific_heat_j_kg_k": 880,
   "conductivity_w_m_k": 1.4, "thickness_m": 0.2, "solar_absorptivity": 0.7,
   "thermal_emissivity": 0.92, "exposed_area": 0.0}
]}
"#;

/// The baseline's `sensors` member: one small frame camera.
macro_rules! sensors {
    () => {
        r#""sensors": [
    {"type": "frame", "name": "cam", "width": 8, "height": 8, "pixel_pitch_m": 1.5e-05,
     "focal_length_m": 0.025, "position": [0, -60, 40], "look_at": [0, 0, 0], "up": [0, 0, 1],
     "bands": [{"name": "LWIR", "response": [8.0, 12.0]}]}
  ]"#
    };
}

/// The baseline scene: a ground plane and a box, one small frame camera,
/// hourly weather from 2025-06-20 00:00 to 06-22 00:00 (local, UTC−4).
const SCENE: &str = concat!(
    r#"{
  "site": {"latitude_deg": 43.16, "longitude_deg": -77.61, "altitude_m": 160, "utc_offset_hours": -4},
  "time": "2025-06-21T14:00:00-04:00",
  "materials": ["mats.json"],
  "weather": {"file": "w.csv"},
  "objects": [
    {"name": "ground", "shapes": [{"plane": {"size": [40, 40]}}], "material": "slab"},
    {"name": "block", "shapes": [{"box": {"size": [4, 4, 4]}}], "material": "slab"}
  ],
  "#,
    sensors!(),
    r#"
}
"#
);

/// Hourly weather covering the baseline's 24 h spin-up; `skip` hours
/// (indices from 06-20 00:00) are left out to make a gap.
fn weather(skip: std::ops::Range<usize>) -> String {
    let mut s = String::from(
        "time,air_temperature_k,dew_point_k,pressure_pa,wind_speed_m_s,global_horizontal_w_m2,\
         direct_normal_w_m2,diffuse_horizontal_w_m2\n",
    );
    for i in 0..=48usize {
        if skip.contains(&i) {
            continue;
        }
        let (day, hour) = (20 + i / 24, i % 24);
        let h = hour as f64;
        let t = 293.0 + 6.0 * ((h - 9.0) * std::f64::consts::PI / 12.0).sin();
        let ghi = (800.0 * ((h - 6.0) * std::f64::consts::PI / 14.0).sin()).max(0.0);
        s.push_str(&format!(
            "2025-06-{day:02}T{hour:02}:00:00-04:00,{t:.1},283,101325,2,{ghi:.0},{:.0},{:.0}\n",
            ghi * 0.9,
            ghi * 0.2
        ));
    }
    s
}

/// How a case must end, for both commands.
#[derive(Debug, Clone, Copy, PartialEq)]
enum End {
    /// Exit status ≠ 0.
    Error,
    /// Exit status 0 with a `warning:` line.
    Warning,
}

/// One case: a text replacement in the baseline scene (`from` must occur),
/// extra or replaced files, how it ends and what both messages contain.
struct Case {
    name: &'static str,
    from: &'static str,
    to: &'static str,
    files: &'static [(&'static str, &'static str)],
    end: End,
    expect: &'static [&'static str],
}

const CAM: &str = r#""focal_length_m": 0.025"#;

const CASES: &[Case] = &[
    // ---- sensors
    Case {
        name: "sensor key misspelt",
        from: CAM,
        to: r#""focal_lenght_m": 0.025"#,
        files: &[],
        end: End::Error,
        expect: &[
            "scene.json:line 12: column 6",
            "sensors[0].focal_lenght_m",
            "did you mean `focal_length_m`?",
        ],
    },
    Case {
        name: "sensor type misspelt",
        from: r#""type": "frame""#,
        to: r#""type": "fram""#,
        files: &[],
        end: End::Error,
        expect: &[
            "scene.json:line 11",
            "sensors[0].type",
            "did you mean `frame`?",
        ],
    },
    Case {
        name: "sensor width not a number",
        from: r#""width": 8"#,
        to: r#""width": "big""#,
        files: &[],
        end: End::Error,
        expect: &[
            "scene.json:line 11: column 38",
            "sensors[0].width",
            "invalid type",
            "usize",
        ],
    },
    Case {
        name: "sensor position element not a number",
        from: r#""position": [0, -60, 40]"#,
        to: r#""position": [0, -60, "high"]"#,
        files: &[],
        end: End::Error,
        expect: &[
            "scene.json:line 12",
            "sensors[0].position[2]",
            "invalid type",
        ],
    },
    Case {
        name: "sensor oversample negative",
        from: r#""width": 8, "#,
        to: r#""width": 8, "oversample": -2, "#,
        files: &[],
        end: End::Error,
        expect: &[
            "scene.json:line 11",
            "sensors[0].oversample",
            "invalid value",
            "usize",
        ],
    },
    Case {
        name: "band response of the wrong type",
        from: r#""response": [8.0, 12.0]"#,
        to: r#""response": true"#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 13", "sensors[0].bands[0].response"],
    },
    Case {
        name: "sensor up not a triple",
        from: r#""up": [0, 0, 1]"#,
        to: r#""up": [0, 1]"#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 12", "sensors[0].up", "3"],
    },
    Case {
        name: "sensor without height",
        from: r#""height": 8, "#,
        to: "",
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 11", "sensors[0]", "missing field `height`"],
    },
    Case {
        name: "sensor names used twice",
        from: r#"     "bands": [{"name": "LWIR", "response": [8.0, 12.0]}]}"#,
        to: r#"     "bands": [{"name": "LWIR", "response": [8.0, 12.0]}]},
    {"type": "frame", "name": "cam", "width": 8, "height": 8, "pixel_pitch_m": 1.5e-05,
     "focal_length_m": 0.025, "position": [0, -60, 40], "look_at": [0, 0, 0], "up": [0, 0, 1],
     "bands": [{"name": "LWIR", "response": [8.0, 12.0]}]}"#,
        files: &[],
        end: End::Error,
        expect: &["sensors[1].name", "used twice"],
    },
    Case {
        name: "no sensors",
        from: sensors!(),
        to: r#""sensors": []"#,
        files: &[],
        end: End::Error,
        expect: &["scene.json", "no sensors"],
    },
    Case {
        name: "band given in nanometres",
        from: "[8.0, 12.0]",
        to: "[8000, 12000]",
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 13", "sensors[0].bands", "nanometres"],
    },
    Case {
        name: "band inverted",
        from: "[8.0, 12.0]",
        to: "[12.0, 8.0]",
        files: &[],
        end: End::Error,
        expect: &["scene.json", "sensors[0]", "LWIR"],
    },
    Case {
        name: "response file missing",
        from: r#""response": [8.0, 12.0]"#,
        to: r#""response": "resp.csv""#,
        files: &[],
        end: End::Error,
        expect: &["resp.csv"],
    },
    Case {
        name: "response file garbage",
        from: r#""response": [8.0, 12.0]"#,
        to: r#""response": "resp.csv""#,
        files: &[("resp.csv", "wavelength_um,response\n8,1\nnine,1\n")],
        end: End::Error,
        expect: &["resp.csv", "line 3"],
    },
    Case {
        name: "image too large for memory",
        from: r#""width": 8, "height": 8"#,
        to: r#""width": 200000, "height": 200000"#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 11", "sensors[0].width", "GiB"],
    },
    Case {
        name: "camera sees nothing",
        from: r#""look_at": [0, 0, 0]"#,
        to: r#""look_at": [0, -120, 80]"#,
        files: &[],
        end: End::Warning,
        expect: &["sensor `cam` sees no scene geometry"],
    },
    Case {
        name: "camera inside an object",
        from: r#""position": [0, -60, 40], "look_at": [0, 0, 0]"#,
        to: r#""position": [0, 1, 2], "look_at": [0, -60, 2]"#,
        files: &[],
        end: End::Warning,
        expect: &[
            "sensor `cam` sees only the backs of faces",
            "inside object `block`",
        ],
    },
    // ---- render section
    Case {
        name: "render key misspelt",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "render": {"max_bounce": 1},"#,
        files: &[],
        end: End::Error,
        expect: &[
            "scene.json:line 4",
            "render.max_bounce",
            "did you mean `max_bounces`?",
        ],
    },
    Case {
        name: "render max_bounces too large",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "render": {"max_bounces": 20},"#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 4", "render.max_bounces", "0 to 8"],
    },
    Case {
        name: "render spectral step zero",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "render": {"spectral_step_um": 0},"#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 4", "render.spectral_step_um", "(0, 1]"],
    },
    Case {
        name: "render facet_samples zero",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "render": {"facet_samples": 0},"#,
        files: &[],
        end: End::Error,
        expect: &["render.facet_samples", "1 to 16"],
    },
    Case {
        name: "render sky sampling of an unknown kind",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "render": {"sky_sampling": "random"},"#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 4", "render", "random"],
    },
    Case {
        name: "render negative sky temperature",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "render": {"sky_temperature_k": -5},"#,
        files: &[],
        end: End::Error,
        expect: &["render.sky_temperature_k", "(0, 400) K"],
    },
    Case {
        name: "render not an object",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "render": 3,"#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 4: column 41", "expected a map"],
    },
    // ---- atmosphere section
    Case {
        name: "atmosphere profile misspelt",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "atmosphere": "midlatitude_sumer","#,
        files: &[],
        end: End::Error,
        expect: &[
            "scene.json:line 4",
            "atmosphere",
            "did you mean `mid-latitude-summer`?",
        ],
    },
    Case {
        name: "atmosphere unknown model",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "atmosphere": {"model": "modtran"},"#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 4", "atmosphere", "modtran"],
    },
    Case {
        name: "atmosphere key misspelt",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "atmosphere": {"model": "builtin", "co2": 400},"#,
        files: &[],
        end: End::Error,
        expect: &["atmosphere.co2", "did you mean `co2_ppmv`?"],
    },
    Case {
        name: "atmosphere profile unknown",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "atmosphere": {"model": "standard", "profile": "arctic"},"#,
        files: &[],
        end: End::Error,
        expect: &[
            "atmosphere",
            "unknown profile `arctic`",
            "sub-arctic-summer",
        ],
    },
    Case {
        name: "atmosphere aerosol unknown",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "atmosphere": {"model": "standard", "aerosol": "desert"},"#,
        files: &[],
        end: End::Error,
        expect: &[
            "scene.json:line 4",
            "atmosphere",
            "unknown aerosol `desert`",
            "none, rural, urban, maritime",
        ],
    },
    Case {
        name: "atmosphere visibility not positive",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "atmosphere": {"model": "builtin", "aerosol": "urban", "visibility_km": 0},"#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 4", "atmosphere", "visibility_km", "> 0 km"],
    },
    Case {
        name: "atmosphere visibility without aerosol",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "atmosphere": {"model": "standard", "aerosol": "none", "visibility_km": 10},"#,
        files: &[],
        end: End::Error,
        expect: &["atmosphere", "visibility_km", "needs an aerosol"],
    },
    Case {
        name: "atmosphere tape7 index missing",
        from: r#""materials": ["mats.json"],"#,
        to: r#""materials": ["mats.json"], "atmosphere": {"model": "tape7", "index": "t7/index.json"},"#,
        files: &[],
        end: End::Error,
        expect: &["index.json"],
    },
    // ---- site, time and weather
    Case {
        name: "site key misspelt",
        from: r#""latitude_deg": 43.16"#,
        to: r#""latitud": 43.16"#,
        files: &[],
        end: End::Error,
        expect: &[
            "scene.json:line 2",
            "latitud",
            "did you mean `latitude_deg`?",
        ],
    },
    Case {
        name: "longitude out of range",
        from: r#""longitude_deg": -77.61"#,
        to: r#""longitude_deg": -277.61"#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 2", "longitude", "-277.61"],
    },
    Case {
        name: "site in radians",
        from: r#""latitude_deg": 43.16, "longitude_deg": -77.61"#,
        to: r#""latitude_deg": 0.7533, "longitude_deg": -1.3545"#,
        files: &[],
        end: End::Warning,
        expect: &["scene.json:line 2", "look like radians"],
    },
    Case {
        name: "utc_offset_hours disagrees with the time",
        from: r#""utc_offset_hours": -4"#,
        to: r#""utc_offset_hours": -5"#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 2", "site.utc_offset_hours", "UTC-04:00"],
    },
    Case {
        name: "time without an offset",
        from: r#""time": "2025-06-21T14:00:00-04:00""#,
        to: r#""time": "2025-06-21T14:00:00""#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 3", "time"],
    },
    Case {
        name: "image time after the weather",
        from: r#""time": "2025-06-21T14:00:00-04:00""#,
        to: r#""time": "2025-06-23T14:00:00-04:00""#,
        files: &[],
        end: End::Error,
        expect: &["scene.json", "weather", "not the image time"],
    },
    Case {
        name: "spin-up not covered by the weather",
        from: r#""time": "2025-06-21T14:00:00-04:00""#,
        to: r#""time": "2025-06-20T10:00:00-04:00""#,
        files: &[],
        end: End::Error,
        expect: &["24 h window", "2025-06-20T00:00:00-04:00"],
    },
    Case {
        name: "no weather",
        from: r#""weather": {"file": "w.csv"},"#,
        to: "",
        files: &[],
        end: End::Error,
        expect: &["scene.json", "weather"],
    },
    Case {
        name: "weather file missing",
        from: r#""file": "w.csv""#,
        to: r#""file": "nowhere.csv""#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 5", "nowhere.csv"],
    },
    Case {
        name: "weather gap in the spin-up",
        from: "",
        to: "",
        files: &[("w.csv", "GAP")],
        end: End::Warning,
        expect: &["no weather records from", "interpolated"],
    },
    // ---- objects and materials
    Case {
        name: "object key misspelt",
        from: r#""material": "slab"},
    {"name": "block""#,
        to: r#""materal": "slab"},
    {"name": "block""#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 7", "materal", "did you mean `material`?"],
    },
    Case {
        name: "material name misspelt",
        from: r#""size": [4, 4, 4]}}], "material": "slab""#,
        to: r#""size": [4, 4, 4]}}], "material": "slabb""#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 8", "objects[1].material", "slabb", "slab"],
    },
    Case {
        name: "box size negative",
        from: r#""size": [4, 4, 4]"#,
        to: r#""size": [4, -4, 4]"#,
        files: &[],
        end: End::Error,
        expect: &["scene.json:line 8", "objects[1]", "size"],
    },
];

/// Write the case's files into a fresh folder; the scene file's path.
fn setup(dir: &std::path::Path, case: &Case) -> std::path::PathBuf {
    assert!(
        SCENE.contains(case.from),
        "{}: `{}` is not in the baseline",
        case.name,
        case.from
    );
    let scene = if case.from.is_empty() {
        SCENE.to_string()
    } else {
        SCENE.replacen(case.from, case.to, 1)
    };
    std::fs::write(dir.join("scene.json"), scene).unwrap();
    std::fs::write(dir.join("mats.json"), MATS).unwrap();
    std::fs::write(dir.join("w.csv"), weather(0..0)).unwrap();
    for (name, text) in case.files {
        let text = match *text {
            "GAP" => weather(20..28),
            t => t.to_string(),
        };
        std::fs::write(dir.join(name), text).unwrap();
    }
    dir.join("scene.json")
}

/// Run `irsig ARGS`; (exit code, stderr), or a problem.
fn run(dir: &std::path::Path, args: &[&str]) -> Result<(i32, String), String> {
    let out = Command::new(irsig_bin())
        .args(args)
        .current_dir(dir)
        .env("RUST_BACKTRACE", "0")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    if stderr.contains("panicked") {
        return Err(format!("panicked: {stderr}"));
    }
    let code = out
        .status
        .code()
        .ok_or_else(|| format!("killed by a signal ({:?})", out.status))?;
    Ok((code, stderr))
}

/// Problems with one case, checked for both commands.
fn check(case: &Case) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    setup(dir.path(), case);
    let mut problems = Vec::new();
    for args in [
        &["scene", "check", "scene.json"][..],
        &["render", "scene.json", "-o", "out", "--quiet"][..],
    ] {
        let what = args[..2].join(" ");
        let (code, stderr) = match run(dir.path(), args) {
            Ok(r) => r,
            Err(e) => {
                problems.push(format!("{}: {what}: {e}", case.name));
                continue;
            }
        };
        let ended = match (code, stderr.contains("warning: ")) {
            (0, true) => Some(End::Warning),
            (0, false) => None,
            _ => Some(End::Error),
        };
        if ended != Some(case.end) {
            problems.push(format!(
                "{}: {what}: expected {:?}, exit {code}: {}",
                case.name,
                case.end,
                stderr.trim()
            ));
        }
        for e in case.expect {
            if !stderr.contains(e) {
                problems.push(format!(
                    "{}: {what}: message lacks `{e}`: {}",
                    case.name,
                    stderr.trim()
                ));
            }
        }
    }
    problems
}

/// The baseline itself renders and checks cleanly, with no warning.
#[test]
fn baseline_scene_checks_and_renders_without_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let case = Case {
        name: "baseline",
        from: "",
        to: "",
        files: &[],
        end: End::Warning,
        expect: &[],
    };
    setup(dir.path(), &case);
    for args in [
        &["scene", "check", "scene.json"][..],
        &["render", "scene.json", "-o", "out", "--quiet"][..],
    ] {
        let (code, stderr) = run(dir.path(), args).unwrap();
        assert!(code == 0 && stderr.trim().is_empty(), "{args:?}: {stderr}");
    }
    assert!(dir.path().join("out/cam.exr").exists());
}

#[test]
fn scene_check_agrees_with_render_on_every_case() {
    assert!(
        CASES.len() + crate::cli::CASE_COUNT >= 80,
        "issue 21 asks for at least 80 malformed-input cases in all"
    );
    let problems: Vec<String> = CASES.iter().flat_map(check).collect();
    assert!(
        problems.is_empty(),
        "{} problem(s) in {} cases:\n{}",
        problems.len(),
        CASES.len(),
        problems.join("\n")
    );
}
