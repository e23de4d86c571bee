//! Sensitivity assembly per frequency, shared by every solver.
//!
//! For one reference (excitation) DOF `v` with excitation equation `e_v` and
//! measured response equations `m_1..m_r`, at one frequency:
//!
//! 1. factorise `Z_FE(w)` once (sparse);
//! 2. solve for the columns `e_v, e_m1, ..., e_mr` together: the first is
//!    `R_FE,v`; by symmetry of `R` the others are the rows `R_FE[m_k, :]`;
//! 3. form the vector `x`: for the response function method (RFM) the hybrid
//!    column `R_EX,v` (measured values at measured rows, model values
//!    elsewhere, paper section 2); for the output-error Jacobian `R_FE,v`;
//! 4. for each parameter `i` the sparse vector `w_i = (dZ/dp_i p_i) x` over
//!    the few DOFs the parameter touches, and the sensitivity
//!    `S[m_k, i] = R_FE[m_k, :] w_i`, a short dot product.
//!
//! So one factorisation and `(measured + references)` solves per frequency;
//! no dense `N x N` matrix is ever formed. Frequencies run in parallel.
//!
//! RFM equation (paper eq. 12 linearised): `S u = R_FE,v - R_EX,v` at the
//! measured rows. Output-error Jacobian: `dH_FE/dp_i p_i = -S` with `x = R_FE,v`.
//!
//! # How it is made fast
//!
//! - **Solves.** `Z` is factorised as a sparse complex-symmetric `L D L^T`
//!   ([`frf::ZSolver`]), its symbolic analysis shared by every line and iteration.
//!   The `(references + measured)` unit right-hand sides are solved together,
//!   row-interleaved (the values of one equation for every right-hand side
//!   are contiguous, so each elimination step is one vectorised update).
//! - **Terms, not parameters.** A derivative `(dZ/dp_i) p_i` is a sum of
//!   `c_i(w) x value x unit matrix` over the terms of the element blocks it
//!   touches ([`damping::Derivative`]), where `c_i` depends only on the
//!   parameter and the term's group and kind. Terms used by the same
//!   parameters in the same group and kind form a class; step 4 sums
//!   `value x R[m, eqs] (U x)` once per class, and each parameter is a few
//!   class sums times their coefficients (a group's `alpha`, `mu` and
//!   stiffness factor share one sum). The coefficients come from the group
//!   data by the rules of `damping::kernel`; this is checked against
//!   [`damping::DampedSystem::derivative`] when the table is made, and the assembly
//!   falls back to calling it at every line (one class per term) otherwise.
//! - **One sweep.** The products of a block are taken as soon as its rows of
//!   the solution are final in the backward substitution, while they are in
//!   cache, instead of in another pass over the `N x (measured + references)`
//!   block.
//! - **Class sums when they are fewer.** By symmetry of `R`, step 4 can also
//!   be taken the other way round: `R[m, :] w = (Z^-1 w)[m]`, so each class
//!   sum `w = sum value U x` (built in the sweep that solves for `x`) is
//!   solved for once and read at the measured rows. That is
//!   `references x (1 + classes)` solves instead of
//!   `references + measured`; each line uses whichever is fewer (class sums
//!   for the paper's beam: 4 classes against 30 measured DOFs; measured rows
//!   for a diagnosis with a thousand element parameters).
//! - **Prepared once per call.** The term table (blocks bucketed by solver
//!   row, distinct unit matrices stored once) is made once per [`assemble`]
//!   call and shared by the threads, which take the lines in parallel, each
//!   with its own [`Scratch`]. `Z(w)` is the system's own
//!   ([`damping::DampedSystem::z_values_into`]), so the model FRFs here equal those of
//!   [`frf::synthesize_with`] bitwise, which the response function method's
//!   step control relies on near convergence.
//!
//! Per line the cost is one factorisation, `min(measured + references,
//! references x (1 + classes))` solves and `O(measured)` work per used term;
//! the memory per thread is the factor, the `N x` (that many) solutions and
//! the per-class sums; the result is `channels x parameters` per line.
//!
//! [`naive`] is the dense textbook formulation, a reference for tests and
//! benchmarks.

//!
//! # Code
//!
//! [`ChannelPlan`] (`plan.rs`) resolves channels to equations; the
//! frequency-independent preparation is the term table (`terms.rs`, classes
//! and coefficient rules, the unit matrices stored once in
//! [`damping::UnitStore`]); `assemble.rs` takes the
//! lines, one factorisation and one sweep each, with the vectorised
//! products of step 4 in `kernels.rs`.

