//! End-to-end tests of the `rfm` binary.

mod catalogue;
mod commands;
mod diagnose;
mod gains;
mod measurement;
mod inspect;
mod nothing_lost;
mod report;
