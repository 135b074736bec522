//! Tests: backends. Embree (packets, single rays) and obvhs must agree hit for
//! hit on random scenes and rays; instancing must behave like the transformed
//! copy; occlusion must agree with closest hit.

use glam::{Affine3A, Quat, Vec3};
use irsig::geometry::procedural::{self, TerrainParams};
use irsig::geometry::{Instance, SceneGeometry, TriangleMesh};
use irsig::trace::embree::{Device, EmbreeTracer, Instancing, RayMode};
use irsig::trace::{self, Backend, Coherence, Hit, Ray, Tracer, Watertight};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn unit_dir(rng: &mut ChaCha8Rng) -> Vec3 {
    loop {
        let v = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let l = v.length();
        if l > 0.05 && l <= 1.0 {
            return v / l;
        }
    }
}

/// Random rays: origins in a box slightly larger than the scene, directions
/// uniform on the sphere; a third aimed at random points of the scene so
/// that most rays hit something.
fn random_rays(geom: &SceneGeometry, n: usize, seed: u64) -> Vec<Ray> {
    let (lo, hi) = geom.bounds().expect("non-empty scene");
    let ext = hi - lo;
    let (lo, hi) = (
        lo - 0.1 * ext,
        hi + 0.1 * ext + Vec3::Z * 0.2 * ext.max_element(),
    );
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|i| {
            let o = Vec3::new(
                rng.random_range(lo.x..hi.x),
                rng.random_range(lo.y..hi.y),
                rng.random_range(lo.z..hi.z),
            );
            let d = if i % 3 == 0 {
                let target = Vec3::new(
                    rng.random_range(lo.x..hi.x),
                    rng.random_range(lo.y..hi.y),
                    rng.random_range(lo.z..hi.z),
                );
                (target - o).normalize_or(Vec3::NEG_Z)
            } else {
                unit_dir(&mut rng)
            };
            Ray::new(o, d)
        })
        .collect()
}

/// A triangle soup placed by several instances (random rotation, non-uniform
/// scale, translation) plus one mesh placed once.
fn soup_scene(seed: u64, tris: usize, copies: usize) -> SceneGeometry {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut soup = TriangleMesh {
        name: "soup".into(),
        ..Default::default()
    };
    for _ in 0..tris {
        let c = Vec3::new(
            rng.random_range(-10.0..10.0),
            rng.random_range(-10.0..10.0),
            rng.random_range(-10.0..10.0),
        );
        let base = soup.positions.len() as u32;
        for _ in 0..3 {
            soup.positions
                .push(c + unit_dir(&mut rng) * rng.random_range(0.2..1.5));
        }
        soup.indices.push([base, base + 1, base + 2]);
    }
    let mut geom = SceneGeometry::single(procedural::box_mesh());
    geom.instances[0].world_from_object = Affine3A::from_scale(Vec3::new(60.0, 60.0, 2.0));
    geom.meshes.push(soup);
    for k in 0..copies {
        geom.instances.push(Instance {
            mesh: 1,
            world_from_object: Affine3A::from_scale_rotation_translation(
                Vec3::new(
                    rng.random_range(0.5..2.0),
                    rng.random_range(0.5..2.0),
                    rng.random_range(0.5..2.0),
                ),
                Quat::from_axis_angle(
                    unit_dir(&mut rng),
                    rng.random_range(0.0..std::f32::consts::TAU),
                ),
                Vec3::new(k as f32 * 25.0 - 25.0, rng.random_range(-5.0..5.0), 20.0),
            ),
        });
    }
    geom
}

fn rel_close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol * a.abs().max(b.abs()).max(1e-6)
}

/// Float resolution of a scene's coordinates (unit-length ray directions).
fn abs_tol(geom: &SceneGeometry) -> f32 {
    let (lo, hi) = geom.bounds().expect("non-empty");
    1e-6 * lo.abs().max(hi.abs()).max_element()
}

/// Whether two world triangles share a vertex (ties on shared edges).
fn share_vertex(geom: &SceneGeometry, a: &Hit, b: &Hit) -> bool {
    let ta = geom.world_triangle(a.instance as usize, a.prim as usize);
    let tb = geom.world_triangle(b.instance as usize, b.prim as usize);
    let scale = ta.iter().map(|p| p.abs().max_element()).fold(1.0, f32::max);
    ta.iter()
        .any(|p| tb.iter().any(|q| p.distance(*q) <= 1e-5 * scale))
}

