//! Benchmarks of the tracing backends and of the render pipeline.
