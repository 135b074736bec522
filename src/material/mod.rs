//! Materials: thermal and optical properties, the material database (JSON)
//! and DIRSIG import (`.mat`, `.ems`). SI units inside.
//!
//! A [`Material`] holds what the THERM-style slab model and the radiometry
//! need. A [`MaterialDb`] is a set of materials with unique names, read from
//! irsig's JSON database ([`MaterialDb::load_json`], format in [`db`]) or from
//! a DIRSIG4 `.mat` file ([`dirsig::load_mat`]); [`MaterialDb::load`] picks by
//! extension. Spectral emissivity comes inline or from a DIRSIG `.ems` or a
//! CSV file ([`dirsig::read_ems`], [`db::read_emissivity_csv`]).
//!
//! # Exposed area
//! `exposed_area` is irsig's reading of DIRSIG/THERM's `EXPOSED_AREA`, whose
//! meaning is not publicly documented. irsig interprets it as **the fraction
//! of the slab's back face that exchanges heat (convection and longwave) with
//! the air**, relative to the front (sunlit, imaged) face:
//! - `0`: the back face is insulated or rests on the ground (a road, a lawn,
//!   an insulated roof): heat leaves only through the front face;
//! - `1`: the back face is fully in the air (a thin plate, a leaf, a car
//!   panel): both faces exchange heat;
//! - in between: partly exposed (a wall with a ventilated cavity).
//!
//! The values in DIRSIG's own `tahoe.mat` (0.13 for coniferous, 0.17 pine,
//! 0.39 concrete, 0.4 asphalt, 0.45 grass, 0.5 water) are consistent with a
//! fraction. Four entries there carry `-0.5` (the "Terrain (proxy)" entry,
//! Class #2, Class #3 and Class #8 — the last a verbatim copy of steel's
//! properties): generic or placeholder classes. The sign's meaning is
//! undocumented, so irsig **keeps the value as read** (import is lossless)
//! and the thermal model uses its magnitude, `|exposed_area|`
//! ([`Material::exposed_fraction`]). Values must lie in −1..=1.
//!
//! Owns [`Material`], [`MaterialDb`] and [`EmissivityCurve`] (its lookups
//! by [`crate::math`]). Takes files through [`db`] and [`dirsig`]; gives
//! materials by name in SI units. Must not know the thermal solver or the
//! radiometry that consume them.

pub mod construction;
pub mod db;
pub mod dirsig;
pub mod stock;
pub mod surface;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Location, Result};
use crate::math::{bracket, interp1d, lerp};
pub use construction::{BackSpec, InteriorSpec, LayerEntry, MaterialLayer};
pub use surface::{
    CanopyModel, ConvectionModel, ConvectionSpec, HeatRoughness, Phenology, PhenologyPoint,
    SoilTexture, SurfaceEnergySpec, SurfaceKind, SurfaceRoughness,
};

/// A spectral emissivity curve, optionally angle-dependent.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default, JsonSchema)]
pub struct EmissivityCurve {
    /// Wavelengths, µm, increasing.
    pub wavelengths_um: Vec<f64>,
    /// Emissivity at each wavelength (at normal incidence when `angles_deg`
    /// is empty; otherwise one row per angle).
    pub emissivity: Vec<Vec<f64>>,
    /// View zenith angles of the rows, degrees; empty = one row, normal view.
    pub angles_deg: Vec<f64>,
}

impl EmissivityCurve {
    /// A grey curve (the same emissivity at every wavelength and angle),
    /// spanning 0.2–100 µm.
    pub fn grey(emissivity: f64) -> Self {
        EmissivityCurve {
            wavelengths_um: vec![0.2, 100.0],
            emissivity: vec![vec![emissivity, emissivity]],
            angles_deg: vec![],
        }
    }

