//! Per-hit temperatures: the surface temperature of the point a ray hits,
//! from that point's own solar history, where a facet's one temperature
//! would not do.
//!
//! # Method
//! The linearised scene solve gives each facet a temperature from its
//! reference's Green's function: `T = T_ref + G·(S − S_ref)` (K, sources
//! in W m⁻²; [`crate::thermal::scene::linearized`]). A point of the facet
//! differs from the facet only in its sunlit history `s_p(t)` (its shadow
//! rays against the facet's sample-point mean `s_f(t)`), and the sources
//! are affine in `s·max(cos θ, 0)` with slope `∂S/∂(s cos θ) = αE_dn`
//! ([`crate::thermal::SourceModel::front_per_sunlit_cos`]). So, to first
//! order,
//!
//! ```text
//! T_p = T_f + Σ_k G[image][k]·αE_dn[k]·cos θ_k·(s_p[k] − s_f[k])
//! ```
//!
//! one dot product over the window's records per hit
//! ([`crate::thermal::scene::PointResponse`]), with the point's `s_p` from
//! one shadow ray toward the sun per record with the sun in front of the
//! facet. Where `s_p = s_f` at every record (and the hit takes no sky view
//! of its own) the sum is exactly zero and the hit takes the facet's
//! temperature bit for bit. The second order adds the curvature of the
//! emission and, for an evaporating property set, of the latent loss
//! ([`crate::thermal::linear::emission_curvature`],
//! [`crate::thermal::linear::latent_curvature`]).
//!
//! # Sky view
//! With [`PerHit::with_sky`], a hit that gets its own temperature on a
//! facet whose hemisphere rays hit the scene ([`PerHit::own_sky`]) also
//! gets its own shape factor `F_p` and background: the facet's own
//! hemisphere pattern (the same directions as its sky view) traced from
//! the hit point. On a double-sided facet it traces both faces' patterns
//! (each at half weight, from the point lifted to each side), so its view
//! has the facet's form: the front face's `F` and the background over both
//! faces (the slab is one, whichever face a ray sees). Hits seen through a
//! reflection or a transmission take their own view as those seen directly
//! ([`PerHitParams::secondary_sky`]). The front source of the slab model is affine in `F`
//! ([`crate::thermal::SourceModel::front_per_shape_factor`], `∂S/∂F` =
//! `ε(E_sky − σT_air⁴) + αE_d`), and the scene solve's last pass adds the
//! background `ε(1 − F)·σ(T_bg⁴ − T_air⁴)` with
//! `T_bg⁴ = (g·T_air⁴ + Σ wᵢTᵢ⁴)/(g + Σ wᵢ)` over what the rays hit. So
//! the point's sources differ from the facet's by (W m⁻²)
//!
//! ```text
//! ΔS_k = (F_p − F_f)·∂S_k/∂F + ε(1 − F_p)σ(T_bg,p⁴ − T_air⁴)_k − ε(1 − F_f)σ(T_bg,f⁴ − T_air⁴)_k
//! ```
//!
//! with the `Tᵢ⁴` histories the last pass used, entering through the
//! image row of `G` as the sunlit difference does. The point's shape
//! factor and its background temperature at the image time go to the
//! radiance and the `shape_factor` truth layer ([`HitSky`]).
//!
//! On a single-sided facet with a traced exposed back
//! ([`SkyInputs::with_exposed_back`]) the point also traces its back's
//! pattern (occlusion rays from the point lifted behind the plane) for its
//! own `F_b,p`; the back's sources (exposed fraction `a`) differ by
//!
//! ```text
//! ΔB_k = (F_b,p − F_b,f)·∂B_k/∂F_b + aε(1 − F_b,p)σ(T_bg,p⁴ − T_air⁴)_k − aε(1 − F_b,f)σ(T_bg,f⁴ − T_air⁴)_k
//! ```
//!
//! (the back's background is the front's, as in the scene solve), entering
//! through the image row of the front's response to the back sources
//! ([`PointResponse::back_rows`]), first order.
//!
//! # Reflected shortwave
//! The reflected shortwave a facet receives ([`crate::exposure::reflected`])
//! is `E_dn·a_f(t) + E_d·b_f` with `a_f = g_f ρ_g sin h + Σ_j w_j ρ_j (E⁰_j +
//! a_j)` over what its hemisphere rays hit (`w_j`, ground weight `g_f`) and
//! `b_f` likewise with the diffuse `E⁰_j = F̄_j`. A hit with its own sky view
//! sees other weights: its reflected shortwave differs from its facet's by
//! `Δa = Δg ρ_g sin h + Σ_j Δw_j ρ_j (E⁰_j + a_j)` and `Δb = Δg ρ_g + Σ_j Δw_j
//! ρ_j (F̄_j + b_j)` over the facets whose weights differ (`a_j`, `b_j` the
//! neighbours' own reflected shortwave after the stage's bounces). Its
//! sources then differ by (W m⁻²)
//!
//! ```text
//! ΔS_refl,k = αE_dn[k]·Δa_k + αE_d[k]·Δb
//! ```
//!
//! (`αE_dn` the response's `∂S/∂(s cos θ)`: the reflected direct weighs
//! like the facet's own sun), entering with `ΔS` above through the image row
//! of `G` and the second order. Where the point sees what its facet's
//! sample points saw, `Δw` and `Δg` are all zero and so is the change.
//!
//! The shadow rays are traced at every [`PerHitParams::stride`]-th record
//! of each run of records with the sun in front (and the run's last), and
//! every record between two of them that disagree: as the exposure's
//! solar stride ([`crate::exposure::solar_history`]), so a shadow that
//! comes and goes between two coarse records is missed.
//!
//! # Adaptivity
//! A hit on facet `f` at range `d` gets its own temperature when the
//! facet has a response (solved by the linearised method) and either its
//! sample points disagree at some record of the window (`0 < s_f < 1`), or
//! it is large against the pixel footprint: its sample spacing
//! `√(area)/n` exceeds [`PerHitParams::size_px`] footprints `d·β` (`β`
//! the pixel's angular size, [`crate::sensor::Sensor::pixel_angle_rad`]).
//! Other hits take the facet's temperature.
//!
//! # What it owns, takes and gives
//! Owns the per-hit rule and arithmetic ([`PerHit`]). Takes the scene
//! solve's solar history, the facets' frames, one image time's
//! [`ImageResponse`] and the sun along the history; gives, for hit points,
//! the temperature change from the facet's and the sunlit fraction at the
//! image time ([`HitState`]). Knows nothing of bands or sensors (the pixel
//! angle comes as a number).

