//! The per-facet state of a render, split across processes and kept on
//! disk: what `irsig thermal-scene --state DIR` writes and
//! `irsig render --state DIR` reads instead of solving.
//!
//! # What it owns, takes and gives
//! - Owns [`FacetStates`] (per facet: surface temperature, sun fraction,
//!   incidence and background at each image time, and the shape factor:
//!   everything the render reads of the per-facet stage), the state
//!   folder's layout ([`Manifest`], the shard files), the split of a
//!   scene's facets into shards ([`shard_range`]) and the hash that ties a
//!   folder to one scene and one set of settings ([`StateKey`]).
//! - Takes a [`Session`] (scene, weather, settings, tracer) and the image
//!   times; gives files in the folder, or [`FacetStates`] back from them.
//!   The render turns a [`FacetStates`] into its conditions with
//!   [`Session::conditions`], whether it was solved or read.
//! - Knows nothing of the command line (no flags, nothing printed) or of
//!   Slurm; the split into processes is the caller's.
//!
//! # The split
//! The per-facet stage is rays (solar history, sky view, ground test: ≈ 85 %
//! of it) then the thermal passes. The thermal solve's linearised method
//! chooses its reference facets among *all* facets' inputs, and pass 2's
//! backgrounds need pass 1's temperatures of every facet seen, so the
//! barrier sits after the rays:
//! - **pass 1** ([`run_pass1`], `K/N`): the rays of shard `K`'s facets →
//!   `rays-K-of-N.arrow`;
//! - **pass 2** ([`run_pass2`], `K/M`): reads every pass-1 shard (refusing to
//!   start while one is missing, naming it), runs both thermal passes over
//!   all facets (a few seconds at a million facets), and writes shard `K`'s
//!   facet states → `state-K-of-M.arrow`;
//! - in one process ([`run_all`]): the same solve, `state-1-of-1.arrow`.
//!
//! Shards start on multiples of the exposure's batch of facets, so each
//! facet is traced in the very batch of a run in one piece, and the merged
//! state equals the unsplit one bit for bit. Each file is written
//! atomically ([`crate::output::atomic`]): a killed shard leaves no file
//! under its final name, and a rerun skips shards already complete.
//!
//! # Format
//! Arrow IPC files (Feather v2: `pyarrow.feather.read_table`,
//! `pandas.read_feather`) and a JSON `manifest.json`, described in
//! `docs/cluster.md`. Every file carries the format version; a reader
//! ignores columns it does not know, so later versions may add columns
//! (or files listed in the manifest, e.g. per-property-set data for
//! render-time temperatures) without breaking older readers of the rest.

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use arrow_array::builder::{
    FixedSizeListBuilder, Float32Builder, ListBuilder, UInt8Builder, UInt16Builder, UInt32Builder,
};
use arrow_array::cast::AsArray;
use arrow_array::types::{Float32Type, UInt8Type, UInt16Type, UInt32Type};
use arrow_array::{Array, ArrayRef, BooleanArray, Float32Array, RecordBatch, UInt32Array};
use arrow_schema::{DataType, Field, Schema};
use chrono::{DateTime, FixedOffset};
use serde::{Deserialize, Serialize};

use super::Fnv;
use super::scene_thermal::{FacetRays, solve_scene_traced, trace_scene_facets};
use super::session::{Session, solve_params};
use crate::exposure::{BackgroundEntry, ExposureStats, SkyView, SolarHistory};
use crate::progress::Progress;
use crate::{Error, Result};

/// The `format` of the manifest.
pub const FORMAT: &str = "irsig-facet-state";
/// The version of the folder's layout and files this build writes and reads.
pub const VERSION: u32 = 2;
/// The manifest's file name.
pub const MANIFEST: &str = "manifest.json";

/// One image time's per-facet state (every vector: one value per facet of
/// the [`FacetStates`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FacetTimeState {
    /// Surface temperature, K.
    pub temperature_k: Vec<f32>,
    /// Sunlit fraction of the facet's sample points.
    pub sun_fraction: Vec<f32>,
    /// Cosine of the solar incidence angle (0 at night or facing away).
    pub cos_sun: Vec<f32>,
    /// Background (non-sky) temperature, K: the radiative mean of what the
    /// facet sees below the sky, the ground beyond the scene at the air
    /// temperature.
    pub background_k: Vec<f32>,
}

/// What a render reads of the per-facet stage, for the facets
/// `first..first + len()` at each image time.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FacetStates {
    /// The image times.
    pub times: Vec<DateTime<FixedOffset>>,
    /// Global id of the first facet (0 for a whole scene).
    pub first: usize,
    /// Shape factor (sky view factor of the front face, the parts'
    /// overrides applied), per facet.
    pub shape_factor: Vec<f32>,
    /// Shape factor of the back face of each double-sided facet (the
    /// parts' overrides applied), `None` for single-sided facets; empty
    /// where unknown (a state file written before the column existed):
    /// the shader then takes the front face's.
    pub back_shape_factor: Vec<Option<f32>>,
    /// Per image time.
    pub at: Vec<FacetTimeState>,
}

impl FacetStates {
    /// Number of facets.
    pub fn len(&self) -> usize {
        self.shape_factor.len()
    }

    /// No facets.
    pub fn is_empty(&self) -> bool {
        self.shape_factor.is_empty()
    }

    /// The facets `range` (global ids) of these states.
    ///
    /// # Panics
    /// When `range` is not within these states' facets.
    pub fn slice(&self, range: Range<usize>) -> FacetStates {
        let local = range.start - self.first..range.end - self.first;
        let cut = |v: &Vec<f32>| v[local.clone()].to_vec();
        FacetStates {
            times: self.times.clone(),
            first: range.start,
            shape_factor: cut(&self.shape_factor),
            back_shape_factor: if self.back_shape_factor.is_empty() {
                Vec::new()
            } else {
                self.back_shape_factor[local.clone()].to_vec()
            },
            at: self
                .at
                .iter()
                .map(|a| FacetTimeState {
                    temperature_k: cut(&a.temperature_k),
                    sun_fraction: cut(&a.sun_fraction),
                    cos_sun: cut(&a.cos_sun),
                    background_k: cut(&a.background_k),
                })
                .collect(),
        }
    }

