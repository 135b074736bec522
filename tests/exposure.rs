//! Tests: exposure (solar history, shape factor, background) against
//! analytic view factors (tilted plane, Masson's urban canyon) and exact
//! shadow geometry.

use glam::Vec3;
use irsig::exposure::sampling::{dirsig_grid, triangle_strata};
use irsig::exposure::{ExposureParams, SkySampling, compute_exposure, exposed_back_shape_factors};
use irsig::geometry::{SceneGeometry, TriangleMesh};
use irsig::trace::{self, Backend, Coherence, Hit, Ray, Tracer};
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// Brute-force reference tracer: every ray against every triangle
/// (Möller & Trumbore 1997), both faces.
struct Brute {
    tris: Vec<([Vec3; 3], u32, u32)>,
}

impl Brute {
    fn new(g: &SceneGeometry) -> Self {
        let mut tris = Vec::new();
        for (ii, inst) in g.instances.iter().enumerate() {
            for p in 0..g.meshes[inst.mesh].triangle_count() {
                tris.push((g.world_triangle(ii, p), ii as u32, p as u32));
            }
        }
        Brute { tris }
    }
    fn hit(r: &Ray, t: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
        let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
        let p = r.dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-12 {
            return None;
        }
        let inv = 1.0 / det;
        let s = r.origin - t[0];
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(e1);
        let v = r.dir.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let d = e2.dot(q) * inv;
        (d >= r.tnear && d <= r.tfar).then_some((d, u, v))
    }
}

impl Tracer for Brute {
    fn name(&self) -> &str {
        "brute"
    }
    fn intersect(&self, rays: &[Ray], _: Coherence, out: &mut [Option<Hit>]) {
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            *o = None;
            for (t, inst, prim) in &self.tris {
                if let Some((d, u, v)) = Self::hit(r, t)
                    && o.is_none_or(|h| d < h.t)
                {
                    *o = Some(Hit {
                        t: d,
                        instance: *inst,
                        prim: *prim,
                        u,
                        v,
                        ng: (t[1] - t[0]).cross(t[2] - t[0]),
                    });
                }
            }
        }
    }
    fn occluded(&self, rays: &[Ray], _: Coherence, out: &mut [bool]) {
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            *o = self.tris.iter().any(|(t, _, _)| Self::hit(r, t).is_some());
        }
    }
}

/// Every query answered by Embree (packets), cross-checked ray by ray
/// against obvhs and the brute-force tracer: hit or miss, and the distance.
/// A disagreement counts only when the ray does not pass within 1e-4 (in
/// barycentrics) of a triangle edge, where backends legitimately differ
/// (e.g. a ray through the end edge of a wall). On drop (unless the test
/// already failed) it asserts that there were none.
pub(crate) struct Checked {
    backends: Vec<Box<dyn Tracer>>,
    brute: Brute,
    rays: AtomicU64,
    mismatches: AtomicU64,
}

impl Checked {
    pub(crate) fn new(g: &SceneGeometry) -> Self {
        Checked {
            backends: vec![
                trace::build(g, Backend::Embree).unwrap(),
                trace::build(g, Backend::Obvhs).unwrap(),
                Box::new(Brute::new(g)),
            ],
            brute: Brute::new(g),
            rays: AtomicU64::new(0),
            mismatches: AtomicU64::new(0),
        }
    }
    /// Whether `r` passes within 1e-4 (barycentric) of an edge of a
    /// triangle it crosses.
    fn grazes_an_edge(&self, r: &Ray) -> bool {
        let wide = 1e-4;
        self.brute.tris.iter().any(|(t, _, _)| {
            // Möller–Trumbore with a widened acceptance band.
            let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
            let p = r.dir.cross(e2);
            let det = e1.dot(p);
            if det.abs() < 1e-12 {
                return false;
            }
            let s = r.origin - t[0];
            let u = s.dot(p) / det;
            let v = r.dir.dot(s.cross(e1)) / det;
            let d = e2.dot(s.cross(e1)) / det;
            let w = 1.0 - u - v;
            d > 0.0 && u > -wide && v > -wide && w > -wide && u.min(v).min(w) < wide
        })
    }
    fn count(&self, rays: &[Ray], bad: impl Iterator<Item = usize>) {
        let real = bad.filter(|&i| !self.grazes_an_edge(&rays[i])).count();
        self.mismatches.fetch_add(real as u64, Relaxed);
    }
}

impl Drop for Checked {
    fn drop(&mut self) {
        let (r, m) = (self.rays.load(Relaxed), self.mismatches.load(Relaxed));
        if !std::thread::panicking() {
            assert_eq!(m, 0, "backends disagree on {m} of {r} rays away from edges");
        }
    }
}

impl Tracer for Checked {
    fn name(&self) -> &str {
        "checked"
    }
    fn intersect(&self, rays: &[Ray], c: Coherence, out: &mut [Option<Hit>]) {
        self.backends[0].intersect(rays, c, out);
        let mut other = vec![None; rays.len()];
        for b in &self.backends[1..] {
            b.intersect(rays, c, &mut other);
            let bad = out
                .iter()
                .zip(&other)
                .enumerate()
                .filter_map(|(i, (a, b))| {
                    let differ = match (a, b) {
                        (None, None) => false,
                        (Some(a), Some(b)) => (a.t - b.t).abs() > 1e-4 * a.t.max(1.0),
                        _ => true,
                    };
                    differ.then_some(i)
                });
            self.count(rays, bad);
        }
        self.rays.fetch_add(rays.len() as u64, Relaxed);
    }
    fn occluded(&self, rays: &[Ray], c: Coherence, out: &mut [bool]) {
        self.backends[0].occluded(rays, c, out);
        let mut other = vec![false; rays.len()];
        for b in &self.backends[1..] {
            b.occluded(rays, c, &mut other);
            let bad = out
                .iter()
                .zip(&other)
                .enumerate()
                .filter_map(|(i, (a, b))| (a != b).then_some(i));
            self.count(rays, bad);
        }
        self.rays.fetch_add(rays.len() as u64, Relaxed);
    }
}

/// Adds an `nu × nv` grid of quads (two triangles each) spanning
/// `p0 + [0,1]·eu + [0,1]·ev`, front face along `eu × ev`. Returns the range
/// of facet ids added.
pub(crate) fn quad(
    m: &mut TriangleMesh,
    p0: Vec3,
    eu: Vec3,
    ev: Vec3,
    nu: u32,
    nv: u32,
) -> std::ops::Range<usize> {
    let first = m.indices.len();
    for i in 0..nu {
        for j in 0..nv {
            let b = m.positions.len() as u32;
            let (u0, u1) = (i as f32 / nu as f32, (i + 1) as f32 / nu as f32);
            let (v0, v1) = (j as f32 / nv as f32, (j + 1) as f32 / nv as f32);
            m.positions.extend([
                p0 + u0 * eu + v0 * ev,
                p0 + u1 * eu + v0 * ev,
                p0 + u1 * eu + v1 * ev,
                p0 + u0 * eu + v1 * ev,
            ]);
            m.indices.extend([[b, b + 1, b + 2], [b, b + 2, b + 3]]);
        }
    }
    first..m.indices.len()
}

pub(crate) fn area_mean(
    exp: &irsig::exposure::Exposure,
    ids: std::ops::Range<usize>,
    v: &[f32],
) -> f64 {
    let (mut s, mut a) = (0.0f64, 0.0f64);
    for f in ids {
        s += (exp.facets.area[f] * v[f]) as f64;
        a += exp.facets.area[f] as f64;
    }
    s / a
}

pub(crate) fn stratified(samples: u32) -> ExposureParams {
    ExposureParams {
        sky: SkySampling::Stratified { samples },
        ..Default::default()
    }
}

