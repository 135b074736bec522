//! A root-zone soil water budget: the volumetric water content θ(t) of a
//! bucket of depth `d_root` that rain wets and evapotranspiration dries, the
//! θ that the surface resistance sees (f_soil of the Jarvis–Stewart canopy,
//! the bare-soil resistance).
//!
//! The root-zone reservoir w₂ of ISBA (Noilhan & Planton 1989, "A simple
//! parameterization of land surface processes for meteorological models",
//! Mon. Wea. Rev. 117:536–549, the w₂ equation, without the force-restore surface
//! layer w_g) with the gravitational drainage of Mahfouf & Noilhan (1996),
//! "Inclusion of gravitational drainage in a land surface scheme based on
//! the force-restore method", J. Appl. Meteor. 35:987–992:
//!
//! ρ_w d_root dθ/dt = P_inf − E − ρ_w d_root (C₃/τ) max(0, θ − θ_fc)
//!
//! in kg m⁻² s⁻¹ (1 kg m⁻² of water = 1 mm), with ρ_w = 1000 kg m⁻³,
//! P_inf the rain that the surface store does not hold, E = LE/λ the
//! evaporation and transpiration of the step (negative: dew), τ = 1 day and
//! C₃ the drainage coefficient (Noilhan & Mahfouf 1996, "The ISBA land
//! surface parameterisation scheme", Global Planet. Change 13:145–159,
//! C₃ = 5.327·X_clay^−1.043, X_clay in %: the clay content of the soil's
//! texture class ([`SoilTexture::clay_pct`], the class means of Cosby et
//! al. 1984; loam, 18 % clay: C₃ = 0.261; sand, 3 %: 1.69; clay, 58 %:
//! 0.077).
//!
//! Each step is split: infiltration and evaporation first (evaporation
//! limited to the water above the residual content), then the drainage
//! integrated exactly over the step (the excess above field capacity decays
//! as exp(−C₃ Δt/τ)), then any water above saturation runs off. Every term
//! is returned, so storage change = P_inf − E − D − R holds to rounding;
//! θ never falls below the residual content θ_r (not by rounding either:
//! a step that evaporates to θ_r ends at θ_r exactly).
//!
//! # Capillary rise from a water table
//! With a water table at depth `z_wt` below the surface (below the root
//! zone: `L = z_wt − d_root` > 0 between the bucket's bottom and the table),
//! water rises into the bucket by the steady upward flux of Gardner (1958),
//! "Some steady-state solutions of the unsaturated moisture flow equation
//! with application to evaporation from a water table", Soil Sci.
//! 85:228–232. Darcy's law for an upward flux q (m s⁻¹) through a soil of
//! conductivity K(h) at suction h (m, > 0), `q = K(h) (dh/dz − 1)` with z
//! up from the table (h = 0 there), integrates to
//!
//! ```text
//! L = ∫₀^{h_r} dh / (1 + q/K(h))                                       (G58 eq. 4)
//! ```
//!
//! with `h_r` the suction at the bucket's bottom, here the bucket's own:
//! the retention and conductivity power laws of Campbell (1974) with the
//! texture parameters of Clapp & Hornberger (1978), Water Resour. Res.
//! 14:601–604, Table 2 ([`SoilTexture`]):
//!
//! ```text
//! h(θ) = ψ_s (θ/θ_s)^−b,   K = K_s for h ≤ ψ_s,   K(h) = K_s (ψ_s/h)^(2 + 3/b)
//! ```
//!
//! `q` is the root of that integral (Newton in ln q to 1e-10, the integral
//! by Simpson's rule over ln h to ≈ 1e-5 relative,
//! [`WaterTable::upward_flux_m_s`]); it is 0 where the bucket is as wet as
//! hydrostatic equilibrium with the table or wetter (`h_r ≤ L`; the water
//! then drains, below), and it grows, as the bucket dries, to what the soil
//! can carry from that depth at all: the flux into infinitely dry soil,
//! which for the pure power law `K = a/hⁿ` is Gardner's
//! `q_max = a (π/n / sin(π/n))ⁿ / Lⁿ` ([`WaterTable::max_upward_flux_m_s`]).
//! Over a step the rise is `q(θ)·Δt` at the bucket's θ after the step's
//! rain and evaporation, at most what fills it to the equilibrium content
//! `θ_eq = θ_s (L/ψ_s)^(−1/b)` (θ_s where L ≤ ψ_s); and the bucket drains
//! to `max(θ_fc, θ_eq)` instead of θ_fc: a soil over a shallow table holds
//! its equilibrium profile (the "field capacity" of a drained profile is
//! that of a deep table). Without a water table, nothing rises and the
//! bucket drains to θ_fc: the ISBA bucket above, exactly.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::{InputError, in_range, positive};

