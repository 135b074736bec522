//! The effect of each per-facet thermal term of issue 19 (reflected
//! shortwave, hemispherical emissivity, wind at each facet) on the bundled
//! town: the scene-wide solve at one time with everything on, then with each
//! term switched off in turn (`render.thermal` of a scene file:
//! [`irsig::render::scene_thermal::ThermalPhysics`]), and the mean and RMS
//! change of wall, road and roof temperatures.
//!
//! Run: `cargo run --release --example thermal_terms [SCENE] [TIME]`
//! (default `scenes/town/scene.json` at `2025-06-21T12:00:00-04:00`).

use std::path::Path;

use irsig::render::scene_thermal::{SceneThermalParams, ThermalPhysics, solve_scene};
use irsig::scene::Scene;
use irsig::trace::{self, Backend};

fn main() -> irsig::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).map_or("scenes/town/scene.json", String::as_str);
    let time = args
        .get(2)
        .map_or("2025-06-21T12:00:00-04:00", String::as_str);
    let time = chrono::DateTime::parse_from_rfc3339(time)
        .map_err(|e| irsig::Error::invalid("time", e.to_string()))?;
    let scene = Scene::load(Path::new(path))?;
    let tracer = trace::build(&scene.geometry, Backend::Embree)?;
    let run = |physics: ThermalPhysics| {
        let params = SceneThermalParams {
            physics,
            ..Default::default()
        };
        solve_scene(&*tracer, &scene, &[time], &params)
    };
    let on = ThermalPhysics::default();
    let all = run(on)?;
    let t_on = all.surface_temperature_k(0).to_vec();
    println!(
        "{path} at {time}: {} facets; thermal solve {:.2} s (setup {:.2} s, rays {:.2} s \
         of which reflected shortwave {:.3} s, passes {:.2} s)",
        t_on.len(),
        all.timings.total().as_secs_f64(),
        all.timings.setup.as_secs_f64(),
        all.timings.rays.as_secs_f64(),
        all.exposure.stats.reflected.as_secs_f64(),
        all.timings.thermal.as_secs_f64(),
    );
    // Classes of facets: walls (|n_z| < 0.3), roads (asphalt facing up on
    // the ground), roofs (facing up, 2 m or more above the lowest point).
    let parts = scene.facet_parts();
    let facets = &all.exposure.facets;
    let zmin = (0..facets.len())
        .flat_map(|f| facets.facet_points(f).iter().map(|p| p.z))
        .fold(f32::INFINITY, f32::min);
    let solved = |f: usize| scene.parts[parts[f] as usize].fixed_temperature_k.is_none();
    let class = |f: usize| -> Option<&'static str> {
        if !solved(f) {
            return None;
        }
        let n = facets.normal[f];
        let z = facets.facet_points(f)[0].z - zmin;
        let m = scene.part_material(parts[f] as usize);
        if n.z.abs() < 0.3 {
            Some("walls")
        } else if n.z > 0.9 && z >= 2.0 {
            Some("roofs")
        } else if n.z > 0.9 && m.name.contains("asphalt") {
            Some("roads")
        } else {
            None
        }
    };
    let stats = |a: &[f32], b: &[f32], which: &str| -> (f64, f64, usize) {
        let d: Vec<f64> = (0..a.len())
            .filter(|&f| class(f) == Some(which))
            .map(|f| (a[f] - b[f]) as f64)
            .collect();
        let n = d.len().max(1) as f64;
        let mean = d.iter().sum::<f64>() / n;
        let rms = (d.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
        (mean, rms, d.len())
    };
    let variants = [
        (
            "reflected shortwave",
            ThermalPhysics {
                reflected_bounces: 0,
                ..on
            },
        ),
        (
            "reflected: 1 bounce instead of the default",
            ThermalPhysics {
                reflected_bounces: 1,
                ..on
            },
        ),
        (
            "reflected: 10 bounces instead of the default",
            ThermalPhysics {
                reflected_bounces: 10,
                ..on
            },
        ),
        (
            "hemispherical emissivity",
            ThermalPhysics {
                hemispherical_emissivity: false,
                ..on
            },
        ),
        (
            "wind at each facet",
            ThermalPhysics {
                facet_wind: false,
                ..on
            },
        ),
        ("all three", ThermalPhysics::OFF),
    ];
    println!("term: change (with − without), K: mean / RMS over walls, roads, roofs");
    for (name, physics) in variants {
        let other = run(physics)?;
        let t = other.surface_temperature_k(0);
        let mut line = format!("{name}:");
        for which in ["walls", "roads", "roofs"] {
            let (mean, rms, n) = stats(&t_on, t, which);
            line += &format!(" {which} {mean:+.2} / {rms:.2} (n {n});");
        }
        println!(
            "{line} thermal solve {:.2} s",
            other.timings.total().as_secs_f64()
        );
    }
    Ok(())
}