    /// Appends the facets of `other`, which must follow these (same times).
    ///
    /// # Errors
    /// `other` does not start where these end, or has other times.
    pub fn append(&mut self, other: FacetStates) -> Result<()> {
        if self.is_empty() && self.at.is_empty() {
            *self = other;
            return Ok(());
        }
        if other.first != self.first + self.len() || other.times != self.times {
            return Err(Error::invalid(
                "facet state",
                format!(
                    "facets {}..{} do not follow facets {}..{} at the same times",
                    other.first,
                    other.first + other.len(),
                    self.first,
                    self.first + self.len()
                ),
            ));
        }
        // Both halves known, or the whole unknown (the shader then takes
        // the front face's F everywhere, as for an old state file).
        if self.back_shape_factor.is_empty() || other.back_shape_factor.is_empty() {
            self.back_shape_factor.clear();
        } else {
            self.back_shape_factor.extend(other.back_shape_factor);
        }
        self.shape_factor.extend(other.shape_factor);
        for (a, b) in self.at.iter_mut().zip(other.at) {
            a.temperature_k.extend(b.temperature_k);
            a.sun_fraction.extend(b.sun_fraction);
            a.cos_sun.extend(b.cos_sun);
            a.background_k.extend(b.background_k);
        }
        Ok(())
    }
}

/// What ties a state folder to one scene: a hash of everything the
/// per-facet state depends on, and the image times.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StateKey {
    /// FNV-1a of the geometry (every vertex, triangle and instance
    /// transform), each facet's part and each part's material with its
    /// overrides (thermal and optical properties, fixed temperature, shape
    /// factor), the site, the weather file's bytes, the per-facet solve's
    /// parameters (facet samples, sky sampling, history window, thermal
    /// method), the backend and the irsig version; 16 hex digits.
    pub scene_hash: String,
    /// The image times, RFC 3339.
    pub times: Vec<String>,
    /// Facets in the scene.
    pub facets: usize,
}

impl StateKey {
    /// The key of `session`'s scene at `times` (the scene's time when
    /// empty).
    ///
    /// # Errors
    /// The weather file cannot be read.
    pub fn of(session: &Session, times: &[DateTime<FixedOffset>]) -> Result<StateKey> {
        let scene = &session.scene;
        let mut h = Fnv::default();
        let geo = &scene.geometry;
        for m in &geo.meshes {
            h.write(&(m.positions.len() as u64).to_le_bytes());
            for p in &m.positions {
                for c in p.to_array() {
                    h.write(&c.to_le_bytes());
                }
            }
            h.write(&(m.indices.len() as u64).to_le_bytes());
            for t in &m.indices {
                for c in t {
                    h.write(&c.to_le_bytes());
                }
            }
        }
        for i in &geo.instances {
            h.write(&(i.mesh as u64).to_le_bytes());
            for c in i.world_from_object.to_cols_array() {
                h.write(&c.to_le_bytes());
            }
        }
        for p in &session.optics.facet_material {
            h.write(&p.to_le_bytes());
        }
        for (i, p) in scene.parts.iter().enumerate() {
            h.write(
                format!(
                    "{:?}|{:?}|{:?}",
                    scene.part_material(i),
                    p.fixed_temperature_k,
                    p.shape_factor
                )
                .as_bytes(),
            );
        }
        h.write(format!("{:?}", scene.site).as_bytes());
        if let Some(w) = &scene.weather {
            h.write(&std::fs::read(&w.path).map_err(|e| Error::io(&w.path, e))?);
        }
        h.write(format!("{:?}", solve_params(session)).as_bytes());
        h.write(session.backend.as_str().as_bytes());
        h.write(env!("CARGO_PKG_VERSION").as_bytes());
        let times = if times.is_empty() {
            vec![scene.time]
        } else {
            times.to_vec()
        };
        Ok(StateKey {
            scene_hash: format!("{:016x}", h.finish()),
            times: times.iter().map(|t| t.to_rfc3339()).collect(),
            facets: geo.facet_count(),
        })
    }
}

/// The state folder's `manifest.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// [`FORMAT`].
    pub format: String,
    /// [`VERSION`].
    pub version: u32,
    /// The scene file (absolute path), for people; the hash decides.
    pub scene: PathBuf,
    /// [`StateKey::scene_hash`].
    pub scene_hash: String,
    /// Facets in the scene.
    pub facets: usize,
    /// The image times, RFC 3339.
    pub times: Vec<String>,
    /// Pass 1's split: `rays-K-of-N.arrow` for K = 1..N (absent until a
    /// pass-1 shard has run; absent after a run in one process).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rays_shards: Option<usize>,
    /// The states' split: `state-K-of-N.arrow` for K = 1..N (absent until
    /// pass 2 has run).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub state_shards: Option<usize>,
}

/// The facets of shard `k` (1-based) of `n` of a scene of `facets` facets:
/// whole batches of `batch` facets, as equal as possible (a shard may be
/// empty when there are more shards than batches).
pub fn shard_range(k: usize, n: usize, facets: usize, batch: usize) -> Range<usize> {
    let batch = batch.max(1);
    let blocks = facets.div_ceil(batch);
    let rows = super::tile::tile_rows(k, n, blocks);
    (rows.start * batch).min(facets)..(rows.end * batch).min(facets)
}

/// The pass-1 file of shard `k` of `n` in `dir`.
pub fn rays_path(dir: &Path, k: usize, n: usize) -> PathBuf {
    dir.join(format!("rays-{k}-of-{n}.arrow"))
}

/// The state file of shard `k` of `n` in `dir`.
pub fn state_path(dir: &Path, k: usize, n: usize) -> PathBuf {
    dir.join(format!("state-{k}-of-{n}.arrow"))
}

/// What a pass did with its shard.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    /// Wrote this file.
    Wrote(PathBuf),
    /// This file was already complete for the same scene and times.
    Skipped(PathBuf),
}

fn check_shard((k, n): (usize, usize)) -> Result<()> {
    if n == 0 || k == 0 || k > n {
        return Err(Error::invalid(
            "shard",
            format!("{k}/{n}: expected K/N with 1 ≤ K ≤ N"),
        ));
    }
    Ok(())
}

