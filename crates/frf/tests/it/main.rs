//! Integration tests of the frf crate.

mod correlation;
mod imported;
mod lscf;
mod modal;
mod physics;
mod planar_in_space;
mod properties;
mod selected_inverse;
mod solver;
mod supernodal;
mod uff;
