//! Integration tests of fe-model.

mod properties;
