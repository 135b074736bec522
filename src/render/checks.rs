//! Checks of a scene that need its sensors and a tracer (the scene module
//! knows neither): what each sensor sees. They return warnings as text (the
//! command line prints them as `warning:` lines); nothing is printed here.

use crate::scene::Scene;

/// Rays per side of the coarse grid [`view_warnings`] traces per sensor.
const VIEW_GRID: usize = 16;

/// Warnings for sensors that would image nothing useful: none of a
/// [`VIEW_GRID`]² grid of their primary rays (evenly spread over rows and
/// columns) hits the scene, or every ray that hits meets the back of a face
/// (the sensor sits inside a closed object, named by the first hit).
pub fn view_warnings(
    scene: &Scene,
    sensors: &[crate::sensor::Sensor],
    tracer: &dyn crate::trace::Tracer,
) -> Vec<String> {
    let mut out = Vec::new();
    for s in sensors {
        let (w, h) = (s.rays_per_row(), s.height());
        if w == 0 || h == 0 {
            continue;
        }
        let mut rays = Vec::new();
        let mut row = Vec::new();
        for k in 0..VIEW_GRID {
            row.clear();
            s.rays_for_row(((2 * k + 1) * h / (2 * VIEW_GRID)).min(h - 1), &mut row);
            let n = row.len();
            rays.extend(
                (0..VIEW_GRID).map(|j| row[((2 * j + 1) * n / (2 * VIEW_GRID)).min(n - 1)]),
            );
        }
        let mut hits = vec![None; rays.len()];
        tracer.intersect(&rays, crate::trace::Coherence::Incoherent, &mut hits);
        let front: Vec<_> = rays
            .iter()
            .zip(&hits)
            .filter_map(|(r, h)| h.map(|h| (h, h.ng.dot(r.dir) < 0.0)))
            .collect();
        let field = format!("{}: sensor `{}`", scene.path.display(), s.name);
        if front.is_empty() {
            out.push(format!(
                "{field} sees no scene geometry (none of a {VIEW_GRID}×{VIEW_GRID} grid of its rays \
                 hits anything): check its position and pointing"
            ));
        } else if front.iter().all(|(_, f)| !f) {
            let inst = front[0].0.instance as usize;
            let name = scene
                .instance_object
                .get(inst)
                .and_then(|&o| scene.objects.get(o))
                .map_or("?", |o| o.name.as_str());
            out.push(format!(
                "{field} sees only the backs of faces: is it inside object `{name}`?"
            ));
        }
    }
    out
}

/// The errors `render` would stop on before its first pixel, found without
/// rendering, for `scene check`: the render sections
/// ([`super::sections::parse`]: `render`, `atmosphere`, `sensors` and their
/// response files), a missing weather history, image times whose thermal
/// history window (the spin-up before the first image time,
/// [`crate::exposure::HistoryWindow`]) the weather does not cover, the
/// materials' thermal setup, and the atmosphere at each image time (a tape7
/// index that cannot be read). `times`: the image times (empty: the
/// scene's). Errors name the scene file and field; at most one per kind.
pub fn render_problems(
    scene: &Scene,
    times: &[chrono::DateTime<chrono::FixedOffset>],
) -> Vec<crate::Error> {
    let lines = std::cell::OnceCell::new();
    problems(scene, times)
        .into_iter()
        .map(|e| super::sections::locate(e, &scene.path, &lines))
        .collect()
}

fn problems(scene: &Scene, times: &[chrono::DateTime<chrono::FixedOffset>]) -> Vec<crate::Error> {
    use crate::{Error, Location};
    let file = Location::file(&scene.path);
    let mut errors = Vec::new();
    let sections = super::sections::parse(scene)
        .map_err(|e| errors.push(e))
        .ok();
    if let Err(e) = super::scene_thermal::FacetThermalSetup::from_scene(scene) {
        errors.push(e);
    }
    let Some(weather) = &scene.weather else {
        errors.push(Error::parse(
            file.with_field("weather"),
            "missing: a render needs a weather history (`\"weather\": {\"file\": …}`)",
        ));
        return errors;
    };
    let given = !times.is_empty();
    let times = if given {
        times.to_vec()
    } else {
        vec![scene.time]
    };
    let window = super::scene_thermal::SceneThermalParams::default().window;
    if let Err(e) = crate::exposure::history_times(&weather.history, &times, &window) {
        let message = match e {
            Error::Invalid { message, .. } => message,
            other => other.to_string(),
        };
        // The scene's `time`, or the image times the caller gave.
        errors.push(if given {
            Error::invalid("image times", message)
        } else {
            Error::parse(file.clone().with_field("time"), message)
        });
        return errors;
    }
    if let Some(s) = &sections {
        for t in &times {
            let made = weather
                .history
                .at(*t)
                .and_then(|rec| super::session::atmosphere_at(&s.atmosphere, scene, &rec));
            if let Err(e) = made {
                errors.push(e);
                break;
            }
        }
    }
    errors
}
