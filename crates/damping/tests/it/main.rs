//! Integration tests of the damping crate (one binary to keep link time down).

mod complex_modes;
mod modal_physics;
