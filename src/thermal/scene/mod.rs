//! The scene-wide thermal solve: every facet's surface temperature through
//! the weather history, from its ray-traced inputs and the 1-D slab model
//! ([`crate::thermal::solve`]), with the facets coupled through their
//! backgrounds.
//!
//! # What it owns, takes and gives
//! - Takes [`SceneInputs`] (per facet: sunlit fraction and cos-incidence
//!   histories, shape factors, the facets it sees — plain borrowed arrays),
//!   a [`FacetThermal`] per facet (solved with a property set, or held at a
//!   fixed temperature), the property sets, the weather [`Forcing`] (one
//!   record per history step) and the records of the image times.
//! - Gives [`SceneTemperatures`]: every facet's surface temperature at the
//!   image records, with [`PassStats`] per pass.
//! - It does not know how the inputs were traced (rays, tracers, the
//!   exposure module), scenes, files or the render: the pipeline that
//!   traces them and calls [`solve_facet_temperatures`] is
//!   [`crate::render::scene_thermal`].
//!
//! # Passes
//! Pass 1 takes the air temperature as every facet's background
//! temperature. Pass `p ≥ 2` takes, for every facet and record, the
//! radiative mean of what its blocked hemisphere rays hit:
//! `T_bg⁴ = (Σ wᵢ Tᵢ⁴ + g T_air⁴) / (Σ wᵢ + g)` with the neighbours'
//! surface temperatures `Tᵢ` from pass `p − 1` and `g` the ground beyond
//! the scene at air temperature. Fixed-temperature facets (and temperatures
//! read from a file) bypass the solver; they still act as neighbours.
//!
//! # Methods ([`ThermalMethod`])
//! - [`ThermalMethod::Linearized`] (default, [`linearized`]): a few
//!   nonlinear reference solves per property set and a Green's-matrix
//!   product per facet.
//! - [`ThermalMethod::PerClass`] ([`per_class`]): one nonlinear solve per
//!   class of facets with equal quantised inputs ([`Dedup`]).
//!
//! Work runs in parallel (rayon); the result is the same for any thread
//! count.

mod inputs;
pub mod linearized;
pub mod per_class;

use std::time::Duration;

pub use inputs::{FacetReflected, NO_SLOT, SceneInputs, SolarArrays, SolarSource};
pub use linearized::LinearizedParams;
pub use per_class::Dedup;

use rayon::prelude::*;

pub use crate::thermal::wind::FacetWind;
use crate::thermal::{self, Exchange, Forcing, Passes, SlabProperties, SolveOptions, convection};
use crate::{Error, Result};

/// How a facet's temperature is obtained.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FacetThermal {
    /// Solved by the slab model with the property set of this index.
    Solve(u32),
    /// Held at this temperature, K, at every record (fixed-temperature
    /// facets, temperatures from a file).
    Fixed(f32),
}

/// How the scene-wide solve gets each facet's temperatures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ThermalMethod {
    /// A few nonlinear reference solves per property set and a
    /// Green's-matrix product per facet (default; fast).
    Linearized(LinearizedParams),
    /// One nonlinear slab solve per dedup class
    /// ([`ThermalParams::dedup`], [`ThermalParams::options`]).
    PerClass,
}

impl Default for ThermalMethod {
    fn default() -> Self {
        ThermalMethod::Linearized(LinearizedParams::default())
    }
}

/// Parameters of the scene-wide solve.
#[derive(Debug, Clone, PartialEq)]
pub struct ThermalParams {
    /// Passes (≥ 1; default 2): pass `p ≥ 2` uses pass `p−1`'s neighbour
    /// temperatures as background.
    pub passes: u32,
    /// Options of the slab solver of [`ThermalMethod::PerClass`] (grid,
    /// sub-steps, spin-up; default [`ThermalParams::scene_options`]).
    pub options: SolveOptions,
    /// Dedup quanta of [`ThermalMethod::PerClass`]; `None` solves every
    /// facet on its own.
    pub dedup: Option<Dedup>,
    /// The method (default [`ThermalMethod::Linearized`]).
    pub method: ThermalMethod,
}

impl Default for ThermalParams {
    fn default() -> Self {
        ThermalParams {
            passes: 2,
            options: ThermalParams::scene_options(),
            dedup: Some(Dedup::default()),
            method: ThermalMethod::default(),
        }
    }
}