/// Density of liquid water, kg m⁻³ (1 mm of water per m² is 1 kg).
pub const WATER_DENSITY_KG_M3: f64 = 1000.0;

/// ISBA's drainage time scale τ, s (one day; Mahfouf & Noilhan 1996).
pub const DRAINAGE_TAU_S: f64 = 86_400.0;

/// ISBA's drainage coefficient C₃ of a soil with `clay_pct` % clay
/// (Noilhan & Mahfouf 1996: C₃ = 5.327·X_clay^−1.043), dimensionless.
pub fn drainage_coefficient_c3(clay_pct: f64) -> f64 {
    5.327 * clay_pct.powf(-1.043)
}

/// Clay content of the loam the stock soils are, % (Clapp & Hornberger
/// 1978, Water Resour. Res. 14:601, Table 2 texture class, as ISBA's loam).
pub const LOAM_CLAY_PCT: f64 = 18.0;

/// The soil texture classes of Clapp & Hornberger (1978), Table 2, each
/// with its mean hydraulic parameters ([`SoilTexture::hydraulics`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SoilTexture {
    /// Sand.
    Sand,
    /// Loamy sand.
    LoamySand,
    /// Sandy loam.
    SandyLoam,
    /// Silt loam.
    SiltLoam,
    /// Loam (ISBA's and irsig's stock soil).
    #[default]
    Loam,
    /// Sandy clay loam.
    SandyClayLoam,
    /// Silty clay loam.
    SiltyClayLoam,
    /// Clay loam.
    ClayLoam,
    /// Sandy clay.
    SandyClay,
    /// Silty clay.
    SiltyClay,
    /// Clay.
    Clay,
}

/// A soil's hydraulic power laws (module docs): `h(θ) = ψ_s (θ/θ_s)^−b`,
/// `K(θ) = K_s (θ/θ_s)^(2b+3)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SoilHydraulics {
    /// Pore-size exponent b (dimensionless, > 0).
    pub b: f64,
    /// Air-entry (saturated) suction ψ_s, m of water (> 0).
    pub air_entry_suction_m: f64,
    /// Saturated hydraulic conductivity K_s, m s⁻¹ (> 0).
    pub saturated_conductivity_m_s: f64,
    /// Water content at saturation θ_s (porosity), m³ m⁻³.
    pub saturation_m3_m3: f64,
}

impl SoilTexture {
    /// Mean clay content of the texture class, % (Cosby, Hornberger, Clapp
    /// & Ginn 1984, "A statistical exploration of the relationships of soil
    /// moisture characteristics to the physical properties of soils", Water
    /// Resour. Res. 20(6):682–690, doi:10.1029/WR020i006p00682, Table 2:
    /// the class means of 1448 US soils; 100 − sand − silt). Sets ISBA's
    /// drainage coefficient C₃ ([`drainage_coefficient_c3`]).
    pub fn clay_pct(self) -> f64 {
        use SoilTexture::*;
        match self {
            Sand => 3.0,
            LoamySand => 6.0,
            SandyLoam => 10.0,
            SiltLoam => 13.0,
            Loam => 18.0,
            SandyClayLoam => 27.0,
            SiltyClayLoam => 34.0,
            ClayLoam => 34.0,
            SandyClay => 42.0,
            SiltyClay => 47.0,
            Clay => 58.0,
        }
    }

    /// Clapp & Hornberger (1978) Table 2: b, ψ_s (cm → m), θ_s and K_s
    /// (cm min⁻¹ → m s⁻¹).
    pub fn hydraulics(self) -> SoilHydraulics {
        use SoilTexture::*;
        let (b, psi_cm, theta_s, k_cm_min) = match self {
            Sand => (4.05, 12.1, 0.395, 1.056),
            LoamySand => (4.38, 9.0, 0.410, 0.938),
            SandyLoam => (4.90, 21.8, 0.435, 0.208),
            SiltLoam => (5.30, 78.6, 0.485, 0.0432),
            Loam => (5.39, 47.8, 0.451, 0.0417),
            SandyClayLoam => (7.12, 29.9, 0.420, 0.0378),
            SiltyClayLoam => (7.75, 35.6, 0.477, 0.0102),
            ClayLoam => (8.52, 63.0, 0.476, 0.0147),
            SandyClay => (10.4, 15.3, 0.426, 0.0130),
            SiltyClay => (10.4, 49.0, 0.492, 0.0062),
            Clay => (11.4, 40.5, 0.482, 0.0077),
        };
        SoilHydraulics {
            b,
            air_entry_suction_m: psi_cm / 100.0,
            saturated_conductivity_m_s: k_cm_min / 100.0 / 60.0,
            saturation_m3_m3: theta_s,
        }
    }
}

