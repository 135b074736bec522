//! The spectral reference pipeline: per ray, the spectral radiance on every
//! band's grid, with secondary rays for specular reflection and
//! transmission.

use super::Shader;
use super::hit::{ANGLE_ROWS, HitStates};
use super::sources::SunRays;
use super::surface::hit_temperature;
use crate::radiometry::{SurfaceInputs, leaving_radiance};
use crate::render::per_hit::HitState;
use crate::trace::{Coherence, Hit, Ray};

impl Shader<'_> {
    /// [`Shader::shade`] for primary rays (unit directions, from the
    /// sensor): the radiance at the sensor, `L·τ₂ + L_u` over the slant
    /// range of each hit.
    pub fn shade_primary(&self, rays: &[Ray], hits: &[Option<Hit>], out: &mut [f64]) {
        self.shade(rays, hits, 0, out);
        let Some(p) = &self.path else { return };
        let n = self.total;
        for (i, (ray, hit)) in rays.iter().zip(hits).enumerate() {
            let Some(h) = hit else { continue };
            let range = (h.t * ray.dir.length()) as f64;
            let z = (ray.origin.z + ray.dir.z * h.t) as f64;
            let cos_theta = p.cos_theta(ray.dir.as_dvec3().to_array());
            for (b, t) in self.bands.iter().enumerate() {
                let s = &mut out[i * n + t.start..i * n + t.start + t.band.len()];
                p.apply(b, range, z, cos_theta, s);
            }
        }
    }

    /// Spectral radiance arriving along each ray (misses see the sky or the
    /// ground beyond), written to `out` (`rays.len() × spectrum_len()`).
    /// `depth` is the number of bounces already taken.
    pub fn shade(&self, rays: &[Ray], hits: &[Option<Hit>], depth: u32, out: &mut [f64]) {
        self.shade_after(rays, hits, depth, &[], out);
    }

    /// [`Shader::shade`] for rays that have already travelled
    /// `travelled[i]` metres from the sensor to their origin (empty: none,
    /// primary rays): a hit seen through a reflection or a transmission
    /// measures its pixel footprint over the whole path from the sensor,
    /// for the per-hit rule ([`crate::render::per_hit::PerHit::wants`]).
    fn shade_after(
        &self,
        rays: &[Ray],
        hits: &[Option<Hit>],
        depth: u32,
        travelled: &[f32],
        out: &mut [f64],
    ) {
        let n = self.total;
        debug_assert_eq!(out.len(), rays.len() * n);
        // Secondary rays: (parent, is_transmission).
        let mut sec_rays = Vec::new();
        let mut sec_parent = Vec::new();
        if depth < self.options.max_bounces {
            for (i, (ray, hit)) in rays.iter().zip(hits).enumerate() {
                let Some(h) = hit else { continue };
                let m =
                    &self.optics.materials[self.optics.facet_material[self.facet_of(h)] as usize];
                if m.specular_fraction <= 0.0 && m.transmissivity <= 0.0 {
                    continue;
                }
                let (p, nrm, d) = self.hit_frame(ray, h);
                if m.specular_fraction > 0.0 {
                    let r = d - 2.0 * d.dot(nrm) * nrm;
                    sec_rays.push(Ray::new(p + nrm * self.options.offset_m, r));
                    sec_parent.push((i, false));
                }
                if m.transmissivity > 0.0 {
                    sec_rays.push(Ray::new(p - nrm * self.options.offset_m, d));
                    sec_parent.push((i, true));
                }
            }
        }
        let mut sec_spec = Vec::new();
        if !sec_rays.is_empty() {
            let mut sec_hits = vec![None; sec_rays.len()];
            self.tracer
                .intersect(&sec_rays, Coherence::Incoherent, &mut sec_hits);
            // The path from the sensor to each secondary ray's origin.
            let sec_travelled: Vec<f32> = sec_parent
                .iter()
                .map(|&(i, _)| {
                    let before = travelled.get(i).copied().unwrap_or(0.0);
                    before + hits[i].as_ref().map_or(0.0, |h| h.t * rays[i].dir.length())
                })
                .collect();
            sec_spec = vec![0.0; sec_rays.len() * n];
            self.shade_after(
                &sec_rays,
                &sec_hits,
                depth + 1,
                &sec_travelled,
                &mut sec_spec,
            );
        }
        // Index of each ray's reflected / transmitted spectrum.
        let mut refl = vec![usize::MAX; rays.len()];
        let mut trans = vec![usize::MAX; rays.len()];
        for (k, &(i, is_t)) in sec_parent.iter().enumerate() {
            if is_t {
                trans[i] = k;
            } else {
                refl[i] = k;
            }
        }
        // The hits' per-hit states, all traced in one call (own sky views
        // for the hits seen directly), then their shadow rays.
        let mut states = HitStates::default();
        self.per_hit_states_of(
            rays,
            hits,
            0..rays.len(),
            depth == 0,
            travelled,
            &mut states,
        );
        let mut sun = SunRays::default();
        self.sun_visibility(rays, hits, |i| states.has(i), &mut sun);
        let mut scratch = LeavingScratch::new(n);
        for (i, (ray, hit)) in rays.iter().zip(hits).enumerate() {
            let o = &mut out[i * n..(i + 1) * n];
            let Some(h) = hit else {
                self.miss_into(ray.dir, o);
                continue;
            };
            let spec_in =
                (refl[i] != usize::MAX).then(|| &sec_spec[refl[i] * n..(refl[i] + 1) * n]);
            let behind =
                (trans[i] != usize::MAX).then(|| &sec_spec[trans[i] * n..(trans[i] + 1) * n]);
            let lit = sun.of(i);
            let state = states.of(i);
            self.leaving_into(ray, h, state, lit, spec_in, behind, &mut scratch, o);
        }
    }

    /// The spectral radiance leaving hit `h` toward the origin of `ray`:
    /// the stages' inputs at the hit (surface terms, sources) handed to the
    /// reference big equation, [`crate::radiometry::leaving_radiance`],
    /// band by band; `state` the hit's per-hit state where it has one
    /// ([`Shader::per_hit_states_of`]), `vis` its own sun visibility where
    /// it traced a shadow ray.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn leaving_into(
        &self,
        ray: &Ray,
        h: &Hit,
        state: Option<HitState>,
        vis: Option<f32>,
        spec_in: Option<&[f64]>,
        behind: Option<&[f64]>,
        sc: &mut LeavingScratch,
        out: &mut [f64],
    ) {
        let f = self.facet_of(h);
        let s = &self.conditions.surface;
        let mi = self.optics.facet_material[f] as usize;
        let m = &self.optics.materials[mi];
        let (_, nrm, d) = self.hit_frame(ray, h);
        let cos_view = (-d.dot(nrm)).clamp(0.0, 1.0) as f64;
        let theta = cos_view.acos().to_degrees();
        let a0 = (theta.floor() as usize).min(ANGLE_ROWS - 2);
        let ta = theta - a0 as f64;
        let (t_hit, sun_fraction) = hit_temperature(s, f, state);
        let sun_fraction = vis.unwrap_or(sun_fraction);
        // The glint lobe toward the viewer: the hit's own visibility (a
        // specular facet always traces it while the sun faces it).
        let glint = match (self.sun_dir, vis) {
            (Some(sd), Some(v)) if self.glint_m2[mi] > 0.0 && v > 0.0 => {
                crate::render::glint::glint_lobe_sr(self.glint_m2[mi], nrm, -d, sd)
            }
            _ => 0.0,
        };
        self.planck_into(t_hit, &mut sc.b_t);
        let (shape_factor, background_k, tilt) = self.seen_sky(f, h.ng, d, state);
        self.planck_into(background_k as f64, &mut sc.b_bg);
        let (kb, wb) = super::tilt_at(tilt);
        let wb = wb as f64;
        // The sun only lights the face it falls on: for a single-sided facet
        // seen from behind, cos σ of the front face does not apply, nor for
        // a double-sided facet's face turned from the sun.
        let cos_sun = if self.seen_face_lit(mi, h.ng, d) {
            (s.cos_sun[f] as f64).max(0.0) * (sun_fraction as f64).clamp(0.0, 1.0)
        } else {
            0.0
        };
        for t in &self.bands {
            let (nl, k) = (t.band.len(), t.start);
            // ε(λ, θ): linear between the 1° angle rows.
            let e = &t.eps[mi];
            let (e0, e1) = (&e[a0 * nl..(a0 + 1) * nl], &e[(a0 + 1) * nl..(a0 + 2) * nl]);
            let eps = &mut sc.eps[..nl];
            for ((x, &a), &b) in eps.iter_mut().zip(e0).zip(e1) {
                *x = a + ta * (b - a);
            }
            // L_eq(λ, β): linear between the tilt nodes.
            let sky = &mut sc.sky[..nl];
            for ((x, &a), &b) in sky.iter_mut().zip(&t.sky_tilt[kb]).zip(&t.sky_tilt[kb + 1]) {
                *x = a + wb * (b - a);
            }
            let inputs = SurfaceInputs {
                blackbody: &sc.b_t[k..k + nl],
                emissivity: eps,
                specular_fraction: m.specular_fraction,
                transmissivity: m.transmissivity,
                shape_factor: shape_factor as f64,
                sky_radiance: &sc.sky[..nl],
                background_radiance: &sc.b_bg[k..k + nl],
                solar_irradiance: Some(&t.sun),
                cos_sun,
                glint_sr: glint,
                specular_radiance: spec_in.map(|v| &v[k..k + nl]),
                transmitted_radiance: behind.map(|v| &v[k..k + nl]),
            };
            leaving_radiance(&inputs, &mut out[k..k + nl]);
        }
    }
}

/// Working spectra of [`Shader::leaving_into`], reused from hit to hit.
pub(super) struct LeavingScratch {
    /// B(λ, T) of the surface, all bands.
    b_t: Vec<f64>,
    /// B(λ, T_bg) of the background, all bands.
    b_bg: Vec<f64>,
    /// ε(λ, θ) of one band.
    eps: Vec<f64>,
    /// The reflected sky L_eq(λ, β) of one band.
    sky: Vec<f64>,
}

impl LeavingScratch {
    /// Scratch for spectra of `n` values (all bands).
    pub(super) fn new(n: usize) -> Self {
        LeavingScratch {
            b_t: vec![0.0; n],
            b_bg: vec![0.0; n],
            eps: vec![0.0; n],
            sky: vec![0.0; n],
        }
    }
}
