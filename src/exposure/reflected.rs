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
//! Memory: the result is held on the day records only (night records are
//! exactly 0: no direct sunlight); the first bounce is written straight
//! into it; each facet's `E⁰` is recomputed from the compact solar history
//! where a bounce needs it (never held per record); the leaving
//! irradiances `ρ_j (E⁰_j + R_j)` are held for one block of [`BLOCK`]
//! records at a time, so a bounce's transient is 128 bytes per facet; the
//! later bounces hold one value per facet and node (two from the third
//! bounce on). The values are those of the plain per-record iteration bit
//! for bit (`tests/exposure.rs`).
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
///
/// The direct coefficient `a_i` is held on the **day records** only (the
/// sun above the horizon, the same records for every facet, as the
/// [`SolarHistory`] holds its lit counts): at night there is no direct
/// sunlight to reflect, so `a_i` is exactly 0 there (the diffuse term
/// `E_d(t) b_i` follows the weather's diffuse irradiance, itself 0 at
/// night, through the constant `b_i`). Memory: 4 bytes per facet and day
/// record (≈ 250 at 62 day records) instead of 4 per record.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReflectedShortwave {
    /// Records per facet, `R`.
    pub records: usize,
    /// The records with the sun above the horizon (`z > 0`), ascending.
    pub day: Vec<u32>,
    /// For each record, its index in [`Self::day`], or [`NIGHT`] when the
    /// sun is down (`R` entries).
    pub slot: Vec<u32>,
    /// `a_i` at the day records: reflected irradiance per unit
    /// direct-normal irradiance, facet-major `[facet·day.len() + d]`
    /// (dimensionless).
    pub direct: Vec<f32>,
    /// `b_i`: reflected irradiance per unit diffuse-horizontal irradiance,
    /// per facet (dimensionless).
    pub diffuse: Vec<f32>,
}

/// [`ReflectedShortwave::slot`] of a record with the sun down.
pub const NIGHT: u32 = u32::MAX;

impl ReflectedShortwave {
    /// All zeros for `facets` facets over the records of `sun_dirs` (unit
    /// vectors toward the sun, one per record).
    pub fn zeros(facets: usize, sun_dirs: &[Vec3]) -> ReflectedShortwave {
        let day = super::solar::day_records(sun_dirs);
        let mut slot = vec![NIGHT; sun_dirs.len()];
        for (d, &k) in day.iter().enumerate() {
            slot[k as usize] = d as u32;
        }
        ReflectedShortwave {
            records: sun_dirs.len(),
            direct: vec![0.0; facets * day.len()],
            day,
            slot,
            diffuse: vec![0.0; facets],
        }
    }

    /// Number of facets.
    pub fn facet_count(&self) -> usize {
        self.diffuse.len()
    }

    /// `a_i` of `facet` at the day records ([`Self::day`]), as held.
    pub fn direct_day(&self, facet: usize) -> &[f32] {
        let nd = self.day.len();
        &self.direct[facet * nd..(facet + 1) * nd]
    }

    /// Writes `a_i` of `facet` at every record into `out` (`records`
    /// values; 0 at night).
    pub fn direct_into(&self, facet: usize, out: &mut [f32]) {
        let row = self.direct_day(facet);
        for (o, &s) in out.iter_mut().zip(&self.slot) {
            *o = if s == NIGHT { 0.0 } else { row[s as usize] };
        }
    }

    /// `a_i` of `facet` at every record (decoded).
    pub fn direct(&self, facet: usize) -> Vec<f32> {
        let mut v = vec![0.0; self.records];
        self.direct_into(facet, &mut v);
        v
    }

    /// `a_i` of `facet` at `record`.
    #[inline]
    pub fn direct_at(&self, facet: usize, record: usize) -> f32 {
        match self.slot[record] {
            NIGHT => 0.0,
            d => self.direct[facet * self.day.len() + d as usize],
        }
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
        direct_normal_w_m2 * self.direct_at(facet, record) as f64
            + diffuse_horizontal_w_m2 * self.diffuse[facet] as f64
    }

