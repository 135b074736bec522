fn main() {
    println!("cargo:rustc-link-lib=embree3");
    println!("cargo:version=3.13.5");
}