/// Compares two backends' closest hits; returns the number of rays that
/// disagree on hit/miss, distance (1e-4 relative) or, off shared edges,
/// the hit facet. Also checks barycentrics and normals of agreeing hits.
fn compare(geom: &SceneGeometry, a: &[Option<Hit>], b: &[Option<Hit>]) -> (usize, usize) {
    let mut mismatched = 0;
    let mut hits = 0;
    for (ha, hb) in a.iter().zip(b) {
        match (ha, hb) {
            (None, None) => {}
            (Some(x), Some(y)) => {
                hits += 1;
                if !trace::distances_agree(x.t, y.t, abs_tol(geom)) {
                    mismatched += 1;
                } else if (x.instance, x.prim) != (y.instance, y.prim) {
                    if !share_vertex(geom, x, y) {
                        mismatched += 1;
                    }
                } else {
                    assert!(
                        (x.u - y.u).abs() < 2e-3 && (x.v - y.v).abs() < 2e-3,
                        "{x:?} vs {y:?}"
                    );
                    let (nx, ny) = (x.ng.normalize(), y.ng.normalize());
                    assert!(nx.dot(ny) > 0.9999, "normals differ: {x:?} vs {y:?}");
                    assert!(
                        rel_close(x.ng.length(), y.ng.length(), 1e-3),
                        "{x:?} vs {y:?}"
                    );
                }
            }
            _ => mismatched += 1,
        }
    }
    (mismatched, hits)
}

#[test]
fn embree_and_obvhs_agree_on_random_scenes_and_rays() {
    let cases = [
        (
            procedural::generate(&TerrainParams::with_triangles(20_000, 7)),
            100_000,
            11,
        ),
        (soup_scene(3, 3000, 3), 60_000, 12),
    ];
    for (geom, n, seed) in cases {
        let rays = random_rays(&geom, n, seed);
        let embree = trace::build(&geom, Backend::Embree).unwrap();
        let obvhs = trace::build(&geom, Backend::Obvhs).unwrap();
        let he = trace::intersect_all(embree.as_ref(), &rays, Coherence::Incoherent);
        let ho = trace::intersect_all(obvhs.as_ref(), &rays, Coherence::Incoherent);
        let (mismatched, hits) = compare(&geom, &he, &ho);
        // Rays must actually exercise the geometry.
        assert!(hits > n / 5, "only {hits} of {n} rays hit");
        assert!(hits < n, "every ray hit: the miss path is untested");
        // Measured elsewhere: ≤ 2 in 1 M rays differ (float ties); allow 1e-4.
        assert!(
            mismatched * 10_000 <= n,
            "{mismatched} of {n} rays disagree"
        );
    }
}

/// Every backend over `geom`, plus Embree with real instancing for every
/// mesh placed more than once (the default flattens small ones, so this
/// keeps Embree's instance path under test).
fn every_tracer(geom: &SceneGeometry) -> Vec<(String, Box<dyn Tracer>)> {
    let mut out: Vec<(String, Box<dyn Tracer>)> = Backend::ALL
        .iter()
        .map(|&b| (b.to_string(), trace::build(geom, b).unwrap()))
        .collect();
    let instanced = EmbreeTracer::with_instancing(
        Device::new().unwrap(),
        geom,
        RayMode::ByCoherence(Device::new().unwrap().native_packet_width()),
        Watertight::Yes,
        Instancing::Always,
    )
    .unwrap();
    out.push(("embree (instancing always)".into(), Box::new(instanced)));
    out
}

