//! Scene description: the JSON scene file, objects → parts → facets, built-in
//! primitives and the procedural generators.
