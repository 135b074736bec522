//! Vibration–rotation bands of linear molecules built from their molecular
//! constants, as narrow-band Malkmus parameters: the CO₂ 4.3 µm band (with
//! ¹³CO₂ and the first hot band). (N₂O 4.5 µm and the other 3–5 µm
//! absorbers are LOWTRAN 7's band models, [`super::lowtran`].)
//!
//! **Lines.** A Σ–Σ parallel band of a linear molecule has P and R branches
//! (Herzberg, *Molecular Spectra and Molecular Structure* I, 2nd ed. 1950,
//! § III.2): with m = −J″ (P) or J″ + 1 (R), the line at
//! ν = ν₀ + (B′ + B″)m + (B′ − B″)m², cm⁻¹, and intensity
//! S = S_band·|m|·exp(−c₂B″J″(J″ + 1)/T)/Q_rot(T), Q_rot = Σ_J (2J + 1)
//! exp(−c₂BJ(J + 1)/T) over the J the nuclear spins allow (even J only for
//! ¹²C¹⁶O₂ and ¹³C¹⁶O₂ in their ground state; the Hönl–London factors
//! J″ (P) and J″ + 1 (R) sum to 2J″ + 1). c₂ = hc/k = 1.4388 cm K. A hot
//! band's intensity scales with its lower state's population,
//! g·exp(−c₂E_v/T). Line half-width γ = γ₀(p/1 atm)(296 K/T)^n (Lorentz;
//! Doppler broadening, ~0.002 cm⁻¹ here, matters only above ~30 km, where
//! these bands are already opaque from below).
//!
//! **Narrow bands.** Over a window Δν around each wavelength of the caller's
//! grid (its cell, at least [`MIN_WINDOW_CM`]) the lines give the Malkmus
//! parameters exactly in both limits (Lacis & Oinas 1991, J. Geophys. Res.
//! 96, 9027, eqs. 12–13): mean absorption coefficient k̄ = ΣSᵢ/Δν and
//! overlap β = 4(Σ√(Sᵢγᵢ))²/(Δν ΣSᵢ), so τ → exp(−k̄u) for weak lines and
//! exp(−Σ2√(Sᵢγᵢu)/Δν) (the sum of the lines' strong-limit equivalent
//! widths) for strong ones.
//!
//! **Far wings.** Lines outside the window add a continuum: their Lorentz
//! wings Sγ/(πΔ²) times Perrin & Hartmann's sub-Lorentzian χ(Δ)
//! ([`chi_factor`]) — what makes the 4.3 µm band's absorption end some
//! 20 cm⁻¹ beyond its head, where a Lorentz wing would stay opaque for
//! another hundred.
//!
//! Units: cm⁻¹ for wavenumbers and widths; S in cm⁻¹/(molecule cm⁻²);
//! k̄ returned in m²/g of the absorbing gas.

/// Second radiation constant hc/k, cm K (CODATA 2018).
pub const C2_CM_K: f64 = 1.438_776_877;
/// Avogadro's number, mol⁻¹.
const AVOGADRO: f64 = 6.022_140_76e23;
/// Narrowest window, cm⁻¹: a few line spacings of CO₂ (1.56 cm⁻¹), the
/// resolution of LOWTRAN's band model (5 cm⁻¹).
pub const MIN_WINDOW_CM: f64 = 5.0;
/// Farthest line whose wing is summed, cm⁻¹.
const WING_CUTOFF_CM: f64 = 300.0;
/// Reference temperature of the intensities and widths, K.
const T_REF: f64 = 296.0;
/// Highest J″ generated (population < 10⁻¹⁵ of the peak at 320 K for CO₂).
const J_MAX: u32 = 160;

/// Which absorbing gas a band belongs to (its amount along the path).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Gas {
    /// CO₂ (all isotopologues; the band's intensity is per CO₂ molecule).
    Co2,
}

