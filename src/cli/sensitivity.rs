//! `irsig sensitivity`: which inputs the temperatures and radiances are
//! most sensitive to, by one-at-a-time bounds or Morris screening, with an
//! estimated-error budget: on a scene's sample pixels (per-facet inputs
//! traced once, [`irsig::analysis::scene`]) or on the one-facet thermal
//! path (`--thermal`).

use std::path::PathBuf;

use anyhow::Context;
use chrono::{DateTime, FixedOffset};
use serde::Serialize;

use std::path::Path;

use irsig::Backend;
use irsig::Session;
use irsig::analysis::csv::{self, PointPosition, TruthPoint};
use irsig::analysis::facet::{self, FacetSpec, OneFacet};
use irsig::analysis::geo;
use irsig::analysis::params::ParamSet;
use irsig::analysis::plot::{self, TornadoBar};
use irsig::analysis::scene::{self as scene_study, PixelPoint, SceneStudy};
use irsig::analysis::sensitivity::{self, ErrorBudget, Morris, MorrisOptions, Oat};
use irsig::analysis::study::MaterialStudy;
use irsig::material::Material;
use irsig::sun::Site;
use irsig::thermal::{BackBoundary, SolveOptions};
use irsig::weather::{self, LoadOptions};

use super::args::{FlagContext, parse_site, parse_time};

/// The one-facet fields and their flags, for errors about them.
pub(crate) const FACET_FLAGS: &[(&str, &str)] = &[
    ("tilt_deg", "--tilt"),
    ("azimuth_deg", "--azimuth"),
    ("shape_factor", "--shape-factor"),
    ("back_shape_factor", "--back-shape-factor"),
    ("ground_albedo", "--ground-albedo"),
    ("material", "--material"),
];

/// The one-facet model options shared by `irsig thermal`, `calibrate` and
/// `sensitivity` (`--thermal`): everything besides material and weather
/// that changes the solved temperatures, so a fit or a study and a later
/// `irsig thermal` run take the same flags.
#[derive(Debug, Clone, clap::Args)]
pub struct FacetArgs {
    /// Facet tilt from horizontal, degrees (0 = facing up, 90 = vertical).
    #[arg(long, value_name = "DEG", default_value_t = 0.0)]
    pub tilt: f64,
    /// Direction the facet faces, degrees clockwise from north (180 = south).
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 180.0,
        allow_negative_numbers = true
    )]
    pub azimuth: f64,
    /// Sky shape factor of the front face, 0–1 (default: (1 + cos tilt)/2,
    /// an unobstructed plane).
    #[arg(long, value_name = "F")]
    pub shape_factor: Option<f64>,
    /// Sky shape factor of the back face, 0–1, where the back is exposed
    /// to outdoor air (the material's exposed area, or --back exposed);
    /// default 1 − F, an unobstructed plane's. A scene render traces it.
    #[arg(long, value_name = "F")]
    pub back_shape_factor: Option<f64>,
    /// Albedo of the open ground the facet sees over 1 − F of its
    /// hemisphere, reflecting sun and sky onto it (0 switches it off; a
    /// horizontal facet sees no ground).
    #[arg(long, value_name = "RHO", default_value_t = irsig::exposure::reflected::GROUND_ALBEDO as f64)]
    pub ground_albedo: f64,
    /// Site as LAT,LON,ALT (degrees north, degrees east, metres); default:
    /// the weather file's site.
    #[arg(long, value_name = "LAT,LON,ALT", allow_hyphen_values = true)]
    pub site: Option<String>,
    /// Local date and time of hour 0 of a DIRSIG .wth file (RFC 3339).
    #[arg(long, value_name = "RFC3339")]
    pub start: Option<String>,
    /// Replace the year of every EPW/TMY3 row. A typical-year file (months
    /// from different years) takes the year of the run's last time without it.
    #[arg(long, value_name = "YEAR")]
    pub year: Option<i32>,
    /// Back boundary, overriding the material's exposed area:
    /// insulated | exposed | ground | building.
    #[arg(long, value_name = "KIND")]
    pub back: Option<String>,
    /// Repeat the first day up to N times before the run (spin-up; default:
    /// the solver preset's, 3 days by default, 6 with --accurate).
    #[arg(long, value_name = "N")]
    pub spinup_days: Option<u32>,
    /// Accurate thermal solver preset (finer grid and sub-steps, tighter
    /// tolerances; default: the default preset).
    #[arg(long)]
    pub accurate: bool,
}

