//! Integration tests of rfm-update.

mod hidden_effects;
mod paper_cases;
mod sensitivity;
