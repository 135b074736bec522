//! Tests: scene.
