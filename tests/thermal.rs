//! Tests: thermal. The slab model against analytic solutions of heat
//! conduction (Carslaw & Jaeger, *Conduction of Heat in Solids*, 2nd ed.,
//! 1959), conservation of energy, the steady surface balance, and the
//! qualitative behaviour of thin and thick objects.

use irsig::thermal::latent::{AirState, TurbulentExchange};
use irsig::thermal::{
    self, BackBoundary, Background, Boundary, FacetInputs, Forcing, Grid, STEFAN_BOLTZMANN_W_M2_K4,
    Slab, SlabProperties, SolveOptions, Spinup, SurfaceFlux, mcadams_h_w_m2_k,
};
use std::f64::consts::PI;

/// The concrete of issue 4: k 1.4 W/(m·K), ρ 2300 kg/m³, c 880 J/(kg·K).
const K_CONCRETE: f64 = 1.4;
const RHO_C_CONCRETE: f64 = 2300.0 * 880.0;
const DAY_S: f64 = 86_400.0;

/// The grid used by the analytic checks: the `accurate` preset.
fn fine_grid() -> Grid {
    SolveOptions::accurate().grid
}

/// erfc(x) for x ≥ 0 (Numerical Recipes §6.2 `erfcc`, fractional error
/// < 1.2e−7).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let ans = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 { ans } else { 2.0 - ans }
}

/// Amplitude and phase (rad) of the component at `omega` of samples `y`
/// taken at times `t` covering exactly whole periods with uniform spacing.
fn fourier(t: &[f64], y: &[f64], omega: f64) -> (f64, f64) {
    let n = y.len() as f64;
    let (mut s, mut c) = (0.0, 0.0);
    for (ti, yi) in t.iter().zip(y) {
        s += yi * (omega * ti).sin();
        c += yi * (omega * ti).cos();
    }
    let (a, b) = (2.0 * s / n, 2.0 * c / n);
    // y ≈ mean + a sin ωt + b cos ωt = mean + A sin(ωt + φ).
    ((a * a + b * b).sqrt(), b.atan2(a))
}

/// Carslaw & Jaeger §2.6: a semi-infinite solid whose surface temperature
/// varies as A sin ωt. At depth x the wave has amplitude A e^(−x/d) and lags
/// by x/d radians, d = √(2κ/ω).
#[test]
fn periodic_surface_temperature_matches_carslaw_jaeger() {
    let omega = 2.0 * PI / DAY_S;
    let kappa = K_CONCRETE / RHO_C_CONCRETE;
    let d = (2.0 * kappa / omega).sqrt();
    // The published values of the issue follow from these formulas.
    for (x, ratio, lag_h) in [(0.05, 0.69592, 1.3847), (0.10, 0.48431, 2.7694)] {
        assert!(((-x / d).exp() - ratio).abs() < 1e-5);
        assert!((x / d / omega / 3600.0 - lag_h).abs() < 1e-4);
    }
    let (tm, amp) = (300.0, 10.0);
    // 1 m of concrete ≈ 7 damping depths: the deep end does not feel the wave.
    let depth = 1.0;
    for (dt, grid, tol_ratio, tol_lag) in [
        (450.0, fine_grid(), 0.01, 0.01),
        (450.0, Grid::default(), 0.02, 0.02),
    ] {
        let mut slab = Slab::new(depth, K_CONCRETE, RHO_C_CONCRETE, grid, tm);
        // Start on the periodic solution, so no start-up transient remains.
        slab.set_temperatures(|x| tm + amp * (-x / d).exp() * (-x / d).sin());
        let insulated = Boundary::Flux(SurfaceFlux::default());
        let steps = (DAY_S / dt) as usize;
        let (mut ts, mut y0, mut y5, mut y10) = (vec![], vec![], vec![], vec![]);
        for i in 0..2 * steps {
            let t = i as f64 * dt;
            slab.step(
                dt,
                |f| Boundary::Temperature(tm + amp * (omega * (t + f * dt)).sin()),
                |_| insulated,
            );
            if i >= steps {
                ts.push(t + dt);
                y0.push(slab.front_k());
                y5.push(slab.temperature_at(0.05));
                y10.push(slab.temperature_at(0.10));
            }
        }
        let (a0, p0) = fourier(&ts, &y0, omega);
        assert!((a0 - amp).abs() < 1e-6 * amp, "surface amplitude {a0}");
        for (x, y, ratio, lag_h) in [(0.05, &y5, 0.69592, 1.3847), (0.10, &y10, 0.48431, 2.7694)] {
            let (a, p) = fourier(&ts, y, omega);
            let got_ratio = a / a0;
            let got_lag_h = (p0 - p).rem_euclid(2.0 * PI) / omega / 3600.0;
            eprintln!(
                "periodic dt {dt} s, {} cells: x = {x} m ratio {got_ratio:.5} (exact {ratio}), \
                 lag {got_lag_h:.4} h (exact {lag_h})",
                grid.cells
            );
            assert!(
                (got_ratio / ratio - 1.0).abs() < tol_ratio,
                "x = {x}: amplitude ratio {got_ratio}, expected {ratio} ± {tol_ratio}"
            );
            assert!(
                (got_lag_h / lag_h - 1.0).abs() < tol_lag,
                "x = {x}: lag {got_lag_h} h, expected {lag_h} h ± {tol_lag}"
            );
        }
    }
}

/// Carslaw & Jaeger §2.9: constant flux q₀ into a semi-infinite solid from
/// t = 0: ΔT(x, t) = (2q₀/k)√(κt/π) e^(−x²/4κt) − (q₀x/k) erfc(x/2√(κt)).
#[test]
fn constant_surface_flux_matches_erfc_solution() {
    let q0 = 500.0;
    let kappa = K_CONCRETE / RHO_C_CONCRETE;
    let exact = |x: f64, t: f64| {
        2.0 * q0 / K_CONCRETE * (kappa * t / PI).sqrt() * (-x * x / (4.0 * kappa * t)).exp()
            - q0 * x / K_CONCRETE * erfc(x / (2.0 * (kappa * t).sqrt()))
    };
    // The issue's published values.
    assert!((exact(0.0, 3600.0) - 20.1098).abs() < 1e-3);
    assert!((exact(0.05, 3600.0) - 7.0990).abs() < 1e-3);
    for (dt, grid, tol) in [(60.0, fine_grid(), 0.01), (450.0, Grid::default(), 0.02)] {
        let mut slab = Slab::new(1.0, K_CONCRETE, RHO_C_CONCRETE, grid, 300.0);
        let heat = Boundary::Flux(SurfaceFlux::constant(q0));
        let insulated = Boundary::Flux(SurfaceFlux::default());
        for _ in 0..(3600.0 / dt) as usize {
            slab.step(dt, |_| heat, |_| insulated);
        }
        let (s, x5) = (slab.front_k() - 300.0, slab.temperature_at(0.05) - 300.0);
        eprintln!(
            "flux dt {dt} s, {} cells: surface +{s:.4} K (exact 20.1098), 5 cm +{x5:.4} K (exact 7.0990)",
            grid.cells
        );
        assert!((s / 20.1098 - 1.0).abs() < tol, "surface rise {s} K");
        assert!((x5 / 7.0990 - 1.0).abs() < tol, "rise at 5 cm {x5} K");
    }
}

/// The front balance of a facet in full sun, as a flux law.
fn sunny_front(t_air: f64, wind: f64) -> SurfaceFlux {
    let (alpha, eps) = (0.7, 0.9);
    let h = mcadams_h_w_m2_k(wind);
    SurfaceFlux {
        source_w_m2: alpha * 800.0 + alpha * 100.0 + eps * 330.0 + h * t_air,
        linear_w_m2_k: h,
        radiative_w_m2_k4: eps * STEFAN_BOLTZMANN_W_M2_K4,
        ..SurfaceFlux::default()
    }
}

/// Energy conservation: the time integral of the net surface flux equals
/// the change in stored heat. The flux is evaluated by the test from the
/// surface temperature and integrated by the trapezoidal rule, independently
/// of the solver's own bookkeeping.
#[test]
fn energy_is_conserved() {
    let front = sunny_front(295.0, 2.0);
    let mut slab = Slab::new(0.2, K_CONCRETE, RHO_C_CONCRETE, Grid::default(), 280.0);
    let e0 = slab.stored_energy_j_m2();
    let dt = 10.0;
    let insulated = Boundary::Flux(SurfaceFlux::default());
    let mut integral = 0.0;
    let mut q_prev = front.flux(slab.front_k());
    for _ in 0..(6.0 * 3600.0 / dt) as usize {
        slab.step(dt, |_| Boundary::Flux(front), |_| insulated);
        let q = front.flux(slab.front_k());
        integral += 0.5 * dt * (q_prev + q);
        q_prev = q;
    }
    let de = slab.stored_energy_j_m2() - e0;
    eprintln!("energy: ∫q dt = {integral:.1} J/m², ΔE = {de:.1} J/m²");
    assert!(de > 1e6, "the slab should have gained heat: {de}");
    assert!(
        (integral / de - 1.0).abs() < 1e-3,
        "∫q dt {integral} vs ΔE {de}"
    );
    // The solver's bookkeeping agrees to rounding.
    let (fin, bin) = slab.boundary_energy_j_m2();
    assert_eq!(bin, 0.0);
    assert!(
        (fin / de - 1.0).abs() < 1e-9,
        "scheme quadrature {fin} vs ΔE {de}"
    );
}

/// The energy budget reported by `solve` closes for every back boundary.
#[test]
fn solve_energy_budget_closes() {
    let times: Vec<f64> = (0..=96).map(|i| i as f64 * 900.0).collect();
    let mut forcing = Forcing::constant(&times, 290.0, 2.0, 0.0, 0.0, 300.0);
    for (i, &t) in times.iter().enumerate() {
        let s = (PI * (t / 3600.0 - 6.0) / 12.0).sin().max(0.0);
        forcing.direct_normal_w_m2[i] = 850.0 * s;
        forcing.diffuse_horizontal_w_m2[i] = 120.0 * s;
        forcing.air_temperature_k[i] = 288.0 + 6.0 * (2.0 * PI * (t / 3600.0 - 9.0) / 24.0).sin();
    }
    let sun = vec![1.0f32; times.len()];
    let cos: Vec<f32> = times
        .iter()
        .map(|t| (PI * (t / 3600.0 - 6.0) / 12.0).sin().max(0.0) as f32)
        .collect();
    // With shortwave reflected onto the facet (issue 19): the energy still
    // closes.
    let refl: Vec<f32> = cos.iter().map(|c| 0.04 * c).collect();
    let inputs = FacetInputs {
        reflected: thermal::Reflected {
            direct: &refl,
            diffuse: 0.04,
        },
        ..FacetInputs::new(&sun, &cos, 0.8)
    };
    for back in [
        BackBoundary::Insulated,
        BackBoundary::BOTH_FACES,
        BackBoundary::Exposed { fraction: 0.5 },
        BackBoundary::BUILDING,
        BackBoundary::GROUND,
    ] {
        let props = SlabProperties {
            conductivity_w_m_k: K_CONCRETE,
            density_kg_m3: 2300.0,
            specific_heat_j_kg_k: 880.0,
            thickness_m: 0.1,
            solar_absorptivity: 0.7,
            thermal_emissivity: 0.9,
            self_power_w_m2: 0.0,
            back,
            surface: None,
            convection: irsig::material::ConvectionSpec::MCADAMS,
            layers: irsig::thermal::Layers::NONE,
        };
        let mut opts = SolveOptions::default();
        opts.spinup.max_cycles = 0;
        let sol = thermal::solve(&props, &forcing, &inputs, &opts).unwrap();
        let e = sol.energy;
        let scale = e.front_in_j_m2.abs().max(e.stored_change_j_m2.abs());
        assert!(scale > 1e5, "{back:?}: {e:?}");
        assert!(
            (e.front_in_j_m2 + e.back_in_j_m2 - e.stored_change_j_m2).abs() < 1e-3 * scale,
            "{back:?}: {e:?}"
        );
    }
}