/// Read `dir/manifest.json`, if there is one.
///
/// # Errors
/// An unreadable or malformed manifest, or one of another format or a
/// newer version, naming the file.
pub fn read_manifest(dir: &Path) -> Result<Option<Manifest>> {
    let path = dir.join(MANIFEST);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(Error::io(&path, e)),
    };
    let m: Manifest = serde_json::from_str(&text).map_err(|e| {
        Error::parse(
            crate::Location::file(&path).at_line(e.line()),
            e.to_string(),
        )
    })?;
    if m.format != FORMAT {
        return Err(Error::parse(
            crate::Location::file(&path).with_field("format"),
            format!("`{}`: expected `{FORMAT}`", m.format),
        ));
    }
    if m.version > VERSION {
        return Err(Error::parse(
            crate::Location::file(&path).with_field("version"),
            format!(
                "{}: written by a newer irsig (this one reads version {VERSION})",
                m.version
            ),
        ));
    }
    Ok(Some(m))
}

/// The manifest of `dir` checked against `key`: the same scene hash,
/// facets and times.
/// The manifest of `dir`, which must exist (`hint`: what to do when it
/// does not) and belong to `key`'s scene and times.
fn existing_manifest(dir: &Path, key: &StateKey, hint: &str) -> Result<Manifest> {
    let manifest = read_manifest(dir)?.ok_or_else(|| {
        Error::invalid(
            "state",
            format!("{} has no {MANIFEST}: {hint}", dir.display()),
        )
    })?;
    check_manifest(dir, &manifest, key)?;
    Ok(manifest)
}

fn check_manifest(dir: &Path, m: &Manifest, key: &StateKey) -> Result<()> {
    let path = dir.join(MANIFEST);
    if m.scene_hash != key.scene_hash || m.facets != key.facets {
        return Err(Error::invalid(
            "state",
            format!(
                "{} was made from another scene or other settings (scene hash {}, {} facets; \
                 this scene: {}, {} facets; made from {}): use another folder or remake it",
                path.display(),
                m.scene_hash,
                m.facets,
                key.scene_hash,
                key.facets,
                m.scene.display()
            ),
        ));
    }
    if m.times != key.times {
        return Err(Error::invalid(
            "state",
            format!(
                "{} holds the times {} but {} were asked for",
                path.display(),
                m.times.join(", "),
                key.times.join(", ")
            ),
        ));
    }
    Ok(())
}

/// Write the manifest atomically.
fn write_manifest(dir: &Path, m: &Manifest) -> Result<()> {
    let path = dir.join(MANIFEST);
    let text = serde_json::to_string_pretty(m)
        .map_err(|e| Error::Other(format!("{}: {e}", path.display())))?;
    crate::output::atomic::write_atomic(&path, |w| {
        w.write_all(text.as_bytes())
            .and_then(|_| w.write_all(b"\n"))
            .map_err(|e| Error::io(&path, e))
    })
}

/// The folder's manifest for `key`, created if absent; refused when it is
/// another scene's or other times'.
fn open_manifest(session: &Session, dir: &Path, key: &StateKey) -> Result<Manifest> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    match read_manifest(dir)? {
        Some(m) => {
            check_manifest(dir, &m, key)?;
            Ok(m)
        }
        None => Ok(Manifest {
            format: FORMAT.to_string(),
            version: VERSION,
            scene: std::path::absolute(&session.scene.path).unwrap_or(session.scene.path.clone()),
            scene_hash: key.scene_hash.clone(),
            facets: key.facets,
            times: key.times.clone(),
            rays_shards: None,
            state_shards: None,
        }),
    }
}

/// The metadata every shard file carries.
fn file_metadata(
    kind: &str,
    key: &StateKey,
    (k, n): (usize, usize),
    range: &Range<usize>,
) -> HashMap<String, String> {
    HashMap::from([
        ("irsig.format".to_string(), kind.to_string()),
        ("irsig.version".to_string(), VERSION.to_string()),
        ("irsig.scene_hash".to_string(), key.scene_hash.clone()),
        (
            "irsig.times".to_string(),
            serde_json::to_string(&key.times).unwrap_or_default(),
        ),
        ("irsig.shard".to_string(), format!("{k}/{n}")),
        (
            "irsig.facets".to_string(),
            format!("{}..{}", range.start, range.end),
        ),
    ])
}

const RAYS_KIND: &str = "irsig-facet-rays";
const STATE_KIND: &str = "irsig-facet-state";

/// Pass 1 of the split per-facet stage: the rays of shard `k` of `n` into
/// `dir/rays-K-of-N.arrow` (skipped when already complete), the manifest
/// created or checked. `progress` sees [`crate::progress::Stage::Exposure`].
///
/// # Errors
/// A bad shard; a folder of another scene, other times or another split
/// (naming the manifest); the rays' errors; writing.
pub fn run_pass1(
    session: &mut Session,
    dir: &Path,
    times: &[DateTime<FixedOffset>],
    (k, n): (usize, usize),
    progress: &dyn Progress,
) -> Result<Outcome> {
    check_shard((k, n))?;
    let key = StateKey::of(session, times)?;
    let mut manifest = open_manifest(session, dir, &key)?;
    if let Some(m) = manifest.rays_shards
        && m != n
    {
        return Err(Error::invalid(
            "shard",
            format!(
                "{} holds pass 1 split into {m} shards, not {n}: use K/{m} or another folder",
                dir.join(MANIFEST).display()
            ),
        ));
    }
    let path = rays_path(dir, k, n);
    let params = solve_params(session);
    let range = shard_range(k, n, key.facets, params.exposure.batch_facets);
    if file_is_complete(&path, RAYS_KIND, &key, (k, n), &range) {
        return Ok(Outcome::Skipped(path));
    }
    if manifest.rays_shards.is_none() {
        manifest.rays_shards = Some(n);
        write_manifest(dir, &manifest)?;
    }
    let times = parse_times(&key)?;
    let own = session.exposure_tracer()?;
    let tracers = super::scene_thermal::FacetTracers {
        exposure: own.as_deref().unwrap_or(session.tracer.as_ref()),
        exact: session.tracer.as_ref(),
    };
    let t0 = std::time::Instant::now();
    let rays = trace_scene_facets(
        tracers,
        &session.scene,
        &times,
        &params,
        range.clone(),
        progress,
    )?;
    drop(own);
    session.timings.thermal += t0.elapsed();
    write_rays(&path, &key, (k, n), &rays)?;
    Ok(Outcome::Wrote(path))
}

