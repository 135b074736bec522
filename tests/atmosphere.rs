//! Tests: atmosphere.