pub mod naive;

mod assemble;
mod kernels;
mod plan;
mod terms;

use faer::Mat;
use frf::FrfSet;
use num_complex::Complex64 as C64;

pub use assemble::{Scratch, assemble, assemble_one};
pub use plan::ChannelPlan;

const ZERO: C64 = C64 { re: 0.0, im: 0.0 };
/// Most free DOFs of one block: two nodes of a frame in space (a planar
/// model's blocks have at most six).
const MAX_BLOCK: usize = 12;

const NONE: u32 = u32::MAX;

/// Which vector multiplies the derivative of Z (step 3 of the module docs).
#[derive(Clone, Copy, Debug)]
pub enum Hybrid<'a> {
    /// Use measured values at measured rows (response function method).
    Measured(&'a FrfSet),
    /// Use the model's own column (output-error Jacobian).
    Model,
}

/// Model FRFs and sensitivities at one frequency line.
#[derive(Clone, Debug)]
pub struct FrequencyBlock {
    /// The line (Hz).
    pub freq_hz: f64,
    /// Model receptance of each channel.
    pub model: Vec<C64>,
    /// `S[channel, parameter]` (see the module docs).
    pub sens: Mat<C64>,
}

#[cfg(test)]
mod tests {
    use damping::DampedSystem;
    use fe_model::{Dof, DofRef, Quantity, samples};
    use frf::{Channel, ZSolver};

    use super::assemble::{Strategy, assemble_line};
    use super::terms::{Coefficients, TermTable};
    use super::*;

    fn every_kind() -> (DampedSystem, Vec<Quantity>) {
        let mut m = samples::frame_with_joint();
        m.set_added_mass(1, 0.7).unwrap();
        let sys = DampedSystem::new(m).unwrap();
        let names = [
            "group.joint.mu",
            "group.joint.alpha",
            "group.frame.beta",
            "group.frame.stiffness",
            "material.steel.E",
            "element.2.added_mass",
            "spring.joint.kr",
            "mass.tip.j",
        ];
        let params = names.iter().map(|n| sys.model().quantity(n).unwrap()).collect();
        (sys, params)
    }

    /// The model FRFs of an assembly equal the synthesised ones bitwise,
    /// after a parameter changed too (the response function method's step
    /// control compares the two near convergence).
    #[test]
    fn the_assembly_models_are_the_synthesised_ones_bitwise() {
        let (mut sys, params) = every_kind();
        let solver = ZSolver::new(sys.assembly().pattern()).unwrap();
        let r = DofRef::new(4, Dof::Uy);
        let channels = [Channel::new(r, r), Channel::new(DofRef::new(3, Dof::Rz), r)];
        let plan = ChannelPlan::new(&sys, &channels).unwrap();
        let freqs = [3.0, 60.0, 170.0, 400.0];
        for round in 0..2 {
            let blocks = assemble(&sys, &solver, &plan, &params, &freqs, Hybrid::Model).unwrap();
            let synth = frf::synthesize_with(&sys, &solver, &channels, &freqs).unwrap();
            for (k, b) in blocks.iter().enumerate() {
                for c in 0..channels.len() {
                    assert_eq!(b.model[c], synth.get(c, k), "round {round}, channel {c} at {} Hz", freqs[k]);
                }
            }
            sys.set(params[4], 1.1 * sys.get(params[4])).unwrap();
        }
    }