/// Pass 2 of the split per-facet stage: reads every pass-1 shard, solves
/// the thermal passes over all facets and writes shard `k` of `n` of the
/// facet states into `dir/state-K-of-N.arrow` (skipped when already
/// complete). `progress` sees [`crate::progress::Stage::Thermal`].
///
/// # Errors
/// No pass 1 in the folder; a pass-1 shard missing (naming each missing
/// file) or of another scene; as [`run_pass1`].
pub fn run_pass2(
    session: &mut Session,
    dir: &Path,
    times: &[DateTime<FixedOffset>],
    (k, n): (usize, usize),
    progress: &dyn Progress,
) -> Result<Outcome> {
    check_shard((k, n))?;
    let key = StateKey::of(session, times)?;
    let manifest = existing_manifest(dir, &key, "run pass 1 into it first")?;
    let Some(m) = manifest.rays_shards else {
        return Err(Error::invalid(
            "state",
            format!(
                "{} records no pass 1: run pass 1 into it first",
                dir.join(MANIFEST).display()
            ),
        ));
    };
    let path = state_path(dir, k, n);
    let params = solve_params(session);
    let range = shard_range(k, n, key.facets, params.exposure.batch_facets);
    if file_is_complete(&path, STATE_KIND, &key, (k, n), &range) {
        return Ok(Outcome::Skipped(path));
    }
    let missing: Vec<String> = (1..=m)
        .map(|j| rays_path(dir, j, m))
        .filter(|p| !p.exists())
        .map(|p| p.display().to_string())
        .collect();
    if !missing.is_empty() {
        return Err(Error::invalid(
            "state",
            format!(
                "pass 1 is not complete: missing {} (rerun pass 1 for {})",
                missing.join(", "),
                if missing.len() == 1 { "it" } else { "them" }
            ),
        ));
    }
    let times = parse_times(&key)?;
    let t0 = std::time::Instant::now();
    let mut parts = Vec::with_capacity(m);
    for j in 1..=m {
        let r = shard_range(j, m, key.facets, params.exposure.batch_facets);
        parts.push(read_rays(&rays_path(dir, j, m), &key, (j, m), r)?);
    }
    let solved = solve_scene_traced(&session.scene, &times, &params, parts, progress)?;
    session.timings.thermal += t0.elapsed();
    session.timings.thermal_solve += solved.timings.thermal;
    session.timings.reflected_shortwave += solved.timings.reflected;
    let states = session.facet_states_of(&solved, &times)?;
    session.note_warnings(super::scene_thermal::unsettled_exchange_warnings(
        &session.scene,
        &solved.temperatures,
    ));
    drop(solved);
    write_states(&path, &key, (k, n), &states.slice(range))?;
    let mut manifest = read_manifest(dir)?.unwrap_or(manifest);
    if manifest.state_shards != Some(n) {
        manifest.state_shards = Some(n);
        write_manifest(dir, &manifest)?;
    }
    Ok(Outcome::Wrote(path))
}

/// The per-facet stage in one process: every facet's rays and thermal
/// passes, written as `dir/state-1-of-1.arrow` (skipped when already
/// complete). `progress` sees [`crate::progress::Stage::Exposure`] then
/// [`crate::progress::Stage::Thermal`].
///
/// # Errors
/// As [`run_pass1`].
pub fn run_all(
    session: &mut Session,
    dir: &Path,
    times: &[DateTime<FixedOffset>],
    progress: &dyn Progress,
) -> Result<Outcome> {
    let key = StateKey::of(session, times)?;
    let mut manifest = open_manifest(session, dir, &key)?;
    let path = state_path(dir, 1, 1);
    let range = 0..key.facets;
    if file_is_complete(&path, STATE_KIND, &key, (1, 1), &range) {
        return Ok(Outcome::Skipped(path));
    }
    let times = parse_times(&key)?;
    let thermal = session.facet_states(&times, progress)?;
    write_states(&path, &key, (1, 1), &thermal)?;
    manifest.state_shards = Some(1);
    write_manifest(dir, &manifest)?;
    Ok(Outcome::Wrote(path))
}

/// The facet states of every facet from `dir`, checked against `session`'s
/// scene and `times`.
///
/// # Errors
/// No manifest or no states yet; a folder of another scene or other times;
/// a state shard missing (naming each) or unreadable.
pub fn read_states(
    session: &Session,
    dir: &Path,
    times: &[DateTime<FixedOffset>],
) -> Result<FacetStates> {
    let key = StateKey::of(session, times)?;
    let manifest = existing_manifest(dir, &key, "make it with the thermal-scene stage first")?;
    let Some(n) = manifest.state_shards else {
        return Err(Error::invalid(
            "state",
            format!(
                "{} holds no facet states yet: run pass 2 into it first",
                dir.display()
            ),
        ));
    };
    let missing: Vec<String> = (1..=n)
        .map(|j| state_path(dir, j, n))
        .filter(|p| !p.exists())
        .map(|p| p.display().to_string())
        .collect();
    if !missing.is_empty() {
        return Err(Error::invalid(
            "state",
            format!(
                "the facet states are not complete: missing {}",
                missing.join(", ")
            ),
        ));
    }
    let batch = solve_params(session).exposure.batch_facets;
    let mut out = FacetStates::default();
    for j in 1..=n {
        let r = shard_range(j, n, key.facets, batch);
        out.append(read_state_file(&state_path(dir, j, n), &key, (j, n), r)?)?;
    }
    if out.len() != key.facets {
        return Err(Error::invalid(
            "state",
            format!(
                "{} holds {} of {} facets",
                dir.display(),
                out.len(),
                key.facets
            ),
        ));
    }
    out.times = parse_times(&key)?;
    Ok(out)
}

fn parse_times(key: &StateKey) -> Result<Vec<DateTime<FixedOffset>>> {
    key.times
        .iter()
        .map(|t| {
            DateTime::parse_from_rfc3339(t)
                .map_err(|e| Error::invalid("times", format!("`{t}`: {e}")))
        })
        .collect()
}

