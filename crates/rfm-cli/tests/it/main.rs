//! End-to-end tests of the `rfm` binary.

mod browser;
mod catalogue;
mod commands;
mod consistency;
mod diagnose;
mod docs;
mod fixtures;
mod gains;
mod imported;
mod imported_diagnosis;
mod inspect;
mod lab_cases;
mod measurement;
mod nothing_lost;
mod pairing;
mod report;
mod space_frame;
mod trust;
