//! `irsig bench`: benchmarks. `irsig bench trace` compares the ray-tracing
//! backends (see [`trace`]); `irsig bench render` times a whole
//! render of a scene file by stage and compares the primary-ray pipeline with
//! bare packet tracing of the same rays.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use irsig::geometry::SceneGeometry;
use irsig::geometry::procedural::{self, TerrainParams};
use irsig::trace::{Coherence, Watertight};
use irsig::{Backend, Session, Timings};
use rayon::prelude::*;

use super::args::FlagContext;
use trace::{TileShape, TraceBenchOptions, trace_bench};

mod exposure;
mod facets;
mod modes;
mod trace;

/// Arguments of `irsig bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    what: What,
}

#[derive(Debug, clap::Subcommand)]
enum What {
    /// Ray-tracing backends: build time and throughput (Mrays/s) of Embree
    /// packets, Embree single rays and obvhs on primary, shadow and diffuse
    /// rays, and how often they disagree.
    Trace(TraceArgs),
    /// A whole render of a scene file, one sensor at the scene's time: the
    /// time of each stage (load, BVH build, per-facet rays + thermal, ray
    /// generation, primary trace, radiometry with secondary rays, sensor,
    /// output), and the primary-ray pipeline (ray generation + primary trace + radiometry +
    /// sensor) against bare coherent tracing of the same primary rays.
    Render(RenderArgs),
    /// Embree's query modes side by side on `bench trace`'s scene and rays:
    /// single rays, native-width packets, the stream API (Embree 3) and the
    /// default choice by coherence (packets for camera rows, the stream or
    /// single rays for scattered rays), Mrays/s per ray class.
    Modes(TraceArgs),
    /// The per-facet rays of a render (solar history, sky view) under
    /// several sampling settings: rays, time, facets/s and accuracy against
    /// an exhaustive reference (the sun at every step, many sky rays).
    Exposure(ExposureArgs),
    /// The per-facet stage of a generated scene of a given size (written
    /// as an OBJ scene file): load, BVH, rays and thermal passes in
    /// seconds, facets/s, and peak memory (total and per facet).
    Facets(facets::FacetsArgs),
}

/// Arguments of `irsig bench exposure`.
#[derive(Debug, clap::Args)]
struct ExposureArgs {
    /// Scene file (JSON).
    #[arg(value_name = "SCENE.json", default_value = "scenes/town/scene.json")]
    scene: PathBuf,
    /// Ray-tracing backend: embree, embree-single or obvhs.
    #[arg(long, default_value = "embree", value_name = "NAME")]
    backend: Backend,
    /// Timed rounds per setting; the best counts.
    #[arg(long, value_name = "N", default_value_t = 1)]
    rounds: usize,
    /// Sky sampling of the reference.
    #[arg(long, value_name = "SPEC", default_value = "stratified:1024")]
    reference: irsig::exposure::SkySampling,
    /// Settings to compare, each SKY@STRIDE (sky sampling, solar stride),
    /// comma-separated.
    #[arg(
        long,
        value_name = "LIST",
        default_value = "dirsig@1,stratified:64@1,stratified:64@2,stratified:64@4,stratified:36@4"
    )]
    settings: String,
    /// Sample points per facet edge, `n²` per facet (`render.facet_samples`;
    /// the render's default, 1).
    #[arg(long, value_name = "N", default_value_t = 1)]
    facet_samples: u32,
}

/// Arguments of `irsig bench render`.
#[derive(Debug, clap::Args)]
struct RenderArgs {
    /// Scene file (JSON).
    #[arg(value_name = "SCENE.json", default_value = "scenes/town/scene.json")]
    scene: PathBuf,
    /// Sensor to render [default: the scene's first].
    #[arg(long, value_name = "NAME")]
    sensor: Option<String>,
    /// Ray-tracing backend: embree, embree-single or obvhs.
    #[arg(long, default_value = "embree", value_name = "NAME")]
    backend: Backend,
    /// Timed rounds, each the row loop (after one thermal solve) then the
    /// bare trace of the same rays; the best of each counts.
    #[arg(long, value_name = "N", default_value_t = 3)]
    rounds: usize,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
}