    /// Heap bytes held.
    pub fn heap_bytes(&self) -> usize {
        4 * (self.day.capacity()
            + self.slot.capacity()
            + self.direct.capacity()
            + self.diffuse.capacity())
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
    let mut out = ReflectedShortwave::zeros(n, sun_dirs);
    if bounces == 0 || n == 0 {
        return Ok(out);
    }
    // E⁰ per unit E_d.
    let e0_diffuse: Vec<f32> = (0..n).map(|f| sky.mean_shape_factor(f)).collect();
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
    out.diffuse = refl_diffuse;
    let nd = out.day.len();
    if nd == 0 {
        // No daytime record: only the diffuse coefficient.
        return Ok(out);
    }
    let surfaces = Surfaces {
        sky,
        solar,
        ground_albedo,
        albedo,
        sun_dirs,
        solar_day: out
            .day
            .iter()
            .map(|&k| solar.day.binary_search(&k).ok())
            .collect(),
        reflects: reflecting(sky, albedo),
    };
    // The first bounce at every day record, written straight into the
    // output: ρ_j E⁰_j per unit E_dn leaves each facet.
    let all: Vec<usize> = (0..nd).collect();
    let mut scratch = Scratch::default();
    direct_bounce(
        &surfaces,
        &out.day,
        &all,
        Previous::None,
        &mut out.direct,
        &mut scratch,
    );
    if bounces < 2 {
        return Ok(out);
    }
    // The later bounces at the nodes (every day record when `stride` is
    // 1: the plain iteration), their addition to the first linear in
    // between.
    let stride = stride.max(1);
    let day = &out.day;
    let nodes: Vec<usize> = (0..nd)
        .filter(|&d| {
            d % stride == 0
                || d + 1 == nd
                || day[d + 1] != day[d] + 1
                || (d > 0 && day[d - 1] + 1 != day[d])
        })
        .collect();
    let nc = nodes.len();
    let mut cur = vec![0.0f32; n * nc];
    direct_bounce(
        &surfaces,
        day,
        &nodes,
        Previous::First(&out.direct),
        &mut cur,
        &mut scratch,
    );
    if bounces > 2 {
        let mut next = vec![0.0f32; n * nc];
        for _ in 2..bounces {
            direct_bounce(
                &surfaces,
                day,
                &nodes,
                Previous::AtNodes(&cur),
                &mut next,
                &mut scratch,
            );
            std::mem::swap(&mut cur, &mut next);
        }
    }
    drop(scratch);
    // R⁽ᴺ⁾ = R⁽¹⁾ + the later bounces' addition, linear between nodes:
    // at day record `d` between nodes `a` and `b` the weight
    // `t = (d − a)/(b − a)` of the next node (the same for every facet).
    let mut weight = vec![0.0f32; nd];
    for w in nodes.windows(2) {
        let (a, b) = (w[0], w[1]);
        for (d, t) in weight.iter_mut().enumerate().take(b).skip(a + 1) {
            *t = (d - a) as f32 / (b - a) as f32;
        }
    }
    out.direct
        .par_chunks_mut(nd)
        .zip(cur.par_chunks(nc))
        .with_min_len(64)
        .for_each_init(Vec::new, |add, (o, last)| {
            add.clear();
            add.extend(nodes.iter().zip(last).map(|(&d, l)| l - o[d]));
            for c in 0..nc {
                o[nodes[c]] = last[c];
                if c + 1 < nc {
                    let (a, b) = (nodes[c], nodes[c + 1]);
                    let (lo, hi) = (add[c], add[c + 1]);
                    for (v, t) in o[a + 1..b].iter_mut().zip(&weight[a + 1..b]) {
                        *v += lo + t * (hi - lo);
                    }
                }
            }
        });
    Ok(out)
}

/// Day records per block of the bounces' gathers: the leaving irradiances
/// of every facet are held for one block of records at a time (32 `f32`,
/// two adjacent 64-byte cache lines per facet), not for every day record.
/// The gather is bound by one random read per background entry and block,
/// not by the lines it reads: 32 records per block take the town's first
/// bounce (62 day records) in two passes over the entries instead of four,
/// and its later bounce (17 nodes) in one instead of two
/// (`docs/performance.md`).
const BLOCK: usize = 2 * HALF;

/// Lanes of one accumulator of the gather ([`gather_bounce`]).
const HALF: usize = 16;

/// What reflects: the sky view's background lists, the ground's albedo
/// beyond the scene and each facet's, and the solar history from which each
/// facet's own direct irradiance `E⁰` is recomputed where it is needed.
struct Surfaces<'a> {
    sky: &'a SkyView,
    solar: &'a SolarHistory,
    ground_albedo: f32,
    albedo: &'a [f32],
    /// Unit vectors toward the sun per record (the ground's irradiance).
    sun_dirs: &'a [Vec3],
    /// Per day record of the output, its index among the solar history's
    /// day records (`None`: the history has the sun down there, so no
    /// facet is lit).
    solar_day: Vec<Option<usize>>,
    /// Per facet, whether it reflects anything to a facet: albedo > 0 and
    /// named in some facet's background. The others' leaving irradiance
    /// is never read, so it is not computed.
    reflects: Vec<bool>,
}

