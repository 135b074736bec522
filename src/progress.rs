//! Progress of long library operations, reported to an observer.
//!
//! Owns the [`Progress`] trait and its [`Stage`]s. A long operation
//! ([`Session::open_observed`](crate::render::session::Session::open_observed):
//! loading and the BVH; [`Session::run`](crate::render::session::Session::run):
//! the per-facet rays, the thermal passes, then the image rows; the
//! split per-facet stage of [`crate::render::state`]) takes an observer
//! and tells it when a stage starts and how much of it is done; the caller
//! decides what to do with that — the command line draws a bar, a test
//! counts the calls, a binding forwards them. [`NoProgress`] ignores them.
//!
//! This module must not know how progress is shown: no terminal, no bar.

/// A stage of a long operation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Stage {
    /// Loading the scene: geometry, materials, weather. No count (the
    /// total is 0).
    Load,
    /// Building the ray-tracing acceleration structures. No count.
    Bvh,
    /// The per-facet rays: solar history then sky view, each counted in
    /// facets (the total is twice the facets), then the ground test.
    Exposure,
    /// The scene-wide thermal passes (the slab model over every facet).
    /// Counted in facets, advanced when the passes are done.
    Thermal,
    /// The images: primary rays, radiometry and sensor, row by row.
    /// Counted in image rows over all the images of the run.
    Rows,
}

impl Stage {
    /// What the stage counts, for messages ("facets", "rows").
    pub fn unit(&self) -> &'static str {
        match self {
            Stage::Load | Stage::Bvh => "",
            Stage::Exposure | Stage::Thermal => "facets",
            Stage::Rows => "rows",
        }
    }
}

/// An observer of a long operation's progress.
///
/// Calls come in this order per stage: [`Progress::start`], then any number
/// of [`Progress::item`] and [`Progress::advance`], then [`Progress::finish`].
/// `advance` may be called from several threads at once. Every method has
/// a do-nothing default, so an observer implements only what it uses.
pub trait Progress: Send + Sync {
    /// `stage` starts; it will advance by `total` in all.
    fn start(&self, stage: Stage, total: u64) {
        let _ = (stage, total);
    }
    /// The stage moves on to the item called `name` (e.g. the output stem
    /// of the image now rendered).
    fn item(&self, name: &str) {
        let _ = name;
    }
    /// `n` more units of the current stage are done.
    fn advance(&self, n: u64) {
        let _ = n;
    }
    /// The current stage is done.
    fn finish(&self) {}
}

/// An observer that ignores everything.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NoProgress;

impl Progress for NoProgress {}
