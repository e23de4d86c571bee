//! Integration tests of the frf crate.

mod physics;
mod solver;
