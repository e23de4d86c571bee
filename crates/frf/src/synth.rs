//! FRF synthesis: `H(w) = Z(w)^-1` at the channels' rows and columns.

use damping::DampedSystem;
use faer::Mat;
use fe_model::{DofRef, Slot};
use num_complex::Complex64 as C64;
use rayon::prelude::*;

use crate::error::FrfError;
use crate::set::{Channel, FrfKind, FrfSet};
use crate::solver::ZSolver;

/// Equation index of a DOF, or a located error.
pub fn equation_of(sys: &DampedSystem, dof: DofRef) -> Result<usize, FrfError> {
    match sys.assembly().dofs.slot(dof) {
        Some(Slot::Free(eq)) => Ok(eq),
        Some(Slot::Fixed) => Err(FrfError::FixedDof { dof }),
        None => Err(FrfError::UnknownDof { dof }),
    }
}

/// Receptance columns `R(w) e_j` for the given excitation equations at one
/// angular frequency, using a prepared solver and workspace.
pub fn receptance_columns(
    sys: &DampedSystem,
    solver: &ZSolver,
    ws: &mut crate::solver::Workspace,
    z: &mut Vec<C64>,
    freq_hz: f64,
    excitation: &[usize],
) -> Result<Mat<C64>, FrfError> {
    let omega = 2.0 * std::f64::consts::PI * freq_hz;
    z.resize(sys.assembly().pattern.nnz(), C64::new(0.0, 0.0));
    sys.z_values_into(omega, z);
    solver.factorize(ws, z, freq_hz)?;
    let mut rhs = Mat::<C64>::zeros(sys.n(), excitation.len());
    for (j, &e) in excitation.iter().enumerate() {
        rhs[(e, j)] = C64::new(1.0, 0.0);
    }
    solver.solve_in_place(ws, rhs.as_mut(), freq_hz)?;
    Ok(rhs)
}

/// Synthesises receptance FRFs of a damped model for the given channels and
/// frequency lines (Hz): one sparse factorisation per line and one solve per
/// distinct reference, lines spread over rayon threads.
pub fn synthesize(sys: &DampedSystem, channels: &[Channel], freqs_hz: &[f64]) -> Result<FrfSet, FrfError> {
    let solver = ZSolver::new(&sys.assembly().pattern)?;
    synthesize_with(sys, &solver, channels, freqs_hz)
}

/// As [`synthesize`], with a solver prepared for this model's pattern.
pub fn synthesize_with(
    sys: &DampedSystem,
    solver: &ZSolver,
    channels: &[Channel],
    freqs_hz: &[f64],
) -> Result<FrfSet, FrfError> {
    let mut set = FrfSet::zeros(freqs_hz.to_vec(), channels.to_vec(), FrfKind::Receptance)?;
    let refs = set.references();
    let ref_eqs: Vec<usize> = refs.iter().map(|&r| equation_of(sys, r)).collect::<Result<_, _>>()?;
    // (response equation, reference column) of every channel
    let picks: Vec<(usize, usize)> = channels
        .iter()
        .map(|c| Ok((equation_of(sys, c.response)?, refs.iter().position(|&r| r == c.reference).unwrap())))
        .collect::<Result<_, FrfError>>()?;
    let lines: Vec<Vec<C64>> = freqs_hz
        .par_iter()
        .map_init(
            || (solver.workspace(), Vec::new()),
            |(ws, z), &f| {
                let cols = receptance_columns(sys, solver, ws, z, f, &ref_eqs)?;
                Ok(picks.iter().map(|&(r, j)| cols[(r, j)]).collect())
            },
        )
        .collect::<Result<_, FrfError>>()?;
    for (k, line) in lines.iter().enumerate() {
        for (c, &v) in line.iter().enumerate() {
            set.set(c, k, v);
        }
    }
    Ok(set)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::{Dof, samples};

    #[test]
    fn fixed_and_unknown_dofs_are_refused_by_name() {
        let sys = DampedSystem::new(samples::cantilever(4)).unwrap();
        let bad = Channel::new(DofRef::new(1, Dof::Uy), DofRef::new(5, Dof::Uy));
        assert_eq!(synthesize(&sys, &[bad], &[10.0]).unwrap_err(), FrfError::FixedDof { dof: DofRef::new(1, Dof::Uy) });
        let bad = Channel::new(DofRef::new(9, Dof::Uy), DofRef::new(5, Dof::Uy));
        assert_eq!(
            synthesize(&sys, &[bad], &[10.0]).unwrap_err(),
            FrfError::UnknownDof { dof: DofRef::new(9, Dof::Uy) }
        );
    }
}