#[test]
fn triangle_strata_are_equal_area_centroids() {
    for n in 1..=5 {
        let s = triangle_strata(n);
        assert_eq!(s.len(), (n * n) as usize);
        for &(a, b) in &s {
            assert!(a > 0.0 && b > 0.0 && a + b < 1.0, "({a},{b}) outside");
        }
        // Equal-area strata of a uniform density: their mean is the centroid.
        let (ma, mb) = s.iter().fold((0.0, 0.0), |(x, y), &(a, b)| (x + a, y + b));
        let k = s.len() as f32;
        assert!((ma / k - 1.0 / 3.0).abs() < 1e-6 && (mb / k - 1.0 / 3.0).abs() < 1e-6);
    }
}

#[test]
fn dirsig_grid_weights_are_the_cosine_measure() {
    let g = dirsig_grid(15.0, 30.0);
    assert_eq!(g.len(), 72);
    let sum: f64 = g.iter().map(|h| h.weight as f64).sum();
    assert!((sum - 1.0).abs() < 1e-6, "weights sum {sum}");
    // The top band (0–15°) holds sin²15° of the cosine-weighted measure.
    let top: f64 = g[..12].iter().map(|h| h.weight as f64).sum();
    assert!((top - (15f64.to_radians().sin().powi(2))).abs() < 1e-6);
    // Weighted mean of cos θ = ∫cos²θ dω/π / 1 = 2/3 (exact: 0.6667); the
    // 15° grid approximates it to 0.5 %.
    let mc: f64 = g.iter().map(|h| (h.weight * h.dir.z) as f64).sum();
    assert!((mc - 2.0 / 3.0).abs() < 0.005, "{mc}");
}

/// A 2 m square (2 × 2 cells) whose normal tilts from +z toward +y by `b`
/// radians, alone; its facets.
fn tilted_square(b: f32) -> (SceneGeometry, std::ops::Range<usize>) {
    let mut m = TriangleMesh::default();
    let eu = Vec3::new(2.0, 0.0, 0.0);
    let ev = Vec3::new(0.0, 2.0 * b.cos(), -2.0 * b.sin());
    let ids = quad(&mut m, Vec3::new(-1.0, -1.0, 1.0), eu, ev, 2, 2);
    (SceneGeometry::single(m), ids)
}

/// An unobstructed plane tilted by β sees (1 + cos β)/2 of the sky.
#[test]
fn tilted_plane_shape_factor() {
    for beta_deg in [0.0f32, 30.0, 60.0, 90.0, 120.0] {
        let b = beta_deg.to_radians();
        let (geo, ids) = tilted_square(b);
        let brute = Checked::new(&geo);
        let exact = (1.0 + b.cos() as f64) / 2.0;
        let exp = compute_exposure(&brute, &geo, &[], &[], &stratified(1024)).unwrap();
        let f = area_mean(&exp, ids.clone(), &exp.sky.shape_factor);
        assert!(
            (f - exact).abs() <= 0.01 * exact,
            "β={beta_deg}: F={f:.5}, (1+cosβ)/2={exact:.5}"
        );
        // Nothing to hit: the rest is ground below the horizon.
        for i in ids.clone() {
            assert!(exp.sky.background(i).is_empty());
            let s = exp.sky.shape_factor[i] + exp.sky.ground_weight[i];
            assert!((s - 1.0).abs() < 1e-5);
        }
        // DIRSIG's fixed grid: exact when horizontal, a few per cent off
        // when the horizon cuts its cells (documented on SkySampling::Grid).
        let grid = compute_exposure(&brute, &geo, &[], &[], &ExposureParams::default()).unwrap();
        let fg = area_mean(&grid, ids, &grid.sky.shape_factor);
        let tol = if beta_deg == 0.0 { 1e-6 } else { 0.04 };
        assert!(
            (fg - exact).abs() <= tol * exact,
            "grid β={beta_deg}: F={fg:.5}, exact {exact:.5}"
        );
    }
}

/// A long street canyon: road (width `w`, along x) between two walls of
/// height `h` facing each other; the middle `w`-long section is cut into
/// 10 strips across the road / up each wall. Returns the geometry and the
/// facet ranges of the road's and of one wall's middle sections.
pub(crate) fn canyon(
    h: f32,
    w: f32,
) -> (
    SceneGeometry,
    std::ops::Range<usize>,
    std::ops::Range<usize>,
) {
    let len = 100.0 * h.max(w);
    let (x0, xm0, xm1) = (-len / 2.0, -w / 2.0, w / 2.0);
    let mut m = TriangleMesh::default();
    let x = Vec3::X;
    // Road (normal +z): ends, then the middle strips.
    quad(
        &mut m,
        Vec3::new(x0, 0.0, 0.0),
        x * (xm0 - x0),
        Vec3::Y * w,
        1,
        1,
    );
    quad(
        &mut m,
        Vec3::new(xm1, 0.0, 0.0),
        x * (-x0 - xm1),
        Vec3::Y * w,
        1,
        1,
    );
    let road = quad(&mut m, Vec3::new(xm0, 0.0, 0.0), x * w, Vec3::Y * w, 1, 10);
    // South wall at y = 0 facing +y: eu = z, ev = x → normal z × x = +y.
    quad(
        &mut m,
        Vec3::new(x0, 0.0, 0.0),
        Vec3::Z * h,
        x * (xm0 - x0),
        1,
        1,
    );
    quad(
        &mut m,
        Vec3::new(xm1, 0.0, 0.0),
        Vec3::Z * h,
        x * (-x0 - xm1),
        1,
        1,
    );
    let wall = quad(&mut m, Vec3::new(xm0, 0.0, 0.0), Vec3::Z * h, x * w, 10, 1);
    // North wall at y = w facing −y: eu = x, ev = z → normal x × z = −y.
    quad(
        &mut m,
        Vec3::new(x0, w, 0.0),
        x * (-2.0 * x0),
        Vec3::Z * h,
        1,
        1,
    );
    (SceneGeometry::single(m), road, wall)
}

/// A street canyon `30·max(h, w)` long (along x) of sections `w` long,
/// each cut into 10 strips across the road (width `w`) and up the two walls
/// (height `h`, facing each other), so that every facet's own sky view is
/// sampled finely. Returns the geometry and the facets of the middle
/// section's road and south wall.
fn fine_canyon(h: f32, w: f32) -> (SceneGeometry, Vec<usize>, Vec<usize>) {
    let sections = (30.0 * h.max(w) / w).round() as usize | 1;
    let len = sections as f32 * w;
    let x0 = -len / 2.0;
    let mid = sections / 2;
    let mut m = TriangleMesh::default();
    let x = Vec3::X * len;
    // Road (normal x × y = +z): section-major.
    let ns = sections as u32;
    let road = quad(&mut m, Vec3::new(x0, 0.0, 0.0), x, Vec3::Y * w, ns, 10);
    let road: Vec<usize> = (road.start + 20 * mid..road.start + 20 * (mid + 1)).collect();
    // South wall at y = 0 (normal z × x = +y): strip-major over height.
    let south = quad(&mut m, Vec3::new(x0, 0.0, 0.0), Vec3::Z * h, x, 10, ns);
    let wall: Vec<usize> = (0..10)
        .flat_map(|i| {
            let f = south.start + 2 * (i * sections + mid);
            [f, f + 1]
        })
        .collect();
    // North wall at y = w (normal x × z = −y).
    quad(&mut m, Vec3::new(x0, w, 0.0), x, Vec3::Z * h, ns, 10);
    (SceneGeometry::single(m), road, wall)
}

