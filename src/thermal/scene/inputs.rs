//! The per-facet inputs of the scene solve: what the ray tracer found for
//! every facet, borrowed as plain arrays.
//!
//! Owns [`SceneInputs`] and the rules that read it (a facet's histories,
//! its mean shape factor, its background entries). Takes nothing but
//! slices; it does not know who traced them (in irsig the exposure
//! module, whose `Exposure` converts into it in
//! [`crate::render::scene_thermal`]).

use glam::Vec3;

use crate::geometry::BackgroundEntry;
use crate::thermal::Reflected;
use crate::thermal::wind::FacetWind;
use crate::{Error, Result};

/// Where the scene solve reads each facet's solar history: sunlit fraction
/// and cosine of incidence per record. The exposure stores it compactly and
/// decodes one facet at a time (`crate::render::scene_thermal` implements
/// this for it); [`SolarArrays`] serves plain per-record arrays.
pub trait SolarSource: Sync + std::fmt::Debug {
    /// Records per facet.
    fn records(&self) -> usize;
    /// Facets.
    fn facets(&self) -> usize;
    /// Writes the sunlit fraction ∈ [0, 1] of `facet` at every record into
    /// `out` (`records()` values).
    fn sun_fraction_into(&self, facet: usize, out: &mut [f32]);
    /// Writes the cosine of the solar incidence angle of `facet` at every
    /// record into `out` (0 at night or behind a single-sided facet; `|n·s|`
    /// for a double-sided one).
    fn cos_incidence_into(&self, facet: usize, out: &mut [f32]);
    /// Writes `clamp(s, 0, 1)·max(cos θ, 0)` of `facet` at every record
    /// into `out` (`records()` values): the direct sunlight per unit
    /// direct-normal irradiance that the linearised solve reads. The default
    /// forms it from the two histories above; a compact history may write
    /// it directly (the same values, bit for bit).
    fn sunlit_cos_into(&self, facet: usize, out: &mut [f32]) {
        let mut cos = vec![0.0; out.len()];
        self.sun_fraction_into(facet, out);
        self.cos_incidence_into(facet, &mut cos);
        for (o, c) in out.iter_mut().zip(&cos) {
            *o = o.clamp(0.0, 1.0) * c.max(0.0);
        }
    }
}

/// A solar history as two plain facet-major arrays, `[facet·R + record]`.
#[derive(Debug, Clone, Copy)]
pub struct SolarArrays<'a> {
    /// Records per facet, `R`.
    pub records: usize,
    /// Sunlit fraction ∈ [0, 1].
    pub sun_fraction: &'a [f32],
    /// Cosine of the solar incidence angle.
    pub cos_incidence: &'a [f32],
}

impl SolarSource for SolarArrays<'_> {
    fn records(&self) -> usize {
        self.records
    }
    /// `usize::MAX` when the two arrays differ in length (which
    /// [`SceneInputs::validate`] then refuses).
    fn facets(&self) -> usize {
        if self.sun_fraction.len() != self.cos_incidence.len() {
            return usize::MAX;
        }
        self.sun_fraction
            .len()
            .checked_div(self.records)
            .unwrap_or(0)
    }
    fn sun_fraction_into(&self, facet: usize, out: &mut [f32]) {
        out.copy_from_slice(&self.sun_fraction[facet * self.records..(facet + 1) * self.records]);
    }
    fn cos_incidence_into(&self, facet: usize, out: &mut [f32]) {
        out.copy_from_slice(&self.cos_incidence[facet * self.records..(facet + 1) * self.records]);
    }
}

/// [`SceneInputs::reflected_slot`] of a record whose reflected direct
/// coefficient is 0 (the sun down).
pub const NO_SLOT: u32 = u32::MAX;

/// The shortwave reflected onto one facet, decoded
/// ([`SceneInputs::reflected`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FacetReflected {
    /// Per unit direct-normal irradiance at each record; empty: none.
    pub direct: Vec<f32>,
    /// Per unit diffuse-horizontal irradiance.
    pub diffuse: f64,
}

impl FacetReflected {
    /// As the slab model takes it, borrowed.
    pub fn as_reflected(&self) -> Reflected<'_> {
        Reflected {
            direct: &self.direct,
            diffuse: self.diffuse,
        }
    }
}

