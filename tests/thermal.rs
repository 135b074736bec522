//! Tests: thermal.