    /// Problems with the curve, as messages; empty when valid. Checks:
    /// wavelengths positive and strictly increasing, one row (no angles) or
    /// one row per angle, rows as long as the wavelengths, values in 0..=1,
    /// angles in 0..=90 increasing.
    pub fn problems(&self) -> Vec<String> {
        let mut p = Vec::new();
        if self.wavelengths_um.is_empty() {
            p.push("emissivity curve has no wavelengths".to_string());
        }
        if self
            .wavelengths_um
            .iter()
            .any(|w| !(w.is_finite() && *w > 0.0))
        {
            p.push("wavelengths must be finite and > 0 µm".to_string());
        }
        if self.wavelengths_um.windows(2).any(|w| w[1] <= w[0]) {
            p.push("wavelengths must be strictly increasing".to_string());
        }
        let rows_expected = self.angles_deg.len().max(1);
        if self.emissivity.len() != rows_expected {
            p.push(format!(
                "expected {rows_expected} emissivity row(s) (one per angle, or one when `angles_deg` is empty), found {}",
                self.emissivity.len()
            ));
        }
        for (i, row) in self.emissivity.iter().enumerate() {
            if row.len() != self.wavelengths_um.len() {
                p.push(format!(
                    "emissivity row {i} has {} values for {} wavelengths",
                    row.len(),
                    self.wavelengths_um.len()
                ));
            }
            if let Some(e) = row.iter().find(|e| !(0.0..=1.0).contains(*e)) {
                p.push(format!("emissivity row {i} has {e}, expected 0..=1"));
            }
        }
        if self.angles_deg.iter().any(|a| !(0.0..=90.0).contains(a))
            || self.angles_deg.windows(2).any(|w| w[1] <= w[0])
        {
            p.push("angles_deg must be increasing within 0..=90".to_string());
        }
        p
    }

    /// Emissivity at `wavelength_um` and view zenith `angle_deg`, linearly
    /// interpolated in both, clamped to the ends of the tables.
    pub fn at(&self, wavelength_um: f64, angle_deg: f64) -> f64 {
        let row_at = |row: &[f64]| interp1d(&self.wavelengths_um, row, wavelength_um);
        if self.angles_deg.len() < 2 {
            return row_at(&self.emissivity[0]);
        }
        match bracket(&self.angles_deg, angle_deg) {
            (i, j, _) if i == j => row_at(&self.emissivity[i]),
            (i, j, t) => lerp(row_at(&self.emissivity[i]), row_at(&self.emissivity[j]), t),
        }
    }

    /// Band-average emissivity at normal view over `[lo_um, hi_um]`
    /// (unweighted, trapezoidal on a fine grid).
    pub fn band_mean(&self, lo_um: f64, hi_um: f64) -> f64 {
        if hi_um <= lo_um {
            return self.at(lo_um, 0.0);
        }
        let n = 200;
        let h = (hi_um - lo_um) / n as f64;
        let mut s = 0.5 * (self.at(lo_um, 0.0) + self.at(hi_um, 0.0));
        for k in 1..n {
            s += self.at(lo_um + k as f64 * h, 0.0);
        }
        s / n as f64
    }
}

/// A material: thermal (THERM) and optical properties, SI units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
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
    /// Broadband thermal emissivity at **normal** view, 0–1 (as DIRSIG's
    /// `THERMAL_EMISSIVITY`). The renderer applies the angular model of
    /// [`crate::radiometry::Emissivity`] to it; the thermal model uses the
    /// hemispherical value of that model
    /// ([`crate::radiometry::emissivity::thermal_hemispherical_emissivity`]).
    pub thermal_emissivity: f64,
    /// Exposed area (see the material module docs for its semantics).
    pub exposed_area: f64,
    /// Self-generated power, W/m².
    pub self_power_w_m2: f64,
    /// Fraction of reflection that is specular, 0–1.
    pub specular_fraction: f64,
    /// RMS facet slope `m` (dimensionless, ≥ 0) of the glint lobe through
    /// which the specular part reflects the sun
    /// ([`crate::render::glint::lobe_slope_variance`]: Beckmann `m²`);
    /// `None`: [`crate::render::glint::GLOSSY_RMS_SLOPE`]. Not for water,
    /// whose roughness is Cox & Munk's from the wind.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub specular_roughness: Option<f64>,
    /// Transmissivity, 0–1.
    pub transmissivity: f64,
    /// Spectral (and angular) emissivity; `None` = grey at `thermal_emissivity`.
    pub emissivity_curve: Option<EmissivityCurve>,
    /// Whether both faces of a facet are front faces.
    pub double_sided: bool,
    /// How the surface evaporates (`None`: a dry surface, convecting as
    /// `convection` says).
    pub surface_energy: Option<SurfaceEnergySpec>,
    /// How the surface convects heat to the air when it is dry
    /// ([`ConvectionSpec`]; ignored with `surface_energy`, whose exchange
    /// is the aerodynamic resistance).
    #[serde(default, skip_serializing_if = "ConvectionSpec::is_default")]
    pub convection: ConvectionSpec,
    /// The construction's layers from the outer face (empty: a single slab
    /// of the properties above). With layers, `conductivity_w_m_k`,
    /// `density_kg_m3` and `specific_heat_j_kg_k` are the outer layer's and
    /// `thickness_m` the total ([`construction`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub layers: Vec<MaterialLayer>,
    /// What the back face touches (`None`: decided by `exposed_area`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub back: Option<BackSpec>,
}

