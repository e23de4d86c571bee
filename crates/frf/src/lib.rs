//! Frequency response functions of non-viscously damped models: synthesis,
//! noise, containers and file formats.
//!
//! The receptance of a [`damping::DampedSystem`] is
//!
//! ```text
//! H(w) = Z(w)^-1,   Z(w) = K - w^2 M + j w sum_g mu_g/(mu_g + j w) C_g
//! ```
//!
//! and is never formed densely: [`ZSolver`] analyses the sparsity pattern once
//! (fill-reducing ordering), then each frequency line costs one numeric sparse
//! complex-symmetric `L D L^T` factorisation (LU with pivoting as a fallback)
//! and one solve per excitation DOF ([`synthesize`]); lines are spread over
//! rayon threads, each with its own reusable [`solver::Workspace`].
//! Because `Z` is complex symmetric, `H` is symmetric (reciprocity).
//!
//! [`FrfSet`] holds FRFs over common lines for a list of [`Channel`]s
//! (response DOF over reference DOF) and is shared by synthesised and
//! measured data; [`NoiseModel`] adds documented, seeded noise; [`io`] reads
//! and writes files atomically.
//!
//! # Example
//!
//! ```
//! use damping::DampedSystem;
//! use fe_model::{Dof, DofRef, samples};
//! use frf::{Channel, NoiseModel, synthesize};
//!
//! let sys = DampedSystem::new(samples::two_material_cantilever()).unwrap();
//! let tip = DofRef::new(31, Dof::Uy);
//! let mid = DofRef::new(16, Dof::Uy);
//! let channels = [Channel::new(tip, tip), Channel::new(mid, tip)];
//! let freqs: Vec<f64> = (1..=400).map(f64::from).collect();
//! let mut h = synthesize(&sys, &channels, &freqs).unwrap();
//! assert_eq!(h.channel(0).len(), 400);
//!
//! NoiseModel::relative(0.01, 42).apply(&mut h); // 1 % complex noise, seed 42
//! ```

pub mod error;
pub mod io;
mod ldlt;
pub mod noise;
pub mod set;
pub mod solver;
pub mod synth;

pub use error::FrfError;
pub use noise::NoiseModel;
pub use set::{Channel, FrfKind, FrfSet};
pub use solver::{FactorKind, Workspace, ZSolver};
pub use synth::{equation_of, receptance_columns, synthesize, synthesize_with};

/// Complex double.
pub use num_complex::Complex64 as C64;
