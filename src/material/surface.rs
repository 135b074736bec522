//! The `surface_energy` block of a material: how a surface that evaporates
//! exchanges heat and water vapour with the air — as the material file
//! spells it, SI units in every name.
//!
//! ```json
//! "surface_energy": {
//!   "kind": "canopy",
//!   "canopy_height_m": 0.12,
//!   "leaf_area_index": 2.9,
//!   "min_stomatal_resistance_s_m": 100,
//!   "soil_moisture_m3_m3": 0.28
//! }
//! ```
//!
//! | kind        | surface resistance r_s                         | skin (canopy layer) |
//! |-------------|------------------------------------------------|---------------------|
//! | `canopy`    | Jarvis–Stewart stomatal resistance             | yes                 |
//! | `bare_soil` | van de Griend & Owe (1994) from soil moisture  | no                  |
//! | `water`     | 0 (open water)                                 | no                  |
//!
//! The physics and the sources of each default are in
//! [`crate::thermal::surface`] and `docs/physics/thermal.md`. This module
//! owns the file-level description and its checks (each problem names the
//! field as `surface_energy.<name>`); it knows nothing of the solver.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

pub use crate::thermal::latent::soil_water::SoilTexture;

/// How a dry surface (one without a `surface_energy` block) convects heat
/// to the air: the material's `"convection"` entry,
/// `{"model": "doe2", "roughness": "medium_rough"}` by default. The models
/// and their sources are in [`crate::thermal::convection`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConvectionSpec {
    /// The model (default `doe2`).
    #[serde(default)]
    pub model: ConvectionModel,
    /// The surface's roughness class (DOE-2's multiplier on the forced
    /// part; default `medium_rough`, concrete).
    #[serde(default)]
    pub roughness: SurfaceRoughness,
}

impl ConvectionSpec {
    /// McAdams' `5.7 + 3.8u` (DIRSIG parity).
    pub const MCADAMS: ConvectionSpec = ConvectionSpec {
        model: ConvectionModel::Mcadams,
        roughness: SurfaceRoughness::MediumRough,
    };

    /// Whether this is the default (omitted when a material is written).
    pub fn is_default(&self) -> bool {
        *self == ConvectionSpec::default()
    }
}

/// The convection model of a dry surface ([`ConvectionSpec`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ConvectionModel {
    /// DOE-2 (EnergyPlus Engineering Reference): Walton's natural
    /// convection by orientation and ΔT with the MoWiTT forced part,
    /// convection only.
    #[default]
    Doe2,
    /// McAdams' `h = 5.7 + 3.8u`, which includes some radiation: with it
    /// the radiative exchange is counted twice (kept for DIRSIG parity).
    Mcadams,
}

/// Roughness classes of the DOE-2 model (EnergyPlus Engineering
/// Reference, "Roughness multipliers", after Walton 1981), with an example
/// material each.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceRoughness {
    /// Stucco; R_f = 2.17.
    VeryRough,
    /// Brick; R_f = 1.67.
    Rough,
    /// Concrete; R_f = 1.52.
    #[default]
    MediumRough,
    /// Clear pine; R_f = 1.13.
    MediumSmooth,
    /// Smooth plaster; R_f = 1.11.
    Smooth,
    /// Glass; R_f = 1.00.
    VerySmooth,
}

impl SurfaceRoughness {
    /// DOE-2's roughness multiplier R_f (type docs).
    pub fn multiplier(self) -> f64 {
        match self {
            SurfaceRoughness::VeryRough => 2.17,
            SurfaceRoughness::Rough => 1.67,
            SurfaceRoughness::MediumRough => 1.52,
            SurfaceRoughness::MediumSmooth => 1.13,
            SurfaceRoughness::Smooth => 1.11,
            SurfaceRoughness::VerySmooth => 1.00,
        }
    }
}

/// Most dated entries of a [`Phenology`].
pub const MAX_PHENOLOGY: usize = 16;

/// One dated state of a growing canopy (`surface_energy.phenology[i]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PhenologyPoint {
    /// The date, `YYYY-MM-DD` (taken at 00:00 UTC).
    #[schemars(with = "String")]
    pub date: chrono::NaiveDate,
    /// Canopy height on that date, m (None: the block's `canopy_height_m`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub canopy_height_m: Option<f64>,
    /// Leaf area index on that date, m² m⁻² (None: the block's
    /// `leaf_area_index`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub leaf_area_index: Option<f64>,
}

