//! Integration tests of the frf crate.

mod physics;
