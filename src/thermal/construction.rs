//! Layered constructions and building interiors: the parts of a facet's
//! column behind its front face.
//!
//! - [`Layers`]: a stack of homogeneous layers from the outer face (a wall:
//!   brick / insulation / plaster), each with its own conductivity, density,
//!   specific heat and thickness, and an optional contact resistance to the
//!   next layer (an air gap between glass panes, a poorly bonded joint). It
//!   is a fixed-capacity value (at most [`MAX_LAYERS`]) so that
//!   [`super::SlabProperties`] stays `Copy`. Empty: the homogeneous slab of
//!   the top-level properties, exactly as before layers existed.
//! - [`InteriorAir`]: the air temperature a building interior holds at each
//!   weather record: constant, an hourly daily schedule, or heating and
//!   cooling set points against the outdoor air.
//! - [`column_cells`]: how many finite-volume cells each layer gets.
//!
//! Owns these types, their validation and the cell allocation. Takes plain
//! numbers; gives [`LayerCells`] for [`super::Slab::layered`] and interior
//! temperatures per record. Must not know files, scenes or materials.

use super::DIURNAL_OMEGA_RAD_S;
use super::conduction::{Grid, LayerCells};
use crate::error::{Error, Result};

/// Most layers in one construction.
pub const MAX_LAYERS: usize = 8;

/// One homogeneous layer of a construction, SI units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Layer {
    /// Thermal conductivity `k`, W m⁻¹ K⁻¹.
    pub conductivity_w_m_k: f64,
    /// Mass density `ρ`, kg m⁻³.
    pub density_kg_m3: f64,
    /// Specific heat `c`, J kg⁻¹ K⁻¹.
    pub specific_heat_j_kg_k: f64,
    /// Thickness, m.
    pub thickness_m: f64,
    /// Contact resistance between this layer and the next one behind it,
    /// m² K W⁻¹ (0: perfect contact; ignored on the last layer).
    pub contact_resistance_m2_k_w: f64,
}

impl Layer {
    /// Thermal diffusivity `κ = k/(ρc)`, m² s⁻¹.
    pub fn diffusivity_m2_s(&self) -> f64 {
        self.conductivity_w_m_k / (self.density_kg_m3 * self.specific_heat_j_kg_k)
    }

    /// Diurnal damping depth `√(2κ/ω)`, m (Carslaw & Jaeger §2.6).
    pub fn diurnal_damping_depth_m(&self) -> f64 {
        (2.0 * self.diffusivity_m2_s() / DIURNAL_OMEGA_RAD_S).sqrt()
    }

    /// Conductive resistance `L/k`, m² K W⁻¹.
    pub fn resistance_m2_k_w(&self) -> f64 {
        self.thickness_m / self.conductivity_w_m_k
    }
}

/// The layers of a construction from the outer (front) face, at most
/// [`MAX_LAYERS`]; empty for a homogeneous slab.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Layers {
    len: u8,
    items: [Layer; MAX_LAYERS],
}

impl Layers {
    /// No layers: the homogeneous slab of the top-level properties.
    pub const NONE: Layers = Layers {
        len: 0,
        items: [Layer {
            conductivity_w_m_k: 0.0,
            density_kg_m3: 0.0,
            specific_heat_j_kg_k: 0.0,
            thickness_m: 0.0,
            contact_resistance_m2_k_w: 0.0,
        }; MAX_LAYERS],
    };

    /// The layers of `layers` (outer face first).
    ///
    /// # Errors
    /// More than [`MAX_LAYERS`] layers (field `layers`).
    pub fn new(layers: &[Layer]) -> Result<Layers> {
        if layers.len() > MAX_LAYERS {
            return Err(Error::invalid(
                "layers",
                format!(
                    "{} layers: at most {MAX_LAYERS} are supported",
                    layers.len()
                ),
            ));
        }
        let mut out = Layers::NONE;
        out.items[..layers.len()].copy_from_slice(layers);
        out.len = layers.len() as u8;
        Ok(out)
    }

    /// The layers, outer face first.
    pub fn as_slice(&self) -> &[Layer] {
        &self.items[..self.len as usize]
    }

    /// Whether there are no layers (a homogeneous slab).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Number of layers.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// Total thickness, m.
    pub fn thickness_m(&self) -> f64 {
        self.as_slice().iter().map(|l| l.thickness_m).sum()
    }

    /// Series resistance of the layers and their contact resistances,
    /// `Σ L_i/k_i + Σ R_c`, m² K W⁻¹ (EN ISO 6946:2017 §6.7.1, without the
    /// surface resistances).
    pub fn resistance_m2_k_w(&self) -> f64 {
        let l = self.as_slice();
        l.iter().map(Layer::resistance_m2_k_w).sum::<f64>()
            + l.iter()
                .take(l.len().saturating_sub(1))
                .map(|x| x.contact_resistance_m2_k_w)
                .sum::<f64>()
    }

