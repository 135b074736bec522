//! Tests: sensor.