impl SoilHydraulics {
    /// Exponent n of the conductivity `K = K_s (ψ_s/h)ⁿ`, `n = 2 + 3/b`.
    pub fn conductivity_exponent(&self) -> f64 {
        2.0 + 3.0 / self.b
    }

    /// Suction at water content `theta`, m (ψ_s at or above θ_s; +∞ at 0).
    pub fn suction_m(&self, theta_m3_m3: f64) -> f64 {
        let w = (theta_m3_m3 / self.saturation_m3_m3).min(1.0);
        if w <= 0.0 {
            return f64::INFINITY;
        }
        self.air_entry_suction_m * w.powf(-self.b)
    }

    /// Water content at suction `h` (m): the inverse of
    /// [`SoilHydraulics::suction_m`].
    pub fn water_content_m3_m3(&self, suction_m: f64) -> f64 {
        if suction_m <= self.air_entry_suction_m {
            return self.saturation_m3_m3;
        }
        self.saturation_m3_m3 * (suction_m / self.air_entry_suction_m).powf(-1.0 / self.b)
    }

    /// Conductivity at suction `h` (m), m s⁻¹.
    pub fn conductivity_m_s(&self, suction_m: f64) -> f64 {
        if suction_m <= self.air_entry_suction_m {
            return self.saturated_conductivity_m_s;
        }
        self.saturated_conductivity_m_s
            * (self.air_entry_suction_m / suction_m).powf(self.conductivity_exponent())
    }
}

/// Intervals of the composite Simpson rule over ln h of
/// [`WaterTable::height_m`].
const SIMPSON_INTERVALS: usize = 128;

/// A water table under the root zone (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaterTable {
    /// Distance L from the bucket's bottom down to the table, m (> 0).
    pub distance_m: f64,
    /// The soil between them.
    pub soil: SoilHydraulics,
}

