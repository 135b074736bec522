//! `irsig bench exposure`: the per-facet rays of a render (solar history
//! and sky view) under several sampling settings, each against an
//! exhaustive reference: rays, time, facets/s and accuracy.
//!
//! The reference traces the sun at every step of the history window and
//! the sky with many stratified rays (`--reference`). Accuracy is the share
//! of (facet, step) sun fractions that differ from the reference, and the
//! RMS and mean error of the shape factor F over facets, and the RMS and
//! largest error of the surface temperatures at the scene's time that the
//! thermal solve makes of them (the render's thermal settings).
//!
//! Besides the wall time it reports the CPU time of the timed part (all
//! threads, from `/proc/self/stat`): on a shared, loaded machine the wall
//! time mostly measures the load, the CPU time the work.

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use anyhow::Context;
use irsig::exposure::reflected::{BOUNCES, GROUND_ALBEDO};
use irsig::exposure::{
    Exposure, ExposureParams, HistoryWindow, SkySampling, compute_exposure, history_times,
    sun_directions,
};
use irsig::render::scene_thermal::FacetThermalSetup;
use irsig::scene::Scene;
use irsig::thermal::Forcing;
use irsig::thermal::scene::{ThermalParams, solve_facet_temperatures};
use irsig::trace::{self, Backend, Watertight};

/// One setting's line of the report.
struct Line {
    name: String,
    exposure: Exposure,
    seconds: f64,
    /// CPU seconds of the same round (all threads), when known.
    cpu: Option<f64>,
}

/// CPU seconds (user + system, all threads) this process has used so far,
/// from `/proc/self/stat` (Linux; its clock ticks are 1/100 s, the
/// `USER_HZ` of every mainstream Linux architecture); `None` where there is
/// no such file.
fn process_cpu_seconds() -> Option<f64> {
    cpu_seconds_of_stat(&std::fs::read_to_string("/proc/self/stat").ok()?)
}

/// User + system CPU seconds in the text of a `/proc/PID/stat` file
/// (`proc(5)`: fields 14 and 15, `utime` and `stime`, in clock ticks of
/// 1/100 s); `None` when the text does not have them.
fn cpu_seconds_of_stat(stat: &str) -> Option<f64> {
    // Fields after the command name (which may hold spaces and parentheses,
    // so split after the last `)`): state, ppid, …; utime and stime are the
    // 12th and 13th of them.
    let f: Vec<&str> = stat[stat.rfind(')')? + 1..].split_whitespace().collect();
    let ticks = f.get(11)?.parse::<u64>().ok()? + f.get(12)?.parse::<u64>().ok()?;
    Some(ticks as f64 / 100.0)
}

