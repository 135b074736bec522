//! Throughput of the one-facet thermal solve: a 48-h history at 15-min steps
//! (193 records) of a synthetic clear diurnal cycle, solved repeatedly on one
//! thread for several materials and option presets.
//!
//! Run: `cargo run --release --example thermal_speed`

use irsig::thermal::{
    self, BackBoundary, FacetInputs, Forcing, STEFAN_BOLTZMANN_W_M2_K4, SlabProperties,
    SolveOptions,
};
use std::f64::consts::PI;
use std::hint::black_box;
use std::time::Instant;

fn main() {
    let times: Vec<f64> = (0..=192).map(|i| i as f64 * 900.0).collect();
    let mut forcing = Forcing::constant(&times, 288.0, 2.0, 0.0, 0.0, 0.0);
    let mut cos = Vec::new();
    for (i, &t) in times.iter().enumerate() {
        let hour = (t / 3600.0) % 24.0;
        let elev = (PI * (hour - 6.0) / 12.0).sin().max(0.0);
        let t_air = 288.0 + 6.0 * (2.0 * PI * (hour - 9.0) / 24.0).sin();
        forcing.air_temperature_k[i] = t_air;
        forcing.direct_normal_w_m2[i] = if elev > 0.0 {
            850.0 * elev.powf(0.3)
        } else {
            0.0
        };
        forcing.diffuse_horizontal_w_m2[i] = 100.0 * elev;
        forcing.sky_longwave_w_m2[i] = 0.75 * STEFAN_BOLTZMANN_W_M2_K4 * t_air.powi(4);
        cos.push(elev as f32);
    }
    let sun = vec![1.0f32; cos.len()];
    let inputs = FacetInputs::new(&sun, &cos, 1.0);
    let concrete = |back, thickness_m| SlabProperties {
        conductivity_w_m_k: 1.4,
        density_kg_m3: 2300.0,
        specific_heat_j_kg_k: 880.0,
        thickness_m,
        solar_absorptivity: 0.7,
        thermal_emissivity: 0.9,
        self_power_w_m2: 0.0,
        back,
        surface: None,
        convection: irsig::material::ConvectionSpec::MCADAMS,
        layers: irsig::thermal::Layers::NONE,
    };
    let aluminium = SlabProperties {
        conductivity_w_m_k: 200.0,
        density_kg_m3: 2700.0,
        specific_heat_j_kg_k: 900.0,
        thickness_m: 0.002,
        back: BackBoundary::BOTH_FACES,
        ..concrete(BackBoundary::Insulated, 0.002)
    };
    let materials = [
        ("concrete ground", concrete(BackBoundary::GROUND, 0.1)),
        ("concrete wall 0.2 m", concrete(BackBoundary::BUILDING, 0.2)),
        ("aluminium panel 2 mm", aluminium),
    ];
    let mut no_spinup = SolveOptions::default();
    no_spinup.spinup.max_cycles = 0;
    let presets = [
        ("default (spin-up ≤ 3 days)", SolveOptions::default()),
        ("default, no spin-up", no_spinup),
        ("fast", SolveOptions::fast()),
    ];
    println!("48 h history, 193 records at 15 min; one thread");
    for (pname, opts) in presets {
        for (mname, props) in &materials {
            // Warm up, then time for ~1 s.
            let reference = thermal::solve(props, &forcing, &inputs, &opts).unwrap();
            // Accuracy: largest difference on the second day from the
            // accurate preset.
            let exact =
                thermal::solve(props, &forcing, &inputs, &SolveOptions::accurate()).unwrap();
            let err = reference.surface_temperature_k[96..]
                .iter()
                .zip(&exact.surface_temperature_k[96..])
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            let start = Instant::now();
            let cpu_start = thread_cpu_s();
            let mut runs = 0u64;
            while start.elapsed().as_secs_f64() < 1.0 {
                for _ in 0..50 {
                    black_box(thermal::solve(black_box(props), &forcing, &inputs, &opts).unwrap());
                }
                runs += 50;
            }
            let secs = start.elapsed().as_secs_f64();
            // CPU time of this thread, when Linux reports it: on a shared,
            // oversubscribed machine it is the fairer measure of one core.
            let cpu = match (cpu_start, thread_cpu_s()) {
                (Some(a), Some(b)) => format!("{:8.0} runs/CPU-s", runs as f64 / (b - a)),
                _ => "n/a".to_string(),
            };
            println!(
                "{pname:30} {mname:22} {:8.0} runs/s wall, {cpu}  ({:6.1} µs/run wall, {} spin-up \
                 cycles, {} Newton iterations, day-2 max |ΔT| vs accurate {:.3} K)",
                runs as f64 / secs,
                1e6 * secs / runs as f64,
                reference.spinup_cycles,
                reference.stats.solves,
                err
            );
        }
    }
}

/// CPU time of the calling thread, s (Linux `/proc/thread-self/schedstat`,
/// first field: nanoseconds on CPU); None elsewhere.
fn thread_cpu_s() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}