    /// The class sums with coefficient rules, and the fallback with one class
    /// per term and coefficients from `DampedSystem::derivative` at every
    /// line, give the same sensitivities.
    #[test]
    fn coefficient_rules_and_the_derivative_fallback_agree() {
        let (sys, params) = every_kind();
        let solver = ZSolver::new(sys.assembly().pattern()).unwrap();
        let r = DofRef::new(4, Dof::Uy);
        let channels = [Channel::new(r, r), Channel::new(DofRef::new(3, Dof::Rz), r)];
        let plan = ChannelPlan::new(&sys, &channels).unwrap();
        let f = 60.0;
        let omega = 2.0 * std::f64::consts::PI * f;
        let rules = TermTable::build(&sys, &solver, &params, omega, true);
        let fallback = TermTable::build(&sys, &solver, &params, omega, false);
        assert!(matches!(rules.coefficients, Coefficients::Rules(_)), "the rules hold for every kind");
        assert!(matches!(fallback.coefficients, Coefficients::Derivatives(_)));
        assert!(rules.n_classes < fallback.n_classes, "classes merge terms");
        let mut scratch = Scratch::new(&solver);
        let mut at = |table: &TermTable| {
            let strategy = Strategy::MeasuredRows;
            assemble_line(&sys, Some(table), strategy, &solver, &plan, &params, f, Hybrid::Model, 0, &mut scratch)
                .unwrap()
        };
        let (a, b) = (at(&rules), at(&fallback));
        for i in 0..params.len() {
            let scale = (0..channels.len()).map(|c| b.sens[(c, i)].norm()).fold(0.0, f64::max);
            assert!(scale > 0.0);
            for c in 0..channels.len() {
                assert!((a.sens[(c, i)] - b.sens[(c, i)]).norm() <= 1e-12 * scale, "parameter {i}, channel {c}");
            }
        }
    }

    /// A fallback table made at one line serves the others, with the
    /// coefficients of a table made there, and refuses parameters whose
    /// derivatives list other terms (the assembly then makes its own).
    #[test]
    fn a_derivative_table_fits_other_lines_and_refuses_other_terms() {
        let (sys, params) = every_kind();
        let solver = ZSolver::new(sys.assembly().pattern()).unwrap();
        let omega = |f: f64| 2.0 * std::f64::consts::PI * f;
        let table = TermTable::build(&sys, &solver, &params, omega(60.0), false);
        let (mut coef, mut own) = (Vec::new(), Vec::new());
        for f in [3.0, 400.0] {
            assert!(table.coefficients(&sys, &params, omega(f), &mut coef).is_some(), "at {f} Hz");
            let there = TermTable::build(&sys, &solver, &params, omega(f), false);
            there.coefficients(&sys, &params, omega(f), &mut own).unwrap();
            assert_eq!(coef, own, "at {f} Hz");
        }
        // the joint's mu and the frame's beta touch other blocks
        let mut swapped = params.clone();
        swapped.swap(0, 2);
        assert!(table.coefficients(&sys, &swapped, omega(60.0), &mut coef).is_none());
    }

    /// Solving for each class sum and reading the measured rows gives what
    /// the unit solves at the measured rows give, for both hybrid modes.
    #[test]
    fn class_sums_and_measured_rows_agree() {
        let (truth, params) = every_kind();
        let mut sys = truth.clone();
        sys.set(params[0], 1.7 * sys.get(params[0])).unwrap();
        let solver = ZSolver::new(sys.assembly().pattern()).unwrap();
        let (a, b) = (DofRef::new(4, Dof::Uy), DofRef::new(2, Dof::Ux));
        let channels: Vec<Channel> = [(2, Dof::Ux), (3, Dof::Rz), (4, Dof::Uy), (4, Dof::Rz)]
            .iter()
            .flat_map(|&(node, dof)| [Channel::new(DofRef::new(node, dof), a), Channel::new(DofRef::new(node, dof), b)])
            .collect();
        let plan = ChannelPlan::new(&sys, &channels).unwrap();
        let freqs = [35.0, 240.0];
        let measured = frf::synthesize(&truth, &channels, &freqs).unwrap();
        let mut scratch = Scratch::new(&solver);
        for (line, &f) in freqs.iter().enumerate() {
            let table = TermTable::new(&sys, &solver, &params, 2.0 * std::f64::consts::PI * f);
            for hybrid in [Hybrid::Model, Hybrid::Measured(&measured)] {
                let mut run = |strategy| {
                    let t = Some(&table);
                    assemble_line(&sys, t, strategy, &solver, &plan, &params, f, hybrid, line, &mut scratch).unwrap()
                };
                let (rows, sums) = (run(Strategy::MeasuredRows), run(Strategy::ClassSums));
                assert_eq!(rows.model, sums.model);
                for i in 0..params.len() {
                    let scale = (0..channels.len()).map(|c| rows.sens[(c, i)].norm()).fold(0.0, f64::max);
                    assert!(scale > 0.0);
                    for c in 0..channels.len() {
                        let e = (rows.sens[(c, i)] - sums.sens[(c, i)]).norm() / scale;
                        assert!(e < 1e-10, "{hybrid:?} parameter {i} channel {c} at {f} Hz: {e:e}");
                    }
                }
            }
        }
    }
}