/// Arguments of `irsig bench trace`.
#[derive(Debug, clap::Args)]
struct TraceArgs {
    /// Wavefront OBJ scene to trace (each object/group placed once).
    #[arg(long, value_name = "FILE.obj", conflicts_with = "triangles")]
    scene: Option<PathBuf>,
    /// Size of the generated scene (terrain + buildings), triangles
    /// [default: 1000000 when no --scene is given].
    #[arg(long, value_name = "N")]
    triangles: Option<usize>,
    /// Rays per ray set.
    #[arg(long, value_name = "N", default_value_t = 1_000_000)]
    rays: usize,
    /// Timed rounds per set and backend; the best counts.
    #[arg(long, value_name = "N", default_value_t = 3)]
    rounds: usize,
    /// Seed of the generated scene and of the random rays.
    #[arg(long, value_name = "N", default_value_t = 1)]
    seed: u64,
    /// Pixel tiles for the primary rays (consecutive rays, one packet),
    /// e.g. 4x2 [default: the renderer's layout, row by row: 8×1 runs].
    #[arg(long, value_name = "WxH")]
    tile: Option<TileShape>,
    /// Embree's triangle tests: `yes` watertight (`RTC_SCENE_FLAG_ROBUST`,
    /// what a render's sensor rays use), `no` Embree's faster default (what
    /// a render's per-facet shadow and sky rays use). obvhs is the same
    /// either way.
    #[arg(long, value_name = "yes|no", default_value = "yes")]
    watertight: Watertight,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
    /// Also write the scene's triangles and the four ray sets as raw
    /// little-endian files into DIR, for an outside harness (e.g.
    /// `scripts/embree-harness/run`, which traces the same rays with
    /// Embree's C API); layout in `docs/embree.md`.
    #[arg(long, value_name = "DIR")]
    dump: Option<PathBuf>,
}

/// Run `irsig bench`.
pub fn run(args: Args) -> anyhow::Result<()> {
    match args.what {
        What::Trace(a) => run_trace(a),
        What::Render(a) => run_render(a),
        What::Facets(a) => facets::run(a),
        What::Modes(a) => {
            let (geom, opts) = scene_and_options(&a)?;
            if let Some(dir) = &a.dump {
                trace::dump(&geom, &opts, dir)
                    .with_context(|| format!("--dump {}", dir.display()))?;
            }
            modes::run(&geom, &opts)
        }
        What::Exposure(a) => {
            anyhow::ensure!(a.rounds > 0, "--rounds must be at least 1");
            let mut settings = Vec::new();
            for item in a.settings.split(',') {
                let (sky, stride) = item.split_once('@').unwrap_or((item, "1"));
                let sky: irsig::exposure::SkySampling = sky
                    .parse()
                    .with_context(|| format!("--settings: `{item}`"))?;
                let stride: u32 = stride
                    .parse()
                    .with_context(|| format!("--settings: `{item}`: bad stride"))?;
                settings.push((
                    item.to_string(),
                    irsig::exposure::ExposureParams {
                        sky,
                        solar_stride: stride,
                        samples_per_edge: a.facet_samples,
                        ..Default::default()
                    },
                ));
            }
            exposure::run(&a.scene, a.backend, a.rounds, a.reference, &settings)
        }
    }
}

/// The scene and ray-set options of `bench trace` and `bench modes`.
fn scene_and_options(a: &TraceArgs) -> anyhow::Result<(SceneGeometry, TraceBenchOptions)> {
    anyhow::ensure!(a.rays > 0, "--rays must be at least 1");
    anyhow::ensure!(a.rounds > 0, "--rounds must be at least 1");
    let opts = TraceBenchOptions {
        rays: a.rays,
        rounds: a.rounds,
        seed: a.seed,
        tile: a.tile,
        watertight: a.watertight,
    };
    Ok((load_scene(a)?, opts))
}

fn load_scene(a: &TraceArgs) -> anyhow::Result<SceneGeometry> {
    if let Some(path) = &a.scene {
        Ok(irsig::scene::obj::load_obj_geometry(path)?)
    } else {
        let n = a.triangles.unwrap_or(1_000_000);
        anyhow::ensure!(
            (2..=200_000_000).contains(&n),
            "--triangles: {n} is out of range (expected 2 to 200000000)"
        );
        Ok(procedural::generate(&TerrainParams::with_triangles(
            n, a.seed,
        )))
    }
}

