//! Stage 3, sources: the sky a facet reflects diffusely — the directional
//! sky ([`super::sources::SKY_NODES`] zenith nodes, linear in cos θ between
//! them) integrated over the part of the sky hemisphere a facet of tilt β
//! faces, as the equivalent radiance
//!
//! ```text
//! L_eq(λ, β) = E_sky(λ, β) / (π·F_geom(β)),   F_geom = (1 + cos β)/2,
//! E_sky(λ, β) = ∫_sky L(λ, θ)·max(cos γ, 0) dω
//! ```
//!
//! (γ the angle between the direction and the facet's normal; the sky
//! below the horizon excluded), so that the diffuse term `F·L_eq` replaces
//! the isotropic `F·L_sky` with the facet's own sky shape factor F. The
//! sky is azimuth-independent, so the azimuth integral of each zenith ring
//! is analytic ([`ring_weight`]; derivation in
//! `docs/physics/radiometry.md`, "Diffusely reflected sky"). The model is
//! `L_eq` on [`TILT_NODES`] tilt nodes, linear between them
//! ([`tilt_position`], [`reflected_sky`]): the spectral reference and every
//! fast path interpolate the same table.

use std::sync::OnceLock;

use super::sources::{SKY_NODES, sky_node, sky_node_cos};

/// Nodes of the tilt table: tilt β_j = π·(1 − (1 − s_j)²), s_j = j/(N − 1),
/// from facing up (β = 0, node 0) to facing down (β = π): denser toward
/// facing down, where a facet sees only a sliver of sky above the horizon
/// and `L_eq` follows the sky's steep rise toward the horizon. Linear in
/// cos β between nodes below 90°, in β from the first node at or beyond
/// 90° (where `L_eq` follows the elevation of the top of the sky the facet
/// sees, π − β, not its cosine).
pub const TILT_NODES: usize = 57;

/// Tilt β (rad) of tilt node `j`.
fn tilt_node_beta(j: usize) -> f64 {
    let s = j as f64 / (TILT_NODES - 1) as f64;
    std::f64::consts::PI * (1.0 - (1.0 - s) * (1.0 - s))
}

/// The position of a facet whose front normal has vertical component
/// `cos_beta` on the tilt table: `k + w` for a tilt between node `k` and
/// node `k + 1`, `w` the fraction of the way in cos β (in β from the
/// first node at or beyond 90°; [`TILT_NODES`])
/// (`0 ≤ k + w ≤ TILT_NODES − 1`; NaN: facing up). [`tilt_at`] splits it.
pub fn tilt_position(cos_beta: f64) -> f32 {
    let c = if cos_beta.is_nan() {
        1.0
    } else {
        cos_beta.clamp(-1.0, 1.0)
    };
    let beta = c.acos();
    let s = 1.0 - (1.0 - beta / std::f64::consts::PI).max(0.0).sqrt();
    let k = ((s * (TILT_NODES - 1) as f64) as usize).min(TILT_NODES - 2);
    let (b0, b1) = (tilt_node_beta(k), tilt_node_beta(k + 1));
    let w = if b0 >= std::f64::consts::FRAC_PI_2 {
        (beta - b0) / (b1 - b0)
    } else {
        (c - b0.cos()) / (b1.cos() - b0.cos())
    };
    let w = w.clamp(0.0, 1.0);
    (k as f64 + w) as f32
}

/// Node `k` (≤ `TILT_NODES − 2`) and fraction `w` toward node `k + 1` of a
/// tilt position from [`tilt_position`].
#[inline(always)]
pub fn tilt_at(u: f32) -> (usize, f32) {
    // u ≥ 0: truncation is the floor.
    let k = (u as usize).min(TILT_NODES - 2);
    (k, u - k as f32)
}

