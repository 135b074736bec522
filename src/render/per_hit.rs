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
//! facet. The background, shape factor and everything else stay the
//! facet's. Where `s_p = s_f` at every record the sum is exactly zero and
//! the hit takes the facet's temperature bit for bit.
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

use super::scene_thermal::ImageResponse;
use crate::exposure::{FacetSamples, SkyView, SolarHistory};
use crate::thermal::linear::emission_curvature;
use crate::thermal::scene::PointResponse;
use crate::trace::{Coherence, Ray, Tracer};

/// Settings of per-hit temperatures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PerHitParams {
    /// Sample spacing, in pixel footprints, above which a facet is large
    /// (default 16: on the bundled town a smaller value makes most ground hits per-hit; see docs/physics/per-hit.md).
    pub size_px: f32,
    /// Shadow rays traced at every `stride`-th record, refined where the
    /// answer changes (default 4).
    pub stride: u32,
}

impl Default for PerHitParams {
    fn default() -> Self {
        PerHitParams {
            size_px: 16.0,
            stride: 4,
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
        for b in 0..blocks {
            let o = b * resp.images * r;
            rows.extend_from_slice(&resp.sun_rows[o..o + r]);
            green_rows.extend_from_slice(&resp.rows[o..o + r]);
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
        }
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

    /// The range of temperatures the hits on a facet can take, K: each
    /// facet's `temperature_k` plus and minus the largest change its
    /// response allows (every record fully lit or shaded).
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

    /// The second-order term of a point whose `s cos θ` differs from its
    /// facet's by `diff` `(record, Δ)`, K: the curvature of the emission
    /// about the reference, `r(δ) = −εσδ²(6T² + 4Tδ + δ²)` with `δ = G·ΔS`
    /// the first-order change history, through the image row of `G` (as
    /// the scene solve's second order,
    /// [`crate::thermal::Linearization::predict`]).
    /// `delta` is scratch space (its contents on entry do not matter).
    fn second_order(&self, block: usize, diff: &[(usize, f32)], delta: &mut Vec<f32>) -> f32 {
        let p = &*self.response;
        let r = p.records;
        let g = &p.green[block * r * r..(block + 1) * r * r];
        let sun = &p.sun[block * r..(block + 1) * r];
        delta.clear();
        delta.resize(r, 0.0);
        for &(k, d) in diff {
            let x = d * sun[k];
            for (o, gk) in delta.iter_mut().zip(&g[k * r..(k + 1) * r]) {
                *o += x * gk;
            }
        }
        let t_ref = &p.reference_k[block * r..(block + 1) * r];
        let rad = p.radiative[block] as f64;
        let row = &self.green_rows[block * r..(block + 1) * r];
        let mut x = 0.0f64;
        for t in 0..r {
            if delta[t] != 0.0 {
                x += row[t] as f64 * emission_curvature(rad, t_ref[t] as f64, delta[t] as f64);
            }
        }
        x as f32
    }

    /// The states of hits `(facet, point)` (points on the facets' planes)
    /// into `out`, one per hit, tracing their shadow rays with `tracer`.
    pub fn states(&self, tracer: &dyn Tracer, hits: &[(u32, Vec3)], out: &mut Vec<HitState>) {
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
        // Scratch of the per-hit loop: (record, Δ(s cos θ)) where the
        // point's history differs, and the second order's change history.
        let mut diff: Vec<(usize, f32)> = Vec::new();
        let mut delta: Vec<f32> = Vec::new();
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
            if !diff.is_empty() {
                dt += self.second_order(b, &diff, &mut delta);
            }
            out.push(HitState {
                dt_k: dt,
                sun_fraction: match st[r - 1] {
                    LIT => 1.0,
                    SHADED => 0.0,
                    _ => s(self.records[r - 1]),
                },
            });
        }
    }
}