/// Issue 19 item 3: the shortwave reflected between the road and walls of
/// a long canyon against its analytic radiosity solution. The reference is
/// the 2-D problem (infinitely long strips), each surface cut into the same
/// 10 strips as the facets, with exact strip-to-strip view factors by
/// Hottel's crossed strings (Modest, *Radiative Heat Transfer*, 3rd ed.,
/// 2013, §4.4; the canyon's cross-section is convex, so every pair sees
/// each other unobstructed), the sky view of a strip `1 − Σ_j F_ij`. The
/// sun shines along the canyon axis at 40° elevation (the road fully
/// sunlit, `E⁰ = sin 40°` per unit `E_dn`; the walls get none); the sky is
/// uniform (`E⁰ = F` per unit `E_d`); the ground beyond the scene is black.
/// One bounce against `R = F ρ E⁰`, forty bounces against the converged
/// radiosity `R = Σ_k (Fρ)ᵏ E⁰, k ≥ 1`; the middle section's mean over its
/// strips within 2 %. (Uniform radiosity per wall — one strip per surface —
/// differs from the resolved solution by ~3 %: a wall's lower part sees
/// less sky.)
#[test]
fn canyon_reflected_shortwave_matches_radiosity() {
    use irsig::exposure::reflected_shortwave;
    let (rho_road, rho_wall) = (0.4f64, 0.6f64);
    for hw in [0.5f64, 1.0, 2.0] {
        let w = 10.0f32;
        let h = hw as f32 * w;
        let (geo, road, wall) = fine_canyon(h, w);
        let elev = 40f32.to_radians();
        let sun = [
            Vec3::new(elev.cos(), 0.0, elev.sin()),
            Vec3::new(1.0, 0.0, -0.2).normalize(),
        ];
        let tracer = trace::build(&geo, Backend::Embree).unwrap();
        let exp = compute_exposure(&*tracer, &geo, &[], &sun, &stratified(1024)).unwrap();
        // The road's facets are those facing up, the walls the rest.
        let n = geo.facet_count();
        let albedo: Vec<f32> = (0..n)
            .map(|f| {
                if exp.facets.normal[f].z > 0.5 {
                    rho_road as f32
                } else {
                    rho_wall as f32
                }
            })
            .collect();
        // The 2-D reference: strips 0–9 road (y from 0 to W), 10–19 south
        // wall (y = 0), 20–29 north wall (y = W), in the (y, z) plane.
        let (wd, hd) = (w as f64, h as f64);
        let mut strips: Vec<([f64; 2], [f64; 2], f64)> = Vec::new();
        for k in 0..10 {
            let (a, b) = (k as f64 / 10.0, (k + 1) as f64 / 10.0);
            strips.push(([a * wd, 0.0], [b * wd, 0.0], rho_road));
        }
        for y in [0.0, wd] {
            for k in 0..10 {
                let (a, b) = (k as f64 / 10.0, (k + 1) as f64 / 10.0);
                strips.push(([y, a * hd], [y, b * hd], rho_wall));
            }
        }
        let dist =
            |p: [f64; 2], q: [f64; 2]| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
        let m = strips.len();
        let mut fv = vec![vec![0.0f64; m]; m];
        for i in 0..m {
            for j in (0..m).filter(|&j| j != i) {
                let ((a1, a2, _), (b1, b2, _)) = (strips[i], strips[j]);
                let crossed = dist(a1, b2) + dist(a2, b1);
                let uncrossed = dist(a1, b1) + dist(a2, b2);
                fv[i][j] = (crossed - uncrossed).abs() / (2.0 * dist(a1, a2));
            }
        }
        let sky: Vec<f64> = (0..m).map(|i| 1.0 - fv[i].iter().sum::<f64>()).collect();
        let sin_e = (elev as f64).sin();
        let e0_direct: Vec<f64> = (0..m).map(|i| if i < 10 { sin_e } else { 0.0 }).collect();
        let radiosity = |e0: &[f64], bounces: usize| -> Vec<f64> {
            let mut r = vec![0.0f64; m];
            for _ in 0..bounces {
                r = (0..m)
                    .map(|i| {
                        (0..m)
                            .map(|j| fv[i][j] * strips[j].2 * (e0[j] + r[j]))
                            .sum()
                    })
                    .collect();
            }
            r
        };
        let mean = |v: &[f64], range: std::ops::Range<usize>| -> f64 {
            v[range.clone()].iter().sum::<f64>() / range.len() as f64
        };
        // Every facet of a section has the same area.
        let mean_of = |ids: &[usize], v: &[f32]| -> f64 {
            ids.iter().map(|&f| v[f] as f64).sum::<f64>() / ids.len() as f64
        };
        for (bounces, label) in [(1u32, "one bounce"), (40, "converged")] {
            let refl =
                reflected_shortwave(&exp.sky, &exp.solar, &albedo, 0.0, &sun, bounces).unwrap();
            let rd = radiosity(&e0_direct, bounces as usize);
            let rs = radiosity(&sky, bounces as usize);
            let direct: Vec<f32> = (0..n).map(|f| refl.direct(f)[0]).collect();
            let got = [
                ("road direct", mean_of(&road, &direct), mean(&rd, 0..10)),
                ("wall direct", mean_of(&wall, &direct), mean(&rd, 10..20)),
                (
                    "road diffuse",
                    mean_of(&road, &refl.diffuse),
                    mean(&rs, 0..10),
                ),
                (
                    "wall diffuse",
                    mean_of(&wall, &refl.diffuse),
                    mean(&rs, 10..20),
                ),
            ];
            for (what, v, exact) in got {
                eprintln!("H/W={hw} {label}: {what} {v:.5} (analytic {exact:.5})");
                if exact == 0.0 {
                    assert_eq!(v, 0.0, "H/W={hw} {label} {what}");
                } else {
                    assert!(
                        (v - exact).abs() <= 0.02 * exact,
                        "H/W={hw} {label}: {what} {v:.5} vs {exact:.5}"
                    );
                }
            }
            // Night: nothing reflected of the direct beam.
            assert!((0..n).all(|f| refl.direct(f)[1] == 0.0));
        }
    }
}

/// The bounces after the first at hourly nodes of the day records (the
/// default, `exposure::reflected::LATER_BOUNCE_STRIDE`), their addition to
/// the first bounce linear in between, against every bounce at every
/// record (stride 1, the reference): a street canyon (H/W = 1) running
/// east–west, the sun sweeping from east through south to west over 15-min
/// records so that the shadows of the walls cross the road. Nodes are
/// exact (bit for bit); between them the error stays a small part of what
/// the later bounces add, and the first bounce is identical.
#[test]
fn later_bounces_at_nodes_match_every_record() {
    use irsig::exposure::reflected::{LATER_BOUNCE_STRIDE, reflected_shortwave_strided};
    let (geo, _, _) = fine_canyon(10.0, 10.0);
    // 06:00–18:00 every 15 min, then two night records.
    let mut dirs: Vec<Vec3> = (0..=48)
        .map(|i| {
            let h = i as f32 / 48.0;
            let elev = 5.0 + 55.0 * (std::f32::consts::PI * h).sin();
            sun(elev, 90.0 + 180.0 * h)
        })
        .collect();
    dirs.extend([sun(-10.0, 300.0), sun(-20.0, 330.0)]);
    let tracer = trace::build(&geo, Backend::Embree).unwrap();
    let exp = compute_exposure(&*tracer, &geo, &[], &dirs, &stratified(256)).unwrap();
    let n = geo.facet_count();
    let albedo: Vec<f32> = (0..n)
        .map(|f| {
            if exp.facets.normal[f].z > 0.5 {
                0.3
            } else {
                0.5
            }
        })
        .collect();
    let r = dirs.len();
    let solve = |bounces: u32, stride: usize| {
        reflected_shortwave_strided(&exp.sky, &exp.solar, &albedo, 0.2, &dirs, bounces, stride)
            .unwrap()
    };
    let first = solve(1, 1);
    assert_eq!(
        first,
        solve(1, LATER_BOUNCE_STRIDE),
        "the first bounce is exact"
    );
    for bounces in [2u32, 10] {
        let every = solve(bounces, 1);
        let nodes = solve(bounces, LATER_BOUNCE_STRIDE);
        assert_eq!(every.diffuse, nodes.diffuse);
        let (mut max_err, mut max_add, mut max_a) = (0.0f32, 0.0f32, 0.0f32);
        for f in 0..n {
            for k in 0..r {
                let (e, c, a1) = (every.direct(f)[k], nodes.direct(f)[k], first.direct(f)[k]);
                max_err = max_err.max((c - e).abs());
                max_add = max_add.max(e - a1);
                max_a = max_a.max(e);
                if k % LATER_BOUNCE_STRIDE == 0 || k >= 48 {
                    // Nodes and night records: the same iteration.
                    assert_eq!(c, e, "facet {f}, record {k}");
                }
            }
        }
        eprintln!(
            "{bounces} bounces: max |nodes − every record| {max_err:.5} per unit E_dn; \
             later bounces add up to {max_add:.4}, reflected up to {max_a:.4}"
        );
        assert!(max_add > 0.01, "the later bounces matter here ({max_add})");
        assert!(max_err <= 0.1 * max_add, "{max_err} vs {max_add}");
    }
}