impl Material {
    /// Problems with the material as `(field, message)` pairs; empty when
    /// valid. Ranges: specific heat, conductivity, density, thickness > 0;
    /// absorptivity, emissivity, specular fraction, transmissivity in 0..=1;
    /// `|exposed_area|` ≤ 1; self power finite; curve valid; the
    /// `surface_energy` block valid (its fields named
    /// `surface_energy.<name>`).
    pub fn problems(&self) -> Vec<(String, String)> {
        let mut p = Vec::new();
        let mut positive = |field: &'static str, v: f64, unit: &str| {
            if !(v.is_finite() && v > 0.0) {
                p.push((field, format!("{v} {unit}: expected a finite value > 0")));
            }
        };
        positive(
            "specific_heat_j_kg_k",
            self.specific_heat_j_kg_k,
            "J/(kg·K)",
        );
        positive("conductivity_w_m_k", self.conductivity_w_m_k, "W/(m·K)");
        positive("density_kg_m3", self.density_kg_m3, "kg/m³");
        positive("thickness_m", self.thickness_m, "m");
        for (field, v) in [
            ("solar_absorptivity", self.solar_absorptivity),
            ("thermal_emissivity", self.thermal_emissivity),
            ("specular_fraction", self.specular_fraction),
            ("transmissivity", self.transmissivity),
        ] {
            if !(0.0..=1.0).contains(&v) {
                p.push((field, format!("{v}: expected a fraction in 0..=1")));
            }
        }
        if let Some(r) = self.specular_roughness {
            if !(r.is_finite() && r >= 0.0) {
                p.push((
                    "specular_roughness",
                    format!("{r}: expected a finite RMS facet slope ≥ 0"),
                ));
            } else if self
                .surface_energy
                .is_some_and(|s| s.kind == crate::material::surface::SurfaceKind::Water)
            {
                p.push((
                    "specular_roughness",
                    format!(
                        "{r}: water's glint roughness comes from the wind (Cox & Munk); \
                         remove `specular_roughness`"
                    ),
                ));
            }
        }
        if !(-1.0..=1.0).contains(&self.exposed_area) {
            p.push((
                "exposed_area",
                format!(
                    "{}: expected -1..=1 (fraction of the back face exposed to air)",
                    self.exposed_area
                ),
            ));
        }
        if !self.self_power_w_m2.is_finite() {
            p.push((
                "self_power_w_m2",
                format!("{}: expected a finite W/m²", self.self_power_w_m2),
            ));
        }
        if self.name.trim().is_empty() {
            p.push(("name", "empty name".to_string()));
        }
        if let Some(c) = &self.emissivity_curve {
            for m in c.problems() {
                p.push(("emissivity_curve", m));
            }
        }
        let mut p: Vec<(String, String)> = p.into_iter().map(|(f, m)| (f.to_string(), m)).collect();
        if let Some(s) = &self.surface_energy {
            for (f, m) in s.problems() {
                p.push((format!("surface_energy.{f}"), m));
            }
        }
        for (i, l) in self.layers.iter().enumerate() {
            for (f, m) in l.problems() {
                p.push((format!("layers[{i}].{f}"), m));
            }
        }
        if let Some(b) = &self.back {
            for (f, m) in b.problems() {
                p.push((format!("back.{f}"), m));
            }
            if self.exposed_area != 0.0 {
                p.push((
                    "exposed_area".to_string(),
                    format!(
                        "{}: give either `exposed_area` or `back`, not both",
                        self.exposed_area
                    ),
                ));
            }
        }
        p
    }

    /// The fraction of the back face exposed to air, `|exposed_area|`
    /// (see the module docs).
    pub fn exposed_fraction(&self) -> f64 {
        self.exposed_area.abs()
    }

    /// Thermal diffusivity κ = k / (ρ c), m²/s (Incropera eq. 2.22).
    pub fn diffusivity_m2_s(&self) -> f64 {
        self.conductivity_w_m_k / (self.density_kg_m3 * self.specific_heat_j_kg_k)
    }

    /// Thermal inertia P = √(k ρ c), J/(m²·K·s½) (Oke 1987, §2.1).
    pub fn thermal_inertia(&self) -> f64 {
        (self.conductivity_w_m_k * self.density_kg_m3 * self.specific_heat_j_kg_k).sqrt()
    }

    /// Spectral emissivity at `wavelength_um`, view zenith `angle_deg`:
    /// from the curve, or grey at `thermal_emissivity`.
    pub fn emissivity_at(&self, wavelength_um: f64, angle_deg: f64) -> f64 {
        match &self.emissivity_curve {
            Some(c) => c.at(wavelength_um, angle_deg),
            None => self.thermal_emissivity,
        }
    }
}

