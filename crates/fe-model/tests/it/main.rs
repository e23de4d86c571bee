//! Integration tests of fe-model.

mod elements;
mod frame3d;
mod properties;
