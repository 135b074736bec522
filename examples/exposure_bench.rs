//! Throughput of the per-facet pipeline (solar history + sky view rays, then
//! the two-pass thermal solve), on a scene file (its parts, weather, site and
//! image time) or on a procedural town: terrain of asphalt-like ground with
//! brick box buildings, the town's synthetic June weather (Rochester NY),
//! image at 14:00 local time; 24 h history either way.
//!
//! Run: `cargo run --release --example exposure_bench -- [SCENE.json | TRIANGLES] [BACKEND] [SKY]`
//! (defaults scenes/town/scene.json, embree, dirsig; SKY = dirsig |
//! grid:DZxDA | stratified:N).
//!
//! The rays are traced as a render traces them: with Embree on a
//! non-watertight scene ([`Watertight::No`], `Session::exposure_tracer`).
//!
//! The facets on the ground get the deep-ground back boundary
//! ([`SceneThermalParams::ground`], the default); `IRSIG_BENCH_GROUND=0`
//! solves them with their materials' insulated backs instead.
//!
//! With `IRSIG_BENCH_COMPARE=1` (scene files only) the thermal passes are
//! solved again with the fine reference ([`ThermalParams::fine_reference`]:
//! per class, fine dedup quanta, `SolveOptions::default()`) and with other
//! settings (linearized bin widths and orders, the old per-class default),
//! and the RMS and max difference of the image-time surface temperatures
//! from the reference are printed.
//!
//! With `IRSIG_BENCH_THERMAL_ROUNDS=N` the thermal passes are solved N more
//! times on the same exposure (no rays) and the best setup and solve time
//! of each pass, and the best total, are printed: steadier numbers on a
//! busy machine than one run's.

use std::path::Path;
use std::time::Instant;