/// The file exists, is readable and belongs to `key`, shard and range.
fn file_is_complete(
    path: &Path,
    kind: &str,
    key: &StateKey,
    shard: (usize, usize),
    range: &Range<usize>,
) -> bool {
    let Ok(f) = std::fs::File::open(path) else {
        return false;
    };
    let Ok((meta, _)) = decode_ipc(f, false) else {
        return false;
    };
    let want = file_metadata(kind, key, shard, range);
    want.iter().all(|(k, v)| meta.get(k) == Some(v))
}

/// Write one record batch atomically.
fn write_batch(path: &Path, batch: &RecordBatch) -> Result<()> {
    let arrow = |e: arrow_schema::ArrowError| Error::Other(format!("{}: {e}", path.display()));
    crate::output::atomic::write_atomic(path, |w| {
        let mut writer =
            arrow_ipc::writer::FileWriter::try_new(w, &batch.schema()).map_err(arrow)?;
        writer.write(batch).map_err(arrow)?;
        writer.finish().map_err(arrow)?;
        Ok(())
    })
}

/// An Arrow IPC file's schema metadata and (`with_batch`) its one record
/// batch (irsig writes one per file; any other count is an error); the
/// error says
/// what is malformed. arrow-ipc 59 panics on some malformed files instead of
/// returning an error (a schema field of type `NONE`; a boolean null bitmap
/// shorter than its column; a buffer slice beyond the body; found by the
/// `state` fuzz target): the panic is caught and reported as a malformed file
/// (the default hook still prints the panic's own message).
fn decode_ipc(
    mut f: std::fs::File,
    with_batch: bool,
) -> std::result::Result<(HashMap<String, String>, Option<RecordBatch>), String> {
    let decoded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let batches = check_ipc_blocks(&mut f)?;
        let mut reader = arrow_ipc::reader::FileReader::try_new(f, None)
            .map_err(|e| format!("not an Arrow IPC file: {e}"))?;
        let meta = reader.schema().metadata().clone();
        if !with_batch {
            return Ok((meta, None));
        }
        // Refuse any other count before decoding: a footer listing many
        // blocks (each pointing at the same few bytes) would otherwise
        // decode batch after batch into gigabytes (found by the `state`
        // fuzz target).
        if batches != 1 {
            return Err(format!("{batches} record batches, expected one"));
        }
        let batch = reader
            .next()
            .ok_or("no record batch")?
            .map_err(|e| e.to_string())?;
        Ok((meta, Some(batch)))
    }));
    decoded.unwrap_or_else(|p| {
        let why = p
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| p.downcast_ref::<&str>().copied())
            .unwrap_or("the Arrow reader failed");
        Err(format!("malformed Arrow IPC file: {why}"))
    })
}

/// Check that every block an Arrow IPC file's footer lists lies inside the
/// file, and leave `f` at its start; the number of record batches it lists. arrow-ipc allocates each block's
/// declared size before reading it, so a footer declaring a block of
/// exabytes aborts the process (an allocation failure is not a panic that
/// [`decode_ipc`] could catch; found by the `state` fuzz target).
fn check_ipc_blocks(f: &mut std::fs::File) -> std::result::Result<usize, String> {
    use std::io::{Read, Seek, SeekFrom};
    let io = |e: std::io::Error| format!("not an Arrow IPC file: {e}");
    let len = f.seek(SeekFrom::End(0)).map_err(io)?;
    if len < 10 {
        return Err(format!("not an Arrow IPC file: {len} bytes"));
    }
    let mut tail = [0u8; 10];
    f.seek(SeekFrom::End(-10)).map_err(io)?;
    f.read_exact(&mut tail).map_err(io)?;
    let footer_len = arrow_ipc::reader::read_footer_length(tail)
        .map_err(|e| format!("not an Arrow IPC file: {e}"))? as u64;
    if footer_len + 10 > len {
        return Err(format!(
            "malformed Arrow IPC file: a footer of {footer_len} bytes in a file of {len}"
        ));
    }
    let mut footer = vec![0u8; footer_len as usize];
    f.seek(SeekFrom::Start(len - 10 - footer_len)).map_err(io)?;
    f.read_exact(&mut footer).map_err(io)?;
    let footer = arrow_ipc::root_as_footer(&footer)
        .map_err(|e| format!("malformed Arrow IPC file: its footer: {e}"))?;
    let blocks = footer
        .dictionaries()
        .into_iter()
        .flatten()
        .chain(footer.recordBatches().into_iter().flatten());
    for b in blocks {
        let end = u64::try_from(b.offset())
            .ok()
            .zip(u64::try_from(b.metaDataLength()).ok())
            .zip(u64::try_from(b.bodyLength()).ok())
            .and_then(|((o, m), n)| o.checked_add(m)?.checked_add(n));
        if end.is_none_or(|e| e > len) {
            return Err(format!(
                "malformed Arrow IPC file: a block at offset {} of {} + {} bytes beyond the file's {len} bytes",
                b.offset(),
                b.metaDataLength(),
                b.bodyLength()
            ));
        }
    }
    f.seek(SeekFrom::Start(0)).map_err(io)?;
    Ok(footer.recordBatches().map_or(0, |b| b.len()))
}

/// Read the one record batch of `path`, checking its metadata.
fn read_batch(
    path: &Path,
    kind: &str,
    key: &StateKey,
    shard: (usize, usize),
    range: &Range<usize>,
) -> Result<RecordBatch> {
    let bad = |m: String| Error::invalid("state", format!("{}: {m}", path.display()));
    let f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let (meta, batch) = decode_ipc(f, true).map_err(bad)?;
    let want = file_metadata(kind, key, shard, range);
    for field in [
        "irsig.format",
        "irsig.scene_hash",
        "irsig.times",
        "irsig.shard",
        "irsig.facets",
    ] {
        if meta.get(field) != want.get(field) {
            return Err(bad(format!(
                "its {field} is {} but {} was expected (a file of another scene, times or split)",
                meta.get(field).map_or("absent", |s| s.as_str()),
                want[field]
            )));
        }
    }
    let batch = batch.ok_or_else(|| bad("no record batch".into()))?;
    if batch.num_rows() != range.len() {
        return Err(bad(format!(
            "{} rows, expected {} (facets {}..{})",
            batch.num_rows(),
            range.len(),
            range.start,
            range.end
        )));
    }
    Ok(batch)
}