fn run_trace(a: TraceArgs) -> anyhow::Result<()> {
    let (geom, opts) = scene_and_options(&a)?;
    if let Some(dir) = &a.dump {
        trace::dump(&geom, &opts, dir).with_context(|| format!("--dump {}", dir.display()))?;
    }
    let (report, info) = trace_bench(&geom, &opts).context("trace benchmark")?;
    let mut out = std::io::stdout().lock();
    if a.json {
        serde_json::to_writer(&mut out, &report)?;
        writeln!(out)?;
        return Ok(());
    }
    let b = &report.backends;
    writeln!(
        out,
        "irsig bench trace: {} triangles ({} stored), Embree {} ({}-wide packets, {}), {} threads (builds and tracing), best of {} rounds",
        report.triangles,
        geom.stored_triangle_count(),
        info.embree_version,
        info.packet_width,
        match a.watertight {
            Watertight::Yes => "watertight",
            Watertight::No => "not watertight",
        },
        report.threads,
        a.rounds
    )?;
    writeln!(
        out,
        "primary: {}x{} camera, {}; shadow: solar-history rays, 4 steps; hemisphere: the default sky-view sampling (stratified, 64 per face); both from facet sample points in batches of 512 facets; diffuse: random",
        info.camera.0,
        info.camera.1,
        match a.tile {
            None => "row by row as the renderer".to_string(),
            Some(t) => format!("{}x{} tiles", t.width, t.height),
        }
    )?;
    writeln!(
        out,
        "{:<14} {:>9} {:>16} {:>15} {:>19} {:>16}",
        "backend",
        "build s",
        "primary Mray/s",
        "shadow Mray/s",
        "hemisphere Mray/s",
        "diffuse Mray/s"
    )?;
    for (name, r) in [
        ("embree_packet", &b.embree_packet),
        ("embree_single", &b.embree_single),
        ("obvhs", &b.obvhs),
    ] {
        writeln!(
            out,
            "{:<14} {:>9.3} {:>16.2} {:>15.2} {:>19.2} {:>16.2}",
            name,
            r.build_s,
            r.primary_mrays_s,
            r.shadow_mrays_s,
            r.hemisphere_mrays_s,
            r.diffuse_mrays_s
        )?;
    }
    writeln!(
        out,
        "{:<11} {:>9} {:<11} {:<10} {:>13} {:>12} {:>8} {:>11}",
        "class",
        "rays",
        "coherence",
        "embree",
        "embree Mray/s",
        "obvhs Mray/s",
        "ratio",
        "mismatched"
    )?;
    let c = &report.classes;
    for (name, r) in trace::CLASSES
        .iter()
        .zip([&c.primary, &c.shadow, &c.hemisphere, &c.diffuse])
    {
        writeln!(
            out,
            "{:<11} {:>9} {:<11} {:<10} {:>13.2} {:>12.2} {:>7.2}x {:>11}",
            name,
            r.rays,
            r.coherence,
            r.embree_mode,
            r.embree_mrays_s,
            r.obvhs_mrays_s,
            r.ratio,
            r.mismatched
        )?;
    }
    writeln!(
        out,
        "agreement: {} of {} rays differ (hit/miss, or the hit: trace::hits_agree)",
        report.agreement.mismatched_rays, report.agreement.rays
    )?;
    Ok(())
}

/// What `irsig bench render` measured (seconds; `--json` prints it).
#[derive(Debug, serde::Serialize)]
struct RenderReport {
    scene: String,
    sensor: String,
    backend: String,
    width: usize,
    height: usize,
    oversample: usize,
    bands: usize,
    facets: usize,
    primary_rays: u64,
    /// Primary hits on specular or transmissive materials (secondary rays).
    secondary_hits: u64,
    threads: usize,
    rounds: usize,
    load_s: f64,
    bvh_build_s: f64,
    rays_thermal_s: f64,
    /// Of `rays_thermal_s`: the thermal stage (reflected shortwave and the
    /// slab model's passes), without the per-facet rays.
    thermal_solve_s: f64,
    /// Of `thermal_solve_s`: sunlight reflected between facets.
    reflected_shortwave_s: f64,
    /// Shading tables and per-facet terms (per image time and sensor).
    radiometry_setup_s: f64,
    ray_generation_s: f64,
    primary_trace_s: f64,
    /// Radiometry of the primary rays without secondary rays.
    radiometry_s: f64,
    /// Hits with secondary rays: their tracing and spectral radiometry.
    secondary_s: f64,
    sensor_s: f64,
    output_s: f64,
    total_s: f64,
    /// Bare coherent tracing of the same primary rays, row by row in
    /// parallel as the pipeline traces them, into reused buffers.
    bare_trace_s: f64,
    /// Ray generation + primary trace + radiometry + sensor, in Mrays/s of primary rays.
    pipeline_mrays_s: f64,
    bare_trace_mrays_s: f64,
    /// (ray generation + primary trace + radiometry + sensor) / bare trace.
    pipeline_over_bare: f64,
    /// (primary trace + radiometry + sensor) / bare trace: the pipeline
    /// given the rays, as the bare trace is.
    given_rays_over_bare: f64,
    /// (ray generation + primary trace + radiometry + secondary + sensor) / bare trace.
    with_secondary_over_bare: f64,
    /// (radiometry setup + ray generation + primary trace + radiometry + secondary +
    /// sensor) / bare trace.
    all_over_bare: f64,
}