impl FacetArgs {
    pub(crate) fn spec(&self) -> FacetSpec {
        FacetSpec {
            tilt_deg: self.tilt,
            azimuth_deg: self.azimuth,
            shape_factor: self.shape_factor,
            back_shape_factor: self.back_shape_factor,
            ground_albedo: self.ground_albedo,
        }
    }
    /// The solver options: the preset, with --spinup-days.
    pub(crate) fn options(&self) -> SolveOptions {
        let mut o = if self.accurate {
            SolveOptions::accurate()
        } else {
            SolveOptions::default()
        };
        if let Some(n) = self.spinup_days {
            o.spinup.max_cycles = n;
        }
        o
    }
    /// A `warning:` on stderr where --back-shape-factor is given for a
    /// facet whose back (`back`, after --back) is not exposed to the air:
    /// the value then changes nothing.
    pub(crate) fn warn_unused_back_shape_factor(&self, back: &BackBoundary) {
        if self.back_shape_factor.is_some() && !matches!(back, BackBoundary::Exposed { .. }) {
            eprintln!(
                "warning: --back-shape-factor is used only with a back exposed to the air; this facet's back is {back:?} (give --back exposed to expose it)"
            );
        }
    }
    /// The --back override, if given.
    pub(crate) fn back(&self) -> anyhow::Result<Option<BackBoundary>> {
        self.back.as_deref().map(parse_back).transpose()
    }
    /// The --site override, if given.
    pub(crate) fn site(&self) -> anyhow::Result<Option<Site>> {
        self.site.as_deref().map(parse_site).transpose()
    }
    /// Weather load options: --site, --start and --year; a typical-year EPW/TMY3
    /// file takes `until`'s year (the run's last time) without --year.
    pub(crate) fn load_options(&self, until: DateTime<FixedOffset>) -> anyhow::Result<LoadOptions> {
        let mut opts = LoadOptions::default();
        if let Some(s) = self.site()? {
            opts = opts.with_site(s);
        }
        if let Some(s) = &self.start {
            opts = opts.with_start(parse_time("--start", s)?);
        }
        opts = opts.with_typical_year(chrono::Datelike::year(&until));
        if let Some(y) = self.year {
            opts = opts.with_year(y);
        }
        Ok(opts)
    }
}

/// The back boundary named by `--back`.
pub(crate) fn parse_back(kind: &str) -> anyhow::Result<BackBoundary> {
    Ok(match kind {
        "insulated" => BackBoundary::Insulated,
        "exposed" => BackBoundary::BOTH_FACES,
        "ground" => BackBoundary::GROUND,
        "building" => BackBoundary::BUILDING,
        _ => anyhow::bail!("--back: `{kind}` is not one of insulated, exposed, ground, building"),
    })
}

/// One-facet mode inputs (`--thermal`).
#[derive(Debug, Clone, clap::Args)]
pub struct ThermalArgs {
    /// One-facet mode: a material under a weather file, no scene.
    #[arg(long)]
    pub thermal: bool,
    /// Material: a name in --materials, a material file, or FILE#NAME.
    #[arg(long, value_name = "NAME|FILE", requires = "thermal")]
    pub material: Option<String>,
    /// Material database for --material NAME (default: the stock library,
    /// built into irsig).
    #[arg(long, value_name = "FILE")]
    pub materials: Option<PathBuf>,
    /// Weather file (irsig CSV/JSON, EPW, TMY3, DIRSIG .wth).
    #[arg(long, value_name = "FILE", requires = "thermal")]
    pub weather: Option<PathBuf>,
}

