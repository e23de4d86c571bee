//! Integration tests of rfm-update.

mod hidden_effects;
mod output_error;
mod paper_cases;
mod sensitivity;
