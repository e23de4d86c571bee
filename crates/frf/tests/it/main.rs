//! Integration tests of the frf crate.

mod correlation;
mod lscf;
mod modal;
mod physics;
mod solver;
mod uff;
