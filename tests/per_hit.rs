//! Tests: per-hit temperatures (`irsig::render::per_hit`, issue 18 item
//! 1) — a hit's own solar history through its facet's Green's function.

use std::sync::Arc;

use chrono::{DateTime, FixedOffset};
use glam::Vec3;
use irsig::exposure::ExposureParams;
use irsig::geometry::{SceneGeometry, TriangleMesh};
use irsig::render::per_hit::{HitState, PerHit, PerHitParams, SkyInputs};
use irsig::render::scene_thermal::{
    FacetThermalSetup, SceneThermal, SceneThermalParams, solve_scene_temperatures,
};
use irsig::thermal::scene::FacetThermal;
use irsig::thermal::{Background, FacetInputs, Forcing, SlabProperties, SolveOptions};
use irsig::trace::{self, Backend, Coherence, Ray, Tracer};

use crate::exposure::quad;
use crate::scene_thermal::asphalt;

/// Half-width of the tower's square footprint and its height, m.
const TOWER: (f32, f32) = (2.0, 20.0);

/// A square tower (`2a × 2a × h` m, centred on the origin, walls facing
/// out, with a roof) on a flat `2·half` m square ground of `n × n` cells
/// (two triangles each). Returns the geometry, the ground's facets and the
/// tower's.
fn tower_scene(
    half: f32,
    n: u32,
) -> (
    SceneGeometry,
    std::ops::Range<usize>,
    std::ops::Range<usize>,
) {
    let (a, h) = TOWER;
    let mut m = TriangleMesh::default();
    let ground = quad(
        &mut m,
        Vec3::new(-half, -half, 0.0),
        Vec3::X * 2.0 * half,
        Vec3::Y * 2.0 * half,
        n,
        n,
    );
    let start = m.indices.len();
    let z = Vec3::Z * h;
    quad(&mut m, Vec3::new(a, -a, 0.0), Vec3::Y * 2.0 * a, z, 1, 1);
    quad(&mut m, Vec3::new(-a, a, 0.0), -Vec3::Y * 2.0 * a, z, 1, 1);
    quad(&mut m, Vec3::new(a, a, 0.0), -Vec3::X * 2.0 * a, z, 1, 1);
    quad(&mut m, Vec3::new(-a, -a, 0.0), Vec3::X * 2.0 * a, z, 1, 1);
    quad(
        &mut m,
        Vec3::new(-a, -a, h),
        Vec3::X * 2.0 * a,
        Vec3::Y * 2.0 * a,
        1,
        1,
    );
    let tower = start..m.indices.len();
    (SceneGeometry::single(m), ground, tower)
}

fn time(s: &str) -> DateTime<FixedOffset> {
    DateTime::parse_from_rfc3339(s).unwrap()
}

const IMAGE: &str = "2025-06-21T14:00:00-04:00";

/// The scene solve of a tower scene at [`IMAGE`] (one sample point per
/// facet; the ground's shape factor set to `ground_f` when given).
fn solve(
    geo: &SceneGeometry,
    ground: &std::ops::Range<usize>,
    tower: &std::ops::Range<usize>,
    ground_f: Option<f32>,
) -> (SceneThermal, Box<dyn Tracer>) {
    solve_with(geo, ground, tower, ground_f, IMAGE, asphalt())
}

/// [`solve`] at `image` with the ground of `props` (the tower's facets
/// held at 300 K).
fn solve_with(
    geo: &SceneGeometry,
    ground: &std::ops::Range<usize>,
    tower: &std::ops::Range<usize>,
    ground_f: Option<f32>,
    image: &str,
    props: irsig::thermal::SlabProperties,
) -> (SceneThermal, Box<dyn Tracer>) {
    let (weather, _) = irsig::weather::synth::town_history().unwrap();
    let site = *weather.site().unwrap();
    let n = geo.facet_count();
    let setup = FacetThermalSetup {
        kinds: (0..n)
            .map(|f| {
                if tower.contains(&f) {
                    FacetThermal::Fixed(300.0)
                } else {
                    FacetThermal::Solve(0)
                }
            })
            .collect(),
        props: vec![props],
        shape_factor_override: match ground_f {
            Some(v) => (0..n).map(|f| ground.contains(&f).then_some(v)).collect(),
            None => Vec::new(),
        },
        ..Default::default()
    };
    let params = SceneThermalParams {
        exposure: ExposureParams {
            samples_per_edge: 1,
            ..Default::default()
        },
        ..Default::default()
    };
    let tracer = trace::build(geo, Backend::Embree).unwrap();
    let r = solve_scene_temperatures(
        &*tracer,
        geo,
        &setup,
        &weather,
        &site,
        &[time(image)],
        &params,
    )
    .unwrap();
    (r, tracer)
}

fn per_hit(r: &SceneThermal) -> PerHit {
    PerHit::new(
        Arc::new(r.exposure.solar.clone()),
        &r.exposure.facets,
        &r.exposure.sky,
        r.point_response[0].as_ref().expect("linearised solve"),
        &r.sun_directions,
        PerHitParams::default(),
    )
}

/// The ground facet under `(x, y)`.
fn facet_at(tracer: &dyn Tracer, x: f32, y: f32) -> usize {
    let mut hit = [None];
    tracer.intersect(
        &[Ray::new(Vec3::new(x, y, -1.0), Vec3::Z)],
        Coherence::Incoherent,
        &mut hit,
    );
    hit[0].expect("ground below every point").prim as usize
}

/// Per-hit states of ground points.
fn states(r: &SceneThermal, tracer: &dyn Tracer, ph: &PerHit, pts: &[(f32, f32)]) -> Vec<HitState> {
    let hits: Vec<(u32, Vec3)> = pts
        .iter()
        .map(|&(x, y)| (facet_at(tracer, x, y) as u32, Vec3::new(x, y, 0.0)))
        .collect();
    let mut out = Vec::new();
    ph.states(tracer, &hits, &mut out);
    let _ = r;
    out
}

/// Whether the ground point `(x, y)` lies in the tower's geometric shadow
/// for the sun along `d` (slab test of the ray `p + t·d`, `t > 0`, against
/// the tower's box).
fn in_shadow(x: f32, y: f32, d: Vec3) -> bool {
    let (a, h) = TOWER;
    let p = Vec3::new(x, y, 0.0);
    let (lo, hi) = (Vec3::new(-a, -a, 0.0), Vec3::new(a, a, h));
    let (mut t0, mut t1) = (0.0f32, f32::INFINITY);
    for i in 0..3 {
        if d[i].abs() < 1e-9 {
            if p[i] < lo[i] || p[i] > hi[i] {
                return false;
            }
            continue;
        }
        let (u, v) = ((lo[i] - p[i]) / d[i], (hi[i] - p[i]) / d[i]);
        t0 = t0.max(u.min(v));
        t1 = t1.min(u.max(v));
    }
    t0 <= t1
}

/// The sun at the image time and the unit ground vector along the shadow.
fn sun_and_shadow(r: &SceneThermal) -> (Vec3, Vec3) {
    let d = r.sun_directions[r.temperatures.image_records[0]];
    (d, (-d.truncate()).normalize().extend(0.0))
}