impl Surfaces<'_> {
    /// `E⁰` per unit `E_dn` of facet `j` at the records of `block`:
    /// `s max(cos θ, 0)`, the sunlit fraction `lit/points` from the lit
    /// count and the cosine from the normal and the sun, as
    /// [`SolarHistory::sun_fraction_into`] and
    /// [`SolarHistory::cos_incidence_into`] decode them — the same
    /// operations, lane by lane and without branches, so that they
    /// vectorise (the cosine is [`crate::geometry::sun_cosine`]'s).
    #[inline(always)]
    fn e0_block(&self, j: usize, block: &BlockSun, e: &mut [f32; BLOCK]) {
        let h = self.solar;
        let (n, double_sided) = (h.normal[j], h.double_sided[j]);
        let p = h.points as f32;
        let mut s = [0.0f32; BLOCK];
        match block.run {
            // One byte per count, the block's records consecutive in the
            // history: its counts are one run of bytes.
            Some(x0) if h.width() == 1 => {
                let row = &h.lit[j * h.day.len() + x0..][..BLOCK];
                for (s, &k) in s.iter_mut().zip(row) {
                    *s = k as f32 / p;
                }
            }
            _ => {
                for (s, &x) in s.iter_mut().zip(&block.solar_day) {
                    if x != NIGHT {
                        *s = h.lit_points(j, x as usize) as f32 / p;
                    }
                }
            }
        }
        for (i, e) in e.iter_mut().enumerate() {
            let (x, y, z) = (block.x[i], block.y[i], block.z[i]);
            let c = (n.x * x) + (n.y * y) + (n.z * z);
            let c = if z <= 0.0 {
                0.0
            } else if double_sided || c > 0.0 {
                c.abs().min(1.0)
            } else {
                0.0
            };
            *e = s[i].clamp(0.0, 1.0) * c.max(0.0);
        }
    }
}

/// The sun over a block of day records, for [`Surfaces::e0_block`];
/// lanes past the block's records have the sun down (`E⁰ = 0`).
struct BlockSun {
    /// The unit vector toward the sun per record of the block (the solar
    /// history's), by component.
    x: [f32; BLOCK],
    y: [f32; BLOCK],
    z: [f32; BLOCK],
    /// The record's index among the solar history's day records, or
    /// [`NIGHT`] where the history has the sun down (no facet lit).
    solar_day: [u32; BLOCK],
    /// `Some(x0)` when the block's [`BLOCK`] records are the history's
    /// day records `x0..x0 + BLOCK`.
    run: Option<usize>,
}

