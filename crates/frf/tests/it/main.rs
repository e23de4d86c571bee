//! Integration tests of the frf crate.

mod correlation;
mod lscf;
mod modal;
mod physics;
mod properties;
mod selected_inverse;
mod solver;
mod uff;