/// Issue 18: a tower on a two-triangle ground plane shows its shadow in
/// the per-hit temperatures (the facets' own show none), and the shadow's
/// edge lies within one pixel (0.1 m here) of the geometric edge from the
/// sun's position at the image time; the sunlit fraction too.
#[test]
fn tower_on_two_triangles_shows_its_shadow() {
    let (geo, ground, tower) = tower_scene(60.0, 1);
    assert_eq!(ground.len(), 2);
    let (r, tracer) = solve(&geo, &ground, &tower, None);
    let ph = per_hit(&r);
    let (sun, s) = sun_and_shadow(&r);
    let (a, h) = TOWER;
    let len = h * sun.truncate().length() / sun.z;
    // A line across the middle of the shadow, 0.1 m "pixels".
    let c = s * (a + len / 2.0);
    let u = Vec3::new(-s.y, s.x, 0.0);
    let px = 0.1f32;
    let pts: Vec<(f32, f32)> = (-100..=100)
        .map(|i| {
            let p = c + u * (i as f32 * px);
            (p.x, p.y)
        })
        .collect();
    let st = states(&r, &*tracer, &ph, &pts);
    let t_facet = r.surface_temperature_k(0);
    let temps: Vec<f32> = pts
        .iter()
        .zip(&st)
        .map(|(&(x, y), s)| t_facet[facet_at(&*tracer, x, y)] + s.dt_k)
        .collect();
    let geo_shadow: Vec<bool> = pts.iter().map(|&(x, y)| in_shadow(x, y, sun)).collect();
    let n_shadow = geo_shadow.iter().filter(|&&b| b).count();
    assert!(n_shadow > 20 && n_shadow < 180, "{n_shadow} shaded pixels");
    // The facets are uniform: without per-hit the line shows no shadow.
    let facets: Vec<usize> = pts.iter().map(|&(x, y)| facet_at(&*tracer, x, y)).collect();
    let lit_facet = |f: usize| r.exposure.solar.sun_fraction(f)[r.temperatures.image_records[0]];
    assert!(facets.iter().all(|&f| lit_facet(f) == 1.0));
    // The per-hit temperatures: shaded ground cooler by kelvins.
    let mean = |shade: bool| {
        let v: Vec<f32> = temps
            .iter()
            .zip(&geo_shadow)
            .filter(|&(_, &g)| g == shade)
            .map(|(&t, _)| t)
            .collect();
        v.iter().sum::<f32>() / v.len() as f32
    };
    let (t_lit, t_shade) = (mean(false), mean(true));
    eprintln!("lit {t_lit:.2} K, shaded {t_shade:.2} K");
    assert!(t_lit - t_shade > 2.0, "lit {t_lit} K, shaded {t_shade} K");
    // The sunlit fraction at the image time matches the geometric shadow
    // except within one pixel of its edge.
    let near_edge = |i: usize| {
        (i.saturating_sub(1)..=(i + 1).min(pts.len() - 1)).any(|j| geo_shadow[j] != geo_shadow[i])
    };
    for i in 0..pts.len() {
        let dark = st[i].sun_fraction == 0.0;
        assert!(
            dark == geo_shadow[i] || near_edge(i),
            "pixel {i}: s {}",
            st[i].sun_fraction
        );
    }
    // The temperature's edge: at each geometric edge (between pixels e and
    // e + 1), the largest step of the temperature within 5 pixels lies
    // within one pixel of it. (Ground that left the shadow earlier keeps
    // part of its deficit: the step is sharp, the tail is its memory.)
    let mut edges = 0;
    for e in 5..pts.len() - 6 {
        if geo_shadow[e] == geo_shadow[e + 1] {
            continue;
        }
        let j = (e - 5..e + 6)
            .max_by(|&a, &b| {
                (temps[a + 1] - temps[a])
                    .abs()
                    .total_cmp(&(temps[b + 1] - temps[b]).abs())
            })
            .unwrap();
        let step = (temps[j + 1] - temps[j]).abs();
        eprintln!(
            "geometric edge at {e}|{}: largest step {step:.2} K at {j}|{}",
            e + 1,
            j + 1
        );
        assert!(
            j.abs_diff(e) <= 1 && step > 1.0,
            "edge {e}: step {step} K at {j}"
        );
        edges += 1;
    }
    assert_eq!(edges, 2);
    // The facet wants per-hit at a realistic footprint (500 m, 0.6 mrad).
    assert!(ph.wants(facets[0], 500.0, 6e-4));
}

/// Issue 18: per-hit and per-facet temperatures agree on uniformly lit
/// ground (exactly: the hit's history equals its facet's), and a batch's
/// states do not depend on its other hits (thread and tile determinism).
#[test]
fn uniformly_lit_hits_take_their_facets_temperature() {
    let (geo, ground, tower) = tower_scene(60.0, 1);
    let (r, tracer) = solve(&geo, &ground, &tower, None);
    let ph = per_hit(&r);
    let (_, s) = sun_and_shadow(&r);
    // Toward the sun from the tower: never shaded during the day.
    let pts: Vec<(f32, f32)> = (0..20)
        .map(|i| {
            let p = -s * (30.0 + i as f32) + Vec3::new(-s.y, s.x, 0.0) * (i as f32 - 10.0);
            (p.x, p.y)
        })
        .collect();
    let st = states(&r, &*tracer, &ph, &pts);
    let worst = st.iter().map(|s| s.dt_k.abs()).fold(0.0f32, f32::max);
    assert!(worst <= 0.01, "per-hit vs per-facet: {worst} K");
    assert!(st.iter().all(|s| s.dt_k == 0.0 && s.sun_fraction == 1.0));
    // One by one equals the batch.
    for (p, b) in pts.iter().zip(&st) {
        assert_eq!(&states(&r, &*tracer, &ph, &[*p])[0], b);
    }
}

/// The sunlit history (0/1 per window record; 0 with the sun behind the
/// ground) of a ground point, traced as per-hit does at every record.
fn sun_history(r: &SceneThermal, tracer: &dyn Tracer, facet: usize, x: f32, y: f32) -> Vec<f32> {
    let w = &r.point_response[0].as_ref().unwrap().records;
    let cos = r.exposure.solar.cos_incidence(facet);
    let off = r.exposure.facets.offset_m;
    w.iter()
        .map(|&k| {
            if cos[k] <= 0.0 {
                return 0.0;
            }
            let mut occ = [false];
            tracer.occluded(
                &[Ray::new(Vec3::new(x, y, off), r.sun_directions[k])],
                Coherence::Incoherent,
                &mut occ,
            );
            if occ[0] { 0.0 } else { 1.0 }
        })
        .collect()
}

/// Issue 18, thermal memory: ground that left the tower's shadow 30 min
/// before the image time is cooler than ground sunlit all morning, by what
/// the library's single-facet solve gives for the same sun-fraction
/// histories (within 0.1 K).
#[test]
fn ground_that_left_the_shadow_remembers_it() {
    let (geo, ground, tower) = tower_scene(60.0, 1);
    let (r, tracer) = solve(&geo, &ground, &tower, None);
    let ph = per_hit(&r);
    let w = r.point_response[0].as_ref().unwrap().records.clone();
    let last = w.len() - 1;
    let step_min = (r.times[w[last]] - r.times[w[last - 1]]).num_minutes();
    let back = (30 / step_min) as usize;
    // Search the ground around the tower: B lit for the last 30 min,
    // shaded just before; A lit at every daytime record; same facet.
    let (mut a_pt, mut b_pt) = (None, None);
    'search: for i in -40..=40 {
        for j in -40..=40 {
            let (x, y) = (i as f32 * 0.5, j as f32 * 0.5);
            if x.abs() <= TOWER.0 + 0.5 && y.abs() <= TOWER.0 + 0.5 {
                continue;
            }
            let f = facet_at(&*tracer, x, y);
            let s = sun_history(&r, &*tracer, f, x, y);
            let cos = r.exposure.solar.cos_incidence(f);
            let day: Vec<bool> = w.iter().map(|&k| cos[k] > 0.0).collect();
            let lit_all = s.iter().zip(&day).all(|(&v, &d)| !d || v == 1.0);
            if lit_all && a_pt.is_none() {
                a_pt = Some((f, x, y, s.clone()));
            }
            let left = s[last - back] == 0.0 && s[last - back + 1..].iter().all(|&v| v == 1.0);
            if left && b_pt.is_none() {
                b_pt = Some((f, x, y, s.clone()));
            }
            if let (Some(a), Some(b)) = (&a_pt, &b_pt)
                && a.0 == b.0
            {
                break 'search;
            }
            if a_pt
                .as_ref()
                .zip(b_pt.as_ref())
                .is_some_and(|(a, b)| a.0 != b.0)
            {
                // Keep A on B's facet.
                a_pt = None;
            }
        }
    }
    let (fa, xa, ya, sa) = a_pt.expect("a point lit all day");
    let (fb, xb, yb, sb) = b_pt.expect("a point that left the shadow 30 min ago");
    assert_eq!(fa, fb);
    let st = states(&r, &*tracer, &ph, &[(xa, ya), (xb, yb)]);
    let per_hit = (st[1].dt_k - st[0].dt_k) as f64;
    // The single-facet solve of both histories.
    let records: Vec<_> = w.iter().map(|&k| r.records[k]).collect();
    let forcing = Forcing::from_records(&records).unwrap();
    let cos: Vec<f32> = w
        .iter()
        .map(|&k| r.exposure.solar.cos_incidence(fa)[k])
        .collect();
    let f = r.exposure.sky.shape_factor[fa] as f64;
    let props = &r.setup.props[match r.setup.kinds[fa] {
        FacetThermal::Solve(p) => p as usize,
        _ => unreachable!(),
    }];
    let t = |s: &[f32]| {
        irsig::thermal::solve(
            props,
            &forcing,
            &FacetInputs::new(s, &cos, f),
            &SolveOptions::default(),
        )
        .unwrap()
        .surface_temperature_k[last]
    };
    let solo = t(&sb) - t(&sa);
    eprintln!(
        "left the shadow {} min ago: per-hit {per_hit:.3} K, single-facet solve {solo:.3} K",
        back as i64 * step_min
    );
    assert!(per_hit < -0.3, "cooler: {per_hit} K");
    assert!(
        (per_hit - solo).abs() <= 0.1,
        "per-hit {per_hit} K vs solve {solo} K"
    );
}

