//! Tests: exposure (solar history, shape factor, background).
