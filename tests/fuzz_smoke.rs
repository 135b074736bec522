//! Tests: fuzz smoke. Every cargo-fuzz target's function (`fuzz/harness.rs`)
//! runs on stable Rust over its seed corpus and a fixed set of seeded,
//! deterministic mutations of it (byte flips, truncations, splices, numbers
//! replaced by NaN/inf/huge/negative values, lines duplicated or dropped).
//! The long coverage-guided runs are `scripts/fuzz` (cargo-fuzz); this keeps
//! every reader's "never panic, always name the file" contract under
//! `cargo test` on every machine.

#[path = "../fuzz/harness.rs"]
mod harness;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::util::repo_path;

/// Values that break naive number handling.
const NASTY: &[&str] = &[
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e309",
    "-1e309",
    "-1",
    "0",
    "-0",
    "1e-320",
    "4294967296",
    "18446744073709551616",
    "-2147483649",
    "999999999",
    "",
    " ",
    "\"\"",
    "null",
    "[]",
    "{}",
    "1.5",
    "0x10",
    "9.",
    ".",
    "-",
    "e5",
];

/// One random mutation of `input`.
fn mutate(rng: &mut ChaCha8Rng, input: &[u8]) -> Vec<u8> {
    let mut v = input.to_vec();
    let n = v.len();
    match rng.random_range(0..9) {
        // Truncate.
        0 if n > 0 => v.truncate(rng.random_range(0..n)),
        // Flip a few bytes.
        1 if n > 0 => {
            for _ in 0..rng.random_range(1..4) {
                let i = rng.random_range(0..n);
                v[i] = rng.random();
            }
        }
        // Delete a range.
        2 if n > 0 => {
            let a = rng.random_range(0..n);
            let b = (a + rng.random_range(1..64)).min(n);
            v.drain(a..b);
        }
        // Duplicate a range elsewhere.
        3 if n > 0 => {
            let a = rng.random_range(0..n);
            let b = (a + rng.random_range(1..128)).min(n);
            let chunk = v[a..b].to_vec();
            let at = rng.random_range(0..=v.len());
            v.splice(at..at, chunk);
        }
        // Replace a number-like token with a nasty value.
        4 | 5 => {
            let starts: Vec<usize> = (0..n)
                .filter(|&i| v[i].is_ascii_digit() && (i == 0 || !v[i - 1].is_ascii_alphanumeric()))
                .collect();
            if !starts.is_empty() {
                let a = starts[rng.random_range(0..starts.len())];
                let mut b = a;
                while b < n && (v[b].is_ascii_digit() || matches!(v[b], b'.' | b'e' | b'-')) {
                    b += 1;
                }
                let s = NASTY[rng.random_range(0..NASTY.len())];
                v.splice(a..b, s.bytes());
            }
        }
        // Drop or duplicate a whole line.
        6 => {
            let lines: Vec<&[u8]> = input.split(|&c| c == b'\n').collect();
            if lines.len() > 1 {
                let i = rng.random_range(0..lines.len());
                let mut out: Vec<&[u8]> = lines.clone();
                if rng.random() {
                    out.remove(i);
                } else {
                    out.insert(i, lines[i]);
                }
                v = out.join(&b'\n');
            }
        }
        // Insert random bytes (binary garbage, NUL, invalid UTF-8).
        7 => {
            let at = rng.random_range(0..=n);
            let k = rng.random_range(1..16);
            let junk: Vec<u8> = (0..k).map(|_| rng.random()).collect();
            v.splice(at..at, junk);
        }
        // Swap two characters' case / separators.
        _ => {
            if n > 0 {
                let i = rng.random_range(0..n);
                v[i] = match v[i] {
                    b',' => b';',
                    b' ' => b'\t',
                    b'\n' => b'\r',
                    c if c.is_ascii_alphabetic() => c ^ 0x20,
                    _ => b',',
                };
            }
        }
    }
    v
}

/// Mutations per target and seed (a few thousand per target in all);
/// `IRSIG_FUZZ_SMOKE_N` overrides.
fn mutations_per_seed(target: &str) -> usize {
    if let Some(n) = std::env::var("IRSIG_FUZZ_SMOKE_N")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        return n;
    }
    match target {
        // Loads materials and builds geometry: slower per input.
        "scene_json" => 400,
        // A whole DIRSIG import (a dozen small files) per input.
        "dirsig_xml" | "dirsig_text" => 300,
        // Large real tape7 files: fewer per seed.
        "tape7" => 200,
        _ => 600,
    }
}

