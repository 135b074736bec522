//! Build script of the `irsig` crate: exposes the Embree version that
//! `embree-sys` found (via its `links = "embree"` metadata) to `--version`,
//! and sets `cfg(embree4)` when it is Embree 4, for the version-specific
//! parts of `trace::embree`.
fn main() {
    println!("cargo:rerun-if-env-changed=DEP_EMBREE_VERSION");
    println!("cargo:rerun-if-env-changed=DEP_EMBREE_MAJOR");
    let v = std::env::var("DEP_EMBREE_VERSION").unwrap_or_else(|_| "unknown".into());
    println!("cargo:rustc-env=IRSIG_EMBREE_VERSION={v}");
    println!("cargo:rustc-check-cfg=cfg(embree4)");
    if std::env::var("DEP_EMBREE_MAJOR").as_deref() == Ok("4") {
        println!("cargo:rustc-cfg=embree4");
    }
}