/// The reflected shortwave is held on the day records only and computed
/// block by block with each facet's `E⁰` recomputed from the solar history
/// (no per-record copy): decoded, it equals bit for bit the exhaustive
/// per-record Jacobi iteration written out here over every record (night
/// records exactly 0), for one and three bounces; the thermal inputs
/// decode the same values, also through a window's slots; a slot out of
/// range is refused, naming it. A street canyon (H/W = 1) over 36 h at
/// 15 min (two nights), the sun sweeping across it so that the walls'
/// shadows cross the road.
#[test]
fn compact_reflected_shortwave_equals_the_exhaustive_records() {
    use irsig::exposure::reflected::{NIGHT, reflected_shortwave_strided};
    use irsig::thermal::scene::SceneInputs;
    let (geo, _, _) = fine_canyon(10.0, 10.0);
    let steps: Vec<Vec3> = (0..=144)
        .map(|i| {
            let hour = (i as f32 * 0.25) % 24.0;
            let s = (std::f32::consts::PI * (hour - 6.0) / 12.0).sin();
            let elev = if s > 0.0 { 60.0 * s } else { -10.0 };
            sun(elev, 90.0 + 180.0 * ((hour - 6.0) / 12.0).clamp(0.0, 1.0))
        })
        .collect();
    let tracer = trace::build(&geo, Backend::Embree).unwrap();
    let exp = compute_exposure(&*tracer, &geo, &[], &steps, &stratified(64)).unwrap();
    let (n, r) = (geo.facet_count(), steps.len());
    let albedo: Vec<f32> = (0..n)
        .map(|f| {
            if exp.facets.normal[f].z > 0.5 {
                0.3
            } else {
                0.5
            }
        })
        .collect();
    let ground_albedo = 0.2f32;
    let day: Vec<u32> = (0..r as u32)
        .filter(|&k| steps[k as usize].z > 0.0)
        .collect();
    assert!(
        day.len() > 40 && day.len() < r - 40,
        "two nights in the window"
    );
    // E⁰ per unit E_dn, every record.
    let e0: Vec<Vec<f32>> = (0..n)
        .map(|f| {
            let (s, c) = (exp.solar.sun_fraction(f), exp.solar.cos_incidence(f));
            s.iter()
                .zip(&c)
                .map(|(s, c)| s.clamp(0.0, 1.0) * c.max(0.0))
                .collect()
        })
        .collect();
    for bounces in [1u32, 3] {
        // The exhaustive iteration, record by record.
        let mut prev = vec![vec![0.0f32; r]; n];
        for _ in 0..bounces {
            let next: Vec<Vec<f32>> = (0..n)
                .map(|i| {
                    (0..r)
                        .map(|k| {
                            let z = steps[k].z;
                            if z <= 0.0 {
                                return 0.0;
                            }
                            let mut o = exp.sky.ground_weight[i] * ground_albedo * z;
                            for e in exp.sky.background(i) {
                                let j = e.facet as usize;
                                o += e.weight * (albedo[j] * (e0[j][k] + prev[j][k]));
                            }
                            o
                        })
                        .collect()
                })
                .collect();
            prev = next;
        }
        let refl = reflected_shortwave_strided(
            &exp.sky,
            &exp.solar,
            &albedo,
            ground_albedo,
            &steps,
            bounces,
            1,
        )
        .unwrap();
        // Held: one value per facet and day record.
        assert_eq!(refl.day, day);
        assert_eq!(refl.direct.len(), n * day.len());
        assert_eq!(refl.slot.len(), r);
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut lit_records = 0;
        for (f, want) in prev.iter().enumerate() {
            let got = refl.direct(f);
            assert_eq!(bits(&got), bits(want), "facet {f}, {bounces} bounces");
            for k in 0..r {
                assert_eq!(refl.direct_at(f, k), want[k]);
                if refl.slot[k] == NIGHT {
                    assert_eq!(got[k].to_bits(), 0, "night record {k}");
                }
            }
            lit_records += got.iter().filter(|&&a| a > 0.0).count();
        }
        assert!(lit_records > n * day.len() / 2, "{lit_records}");
        // The thermal inputs decode the same coefficients, over the whole
        // history and over a window of it.
        let mut with = exp.clone();
        with.reflected = refl.clone();
        let inputs = SceneInputs::from(&with);
        inputs.validate().unwrap();
        let window: Vec<usize> = (30..130).step_by(3).collect();
        let slots: Vec<u32> = window.iter().map(|&k| refl.slot[k]).collect();
        for (f, all) in prev.iter().enumerate() {
            let d = inputs.reflected(f);
            assert_eq!(bits(&d.direct), bits(all));
            assert_eq!(d.diffuse, refl.diffuse[f] as f64);
            let w = SceneInputs {
                reflected_slot: &slots,
                records: window.len(),
                ..inputs
            };
            let got = w.reflected(f).direct;
            let want: Vec<f32> = window.iter().map(|&k| all[k]).collect();
            assert_eq!(bits(&got), bits(&want));
        }
        // A slot beyond the values held is refused, named.
        let mut bad = refl.slot.clone();
        bad[day[0] as usize] = day.len() as u32;
        let e = SceneInputs {
            reflected_slot: &bad,
            ..inputs
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(e.contains(&format!("reflected_slot[{}]", day[0])), "{e}");
    }
}

/// Masson (2000), Boundary-Layer Meteorol. 94, 357–397, eqs. 8–9: sky view
/// factors of the road and walls of an infinite canyon.
#[test]
fn urban_canyon_shape_factors_match_masson() {
    let cases = [
        (0.5f64, 0.618034, 0.381966),
        (1.0, 0.414214, 0.292893),
        (2.0, 0.236068, 0.190983),
    ];
    for (hw, road_ref, wall_ref) in cases {
        // The formulas themselves, as a check of the reference values.
        let r = (hw * hw + 1.0).sqrt() - hw;
        let wl = 0.5 * (hw + 1.0 - (hw * hw + 1.0).sqrt()) / hw;
        assert!((r - road_ref).abs() < 1e-6 && (wl - wall_ref).abs() < 1e-6);
        let w = 10.0f32;
        let (geo, road, wall) = canyon(hw as f32 * w, w);
        let brute = Checked::new(&geo);
        let exp = compute_exposure(&brute, &geo, &[], &[], &stratified(4096)).unwrap();
        let fr = area_mean(&exp, road.clone(), &exp.sky.shape_factor);
        let fw = area_mean(&exp, wall.clone(), &exp.sky.shape_factor);
        eprintln!(
            "H/W={hw}: road F={fr:.5} (Masson {road_ref}), wall F={fw:.5} (Masson {wall_ref})"
        );
        assert!(
            (fr - road_ref).abs() <= 0.02 * road_ref,
            "road H/W={hw}: {fr:.5} vs {road_ref}"
        );
        assert!(
            (fw - wall_ref).abs() <= 0.02 * wall_ref,
            "wall H/W={hw}: {fw:.5} vs {wall_ref}"
        );
        // View factors of every facet add up to one; the road sees only
        // sky and walls, the wall sky, road and the other wall.
        for f in 0..geo.facet_count() {
            let bg: f32 = exp.sky.background(f).iter().map(|e| e.weight).sum();
            let total = exp.sky.shape_factor[f] + exp.sky.ground_weight[f] + bg;
            assert!((total - 1.0).abs() < 1e-4, "facet {f}: sum {total}");
        }
        for f in road.clone() {
            assert_eq!(exp.sky.ground_weight[f], 0.0);
            assert!(
                exp.sky
                    .background(f)
                    .iter()
                    .all(|e| !road.contains(&(e.facet as usize)))
            );
        }
        // Road ↔ walls: the road sees the walls with 1 − F_road (Masson's
        // road-to-wall factor), each wall with half of it.
        let road_to_wall: f64 = road
            .clone()
            .map(|f| {
                let s: f32 = exp
                    .sky
                    .background(f)
                    .iter()
                    .filter(|e| e.facet as usize >= road.end)
                    .map(|e| e.weight)
                    .sum();
                (s * exp.facets.area[f]) as f64
            })
            .sum::<f64>()
            / road.clone().map(|f| exp.facets.area[f] as f64).sum::<f64>();
        assert!((road_to_wall - (1.0 - road_ref)).abs() < 0.02 * (1.0 - road_ref));
        // DIRSIG's fixed grid, for the record (its quadrature error is
        // larger in a deep canyon).
        let g = compute_exposure(&brute, &geo, &[], &[], &ExposureParams::default()).unwrap();
        eprintln!(
            "  DIRSIG grid: road F={:.5}, wall F={:.5}",
            area_mean(&g, road.clone(), &g.sky.shape_factor),
            area_mean(&g, wall.clone(), &g.sky.shape_factor)
        );
    }
}

/// A wall (x from −5 to 5, height 2 m, along y = 0, facing −y = south) on a
/// ground of 1 m strips from y = −4 to y = 4 (the wall's foot at y = 0).
pub(crate) fn wall_on_ground(
    double_sided_wall: bool,
) -> (
    SceneGeometry,
    Vec<bool>,
    std::ops::Range<usize>,
    std::ops::Range<usize>,
) {
    let mut m = TriangleMesh::default();
    let ground = quad(
        &mut m,
        Vec3::new(-5.0, -4.0, 0.0),
        Vec3::X * 10.0,
        Vec3::Y * 8.0,
        1,
        8,
    );
    // eu = x, ev = z → normal x × z = −y.
    let wall = quad(
        &mut m,
        Vec3::new(-5.0, 0.0, 0.0),
        Vec3::X * 10.0,
        Vec3::Z * 2.0,
        1,
        1,
    );
    let mut ds = vec![false; m.indices.len()];
    for f in wall.clone() {
        ds[f] = double_sided_wall;
    }
    (SceneGeometry::single(m), ds, ground, wall)
}

/// Sun direction from elevation and azimuth (degrees clockwise from north).
pub(crate) fn sun(elev_deg: f32, az_deg: f32) -> Vec3 {
    let (e, a) = (elev_deg.to_radians(), az_deg.to_radians());
    Vec3::new(e.cos() * a.sin(), e.cos() * a.cos(), e.sin())
}

#[test]
fn solar_history_of_ground_shaded_by_a_wall() {
    let (geo, _, ground, wall) = wall_on_ground(false);
    let brute = Checked::new(&geo);
    // Steps: night; sun due north at 45° (the wall, 2 m, shades y ∈ [−2, 0]
    // to the south); due south at 45° (shades y ∈ [0, 2], and lights the
    // south-facing wall); due east at 30° (the wall is edge-on: no shadow,
    // cos θ = 0 on the wall).
    let steps = [
        sun(-10.0, 180.0),
        sun(45.0, 0.0),
        sun(45.0, 180.0),
        sun(30.0, 90.0),
    ];
    let params = ExposureParams {
        samples_per_edge: 4,
        ..Default::default()
    };
    let exp = compute_exposure(&brute, &geo, &[], &steps, &params).unwrap();
    let s = &exp.solar;
    assert_eq!(s.steps, 4);
    // Strip k (two facets) spans y ∈ [−4 + k, −3 + k].
    let strip = |f: usize| ((f - ground.start) / 2) as i32 - 4;
    for f in ground.clone() {
        let (fr, ci) = (s.sun_fraction(f), s.cos_incidence(f));
        let y0 = strip(f) as f32;
        assert_eq!((fr[0], ci[0]), (0.0, 0.0), "night");
        for k in 1..4 {
            assert!(
                (ci[k] - steps[k].z).abs() < 1e-6,
                "cos θ of a horizontal facet is sin(elevation)"
            );
        }
        // Sun north at 45°: shadow on y ∈ [−2, 0] exactly.
        let expect = if (-2.0..0.0).contains(&y0) { 0.0 } else { 1.0 };
        assert_eq!(fr[1], expect, "step 1, strip at y={y0}");
        // Sun south at 45°: shadow on y ∈ [0, 2].
        let expect = if (0.0..2.0).contains(&y0) { 0.0 } else { 1.0 };
        assert_eq!(fr[2], expect, "step 2, strip at y={y0}");
        assert_eq!(fr[3], 1.0, "sun along the wall: no shadow");
    }
    for f in wall {
        let (fr, ci) = (s.sun_fraction(f), s.cos_incidence(f));
        // Facing south: the northern sun is behind it.
        assert_eq!((fr[1], ci[1]), (0.0, 0.0));
        assert_eq!(fr[2], 1.0);
        assert!((ci[2] - 45f32.to_radians().cos()).abs() < 1e-6);
        assert!(ci[3].abs() < 1e-6, "edge-on sun: cos θ = {}", ci[3]);
    }
}

#[test]
fn partial_shadow_matches_the_sunlit_area() {
    let (geo, _, ground, _) = wall_on_ground(false);
    let brute = Checked::new(&geo);
    // Sun south at atan(2/1.5): the 2 m wall shades y ∈ [0, 1.5]; the strip
    // y ∈ [1, 2] is half in shadow.
    let elev = (2.0f32 / 1.5).atan().to_degrees();
    let params = ExposureParams {
        samples_per_edge: 8,
        ..Default::default()
    };
    let exp = compute_exposure(&brute, &geo, &[], &[sun(elev, 180.0)], &params).unwrap();
    // Strip 5 (facets 10, 11 of the ground) spans y ∈ [1, 2].
    let strip = ground.start + 10..ground.start + 12;
    let mean = area_mean(&exp, strip, &crate::util::sun_fractions(&exp.solar));
    assert!((mean - 0.5).abs() < 1.0 / 32.0, "half-shaded strip: {mean}");
}

#[test]
fn double_sided_facets_take_sun_and_sky_on_both_faces() {
    let (geo, ds, _, wall) = wall_on_ground(true);
    let brute = Checked::new(&geo);
    let steps = [sun(45.0, 0.0), sun(45.0, 180.0)];
    let exp = compute_exposure(&brute, &geo, &ds, &steps, &stratified(1024)).unwrap();
    let c45 = 45f32.to_radians().cos();
    for f in wall.clone() {
        assert_eq!(exp.solar.sun_fraction(f), &[1.0, 1.0]);
        for c in exp.solar.cos_incidence(f) {
            assert!((c - c45).abs() < 1e-6);
        }
        // Each face of a vertical wall standing on the ground sees half the
        // sky (F = 1/2 each), and ground below it: the mean is 1/2 too.
        assert!(
            (exp.sky.shape_factor[f] - 0.5).abs() < 0.01,
            "{}",
            exp.sky.shape_factor[f]
        );
    }
    // Single-sided: the wall's back gets no sun.
    let one = compute_exposure(&brute, &geo, &[], &steps, &stratified(64)).unwrap();
    for f in wall {
        assert_eq!(one.solar.sun_fraction(f), &[0.0, 1.0]);
        assert_eq!(one.sky.back_shape_factor(f), None);
    }
}

#[test]
fn results_do_not_depend_on_threads_or_batches() {
    let (geo, _, _) = canyon(10.0, 10.0);
    let brute = Checked::new(&geo);
    let steps = [sun(30.0, 135.0), sun(60.0, 200.0)];
    let run = |threads: usize, batch: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let params = ExposureParams {
            batch_facets: batch,
            ..stratified(256)
        };
        pool.install(|| compute_exposure(&brute, &geo, &[], &steps, &params).unwrap())
    };
    let a = run(1, 512);
    for (t, b) in [(2, 1), (3, 7)] {
        let b = run(t, b);
        assert_eq!(a.sky, b.sky);
        assert_eq!(a.solar, b.solar);
    }
}

