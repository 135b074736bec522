//! Tests: cli. The malformed-input table (issue 8): each case feeds the real
//! `irsig` binary a broken input and checks that it fails cleanly — exit
//! status ≠ 0 and not killed by a signal, no panic — and that the message
//! names the file (or option) and the line/field, and says what was
//! expected.

use std::process::Command;

use crate::util::irsig_bin;

/// One malformed input: files to write into a fresh directory, the
/// arguments (`@` is replaced by that directory), and substrings the error
/// message must contain (all of them).
struct Case {
    name: &'static str,
    files: &'static [(&'static str, &'static [u8])],
    args: &'static [&'static str],
    expect: &'static [&'static str],
}

macro_rules! scene {
    ($($t:tt)*) => { concat!(r#"{
  "site": {"latitude_deg": 43.16, "longitude_deg": -77.61, "altitude_m": 160, "utc_offset_hours": -4},
  "time": "2025-06-21T14:00:00-04:00",
  "materials": ["mats.json"],
"#, $($t)*).as_bytes() };
}

/// A valid one-material database.
const MATS: &[u8] = br#"{"materials": [
  {"name": "slab", "id": 7, "density_kg_m3": 2300, "specific_heat_j_kg_k": 880,
   "conductivity_w_m_k": 1.4, "thickness_m": 0.2, "solar_absorptivity": 0.7,
   "thermal_emissivity": 0.92, "exposed_area": 0.0}
]}
"#;

macro_rules! objects_box {
    () => {
        r#"  "objects": [{"name": "b", "shapes": [{"box": {"size": [1, 1, 1]}}], "material": "slab"}]
}"#
    };
}

macro_rules! weather_csv {
    ($($t:tt)*) => { concat!("time,air_temperature_k,dew_point_k,pressure_pa,wind_speed_m_s,global_horizontal_w_m2\n", $($t)*).as_bytes() };
}

const GOOD_WEATHER: &[u8] = weather_csv!(
    "2025-06-21T00:00:00-04:00,290,280,101325,2,0\n",
    "2025-06-21T01:00:00-04:00,289,280,101325,2,0\n",
    "2025-06-21T02:00:00-04:00,288,280,101325,2,0\n"
);

/// How many cases the table has (counted with `tests/check_parity.rs`'s).
pub const CASE_COUNT: usize = CASES.len();