/// A parallel vibration–rotation band of a linear molecule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearBand {
    /// The gas whose amount the band absorbs with.
    pub gas: Gas,
    /// Molar mass of that gas, g/mol.
    pub molar_mass: f64,
    /// Band origin ν₀, cm⁻¹.
    pub origin: f64,
    /// Rotational constant of the lower state B″, cm⁻¹.
    pub b_lower: f64,
    /// Rotational constant of the upper state B′, cm⁻¹.
    pub b_upper: f64,
    /// Integrated intensity at 296 K per molecule of the gas,
    /// cm⁻¹/(molecule cm⁻²) (isotopic abundance included).
    pub intensity_296: f64,
    /// Vibrational energy of the lower state, cm⁻¹ (0: a fundamental).
    pub lower_energy: f64,
    /// Only even J″ (symmetric ¹⁶O–C–¹⁶O in a Σg⁺ state).
    pub even_j: bool,
    /// Air-broadened half-width at 296 K and 1 atm, cm⁻¹.
    pub gamma_296: f64,
    /// Temperature exponent of the half-width.
    pub gamma_exponent: f64,
}

/// Edwards' integrated intensity of the CO₂ 4.3 µm band, 110 cm⁻¹/(g m⁻²)
/// (Edwards 1976; Modest, *Radiative Heat Transfer*, 3rd ed., table 11.3),
/// in cm⁻¹/(molecule cm⁻²): 110·10⁴ cm²/m² · 44.01 g/mol / N_A.
const CO2_V3_INTENSITY: f64 = 110.0 * 1e4 * 44.01 / AVOGADRO;

/// The bands: ¹²C¹⁶O₂ ν₃ (00⁰1–00⁰0), its first hot band (01¹1–01¹0) and
/// ¹³C¹⁶O₂ ν₃. Constants: band origins and rotational constants
/// from Herzberg, *Molecular Spectra and Molecular Structure* II (1945) and
/// Rothman & Young 1981 (J. Quant. Spectrosc. Radiat. Transfer 25, 505);
/// the hot band's intensity is the fundamental's times the population of
/// 01¹0 (degeneracy 2, 667.4 cm⁻¹) — the ν₃ transition moment hardly
/// depends on the bending quantum (harmonic approximation); ¹³CO₂ is the
/// fundamental times its natural abundance, 1.106 %. Widths: air-broadened
/// CO₂ lines, 0.07 cm⁻¹/atm at mid J with exponent 0.75 (HITRAN
/// averages; Rothman et al. 2013, J. Quant. Spectrosc. Radiat. Transfer
/// 130, 4).
pub const BANDS: [LinearBand; 3] = [
    LinearBand {
        gas: Gas::Co2,
        molar_mass: 44.01,
        origin: 2349.143,
        b_lower: 0.390_22,
        b_upper: 0.387_14,
        intensity_296: CO2_V3_INTENSITY,
        lower_energy: 0.0,
        even_j: true,
        gamma_296: 0.07,
        gamma_exponent: 0.75,
    },
    LinearBand {
        gas: Gas::Co2,
        molar_mass: 44.01,
        origin: 2336.632,
        b_lower: 0.390_64,
        b_upper: 0.387_54,
        intensity_296: CO2_V3_INTENSITY * 2.0 * 0.039_13,
        lower_energy: 667.38,
        even_j: false,
        gamma_296: 0.07,
        gamma_exponent: 0.75,
    },
    LinearBand {
        gas: Gas::Co2,
        molar_mass: 44.01,
        origin: 2283.488,
        b_lower: 0.390_24,
        b_upper: 0.387_07,
        intensity_296: CO2_V3_INTENSITY * 0.011_06,
        lower_energy: 0.0,
        even_j: true,
        gamma_296: 0.07,
        gamma_exponent: 0.75,
    },
];

/// The lines of every band of [`BANDS`], generated once.
pub fn co2_bands() -> &'static [BandLines] {
    static B: std::sync::OnceLock<Vec<BandLines>> = std::sync::OnceLock::new();
    B.get_or_init(|| BANDS.iter().map(|&b| BandLines::new(b)).collect())
}

/// One line: position (cm⁻¹), lower-state rotational energy (cm⁻¹) and
/// Hönl–London factor |m|.
#[derive(Debug, Clone, Copy)]
struct Line {
    nu: f64,
    energy: f64,
    hl: f64,
}

