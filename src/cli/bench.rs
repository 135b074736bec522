//! `irsig bench`: benchmarks. `irsig bench trace` compares the ray-tracing
//! backends (see [`irsig::bench`]).

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use irsig::bench::{TileShape, TraceBenchOptions, trace_bench};
use irsig::geometry::SceneGeometry;
use irsig::geometry::procedural::{self, TerrainParams};

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