impl WaterTable {
    /// The height above the table, m, at which a steady upward flux `q`
    /// (m s⁻¹, ≥ 0) reaches suction `h_r` (m): G58 eq. 4 (module docs),
    /// the saturated part exactly and the rest by Simpson's rule over
    /// ln h; with its derivative in ln q.
    pub fn height_m(&self, flux_m_s: f64, suction_m: f64) -> (f64, f64) {
        let s = &self.soil;
        let c = flux_m_s / s.saturated_conductivity_m_s;
        let psi = s.air_entry_suction_m;
        let sat = suction_m.min(psi);
        let mut height = sat / (1.0 + c);
        let mut slope = -sat * c / ((1.0 + c) * (1.0 + c));
        if suction_m > psi {
            let n = s.conductivity_exponent();
            let top = (suction_m / psi).ln();
            let m = SIMPSON_INTERVALS;
            let du = top / m as f64;
            let (mut sum_h, mut sum_d) = (0.0, 0.0);
            // e^u and c·e^{nu} by recurrence along the nodes.
            let (step_h, step_g) = (du.exp(), (n * du).exp());
            let (mut e_u, mut g) = (1.0, c);
            for i in 0..=m {
                let weight = if i == 0 || i == m {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                // dh = h du; 1/(1 + q/K) with q/K = c (h/ψ_s)ⁿ.
                let f = 1.0 / (1.0 + g);
                sum_h += weight * e_u * f;
                sum_d -= weight * e_u * g * f * f;
                e_u *= step_h;
                g *= step_g;
            }
            height += psi * sum_h * du / 3.0;
            slope += psi * sum_d * du / 3.0;
        }
        (height, slope)
    }

    /// The steady upward flux (m s⁻¹, ≥ 0) from the table into a bucket at
    /// `theta` (module docs): 0 at or wetter than equilibrium, else the
    /// root of [`WaterTable::height_m`] = L by Newton's method in ln q,
    /// bracketed, to 1e-10 in ln q (the quadrature's own accuracy is
    /// ≈ 1e-5).
    pub fn upward_flux_m_s(&self, theta_m3_m3: f64) -> f64 {
        let h_r = self.soil.suction_m(theta_m3_m3).min(1e7);
        let l = self.distance_m;
        // At equilibrium (to the rounding of θ ↔ h) or wetter: none.
        if h_r <= l * (1.0 + 1e-12) {
            return 0.0;
        }
        // Bracket in y = ln q (the height falls with q): the height is at
        // most ψ_s/(1 + c) + ψ_s A c^(−1/n) < ψ_s/c + ψ_s A c^(−1/n) (the
        // saturated part and Gardner's closed form above ψ_s, h_r → ∞;
        // A = (π/n)/sin(π/n)), below L where each term is below L/2.
        let s = &self.soil;
        let n = s.conductivity_exponent();
        let a = (std::f64::consts::PI / n) / (std::f64::consts::PI / n).sin();
        let psi = s.air_entry_suction_m;
        let c_hi = (2.0 * psi / l).max((2.0 * psi * a / l).powf(n));
        let mut hi = (c_hi * s.saturated_conductivity_m_s).ln();
        let mut lo = hi - 60.0;
        let mut y = hi - 1.0;
        for _ in 0..100 {
            let (z, dz) = self.height_m(y.exp(), h_r);
            let f = z - l;
            if f > 0.0 {
                lo = y;
            } else {
                hi = y;
            }
            let step = f / dz;
            let mut next = y - step;
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            if (next - y).abs() < 1e-10 || hi - lo < 1e-10 {
                return next.exp();
            }
            y = next;
        }
        y.exp()
    }

    /// The largest flux the soil carries from the table to the bucket's
    /// bottom (into infinitely dry soil), m s⁻¹: G58 eq. 4 with h_r → ∞,
    /// the saturated part and Gardner's closed form above ψ_s,
    /// `∫_ψs^∞ dh/(1 + c (h/ψ_s)ⁿ) = ψ_s (c^(−1/n) (π/n)/sin(π/n) − ∫₀¹ dv/(1 + c vⁿ))`,
    /// solved for c = q/K_s by bisection in ln c.
    pub fn max_upward_flux_m_s(&self) -> f64 {
        let s = &self.soil;
        let n = s.conductivity_exponent();
        let psi = s.air_entry_suction_m;
        let a_n = (std::f64::consts::PI / n) / (std::f64::consts::PI / n).sin();
        let height = |c: f64| {
            // ∫₀¹ dv/(1 + c vⁿ) by Simpson (smooth on [0, 1]).
            let m = 64;
            let mut sum = 0.0;
            for i in 0..=m {
                let v = i as f64 / m as f64;
                let w = if i == 0 || i == m {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                sum += w / (1.0 + c * v.powf(n));
            }
            psi / (1.0 + c) + psi * (c.powf(-1.0 / n) * a_n - sum / (3.0 * m as f64))
        };
        let (mut lo, mut hi) = (-80.0f64, 40.0f64);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if height(mid.exp()) > self.distance_m {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        s.saturated_conductivity_m_s * (0.5 * (lo + hi)).exp()
    }

    /// Water content in hydrostatic equilibrium with the table at the
    /// bucket's bottom, m³ m⁻³: `θ_s (L/ψ_s)^(−1/b)`, θ_s where L ≤ ψ_s.
    pub fn equilibrium_m3_m3(&self) -> f64 {
        self.soil.water_content_m3_m3(self.distance_m)
    }
}

/// The root-zone bucket (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RootZone {
    /// Depth d_root, m (> 0).
    pub depth_m: f64,
    /// Residual water content θ_r that evaporation cannot take, m³ m⁻³.
    pub residual_m3_m3: f64,
    /// Field capacity θ_fc, m³ m⁻³: drainage above it.
    pub field_capacity_m3_m3: f64,
    /// Saturation (porosity) θ_sat, m³ m⁻³: runoff above it.
    pub saturation_m3_m3: f64,
    /// Drainage coefficient C₃ (dimensionless; module docs).
    pub drainage_c3: f64,
    /// The water table under it (None: none; module docs).
    pub water_table: Option<WaterTable>,
}

/// One step of the bucket: the new θ and each flux of water over the step,
/// mm (kg m⁻²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaterStep {
    /// θ at the end of the step, m³ m⁻³.
    pub theta_m3_m3: f64,
    /// Rain that entered the bucket, mm.
    pub infiltration_mm: f64,
    /// Evaporation and transpiration taken (negative: dew), mm.
    pub evaporation_mm: f64,
    /// Gravitational drainage below the root zone, mm.
    pub drainage_mm: f64,
    /// Water above saturation that ran off, mm.
    pub runoff_mm: f64,
    /// Water that rose from the water table, mm (0 without one).
    pub capillary_rise_mm: f64,
}

impl RootZone {
    /// A checked bucket; errors name the field.
    ///
    /// # Errors
    /// [`InputError`] naming `root_zone_depth_m` (not finite and > 0), or
    /// a water content out of 0..=1 or out of order
    /// (θ_r ≤ θ_fc ≤ θ_sat).
    pub fn new(
        depth_m: f64,
        residual_m3_m3: f64,
        field_capacity_m3_m3: f64,
        saturation_m3_m3: f64,
    ) -> Result<RootZone, InputError> {
        positive("root_zone_depth_m", depth_m)?;
        in_range("field_capacity_m3_m3", field_capacity_m3_m3, 0.0, 1.0)?;
        in_range(
            "saturation_m3_m3",
            saturation_m3_m3,
            field_capacity_m3_m3,
            1.0,
        )?;
        in_range("residual_m3_m3", residual_m3_m3, 0.0, field_capacity_m3_m3)?;
        Ok(RootZone {
            depth_m,
            residual_m3_m3,
            field_capacity_m3_m3,
            saturation_m3_m3,
            drainage_c3: drainage_coefficient_c3(LOAM_CLAY_PCT),
            water_table: None,
        })
    }