/// The facets that reflect ([`Surfaces::reflects`]).
fn reflecting(sky: &SkyView, albedo: &[f32]) -> Vec<bool> {
    use std::sync::atomic::{AtomicBool, Ordering};
    let named: Vec<AtomicBool> = albedo.iter().map(|_| AtomicBool::new(false)).collect();
    sky.entries.par_chunks(4096).for_each(|c| {
        for e in c {
            named[e.facet as usize].store(true, Ordering::Relaxed);
        }
    });
    named
        .into_iter()
        .zip(albedo)
        .map(|(n, &a)| n.into_inner() && a > 0.0)
        .collect()
}

/// The previous bounce's direct coefficient `R` that a bounce adds to
/// each facet's `E⁰`.
#[derive(Clone, Copy)]
enum Previous<'a> {
    /// None: the first bounce (`R = 0`).
    None,
    /// The first bounce at every day record (`[facet·day + d]`), read at
    /// the nodes.
    First(&'a [f32]),
    /// A later bounce at the nodes (`[facet·nodes + c]`).
    AtNodes(&'a [f32]),
}

/// A bounce's buffers, reused from block to block and bounce to bounce.
#[derive(Default)]
struct Scratch {
    /// `ρ_j (E⁰_j + R_j)` of every facet over one block of records, then
    /// one row of zeros (the "dark" row, [`gather_bounce`]).
    leaving: Vec<[f32; BLOCK]>,
    /// Whether any of it is not zero, per facet.
    lit: Vec<bool>,
}

/// One bounce of the direct coefficient at the day records `at` (indices
/// into `day`; `m = at.len()` per facet in `out`, facet-major):
/// `out_i = g_i ρ_g z + Σ_j F_ij ρ_j (E⁰_j + R_j)` with `R` the previous
/// bounce's and `z` the sine of the sun's elevation. It goes [`BLOCK`]
/// records at a time, so the leaving irradiances are held for one block;
/// sources that send nothing over the block (no albedo, not lit) add
/// zeros, which change nothing.
fn direct_bounce(
    surfaces: &Surfaces,
    day: &[u32],
    at: &[usize],
    prev: Previous,
    out: &mut [f32],
    scratch: &mut Scratch,
) {
    let (sky, albedo) = (surfaces.sky, surfaces.albedo);
    let (n, m, nd) = (albedo.len(), at.len(), day.len());
    let Scratch { leaving, lit } = scratch;
    // Allocated (zeroed) at the first bounce, then kept: a row is read only
    // where its `lit` is set, which its block's computation sets, and the
    // dark row is never written.
    leaving.resize(n + 1, [0.0; BLOCK]);
    lit.resize(n, false);
    // Blocks of BLOCK records; when there are more, the last one ends at
    // the last record (overlapping the one before, whose values it
    // recomputes bit for bit), so that every block is full.
    for c0 in (0..m)
        .step_by(BLOCK)
        .map(|c| c.min(m.saturating_sub(BLOCK)))
    {
        let block = &at[c0..(c0 + BLOCK).min(m)];
        let b = block.len();
        let mut z = [0.0f32; BLOCK];
        let mut sun = BlockSun {
            x: [0.0; BLOCK],
            y: [0.0; BLOCK],
            z: [0.0; BLOCK],
            solar_day: [NIGHT; BLOCK],
            run: None,
        };
        for (i, &d) in block.iter().enumerate() {
            let k = day[d] as usize;
            z[i] = surfaces.sun_dirs[k].z;
            let v = surfaces.solar.sun[k];
            (sun.x[i], sun.y[i], sun.z[i]) = (v.x, v.y, v.z);
            sun.solar_day[i] = surfaces.solar_day[d].map_or(NIGHT, |x| x as u32);
        }
        let x0 = sun.solar_day[0] as usize;
        if b == BLOCK && (0..BLOCK).all(|i| sun.solar_day[i] as usize == x0 + i) {
            sun.run = Some(x0);
        }
        let sun = &sun;
        leaving[..n]
            .par_iter_mut()
            .zip(lit.par_iter_mut())
            .enumerate()
            .with_min_len(256)
            .for_each(|(j, (l, lit))| {
                if !surfaces.reflects[j] {
                    return;
                }
                let a = albedo[j];
                let mut e0 = [0.0f32; BLOCK];
                surfaces.e0_block(j, sun, &mut e0);
                for (i, ((l, &d), &e)) in l.iter_mut().zip(block).zip(&e0).enumerate() {
                    *l = match prev {
                        Previous::None => a * e,
                        Previous::First(r) => a * (e + r[j * nd + d]),
                        Previous::AtNodes(r) => a * (e + r[j * m + c0 + i]),
                    };
                }
                l[b..].fill(0.0);
                *lit = l[..b].iter().any(|&x| x != 0.0);
            });
        let (leaving, lit, z) = (&*leaving, &*lit, &z);
        out.par_chunks_mut(m)
            .enumerate()
            .with_min_len(64)
            .for_each(|(i, out)| {
                crate::simd::vectorized(GatherBounce {
                    out: &mut out[c0..c0 + b],
                    g: sky.ground_weight[i] * surfaces.ground_albedo,
                    z,
                    entries: sky.background(i),
                    leaving,
                    lit,
                })
            });
    }
}

crate::simd::simd_kernel!(GatherBounce<'a> {
    out: &'a mut [f32],
    g: f32,
    z: &'a [f32; BLOCK],
    entries: &'a [super::BackgroundEntry],
    leaving: &'a [[f32; BLOCK]],
    lit: &'a [bool],
} -> () => gather_bounce);