/// `a − b`, per stage.
fn timings_since(a: &Timings, b: &Timings) -> Timings {
    Timings {
        load: a.load - b.load,
        bvh_build: a.bvh_build - b.bvh_build,
        thermal: a.thermal - b.thermal,
        thermal_solve: a.thermal_solve - b.thermal_solve,
        reflected_shortwave: a.reflected_shortwave - b.reflected_shortwave,
        radiometry_setup: a.radiometry_setup - b.radiometry_setup,
        ray_generation: a.ray_generation - b.ray_generation,
        primary_trace: a.primary_trace - b.primary_trace,
        radiometry: a.radiometry - b.radiometry,
        secondary: a.secondary - b.secondary,
        sensor: a.sensor - b.sensor,
        output: a.output - b.output,
        primary_rays: a.primary_rays - b.primary_rays,
        secondary_hits: a.secondary_hits - b.secondary_hits,
    }
}

fn run_render(a: RenderArgs) -> anyhow::Result<()> {
    anyhow::ensure!(a.rounds > 0, "--rounds must be at least 1");
    let mut session = Session::open(&a.scene, a.backend)
        .with_context(|| format!("loading {}", a.scene.display()))?;
    let s = match &a.sensor {
        None => 0,
        Some(name) => session
            .sensor_index(name)
            .for_flags(&[("sensor", "--sensor")])
            .with_context(|| format!("in {}", a.scene.display()))?,
    };
    let name = session.sensors[s].name.clone();
    let out_dir = tempfile::tempdir().context("creating a temporary output folder")?;
    let time = session.scene.time;
    let states = session
        .thermal(&[time])
        .with_context(|| format!("thermal state of {}", a.scene.display()))?;
    let cond = &states.conditions[0];
    let height = session.sensors[s].height();
    let seed = session.sensors[s].effects.seed;
    // The same primary rays, for the bare trace: row by row in parallel as
    // the pipeline traces them, into buffers allocated once.
    let sensor = &session.sensors[s];
    let per_row = sensor.rays_per_row();
    let mut rays = Vec::with_capacity(per_row * height);
    for row in 0..height {
        sensor.rays_for_row(row, &mut rays);
    }
    let mut hits = vec![None; rays.len()];
    let mut bare = f64::INFINITY;
    // The row loop with the image-wide sensor effects, then the bare trace,
    // round after round (so both see the same machine load); the best
    // round of each counts.
    let base = session.timings;
    let mut best: Option<(f64, Timings)> = None;
    let mut finished = None;
    for _ in 0..a.rounds {
        let before = session.timings;
        let band = session
            .render_rows(s, cond, 0..height, &|_| {})
            .with_context(|| format!("rendering {}", a.scene.display()))?;
        let f = session.finish(s, band, seed)?;
        let d = timings_since(&session.timings, &before);
        let pipeline = (d.ray_generation + d.primary_trace + d.radiometry + d.sensor).as_secs_f64();
        if best.as_ref().is_none_or(|(p, _)| pipeline < *p) {
            best = Some((pipeline, d));
        }
        finished = Some(f);
        let tracer = session.tracer.as_ref();
        let t0 = std::time::Instant::now();
        rays.par_chunks(per_row)
            .zip(hits.par_chunks_mut(per_row))
            .for_each(|(r, o)| tracer.intersect(r, Coherence::Coherent, o));
        bare = bare.min(t0.elapsed().as_secs_f64());
        std::hint::black_box(&hits);
    }
    let (_, round) = best.expect("at least one round");
    let finished = finished.expect("at least one round");
    let before = session.timings;
    session.write_image(out_dir.path(), &name, s, &time, &finished)?;
    let sensor = &session.sensors[s];
    let t = Timings {
        output: session.timings.output - before.output,
        ..timings_since(&base, &Timings::default())
    };
    let t = Timings {
        radiometry_setup: round.radiometry_setup,
        ray_generation: round.ray_generation,
        primary_trace: round.primary_trace,
        radiometry: round.radiometry,
        secondary: round.secondary,
        sensor: round.sensor,
        primary_rays: round.primary_rays,
        secondary_hits: round.secondary_hits,
        ..t
    };

    let secs = |d: std::time::Duration| d.as_secs_f64();
    let pipeline =
        secs(t.ray_generation) + secs(t.primary_trace) + secs(t.radiometry) + secs(t.sensor);
    let mrays = |n: usize, s: f64| n as f64 / s.max(1e-12) / 1e6;
    let report = RenderReport {
        scene: a.scene.display().to_string(),
        sensor: name,
        backend: a.backend.as_str().to_string(),
        width: sensor.width(),
        height: sensor.height(),
        oversample: sensor.oversample(),
        bands: sensor.bands.len(),
        facets: session.scene.geometry.facet_count(),
        primary_rays: t.primary_rays,
        secondary_hits: t.secondary_hits,
        threads: rayon::current_num_threads(),
        rounds: a.rounds,
        load_s: secs(t.load),
        bvh_build_s: secs(t.bvh_build),
        rays_thermal_s: secs(t.thermal),
        thermal_solve_s: secs(t.thermal_solve),
        reflected_shortwave_s: secs(t.reflected_shortwave),
        radiometry_setup_s: secs(t.radiometry_setup),
        ray_generation_s: secs(t.ray_generation),
        primary_trace_s: secs(t.primary_trace),
        radiometry_s: secs(t.radiometry),
        secondary_s: secs(t.secondary),
        sensor_s: secs(t.sensor),
        output_s: secs(t.output),
        total_s: secs(t.total()),
        bare_trace_s: bare,
        pipeline_mrays_s: mrays(rays.len(), pipeline),
        bare_trace_mrays_s: mrays(rays.len(), bare),
        pipeline_over_bare: pipeline / bare.max(1e-12),
        given_rays_over_bare: (pipeline - secs(t.ray_generation)) / bare.max(1e-12),
        with_secondary_over_bare: (pipeline + secs(t.secondary)) / bare.max(1e-12),
        all_over_bare: (pipeline + secs(t.secondary) + secs(t.radiometry_setup)) / bare.max(1e-12),
    };
    let mut out = std::io::stdout().lock();
    if a.json {
        serde_json::to_writer(&mut out, &report)?;
        writeln!(out)?;
        return Ok(());
    }
    let r = &report;
    writeln!(
        out,
        "irsig bench render: {} sensor {} ({}x{} px, oversample {}, {} bands), {} facets, {} primary rays, backend {}, {} threads, best of {} rounds",
        r.scene,
        r.sensor,
        r.width,
        r.height,
        r.oversample,
        r.bands,
        r.facets,
        r.primary_rays,
        r.backend,
        r.threads,
        r.rounds
    )?;
    writeln!(out, "{:<36} {:>10}", "stage", "seconds")?;
    let secondary = format!("secondary rays ({} hits)", r.secondary_hits);
    for (stage, v) in [
        ("load", r.load_s),
        ("BVH build", r.bvh_build_s),
        ("per-facet rays + thermal", r.rays_thermal_s),
        ("  of which thermal solve", r.thermal_solve_s),
        ("    of which reflected shortwave", r.reflected_shortwave_s),
        ("radiometry setup", r.radiometry_setup_s),
        ("primary ray generation", r.ray_generation_s),
        ("primary trace", r.primary_trace_s),
        ("radiometry", r.radiometry_s),
        (secondary.as_str(), r.secondary_s),
        ("sensor", r.sensor_s),
        ("output", r.output_s),
        ("total", r.total_s),
    ] {
        writeln!(out, "{stage:<36} {v:>10.3}")?;
    }
    writeln!(
        out,
        "thermal solve: {:.1} % of the render",
        100.0 * r.thermal_solve_s / r.total_s.max(f64::MIN_POSITIVE)
    )?;
    writeln!(
        out,
        "primary pipeline (ray generation + trace + radiometry + sensor): {:.3} s, {:.2} Mray/s",
        pipeline, r.pipeline_mrays_s
    )?;
    writeln!(
        out,
        "bare coherent trace of the same rays: {:.3} s, {:.2} Mray/s",
        r.bare_trace_s, r.bare_trace_mrays_s
    )?;
    writeln!(
        out,
        "pipeline / bare trace: {:.2}x (without ray generation: {:.2}x; with the secondary rays: {:.2}x; with those and the radiometry setup: {:.2}x)",
        r.pipeline_over_bare, r.given_rays_over_bare, r.with_secondary_over_bare, r.all_over_bare
    )?;
    Ok(())
}
