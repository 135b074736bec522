//! (sensor: being written.)
