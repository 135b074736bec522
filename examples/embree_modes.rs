//! Embree's query modes side by side, in one run: single rays, packets at
//! the native width and (Embree 3) the stream API, on the three ray sets of
//! `irsig bench trace` (same scene, same rays), plus the default
//! [`RayMode::ByCoherence`]. Prints Mrays/s per class and mode, best of the
//! rounds, rounds interleaved mode after mode.
//!
//! `cargo run --release --example embree_modes -- [TRIANGLES] [RAYS] [ROUNDS] [THREADS] [WATERTIGHT yes|no]`
use std::time::Instant;

use irsig::bench::{TraceBenchOptions, make_ray_sets};
use irsig::geometry::procedural::{self, TerrainParams};
use irsig::trace::embree::{Device, EmbreeTracer, RayMode};
use irsig::trace::{self, Coherence, Watertight};

fn main() -> irsig::Result<()> {
    let arg = |i: usize, d: usize| {
        std::env::args()
            .nth(i)
            .and_then(|s| s.parse().ok())
            .unwrap_or(d)
    };
    let (tris, rays, rounds, threads) =
        (arg(1, 1_000_000), arg(2, 1_000_000), arg(3, 5), arg(4, 2));
    let watertight: Watertight = std::env::args()
        .nth(5)
        .unwrap_or_else(|| "yes".into())
        .parse()?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
        .expect("global pool");
    let geom = procedural::generate(&TerrainParams::with_triangles(tris, 1));
    let opts = TraceBenchOptions {
        rays,
        watertight,
        ..Default::default()
    };
    let sets = make_ray_sets(&geom, &opts)?;
    let w = Device::new()?.native_packet_width();
    let mut modes = vec![RayMode::Single, RayMode::Packet(w), RayMode::ByCoherence(w)];
    if let Ok(t) =
        EmbreeTracer::with_mode(&irsig::geometry::SceneGeometry::default(), RayMode::Stream)
    {
        drop(t);
        modes.insert(2, RayMode::Stream);
    }
    let tracers: Vec<EmbreeTracer> = modes
        .iter()
        .map(|&m| EmbreeTracer::with_device(Device::new()?, &geom, m, watertight))
        .collect::<irsig::Result<_>>()?;
    let mut best = vec![[0f64; 3]; modes.len()];
    let mrays = |n: usize, s: f64| n as f64 / s / 1e6;
    for _ in 0..rounds {
        for (t, b) in tracers.iter().zip(best.iter_mut()) {
            let t0 = Instant::now();
            let p = trace::intersect_all(t, &sets.primary, Coherence::Coherent);
            let t1 = Instant::now();
            let s = trace::occluded_all(t, &sets.shadow, Coherence::Incoherent);
            let t2 = Instant::now();
            let d = trace::intersect_all(t, &sets.diffuse, Coherence::Incoherent);
            let t3 = Instant::now();
            std::hint::black_box((p, s, d));
            b[0] = b[0].max(mrays(sets.primary.len(), (t1 - t0).as_secs_f64()));
            b[1] = b[1].max(mrays(sets.shadow.len(), (t2 - t1).as_secs_f64()));
            b[2] = b[2].max(mrays(sets.diffuse.len(), (t3 - t2).as_secs_f64()));
        }
    }
    println!(
        "Embree {} · {} triangles · {} threads · watertight {:?} · best of {rounds} (Mrays/s)",
        Device::new()?.version(),
        geom.stored_triangle_count(),
        threads,
        watertight
    );
    println!(
        "{:<16} {:>9} {:>9} {:>9}",
        "mode", "primary", "shadow", "diffuse"
    );
    for (m, b) in modes.iter().zip(&best) {
        println!(
            "{:<16} {:>9.2} {:>9.2} {:>9.2}",
            format!("{m:?}"),
            b[0],
            b[1],
            b[2]
        );
    }
    Ok(())
}
