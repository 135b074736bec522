//! Shortwave reflected between facets: the diffuse (Lambertian) reflection
//! of direct and diffuse sunlight from the facets and the ground that each
//! facet's hemisphere rays hit, over the background lists of the sky view.
//!
//! # Model
//! Every surface reflects diffusely with albedo `ρ` (for an opaque
//! material `1 − α`, α its solar absorptivity). The irradiance of facet `i`
//! is its own sky and sun irradiance plus what it receives from the
//! surfaces it sees (radiosity; Modest, *Radiative Heat Transfer*, 3rd ed.,
//! 2013, ch. 5–6; the view factors are those of the traced background,
//! `F_ij` = [`BackgroundEntry::weight`]):
//!
//! `E_i = E⁰_i + R_i`, `R_i = Σ_j F_ij ρ_j E_j + g_i ρ_g E_ground`
//!
//! with `E⁰_i = E_dn s_i max(cos θ_i, 0) + F_i E_d` (direct-normal `E_dn`,
//! sunlit fraction `s`, incidence `θ`, sky view `F`, diffuse-horizontal
//! `E_d`), `g_i` the view factor to the ground beyond the scene (open and
//! sunlit: `E_ground = E_dn max(sin h, 0) + E_d`, `h` the sun's elevation;
//! it receives nothing back from the scene) and `ρ_g` its albedo. Both
//! sources scale with `E_dn` and `E_d`, so each facet's reflected
//! irradiance is
//!
//! `R_i(t) = E_dn(t) · a_i(t) + E_d(t) · b_i`
//!
//! with a dimensionless per-record history `a_i` (direct) and a constant
//! `b_i` (diffuse), computed here from geometry and albedo alone, before
//! the weather is known. `N` bounces iterate `R⁽ᵏ⁾_i = Σ_j F_ij ρ_j (E⁰_j +
//! R⁽ᵏ⁻¹⁾_j) + g_i ρ_g E_ground` from `R⁽⁰⁾ = 0` (Jacobi): one bounce is the
//! first term; the series converges geometrically (ratio `≲ max ρ·(1 − F)`).
//! On the bundled town two bounces are within 0.10 K (mean) of ten on the
//! walls, whose reflected-shortwave warming is 2.5 K at noon
//! (`docs/physics/reflected-and-wind.md`).
//!
//! Cost: one sparse product over the background entries per daytime record
//! for the first bounce (`entries × day records` multiply-adds); the later
//! bounces, a fraction of the first and smooth in time, at every
//! [`LATER_BOUNCE_STRIDE`]-th daytime record, their addition linear in
//! between ([`reflected_shortwave_strided`]; in a street canyon with the
//! sun sweeping over it within 4 % of what the later bounces add,
//! `docs/physics/reflected-and-wind.md`).
//!
//! # Approximations
//! - Lambertian reflection (no specular glint from glass or water).
//! - A double-sided facet's background is the mean over its faces (as
//!   [`super::SkyView`] stores it); what it reflects is its lit face's
//!   irradiance.
//!
//! # What it owns, takes and gives
//! Owns the reflected-shortwave coefficients. Takes the [`SkyView`], the
//! [`SolarHistory`], per-facet albedos and the sun's directions (plain
//! arrays); gives [`ReflectedShortwave`]. Knows no materials (the caller
//! turns them into albedos) and no weather.

use glam::Vec3;
use rayon::prelude::*;

use super::{SkyView, SolarHistory};
use crate::{Error, Result};

/// Default albedo of the ground beyond the modelled scene (and the ground a
/// free-standing facet sees): 0.2, the conventional value for grass and
/// mixed ground (Duffie & Beckman, *Solar Engineering of Thermal
/// Processes*, 4th ed., 2013, §2.16 and Table 2.16.1).
pub const GROUND_ALBEDO: f32 = 0.2;

/// Default bounces of [`reflected_shortwave`] (2: on the bundled town
/// within 0.10 K mean, 0.20 K RMS of ten bounces on the walls at noon).
pub const BOUNCES: u32 = 2;

/// The reflected shortwave of every facet, per unit of the weather's
/// irradiances (module docs): `R_i(t) = E_dn(t) a_i(t) + E_d(t) b_i`, W m⁻².
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReflectedShortwave {
    /// Records per facet, `R`.
    pub records: usize,
    /// `a_i(t)`: reflected irradiance per unit direct-normal irradiance,
    /// facet-major `[facet·R + record]` (dimensionless).
    pub direct: Vec<f32>,
    /// `b_i`: reflected irradiance per unit diffuse-horizontal irradiance,
    /// per facet (dimensionless).
    pub diffuse: Vec<f32>,
}