    /// The bucket in a soil of `texture`: ISBA's drainage coefficient C₃
    /// from its clay content ([`SoilTexture::clay_pct`],
    /// [`drainage_coefficient_c3`]; [`RootZone::new`] is a loam's).
    pub fn with_texture(mut self, texture: SoilTexture) -> RootZone {
        self.drainage_c3 = drainage_coefficient_c3(texture.clay_pct());
        self
    }

    /// The bucket over a water table `depth_m` below the surface in a soil
    /// of `texture` whose porosity is the bucket's θ_sat (module docs).
    ///
    /// # Errors
    /// [`InputError`] naming `water_table_depth_m` when it is not finite or
    /// not below the root zone.
    pub fn with_water_table(
        mut self,
        depth_m: f64,
        texture: SoilTexture,
    ) -> Result<RootZone, InputError> {
        positive("water_table_depth_m", depth_m)?;
        if depth_m <= self.depth_m {
            return Err(InputError::OutOfRange {
                field: "water_table_depth_m",
                value: depth_m,
                expected: format!(
                    "a depth below the root zone (> root_zone_depth_m = {} m)",
                    self.depth_m
                ),
            });
        }
        let mut soil = texture.hydraulics();
        soil.saturation_m3_m3 = self.saturation_m3_m3;
        self.water_table = Some(WaterTable {
            distance_m: depth_m - self.depth_m,
            soil,
        });
        Ok(self)
    }

    /// Water held at `theta`, mm (kg m⁻²).
    pub fn storage_mm(&self, theta_m3_m3: f64) -> f64 {
        WATER_DENSITY_KG_M3 * self.depth_m * theta_m3_m3
    }

