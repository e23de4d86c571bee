//! Integration tests of the damping crate (one binary to keep link time down).

mod modal_physics;
