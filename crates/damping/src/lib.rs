//! Exponential non-viscous, non-proportional damping for planar frame models.
//!
//! Each group `g` of a [`fe_model::Model`] has Rayleigh-type damping
//! `C_g = alpha_g K_g + beta_g M_g` (alpha multiplies K, the paper's
//! convention) acting through an exponential kernel with relaxation
//! parameter `mu_g` (Adhikari and Woodhouse; Arora, Adhikari and Vijayan 2023,
//! eqs. 1-7):
//!
//! ```text
//! G(w) = sum_g mu_g / (mu_g + j w) C_g          (mu_g = infinity: viscous)
//! Z(w) = K - w^2 M + j w G(w)                   R(w) = Z(w)^-1
//! ```
//!
//! `Z` is complex symmetric, so the receptance `R` is symmetric (reciprocity).
//! [`DampedSystem`] produces `Z(w)` on the model's sparsity pattern and the
//! derivative of `Z` with respect to any model [`fe_model::Quantity`], in the
//! relative form used by the response function method, `(dZ/dp) p`:
//!
//! | p | `(dZ/dp) p` |
//! |---|---|
//! | `alpha_g` | `j w h_g alpha_g K_g` |
//! | `beta_g` | `j w h_g beta_g M_g` |
//! | `mu_g` | `j w [j w mu_g / (mu_g + j w)^2] C_g` |
//! | a stiffness factor (E, spring k, group/element factor) | `(1 + j w h_g alpha_g) K_part` |
//! | a mass factor (rho, lumped or added mass, factor) | `(-w^2 + j w h_g beta_g) M_part` |
//!
//! with `h_g = mu_g / (mu_g + j w)` and `K_part`, `M_part` the share of the
//! group's matrices that the quantity multiplies. Every row is checked
//! against central finite differences in the tests.
//!
//! # Modes
//!
//! [`normal_modes`] gives the undamped modes (`K phi = w^2 M phi`).
//! [`complex_modes()`] gives the exact complex modes of the damped model, the
//! roots of `Z(s) phi = 0` with
//!
//! ```text
//! Z(s) = K + s^2 M + s sum_g mu_g / (mu_g + s) C_g        (s = j w on the frequency axis)
//! ```
//!
//! through a state-space expansion with one internal variable per retained
//! direction of each exponential group's `C_g` (`C_g = sum_i d_i r_i r_i^T`,
//! rank-revealing on the group's DOFs):
//! `s q_i = mu_g (r_i^T s x - q_i)`, `s^2 M x + s C_v x + K x + sum_i d_i r_i q_i = 0`.
//! Oscillatory modes ([`ComplexMode`]: eigenvalue, natural frequency
//! `|s| / 2 pi`, damping ratio `-Re s / |s|`, shape scaled to
//! `phi^T Z'(s) phi = 1` so that the receptance residue is `phi phi^T`) and
//! real non-oscillatory modes ([`RealMode`]: the kernels' relaxation modes and
//! overdamped modes) are reported separately. Dense: a few hundred DOFs; see
//! [`complex_modes`](mod@complex_modes) for the formulation and limits.
//!
//! # Example
//!
//! ```
//! use damping::DampedSystem;
//! use fe_model::samples;
//!
//! let sys = DampedSystem::new(samples::two_material_cantilever()).unwrap();
//! let omega = 2.0 * std::f64::consts::PI * 50.0;
//! let z = sys.z_values(omega); // values on sys.assembly().pattern
//! assert_eq!(z.len(), sys.assembly().pattern().nnz());
//!
//! // the relative derivative with respect to the steel group's relaxation parameter
//! let mu = sys.model().quantity("group.steel.mu").unwrap();
//! let d = sys.derivative(mu, omega);
//! assert!(!d.is_zero());
//!
//! // the complex modes: the first bending mode near 7.9 Hz, lightly damped
//! let modes = damping::complex_modes(&sys).unwrap();
//! let first = &modes.oscillatory[0];
//! assert!((first.frequency_hz - 7.88).abs() < 0.01 && first.damping_ratio < 0.01);
//! ```

pub mod complex_modes;
pub mod eigen;
pub mod kernel;
pub mod modal;
pub mod system;
pub mod units;

pub use complex_modes::{ComplexMode, ComplexModes, RealMode, complex_modes};
pub use kernel::{GroupCoefficients, relaxation_factor};
pub use modal::{ModalError, NormalModes, normal_modes};
pub use system::{DampedSystem, Derivative};
pub use units::UnitStore;

/// Complex double, the scalar of every frequency-domain quantity.
pub use num_complex::Complex64 as C64;
