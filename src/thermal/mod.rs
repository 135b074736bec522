//! (thermal: being written.)
