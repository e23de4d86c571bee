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

use damping::DampedSystem;
use faer::Mat;
use fe_model::Quantity;
use frf::{Channel, FrfSet, Workspace, ZSolver, equation_of};
use num_complex::Complex64 as C64;
use rayon::prelude::*;

use crate::error::UpdateError;

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

/// Channel layout resolved to equations, reusable across iterations.
#[derive(Clone, Debug)]
pub struct ChannelPlan {
    /// Channels in data order.
    pub channels: Vec<Channel>,
    /// Distinct excitation equations.
    ref_eqs: Vec<usize>,
    /// Distinct response equations (solved as unit columns).
    resp_eqs: Vec<usize>,
    /// Per channel: (index into ref_eqs, index into resp_eqs).
    picks: Vec<(usize, usize)>,
}

impl ChannelPlan {
    /// Resolves channels to equations of a system.
    pub fn new(sys: &DampedSystem, channels: &[Channel]) -> Result<Self, UpdateError> {
        let mut ref_eqs = Vec::new();
        let mut resp_eqs = Vec::new();
        let mut picks = Vec::new();
        for c in channels {
            let r = equation_of(sys, c.reference)?;
            let m = equation_of(sys, c.response)?;
            let ri = ref_eqs.iter().position(|&e| e == r).unwrap_or_else(|| {
                ref_eqs.push(r);
                ref_eqs.len() - 1
            });
            let mi = resp_eqs.iter().position(|&e| e == m).unwrap_or_else(|| {
                resp_eqs.push(m);
                resp_eqs.len() - 1
            });
            picks.push((ri, mi));
        }
        Ok(ChannelPlan { channels: channels.to_vec(), ref_eqs, resp_eqs, picks })
    }

    /// Number of linear solves per frequency.
    pub fn solves_per_frequency(&self) -> usize {
        self.ref_eqs.len() + self.resp_eqs.len()
    }
}

/// Per-thread scratch for [`assemble_one`].
pub struct Scratch {
    ws: Workspace,
    z: Vec<C64>,
    rhs: Mat<C64>,
    x: Vec<C64>,
    w: Vec<(usize, C64)>,
}

impl Scratch {
    /// Scratch for a solver.
    pub fn new(solver: &ZSolver) -> Self {
        Scratch { ws: solver.workspace(), z: Vec::new(), rhs: Mat::zeros(0, 0), x: Vec::new(), w: Vec::new() }
    }
}

/// Model FRFs and sensitivities at one line; see the module docs.
pub fn assemble_one(
    sys: &DampedSystem,
    solver: &ZSolver,
    plan: &ChannelPlan,
    params: &[Quantity],
    freq_hz: f64,
    hybrid: Hybrid<'_>,
    line: usize,
    scratch: &mut Scratch,
) -> Result<FrequencyBlock, UpdateError> {
    let omega = 2.0 * std::f64::consts::PI * freq_hz;
    let n = sys.n();
    let (n_ref, n_resp) = (plan.ref_eqs.len(), plan.resp_eqs.len());
    scratch.z.resize(sys.assembly().pattern.nnz(), C64::new(0.0, 0.0));
    sys.z_values_into(omega, &mut scratch.z);
    solver.factorize(&mut scratch.ws, &scratch.z, freq_hz)?;
    if scratch.rhs.nrows() != n || scratch.rhs.ncols() != n_ref + n_resp {
        scratch.rhs = Mat::zeros(n, n_ref + n_resp);
    } else {
        scratch.rhs.fill(C64::new(0.0, 0.0));
    }
    for (j, &e) in plan.ref_eqs.iter().chain(&plan.resp_eqs).enumerate() {
        scratch.rhs[(e, j)] = C64::new(1.0, 0.0);
    }
    solver.solve_in_place(&mut scratch.ws, scratch.rhs.as_mut(), freq_hz)?;
    let cols = &scratch.rhs;

    let n_ch = plan.channels.len();
    let mut model = vec![C64::new(0.0, 0.0); n_ch];
    for (c, &(ri, mi)) in plan.picks.iter().enumerate() {
        model[c] = cols[(plan.resp_eqs[mi], ri)];
    }
    let derivs: Vec<_> = params.iter().map(|&q| sys.derivative(q, omega)).collect();
    let mut sens = Mat::<C64>::zeros(n_ch, params.len());
    for ri in 0..n_ref {
        // x: the reference's column, with measured rows replaced for the RFM
        scratch.x.clear();
        scratch.x.extend((0..n).map(|i| cols[(i, ri)]));
        if let Hybrid::Measured(meas) = hybrid {
            for (c, &(r2, mi)) in plan.picks.iter().enumerate() {
                if r2 == ri {
                    scratch.x[plan.resp_eqs[mi]] = meas.get(c, line);
                }
            }
        }
        for (i, d) in derivs.iter().enumerate() {
            scratch.w.clear();
            d.apply(sys.assembly(), &scratch.x, &mut scratch.w);
            for (c, &(r2, mi)) in plan.picks.iter().enumerate() {
                if r2 != ri {
                    continue;
                }
                let col = n_ref + mi;
                let mut acc = C64::new(0.0, 0.0);
                for &(eq, val) in &scratch.w {
                    acc += cols[(eq, col)] * val;
                }
                sens[(c, i)] = acc;
            }
        }
    }
    Ok(FrequencyBlock { freq_hz, model, sens })
}

/// [`assemble_one`] over all lines of `freqs_hz`, in parallel. With
/// [`Hybrid::Measured`], the measured set's lines must be `freqs_hz` and its
/// channels `plan.channels`.
pub fn assemble(
    sys: &DampedSystem,
    solver: &ZSolver,
    plan: &ChannelPlan,
    params: &[Quantity],
    freqs_hz: &[f64],
    hybrid: Hybrid<'_>,
) -> Result<Vec<FrequencyBlock>, UpdateError> {
    if let Hybrid::Measured(m) = hybrid {
        assert_eq!(m.frequencies_hz(), freqs_hz, "measured lines must be the assembly lines");
        assert_eq!(m.channels(), plan.channels.as_slice(), "measured channels must be the plan's");
    }
    freqs_hz
        .par_iter()
        .enumerate()
        .map_init(|| Scratch::new(solver), |s, (k, &f)| assemble_one(sys, solver, plan, params, f, hybrid, k, s))
        .collect()
}
