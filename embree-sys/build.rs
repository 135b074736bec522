//! Finds Debian's Embree (4 or 3), generates bindings to the installed
//! `rtcore.h` with bindgen, and compiles a tiny C shim exporting the
//! header-only (`RTC_FORCEINLINE`) helpers.
//!
//! Search order: `EMBREE_DIR` (a prefix holding `include/embree4/rtcore.h`
//! and `lib/libembree4.so`, or the same for `embree3`), then pkg-config
//! (`embree4`, then `embree3`), then the standard paths `/usr` and
//! `/usr/local`. Where both versions are installed, Embree 4 is taken unless
//! `EMBREE_VERSION=3`. Debian ships only CMake configs, no `.pc` files, so
//! the paths are the usual way: Debian 12's `libembree-dev` is Embree 3.13
//! (`embree3/`), Debian 13's is Embree 4.3 (`embree4/`).
//!
//! The API differs between the two (Embree 4: `RTCRayQueryContext`,
//! `RTCIntersectArguments`/`RTCOccludedArguments` instead of
//! `RTCIntersectContext`, no stream API); the safe layer in `irsig` handles
//! it behind `cfg(embree4)`, set here for this crate and, through the
//! `links = "embree"` metadata (`DEP_EMBREE_MAJOR`), by irsig's build.rs.
//!
//! Metadata for dependants: `DEP_EMBREE_VERSION` (e.g. `4.3.3`),
//! `DEP_EMBREE_MAJOR` (`3` or `4`) and `DEP_EMBREE_INCLUDE`.

use std::env;
use std::path::{Path, PathBuf};

const FIX: &str = "install Embree and the bindgen prerequisites: on Debian 13 \
     `apt-get install libembree-dev libclang-dev pkg-config gcc` (Embree 4), on Debian 12 \
     `apt-get install libembree-dev libclang1-14 libclang-common-14-dev pkg-config gcc` \
     (Embree 3); or set EMBREE_DIR to a prefix with include/embree4/rtcore.h and \
     lib/libembree4.so (or embree3)";

struct Found {
    /// `embree4` or `embree3`: the header folder and library name.
    name: &'static str,
    include: PathBuf,
    link_dirs: Vec<PathBuf>,
    how: String,
}

/// The names to try, preferred first (`EMBREE_VERSION` narrows them).
fn names() -> Vec<&'static str> {
    println!("cargo:rerun-if-env-changed=EMBREE_VERSION");
    match env::var("EMBREE_VERSION").as_deref() {
        Ok("3") => vec!["embree3"],
        Ok("4") => vec!["embree4"],
        Ok(v) => panic!("EMBREE_VERSION={v}: expected 3 or 4"),
        Err(_) => vec!["embree4", "embree3"],
    }
}

fn probe_pkg_config(name: &'static str) -> Option<Found> {
    let range = if name == "embree4" {
        "4.0".."5.0"
    } else {
        "3.0".."4.0"
    };
    match pkg_config::Config::new()
        .range_version(range)
        .cargo_metadata(true)
        .probe(name)
    {
        Ok(lib) => {
            let include = lib
                .include_paths
                .iter()
                .find(|p| p.join(name).join("rtcore.h").exists())
                .cloned()
                .unwrap_or_else(|| PathBuf::from("/usr/include"));
            Some(Found {
                name,
                include,
                link_dirs: Vec::new(), // pkg-config already printed them
                how: format!("pkg-config {name}"),
            })
        }
        Err(e) => {
            // Expected on Debian (no .pc files); only informative.
            let msg = e.to_string();
            if !msg.contains("was not found") {
                println!(
                    "cargo:warning=pkg-config {name}: {}",
                    msg.lines().next().unwrap_or("")
                );
            }
            None
        }
    }
}

fn probe_prefix(prefix: &Path, name: &'static str) -> Option<Found> {
    let include = prefix.join("include");
    if !include.join(name).join("rtcore.h").exists() {
        return None;
    }
    let candidates = [
        prefix.join("lib"),
        prefix.join("lib64"),
        prefix.join("lib/x86_64-linux-gnu"),
        prefix.join("lib/aarch64-linux-gnu"),
    ];
    let lib = candidates
        .into_iter()
        .find(|d| d.join(format!("lib{name}.so")).exists())?;
    Some(Found {
        name,
        include,
        link_dirs: vec![lib],
        how: format!("{}", prefix.display()),
    })
}

fn find() -> Found {
    let names = names();
    println!("cargo:rerun-if-env-changed=EMBREE_DIR");
    if let Some(dir) = env::var_os("EMBREE_DIR") {
        let dir = PathBuf::from(dir);
        return names
            .iter()
            .find_map(|n| probe_prefix(&dir, n))
            .map(|f| Found {
                how: format!("EMBREE_DIR={}", dir.display()),
                ..f
            })
            .unwrap_or_else(|| {
                panic!(
                    "EMBREE_DIR={} has no include/{{{}}}/rtcore.h with the matching lib/lib*.so; {FIX}",
                    dir.display(),
                    names.join(",")
                )
            });
    }
    for n in &names {
        if let Some(f) = probe_pkg_config(n) {
            return f;
        }
    }
    for prefix in ["/usr", "/usr/local"] {
        for n in &names {
            if let Some(f) = probe_prefix(Path::new(prefix), n) {
                return f;
            }
        }
    }
    panic!(
        "Embree not found (tried EMBREE_DIR, pkg-config {}, /usr, /usr/local): {FIX}",
        names.join(" and ")
    );
}