use chrono::DateTime;
use irsig::exposure::SkySampling;
use irsig::geometry::procedural::{TerrainParams, generate};
use irsig::render::scene_thermal::{
    FacetThermalSetup, SceneThermal, SceneThermalParams, solve_scene, solve_scene_temperatures,
};
use irsig::scene::Scene;
use irsig::thermal::scene::{
    Dedup, FacetThermal, LinearizedParams, SceneTemperatures, ThermalMethod, ThermalParams,
    solve_facet_temperatures,
};
use irsig::thermal::{BackBoundary, Forcing, SlabProperties};
use irsig::trace::{self, Backend, Watertight};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let what = args
        .first()
        .map_or("scenes/town/scene.json", String::as_str);
    let backend: Backend = args.get(1).map_or(Ok(Backend::Embree), |s| s.parse())?;
    let sky: SkySampling = args.get(2).map_or(Ok(SkySampling::DIRSIG), |s| s.parse())?;
    rayon::ThreadPoolBuilder::new().build_global()?;
    let params = SceneThermalParams {
        exposure: irsig::exposure::ExposureParams {
            sky,
            ..Default::default()
        },
        ground: std::env::var("IRSIG_BENCH_GROUND").map_or(true, |v| v != "0"),
        ..Default::default()
    };

    let t0 = Instant::now();
    let (geo, r, tracer_name, build) = if what.ends_with(".json") {
        let scene = Scene::load(Path::new(what))?;
        let load = t0.elapsed();
        let t1 = Instant::now();
        let tracer = trace::build_with(&scene.geometry, backend, Watertight::No)?;
        let build = t1.elapsed();
        println!("scene {what} loaded in {:.2} s", load.as_secs_f64());
        let r = solve_scene(&*tracer, &scene, &[], &params)?;
        (scene.geometry, r, tracer.name().to_string(), build)
    } else {
        let geo = generate(&TerrainParams::with_triangles(what.parse()?, 7));
        let tracer = trace::build_with(&geo, backend, Watertight::No)?;
        let build = t0.elapsed();
        let (weather, _) = irsig::weather::synth::town_history()?;
        let site = *weather.site().expect("town weather has a site");
        let ground = SlabProperties {
            conductivity_w_m_k: 0.75,
            density_kg_m3: 2100.0,
            specific_heat_j_kg_k: 920.0,
            thickness_m: 0.1,
            solar_absorptivity: 0.9,
            thermal_emissivity: 0.95,
            self_power_w_m2: 0.0,
            back: BackBoundary::GROUND,
            surface: None,
            convection: irsig::material::ConvectionSpec::MCADAMS,
            layers: irsig::thermal::Layers::NONE,
        };
        let brick = SlabProperties {
            conductivity_w_m_k: 0.7,
            density_kg_m3: 1900.0,
            specific_heat_j_kg_k: 840.0,
            thickness_m: 0.2,
            solar_absorptivity: 0.65,
            thermal_emissivity: 0.9,
            self_power_w_m2: 0.0,
            back: BackBoundary::BUILDING,
            surface: None,
            convection: irsig::material::ConvectionSpec::MCADAMS,
            layers: irsig::thermal::Layers::NONE,
        };
        let offsets = geo.facet_offsets();
        let setup = FacetThermalSetup {
            kinds: (0..geo.facet_count())
                .map(|f| FacetThermal::Solve((f >= offsets[1]) as u32))
                .collect(),
            props: vec![ground, brick],
            ..Default::default()
        };
        let image = DateTime::parse_from_rfc3339("2025-06-21T14:00:00-04:00")?;
        let r =
            solve_scene_temperatures(&*tracer, &geo, &setup, &weather, &site, &[image], &params)?;
        (geo, r, tracer.name().to_string(), build)
    };

    let n = geo.facet_count();
    let s = &r.exposure.stats;
    let tm = &r.timings;
    println!(
        "{n} facets ({} instances), {} records; backend {tracer_name}, sky {:?}, {} threads",
        geo.instances.len(),
        r.times.len(),
        params.exposure.sky,
        rayon::current_num_threads()
    );
    println!("build (geometry + BVH): {:.2} s", build.as_secs_f64());
    println!(
        "{} facets on the ground (deep-ground back boundary)",
        r.ground_facets
    );
    println!(
        "rays: {:.2} s — solar {:.1} M rays in {:.2} s ({:.2} Mrays/s), sky {:.1} M rays in {:.2} s ({:.2} Mrays/s)",
        tm.rays.as_secs_f64(),
        s.solar_rays as f64 * 1e-6,
        s.solar.as_secs_f64(),
        s.solar_rays as f64 * 1e-6 / s.solar.as_secs_f64(),
        s.sky_rays as f64 * 1e-6,
        s.sky.as_secs_f64(),
        s.sky_rays as f64 * 1e-6 / s.sky.as_secs_f64(),
    );
    for (i, p) in r.temperatures.passes.iter().enumerate() {
        println!(
            "thermal pass {}: {} facets in {} classes, setup {:.2} s, solve {:.2} s; spin-up change ≤ {:.3} K{}",
            i + 1,
            p.solved_facets,
            p.classes,
            p.setup.as_secs_f64(),
            p.solve.as_secs_f64(),
            p.max_spinup_change_k,
            p.max_change_from_previous_pass_k
                .map_or(String::new(), |c| format!(
                    ", ≤ {c:.2} K from the previous pass"
                ))
        );
    }
    println!(
        "total {:.2} s (setup {:.2}, rays {:.2}, thermal {:.2}): {:.0} facets/s",
        tm.total().as_secs_f64(),
        tm.setup.as_secs_f64(),
        tm.rays.as_secs_f64(),
        tm.thermal.as_secs_f64(),
        r.facets_per_second()
    );
    let t = r.surface_temperature_k(0);
    let (lo, hi) = t
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    println!(
        "surface temperatures at {}: {lo:.1} – {hi:.1} K",
        r.image_times[0].to_rfc3339()
    );
    if let Some(rounds) = std::env::var("IRSIG_BENCH_THERMAL_ROUNDS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
    {
        thermal_rounds(&r, &params.thermal, rounds)?;
    }
    if std::env::var_os("IRSIG_BENCH_COMPARE").is_some() && what.ends_with(".json") {
        compare(&r, &r.setup)?;
    }
    Ok(())
}

