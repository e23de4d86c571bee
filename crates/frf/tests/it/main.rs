//! Integration tests of the frf crate.

mod correlation;
mod physics;
