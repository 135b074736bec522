//! (analysis: being written.)