use std::sync::Arc;

use glam::Vec3;

use super::scene_thermal::{ImageResponse, SceneThermal};
use crate::exposure::reflected::NIGHT;
use crate::exposure::{
    FacePatterns, FacetSamples, ReflectedShortwave, SkySampling, SkyView, SolarHistory,
};
use crate::geometry::SceneGeometry;
use crate::thermal::linear::{emission_curvature, latent_curvature};
use crate::thermal::scene::PointResponse;
use crate::trace::{Coherence, Hit, Ray, Tracer};

/// Settings of per-hit temperatures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PerHitParams {
    /// Sample spacing, in pixel footprints, above which a facet is large
    /// (default 16: on the bundled town a smaller value makes most ground hits per-hit; see docs/physics/per-hit.md).
    pub size_px: f32,
    /// Shadow rays traced at every `stride`-th record, refined where the
    /// answer changes (default 4).
    pub stride: u32,
    /// Whether the second order of an evaporating property set includes
    /// the curvature of its latent loss in `T` (default true; false: the
    /// emission's curvature alone, for comparison).
    pub latent_curvature: bool,
    /// Whether hits seen through a reflection or a transmission take their
    /// own sky view, as hits seen directly do (default true; false: their
    /// facet's, for comparison).
    pub secondary_sky: bool,
}

impl Default for PerHitParams {
    fn default() -> Self {
        PerHitParams {
            size_px: 16.0,
            stride: 4,
            latent_curvature: true,
            secondary_sky: true,
        }
    }
}

/// Which hits on a facet [`PerHit::wants`] gives their own temperature.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PerHitRule {
    /// None.
    Never,
    /// All (the facet's sample points disagree at some window record).
    Always,
    /// Those at ranges where the facet is large against the pixel
    /// footprint ([`PerHit::large`]).
    ByRange,
}

/// A hit's own thermal state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HitState {
    /// Its temperature minus its facet's, K.
    pub dt_k: f32,
    /// Its sunlit fraction at the image time (0 or 1).
    pub sun_fraction: f32,
    /// Its own sky view, where it has one ([`PerHit::own_sky`]); `None`:
    /// its facet's.
    pub sky: Option<HitSky>,
}

/// A hit's own view of the sky and the scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HitSky {
    /// Its shape factor `F_p` (view factor to the sky) of the facet's front
    /// face.
    pub shape_factor: f32,
    /// On a double-sided facet, the shape factor of its back face at the
    /// point (from the back face's own rays; `None` on a single-sided
    /// facet). A ray that sees the back face sees the sky this face sees:
    /// the reflected sky of a back-face hit takes this one, not
    /// [`HitSky::shape_factor`].
    pub back_shape_factor: Option<f32>,
    /// Its background temperature at the image time, K: the radiative mean
    /// of what its blocked hemisphere rays hit, the ground beyond the scene
    /// at the air temperature (as
    /// [`crate::exposure::SkyView::background_temperature`] for a facet).
    pub background_k: f32,
    /// Its reflected shortwave irradiance at the image time, W m⁻² (module
    /// docs, "Reflected shortwave"): its facet's where the reflected
    /// shortwave is off.
    pub reflected_w_m2: f32,
}

/// What hits' own sky views need of the scene (shared by the image times
/// of a render; module docs, "Sky view").
#[derive(Debug, Clone, PartialEq)]
pub struct SkyInputs {
    /// The facets' sky views (shape factors and what their rays hit).
    sky: Arc<SkyView>,
    /// The hemisphere patterns of the facets' sky views.
    patterns: FacePatterns,
    /// Per facet: tangent and bitangent of its frame.
    frame: Arc<Vec<(Vec3, Vec3)>>,
    /// First facet of each instance.
    instance_offsets: Arc<Vec<usize>>,
    /// Per facet: whether its hits may take their own sky view (shape
    /// factor not set by hand, some of its hemisphere rays hit the scene).
    eligible: Arc<Vec<bool>>,
    /// What a point's own reflected shortwave needs (`None`: the reflected
    /// shortwave is off, every hit keeps its facet's).
    refl: Option<Arc<ReflInputs>>,
    /// Per facet: the traced sky view of its exposed back (single-sided
    /// facets whose slab has one; `None` elsewhere, or empty: none traced).
    exposed_back: Arc<Vec<Option<f32>>>,
}

/// What a point's own reflected shortwave needs (module docs, "Reflected
/// shortwave"): the facets' reflected-shortwave coefficients and albedos
/// and the weather's irradiances.
#[derive(Debug, Clone, PartialEq)]
struct ReflInputs {
    /// Every facet's reflected shortwave (per unit `E_dn` and `E_d`).
    reflected: Arc<ReflectedShortwave>,
    /// Per facet: the albedo its neighbours receive reflected sunlight from.
    albedo: Vec<f32>,
    /// Albedo of the ground beyond the scene.
    ground_albedo: f32,
    /// Per facet: its solar absorptivity α (0 for a fixed facet).
    absorptivity: Vec<f32>,
    /// Per history record: direct-normal and diffuse-horizontal
    /// irradiance, W m⁻², and the sine of the sun's elevation.
    direct_normal: Vec<f32>,
    diffuse: Vec<f32>,
    sun_z: Vec<f32>,
}

