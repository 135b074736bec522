//! `irsig bench`: benchmarks. `irsig bench trace` compares the ray-tracing
//! backends (see [`irsig::bench`]); `irsig bench render` times a whole
//! render of a scene file by stage and compares the primary-ray pipeline with
//! bare packet tracing of the same rays.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use irsig::bench::{TileShape, TraceBenchOptions, trace_bench};
use irsig::geometry::SceneGeometry;
use irsig::geometry::procedural::{self, TerrainParams};
use irsig::render::session::{RunOptions, Session};
use irsig::trace::{Backend, Coherence};

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
    /// output), and the primary-ray pipeline (primary trace + radiometry +
    /// sensor) against bare coherent tracing of the same primary rays.
    Render(RenderArgs),
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
    /// Pixel tile of the primary rays (consecutive rays, one packet).
    #[arg(long, value_name = "WxH", default_value = "4x2")]
    tile: TileShape,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
}

/// Run `irsig bench`.
pub fn run(args: Args) -> anyhow::Result<()> {
    match args.what {
        What::Trace(a) => run_trace(a),
        What::Render(a) => run_render(a),
    }
}

fn load_scene(a: &TraceArgs) -> anyhow::Result<SceneGeometry> {
    if let Some(path) = &a.scene {
        let groups = irsig::scene::obj::load_obj(path)?;
        let mut geom = SceneGeometry::default();
        for g in groups {
            geom.meshes.push(g.mesh);
            geom.instances.push(irsig::geometry::Instance {
                mesh: geom.meshes.len() - 1,
                world_from_object: glam::Affine3A::IDENTITY,
            });
        }
        anyhow::ensure!(
            geom.facet_count() > 0,
            "{}: the OBJ file has no faces (expected `f` lines)",
            path.display()
        );
        Ok(geom)
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
    anyhow::ensure!(a.rays > 0, "--rays must be at least 1");
    anyhow::ensure!(a.rounds > 0, "--rounds must be at least 1");
    let geom = load_scene(&a)?;
    let opts = TraceBenchOptions {
        rays: a.rays,
        rounds: a.rounds,
        seed: a.seed,
        tile: a.tile,
    };
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
        "irsig bench trace: {} triangles ({} stored), Embree {} ({}-wide packets, {} tiles), {} threads, best of {} rounds",
        report.triangles,
        geom.stored_triangle_count(),
        info.embree_version,
        info.packet_width,
        format_args!("{}x{}", a.tile.width, a.tile.height),
        info.threads,
        a.rounds
    )?;
    writeln!(
        out,
        "rays per set: primary {}, shadow {}, diffuse {}",
        info.rays[0], info.rays[1], info.rays[2]
    )?;
    writeln!(
        out,
        "{:<14} {:>9} {:>16} {:>15} {:>16}",
        "backend", "build s", "primary Mray/s", "shadow Mray/s", "diffuse Mray/s"
    )?;
    for (name, r) in [
        ("embree_packet", &b.embree_packet),
        ("embree_single", &b.embree_single),
        ("obvhs", &b.obvhs),
    ] {
        writeln!(
            out,
            "{:<14} {:>9.3} {:>16.2} {:>15.2} {:>16.2}",
            name, r.build_s, r.primary_mrays_s, r.shadow_mrays_s, r.diffuse_mrays_s
        )?;
    }
    let ratio = |x: f64, y: f64| x / y.max(1e-12);
    writeln!(
        out,
        "embree_packet / obvhs: primary {:.2}x, shadow {:.2}x, diffuse {:.2}x",
        ratio(b.embree_packet.primary_mrays_s, b.obvhs.primary_mrays_s),
        ratio(b.embree_packet.shadow_mrays_s, b.obvhs.shadow_mrays_s),
        ratio(b.embree_packet.diffuse_mrays_s, b.obvhs.diffuse_mrays_s)
    )?;
    writeln!(
        out,
        "agreement: {} of {} rays differ (hit/miss, or distance beyond 1e-4 relative)",
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
    facets: usize,
    primary_rays: u64,
    threads: usize,
    load_s: f64,
    bvh_build_s: f64,
    rays_thermal_s: f64,
    ray_generation_s: f64,
    primary_trace_s: f64,
    radiometry_s: f64,
    sensor_s: f64,
    output_s: f64,
    total_s: f64,
    /// Bare coherent tracing of the same primary rays ([`irsig::trace::intersect_all`]).
    bare_trace_s: f64,
    /// Primary trace + radiometry + sensor, in Mrays/s of primary rays.
    pipeline_mrays_s: f64,
    bare_trace_mrays_s: f64,
    /// (primary trace + radiometry + sensor) / bare trace.
    pipeline_over_bare: f64,
}

fn run_render(a: RenderArgs) -> anyhow::Result<()> {
    let mut session = Session::open(&a.scene, a.backend)
        .with_context(|| format!("loading {}", a.scene.display()))?;
    let s = match &a.sensor {
        None => 0,
        Some(name) => session
            .sensors
            .iter()
            .position(|s| &s.name == name)
            .with_context(|| {
                format!(
                    "--sensor `{name}`: no such sensor in {} (it has {})",
                    a.scene.display(),
                    session
                        .sensors
                        .iter()
                        .map(|s| s.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })?,
    };
    let name = session.sensors[s].name.clone();
    let out_dir = tempfile::tempdir().context("creating a temporary output folder")?;
    let options = RunOptions {
        backend: a.backend,
        progress: false,
        sensors: vec![name.clone()],
        ..RunOptions::default()
    };
    session
        .run(out_dir.path(), &options)
        .with_context(|| format!("rendering {}", a.scene.display()))?;
    let t = session.timings;

    // The same primary rays, traced bare.
    let sensor = &session.sensors[s];
    let mut rays = Vec::with_capacity(sensor.rays_per_row() * sensor.height());
    for row in 0..sensor.height() {
        sensor.rays_for_row(row, &mut rays);
    }
    let t0 = std::time::Instant::now();
    let hits = irsig::trace::intersect_all(session.tracer.as_ref(), &rays, Coherence::Coherent);
    let bare = t0.elapsed().as_secs_f64();
    std::hint::black_box(&hits);

    let secs = |d: std::time::Duration| d.as_secs_f64();
    let pipeline = secs(t.primary_trace) + secs(t.radiometry) + secs(t.sensor);
    let mrays = |n: usize, s: f64| n as f64 / s.max(1e-12) / 1e6;
    let report = RenderReport {
        scene: a.scene.display().to_string(),
        sensor: name,
        backend: a.backend.as_str().to_string(),
        width: sensor.width(),
        height: sensor.height(),
        oversample: sensor.oversample(),
        facets: session.scene.geometry.facet_count(),
        primary_rays: t.primary_rays,
        threads: rayon::current_num_threads(),
        load_s: secs(t.load),
        bvh_build_s: secs(t.bvh_build),
        rays_thermal_s: secs(t.thermal),
        ray_generation_s: secs(t.ray_generation),
        primary_trace_s: secs(t.primary_trace),
        radiometry_s: secs(t.radiometry),
        sensor_s: secs(t.sensor),
        output_s: secs(t.output),
        total_s: secs(t.total()),
        bare_trace_s: bare,
        pipeline_mrays_s: mrays(rays.len(), pipeline),
        bare_trace_mrays_s: mrays(rays.len(), bare),
        pipeline_over_bare: pipeline / bare.max(1e-12),
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
        "irsig bench render: {} sensor {} ({}x{} px, oversample {}), {} facets, {} primary rays, backend {}, {} threads",
        r.scene,
        r.sensor,
        r.width,
        r.height,
        r.oversample,
        r.facets,
        r.primary_rays,
        r.backend,
        r.threads
    )?;
    writeln!(out, "{:<28} {:>10}", "stage", "seconds")?;
    for (stage, v) in [
        ("load", r.load_s),
        ("BVH build", r.bvh_build_s),
        ("per-facet rays + thermal", r.rays_thermal_s),
        ("primary ray generation", r.ray_generation_s),
        ("primary trace", r.primary_trace_s),
        ("radiometry (+ secondary)", r.radiometry_s),
        ("sensor", r.sensor_s),
        ("output", r.output_s),
        ("total", r.total_s),
    ] {
        writeln!(out, "{stage:<28} {v:>10.3}")?;
    }
    writeln!(
        out,
        "primary pipeline (trace + radiometry + sensor): {:.3} s, {:.2} Mray/s",
        pipeline, r.pipeline_mrays_s
    )?;
    writeln!(
        out,
        "bare coherent trace of the same rays: {:.3} s, {:.2} Mray/s",
        r.bare_trace_s, r.bare_trace_mrays_s
    )?;
    writeln!(out, "pipeline / bare trace: {:.2}x", r.pipeline_over_bare)?;
    Ok(())
}
