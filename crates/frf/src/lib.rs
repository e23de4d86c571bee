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
//! and writes files atomically; [`correlation`] measures how far a model's
//! FRFs are from measured ones (dB and phase errors, FRAC, per band).
//!
//! # Modal parameters and correlation
//!
//! [`lscf()`] estimates the modes in a band from receptances: the
//! (poly-reference) least-squares complex frequency-domain estimator fits
//! `H_o(w) ~ B_o(z) A(z)^-1` with `z = exp(j w dt)` and real matrix
//! coefficients, over model orders `p`; poles `s = ln(z) / dt` that stay
//! stable in frequency, damping and participation over consecutive orders
//! are kept (the whole stabilisation diagram is returned), then residues and
//! shapes come from a least-squares fit of
//! `H(w) = sum_k [R_k / (j w - s_k) + conj(R_k) / (j w - conj(s_k))] + UR + LR / (j w)^2`.
//! [`modal`] compares model modes ([`model_modes`], from
//! [`damping::complex_modes()`]) with measured ones ([`measured_modes`]) by
//! the MAC, `|a^H b|^2 / ((a^H a)(b^H b))`, and pairs them ([`pair_modes`]).
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
//!
//! Modes from FRFs, paired with the model's:
//!
//! ```
//! use damping::DampedSystem;
//! use fe_model::{Dof, DofRef, samples};
//! use frf::{Channel, LscfOptions, lscf, measured_modes, model_modes, pair_modes, synthesize};
//!
//! let sys = DampedSystem::new(samples::frame_with_joint()).unwrap();
//! let tip = DofRef::new(4, Dof::Uy);
//! let dofs = [DofRef::new(2, Dof::Ux), DofRef::new(4, Dof::Ux), tip];
//! let channels: Vec<Channel> = dofs.iter().map(|&d| Channel::new(d, tip)).collect();
//! let freqs: Vec<f64> = (0..=1920).map(|k| 40.0 + 0.5 * f64::from(k)).collect();
//! let h = synthesize(&sys, &channels, &freqs).unwrap();
//!
//! let estimate = lscf(&h, &LscfOptions::new(40.0, 1000.0)).unwrap();
//! let model = model_modes(&sys, &dofs, 1000.0).unwrap();
//! let pairing = pair_modes(&model, &measured_modes(&estimate), 0.9);
//! assert_eq!(pairing.pairs.len(), 3); // 120, 274 and 663 Hz
//! for p in &pairing.pairs {
//!     assert!(p.frequency_error_pct.abs() < 1e-3 && p.mac > 0.99);
//! }
//! ```

mod channel;
pub mod comparison;
pub mod correlation;
pub mod error;
mod factor_kind;
pub mod io;
mod label;
mod ldlt;
pub mod lscf;
mod mac;
pub mod modal;
pub mod noise;
pub mod set;
pub mod solver;
pub mod synth;

pub use comparison::{ComparisonError, ModalComparison, compare_modes, compare_modes_with};
pub use correlation::{BandSpec, Correlation, correlate};
pub use error::{FileError, FrfError, MismatchError};
pub use lscf::{EstimatedMode, LscfError, LscfOptions, ModalEstimate, PoleStatus, lscf};
pub use modal::{
    Mode, ModeError, ModePair, Pairing, Symptom, mac, mac_matrix, measured_modes, model_modes, pair_modes, symptom,
};
pub use noise::NoiseModel;
pub use set::{Channel, FrfKind, FrfSet};
pub use solver::{FactorKind, Layout, Reach, SelectedInverse, Workspace, ZSolver};
pub use synth::{equation_of, lines_per_job, receptance_columns, synthesize, synthesize_regular, synthesize_with};

/// Complex double.
pub use num_complex::Complex64 as C64;