const CASES: &[Case] = &[
    // ---- scene JSON
    Case {
        name: "scene: truncated JSON",
        files: &[("scene.json", br#"{"site": {"latitude_deg": 43.1"#)],
        args: &["scene", "check", "@/scene.json"],
        expect: &["scene.json", "line 1", "EOF"],
    },
    Case {
        name: "scene: binary garbage",
        files: &[("scene.json", b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\xff\xfe")],
        args: &["scene", "check", "@/scene.json"],
        expect: &["scene.json", "UTF-8"],
    },
    Case {
        name: "scene: latitude 95",
        files: &[
            ("mats.json", MATS),
            (
                "scene.json",
                br#"{"site": {"latitude_deg": 95, "longitude_deg": 0, "altitude_m": 0, "utc_offset_hours": 0},
 "time": "2025-06-21T14:00:00Z", "materials": ["mats.json"],
 "objects": [{"name": "b", "shapes": [{"box": {"size": [1, 1, 1]}}], "material": "slab"}]}"#,
            ),
        ],
        args: &["scene", "check", "@/scene.json"],
        expect: &["scene.json", "latitude", "95", "90"],
    },
    Case {
        name: "scene: unknown material",
        files: &[
            ("mats.json", MATS),
            (
                "scene.json",
                scene!(r#"  "objects": [{"name": "b", "shapes": [{"box": {"size": [1, 1, 1]}}], "material": "slabb"}]}"#),
            ),
        ],
        args: &["scene", "check", "@/scene.json"],
        expect: &["scene.json", "line 5", "objects[0].material", "slabb", "slab"],
    },
    Case {
        name: "scene: missing geometry file",
        files: &[
            ("mats.json", MATS),
            (
                "scene.json",
                scene!(r#"  "objects": [{"name": "b", "shapes": [{"obj": "geo/missing.obj"}], "material": "slab"}]}"#),
            ),
        ],
        args: &["scene", "check", "@/scene.json"],
        expect: &["missing.obj", "objects[0].shapes[0]"],
    },
    Case {
        name: "scene: negative part thickness",
        files: &[
            ("mats.json", MATS),
            (
                "scene.json",
                scene!(r#"  "objects": [{"name": "b", "shapes": [{"box": {"size": [1, 1, 1]}}], "material": "slab",
    "parts": [{"name": "top", "material": "slab", "thickness_m": -0.1}]}]}"#),
            ),
        ],
        args: &["scene", "check", "@/scene.json"],
        expect: &["scene.json", "thickness_m", "-0.1", "> 0"],
    },
    Case {
        name: "scene: unknown field",
        files: &[
            ("mats.json", MATS),
            ("scene.json", scene!(r#"  "objcts": []}"#)),
        ],
        args: &["scene", "check", "@/scene.json"],
        expect: &["scene.json", "line 5", "objcts", "expected one of"],
    },
    Case {
        name: "scene: missing material database",
        files: &[("scene.json", scene!(r#"  "objects": []}"#))],
        args: &["scene", "check", "@/scene.json"],
        expect: &["scene.json", "line 4", "materials[0]", "mats.json", "not found"],
    },
    Case {
        name: "scene: bad OBJ index",
        files: &[
            ("mats.json", MATS),
            ("g.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"),
            (
                "scene.json",
                scene!(r#"  "objects": [{"name": "b", "shapes": [{"obj": "g.obj"}], "material": "slab"}]}"#),
            ),
        ],
        args: &["scene", "check", "@/scene.json"],
        expect: &["g.obj", "line 4", "index 9", "have 3"],
    },
    Case {
        name: "scene: OBJ vertex not a number",
        files: &[
            ("mats.json", MATS),
            ("g.obj", b"v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n"),
            (
                "scene.json",
                scene!(r#"  "objects": [{"name": "b", "shapes": [{"obj": "g.obj"}], "material": "slab"}]}"#),
            ),
        ],
        args: &["scene", "check", "@/scene.json"],
        expect: &["g.obj", "line 2", "zero"],
    },
    Case {
        name: "scene: box with NaN size",
        files: &[
            ("mats.json", MATS),
            (
                "scene.json",
                scene!(r#"  "objects": [{"name": "b", "shapes": [{"box": {"size": [1, NaN, 1]}}], "material": "slab"}]}"#),
            ),
        ],
        args: &["scene", "check", "@/scene.json"],
        expect: &["scene.json", "line 5"],
    },
    Case {
        name: "scene: time outside the weather history",
        files: &[
            ("mats.json", MATS),
            ("w.csv", GOOD_WEATHER),
            (
                "scene.json",
                scene!(r#"  "weather": {"file": "w.csv"},
"#, objects_box!()),
            ),
        ],
        args: &["scene", "check", "@/scene.json"],
        expect: &["scene.json", "weather.file", "2025-06-21T14:00:00-04:00", "2025-06-21T02:00:00-04:00"],
    },
    // ---- material databases
    Case {
        name: "materials: emissivity > 1",
        files: &[
            (
                "mats.json",
                br#"{"materials": [
  {"name": "slab", "id": 7, "density_kg_m3": 2300, "specific_heat_j_kg_k": 880,
   "conductivity_w_m_k": 1.4, "thickness_m": 0.2, "solar_absorptivity": 0.7,
   "thermal_emissivity": 1.2, "exposed_area": 0.0}]}"#,
            ),
            ("scene.json", scene!(objects_box!())),
        ],
        args: &["scene", "check", "@/scene.json"],
        expect: &["mats.json", "line 4", "thermal_emissivity", "1.2", "0..=1"],
    },
    Case {
        name: "materials: negative thickness",
        files: &[
            (
                "mats.json",
                br#"{"materials": [
  {"name": "slab", "id": 7, "density_kg_m3": 2300, "specific_heat_j_kg_k": 880,
   "conductivity_w_m_k": 1.4, "thickness_m": -0.2, "solar_absorptivity": 0.7,
   "thermal_emissivity": 0.9, "exposed_area": 0.0}]}"#,
            ),
            ("scene.json", scene!(objects_box!())),
        ],
        args: &["scene", "check", "@/scene.json"],
        expect: &["mats.json", "line 3", "thickness_m", "-0.2", "> 0"],
    },
    Case {
        name: "materials: number where a string is expected",
        files: &[
            ("mats.json", br#"{"materials": [{"name": 12}]}"#),
            ("scene.json", scene!(objects_box!())),
        ],
        args: &["scene", "check", "@/scene.json"],
        expect: &["mats.json", "line 1", "expected a string"],
    },
    Case {
        name: "thermal: DIRSIG .mat with an unclosed block",
        files: &[
            ("w.csv", GOOD_WEATHER),
            ("m.mat", b"MATERIAL_ENTRY {\n    ID = 1\n    NAME = Grass\n"),
        ],
        args: &[
            "thermal", "--material", "@/m.mat", "--weather", "@/w.csv", "--site", "43,-77,0",
            "--time", "2025-06-21T02:00:00-04:00",
        ],
        expect: &["m.mat", "line", "}"],
    },
    Case {
        name: "thermal: DIRSIG .ems with a bad count",
        files: &[
            ("w.csv", GOOD_WEATHER),
            ("e.ems", b"three\n1.0\n"),
            (
                "m.mat",
                b"MATERIAL_ENTRY {\n  ID = 1\n  NAME = Grass\n  TEMP_SOLVER_NAME = Therm\n  TEMP_SOLVER {\n    SPECIFIC_HEAT = 0.4\n    MASS_DENSITY = 1.6\n    THERMAL_CONDUCTIVITY = 1.2\n    SOLAR_ABSORPTION = 0.7\n    THERMAL_EMISSIVITY = 0.9\n    EXPOSED_AREA = 0\n    THICKNESS = 5\n  }\n  SURFACE_PROPERTIES {\n    EMISSIVITY_PROP_NAME = ClassicEmissivity\n    EMISSIVITY_PROP {\n      FILENAME = e.ems\n    }\n  }\n}\n",
            ),
        ],
        args: &[
            "thermal", "--material", "@/m.mat", "--weather", "@/w.csv", "--site", "43,-77,0",
            "--time", "2025-06-21T02:00:00-04:00",
        ],
        expect: &["e.ems", "line 1", "three"],
    },
    // ---- weather
    Case {
        name: "weather: empty file",
        files: &[("w.csv", b"")],
        args: &["weather", "show", "@/w.csv"],
        expect: &["w.csv", "expected"],
    },
    Case {
        name: "weather: misspelt column",
        files: &[(
            "w.csv",
            b"time,air_temprature_k,dew_point_k\n2025-06-21T00:00:00-04:00,290,280\n",
        )],
        args: &["weather", "show", "@/w.csv"],
        expect: &["w.csv", "line 1", "air_temprature_k", "did you mean `air_temperature_k`?"],
    },
    Case {
        name: "weather: NaN in a row",
        files: &[(
            "w.csv",
            weather_csv!(
                "2025-06-21T00:00:00-04:00,290,280,101325,2,0\n",
                "2025-06-21T01:00:00-04:00,NaN,280,101325,2,0\n"
            ),
        )],
        args: &["weather", "show", "@/w.csv"],
        expect: &["w.csv", "line 3", "air_temperature_k", "NaN"],
    },
    Case {
        name: "weather: times out of order",
        files: &[(
            "w.csv",
            weather_csv!(
                "2025-06-21T01:00:00-04:00,290,280,101325,2,0\n",
                "2025-06-21T00:00:00-04:00,290,280,101325,2,0\n"
            ),
        )],
        args: &["weather", "show", "@/w.csv"],
        expect: &["w.csv", "line 3", "time", "increasing"],
    },
    Case {
        name: "weather: short row",
        files: &[(
            "w.csv",
            weather_csv!(
                "2025-06-21T00:00:00-04:00,290,280,101325,2,0\n",
                "2025-06-21T01:00:00-04:00,290,280\n"
            ),
        )],
        args: &["weather", "show", "@/w.csv"],
        expect: &["w.csv", "line 3", "6"],
    },
    Case {
        name: "weather: binary garbage",
        files: &[("w.bin", b"\x00\x01\x02\xff\xfe garbage \x00")],
        args: &["weather", "show", "@/w.bin"],
        expect: &["w.bin", "UTF-8"],
    },
    Case {
        name: "weather: unrecognised format",
        files: &[("w.txt", b"hello world\nthis is not weather\n")],
        args: &["weather", "show", "@/w.txt"],
        expect: &["w.txt", "line 1", "expected irsig CSV"],
    },
    Case {
        name: "weather: .wth without a start date",
        files: &[(
            "w.wth",
            b"2 1.0\n0.00 15.00 1000.00  0.68 10.00   5.00     0.00     0.00 1.00  0  0   0.00  0.00\n1.00 15.00 1000.00  0.68 10.00   5.00     0.00     0.00 1.00  0  0   0.00  0.00\n",
        )],
        args: &["weather", "show", "@/w.wth"],
        expect: &["w.wth", "--start"],
    },
    Case {
        name: "weather: .wth row with a letter",
        files: &[(
            "w.wth",
            b"2 1.0\n0.00 15.00 1000.00  0.68 10.00   5.00     0.00     0.00 1.00  0  0   0.00  0.00\n1.00 15.00 1000.00  0.6x 10.00   5.00     0.00     0.00 1.00  0  0   0.00  0.00\n",
        )],
        args: &["weather", "show", "@/w.wth", "--start", "2025-06-21T00:00:00-04:00"],
        expect: &["w.wth", "line 3"],
    },
    Case {
        name: "weather: truncated EPW",
        files: &[("w.epw", b"LOCATION,Rochester,NY,USA,TMY3,725290,43.12,-77.67,-5.0,169.0\nDESIGN CONDITIONS,0\n")],
        args: &["weather", "show", "@/w.epw"],
        expect: &["w.epw", "line"],
    },
    // ---- thermal
    Case {
        name: "thermal: unknown material",
        files: &[("w.csv", GOOD_WEATHER), ("mats.json", MATS)],
        args: &[
            "thermal", "--material", "slabb", "--materials", "@/mats.json", "--weather",
            "@/w.csv", "--site", "43,-77,0", "--time", "2025-06-21T02:00:00-04:00",
        ],
        expect: &["slabb", "mats.json", "did you mean `slab`?"],
    },
    Case {
        name: "thermal: time outside the weather history",
        files: &[("w.csv", GOOD_WEATHER), ("mats.json", MATS)],
        args: &[
            "thermal", "--material", "slab", "--materials", "@/mats.json", "--weather",
            "@/w.csv", "--site", "43,-77,0", "--time", "2025-06-22T12:00:00-04:00",
        ],
        expect: &["w.csv", "--time", "2025-06-22T12:00:00-04:00"],
    },
    Case {
        name: "thermal: site latitude 95",
        files: &[("w.csv", GOOD_WEATHER), ("mats.json", MATS)],
        args: &[
            "thermal", "--material", "slab", "--materials", "@/mats.json", "--weather",
            "@/w.csv", "--site", "95,-77,0", "--time", "2025-06-21T02:00:00-04:00",
        ],
        expect: &["latitude", "95", "90"],
    },
    Case {
        name: "thermal: unknown --back",
        files: &[("w.csv", GOOD_WEATHER), ("mats.json", MATS)],
        args: &[
            "thermal", "--material", "slab", "--materials", "@/mats.json", "--weather",
            "@/w.csv", "--site", "43,-77,0", "--time", "2025-06-21T02:00:00-04:00", "--back",
            "floating",
        ],
        expect: &["--back", "floating", "insulated"],
    },
    // The library names the field (tilt_deg, shape_factor); the CLI the flag.
    Case {
        name: "thermal: tilt 200",
        files: &[("w.csv", GOOD_WEATHER), ("mats.json", MATS)],
        args: &[
            "thermal", "--material", "slab", "--materials", "@/mats.json", "--weather",
            "@/w.csv", "--site", "43,-77,0", "--time", "2025-06-21T02:00:00-04:00", "--tilt",
            "200",
        ],
        expect: &["--tilt", "tilt_deg", "200", "0..=180"],
    },
    Case {
        name: "thermal: shape factor 2",
        files: &[("w.csv", GOOD_WEATHER), ("mats.json", MATS)],
        args: &[
            "thermal", "--material", "slab", "--materials", "@/mats.json", "--weather",
            "@/w.csv", "--site", "43,-77,0", "--time", "2025-06-21T02:00:00-04:00",
            "--shape-factor", "2",
        ],
        expect: &["--shape-factor", "shape_factor", "0..=1"],
    },
    Case {
        name: "thermal: back shape factor 1.5",
        files: &[("w.csv", GOOD_WEATHER), ("mats.json", MATS)],
        args: &[
            "thermal", "--material", "slab", "--materials", "@/mats.json", "--weather",
            "@/w.csv", "--site", "43,-77,0", "--time", "2025-06-21T02:00:00-04:00",
            "--tilt", "90", "--back", "exposed", "--back-shape-factor", "1.5",
        ],
        expect: &["--back-shape-factor", "back_shape_factor", "1.5", "0..=1"],
    },
    Case {
        name: "thermal: ground albedo 1.5",
        files: &[("w.csv", GOOD_WEATHER), ("mats.json", MATS)],
        args: &[
            "thermal", "--material", "slab", "--materials", "@/mats.json", "--weather",
            "@/w.csv", "--site", "43,-77,0", "--time", "2025-06-21T02:00:00-04:00",
            "--tilt", "90", "--ground-albedo", "1.5",
        ],
        expect: &["--ground-albedo", "ground_albedo", "1.5", "0..=1"],
    },
    Case {
        name: "thermal: missing weather file",
        files: &[("mats.json", MATS)],
        args: &[
            "thermal", "--material", "slab", "--materials", "@/mats.json", "--weather",
            "@/nowhere.csv", "--site", "43,-77,0", "--time", "2025-06-21T02:00:00-04:00",
        ],
        expect: &["nowhere.csv", "No such file"],
    },
    // ---- sun
    Case {
        name: "sun: latitude 95",
        files: &[],
        args: &["sun", "--lat", "95", "--lon", "0", "--time", "2025-06-21T12:00:00Z"],
        expect: &["lat", "95", "90"],
    },
    Case {
        name: "sun: longitude 200",
        files: &[],
        args: &["sun", "--lat", "43", "--lon", "200", "--time", "2025-06-21T12:00:00Z"],
        expect: &["lon", "200", "180"],
    },
    Case {
        name: "sun: time without an offset",
        files: &[],
        args: &["sun", "--lat", "43", "--lon", "-77", "--time", "2025-06-21 12:00"],
        expect: &["--time", "RFC 3339"],
    },
    // ---- radiance and response CSV
    Case {
        name: "radiance: response wavelengths decreasing",
        files: &[("r.csv", b"wavelength_um,response\n8,0\n9,1\n8.5,1\n14,0\n")],
        args: &["radiance", "--temperature", "300", "--response", "@/r.csv"],
        expect: &["r.csv", "line 4", "wavelength_um", "increase"],
    },
    Case {
        name: "radiance: response value not a number",
        files: &[("r.csv", b"wavelength_um,response\n8,0\n9,one\n14,0\n")],
        args: &["radiance", "--temperature", "300", "--response", "@/r.csv"],
        expect: &["r.csv", "line 3", "one"],
    },
    Case {
        name: "radiance: negative response",
        files: &[("r.csv", b"8,0\n9,-1\n14,0\n")],
        args: &["radiance", "--temperature", "300", "--response", "@/r.csv"],
        expect: &["r.csv", "line 2", "-1"],
    },
    Case {
        name: "radiance: inverted band",
        files: &[],
        args: &["radiance", "--temperature", "300", "--band", "14-8"],
        expect: &["--band", "14-8"],
    },
    Case {
        name: "radiance: unknown CODATA year",
        files: &[],
        args: &["radiance", "--temperature", "300", "--codata", "1999"],
        expect: &["--codata", "1999", "2018"],
    },
    Case {
        name: "radiance: negative temperature",
        files: &[],
        args: &["radiance", "--temperature", "-5"],
        expect: &["--temperature", "-5"],
    },
    // ---- images
    Case {
        name: "info: binary garbage .exr",
        files: &[("i.exr", b"\x76\x2f\x31\x01\x02\x00\x00\x00garbage")],
        args: &["info", "@/i.exr"],
        expect: &["i.exr"],
    },
    Case {
        name: "info: ENVI header missing fields",
        files: &[("i.hdr", b"ENVI\nsamples = 4\n"), ("i.img", b"\0\0\0\0")],
        args: &["info", "@/i.hdr"],
        expect: &["i.hdr", "lines"],
    },
    Case {
        name: "info: unknown extension",
        files: &[("i.jpg", b"\xff\xd8\xff")],
        args: &["info", "@/i.jpg"],
        expect: &["i.jpg", ".exr"],
    },
    Case {
        name: "compare: truth image is garbage",
        files: &[("a.exr", b"not an exr"), ("b.exr", b"not an exr")],
        args: &["compare", "@/a.exr", "@/b.exr"],
        expect: &["a.exr"],
    },
    // ---- irsig atmosphere (issue 17)
    Case {
        name: "atmosphere: unknown profile lists the valid ones",
        files: &[],
        args: &["atmosphere", "--profile", "arctic", "--band", "8-12"],
        expect: &["--profile", "arctic", "tropical", "mid-latitude-summer", "us-standard"],
    },
    Case {
        name: "atmosphere: zenith outside 0-180",
        files: &[],
        args: &["atmosphere", "--profile", "tropical", "--band", "8-12", "--zenith", "190"],
        expect: &["--zenith", "0–180"],
    },
    Case {
        name: "atmosphere: looking up below the horizon",
        files: &[],
        args: &["atmosphere", "--profile", "tropical", "--band", "8-12", "--look", "up", "--zenith", "120"],
        expect: &["--zenith", "below 90"],
    },
    Case {
        name: "atmosphere: negative altitude",
        files: &[],
        args: &["atmosphere", "--profile", "tropical", "--band", "8-12", "--target-altitude", "-3"],
        expect: &["--target-altitude", "≥ 0"],
    },
    Case {
        name: "atmosphere: negative range",
        files: &[],
        args: &["atmosphere", "--profile", "tropical", "--band", "8-12", "--range", "-10"],
        expect: &["--range", "≥ 0"],
    },
    Case {
        name: "atmosphere: unknown aerosol lists the valid ones",
        files: &[],
        args: &["atmosphere", "--profile", "tropical", "--band", "8-12", "--aerosol", "fog"],
        expect: &["--aerosol", "fog", "rural", "urban", "maritime", "none"],
    },
    Case {
        name: "atmosphere: visibility not above 0",
        files: &[],
        args: &["atmosphere", "--profile", "tropical", "--band", "8-12", "--visibility-km", "-2"],
        expect: &["--visibility-km", "> 0 km", "-2"],
    },
    Case {
        name: "atmosphere: visibility without an aerosol",
        files: &[],
        args: &["atmosphere", "--profile", "tropical", "--band", "8-12", "--aerosol", "none", "--visibility-km", "5"],
        expect: &["--visibility-km", "--aerosol none"],
    },
    Case {
        name: "atmosphere: sun zenith out of range",
        files: &[],
        args: &["atmosphere", "--profile", "tropical", "--band", "3-5", "--sun-zenith", "200", "--sun-azimuth", "0"],
        expect: &["--sun-zenith", "0–180°", "200"],
    },
    Case {
        name: "atmosphere: sun azimuth out of range",
        files: &[],
        args: &["atmosphere", "--profile", "tropical", "--band", "3-5", "--sun-zenith", "30", "--sun-azimuth", "400"],
        expect: &["--sun-azimuth", "0–360°", "400"],
    },
    Case {
        name: "atmosphere: band outside the model",
        files: &[],
        args: &["atmosphere", "--profile", "tropical", "--band", "1-2"],
        expect: &["--band", "3–16 µm"],
    },
    // ---- command line values
    Case {
        name: "cli: unknown subcommand value",
        files: &[],
        args: &["scene", "frobnicate"],
        expect: &["frobnicate"],
    },
    Case {
        name: "cli: render --sky-sampling of an unknown kind",
        files: &[],
        args: &["render", "@/scene.json", "-o", "@/out", "--sky-sampling", "hexagons"],
        expect: &["--sky-sampling", "hexagons", "stratified:N"],
    },
    Case {
        name: "cli: render --facet-samples 0",
        files: &[],
        args: &["render", "@/scene.json", "-o", "@/out", "--facet-samples", "0"],
        expect: &["--facet-samples", "1 to 16"],
    },
    Case {
        name: "cli: --threads 0",
        files: &[],
        args: &["--threads", "0", "sun", "--lat", "43", "--lon", "-77", "--time", "2025-06-21T12:00:00Z"],
        expect: &["--threads", "1"],
    },
];

/// Run one case; returns a description of what went wrong, if anything.
fn run_case(case: &Case) -> Option<String> {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in case.files {
        let p = dir.path().join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, bytes).unwrap();
    }
    let d = dir.path().to_str().unwrap();
    let args: Vec<String> = case.args.iter().map(|a| a.replace('@', d)).collect();
    let out = Command::new(irsig_bin())
        .args(&args)
        .current_dir(dir.path())
        .env("RUST_BACKTRACE", "0")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let mut problems = Vec::new();
    match out.status.code() {
        None => problems.push(format!("killed by a signal ({:?})", out.status)),
        Some(0) => problems.push("exit status 0".to_string()),
        Some(_) => {}
    }
    if stderr.contains("panicked") {
        problems.push("panicked".to_string());
    }
    for e in case.expect {
        if !stderr.contains(e) {
            problems.push(format!("message lacks `{e}`"));
        }
    }
    if problems.is_empty() {
        None
    } else {
        Some(format!(
            "{}: {}\n    irsig {}\n    stderr: {}",
            case.name,
            problems.join(", "),
            case.args.join(" "),
            stderr.trim().replace('\n', "\n            ")
        ))
    }
}

#[test]
fn malformed_input_table() {
    assert!(CASES.len() >= 30, "the table needs at least 30 cases");
    let failures: Vec<String> = CASES.iter().filter_map(run_case).collect();
    assert!(
        failures.is_empty(),
        "{} of {} malformed-input cases failed:\n{}",
        failures.len(),
        CASES.len(),
        failures.join("\n")
    );
}

/// The table's fixtures are themselves valid where meant to be: the good
/// weather file and material database pass `irsig thermal`, so each case
/// fails for its own defect.
#[test]
fn malformed_input_table_baseline_is_valid() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("w.csv"), GOOD_WEATHER).unwrap();
    std::fs::write(dir.path().join("mats.json"), MATS).unwrap();
    let out = Command::new(irsig_bin())
        .current_dir(dir.path())
        .args([
            "thermal",
            "--material",
            "slab",
            "--materials",
            "mats.json",
            "--weather",
            "w.csv",
            "--site",
            "43,-77,0",
            "--time",
            "2025-06-21T02:00:00-04:00",
            "--csv",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s = String::from_utf8_lossy(&out.stdout);
    assert_eq!(s.lines().count(), 4, "{s}");
    // And the scene skeleton (no sensors, no weather: what loading needs)
    // passes `irsig scene check --load-only`.
    std::fs::write(dir.path().join("scene.json"), scene!(objects_box!())).unwrap();
    let out = Command::new(irsig_bin())
        .current_dir(dir.path())
        .args(["scene", "check", "--load-only", "scene.json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A closed stdout (`irsig … | head`) ends a command quietly with success:
/// no panic, no error message (ripgrep's convention). The reading end of the
/// pipe is closed before the command starts, so its first write fails.
#[test]
fn closed_stdout_is_not_an_error() {
    for args in [
        &[
            "radiance",
            "--band",
            "8-14",
            "--temperature",
            "300",
            "--json",
        ][..],
        &["radiance", "--band", "8-14", "--temperature", "300"][..],
        &["weather", "show", "scenes/town/weather.csv"][..],
    ] {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let out = Command::new(irsig_bin())
            .args(args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .stdout(writer)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{args:?}: {:?} {stderr}", out.status);
        assert!(stderr.is_empty(), "{args:?}: {stderr}");
    }
}

/// Issue 17: `irsig atmosphere --json` prints exactly the transmittance and
/// the path radiance; looking up, the path radiance is the sky radiance.
#[test]
fn atmosphere_json_has_the_issue_keys() {
    let run = |args: &[&str]| -> serde_json::Value {
        let out = Command::new(irsig_bin()).args(args).output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let up = run(&[
        "atmosphere",
        "--profile",
        "mid-latitude-summer",
        "--band",
        "8-14",
        "--look",
        "up",
        "--zenith",
        "0",
        "--json",
    ]);
    let keys: Vec<&String> = up.as_object().unwrap().keys().collect();
    assert_eq!(keys, ["aerosol", "path_radiance_w_m2_sr", "transmittance"]);
    assert_eq!(
        up["aerosol"],
        serde_json::json!({"model": "rural", "visibility_km": 23.0})
    );
    let (tau, l) = (
        up["transmittance"].as_f64().unwrap(),
        up["path_radiance_w_m2_sr"].as_f64().unwrap(),
    );
    assert!(
        (0.3..0.8).contains(&tau) && (5.0..40.0).contains(&l),
        "{up}"
    );
    let down = run(&[
        "atmosphere",
        "--profile",
        "us-standard",
        "--band",
        "8-12",
        "--sensor-altitude",
        "1000",
        "--target-altitude",
        "0",
        "--zenith",
        "30",
        "--json",
    ]);
    let (td, ld) = (
        down["transmittance"].as_f64().unwrap(),
        down["path_radiance_w_m2_sr"].as_f64().unwrap(),
    );
    assert!(td > tau && td < 1.0 && ld > 0.0 && ld < l, "{down}");
}

/// Issue 17: `irsig atmosphere --aerosol` and `--visibility-km`. Down 1 km in 8–12 µm:
/// clear air (`--aerosol none`) transmits more and emits less than LOWTRAN's rural
/// aerosol at 23 km, which transmits more than at 5 km; the text and JSON name the
/// aerosol. With `--weather`, the record's visibility sets the aerosol's (5 km in the
/// file: the same path as `--visibility-km 5`), an explicit `--visibility-km` wins,
/// and a missing visibility (9999) keeps 23 km.
#[test]
fn atmosphere_aerosol_options_and_weather_visibility() {
    let run = |args: &[&str]| -> (serde_json::Value, String) {
        let out = Command::new(irsig_bin()).args(args).output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let s = String::from_utf8(out.stdout).unwrap();
        (serde_json::from_str(&s).unwrap_or_default(), s)
    };
    let base = [
        "atmosphere",
        "--profile",
        "mid-latitude-summer",
        "--band",
        "8-12",
    ];
    let json =
        |extra: &[&str]| -> serde_json::Value { run(&[&base[..], extra, &["--json"]].concat()).0 };
    let tau = |v: &serde_json::Value| v["transmittance"].as_f64().unwrap();
    let lu = |v: &serde_json::Value| v["path_radiance_w_m2_sr"].as_f64().unwrap();
    let clear = json(&["--aerosol", "none"]);
    let v23 = json(&[]);
    let v5 = json(&["--aerosol", "rural", "--visibility-km", "5"]);
    assert_eq!(clear["aerosol"], serde_json::Value::Null);
    assert_eq!(
        v5["aerosol"],
        serde_json::json!({"model": "rural", "visibility_km": 5.0})
    );
    assert!(
        tau(&clear) > tau(&v23) && tau(&v23) > tau(&v5),
        "{clear} {v23} {v5}"
    );
    assert!(tau(&clear) - tau(&v5) > 0.01, "{clear} {v5}");
    assert!(lu(&clear) < lu(&v5), "{clear} {v5}");
    let urban = json(&["--aerosol", "urban"]);
    assert_eq!(
        urban["aerosol"],
        serde_json::json!({"model": "urban", "visibility_km": 5.0})
    );
    let text = run(&[&base[..], &["--visibility-km", "5"]].concat()).1;
    assert!(
        text.contains("aerosol rural (LOWTRAN 7), visibility 5 km"),
        "{text}"
    );
    let text = run(&[&base[..], &["--aerosol", "none"]].concat()).1;
    assert!(text.contains("no aerosol (gases only)"), "{text}");

    let dir = tempfile::tempdir().unwrap();
    let weather = |name: &str, v: f64| -> String {
        let p = dir.path().join(name);
        std::fs::write(&p, crate::weather::epw_visibility_day(&[v; 24])).unwrap();
        p.to_str().unwrap().to_string()
    };
    let (hazy, missing) = (weather("hazy.epw", 5.0), weather("missing.epw", 9999.0));
    let w = |file: &str, extra: &[&str]| -> serde_json::Value {
        let args = [
            &[
                "atmosphere",
                "--weather",
                file,
                "--time",
                "1990-06-21T10:00:00-05:00",
            ][..],
            &["--band", "8-12", "--json"],
            extra,
        ]
        .concat();
        run(&args).0
    };
    let from_file = w(&hazy, &[]);
    assert_eq!(
        from_file["aerosol"],
        serde_json::json!({"model": "rural", "visibility_km": 5.0})
    );
    assert_eq!(from_file, w(&missing, &["--visibility-km", "5"]));
    let explicit = w(&hazy, &["--visibility-km", "40"]);
    assert_eq!(explicit["aerosol"]["visibility_km"], 40.0);
    assert!(tau(&explicit) > tau(&from_file), "{explicit} {from_file}");
    assert_eq!(w(&missing, &[])["aerosol"]["visibility_km"], 23.0);
}

/// Copy the folder `from` into `to` (recursively).
fn copy_dir(from: &std::path::Path, to: &std::path::Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let p = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &p);
        } else {
            std::fs::copy(e.path(), &p).unwrap();
        }
    }
}

/// Issue 20: `irsig import dirsig` through the binary. The hand-written DIRSIG
/// simulation in `tests/data/dirsig/` (a `.sim` naming a `.scene`, a `.glist` of two
/// OBJ files, a `.mat`, a `.tasks`, a `.platform` + `.ppd` and a `.atm` with a `.wth`)
/// is imported with `-o`; the written scene passes `irsig scene check` and renders
/// its camera. A `.glist` naming a missing OBJ file fails: exit ≠ 0, naming the
/// `.glist`, its line and the missing file, writing nothing.
#[test]
fn import_dirsig_cli_writes_a_scene_that_checks_and_renders() {
    let dir = tempfile::tempdir().unwrap();
    let set = dir.path().join("dirsig");
    copy_dir(&crate::util::repo_path("tests/data/dirsig"), &set);
    let irsig = |args: &[&str]| {
        let out = Command::new(irsig_bin())
            .args(args)
            .current_dir(dir.path())
            .env("RUST_BACKTRACE", "0")
            .output()
            .unwrap();
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        (out.status.code(), text)
    };
    let (code, text) = irsig(&["import", "dirsig", "dirsig/demo.sim", "-o", "out/demo.json"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(
        text.contains("2 object(s)")
            && text.contains("2 material(s)")
            && text.contains("1 sensor(s)")
            && text.contains("time 2025-06-21T11:00:00-04:00"),
        "{text}"
    );
    let out = dir.path().join("out");
    assert!(out.join("demo.json").is_file() && out.join("demo.materials.json").is_file());
    let scene: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("demo.json")).unwrap()).unwrap();
    // The block's instance as the `.glist` placed it; the `.atm`'s sky temperature.
    let block = &scene["objects"][1];
    assert_eq!(
        block["instances"][0]["translate"],
        serde_json::json!([5.0, -5.0, 0.0])
    );
    assert_eq!(
        scene["render"]["sky_temperature_k"],
        serde_json::json!(250.0)
    );
    let (code, text) = irsig(&["scene", "check", "out/demo.json"]);
    assert_eq!(code, Some(0), "{text}");
    let (code, text) = irsig(&["render", "out/demo.json", "-o", "img"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(dir.path().join("img/lwir.exr").is_file(), "{text}");
    // `scene check` and `render` take the DIRSIG simulation directly (imported on the
    // fly), with the import's warnings.
    let (code, text) = irsig(&["scene", "check", "dirsig/demo.sim"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("warning:"), "{text}");
    let (code, text) = irsig(&["render", "dirsig/demo.sim", "-o", "img2"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(dir.path().join("img2/lwir.exr").is_file(), "{text}");

    // A missing referenced file: an error naming the list, its line and the file.
    let glist = set.join("scene/geometry/demo.glist");
    let text = std::fs::read_to_string(&glist).unwrap();
    std::fs::write(&glist, text.replace("block.obj", "blok.obj")).unwrap();
    let (code, text) = irsig(&["import", "dirsig", "dirsig/demo.sim", "-o", "bad/demo.json"]);
    assert!(matches!(code, Some(c) if c != 0), "{code:?} {text}");
    assert!(!text.contains("panicked"), "{text}");
    assert!(
        text.contains("demo.glist:line 7") && text.contains("`blok.obj` not found"),
        "{text}"
    );
    assert!(!dir.path().join("bad/demo.json").exists());
}