impl SkyInputs {
    /// From the facets' frames and sky view, traced with `sampling` and
    /// `seed`; `shape_factor_override` per facet (or empty) marks the
    /// facets whose shape factor was set by hand.
    pub fn new(
        facets: &FacetSamples,
        sky: Arc<SkyView>,
        sampling: SkySampling,
        seed: u64,
        shape_factor_override: &[Option<f32>],
    ) -> SkyInputs {
        let eligible = (0..facets.len())
            .map(|f| {
                shape_factor_override.get(f).is_none_or(Option::is_none)
                    && !sky.background(f).is_empty()
            })
            .collect();
        SkyInputs {
            patterns: FacePatterns::new(sampling, seed),
            frame: Arc::new(
                facets
                    .tangent
                    .iter()
                    .zip(&facets.bitangent)
                    .map(|(&t, &b)| (t, b))
                    .collect(),
            ),
            instance_offsets: Arc::new(facets.instance_offsets.clone()),
            eligible: Arc::new(eligible),
            sky,
            refl: None,
            exposed_back: Arc::new(Vec::new()),
        }
    }

    /// These inputs with the facets' traced exposed-back sky views
    /// ([`crate::render::scene_thermal::SceneThermal::exposed_back_shape_factor`]):
    /// a hit with its own sky view on such a facet also traces its back's
    /// (module docs, "Sky view").
    pub fn with_exposed_back(mut self, exposed_back: Vec<Option<f32>>) -> SkyInputs {
        self.exposed_back = Arc::new(exposed_back);
        self
    }

    /// These inputs with what a point's own reflected shortwave needs:
    /// `reflected` the scene solve's reflected-shortwave stage (shared, not
    /// copied), `solved` that solve (albedos, absorptivities, weather and
    /// sun), `ground_albedo` the albedo of the ground beyond the scene that
    /// stage used. Unchanged where the solve has no reflected shortwave
    /// (`reflected_bounces` 0).
    pub fn with_reflected(
        mut self,
        reflected: Arc<ReflectedShortwave>,
        solved: &SceneThermal,
        ground_albedo: f32,
    ) -> SkyInputs {
        let n = self.eligible.len();
        let rs = &*reflected;
        if rs.facet_count() != n || rs.records != solved.records.len() {
            return self;
        }
        let setup = &solved.setup;
        let absorptivity = (0..n)
            .map(|f| match setup.kinds.get(f) {
                Some(crate::thermal::scene::FacetThermal::Solve(p)) => {
                    setup.props[*p as usize].solar_absorptivity as f32
                }
                _ => 0.0,
            })
            .collect();
        self.refl = Some(Arc::new(ReflInputs {
            reflected,
            albedo: setup.facet_albedo(),
            ground_albedo,
            absorptivity,
            direct_normal: solved
                .records
                .iter()
                .map(|w| w.direct_normal_w_m2 as f32)
                .collect(),
            diffuse: solved
                .records
                .iter()
                .map(|w| w.diffuse_horizontal_w_m2 as f32)
                .collect(),
            sun_z: solved.sun_directions.iter().map(|d| d.z).collect(),
        }));
        self
    }
}

/// [`SkyInputs`] with one image time's temperatures.
#[derive(Debug, Clone, PartialEq)]
struct PointSky {
    inputs: SkyInputs,
    /// Every facet's temperature at the image time, K.
    temperature_k: Vec<f32>,
}

/// What per-hit temperatures need for one image time (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct PerHit {
    solar: Arc<SolarHistory>,
    /// The window's records (indices into the history).
    records: Vec<usize>,
    /// Unit vector toward the sun at each window record.
    sun: Vec<Vec3>,
    /// Per facet: its response row block (u32::MAX: none).
    block_of: Vec<u32>,
    /// `[block][k]`, K per unit of `s cos θ`.
    rows: Vec<f32>,
    /// `[block][k]`, K per W m⁻²: the image row of the Green's matrix.
    green_rows: Vec<f32>,
    /// `[block][k]`, K per W m⁻²: the image row of the front's response
    /// to the exposed back's sources (empty when no block has one).
    back_rows: Vec<f32>,
    /// The response (whole Green's matrices, reference histories) for the
    /// second order.
    response: Arc<PointResponse>,
    /// Per facet: its sample points disagree at some window record.
    mixed: Vec<bool>,
    /// Per facet: sample spacing `√area / n`, m; 0 for a facet whose
    /// hemisphere rays hit nothing of the scene (nothing above its horizon
    /// that could shade part of it).
    spacing: Vec<f32>,
    /// Per facet: unit front normal.
    normal: Vec<Vec3>,
    /// Lift of ray origins off the surface, m.
    offset_m: f32,
    params: PerHitParams,
    /// Hits' own sky views (`None`: every hit takes its facet's).
    sky: Option<PointSky>,
}

impl PerHit {
    /// The per-hit state of one image time: `solar` the scene's solar
    /// history, `facets` its frames, `image` the image's response over its
    /// window, `sun_history` the sun at every history record.
    pub fn new(
        solar: Arc<SolarHistory>,
        facets: &FacetSamples,
        sky: &SkyView,
        image: &ImageResponse,
        sun_history: &[Vec3],
        params: PerHitParams,
    ) -> PerHit {
        let resp = &image.response;
        let r = resp.records;
        debug_assert_eq!(r, image.records.len());
        let blocks = resp.sun_rows.len() / (r * resp.images).max(1);
        let mut rows = Vec::with_capacity(blocks * r);
        let mut green_rows = Vec::with_capacity(blocks * r);
        let mut back_rows = Vec::new();
        for b in 0..blocks {
            let o = b * resp.images * r;
            rows.extend_from_slice(&resp.sun_rows[o..o + r]);
            green_rows.extend_from_slice(&resp.rows[o..o + r]);
            if let Some(x) = resp.back_rows.get(o..o + r) {
                back_rows.extend_from_slice(x);
            }
        }
        let n = facets.len();
        let per = facets.per_facet.max(1) as f32;
        let mixed = (0..n)
            .map(|f| {
                image.records.iter().any(|&k| {
                    let s = solar.sun_fraction_at(f, k);
                    solar.cos_incidence_at(f, k) > 0.0 && s > 0.0 && s < 1.0
                })
            })
            .collect();
        PerHit {
            records: image.records.clone(),
            sun: image.records.iter().map(|&k| sun_history[k]).collect(),
            block_of: resp.block_of.clone(),
            rows,
            green_rows,
            back_rows,
            response: Arc::new(resp.clone()),
            mixed,
            spacing: facets
                .area
                .iter()
                .enumerate()
                .map(|(f, a)| {
                    if sky.background(f).is_empty() {
                        0.0
                    } else {
                        a.max(0.0).sqrt() / per.sqrt()
                    }
                })
                .collect(),
            normal: facets.normal.clone(),
            offset_m: facets.offset_m,
            solar,
            params,
            sky: None,
        }
    }