/// Runs the benchmark on `scene` with `backend`: every setting in
/// `settings` (name, parameters), best of `rounds`, then the reference
/// with `reference` sky sampling; prints a table.
pub fn run(
    scene: &Path,
    backend: Backend,
    rounds: usize,
    reference: SkySampling,
    settings: &[(String, ExposureParams)],
) -> anyhow::Result<()> {
    let scene = Scene::load(scene).with_context(|| format!("loading {}", scene.display()))?;
    let weather = &scene
        .weather
        .as_ref()
        .context("the scene has no weather history")?
        .history;
    let times = history_times(weather, &[scene.time], &HistoryWindow::default())?;
    let sun = sun_directions(&scene.site, &times)?;
    let setup = FacetThermalSetup::from_scene(&scene)?;
    let tracer = trace::build_with(&scene.geometry, backend, Watertight::No)?;
    let exact = trace::build(&scene.geometry, backend)?;
    let geo = &scene.geometry;
    let records = times
        .iter()
        .map(|&t| weather.at(t))
        .collect::<irsig::Result<Vec<_>>>()?;
    let forcing = Forcing::from_records(&records)?;
    let last = times.len() - 1;
    // The surface temperatures at the scene's time from an exposure, as a
    // render solves them (ground facets found once, on the reference).
    let mut ground_setup: Option<FacetThermalSetup> = None;
    let mut temperatures = |e: &Exposure| -> anyhow::Result<Vec<f32>> {
        let s = ground_setup
            .get_or_insert_with(|| setup.with_ground(&setup.ground_facets(&*exact, &e.facets)));
        let mut t = solve_facet_temperatures(
            e,
            &s.kinds,
            &s.props,
            &forcing,
            &[last],
            &ThermalParams::default(),
        )?;
        Ok(t.surface_temperature_k.remove(0))
    };
    let n = geo.facet_count();
    let albedo = setup.facet_albedo();
    let time_it = |p: &ExposureParams| -> anyhow::Result<(Exposure, f64, Option<f64>)> {
        let mut best: Option<(Exposure, f64, Option<f64>)> = None;
        for _ in 0..rounds {
            let c0 = process_cpu_seconds();
            let t0 = Instant::now();
            let e = compute_exposure(&*tracer, geo, &setup.double_sided, &sun, p)?;
            let e = e.with_reflected(&albedo, GROUND_ALBEDO, &sun, BOUNCES)?;
            let s = t0.elapsed().as_secs_f64();
            let cpu = c0.zip(process_cpu_seconds()).map(|(a, b)| b - a);
            if best.as_ref().is_none_or(|b| s < b.1) {
                best = Some((e, s, cpu));
            }
        }
        Ok(best.expect("at least one round"))
    };
    let mut lines = Vec::new();
    for (name, p) in settings {
        let (exposure, seconds, cpu) = time_it(p)?;
        lines.push(Line {
            name: name.clone(),
            exposure,
            seconds,
            cpu,
        });
    }
    let reference_params = ExposureParams {
        sky: reference,
        solar_stride: 1,
        samples_per_edge: settings.first().map_or(1, |(_, p)| p.samples_per_edge),
        ..ExposureParams::default()
    };
    let (r, rs, _) = time_it(&reference_params)?;
    let tr = temperatures(&r)?;
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "irsig bench exposure: {}, {n} facets, {} history steps; {} threads; best of {rounds}",
        scene.path.display(),
        sun.len(),
        rayon::current_num_threads()
    )?;
    writeln!(
        out,
        "reference: sun at every step, sky {reference:?}: {:.2} s ({:.1} M solar + {:.1} M sky rays)",
        rs,
        r.stats.solar_rays as f64 * 1e-6,
        r.stats.sky_rays as f64 * 1e-6
    )?;
    writeln!(
        out,
        "{:<26} {:>9} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>11} {:>12} {:>8} {:>10} {:>8} {:>8}",
        "setting",
        "solar Mr",
        "sky Mr",
        "time s",
        "cpu s",
        "setup s",
        "solar s",
        "sky s",
        "refl s",
        "facets/s",
        "sun differs",
        "F rms",
        "F mean err",
        "T rms K",
        "T max K"
    )?;
    for l in &lines {
        let e = &l.exposure;
        let (mut differ, mut day) = (0u64, 0u64);
        // Both histories hold the same day records and sample points, so
        // their lit counts compare entry by entry.
        for (a, b) in e.solar.lit.iter().zip(&r.solar.lit) {
            differ += (a != b) as u64;
        }
        let mut cos = vec![0.0f32; r.solar.steps];
        for f in 0..r.solar.facet_count() {
            r.solar.cos_incidence_into(f, &mut cos);
            day += cos.iter().filter(|&&c| c > 0.0).count() as u64;
        }
        let (mut se, mut me) = (0.0f64, 0.0f64);
        for (a, b) in e.sky.shape_factor.iter().zip(&r.sky.shape_factor) {
            let d = (*a - *b) as f64;
            se += d * d;
            me += d;
        }
        let t = temperatures(e)?;
        let (mut ts, mut tm) = (0.0f64, 0.0f64);
        for (a, b) in t.iter().zip(&tr) {
            let d = (*a - *b) as f64;
            ts += d * d;
            tm = tm.max(d.abs());
        }
        writeln!(
            out,
            "{:<26} {:>9.2} {:>9.2} {:>8.3} {:>8} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>11.0} {:>11.4}% {:>8.4} {:>10.4} {:>8.3} {:>8.2}",
            l.name,
            e.stats.solar_rays as f64 * 1e-6,
            e.stats.sky_rays as f64 * 1e-6,
            l.seconds,
            l.cpu.map_or_else(|| "—".to_string(), |c| format!("{c:.2}")),
            e.stats.setup.as_secs_f64(),
            e.stats.solar.as_secs_f64(),
            e.stats.sky.as_secs_f64(),
            e.stats.reflected.as_secs_f64(),
            n as f64 / l.seconds.max(1e-9),
            100.0 * differ as f64 / day.max(1) as f64,
            (se / n.max(1) as f64).sqrt(),
            me / n.max(1) as f64,
            (ts / n.max(1) as f64).sqrt(),
            tm
        )?;
    }
    writeln!(
        out,
        "time: setup (sample points) + solar history + sky view + reflected shortwave ({BOUNCES} bounces), what facets/s counts"
    )?;
    writeln!(
        out,
        "cpu: CPU seconds of all threads over the same time (/proc/self/stat, 1/100 s); compare these on a loaded machine"
    )?;
    writeln!(
        out,
        "sun differs: share of the (facet, step) pairs with the sun in front whose sun fraction differs from the reference's"
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_seconds_are_utime_plus_stime() {
        // A process named `a) b` (a name may hold both), utime 250 and
        // stime 32 ticks: 2.82 s.
        let stat = "4242 (a) b) R 1 4242 4242 0 -1 4194304 1000 0 0 0 250 32 0 0 20 0 3 0 \
                    100 1000000 500";
        assert_eq!(cpu_seconds_of_stat(stat), Some(2.82));
        assert_eq!(cpu_seconds_of_stat("4242 (irsig) R 1 2"), None);
        assert_eq!(cpu_seconds_of_stat("garbage"), None);
        // This process's own counter reads and does not run backwards.
        if let Some(a) = process_cpu_seconds() {
            let b = process_cpu_seconds().expect("read once, reads again");
            assert!(b >= a);
        }
    }
}