#[test]
fn instanced_object_hits_where_its_transformed_copy_would() {
    let geom = soup_scene(5, 1500, 3);
    // Every instance flattened into one world-space mesh, in facet order.
    let flat = SceneGeometry::single(geom.flatten());
    let offsets = geom.facet_offsets();
    let rays = random_rays(&geom, 30_000, 21);
    for (backend, inst) in every_tracer(&geom) {
        let copy = trace::build(&flat, Backend::Obvhs).unwrap();
        let hi = trace::intersect_all(inst.as_ref(), &rays, Coherence::Incoherent);
        let hc = trace::intersect_all(copy.as_ref(), &rays, Coherence::Incoherent);
        let mut bad = 0;
        let mut hits = 0;
        for (a, b) in hi.iter().zip(&hc) {
            match (a, b) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    hits += 1;
                    let fa = SceneGeometry::facet_id(&offsets, a.instance, a.prim);
                    if !trace::distances_agree(a.t, b.t, abs_tol(&geom)) || fa != b.prim as usize {
                        bad += 1;
                        continue;
                    }
                    // World-space geometric normal, also for Embree instances
                    // (which report Ng in object space).
                    assert!(
                        a.ng.normalize().dot(b.ng.normalize()) > 0.999,
                        "{a:?} vs {b:?}"
                    );
                    assert!(
                        rel_close(a.ng.length(), b.ng.length(), 1e-3),
                        "{a:?} vs {b:?}"
                    );
                }
                _ => bad += 1,
            }
        }
        assert!(hits > 3000, "{backend}: only {hits} hits");
        assert!(bad * 2000 <= rays.len(), "{backend}: {bad} rays differ");
    }
}

#[test]
fn box_instance_top_is_hit_at_its_analytic_height() {
    // A 10×10×5 m box, rotated 30° about z, standing at (100, 50, 2).
    let mut geom = SceneGeometry::single(procedural::box_mesh());
    geom.instances[0].world_from_object = Affine3A::from_scale_rotation_translation(
        Vec3::new(10.0, 10.0, 5.0),
        Quat::from_rotation_z(std::f32::consts::FRAC_PI_6),
        Vec3::new(100.0, 50.0, 2.0),
    );
    // Twice, so that Embree uses real instancing for the box.
    let mut second = geom.instances[0].clone();
    second.world_from_object.translation.x += 1000.0;
    geom.instances.push(second);
    let rays = [
        Ray::new(Vec3::new(100.0, 50.0, 100.0), Vec3::NEG_Z),
        Ray::new(Vec3::new(1101.0, 51.0, 100.0), Vec3::new(0.0, 0.0, -2.0)),
        Ray::new(Vec3::new(120.0, 50.0, 100.0), Vec3::NEG_Z),
    ];
    for (backend, t) in every_tracer(&geom) {
        let mut out = [None; 3];
        t.intersect(&rays, Coherence::Coherent, &mut out);
        let h = out[0].expect("hits the first box");
        assert!((h.t - 93.0).abs() < 1e-4, "{backend}: t = {}", h.t);
        assert_eq!(h.instance, 0);
        assert!(h.prim < 2, "{backend}: top face, got prim {}", h.prim);
        assert!(
            h.ng.normalize().dot(Vec3::Z) > 0.99999,
            "{backend}: {:?}",
            h.ng
        );
        // |ng| = twice the triangle area = 10·10 m².
        assert!(
            (h.ng.length() - 100.0).abs() < 1e-2,
            "{backend}: {:?}",
            h.ng
        );
        let h = out[1].expect("hits the second box");
        assert!(
            (h.t - 46.5).abs() < 1e-4,
            "{backend}: t in units of |dir|: {}",
            h.t
        );
        assert_eq!(h.instance, 1);
        assert!(out[2].is_none(), "{backend}: beside the box");
    }
}

#[test]
fn packet_and_single_ray_paths_give_identical_results() {
    let geom = procedural::generate(&TerrainParams::with_triangles(20_000, 3));
    let rays = random_rays(&geom, 40_000, 5);
    let single = EmbreeTracer::with_mode(&geom, RayMode::Single).unwrap();
    let reference = trace::intersect_all(&single, &rays, Coherence::Incoherent);
    let occ_ref = trace::occluded_all(&single, &rays, Coherence::Incoherent);
    let device = Device::new().unwrap();
    let widths: Vec<usize> = [4, 8, 16]
        .into_iter()
        .filter(|&w| device.supports_packet_width(w))
        .collect();
    assert!(!widths.is_empty(), "no packet width supported");
    for w in widths {
        let packet = EmbreeTracer::with_mode(&geom, RayMode::Packet(w)).unwrap();
        for coherence in [
            Coherence::Coherent,
            Coherence::Incoherent,
            Coherence::Scattered,
        ] {
            let hits = trace::intersect_all(&packet, &rays, coherence);
            let (mismatched, _) = compare(&geom, &reference, &hits);
            assert_eq!(mismatched, 0, "width {w}");
            let same = reference.iter().zip(&hits).filter(|(a, b)| a == b).count();
            assert_eq!(same, rays.len(), "width {w}: not bit-identical");
            let occ = trace::occluded_all(&packet, &rays, coherence);
            assert_eq!(occ, occ_ref, "width {w}");
        }
    }
    // An odd-sized batch exercises the partially filled last packet.
    let packet = EmbreeTracer::new(&geom, true).unwrap();
    let mut out = vec![None; 13];
    packet.intersect(&rays[..13], Coherence::Coherent, &mut out);
    assert_eq!(out, reference[..13]);
}