/// A column of `batch` by name.
fn column<'b>(batch: &'b RecordBatch, path: &Path, name: &str) -> Result<&'b ArrayRef> {
    batch
        .column_by_name(name)
        .ok_or_else(|| Error::invalid("state", format!("{}: no column `{name}`", path.display())))
}

/// A float32 column of `batch` by name (a mistyped one is an error naming
/// the file and the column).
fn float32_array<'b>(batch: &'b RecordBatch, path: &Path, name: &str) -> Result<&'b Float32Array> {
    let c = column(batch, path, name)?;
    c.as_primitive_opt::<Float32Type>().ok_or_else(|| {
        Error::invalid(
            "state",
            format!(
                "{}: column `{name}` is {}, expected float32",
                path.display(),
                c.data_type()
            ),
        )
    })
}

fn f32_column(batch: &RecordBatch, path: &Path, name: &str) -> Result<Vec<f32>> {
    let a = float32_array(batch, path, name)?;
    if a.null_count() > 0 {
        return Err(Error::invalid(
            "state",
            format!("{}: column `{name}` has nulls", path.display()),
        ));
    }
    check_finite(path, name, a.values())?;
    Ok(a.values().to_vec())
}

/// Every value of column `name` is finite: a NaN or an infinity would pass
/// silently into the thermal solve or the image.
fn check_finite(path: &Path, name: &str, v: &[f32]) -> Result<()> {
    match v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        Some((i, x)) => Err(Error::invalid(
            "state",
            format!(
                "{}: column `{name}` holds {x} at row {i}: expected a finite number",
                path.display()
            ),
        )),
        None => Ok(()),
    }
}

fn check_facet_ids(batch: &RecordBatch, path: &Path, range: &Range<usize>) -> Result<()> {
    let c = column(batch, path, "facet")?;
    let a = c.as_primitive_opt::<UInt32Type>().ok_or_else(|| {
        Error::invalid(
            "state",
            format!("{}: column `facet` is not uint32", path.display()),
        )
    })?;
    if let Some((i, &v)) = a
        .values()
        .iter()
        .enumerate()
        .find(|&(i, &v)| v as usize != range.start + i)
    {
        return Err(Error::invalid(
            "state",
            format!(
                "{}: row {i} holds facet {v}, expected {}",
                path.display(),
                range.start + i
            ),
        ));
    }
    Ok(())
}

/// The name of a per-time column: `QUANTITY_I` for image time `I`
/// (0-based, in the manifest's order).
fn time_column(quantity: &str, i: usize) -> String {
    format!("{quantity}_{i}")
}

/// Write the facet states `states` (shard `k` of `n`, facets
/// `states.first..`) to `path`, atomically: one state file of a folder
/// ([`run_all`] and [`run_pass2`] name and write them; public for tools and
/// the fuzz harness's seeds).
///
/// # Errors
/// Writing the file.
pub fn write_states(
    path: &Path,
    key: &StateKey,
    shard: (usize, usize),
    states: &FacetStates,
) -> Result<()> {
    let range = states.first..states.first + states.len();
    let mut fields = vec![
        Field::new("facet", DataType::UInt32, false),
        Field::new("shape_factor", DataType::Float32, false),
    ];
    let mut columns: Vec<ArrayRef> = vec![
        Arc::new(UInt32Array::from_iter_values(
            range.clone().map(|f| f as u32),
        )),
        Arc::new(Float32Array::from(states.shape_factor.clone())),
    ];
    if !states.back_shape_factor.is_empty() {
        fields.push(Field::new("back_shape_factor", DataType::Float32, true));
        columns.push(Arc::new(Float32Array::from(
            states.back_shape_factor.clone(),
        )));
    }
    for (i, at) in states.at.iter().enumerate() {
        let time = HashMap::from([("time".to_string(), key.times[i].clone())]);
        for (q, v) in [
            ("temperature_k", &at.temperature_k),
            ("sun_fraction", &at.sun_fraction),
            ("cos_sun", &at.cos_sun),
            ("background_k", &at.background_k),
        ] {
            fields.push(
                Field::new(time_column(q, i), DataType::Float32, false).with_metadata(time.clone()),
            );
            columns.push(Arc::new(Float32Array::from(v.clone())));
        }
    }
    let schema = Schema::new(fields).with_metadata(file_metadata(STATE_KIND, key, shard, &range));
    let batch = RecordBatch::try_new(Arc::new(schema), columns)
        .map_err(|e| Error::Other(format!("{}: {e}", path.display())))?;
    write_batch(path, &batch)
}

/// Read one state file (`state-K-of-N.arrow`) on its own: shard `shard` of
/// `key`'s scene, facets `range` ([`read_states`] reads a whole folder;
/// public for tools and the fuzz harness).
///
/// # Errors
/// Not an Arrow IPC file, metadata of another scene, times or split, rows
/// other than `range`, a missing, mistyped or null column, a non-finite
/// value: each naming the file (and the column).
pub fn read_state_file(
    path: &Path,
    key: &StateKey,
    shard: (usize, usize),
    range: Range<usize>,
) -> Result<FacetStates> {
    let batch = read_batch(path, STATE_KIND, key, shard, &range)?;
    check_facet_ids(&batch, path, &range)?;
    let mut at = Vec::with_capacity(key.times.len());
    for i in 0..key.times.len() {
        at.push(FacetTimeState {
            temperature_k: f32_column(&batch, path, &time_column("temperature_k", i))?,
            sun_fraction: f32_column(&batch, path, &time_column("sun_fraction", i))?,
            cos_sun: f32_column(&batch, path, &time_column("cos_sun", i))?,
            background_k: f32_column(&batch, path, &time_column("background_k", i))?,
        });
    }
    let back_shape_factor = match batch.column_by_name("back_shape_factor") {
        Some(_) => fraction_column(&batch, path, "back_shape_factor", range.len())?,
        None => Vec::new(),
    };
    Ok(FacetStates {
        times: Vec::new(),
        first: range.start,
        shape_factor: f32_column(&batch, path, "shape_factor")?,
        back_shape_factor,
        at,
    })
}