impl ThermalArgs {
    /// The --material, resolved in --materials.
    pub(crate) fn material(&self) -> anyhow::Result<Material> {
        let spec = self
            .material
            .as_deref()
            .context("--thermal needs --material NAME|FILE")?;
        super::thermal::find_material(spec, self.materials.as_deref()).for_flags(FACET_FLAGS)
    }
}

/// Materials, weather records up to `until`, and site: from a scene or
/// from --thermal inputs.
pub(crate) struct Setup {
    pub materials: Vec<Material>,
    pub facet: OneFacet,
    pub time: DateTime<FixedOffset>,
}

pub(crate) fn setup_thermal(
    t: &ThermalArgs,
    f: &FacetArgs,
    until: DateTime<FixedOffset>,
) -> anyhow::Result<Setup> {
    let material = t.material()?;
    let wpath = t
        .weather
        .as_ref()
        .context("--thermal needs --weather FILE")?;
    let site = f.site()?;
    let history = weather::load_with(wpath, &f.load_options(until)?)?;
    let site = site.or(history.site().copied()).with_context(|| {
        format!(
            "{}: the weather file names no site; give --site LAT,LON,ALT",
            wpath.display()
        )
    })?;
    let records =
        facet::records_until(&history, until).with_context(|| format!("{}", wpath.display()))?;
    let facet = OneFacet::new(records, &site, &f.spec(), f.options(), facet::lwir_band()?)
        .for_flags(FACET_FLAGS)?
        .with_back(f.back()?);
    if let Ok(p) = facet.slab(&material) {
        f.warn_unused_back_shape_factor(&p.back);
    }
    Ok(Setup {
        materials: vec![material],
        facet,
        time: until,
    })
}

/// Scene-form options shared by `sensitivity`, `calibrate` and `diurnal`.
#[derive(Debug, Clone, clap::Args)]
pub struct SceneArgs {
    /// Sensor whose image the points and sample pixels refer to (default:
    /// the scene's first).
    #[arg(long, value_name = "NAME")]
    pub sensor: Option<String>,
    /// Ray-tracing backend: embree, embree-single or obvhs.
    #[arg(long, default_value = "embree", value_name = "NAME")]
    pub backend: Backend,
}

impl SceneArgs {
    /// Open the scene's render session and pick the sensor.
    pub(crate) fn open(&self, scene: &Path) -> anyhow::Result<(Session, usize)> {
        let session = Session::open(scene, self.backend)?;
        let s = match &self.sensor {
            None => 0,
            Some(n) => session
                .sensor_index(n)
                .for_flags(&[("sensor", "--sensor")])
                .with_context(|| format!("in {}", scene.display()))?,
        };
        Ok((session, s))
    }
}

/// Truth or validation points of a CSV file as sample pixels of sensor `s`
/// (lat/lon converted through the scene's site and the sensor).
pub(crate) fn pixel_points(
    session: &Session,
    s: usize,
    file: &Path,
) -> anyhow::Result<(Vec<PixelPoint>, Vec<TruthPoint>)> {
    let pts = csv::read_truth_points(file)?;
    let pts = geo::points_to_pixels(session, s, &pts, file)?;
    let px = pts
        .iter()
        .map(|p| match p.position {
            PointPosition::Pixel { x, y } => PixelPoint {
                label: p.id.clone(),
                x,
                y,
            },
            PointPosition::LatLon { .. } => unreachable!("converted above"),
        })
        .collect();
    Ok((px, pts))
}

/// A study: one-facet (`--thermal`) or on a scene.
pub(crate) enum Study {
    /// One free-standing facet per material.
    Facet(Box<MaterialStudy>),
    /// Sample pixels of a scene, per-facet inputs traced once.
    Scene(Box<SceneStudy>),
}

