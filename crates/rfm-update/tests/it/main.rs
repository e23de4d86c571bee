//! Integration tests of rfm-update.

mod paper_cases;
mod sensitivity;
