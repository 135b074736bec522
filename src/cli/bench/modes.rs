//! `irsig bench modes`: Embree's query modes side by side, in one run —
//! single rays, packets at the native width, (Embree 3) the stream API, and
//! the default per-coherence choice ([`RayMode::ByCoherence`]) — on the four
//! ray classes of `irsig bench trace` (same scene, same rays). Rounds are
//! interleaved mode after mode; the best of each counts.

use std::io::Write;
use std::time::Instant;

use irsig::geometry::SceneGeometry;
use irsig::trace::Watertight;
use irsig::trace::embree::{Device, EmbreeTracer, RayMode};

use super::trace::{TraceBenchOptions, make_ray_sets};

/// Throughput (Mrays/s, best of `rounds`) of every Embree mode on
/// primary, shadow, hemisphere and diffuse rays, printed as a table.
pub fn run(geom: &SceneGeometry, opts: &TraceBenchOptions) -> anyhow::Result<()> {
    let sets = make_ray_sets(geom, opts)?;
    let w = Device::new()?.native_packet_width();
    let mut modes = vec![RayMode::Single, RayMode::Packet(w), RayMode::ByCoherence(w)];
    if EmbreeTracer::with_mode(&SceneGeometry::default(), RayMode::Stream).is_ok() {
        modes.insert(2, RayMode::Stream);
    }
    let tracers: Vec<EmbreeTracer> = modes
        .iter()
        .map(|&m| EmbreeTracer::with_device(Device::new()?, geom, m, opts.watertight))
        .collect::<irsig::Result<_>>()?;
    let classes = [&sets.primary, &sets.shadow, &sets.hemisphere, &sets.diffuse];
    let mut best = vec![[0f64; 4]; modes.len()];
    let mrays = |n: usize, s: f64| n as f64 / s.max(1e-12) / 1e6;
    // Answer buffers allocated once, outside the clock.
    let mut hits = vec![None; classes.iter().map(|s| s.rays.len()).max().unwrap_or(0)];
    let mut occluded = vec![false; sets.shadow.rays.len()];
    for _ in 0..opts.rounds {
        for (t, b) in tracers.iter().zip(best.iter_mut()) {
            for (c, set) in classes.iter().enumerate() {
                let t0 = Instant::now();
                // Shadow rays are occlusion queries, the rest closest hits.
                if c == 1 {
                    set.occluded_into(t, &mut occluded);
                } else {
                    set.intersect_into(t, &mut hits[..set.rays.len()]);
                }
                std::hint::black_box((&hits, &occluded));
                b[c] = b[c].max(mrays(set.rays.len(), t0.elapsed().as_secs_f64()));
            }
        }
    }
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "irsig bench modes: Embree {} · {} triangles · {} threads · {} · best of {} rounds (Mrays/s)",
        Device::new()?.version(),
        geom.stored_triangle_count(),
        rayon::current_num_threads(),
        match opts.watertight {
            Watertight::Yes => "watertight",
            Watertight::No => "not watertight",
        },
        opts.rounds
    )?;
    writeln!(
        out,
        "{:<16} {:>9} {:>9} {:>10} {:>9}",
        "mode", "primary", "shadow", "hemisphere", "diffuse"
    )?;
    for (m, b) in modes.iter().zip(&best) {
        writeln!(
            out,
            "{:<16} {:>9.2} {:>9.2} {:>10.2} {:>9.2}",
            format!("{m:?}"),
            b[0],
            b[1],
            b[2],
            b[3]
        )?;
    }
    Ok(())
}