/// A canopy that grows through the run (`surface_energy.phenology`): up
/// to [`MAX_PHENOLOGY`] dated heights and leaf area indices in increasing
/// date order, interpolated linearly in time and held at the first and
/// last entries outside them. Empty: the canopy is constant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Phenology {
    len: usize,
    points: [Option<PhenologyPoint>; MAX_PHENOLOGY],
}

impl Phenology {
    /// The dated entries, in the file's order.
    pub fn points(&self) -> impl Iterator<Item = &PhenologyPoint> {
        self.points[..self.len].iter().flatten()
    }

    /// Whether any entry gives a leaf area index.
    pub fn gives_leaf_area(&self) -> bool {
        self.points().any(|p| p.leaf_area_index.is_some())
    }

    /// Whether no entry is given (a constant canopy).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Height and LAI at `unix_s` (seconds since 1970-01-01 UTC), each
    /// interpolated linearly between the dates that give it, `default_*`
    /// where no entry gives it.
    pub fn at(&self, unix_s: f64, default_height_m: f64, default_lai: f64) -> (f64, f64) {
        let series = |get: fn(&PhenologyPoint) -> Option<f64>, default: f64| {
            let pts: Vec<(f64, f64)> = self
                .points()
                .filter_map(|p| {
                    let t = p.date.and_hms_opt(0, 0, 0)?.and_utc().timestamp() as f64;
                    Some((t, get(p)?))
                })
                .collect();
            match pts.as_slice() {
                [] => default,
                [(_, v)] => *v,
                _ => {
                    let j = pts.partition_point(|&(t, _)| t <= unix_s);
                    if j == 0 {
                        pts[0].1
                    } else if j == pts.len() {
                        pts[j - 1].1
                    } else {
                        let ((t0, v0), (t1, v1)) = (pts[j - 1], pts[j]);
                        v0 + (v1 - v0) * (unix_s - t0) / (t1 - t0)
                    }
                }
            }
        };
        (
            series(|p| p.canopy_height_m, default_height_m),
            series(|p| p.leaf_area_index, default_lai),
        )
    }
}

impl TryFrom<Vec<PhenologyPoint>> for Phenology {
    type Error = String;
    fn try_from(v: Vec<PhenologyPoint>) -> Result<Phenology, String> {
        if v.len() > MAX_PHENOLOGY {
            return Err(format!(
                "{} entries; at most {MAX_PHENOLOGY} dates are supported",
                v.len()
            ));
        }
        let mut p = Phenology {
            len: v.len(),
            ..Phenology::default()
        };
        for (slot, x) in p.points.iter_mut().zip(v) {
            *slot = Some(x);
        }
        Ok(p)
    }
}

impl Serialize for Phenology {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.points())
    }
}

impl<'de> Deserialize<'de> for Phenology {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Phenology, D::Error> {
        let v = Vec::<PhenologyPoint>::deserialize(d)?;
        Phenology::try_from(v).map_err(serde::de::Error::custom)
    }
}

/// How the roughness length for heat z_oh of an evaporating surface is
/// found (`surface_energy.heat_roughness`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum HeatRoughness {
    /// FAO-56: z_oh = z_om / 10 (kB⁻¹ = ln 10 = 2.3), whatever the cover.
    #[default]
    Fao56,
    /// Su et al. (2001): kB⁻¹ from the leaf area, canopy height, leaf
    /// width and wind at each record (full canopy 1–3, sparse canopy
    /// higher, bare soil 4–7; `crate::thermal::latent::aerodynamic`).
    Su2001,
}

/// How a canopy's leaves and the soil under them share the surface
/// energy balance (`surface_energy.canopy`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum CanopyModel {
    /// One big leaf: a canopy skin over the soil slab, the skin's
    /// temperature what the sensor sees (`crate::thermal::surface`).
    #[default]
    BigLeaf,
    /// Two sources: leaves and soil with their own temperatures, net
    /// radiation, sensible and latent heat in series resistances, the
    /// radiometric temperature composed by the cover (Norman, Kustas &
    /// Anderson 1995; `crate::thermal::two_source`).
    TwoSource,
}

fn is_big_leaf(c: &CanopyModel) -> bool {
    *c == CanopyModel::BigLeaf
}

/// What kind of evaporating surface (module table).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceKind {
    /// Vegetation: a transpiring canopy over the soil slab.
    Canopy,
    /// Bare soil evaporating from its top layer.
    BareSoil,
    /// Open water.
    Water,
}