/// Solves the thermal passes of `r` again `rounds` times (same exposure,
/// setup and parameters) and prints the best time of each stage.
fn thermal_rounds(r: &SceneThermal, params: &ThermalParams, rounds: usize) -> anyhow::Result<()> {
    let forcing = Forcing::from_records(&r.records)?;
    let images = &r.temperatures.image_records;
    let setup = &r.setup;
    let mut best_total = f64::INFINITY;
    let mut best: Vec<(f64, f64)> = Vec::new();
    for _ in 0..rounds {
        let t = Instant::now();
        let s = solve_facet_temperatures(
            &r.exposure,
            &setup.kinds,
            &setup.props,
            &forcing,
            images,
            params,
        )?;
        best_total = best_total.min(t.elapsed().as_secs_f64());
        best.resize(s.passes.len(), (f64::INFINITY, f64::INFINITY));
        for (b, p) in best.iter_mut().zip(&s.passes) {
            b.0 = b.0.min(p.setup.as_secs_f64());
            b.1 = b.1.min(p.solve.as_secs_f64());
        }
    }
    for (i, (setup, solve)) in best.iter().enumerate() {
        println!(
            "best of {rounds} thermal solves, pass {}: setup {setup:.3} s, solve {solve:.3} s",
            i + 1
        );
    }
    println!("best of {rounds} thermal solves: total {best_total:.3} s");
    Ok(())
}

/// Re-solves the thermal passes of `r` with the fine quanta (reference) and
/// with the fast slab options, and prints their time and the difference of
/// the image-time temperatures.
fn compare(r: &SceneThermal, setup: &FacetThermalSetup) -> anyhow::Result<()> {
    let forcing = Forcing::from_records(&r.records)?;
    let images = &r.temperatures.image_records;
    let solve = |p: &ThermalParams| {
        let t = Instant::now();
        let s =
            solve_facet_temperatures(&r.exposure, &setup.kinds, &setup.props, &forcing, images, p)?;
        anyhow::Ok((s, t.elapsed().as_secs_f64()))
    };
    let (reference, t_ref) = solve(&ThermalParams::fine_reference())?;
    let report = |name: &str, s: &SceneTemperatures, secs: f64| {
        let (a, b) = (
            &s.surface_temperature_k[0],
            &reference.surface_temperature_k[0],
        );
        let n = a.len() as f64;
        let (sq, max) = a.iter().zip(b).fold((0.0f64, 0.0f64), |(sq, m), (x, y)| {
            let d = (x - y).abs() as f64;
            (sq + d * d, m.max(d))
        });
        let classes: Vec<usize> = s.passes.iter().map(|p| p.classes).collect();
        println!(
            "{name}: thermal {secs:.2} s, classes/references per pass {classes:?}; vs fine: RMS {:.3} K, max {max:.3} K",
            (sq / n).sqrt()
        );
    };
    report(
        "fine quanta + SolveOptions::default() (reference)",
        &reference,
        t_ref,
    );
    report(
        "this run's settings",
        &r.temperatures,
        r.timings.thermal.as_secs_f64(),
    );
    let lin = |bin_k: f32, second_order: bool| ThermalParams {
        method: ThermalMethod::Linearized(LinearizedParams {
            bin_k,
            second_order,
            ..Default::default()
        }),
        ..Default::default()
    };
    for (name, p) in [
        (
            "linearized, bins 3 K, first order (default)",
            lin(3.0, false),
        ),
        ("linearized, bins 3 K, second order", lin(3.0, true)),
        ("linearized, bins 1 K, first order", lin(1.0, false)),
        ("linearized, bins 6 K, first order", lin(6.0, false)),
        ("linearized, bins 6 K, second order", lin(6.0, true)),
        ("linearized, bins 12 K, second order", lin(12.0, true)),
        (
            "linearized, one reference per material, second order",
            lin(1e4, true),
        ),
        (
            "linearized, one reference per material, first order",
            lin(1e4, false),
        ),
        (
            "per class, default quanta + scene_options (old default)",
            ThermalParams::per_class(Some(Dedup::default()), ThermalParams::scene_options()),
        ),
    ] {
        let (s, t) = solve(&p)?;
        report(name, &s, t);
    }
    Ok(())
}
