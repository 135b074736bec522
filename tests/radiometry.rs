//! Tests: radiometry.