/// The `surface_energy` block (module docs). Every field but `kind` has a
/// default; `None` fields take a default that depends on the kind.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SurfaceEnergySpec {
    /// The kind of surface.
    pub kind: SurfaceKind,
    /// Height of the canopy, m (canopy: required; gives the displacement
    /// height d = 2/3 h and roughness z_om = 0.123 h of FAO-56).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub canopy_height_m: Option<f64>,
    /// Roughness length for momentum z_om, m (default: canopy 0.123 h; bare
    /// soil 0.005; water 0.0002); z_oh = z_om / 10.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub roughness_length_m: Option<f64>,
    /// Height of the wind and air measurement above the ground, m (default:
    /// 2 m above the canopy top, or 2 m over soil and water).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measurement_height_m: Option<f64>,
    /// One-sided leaf area index, m² m⁻² (canopy).
    #[serde(default)]
    pub leaf_area_index: f64,
    /// Minimum stomatal resistance of a leaf, s m⁻¹ (canopy; default 100).
    #[serde(default = "default_rs_min")]
    pub min_stomatal_resistance_s_m: f64,
    /// Maximum (cuticular) resistance, s m⁻¹ (default 5000).
    #[serde(default = "default_rs_max")]
    pub max_stomatal_resistance_s_m: f64,
    /// Shortwave limit of the light response, W m⁻² (default: 30 for a
    /// canopy under 2 m, 100 above).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shortwave_limit_w_m2: Option<f64>,
    /// Sensitivity of the stomata to the vapour-pressure deficit, Pa⁻¹
    /// (default 0).
    #[serde(default)]
    pub vpd_sensitivity_per_pa: f64,
    /// Volumetric water content of the root zone (canopy) or the top layer
    /// (bare soil), m³ m⁻³.
    #[serde(default = "default_theta")]
    pub soil_moisture_m3_m3: f64,
    /// Volumetric water content at the wilting point, m³ m⁻³ (default 0.12).
    #[serde(default = "default_theta_wilt")]
    pub wilting_point_m3_m3: f64,
    /// Volumetric water content at field capacity, m³ m⁻³ (default 0.32).
    #[serde(default = "default_theta_fc")]
    pub field_capacity_m3_m3: f64,
    /// Heat capacity of the canopy layer, J m⁻² K⁻¹ (canopy; default
    /// 1200 × LAI + 2000).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub canopy_heat_capacity_j_m2_k: Option<f64>,
    /// Conductance between canopy and soil, W m⁻² K⁻¹ (canopy; default 10
    /// under 2 m, 20 above).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skin_conductance_w_m2_k: Option<f64>,
    /// How z_oh is found (default `fao56`, z_om/10; `su2001`: from the
    /// canopy's cover, [`HeatRoughness`]).
    #[serde(default, skip_serializing_if = "is_fao56")]
    pub heat_roughness: HeatRoughness,
    /// Characteristic leaf width, m (`su2001` only; default 0.04, the
    /// leaf dimension of the Noah-MP vegetation table).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub leaf_width_m: Option<f64>,
    /// A canopy that grows: dated heights and leaf area indices
    /// ([`Phenology`]; default none: constant). The canopy's roughness,
    /// displacement, stomatal conductance and kB⁻¹ follow it; its heat
    /// capacity and the big leaf's rain store keep the block's `leaf_area_index`.
    #[serde(default, skip_serializing_if = "Phenology::is_empty")]
    #[schemars(with = "Vec<PhenologyPoint>")]
    pub phenology: Phenology,
    /// Leaf area per metre of canopy height, m⁻¹ (canopy; default none:
    /// the LAI does not follow the height). Where the phenology gives no
    /// leaf area index, the canopy's LAI at each record is
    /// `min(a·h, leaf_area_index)`: the leaves grow with the height up to
    /// the block's LAI, the full canopy's. FAO-56 (Allen et al. 1998)
    /// ch. 2 (with eq. 5): LAI = 24 h for clipped grass; METRIC's short-crop roughness
    /// z_om = 0.018 LAI (Allen, Tasumi & Trezza 2007, J. Irrig. Drain. Eng.
    /// 133:380) with FAO-56's z_om = 0.123 h: a = 0.123/0.018 = 6.8 m⁻¹ for
    /// field crops.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub leaf_area_per_height_per_m: Option<f64>,
    /// Whether the canopy is a layer over the material's slab (default: true
    /// for a canopy). A tree crown modelled as a thin leaf slab with an
    /// exposed back sets `false`: the leaves are the slab.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skin: Option<bool>,
    /// How leaves and soil share the balance (default `big_leaf`;
    /// `two_source`: [`CanopyModel::TwoSource`], canopy only).
    #[serde(default, skip_serializing_if = "is_big_leaf")]
    pub canopy: CanopyModel,
    /// Clumping index Ω of the foliage, (0, 1] (`two_source`; default 1,
    /// leaves spread at random; row crops and shrubs 0.5–0.9).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clumping_index: Option<f64>,
    /// Volumetric water content at saturation (porosity), m³ m⁻³, for the
    /// soil surface's resistance to evaporation (`two_source`; default
    /// 0.451, loam, Clapp & Hornberger 1978).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub saturation_m3_m3: Option<f64>,
    /// Depth of the root zone whose water content rain wets and
    /// evaporation dries, m (> 0; default none: `soil_moisture_m3_m3` stays
    /// constant through the run). [`crate::thermal::latent::RootZone`]:
    /// ISBA's root-zone bucket, starting at `soil_moisture_m3_m3`, draining
    /// above `field_capacity_m3_m3`, full at `saturation_m3_m3`. Canopy
    /// (big leaf or two sources) and bare soil.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub root_zone_depth_m: Option<f64>,
    /// Depth of a water table below the surface, m (> `root_zone_depth_m`;
    /// needs a root zone; default none: no water rises from below). Water
    /// rises into the root zone by Gardner's (1958) steady capillary flux
    /// through the `soil_texture`, and the root zone drains only to its
    /// equilibrium with the table ([`crate::thermal::latent::soil_water`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub water_table_depth_m: Option<f64>,
    /// The soil's texture class of Clapp & Hornberger (1978) Table 2
    /// (default `loam`): its hydraulic conductivity and retention carry the
    /// water table's capillary rise, and its porosity is the default
    /// `saturation_m3_m3`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub soil_texture: Option<SoilTexture>,
}

