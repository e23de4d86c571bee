//! Integration tests of fe-model.

mod elements;
mod properties;