/// `∫₀^{2π} max(cos γ, 0) dφ` over the zenith ring at cos θ = `mu` for a
/// facet of tilt β (`cos_beta`, `sin_beta ≥ 0`): with the facet's normal in
/// the x–z plane, `cos γ = a·cos φ + b`, `a = sin β·sin θ`,
/// `b = cos β·cos θ`, so the ring gives `2π·b` where the whole ring lies in
/// front (`b ≥ a`), nothing where none does (`b ≤ −a`), else
/// `2·(√(a² − b²) + b·φ₀)` with `cos φ₀ = −b/a`.
pub fn ring_weight(mu: f64, cos_beta: f64, sin_beta: f64) -> f64 {
    let a = sin_beta * (1.0 - mu * mu).max(0.0).sqrt();
    let b = cos_beta * mu;
    if b >= a {
        std::f64::consts::TAU * b
    } else if b <= -a {
        0.0
    } else {
        2.0 * ((a * a - b * b).max(0.0).sqrt() + b * (-b / a).clamp(-1.0, 1.0).acos())
    }
}

/// Gauss–Legendre nodes and weights on [−1, 1], `n` points (Newton on the
/// Legendre recurrence; Press et al., *Numerical Recipes*, 3rd ed., §4.6.1,
/// `gauleg`).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p1, mut p2) = (1.0, 0.0);
            for j in 0..n {
                let p3 = p2;
                p2 = p1;
                p1 = ((2 * j + 1) as f64 * z * p2 - j as f64 * p3) / (j + 1) as f64;
            }
            dp = n as f64 * (z * p1 - p2) / (z * z - 1.0);
            let dz = p1 / dp;
            z -= dz;
            if dz.abs() < 1e-15 {
                break;
            }
        }
        out.push((z, 2.0 / ((1.0 - z * z) * dp * dp)));
    }
    out
}

/// Per sky node `k`, the share of `L_eq` of a facet of tilt `cos_beta`
/// that comes from node `k`: `∫₀¹ h_k(μ)·ring_weight(μ, β) dμ / (π·F_geom)`
/// with `h_k` the hat function of node `k` in the sky's interpolation
/// (linear in cos θ between the nodes; the sky between the last node,
/// θ = [`crate::atmosphere::MAX_SKY_ZENITH_DEG`], and the horizon takes
/// node 0's radiance, as a ray leaving the scene there does). Exact up to
/// the quadrature: 32-point Gauss–Legendre on every interval between the
/// sky nodes and the kink of the ring weight at μ = sin β. For an
/// isotropic sky the shares sum to 1 (`∫₀¹ ring_weight dμ = π·F_geom`).
/// The quadrature runs in θ (dμ = sin θ dθ), where the ring weight has no
/// square-root end point at the zenith.
/// A facet facing down so far that it sees no sky above node 0
/// (sin β ≤ cos θ₀) takes node 0 (the limit of `L_eq` as `F_geom → 0`).
pub fn sky_tilt_weights(cos_beta: f64) -> [f64; SKY_NODES] {
    static GL: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    let gl = GL.get_or_init(|| gauss_legendre(32));
    let c = if cos_beta.is_nan() {
        1.0
    } else {
        cos_beta.clamp(-1.0, 1.0)
    };
    let s = (1.0 - c * c).max(0.0).sqrt();
    let mu0 = sky_node_cos(0);
    let mut w = [0.0; SKY_NODES];
    if c < 0.0 && s <= mu0 {
        w[0] = 1.0;
        return w;
    }
    // Breakpoints in θ: the zenith, the sky nodes, the kink, the horizon.
    let mut cuts: Vec<f64> = std::iter::once(0.0)
        .chain((0..SKY_NODES).map(sky_node_cos))
        .map(|mu| mu.clamp(0.0, 1.0).acos())
        .collect();
    if s > 0.0 && s < 1.0 {
        cuts.push(s.acos());
    }
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    for seg in cuts.windows(2) {
        let (lo, hi) = (seg[0], seg[1]);
        let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        for &(x, gw) in gl {
            let (sin_t, mu) = (mid + half * x).sin_cos();
            let g = ring_weight(mu, c, s) * sin_t * gw * half;
            if mu <= mu0 {
                w[0] += g;
            } else {
                let (k, f) = sky_node(mu, 1.0);
                w[k] += g * (1.0 - f);
                w[k + 1] += g * f;
            }
        }
    }
    let norm = std::f64::consts::PI * 0.5 * (1.0 + c);
    for v in &mut w {
        *v /= norm;
    }
    w
}