/// Issue 18: one large triangle across the shadow's edge — its points on
/// each side take the temperatures of small facets there (the ground
/// solved as 1 m cells), the shape factor held equal (1) so that only the
/// sunlit histories differ.
#[test]
fn large_triangle_matches_small_facets_across_a_shadow_edge() {
    let half = 20.0;
    let (coarse, cg, ct) = tower_scene(half, 1);
    let (fine, fg, ft) = tower_scene(half, 40);
    let (rc, tc) = solve(&coarse, &cg, &ct, Some(1.0));
    let (rf, tf) = solve(&fine, &fg, &ft, Some(1.0));
    let ph = per_hit(&rc);
    let (sun, s) = sun_and_shadow(&rc);
    let (a, h) = TOWER;
    let len = h * sun.truncate().length() / sun.z;
    let c = s * (a + len / 2.0);
    let u = Vec3::new(-s.y, s.x, 0.0);
    // Fine-cell centroids either side of the shadow's edge.
    let mut checked = [0usize; 2];
    let mut worst = 0.0f32;
    for i in -40..=40 {
        let p = c + u * (i as f32 * 0.25);
        let f = facet_at(&*tf, p.x, p.y);
        let q = rf.exposure.facets.facet_points(f)[0];
        if !(-half + 1.0..half - 1.0).contains(&q.x) || !(-half + 1.0..half - 1.0).contains(&q.y) {
            continue;
        }
        let shade = in_shadow(q.x, q.y, sun);
        let t_small = rf.surface_temperature_k(0)[f];
        let st = states(&rc, &*tc, &ph, &[(q.x, q.y)])[0];
        let t_hit = rc.surface_temperature_k(0)[facet_at(&*tc, q.x, q.y)] + st.dt_k;
        worst = worst.max((t_hit - t_small).abs());
        checked[shade as usize] += 1;
    }
    eprintln!("large triangle vs small facets: worst {worst:.4} K over {checked:?} (lit, shaded)");
    assert!(checked[0] > 3 && checked[1] > 3, "{checked:?}");
    // The small facets' own values are the default scene solve's (first
    // order about 3 K bins: within max 0.31 K of the fine reference on
    // the town, docs/performance.md); measured 0.10 K.
    assert!(worst <= 0.15, "{worst} K");
}

/// End to end through the command line and the written image: a tower on a
/// two-triangle ground plane, seen from above. With per-hit temperatures
/// (the default) the rendered `surface_temperature` layer shows the
/// tower's shadow on the ground north of it; with `--per-hit off` the two
/// ground triangles carry one value each and the shadow is absent.
#[test]
fn rendered_surface_temperature_shows_the_shadow_on_a_two_triangle_ground() {
    let dir = tempfile::tempdir().unwrap();
    let repo = crate::util::repo_path("scenes");
    let scene = serde_json::json!({
        "site": {"latitude_deg": 43.16, "longitude_deg": -77.61, "altitude_m": 160, "utc_offset_hours": -4},
        "time": "2025-06-21T14:00:00-04:00",
        "weather": {"file": repo.join("town/weather.csv")},
        "materials": [repo.join("materials.json")],
        "objects": [
            {"name": "ground", "material": "asphalt", "shapes": [{"plane": {"size": [60, 60]}}]},
            {"name": "tower", "material": "concrete", "shapes": [{"box": {"size": [4, 4, 20], "bottom": false}}]}
        ],
        "sensors": [{"type": "frame", "name": "cam", "width": 64, "height": 64, "fov_deg": 11.4,
                     "position": [0, 0, 300], "look_at": [0, 0, 0], "up": [0, 1, 0],
                     "bands": [{"name": "lwir", "response": [8.0, 12.0]}],
                     "truth_layers": ["x", "y", "z"]}]
    });
    let path = dir.path().join("scene.json");
    std::fs::write(&path, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    let render = |per_hit: &str| {
        let out = dir.path().join(per_hit);
        let o = std::process::Command::new(crate::util::irsig_bin())
            .args(["render", "--quiet", "--per-hit", per_hit, "-o"])
            .arg(&out)
            .arg(&path)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        irsig::output::read_exr(out.join("cam.exr")).unwrap()
    };
    // Mean ground surface temperature over pixels whose hit lies in the
    // box [x0, x1] × [y0, y1] on the ground.
    let mean = |s: &irsig::output::ImageStack, x0: f32, x1: f32, y0: f32, y1: f32| {
        let l = |n: &str| s.layer(n).unwrap().data.clone();
        let (x, y, z, t) = (l("x"), l("y"), l("z"), l("surface_temperature"));
        let v: Vec<f32> = (0..t.len())
            .filter(|&k| {
                z[k].abs() < 1e-3 && (x0..=x1).contains(&x[k]) && (y0..=y1).contains(&y[k])
            })
            .map(|k| t[k])
            .collect();
        assert!(
            v.len() >= 4,
            "{} pixels in [{x0}, {x1}] × [{y0}, {y1}]",
            v.len()
        );
        v.iter().sum::<f32>() / v.len() as f32
    };
    // At 14:00 EDT on 21 June in Rochester the sun stands ≈ 68° high a
    // little west of south: the 20 m tower's shadow reaches ≈ 8 m north.
    let (shade, lit) = ((-1.0, 1.0, 3.0, 6.0), (-1.0, 1.0, -20.0, -12.0));
    let on = render("on");
    let on_shade = mean(&on, shade.0, shade.1, shade.2, shade.3);
    let on_lit = mean(&on, lit.0, lit.1, lit.2, lit.3);
    assert!(
        on_lit - on_shade > 3.0,
        "per-hit: shadow {on_shade:.2} K, sunlit {on_lit:.2} K"
    );
    let off = render("off");
    let off_shade = mean(&off, shade.0, shade.1, shade.2, shade.3);
    let off_lit = mean(&off, lit.0, lit.1, lit.2, lit.3);
    eprintln!(
        "ground surface temperature, shadow / sunlit: per hit {on_shade:.2} / {on_lit:.2} K, \
         per facet {off_shade:.2} / {off_lit:.2} K"
    );
    assert!(
        (off_lit - off_shade).abs() < 0.5,
        "per facet the shadow should not show: {off_shade:.2} K vs {off_lit:.2} K"
    );
}

/// [`per_hit`] with hits' own sky views, as a render makes it.
fn per_hit_with_sky(r: &SceneThermal, params: PerHitParams) -> PerHit {
    let e = ExposureParams::default();
    PerHit::new(
        Arc::new(r.exposure.solar.clone()),
        &r.exposure.facets,
        &r.exposure.sky,
        r.point_response[0].as_ref().expect("linearised solve"),
        &r.sun_directions,
        params,
    )
    .with_sky(
        SkyInputs::new(
            &r.exposure.facets,
            Arc::new(r.exposure.sky.clone()),
            e.sky,
            e.seed,
            &r.setup.shape_factor_override,
        ),
        r.surface_temperature_k(0),
    )
}

/// A courtyard corner on a two-triangle ground: two walls `l` m long and
/// `h` m high meeting at the origin, facing the courtyard (`x, y > 0`),
/// on an 80 m square ground. Returns the geometry, the ground's facets and
/// the walls'.
fn courtyard(
    l: f32,
    h: f32,
) -> (
    SceneGeometry,
    std::ops::Range<usize>,
    std::ops::Range<usize>,
) {
    let mut m = TriangleMesh::default();
    let ground = quad(
        &mut m,
        Vec3::new(-40.0, -40.0, 0.0),
        Vec3::X * 80.0,
        Vec3::Y * 80.0,
        1,
        1,
    );
    let start = m.indices.len();
    quad(
        &mut m,
        Vec3::new(l, 0.0, 0.0),
        -Vec3::X * l,
        Vec3::Z * h,
        1,
        1,
    );
    quad(&mut m, Vec3::ZERO, Vec3::Y * l, Vec3::Z * h, 1, 1);
    let walls = start..m.indices.len();
    (SceneGeometry::single(m), ground, walls)
}

/// The sky view factor of a ground point, by brute force: 64 × 64
/// cosine-weighted strata (their centres) from the point, the fraction
/// that escapes upward.
fn brute_force_shape_factor(tracer: &dyn Tracer, x: f32, y: f32, lift: f32) -> f32 {
    let m = 64;
    let rays: Vec<Ray> = (0..m * m)
        .map(|i| {
            let (u, v) = (
                ((i / m) as f32 + 0.5) / m as f32,
                ((i % m) as f32 + 0.5) / m as f32,
            );
            let (r, phi) = (u.sqrt(), std::f32::consts::TAU * v);
            let d = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u).sqrt());
            Ray::new(Vec3::new(x, y, lift), d)
        })
        .collect();
    let mut occ = vec![false; rays.len()];
    tracer.occluded(&rays, Coherence::Incoherent, &mut occ);
    occ.iter().filter(|&&o| !o).count() as f32 / rays.len() as f32
}