fn run_target(name: &str) {
    let f = harness::TARGETS
        .iter()
        .find(|(n, _)| *n == name)
        .expect("target")
        .1;
    let seeds = harness::seeds(name, &repo_path(""));
    assert!(
        !seeds.is_empty(),
        "no seeds for fuzz target {name}: its seed files are under ../shared/data, which is absent"
    );
    // Seed-derived but stable stream: the same mutations on every run.
    let mut rng = ChaCha8Rng::seed_from_u64(name.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    }));
    let per_seed = mutations_per_seed(name);
    let (mut accepted, mut rejected) = (0usize, 0usize);
    // Real files whose references lie outside the harness's set: mutated too, not
    // required to be accepted.
    let n_valid = seeds.len();
    let mut seeds = seeds;
    seeds.extend(harness::extra_seeds(name, &repo_path("")));
    for (k, seed) in seeds.iter().enumerate() {
        // The seeds are valid inputs: the reader must accept them.
        assert!(k >= n_valid || f(seed), "{name}: seed {k} rejected");
        let mut cur = seed.clone();
        for i in 0..per_seed {
            let m = mutate(&mut rng, &cur);
            match std::panic::catch_unwind(|| f(&m)) {
                Ok(true) => accepted += 1,
                Ok(false) => rejected += 1,
                Err(_) => {
                    let dump =
                        std::env::temp_dir().join(format!("irsig-fuzz-smoke-{name}-{k}-{i}"));
                    let _ = std::fs::write(&dump, &m);
                    panic!("{name}: input written to {} panicked", dump.display());
                }
            }
            // Stack mutations a little, restarting from the seed regularly.
            cur = if i % 4 == 3 { seed.clone() } else { m };
            if cur.len() > 200_000 {
                cur = seed.clone();
            }
        }
    }
    // The mutations reach both the accepting and the rejecting paths (a
    // reader that rejects everything, or nothing, would not be tested).
    eprintln!("{name}: {accepted} mutants accepted, {rejected} rejected");
    assert!(
        accepted > 0 && rejected > 0,
        "{name}: {accepted} accepted, {rejected} rejected"
    );
}

#[test]
fn fuzz_smoke_scene_json() {
    run_target("scene_json");
}
#[test]
fn fuzz_smoke_obj() {
    run_target("obj");
}
#[test]
fn fuzz_smoke_gltf() {
    run_target("gltf");
}
#[test]
fn fuzz_smoke_material_json() {
    run_target("material_json");
}
#[test]
#[ignore = "needs ../shared/data"]
fn fuzz_smoke_dirsig_mat() {
    run_target("dirsig_mat");
}
#[test]
#[ignore = "needs ../shared/data"]
fn fuzz_smoke_dirsig_ems() {
    run_target("dirsig_ems");
}
#[test]
fn fuzz_smoke_weather() {
    run_target("weather");
}
#[test]
#[ignore = "needs ../shared/data"]
fn fuzz_smoke_tape7() {
    run_target("tape7");
}
#[test]
fn fuzz_smoke_response_csv() {
    run_target("response_csv");
}
#[test]
fn fuzz_smoke_params() {
    run_target("params");
}
#[test]
fn fuzz_smoke_points() {
    run_target("points");
}
#[test]
fn fuzz_smoke_dirsig_xml() {
    run_target("dirsig_xml");
}
#[test]
fn fuzz_smoke_dirsig_text() {
    run_target("dirsig_text");
}
#[test]
fn fuzz_smoke_state() {
    run_target("state");
}

/// Issue 8: the inputs `scripts/fuzz` found crashing (kept in
/// `tests/data/fuzz/<target>/`) are rejected cleanly: an OBJ whose relative
/// texture index overflowed inside tobj, a `.wth` header claiming ~10¹⁰ rows
/// (allocation abort), a radiance-mode tape7 without `SOL_SCAT` (`expect`);
/// then, in the 10-minute runs, an EPW row of year 0 whose solar-position
/// error named no file, and a tape7 whose first wavenumber was 0 (infinite
/// wavelength accepted); and glTF inputs crashing inside the gltf crate (a
/// POSITION accessor index out of range panicked in its validation; a GLB
/// header declaring under 12 bytes overflowed a subtraction); and two state
/// shards on which arrow-ipc panicked (a boolean null bitmap shorter than its
/// column; a schema field of type `NONE`; found by the smoke mutations of the
/// `state` target).
#[test]
fn r8_fuzz_crash_regressions() {
    let root = repo_path("tests/data/fuzz");
    let mut n = 0;
    for (name, f) in harness::TARGETS {
        let Ok(dir) = std::fs::read_dir(root.join(name)) else {
            continue;
        };
        for e in dir {
            let p = e.unwrap().path();
            let data = std::fs::read(&p).unwrap();
            assert!(!f(&data), "{}: accepted", p.display());
            n += 1;
        }
    }
    assert_eq!(n, 11, "expected the eleven crash inputs");
}
