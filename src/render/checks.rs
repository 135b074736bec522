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