/// Issue 23: the solar history is stored compactly (lit sample points per
/// facet and day record, one byte — two above 255 points; no night
/// records; the cosine of incidence recomputed from the normal and the
/// sun), and its decoded sun fractions and cosines equal, bit for bit, the
/// exhaustive per-record `f32` answer traced here ray by ray: a wall
/// (single- and double-sided) shading the ground over 36 h at 15 min (two
/// nights), with 9 and 256 sample points per facet.
#[test]
fn compact_solar_history_equals_the_exhaustive_arrays() {
    let steps: Vec<Vec3> = (0..=144)
        .map(|i| {
            let hour = (i as f32 * 0.25) % 24.0;
            let s = (std::f32::consts::PI * (hour - 6.0) / 12.0).sin();
            let elev = if s > 0.0 { 60.0 * s } else { -10.0 };
            sun(elev, 90.0 + 180.0 * ((hour - 6.0) / 12.0).clamp(0.0, 1.0))
        })
        .collect();
    let day = steps.iter().filter(|d| d.z > 0.0).count();
    assert!(day > 0 && day < steps.len());
    for (double_sided, per_edge) in [(false, 3), (true, 3), (false, 16)] {
        let (geo, ds, _, _) = wall_on_ground(double_sided);
        let tracer = Brute::new(&geo);
        let params = ExposureParams {
            samples_per_edge: per_edge,
            ..Default::default()
        };
        let exp = compute_exposure(&tracer, &geo, &ds, &steps, &params).unwrap();
        let (fx, s) = (&exp.facets, &exp.solar);
        let m = fx.per_facet;
        assert_eq!(m, (per_edge * per_edge) as usize);
        // The storage: one count per facet and day record.
        assert_eq!(s.day.len(), day);
        assert_eq!(s.width(), if m > 255 { 2 } else { 1 });
        assert_eq!(s.lit.len(), fx.len() * day * s.width());
        // The exhaustive answer, ray by ray.
        let mut sun_ref = vec![0.0f32; fx.len() * steps.len()];
        let mut cos_ref = vec![0.0f32; fx.len() * steps.len()];
        for f in 0..fx.len() {
            for (k, &dir) in steps.iter().enumerate() {
                let c = fx.normal[f].dot(dir);
                if dir.z <= 0.0 || !(fx.double_sided[f] || c > 0.0) || c == 0.0 {
                    continue;
                }
                let lift = fx.normal[f] * (c.signum() * fx.offset_m);
                let rays: Vec<Ray> = fx
                    .facet_points(f)
                    .iter()
                    .map(|&p| Ray::new(p + lift, dir))
                    .collect();
                let mut occ = vec![false; rays.len()];
                tracer.occluded(&rays, Coherence::Coherent, &mut occ);
                let lit = occ.iter().filter(|&&o| !o).count();
                sun_ref[f * steps.len() + k] = lit as f32 / m as f32;
                cos_ref[f * steps.len() + k] = c.abs().min(1.0);
            }
        }
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&crate::util::sun_fractions(s)), bits(&sun_ref));
        assert_eq!(bits(&crate::util::cos_incidences(s)), bits(&cos_ref));
        // Partial shadows occur (the counts are not all 0 or m).
        assert!(sun_ref.iter().any(|&x| x > 0.0 && x < 1.0));
        // Per-record access agrees with the decoded histories.
        for f in 0..fx.len() {
            for k in [0, 40, 72, 100, 144] {
                assert_eq!(s.sun_fraction_at(f, k), sun_ref[f * steps.len() + k]);
                assert_eq!(s.cos_incidence_at(f, k), cos_ref[f * steps.len() + k]);
            }
        }
        // The compact history of the exhaustive arrays is the traced one.
        let back = irsig::exposure::SolarHistory::from_fractions(
            &sun_ref,
            &steps,
            m as u32,
            &fx.normal,
            &fx.double_sided,
        )
        .unwrap();
        assert_eq!(&back, s);
        // A value that is not a multiple of 1/m, or sun at night, is refused.
        let mut bad = sun_ref.clone();
        bad[0] = 0.5 / m as f32;
        let e = irsig::exposure::SolarHistory::from_fractions(
            &bad,
            &steps,
            m as u32,
            &fx.normal,
            &fx.double_sided,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("facet 0, record 0"), "{e}");
    }
}

