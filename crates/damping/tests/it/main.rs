//! Integration tests of the damping crate (one binary to keep link time down).

mod complex_modes;
mod derivatives;
mod frames_3d;
mod imported_damping;
mod modal_physics;
mod spring_axes;