    /// θ after `dt_s` seconds from `theta_m3_m3` with `infiltration_mm` of
    /// rain in and `evaporation_mm` out (module docs).
    pub fn step(
        &self,
        theta_m3_m3: f64,
        infiltration_mm: f64,
        evaporation_mm: f64,
        dt_s: f64,
    ) -> WaterStep {
        let w = self.storage_mm(theta_m3_m3);
        let w_res = self.storage_mm(self.residual_m3_m3);
        let w_fc = self.storage_mm(self.field_capacity_m3_m3);
        let w_sat = self.storage_mm(self.saturation_m3_m3);
        let inf = infiltration_mm.max(0.0);
        // Evaporation cannot take water below the residual content.
        let e = evaporation_mm.min((w + inf - w_res).max(0.0));
        let w1 = w + inf - e;
        // Capillary rise from a water table, at most to equilibrium; the
        // bucket then drains to the larger of field capacity and
        // equilibrium (module docs).
        let (rise, w_drained) = match &self.water_table {
            None => (0.0, w_fc),
            Some(table) => {
                let w_eq = self.storage_mm(table.equilibrium_m3_m3());
                let theta1 = w1 / (WATER_DENSITY_KG_M3 * self.depth_m);
                let q = table.upward_flux_m_s(theta1);
                let rise = (q * WATER_DENSITY_KG_M3 * dt_s.max(0.0)).min((w_eq - w1).max(0.0));
                (rise, w_fc.max(w_eq))
            }
        };
        let w1 = w1 + rise;
        let drainage = (w1 - w_drained).max(0.0)
            * -(-self.drainage_c3 * dt_s.max(0.0) / DRAINAGE_TAU_S).exp_m1();
        let w2 = w1 - drainage;
        let runoff = (w2 - w_sat).max(0.0);
        // θ moves by the net flux (exactly unchanged when nothing flows),
        // never below θ_r (or where it started, if below): evaporation to
        // the residual content ends there, not a rounding below it.
        let net = inf - e + rise - drainage - runoff;
        let floor = self.residual_m3_m3.min(theta_m3_m3);
        WaterStep {
            theta_m3_m3: (theta_m3_m3 + net / (WATER_DENSITY_KG_M3 * self.depth_m)).max(floor),
            infiltration_mm: inf,
            evaporation_mm: e,
            drainage_mm: drainage,
            runoff_mm: runoff,
            capillary_rise_mm: rise,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn loam() -> RootZone {
        RootZone::new(1.0, 0.0, 0.32, 0.451).unwrap()
    }

    /// Noilhan & Mahfouf (1996): C₃ of a loam ≈ 0.26.
    #[test]
    fn loam_drainage_coefficient() {
        let c3 = drainage_coefficient_c3(18.0);
        assert!((c3 - 0.261).abs() < 0.002, "{c3}");
    }

    /// Above field capacity with nothing in or out, the excess decays as
    /// exp(−C₃ t/τ) (the exact solution of the drainage equation), and
    /// the drained water is what the bucket lost.
    #[test]
    fn drainage_is_the_exact_exponential_decay() {
        let b = loam();
        let theta0 = 0.40;
        let mut theta = theta0;
        let mut drained = 0.0;
        for _ in 0..48 {
            let s = b.step(theta, 0.0, 0.0, 1800.0);
            drained += s.drainage_mm;
            theta = s.theta_m3_m3;
        }
        let expect = 0.32 + (theta0 - 0.32) * (-b.drainage_c3).exp();
        assert!((theta - expect).abs() < 1e-12, "{theta} vs {expect}");
        assert!((b.storage_mm(theta0) - b.storage_mm(theta) - drained).abs() < 1e-9);
        // Below field capacity nothing drains.
        let s = b.step(0.2, 0.0, 0.0, 86_400.0);
        assert_eq!(s.theta_m3_m3, 0.2);
        assert_eq!(s.drainage_mm, 0.0);
    }

    /// Evaporation stops at the residual content; rain above saturation
    /// runs off.
    #[test]
    fn bounds_hold() {
        let b = RootZone::new(0.1, 0.05, 0.32, 0.451).unwrap();
        let s = b.step(0.06, 0.0, 50.0, 3600.0);
        assert!((s.theta_m3_m3 - 0.05).abs() < 1e-15);
        assert!((s.evaporation_mm - 1.0).abs() < 1e-9);
        let s = b.step(0.44, 100.0, 0.0, 1.0);
        assert!((s.theta_m3_m3 - 0.451).abs() < 1e-12, "{}", s.theta_m3_m3);
        assert!(s.runoff_mm > 80.0);
    }

    /// A long drought (a year of hourly steps, each asking for more
    /// evaporation than the bucket holds over θ_r, then a dry spell with
    /// dew and none): θ reaches θ_r and never falls below it, not even by
    /// rounding, in any of several depths, residuals and starting
    /// contents; the water taken is exactly the storage lost.
    #[test]
    fn drought_never_takes_theta_below_residual() {
        for depth in [0.1, 0.3, 0.7, 1.3] {
            for residual in [0.03, 0.05, 0.07, 0.1] {
                let b = RootZone::new(depth, residual, 0.32, 0.451).unwrap();
                for theta0 in [0.15, 0.23, 0.29, 0.4] {
                    let mut theta = theta0;
                    let (mut taken, mut drained) = (0.0, 0.0);
                    for k in 0..8760 {
                        // 0.5 mm/h, some hours of dew (−0.05 mm).
                        let e = if k % 24 < 6 { -0.05 } else { 0.5 };
                        let s = b.step(theta, 0.0, e, 3600.0);
                        assert!(
                            s.theta_m3_m3 >= residual,
                            "d {depth}, θ_r {residual}, θ₀ {theta0}: step {k} θ {:e}",
                            s.theta_m3_m3
                        );
                        taken += s.evaporation_mm;
                        drained += s.drainage_mm;
                        theta = s.theta_m3_m3;
                    }
                    let lost = b.storage_mm(theta0) - b.storage_mm(theta);
                    assert!(
                        (taken + drained - lost).abs() < 1e-9 * lost,
                        "{taken} + {drained} vs {lost}"
                    );
                    assert!((theta - residual).abs() < 0.01, "dried to {theta}");
                }
            }
        }
    }

    /// C₃ follows the texture's clay (Cosby et al. 1984 class means): the
    /// loam keeps ISBA's 0.261; sandier soils drain faster, clayier slower,
    /// in the order of their clay; a bucket of a texture drains with its
    /// C₃ (the excess above field capacity after a day is `exp(−C₃)`).
    #[test]
    fn drainage_follows_the_texture() {
        use SoilTexture::*;
        let order = [
            Sand,
            LoamySand,
            SandyLoam,
            SiltLoam,
            Loam,
            SandyClayLoam,
            SiltyClayLoam,
            SandyClay,
            SiltyClay,
            Clay,
        ];
        let c3: Vec<f64> = order
            .iter()
            .map(|t| drainage_coefficient_c3(t.clay_pct()))
            .collect();
        assert!(c3.windows(2).all(|w| w[1] < w[0]), "{c3:?}");
        assert_eq!(loam().drainage_c3, loam().with_texture(Loam).drainage_c3);
        assert!((drainage_coefficient_c3(Clay.clay_pct()) - 0.0772).abs() < 5e-4);
        assert!((drainage_coefficient_c3(Sand.clay_pct()) - 1.694).abs() < 5e-4);
        for t in [Sand, Loam, Clay] {
            let b = loam().with_texture(t);
            let s = b.step(0.40, 0.0, 0.0, 86_400.0);
            let expect = 0.32 + 0.08 * (-drainage_coefficient_c3(t.clay_pct())).exp();
            assert!((s.theta_m3_m3 - expect).abs() < 1e-12, "{t:?}");
        }
    }

    /// A soil of the pure power law `K = a/hⁿ` (ψ_s → 0, a = K_s ψ_s^n),
    /// whose steady flux into dry soil Gardner (1958) gives in closed form:
    /// `q_max Lⁿ / a = (π/n / sin(π/n))ⁿ` (π²/4 = 2.467 at n = 2, 1.768 at
    /// n = 3, 1.522 at n = 4). Both the closed form with its saturated
    /// part ([`WaterTable::max_upward_flux_m_s`]) and the Simpson integral
    /// solved for q at a near-dry bucket ([`WaterTable::upward_flux_m_s`])
    /// reproduce it.
    #[test]
    fn gardner_maximum_capillary_rise() {
        for b in [1.5, 3.0, 6.0, 1e9] {
            let soil = SoilHydraulics {
                b,
                air_entry_suction_m: 1e-4,
                saturated_conductivity_m_s: 1e-5,
                saturation_m3_m3: 0.45,
            };
            let n = soil.conductivity_exponent();
            let a = 1e-5 * 1e-4f64.powf(n);
            let expect_a_n =
                ((std::f64::consts::PI / n) / (std::f64::consts::PI / n).sin()).powf(n);
            for l in [0.5, 1.0, 3.0] {
                let table = WaterTable {
                    distance_m: l,
                    soil,
                };
                let q_max = table.max_upward_flux_m_s();
                let a_n = q_max * l.powf(n) / a;
                assert!(
                    (a_n / expect_a_n - 1.0).abs() < 1e-3,
                    "n {n} L {l}: {a_n} vs {expect_a_n}"
                );
            }
        }
        // n = 2 (b → ∞): π²/4.
        let pi2_4 = std::f64::consts::PI.powi(2) / 4.0;
        assert!((((std::f64::consts::PI / 2.0) / 1.0f64).powi(2) - pi2_4).abs() < 1e-15);
        // The loam near dry: the flux is the maximum (the suction at the
        // bucket's bottom ≫ L), and the root of the Simpson integral.
        let table = WaterTable {
            distance_m: 1.0,
            soil: SoilTexture::Loam.hydraulics(),
        };
        let q = table.upward_flux_m_s(1e-3);
        let q_max = table.max_upward_flux_m_s();
        assert!((q / q_max - 1.0).abs() < 1e-3, "{q} vs {q_max}");
    }

    /// The steady flux is a solution of Darcy's law: integrating
    /// `dh/dz = 1 + q/K(h)` from the table (h = 0) up by L with RK4 at the
    /// solved q reaches the bucket's suction at L; the flux falls as the bucket
    /// wets and the table deepens, never exceeds the maximum (to the
    /// quadrature's 1e-5), and is 0 at
    /// and above equilibrium.
    #[test]
    fn steady_flux_solves_darcys_law() {
        for texture in [
            SoilTexture::Loam,
            SoilTexture::SiltyClay,
            SoilTexture::SandyLoam,
        ] {
            let soil = texture.hydraulics();
            for (l, theta) in [(0.5, 0.25), (1.0, 0.3), (2.0, 0.2), (1.0, 0.12)] {
                let table = WaterTable {
                    distance_m: l,
                    soil,
                };
                let h_r = soil.suction_m(theta);
                if h_r <= l {
                    assert_eq!(table.upward_flux_m_s(theta), 0.0);
                    continue;
                }
                let q = table.upward_flux_m_s(theta);
                assert!(
                    q > 0.0 && q <= table.max_upward_flux_m_s() * (1.0 + 1e-5),
                    "{texture:?} {l} {theta} {q} {}",
                    table.max_upward_flux_m_s()
                );
                // RK4 in z up to where the suction reaches h_r: at L.
                let f = |h: f64| 1.0 + q / soil.conductivity_m_s(h);
                let dz = l / 100_000.0;
                let (mut z, mut h) = (0.0, 0.0);
                while z < 2.0 * l {
                    let k1 = f(h);
                    let k2 = f(h + 0.5 * dz * k1);
                    let k3 = f(h + 0.5 * dz * k2);
                    let k4 = f(h + dz * k3);
                    let next = h + dz / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
                    if next >= h_r {
                        z += dz * (h_r - h) / (next - h);
                        break;
                    }
                    h = next;
                    z += dz;
                }
                assert!(
                    (z / l - 1.0).abs() < 1e-4,
                    "{texture:?} L {l} θ {theta}: z {z}"
                );
            }
            let table = WaterTable {
                distance_m: 1.0,
                soil,
            };
            let eq = table.equilibrium_m3_m3();
            assert!((soil.suction_m(eq) - 1.0).abs() < 1e-9 || eq == soil.saturation_m3_m3);
            assert_eq!(table.upward_flux_m_s(eq), 0.0);
            let (wet, dry) = (
                table.upward_flux_m_s(0.9 * eq),
                table.upward_flux_m_s(0.6 * eq),
            );
            assert!(0.0 < wet && wet < dry, "{wet} {dry}");
            let deep = WaterTable {
                distance_m: 2.0,
                soil,
            };
            assert!(deep.upward_flux_m_s(0.6 * eq) < dry);
        }
    }

    /// A dry bucket over a water table, nothing else in or out: water rises
    /// until the bucket is in equilibrium with the table and then nothing
    /// flows; at every step at most the maximum flux rises; the budget
    /// closes. A wet one over the same table drains to equilibrium, not to
    /// field capacity. A table whose equilibrium is drier than field
    /// capacity leaves a wet bucket's drainage exactly as without it.
    #[test]
    fn water_table_fills_the_bucket_to_equilibrium() {
        let b = RootZone::new(0.5, 0.0, 0.32, 0.451)
            .unwrap()
            .with_water_table(1.2, SoilTexture::Loam)
            .unwrap();
        let table = b.water_table.unwrap();
        let eq = table.equilibrium_m3_m3();
        assert!(eq > 0.32 && eq < 0.451, "{eq}");
        let q_max = table.max_upward_flux_m_s();
        let mut theta = 0.15;
        let mut rose = 0.0;
        for _ in 0..(200 * 48) {
            let s = b.step(theta, 0.0, 0.0, 1800.0);
            assert!(s.capillary_rise_mm <= q_max * 1000.0 * 1800.0 + 1e-12);
            assert!(s.theta_m3_m3 >= theta && s.theta_m3_m3 <= eq + 1e-12);
            rose += s.capillary_rise_mm - s.drainage_mm;
            theta = s.theta_m3_m3;
        }
        assert!((theta - eq).abs() < 1e-6, "{theta} vs {eq}");
        assert!((b.storage_mm(theta) - b.storage_mm(0.15) - rose).abs() < 1e-9);
        let s = b.step(eq, 0.0, 0.0, 1800.0);
        assert_eq!((s.capillary_rise_mm, s.drainage_mm), (0.0, 0.0));
        // Wetter than equilibrium: drains to it.
        let mut theta = 0.44;
        for _ in 0..(60 * 48) {
            theta = b.step(theta, 0.0, 0.0, 1800.0).theta_m3_m3;
        }
        assert!((theta - eq).abs() < 1e-4 && theta > eq, "{theta}");
        // A deep table: equilibrium below field capacity, drainage as before.
        let deep = RootZone::new(0.5, 0.0, 0.32, 0.451)
            .unwrap()
            .with_water_table(20.0, SoilTexture::Loam)
            .unwrap();
        let none = RootZone::new(0.5, 0.0, 0.32, 0.451).unwrap();
        let (a, c) = (
            deep.step(0.40, 0.0, 0.0, 1800.0),
            none.step(0.40, 0.0, 0.0, 1800.0),
        );
        assert_eq!(a.theta_m3_m3, c.theta_m3_m3);
        assert_eq!(a.drainage_mm, c.drainage_mm);
    }

    #[test]
    fn bad_water_table_names_the_field() {
        let b = RootZone::new(1.0, 0.0, 0.32, 0.451).unwrap();
        for d in [0.0, -1.0, f64::NAN, 0.5, 1.0] {
            let e = b.with_water_table(d, SoilTexture::Loam).unwrap_err();
            assert_eq!(e.field(), "water_table_depth_m", "{d}");
        }
        assert!(b.with_water_table(1.5, SoilTexture::Clay).is_ok());
    }

    #[test]
    fn bad_depth_names_the_field() {
        for d in [0.0, -1.0, f64::NAN] {
            let e = RootZone::new(d, 0.0, 0.32, 0.45).unwrap_err();
            assert_eq!(e.field(), "root_zone_depth_m");
        }
        let e = RootZone::new(1.0, 0.0, 0.32, 0.30).unwrap_err();
        assert_eq!(e.field(), "saturation_m3_m3");
    }
}
