//! Build script of the `irsig` crate: exposes the Embree version that
//! `embree-sys` found (via its `links = "embree3"` metadata) to `--version`.
fn main() {
    println!("cargo:rerun-if-env-changed=DEP_EMBREE3_VERSION");
    let v = std::env::var("DEP_EMBREE3_VERSION").unwrap_or_else(|_| "unknown".into());
    println!("cargo:rustc-env=IRSIG_EMBREE_VERSION={v}");
}