/// [`sky_tilt_weights`] at every tilt node (computed once).
pub(super) fn tilt_node_weights() -> &'static [[f64; SKY_NODES]; TILT_NODES] {
    static W: OnceLock<[[f64; SKY_NODES]; TILT_NODES]> = OnceLock::new();
    W.get_or_init(|| std::array::from_fn(|j| sky_tilt_weights(tilt_node_beta(j).cos())))
}

/// `L_eq(λ)` at every tilt node from the directional sky `sky_dir`
/// (`SKY_NODES` spectra, at [`sky_node_cos`]).
pub(super) fn tilt_table(sky_dir: &[Vec<f64>]) -> Vec<Vec<f64>> {
    debug_assert_eq!(sky_dir.len(), SKY_NODES);
    let n = sky_dir.first().map_or(0, Vec::len);
    tilt_node_weights()
        .iter()
        .map(|w| {
            let mut out = vec![0.0; n];
            for (&wk, row) in w.iter().zip(sky_dir) {
                for (o, &l) in out.iter_mut().zip(row) {
                    *o += wk * l;
                }
            }
            out
        })
        .collect()
}

/// The equivalent radiance `L_eq(λ, β)` of the sky reflected diffusely by a
/// facet whose front normal has vertical component `cos_beta`, as the
/// renderer models it: linear on the tilt table ([`tilt_position`]) between
/// the nodes' exact integrals of the directional sky `sky_dir`
/// (`SKY_NODES` spectra at the sky nodes' zeniths, [`sky_node_zeniths_deg`]).
pub fn reflected_sky(sky_dir: &[Vec<f64>], cos_beta: f64) -> Vec<f64> {
    let table = tilt_table(sky_dir);
    let (k, w) = tilt_at(tilt_position(cos_beta));
    let w = w as f64;
    table[k]
        .iter()
        .zip(&table[k + 1])
        .map(|(&a, &b)| a + w * (b - a))
        .collect()
}