impl ThermalParams {
    /// The per-class (dedup) solve with these quanta and slab options.
    pub fn per_class(dedup: Option<Dedup>, options: SolveOptions) -> Self {
        ThermalParams {
            options,
            dedup,
            method: ThermalMethod::PerClass,
            ..ThermalParams::default()
        }
    }

    /// The reference of the accuracy figures: every facet's exact inputs
    /// to fine quanta ([`Dedup::fine`]), [`SolveOptions::default`].
    pub fn fine_reference() -> Self {
        ThermalParams::per_class(Some(Dedup::fine()), SolveOptions::default())
    }

    /// The slab options of per-class scene solves: [`SolveOptions::fast`] (8 cells,
    /// one sub-step per 15-min record) with one spin-up day. On the bundled
    /// town this is about twice as fast as [`SolveOptions::default`] (12
    /// cells, up to 3 spin-up days) and within RMS 0.17 K, max 0.27 K of
    /// it at the image time; [`SolveOptions::fast`] alone (no spin-up) is
    /// twice as fast again but within RMS 0.35 K, max 0.57 K.
    pub fn scene_options() -> SolveOptions {
        SolveOptions {
            spinup: thermal::Spinup {
                max_cycles: 1,
                ..thermal::Spinup::default()
            },
            ..SolveOptions::fast()
        }
    }
}

/// Work and convergence of one pass.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PassStats {
    /// Facets solved (not fixed).
    pub solved_facets: usize,
    /// Distinct classes actually solved.
    pub classes: usize,
    /// Facets that kept the previous pass's temperature (seeing only sky, or
    /// within [`Dedup::reuse_tolerance_w_m2`] in pass 2).
    pub reused_facets: usize,
    /// Time building keys and background histories.
    pub setup: Duration,
    /// Time in the slab solver.
    pub solve: Duration,
    /// Largest spin-up change over the classes (last spin-up cycle), K.
    pub max_spinup_change_k: f64,
    /// Largest |T − T_previous pass| over facets and image records, K
    /// (`None` for pass 1): the convergence of the background iteration.
    pub max_change_from_previous_pass_k: Option<f64>,
}

/// Surface temperatures of every facet at the image records.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneTemperatures {
    /// Record indices of the image times.
    pub image_records: Vec<usize>,
    /// Surface temperature, K, `[image][facet]`.
    pub surface_temperature_k: Vec<Vec<f32>>,
    /// One entry per pass.
    pub passes: Vec<PassStats>,
    /// How each facet's image-time temperature responds to a change of its
    /// sunlit history at one point of it ([`PointResponse`]; the
    /// linearised method only, `None` for the per-class one).
    pub point_response: Option<PointResponse>,
    /// The property sets (indices into the caller's `props`) whose
    /// exchange's reference passes stopped on their cap without settling
    /// ([`crate::thermal::surface::Passes`]; the least settled twin of
    /// each), in index order; empty when every one settled.
    pub unsettled_exchanges: Vec<(usize, Passes)>,
}

