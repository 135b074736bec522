//! Writes every fuzz target's seed inputs to `DIR/<target>/seed-N`, for
//! `scripts/fuzz` (cargo-fuzz starts from the same inputs as the smoke test
//! in `tests/fuzz_smoke.rs`).
//!
//! ```sh
//! cargo run --example fuzz_seeds -- fuzz/corpus
//! ```

#[path = "../fuzz/harness.rs"]
mod harness;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

fn main() -> ExitCode {
    let Some(root) = std::env::args_os().nth(1).map(PathBuf::from) else {
        eprintln!("usage: fuzz_seeds DIR");
        return ExitCode::from(2);
    };
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (name, _) in harness::TARGETS {
        let mut seeds = harness::seeds(name, repo);
        seeds.extend(harness::extra_seeds(name, repo));
        if seeds.is_empty() {
            eprintln!("warning: no seeds for {name} (its seed files are under ../shared/data)");
        }
        let dir = root.join(name);
        let written = std::fs::create_dir_all(&dir).and_then(|()| {
            seeds
                .iter()
                .enumerate()
                .try_for_each(|(i, s)| std::fs::write(dir.join(format!("seed-{i}")), s))
        });
        if let Err(e) = written {
            eprintln!("fuzz_seeds: {}: {e}", dir.display());
            return ExitCode::FAILURE;
        }
    }
    ExitCode::SUCCESS
}