    /// This with hits' own sky views (module docs, "Sky view"):
    /// `temperature_k` every facet's temperature at the image time, K.
    pub fn with_sky(mut self, inputs: SkyInputs, temperature_k: &[f32]) -> PerHit {
        self.sky = Some(PointSky {
            inputs,
            temperature_k: temperature_k.to_vec(),
        });
        self
    }

    /// The hemisphere rays of one face of `facet` from point `p` lifted
    /// off its plane on that face's side: the facet's own pattern of the
    /// face (the directions of its sky view) in its frame, the back face's
    /// frame `FacetSamples::to_world` with side −1; weights times `scale`.
    #[allow(clippy::too_many_arguments)]
    fn face_rays(
        &self,
        inputs: &SkyInputs,
        facet: usize,
        p: Vec3,
        back: bool,
        scale: f32,
        pat: &mut Vec<crate::exposure::sampling::HemiSample>,
        rays: &mut Vec<Ray>,
        weights: &mut Vec<f32>,
    ) {
        let n = self.normal[facet];
        let (t, b) = inputs.frame[facet];
        let side = if back { -1.0 } else { 1.0 };
        let o = p + n * (side * self.offset_m);
        let pattern = if back {
            inputs.patterns.back(facet, pat)
        } else {
            inputs.patterns.front(facet, pat)
        };
        for h in pattern {
            let d = t * h.dir.x + b * (side * h.dir.y) + n * (side * h.dir.z);
            rays.push(Ray::new(o, d));
            weights.push(h.weight * scale);
        }
    }

    /// The traced sky view of `facet`'s exposed back where its hits that
    /// take their own sky view also take their back's: the facet has one
    /// (single-sided, exposed back) and its reference responds to the back.
    fn own_back(&self, facet: usize) -> Option<f32> {
        // (`back_radiative`, `back_shape` and `back_rows` are filled
        // together.)
        let fb = (*self.sky.as_ref()?.inputs.exposed_back.get(facet)?)?;
        let b = *self.block_of.get(facet)? as usize;
        let rb = *self.response.back_radiative.get(b)?;
        (rb > 0.0).then_some(fb)
    }

    /// Whether hits on `facet` that get their own temperature also get their
    /// own sky view: per-hit sky views are on, the facet has a response, its
    /// shape factor was not set by hand, and some of its hemisphere rays hit
    /// the scene (otherwise every point of its plane sees the same sky and
    /// ground).
    #[inline]
    pub fn own_sky(&self, facet: usize) -> bool {
        self.sky
            .as_ref()
            .is_some_and(|s| s.inputs.eligible.get(facet).copied().unwrap_or(false))
            && self.block_of.get(facet).is_some_and(|&b| b != u32::MAX)
    }

    /// Whether a hit on `facet` at range `range_m` seen with pixel angle
    /// `pixel_angle_rad` (0: unknown) gets its own temperature:
    /// [`PerHit::rule`], with [`PerHit::large`] where it depends on the
    /// range.
    #[inline]
    pub fn wants(&self, facet: usize, range_m: f32, pixel_angle_rad: f32) -> bool {
        match self.rule(facet, pixel_angle_rad) {
            PerHitRule::Never => false,
            PerHitRule::Always => true,
            PerHitRule::ByRange => self.large(facet, range_m, pixel_angle_rad),
        }
    }

    /// The part of [`PerHit::wants`] that is the same for every hit on
    /// `facet` (pixel angle `pixel_angle_rad`): never (no response, or
    /// neither mixed nor a known pixel angle), always (its sample points
    /// disagree), or by range ([`PerHit::large`]).
    #[inline]
    pub fn rule(&self, facet: usize, pixel_angle_rad: f32) -> PerHitRule {
        if self.block_of.get(facet).is_none_or(|&b| b == u32::MAX) {
            PerHitRule::Never
        } else if self.mixed[facet] {
            PerHitRule::Always
        } else if pixel_angle_rad > 0.0 {
            PerHitRule::ByRange
        } else {
            PerHitRule::Never
        }
    }

    /// Whether `facet` (one of [`PerHitRule::ByRange`]) is large against
    /// the pixel footprint at range `range_m`: its sample spacing over
    /// [`PerHitParams::size_px`] footprints `range_m · pixel_angle_rad`.
    #[inline]
    pub fn large(&self, facet: usize, range_m: f32, pixel_angle_rad: f32) -> bool {
        pixel_angle_rad > 0.0
            && self.spacing[facet] > self.params.size_px * range_m * pixel_angle_rad
    }