impl ReflectedShortwave {
    /// Number of facets.
    pub fn facet_count(&self) -> usize {
        self.diffuse.len()
    }

    /// `a_i` of `facet` at every record.
    pub fn direct(&self, facet: usize) -> &[f32] {
        &self.direct[facet * self.records..(facet + 1) * self.records]
    }

    /// Reflected irradiance of `facet` at `record`, W m⁻², for the
    /// direct-normal and diffuse-horizontal irradiances there.
    pub fn irradiance_w_m2(
        &self,
        facet: usize,
        record: usize,
        direct_normal_w_m2: f64,
        diffuse_horizontal_w_m2: f64,
    ) -> f64 {
        direct_normal_w_m2 * self.direct[facet * self.records + record] as f64
            + diffuse_horizontal_w_m2 * self.diffuse[facet] as f64
    }
}

/// Day records between the nodes at which the bounces after the first are
/// computed ([`reflected_shortwave_strided`]): 4, hourly at 15-min records.
pub const LATER_BOUNCE_STRIDE: usize = 4;

/// The reflected shortwave of every facet (module docs) after `bounces`
/// bounces (0: none, all zeros). `albedo` has one value per facet (0 for
/// facets that reflect nothing, e.g. fixed-temperature ones without a
/// material); `sun_dirs` one unit vector per record (as the solar history
/// was traced with).
///
/// The first bounce is computed at every daytime record, the later ones at
/// every [`LATER_BOUNCE_STRIDE`]-th ([`reflected_shortwave_strided`]).
///
/// # Errors
/// [`Error::Invalid`] for lengths that do not match the sky view and solar
/// history, or an albedo outside `[0, 1]`.
pub fn reflected_shortwave(
    sky: &SkyView,
    solar: &SolarHistory,
    albedo: &[f32],
    ground_albedo: f32,
    sun_dirs: &[Vec3],
    bounces: u32,
) -> Result<ReflectedShortwave> {
    reflected_shortwave_strided(
        sky,
        solar,
        albedo,
        ground_albedo,
        sun_dirs,
        bounces,
        LATER_BOUNCE_STRIDE,
    )
}