fn is_fao56(h: &HeatRoughness) -> bool {
    *h == HeatRoughness::Fao56
}
fn default_rs_min() -> f64 {
    100.0
}
fn default_rs_max() -> f64 {
    5000.0
}
fn default_theta() -> f64 {
    0.28
}
fn default_theta_wilt() -> f64 {
    0.12
}
fn default_theta_fc() -> f64 {
    0.32
}

/// Height above which a canopy counts as high vegetation (trees), m.
pub const HIGH_VEGETATION_M: f64 = 2.0;

impl SurfaceEnergySpec {
    /// Roughness length for momentum, m (field docs for the defaults).
    pub fn roughness_m(&self) -> f64 {
        self.roughness_length_m.unwrap_or(match self.kind {
            SurfaceKind::Canopy => 0.123 * self.canopy_height_m.unwrap_or(0.0),
            SurfaceKind::BareSoil => 0.005,
            SurfaceKind::Water => 0.0002,
        })
    }

    /// Displacement height, m (2/3 of the canopy height; 0 otherwise).
    pub fn displacement_m(&self) -> f64 {
        match self.kind {
            SurfaceKind::Canopy => 2.0 / 3.0 * self.canopy_height_m.unwrap_or(0.0),
            _ => 0.0,
        }
    }

    /// Measurement height above the ground, m.
    pub fn measurement_m(&self) -> f64 {
        self.measurement_height_m
            .unwrap_or(self.canopy_height_m.unwrap_or(0.0) + 2.0)
    }

    /// Whether the canopy is a skin layer over the slab (field docs).
    pub fn has_skin(&self) -> bool {
        self.kind == SurfaceKind::Canopy && self.skin.unwrap_or(true)
    }

    /// Whether the canopy is high vegetation (trees).
    pub fn is_high(&self) -> bool {
        self.canopy_height_m.unwrap_or(0.0) > HIGH_VEGETATION_M
    }

    /// Shortwave limit of the light response, W m⁻² (Noilhan & Planton 1989:
    /// 30 crops, 100 forest).
    pub fn shortwave_limit(&self) -> f64 {
        self.shortwave_limit_w_m2
            .unwrap_or(if self.is_high() { 100.0 } else { 30.0 })
    }

    /// Canopy heat capacity, J m⁻² K⁻¹: leaves hold about 0.3 kg of water
    /// per m² of leaf (≈ 1200 J m⁻² K⁻¹ per unit LAI with c_w = 4180), plus
    /// stems and the air and litter within the canopy (2000).
    pub fn canopy_capacity(&self) -> f64 {
        self.canopy_heat_capacity_j_m2_k
            .unwrap_or(1200.0 * self.leaf_area_index + 2000.0)
    }

    /// Characteristic leaf width, m (field docs).
    pub fn leaf_width(&self) -> f64 {
        self.leaf_width_m.unwrap_or(0.04)
    }

    /// Canopy–soil conductance, W m⁻² K⁻¹ (ECMWF IFS Cy47r3 Part IV Table
    /// 8.1: Λ = 10 low vegetation, 20 high vegetation).
    pub fn skin_conductance(&self) -> f64 {
        self.skin_conductance_w_m2_k
            .unwrap_or(if self.is_high() { 20.0 } else { 10.0 })
    }

