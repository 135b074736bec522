//! Planck's law for spectral radiance, per unit wavelength (µm), its
//! temperature derivative, and the physical constants behind it.
//!
//! B(λ, T) = 2hc² / λ⁵ · 1 / (exp(hc / (λ k T)) − 1)  (Planck 1901; e.g. Siegel
//! & Howell, *Thermal Radiation Heat Transfer*, eq. 1.13), returned in
//! W·m⁻²·sr⁻¹·µm⁻¹ for λ in µm and T in K.
//!
//! Constants: the default set is **CODATA 2018**, in which h, c and k are
//! exact by the 2019 SI definition ([`Constants::CODATA_2018`]).
//! [`Constants::CODATA_2010`] is provided for comparison with older
//! references: with it B(11 µm, 300 K) = 9.573176935 W·m⁻²·sr⁻¹·µm⁻¹, the value
//! pyspectral tests against; CODATA 2018 gives 9.573180197 (3.4·10⁻⁷ relative
//! difference).

/// A set of the physical constants Planck's law needs, SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Constants {
    /// Planck constant h, J·s.
    pub planck_j_s: f64,
    /// Speed of light in vacuum c, m/s.
    pub speed_of_light_m_s: f64,
    /// Boltzmann constant k, J/K.
    pub boltzmann_j_k: f64,
}

impl Constants {
    /// CODATA 2018 (exact SI values since 2019): the default.
    pub const CODATA_2018: Constants = Constants {
        planck_j_s: 6.626_070_15e-34,
        speed_of_light_m_s: 299_792_458.0,
        boltzmann_j_k: 1.380_649e-23,
    };
    /// CODATA 2010 (Mohr, Taylor & Newell 2012, Rev. Mod. Phys. 84, 1527).
    pub const CODATA_2010: Constants = Constants {
        planck_j_s: 6.626_069_57e-34,
        speed_of_light_m_s: 299_792_458.0,
        boltzmann_j_k: 1.380_648_8e-23,
    };

    /// First radiation constant for radiance, c₁L = 2hc², in W·µm⁴·m⁻²·sr⁻¹
    /// (so that c₁L/λ⁵ with λ in µm is in W·m⁻²·sr⁻¹·µm⁻¹).
    pub fn c1l_w_um4_m2_sr(&self) -> f64 {
        // 2hc² is in W·m²·sr⁻¹. With λ in µm, λ⁵ [m⁵] = λ⁵ [µm⁵]·1e-30, and
        // "per µm" is 1e-6 × "per m": 2hc² · 1e30 · 1e-6 = 2hc² · 1e24.
        2.0 * self.planck_j_s * self.speed_of_light_m_s * self.speed_of_light_m_s * 1e24
    }
    /// Second radiation constant c₂ = hc/k, in µm·K.
    pub fn c2_um_k(&self) -> f64 {
        self.planck_j_s * self.speed_of_light_m_s / self.boltzmann_j_k * 1e6
    }
    /// Stefan–Boltzmann constant σ = 2π⁵k⁴/(15h³c²), W·m⁻²·K⁻⁴.
    pub fn stefan_boltzmann_w_m2_k4(&self) -> f64 {
        let (h, c, k) = (self.planck_j_s, self.speed_of_light_m_s, self.boltzmann_j_k);
        2.0 * std::f64::consts::PI.powi(5) * k.powi(4) / (15.0 * h.powi(3) * c * c)
    }
}

/// Precomputed Planck function for one set of constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Planck {
    c1l: f64,
    c2: f64,
}

impl Default for Planck {
    fn default() -> Self {
        Planck::new(Constants::CODATA_2018)
    }
}

impl Planck {
    /// Planck's law with the given constants.
    pub fn new(constants: Constants) -> Self {
        Planck {
            c1l: constants.c1l_w_um4_m2_sr(),
            c2: constants.c2_um_k(),
        }
    }

    /// Spectral radiance B(λ, T), W·m⁻²·sr⁻¹·µm⁻¹, for λ in µm and T in K.
    /// Returns 0 for T ≤ 0 (and for λ ≤ 0).
    #[inline]
    pub fn radiance(&self, wavelength_um: f64, temperature_k: f64) -> f64 {
        debug_assert!(wavelength_um.is_finite() && temperature_k.is_finite());
        if temperature_k <= 0.0 || wavelength_um <= 0.0 {
            return 0.0;
        }
        let x = self.c2 / (wavelength_um * temperature_k);
        if x > 700.0 {
            return 0.0;
        }
        let l2 = wavelength_um * wavelength_um;
        self.c1l / (l2 * l2 * wavelength_um * x.exp_m1())
    }

    /// ∂B/∂T (λ, T), W·m⁻²·sr⁻¹·µm⁻¹·K⁻¹.
    #[inline]
    pub fn radiance_derivative(&self, wavelength_um: f64, temperature_k: f64) -> f64 {
        if temperature_k <= 0.0 || wavelength_um <= 0.0 {
            return 0.0;
        }
        let x = self.c2 / (wavelength_um * temperature_k);
        if x > 700.0 {
            return 0.0;
        }
        let em1 = x.exp_m1();
        let b = self.c1l / (wavelength_um.powi(5) * em1);
        // dB/dT = B · x eˣ / ((eˣ − 1) T)
        b * x * (em1 + 1.0) / (em1 * temperature_k)
    }

    /// Second radiation constant c₂ in µm·K.
    pub fn c2_um_k(&self) -> f64 {
        self.c2
    }
}

/// B(λ, T) with the default (CODATA 2018) constants, W·m⁻²·sr⁻¹·µm⁻¹,
/// λ in µm, T in K.
#[inline]
pub fn planck_radiance(wavelength_um: f64, temperature_k: f64) -> f64 {
    Planck::default().radiance(wavelength_um, temperature_k)
}

/// Spectral radiance per unit wavenumber, W·m⁻²·sr⁻¹·(cm⁻¹)⁻¹, for ν in cm⁻¹:
/// L_ν = L_λ · λ²/10⁴ (λ in µm), since λ = 10⁴/ν and |dλ/dν| = 10⁴/ν² = λ²/10⁴.
pub fn planck_radiance_wavenumber(wavenumber_cm: f64, temperature_k: f64) -> f64 {
    let l = 1e4 / wavenumber_cm;
    planck_radiance(l, temperature_k) * l * l / 1e4
}