/// Where a material's values come from: one text for the whole entry, or one
/// per field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum MaterialSource {
    /// One citation for the entry.
    Text(String),
    /// A citation per field name.
    PerField(std::collections::BTreeMap<String, String>),
}

/// A set of materials with unique names, with where each came from.
#[derive(Debug, Clone, Default)]
pub struct MaterialDb {
    materials: Vec<Material>,
    sources: Vec<Option<MaterialSource>>,
    origins: Vec<PathBuf>,
    by_name: HashMap<String, usize>,
    /// Non-fatal notes from loading (e.g. a DIRSIG emissivity file that was
    /// not found, so the material is grey).
    pub warnings: Vec<String>,
}

impl MaterialDb {
    /// An empty database.
    pub fn new() -> Self {
        Self::default()
    }

    /// Load a database by extension: `.mat` → DIRSIG4 material file,
    /// anything else → irsig JSON.
    pub fn load(path: &Path) -> Result<Self> {
        if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("mat"))
        {
            dirsig::load_mat(path)
        } else {
            Self::load_json(path)
        }
    }

    /// Load an irsig JSON material database; the first problem is the error.
    pub fn load_json(path: &Path) -> Result<Self> {
        db::load_json_all(path).map_err(|mut v| v.swap_remove(0))
    }

    /// Add a material; errors if the name is taken or the material is
    /// invalid. Returns its index.
    pub fn insert(
        &mut self,
        material: Material,
        source: Option<MaterialSource>,
        origin: &Path,
    ) -> Result<usize> {
        if let Some((field, msg)) = material.problems().into_iter().next() {
            return Err(Error::parse(
                Location::file(origin).with_field(format!("{}.{field}", material.name)),
                msg,
            ));
        }
        if let Some(&i) = self.by_name.get(&material.name) {
            return Err(Error::parse(
                Location::file(origin).with_field(material.name.clone()),
                format!(
                    "material name `{}` is already defined in {}",
                    material.name,
                    self.origins[i].display()
                ),
            ));
        }
        let i = self.materials.len();
        self.by_name.insert(material.name.clone(), i);
        self.materials.push(material);
        self.sources.push(source);
        self.origins.push(origin.to_path_buf());
        Ok(i)
    }

    /// Add every material of `other` (names must stay unique).
    pub fn merge(&mut self, other: MaterialDb) -> Result<()> {
        self.warnings.extend(other.warnings);
        for ((m, s), o) in other
            .materials
            .into_iter()
            .zip(other.sources)
            .zip(other.origins)
        {
            self.insert(m, s, &o)?;
        }
        Ok(())
    }

    /// The material named `name`.
    pub fn get(&self, name: &str) -> Option<&Material> {
        self.index_of(name).map(|i| &self.materials[i])
    }

    /// Index of the material named `name`.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.by_name.get(name).copied()
    }

    /// The first material with numeric id `id`.
    pub fn by_id(&self, id: u32) -> Option<&Material> {
        self.materials.iter().find(|m| m.id == id)
    }

    /// All materials, in insertion order.
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// The source citation of material `index`, if given.
    pub fn source(&self, index: usize) -> Option<&MaterialSource> {
        self.sources.get(index).and_then(|s| s.as_ref())
    }

    /// The file material `index` was read from.
    pub fn origin(&self, index: usize) -> &Path {
        &self.origins[index]
    }

    /// Number of materials.
    pub fn len(&self) -> usize {
        self.materials.len()
    }

    /// Whether there are no materials.
    pub fn is_empty(&self) -> bool {
        self.materials.is_empty()
    }

    /// Names close to `name`, for "did you mean" hints: sharing a word
    /// (split at `_`, space, `-`) or containing one another, case-insensitive,
    /// best first, at most five.
    pub fn similar_names(&self, name: &str) -> Vec<&str> {
        let words = |s: &str| -> Vec<String> {
            s.to_lowercase()
                .split(['_', ' ', '-'])
                .filter(|w| !w.is_empty())
                .map(str::to_string)
                .collect()
        };
        let l = name.to_lowercase();
        let mine = words(name);
        let mut v: Vec<(usize, &str)> = self
            .materials
            .iter()
            .map(|m| {
                let nl = m.name.to_lowercase();
                let shared = words(&m.name).iter().filter(|w| mine.contains(w)).count();
                let sub = usize::from(nl.contains(&l) || l.contains(&nl));
                (2 * shared + sub, m.name.as_str())
            })
            .filter(|(s, _)| *s > 0)
            .collect();
        v.sort_by_key(|x| std::cmp::Reverse(x.0));
        v.into_iter().take(5).map(|(_, n)| n).collect()
    }
}
