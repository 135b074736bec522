//! Studies on the one-facet path: the model `x ↦ outputs` that the
//! sensitivity and calibration engines drive, for a set of materials under
//! one weather history, with [`ParamSet`] parameters applied to the weather
//! and to the materials.

use super::facet::OneFacet;
use super::params::ParamSet;
use crate::material::Material;
use crate::{Error, Result};

/// Materials on a fixed facet under a weather history, perturbed by
/// parameters.
#[derive(Debug, Clone)]
pub struct MaterialStudy {
    /// Facet geometry and nominal weather.
    pub facet: OneFacet,
    /// The materials (nominal).
    pub materials: Vec<Material>,
    /// The parameters.
    pub params: ParamSet,
    /// Record index of the image time.
    pub time_index: usize,
}

impl MaterialStudy {
    /// Output names: per material, surface temperature (K) and
    /// surface-leaving band radiance (W·m⁻²·sr⁻¹) at the image time.
    pub fn output_names(&self) -> Vec<String> {
        self.materials
            .iter()
            .flat_map(|m| {
                [
                    format!("{}.surface_temperature_k", m.name),
                    format!("{}.band_radiance_w_m2_sr", m.name),
                ]
            })
            .collect()
    }

    /// Surface temperatures at every record of material `k` with
    /// parameter values `x`.
    pub fn temperature_series(&self, x: &[f64], k: usize) -> Result<Vec<f64>> {
        let w = self
            .params
            .apply_weather_at(x, &self.facet.records, Some(&self.facet.site))?;
        let m = self.params.apply_material(x, &self.materials[k])?;
        self.facet.surface_temperatures(&m, &w)
    }

    /// The outputs (see [`MaterialStudy::output_names`]) at `x`.
    pub fn evaluate(&self, x: &[f64]) -> Result<Vec<f64>> {
        let w = self
            .params
            .apply_weather_at(x, &self.facet.records, Some(&self.facet.site))?;
        let i = self.time_index;
        if i >= w.len() {
            return Err(Error::invalid(
                "time",
                "image time beyond the weather records",
            ));
        }
        let mut out = Vec::with_capacity(2 * self.materials.len());
        for base in &self.materials {
            let m = self.params.apply_material(x, base)?;
            let t = self.facet.surface_temperatures(&m, &w)?;
            out.push(t[i]);
            out.push(self.facet.band_radiance(&m, &w[i], t[i]));
        }
        Ok(out)
    }
}
