//! Materials: thermal and optical properties, the material database (JSON)
//! and DIRSIG import (`.mat`, `.ems`). SI units inside.

use serde::{Deserialize, Serialize};

/// A spectral emissivity curve, optionally angle-dependent.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct EmissivityCurve {
    /// Wavelengths, µm, increasing.
    pub wavelengths_um: Vec<f64>,
    /// Emissivity at each wavelength (at normal incidence when `angles_deg`
    /// is empty; otherwise one row per angle).
    pub emissivity: Vec<Vec<f64>>,
    /// View zenith angles of the rows, degrees; empty = one row, normal view.
    pub angles_deg: Vec<f64>,
}

/// A material: thermal (THERM) and optical properties, SI units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Numeric id (as in DIRSIG material files).
    pub id: u32,
    /// Name (unique within a database).
    pub name: String,
    /// Specific heat, J/(kg·K).
    pub specific_heat_j_kg_k: f64,
    /// Thermal conductivity, W/(m·K).
    pub conductivity_w_m_k: f64,
    /// Mass density, kg/m³.
    pub density_kg_m3: f64,
    /// Slab thickness, m.
    pub thickness_m: f64,
    /// Solar (shortwave) absorptivity, 0–1.
    pub solar_absorptivity: f64,
    /// Broadband thermal emissivity, 0–1.
    pub thermal_emissivity: f64,
    /// Exposed area (see the material module docs for its semantics).
    pub exposed_area: f64,
    /// Self-generated power, W/m².
    pub self_power_w_m2: f64,
    /// Fraction of reflection that is specular, 0–1.
    pub specular_fraction: f64,
    /// Transmissivity, 0–1.
    pub transmissivity: f64,
    /// Spectral (and angular) emissivity; `None` = grey at `thermal_emissivity`.
    pub emissivity_curve: Option<EmissivityCurve>,
    /// Whether both faces of a facet are front faces.
    pub double_sided: bool,
}