/// Issue 18 item 1, a hit's own sky view: a point in the corner of a
/// narrow courtyard (walls held at 300 K) on one large ground triangle sees
/// far less sky than the triangle's sample point, and at night (23:00,
/// after a day mostly in the walls' shade) its per-hit temperature change
/// from the facet matches the difference of two single-point slab solves
/// (`irsig::thermal::solve`: the point with its own shape factor, sunlit
/// history and background, the facet with its own) within 0.05 K. Its
/// view is the brute-force one (4096 rays) within 0.05, and its states
/// are the same in a batch, one by one and on one thread.
#[test]
fn courtyard_corner_takes_its_own_sky_view() {
    let (geo, ground, walls) = courtyard(15.0, 10.0);
    let night = "2025-06-21T23:00:00-04:00";
    let (r, tracer) = solve_with(&geo, &ground, &walls, None, night, asphalt());
    let ph = per_hit_with_sky(&r, PerHitParams::default());
    let (x, y) = (0.8f32, 0.4f32);
    let f = facet_at(&*tracer, x, y);
    assert!(ground.contains(&f));
    assert!(ph.own_sky(f), "the ground sees the walls");
    let st = states(&r, &*tracer, &ph, &[(x, y)])[0];
    let sky = st.sky.expect("its own sky view");
    let ff = r.exposure.sky.shape_factor[f];
    let brute = brute_force_shape_factor(&*tracer, x, y, r.exposure.facets.offset_m);
    eprintln!(
        "corner F_p {:.3} (brute force {brute:.3}), facet F {ff:.3}, T_bg {:.2} K, ΔT {:.3} K",
        sky.shape_factor, sky.background_k, st.dt_k
    );
    assert!(
        (sky.shape_factor - brute).abs() <= 0.05,
        "{} vs {brute}",
        sky.shape_factor
    );
    assert!(sky.shape_factor < ff - 0.3, "{} vs {ff}", sky.shape_factor);
    // Only sky and the walls above the ground: the walls' temperature.
    assert!(
        (sky.background_k - 300.0).abs() < 0.01,
        "{}",
        sky.background_k
    );
    // The single-point solves over the window.
    let w = r.point_response[0].as_ref().unwrap().records.clone();
    let last = w.len() - 1;
    let records: Vec<_> = w.iter().map(|&k| r.records[k]).collect();
    let forcing = Forcing::from_records(&records).unwrap();
    let cos: Vec<f32> = w
        .iter()
        .map(|&k| r.exposure.solar.cos_incidence(f)[k])
        .collect();
    let s_f: Vec<f32> = w
        .iter()
        .map(|&k| r.exposure.solar.sun_fraction(f)[k])
        .collect();
    let s_p = sun_history(&r, &*tracer, f, x, y);
    let props = asphalt();
    let t = |s: &[f32], shape: f32| {
        irsig::thermal::solve(
            &props,
            &forcing,
            &FacetInputs {
                background: Background::Constant(300.0),
                ..FacetInputs::new(s, &cos, shape as f64)
            },
            &SolveOptions::default(),
        )
        .unwrap()
        .surface_temperature_k[last]
    };
    let solo = t(&s_p, sky.shape_factor) - t(&s_f, ff);
    eprintln!(
        "night: per-hit {:.3} K, single-point solves {solo:.3} K",
        st.dt_k
    );
    assert!(
        (st.dt_k as f64 - solo).abs() <= 0.05,
        "per-hit {} K vs solve {solo} K",
        st.dt_k
    );
    // The sky view matters: with the facet's view (shade alone) the point
    // would be kelvins colder; with its own, walls at 300 K replace most
    // of the night sky (measured: −0.18 K against the facet, the shade's
    // memory and the walls' warmth nearly cancelling).
    let shade_only = states(&r, &*tracer, &per_hit(&r), &[(x, y)])[0];
    let t_shade = t(&s_p, ff) - t(&s_f, ff);
    eprintln!(
        "with the facet's view: per-hit {:.3} K, single-point solves {t_shade:.3} K",
        shade_only.dt_k
    );
    assert!(shade_only.sky.is_none());
    assert!(st.dt_k - shade_only.dt_k > 1.0);
    assert!(((st.dt_k - shade_only.dt_k) as f64 - (solo - t_shade)).abs() <= 0.05);
    // Determinism: a batch equals its hits one by one, on any thread count.
    let pts = [(x, y), (3.0, 1.0), (10.0, 0.5), (20.0, -5.0)];
    let batch = states(&r, &*tracer, &ph, &pts);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| states(&r, &*tracer, &ph, &pts));
    assert_eq!(batch, one);
    for (p, b) in pts.iter().zip(&batch) {
        assert_eq!(&states(&r, &*tracer, &ph, &[*p])[0], b);
    }
    assert_eq!(batch[0], st);
}

/// Issue 18 item 1: a hit on a facet whose hemisphere rays hit nothing of
/// the scene (open ground far from the tower) takes no sky view of its
/// own, and where its sunlit history is its facet's its temperature is the
/// facet's bit for bit.
#[test]
fn hits_on_an_open_facet_take_the_facets_temperature_bit_for_bit() {
    // 8 × 8 cells of 15 m around the tower.
    let (geo, ground, tower) = tower_scene(60.0, 8);
    let (r, tracer) = solve(&geo, &ground, &tower, None);
    let ph = per_hit_with_sky(&r, PerHitParams::default());
    let w = r.point_response[0].as_ref().unwrap().records.clone();
    // Points on a 3 m grid over the ground's open facets.
    let pts: Vec<(f32, f32)> = (-19..=19)
        .flat_map(|i| (-19..=19).map(move |j| (i as f32 * 3.0 + 0.1, j as f32 * 3.0 + 0.2)))
        .filter(|&(x, y)| {
            r.exposure
                .sky
                .background(facet_at(&*tracer, x, y))
                .is_empty()
        })
        .collect();
    assert!(pts.len() >= 50, "{} open points", pts.len());
    for &(x, y) in &pts {
        assert!(!ph.own_sky(facet_at(&*tracer, x, y)));
    }
    let st = states(&r, &*tracer, &ph, &pts);
    assert!(st.iter().all(|s| s.sky.is_none()));
    // Those lit whenever the sun is in front, as their facets: the
    // facet's temperature.
    let mut same = 0;
    for (&(x, y), s) in pts.iter().zip(&st) {
        let f = facet_at(&*tracer, x, y);
        let day: Vec<f32> = w
            .iter()
            .map(|&k| (r.exposure.solar.cos_incidence(f)[k] > 0.0) as u8 as f32)
            .collect();
        let s_f: Vec<f32> = w
            .iter()
            .zip(&day)
            .map(|(&k, d)| d * r.exposure.solar.sun_fraction(f)[k])
            .collect();
        if s_f == day && sun_history(&r, &*tracer, f, x, y) == day {
            assert_eq!(s.dt_k, 0.0, "({x}, {y})");
            same += 1;
        }
    }
    assert!(same >= 10, "{same} points lit all day");
    // Near the tower the ground sees it: its hits take their own view.
    let (_, s) = sun_and_shadow(&r);
    let near = facet_at(&*tracer, -s.x * 4.0, -s.y * 4.0);
    assert!(ph.own_sky(near));
}

/// Issue 18 item 1, the latent curvature: on evaporating grass, a point
/// in the tower's shadow against its sunlit facet. The per-hit change
/// against the difference of two exact single-point solves: nearer with
/// the curvature of the latent loss in the second order than without it.
#[test]
fn shaded_grass_point_needs_the_latent_curvature() {
    use irsig::thermal::BackBoundary;
    let grass = crate::util::stock_props("grass").with_back(BackBoundary::GROUND);
    let (geo, ground, tower) = tower_scene(60.0, 1);
    let (r, tracer) = solve_with(&geo, &ground, &tower, None, IMAGE, grass);
    assert!(
        !r.point_response[0]
            .as_ref()
            .unwrap()
            .response
            .latent
            .is_empty(),
        "grass evaporates"
    );
    let (sun, s) = sun_and_shadow(&r);
    let (a, h) = TOWER;
    let len = h * sun.truncate().length() / sun.z;
    let c = s * (a + len / 2.0);
    assert!(in_shadow(c.x, c.y, sun));
    let f = facet_at(&*tracer, c.x, c.y);
    let image = r.temperatures.image_records[0];
    assert_eq!(r.exposure.solar.sun_fraction(f)[image], 1.0);
    let dt = |latent_curvature: bool| {
        let params = PerHitParams {
            latent_curvature,
            ..Default::default()
        };
        let ph = PerHit::new(
            Arc::new(r.exposure.solar.clone()),
            &r.exposure.facets,
            &r.exposure.sky,
            r.point_response[0].as_ref().unwrap(),
            &r.sun_directions,
            params,
        );
        states(&r, &*tracer, &ph, &[(c.x, c.y)])[0].dt_k as f64
    };
    let (with, without) = (dt(true), dt(false));
    let w = r.point_response[0].as_ref().unwrap().records.clone();
    let last = w.len() - 1;
    let records: Vec<_> = w.iter().map(|&k| r.records[k]).collect();
    let forcing = Forcing::from_records(&records).unwrap();
    let cos: Vec<f32> = w
        .iter()
        .map(|&k| r.exposure.solar.cos_incidence(f)[k])
        .collect();
    let s_f: Vec<f32> = w
        .iter()
        .map(|&k| r.exposure.solar.sun_fraction(f)[k])
        .collect();
    let s_p = sun_history(&r, &*tracer, f, c.x, c.y);
    let shape = r.exposure.sky.shape_factor[f] as f64;
    let t = |s: &[f32]| {
        irsig::thermal::solve(
            &grass,
            &forcing,
            &FacetInputs {
                background: Background::Constant(300.0),
                ..FacetInputs::new(s, &cos, shape)
            },
            &SolveOptions::default(),
        )
        .unwrap()
        .surface_temperature_k[last]
    };
    let solo = t(&s_p) - t(&s_f);
    eprintln!(
        "shaded grass: exact {solo:.3} K, per-hit {with:.3} K with the latent curvature, \
         {without:.3} K without"
    );
    assert!(solo < -1.0, "{solo} K");
    assert!(
        (with - solo).abs() < (without - solo).abs(),
        "with {with} K, without {without} K, exact {solo} K"
    );
    // Measured: exact −8.443 K, with −8.296 K, without −7.595 K (the
    // second order is one fixed-point step, as the scene solve's).
    assert!((with - solo).abs() <= 0.2, "with {with} K vs {solo} K");
    assert!(
        (without - solo).abs() > 0.5,
        "without {without} K vs {solo} K"
    );
}