#[test]
fn occlusion_agrees_with_closest_hit() {
    let geom = soup_scene(9, 2000, 2);
    let rays = random_rays(&geom, 20_000, 9);
    for backend in Backend::ALL {
        let t = trace::build(&geom, backend).unwrap();
        let hits = trace::intersect_all(t.as_ref(), &rays, Coherence::Incoherent);
        let occ = trace::occluded_all(t.as_ref(), &rays, Coherence::Incoherent);
        for (h, o) in hits.iter().zip(&occ) {
            assert_eq!(h.is_some(), *o, "{backend}");
        }
        // Shortened to just before the closest hit: nothing in the way.
        let short: Vec<Ray> = rays
            .iter()
            .zip(&hits)
            .filter_map(|(r, h)| {
                h.map(|h| Ray {
                    tfar: h.t * 0.999,
                    ..*r
                })
            })
            .collect();
        assert!(short.len() > 2000);
        let occ = trace::occluded_all(t.as_ref(), &short, Coherence::Incoherent);
        let blocked = occ.iter().filter(|&&o| o).count();
        assert!(
            blocked * 1000 <= short.len(),
            "{backend}: {blocked} blocked before the closest hit"
        );
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let geom = procedural::generate(&TerrainParams::with_triangles(10_000, 4));
    let rays = random_rays(&geom, 10_000, 4);
    for backend in [Backend::Embree, Backend::Obvhs] {
        let t = trace::build(&geom, backend).unwrap();
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| trace::intersect_all(t.as_ref(), &rays, Coherence::Incoherent))
        };
        assert_eq!(run(1), run(2), "{backend}");
    }
}

#[test]
fn procedural_scene_has_the_requested_size_and_is_seeded() {
    for n in [10_000, 100_000, 1_000_000] {
        let g = procedural::generate(&TerrainParams::with_triangles(n, 1));
        let got = g.facet_count();
        assert!(got.abs_diff(n) * 100 <= n, "asked {n}, got {got}");
    }
    let p = TerrainParams::with_triangles(10_000, 42);
    let (a, b) = (procedural::generate(&p), procedural::generate(&p));
    assert_eq!(a.meshes[0].positions, b.meshes[0].positions);
    assert_eq!(a.instances.len(), b.instances.len());
    let c = procedural::generate(&TerrainParams {
        seed: 43,
        ..p.clone()
    });
    assert_ne!(a.meshes[0].positions, c.meshes[0].positions);
    // Instanced: one box mesh stored once, placed by every building.
    assert_eq!(a.meshes.len(), 2);
    assert_eq!(a.instances.len(), 1 + p.buildings);
    // Buildings stand on the terrain: the box base is 1 m below the ground.
    for inst in &a.instances[1..] {
        let t = inst.world_from_object.translation;
        assert!((t.z - (p.height_at(t.x, t.y) - 1.0)).abs() < 1e-3);
    }
}

#[test]
fn backend_names_round_trip_and_bad_input_is_reported() {
    for b in Backend::ALL {
        assert_eq!(b.to_string().parse::<Backend>().unwrap(), b);
    }
    let e = "optix".parse::<Backend>().unwrap_err().to_string();
    assert!(e.contains("optix") && e.contains("embree-single"), "{e}");
    let bad = SceneGeometry::single(TriangleMesh {
        name: "bad".into(),
        positions: vec![Vec3::ZERO; 3],
        indices: vec![[0, 1, 3]],
    });
    for b in Backend::ALL {
        let e = trace::build(&bad, b)
            .err()
            .expect("index 3 is out of range")
            .to_string();
        assert!(
            e.contains("out of range") && e.contains("triangle 0"),
            "{b}: {e}"
        );
    }
    let e = EmbreeTracer::with_mode(&bad, RayMode::Packet(5))
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("packet width"), "{e}");
    // An empty scene traces without hits.
    let empty = SceneGeometry::default();
    for b in Backend::ALL {
        let t = trace::build(&empty, b).unwrap();
        let mut out = [Some(Hit {
            t: 0.0,
            instance: 0,
            prim: 0,
            u: 0.0,
            v: 0.0,
            ng: Vec3::Z,
        })];
        t.intersect(
            &[Ray::new(Vec3::ZERO, Vec3::Z)],
            Coherence::Coherent,
            &mut out,
        );
        assert_eq!(out[0], None, "{b}");
    }
}