impl Study {
    pub(crate) fn params(&self) -> &ParamSet {
        match self {
            Study::Facet(s) => &s.params,
            Study::Scene(s) => &s.params,
        }
    }
    pub(crate) fn output_names(&self) -> Vec<String> {
        match self {
            Study::Facet(s) => s.output_names(),
            Study::Scene(s) => s.output_names(),
        }
    }
    pub(crate) fn evaluate(&self, x: &[f64]) -> irsig::Result<Vec<f64>> {
        match self {
            Study::Facet(s) => s.evaluate(x),
            Study::Scene(s) => s.evaluate(x),
        }
    }
    pub(crate) fn time(&self) -> String {
        match self {
            Study::Facet(s) => s.facet.records[s.time_index].time.to_rfc3339(),
            Study::Scene(s) => s.time.to_rfc3339(),
        }
    }
    /// Suffix of the outputs the tornado plot shows.
    fn plotted(&self) -> &'static str {
        match self {
            Study::Facet(_) => ".surface_temperature_k",
            Study::Scene(_) => ".apparent_temperature_k",
        }
    }
}

/// Arguments of `irsig sensitivity`.
#[derive(Debug, clap::Args)]
#[command(after_long_help = "\
Scene form: at sample pixels of the scene's sensor image (--points POINTS.csv
with x,y or lat,lon columns: one output group per point; default: up to
--per-material pixels per material, averaged per material), the change of the
surface temperature (K), the apparent temperature (K) and the band radiance at
the sensor (W/m2/sr) at the image time, for each parameter of PARAMS.json,
ranked. The scene's per-facet solar history, shape factor and background are
traced once; each evaluation re-solves the slab model of the facets under the
pixels (and their neighbours) and shades the pixels through the render's
radiometry. --thermal: one free-standing facet per material (surface
temperature and surface-leaving 8-14 um radiance).

  oat     each parameter at its low and high bound, the others nominal
  morris  Morris elementary effects: mu* (mean |effect|), mu, sigma, per full range

The error budget multiplies each parameter's standard uncertainty by the
output's sensitivity and combines them root-sum-square.

Examples:
  irsig sensitivity scenes/town/scene.json --params params.json --plot tornado.png
  irsig sensitivity --thermal --material asphalt --weather w.csv --time 2024-06-21T14:00:00-04:00 \\
      --params params.json --method morris --json")]
pub struct Args {
    /// Scene file (omit with --thermal).
    pub scene: Option<PathBuf>,
    /// Parameters with bounds (JSON; see the analysis docs).
    #[arg(long, value_name = "PARAMS.json")]
    pub params: PathBuf,
    /// Method.
    #[arg(long, value_enum, default_value = "oat")]
    pub method: Method,
    /// Morris trajectories.
    #[arg(long, default_value_t = 20, value_name = "R")]
    pub trajectories: usize,
    /// Morris grid levels (even).
    #[arg(long, default_value_t = 4, value_name = "P")]
    pub levels: usize,
    /// Morris random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Image time (default: the scene's; required with --thermal).
    #[arg(long, value_name = "RFC3339")]
    pub time: Option<String>,
    #[command(flatten)]
    pub one: ThermalArgs,
    #[command(flatten)]
    pub facet: FacetArgs,
    #[command(flatten)]
    pub scene_args: SceneArgs,
    /// Validation points (scene form; CSV `x,y` or `lat,lon`, optional `id`).
    #[arg(long, value_name = "POINTS.csv")]
    pub points: Option<PathBuf>,
    /// Sample pixels per material without --points (scene form).
    #[arg(long, default_value_t = 4, value_name = "N")]
    pub per_material: usize,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Bars in the tornado plot (the largest effects).
    #[arg(long, default_value_t = 24, value_name = "N")]
    pub plot_bars: usize,
    /// Write a tornado plot (apparent temperatures; surface temperatures
    /// with --thermal).
    #[arg(long, value_name = "OUT.png")]
    pub plot: Option<PathBuf>,
}

/// Sensitivity method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// One at a time (low/high bounds).
    Oat,
    /// Morris elementary effects.
    Morris,
}