/// The scene solve of `geo` with `setup` at `image` (one sample point per
/// facet; the ground beyond the scene of albedo `ground_albedo`).
fn solve_setup(
    geo: &SceneGeometry,
    setup: &FacetThermalSetup,
    image: &str,
    ground_albedo: f32,
) -> (SceneThermal, Box<dyn Tracer>) {
    let (weather, _) = irsig::weather::synth::town_history().unwrap();
    let site = *weather.site().unwrap();
    let mut params = SceneThermalParams {
        exposure: ExposureParams {
            samples_per_edge: 1,
            ..Default::default()
        },
        ..Default::default()
    };
    params.physics.ground_albedo = ground_albedo;
    let tracer = trace::build(geo, Backend::Embree).unwrap();
    let r = solve_scene_temperatures(
        &*tracer,
        geo,
        setup,
        &weather,
        &site,
        &[time(image)],
        &params,
    )
    .unwrap();
    (r, tracer)
}

/// [`per_hit_with_sky`] with the points' own reflected shortwave (ground
/// beyond the scene of albedo `ground_albedo`), as a render makes it.
fn per_hit_full(r: &SceneThermal, ground_albedo: f32) -> PerHit {
    let e = ExposureParams::default();
    PerHit::new(
        Arc::new(r.exposure.solar.clone()),
        &r.exposure.facets,
        &r.exposure.sky,
        r.point_response[0].as_ref().expect("linearised solve"),
        &r.sun_directions,
        PerHitParams::default(),
    )
    .with_sky(
        SkyInputs::new(
            &r.exposure.facets,
            Arc::new(r.exposure.sky.clone()),
            e.sky,
            e.seed,
            &r.setup.shape_factor_override,
        )
        .with_reflected(Arc::new(r.exposure.reflected.clone()), r, ground_albedo)
        .with_exposed_back(r.exposed_back_shape_factor.clone()),
        r.surface_temperature_k(0),
    )
}

/// A thin panel 4 m high at x = 0 along y in [−20, 20] (front face +x,
/// one quad: its two triangles' sample points at y = ±6.7) on a 1 km
/// ground, and the `walls` `(x, y0, height, facing +x)` beside it, each
/// 20 m long from `y0`: the mesh, the ground's, panel's and each wall's
/// facets.
fn panel_scene(
    walls: &[(f32, f32, f32, bool)],
) -> (
    SceneGeometry,
    std::ops::Range<usize>,
    std::ops::Range<usize>,
    Vec<std::ops::Range<usize>>,
) {
    let mut m = TriangleMesh::default();
    let ground = quad(
        &mut m,
        Vec3::new(-500.0, -500.0, 0.0),
        Vec3::X * 1000.0,
        Vec3::Y * 1000.0,
        1,
        1,
    );
    let panel = quad(
        &mut m,
        Vec3::new(0.0, -20.0, 0.0),
        Vec3::Y * 40.0,
        Vec3::Z * 4.0,
        1,
        1,
    );
    let walls = walls
        .iter()
        .map(|&(x, y0, h, facing_x)| {
            let o = Vec3::new(x, y0, 0.0);
            // The winding sets the front: (Y, Z) faces +x, (Z, Y) −x.
            if facing_x {
                quad(&mut m, o, Vec3::Y * 20.0, Vec3::Z * h, 1, 1)
            } else {
                quad(&mut m, o, Vec3::Z * h, Vec3::Y * 20.0, 1, 1)
            }
        })
        .collect();
    (SceneGeometry::single(m), ground, panel, walls)
}

/// What single-point slab solves of a point of facet `f` need over the
/// image's window: the weather, the facet's cosines and sun fractions,
/// and the point's own sunlit history (its shadow rays from `p` lifted
/// `lift` toward the sun's side when `two_sided`, else along +x).
struct PointSolves {
    forcing: Forcing,
    cos: Vec<f32>,
    s_f: Vec<f32>,
    s_p: Vec<f32>,
    last: usize,
}

impl PointSolves {
    fn new(r: &SceneThermal, tracer: &dyn Tracer, f: usize, p: Vec3, two_sided: bool) -> Self {
        let w = r.point_response[0].as_ref().unwrap().records.clone();
        let records: Vec<_> = w.iter().map(|&k| r.records[k]).collect();
        let off = r.exposure.facets.offset_m;
        let s_p = w
            .iter()
            .map(|&k| {
                if r.exposure.solar.cos_incidence(f)[k] <= 0.0 {
                    return 0.0;
                }
                let d = r.sun_directions[k];
                let side = if !two_sided || d.x >= 0.0 { 1.0 } else { -1.0 };
                let mut occ = [false];
                tracer.occluded(
                    &[Ray::new(p + Vec3::X * (side * off), d)],
                    Coherence::Incoherent,
                    &mut occ,
                );
                if occ[0] { 0.0 } else { 1.0 }
            })
            .collect();
        PointSolves {
            forcing: Forcing::from_records(&records).unwrap(),
            cos: w
                .iter()
                .map(|&k| r.exposure.solar.cos_incidence(f)[k])
                .collect(),
            s_f: w
                .iter()
                .map(|&k| r.exposure.solar.sun_fraction(f)[k])
                .collect(),
            s_p,
            last: w.len() - 1,
        }
    }

    /// The image-time temperature of slab `props` with sun fractions `s`,
    /// shape factor `shape`, the background held at `bg` (K) and the back's
    /// shape factor `back`.
    fn t(&self, props: &SlabProperties, s: &[f32], shape: f32, bg: f32, back: Option<f32>) -> f64 {
        irsig::thermal::solve(
            props,
            &self.forcing,
            &FacetInputs {
                background: Background::Constant(bg as f64),
                back_shape_factor: back.map(f64::from),
                ..FacetInputs::new(s, &self.cos, shape as f64)
            },
            &SolveOptions::default(),
        )
        .unwrap()
        .surface_temperature_k[self.last]
    }
}

/// Brute force over 64 × 64 cosine-weighted strata (their centres) about
/// the unit normal `n` from `p` lifted by `lift` along it: the fraction
/// that escapes upward (the face's sky view factor), and the rays that
/// hit a facet, with that facet (ids of a single mesh).
fn brute_force_face(tracer: &dyn Tracer, p: Vec3, n: Vec3, lift: f32) -> (f32, Vec<usize>) {
    let m = 64;
    let t = n.any_orthonormal_vector();
    let b = n.cross(t);
    let rays: Vec<Ray> = (0..m * m)
        .map(|i| {
            let (u, v) = (
                ((i / m) as f32 + 0.5) / m as f32,
                ((i % m) as f32 + 0.5) / m as f32,
            );
            let (r, phi) = (u.sqrt(), std::f32::consts::TAU * v);
            let d = t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u).sqrt();
            Ray::new(p + n * lift, d)
        })
        .collect();
    let mut hits = vec![None; rays.len()];
    tracer.intersect(&rays, Coherence::Incoherent, &mut hits);
    let sky = rays
        .iter()
        .zip(&hits)
        .filter(|(r, h)| h.is_none() && r.dir.z > 0.0)
        .count();
    let seen = hits.iter().flatten().map(|h| h.prim as usize).collect();
    (sky as f32 / rays.len() as f32, seen)
}

