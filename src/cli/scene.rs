//! `irsig scene`: check a scene file, print the scene JSON Schema, write the
//! bundled town.

use std::io::Write;
use std::path::{Path, PathBuf};

use irsig::render::sections::schema_json;
use irsig::scene::{Scene, town};

/// Arguments of `irsig scene`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: SceneCommand,
}

#[derive(Debug, clap::Subcommand)]
enum SceneCommand {
    /// Load a scene and run every check `render` runs before its first
    /// pixel (materials, geometry, weather, sensors and their response
    /// files, `render` and `atmosphere` sections, weather coverage of the
    /// thermal spin-up, image memory, what each sensor sees); print a
    /// summary, or every problem found (exit status 2).
    Check {
        /// The scene file (JSON), or a DIRSIG `.scene`/`.jsim`/`.sim` (imported first).
        file: PathBuf,
        /// Image times to check the weather coverage for, as `render
        /// --times` takes them [default: the scene's time].
        #[arg(long, value_name = "TIMES")]
        times: Option<String>,
        /// Check only what loading the scene needs (materials, geometry,
        /// weather file), not what `render` needs (sensors, `render`,
        /// `atmosphere`, weather over the spin-up): for scenes used only
        /// by the thermal and analysis commands.
        #[arg(long)]
        load_only: bool,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
        /// For a DIRSIG scene or simulation: a folder to look in for files not found
        /// where the DIRSIG files say (see `irsig import dirsig`); repeat for more.
        #[arg(long, value_name = "DIR")]
        search: Vec<PathBuf>,
    },
    /// Print the JSON Schema of the scene file format.
    Schema {
        /// Write it to this file instead of standard output.
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
    },
    /// Write the bundled town scene (deterministic generator).
    Town {
        /// Output file, e.g. scenes/town/scene.json.
        #[arg(long, value_name = "FILE")]
        out: PathBuf,
    },
}

fn write_file(path: &Path, text: &str) -> anyhow::Result<()> {
    irsig::output::write_atomic(path, |w| {
        w.write_all(text.as_bytes())
            .map_err(|e| irsig::Error::io(path, e))
    })?;
    Ok(())
}

/// Run `irsig scene`.
pub fn run(args: Args) -> anyhow::Result<()> {
    match args.command {
        SceneCommand::Check {
            file,
            times,
            load_only,
            json,
            search,
        } => check(&file, times.as_deref(), load_only, json, search),
        SceneCommand::Schema { out } => {
            let s = schema_json();
            match out {
                Some(p) => write_file(&p, &s),
                None => {
                    std::io::stdout().write_all(s.as_bytes())?;
                    Ok(())
                }
            }
        }
        SceneCommand::Town { out } => {
            let s = serde_json::to_string_pretty(&town::town_scene())? + "\n";
            write_file(&out, &s)
        }
    }
}

fn check(
    file: &Path,
    times: Option<&str>,
    load_only: bool,
    json: bool,
    search: Vec<PathBuf>,
) -> anyhow::Result<()> {
    let times = times
        .map(super::args::parse_times)
        .transpose()?
        .unwrap_or_default();
    anyhow::ensure!(
        search.is_empty() || irsig::scene::dirsig::is_dirsig_scene(file),
        "--search: {} is not a DIRSIG scene or simulation (.scene, .jsim, .sim)",
        file.display()
    );
    let loaded = if search.is_empty() {
        Scene::check(file)
    } else {
        let opts = irsig::scene::dirsig::ImportOptions {
            search_dirs: search,
            time: None,
        };
        Scene::check_dirsig(file, &opts)
    };
    let scene = match loaded {
        Ok(s) => s,
        Err(errs) => {
            let mut err = std::io::stderr().lock();
            for e in &errs {
                writeln!(err, "{e}")?;
            }
            anyhow::bail!("{}: {} problem(s) found", file.display(), errs.len());
        }
    };
    let view = if load_only {
        Vec::new()
    } else {
        check_view(&scene)
    };
    let visibility = if load_only {
        Vec::new()
    } else {
        irsig::render::session::scene_visibility_warnings(&scene, &times)
    };
    for w in scene.warnings.iter().chain(&view).chain(&visibility) {
        eprintln!("warning: {w}");
    }
    // What `render` checks before its first pixel, in the order it does.
    let mut errs = Vec::new();
    if !load_only {
        errs = irsig::scene::image_memory_errors(
            &scene,
            irsig::render::TRUTH_LAYERS.len(),
            1,
            irsig::scene::available_memory_bytes(),
        );
        errs.extend(irsig::render::checks::render_problems(&scene, &times));
    }
    if !errs.is_empty() {
        let mut err = std::io::stderr().lock();
        for e in &errs {
            writeln!(err, "{e}")?;
        }
        anyhow::bail!("{}: {} problem(s) found", file.display(), errs.len());
    }
    let s = scene.summary();
    let mut out = std::io::stdout().lock();
    if json {
        serde_json::to_writer_pretty(&mut out, &s)?;
        writeln!(out)?;
        return Ok(());
    }
    writeln!(out, "scene      {}", s.path.display())?;
    writeln!(
        out,
        "site       {:.4}°, {:.4}°, {:.0} m; time {}",
        s.site[0], s.site[1], s.site[2], s.time
    )?;
    if let (Some(w), Some((n, a, b))) = (&s.weather, &s.weather_records) {
        writeln!(out, "weather    {}: {n} records, {a} .. {b}", w.display())?;
    }
    writeln!(
        out,
        "objects    {}  instances {}  parts {}  sensors {}",
        s.objects, s.instances, s.parts, s.sensors
    )?;
    writeln!(
        out,
        "triangles  {} stored, {} placed",
        s.triangles_stored, s.triangles_placed
    )?;
    writeln!(
        out,
        "bounds     [{:.1}, {:.1}, {:.1}] .. [{:.1}, {:.1}, {:.1}] m",
        s.bounds_min[0],
        s.bounds_min[1],
        s.bounds_min[2],
        s.bounds_max[0],
        s.bounds_max[1],
        s.bounds_max[2]
    )?;
    writeln!(
        out,
        "materials  {} used of {}:",
        s.materials_used.len(),
        s.materials_available
    )?;
    for (m, n) in &s.materials_used {
        writeln!(out, "  {m:<24} {n:>9} facets")?;
    }
    writeln!(out, "objects:")?;
    for (name, inst, tris) in &s.object_list {
        writeln!(out, "  {name:<24} {inst:>5} × {tris:>7} triangles")?;
    }
    Ok(())
}

/// [`irsig::render::checks::view_warnings`] for `scene check`: the sensors that build and the
/// default tracer; nothing when either fails (their errors are `render`'s).
fn check_view(scene: &Scene) -> Vec<String> {
    let loc = irsig::Location::file(&scene.path);
    let sensors: Vec<irsig::sensor::Sensor> = scene
        .sensors
        .iter()
        .enumerate()
        .filter_map(|(i, v)| {
            let c: irsig::sensor::SensorConfig = serde_json::from_value(v.clone()).ok()?;
            irsig::sensor::Sensor::from_config(&c, &loc.clone().with_field(format!("sensors[{i}]")))
                .ok()
        })
        .collect();
    if sensors.is_empty() {
        return Vec::new();
    }
    match irsig::trace::build(&scene.geometry, irsig::Backend::default()) {
        Ok(t) => irsig::render::checks::view_warnings(scene, &sensors, t.as_ref()),
        Err(_) => Vec::new(),
    }
}
