//! Finds Debian's Embree 3, generates bindings to the installed `rtcore.h`
//! with bindgen, and compiles a tiny C shim exporting the header-only
//! (`RTC_FORCEINLINE`) helpers.
//!
//! Search order: pkg-config (`embree3`), then `EMBREE_DIR` (a prefix holding
//! `include/embree3/rtcore.h` and `lib/libembree3.so`), then the standard
//! Debian paths. Debian 12's `libembree-dev` ships only a CMake config, no
//! `embree3.pc`, so the last step is the usual one.
//!
//! Metadata for dependants (`links = "embree3"`): `DEP_EMBREE3_VERSION`
//! (e.g. `3.13.5`) and `DEP_EMBREE3_INCLUDE`.

use std::env;
use std::path::{Path, PathBuf};

const FIX: &str = "install Embree 3 and the bindgen prerequisites, on Debian 12: \
     `apt-get install libembree-dev libclang1-14 libclang-common-14-dev pkg-config` \
     (or set EMBREE_DIR to a prefix with include/embree3/rtcore.h and lib/libembree3.so)";

struct Found {
    include: PathBuf,
    link_dirs: Vec<PathBuf>,
}

fn probe_pkg_config() -> Option<Found> {
    match pkg_config::Config::new()
        .range_version("3.0".."4.0")
        .cargo_metadata(true)
        .probe("embree3")
    {
        Ok(lib) => {
            let include = lib
                .include_paths
                .iter()
                .find(|p| p.join("embree3/rtcore.h").exists())
                .cloned()
                .unwrap_or_else(|| PathBuf::from("/usr/include"));
            Some(Found {
                include,
                link_dirs: Vec::new(), // pkg-config already printed them
            })
        }
        Err(e) => {
            // Expected on Debian 12 (no embree3.pc); only informative.
            let msg = e.to_string();
            if !msg.contains("was not found") {
                println!(
                    "cargo:warning=pkg-config embree3: {}",
                    msg.lines().next().unwrap_or("")
                );
            }
            None
        }
    }
}

fn probe_prefix(prefix: &Path) -> Option<Found> {
    let include = prefix.join("include");
    if !include.join("embree3/rtcore.h").exists() {
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
        .find(|d| d.join("libembree3.so").exists())?;
    Some(Found {
        include,
        link_dirs: vec![lib],
    })
}

fn find() -> Found {
    println!("cargo:rerun-if-env-changed=EMBREE_DIR");
    if let Some(dir) = env::var_os("EMBREE_DIR") {
        let dir = PathBuf::from(dir);
        return probe_prefix(&dir).unwrap_or_else(|| {
            panic!(
                "EMBREE_DIR={} has no include/embree3/rtcore.h with lib/libembree3.so; {FIX}",
                dir.display()
            )
        });
    }
    if let Some(f) = probe_pkg_config() {
        return f;
    }
    if let Some(f) = probe_prefix(Path::new("/usr")) {
        return f;
    }
    if let Some(f) = probe_prefix(Path::new("/usr/local")) {
        return f;
    }
    panic!("Embree 3 not found (tried pkg-config `embree3`, EMBREE_DIR, /usr, /usr/local): {FIX}");
}

/// `(major, minor, patch)` from `rtcore_config.h`.
fn version(include: &Path) -> (u32, u32, u32) {
    let cfg = include.join("embree3/rtcore_config.h");
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

/// bindgen loads libclang at run time; Debian's `libclang1-14` puts it where
/// clang-sys may not look. Point it there unless the user chose already.
fn libclang_hint() {
    println!("cargo:rerun-if-env-changed=LIBCLANG_PATH");
    if env::var_os("LIBCLANG_PATH").is_some() {
        return;
    }
    for dir in ["/usr/lib/llvm-14/lib", "/usr/lib/x86_64-linux-gnu"] {
        let d = Path::new(dir);
        if d.join("libclang.so.1").exists() || d.join("libclang-14.so.1").exists() {
            // SAFETY: build scripts are single-threaded at this point; nothing
            // else reads or writes the environment concurrently.
            unsafe { env::set_var("LIBCLANG_PATH", d) };
            return;
        }
    }
}

fn main() {
    let found = find();
    let (major, minor, patch) = version(&found.include);
    if major != 3 {
        panic!(
            "found Embree {major}.{minor}.{patch} at {}, but irsig needs Embree 3.x; {FIX}",
            found.include.display()
        );
    }
    for d in &found.link_dirs {
        println!("cargo:rustc-link-search=native={}", d.display());
    }
    println!("cargo:rustc-link-lib=dylib=embree3");
    println!("cargo:version={major}.{minor}.{patch}");
    println!("cargo:rustc-env=EMBREE_SYS_VERSION={major}.{minor}.{patch}");
    println!("cargo:include={}", found.include.display());

    let header = found.include.join("embree3/rtcore.h");
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
        .warnings(true)
        .compile("embree_sys_shim");
}