/// Issue 18 item 1, a double-sided facet's own sky view: a point of a
/// thin fence (double-sided, solved as asphalt) between two walls held at
/// different temperatures, one facing each of its faces, on a 1 km ground
/// held at 290 K. Its own front shape factor and its background (the
/// radiative mean over both faces, as its facet's) against a brute-force
/// 4096 rays per face (within 0.05, 0.3 K); its change from the facet
/// against two single-point slab solves (each with its own shape factor,
/// sunlit history and background) within 0.05 K; a point at the facet's
/// sample point takes the facet's view and temperature bit for bit.
#[test]
fn double_sided_fence_takes_its_own_sky_view() {
    // The fence is the panel. Facing its front (x = 2, facing −x) along
    // y < 0, and its back (x = −2, facing +x) along y > 0; 8 m high.
    let (geo, ground, fence, walls) =
        panel_scene(&[(2.0, -20.0, 8.0, false), (-2.0, 0.0, 8.0, true)]);
    let (front_wall, back_wall) = (walls[0].clone(), walls[1].clone());
    let n = geo.facet_count();
    let temp_of = |f: usize| {
        if ground.contains(&f) {
            290.0
        } else if front_wall.contains(&f) {
            300.0
        } else if back_wall.contains(&f) {
            320.0
        } else {
            f32::NAN
        }
    };
    let setup = FacetThermalSetup {
        kinds: (0..n)
            .map(|f| {
                if fence.contains(&f) {
                    FacetThermal::Solve(0)
                } else {
                    FacetThermal::Fixed(temp_of(f))
                }
            })
            .collect(),
        props: vec![asphalt()],
        double_sided: (0..n).map(|f| fence.contains(&f)).collect(),
        ..Default::default()
    };
    let night = "2025-06-21T23:00:00-04:00";
    let (r, tracer) = solve_setup(&geo, &setup, night, 0.2);
    let ph = per_hit_full(&r, 0.2);
    // A point of the fence 1 m up, 10 m along its front wall.
    let p = Vec3::new(0.0, -10.0, 1.0);
    let mut hit = [None];
    tracer.intersect(
        &[Ray::new(Vec3::new(1.0, -10.0, 1.0), -Vec3::X)],
        Coherence::Incoherent,
        &mut hit,
    );
    let f = hit[0].expect("the fence").prim as usize;
    assert!(fence.contains(&f));
    assert!(
        r.exposure.sky.back_shape_factor(f).is_some(),
        "double-sided"
    );
    assert!(ph.own_sky(f));
    let mut out = Vec::new();
    ph.states(&*tracer, &[(f as u32, p)], &mut out);
    let st = out[0];
    let sky = st.sky.expect("its own sky view");
    // Brute force, both faces (each half the weight of the background).
    let off = r.exposure.facets.offset_m;
    let (f_front, seen_front) = brute_force_face(&*tracer, p, Vec3::X, off);
    let (f_back, seen_back) = brute_force_face(&*tracer, p, -Vec3::X, off);
    // The rays that hit nothing below the horizon would see the ground
    // beyond at the air temperature; with a 1 km ground they are a few per
    // mille.
    let t4: f64 = seen_front
        .iter()
        .chain(&seen_back)
        .map(|&j| (temp_of(j) as f64).powi(4))
        .sum();
    let t_bg = (t4 / (seen_front.len() + seen_back.len()) as f64).powf(0.25) as f32;
    let ff = r.exposure.sky.shape_factor[f];
    eprintln!(
        "fence point: F_p {:.3} (brute force {f_front:.3}), facet F {ff:.3}; T_bg {:.2} K \
         (brute force {t_bg:.2} K, facet {:.2} K); ΔT {:.3} K",
        sky.shape_factor,
        sky.background_k,
        r.background_temperature_k(0)[f],
        st.dt_k
    );
    assert!((sky.shape_factor - f_front).abs() <= 0.05);
    assert!((sky.background_k - t_bg).abs() <= 0.3);
    // The back face's own shape factor at the point (what a ray that sees
    // the back face sees reflected): its own rays against brute force, far
    // from the front face's (the front faces the 8 m wall 2 m away, the
    // back open ground).
    let fb = sky.back_shape_factor.expect("double-sided: a back face");
    eprintln!("fence point: back F_p {fb:.3} (brute force {f_back:.3})");
    assert!((fb - f_back).abs() <= 0.05, "{fb} vs {f_back}");
    assert!(fb - sky.shape_factor > 0.3, "{fb} vs {}", sky.shape_factor);
    // The back face matters: its front face alone sees mostly the 300 K
    // wall, the back face mostly the 290 K ground.
    let front_only = (seen_front
        .iter()
        .map(|&j| (temp_of(j) as f64).powi(4))
        .sum::<f64>()
        / seen_front.len() as f64)
        .powf(0.25) as f32;
    eprintln!("front face alone: T_bg {front_only:.2} K");
    assert!(front_only - sky.background_k > 1.0, "{front_only} K");
    // Single-point solves (the background held at each one's T_bg: every
    // surface seen is held fixed).
    let back = r.exposure.sky.back_shape_factor(f);
    let props = asphalt();
    let ps = PointSolves::new(&r, &*tracer, f, p, true);
    let t = |s: &[f32], shape: f32, bg: f32| ps.t(&props, s, shape, bg, back);
    let (s_p, s_f) = (&ps.s_p, &ps.s_f);
    let t_bg_f = r.background_temperature_k(0)[f];
    let solo = t(s_p, sky.shape_factor, sky.background_k) - t(s_f, ff, t_bg_f);
    eprintln!(
        "fence point: per-hit {:.3} K, single-point solves {solo:.3} K",
        st.dt_k
    );
    assert!(solo.abs() > 0.3, "the point's view matters: {solo} K");
    assert!(
        (st.dt_k as f64 - solo).abs() <= 0.05,
        "per-hit {} K vs solves {solo} K",
        st.dt_k
    );
    // At the facet's sample point: the facet's view, bit for bit.
    let q = r.exposure.facets.facet_points(f)[0];
    ph.states(&*tracer, &[(f as u32, q)], &mut out);
    let at = out[0];
    let k = at.sky.expect("its own sky view");
    assert_eq!(k.shape_factor, ff);
    assert_eq!(k.back_shape_factor, r.exposure.sky.back_shape_factor(f));
    assert_eq!(k.background_k, t_bg_f);
    assert_eq!(at.dt_k, 0.0);
}

/// Issue 18 item 1, hits seen through a reflection: a ground point of the
/// courtyard seen in one of its walls (a mirror ray reflected off the wall
/// down to the ground) takes the same state as the same point seen
/// directly from above (to rounding): its own sunlit history and its own
/// sky view. With [`PerHitParams::secondary_sky`] off it keeps its facet's
/// view.
#[test]
fn point_seen_in_a_mirror_takes_the_state_seen_directly() {
    let (geo, ground, walls) = courtyard(15.0, 10.0);
    let night = "2025-06-21T23:00:00-04:00";
    let (r, tracer) = solve_with(&geo, &ground, &walls, None, night, asphalt());
    let ph = per_hit_with_sky(&r, PerHitParams::default());
    let trace1 = |o: Vec3, d: Vec3| {
        let mut hit = [None];
        tracer.intersect(&[Ray::new(o, d)], Coherence::Incoherent, &mut hit);
        hit[0].expect("a hit")
    };
    // Off the wall along the x axis (normal +y) down to the ground.
    let cam = Vec3::new(20.0, 20.0, 10.0);
    let d = Vec3::new(10.0, 0.0, 3.0) - cam;
    let h = trace1(cam, d);
    assert!(walls.contains(&(h.prim as usize)));
    let q = cam + d * h.t;
    let n = h.ng.normalize();
    let d2 = d - 2.0 * d.dot(n) * n;
    let o2 = q + n * 1e-3;
    let h2 = trace1(o2, d2);
    let f = h2.prim as usize;
    assert!(ground.contains(&f));
    let mirrored = o2 + d2 * h2.t;
    // The same point from above.
    let top = Vec3::new(mirrored.x, mirrored.y, 50.0);
    let h3 = trace1(top, -Vec3::Z);
    assert_eq!(h3.prim as usize, f);
    let direct = top - Vec3::Z * h3.t;
    eprintln!("mirror point {mirrored:?}, direct point {direct:?}");
    assert!(ph.own_sky(f));
    let state = |ph: &PerHit, p: Vec3, direct: bool| {
        let mut out = Vec::new();
        ph.states_of(&*tracer, &[(f as u32, p)], direct, &mut out);
        out[0]
    };
    let seen = state(&ph, direct, true);
    let in_mirror = state(&ph, mirrored, false);
    eprintln!("seen directly: {seen:?}\nseen in the mirror: {in_mirror:?}");
    let (a, b) = (
        seen.sky.expect("own view"),
        in_mirror.sky.expect("own view"),
    );
    assert_eq!(a.shape_factor, b.shape_factor);
    assert!((a.background_k - b.background_k).abs() <= 1e-4);
    assert_eq!(seen.sun_fraction, in_mirror.sun_fraction);
    assert!(
        (seen.dt_k - in_mirror.dt_k).abs() <= 1e-4,
        "{seen:?} vs {in_mirror:?}"
    );
    // The view matters here (the courtyard's walls), and without
    // `secondary_sky` the mirrored point keeps its facet's.
    let facet_view = per_hit(&r);
    assert!((state(&facet_view, direct, true).dt_k - seen.dt_k).abs() > 0.5);
    let old = per_hit_with_sky(
        &r,
        PerHitParams {
            secondary_sky: false,
            ..Default::default()
        },
    );
    assert!(state(&old, mirrored, false).sky.is_none());
    assert_eq!(state(&old, direct, true), seen);
}

