//! (radiometry: being written.)