/// Zenith angles (degrees) of the directional sky's nodes, in node order
/// (from the horizon limit up).
pub fn sky_node_zeniths_deg() -> Vec<f64> {
    (0..SKY_NODES)
        .map(|k| sky_node_cos(k).clamp(-1.0, 1.0).acos().to_degrees())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A sky radiance at cos θ = `mu` as the renderer interpolates the
    /// node values `nodes` (linear in cos θ, node 0 below it).
    fn sky_at(nodes: &[f64; SKY_NODES], mu: f64) -> f64 {
        if mu <= sky_node_cos(0) {
            return nodes[0];
        }
        let (k, f) = sky_node(mu, 1.0);
        nodes[k] + f * (nodes[k + 1] - nodes[k])
    }

    fn dot(w: &[f64; SKY_NODES], l: &[f64; SKY_NODES]) -> f64 {
        w.iter().zip(l).map(|(a, b)| a * b).sum()
    }

    /// Tilts from facing up to facing down (cos β decreasing), including
    /// the exact ends, vertical, and tilts just either side of the tilt
    /// nodes.
    fn tilts() -> Vec<f64> {
        let mut c: Vec<f64> = (0..=200).map(|i| 1.0 - 2.0 * i as f64 / 200.0).collect();
        for j in 0..TILT_NODES {
            let b = tilt_node_beta(j);
            c.extend([b.cos(), (b + 1e-4).cos(), (b - 1e-4).cos()]);
        }
        c.sort_by(|a, b| b.total_cmp(a));
        c
    }

    /// The ring weight against a brute-force azimuth sum (midpoint rule,
    /// 20 000 steps) of max(cos γ, 0) for the normal (sin β, 0, cos β).
    #[test]
    fn ring_weight_is_the_azimuth_integral_of_the_projected_cosine() {
        for &cb in &[1.0, 0.9, 0.5, 0.1, 0.0, -0.2, -0.7, -0.99, -1.0] {
            let sb = (1.0f64 - cb * cb).sqrt();
            for i in 0..=40 {
                let mu = i as f64 / 40.0;
                let st = (1.0 - mu * mu).sqrt();
                let n = 20_000;
                let brute: f64 = (0..n)
                    .map(|k| {
                        let phi = (k as f64 + 0.5) / n as f64 * 2.0 * PI;
                        (sb * st * phi.cos() + cb * mu).max(0.0)
                    })
                    .sum::<f64>()
                    * 2.0
                    * PI
                    / n as f64;
                let w = ring_weight(mu, cb, sb);
                assert!(
                    (w - brute).abs() <= 1e-6,
                    "cos β {cb}, μ {mu}: {w} vs {brute}"
                );
            }
        }
    }

    /// An isotropic sky: the shares sum to 1 at every tilt (the quadrature
    /// reproduces ∫ max(cos γ, 0) dω over the sky = π·(1 + cos β)/2, which
    /// it does not assume), so `L_eq = L` everywhere.
    #[test]
    fn an_isotropic_sky_gives_its_own_radiance_at_every_tilt() {
        for c in tilts() {
            let w = sky_tilt_weights(c);
            let sum: f64 = w.iter().sum();
            assert!((sum - 1.0).abs() <= 1e-9, "cos β {c}: Σ shares {sum}");
            assert!(w.iter().all(|&x| x >= 0.0), "cos β {c}: {w:?}");
        }
    }

    /// A sky that brightens toward the horizon, `L(μ) = 1 − 0.7^(1/μ)`
    /// sampled at the sky nodes: the shares against a brute-force
    /// two-dimensional quadrature of `L·max(cos γ, 0)` over the hemisphere
    /// (midpoint rule in θ and φ, independent of the analytic ring
    /// weight); the horizontal facet against `E = 2π∫L μ dμ` (the
    /// irradiance of a horizontal receiver under an azimuth-independent
    /// sky); a wall sees more than a roof, a facet facing down the
    /// horizon's radiance.
    #[test]
    fn the_reflected_sky_is_the_cosine_weighted_sky_over_the_facets_hemisphere() {
        let l: [f64; SKY_NODES] = std::array::from_fn(|k| 1.0 - 0.7f64.powf(1.0 / sky_node_cos(k)));
        let leq = |c: f64| dot(&sky_tilt_weights(c), &l);
        // Horizontal: L_eq = 2∫₀¹ L(μ) μ dμ.
        let n = 200_000;
        let horiz: f64 = (0..n)
            .map(|i| {
                let mu = (i as f64 + 0.5) / n as f64;
                2.0 * sky_at(&l, mu) * mu
            })
            .sum::<f64>()
            / n as f64;
        assert!(
            (leq(1.0) - horiz).abs() <= 1e-7 * horiz,
            "{} vs {horiz}",
            leq(1.0)
        );
        // Tilted: brute force over θ and φ.
        for &cb in &[0.8, 0.3, 0.0, -0.4, -0.9] {
            let sb = (1.0f64 - cb * cb).sqrt();
            let (nt, np) = (3000, 2880);
            let mut e = 0.0;
            for i in 0..nt {
                let th = (i as f64 + 0.5) / nt as f64 * PI / 2.0;
                let (st, mu) = th.sin_cos();
                let lr = sky_at(&l, mu);
                let mut ring = 0.0;
                for k in 0..np {
                    let phi = (k as f64 + 0.5) / np as f64 * 2.0 * PI;
                    ring += (sb * st * phi.cos() + cb * mu).max(0.0);
                }
                e += lr * ring * (2.0 * PI / np as f64) * st * (PI / 2.0 / nt as f64);
            }
            let want = e / (PI * 0.5 * (1.0 + cb));
            let got = leq(cb);
            assert!(
                (got - want).abs() <= 2e-5 * want,
                "cos β {cb}: {got} vs {want}"
            );
        }
        // A wall sees the bright horizon more than a roof does; facing
        // down, only the horizon (node 0).
        assert!(
            leq(0.0) > leq(1.0) * 1.05,
            "wall {} roof {}",
            leq(0.0),
            leq(1.0)
        );
        assert!((leq(-1.0) - l[0]).abs() <= 1e-12);
        assert!((leq(-0.99999) - l[0]).abs() <= 1e-12);
        // Monotone: the more a facet tilts, the more horizon it sees.
        let v: Vec<f64> = tilts().into_iter().map(leq).collect();
        assert!(v.windows(2).all(|w| w[1] >= w[0] - 1e-9));
    }

    /// An isothermal atmosphere of optical depth δ at temperature T: the
    /// sky `L(μ) = B·(1 − e^(−δ/μ))`, whose irradiance on a horizontal
    /// surface is the classical `π·B·(1 − 2·E₃(δ))` (Chandrasekhar,
    /// *Radiative Transfer*, 1960, §2; E₃ by A&S 5.1.11 and 5.1.14). With
    /// the sky sampled at the 24 nodes the renderer uses (and θ > 89° at
    /// the 89° value) the horizontal `L_eq` is within 2·10⁻³ of it; and an
    /// optically thick (overcast) sky is B at every tilt.
    #[test]
    fn an_isothermal_sky_matches_the_exponential_integral_and_the_overcast_limit() {
        fn e1(x: f64) -> f64 {
            // A&S 5.1.11 (x ≤ 1 here).
            let mut sum = 0.0;
            let mut term = 1.0;
            for k in 1..60 {
                term *= -x / k as f64;
                sum += term / k as f64;
            }
            -0.577_215_664_901_532_9 - x.ln() - sum
        }
        let e3 = |x: f64| {
            let e2 = (-x).exp() - x * e1(x);
            0.5 * ((-x).exp() - x * e2)
        };
        for &delta in &[0.05, 0.2, 0.6, 1.0] {
            let l: [f64; SKY_NODES] =
                std::array::from_fn(|k| 1.0 - (-delta / sky_node_cos(k)).exp());
            let got = dot(&sky_tilt_weights(1.0), &l);
            let want = 1.0 - 2.0 * e3(delta);
            assert!(
                (got - want).abs() <= 2e-3 * want,
                "δ {delta}: {got} vs {want}"
            );
        }
        let thick: [f64; SKY_NODES] =
            std::array::from_fn(|k| 1.0 - (-40.0 / sky_node_cos(k)).exp());
        for c in tilts() {
            let v = dot(&sky_tilt_weights(c), &thick);
            assert!((v - 1.0).abs() <= 1e-9, "cos β {c}: {v}");
        }
    }

    /// The tilt table: position 0 facing up, `TILT_NODES − 1` facing down,
    /// node `j` at its tilt, monotone, linear in cos β between nodes;
    /// [`tilt_at`] keeps `k ≤ N − 2`.
    #[test]
    fn tilt_positions_map_the_nodes_and_the_ends() {
        assert_eq!(tilt_position(1.0), 0.0);
        assert_eq!(tilt_position(-1.0), (TILT_NODES - 1) as f32);
        assert_eq!(tilt_position(f64::NAN), 0.0);
        for j in 0..TILT_NODES {
            let u = tilt_position(tilt_node_beta(j).cos());
            assert!((u - j as f32).abs() <= 1e-4, "node {j}: {u}");
        }
        assert_eq!(tilt_at((TILT_NODES - 1) as f32), (TILT_NODES - 2, 1.0));
        let (c0, c1) = (tilt_node_beta(3).cos(), tilt_node_beta(4).cos());
        let u = tilt_position(0.25 * c0 + 0.75 * c1);
        assert!((u - 3.75).abs() <= 1e-5, "{u}");
        let j = TILT_NODES - 5;
        assert!(tilt_node_beta(j) > std::f64::consts::FRAC_PI_2);
        let (b0, b1) = (tilt_node_beta(j), tilt_node_beta(j + 1));
        let u = tilt_position((0.25 * b0 + 0.75 * b1).cos());
        assert!((u - (j as f32 + 0.75)).abs() <= 1e-4, "{u}");
        let u: Vec<f32> = tilts().into_iter().map(tilt_position).collect();
        assert!(u.windows(2).all(|w| w[1] >= w[0]), "{u:?}");
    }
}