/// Issue 18 item 1, a point's own reflected shortwave: open ground (two
/// 200 m triangles) south of a long sunlit wall (200 m × `H` = 20 m,
/// facing south, albedo 0.5, held at 300 K) that reflects a uniform
/// radiosity `J`; the ground and the ground beyond reflect nothing. The
/// view factor of a horizontal element at distance `x` to the wall is
/// `F = ½(1 − x/√(x² + H²))` (Howell, *A Catalog of Radiation Heat Transfer
/// Configuration Factors*, differential strip to a parallel-edged
/// perpendicular plane of infinite length), so the point's reflected
/// irradiance is `J·F(x)`. Per-hit values at x = 1, 3, 10, 30 m against it
/// within the binomial Monte Carlo error of 64 rays,
/// `2.5·J·√(F(1 − F)/64)` (stratified sampling does better); the point
/// nearer the wall warmer; the point at 1 m against two single-point slab
/// solves (each with its own sunlit history, shape factor and reflected
/// shortwave) within 0.05 K; a point at its facet's sample point takes the
/// facet's reflected shortwave and temperature bit for bit.
#[test]
fn ground_before_a_sunlit_wall_takes_its_own_reflected_shortwave() {
    let h = 20.0f32;
    let mut m = TriangleMesh::default();
    let ground = quad(
        &mut m,
        Vec3::new(-100.0, -100.0, 0.0),
        Vec3::X * 200.0,
        Vec3::Y * 200.0,
        1,
        1,
    );
    let wall = quad(
        &mut m,
        Vec3::new(-100.0, 0.0, 0.0),
        Vec3::X * 200.0,
        Vec3::Z * h,
        1,
        1,
    );
    let geo = SceneGeometry::single(m);
    let n = geo.facet_count();
    let setup = FacetThermalSetup {
        kinds: (0..n)
            .map(|f| {
                if wall.contains(&f) {
                    FacetThermal::Fixed(300.0)
                } else {
                    FacetThermal::Solve(0)
                }
            })
            .collect(),
        props: vec![asphalt()],
        albedo: (0..n)
            .map(|f| if wall.contains(&f) { 0.5 } else { 0.0 })
            .collect(),
        ..Default::default()
    };
    let (r, tracer) = solve_setup(&geo, &setup, IMAGE, 0.0);
    let ph = per_hit_full(&r, 0.0);
    let k = r.temperatures.image_records[0];
    let (edn, ed) = (
        r.records[k].direct_normal_w_m2 as f32,
        r.records[k].diffuse_horizontal_w_m2 as f32,
    );
    // The wall's radiosity: it is lit and receives nothing reflected.
    let (sol, sky) = (&r.exposure.solar, &r.exposure.sky);
    let j = wall
        .clone()
        .map(|w| {
            assert_eq!(sol.sun_fraction(w)[k], 1.0);
            assert_eq!(r.exposure.reflected.irradiance_w_m2(w, k, 1.0, 1.0), 0.0);
            0.5 * (edn * sol.cos_incidence(w)[k] + ed * sky.mean_shape_factor(w))
        })
        .sum::<f32>()
        / wall.len() as f32;
    assert!(j > 100.0, "J {j} W m⁻²");
    let mut prev = None;
    for x in [1.0f32, 3.0, 10.0, 30.0] {
        let p = Vec3::new(0.0, -x, 0.0);
        let f = facet_at(&*tracer, p.x, p.y);
        assert!(ground.contains(&f) && ph.own_sky(f));
        let mut out = Vec::new();
        ph.states(&*tracer, &[(f as u32, p)], &mut out);
        let got = out[0].sky.expect("its own view").reflected_w_m2;
        let view = 0.5 * (1.0 - x / (x * x + h * h).sqrt());
        let want = j * view;
        let tol = 2.5 * j * (view * (1.0 - view) / 64.0).sqrt();
        let facet = r
            .exposure
            .reflected
            .irradiance_w_m2(f, k, edn as f64, ed as f64);
        eprintln!(
            "x {x} m: F {view:.4}, E_refl per hit {got:.2} W m⁻², analytic {want:.2} \
             (± {tol:.2}), facet {facet:.2}; ΔT {:.3} K",
            out[0].dt_k
        );
        assert!((got - want).abs() <= tol, "x {x}: {got} vs {want} ± {tol}");
        if let Some((t, e)) = prev {
            // Farther from the wall: less reflected sunlight, cooler.
            assert!(got < e && out[0].dt_k < t, "x {x}");
        }
        prev = Some((out[0].dt_k, got));
    }
    // Its temperature change against two single-point slab solves (the
    // point with its own sunlit history, shape factor and reflected
    // shortwave, the facet with its own; both see the 300 K wall and sky).
    // The ground point's rays all leave upward: what is not sky is wall,
    // whose radiosity per unit E_dn is ρ_w s_w cos θ_w (and ρ_w F̄_w per E_d).
    let (x, y) = (0.0f32, -1.0f32);
    let f = facet_at(&*tracer, x, y);
    let mut out = Vec::new();
    ph.states(&*tracer, &[(f as u32, Vec3::new(x, y, 0.0))], &mut out);
    let st = out[0];
    let fp = st.sky.unwrap().shape_factor;
    let w = r.point_response[0].as_ref().unwrap().records.clone();
    let last = w.len() - 1;
    let records: Vec<_> = w.iter().map(|&k| r.records[k]).collect();
    let forcing = Forcing::from_records(&records).unwrap();
    let at = |v: Vec<f32>| w.iter().map(|&k| v[k]).collect::<Vec<f32>>();
    let cos = at(sol.cos_incidence(f));
    let s_f = at(sol.sun_fraction(f));
    let s_p = sun_history(&r, &*tracer, f, x, y);
    let w0 = wall.start;
    let lit_wall: Vec<f32> = at(sol.sun_fraction(w0))
        .iter()
        .zip(at(sol.cos_incidence(w0)))
        .map(|(s, c)| s * c.max(0.0))
        .collect();
    let a_p: Vec<f32> = lit_wall.iter().map(|l| (1.0 - fp) * 0.5 * l).collect();
    let mean_f_wall =
        wall.clone().map(|j| sky.mean_shape_factor(j)).sum::<f32>() / wall.len() as f32;
    let b_p = ((1.0 - fp) * 0.5 * mean_f_wall) as f64;
    let a_f = at(r.exposure.reflected.direct(f));
    let b_f = r.exposure.reflected.diffuse[f] as f64;
    let props = asphalt();
    let t = |s: &[f32], shape: f32, direct: &[f32], diffuse: f64| {
        irsig::thermal::solve(
            &props,
            &forcing,
            &FacetInputs {
                background: Background::Constant(300.0),
                reflected: irsig::thermal::Reflected { direct, diffuse },
                ..FacetInputs::new(s, &cos, shape as f64)
            },
            &SolveOptions::default(),
        )
        .unwrap()
        .surface_temperature_k[last]
    };
    let ff = sky.shape_factor[f];
    let solo = t(&s_p, fp, &a_p, b_p) - t(&s_f, ff, &a_f, b_f);
    let no_refl = t(&s_p, fp, &a_f, b_f) - t(&s_f, ff, &a_f, b_f);
    eprintln!(
        "x 1 m: per-hit {:.3} K, single-point solves {solo:.3} K ({no_refl:.3} K with the \
         facet's reflected shortwave)",
        st.dt_k
    );
    assert!(solo - no_refl > 0.5, "the reflected shortwave matters");
    assert!(
        (st.dt_k as f64 - solo).abs() <= 0.05,
        "per-hit {} K vs solves {solo} K",
        st.dt_k
    );
    // A point at a facet's sample point sees what the facet saw.
    for f in ground.clone() {
        let q = r.exposure.facets.facet_points(f)[0];
        let mut out = Vec::new();
        ph.states(&*tracer, &[(f as u32, q)], &mut out);
        let facet = r
            .exposure
            .reflected
            .irradiance_w_m2(f, k, edn as f64, ed as f64) as f32;
        if let Some(s) = out[0].sky {
            assert_eq!(s.reflected_w_m2, facet);
            assert_eq!(s.shape_factor, sky.shape_factor[f]);
        }
        assert_eq!(out[0].dt_k, 0.0);
    }
}