/// The ray-traced inputs of every facet of a scene, in global facet order:
/// `n` facets, `R` records per history (one per weather record).
///
/// The view factors of a facet add up to one:
/// `F + ground_weight + Σ background.weight = 1` (for a double-sided facet
/// `(F + F_back)/2 + …`, see [`SceneInputs::mean_shape_factor`]).
#[derive(Debug, Clone, Copy)]
pub struct SceneInputs<'a> {
    /// Records per facet history, `R`.
    pub records: usize,
    /// Sunlit fraction and cosine of incidence per facet and record.
    pub solar: &'a dyn SolarSource,
    /// Unit front normal per facet (it fixes the cos θ history, so the
    /// per-class method keys on it).
    pub normal: &'a [Vec3],
    /// Whether both faces of the facet are front faces, per facet.
    pub double_sided: &'a [bool],
    /// Shape factor F (view factor to the sky) of the front face, per facet.
    pub shape_factor: &'a [f32],
    /// Shape factor of the back face of double-sided facets (`None` for
    /// single-sided ones), per facet.
    pub back_shape_factor: &'a [Option<f32>],
    /// Shape factor of the back face of single-sided facets whose slab has
    /// an exposed back ([`crate::thermal::BackBoundary::Exposed`]), traced
    /// from the back (`crate::exposure::exposed_back_shape_factors`), per
    /// facet; `None` (or an empty slice: none at all) keeps the slab
    /// model's `1 − F`, exact only for an unobstructed plane. It feeds only
    /// the exposed back's radiative exchange
    /// ([`SceneInputs::slab_back_shape_factor`]), not the facet's mean sky
    /// view ([`SceneInputs::mean_shape_factor`]).
    pub exposed_back_shape_factor: &'a [Option<f32>],
    /// View factor to the ground beyond the scene (taken at the air
    /// temperature), per facet.
    pub ground_weight: &'a [f32],
    /// Start of each facet's entries in `background`; `n + 1` entries.
    pub background_offsets: &'a [u32],
    /// The facets each facet sees, with their view factors, facet after
    /// facet.
    pub background: &'a [BackgroundEntry],
    /// Shortwave reflected onto each facet per unit direct-normal
    /// irradiance ([`crate::thermal::Reflected::direct`]) at the records
    /// that hold it (the day records: [`Self::reflected_slot`]),
    /// facet-major `[facet·K + slot]`, `K` slots per facet.
    pub reflected_direct: &'a [f32],
    /// For each record, the slot of `reflected_direct` that holds its
    /// coefficient, or [`NO_SLOT`] where it is 0 (the sun down); `R`
    /// entries, or none for no reflected shortwave.
    pub reflected_slot: &'a [u32],
    /// Shortwave reflected onto each facet per unit diffuse-horizontal
    /// irradiance, per facet ([`crate::thermal::Reflected::diffuse`]);
    /// empty: none.
    pub reflected_diffuse: &'a [f32],
    /// The reduction of the weather's wind at each facet
    /// ([`crate::thermal::wind`]); empty: the weather's wind everywhere.
    pub wind: &'a [FacetWind],
}

impl<'a> SceneInputs<'a> {
    /// Number of facets.
    pub fn facet_count(&self) -> usize {
        self.shape_factor.len()
    }

    /// Sunlit fraction of `facet` at every record (decoded for the
    /// caller: the solar history is held compactly).
    #[inline]
    pub fn sun_fraction(&self, facet: usize) -> Vec<f32> {
        let mut v = vec![0.0; self.records];
        self.solar.sun_fraction_into(facet, &mut v);
        v
    }

    /// Cosine of incidence of `facet` at every record (decoded for the
    /// caller).
    #[inline]
    pub fn cos_incidence(&self, facet: usize) -> Vec<f32> {
        let mut v = vec![0.0; self.records];
        self.solar.cos_incidence_into(facet, &mut v);
        v
    }

    /// Shape factor of the back face of `facet` when it is double-sided.
    #[inline]
    pub fn back_shape_factor(&self, facet: usize) -> Option<f32> {
        self.back_shape_factor[facet]
    }

    /// The back face's shape factor the slab model takes
    /// ([`crate::thermal::FacetInputs::back_shape_factor`]): a double-sided
    /// facet's back face, else the traced exposed back
    /// ([`SceneInputs::exposed_back_shape_factor`]), else `None` (the slab
    /// model's `1 − F`).
    #[inline]
    pub fn slab_back_shape_factor(&self, facet: usize) -> Option<f32> {
        self.back_shape_factor[facet]
            .or_else(|| self.exposed_back_shape_factor.get(facet).copied().flatten())
    }

    /// Mean sky view factor over the facet's faces: F, or `(F + F_back)/2`
    /// for a double-sided facet. `1 −` it is the view factor to the
    /// background (neighbours and ground).
    #[inline]
    pub fn mean_shape_factor(&self, facet: usize) -> f32 {
        match self.back_shape_factor(facet) {
            Some(b) => 0.5 * (self.shape_factor[facet] + b),
            None => self.shape_factor[facet],
        }
    }

    /// Slots of `reflected_direct` per facet.
    fn reflected_slots(&self) -> usize {
        self.reflected_direct
            .len()
            .checked_div(self.facet_count())
            .unwrap_or(0)
    }

    /// The shortwave reflected onto `facet` ([`crate::thermal::Reflected`]),
    /// its direct coefficient decoded at every record (0 where it has no
    /// slot; empty for none).
    pub fn reflected(&self, facet: usize) -> FacetReflected {
        let mut direct = vec![0.0; self.reflected_slot.len()];
        self.add_reflected_direct(facet, &mut direct);
        FacetReflected {
            direct,
            diffuse: self.reflected_diffuse(facet),
        }
    }