/// [`reflected_shortwave`] with the bounces after the first at every
/// `stride`-th daytime record only (and the first and last of each run of
/// daytime records): there the Jacobi iteration is exact; between them the
/// later bounces' addition to the first, `R⁽ᴺ⁾ − R⁽¹⁾`, is linear in time,
/// while the first bounce, which carries the neighbours' own shadow edges,
/// stays exact at every record. The later bounces are a fraction
/// `≲ ρ(1 − F)` of the first and smooth in time (each sums the first bounce
/// of many neighbours), and they cost a `stride`-th. `stride` 1 is every
/// record: the plain iteration (module docs), the reference.
///
/// # Errors
/// As [`reflected_shortwave`].
pub fn reflected_shortwave_strided(
    sky: &SkyView,
    solar: &SolarHistory,
    albedo: &[f32],
    ground_albedo: f32,
    sun_dirs: &[Vec3],
    bounces: u32,
    stride: usize,
) -> Result<ReflectedShortwave> {
    let n = sky.facet_count();
    let r = solar.steps;
    if solar.facet_count() != n || albedo.len() != n || sun_dirs.len() != r {
        return Err(Error::invalid(
            "reflected shortwave",
            format!(
                "expected {n} facets of sky view, solar history and albedo and {r} sun \
                 directions, got {}, {} and {}",
                solar.facet_count(),
                albedo.len(),
                sun_dirs.len()
            ),
        ));
    }
    if let Some((i, a)) = albedo
        .iter()
        .chain([&ground_albedo])
        .enumerate()
        .find(|(_, a)| !(0.0..=1.0).contains(*a))
    {
        return Err(Error::invalid(
            if i == n {
                "ground_albedo".to_string()
            } else {
                format!("albedo[{i}]")
            },
            format!("expected a fraction in [0, 1], got {a}"),
        ));
    }
    let mut out = ReflectedShortwave {
        records: r,
        direct: vec![0.0; n * r],
        diffuse: vec![0.0; n],
    };
    if bounces == 0 || n == 0 {
        return Ok(out);
    }
    // Daytime records (the only ones with direct sunlight).
    let day: Vec<usize> = (0..r).filter(|&k| sun_dirs[k].z > 0.0).collect();
    let ground_direct: Vec<f32> = day.iter().map(|&k| sun_dirs[k].z).collect();
    let nd = day.len();
    // E⁰ per unit E_dn on the day records, facet-major `[f·nd + d]`, and
    // per unit E_d.
    let e0_diffuse: Vec<f32> = (0..n).map(|f| sky.mean_shape_factor(f)).collect();
    if nd == 0 {
        // No daytime record: only the diffuse coefficient.
        let mut refl_diffuse = vec![0.0f32; n];
        for _ in 0..bounces {
            let leaving: Vec<f32> = (0..n)
                .map(|j| albedo[j] * (e0_diffuse[j] + refl_diffuse[j]))
                .collect();
            refl_diffuse = diffuse_bounce(sky, ground_albedo, &leaving);
        }
        out.diffuse = refl_diffuse;
        return Ok(out);
    }
    // E⁰ per unit E_dn on the day records, facet-major `[f·nd + d]`.
    let mut e0_direct = vec![0.0f32; n * nd];
    e0_direct.par_chunks_mut(nd).enumerate().for_each(|(f, e)| {
        let (s, c) = (solar.sun_fraction(f), solar.cos_incidence(f));
        for (e, &k) in e.iter_mut().zip(&day) {
            *e = s[k].clamp(0.0, 1.0) * c[k].max(0.0);
        }
    });
    let mut refl_diffuse = vec![0.0f32; n];
    for _ in 0..bounces {
        let leaving_diffuse: Vec<f32> = e0_diffuse
            .iter()
            .zip(&refl_diffuse)
            .zip(albedo)
            .map(|((e, rr), a)| a * (e + rr))
            .collect();
        refl_diffuse = diffuse_bounce(sky, ground_albedo, &leaving_diffuse);
    }
    // The first bounce at every day record: ρ_j E⁰_j per unit E_dn leaves
    // each facet.
    let mut refl_direct = vec![0.0f32; n * nd];
    let mut scratch = (Vec::new(), Vec::new());
    let surfaces = Surfaces {
        sky,
        ground_albedo,
        albedo,
    };
    direct_bounce(
        surfaces,
        &ground_direct,
        &e0_direct,
        None,
        &mut refl_direct,
        &mut scratch,
    );
    let stride = stride.max(1);
    if bounces > 1 && stride == 1 {
        // The reference: every bounce at every day record.
        let mut next = vec![0.0f32; n * nd];
        for _ in 1..bounces {
            direct_bounce(
                surfaces,
                &ground_direct,
                &e0_direct,
                Some(&refl_direct),
                &mut next,
                &mut scratch,
            );
            std::mem::swap(&mut refl_direct, &mut next);
        }
    } else if bounces > 1 {
        // The later bounces at the nodes, their addition to the first
        // linear in between.
        let nodes: Vec<usize> = (0..nd)
            .filter(|&d| {
                d % stride == 0
                    || d + 1 == nd
                    || day[d + 1] != day[d] + 1
                    || (d > 0 && day[d - 1] + 1 != day[d])
            })
            .collect();
        let nc = nodes.len();
        let at_nodes = |v: &[f32]| -> Vec<f32> {
            let mut o = vec![0.0f32; n * nc];
            o.par_chunks_mut(nc)
                .zip(v.par_chunks(nd))
                .for_each(|(o, v)| o.iter_mut().zip(&nodes).for_each(|(o, &d)| *o = v[d]));
            o
        };
        let (e0_c, first_c) = (at_nodes(&e0_direct), at_nodes(&refl_direct));
        let ground_c: Vec<f32> = nodes.iter().map(|&d| ground_direct[d]).collect();
        let mut cur = first_c.clone();
        let mut next = vec![0.0f32; n * nc];
        for _ in 1..bounces {
            direct_bounce(
                surfaces,
                &ground_c,
                &e0_c,
                Some(&cur),
                &mut next,
                &mut scratch,
            );
            std::mem::swap(&mut cur, &mut next);
        }
        // Free what the bounces needed before the last steps touch new pages
        // (these temporaries set the peak memory of a large scene).
        drop((next, e0_c, e0_direct));
        // R⁽ᴺ⁾ = R⁽¹⁾ + the later bounces' addition, linear between nodes.
        refl_direct
            .par_chunks_mut(nd)
            .zip(cur.par_chunks(nc).zip(first_c.par_chunks(nc)))
            .for_each(|(o, (last, first))| {
                let add = |c: usize| last[c] - first[c];
                for c in 0..nc {
                    o[nodes[c]] = last[c];
                    if c + 1 < nc {
                        let (a, b) = (nodes[c], nodes[c + 1]);
                        for (d, v) in o.iter_mut().enumerate().take(b).skip(a + 1) {
                            let t = (d - a) as f32 / (b - a) as f32;
                            *v += add(c) + t * (add(c + 1) - add(c));
                        }
                    }
                }
            });
    }
    out.direct
        .par_chunks_mut(r)
        .zip(refl_direct.par_chunks(nd))
        .for_each(|(o, rd)| {
            for (&v, &k) in rd.iter().zip(&day) {
                o[k] = v;
            }
        });
    out.diffuse = refl_diffuse;
    Ok(out)
}