/// Issue 18: the solar history traced at coarse steps and refined where a
/// sample point's visibility changes gives the answer of tracing every step
/// but for brief shadows (here, near the wall's ends at sunrise and sunset,
/// where a point's visibility flips for a step or two between two coarse
/// steps: at most stride/2 % of the daytime sun fractions), with far fewer
/// rays: a wall and a double-sided one over 36 h at
/// 15-min steps, two nights in the window.
#[test]
fn refined_solar_history_matches_every_step() {
    for double_sided in [false, true] {
        let (geo, ds, _, _) = wall_on_ground(double_sided);
        let tracer = Checked::new(&geo);
        // 36 h at 15 min: night, a day with the sun from east through
        // south to west, night, and half a day.
        let steps: Vec<Vec3> = (0..=144)
            .map(|i| {
                let hour = (i as f32 * 0.25) % 24.0;
                let s = (std::f32::consts::PI * (hour - 6.0) / 12.0).sin();
                let elev = if s > 0.0 { 60.0 * s } else { -10.0 };
                sun(elev, 90.0 + 180.0 * ((hour - 6.0) / 12.0).clamp(0.0, 1.0))
            })
            .collect();
        let run = |stride| {
            let params = ExposureParams {
                samples_per_edge: 3,
                solar_stride: stride,
                ..Default::default()
            };
            compute_exposure(&tracer, &geo, &ds, &steps, &params).unwrap()
        };
        let every = run(1);
        assert!(
            crate::util::sun_fractions(&every.solar)
                .iter()
                .any(|&f| f > 0.0 && f < 1.0)
        );
        for stride in [2, 4, 8] {
            let r = run(stride);
            assert_eq!(
                crate::util::cos_incidences(&r.solar),
                crate::util::cos_incidences(&every.solar)
            );
            let day = crate::util::cos_incidences(&every.solar)
                .iter()
                .filter(|&&c| c > 0.0)
                .count();
            let differ = crate::util::sun_fractions(&r.solar)
                .iter()
                .zip(&crate::util::sun_fractions(&every.solar))
                .filter(|(a, b)| a != b)
                .count();
            eprintln!(
                "stride {stride}, double-sided {double_sided}: {differ} of {day} daytime sun fractions differ"
            );
            assert!(
                differ * 200 <= day * stride as usize,
                "stride {stride}, double-sided {double_sided}: {differ} of {day} differ"
            );
            assert!(
                (r.stats.solar_rays as f64)
                    < every.stats.solar_rays as f64 * (1.0 / stride as f64 + 0.1),
                "stride {stride}: {} rays vs {}",
                r.stats.solar_rays,
                every.stats.solar_rays
            );
        }
    }
}

