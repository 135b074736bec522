//! Raw bindings to Embree 3 (placeholder until bindgen generation lands).
