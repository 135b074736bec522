//! (atmosphere: being written.)