    /// The range of temperatures the hits on a facet can take through
    /// their sunlit histories, K: each facet's `temperature_k` plus and
    /// minus the largest change its response allows (every record fully
    /// lit or shaded). An own sky view's change (a few kelvins) is not
    /// bounded here: its rare hits beyond a table built on this range take
    /// the exact path.
    pub fn temperature_bounds(&self, temperature_k: &[f32]) -> (f32, f32) {
        use rayon::prelude::*;
        let r = self.records.len();
        // Facets in parallel (min and max do not depend on the order).
        temperature_k
            .par_iter()
            .enumerate()
            .fold(
                || (f32::INFINITY, f32::NEG_INFINITY),
                |(lo, hi), (f, &t)| {
                    let Some(&b) = self.block_of.get(f) else {
                        return (lo, hi);
                    };
                    if b == u32::MAX {
                        return (lo, hi);
                    }
                    let row = &self.rows[b as usize * r..(b as usize + 1) * r];
                    let m: f32 = row
                        .iter()
                        .zip(&self.records)
                        .map(|(g, &k)| (g * self.solar.cos_incidence_at(f, k).max(0.0)).abs())
                        .sum();
                    (lo.min(t - m), hi.max(t + m))
                },
            )
            .reduce(
                || (f32::INFINITY, f32::NEG_INFINITY),
                |(a, b), (c, d)| (a.min(c), b.max(d)),
            )
    }

    /// The second-order term of a point whose sources differ from its
    /// facet's by `src` (W m⁻² per record, zeros where they agree), K: the
    /// curvature of the emission about the reference,
    /// `r(δ) = −εσδ²(6T² + 4Tδ + δ²)`, and of an evaporating surface's
    /// latent loss, `−g_v[e°(T+δ) − e°(T) − e°′(T)δ]`
    /// ([`PerHitParams::latent_curvature`]), with `δ = G·ΔS` the
    /// first-order change history, through the image row of `G` (as the
    /// scene solve's second order, [`crate::thermal::Linearization::predict`],
    /// whose curvature functions these are). `delta` is scratch space.
    fn second_order(&self, block: usize, src: &[f32], delta: &mut Vec<f32>) -> f32 {
        let p = &*self.response;
        let r = p.records;
        let g = &p.green[block * r * r..(block + 1) * r * r];
        delta.clear();
        delta.resize(r, 0.0);
        for (k, &x) in src.iter().enumerate() {
            if x == 0.0 {
                continue;
            }
            for (o, gk) in delta.iter_mut().zip(&g[k * r..(k + 1) * r]) {
                *o += x * gk;
            }
        }
        let t_ref = &p.reference_k[block * r..(block + 1) * r];
        let rad = p.radiative[block] as f64;
        let latent = if self.params.latent_curvature {
            p.latent.get(block * r..(block + 1) * r).unwrap_or(&[])
        } else {
            &[]
        };
        let row = &self.green_rows[block * r..(block + 1) * r];
        let mut x = 0.0f64;
        for t in 0..r {
            if delta[t] != 0.0 {
                let (tr, d) = (t_ref[t] as f64, delta[t] as f64);
                let mut c = emission_curvature(rad, tr, d);
                if let Some(&gv) = latent.get(t) {
                    c += latent_curvature(gv, tr, d);
                }
                x += row[t] as f64 * c;
            }
        }
        x as f32
    }

    /// The own sky view of a point of a facet from its hemisphere rays
    /// `rays`, `hits`, `weights` (the facet's pattern, from the point; for
    /// a double-sided facet its front face's rays then its back face's, each
    /// at half weight, as [`crate::exposure::sky_view`] traces them): its
    /// front face's shape factor, ground weight and the facets hit with
    /// their weights (into `seen`, merged by facet), as the facet's
    /// [`SkyView`] holds them; and, on a double-sided facet, its back
    /// face's shape factor.
    fn point_view(
        inputs: &SkyInputs,
        rays: &[Ray],
        hits: &[Option<Hit>],
        weights: &[f32],
        double_sided: bool,
        seen: &mut Vec<(u32, f32)>,
    ) -> (f32, f32, Option<f32>) {
        let (mut sky, mut back, mut ground) = (0.0f64, 0.0f64, 0.0f64);
        let front = if double_sided {
            rays.len() / 2
        } else {
            rays.len()
        };
        seen.clear();
        for (i, ((ray, h), &w)) in rays.iter().zip(hits).zip(weights).enumerate() {
            match h {
                Some(h) => seen.push((
                    SceneGeometry::facet_id(&inputs.instance_offsets, h.instance, h.prim) as u32,
                    w,
                )),
                None if ray.dir.z > 0.0 => {
                    if i < front {
                        sky += w as f64
                    } else {
                        back += w as f64
                    }
                }
                None => ground += w as f64,
            }
        }
        if double_sided {
            // Each face's rays carried half weight.
            sky *= 2.0;
            back *= 2.0;
        }
        seen.sort_by_key(|e| e.0);
        seen.dedup_by(|b, a| {
            let same = a.0 == b.0;
            if same {
                a.1 += b.1;
            }
            same
        });
        (
            sky as f32,
            ground as f32,
            double_sided.then_some(back as f32),
        )
    }

    /// The background excess `T_bg⁴ − T_air⁴` (K⁴ per record) of a view
    /// with ground weight `g` and the facets `seen` (with weights), into
    /// `out`: `T_bg⁴ = (g·T_air⁴ + Σ wᵢTᵢ⁴)/(g + Σ wᵢ)`, `Tᵢ⁴` the `T⁴`
    /// history the scene solve's last pass used, or (a facet no other facet
    /// sees) its temperature at the image time. A face's background source
    /// is `ε(1 − F)·σ` times it ([`add_background`]), the term that pass
    /// adds to a facet's sources
    /// ([`crate::thermal::background_coefficients`]). `out` is left empty
    /// with one pass (the air is every background) or an empty view.
    fn background_excess(
        &self,
        sky: &PointSky,
        g: f32,
        seen: &mut dyn Iterator<Item = (u32, f32)>,
        out: &mut Vec<f32>,
    ) {
        let p = &*self.response;
        out.clear();
        if p.slot_of.is_empty() {
            return;
        }
        let r = p.records;
        out.extend(p.air4.iter().map(|a| g * a));
        let mut den = g;
        for (j, w) in seen {
            den += w;
            match p.slot_of.get(j as usize) {
                Some(&s) if s != u32::MAX => {
                    let h = &p.background4[s as usize * r..(s as usize + 1) * r];
                    out.iter_mut().zip(h).for_each(|(o, t4)| *o += w * t4);
                }
                _ => {
                    let t4 = w * sky.temperature_k[j as usize].powi(4);
                    out.iter_mut().for_each(|o| *o += t4);
                }
            }
        }
        if den <= 0.0 {
            out.clear();
            return;
        }
        for (o, air) in out.iter_mut().zip(&p.air4) {
            *o = *o / den - air;
        }
    }

