//! Integration tests of rfm-update.

mod apply_every;
mod bending_loss;
mod calibration;
mod coherence_noise;
mod fast_vs_naive;
mod held_out;
mod hidden_effects;
mod hidden_effects_3d;
mod lab;
mod lab_study;
mod noise_estimate;
mod numerics;
mod output_error;
mod paper_cases;
mod per_direction;
mod resonators;
mod sensitivity;
mod setup_checks;
mod study;
mod trust;
mod truths;
