//! Integration tests of rfm-update.

mod fast_vs_naive;
mod hidden_effects;
mod numerics;
mod output_error;
mod paper_cases;
mod sensitivity;
mod truths;