    /// The facets a point sees with weights other than its facet's: `seen`
    /// (the point's, merged by facet and sorted by id) minus `entries` (the
    /// facet's, sorted by id), the non-zero differences into `out` (sorted
    /// by id). Empty where the point sees what its facet's sample points
    /// saw.
    fn view_difference(
        seen: &[(u32, f32)],
        entries: &[crate::geometry::BackgroundEntry],
        out: &mut Vec<(u32, f32)>,
    ) {
        out.clear();
        let (mut i, mut j) = (0, 0);
        while i < seen.len() || j < entries.len() {
            let a = seen.get(i).map_or(u32::MAX, |e| e.0);
            let b = entries.get(j).map_or(u32::MAX, |e| e.facet);
            let (id, w) = if a < b {
                i += 1;
                (a, seen[i - 1].1)
            } else if b < a {
                j += 1;
                (b, -entries[j - 1].weight)
            } else {
                i += 1;
                j += 1;
                (a, seen[i - 1].1 - entries[j - 1].weight)
            };
            if w != 0.0 {
                out.push((id, w));
            }
        }
    }

    /// The change of a point's sources through its own reflected shortwave
    /// (module docs, "Reflected shortwave"), added to `out` (W m⁻² per
    /// window record), for a point of `facet` (response block `block`)
    /// whose view differs from its facet's by the ground weight `dg` and
    /// the facet weights `dw` ([`PerHit::view_difference`]); `da` is
    /// scratch. Returns the point's reflected irradiance at the image time,
    /// W m⁻² (0 without the reflected shortwave).
    #[allow(clippy::too_many_arguments)]
    fn add_reflected(
        &self,
        sky: &PointSky,
        facet: usize,
        block: usize,
        dg: f32,
        dw: &[(u32, f32)],
        out: &mut [f32],
        da: &mut Vec<f32>,
    ) -> f32 {
        let Some(ri) = sky.inputs.refl.as_deref() else {
            return 0.0;
        };
        let rs = &ri.reflected;
        let r = self.records.len();
        let last = self.records[r - 1];
        let (edn, ed) = (ri.direct_normal[last], ri.diffuse[last]);
        let facet_now = rs.irradiance_w_m2(facet, last, edn as f64, ed as f64) as f32;
        if dw.is_empty() && dg == 0.0 {
            return facet_now;
        }
        // Δa_k (per unit E_dn) and Δb (per unit E_d).
        da.clear();
        da.resize(r, 0.0);
        let mut db = 0.0f32;
        if dg != 0.0 {
            let g = dg * ri.ground_albedo;
            db += g;
            for (o, &k) in da.iter_mut().zip(&self.records) {
                if rs.slot[k] != NIGHT {
                    *o += g * ri.sun_z[k].max(0.0);
                }
            }
        }
        let view = &sky.inputs.sky;
        for &(j, w) in dw {
            let j = j as usize;
            let c = w * ri.albedo[j];
            if c == 0.0 {
                continue;
            }
            db += c * (view.mean_shape_factor(j) + rs.diffuse[j]);
            for (o, &k) in da.iter_mut().zip(&self.records) {
                if rs.slot[k] != NIGHT {
                    let e0 = self.solar.sun_fraction_at(j, k).clamp(0.0, 1.0)
                        * self.solar.cos_incidence_at(j, k).max(0.0);
                    *o += c * (e0 + rs.direct_at(j, k));
                }
            }
        }
        // ΔS_k = αE_dn·Δa_k + αE_d·Δb: the response's `∂S/∂(s cos θ)` is
        // αE_dn (the reflected direct weighs like the facet's own sun).
        let sun = &self.response.sun[block * r..(block + 1) * r];
        let ad = ri.absorptivity[facet] * db;
        for (((o, &x), &s), &k) in out.iter_mut().zip(da.iter()).zip(sun).zip(&self.records) {
            *o += s * x + ad * ri.diffuse[k];
        }
        facet_now + edn * da[r - 1] + ed * db
    }

    /// Background temperature at the image time of a face with ground
    /// weight `g` and the facets `seen`, K (air temperature `air_k` for the
    /// ground beyond the scene and for a face that sees only sky).
    fn background_now(sky: &PointSky, g: f32, seen: &[(u32, f32)], air_k: f32) -> f32 {
        let mut num = g * air_k.powi(4);
        let mut den = g;
        for &(j, w) in seen {
            num += w * sky.temperature_k[j as usize].powi(4);
            den += w;
        }
        if den > 0.0 {
            (num / den).powf(0.25)
        } else {
            air_k
        }
    }

    /// The states of hits `(facet, point)` (points on the facets' planes)
    /// into `out`, one per hit, tracing their shadow rays with `tracer`
    /// (and their own sky views where [`PerHit::own_sky`]).
    pub fn states(&self, tracer: &dyn Tracer, hits: &[(u32, Vec3)], out: &mut Vec<HitState>) {
        self.states_of(tracer, hits, true, out);
    }