/// `out = g·z + Σ_e w_e l_{j_e}` over the background entries whose source
/// is lit, `l_j` the `j`-th row of `leaving` (the first `out.len()` lanes
/// written). An entry whose source is not lit reads the last row, all
/// zeros, instead of branching: `w·0 = +0` added to the sum (never −0: it
/// starts at `g·z ≥ +0` and adds non-negative terms) leaves it bit for
/// bit, so each lane is the plain iteration's sum in the entries' order.
#[inline(always)]
fn gather_bounce(
    out: &mut [f32],
    g: f32,
    z: &[f32; BLOCK],
    entries: &[super::BackgroundEntry],
    leaving: &[[f32; BLOCK]],
    lit: &[bool],
) {
    let dark = leaving.len() - 1;
    // Two accumulators of `HALF` lanes (vector registers; one array of
    // `BLOCK` lanes is not kept in registers, and the loop runs scalar).
    let mut lo: [f32; HALF] = std::array::from_fn(|k| g * z[k]);
    let mut hi: [f32; HALF] = std::array::from_fn(|k| g * z[HALF + k]);
    for e in entries {
        let j = e.facet as usize;
        let src = &leaving[if lit[j] { j } else { dark }];
        let (Some(s0), Some(s1)) = (src.first_chunk::<HALF>(), src.last_chunk::<HALF>()) else {
            unreachable!("a row is two halves")
        };
        let w = e.weight;
        for (a, l) in lo.iter_mut().zip(s0) {
            *a += w * l;
        }
        for (a, l) in hi.iter_mut().zip(s1) {
            *a += w * l;
        }
    }
    let mut acc = [0.0f32; BLOCK];
    acc[..HALF].copy_from_slice(&lo);
    acc[HALF..].copy_from_slice(&hi);
    match <&mut [f32; BLOCK]>::try_from(&mut *out) {
        Ok(full) => *full = acc,
        Err(_) => {
            let k = out.len();
            out.copy_from_slice(&acc[..k]);
        }
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