#[derive(Serialize)]
struct Report {
    method: &'static str,
    time: String,
    outputs: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    oat: Option<Oat>,
    #[serde(skip_serializing_if = "Option::is_none")]
    morris: Option<Morris>,
    error_budget: Vec<ErrorBudget>,
    /// Scene form: the sample pixels (label, x, y).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    points: Vec<(String, f64, f64)>,
}

/// What the sample pixels of a scene study are.
pub(crate) enum Samples<'a> {
    /// Points of a CSV file (one output group each).
    Points(&'a Path),
    /// Up to this many pixels per material (one group per material).
    PerMaterial(usize),
}

pub(crate) fn build_study(
    scene: Option<&PathBuf>,
    one: &ThermalArgs,
    facet_args: &FacetArgs,
    scene_args: &SceneArgs,
    samples: Samples<'_>,
    time: Option<&str>,
    params: &std::path::Path,
) -> anyhow::Result<Study> {
    let time = time.map(|t| parse_time("--time", t)).transpose()?;
    match (scene, one.thermal) {
        (Some(_), true) => anyhow::bail!("give either SCENE.json or --thermal, not both"),
        (None, false) => {
            anyhow::bail!("give a SCENE.json, or --thermal --material … --weather … --time …")
        }
        (None, true) => {
            let setup = setup_thermal(one, facet_args, time.context("--thermal needs --time")?)?;
            let params = ParamSet::load(params, &setup.materials)?;
            let time_index = setup.facet.index_at(setup.time)?;
            Ok(Study::Facet(Box::new(MaterialStudy {
                facet: setup.facet,
                materials: setup.materials,
                params,
                time_index,
            })))
        }
        (Some(p), false) => {
            let (session, s) = scene_args.open(p)?;
            let time = time.unwrap_or(session.scene.time);
            let params = ParamSet::load(params, session.scene.materials.materials())?;
            let (points, groups) = match samples {
                Samples::Points(file) => (pixel_points(&session, s, file)?.0, Vec::new()),
                Samples::PerMaterial(n) => scene_study::material_samples(&session, s, n),
            };
            anyhow::ensure!(
                !points.is_empty(),
                "{}: sensor `{}` sees no facet that uses the thermal model",
                p.display(),
                session.sensors[s].name
            );
            let study = SceneStudy::new(session, s, time, params, points, groups)?;
            Ok(Study::Scene(Box::new(study)))
        }
    }
}

