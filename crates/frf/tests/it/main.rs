//! Integration tests of the frf crate.

mod lscf;
mod modal;
mod physics;
mod uff;