/// The response of a facet's front temperature at the image records to a
/// change of `s·max(cos θ, 0)` (sunlit fraction × cosine of incidence) at
/// each record, from the Green's function of the facet's reference in the
/// linearised solve times the property set's `∂S/∂(s cos θ)`
/// ([`crate::thermal::SourceModel::front_per_sunlit_cos`]): a point of the
/// facet whose own sunlit history differs from the facet's by `Δ(s cos θ)`
/// is, to first order, `Σ_k row[k]·Δ(s cos θ)_k` warmer (K) than the
/// facet. This is what per-hit temperatures use
/// (`crate::render::per_hit`): one dot product per hit.
#[derive(Debug, Clone, PartialEq)]
pub struct PointResponse {
    /// Records of the history (the length of a row).
    pub records: usize,
    /// Image records (rows per block).
    pub images: usize,
    /// Per facet: its block of rows (`u32::MAX`: a fixed facet, no
    /// response).
    pub block_of: Vec<u32>,
    /// `[block][image][k]`, K per unit of `s·max(cos θ, 0)` at record `k`.
    pub sun_rows: Vec<f32>,
    /// `[block][image][k]`: the image rows themselves, `∂T(image)/∂S_k`,
    /// K per W m⁻² (for the second order).
    pub rows: Vec<f32>,
    /// `[block][k·R + t]`: the reference's whole Green's matrix of the
    /// front, `∂T(t)/∂S_k`, K per W m⁻² (for the second order).
    pub green: Vec<f32>,
    /// `[block][t]`: the reference's front temperature history, K.
    pub reference_k: Vec<f32>,
    /// `[block][k]`: `∂S_k/∂(s cos θ)`, W m⁻².
    pub sun: Vec<f32>,
    /// `[block]`: `εσ` of the front, W m⁻² K⁻⁴.
    pub radiative: Vec<f32>,
    /// `[block][t]`: the reference's vapour conductance of the front's
    /// latent loss, W m⁻² Pa⁻¹ (0 for a dry block; empty when no block
    /// evaporates): the second order's latent curvature
    /// ([`crate::thermal::linear::latent_curvature`]).
    pub latent: Vec<f64>,
    /// `[block][k]`: `∂S_k/∂F` of the property set, W m⁻² (for a point's
    /// own shape factor).
    pub shape: Vec<f32>,
    /// `[block][image][k]`: the front's response to the back sources at
    /// each image record, `∂T(image)/∂B_k`, K per W m⁻² (zeros for a block
    /// without an exposed back; empty when no block has one): for a
    /// point's own back sky view.
    pub back_rows: Vec<f32>,
    /// `[block][k]`: `∂B_k/∂F_b` of the property set, W m⁻² (zeros for a
    /// block without an exposed back; empty when no block has one).
    pub back_shape: Vec<f32>,
    /// `[block]`: `a·εσ` of the exposed back, W m⁻² K⁻⁴ (0 without one;
    /// empty when no block has one).
    pub back_radiative: Vec<f32>,
    /// `[k]`: `T_air⁴`, K⁴.
    pub air4: Vec<f32>,
    /// The `T⁴` histories (K⁴, `[slot][k]`) of the facets others see, as
    /// the last pass's backgrounds used them (empty with one pass: the
    /// air is every background); shared, not copied, by clones.
    pub background4: std::sync::Arc<Vec<f32>>,
    /// Per facet: its slot in `background4` (`u32::MAX`: none).
    pub slot_of: std::sync::Arc<Vec<u32>>,
}

impl PointResponse {
    /// Row of `facet` at image `image` (`None` for a fixed facet).
    pub fn row(&self, facet: usize, image: usize) -> Option<&[f32]> {
        let b = *self.block_of.get(facet)?;
        if b == u32::MAX || image >= self.images {
            return None;
        }
        let o = (b as usize * self.images + image) * self.records;
        Some(&self.sun_rows[o..o + self.records])
    }
}

impl SceneTemperatures {
    /// Total time in the solver and its setup over all passes.
    pub fn total_time(&self) -> Duration {
        self.passes.iter().map(|p| p.setup + p.solve).sum()
    }
}