/// Bisection root of a decreasing function on [lo, hi].
fn bisect(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    assert!(f(lo) > 0.0 && f(hi) < 0.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Under constant forcing the surface settles where the balance is zero
/// (insulated back), or where it equals the conduction through the wall to
/// the interior (building back).
#[test]
fn steady_state_is_root_of_surface_balance() {
    let (t_air, wind, dni, dh, sky, cos, f_sky) = (293.0, 1.5, 700.0, 90.0, 320.0, 0.6, 0.75);
    let (alpha, eps) = (0.65, 0.92);
    let sigma = STEFAN_BOLTZMANN_W_M2_K4;
    let h = 5.7 + 3.8 * wind;
    let t_bg: f64 = 290.0;
    let balance = |t: f64| {
        alpha * dni * cos
            + alpha * f_sky * dh
            + eps * f_sky * sky
            + eps * (1.0 - f_sky) * sigma * t_bg.powi(4)
            - eps * sigma * t.powi(4)
            + h * (t_air - t)
            + 25.0
    };
    let times: Vec<f64> = (0..=10 * 96).map(|i| i as f64 * 900.0).collect();
    let forcing = Forcing::constant(&times, t_air, wind, dni, dh, sky);
    let sun = vec![1.0f32; times.len()];
    let cosv = vec![cos as f32; times.len()];
    let mut inputs = FacetInputs::new(&sun, &cosv, f_sky);
    inputs.background = Background::Constant(t_bg);
    let thickness = 0.15;
    let (t_in, h_in) = (295.0, 7.7);
    for back in [
        BackBoundary::Insulated,
        BackBoundary::Interior {
            air: irsig::thermal::InteriorAir::Constant(t_in),
            film_coefficient_w_m2_k: h_in,
        },
    ] {
        let props = SlabProperties {
            conductivity_w_m_k: K_CONCRETE,
            density_kg_m3: 2300.0,
            specific_heat_j_kg_k: 880.0,
            thickness_m: thickness,
            solar_absorptivity: alpha,
            thermal_emissivity: eps,
            self_power_w_m2: 25.0,
            back,
            surface: None,
            convection: irsig::material::ConvectionSpec::MCADAMS,
            layers: irsig::thermal::Layers::NONE,
        };
        let expected = match back {
            BackBoundary::Insulated => bisect(balance, 200.0, 450.0),
            // Series resistance of the wall and the interior film.
            _ => bisect(
                |t| balance(t) - (t - t_in) / (thickness / K_CONCRETE + 1.0 / h_in),
                200.0,
                450.0,
            ),
        };
        let sol = thermal::solve(&props, &forcing, &inputs, &SolveOptions::default()).unwrap();
        let got = *sol.surface_temperature_k.last().unwrap();
        eprintln!("steady {back:?}: solver {got:.5} K, root {expected:.5} K");
        assert!((got - expected).abs() < 1e-3, "{got} vs {expected}");
        assert!(sol.last_period_change_k.unwrap() < 1e-3);
    }
}

/// A synthetic clear or overcast two-day history for a horizontal facet,
/// solar noon at 12:00, sunrise 06:00; returns the forcing and cos θ.
fn synthetic_days(clear: bool) -> (Forcing, Vec<f32>) {
    let times: Vec<f64> = (0..=192).map(|i| i as f64 * 900.0).collect();
    let mut forcing = Forcing::constant(&times, 288.0, 2.0, 0.0, 0.0, 0.0);
    let mut cos = Vec::with_capacity(times.len());
    for (i, &t) in times.iter().enumerate() {
        let hour = (t / 3600.0) % 24.0;
        let elev = (PI * (hour - 6.0) / 12.0).sin().max(0.0); // sin of solar elevation
        let t_air = 288.0 + 6.0 * (2.0 * PI * (hour - 9.0) / 24.0).sin();
        forcing.air_temperature_k[i] = t_air;
        let blackbody = STEFAN_BOLTZMANN_W_M2_K4 * t_air.powi(4);
        if clear {
            forcing.direct_normal_w_m2[i] = 850.0 * elev.powf(0.3) * (elev > 0.0) as u8 as f64;
            forcing.diffuse_horizontal_w_m2[i] = 100.0 * elev;
            forcing.sky_longwave_w_m2[i] = 0.75 * blackbody;
        } else {
            forcing.diffuse_horizontal_w_m2[i] = 150.0 * elev;
            forcing.sky_longwave_w_m2[i] = 0.97 * blackbody;
        }
        cos.push(elev as f32);
    }
    (forcing, cos)
}

/// A thin aluminium panel (both faces exposed) and a thick wood wall (back
/// to a building interior), same optical properties.
fn panel_and_wall() -> (SlabProperties, SlabProperties) {
    let panel = SlabProperties {
        conductivity_w_m_k: 200.0,
        density_kg_m3: 2700.0,
        specific_heat_j_kg_k: 900.0,
        thickness_m: 0.002,
        solar_absorptivity: 0.7,
        thermal_emissivity: 0.9,
        self_power_w_m2: 0.0,
        back: BackBoundary::BOTH_FACES,
        surface: None,
        convection: irsig::material::ConvectionSpec::MCADAMS,
        layers: irsig::thermal::Layers::NONE,
    };
    let wall = SlabProperties {
        conductivity_w_m_k: 0.15,
        density_kg_m3: 600.0,
        specific_heat_j_kg_k: 1700.0,
        thickness_m: 0.1,
        back: BackBoundary::BUILDING,
        ..panel
    };
    (panel, wall)
}

/// The seed's finding, part 1: in sun, a thin aluminium panel heats and
/// cools much faster than a thick wood wall. Both sit 6 h in steady sun
/// (records every minute); then a shadow falls abruptly for 3 h. The panel
/// relaxes exponentially with time constant `ρcL / 2(h + 4εσT³)` ≈ 2.7 min;
/// the wall surface cools like that of a semi-infinite solid, quickly at
/// first then with a long √t tail (its characteristic time `(e/H)²`, `e` =
/// √(kρc), is ≈ 11 min and the tail lasts hours).
#[test]
fn thin_panel_heats_and_cools_faster_than_thick_wall() {
    let (panel, wall) = panel_and_wall();
    let n = 9 * 60 + 1;
    let times: Vec<f64> = (0..n).map(|i| i as f64 * 60.0).collect();
    let t_air: f64 = 293.0;
    let sky = 0.75 * STEFAN_BOLTZMANN_W_M2_K4 * t_air.powi(4);
    let forcing = Forcing::constant(&times, t_air, 2.0, 800.0, 100.0, sky);
    let mut sun = vec![1.0f32; n];
    sun[361..].fill(0.0); // shadow from 6 h 01 min
    let cos = vec![0.8f32; n];
    let inputs = FacetInputs::new(&sun, &cos, 1.0);
    let mut opts = SolveOptions::default();
    opts.spinup.max_cycles = 0;
    // Minutes after the shadow falls until 63 % and 90 % of the 3-h drop.
    let mut t63 = [0.0; 2];
    let mut t90 = [0.0; 2];
    for (j, props) in [panel, wall].iter().enumerate() {
        let t = thermal::solve(props, &forcing, &inputs, &opts)
            .unwrap()
            .surface_temperature_k;
        let (start, end) = (t[360], t[n - 1]);
        assert!(
            start - end > 10.0,
            "the shadow should cool the surface: {start} → {end}"
        );
        let minutes_to = |share: f64| {
            (360..n)
                .find(|&i| start - t[i] >= share * (start - end))
                .unwrap() as f64
                - 360.0
        };
        t63[j] = minutes_to(0.632);
        t90[j] = minutes_to(0.9);
        eprintln!(
            "step response: {} from {start:.2} K to {end:.2} K, 63 % after {} min, 90 % after {} min",
            ["panel", "wall"][j],
            t63[j],
            t90[j]
        );
    }
    assert!(
        t63[0] <= 6.0 && t90[0] <= 10.0,
        "panel: {} / {} min",
        t63[0],
        t90[0]
    );
    assert!(
        t63[1] > 2.0 * t63[0],
        "63 %: wall {} min vs panel {} min",
        t63[1],
        t63[0]
    );
    assert!(
        t90[1] > 4.0 * t90[0],
        "90 %: wall {} min vs panel {} min",
        t90[1],
        t90[0]
    );
}

/// The seed's finding, part 2: through a clear day the panel and the wall
/// surface temperatures differ by many kelvin; under overcast (no direct
/// sun, warm cloudy sky) both stay near the air temperature and differ much
/// less.
#[test]
fn panel_and_wall_differ_much_less_under_overcast() {
    let (panel, wall) = panel_and_wall();
    let mut max_gap = [0.0; 2];
    for (case, clear) in [true, false].into_iter().enumerate() {
        let (forcing, cos) = synthetic_days(clear);
        let sun = vec![1.0f32; cos.len()];
        let inputs = FacetInputs::new(&sun, &cos, 1.0);
        let opts = SolveOptions::default();
        let p = thermal::solve(&panel, &forcing, &inputs, &opts).unwrap();
        let w = thermal::solve(&wall, &forcing, &inputs, &opts).unwrap();
        let (tp, tw) = (&p.surface_temperature_k, &w.surface_temperature_k);
        max_gap[case] = tp[96..]
            .iter()
            .zip(&tw[96..])
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        eprintln!(
            "{}: diurnal range panel {:.2} K, wall {:.2} K; max |T_panel − T_wall| {:.2} K",
            if clear { "clear" } else { "overcast" },
            range(&tp[96..]),
            range(&tw[96..]),
            max_gap[case]
        );
    }
    assert!(max_gap[0] > 5.0, "clear-day gap {} K", max_gap[0]);
    assert!(
        max_gap[1] < 0.25 * max_gap[0],
        "overcast gap {} K should be much smaller than clear gap {} K",
        max_gap[1],
        max_gap[0]
    );
}

fn range(t: &[f64]) -> f64 {
    t.iter().cloned().fold(f64::MIN, f64::max) - t.iter().cloned().fold(f64::MAX, f64::min)
}

/// Self-convergence: on two synthetic clear days, the default options agree
/// with the `accurate` preset (24 cells, 120-s steps, up to 6 spin-up days)
/// to 0.15 K on the second day, and the `fast` preset to 1 K, for a thin
/// panel, a building wall and a ground column.
#[test]
fn presets_converge_to_accurate_solution() {
    let (forcing, cos) = synthetic_days(true);
    let sun = vec![1.0f32; cos.len()];
    let inputs = FacetInputs::new(&sun, &cos, 1.0);
    let (panel, wall) = panel_and_wall();
    let ground = SlabProperties {
        conductivity_w_m_k: K_CONCRETE,
        density_kg_m3: 2300.0,
        specific_heat_j_kg_k: 880.0,
        back: BackBoundary::GROUND,
        ..wall
    };
    for props in [panel, wall, ground] {
        let exact = thermal::solve(&props, &forcing, &inputs, &SolveOptions::accurate()).unwrap();
        for (opts, tol) in [(SolveOptions::default(), 0.15), (SolveOptions::fast(), 1.0)] {
            let sol = thermal::solve(&props, &forcing, &inputs, &opts).unwrap();
            let err = sol.surface_temperature_k[96..]
                .iter()
                .zip(&exact.surface_temperature_k[96..])
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(
                err < tol,
                "{:?}: {err} K from accurate (tolerance {tol} K)",
                props.back
            );
        }
    }
}

/// Degenerate grids (one to three cells) take the same code paths' edge
/// cases: they must still conserve energy and reach the analytic steady
/// state of a wall between outdoor balance and interior film.
#[test]
fn coarse_grids_conserve_energy_and_reach_steady_state() {
    let times: Vec<f64> = (0..=4 * 96).map(|i| i as f64 * 900.0).collect();
    let forcing = Forcing::constant(&times, 290.0, 3.0, 600.0, 80.0, 310.0);
    let sun = vec![1.0f32; times.len()];
    let cos = vec![0.5f32; times.len()];
    let inputs = FacetInputs::new(&sun, &cos, 0.9);
    let props = SlabProperties {
        conductivity_w_m_k: 0.8,
        density_kg_m3: 1800.0,
        specific_heat_j_kg_k: 840.0,
        thickness_m: 0.02,
        solar_absorptivity: 0.6,
        thermal_emissivity: 0.9,
        self_power_w_m2: 0.0,
        back: BackBoundary::Interior {
            air: irsig::thermal::InteriorAir::Constant(295.0),
            film_coefficient_w_m2_k: 8.0,
        },
        surface: None,
        convection: irsig::material::ConvectionSpec::MCADAMS,
        layers: irsig::thermal::Layers::NONE,
    };
    let sigma = STEFAN_BOLTZMANN_W_M2_K4;
    let h = 5.7 + 3.8 * 3.0;
    let front = |t: f64| {
        0.6 * 600.0 * 0.5
            + 0.6 * 0.9 * 80.0
            + 0.9 * 0.9 * 310.0
            + 0.9 * 0.1 * sigma * 290.0f64.powi(4)
            - 0.9 * sigma * t.powi(4)
            + h * (290.0 - t)
    };
    let expected = bisect(
        |t| front(t) - (t - 295.0) / (0.02 / 0.8 + 1.0 / 8.0),
        200.0,
        450.0,
    );
    for cells in [1, 2, 3] {
        let opts = SolveOptions {
            grid: Grid { cells, growth: 1.3 },
            spinup: Spinup::none(),
            ..SolveOptions::default()
        };
        let sol = thermal::solve(&props, &forcing, &inputs, &opts).unwrap();
        let got = *sol.surface_temperature_k.last().unwrap();
        assert!(
            (got - expected).abs() < 1e-3,
            "{cells} cells: {got} vs {expected}"
        );
        let e = sol.energy;
        assert!(
            (e.front_in_j_m2 + e.back_in_j_m2 - e.stored_change_j_m2).abs()
                < 1e-6 * e.front_in_j_m2.abs(),
            "{cells} cells: {e:?}"
        );
    }
}

/// Bad inputs are reported with the field at fault, not solved.
#[test]
fn invalid_inputs_name_the_field() {
    let times = [0.0, 900.0, 1800.0];
    let forcing = Forcing::constant(&times, 290.0, 1.0, 0.0, 0.0, 300.0);
    let sun = [1.0f32; 3];
    let cos = [0.5f32; 3];
    let good = SlabProperties {
        conductivity_w_m_k: 1.0,
        density_kg_m3: 1000.0,
        specific_heat_j_kg_k: 1000.0,
        thickness_m: 0.1,
        solar_absorptivity: 0.5,
        thermal_emissivity: 0.9,
        self_power_w_m2: 0.0,
        back: BackBoundary::Insulated,
        surface: None,
        convection: irsig::material::ConvectionSpec::MCADAMS,
        layers: irsig::thermal::Layers::NONE,
    };
    let opts = SolveOptions::default();
    let err = |props: &SlabProperties, forcing: &Forcing, inputs: &FacetInputs| {
        thermal::solve(props, forcing, inputs, &opts)
            .unwrap_err()
            .to_string()
    };
    let inputs = FacetInputs::new(&sun, &cos, 1.0);
    let bad = SlabProperties {
        thickness_m: 0.0,
        ..good
    };
    assert!(err(&bad, &forcing, &inputs).contains("thickness_m"));
    let bad = SlabProperties {
        thermal_emissivity: 1.5,
        ..good
    };
    assert!(err(&bad, &forcing, &inputs).contains("thermal_emissivity"));
    let mut f = forcing.clone();
    f.times_s[2] = 900.0;
    assert!(err(&good, &f, &inputs).contains("records[2].time"));
    let mut f = forcing.clone();
    f.air_temperature_k[1] = f64::NAN;
    assert!(err(&good, &f, &inputs).contains("records[1].air_temperature_k"));
    let short = FacetInputs::new(&sun[..2], &cos, 1.0);
    assert!(err(&good, &forcing, &short).contains("sun_fraction"));
    let bad_f = FacetInputs::new(&sun, &cos, 1.2);
    assert!(err(&good, &forcing, &bad_f).contains("shape_factor"));
}

/// `EXPOSED_AREA` → back boundary, as documented on
/// `BackBoundary::from_exposed_area`.
#[test]
fn exposed_area_maps_to_back_boundary() {
    assert_eq!(
        BackBoundary::from_exposed_area(0.0),
        BackBoundary::Insulated
    );
    assert_eq!(
        BackBoundary::from_exposed_area(0.5),
        BackBoundary::Exposed { fraction: 0.5 }
    );
    // DIRSIG's negative values: the magnitude (see `Material::exposed_fraction`).
    assert_eq!(
        BackBoundary::from_exposed_area(-0.5),
        BackBoundary::Exposed { fraction: 0.5 }
    );
    assert_eq!(
        BackBoundary::from_exposed_area(1.0),
        BackBoundary::BOTH_FACES
    );
}

// ---- One-facet mode (`irsig thermal`) ----

use crate::util::{irsig_bin, repo_path};
use std::process::Command;

/// Write a night-time (no sun) irsig CSV history with constant weather,
/// hourly for `days` days, without a site line.
fn write_constant_night_csv(path: &std::path::Path, days: u32, t_air: f64, wind: f64, sky: f64) {
    let mut s = String::from(
        "time,air_temperature_k,dew_point_k,relative_humidity,pressure_pa,wind_speed_m_s,\
         wind_direction_deg,direct_normal_w_m2,diffuse_horizontal_w_m2,global_horizontal_w_m2,\
         sky_longwave_w_m2,total_sky_cover,opaque_sky_cover\n",
    );
    let start = chrono::DateTime::parse_from_rfc3339("2025-01-10T00:00:00+00:00").unwrap();
    for h in 0..=days * 24 {
        let t = start + chrono::TimeDelta::hours(h as i64);
        s += &format!(
            "{},{t_air},{},0.7,101325,{wind},180,0,0,0,{sky},0,0\n",
            t.to_rfc3339(),
            t_air - 5.0
        );
    }
    std::fs::write(path, s).unwrap();
}

fn run_irsig(args: &[&str]) -> std::process::Output {
    Command::new(irsig_bin()).args(args).output().unwrap()
}

/// A temporary folder with four days of constant night weather
/// (`write_constant_night_csv`: 285 K air, 1 m/s wind, 280 W/m² sky) and
/// a material file holding `material` (one JSON material object): the
/// folder, the weather file and the material file.
fn night_case(material: &str) -> (tempfile::TempDir, std::path::PathBuf, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let weather = dir.path().join("night.csv");
    write_constant_night_csv(&weather, 4, NIGHT.0, NIGHT.1, NIGHT.2);
    let mat = dir.path().join("m.json");
    std::fs::write(&mat, format!(r#"{{"materials": [{material}]}}"#)).unwrap();
    (dir, weather, mat)
}

/// Air temperature (K), wind (m/s) and sky longwave (W/m²) of [`night_case`].
const NIGHT: (f64, f64, f64) = (285.0, 1.0, 280.0);

/// The hemispherical emissivity the balance uses for a normal emissivity
/// of 0.95 (the Fresnel fall-off; issue 19 item 4).
fn hemispherical_095() -> f64 {
    0.95 * irsig::radiometry::emissivity::hemispherical_ratio(|t| {
        irsig::radiometry::fresnel_emissivity(0.95, t)
    })
}

/// `irsig thermal --json` under constant weather without sun reaches the
/// root of the balance of a plane tilted 60°, whose default sky shape factor
/// is (1 + cos 60°)/2 = 0.75; the output has one record per weather record.
#[test]
fn cli_one_facet_reaches_steady_balance_of_tilted_plane() {
    let (_dir, weather, mat) = night_case(
        r#"{"id": 7, "name": "slab", "specific_heat_j_kg_k": 900,
            "conductivity_w_m_k": 1.0, "density_kg_m3": 2000, "thickness_m": 0.02,
            "solar_absorptivity": 0.5, "thermal_emissivity": 0.95, "exposed_area": 0}"#,
    );
    let (t_air, wind, sky) = NIGHT;
    let out = run_irsig(&[
        "thermal",
        "--material",
        mat.to_str().unwrap(),
        "--weather",
        weather.to_str().unwrap(),
        "--time",
        "2025-01-14T00:00:00+00:00",
        "--tilt",
        "60",
        "--azimuth",
        "90",
        "--site",
        "43.16,-77.61,170",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let recs = v["records"].as_array().unwrap();
    assert_eq!(recs.len(), 4 * 24 + 1);
    assert_eq!(recs[0]["time"], "2025-01-10T00:00:00+00:00");
    assert_eq!(recs[96]["time"], "2025-01-14T00:00:00+00:00");
    let got = recs[96]["surface_temperature_k"].as_f64().unwrap();
    // The material's 0.95 is normal; the balance uses the hemispherical
    // emissivity of the Fresnel fall-off.
    let eps = hemispherical_095();
    let (f, sigma) = (0.75, STEFAN_BOLTZMANN_W_M2_K4);
    // The default DOE-2 convection of a concrete-rough surface tilted 60°
    // (cos Σ = 0.5), at the facet's own ΔT: the one-facet reference surface
    // is the facet itself at night.
    let h = |t: f64| irsig::thermal::convection::doe2_w_m2_k(t - t_air, 0.5, wind, 1.52);
    let expected = bisect(
        |t| {
            eps * f * sky + eps * (1.0 - f) * sigma * t_air.powi(4) - eps * sigma * t.powi(4)
                + h(t) * (t_air - t)
        },
        200.0,
        400.0,
    );
    assert!((got - expected).abs() < 1e-3, "{got} vs {expected}");
    // With --shape-factor 1 the facet sees a colder sky: cooler.
    let out = run_irsig(&[
        "thermal",
        "--material",
        mat.to_str().unwrap(),
        "--weather",
        weather.to_str().unwrap(),
        "--time",
        "2025-01-14T00:00:00+00:00",
        "--site",
        "43.16,-77.61,170",
        "--shape-factor",
        "1",
        "--csv",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("time,surface_temperature_k"));
    let last: f64 = lines
        .last()
        .unwrap()
        .split(',')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert!(last < got - 1.0, "F = 1: {last} K, F = 0.75: {got} K");
}

/// `irsig thermal --back-shape-factor`: a thin, highly conducting wall
/// (tilt 90°, F = 0.5) exposed on both faces settles under constant night
/// weather where the two faces' balances sum to zero, each face seeing the
/// sky over its own shape factor; the back's default is `1 − F`, and a back
/// that sees less sky (a canyon's next street) runs warmer by what the
/// balance predicts.
#[test]
fn cli_one_facet_back_takes_its_own_shape_factor() {
    // 0.02 m at 200 W/(m K): 1e-4 K m²/W across the wall, so its two faces
    // are within a few mK of each other.
    let (_dir, weather, mat) = night_case(
        r#"{"id": 7, "name": "wall", "specific_heat_j_kg_k": 900,
            "conductivity_w_m_k": 200.0, "density_kg_m3": 2700, "thickness_m": 0.02,
            "solar_absorptivity": 0.5, "thermal_emissivity": 0.95, "exposed_area": 1}"#,
    );
    let (t_air, wind, sky) = NIGHT;
    let run = |extra: &[&str]| {
        let mut args = vec![
            "thermal",
            "--material",
            mat.to_str().unwrap(),
            "--weather",
            weather.to_str().unwrap(),
            "--time",
            "2025-01-14T00:00:00+00:00",
            "--tilt",
            "90",
            "--site",
            "43.16,-77.61,170",
            "--json",
        ];
        args.extend_from_slice(extra);
        let out = run_irsig(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let t = v["records"].as_array().unwrap()[96]["surface_temperature_k"]
            .as_f64()
            .unwrap();
        (t, stderr)
    };
    let eps = hemispherical_095();
    let sigma = STEFAN_BOLTZMANN_W_M2_K4;
    // Vertical: both faces convect as vertical surfaces (cos Σ = 0), with
    // DOE-2's ΔT from the orientation class's reference surface — the
    // unobstructed plane, whose back sees 1 − F — so the coefficient is
    // the default facet's, whatever F_b.
    let h = |t: f64| irsig::thermal::convection::doe2_w_m2_k(t - t_air, 0.0, wind, 1.52);
    let face = |f: f64, t: f64, h: f64| {
        eps * f * sky + eps * (1.0 - f) * sigma * t_air.powi(4) - eps * sigma * t.powi(4)
            + h * (t_air - t)
    };
    let reference = bisect(|t| 2.0 * face(0.5, t, h(t)), 200.0, 400.0);
    let expected = |f_back: f64| {
        let h = h(reference);
        bisect(|t| face(0.5, t, h) + face(f_back, t, h), 200.0, 400.0)
    };
    let (default, err) = run(&[]);
    assert!(!err.contains("warning"), "{err}");
    let (same, _) = run(&["--back-shape-factor", "0.5"]);
    assert_eq!(same, default, "F_b = 1 − F is the default");
    assert!(
        (default - expected(0.5)).abs() < 5e-3,
        "{default} vs {}",
        expected(0.5)
    );
    let (sheltered, _) = run(&["--back-shape-factor", "0.1"]);
    let want = expected(0.1);
    assert!((sheltered - want).abs() < 5e-3, "{sheltered} vs {want}");
    // The sheltered back sees the air-temperature background instead of the
    // colder sky: the wall is warmer, by a physical margin.
    assert!(
        sheltered > default + 0.3,
        "F_b 0.1: {sheltered} K, 0.5: {default} K"
    );
    // An insulated back ignores it, with a warning.
    let (_, err) = run(&["--back", "insulated", "--back-shape-factor", "0.1"]);
    assert!(
        err.contains("warning: --back-shape-factor"),
        "no warning for an unused --back-shape-factor: {err}"
    );
}

/// A sunlit day of the bundled town weather: a south-facing wall is warmer
/// at noon than a north-facing one, and the time between records is
/// interpolated for an image time between records.
#[test]
fn cli_south_wall_warmer_than_north_wall_at_noon() {
    let weather = repo_path("scenes/town/weather.csv");
    let db = repo_path("scenes/materials.json");
    let noon = |az: &str| {
        let out = run_irsig(&[
            "thermal",
            "--material",
            "brick",
            "--materials",
            db.to_str().unwrap(),
            "--weather",
            weather.to_str().unwrap(),
            "--time",
            "2025-06-20T13:07:00-04:00",
            "--tilt",
            "90",
            "--azimuth",
            az,
            "--json",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let recs = v["records"].as_array().unwrap().clone();
        assert_eq!(recs.last().unwrap()["time"], "2025-06-20T13:07:00-04:00");
        recs.last().unwrap()["surface_temperature_k"]
            .as_f64()
            .unwrap()
    };
    let (south, north) = (noon("180"), noon("0"));
    assert!(south > north + 3.0, "south {south} K, north {north} K");
}

/// Errors name what is wrong: an unknown material lists the names, a bad
/// site says what was expected, a time outside the history names the file.
#[test]
fn cli_errors_are_clear() {
    let dir = tempfile::tempdir().unwrap();
    let weather = dir.path().join("w.csv");
    write_constant_night_csv(&weather, 1, 285.0, 1.0, 280.0);
    let db = repo_path("scenes/materials.json");
    let base = |extra: &[&str]| {
        let mut a = vec![
            "thermal",
            "--weather",
            weather.to_str().unwrap(),
            "--materials",
            db.to_str().unwrap(),
        ];
        a.extend_from_slice(extra);
        let out = run_irsig(&a);
        assert!(!out.status.success());
        String::from_utf8(out.stderr).unwrap()
    };
    if db.exists() {
        let e = base(&[
            "--material",
            "unobtainium",
            "--time",
            "2025-01-10T12:00:00Z",
            "--site",
            "43,-77,0",
        ]);
        assert!(e.contains("unobtainium") && e.contains("asphalt"), "{e}");
        let e = base(&[
            "--material",
            "asphalt",
            "--time",
            "2025-01-10T12:00:00Z",
            "--site",
            "43;-77",
        ]);
        assert!(e.contains("--site"), "{e}");
        let e = base(&[
            "--material",
            "asphalt",
            "--time",
            "2025-03-01T00:00:00Z",
            "--site",
            "43,-77,0",
        ]);
        assert!(e.contains("w.csv"), "{e}");
        let e = base(&["--material", "asphalt", "--time", "2025-01-10T12:00:00Z"]);
        assert!(e.contains("--site"), "{e}");
    }
}

/// One clear day of [`synthetic_days`] (97 records, 15 min).
fn one_clear_day() -> (Forcing, Vec<f32>) {
    let (mut f, cos) = synthetic_days(true);
    let n = 97;
    f.truncate(n);
    (f, cos[..n].to_vec())
}

/// Concrete 0.2 m with each kind of back boundary.
fn concrete_with_backs() -> Vec<SlabProperties> {
    let base = SlabProperties {
        conductivity_w_m_k: K_CONCRETE,
        density_kg_m3: 2300.0,
        specific_heat_j_kg_k: 880.0,
        thickness_m: 0.2,
        solar_absorptivity: 0.7,
        thermal_emissivity: 0.9,
        self_power_w_m2: 0.0,
        back: BackBoundary::Insulated,
        surface: None,
        convection: irsig::material::ConvectionSpec::MCADAMS,
        layers: irsig::thermal::Layers::NONE,
    };
    vec![
        base,
        base.with_back(BackBoundary::GROUND),
        base.with_back(BackBoundary::Exposed { fraction: 0.5 }),
        base.with_back(BackBoundary::BUILDING),
        SlabProperties {
            conductivity_w_m_k: 200.0,
            density_kg_m3: 2700.0,
            thickness_m: 0.002,
            back: BackBoundary::BOTH_FACES,
            ..base
        },
    ]
}

/// The tangent-linear Green's matrices against finite differences of the
/// nonlinear solver: a small background-temperature change at one record
/// (front and, for an exposed back, back sources change) predicts the
/// change of the whole surface-temperature history to 1e-3 of its size
/// (measured: ≤ 2.5e-4, the finite difference's own second-order error),
/// without spin-up and with the default spin-up (whose cycles the tangent
/// folds in with the one-period maps of the reference's real run).
#[test]
fn tangent_linear_model_matches_finite_differences() {
    let (forcing, cos) = one_clear_day();
    let sun = vec![1.0f32; forcing.len()];
    let bg0 = vec![290.0f32; forcing.len()];
    for (opts, tol) in [
        (
            SolveOptions {
                spinup: Spinup::none(),
                newton_tolerance_k: 1e-10,
                ..SolveOptions::default()
            },
            1e-3,
        ),
        (
            SolveOptions {
                newton_tolerance_k: 1e-10,
                ..SolveOptions::default()
            },
            1e-3,
        ),
    ] {
        for props in concrete_with_backs() {
            let inputs = FacetInputs {
                background: Background::PerRecord(&bg0),
                ..FacetInputs::new(&sun, &cos, 0.6)
            };
            let lin = thermal::linearize(&props, &forcing, &inputs, &opts).unwrap();
            let reference = thermal::solve(&props, &forcing, &inputs, &opts).unwrap();
            assert_eq!(
                lin.solution.surface_temperature_k,
                reference.surface_temperature_k
            );
            for k in [10usize, 50, 80] {
                let mut bg = bg0.clone();
                bg[k] += 2.0;
                let pert = FacetInputs {
                    background: Background::PerRecord(&bg),
                    ..inputs
                };
                let exact = thermal::solve(&props, &forcing, &pert, &opts).unwrap();
                let src = thermal::source_history(&props, &forcing, &pert).unwrap();
                let pred = lin.predict(&src.front_w_m2, src.back_w_m2.as_deref(), false);
                let size = exact
                    .surface_temperature_k
                    .iter()
                    .zip(&reference.surface_temperature_k)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                let err = exact
                    .surface_temperature_k
                    .iter()
                    .zip(&pred)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                assert!(size > 1e-3, "{props:?} k {k}: change {size}");
                assert!(
                    err <= tol * size,
                    "{:?} spin-up {}: record {k}: change {size:.4} K, tangent error {err:.2e} K",
                    props.back,
                    opts.spinup.max_cycles
                );
            }
        }
    }
}

/// The second-order correction: a facet shaded all afternoon differs from
/// the sunlit reference by ~10 K; the first-order prediction misses the
/// emission's curvature by 0.2–0.4 K, the corrected one by ≤ 0.04 K
/// (measured).
#[test]
fn second_order_correction_captures_emission_curvature() {
    let (forcing, cos) = one_clear_day();
    let opts = SolveOptions::default();
    let sun = vec![1.0f32; forcing.len()];
    let mut shaded = sun.clone();
    shaded[48..].iter_mut().for_each(|s| *s = 0.0);
    for props in concrete_with_backs() {
        let lin = thermal::linearize(&props, &forcing, &FacetInputs::new(&sun, &cos, 0.8), &opts)
            .unwrap();
        let inputs = FacetInputs::new(&shaded, &cos, 0.8);
        let exact = thermal::solve(&props, &forcing, &inputs, &opts).unwrap();
        let src = thermal::source_history(&props, &forcing, &inputs).unwrap();
        let err = |second: bool| {
            let p = lin.predict(&src.front_w_m2, src.back_w_m2.as_deref(), second);
            p.iter()
                .zip(&exact.surface_temperature_k)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        };
        let size = exact
            .surface_temperature_k
            .iter()
            .zip(&lin.solution.surface_temperature_k)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let (e1, e2) = (err(false), err(true));
        assert!(
            size > 5.0,
            "{:?}: shading changes T by {size} K",
            props.back
        );
        assert!(
            e2 < 0.06 && e2 < 0.15 * e1,
            "{:?}: ΔT {size:.2} K, first-order error {e1:.3} K, second-order {e2:.3} K",
            props.back
        );
    }
}

/// The deep-ground back boundary: under constant weather a ground column
/// (depth L, bottom held at T_deep) reaches the steady state where the
/// surface balance equals the conduction down the column,
/// `S − hT − εσT⁴ = k (T − T_deep)/L` (linear profile; exact for the finite
/// volumes), while the same slab with an insulated back reaches the root of
/// the surface balance alone — much hotter in sun, and the ground's surface
/// lies between that and the deep temperature.
#[test]
fn ground_column_conducts_to_the_deep_soil() {
    let times: Vec<f64> = (0..=96).map(|i| i as f64 * 900.0).collect();
    let forcing = Forcing::constant(&times, 290.0, 2.0, 600.0, 80.0, 330.0);
    let sun = vec![1.0f32; times.len()];
    let cos = vec![0.7f32; times.len()];
    let inputs = FacetInputs::new(&sun, &cos, 1.0);
    let (depth, deep) = (0.3, 280.0);
    let soil = SlabProperties {
        conductivity_w_m_k: 1.0,
        density_kg_m3: 1600.0,
        specific_heat_j_kg_k: 1000.0,
        thickness_m: 0.1,
        solar_absorptivity: 0.8,
        thermal_emissivity: 0.95,
        self_power_w_m2: 0.0,
        back: BackBoundary::Ground {
            deep_temperature_k: Some(deep),
            depth_m: Some(depth),
        },
        surface: None,
        convection: irsig::material::ConvectionSpec::MCADAMS,
        layers: irsig::thermal::Layers::NONE,
    };
    let opts = SolveOptions {
        spinup: Spinup {
            max_cycles: 40,
            period_s: DAY_S,
            tolerance_k: 1e-6,
            ..Spinup::default()
        },
        ..SolveOptions::default()
    };
    let s = thermal::source_history(&soil, &forcing, &inputs)
        .unwrap()
        .front_w_m2[0];
    let (h, r) = (mcadams_h_w_m2_k(2.0), 0.95 * STEFAN_BOLTZMANN_W_M2_K4);
    let balance = |t: f64| s - h * t - r * t.powi(4);
    let ground = thermal::solve(&soil, &forcing, &inputs, &opts).unwrap();
    let t_ground = *ground.surface_temperature_k.last().unwrap();
    let root = bisect(
        |t| balance(t) - soil.conductivity_w_m_k * (t - deep) / depth,
        200.0,
        400.0,
    );
    let insulated = soil.with_back(BackBoundary::Insulated);
    let t_ins = *thermal::solve(&insulated, &forcing, &inputs, &opts)
        .unwrap()
        .surface_temperature_k
        .last()
        .unwrap();
    let root_ins = bisect(balance, 200.0, 400.0);
    eprintln!(
        "ground {t_ground:.4} K (steady root {root:.4}), insulated {t_ins:.4} K (root {root_ins:.4})"
    );
    assert!((t_ground - root).abs() < 0.01, "{t_ground} vs {root}");
    assert!((t_ins - root_ins).abs() < 0.01, "{t_ins} vs {root_ins}");
    assert!(deep < t_ground && t_ground < t_ins - 3.0);
}

/// The affine source model of a material equals the balance's source
/// history for any facet inputs (front and exposed back), and the
/// background coefficients give the change of the sources with `σT_bg⁴`.
#[test]
fn source_model_matches_the_balance() {
    let (forcing, cos) = one_clear_day();
    let n = forcing.len();
    let sun: Vec<f32> = (0..n).map(|k| ((k * 7) % 5) as f32 / 4.0).collect();
    for props in concrete_with_backs() {
        let model =
            thermal::SourceModel::new(&props, &forcing, &thermal::Exchange::mcadams(&forcing));
        for (f, fb) in [(1.0, None), (0.3, Some(0.8)), (0.0, Some(0.0))] {
            let inputs = FacetInputs {
                back_shape_factor: fb,
                ..FacetInputs::new(&sun, &cos, f)
            };
            let exact = thermal::source_history(&props, &forcing, &inputs).unwrap();
            let mut front = vec![0.0f32; n];
            model.front_into(&sun, &cos, f, &mut front);
            for (a, b) in front.iter().zip(&exact.front_w_m2) {
                assert!(
                    (*a as f64 - b).abs() < 1e-3 * b.abs().max(1.0),
                    "{a} vs {b}"
                );
            }
            // With reflected shortwave: `a` weighs like `s·cos θ`, `b` like αE_d.
            let a_hist: Vec<f32> = (0..n).map(|k| 0.05 * (k % 3) as f32).collect();
            let refl = thermal::Reflected {
                direct: &a_hist,
                diffuse: 0.15,
            };
            let lit = FacetInputs {
                reflected: refl,
                ..inputs
            };
            let with = thermal::source_history(&props, &forcing, &lit).unwrap();
            model.front_reflected_into(&sun, &cos, f, refl, &mut front);
            for (k, (a, b)) in front.iter().zip(&with.front_w_m2).enumerate() {
                assert!(
                    (*a as f64 - b).abs() < 1e-3 * b.abs().max(1.0),
                    "{a} vs {b}"
                );
                // The balance adds α·E_r, E_r = E_dn·a + E_d·b.
                let added = props.solar_absorptivity
                    * (forcing.direct_normal_w_m2[k] * a_hist[k] as f64
                        + forcing.diffuse_horizontal_w_m2[k] * 0.15);
                let d = b - exact.front_w_m2[k];
                assert!((d - added).abs() < 1e-9 * added.max(1.0), "{d} vs {added}");
            }
            assert_eq!(model.has_back(), exact.back_w_m2.is_some());
            if let Some(back) = &exact.back_w_m2 {
                let mut out = vec![0.0f32; n];
                model.back_into(fb.unwrap_or(1.0 - f), &mut out);
                for (a, b) in out.iter().zip(back) {
                    assert!(
                        (*a as f64 - b).abs() < 1e-3 * b.abs().max(1.0),
                        "{a} vs {b}"
                    );
                }
            }
            // A background of 300 K instead of the air.
            let bg = vec![300.0f32; n];
            let warm = FacetInputs {
                background: Background::PerRecord(&bg),
                ..inputs
            };
            let w = thermal::source_history(&props, &forcing, &warm).unwrap();
            let (cf, cb) = thermal::background_coefficients(&props, f, fb);
            for k in 0..n {
                let excess = STEFAN_BOLTZMANN_W_M2_K4
                    * (300f64.powi(4) - forcing.air_temperature_k[k].powi(4));
                let d = w.front_w_m2[k] - exact.front_w_m2[k];
                assert!(
                    (d - cf * excess).abs() < 1e-6 * excess.abs().max(1.0),
                    "{d}"
                );
                if let (Some(a), Some(b)) = (&w.back_w_m2, &exact.back_w_m2) {
                    assert!((a[k] - b[k] - cb * excess).abs() < 1e-6 * excess.abs().max(1.0));
                }
            }
        }
    }
}

/// The front law of `sunny_front` with a latent term for grass-like
/// resistances: r_a 50 s/m, r_s `r_s` s/m, air at 60 % relative humidity.
fn evaporating_front(t_air: f64, wind: f64, r_s: f64) -> SurfaceFlux {
    let air = AirState::from_relative_humidity(t_air, 0.6, 101_325.0).unwrap();
    let x = TurbulentExchange::new(air, 50.0, r_s).unwrap();
    SurfaceFlux {
        vapour_conductance_w_m2_pa: x.vapour_conductance_w_m2_pa(),
        air_vapour_pressure_pa: air.vapour_pressure_pa(),
        ..sunny_front(t_air, wind)
    }
}

/// The latent term of the flux law is the Penman–Monteith latent flux at
/// the surface temperature (FAO-56 eq. 3 through `TurbulentExchange`), and
/// the derivative the Newton solve uses is the law's derivative.
#[test]
fn latent_flux_law_matches_penman_monteith_and_its_derivative() {
    let dry = sunny_front(300.0, 2.0);
    let wet = evaporating_front(300.0, 2.0, 70.0);
    let air = AirState::from_relative_humidity(300.0, 0.6, 101_325.0).unwrap();
    let x = TurbulentExchange::new(air, 50.0, 70.0).unwrap();
    for t in [285.0, 300.0, 315.0] {
        let le = x.latent_w_m2(t);
        assert!((wet.latent_w_m2(t) - le).abs() < 1e-9 * le.abs().max(1.0));
        assert!((dry.flux(t) - le - wet.flux(t)).abs() < 1e-9 * dry.flux(t).abs().max(1.0));
        let h = 1e-3;
        let fd = (wet.flux(t + h) - wet.flux(t - h)) / (2.0 * h);
        let d = wet.derivative(t);
        assert!((fd / d - 1.0).abs() < 1e-6, "dq/dT {d} vs FD {fd} at {t} K");
        assert!(d < dry.derivative(t), "evaporation steepens the law");
    }
    assert!(wet.has_latent() && !dry.has_latent());
    assert_eq!(dry.latent_w_m2(300.0), 0.0);
    // lerp interpolates the latent fields.
    let mid = dry.lerp(&wet, 0.5);
    assert_eq!(
        mid.vapour_conductance_w_m2_pa,
        0.5 * wet.vapour_conductance_w_m2_pa
    );
    assert_eq!(mid.air_vapour_pressure_pa, 0.5 * wet.air_vapour_pressure_pa);
}

/// Runs a 0.3 m soil-like slab 12 h under `front`, insulated behind;
/// returns the surface temperature after every 10 s step.
fn surface_history(front: SurfaceFlux) -> Vec<f64> {
    let mut slab = Slab::new(0.3, 1.0, 1.4e6, Grid::default(), 290.0);
    let insulated = Boundary::Flux(SurfaceFlux::default());
    (0..4320)
        .map(|_| {
            slab.step(10.0, |_| Boundary::Flux(front), |_| insulated);
            slab.front_k()
        })
        .collect()
}

/// Issue 16: latent heat → 0 as the surface resistance → ∞ recovers
/// today's (dry) model exactly: r_s = ∞ gives g_v = 0 and the same surface
/// temperatures bit for bit; a huge finite r_s converges to them; a grass-
/// like r_s cools the surface by kelvins.
#[test]
fn infinite_surface_resistance_recovers_the_dry_model_exactly() {
    let dry = surface_history(sunny_front(295.0, 2.0));
    let sealed = evaporating_front(295.0, 2.0, f64::INFINITY);
    assert_eq!(sealed.vapour_conductance_w_m2_pa, 0.0);
    assert_eq!(
        surface_history(sealed),
        dry,
        "r_s = ∞ must be the dry model"
    );
    let nearly = surface_history(evaporating_front(295.0, 2.0, 1e9));
    let max_diff = dry
        .iter()
        .zip(&nearly)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        max_diff > 0.0 && max_diff < 1e-4,
        "r_s = 1e9 s/m: {max_diff} K"
    );
    let wet = surface_history(evaporating_front(295.0, 2.0, 70.0));
    let cooling = dry.last().unwrap() - wet.last().unwrap();
    eprintln!("r_s 70 s/m cools the surface by {cooling:.2} K after 12 h of sun");
    assert!(
        cooling > 3.0,
        "evaporation should cool the surface: {cooling} K"
    );
}

/// Issue 16: the surface energy balance closes every step with the latent
/// term: the heat the scheme took in through the front face in a step
/// equals the change of stored heat to 1e-6 relative, and the trapezoidal
/// integral of the full law (absorbed, emitted, convected and evaporated)
/// agrees with the stored heat to the quadrature error.
#[test]
fn surface_balance_with_latent_heat_closes_every_step() {
    let front = evaporating_front(295.0, 2.0, 70.0);
    let mut slab = Slab::new(0.2, K_CONCRETE, RHO_C_CONCRETE, Grid::default(), 280.0);
    let e0 = slab.stored_energy_j_m2();
    let insulated = Boundary::Flux(SurfaceFlux::default());
    let dt = 10.0;
    let mut integral = 0.0;
    let mut latent = 0.0;
    let mut q_prev = front.flux(slab.front_k());
    let mut le_prev = front.latent_w_m2(slab.front_k());
    let mut worst: f64 = 0.0;
    for _ in 0..(6.0 * 3600.0 / dt) as usize {
        let (e_before, (f_before, _)) = (slab.stored_energy_j_m2(), slab.boundary_energy_j_m2());
        slab.step(dt, |_| Boundary::Flux(front), |_| insulated);
        let de = slab.stored_energy_j_m2() - e_before;
        let df = slab.boundary_energy_j_m2().0 - f_before;
        worst = worst.max((de - df).abs() / de.abs().max(df.abs()).max(1e-300));
        let q = front.flux(slab.front_k());
        let le = front.latent_w_m2(slab.front_k());
        integral += 0.5 * dt * (q_prev + q);
        latent += 0.5 * dt * (le_prev + le);
        q_prev = q;
        le_prev = le;
    }
    let de = slab.stored_energy_j_m2() - e0;
    eprintln!(
        "latent energy: ∫q dt = {integral:.1} J/m², ΔE = {de:.1} J/m², ∫LE dt = {latent:.1} J/m², \
         worst step closure {worst:.2e}"
    );
    assert!(worst < 1e-6, "a step's budget is off by {worst:e} relative");
    assert!(latent > 1e6, "the surface should have evaporated: {latent}");
    assert!(
        (integral / de - 1.0).abs() < 1e-3,
        "∫q dt {integral} vs ΔE {de}"
    );
}

/// Issue 20: `irsig thermal` run from any folder finds the stock material library (built
/// in, not `scenes/materials.json` under the working directory), reads a typical-year
/// EPW (months from different years) with the year of `--time`, and `--year` replaces it.
#[test]
fn cli_thermal_stock_library_and_typical_year_epw() {
    let dir = tempfile::tempdir().unwrap();
    let fixture =
        std::fs::read_to_string(repo_path("tests/data/weather/rochester_sample.epw")).unwrap();
    let mut epw: String = fixture.lines().take(8).map(|l| format!("{l}\n")).collect();
    // 30 June from 2001, 1 July from 1994: a typical year.
    for (y, m, d) in [(2001, 6, 30), (1994, 7, 1)] {
        for h in 1..=24 {
            let sun = if (7..=18).contains(&h) { 500 } else { 0 };
            epw += &format!(
                "{y},{m},{d},{h},60,?9?9?9?9E0?9?9?9?9?9?9?9?9?9?9?9?9?9?9?9*9*9?9?9?9,20.0,10.0,52,99800,0,1321,330,{sun},{},{},0,0,0,0,200,1.5,2,1,16.1,77777,9,999999999,25,0.1,0,88,0.0,0.0,0.0\n",
                sun / 2,
                sun / 2
            );
        }
    }
    let w = dir.path().join("tmy.epw");
    std::fs::write(&w, epw).unwrap();
    let run_in = |extra: &[&str]| {
        let mut args = vec![
            "thermal",
            "--material",
            "asphalt",
            "--weather",
            w.to_str().unwrap(),
            "--csv",
        ];
        args.extend_from_slice(extra);
        Command::new(irsig_bin())
            .args(&args)
            .current_dir(dir.path())
            .output()
            .unwrap()
    };
    let out = run_in(&["--time", "2025-07-01T12:00:00-05:00"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Hour-ending 01:00 on 30 June is placed at 00:30; the run ends at the --time.
    assert!(
        text.lines()
            .nth(1)
            .unwrap()
            .starts_with("2025-06-30T00:30:00-05:00,"),
        "{text}"
    );
    assert!(
        text.lines()
            .last()
            .unwrap()
            .starts_with("2025-07-01T12:00:00-05:00,"),
        "{text}"
    );
    // --year replaces every row's year (and then --time must lie in that year).
    let out = run_in(&["--time", "2024-07-01T12:00:00-05:00", "--year", "2024"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("2024-06-30T00:30:00-05:00,"));
    // A name the stock library lacks: the error lists what it has.
    let out = Command::new(irsig_bin())
        .args(["thermal", "--material", "unobtainium", "--weather"])
        .arg(&w)
        .args(["--time", "2025-07-01T12:00:00-05:00"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("stock library") && err.contains("asphalt"),
        "{err}"
    );
}

use crate::util::stock_props as stock;

/// A stock material, or `"NAME su2001"` with kB⁻¹ from its canopy (Su et
/// al. 2001), or `"NAME growing …"` with a canopy growing from 0.2 m and
/// LAI 0.5 to 1.2 m and LAI 4 over the first day of the forcing (which
/// starts at 1970-01-01 00:00 UTC).
fn stock_variant(name: &str) -> SlabProperties {
    use irsig::material::{HeatRoughness, Phenology, PhenologyPoint};
    let mut words = name.split(' ');
    let db = irsig::material::stock::stock().unwrap();
    let mut m = db.get(words.next().unwrap()).unwrap().clone();
    for w in words {
        let s = m.surface_energy.as_mut().unwrap();
        match w {
            "su2001" => s.heat_roughness = HeatRoughness::Su2001,
            "two_source" => s.canopy = irsig::material::CanopyModel::TwoSource,
            "growing" => {
                let pt = |date: &str, h: f64, lai: f64| PhenologyPoint {
                    date: date.parse().unwrap(),
                    canopy_height_m: Some(h),
                    leaf_area_index: Some(lai),
                };
                s.phenology = Phenology::try_from(vec![
                    pt("1970-01-01", 0.2, 0.5),
                    pt("1970-01-02", 1.2, 4.0),
                ])
                .unwrap();
            }
            _ => panic!("{w}"),
        }
    }
    SlabProperties::from_material(&m).unwrap()
}

/// Surfaces that evaporate, on the synthetic clear days: the latent flux
/// is positive by day and takes a large part of the absorbed sunlight; the
/// surface energy balance closes every step (front energy in = change of
/// stored heat, to 1e-6 relative) with all terms; open water stays near
/// the air temperature while the dry slab of the same thickness heats; and
/// with the stomata shut (r_s → ∞) the canopy's exchange is the dry one.
#[test]
fn surfaces_that_evaporate_close_their_energy_balance() {
    use irsig::thermal::Exchange;
    use irsig::thermal::latent::psychrometrics::saturation_vapour_pressure_pa;
    let (mut forcing, cos) = one_clear_day();
    let n = forcing.len();
    for (k, c) in cos.iter().enumerate() {
        forcing.global_horizontal_w_m2[k] =
            forcing.diffuse_horizontal_w_m2[k] + forcing.direct_normal_w_m2[k] * f64::from(*c);
    }
    let sun = vec![1.0f32; n];
    let inputs = FacetInputs::new(&sun, &cos, 1.0);
    let opts = SolveOptions::default();
    for name in [
        "grass",
        "crop",
        "water",
        "bare_soil",
        "deciduous_canopy",
        "crop su2001",
        "bare_soil su2001",
        "crop growing su2001",
    ] {
        let props = stock_variant(name);
        let ex = Exchange::new(&props, &forcing).unwrap();
        let sol = thermal::solve(&props, &forcing, &inputs, &opts).unwrap();
        let noon = (0..n)
            .max_by(|&a, &b| {
                forcing.direct_normal_w_m2[a].total_cmp(&forcing.direct_normal_w_m2[b])
            })
            .unwrap();
        let t = sol.surface_temperature_k[noon];
        let le = ex.vapour_conductance_w_m2_pa[noon]
            * (saturation_vapour_pressure_pa(t) - forcing.vapour_pressure_pa[noon]);
        let absorbed = props.solar_absorptivity * forcing.global_horizontal_w_m2[noon];
        eprintln!(
            "{name}: noon {t:.2} K (air {:.2} K), LE {le:.0} W/m², absorbed SW {absorbed:.0} W/m², \
             h {:.1} W/(m²K)",
            forcing.air_temperature_k[noon], ex.sensible_w_m2_k[noon]
        );
        assert!(le > 0.1 * absorbed, "{name}: LE {le} absorbed {absorbed}");
        let e = sol.energy;
        let closure = (e.front_in_j_m2 + e.back_in_j_m2 - e.stored_change_j_m2).abs()
            / e.front_in_j_m2
                .abs()
                .max(e.stored_change_j_m2.abs())
                .max(1.0);
        assert!(closure < 1e-6, "{name}: energy closure {closure}");
    }
}

/// Dry surfaces with the default DOE-2 convection
/// (`irsig::thermal::convection`): a concrete slab facing up, vertical and
/// facing down closes its energy balance every step (1e-6 relative); the
/// horizontal one's exchange is DOE-2's coefficient at its own surface
/// temperature (the reference surface is the facet itself: the fixed point
/// converged); convection alone (no radiation folded in) leaves it hotter
/// at noon than McAdams' combined coefficient does.
#[test]
fn dry_surfaces_with_doe2_convection_close_their_energy_balance() {
    use irsig::material::ConvectionSpec;
    use irsig::thermal::Exchange;
    use irsig::thermal::convection::doe2_w_m2_k;
    let (mut forcing, cos) = one_clear_day();
    let n = forcing.len();
    for (k, c) in cos.iter().enumerate() {
        forcing.global_horizontal_w_m2[k] =
            forcing.diffuse_horizontal_w_m2[k] + forcing.direct_normal_w_m2[k] * f64::from(*c);
    }
    let sun = vec![1.0f32; n];
    let opts = SolveOptions::default();
    let mut props = concrete_with_backs()[0];
    props.convection = ConvectionSpec::default();
    let noon = (0..n)
        .max_by(|&a, &b| forcing.direct_normal_w_m2[a].total_cmp(&forcing.direct_normal_w_m2[b]))
        .unwrap();
    for normal_z in [1.0, 0.0, -1.0] {
        let f = 0.5 * (1.0 + normal_z);
        let c: Vec<f32> = cos.iter().map(|&c| c * normal_z as f32).collect();
        let inputs = FacetInputs::new(&sun, &c, f);
        let sol = thermal::solve_facing(&props, &forcing, &inputs, &opts, normal_z).unwrap();
        let e = sol.energy;
        let closure = (e.front_in_j_m2 + e.back_in_j_m2 - e.stored_change_j_m2).abs()
            / e.front_in_j_m2
                .abs()
                .max(e.stored_change_j_m2.abs())
                .max(1.0);
        eprintln!(
            "DOE-2, cos Σ {normal_z}: noon {:.2} K (air {:.2} K), closure {closure:.1e}",
            sol.surface_temperature_k[noon], forcing.air_temperature_k[noon]
        );
        assert!(closure < 1e-6, "cos Σ {normal_z}: energy closure {closure}");
    }
    let inputs = FacetInputs::new(&sun, &cos, 1.0);
    let ex = Exchange::new(&props, &forcing).unwrap();
    let sol = thermal::solve(&props, &forcing, &inputs, &opts).unwrap();
    for k in 0..n {
        let own = doe2_w_m2_k(
            sol.surface_temperature_k[k] - forcing.air_temperature_k[k],
            1.0,
            forcing.wind_speed_m_s[k],
            1.52,
        );
        assert!(
            (ex.sensible_w_m2_k[k] - own).abs() < 0.02 * own.max(1.0),
            "record {k}: exchange {} vs DOE-2 at the surface {own}",
            ex.sensible_w_m2_k[k]
        );
    }
    let mcadams = ConvectionSpec::MCADAMS;
    let old = thermal::solve(
        &irsig::thermal::SlabProperties {
            convection: mcadams,
            ..props
        },
        &forcing,
        &inputs,
        &opts,
    )
    .unwrap();
    let (t_new, t_old) = (
        sol.surface_temperature_k[noon],
        old.surface_temperature_k[noon],
    );
    eprintln!("noon: DOE-2 {t_new:.2} K, McAdams {t_old:.2} K");
    assert!(t_new > t_old + 1.0, "DOE-2 {t_new} McAdams {t_old}");
}

/// Rain wets a surface, which evaporates and cools, dries, and returns to
/// the dry solution (issue 16): asphalt and the stock grass under two
/// clear days with a 4 mm shower at 07:00 on the second (after the spin-up
/// day, which would otherwise repeat it). Without rain the exchange is
/// exactly the dry one (no latent term on asphalt).
#[test]
fn a_wet_surface_dries_and_returns_to_the_dry_solution() {
    use irsig::thermal::{Exchange, WetStore};
    let (mut forcing, cos) = synthetic_days(true);
    let n = forcing.len();
    for (k, c) in cos.iter().enumerate() {
        forcing.global_horizontal_w_m2[k] =
            forcing.diffuse_horizontal_w_m2[k] + forcing.direct_normal_w_m2[k] * f64::from(*c);
    }
    let sun = vec![1.0f32; n];
    let inputs = FacetInputs::new(&sun, &cos, 1.0);
    let opts = SolveOptions::default();
    let asphalt = concrete_with_backs()[0]; // a dry slab (insulated back)
    assert!(!Exchange::new(&asphalt, &forcing).unwrap().has_latent());
    let mut wet = forcing.clone();
    let shower = 96 + 28; // 07:00 of the second day
    wet.precipitation_mm[shower] = 4.0;
    for (name, props) in [("asphalt-like slab", asphalt), ("grass", stock("grass"))] {
        let dry = thermal::solve(&props, &forcing, &inputs, &opts).unwrap();
        let rained = thermal::solve(&props, &wet, &inputs, &opts).unwrap();
        let ex = Exchange::new(&props, &wet).unwrap();
        let t_ref: Vec<f64> = rained.surface_temperature_k.clone();
        let mut ex_dry = Exchange::new(&props, &forcing).unwrap();
        let delta = WetStore::of(&props).wet(&wet, &t_ref, &mut ex_dry).unwrap();
        let dried = delta.iter().rposition(|&d| d > 0.0).unwrap();
        let diff: Vec<f64> = (0..n)
            .map(|k| rained.surface_temperature_k[k] - dry.surface_temperature_k[k])
            .collect();
        let noon = shower + 20;
        eprintln!(
            "{name}: wet until record {dried} ({:.1} h after the shower); at 12:00 {:+.2} K; \
             at midnight {:+.4} K",
            (dried - shower) as f64 / 4.0,
            diff[noon],
            diff[n - 1]
        );
        assert!(ex.has_latent());
        assert!(
            diff[..shower].iter().all(|d| d.abs() < 1e-9),
            "{name}: before the rain"
        );
        assert!(
            diff[shower + 4] < -0.5,
            "{name}: a wet surface cools: {}",
            diff[shower + 4]
        );
        assert!(dried > shower && dried < n - 4, "{name}: dries ({dried})");
        // After drying, the difference decays toward 0 (the slab's memory).
        let max = diff.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        assert!(
            diff[n - 1].abs() < 0.2 * max,
            "{name}: returns ({} of {max})",
            diff[n - 1]
        );
        // The dry slab's difference decays monotonically once dry (the
        // grass's exchange, fixed by its stability passes, wobbles by
        // hundredths of a kelvin).
        if props.surface.is_none() {
            assert!(
                diff[dried + 8..]
                    .windows(2)
                    .all(|w| w[1].abs() <= w[0].abs() + 1e-6),
                "{name}: decays monotonically once dry"
            );
        }
    }
}

/// A two-source canopy wet by rain (leaves and soil each hold a store,
/// `irsig::thermal::two_source`) cools, dries and returns to the dry
/// solution: the stock crop as two sources under four clear days (the
/// synthetic days' first day repeated) with a 4 mm shower at 07:00 on the
/// second. Its leaves hold 0.6 mm and dry within hours; the soil under
/// them holds 1 mm and, shaded, dries over a day. Without rain no source
/// is wet and the solution is the dry one; before the shower the two runs
/// agree to the reference passes' convergence (1e-7 K).
#[test]
fn a_wet_two_source_canopy_dries_and_returns_to_the_dry_solution() {
    use irsig::thermal::Exchange;
    let (day, day_cos) = synthetic_days(true);
    let per_day = 96;
    let n = 4 * per_day + 1;
    let times: Vec<f64> = (0..n).map(|i| i as f64 * 900.0).collect();
    let mut forcing = Forcing::constant(&times, 288.0, 2.0, 0.0, 0.0, 0.0);
    let mut cos = Vec::with_capacity(n);
    for k in 0..n {
        let j = k % per_day;
        forcing.air_temperature_k[k] = day.air_temperature_k[j];
        forcing.direct_normal_w_m2[k] = day.direct_normal_w_m2[j];
        forcing.diffuse_horizontal_w_m2[k] = day.diffuse_horizontal_w_m2[j];
        forcing.sky_longwave_w_m2[k] = day.sky_longwave_w_m2[j];
        forcing.global_horizontal_w_m2[k] =
            day.diffuse_horizontal_w_m2[j] + day.direct_normal_w_m2[j] * f64::from(day_cos[j]);
        cos.push(day_cos[j]);
    }
    let sun = vec![1.0f32; n];
    let inputs = FacetInputs::new(&sun, &cos, 1.0);
    let opts = SolveOptions::default();
    let props = stock_variant("crop two_source");
    let mut wet = forcing.clone();
    let shower = per_day + 28; // 07:00 of the second day
    wet.precipitation_mm[shower] = 4.0;
    let dry = thermal::solve(&props, &forcing, &inputs, &opts).unwrap();
    let rained = thermal::solve(&props, &wet, &inputs, &opts).unwrap();
    let ex = Exchange::new(&props, &wet).unwrap();
    let ex_dry = Exchange::new(&props, &forcing).unwrap();
    assert!(!ex_dry.two_source.iter().any(|s| s.is_wet()));
    assert!(!ex.two_source[shower - 1].is_wet() && ex.two_source[shower].is_wet());
    let dried = ex.two_source.iter().rposition(|s| s.is_wet()).unwrap();
    let diff: Vec<f64> = (0..n)
        .map(|k| rained.surface_temperature_k[k] - dry.surface_temperature_k[k])
        .collect();
    let max = diff.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    let hourly: Vec<String> = diff[shower..]
        .iter()
        .step_by(4)
        .map(|d| format!("{d:+.2}"))
        .collect();
    eprintln!(
        "crop two_source: wet until record {dried} ({:.1} h after the shower); largest \
         change {max:.2} K; at the end {:+.4} K; hourly from the shower: {}",
        (dried - shower) as f64 / 4.0,
        diff[n - 1],
        hourly.join(" ")
    );
    assert!(
        diff[..shower].iter().all(|d| d.abs() < 1e-5),
        "before the rain"
    );
    assert!(
        diff[shower + 1..shower + 24].iter().all(|&d| d < 0.0),
        "a wet canopy cools"
    );
    assert!(max > 0.3, "the shower shows: {max} K");
    assert!(dried > shower && dried < n - per_day / 2, "dries ({dried})");
    // After drying, the difference decays toward 0 (the soil's memory).
    assert!(
        diff[n - 1].abs() < 0.2 * max,
        "returns ({} of {max})",
        diff[n - 1]
    );
}

/// Spin-up from the steady state of the first day's mean forcing
/// (`SpinupStart::MeanSteady`, the default) against the old start at the
/// first record's air temperature, on the bundled town's June weather with
/// the default three spin-up days: the 1 m pond ends its last spin-up day
/// ten times closer to periodic; the soil columns (grass, crop, asphalt on
/// the ground), whose deep nodes are near the mean already, no worse.
/// Every run closes its energy budget. Printed for
/// `docs/physics/thermal.md`.
#[test]
fn mean_steady_start_settles_slow_surfaces() {
    use irsig::analysis::facet::{FacetSpec, solve_free_facet};
    use irsig::thermal::SpinupStart;
    let h = irsig::weather::load(&crate::util::repo_path("scenes/town/weather.csv")).unwrap();
    let site = *h.site().expect("the town's weather names its site");
    for (name, back) in [
        ("water", None),
        ("grass", Some(BackBoundary::GROUND)),
        ("crop", Some(BackBoundary::GROUND)),
        ("asphalt", Some(BackBoundary::GROUND)),
    ] {
        let mut props = crate::util::stock_props(name);
        if let Some(b) = back {
            props = props.with_back(b);
        }
        let change = |start: SpinupStart| {
            let mut opts = SolveOptions::default();
            opts.spinup.start = start;
            opts.spinup.tolerance_k = 0.0;
            let (sol, _) =
                solve_free_facet(&props, h.records(), &site, &FacetSpec::default(), &opts).unwrap();
            let e = sol.energy;
            let rel = (e.front_in_j_m2 + e.back_in_j_m2 - e.stored_change_j_m2).abs()
                / e.stored_change_j_m2.abs().max(1e4);
            assert!(rel < 1e-3, "{name}: {e:?}");
            (sol.spinup_change_k.unwrap(), sol.surface_temperature_k)
        };
        let (first_air, t_old) = change(SpinupStart::FirstAir);
        let (mean, t_new) = change(SpinupStart::MeanSteady);
        let last = t_old.len() - 1;
        println!(
            "{name}: last spin-up day changed the state by {first_air:.3} K from the first air \
             temperature, {mean:.3} K from the mean-forcing steady state; surface at the last \
             record {:.2} K vs {:.2} K",
            t_old[last], t_new[last]
        );
        // The pond's deep water is the slow part: it settles; the thinner
        // columns, whose last day is the diurnal wave, stay as they were.
        let bound = if name == "water" {
            0.1 * first_air
        } else {
            first_air + 0.05
        };
        assert!(mean <= bound, "{name}: {mean} K vs {first_air} K");
    }
}

/// Leaves that grow with the canopy height (`leaf_area_per_height_per_m`,
/// a): where the phenology gives no LAI, the LAI at each record is
/// `min(a·h, LAI)`; a phenology's own LAI wins; without `a` the LAI is the
/// block's at every height; and a growth that reaches the full LAI at every
/// date gives exactly the exchange without it.
#[test]
fn leaves_grow_with_the_canopy_height() {
    use irsig::material::{Phenology, PhenologyPoint, SurfaceEnergySpec};
    use irsig::thermal::latent::SurfaceResistance;
    use irsig::thermal::{Exchange, LandSurface};
    let db = irsig::material::stock::stock().unwrap();
    let crop = db.get("crop").unwrap().clone();
    let pt = |date: &str, h: f64, lai: Option<f64>| PhenologyPoint {
        date: date.parse().unwrap(),
        canopy_height_m: Some(h),
        leaf_area_index: lai,
    };
    let heights = Phenology::try_from(vec![
        pt("1970-01-01", 0.15, None),
        pt("1970-01-11", 0.9, None),
    ])
    .unwrap();
    let lai_at = |spec: &SurfaceEnergySpec, day: f64| match LandSurface::from_spec(spec)
        .unwrap()
        .on(day * 86_400.0)
        .resistance
    {
        SurfaceResistance::Canopy(js) => js.leaf_area_index,
        r => panic!("{r:?}"),
    };
    let mut spec = crop.surface_energy.unwrap();
    spec.phenology = heights;
    assert_eq!(lai_at(&spec, 0.0), 3.0);
    spec.leaf_area_per_height_per_m = Some(6.8);
    assert!((lai_at(&spec, 0.0) - 6.8 * 0.15).abs() < 1e-12);
    // Day 2: h = 0.15 + 0.075·2 = 0.3 m.
    assert!((lai_at(&spec, 2.0) - 6.8 * 0.3).abs() < 1e-12);
    assert_eq!(lai_at(&spec, 10.0), 3.0);
    // A constant canopy grows to min(a·h, LAI) too: 1 m gives the full 3.
    let mut still = crop.surface_energy.unwrap();
    still.leaf_area_per_height_per_m = Some(2.0);
    assert_eq!(lai_at(&still, 5.0), 2.0);
    // A phenology that gives the LAI keeps it.
    let mut given = spec;
    given.phenology = Phenology::try_from(vec![pt("1970-01-01", 0.15, Some(0.5))]).unwrap();
    assert_eq!(lai_at(&given, 0.0), 0.5);
    // Reaching the full LAI everywhere: exactly the model without growth.
    let (forcing, _) = synthetic_days(true);
    let exchange = |a: Option<f64>| {
        let mut s = spec;
        s.leaf_area_per_height_per_m = a;
        let mut m = crop.clone();
        m.surface_energy = Some(s);
        Exchange::new(&SlabProperties::from_material(&m).unwrap(), &forcing).unwrap()
    };
    assert_eq!(exchange(Some(1e3)), exchange(None));
    assert_ne!(exchange(Some(6.8)), exchange(None));
}

/// `days` copies of the synthetic clear day (15-minute records), with the
/// global horizontal irradiance the stomata see, and the cosines of
/// incidence of a horizontal facet.
fn clear_days(days: usize) -> (Forcing, Vec<f32>) {
    let (day, day_cos) = synthetic_days(true);
    let per_day = 96;
    let n = days * per_day + 1;
    let times: Vec<f64> = (0..n).map(|i| i as f64 * 900.0).collect();
    let mut forcing = Forcing::constant(&times, 288.0, 2.0, 0.0, 0.0, 0.0);
    let mut cos = Vec::with_capacity(n);
    for k in 0..n {
        let j = k % per_day;
        forcing.air_temperature_k[k] = day.air_temperature_k[j];
        forcing.direct_normal_w_m2[k] = day.direct_normal_w_m2[j];
        forcing.diffuse_horizontal_w_m2[k] = day.diffuse_horizontal_w_m2[j];
        forcing.sky_longwave_w_m2[k] = day.sky_longwave_w_m2[j];
        forcing.global_horizontal_w_m2[k] =
            day.diffuse_horizontal_w_m2[j] + day.direct_normal_w_m2[j] * f64::from(day_cos[j]);
        cos.push(day_cos[j]);
    }
    (forcing, cos)
}

/// Stock material `name` with a root-zone water budget of depth `depth_m`
/// (`surface_energy.root_zone_depth_m`), its surface block changed by
/// `tweak`.
fn with_root_zone(
    name: &str,
    depth_m: Option<f64>,
    tweak: impl Fn(&mut irsig::material::SurfaceEnergySpec),
) -> SlabProperties {
    let db = irsig::material::stock::stock().unwrap();
    let mut m = db.get(name).unwrap().clone();
    let s = m.surface_energy.as_mut().unwrap();
    s.root_zone_depth_m = depth_m;
    tweak(s);
    SlabProperties::from_material(&m).unwrap()
}

/// The root zone's water over a run with showers (the stock grass, a 0.3 m
/// root zone, three clear days, 4, 25 and 60 mm showers): storage change =
/// infiltration − evapotranspiration − drainage − runoff summed over the
/// steps, to 1e-9 of the gross flux; rain that the leaves' store does not
/// hold infiltrates (none is lost below saturation); the showers wet the
/// soil above field capacity and it drains; θ stays within [0, θ_sat].
#[test]
fn root_zone_water_is_conserved_with_showers() {
    use irsig::thermal::Exchange;
    let (mut forcing, _) = clear_days(3);
    for (k, p) in [(124, 4.0), (150, 25.0), (200, 60.0)] {
        forcing.precipitation_mm[k] = p;
    }
    let props = with_root_zone("grass", Some(0.3), |_| {});
    let zone = props.surface.unwrap().root_zone.unwrap();
    let ex = Exchange::new(&props, &forcing).unwrap();
    let n = forcing.len();
    assert_eq!(ex.soil_moisture_m3_m3.len(), n);
    assert_eq!(ex.soil_water.len(), n - 1);
    let (mut inf, mut e, mut d, mut r, mut gross) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for s in &ex.soil_water {
        inf += s.infiltration_mm;
        e += s.evaporation_mm;
        d += s.drainage_mm;
        r += s.runoff_mm;
        gross += s.infiltration_mm + s.evaporation_mm.abs() + s.drainage_mm + s.runoff_mm;
    }
    let theta = &ex.soil_moisture_m3_m3;
    let change = zone.storage_mm(theta[n - 1]) - zone.storage_mm(theta[0]);
    let net = inf - e - d - r;
    eprintln!(
        "grass, 0.3 m root zone: rain 89 mm, infiltrated {inf:.3}, ET {e:.3}, drained {d:.3}, \
         runoff {r:.3} mm; θ {:.4} → max {:.4} → {:.4}",
        theta[0],
        theta.iter().fold(0.0f64, |m, &t| m.max(t)),
        theta[n - 1]
    );
    assert!(
        (change - net).abs() <= 1e-9 * gross,
        "storage change {change} vs net {net}"
    );
    // Every shower but what the leaves hold (0.2 LAI = 0.576 mm; they
    // dry between the showers) enters.
    assert!(
        (89.0 - 3.0 * 0.2 * 2.88 - 1e-9..=89.0).contains(&inf),
        "{inf}"
    );
    assert!(e > 0.0 && d > 0.0, "ET {e}, drainage {d}");
    assert!(theta[201] > zone.field_capacity_m3_m3, "{}", theta[201]);
    assert!(theta[202] < theta[201], "drains above field capacity");
    assert!(
        theta
            .iter()
            .all(|&t| (0.0..=zone.saturation_m3_m3 + 1e-15).contains(&t))
    );
    // Water held as θ × depth: each step's θ is the last one's plus the
    // net flux over ρ_w d_root.
    for (k, s) in ex.soil_water.iter().enumerate() {
        assert_eq!(s.theta_m3_m3, theta[k + 1]);
    }
}

/// With the stomata shut (the root zone below the wilting point: f_soil =
/// 0, r_s → ∞) nothing evaporates from the root zone: without rain θ keeps
/// its starting value exactly; with a shower that leaves it below the
/// wilting point it rises, but the exchange — and so the solution — is bit
/// for bit that of the constant-θ model (`root_zone_depth_m` absent), the
/// wet store included.
#[test]
fn root_zone_without_evaporation_keeps_theta_and_the_exchange() {
    use irsig::thermal::Exchange;
    let (forcing, cos) = clear_days(2);
    let shut = |s: &mut irsig::material::SurfaceEnergySpec| s.soil_moisture_m3_m3 = 0.10;
    let on = with_root_zone("grass", Some(0.5), shut);
    let off = with_root_zone("grass", None, shut);
    let ex = Exchange::new(&on, &forcing).unwrap();
    assert!(ex.soil_moisture_m3_m3.iter().all(|&t| t == 0.10));
    assert!(
        ex.soil_water
            .iter()
            .all(|s| s.evaporation_mm == 0.0 && s.drainage_mm == 0.0)
    );
    let mut wet = forcing.clone();
    wet.precipitation_mm[124] = 5.0; // 0.5 m: θ to ≈ 0.109 < θ_wilt = 0.12
    let n = forcing.len();
    let sun = vec![1.0f32; n];
    let inputs = FacetInputs::new(&sun, &cos, 1.0);
    let opts = SolveOptions::default();
    for f in [&forcing, &wet] {
        let a = Exchange::new(&on, f).unwrap();
        let b = Exchange::new(&off, f).unwrap();
        assert_eq!(a.sensible_w_m2_k, b.sensible_w_m2_k);
        assert_eq!(a.vapour_conductance_w_m2_pa, b.vapour_conductance_w_m2_pa);
        assert!(b.soil_moisture_m3_m3.is_empty());
        let sa = thermal::solve(&on, f, &inputs, &opts).unwrap();
        let sb = thermal::solve(&off, f, &inputs, &opts).unwrap();
        assert_eq!(sa.surface_temperature_k, sb.surface_temperature_k);
    }
    let ex = Exchange::new(&on, &wet).unwrap();
    let end = ex.soil_moisture_m3_m3[n - 1];
    assert!(end > 0.10 + 4.0 / 500.0 && end < 0.12, "{end}");
}

/// A dry-down after rain: bare soil (van de Griend & Owe's resistance,
/// 10 s/m above 15 % water, rising steeply below) with a 5 cm root zone
/// starting at θ = 0.10, a 6 mm shower on the morning of the second of six
/// clear days (θ at noon 0.126, 0.060, 0.025, 0.007, 0.000 from the second
/// day; the noon surface temperature 298.9, 303.9, 307.2, 308.4, 308.8 K,
/// with θ constant 300.3 K each day). After the shower θ falls (never rises by more than the
/// night's dew), the bare-soil resistance rises, and the noon surface
/// temperature climbs day after day; with θ held constant (no root zone)
/// the noon temperatures of the same days repeat.
#[test]
fn a_dry_down_after_rain_dries_the_soil_and_warms_the_surface() {
    use irsig::thermal::Exchange;
    let (mut forcing, cos) = clear_days(6);
    let shower = 96 + 28; // 07:00 of the second day
    forcing.precipitation_mm[shower] = 6.0;
    let dry_start = |s: &mut irsig::material::SurfaceEnergySpec| s.soil_moisture_m3_m3 = 0.10;
    let on = with_root_zone("bare_soil", Some(0.05), dry_start);
    let off = with_root_zone("bare_soil", None, dry_start);
    let n = forcing.len();
    let sun = vec![1.0f32; n];
    let inputs = FacetInputs::new(&sun, &cos, 1.0);
    let opts = SolveOptions::default();
    let ex = Exchange::new(&on, &forcing).unwrap();
    let theta = &ex.soil_moisture_m3_m3;
    let sol = thermal::solve(&on, &forcing, &inputs, &opts).unwrap();
    let still = thermal::solve(&off, &forcing, &inputs, &opts).unwrap();
    let noons: Vec<usize> = (1..6).map(|d| d * 96 + 48).collect();
    let noon_t: Vec<f64> = noons
        .iter()
        .map(|&k| sol.surface_temperature_k[k])
        .collect();
    let noon_still: Vec<f64> = noons
        .iter()
        .map(|&k| still.surface_temperature_k[k])
        .collect();
    let noon_theta: Vec<String> = noons.iter().map(|&k| format!("{:.3}", theta[k])).collect();
    let dew: f64 = ex.soil_water[shower + 1..]
        .iter()
        .map(|s| (-s.evaporation_mm).max(0.0))
        .sum();
    eprintln!(
        "bare soil dry-down: θ at noon {}; T_s at noon {:?} K (θ constant: {:?}); dew {dew:.3} mm",
        noon_theta.join(" "),
        noon_t,
        noon_still
    );
    // 5 mm of the 6 (the store holds 1 mm) over 50 mm of root zone.
    assert!(
        theta[shower + 1] > theta[shower] + 0.09,
        "{} after {}",
        theta[shower + 1],
        theta[shower]
    );
    // Falls after the shower except by dew at night.
    for (k, s) in ex.soil_water.iter().enumerate().skip(shower + 1) {
        assert!(
            theta[k + 1] <= theta[k] || s.evaporation_mm < 0.0,
            "record {k}: θ rose without dew"
        );
    }
    for w in noons.windows(2) {
        assert!(theta[w[1]] < theta[w[0]], "θ falls day by day");
    }
    let days_after = &noon_t[1..];
    assert!(
        days_after.windows(2).all(|w| w[1] > w[0] + 0.05),
        "noon T rises as the soil dries: {noon_t:?}"
    );
    assert!(
        noon_still[1..]
            .windows(2)
            .all(|w| (w[1] - w[0]).abs() < 0.05),
        "θ constant: {noon_still:?}"
    );
}

/// The stock crop as two sources (`canopy: two_source`) with a root zone
/// of `depth_m`, its surface block changed by `tweak`.
fn two_source_with_root_zone(
    depth_m: f64,
    tweak: impl Fn(&mut irsig::material::SurfaceEnergySpec),
) -> SlabProperties {
    with_root_zone("crop", Some(depth_m), |s| {
        s.canopy = irsig::material::CanopyModel::TwoSource;
        tweak(s);
    })
}

/// A two-source crop over a 0.3 m root zone through three clear days with
/// 4, 25 and 60 mm showers: the leaves' transpiration and the soil's
/// evaporation both come out of the bucket. Water: storage change =
/// infiltration − evapotranspiration − drainage − runoff to 1e-9 of the
/// gross flux; the rain the two stores (leaves 0.2 LAI, soil 1 mm) do not
/// hold infiltrates. Energy: solved as the open surface, both sources
/// close their balances at every record (leaves to 1e-6 W/m², the soil's G
/// the slab's front flux); the passes settle by their tolerance (not
/// their count), so the water the bucket lost is the dry latent heat of
/// the solution over λ to 1e-3.
#[test]
fn two_source_root_zone_conserves_water_and_energy_with_showers() {
    use irsig::thermal::Exchange;
    use irsig::thermal::latent::psychrometrics::latent_heat_of_vaporisation_j_kg;
    let (mut forcing, cos) = clear_days(3);
    for (k, p) in [(124, 4.0), (150, 25.0), (200, 60.0)] {
        forcing.precipitation_mm[k] = p;
    }
    let props = two_source_with_root_zone(0.3, |_| {});
    let zone = props.surface.unwrap().root_zone.unwrap();
    let ex = Exchange::new(&props, &forcing).unwrap();
    let n = forcing.len();
    assert_eq!(ex.two_source.len(), n);
    assert_eq!(ex.soil_moisture_m3_m3.len(), n);
    assert_eq!(ex.soil_water.len(), n - 1);
    let (mut inf, mut e, mut d, mut r, mut gross) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for s in &ex.soil_water {
        inf += s.infiltration_mm;
        e += s.evaporation_mm;
        d += s.drainage_mm;
        r += s.runoff_mm;
        assert_eq!(s.capillary_rise_mm, 0.0, "no water table");
        gross += s.infiltration_mm + s.evaporation_mm.abs() + s.drainage_mm + s.runoff_mm;
    }
    let theta = &ex.soil_moisture_m3_m3;
    let change = zone.storage_mm(theta[n - 1]) - zone.storage_mm(theta[0]);
    let net = inf - e - d - r;
    eprintln!(
        "two-source crop, 0.3 m root zone: rain 89 mm, infiltrated {inf:.3}, ET {e:.3}, \
         drained {d:.3}, runoff {r:.3} mm; θ {:.4} → {:.4}",
        theta[0],
        theta[n - 1]
    );
    assert!(
        (change - net).abs() <= 1e-9 * gross,
        "storage change {change} vs net {net}"
    );
    let held = 3.0 * (1.0 + 0.2 * 3.0);
    assert!((89.0 - held - 1e-9..=89.0).contains(&inf), "{inf}");
    assert!(e > 0.0 && d > 0.0, "ET {e}, drainage {d}");
    assert!(theta[202] > zone.field_capacity_m3_m3, "{}", theta[202]);
    for (k, s) in ex.soil_water.iter().enumerate() {
        assert_eq!(s.theta_m3_m3, theta[k + 1]);
    }
    // Energy: the open surface's solution.
    let sun = vec![1.0f32; n];
    let facet = FacetInputs::new(&sun, &cos, 1.0);
    let mut opts = SolveOptions::default();
    opts.spinup.tolerance_k = 0.0;
    let sol = thermal::solve_with(&props, &forcing, &ex, &facet, &opts).unwrap();
    let sources = thermal::source_history_with(&props, &forcing, &ex, &facet).unwrap();
    let (mut worst, mut e_solution) = (0.0f64, 0.0);
    for k in 0..n {
        let step = &ex.two_source[k];
        let f = step.fluxes(sources.front_w_m2[k], sol.soil_temperature_k[k]);
        worst = worst
            .max(f.canopy_residual_w_m2().abs())
            .max((f.ground_w_m2 - sol.net_front_flux_w_m2[k]).abs());
        if k + 1 < n {
            let (le_c, le_s) = step.dry_latent_w_m2(f.canopy_k, f.soil_k);
            let dt = forcing.times_s[k + 1] - forcing.times_s[k];
            e_solution +=
                (le_c + le_s) / latent_heat_of_vaporisation_j_kg(forcing.air_temperature_k[k]) * dt;
        }
    }
    eprintln!("bucket ET {e:.4} mm, the solution's dry latent heat {e_solution:.4} mm");
    assert!(worst < 1e-6, "largest imbalance {worst} W/m²");
    let settled = ex.passes.unwrap().residual_k;
    assert!(
        ex.passes.unwrap().settled && settled < irsig::thermal::surface::REFERENCE_TOLERANCE_K,
        "the passes stopped on their count: last change {settled} K"
    );
    assert!(
        (e_solution / e - 1.0).abs() < 1e-3,
        "bucket ET {e} mm vs the solution's dry latent heat {e_solution} mm"
    );
}

/// A two-source crop over a 1 m root zone starting dry (θ = 0.20, the
/// stomata at 40 % of their soil-water factor), six clear days without
/// rain. Without a water table θ falls every day; over a water table 1.5 m
/// down (0.5 m below the roots, in the stock loam: equilibrium θ 0.447)
/// water rises (Gardner's steady flux), θ climbs towards equilibrium, the
/// leaves transpire more and the noon radiometric temperature is lower;
/// the budget (with the rise) closes to 1e-9 of the gross flux. A table
/// 100 m down (equilibrium θ 0.168, drier than the bucket) supplies
/// nothing: the run is exactly the one without.
#[test]
fn a_water_table_keeps_the_two_source_root_zone_wet() {
    use irsig::thermal::Exchange;
    let (forcing, cos) = clear_days(6);
    let n = forcing.len();
    let dry = |s: &mut irsig::material::SurfaceEnergySpec| s.soil_moisture_m3_m3 = 0.20;
    let runs: Vec<(Option<f64>, Exchange, thermal::ThermalSolution)> =
        [None, Some(1.5), Some(100.0)]
            .into_iter()
            .map(|z| {
                let props = two_source_with_root_zone(1.0, |s| {
                    dry(s);
                    s.water_table_depth_m = z;
                });
                let ex = Exchange::new(&props, &forcing).unwrap();
                let sun = vec![1.0f32; n];
                let facet = FacetInputs::new(&sun, &cos, 1.0);
                let sol =
                    thermal::solve_with(&props, &forcing, &ex, &facet, &SolveOptions::default())
                        .unwrap();
                (z, ex, sol)
            })
            .collect();
    let noon = 5 * 96 + 48;
    for (z, ex, sol) in &runs {
        let theta = &ex.soil_moisture_m3_m3;
        let rise: f64 = ex.soil_water.iter().map(|s| s.capillary_rise_mm).sum();
        let (mut net, mut gross) = (0.0, 0.0);
        for s in &ex.soil_water {
            net += s.infiltration_mm - s.evaporation_mm + s.capillary_rise_mm
                - s.drainage_mm
                - s.runoff_mm;
            gross += s.infiltration_mm
                + s.evaporation_mm.abs()
                + s.capillary_rise_mm
                + s.drainage_mm
                + s.runoff_mm;
        }
        let change = 1000.0 * (theta[n - 1] - theta[0]);
        let settled = ex.passes.unwrap().residual_k;
        eprintln!(
            "two-source crop, water table {z:?} m: θ 0.200 → {:.4}, rise {rise:.2} mm, \
             noon T_rad day 6 {:.2} K, passes settled to {settled:.1e} K",
            theta[n - 1],
            sol.surface_temperature_k[noon]
        );
        assert!(
            settled < irsig::thermal::surface::REFERENCE_TOLERANCE_K,
            "{z:?}: the passes stopped on their count: last change {settled} K"
        );
        assert!(
            (change - net).abs() <= 1e-9 * gross,
            "{z:?}: {change} vs {net}"
        );
    }
    let (none, shallow, deep) = (&runs[0], &runs[1], &runs[2]);
    let last =
        |r: &(Option<f64>, Exchange, thermal::ThermalSolution)| r.1.soil_moisture_m3_m3[n - 1];
    assert!(last(none) < 0.20, "dries without a table");
    assert!(
        none.1
            .soil_moisture_m3_m3
            .windows(2)
            .all(|w| w[1] <= w[0] + 1e-4),
        "falls but for dew"
    );
    assert!(last(shallow) > 0.25, "the table wets it: {}", last(shallow));
    assert!(
        shallow
            .1
            .soil_water
            .iter()
            .all(|s| s.capillary_rise_mm >= 0.0)
    );
    assert!(
        shallow.2.surface_temperature_k[noon] < none.2.surface_temperature_k[noon] - 0.1,
        "a wetter root zone transpires more and is cooler at noon"
    );
    let deep_rise: f64 = deep.1.soil_water.iter().map(|s| s.capillary_rise_mm).sum();
    assert_eq!(
        deep_rise, 0.0,
        "equilibrium below the bucket: nothing rises"
    );
    assert_eq!(deep.1.soil_moisture_m3_m3, none.1.soil_moisture_m3_m3);
    assert_eq!(deep.2.surface_temperature_k, none.2.surface_temperature_k);
}

/// The passes of the open reference surface settle by their tolerance,
/// not their count, at showers: the stock crop as two sources without a
/// root zone through three clear days with 4, 25 and 60 mm showers (where
/// the leaves' store, evaporating at the previous pass's leaves, swung the
/// leaves by ≈ 8 K from pass to pass) and dry; both sources close their
/// balances at every record to 1e-6 W/m².
#[test]
fn reference_passes_settle_at_showers() {
    use irsig::thermal::Exchange;
    let (dry, cos) = clear_days(3);
    let mut showers = dry.clone();
    for (k, p) in [(124, 4.0), (150, 25.0), (200, 60.0)] {
        showers.precipitation_mm[k] = p;
    }
    let n = dry.len();
    let sun = vec![1.0f32; n];
    let facet = FacetInputs::new(&sun, &cos, 1.0);
    let mut opts = SolveOptions::default();
    opts.spinup.tolerance_k = 0.0;
    let two_source = with_root_zone("crop", None, |s| {
        s.canopy = irsig::material::CanopyModel::TwoSource;
    });
    for (label, forcing) in [("dry", &dry), ("showers", &showers)] {
        let ex = Exchange::new(&two_source, forcing).unwrap();
        let settled = ex.passes.unwrap().residual_k;
        eprintln!("two-source crop, {label}: the passes settle to {settled:.2e} K");
        assert!(
            settled < irsig::thermal::surface::REFERENCE_TOLERANCE_K,
            "{label}: stopped on the pass count, last change {settled} K"
        );
        let sol = thermal::solve_with(&two_source, forcing, &ex, &facet, &opts).unwrap();
        let sources = thermal::source_history_with(&two_source, forcing, &ex, &facet).unwrap();
        let mut worst = 0.0f64;
        for k in 0..n {
            let f = ex.two_source[k].fluxes(sources.front_w_m2[k], sol.soil_temperature_k[k]);
            worst = worst
                .max(f.canopy_residual_w_m2().abs())
                .max((f.ground_w_m2 - sol.net_front_flux_w_m2[k]).abs());
        }
        assert!(worst < 1e-6, "{label}: largest imbalance {worst} W/m²");
    }
}

/// Three clear days with 4, 25 and 60 mm showers ([`clear_days`]).
fn showers(days: usize) -> (Forcing, Vec<f32>) {
    let (mut forcing, cos) = clear_days(days);
    for (k, p) in [(124, 4.0), (150, 25.0), (200, 60.0)] {
        forcing.precipitation_mm[k] = p;
    }
    (forcing, cos)
}

/// Every single-source surface's reference passes settle by their
/// tolerance, not their cap, dry and at showers (where a fixed three passes
/// left the wet store and the stability swinging from pass to pass): the
/// stock crop and grass (big leaf with a skin), the grass over a 0.3 m root
/// zone, bare soil (its `surface_energy` block) and asphalt and a wall
/// (DOE-2 slabs, the natural convection by orientation). The exchange is
/// then that of its own reference: one more pass (the exchange remade at
/// the open surface's temperatures under it, and solved) moves no record
/// by more than ten times the tolerance.
#[test]
fn single_source_reference_passes_settle_at_showers() {
    use irsig::thermal::Exchange;
    use irsig::thermal::surface::{REFERENCE_PASSES, REFERENCE_TOLERANCE_K};
    let (dry, cos) = clear_days(3);
    let (wet, _) = showers(3);
    let db = irsig::material::stock::stock().unwrap();
    let stock = |name: &str| SlabProperties::from_material(db.get(name).unwrap()).unwrap();
    let cases = [
        ("crop", stock("crop"), 1.0),
        ("grass", stock("grass"), 1.0),
        (
            "grass, root zone",
            with_root_zone("grass", Some(0.3), |_| {}),
            1.0,
        ),
        ("bare_soil", stock("bare_soil"), 1.0),
        ("asphalt", stock("asphalt"), 1.0),
        ("brick wall", stock("brick"), 0.0),
    ];
    let n = dry.len();
    let sun = vec![1.0f32; n];
    for (name, props, normal_z) in &cases {
        for (label, forcing) in [("dry", &dry), ("showers", &wet)] {
            let ex = Exchange::facing(props, forcing, *normal_z).unwrap();
            let p = ex.passes.expect("a reference was solved");
            eprintln!(
                "{name}, {label}: {} passes, last change {:.2e} K",
                p.count, p.residual_k
            );
            assert!(
                p.settled && p.residual_k < REFERENCE_TOLERANCE_K,
                "{name}, {label}: unsettled after {} passes: {} K",
                p.count,
                p.residual_k
            );
            assert!(p.count < REFERENCE_PASSES, "{name}, {label}: {p:?}");
            assert_eq!(ex.warning(name), None);
            if *normal_z == 1.0 {
                // The horizontal open surface again under the settled
                // exchange (the reference's own inputs: full sun, the
                // whole sky, the spin-up days of its first pass).
                let facet = FacetInputs::new(&sun, &cos, 1.0);
                let first = thermal::solve_with(
                    props,
                    forcing,
                    &Exchange::at_temperatures(props, forcing, &forcing.air_temperature_k).unwrap(),
                    &facet,
                    &SolveOptions::default(),
                )
                .unwrap();
                let mut opts = SolveOptions::default();
                opts.spinup.max_cycles = first.spinup_cycles;
                opts.spinup.tolerance_k = 0.0;
                let again = thermal::solve_with(props, forcing, &ex, &facet, &opts).unwrap();
                let exact = Exchange::at_temperatures(props, forcing, &again.surface_temperature_k)
                    .unwrap();
                let next = thermal::solve_with(props, forcing, &exact, &facet, &opts).unwrap();
                let worst = next
                    .surface_temperature_k
                    .iter()
                    .zip(&again.surface_temperature_k)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0f64, f64::max);
                assert!(
                    worst < 10.0 * REFERENCE_TOLERANCE_K,
                    "{name}, {label}: one more pass moves the reference by {worst:e} K"
                );
            }
        }
    }
}

/// Passes stopped on their cap are reported, never silent: the stock grass
/// at showers with a cap of two passes says it did not settle (residual
/// above the tolerance, two passes), and its warning names the material
/// and the residual; `irsig thermal`'s solve carries the report.
#[test]
fn unsettled_reference_passes_are_reported() {
    use irsig::thermal::Exchange;
    use irsig::thermal::surface::PassLimits;
    let (wet, cos) = showers(3);
    let db = irsig::material::stock::stock().unwrap();
    for name in ["grass", "asphalt"] {
        let props = SlabProperties::from_material(db.get(name).unwrap()).unwrap();
        let limits = PassLimits {
            cap: 2,
            ..PassLimits::default()
        };
        let ex = Exchange::facing_limited(&props, &wet, 1.0, limits).unwrap();
        let p = ex.passes.unwrap();
        assert_eq!(p.count, 2, "{name}");
        assert!(
            !p.settled && p.residual_k > limits.tolerance_k,
            "{name}: {p:?}"
        );
        let w = ex.warning(name).expect("a warning");
        assert!(
            w.contains(name) && w.contains(&format!("{:.2e}", p.residual_k)),
            "{w}"
        );
        // The default settles, and a solve reports how.
        let n = wet.len();
        let sun = vec![1.0f32; n];
        let facet = FacetInputs::new(&sun, &cos, 1.0);
        let sol = thermal::solve(&props, &wet, &facet, &SolveOptions::default()).unwrap();
        let p = sol.exchange_passes.unwrap();
        assert!(p.settled && p.count > 2, "{name}: {p:?}");
    }
    let bad = PassLimits {
        cap: 0,
        ..PassLimits::default()
    };
    let props = SlabProperties::from_material(db.get("grass").unwrap()).unwrap();
    let e = Exchange::facing_limited(&props, &wet, 1.0, bad).unwrap_err();
    assert!(e.to_string().contains("passes.cap"), "{e}");
}

/// A texture's clay sets the root zone's drainage (ISBA's C₃, Cosby et al.
/// 1984 class means): a material's `soil_texture` reaches its bucket, a
/// clay drains slower than the loam and a sand faster, and the loam is
/// ISBA's 0.261.
#[test]
fn root_zone_drainage_follows_the_soil_texture() {
    use irsig::material::SoilTexture;
    let c3 = |t: Option<SoilTexture>| {
        with_root_zone("grass", Some(0.5), |s| s.soil_texture = t)
            .surface
            .unwrap()
            .root_zone
            .unwrap()
            .drainage_c3
    };
    let (loam, clay, sand) = (
        c3(None),
        c3(Some(SoilTexture::Clay)),
        c3(Some(SoilTexture::Sand)),
    );
    assert!((loam - 0.261).abs() < 0.002, "{loam}");
    assert!(
        clay < 0.5 * loam && sand > 4.0 * loam,
        "{clay} {loam} {sand}"
    );
}

/// A water table in a material file that is not below the root zone, or
/// without one: an error naming the file and the field.
#[test]
fn bad_water_table_names_file_and_field() {
    let file = |extra: &str| {
        format!(
            r#"{{"materials": [{{"id": 1, "name": "field", "specific_heat_j_kg_k": 1220,
            "conductivity_w_m_k": 0.92, "density_kg_m3": 1800, "thickness_m": 0.3,
            "solar_absorptivity": 0.8, "thermal_emissivity": 0.93,
            "surface_energy": {{"kind": "canopy", "canopy_height_m": 1, "leaf_area_index": 3,
            "canopy": "two_source", {extra}}}}}]}}"#
        )
    };
    let path = std::path::Path::new("fields.json");
    for extra in [
        r#""root_zone_depth_m": 1, "water_table_depth_m": 0.8"#,
        r#""root_zone_depth_m": 1, "water_table_depth_m": 0"#,
        r#""water_table_depth_m": 2"#,
    ] {
        let errors = irsig::material::db::load_json_str_all(&file(extra), path).unwrap_err();
        let text = errors
            .iter()
            .map(|e| e.to_string())
            .collect::<Vec<_>>()
            .join("; ");
        assert!(
            text.contains("fields.json") && text.contains("surface_energy.water_table_depth_m"),
            "{extra}: {text}"
        );
    }
    let ok = r#""root_zone_depth_m": 1, "water_table_depth_m": 1.5, "soil_texture": "silty_clay""#;
    assert!(irsig::material::db::load_json_str_all(&file(ok), path).is_ok());
}
