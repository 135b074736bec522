//! Scene description: the JSON scene file, objects → parts → facets, built-in
//! primitives and the procedural generators.

pub mod jsonloc;
pub mod obj;

pub use obj::{ObjGroup, load_obj};
