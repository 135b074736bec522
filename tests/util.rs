//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// The project's `../shared/data/<sub>` folder, or `None` (with a printed
/// notice) where it is absent, as on a user's fresh clone.
pub fn shared_data(sub: &str) -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data")
        .join(sub);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("notice: {} is absent; skipping this test", p.display());
        None
    }
}

/// Path of a file in the repository.
pub fn repo_path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Path of the built `irsig` binary, for CLI tests.
pub fn irsig_bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_irsig"))
}