/// Write pass 1's rays of a shard to `path`, atomically (public for tools
/// and the fuzz harness's seeds).
///
/// # Errors
/// Writing the file.
pub fn write_rays(
    path: &Path,
    key: &StateKey,
    shard: (usize, usize),
    rays: &FacetRays,
) -> Result<()> {
    let range = rays.range.clone();
    let steps = rays.solar.steps;
    let sky = &rays.sky;
    let mut bg_facet = ListBuilder::new(UInt32Builder::new());
    let mut bg_weight = ListBuilder::new(Float32Builder::new());
    for f in 0..range.len() {
        let e = &sky.entries[sky.offsets[f] as usize..sky.offsets[f + 1] as usize];
        bg_facet
            .values()
            .append_slice(&e.iter().map(|x| x.facet).collect::<Vec<_>>());
        bg_facet.append(true);
        bg_weight
            .values()
            .append_slice(&e.iter().map(|x| x.weight).collect::<Vec<_>>());
        bg_weight.append(true);
    }
    // The sun at the history's day records: lit sample points per facet and
    // day record, uint8 (uint16 above 255 points per facet).
    let solar = &rays.solar;
    let nd = solar.day.len();
    let sun: ArrayRef = if solar.width() == 1 {
        let mut b = FixedSizeListBuilder::with_capacity(
            UInt8Builder::with_capacity(solar.lit.len()),
            nd as i32,
            range.len(),
        );
        for f in 0..range.len() {
            b.values().append_slice(&solar.lit[f * nd..(f + 1) * nd]);
            b.append(true);
        }
        Arc::new(b.finish())
    } else {
        let mut b = FixedSizeListBuilder::with_capacity(
            UInt16Builder::with_capacity(solar.lit.len() / 2),
            nd as i32,
            range.len(),
        );
        for f in 0..range.len() {
            for d in 0..nd {
                b.values().append_value(solar.lit_points(f, d) as u16);
            }
            b.append(true);
        }
        Arc::new(b.finish())
    };
    let (bg_facet, bg_weight) = (bg_facet.finish(), bg_weight.finish());
    let fields = vec![
        Field::new("facet", DataType::UInt32, false),
        Field::new("shape_factor", DataType::Float32, false),
        Field::new("back_shape_factor", DataType::Float32, true),
        Field::new("exposed_back_shape_factor", DataType::Float32, true),
        Field::new("shape_factor_std_error", DataType::Float32, false),
        Field::new("ground_weight", DataType::Float32, false),
        Field::new("on_ground", DataType::Boolean, false),
        Field::new("background_facet", bg_facet.data_type().clone(), false),
        Field::new("background_weight", bg_weight.data_type().clone(), false),
        Field::new("sun_lit", sun.data_type().clone(), false),
    ];
    let columns: Vec<ArrayRef> = vec![
        Arc::new(UInt32Array::from_iter_values(
            range.clone().map(|f| f as u32),
        )),
        Arc::new(Float32Array::from(sky.shape_factor.clone())),
        Arc::new(Float32Array::from(sky.back_shape_factor.clone())),
        Arc::new(Float32Array::from(rays.exposed_back_shape_factor.clone())),
        Arc::new(Float32Array::from(sky.std_error.clone())),
        Arc::new(Float32Array::from(sky.ground_weight.clone())),
        Arc::new(BooleanArray::from(rays.ground.clone())),
        Arc::new(bg_facet),
        Arc::new(bg_weight),
        sun,
    ];
    let mut meta = file_metadata(RAYS_KIND, key, shard, &range);
    meta.insert("irsig.history_steps".into(), steps.to_string());
    meta.insert(
        "irsig.day_records".into(),
        serde_json::to_string(&solar.day).unwrap_or_default(),
    );
    meta.insert("irsig.sample_points".into(), solar.points.to_string());
    let schema = Schema::new(fields).with_metadata(meta);
    let batch = RecordBatch::try_new(Arc::new(schema), columns)
        .map_err(|e| Error::Other(format!("{}: {e}", path.display())))?;
    write_batch(path, &batch)
}

/// The solar history of a rays file: metadata `irsig.history_steps`,
/// `irsig.day_records` and `irsig.sample_points`, column `sun_lit`. The
/// history carries no geometry (normals, sun): the thermal stage adds the
/// scene's.
fn read_sun_lit(batch: &RecordBatch, path: &Path, nf: usize) -> Result<SolarHistory> {
    let bad = |m: String| Error::invalid("state", format!("{}: {m}", path.display()));
    let schema = batch.schema();
    let meta = schema.metadata();
    let version: u32 = meta
        .get("irsig.version")
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    if version < 2 {
        return Err(bad(format!(
            "a rays file of format version {version}, which held the solar history as float32 \
             columns; this irsig reads version {VERSION}: rerun pass 1 into a new folder"
        )));
    }
    let get = |k: &str| meta.get(k).ok_or_else(|| bad(format!("no metadata `{k}`")));
    let steps: usize = get("irsig.history_steps")?
        .parse()
        .map_err(|e| bad(format!("metadata `irsig.history_steps`: {e}")))?;
    let points: u32 = get("irsig.sample_points")?
        .parse()
        .map_err(|e| bad(format!("metadata `irsig.sample_points`: {e}")))?;
    let day: Vec<u32> = serde_json::from_str(get("irsig.day_records")?)
        .map_err(|e| bad(format!("metadata `irsig.day_records`: {e}")))?;
    if !(1..=256).contains(&points) {
        return Err(bad(format!(
            "metadata `irsig.sample_points`: {points}, expected 1 to 256"
        )));
    }
    if day.windows(2).any(|w| w[0] >= w[1]) || day.last().is_some_and(|&d| d as usize >= steps) {
        return Err(bad(format!(
            "metadata `irsig.day_records`: expected ascending records below {steps}"
        )));
    }
    let nd = day.len();
    let l = column(batch, path, "sun_lit")?
        .as_fixed_size_list_opt()
        .ok_or_else(|| bad("column `sun_lit` is not a fixed-size list".into()))?;
    if l.value_length() as usize != nd {
        return Err(bad(format!(
            "column `sun_lit` holds {} values per facet, expected {nd} (one per day record)",
            l.value_length()
        )));
    }
    let start = if nf > 0 {
        l.value_offset(0) as usize
    } else {
        0
    };
    let mut h = SolarHistory {
        steps,
        facets: nf,
        day,
        points,
        ..SolarHistory::default()
    };
    let counts: Vec<u32> = if h.width() == 1 {
        let v = l
            .values()
            .as_primitive_opt::<UInt8Type>()
            .ok_or_else(|| bad("`sun_lit` does not hold uint8".into()))?;
        h.lit = v.values()[start..start + nf * nd].to_vec();
        h.lit.iter().map(|&c| c as u32).collect()
    } else {
        let v = l
            .values()
            .as_primitive_opt::<UInt16Type>()
            .ok_or_else(|| bad("`sun_lit` does not hold uint16".into()))?;
        let v = &v.values()[start..start + nf * nd];
        h.lit = v.iter().flat_map(|c| c.to_le_bytes()).collect();
        v.iter().map(|&c| c as u32).collect()
    };
    if let Some(i) = counts.iter().position(|&c| c > points) {
        return Err(bad(format!(
            "`sun_lit` of facet row {} is {}, more than the {points} sample points",
            i / nd.max(1),
            counts[i]
        )));
    }
    Ok(h)
}