/// Run `irsig sensitivity`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let samples = match &args.points {
        Some(p) => Samples::Points(p),
        None => Samples::PerMaterial(args.per_material),
    };
    let study = build_study(
        args.scene.as_ref(),
        &args.one,
        &args.facet,
        &args.scene_args,
        samples,
        args.time.as_deref(),
        &args.params,
    )?;
    let factors = study.params().factors();
    let outputs = study.output_names();
    let model = |x: &[f64]| study.evaluate(x);
    let time = study.time();
    let plotted = study.plotted();
    let mut report = Report {
        method: match args.method {
            Method::Oat => "oat",
            Method::Morris => "morris",
        },
        time,
        outputs: outputs.clone(),
        oat: None,
        morris: None,
        error_budget: Vec::new(),
        points: match &study {
            Study::Scene(s) => s
                .points
                .iter()
                .map(|p| (p.label.clone(), p.x, p.y))
                .collect(),
            Study::Facet(_) => Vec::new(),
        },
    };
    let mut bars;
    match args.method {
        Method::Oat => {
            let oat = sensitivity::one_at_a_time(&factors, &outputs, &model)?;
            let s: Vec<Vec<f64>> = oat
                .effects
                .iter()
                .map(|o| o.iter().map(|e| e.per_unit).collect())
                .collect();
            report.error_budget = sensitivity::error_budget(&factors, &outputs, &s);
            bars = tornado_bars(&outputs, plotted, &factors, &oat.effects, |e| {
                (e.swing() > 0.0).then_some((e.at_low, e.at_high))
            });
            report.oat = Some(oat);
        }
        Method::Morris => {
            let opts = MorrisOptions {
                trajectories: args.trajectories,
                levels: args.levels,
                seed: args.seed,
            };
            let m = sensitivity::morris(&factors, &outputs, &model, opts)
                .for_flags(&[("levels", "--levels"), ("trajectories", "--trajectories")])?;
            let s: Vec<Vec<f64>> = m
                .effects
                .iter()
                .map(|o| o.iter().map(|e| e.mu_star_per_unit).collect())
                .collect();
            report.error_budget = sensitivity::error_budget(&factors, &outputs, &s);
            bars = tornado_bars(&outputs, plotted, &factors, &m.effects, |e| {
                (e.mu_star > 0.0).then_some((e.mu, e.mu_star))
            });
            report.morris = Some(m);
        }
    }
    if let Some(p) = &args.plot {
        let (title, legend) = match args.method {
            Method::Oat => (
                if plotted.contains("apparent") {
                    "Apparent temperature change at the parameter bounds"
                } else {
                    "Surface temperature change at the parameter bounds"
                },
                ["low bound", "high bound"],
            ),
            Method::Morris => (
                "Morris elementary effects per full range",
                ["mu (signed mean)", "mu* (mean |effect|)"],
            ),
        };
        let total = bars.len();
        bars.sort_by(|a, b| {
            let m = |t: &TornadoBar| t.at_low.abs().max(t.at_high.abs());
            m(b).total_cmp(&m(a))
        });
        bars.truncate(args.plot_bars.max(1));
        let title = if total > bars.len() {
            format!("{title} (largest {} of {total})", bars.len())
        } else {
            title.to_string()
        };
        plot::tornado(p, &title, "ΔT (K)", legend, &bars)?;
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    outln!("sensitivity ({}) at {}", report.method, report.time);
    if let Study::Scene(s) = &study {
        let (sampled, neighbours) = s.facet_counts();
        outln!(
            "scene study: {} sample pixels of sensor `{}`; per evaluation {sampled} facets under them and {neighbours} neighbours re-solved",
            s.points.len(),
            s.session.sensors[s.sensor].name
        );
    }
    for (o, name) in outputs.iter().enumerate() {
        outln!("{name}:");
        if let Some(oat) = &report.oat {
            outln!("  nominal {:.4}", oat.nominal_outputs[o]);
            for i in oat.ranking(o) {
                let e = &oat.effects[o][i];
                outln!(
                    "  {:<40} low {:+10.4}  high {:+10.4}  per unit {:+.4e}",
                    factors[i].name,
                    e.at_low,
                    e.at_high,
                    e.per_unit
                );
            }
        }
        if let Some(m) = &report.morris {
            for i in m.ranking(o) {
                let e = &m.effects[o][i];
                outln!(
                    "  {:<40} mu* {:10.4}  mu {:+10.4}  sigma {:10.4}",
                    factors[i].name,
                    e.mu_star,
                    e.mu,
                    e.sigma
                );
            }
        }
        let b = &report.error_budget[o];
        outln!(
            "  estimated error (RSS of uncertainty × sensitivity): {:.4}",
            b.combined
        );
    }
    Ok(())
}

/// One tornado bar per (plotted output, factor) whose effect `bar` keeps:
/// `bar` gives the bar's two ends (low/high bound, or Morris μ/μ*).
fn tornado_bars<E>(
    outputs: &[String],
    plotted: &str,
    factors: &[sensitivity::Factor],
    effects: &[Vec<E>],
    bar: impl Fn(&E) -> Option<(f64, f64)>,
) -> Vec<TornadoBar> {
    let mut bars = Vec::new();
    for (o, name) in outputs
        .iter()
        .enumerate()
        .filter(|(_, n)| n.ends_with(plotted))
    {
        let mat = name.trim_end_matches(plotted);
        for (i, e) in effects[o].iter().enumerate() {
            if let Some((at_low, at_high)) = bar(e) {
                bars.push(TornadoBar {
                    name: format!("{mat}: {}", factors[i].name),
                    at_low,
                    at_high,
                });
            }
        }
    }
    bars
}