/// The paired-strata error estimate is honest: across many independent
/// facets, the actual errors' RMS is of the order of the estimated SE's.
#[test]
fn stratified_error_estimate_tracks_the_actual_error() {
    let b = 60f32.to_radians();
    let mut m = TriangleMesh::default();
    // 400 small coplanar facets on a plane tilted 60°: independent jitter.
    let eu = Vec3::new(20.0, 0.0, 0.0);
    let ev = Vec3::new(0.0, 10.0 * b.cos(), -10.0 * b.sin());
    quad(&mut m, Vec3::ZERO, eu, ev, 20, 10);
    let geo = SceneGeometry::single(m);
    let exact = (1.0 + b.cos()) / 2.0;
    let exp = compute_exposure(&Checked::new(&geo), &geo, &[], &[], &stratified(64)).unwrap();
    let n = geo.facet_count() as f32;
    let rms_err = (exp
        .sky
        .shape_factor
        .iter()
        .map(|f| (f - exact).powi(2))
        .sum::<f32>()
        / n)
        .sqrt();
    let rms_se = (exp.sky.std_error.iter().map(|s| s * s).sum::<f32>() / n).sqrt();
    eprintln!("64 rays: RMS error {rms_err:.5}, RMS estimated SE {rms_se:.5}");
    assert!(rms_err > 0.0);
    assert!(
        rms_se >= 0.7 * rms_err && rms_se <= 4.0 * rms_err,
        "{rms_se} vs {rms_err}"
    );
}

#[test]
fn bad_inputs_are_reported() {
    let (geo, _, _, _) = wall_on_ground(false);
    let brute = Checked::new(&geo);
    let e =
        compute_exposure(&brute, &geo, &[true; 3], &[], &ExposureParams::default()).unwrap_err();
    assert!(
        e.to_string().contains("double_sided") && e.to_string().contains("one flag per facet"),
        "{e}"
    );
    let e = compute_exposure(
        &brute,
        &geo,
        &[],
        &[Vec3::new(0.0, 0.0, 2.0)],
        &ExposureParams::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("sun_dirs[0]"), "{e}");
    let p = ExposureParams {
        samples_per_edge: 0,
        ..Default::default()
    };
    assert!(
        compute_exposure(&brute, &geo, &[], &[], &p)
            .unwrap_err()
            .to_string()
            .contains("samples_per_edge")
    );
}

#[test]
fn history_window_puts_the_image_times_on_the_grid() {
    use chrono::{DateTime, TimeDelta};
    use irsig::exposure::{HistoryWindow, history_times};
    let (weather, _) = irsig::weather::synth::town_history().unwrap();
    let a = DateTime::parse_from_rfc3339("2025-06-21T13:00:00-04:00").unwrap();
    let b = DateTime::parse_from_rfc3339("2025-06-21T13:07:00-04:00").unwrap();
    let w = HistoryWindow::default();
    let t = history_times(&weather, &[b, a], &w).unwrap();
    // 24 h at 15 min from 13:00 the day before, then 13:07.
    assert_eq!(t.len(), 96 + 1 + 1);
    assert_eq!(t[0], a - TimeDelta::hours(24));
    assert!(
        t.windows(2)
            .all(|p| p[1] > p[0] && p[1] - p[0] <= TimeDelta::minutes(15))
    );
    assert_eq!(t[96], a);
    assert_eq!(t[97], b);
    // An hourly-coarse step is capped; a finer one is kept.
    let w5 = HistoryWindow {
        max_step: TimeDelta::minutes(5),
        ..w
    };
    assert_eq!(
        history_times(&weather, &[a], &w5).unwrap().len(),
        24 * 12 + 1
    );
    // Outside the weather: an error naming the spans.
    let early = DateTime::parse_from_rfc3339("2025-06-19T06:00:00-04:00").unwrap();
    let e = history_times(&weather, &[early], &w)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("weather history covers") && e.contains("2025-06-18T06:00:00-04:00"),
        "{e}"
    );
    assert!(history_times(&weather, &[], &w).is_err());
}

#[test]
fn sun_directions_follow_the_ephemeris() {
    use chrono::{DateTime, TimeDelta};
    use irsig::exposure::sun_directions;
    let (weather, _) = irsig::weather::synth::town_history().unwrap();
    let site = *weather.site().unwrap();
    let t0 = DateTime::parse_from_rfc3339("2025-06-21T00:00:00-04:00").unwrap();
    let times: Vec<_> = (0..96).map(|i| t0 + TimeDelta::minutes(15 * i)).collect();
    let d = sun_directions(&site, &times).unwrap();
    assert!(d.iter().all(|v| (v.length() - 1.0).abs() < 1e-5));
    // Highest sun at the solstice: 90° − (latitude − 23.44°), to the south.
    let (k, top) = d
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.z.total_cmp(&b.1.z))
        .unwrap();
    let elev = top.z.asin().to_degrees() as f64;
    let expect = 90.0 - (site.latitude_deg - 23.44);
    assert!(
        (elev - expect).abs() < 0.3,
        "noon elevation {elev} vs {expect}"
    );
    assert!(top.y < 0.0 && top.x.abs() < 0.1, "due south: {top}");
    // Solar noon at Rochester (77.6° W, EDT = UTC−4) is about 13:15 local.
    let noon = times[k];
    assert!(
        (noon - DateTime::parse_from_rfc3339("2025-06-21T13:15:00-04:00").unwrap())
            .num_minutes()
            .abs()
            <= 15
    );
    // Night: below the horizon.
    assert!(d[4].z < 0.0 && d[92].z < 0.0);
}

#[test]
fn sky_sampling_parses_from_text() {
    assert_eq!(
        "dirsig".parse::<SkySampling>().unwrap(),
        SkySampling::DIRSIG
    );
    assert_eq!(
        "grid:5x10".parse::<SkySampling>().unwrap(),
        SkySampling::Grid {
            zenith_step_deg: 5.0,
            azimuth_step_deg: 10.0
        }
    );
    assert_eq!(
        "stratified:256".parse::<SkySampling>().unwrap(),
        SkySampling::Stratified { samples: 256 }
    );
    assert_eq!(
        SkySampling::Stratified { samples: 250 }.rays_per_face(),
        256
    );
    assert_eq!(SkySampling::DIRSIG.rays_per_face(), 72);
    for bad in ["", "grid:0x30", "stratified:0", "stratified:x", "hemi"] {
        let e = bad.parse::<SkySampling>().unwrap_err().to_string();
        assert!(e.contains("expected `dirsig`"), "{bad}: {e}");
    }
}

