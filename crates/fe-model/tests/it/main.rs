//! Integration tests of fe-model.

mod bending;
mod elements;
mod frame3d;
mod properties;
mod spring_axes;