    /// Check every layer; errors name `layers[i].<field>`.
    pub fn validate(&self) -> Result<()> {
        for (i, l) in self.as_slice().iter().enumerate() {
            for (name, v, unit) in [
                ("conductivity_w_m_k", l.conductivity_w_m_k, "W/(m·K)"),
                ("density_kg_m3", l.density_kg_m3, "kg/m³"),
                ("specific_heat_j_kg_k", l.specific_heat_j_kg_k, "J/(kg·K)"),
                ("thickness_m", l.thickness_m, "m"),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(Error::invalid(
                        format!("layers[{i}].{name}"),
                        format!("expected a positive number ({unit}), got {v}"),
                    ));
                }
            }
            let r = l.contact_resistance_m2_k_w;
            if !(r.is_finite() && r >= 0.0) {
                return Err(Error::invalid(
                    format!("layers[{i}].contact_resistance_m2_k_w"),
                    format!("expected a resistance ≥ 0 (m²·K/W), got {r}"),
                ));
            }
        }
        Ok(())
    }
}

/// The cells of a layered column of total depth `depth_m` (≥ the layers'
/// thickness: a ground column extends its last layer down to it).
///
/// Each layer gets cells in proportion to its thickness in diurnal damping
/// depths, `τ_i = L_i/√(2κ_i/ω)` (the phase the daily wave turns through in
/// it, Carslaw & Jaeger §2.6): `n_i = max(2, round(N τ_i/Σ τ))` with `N`
/// the grid's cell count, growing by the grid's ratio from each layer's
/// front face, so every interface is a node and the steep part of the wave
/// behind each interface is resolved like the front face's. A thin layer
/// the wave crosses quickly (a membrane, a metal sheet) still gets two
/// cells.
pub fn column_cells(layers: &Layers, depth_m: f64, grid: Grid) -> Vec<LayerCells> {
    let l = layers.as_slice();
    let total = layers.thickness_m();
    let extra = (depth_m - total).max(0.0);
    let thick = |i: usize| {
        if i + 1 == l.len() {
            l[i].thickness_m + extra
        } else {
            l[i].thickness_m
        }
    };
    let tau: Vec<f64> = (0..l.len())
        .map(|i| thick(i) / l[i].diurnal_damping_depth_m())
        .collect();
    let sum: f64 = tau.iter().sum();
    (0..l.len())
        .map(|i| LayerCells {
            thickness_m: thick(i),
            conductivity_w_m_k: l[i].conductivity_w_m_k,
            rho_c: l[i].density_kg_m3 * l[i].specific_heat_j_kg_k,
            contact_resistance_m2_k_w: l[i].contact_resistance_m2_k_w,
            cells: ((grid.cells as f64 * tau[i] / sum).round() as usize).max(2),
            growth: grid.growth,
        })
        .collect()
}

pub use crate::material::construction::SCHEDULE_HOURS;

/// The air temperature a building interior holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum InteriorAir {
    /// A constant temperature, K.
    Constant(f64),
    /// One temperature per local hour of the day, K: entry `h` holds from
    /// `h:00` to `h+1:00` local time (as an EnergyPlus `Schedule:Day:Hourly`).
    /// Read at each weather record and interpolated linearly between
    /// records like the rest of the forcing.
    Hourly([f64; SCHEDULE_HOURS]),
    /// Heating and cooling set points against the outdoor air, K: the
    /// interior is at `heating_k` while the outdoor air is below it, at
    /// `cooling_k` while the outdoor air is above it, and free-floating at
    /// the outdoor air temperature in between,
    /// `T_in = clamp(T_out, heating_k, cooling_k)` (an ideal HVAC with no
    /// interior gains or thermal mass of its own; irsig's simple rule).
    SetPoints {
        /// Heating set point, K.
        heating_k: f64,
        /// Cooling set point, K (≥ the heating set point).
        cooling_k: f64,
    },
}

impl InteriorAir {
    /// The interior temperature, K, at local time of day `second_of_day`
    /// (s after local midnight, any value: wrapped to a day) with outdoor
    /// air at `outdoor_k`.
    pub fn temperature_k(&self, second_of_day: f64, outdoor_k: f64) -> f64 {
        match *self {
            InteriorAir::Constant(t) => t,
            InteriorAir::Hourly(h) => {
                let s = second_of_day.rem_euclid(86_400.0);
                h[((s / 3600.0) as usize).min(SCHEDULE_HOURS - 1)]
            }
            InteriorAir::SetPoints {
                heating_k,
                cooling_k,
            } => outdoor_k.clamp(heating_k, cooling_k),
        }
    }

    /// Check the temperatures; errors name `<prefix>.<field>` (e.g.
    /// `back.air_temperature_k`, `back.schedule_k[3]`).
    pub fn validate(&self, prefix: &str) -> Result<()> {
        let check = |name: String, t: f64| {
            if t.is_finite() && t > 0.0 {
                Ok(())
            } else {
                Err(Error::invalid(
                    format!("{prefix}.{name}"),
                    format!("expected a temperature > 0 K, got {t}"),
                ))
            }
        };
        match *self {
            InteriorAir::Constant(t) => check("air_temperature_k".into(), t),
            InteriorAir::Hourly(h) => {
                for (i, t) in h.iter().enumerate() {
                    check(format!("schedule_k[{i}]"), *t)?;
                }
                Ok(())
            }
            InteriorAir::SetPoints {
                heating_k,
                cooling_k,
            } => {
                check("heating_setpoint_k".into(), heating_k)?;
                check("cooling_setpoint_k".into(), cooling_k)?;
                if cooling_k < heating_k {
                    return Err(Error::invalid(
                        format!("{prefix}.cooling_setpoint_k"),
                        format!(
                            "the cooling set point {cooling_k} K is below the heating set point {heating_k} K"
                        ),
                    ));
                }
                Ok(())
            }
        }
    }
}
