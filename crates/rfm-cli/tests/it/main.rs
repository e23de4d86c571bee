//! End-to-end tests of the `rfm` binary.

mod browser;
mod catalogue;
mod commands;
mod diagnose;
mod fixtures;
mod inspect;
mod nothing_lost;
mod report;
