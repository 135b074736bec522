//! `irsig bench facets`: the per-facet stage of a generated scene of a
//! given size, written as an OBJ scene file and rendered's way: load
//! (parse, validate), BVH, rays, thermal passes; facets/s and peak memory.

use std::io::Write;
use std::path::Path;

use anyhow::Context;
use irsig::Session;
use irsig::geometry::procedural::{self, TerrainParams};

/// Arguments of `irsig bench facets`.
#[derive(Debug, clap::Args)]
pub(super) struct FacetsArgs {
    /// Facets of the generated scene (terrain + instanced buildings,
    /// within about 1 %).
    #[arg(long, value_name = "N", default_value_t = 1_000_000)]
    facets: usize,
    /// Seed of the generated scene.
    #[arg(long, value_name = "N", default_value_t = 1)]
    seed: u64,
    /// Ray-tracing backend: embree, embree-single or obvhs.
    #[arg(long, default_value = "embree", value_name = "NAME")]
    backend: irsig::Backend,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
    /// Write the generated scene (scene.json, scene.obj, weather,
    /// materials) into this folder and keep it, e.g. to render it
    /// (default: a temporary folder, removed).
    #[arg(long, value_name = "DIR")]
    keep: Option<std::path::PathBuf>,
}

/// What `irsig bench facets` measures.
#[derive(Debug, serde::Serialize)]
struct FacetsReport {
    facets: usize,
    threads: usize,
    /// Writing the generated OBJ, weather and scene files (not counted).
    write_s: f64,
    /// Scene load: OBJ parse, validation, materials, weather.
    load_s: f64,
    /// BVH builds (the render's and the exposure's).
    bvh_build_s: f64,
    /// Per-facet rays (solar history, sky view, ground test).
    rays_s: f64,
    /// Thermal passes.
    thermal_s: f64,
    /// Of `thermal_s`: the sunlight reflected between facets.
    reflected_s: f64,
    /// Facets per second through rays and thermal passes.
    facets_per_s: f64,
    /// Peak resident memory of the process (`VmHWM`), bytes.
    peak_rss_bytes: Option<u64>,
    /// Peak resident memory per facet, bytes.
    peak_bytes_per_facet: Option<f64>,
}

/// Peak resident set of this process, bytes (Linux `VmHWM`).
fn peak_rss_bytes() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Write the generated scene into `dir`: `scene.obj` (world coordinates,
/// one object per instance), `weather.csv` (the bundled town's),
/// `materials.json` (the built-in library) and `scene.json`.
fn write_scene(dir: &Path, facets: usize, seed: u64) -> anyhow::Result<std::path::PathBuf> {
    let geo = procedural::generate(&TerrainParams::with_triangles(facets, seed));
    let obj = dir.join("scene.obj");
    let mut w = std::io::BufWriter::new(std::fs::File::create(&obj)?);
    let mut base = 1usize;
    for (i, inst) in geo.instances.iter().enumerate() {
        let m = &geo.meshes[inst.mesh];
        writeln!(
            w,
            "o {}",
            if i == 0 {
                "terrain".to_string()
            } else {
                format!("building{i}")
            }
        )?;
        for p in &m.positions {
            let q = inst.world_from_object.transform_point3(*p);
            writeln!(w, "v {} {} {}", q.x, q.y, q.z)?;
        }
        for t in &m.indices {
            writeln!(
                w,
                "f {} {} {}",
                t[0] as usize + base,
                t[1] as usize + base,
                t[2] as usize + base
            )?;
        }
        base += m.positions.len();
    }
    w.flush()?;
    let (history, comments) = irsig::weather::synth::town_history()?;
    let comments: Vec<&str> = comments.iter().map(String::as_str).collect();
    let mut buf = Vec::new();
    irsig::weather::write_csv(&history, &comments, &mut buf)?;
    std::fs::write(dir.join("weather.csv"), buf)?;
    std::fs::write(
        dir.join("materials.json"),
        irsig::material::stock::STOCK_JSON,
    )?;
    let scene = serde_json::json!({
        "site": {"latitude_deg": 43.16, "longitude_deg": -77.61, "altitude_m": 160.0,
                 "utc_offset_hours": -4.0},
        "time": "2025-06-21T14:00:00-04:00",
        "weather": {"file": "weather.csv"},
        "materials": ["materials.json"],
        "objects": [{"name": "generated", "material": "asphalt", "shapes": [{"obj": "scene.obj"}]}],
        "sensors": [{"type": "frame", "name": "cam", "width": 8, "height": 6, "fov_deg": 60.0,
                     "position": [0.0, -600.0, 400.0], "look_at": [0.0, 0.0, 0.0],
                     "bands": [{"name": "LWIR", "response": [8.0, 12.0]}]}]
    });
    let path = dir.join("scene.json");
    std::fs::write(&path, serde_json::to_string_pretty(&scene)?)?;
    Ok(path)
}

pub(super) fn run(a: FacetsArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        (2..=200_000_000).contains(&a.facets),
        "--facets: {} is out of range (expected 2 to 200000000)",
        a.facets
    );
    let tmp;
    let dir = match &a.keep {
        Some(d) => {
            std::fs::create_dir_all(d).with_context(|| format!("--keep: {}", d.display()))?;
            d.as_path()
        }
        None => {
            tmp = tempfile::tempdir()?;
            tmp.path()
        }
    };
    let t0 = std::time::Instant::now();
    let scene = write_scene(dir, a.facets, a.seed).context("writing the generated scene")?;
    let write_s = t0.elapsed().as_secs_f64();
    let mut session = Session::open(&scene, a.backend).context("loading the generated scene")?;
    let states = session
        .facet_states(&[], &irsig::progress::NoProgress)
        .context("per-facet stage")?;
    let t = &session.timings;
    let facets = states.len();
    let thermal_s = t.thermal_solve.as_secs_f64();
    let stage = t.thermal.as_secs_f64();
    let peak = peak_rss_bytes();
    let r = FacetsReport {
        facets,
        threads: rayon::current_num_threads(),
        write_s,
        load_s: t.load.as_secs_f64(),
        bvh_build_s: t.bvh_build.as_secs_f64(),
        rays_s: stage - thermal_s,
        thermal_s,
        reflected_s: t.reflected_shortwave.as_secs_f64(),
        facets_per_s: facets as f64 / stage.max(1e-9),
        peak_rss_bytes: peak,
        peak_bytes_per_facet: peak.map(|p| p as f64 / facets.max(1) as f64),
    };
    if a.json {
        outln!("{}", serde_json::to_string(&r)?);
        return Ok(());
    }
    outln!(
        "generated scene: {} facets, {} threads",
        r.facets,
        r.threads
    );
    outln!("  load (parse, validate)   {:8.3} s", r.load_s);
    outln!("  BVH builds               {:8.3} s", r.bvh_build_s);
    outln!("  rays (sun, sky, ground)  {:8.3} s", r.rays_s);
    outln!("  thermal passes           {:8.3} s", r.thermal_s);
    outln!("    of which reflected     {:8.3} s", r.reflected_s);
    outln!("  per-facet stage          {:8.0} facets/s", r.facets_per_s);
    match (r.peak_rss_bytes, r.peak_bytes_per_facet) {
        (Some(p), Some(b)) => outln!(
            "  peak memory              {:8.1} MiB ({:.0} bytes/facet)",
            p as f64 / (1 << 20) as f64,
            b
        ),
        _ => outln!("  peak memory              unknown (no /proc/self/status)"),
    }
    Ok(())
}