/// Issue 18 item 1, the footprint rule of hits seen through a reflection:
/// a hit seen in a mirror takes its own temperature only where its facet
/// is large against the footprint of its **whole path** from the sensor
/// (the range to the mirror plus the mirror's range to the hit), as a
/// primary hit at that range would. The tower on a two-triangle ground
/// (spacing √7200 = 84.9 m), seen in a 20 m vertical mirror 15 m east of
/// it (ε = 0.05, wholly specular) by a camera of 0.0055 rad pixels; a
/// shaded and a sunlit patch of one ground triangle, seen in the mirror
/// only. With `per_hit_size_px` 160 the triangle is large against the
/// whole path's footprint: the mirror shows the tower's shadow. With 400 it
/// is not, though it would be against the part after the mirror alone
/// (the test checks both against the measured paths): the mirrored ground
/// takes its facet's one temperature and shows no shadow.
#[test]
fn ground_seen_in_a_mirror_takes_its_own_state_by_its_whole_path() {
    let dir = tempfile::tempdir().unwrap();
    let repo = crate::util::repo_path("scenes");
    let mats = dir.path().join("mirror.json");
    std::fs::write(
        &mats,
        r#"{"materials": [{"id": 90, "name": "mirror", "specific_heat_j_kg_k": 900,
            "conductivity_w_m_k": 200, "density_kg_m3": 2700, "thickness_m": 0.005,
            "solar_absorptivity": 0.1, "thermal_emissivity": 0.05, "exposed_area": 1,
            "specular_fraction": 1.0}]}"#,
    )
    .unwrap();
    let (cam, mirror_x) = (Vec3::new(-20.0, 6.0, 45.0), 14.9f32);
    let scene_for = |size_px: f32| {
        serde_json::json!({
            "site": {"latitude_deg": 43.16, "longitude_deg": -77.61, "altitude_m": 160, "utc_offset_hours": -4},
            "time": "2025-06-21T14:00:00-04:00",
            "weather": {"file": repo.join("town/weather.csv")},
            "materials": [repo.join("materials.json"), mats.clone()],
            "render": {"per_hit_size_px": size_px},
            "objects": [
                {"name": "ground", "material": "asphalt", "shapes": [{"plane": {"size": [120, 120]}}]},
                {"name": "tower", "material": "concrete", "shapes": [{"box": {"size": [4, 4, 20], "bottom": false}}]},
                {"name": "mirror", "material": "mirror", "shapes": [{"box": {"size": [0.2, 40, 20]},
                  "transform": {"translate": [mirror_x + 0.1, 6, 0]}}]}
            ],
            "sensors": [{"type": "frame", "name": "cam", "width": 128, "height": 128, "fov_deg": 40,
                         "position": [cam.x, cam.y, cam.z], "look_at": [mirror_x, 5, 15], "up": [0, 0, 1],
                         "bands": [{"name": "lwir", "response": [8.0, 12.0]}],
                         "truth_layers": ["x", "y", "z"]}]
        })
    };
    // Mean apparent temperature of the mirror's pixels whose mirrored ray
    // reaches the ground in [x0, x1] × [y0, y1], and the longest and
    // shortest whole path to those points and its part after the mirror.
    let render = |size_px: f32| {
        let path = dir.path().join(format!("scene-{size_px}.json"));
        std::fs::write(&path, serde_json::to_string(&scene_for(size_px)).unwrap()).unwrap();
        let out = dir.path().join(format!("out-{size_px}"));
        let o = std::process::Command::new(crate::util::irsig_bin())
            .args(["render", "--quiet", "-o"])
            .arg(&out)
            .arg(&path)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s = irsig::output::read_exr(out.join("cam.exr")).unwrap();
        let l = |n: &str| s.layer(n).unwrap().data.clone();
        (l("x"), l("y"), l("z"), l("apparent_temperature"))
    };
    type Image = (Vec<f32>, Vec<f32>, Vec<f32>, Vec<f32>);
    let mirrored = |(x, y, z, t): &Image, bx: (f32, f32, f32, f32)| {
        let (mut v, mut whole, mut after) = (Vec::new(), (f32::MAX, 0.0f32), (f32::MAX, 0.0f32));
        for k in 0..t.len() {
            let m = Vec3::new(x[k], y[k], z[k]);
            if (m.x - mirror_x).abs() > 1e-2 || m.z < 0.5 {
                continue;
            }
            let d = m - cam;
            let r = Vec3::new(-d.x, d.y, d.z).normalize();
            if r.z >= 0.0 {
                continue;
            }
            let g = m + r * (-m.z / r.z);
            if (bx.0..=bx.1).contains(&g.x) && (bx.2..=bx.3).contains(&g.y) {
                v.push(t[k]);
                let (w, a) = (d.length() + (g - m).length(), (g - m).length());
                whole = (whole.0.min(w), whole.1.max(w));
                after = (after.0.min(a), after.1.max(a));
            }
        }
        assert!(v.len() >= 4, "{} mirrored pixels in {bx:?}", v.len());
        (v.iter().sum::<f32>() / v.len() as f32, whole, after)
    };
    let (shade, lit) = ((-1.0, 1.0, 3.0, 6.0), (-9.0, -6.0, 3.0, 6.0));
    // The rule's numbers: the facets' spacing against size × path × β.
    let spacing = 7200.0f32.sqrt();
    let beta = 40f32.to_radians() / 128.0;
    let small = render(160.0);
    let (small_shade, whole_s, after_s) = mirrored(&small, shade);
    let (small_lit, whole_l, after_l) = mirrored(&small, lit);
    let (lo, hi) = (whole_s.0.min(whole_l.0), whole_s.1.max(whole_l.1));
    let after_hi = after_s.1.max(after_l.1);
    eprintln!(
        "whole path {lo:.1}–{hi:.1} m, after the mirror ≤ {after_hi:.1} m; \
         size 160: mirrored shadow {small_shade:.2} K, lit {small_lit:.2} K"
    );
    assert!(spacing > 160.0 * hi * beta);
    assert!(spacing < 400.0 * lo * beta && spacing > 400.0 * after_hi * beta);
    assert!(
        small_lit - small_shade > 3.0,
        "size 160: the mirror should show the shadow: {small_shade:.2} K vs {small_lit:.2} K"
    );
    let big = render(400.0);
    let (big_shade, _, _) = mirrored(&big, shade);
    let (big_lit, _, _) = mirrored(&big, lit);
    eprintln!("size 400: mirrored shadow {big_shade:.2} K, lit {big_lit:.2} K");
    assert!(
        (big_lit - big_shade).abs() < 0.5,
        "size 400: the facets' own (lit) values: {big_shade:.2} K vs {big_lit:.2} K"
    );
}

/// Issue 18 item 1, an exposed back's own sky view: a point of a thin
/// single-sided steel panel (both faces in the air) whose back is
/// sheltered by an 8 m wall 2 m behind it, on a triangle whose sample
/// point's back is open. The point traces its back's own view: its
/// temperature change from its facet against two single-point slab solves
/// (each with its own shape factors, sunlit history and background; the
/// back's `F_b` by brute force) within 0.1 K, where keeping the facet's
/// back view would be off by more than 0.5 K; at the facet's sample point
/// it takes the facet's temperature bit for bit.
#[test]
fn exposed_back_point_takes_its_own_back_sky_view() {
    use irsig::thermal::{BackBoundary, SlabProperties};
    // The panel; behind it (x = −2, facing +x) along y > 0, 8 m high.
    let (geo, ground, panel, walls) = panel_scene(&[(-2.0, 0.0, 8.0, true)]);
    let shelter = walls[0].clone();
    let n = geo.facet_count();
    let temp_of = |f: usize| {
        if ground.contains(&f) {
            290.0
        } else if shelter.contains(&f) {
            295.0
        } else {
            f32::NAN
        }
    };
    let steel = SlabProperties {
        conductivity_w_m_k: 45.0,
        density_kg_m3: 7800.0,
        specific_heat_j_kg_k: 500.0,
        thickness_m: 0.003,
        solar_absorptivity: 0.6,
        thermal_emissivity: 0.9,
        back: BackBoundary::BOTH_FACES,
        ..asphalt()
    };
    let setup = FacetThermalSetup {
        kinds: (0..n)
            .map(|f| {
                if panel.contains(&f) {
                    FacetThermal::Solve(0)
                } else {
                    FacetThermal::Fixed(temp_of(f))
                }
            })
            .collect(),
        props: vec![steel],
        ..Default::default()
    };
    let night = "2025-06-21T23:00:00-04:00";
    let (r, tracer) = solve_setup(&geo, &setup, night, 0.2);
    let ph = per_hit_full(&r, 0.2);
    // A point 3.5 m up at y = 10, in front of the shelter.
    let p = Vec3::new(0.0, 10.0, 3.5);
    let mut hit = [None];
    tracer.intersect(
        &[Ray::new(Vec3::new(1.0, 10.0, 3.5), -Vec3::X)],
        Coherence::Incoherent,
        &mut hit,
    );
    let f = hit[0].expect("the panel").prim as usize;
    assert!(panel.contains(&f));
    let fb_f = r.exposed_back_shape_factor[f].expect("an exposed back, traced");
    assert!(
        r.exposure.facets.facet_points(f)[0].y < 0.0,
        "the facet's sample point is clear of the shelter"
    );
    assert!(ph.own_sky(f));
    let mut out = Vec::new();
    ph.states(&*tracer, &[(f as u32, p)], &mut out);
    let st = out[0];
    let sky = st.sky.expect("its own sky view");
    let off = r.exposure.facets.offset_m;
    let (fb_p, _) = brute_force_face(&*tracer, p, -Vec3::X, off);
    eprintln!("panel point: back F_p {fb_p:.3} (brute force), facet's back F {fb_f:.3}");
    assert!(fb_f - fb_p > 0.2, "{fb_f} vs {fb_p}: the shelter matters");
    // Single-point solves, as in `double_sided_fence_takes_its_own_sky_view`.
    let ps = PointSolves::new(&r, &*tracer, f, p, false);
    let t = |s: &[f32], shape: f32, bg: f32, fb: f32| ps.t(&steel, s, shape, bg, Some(fb));
    let (s_p, s_f) = (&ps.s_p, &ps.s_f);
    let ff = r.exposure.sky.shape_factor[f];
    let t_bg_f = r.background_temperature_k(0)[f];
    let facet = t(s_f, ff, t_bg_f, fb_f);
    let solo = t(s_p, sky.shape_factor, sky.background_k, fb_p) - facet;
    let front_only = t(s_p, sky.shape_factor, sky.background_k, fb_f) - facet;
    eprintln!(
        "panel point: per-hit {:.3} K, single-point solves {solo:.3} K ({front_only:.3} K with the facet's back view)",
        st.dt_k
    );
    assert!(
        (solo - front_only).abs() > 0.5,
        "the back's view matters: {solo} vs {front_only} K"
    );
    assert!(
        (st.dt_k as f64 - solo).abs() <= 0.1,
        "per-hit {} K vs solves {solo} K",
        st.dt_k
    );
    // At the facet's sample point: the facet's temperature, bit for bit.
    let q = r.exposure.facets.facet_points(f)[0];
    ph.states(&*tracer, &[(f as u32, q)], &mut out);
    assert_eq!(out[0].dt_k, 0.0);
}