/// The lines of one band, sorted by wavenumber, and the J″ levels of its
/// rotational partition function.
#[derive(Debug, Clone)]
pub struct BandLines {
    band: LinearBand,
    lines: Vec<Line>,
    levels: Vec<(f64, f64)>,
}

impl BandLines {
    /// Generate the lines of `band`.
    pub fn new(band: LinearBand) -> Self {
        let mut lines = Vec::new();
        let mut levels = Vec::new();
        let (b0, b1) = (band.b_lower, band.b_upper);
        for j in 0..=J_MAX {
            if band.even_j && j % 2 == 1 {
                continue;
            }
            let jf = j as f64;
            let e = b0 * jf * (jf + 1.0);
            levels.push((2.0 * jf + 1.0, e));
            // R(J″): m = J″ + 1; P(J″): m = −J″ (none for J″ = 0).
            for m in [jf + 1.0, -jf] {
                if m == 0.0 {
                    continue;
                }
                lines.push(Line {
                    nu: band.origin + (b1 + b0) * m + (b1 - b0) * m * m,
                    energy: e,
                    hl: m.abs(),
                });
            }
        }
        lines.sort_by(|a, b| a.nu.total_cmp(&b.nu));
        BandLines {
            band,
            lines,
            levels,
        }
    }

    /// The band.
    pub fn band(&self) -> &LinearBand {
        &self.band
    }

    /// Line intensities at temperature `t_k`, cm⁻¹/(molecule cm⁻²), in the
    /// order of the sorted lines.
    fn intensities(&self, t_k: f64) -> Vec<f64> {
        let q: f64 = self
            .levels
            .iter()
            .map(|&(g, e)| g * (-C2_CM_K * e / t_k).exp())
            .sum();
        let vib = (-C2_CM_K * self.band.lower_energy * (1.0 / t_k - 1.0 / T_REF)).exp();
        let s = self.band.intensity_296 * vib / q;
        self.lines
            .iter()
            .map(|l| s * l.hl * (-C2_CM_K * l.energy / t_k).exp())
            .collect()
    }
}

/// Perrin & Hartmann's χ factor for CO₂ lines broadened by N₂ at 296 K
/// (Perrin & Hartmann 1989, J. Quant. Spectrosc. Radiat. Transfer 42, 311):
/// the far wing of a line is sub-Lorentzian, its Lorentz profile times
/// χ(Δ) = 1 for |Δ| ≤ 3 cm⁻¹, exp(−B₁(|Δ| − 3)) to 30 cm⁻¹,
/// exp(−27B₁ − B₂(|Δ| − 30)) to 120 cm⁻¹ and exp(−27B₁ − 90B₂ − B₃(|Δ| − 120))
/// beyond, B₁ = 0.0888, B₂ = 0.0526, B₃ = 0.0232 cm. It sets where the
/// 4.3 µm band's absorption ends beyond its head.
pub fn chi_factor(delta_cm: f64) -> f64 {
    const B1: f64 = 0.0888;
    const B2: f64 = 0.0526;
    const B3: f64 = 0.0232;
    let d = delta_cm.abs();
    if d <= 3.0 {
        1.0
    } else if d <= 30.0 {
        (-B1 * (d - 3.0)).exp()
    } else if d <= 120.0 {
        (-B1 * 27.0 - B2 * (d - 30.0)).exp()
    } else {
        (-B1 * 27.0 - B2 * 90.0 - B3 * (d - 120.0)).exp()
    }
}

/// Per-wavelength windows into the sorted lines of each band, for one
/// spectral grid.
#[derive(Debug, Clone)]
pub struct LineWindows {
    /// For each band, per wavelength: (first line, one past the last, Δν).
    windows: Vec<Vec<(usize, usize, f64)>>,
    /// For each band, per wavelength: the far wings of the lines outside the
    /// window, Σ Sᵢ(296 K)·χ(Δᵢ)/(πΔᵢ²) — times the half-width γ (cm⁻¹) an
    /// absorption cross-section per molecule, cm² (see [`layer_parameters`]).
    wings: Vec<Vec<f64>>,
}