/// `(major, minor, patch)` from `rtcore_config.h`.
fn version(found: &Found) -> (u32, u32, u32) {
    let cfg = found.include.join(found.name).join("rtcore_config.h");
    let text = std::fs::read_to_string(&cfg)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}; {FIX}", cfg.display()));
    let get = |name: &str| -> u32 {
        text.lines()
            .find_map(|l| {
                let mut w = l.split_whitespace();
                (w.next() == Some("#define") && w.next() == Some(name))
                    .then(|| w.next().and_then(|v| v.parse().ok()))
                    .flatten()
            })
            .unwrap_or_else(|| panic!("{}: no `#define {name}`; {FIX}", cfg.display()))
    };
    (
        get("RTC_VERSION_MAJOR"),
        get("RTC_VERSION_MINOR"),
        get("RTC_VERSION_PATCH"),
    )
}

/// bindgen loads libclang at run time; Debian puts it where clang-sys may
/// not look (`/usr/lib/llvm-N/lib`). Point it at the newest there unless the
/// user chose already.
fn libclang_hint() {
    println!("cargo:rerun-if-env-changed=LIBCLANG_PATH");
    if env::var_os("LIBCLANG_PATH").is_some() {
        return;
    }
    let mut llvm: Vec<(u32, PathBuf)> = std::fs::read_dir("/usr/lib")
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            let v = name.strip_prefix("llvm-")?.parse().ok()?;
            Some((v, e.path().join("lib")))
        })
        .collect();
    llvm.sort();
    let dirs = llvm
        .into_iter()
        .rev()
        .map(|(_, d)| d)
        .chain([PathBuf::from("/usr/lib/x86_64-linux-gnu")]);
    for d in dirs {
        let has = std::fs::read_dir(&d)
            .into_iter()
            .flatten()
            .flatten()
            .any(|e| {
                e.file_name()
                    .to_str()
                    .is_some_and(|n| n.starts_with("libclang") && n.contains(".so"))
            });
        if has {
            // SAFETY: build scripts are single-threaded at this point; nothing
            // else reads or writes the environment concurrently.
            unsafe { env::set_var("LIBCLANG_PATH", &d) };
            return;
        }
    }
}

fn main() {
    let found = find();
    let (major, minor, patch) = version(&found);
    let expected = if found.name == "embree4" { 4 } else { 3 };
    if major != expected {
        panic!(
            "{}/{}/rtcore_config.h says Embree {major}.{minor}.{patch}, expected {expected}.x; {FIX}",
            found.include.display(),
            found.name
        );
    }
    println!(
        "cargo:warning=embree-sys: using Embree {major}.{minor}.{patch} \
         (headers {}/{}, lib{}.so; found by {})",
        found.include.display(),
        found.name,
        found.name,
        found.how
    );
    for d in &found.link_dirs {
        println!("cargo:rustc-link-search=native={}", d.display());
    }
    println!("cargo:rustc-link-lib=dylib={}", found.name);
    println!("cargo:rustc-check-cfg=cfg(embree4)");
    if major == 4 {
        println!("cargo:rustc-cfg=embree4");
    }
    println!("cargo:version={major}.{minor}.{patch}");
    println!("cargo:major={major}");
    println!("cargo:rustc-env=EMBREE_SYS_VERSION={major}.{minor}.{patch}");
    println!("cargo:include={}", found.include.display());

    let header = found.include.join(found.name).join("rtcore.h");
    println!("cargo:rerun-if-changed={}", header.display());
    println!("cargo:rerun-if-changed=shim/shim.c");

    libclang_hint();
    let bindings = bindgen::Builder::default()
        .header(header.to_string_lossy())
        .clang_arg(format!("-I{}", found.include.display()))
        .allowlist_function("rtc.*")
        .allowlist_type("RTC.*")
        .allowlist_var("RTC.*")
        .default_enum_style(bindgen::EnumVariation::Consts)
        .prepend_enum_name(false)
        .layout_tests(true)
        .derive_default(true)
        .generate()
        .unwrap_or_else(|e| panic!("bindgen failed on {}: {e}; {FIX}", header.display()));
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    bindings
        .write_to_file(out.join("bindings.rs"))
        .expect("write bindings.rs");

    cc::Build::new()
        .file("shim/shim.c")
        .include(&found.include)
        .define(
            if major == 4 {
                "EMBREE_SYS_4"
            } else {
                "EMBREE_SYS_3"
            },
            None,
        )
        .warnings(true)
        .compile("embree_sys_shim");
}
