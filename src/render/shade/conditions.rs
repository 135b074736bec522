//! The inputs of shading: the per-facet thermal state, the sky, the sun
//! and the atmosphere at the image time ([`Conditions`]), what is known
//! about each facet ([`SceneOptics`]) and the options ([`ShadeOptions`]).

use glam::Vec3;

use crate::atmosphere::{Atmosphere, SkyConditions};
use crate::material::Material;
use crate::render::per_hit::PerHit;

/// Sky radiance model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sky {
    /// An isotropic sky: a blackbody at this temperature, K.
    Blackbody {
        /// Effective sky temperature, K.
        temperature_k: f64,
    },
    /// The atmosphere's sky radiance ([`Atmosphere::sky_radiance`]) for
    /// these surface conditions.
    Atmosphere(SkyConditions),
}

/// The sun as the renderer sees it at the image time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SunInput {
    /// Unit east-north-up vector toward the sun.
    pub direction: Vec3,
    /// Direct normal irradiance at the surface, W/m² (broadband; distributed
    /// over wavelength by [`super::surface_solar_spectrum`]).
    pub direct_normal_w_m2: f64,
}

/// Per-facet thermal state at the image time (global facet order).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SurfaceState {
    /// Surface temperature, K.
    pub temperature_k: Vec<f32>,
    /// Sky shape factor F, 0–1, of the front face.
    pub shape_factor: Vec<f32>,
    /// Sky shape factor of the back face of a double-sided facet, 0–1
    /// ([`crate::exposure::SkyView::back_shape_factor`]); `None`: a
    /// single-sided facet, or one whose back face's view is not known —
    /// a hit on its back face then takes the front face's `shape_factor`.
    /// Empty: `None` for every facet.
    pub back_shape_factor: Vec<Option<f32>>,
    /// Sunlit fraction, 0–1.
    pub sun_fraction: Vec<f32>,
    /// Cosine of the solar incidence on the front face (0 when the sun is
    /// behind the face or below the horizon).
    pub cos_sun: Vec<f32>,
    /// Radiative mean temperature of the background (non-sky) seen, K.
    pub background_k: Vec<f32>,
}

impl SurfaceState {
    /// Every facet at `temperature_k`, seeing only sky (F = 1), in shade.
    pub fn uniform(facets: usize, temperature_k: f32) -> Self {
        SurfaceState {
            temperature_k: vec![temperature_k; facets],
            shape_factor: vec![1.0; facets],
            back_shape_factor: vec![None; facets],
            sun_fraction: vec![0.0; facets],
            cos_sun: vec![0.0; facets],
            background_k: vec![temperature_k; facets],
        }
    }

    /// Number of facets.
    pub fn len(&self) -> usize {
        self.temperature_k.len()
    }

    /// The back face's shape factor of facet `f`, where known.
    #[inline]
    pub fn back_shape_factor(&self, f: usize) -> Option<f32> {
        self.back_shape_factor.get(f).copied().flatten()
    }

    /// Whether there are no facets.
    pub fn is_empty(&self) -> bool {
        self.temperature_k.is_empty()
    }

    /// Check the lengths agree and the values are finite and in range.
    pub fn validate(&self, facets: usize) -> crate::Result<()> {
        let lens = [
            ("temperature_k", self.temperature_k.len()),
            ("shape_factor", self.shape_factor.len()),
            ("sun_fraction", self.sun_fraction.len()),
            ("cos_sun", self.cos_sun.len()),
            ("background_k", self.background_k.len()),
        ];
        for (name, n) in lens {
            if n != facets {
                return Err(crate::Error::invalid(
                    format!("surface state `{name}`"),
                    format!("{n} values: expected one per facet ({facets})"),
                ));
            }
        }
        let nb = self.back_shape_factor.len();
        if nb != 0 && nb != facets {
            return Err(crate::Error::invalid(
                "surface state `back_shape_factor`",
                format!("{nb} values: expected none or one per facet ({facets})"),
            ));
        }
        if let Some((f, v)) = self
            .back_shape_factor
            .iter()
            .enumerate()
            .find_map(|(f, v)| v.filter(|v| !v.is_finite()).map(|v| (f, v)))
        {
            return Err(crate::Error::invalid(
                "surface state `back_shape_factor`",
                format!("facet {f}: {v}, expected a finite shape factor"),
            ));
        }
        if let Some((i, t)) = self
            .temperature_k
            .iter()
            .chain(&self.background_k)
            .enumerate()
            .find(|(_, t)| !(t.is_finite() && **t > 0.0))
        {
            return Err(crate::Error::invalid(
                "surface temperature",
                format!("value {i} is {t} K: expected a finite positive temperature"),
            ));
        }
        Ok(())
    }
}

/// Everything about the image time the shading needs.
#[derive(Debug, Clone, PartialEq)]
pub struct Conditions {
    /// Per-facet thermal state.
    pub surface: SurfaceState,
    /// Sky radiance.
    pub sky: Sky,
    /// The sun, `None` at night.
    pub sun: Option<SunInput>,
    /// Temperature of the ground beyond the scene (rays leaving the scene
    /// downward), K; a blackbody.
    pub ground_temperature_k: f64,
    /// The atmosphere: sky radiance for [`Sky::Atmosphere`]; the sensor
    /// path is applied through [`super::Shader::with_path`].
    pub atmosphere: Atmosphere,
    /// Per-hit temperatures ([`crate::render::per_hit`]); `None`: every hit takes
    /// its facet's state.
    pub per_hit: Option<std::sync::Arc<PerHit>>,
    /// Wind speed, m/s: the roughness of water's glint lobe
    /// ([`crate::render::glint::cox_munk_slope_variance`]).
    pub wind_speed_m_s: f64,
}

/// What the renderer knows about each facet of the scene.
#[derive(Debug, Clone)]
pub struct SceneOptics {
    /// Materials; facets index into this.
    pub materials: Vec<Material>,
    /// Per facet: index into `materials`.
    pub facet_material: Vec<u32>,
    /// Per facet: object id (written to the `object_id` layer).
    pub facet_object: Vec<u32>,
}

/// Shading options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadeOptions {
    /// Most secondary bounces (specular reflection / transmission) per
    /// primary ray.
    pub max_bounces: u32,
    /// Secondary-ray origin offset along the normal, m.
    pub offset_m: f32,
}