impl LineWindows {
    /// Whether band `b` absorbs anywhere on the grid (lines in a window or
    /// wings within reach).
    pub fn active(&self, b: usize) -> bool {
        self.windows[b].iter().any(|&(lo, hi, _)| hi > lo) || self.wings[b].iter().any(|&w| w > 0.0)
    }
}

/// Window width around each wavenumber of `nu` (cm⁻¹, any order): the
/// grid cell, at least [`MIN_WINDOW_CM`].
pub fn window_widths(nu: &[f64]) -> Vec<f64> {
    let n = nu.len();
    (0..n)
        .map(|i| {
            let lo = if i > 0 { nu[i - 1] } else { nu[i] };
            let hi = if i + 1 < n { nu[i + 1] } else { nu[i] };
            let span = if n > 1 {
                (hi - lo).abs() / if i > 0 && i + 1 < n { 2.0 } else { 1.0 }
            } else {
                0.0
            };
            span.max(MIN_WINDOW_CM)
        })
        .collect()
}

impl LineWindows {
    /// Windows of `bands` around the wavenumbers `nu` (cm⁻¹).
    pub fn new(bands: &[BandLines], nu: &[f64]) -> Self {
        let widths = window_widths(nu);
        let windows: Vec<Vec<(usize, usize, f64)>> = bands
            .iter()
            .map(|b| {
                nu.iter()
                    .zip(&widths)
                    .map(|(&v, &w)| {
                        let lo = b.lines.partition_point(|l| l.nu < v - 0.5 * w);
                        let hi = b.lines.partition_point(|l| l.nu < v + 0.5 * w);
                        (lo, hi, w)
                    })
                    .collect()
            })
            .collect();
        // The wings use the 296 K intensities: beyond the window what counts
        // is the band's total strength and position, not its rotational
        // temperature.
        let wings = bands
            .iter()
            .zip(&windows)
            .map(|(b, win)| {
                let s = b.intensities(T_REF);
                nu.iter()
                    .zip(win)
                    .map(|(&v, &(lo, hi, _))| {
                        // Lines within WING_CUTOFF_CM (χ < 2·10⁻⁵ beyond).
                        let a = b.lines.partition_point(|l| l.nu < v - WING_CUTOFF_CM);
                        let z = b.lines.partition_point(|l| l.nu < v + WING_CUTOFF_CM);
                        b.lines[a..z]
                            .iter()
                            .zip(&s[a..z])
                            .enumerate()
                            .map(|(k, x)| (k + a, x))
                            .filter(|(k, _)| *k < lo || *k >= hi)
                            .map(|(_, (l, &si))| {
                                let d = v - l.nu;
                                si * chi_factor(d) / (std::f64::consts::PI * d * d)
                            })
                            .sum()
                    })
                    .collect()
            })
            .collect();
        LineWindows { windows, wings }
    }
}

/// Narrow-band parameters of one band at every wavelength for one layer:
/// k̄ (m²/g) and β/p-free part, see [`layer_parameters`].
pub struct LayerBand {
    /// Mean absorption coefficient k̄, m²/g of the gas.
    pub kbar: Vec<f64>,
    /// Far-wing (continuum) absorption coefficient, m²/g of the gas: the
    /// lines outside the window, Lorentz times χ.
    pub wing: Vec<f64>,
    /// Malkmus overlap parameter β at the layer's pressure and temperature.
    pub beta: Vec<f64>,
}

