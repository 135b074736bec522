//! Tests: material.
