//! irsig's integration tests: one binary, one module per concern.
//! Tests that read `../shared/data` are `#[ignore = "needs ../shared/data"]`;
//! `scripts/test` runs them too where that folder exists (CI has it).

mod util;

mod analysis;
mod atmosphere;
mod backends;
mod check_parity;
mod cli;
mod dirsig;
mod exposure;
mod exposure_pipeline;
mod flux;
mod fuzz_smoke;
mod georef;
mod layers;
mod material;
mod per_hit;
mod radiometry;
mod reliability;
mod render;
mod scene;
mod scene_thermal;
mod sensor;
mod state;
mod sun;
mod thermal;
mod weather;
