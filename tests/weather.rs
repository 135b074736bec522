//! Tests: weather.