    /// The reflected shortwave's diffuse coefficient of `facet`: per unit
    /// diffuse-horizontal irradiance (0 for none); [`Self::reflected`]'s
    /// `diffuse` without decoding the direct part.
    #[inline]
    pub fn reflected_diffuse(&self, facet: usize) -> f64 {
        self.reflected_diffuse.get(facet).map_or(0.0, |&b| b as f64)
    }

    /// Adds `facet`'s reflected direct coefficient at every record to `out`
    /// (one per record): [`Self::reflected`]'s `direct` without a vector.
    #[inline]
    pub fn add_reflected_direct(&self, facet: usize, out: &mut [f32]) {
        if self.reflected_slot.is_empty() {
            return;
        }
        let k = self.reflected_slots();
        let row = &self.reflected_direct[facet * k..(facet + 1) * k];
        for (o, &s) in out.iter_mut().zip(self.reflected_slot) {
            if s != NO_SLOT {
                *o += row[s as usize];
            }
        }
    }

    /// The facets seen by `facet`, with their view factors.
    #[inline]
    pub fn background(&self, facet: usize) -> &'a [BackgroundEntry] {
        &self.background
            [self.background_offsets[facet] as usize..self.background_offsets[facet + 1] as usize]
    }

    /// Checks that every array has one entry per facet (`R` per facet for
    /// the histories) and that the background entries are in range.
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the array.
    pub fn validate(&self) -> Result<()> {
        let n = self.facet_count();
        let per_facet = [
            ("normal", self.normal.len()),
            ("double_sided", self.double_sided.len()),
            ("back_shape_factor", self.back_shape_factor.len()),
            ("ground_weight", self.ground_weight.len()),
        ];
        for (name, len) in per_facet {
            if len != n {
                return Err(Error::invalid(
                    name,
                    format!("expected one entry per facet ({n}), got {len}"),
                ));
            }
        }
        // Optional per-facet inputs: one entry per facet or none.
        for (name, len) in [
            ("wind", self.wind.len()),
            (
                "exposed_back_shape_factor",
                self.exposed_back_shape_factor.len(),
            ),
            ("reflected_diffuse", self.reflected_diffuse.len()),
        ] {
            if len != 0 && len != n {
                return Err(Error::invalid(
                    name,
                    format!("expected one entry per facet ({n}) or none, got {len}"),
                ));
            }
        }
        if let Some(i) = self.wind.iter().position(|w| {
            !(w.height.is_finite() && w.height >= 0.0 && w.canyon.is_finite() && w.canyon >= 0.0)
        }) {
            return Err(Error::invalid(
                format!("wind[{i}]"),
                format!("expected finite factors ≥ 0, got {:?}", self.wind[i]),
            ));
        }
        if let Some((i, v)) = self
            .exposed_back_shape_factor
            .iter()
            .enumerate()
            .find_map(|(i, v)| v.filter(|v| !(0.0..=1.0).contains(v)).map(|v| (i, v)))
        {
            return Err(Error::invalid(
                format!("exposed_back_shape_factor[{i}]"),
                format!("expected a fraction in [0, 1], got {v}"),
            ));
        }
        if self.solar.records() != self.records || self.solar.facets() != n {
            return Err(Error::invalid(
                "solar",
                format!(
                    "expected {} records for each of {n} facets, got {} records of {} facets",
                    self.records,
                    self.solar.records(),
                    self.solar.facets()
                ),
            ));
        }
        if !self.reflected_slot.is_empty() || !self.reflected_direct.is_empty() {
            let k = self.reflected_slots();
            if self.reflected_slot.len() != self.records || self.reflected_direct.len() != n * k {
                return Err(Error::invalid(
                    "reflected_direct",
                    format!(
                        "expected one slot per record ({}) and the same number of values for \
                         each of {n} facets, got {} slots and {} values",
                        self.records,
                        self.reflected_slot.len(),
                        self.reflected_direct.len()
                    ),
                ));
            }
            if let Some(r) = self
                .reflected_slot
                .iter()
                .position(|&s| s != NO_SLOT && s as usize >= k)
            {
                return Err(Error::invalid(
                    format!("reflected_slot[{r}]"),
                    format!(
                        "expected a slot below {k} (the values per facet) or none, got {}",
                        self.reflected_slot[r]
                    ),
                ));
            }
        }
        let offsets = self.background_offsets;
        if offsets.len() != n + 1
            || offsets.first() != Some(&0)
            || offsets.windows(2).any(|w| w[0] > w[1])
            || offsets[n] as usize != self.background.len()
        {
            return Err(Error::invalid(
                "background_offsets",
                format!(
                    "expected {} ascending offsets from 0 to the {} entries",
                    n + 1,
                    self.background.len()
                ),
            ));
        }
        // One pass over what may be millions of entries: the largest id.
        if let Some(last) = self.background.iter().map(|e| e.facet).max()
            && last as usize >= n
        {
            return Err(Error::invalid(
                "background",
                format!("facet {last} does not exist (there are {n})"),
            ));
        }
        Ok(())
    }
}