/// Read pass 1's rays of a shard from `path` (`rays-K-of-N.arrow`): shard
/// `shard` of `key`'s scene, facets `range` (public for tools and the fuzz
/// harness).
///
/// # Errors
/// As [`read_state_file`]; also background facets beyond the scene's and
/// lists of mismatched lengths.
pub fn read_rays(
    path: &Path,
    key: &StateKey,
    shard: (usize, usize),
    range: Range<usize>,
) -> Result<FacetRays> {
    let batch = read_batch(path, RAYS_KIND, key, shard, &range)?;
    let bad = |m: String| Error::invalid("state", format!("{}: {m}", path.display()));
    check_facet_ids(&batch, path, &range)?;
    let nf = range.len();
    let back = column(&batch, path, "back_shape_factor")?
        .as_primitive_opt::<Float32Type>()
        .ok_or_else(|| bad("column `back_shape_factor` is not float32".into()))?;
    let back_shape_factor: Vec<Option<f32>> = (0..nf)
        .map(|i| (!back.is_null(i)).then(|| back.value(i)))
        .collect();
    let backs: Vec<f32> = back_shape_factor.iter().flatten().copied().collect();
    check_finite(path, "back_shape_factor", &backs)?;
    let exposed_back_shape_factor = exposed_back_column(&batch, path, nf)?;
    let on_ground = column(&batch, path, "on_ground")?
        .as_boolean_opt()
        .ok_or_else(|| bad("column `on_ground` is not boolean".into()))?;
    let ground = (0..nf).map(|i| on_ground.value(i)).collect();
    let list = |name: &str| -> Result<(Vec<usize>, ArrayRef)> {
        let l = column(&batch, path, name)?
            .as_list_opt::<i32>()
            .ok_or_else(|| bad(format!("column `{name}` is not a list")))?;
        let o = l.offsets();
        let base = o[0];
        Ok((
            o.iter().map(|&x| (x - base) as usize).collect(),
            l.values().slice(base as usize, (o[nf] - base) as usize),
        ))
    };
    let (off_f, facets) = list("background_facet")?;
    let (off_w, weights) = list("background_weight")?;
    if off_f != off_w {
        return Err(bad(
            "`background_facet` and `background_weight` differ in length".into(),
        ));
    }
    let facets = facets
        .as_primitive_opt::<UInt32Type>()
        .ok_or_else(|| bad("`background_facet` does not hold uint32".into()))?;
    let weights = weights
        .as_primitive_opt::<Float32Type>()
        .ok_or_else(|| bad("`background_weight` does not hold float32".into()))?;
    check_finite(path, "background_weight", weights.values())?;
    if let Some(&f) = facets.values().iter().find(|&&f| f as usize >= key.facets) {
        return Err(bad(format!(
            "background facet {f} is beyond the scene's {} facets",
            key.facets
        )));
    }
    let entries = facets
        .values()
        .iter()
        .zip(weights.values().iter())
        .map(|(&facet, &weight)| BackgroundEntry { facet, weight })
        .collect();
    let solar = read_sun_lit(&batch, path, nf)?;
    Ok(FacetRays {
        range,
        solar,
        sky: SkyView {
            shape_factor: f32_column(&batch, path, "shape_factor")?,
            back_shape_factor,
            std_error: f32_column(&batch, path, "shape_factor_std_error")?,
            ground_weight: f32_column(&batch, path, "ground_weight")?,
            offsets: off_f.iter().map(|&o| o as u32).collect(),
            entries,
        },
        ground,
        exposed_back_shape_factor,
        stats: ExposureStats::default(),
    })
}

/// Column `exposed_back_shape_factor` of a rays file: per facet, the
/// traced shape factor of its exposed back, null where the slab model
/// takes `1 − F`. A file written before the column existed has none: every
/// facet then takes `1 − F`, as when it was written.
fn exposed_back_column(batch: &RecordBatch, path: &Path, nf: usize) -> Result<Vec<Option<f32>>> {
    const NAME: &str = "exposed_back_shape_factor";
    if batch.column_by_name(NAME).is_none() {
        return Ok(vec![None; nf]);
    }
    fraction_column(batch, path, NAME, nf)
}

/// A nullable float32 column of fractions in [0, 1] (`nf` rows): a
/// mistyped column or a value outside [0, 1] (NaN included) is an error
/// naming the file, the column and the row.
fn fraction_column(
    batch: &RecordBatch,
    path: &Path,
    name: &str,
    nf: usize,
) -> Result<Vec<Option<f32>>> {
    let a = float32_array(batch, path, name)?;
    let v: Vec<Option<f32>> = (0..nf)
        .map(|i| (!a.is_null(i)).then(|| a.value(i)))
        .collect();
    if let Some((i, x)) = v
        .iter()
        .enumerate()
        .find_map(|(i, x)| x.filter(|x| !(0.0..=1.0).contains(x)).map(|x| (i, x)))
    {
        return Err(Error::invalid(
            "state",
            format!(
                "{}: column `{name}` holds {x} at row {i}: expected a fraction in [0, 1] or null",
                path.display()
            ),
        ));
    }
    Ok(v)
}