/// Embree and obvhs give the same shape factors and sun fractions on a
/// procedural town (terrain + buildings, instanced), facet by facet, up to
/// rays that graze an edge.
#[test]
fn backends_agree_on_a_procedural_town() {
    use irsig::geometry::procedural::{TerrainParams, generate};
    let mut p = TerrainParams::with_triangles(4000, 3);
    p.size_m = 200.0;
    let geo = generate(&p);
    let steps = [sun(20.0, 100.0), sun(55.0, 180.0), sun(35.0, 250.0)];
    let params = ExposureParams::default();
    let run = |b: Backend| {
        let t = trace::build(&geo, b).unwrap();
        compute_exposure(&*t, &geo, &[], &steps, &params).unwrap()
    };
    let (e, o) = (run(Backend::Embree), run(Backend::Obvhs));
    let n = geo.facet_count();
    let same_f = (0..n)
        .filter(|&f| e.sky.shape_factor[f] == o.sky.shape_factor[f])
        .count();
    let (es, os) = (
        crate::util::sun_fractions(&e.solar),
        crate::util::sun_fractions(&o.solar),
    );
    let same_s = (0..es.len()).filter(|&i| es[i] == os[i]).count();
    let worst = (0..n)
        .map(|f| (e.sky.shape_factor[f] - o.sky.shape_factor[f]).abs())
        .fold(0.0f32, f32::max);
    eprintln!(
        "{n} facets: F identical on {same_f}, sun fraction on {same_s} of {} facet-steps; worst |ΔF| {worst}",
        crate::util::sun_fractions(&e.solar).len()
    );
    assert!(same_f as f64 >= 0.995 * n as f64);
    assert!(same_s as f64 >= 0.995 * crate::util::sun_fractions(&e.solar).len() as f64);
    assert!(worst <= 0.05, "{worst}");
    // Some facets are shaded and some see buildings: the scene exercises both.
    assert!(
        crate::util::sun_fractions(&e.solar)
            .iter()
            .any(|&s| s > 0.0 && s < 1.0)
    );
    assert!((0..n).any(|f| !e.sky.background(f).is_empty()));
}

/// The exposure's rays start at interior sample points and run in generic
/// directions, so the faster non-watertight Embree scene the render traces
/// them on ([`Watertight::No`], `Session::exposure_tracer`) must give the
/// watertight scene's solar history and sky view: on a procedural town (a
/// regular heightmap with instanced buildings, where rays in the planes of
/// shared edges would slip through a non-watertight scene), with suns along
/// the grid's axes and diagonal, at most one facet in a thousand may differ
/// at all, and then by at most one sample ray (`1/n²` of the sunlit
/// fraction, one sky direction's weight of the shape factor).
#[test]
fn exposure_on_the_non_watertight_scene_matches_the_watertight_one() {
    use irsig::geometry::procedural::{self, TerrainParams};
    use irsig::trace::Watertight;
    let geom = procedural::generate(&TerrainParams::with_triangles(30_000, 5));
    let steps = [
        sun(30.0, 0.0),
        sun(45.0, 45.0),
        sun(20.0, 90.0),
        sun(60.0, 180.0),
        sun(10.0, 270.0),
        sun(35.0, 123.4),
    ];
    let params = ExposureParams::default();
    let exposure = |w| {
        let tracer = trace::build_with(&geom, Backend::Embree, w).unwrap();
        compute_exposure(tracer.as_ref(), &geom, &[], &steps, &params).unwrap()
    };
    let (tight, fast) = (exposure(Watertight::Yes), exposure(Watertight::No));
    let n = geom.facet_count();
    let samples = (params.samples_per_edge * params.samples_per_edge) as f32;
    let (mut sun_diff, mut sky_diff) = (0usize, 0usize);
    let (mut sun_max, mut sky_max) = (0.0f32, 0.0f32);
    for f in 0..n {
        let (a, b) = (tight.solar.sun_fraction(f), fast.solar.sun_fraction(f));
        let d = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f32::max);
        sun_diff += (d > 0.0) as usize;
        sun_max = sun_max.max(d);
        let d = (tight.sky.shape_factor[f] - fast.sky.shape_factor[f]).abs();
        sky_diff += (d > 0.0) as usize;
        sky_max = sky_max.max(d);
    }
    eprintln!(
        "{n} facets: sun fraction differs on {sun_diff} (max {sun_max}), shape factor on {sky_diff} (max {sky_max})"
    );
    assert!(sun_diff * 1000 <= n && sky_diff * 1000 <= n);
    assert!(sun_max <= 1.0 / samples + 1e-6, "{sun_max}");
    // One of the grid's directions carries at most a few per cent of F.
    assert!(sky_max <= 0.05, "{sky_max}");
}

/// Issue 18: the back face of a single-sided facet with an exposed back
/// (a wall with a ventilated cavity, a panel) gets its own shape factor
/// `F_b` (`exposed_back_shape_factors`) instead of the thermal model's
/// default `1 − F`, exact only for an unobstructed plane. The walls of
/// Masson's street canyon (H/W = 1 and 2) have their fronts in the canyon
/// (F = 0.293, 0.191) and their backs open to the outside, where a vertical
/// face sees `(1 − cos 90°)/2 = 0.5` of the sky: traced within 1 %, against
/// 1 − F = 0.707 and 0.809. An unobstructed plane tilted β sees
/// `(1 − cos β)/2` from its back, which there equals `1 − F`. Unflagged and
/// double-sided facets get none (a double-sided facet's back face is in its
/// sky view).
#[test]
fn exposed_back_takes_its_own_shape_factor() {
    for (hw, wall_ref) in [(1.0f64, 0.292893), (2.0, 0.190983)] {
        let w = 10.0f32;
        let (geo, _, wall) = canyon(hw as f32 * w, w);
        let brute = Checked::new(&geo);
        let p = stratified(1024);
        let exp = compute_exposure(&brute, &geo, &[], &[], &p).unwrap();
        let n = geo.facet_count();
        let flags: Vec<bool> = (0..n).map(|f| wall.contains(&f)).collect();
        let (fb, rays) = exposed_back_shape_factors(&brute, &exp.facets, &flags, p.sky, p.seed, 7);
        assert_eq!(rays, 1024 * wall.len() as u64);
        let back: Vec<f32> = fb.iter().map(|v| v.unwrap_or(f32::NAN)).collect();
        let mean_back = area_mean(&exp, wall.clone(), &back);
        let one_minus = 1.0 - area_mean(&exp, wall.clone(), &exp.sky.shape_factor);
        eprintln!("H/W={hw}: wall F_b {mean_back:.4} (exact 0.5), 1 − F {one_minus:.4}");
        assert!((mean_back - 0.5).abs() <= 0.005, "{mean_back}");
        assert!((one_minus - (1.0 - wall_ref)).abs() <= 0.02);
        assert!(one_minus - mean_back > 0.19);
        for (f, v) in fb.iter().enumerate() {
            assert_eq!(v.is_some(), wall.contains(&f), "facet {f}");
        }
        // Batches do not change the answer.
        let (again, _) =
            exposed_back_shape_factors(&brute, &exp.facets, &flags, p.sky, p.seed, 512);
        assert_eq!(again, fb);
    }
    for beta_deg in [30.0f32, 60.0, 90.0, 120.0] {
        let b = beta_deg.to_radians();
        let (geo, ids) = tilted_square(b);
        let brute = Checked::new(&geo);
        let p = stratified(1024);
        let exp = compute_exposure(&brute, &geo, &[], &[], &p).unwrap();
        let all = vec![true; geo.facet_count()];
        let (fb, _) = exposed_back_shape_factors(&brute, &exp.facets, &all, p.sky, p.seed, 512);
        let back: Vec<f32> = fb.iter().map(|v| v.unwrap()).collect();
        let exact = (1.0 - b.cos() as f64) / 2.0;
        let got = area_mean(&exp, ids.clone(), &back);
        assert!(
            (got - exact).abs() <= 0.01,
            "β={beta_deg}: F_b {got:.4} vs {exact:.4}"
        );
        // Double-sided: none here (the sky view traces its back face).
        let ds = compute_exposure(&brute, &geo, &all, &[], &p).unwrap();
        let (none, rays) = exposed_back_shape_factors(&brute, &ds.facets, &all, p.sky, p.seed, 512);
        assert!(none.iter().all(Option::is_none));
        assert_eq!(rays, 0);
        let traced = area_mean(
            &ds,
            ids.clone(),
            &ds.sky
                .back_shape_factor
                .iter()
                .map(|v| v.unwrap())
                .collect::<Vec<_>>(),
        );
        assert!((traced - exact).abs() <= 0.01);
    }
}