    /// The clumping index Ω (default 1).
    pub fn clumping(&self) -> f64 {
        self.clumping_index.unwrap_or(1.0)
    }

    /// The soil's water content at saturation, m³ m⁻³ (default: the
    /// texture's porosity, 0.451 for the default loam).
    pub fn saturation(&self) -> f64 {
        self.saturation_m3_m3
            .unwrap_or(self.texture().hydraulics().saturation_m3_m3)
    }

    /// The soil's texture class (default loam).
    pub fn texture(&self) -> SoilTexture {
        self.soil_texture.unwrap_or_default()
    }

    /// Problems as `(field, message)`, the field relative to the block
    /// (`canopy_height_m`); empty when valid.
    pub fn problems(&self) -> Vec<(&'static str, String)> {
        let mut p = Vec::new();
        fn check(
            p: &mut Vec<(&'static str, String)>,
            field: &'static str,
            v: f64,
            ok: bool,
            expected: &str,
        ) {
            if !(v.is_finite() && ok) {
                p.push((field, format!("{v}: expected {expected}")));
            }
        }
        if self.kind == SurfaceKind::Canopy {
            match self.canopy_height_m {
                Some(h) => check(&mut p, "canopy_height_m", h, h > 0.0, "a height > 0 m"),
                None => p.push((
                    "canopy_height_m",
                    "missing: a canopy needs its height (m)".to_string(),
                )),
            }
        } else if let Some(h) = self.canopy_height_m {
            check(&mut p, "canopy_height_m", h, h >= 0.0, "a height ≥ 0 m");
        }
        if let Some(z0) = self.roughness_length_m {
            check(&mut p, "roughness_length_m", z0, z0 > 0.0, "a length > 0 m");
        }
        if let Some(z) = self.measurement_height_m {
            check(&mut p, "measurement_height_m", z, z > 0.0, "a height > 0 m");
        }
        let (z, d, z0) = (
            self.measurement_m(),
            self.displacement_m(),
            self.roughness_m(),
        );
        if z.is_finite() && z0.is_finite() && z0 > 0.0 && z0 >= z - d {
            p.push((
                "roughness_length_m",
                format!(
                    "{z0} m is not below the measurement height above the displacement height \
                     ({} m); the log wind profile needs z₀ < z − d",
                    z - d
                ),
            ));
        }
        let lai = self.leaf_area_index;
        check(
            &mut p,
            "leaf_area_index",
            lai,
            (0.0..=15.0).contains(&lai),
            "0..=15 m²/m²",
        );
        if self.kind == SurfaceKind::Canopy && lai == 0.0 {
            p.push((
                "leaf_area_index",
                "0: a canopy needs leaves (use kind \"bare_soil\" for soil)".to_string(),
            ));
        }
        let (rmin, rmax) = (
            self.min_stomatal_resistance_s_m,
            self.max_stomatal_resistance_s_m,
        );
        check(
            &mut p,
            "min_stomatal_resistance_s_m",
            rmin,
            rmin >= 0.0,
            "a resistance ≥ 0 s/m",
        );
        check(
            &mut p,
            "max_stomatal_resistance_s_m",
            rmax,
            rmax > rmin,
            "a resistance above min_stomatal_resistance_s_m",
        );
        if let Some(s) = self.shortwave_limit_w_m2 {
            check(&mut p, "shortwave_limit_w_m2", s, s > 0.0, "> 0 W/m²");
        }
        let g = self.vpd_sensitivity_per_pa;
        check(&mut p, "vpd_sensitivity_per_pa", g, g >= 0.0, "≥ 0 per Pa");
        for (field, v) in [
            ("soil_moisture_m3_m3", self.soil_moisture_m3_m3),
            ("wilting_point_m3_m3", self.wilting_point_m3_m3),
            ("field_capacity_m3_m3", self.field_capacity_m3_m3),
        ] {
            check(
                &mut p,
                field,
                v,
                (0.0..=1.0).contains(&v),
                "a fraction in 0..=1",
            );
        }
        check(
            &mut p,
            "field_capacity_m3_m3",
            self.field_capacity_m3_m3,
            self.field_capacity_m3_m3 > self.wilting_point_m3_m3,
            "above wilting_point_m3_m3",
        );
        if let Some(c) = self.canopy_heat_capacity_j_m2_k {
            check(
                &mut p,
                "canopy_heat_capacity_j_m2_k",
                c,
                c > 0.0,
                "> 0 J/(m²·K)",
            );
        }
        if !self.phenology.is_empty() && self.kind != SurfaceKind::Canopy {
            p.push((
                "phenology",
                "only a canopy grows (kind \"canopy\")".to_string(),
            ));
        }
        let mut last: Option<chrono::NaiveDate> = None;
        for x in self.phenology.points() {
            if let Some(prev) = last
                && x.date <= prev
            {
                p.push((
                    "phenology",
                    format!("{} after {prev}: the dates must increase", x.date),
                ));
            }
            last = Some(x.date);
            if let Some(h) = x.canopy_height_m {
                check(
                    &mut p,
                    "phenology.canopy_height_m",
                    h,
                    h > 0.0,
                    "a height > 0 m",
                );
            }
            if let Some(l) = x.leaf_area_index {
                check(
                    &mut p,
                    "phenology.leaf_area_index",
                    l,
                    l > 0.0 && l <= 15.0,
                    "a leaf area index in (0, 15] m²/m² (a canopy needs leaves)",
                );
            }
        }
        if let Some(w) = self.leaf_width_m {
            check(&mut p, "leaf_width_m", w, w > 0.0, "a width > 0 m");
        }
        if let Some(a) = self.leaf_area_per_height_per_m {
            check(
                &mut p,
                "leaf_area_per_height_per_m",
                a,
                a > 0.0 && a.is_finite(),
                "a leaf area per metre of height > 0 m⁻¹",
            );
            if self.kind != SurfaceKind::Canopy {
                p.push((
                    "leaf_area_per_height_per_m",
                    "only a canopy has leaves (kind \"canopy\")".to_string(),
                ));
            }
        }
        if self.heat_roughness == HeatRoughness::Su2001 && self.kind == SurfaceKind::Water {
            p.push((
                "heat_roughness",
                "su2001 is for vegetation and soil; open water keeps fao56".to_string(),
            ));
        }
        if let Some(c) = self.skin_conductance_w_m2_k {
            check(
                &mut p,
                "skin_conductance_w_m2_k",
                c,
                c > 0.0,
                "> 0 W/(m²·K)",
            );
        }
        if self.canopy == CanopyModel::TwoSource && self.kind != SurfaceKind::Canopy {
            p.push((
                "canopy",
                "two_source needs leaves (kind \"canopy\")".to_string(),
            ));
        }
        if let Some(c) = self.clumping_index {
            check(
                &mut p,
                "clumping_index",
                c,
                c > 0.0 && c <= 1.0,
                "a clumping index in (0, 1]",
            );
        }
        if let Some(d) = self.root_zone_depth_m {
            check(&mut p, "root_zone_depth_m", d, d > 0.0, "a depth > 0 m");
            if self.kind == SurfaceKind::Water {
                p.push((
                    "root_zone_depth_m",
                    "water has no soil (kind \"canopy\" or \"bare_soil\")".to_string(),
                ));
            }
            let sat = self.saturation();
            check(
                &mut p,
                "soil_moisture_m3_m3",
                self.soil_moisture_m3_m3,
                self.soil_moisture_m3_m3 <= sat && self.field_capacity_m3_m3 <= sat,
                "a root zone's water content and field capacity at or below saturation_m3_m3",
            );
        }
        if let Some(z) = self.water_table_depth_m {
            match self.root_zone_depth_m {
                None => p.push((
                    "water_table_depth_m",
                    "a water table feeds a root zone: set root_zone_depth_m".to_string(),
                )),
                Some(d) => check(
                    &mut p,
                    "water_table_depth_m",
                    z,
                    z > d,
                    &format!("a depth below the root zone (> root_zone_depth_m = {d} m)"),
                ),
            }
        }
        if let Some(t) = self.saturation_m3_m3 {
            check(
                &mut p,
                "saturation_m3_m3",
                t,
                t > 0.0 && t <= 1.0 && t >= self.soil_moisture_m3_m3,
                "a water content in (0, 1] at or above soil_moisture_m3_m3",
            );
        }
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> SurfaceEnergySpec {
        serde_json::from_str(s).unwrap()
    }

    #[test]
    fn defaults_follow_the_kind() {
        let g = parse(r#"{"kind": "canopy", "canopy_height_m": 0.12, "leaf_area_index": 2.9}"#);
        assert!(g.problems().is_empty(), "{:?}", g.problems());
        assert!((g.roughness_m() - 0.01476).abs() < 1e-9);
        assert!((g.measurement_m() - 2.12).abs() < 1e-12);
        assert_eq!(g.skin_conductance(), 10.0);
        let w = parse(r#"{"kind": "water"}"#);
        assert!(w.problems().is_empty());
        assert_eq!(w.roughness_m(), 0.0002);
    }

    #[test]
    fn bad_two_source_values_name_their_field() {
        let fields = |s: &str| -> Vec<&'static str> {
            parse(s).problems().into_iter().map(|(f, _)| f).collect()
        };
        let base = r#""kind": "canopy", "canopy_height_m": 1, "leaf_area_index": 3, "canopy": "two_source""#;
        assert!(fields(&format!("{{{base}}}")).is_empty());
        for (extra, field) in [
            (r#""clumping_index": 0"#, "clumping_index"),
            (r#""clumping_index": 1.2"#, "clumping_index"),
            (r#""clumping_index": -0.5"#, "clumping_index"),
            (r#""saturation_m3_m3": 0.1"#, "saturation_m3_m3"),
        ] {
            let f = fields(&format!("{{{base}, {extra}}}"));
            assert!(f.contains(&field), "{extra}: {f:?}");
        }
        assert!(
            fields(r#"{"kind": "bare_soil", "canopy": "two_source"}"#).contains(&"canopy"),
            "two sources need leaves"
        );
    }

    #[test]
    fn bad_root_zones_name_their_field() {
        let fields = |s: &str| -> Vec<&'static str> {
            parse(s).problems().into_iter().map(|(f, _)| f).collect()
        };
        let base = r#""kind": "canopy", "canopy_height_m": 1, "leaf_area_index": 3"#;
        assert!(fields(&format!("{{{base}, \"root_zone_depth_m\": 1}}")).is_empty());
        assert!(fields(r#"{"kind": "bare_soil", "root_zone_depth_m": 0.1}"#).is_empty());
        let two = r#""canopy": "two_source", "root_zone_depth_m": 1, "water_table_depth_m": 1.5"#;
        assert!(fields(&format!("{{{base}, {two}}}")).is_empty());
        let silty = parse(&format!("{{{base}, \"soil_texture\": \"silty_clay\"}}"));
        assert_eq!(silty.saturation(), 0.492);
        for (extra, field) in [
            (r#""root_zone_depth_m": 0"#, "root_zone_depth_m"),
            (r#""root_zone_depth_m": -1"#, "root_zone_depth_m"),
            (r#""water_table_depth_m": 2"#, "water_table_depth_m"),
            (
                r#""root_zone_depth_m": 1, "water_table_depth_m": 1"#,
                "water_table_depth_m",
            ),
            (
                r#""root_zone_depth_m": 1, "water_table_depth_m": 0.5"#,
                "water_table_depth_m",
            ),
            (
                r#""root_zone_depth_m": 1, "water_table_depth_m": -2"#,
                "water_table_depth_m",
            ),
            (
                r#""root_zone_depth_m": 1, "saturation_m3_m3": 0.3"#,
                "soil_moisture_m3_m3",
            ),
        ] {
            let f = fields(&format!("{{{base}, {extra}}}"));
            assert!(f.contains(&field), "{extra}: {f:?}");
        }
        assert!(
            fields(r#"{"kind": "water", "root_zone_depth_m": 1}"#).contains(&"root_zone_depth_m"),
            "water has no soil"
        );
    }

    #[test]
    fn bad_values_name_their_field() {
        let fields = |s: &str| -> Vec<&'static str> {
            parse(s).problems().into_iter().map(|(f, _)| f).collect()
        };
        assert!(fields(r#"{"kind": "canopy", "leaf_area_index": 2}"#).contains(&"canopy_height_m"));
        assert!(
            fields(r#"{"kind": "canopy", "canopy_height_m": 1, "leaf_area_index": -1}"#)
                .contains(&"leaf_area_index")
        );
        assert!(
            fields(r#"{"kind": "water", "min_stomatal_resistance_s_m": -5}"#)
                .contains(&"min_stomatal_resistance_s_m")
        );
        assert!(
            fields(r#"{"kind": "bare_soil", "roughness_length_m": 3, "measurement_height_m": 2}"#)
                .contains(&"roughness_length_m")
        );
        assert!(
            serde_json::from_str::<SurfaceEnergySpec>(r#"{"kind": "lava"}"#).is_err(),
            "unknown kind"
        );
    }

    /// A growing canopy: dated heights and LAI interpolate linearly in
    /// time, hold outside the dates, and round-trip through JSON; an entry
    /// may give one of the two (the other keeps the block's value).
    #[test]
    fn phenology_interpolates_between_its_dates() {
        let g = parse(
            r#"{"kind": "canopy", "canopy_height_m": 1.0, "leaf_area_index": 3,
                "heat_roughness": "su2001",
                "phenology": [
                  {"date": "2011-07-05", "canopy_height_m": 0.15, "leaf_area_index": 1},
                  {"date": "2011-07-26", "canopy_height_m": 0.45},
                  {"date": "2011-08-19", "canopy_height_m": 0.975, "leaf_area_index": 5}
                ]}"#,
        );
        assert!(g.problems().is_empty(), "{:?}", g.problems());
        let day = |d: &str| {
            chrono::NaiveDate::parse_from_str(d, "%Y-%m-%d")
                .unwrap()
                .and_hms_opt(0, 0, 0)
                .unwrap()
                .and_utc()
                .timestamp() as f64
        };
        let ph = g.phenology;
        assert_eq!(ph.at(day("2011-07-01"), 1.0, 3.0), (0.15, 1.0));
        assert_eq!(ph.at(day("2011-09-01"), 1.0, 3.0), (0.975, 5.0));
        let (h, lai) = ph.at(day("2011-07-26"), 1.0, 3.0);
        assert!((h - 0.45).abs() < 1e-12, "{h}");
        // LAI from its own dates only: 1 on 5 Jul → 5 on 19 Aug (45 days).
        assert!((lai - (1.0 + 4.0 * 21.0 / 45.0)).abs() < 1e-12, "{lai}");
        // Half a day after 26 Jul: h moves by half a day's share of 0.525 m / 24 d.
        let (h, _) = ph.at(day("2011-07-26") + 43_200.0, 1.0, 3.0);
        assert!((h - (0.45 + 0.525 * 0.5 / 24.0)).abs() < 1e-12, "{h}");
        let back: SurfaceEnergySpec =
            serde_json::from_str(&serde_json::to_string(&g).unwrap()).unwrap();
        assert_eq!(back, g);
        // No phenology: the defaults.
        assert_eq!(Phenology::default().at(0.0, 0.7, 2.0), (0.7, 2.0));
    }

    #[test]
    fn bad_phenology_and_leaf_width_name_their_field() {
        let fields = |s: &str| -> Vec<&'static str> {
            parse(s).problems().into_iter().map(|(f, _)| f).collect()
        };
        let base = r#""kind": "canopy", "canopy_height_m": 1, "leaf_area_index": 3"#;
        for a in ["0", "-6.8"] {
            assert_eq!(
                fields(&format!(r#"{{{base}, "leaf_area_per_height_per_m": {a}}}"#)),
                ["leaf_area_per_height_per_m"]
            );
        }
        assert!(fields(&format!(r#"{{{base}, "leaf_area_per_height_per_m": 6.8}}"#)).is_empty());
        assert_eq!(
            fields(r#"{"kind": "bare_soil", "leaf_area_per_height_per_m": 6.8}"#),
            ["leaf_area_per_height_per_m"]
        );
        assert!(
            fields(&format!(
                r#"{{{base}, "phenology": [{{"date": "2011-08-01"}}, {{"date": "2011-07-01"}}]}}"#
            ))
            .contains(&"phenology")
        );
        assert!(
            fields(&format!(
                r#"{{{base}, "phenology": [{{"date": "2011-08-01", "leaf_area_index": -1}}]}}"#
            ))
            .contains(&"phenology.leaf_area_index")
        );
        assert!(
            fields(&format!(
                r#"{{{base}, "phenology": [{{"date": "2011-08-01", "canopy_height_m": 0}}]}}"#
            ))
            .contains(&"phenology.canopy_height_m")
        );
        assert!(
            fields(r#"{"kind": "bare_soil", "phenology": [{"date": "2011-08-01"}]}"#)
                .contains(&"phenology")
        );
        assert!(fields(&format!(r#"{{{base}, "leaf_width_m": 0}}"#)).contains(&"leaf_width_m"));
        assert!(
            fields(r#"{"kind": "water", "heat_roughness": "su2001"}"#).contains(&"heat_roughness")
        );
        // A date that is not one, or too many dates: a parse error.
        assert!(
            serde_json::from_str::<SurfaceEnergySpec>(&format!(
                r#"{{{base}, "phenology": [{{"date": "2011-13-01"}}]}}"#
            ))
            .is_err()
        );
        let many: Vec<String> = (1..=17)
            .map(|d| format!(r#"{{"date": "2011-07-{d:02}"}}"#))
            .collect();
        let e = serde_json::from_str::<SurfaceEnergySpec>(&format!(
            r#"{{{base}, "phenology": [{}]}}"#,
            many.join(",")
        ))
        .unwrap_err()
        .to_string();
        assert!(e.contains("at most 16"), "{e}");
    }
}