/// The Malkmus parameters of band `b` (index into `windows`) for a layer at
/// temperature `t_k` and pressure `p_atm` (atm).
pub fn layer_parameters(
    bands: &[BandLines],
    windows: &LineWindows,
    b: usize,
    t_k: f64,
    p_atm: f64,
) -> LayerBand {
    let lines = &bands[b];
    let s = lines.intensities(t_k);
    // Prefix sums of S and √S over the sorted lines.
    let mut cs = Vec::with_capacity(s.len() + 1);
    let mut cr = Vec::with_capacity(s.len() + 1);
    let (mut a, mut r) = (0.0, 0.0);
    cs.push(0.0);
    cr.push(0.0);
    for &v in &s {
        a += v;
        r += v.sqrt();
        cs.push(a);
        cr.push(r);
    }
    let band = &lines.band;
    let gamma = band.gamma_296 * p_atm * (T_REF / t_k).powf(band.gamma_exponent);
    // cm²/molecule → m²/g.
    let per_gram = AVOGADRO / band.molar_mass * 1e-4;
    let n = windows.windows[b].len();
    let mut kbar = Vec::with_capacity(n);
    let mut beta = Vec::with_capacity(n);
    let wing = windows.wings[b]
        .iter()
        .map(|&c| c * gamma * per_gram)
        .collect();
    for &(lo, hi, w) in &windows.windows[b] {
        let sum_s = cs[hi] - cs[lo];
        if sum_s <= 0.0 {
            kbar.push(0.0);
            beta.push(1.0);
            continue;
        }
        let sum_r = cr[hi] - cr[lo];
        kbar.push(sum_s / w * per_gram);
        beta.push(4.0 * gamma * sum_r * sum_r / (w * sum_s));
    }
    LayerBand { kbar, wing, beta }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi_factor_is_continuous_and_sub_lorentzian() {
        assert_eq!(chi_factor(0.5), 1.0);
        for d in [3.0, 30.0, 120.0] {
            let (a, b) = (chi_factor(d - 1e-9), chi_factor(d + 1e-9));
            assert!((a - b).abs() < 1e-9, "{d}: {a} {b}");
        }
        assert!(chi_factor(-50.0) == chi_factor(50.0) && chi_factor(50.0) < 0.1);
    }

    #[test]
    fn line_intensities_sum_to_the_band_intensity() {
        for band in BANDS {
            let b = BandLines::new(band);
            for t in [200.0, 296.0] {
                let total: f64 = b.intensities(t).iter().sum();
                let want = band.intensity_296
                    * (-C2_CM_K * band.lower_energy * (1.0 / t - 1.0 / T_REF)).exp();
                assert!((total / want - 1.0).abs() < 1e-3, "{total} vs {want}");
            }
        }
    }

    #[test]
    fn co2_r_branch_head_and_strongest_lines() {
        // The R branch folds back (B′ < B″) at m = (B′ + B″)/(2(B″ − B′)) ≈ 126,
        // ν ≈ 2397 cm⁻¹; the strongest lines at 296 K are near J″ = 16–18
        // (J_max = √(T/(2c₂B)) − ½ ≈ 16).
        let b = BandLines::new(BANDS[0]);
        let max_nu = b.lines.iter().map(|l| l.nu).fold(0.0, f64::max);
        assert!((max_nu - 2397.0).abs() < 2.0, "{max_nu}");
        let s = b.intensities(296.0);
        let (i, _) = s
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .unwrap();
        let j = (b.lines[i].energy / BANDS[0].b_lower + 0.25).sqrt() - 0.5;
        assert!((14.0..=20.0).contains(&j), "J″ = {j}");
    }

    #[test]
    fn malkmus_limits_match_the_lines() {
        // One window: weak limit k̄ = ΣS/Δν; strong-limit absorption √(βk̄u)
        // = Σ 2√(Sγu)/Δν.
        let bands = [BandLines::new(BANDS[0])];
        let nu = [2360.0];
        let w = LineWindows::new(&bands, &nu);
        let p = layer_parameters(&bands, &w, 0, 296.0, 1.0);
        let (lo, hi, dn) = w.windows[0][0];
        assert!(hi > lo && dn == MIN_WINDOW_CM);
        let s = bands[0].intensities(296.0);
        let per_gram = AVOGADRO / 44.01 * 1e-4;
        let sum_s: f64 = s[lo..hi].iter().sum();
        assert!((p.kbar[0] - sum_s / dn * per_gram).abs() < 1e-9 * p.kbar[0]);
        let strong: f64 = s[lo..hi]
            .iter()
            .map(|v| 2.0 * (v * 0.07).sqrt())
            .sum::<f64>()
            / dn;
        // u = 1/per_gram g/m² is 1 molecule/cm².
        let got = (p.beta[0] * p.kbar[0] / per_gram).sqrt();
        assert!((got / strong - 1.0).abs() < 1e-9, "{got} vs {strong}");
    }
}
