//! Tests: sun.