/// Solves every facet's surface temperature over the history of `forcing`
/// (one record per history step of `inputs`) and returns it at the
/// `image_records`.
///
/// `inputs` is a [`SceneInputs`] or anything that converts into one (in
/// irsig, `&Exposure`: see [`crate::render::scene_thermal`]). `kinds` has
/// one entry per facet; `props` holds the property sets that
/// [`FacetThermal::Solve`] indexes.
///
/// # Errors
/// [`Error::Invalid`] for mismatched lengths, a property index out of range,
/// an image record out of range, zero passes; the slab solver's errors,
/// naming the facet.
pub fn solve_facet_temperatures<'a>(
    inputs: impl Into<SceneInputs<'a>>,
    kinds: &[FacetThermal],
    props: &[SlabProperties],
    forcing: &Forcing,
    image_records: &[usize],
    params: &ThermalParams,
) -> Result<SceneTemperatures> {
    let inputs = &inputs.into();
    validate(inputs, kinds, props, forcing, image_records, params)?;
    // Each property set's exchange with the air (shared by its facets), per
    // class of facet wind.
    let WindSets {
        kinds,
        props,
        origin,
        wind_class,
        orientation,
    } = WindSets::new(inputs, kinds, props);
    let (kinds, props) = (&kinds[..], &props[..]);
    let mut scaled: Vec<(u32, Forcing)> = Vec::new();
    for &q in &wind_class {
        if q != WIND_NONE && !scaled.iter().any(|(c, _)| *c == q) {
            scaled.push((q, forcing_with_wind_class(forcing, q)));
        }
    }
    let exchanges = props
        .par_iter()
        .zip(&wind_class)
        .zip(&orientation)
        .enumerate()
        .map(|(i, ((p, &q), &o))| {
            let f = match scaled.iter().find(|(c, _)| *c == q) {
                Some((_, f)) => f,
                None => forcing,
            };
            Exchange::facing(p, f, convection::class_cos_tilt(o))
                .map_err(|e| Error::Other(format!("thermal exchange of property set {i}: {e}")))
        })
        .collect::<Result<Vec<_>>>()?;
    // Twins of one property set differ by wind and orientation class.
    let set_class: Vec<u32> = wind_class
        .iter()
        .zip(&orientation)
        .map(|(&q, &o)| {
            q.wrapping_mul(convection::ORIENTATION_CLASSES)
                .wrapping_add(o)
        })
        .collect();
    let wind_class = set_class;
    // The caller's property sets whose reference passes stopped on their
    // cap (the least settled twin of each), for a warning.
    let mut unsettled: Vec<(usize, Passes)> = Vec::new();
    for (e, &o) in exchanges.iter().zip(&origin) {
        if let Some(p) = e.passes.filter(|p| !p.settled) {
            note_unsettled(&mut unsettled, o as usize, p);
        }
    }
    let mut out = match &params.method {
        ThermalMethod::Linearized(lp) => linearized::solve(
            inputs,
            kinds,
            PropertySets {
                props,
                exchanges: &exchanges,
                wind_class: &wind_class,
            },
            forcing,
            image_records,
            params.passes,
            lp,
        ),
        ThermalMethod::PerClass => per_class::solve(
            inputs,
            kinds,
            props,
            &exchanges,
            forcing,
            image_records,
            params,
        ),
    }?;
    out.unsettled_exchanges = unsettled;
    Ok(out)
}

/// Adds property set `set`'s unsettled `passes` to `list` (kept in set
/// order), keeping the larger residual where the set is there already (a
/// twin, or another image window's solve).
pub fn note_unsettled(list: &mut Vec<(usize, Passes)>, set: usize, passes: Passes) {
    match list.binary_search_by_key(&set, |(s, _)| *s) {
        Ok(i) if list[i].1.residual_k < passes.residual_k => list[i].1 = passes,
        Ok(_) => {}
        Err(i) => list.insert(i, (set, passes)),
    }
}

/// The property sets of a scene solve and each one's exchange with the
/// air ([`Exchange::new`]), index for index.
#[derive(Clone, Copy)]
struct PropertySets<'a> {
    props: &'a [SlabProperties],
    exchanges: &'a [Exchange],
    /// Class of each property set: its wind and orientation classes
    /// ([`WindSets`]) in one number; sets of equal properties and class
    /// share an exchange.
    wind_class: &'a [u32],
}

/// Quantum of the factor on the weather's wind that splits a property set
/// by facet wind ([`SceneInputs::wind`]): facets whose factors round to the
/// same multiple share one exchange (McAdams' `h` within `3.8·u·0.01`,
/// 0.15 W m⁻² K⁻¹ at 4 m/s, of the facet's own; at 0.05 the classes'
/// steps showed as a 0.04 K azimuthal pattern on open ground whose sky
/// views differ by sampling noise).
pub const WIND_QUANTUM: f64 = 0.02;

/// Wind class of a property set that takes the weather's wind as it is.
const WIND_NONE: u32 = u32::MAX;

/// The wind class of a facet of `props` with wind `wind`: its factor on
/// the weather's wind ([`FacetWind::factor_for`]) in units of
/// [`WIND_QUANTUM`], rounded, at least 1.
pub fn wind_class(wind: &FacetWind, props: &SlabProperties) -> u32 {
    let x = wind.factor_for(props.surface.is_some());
    (x / WIND_QUANTUM).round().max(1.0) as u32
}

/// `forcing` with its wind scaled to wind class `class` ([`wind_class`]):
/// what the exchange of that class is made from ([`Exchange::new`]).
pub fn forcing_with_wind_class(forcing: &Forcing, class: u32) -> Forcing {
    let mut f = forcing.clone();
    let k = class as f64 * WIND_QUANTUM;
    f.wind_speed_m_s.iter_mut().for_each(|u| *u *= k);
    f
}