/// What reflects: the sky view's background lists, the ground's albedo
/// beyond the scene and each facet's.
#[derive(Clone, Copy)]
struct Surfaces<'a> {
    sky: &'a SkyView,
    ground_albedo: f32,
    albedo: &'a [f32],
}

/// One bounce of the direct coefficient at the day records of `e0`
/// (`m` per facet, facet-major): `out_i = g_i ρ_g z + Σ_j F_ij ρ_j (E⁰_j +
/// R_j)` with `R` = `refl` the previous bounce's (`None`: the first
/// bounce, `R = 0`) and `z` = `ground_direct`
/// (the sine of the sun's elevation) at those records. Sources that send
/// nothing (no albedo, never lit) are skipped: adding their zeros changes
/// nothing. `scratch` holds the leaving irradiances between calls.
fn direct_bounce(
    surfaces: Surfaces,
    ground_direct: &[f32],
    e0: &[f32],
    refl: Option<&[f32]>,
    out: &mut [f32],
    scratch: &mut (Vec<f32>, Vec<bool>),
) {
    let Surfaces {
        sky,
        ground_albedo,
        albedo,
    } = surfaces;
    let m = ground_direct.len();
    let n = albedo.len();
    // ρ_j (E⁰_j + R_j), and whether any of it is not zero.
    let (leaving, lit) = scratch;
    leaving.resize(n * m, 0.0);
    lit.resize(n, false);
    leaving
        .par_chunks_mut(m)
        .zip(lit.par_iter_mut())
        .zip(e0.par_chunks(m))
        .zip(albedo.par_iter())
        .enumerate()
        .for_each(|(j, (((l, lit), e), &a))| {
            match refl {
                Some(refl) => {
                    let rr = &refl[j * m..(j + 1) * m];
                    for ((l, e), rr) in l.iter_mut().zip(e).zip(rr) {
                        *l = a * (e + rr);
                    }
                }
                None => l.iter_mut().zip(e).for_each(|(l, e)| *l = a * e),
            }
            *lit = l.iter().any(|&x| x != 0.0);
        });
    out.par_chunks_mut(m).enumerate().for_each(|(i, out)| {
        let g = sky.ground_weight[i] * ground_albedo;
        let entries = sky.background(i);
        crate::simd::vectorized(GatherBounce {
            out,
            g,
            z: ground_direct,
            entries,
            leaving,
            lit,
        })
    });
}

crate::simd::simd_kernel!(GatherBounce<'a> {
    out: &'a mut [f32],
    g: f32,
    z: &'a [f32],
    entries: &'a [super::BackgroundEntry],
    leaving: &'a [f32],
    lit: &'a [bool],
} -> () => gather_bounce);

/// `out = g·z + Σ_e w_e l_{j_e}` over the background entries whose source
/// is lit, `l_j` the `j`-th row (`out.len()` long) of `leaving`.
#[inline(always)]
fn gather_bounce(
    out: &mut [f32],
    g: f32,
    z: &[f32],
    entries: &[super::BackgroundEntry],
    leaving: &[f32],
    lit: &[bool],
) {
    let m = out.len();
    out.iter_mut().zip(z).for_each(|(o, z)| *o = g * z);
    for e in entries {
        let j = e.facet as usize;
        if !lit[j] {
            continue;
        }
        let src = &leaving[j * m..(j + 1) * m];
        out.iter_mut()
            .zip(src)
            .for_each(|(o, l)| *o += e.weight * l);
    }
}

/// One bounce of the diffuse coefficient: `Σ_j F_ij ρ_j E_j + g_i ρ_g` for
/// each facet `i`, given `leaving[j] = ρ_j E_j` per unit `E_d`.
fn diffuse_bounce(sky: &SkyView, ground_albedo: f32, leaving: &[f32]) -> Vec<f32> {
    (0..leaving.len())
        .into_par_iter()
        .map(|i| {
            sky.ground_weight[i] * ground_albedo
                + sky
                    .background(i)
                    .iter()
                    .map(|e| e.weight * leaving[e.facet as usize])
                    .sum::<f32>()
        })
        .collect()
}
