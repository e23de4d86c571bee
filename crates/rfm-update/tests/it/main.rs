//! Integration tests of rfm-update.

mod fast_vs_naive;
mod paper_cases;
mod sensitivity;