    /// [`PerHit::states`] of hits seen directly (`direct`) or through a
    /// reflection or transmission (`!direct`: these take their own sky view
    /// only with [`PerHitParams::secondary_sky`], else their facet's).
    pub fn states_of(
        &self,
        tracer: &dyn Tracer,
        hits: &[(u32, Vec3)],
        direct: bool,
        out: &mut Vec<HitState>,
    ) {
        let own_sky = direct || self.params.secondary_sky;
        out.clear();
        let r = self.records.len();
        if hits.is_empty() || r == 0 {
            return;
        }
        let stride = self.params.stride.max(1) as usize;
        // Per hit and record: no ray (the sun not in front of the facet),
        // lit, shaded, or not traced yet.
        const NONE: u8 = 0;
        const LIT: u8 = 1;
        const SHADED: u8 = 2;
        const UNKNOWN: u8 = 3;
        let mut state = vec![NONE; hits.len() * r];
        let mut coarse = vec![false; hits.len() * r];
        for (j, &(f, _)) in hits.iter().enumerate() {
            let c = |k: usize| self.solar.cos_incidence_at(f as usize, self.records[k]);
            let st = &mut state[j * r..(j + 1) * r];
            let co = &mut coarse[j * r..(j + 1) * r];
            let mut k = 0;
            while k < r {
                if c(k) <= 0.0 {
                    k += 1;
                    continue;
                }
                let a = k;
                while k + 1 < r && c(k + 1) > 0.0 {
                    k += 1;
                }
                st[a..=k].fill(UNKNOWN);
                for t in (a..=k).step_by(stride) {
                    co[t] = true;
                }
                co[k] = true;
                k += 1;
            }
        }
        let ray = |f: usize, p: Vec3, k: usize| {
            let d = self.sun[k];
            let n = self.normal[f];
            let side = if n.dot(d) >= 0.0 { 1.0 } else { -1.0 };
            Ray::new(p + n * (side * self.offset_m), d)
        };
        let trace = |want: &dyn Fn(usize) -> bool, state: &mut [u8]| {
            // Record by record: one record's rays are parallel and start at
            // neighbouring points (coherent).
            let mut rays = Vec::new();
            let mut idx = Vec::new();
            for k in 0..r {
                for (j, &(f, p)) in hits.iter().enumerate() {
                    if want(j * r + k) {
                        rays.push(ray(f as usize, p, k));
                        idx.push(j * r + k);
                    }
                }
            }
            let mut occ = vec![false; rays.len()];
            tracer.occluded(&rays, Coherence::Coherent, &mut occ);
            for (&i, &o) in idx.iter().zip(&occ) {
                state[i] = if o { SHADED } else { LIT };
            }
        };
        trace(&|i| coarse[i], &mut state);
        // Between two coarse records of a run that disagree: every record.
        let mut need = vec![false; hits.len() * r];
        for j in 0..hits.len() {
            let mut prev: Option<usize> = None;
            for k in 0..r {
                let i = j * r + k;
                if state[i] == NONE {
                    prev = None;
                    continue;
                }
                if !coarse[i] {
                    continue;
                }
                if let Some(a) = prev
                    && state[j * r + a] != state[i]
                {
                    for t in a + 1..k {
                        need[j * r + t] = true;
                    }
                }
                prev = Some(k);
            }
        }
        trace(&|i| need[i], &mut state);
        // The own hemisphere rays of the hits that take their own sky view:
        // their facet's pattern (the directions of its own sky view; a
        // double-sided facet's front then back face, each at half weight),
        // all from the hit point lifted off the plane on the face's side;
        // hit `j`'s rays are `sky_rays[sky_at[j]..sky_at[j + 1]]` (an empty
        // range: none).
        let mut sky_rays = Vec::new();
        let mut sky_w = Vec::new();
        let mut sky_at = Vec::with_capacity(hits.len() + 1);
        // A hit with its own sky view on a facet with a traced exposed back
        // also traces the back's pattern from the point lifted to the back
        // side (occlusion only: the back's background is the front's, as in
        // the scene solve); hit `j`'s are `back_rays[back_at[j]..back_at[j
        // + 1]]`.
        let mut back_rays = Vec::new();
        let mut back_w = Vec::new();
        let mut back_at = Vec::with_capacity(hits.len() + 1);
        let mut pat = Vec::new();
        for &(f, p) in hits {
            sky_at.push(sky_rays.len());
            back_at.push(back_rays.len());
            let f = f as usize;
            if let Some(ps) = self.sky.as_ref().filter(|_| own_sky && self.own_sky(f)) {
                let two = ps.inputs.sky.back_shape_factor(f).is_some();
                let scale = if two { 0.5 } else { 1.0 };
                let mut face = |back: bool, scale: f32, rays: &mut Vec<Ray>, w: &mut Vec<f32>| {
                    self.face_rays(&ps.inputs, f, p, back, scale, &mut pat, rays, w)
                };
                face(false, scale, &mut sky_rays, &mut sky_w);
                if two {
                    face(true, scale, &mut sky_rays, &mut sky_w);
                } else if self.own_back(f).is_some() {
                    face(true, 1.0, &mut back_rays, &mut back_w);
                }
            }
        }
        sky_at.push(sky_rays.len());
        back_at.push(back_rays.len());
        let mut sky_hits = vec![None; sky_rays.len()];
        if !sky_rays.is_empty() {
            tracer.intersect(&sky_rays, Coherence::Incoherent, &mut sky_hits);
        }
        let mut back_occ = vec![false; back_rays.len()];
        if !back_rays.is_empty() {
            tracer.occluded(&back_rays, Coherence::Incoherent, &mut back_occ);
        }
        // Scratch of the per-hit loop: (record, Δ(s cos θ)) where the
        // point's history differs, the sky view's source change, the point's
        // source change, the second order's change history, what the point
        // sees, the point's and the facet's background excess.
        let mut diff: Vec<(usize, f32)> = Vec::new();
        let mut ds_sky: Vec<f32> = Vec::new();
        let mut ds_back: Vec<f32> = Vec::new();
        let mut src: Vec<f32> = Vec::new();
        let mut delta: Vec<f32> = Vec::new();
        let mut seen: Vec<(u32, f32)> = Vec::new();
        let (mut exc_p, mut exc_f): (Vec<f32>, Vec<f32>) = (Vec::new(), Vec::new());
        let mut dw: Vec<(u32, f32)> = Vec::new();
        let mut da: Vec<f32> = Vec::new();
        for (j, &(f, _)) in hits.iter().enumerate() {
            let f = f as usize;
            let s = |k: usize| self.solar.sun_fraction_at(f, k);
            let c = |k: usize| self.solar.cos_incidence_at(f, k);
            let b = self.block_of[f] as usize;
            let row = &self.rows[b * r..(b + 1) * r];
            let st = &mut state[j * r..(j + 1) * r];
            // The rest take the answer of the coarse record after them.
            let mut next = UNKNOWN;
            for v in st.iter_mut().rev() {
                match *v {
                    NONE => next = UNKNOWN,
                    UNKNOWN => *v = next,
                    x => next = x,
                }
            }
            let mut dt = 0.0f32;
            diff.clear();
            for (k, &v) in st.iter().enumerate() {
                if v == NONE {
                    continue;
                }
                let h = s(self.records[k]).clamp(0.0, 1.0);
                let own = if v == LIT { 1.0 } else { 0.0 };
                if own != h {
                    let d = c(self.records[k]).max(0.0) * (own - h);
                    dt += row[k] * d;
                    diff.push((k, d));
                }
            }
            // The own sky view's source change (module docs, "Sky view").
            let (r0, r1) = (sky_at[j], sky_at[j + 1]);
            let mut own_sky = None;
            if let Some(ps) = self.sky.as_ref().filter(|_| r1 > r0) {
                let sky = &ps.inputs.sky;
                let (fp, gp, fp_back) = Self::point_view(
                    &ps.inputs,
                    &sky_rays[r0..r1],
                    &sky_hits[r0..r1],
                    &sky_w[r0..r1],
                    sky.back_shape_factor(f).is_some(),
                    &mut seen,
                );
                let ff = sky.shape_factor[f];
                let p = &*self.response;
                ds_sky.clear();
                match p.shape.get(b * r..(b + 1) * r) {
                    Some(shape) => ds_sky.extend(shape.iter().map(|x| (fp - ff) * x)),
                    None => ds_sky.resize(r, 0.0),
                }
                // The point's and the facet's background excess, for the
                // front's and an exposed back's background terms.
                self.background_excess(ps, gp, &mut seen.iter().copied(), &mut exc_p);
                self.background_excess(
                    ps,
                    sky.ground_weight[f],
                    &mut sky.background(f).iter().map(|e| (e.facet, e.weight)),
                    &mut exc_f,
                );
                let rf = p.radiative[b];
                add_background(&mut ds_sky, rf * (1.0 - fp), &exc_p);
                add_background(&mut ds_sky, -(rf * (1.0 - ff)), &exc_f);
                Self::view_difference(&seen, sky.background(f), &mut dw);
                let reflected_w_m2 = self.add_reflected(
                    ps,
                    f,
                    b,
                    gp - sky.ground_weight[f],
                    &dw,
                    &mut ds_sky,
                    &mut da,
                );
                let green = &self.green_rows[b * r..(b + 1) * r];
                dt += green.iter().zip(&ds_sky).map(|(g, x)| g * x).sum::<f32>();
                // The exposed back's own sky view: its sources differ by
                // `(F_b,p − F_b,f)·∂B/∂F_b` and the back's background term
                // `a·ε(1 − F_b)σ(T_bg⁴ − T_air⁴)` at the point's `F_b` and
                // background, through the front's response to the back
                // (first order).
                let (b0, b1) = (back_at[j], back_at[j + 1]);
                if let Some(fb_f) = self.own_back(f).filter(|_| b1 > b0) {
                    let fb_p = (b0..b1)
                        .filter(|&i| !back_occ[i] && back_rays[i].dir.z > 0.0)
                        .map(|i| back_w[i] as f64)
                        .sum::<f64>() as f32;
                    let rb = p.back_radiative[b];
                    ds_back.clear();
                    ds_back.extend(
                        p.back_shape[b * r..(b + 1) * r]
                            .iter()
                            .map(|x| (fb_p - fb_f) * x),
                    );
                    add_background(&mut ds_back, rb * (1.0 - fb_p), &exc_p);
                    add_background(&mut ds_back, -(rb * (1.0 - fb_f)), &exc_f);
                    let row = &self.back_rows[b * r..(b + 1) * r];
                    dt += row.iter().zip(&ds_back).map(|(g, x)| g * x).sum::<f32>();
                }
                let air = p.air4.last().map_or(0.0, |a| a.powf(0.25));
                own_sky = Some(HitSky {
                    shape_factor: fp,
                    back_shape_factor: fp_back,
                    background_k: Self::background_now(ps, gp, &seen, air),
                    reflected_w_m2,
                });
            }
            if !diff.is_empty() || own_sky.is_some() {
                src.clear();
                src.resize(r, 0.0);
                let sun = &self.response.sun[b * r..(b + 1) * r];
                for &(k, d) in &diff {
                    src[k] = d * sun[k];
                }
                if own_sky.is_some() {
                    src.iter_mut().zip(&ds_sky).for_each(|(o, x)| *o += x);
                }
                dt += self.second_order(b, &src, &mut delta);
            }
            out.push(HitState {
                dt_k: dt,
                sun_fraction: match st[r - 1] {
                    LIT => 1.0,
                    SHADED => 0.0,
                    _ => s(self.records[r - 1]),
                },
                sky: own_sky,
            });
        }
    }
}

/// `out += c·excess` per record (W m⁻²): a face's background source with
/// `c = ±ε(1 − F)σ` ([`PerHit::background_excess`]); nothing with an empty
/// excess.
fn add_background(out: &mut [f32], c: f32, excess: &[f32]) {
    for (o, e) in out.iter_mut().zip(excess) {
        *o += c * e;
    }
}