/// The orientation class of a facet of `props` with unit normal
/// z-component `normal_z` ([`convection::orientation_class`]): the facet's
/// own for a dry DOE-2 material, whose natural convection depends on it;
/// the class of a horizontal surface for the others.
pub fn orientation_class(normal_z: f64, props: &SlabProperties) -> u32 {
    let oriented =
        props.surface.is_none() && props.convection.model == crate::material::ConvectionModel::Doe2;
    convection::orientation_class(if oriented { normal_z } else { 1.0 })
}

/// The property sets of a solve split by wind and orientation class: the
/// kinds remapped to the (property set, wind class, orientation class)
/// twins, the twins, the wind class of each (a multiple of
/// [`WIND_QUANTUM`]; [`WIND_NONE`] without facet wind) and its orientation
/// class ([`orientation_class`]).
struct WindSets {
    kinds: Vec<FacetThermal>,
    props: Vec<SlabProperties>,
    /// The caller's property set each of `props` is a twin of.
    origin: Vec<u32>,
    wind_class: Vec<u32>,
    orientation: Vec<u32>,
}

impl WindSets {
    fn new(inputs: &SceneInputs, kinds: &[FacetThermal], props: &[SlabProperties]) -> WindSets {
        let mut twins: std::collections::BTreeMap<(u32, u32, u32), u32> = Default::default();
        let mut out = WindSets {
            kinds: Vec::with_capacity(kinds.len()),
            props: Vec::new(),
            origin: Vec::new(),
            wind_class: Vec::new(),
            orientation: Vec::new(),
        };
        for (f, k) in kinds.iter().enumerate() {
            out.kinds.push(match *k {
                FacetThermal::Solve(pi) => {
                    let p = &props[pi as usize];
                    let q = match inputs.wind.get(f) {
                        Some(w) => wind_class(w, p),
                        None => WIND_NONE,
                    };
                    let o = orientation_class(inputs.normal[f].z as f64, p);
                    let next = out.props.len() as u32;
                    let i = *twins.entry((pi, q, o)).or_insert(next);
                    if i == next {
                        out.props.push(*p);
                        out.origin.push(pi);
                        out.wind_class.push(q);
                        out.orientation.push(o);
                    }
                    FacetThermal::Solve(i)
                }
                fixed => fixed,
            });
        }
        out
    }
}

/// The checks of [`solve_facet_temperatures`], before any work.
fn validate(
    inputs: &SceneInputs,
    kinds: &[FacetThermal],
    props: &[SlabProperties],
    forcing: &Forcing,
    image_records: &[usize],
    params: &ThermalParams,
) -> Result<()> {
    let n = inputs.facet_count();
    let records = forcing.len();
    if kinds.len() != n {
        return Err(Error::invalid(
            "facet thermal kinds",
            format!("expected one per facet ({n}), got {}", kinds.len()),
        ));
    }
    if inputs.records != records {
        return Err(Error::invalid(
            "forcing",
            format!(
                "the weather history has {records} records but the solar history {} steps; \
                 trace the sun at the record times",
                inputs.records
            ),
        ));
    }
    inputs.validate()?;
    if let Some((f, i)) = kinds.iter().enumerate().find_map(|(f, k)| match *k {
        FacetThermal::Solve(i) if i as usize >= props.len() => Some((f, i)),
        _ => None,
    }) {
        return Err(Error::invalid(
            format!("facet {f}"),
            format!(
                "property set {i} does not exist (there are {})",
                props.len()
            ),
        ));
    }
    if let Some(&r) = image_records.iter().find(|&&r| r >= records) {
        return Err(Error::invalid(
            "image_records",
            format!("record {r} is beyond the history ({records} records)"),
        ));
    }
    if params.passes == 0 {
        return Err(Error::invalid("passes", "expected at least 1 pass"));
    }
    if let ThermalMethod::Linearized(lp) = &params.method
        && !(lp.bin_k.is_finite() && lp.bin_k > 0.0)
    {
        return Err(Error::invalid(
            "bin_k",
            format!("expected a positive bin width (K), got {}", lp.bin_k),
        ));
    }
    Ok(())
}

/// Largest |a − b| over two `[image][facet]` temperature sets, K.
fn max_change(a: &[Vec<f32>], b: &[Vec<f32>]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs() as f64))
        .fold(0.0, f64::max)
}