#[test]
fn bench_trace_cli_prints_the_documented_json() {
    let out = std::process::Command::new(crate::util::irsig_bin())
        .args(["bench", "trace", "--triangles", "10000", "--rays", "4000"])
        .args(["--rounds", "1", "--threads", "2", "--json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let tris = v["triangles"].as_u64().unwrap();
    assert!(tris.abs_diff(10_000) <= 100, "{tris}");
    for b in ["embree_packet", "embree_single", "obvhs"] {
        for k in [
            "build_s",
            "primary_mrays_s",
            "shadow_mrays_s",
            "diffuse_mrays_s",
        ] {
            let x = v["backends"][b][k].as_f64().unwrap_or(-1.0);
            assert!(x > 0.0 && x.is_finite(), "{b}.{k} = {x}");
        }
    }
    assert_eq!(v["threads"].as_u64(), Some(2));
    let rays = v["agreement"]["rays"].as_u64().unwrap();
    assert!((15_900..=16_100).contains(&rays), "{rays}");
    let bad = v["agreement"]["mismatched_rays"].as_u64().unwrap();
    assert!(bad * 1000 <= rays, "{bad} of {rays} rays disagree");
    // One object per ray class, with the coherence its producer declares
    // and the Embree query that coherence gets.
    let width = Device::new().unwrap().native_packet_width();
    let packets = format!("Packet({width})");
    let scattered = if irsig::trace::embree::STREAM_API {
        "Stream"
    } else {
        "Single"
    };
    let mut class_rays = 0;
    let mut class_bad = 0;
    for (class, coherence, mode) in [
        ("primary", "Coherent", packets.as_str()),
        ("shadow", "Coherent", packets.as_str()),
        ("hemisphere", "Incoherent", packets.as_str()),
        ("diffuse", "Scattered", scattered),
    ] {
        let c = &v["classes"][class];
        assert_eq!(c["coherence"].as_str(), Some(coherence), "{class}: {c}");
        assert_eq!(c["embree_mode"].as_str(), Some(mode), "{class}: {c}");
        let n = c["rays"].as_u64().unwrap();
        assert!((3_900..=4_100).contains(&n), "{class}: {n} rays");
        let (e, o, r) = (
            c["embree_mrays_s"].as_f64().unwrap(),
            c["obvhs_mrays_s"].as_f64().unwrap(),
            c["ratio"].as_f64().unwrap(),
        );
        assert!(
            e > 0.0 && o > 0.0 && ((r - e / o) / r).abs() < 1e-9,
            "{class}: {c}"
        );
        class_rays += n;
        class_bad += c["mismatched"].as_u64().unwrap();
    }
    assert_eq!(class_rays, rays);
    assert_eq!(class_bad, bad);
    // The per-backend hemisphere column.
    for b in ["embree_packet", "embree_single", "obvhs"] {
        let x = v["backends"][b]["hemisphere_mrays_s"]
            .as_f64()
            .unwrap_or(-1.0);
        assert!(x > 0.0 && x.is_finite(), "{b}.hemisphere_mrays_s = {x}");
    }
}

/// `--watertight no` builds the Embree scenes without the robust flag (as
/// a render's exposure scene): the header says so and the backends still
/// agree on random rays; a value other than yes/no is refused by name.
#[test]
fn bench_trace_cli_without_watertight_tests() {
    let run = |extra: &[&str]| {
        std::process::Command::new(crate::util::irsig_bin())
            .args(["bench", "trace", "--triangles", "10000", "--rays", "4000"])
            .args(["--rounds", "1", "--threads", "2"])
            .args(extra)
            .output()
            .unwrap()
    };
    let out = run(&["--watertight", "no"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("not watertight"), "{text}");
    let out = run(&["--watertight", "no", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rays = v["agreement"]["rays"].as_u64().unwrap();
    let bad = v["agreement"]["mismatched_rays"].as_u64().unwrap();
    assert!(
        rays > 0 && bad * 1000 <= rays,
        "{bad} of {rays} rays disagree"
    );
    let out = run(&["--watertight", "maybe"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("maybe") && err.contains("expected yes or no"),
        "{err}"
    );
}

#[test]
fn bench_trace_cli_reads_an_obj_scene_and_reports_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("cube.obj");
    // A 10 m cube of quads: 12 triangles once triangulated.
    std::fs::write(
        &obj,
        "v 0 0 0\nv 10 0 0\nv 10 10 0\nv 0 10 0\nv 0 0 10\nv 10 0 10\nv 10 10 10\nv 0 10 10\n\
         f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n",
    )
    .unwrap();
    let run = |extra: &[&str]| {
        std::process::Command::new(crate::util::irsig_bin())
            .args(["bench", "trace", "--rays", "2000", "--rounds", "1"])
            .args(extra)
            .output()
            .unwrap()
    };
    let out = run(&["--scene", obj.to_str().unwrap(), "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["triangles"], 12);
    assert_eq!(v["agreement"]["mismatched_rays"], 0);
    let out = run(&["--scene", dir.path().join("missing.obj").to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.obj"));
    let out = run(&["--tile", "4by2"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("expected WxH"));
}

/// A regular heightmap (shared vertices, 2 m cells) and rays that run in
/// the vertical planes of its cell edges, as a scan line over the
/// bundled town's terrain does when the aircraft is over an edge: the
/// Embree scenes are robust (watertight), so none slips between the
/// triangles (before the scenes were made robust, about 0.6 % of the town
/// scanner's ground pixels did). obvhs is checked to be as watertight.
#[test]
fn rays_in_the_planes_of_shared_edges_do_not_slip_through_a_heightmap() {
    let cells = 60usize;
    let step = 2.0f32;
    let half = 0.5 * cells as f32 * step;
    let mut mesh = TriangleMesh {
        name: "terrain".into(),
        ..Default::default()
    };
    for j in 0..=cells {
        for i in 0..=cells {
            let (x, y) = (i as f32 * step - half, j as f32 * step - half);
            let z = 0.4 * (0.05 * x).sin() * (0.07 * y).cos();
            mesh.positions.push(Vec3::new(x, y, z));
        }
    }
    let v = |i: usize, j: usize| (j * (cells + 1) + i) as u32;
    for j in 0..cells {
        for i in 0..cells {
            mesh.indices.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            mesh.indices.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    let geom = SceneGeometry::single(mesh);
    // Rays from 300 m up in the planes y = edge and x = edge, fanning out
    // ±10° within the plane (300 m·tan 10° = 53 m: all inside the
    // heightmap).
    let mut rays = Vec::new();
    for k in 1..cells {
        let e = k as f32 * step - half;
        for s in 0..256 {
            let a = (-10.0f32 + 20.0 * (s as f32 + 0.5) / 256.0).to_radians();
            let (sa, ca) = a.sin_cos();
            rays.push(Ray::new(Vec3::new(0.0, e, 300.0), Vec3::new(sa, 0.0, -ca)));
            rays.push(Ray::new(Vec3::new(e, 0.0, 300.0), Vec3::new(0.0, sa, -ca)));
        }
    }
    for backend in Backend::ALL {
        let tracer = trace::build(&geom, backend).unwrap();
        for coherence in [
            Coherence::Coherent,
            Coherence::Incoherent,
            Coherence::Scattered,
        ] {
            let hits = trace::intersect_all(tracer.as_ref(), &rays, coherence);
            let misses = hits.iter().filter(|h| h.is_none()).count();
            assert_eq!(
                misses,
                0,
                "{}: {misses} of {} rays slipped through",
                backend.as_str(),
                rays.len()
            );
        }
    }
}

/// Issue 22: every Embree batch sets flush-to-zero / denormals-are-zero for
/// its own calls only; the thread's MXCSR (all of it: modes and flags) is as
/// it was before, so the caller's maths keeps IEEE denormals.
#[cfg(target_arch = "x86_64")]
#[test]
fn r22_mxcsr_is_unchanged_after_a_batch() {
    use irsig::trace::embree::mxcsr;
    let geom = procedural::generate(&TerrainParams::with_triangles(2_000, 2));
    let rays = random_rays(&geom, 1000, 22);
    // A fresh thread: Rust starts it with FTZ and DAZ off.
    std::thread::spawn(move || {
        const FTZ_DAZ: u32 = (1 << 15) | (1 << 6);
        assert_eq!(mxcsr() & FTZ_DAZ, 0, "FTZ/DAZ already on");
        let tracers = [
            EmbreeTracer::new(&geom, true).unwrap(),
            EmbreeTracer::with_mode(&geom, RayMode::Single).unwrap(),
        ];
        for t in &tracers {
            let mode = t.mode();
            for coherence in [
                Coherence::Coherent,
                Coherence::Incoherent,
                Coherence::Scattered,
            ] {
                let before = mxcsr();
                let mut hits = vec![None; rays.len()];
                t.intersect(&rays, coherence, &mut hits);
                assert_eq!(mxcsr(), before, "{mode:?} {coherence:?}: intersect");
                let mut occ = vec![false; rays.len()];
                t.occluded(&rays, coherence, &mut occ);
                assert_eq!(mxcsr(), before, "{mode:?} {coherence:?}: occluded");
                assert!(hits.iter().any(Option::is_some));
            }
        }
        // The denormal 1e-40 survives in this thread's maths.
        let tiny = std::hint::black_box(1e-39_f32) * std::hint::black_box(0.1_f32);
        assert!(tiny > 0.0, "flushed to zero after the batches");
    })
    .join()
    .unwrap();
}

/// Issue 22: the Embree device is created with `threads=N` from the caller's
/// setting, rayon's thread count by default. Embree has no property to read
/// the count back, so the check is what Embree itself prints with
/// `verbose=1` (its configuration dump, "Threads : N"): a child process (this
/// test binary, re-run on this test) creates the device and the parent reads
/// its standard output.
#[test]
fn r22_device_thread_count_is_the_callers() {
    use irsig::trace::embree::DeviceConfig;
    if let Ok(n) = std::env::var("IRSIG_R22_THREADS") {
        let threads = n.parse::<usize>().unwrap();
        let make = || {
            Device::with_config(&DeviceConfig {
                threads: None,
                verbose: 1,
            })
            .unwrap()
        };
        let d = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(make);
        assert_eq!(d.config(), format!("threads={threads},verbose=1"));
        return;
    }
    for threads in [1, 3] {
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args([
                "--exact",
                "backends::r22_device_thread_count_is_the_callers",
            ])
            .args(["--nocapture", "--test-threads=1"])
            .env("IRSIG_R22_THREADS", threads.to_string())
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "child failed: {stdout}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let reported: Vec<&str> = stdout
            .lines()
            .filter(|l| {
                let w: Vec<&str> = l.split_whitespace().collect();
                w.len() == 3 && w[0] == "Threads" && w[1] == ":"
            })
            .collect();
        assert!(
            reported
                .iter()
                .any(|l| l.split_whitespace().nth(2) == Some(&threads.to_string())),
            "Embree did not report {threads} threads: {reported:?}\n{stdout}"
        );
    }
    // Explicit counts and the default.
    assert_eq!(Device::with_threads(2).unwrap().config(), "threads=2");
    let d = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| Device::new().unwrap());
    assert_eq!(d.config(), "threads=1");
}

/// Issue 22: a geometry reading an `Arc`-shared vertex buffer keeps it
/// alive, as does the scene it is attached to: the caller's handles can go
/// first (that dropping a *borrowed* buffer early does not compile is the
/// `compile_fail` doctest on `irsig::trace::embree::Geometry::triangles`).
#[test]
fn r22_shared_vertex_buffer_outlives_the_callers_handles() {
    use irsig::trace::Watertight;
    use irsig::trace::embree::{Geometry, Scene, VertexBuffer};
    use std::sync::Arc;
    let device = Device::new().unwrap();
    let mut scene = Scene::new(&device, Watertight::Yes).unwrap();
    {
        let vb = Arc::new(VertexBuffer::new(
            [Vec3::ZERO, Vec3::X, Vec3::Y].into_iter(),
        ));
        let g = Geometry::triangles_shared(&device, vb, &[[0, 1, 2]]).unwrap();
        scene.attach(&g, 0).unwrap();
    }
    scene.commit().unwrap();
    let scene = Arc::new(scene);
    // An instance keeps the instanced scene; a scene keeps its instances.
    let mut top = Scene::new(&device, Watertight::Yes).unwrap();
    let g = Geometry::instance(&device, &scene, &Affine3A::IDENTITY).unwrap();
    drop(scene);
    top.attach(&g, 0).unwrap();
    drop(g);
    top.commit().unwrap();
    // Not committed, or of another device: refused.
    let other = Device::new().unwrap();
    let open = Arc::new(Scene::new(&device, Watertight::Yes).unwrap());
    let e = Geometry::instance(&device, &open, &Affine3A::IDENTITY)
        .err()
        .unwrap();
    assert!(e.to_string().contains("not committed"), "{e}");
    let vb = VertexBuffer::new([Vec3::ZERO, Vec3::X, Vec3::Y].into_iter());
    let mut mine = Scene::new(&device, Watertight::Yes).unwrap();
    let g = Geometry::triangles(&other, &vb, &[[0, 1, 2]]).unwrap();
    let e = mine.attach(&g, 1).unwrap_err();
    assert!(e.to_string().contains("another Embree device"), "{e}");
}

/// Issue 22: the default Embree tracer picks its query from the batch's
/// coherence — packets for coherent batches, the stream API (Embree 3) or
/// single rays (Embree 4) for incoherent ones — and every mode gives the
/// same hits, bit for bit.
#[test]
fn r22_query_mode_follows_coherence_and_all_modes_agree() {
    let geom = procedural::generate(&TerrainParams::with_triangles(20_000, 7));
    let rays = random_rays(&geom, 20_000, 22);
    let auto = EmbreeTracer::new(&geom, true).unwrap();
    let w = match auto.mode() {
        RayMode::ByCoherence(w) => w,
        m => panic!("default mode {m:?}"),
    };
    assert_eq!(auto.name(), "embree");
    assert_eq!(
        auto.mode().for_batch(Coherence::Coherent),
        RayMode::Packet(w)
    );
    let scattered = if irsig::trace::embree::STREAM_API {
        RayMode::Stream
    } else {
        RayMode::Single
    };
    assert_eq!(
        auto.mode().for_batch(Coherence::Incoherent),
        RayMode::Packet(w)
    );
    assert_eq!(auto.mode().for_batch(Coherence::Scattered), scattered);
    let single = EmbreeTracer::with_mode(&geom, RayMode::Single).unwrap();
    let reference = trace::intersect_all(&single, &rays, Coherence::Incoherent);
    let occ_ref = trace::occluded_all(&single, &rays, Coherence::Incoherent);
    let mut others = vec![auto];
    let stream = EmbreeTracer::with_mode(&geom, RayMode::Stream);
    assert_eq!(stream.is_ok(), irsig::trace::embree::STREAM_API);
    match stream {
        Ok(t) => others.push(t),
        Err(e) => assert!(e.to_string().contains("no stream API"), "{e}"),
    }
    for t in &others {
        for coherence in [
            Coherence::Coherent,
            Coherence::Incoherent,
            Coherence::Scattered,
        ] {
            let hits = trace::intersect_all(t, &rays, coherence);
            assert!(hits == reference, "{} {coherence:?}", t.name());
            let occ = trace::occluded_all(t, &rays, coherence);
            assert!(occ == occ_ref, "{} {coherence:?}", t.name());
        }
    }
}

/// `irsig bench modes` times every Embree query mode on `bench trace`'s
/// rays: one row per mode (the stream only on Embree 3), each with finite
/// positive throughputs for the three ray classes.
#[test]
fn bench_modes_cli_prints_every_mode() {
    let out = std::process::Command::new(crate::util::irsig_bin())
        .args(["bench", "modes", "--triangles", "5000", "--rays", "2000"])
        .args(["--rounds", "1", "--threads", "2"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let mut modes = vec!["Single", "Packet(", "ByCoherence("];
    if irsig::trace::embree::STREAM_API {
        modes.push("Stream");
    }
    for m in modes {
        let line = text
            .lines()
            .find(|l| l.starts_with(m))
            .unwrap_or_else(|| panic!("no row for {m}: {text}"));
        let v: Vec<f64> = line
            .split_whitespace()
            .skip(1)
            .map(|x| x.parse().unwrap())
            .collect();
        // Primary, shadow, hemisphere, diffuse.
        assert_eq!(v.len(), 4, "{line}");
        assert!(v.iter().all(|x| x.is_finite() && *x > 0.0), "{line}");
    }
}
