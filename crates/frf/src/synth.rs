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
    match sys.assembly().dofs().slot(dof) {
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
    z.resize(sys.assembly().pattern().nnz(), C64::new(0.0, 0.0));
    sys.z_values_into(omega, z);
    solver.factorize(ws, z, freq_hz)?;
    let mut rhs = Mat::<C64>::zeros(sys.n(), excitation.len());
    for (j, &e) in excitation.iter().enumerate() {
        rhs[(e, j)] = C64::new(1.0, 0.0);
    }
    solver.solve_in_place(ws, rhs.as_mut(), freq_hz)?;
    Ok(rhs)
}

/// The fewest lines one parallel job takes, when each job prepares its own
/// workspace of a factorisation (`map_init`): at most two jobs per thread.
/// Left to itself rayon split 20 lines of a 100,000-DOF frame into 16
/// jobs, each allocating and first touching the workspace of a factor of
/// millions of entries; two per thread still lets an idle thread take over
/// half of a busy one's lines.
pub fn lines_per_job(lines: usize) -> usize {
    lines.div_ceil(2 * rayon::current_num_threads()).max(1)
}

/// Synthesises receptance FRFs of a damped model for the given channels and
/// frequency lines (Hz): one sparse factorisation per line and one solve per
/// distinct reference, lines spread over rayon threads.
pub fn synthesize(sys: &DampedSystem, channels: &[Channel], freqs_hz: &[f64]) -> Result<FrfSet, FrfError> {
    let solver = ZSolver::new(sys.assembly().pattern())?;
    synthesize_with(sys, &solver, channels, freqs_hz)
}

/// As [`synthesize`], with a solver prepared for this model's pattern.
pub fn synthesize_with(
    sys: &DampedSystem,
    solver: &ZSolver,
    channels: &[Channel],
    freqs_hz: &[f64],
) -> Result<FrfSet, FrfError> {
    Ok(synthesize_lines(sys, solver, channels, freqs_hz, false)?.0)
}

/// As [`synthesize`], except that a line where `Z` is singular
/// ([`FrfError::Singular`]) gets NaN values instead of failing the whole
/// set; those lines (Hz) are returned beside it. For figures of a model that
/// may be singular at a few lines, such as the result of an updating run
/// that wandered off (correlations and plots leave non-finite values out).
pub fn synthesize_regular(
    sys: &DampedSystem,
    channels: &[Channel],
    freqs_hz: &[f64],
) -> Result<(FrfSet, Vec<f64>), FrfError> {
    let solver = ZSolver::new(sys.assembly().pattern())?;
    synthesize_lines(sys, &solver, channels, freqs_hz, true)
}

/// The FRFs at every line, and with `lenient` NaN at the singular lines
/// (listed) instead of an error.
fn synthesize_lines(
    sys: &DampedSystem,
    solver: &ZSolver,
    channels: &[Channel],
    freqs_hz: &[f64],
    lenient: bool,
) -> Result<(FrfSet, Vec<f64>), FrfError> {
    let mut set = FrfSet::zeros(freqs_hz.to_vec(), channels.to_vec(), FrfKind::Receptance)?;
    let refs = set.references();
    let ref_eqs: Vec<usize> = refs.iter().map(|&r| equation_of(sys, r)).collect::<Result<_, _>>()?;
    // (response equation, reference column) of every channel
    let picks: Vec<(usize, usize)> = channels
        .iter()
        .map(|c| Ok((equation_of(sys, c.response)?, refs.iter().position(|&r| r == c.reference).unwrap())))
        .collect::<Result<_, FrfError>>()?;
    // collected per line and then read in order: a parallel collect into
    // one `Result` keeps whichever thread's error came first, so the line a
    // failure names would change from run to run
    //
    // Only the rows read are solved for: the references' and responses'
    // equations and their ancestors in the elimination tree (a few
    // thousand of the 100,000-DOF frame's rows), the same numbers as the
    // whole solve at a fraction of its cost, which on that frame was two
    // thirds of the factorisation's.
    let k = ref_eqs.len();
    let within = solver.reach(ref_eqs.iter().copied().chain(picks.iter().map(|&(r, _)| r)));
    let read: Vec<usize> = picks.iter().map(|&(r, j)| solver.position(r) * k + j).collect();
    let lines: Vec<Result<Option<Vec<C64>>, FrfError>> = freqs_hz
        .par_iter()
        .with_min_len(lines_per_job(freqs_hz.len()))
        .map_init(
            || (solver.workspace(), Vec::new(), Vec::new()),
            |(ws, z, x), &f| {
                let mut line = || -> Result<(), FrfError> {
                    z.resize(sys.assembly().pattern().nnz(), C64::new(0.0, 0.0));
                    sys.z_values_into(2.0 * std::f64::consts::PI * f, z);
                    solver.factorize(ws, z, f)?;
                    solver.solve_units_within(ws, &ref_eqs, &within, x, f)
                };
                match line() {
                    Ok(()) => Ok(Some(read.iter().map(|&at| x[at]).collect())),
                    Err(FrfError::Singular { .. }) if lenient => Ok(None),
                    Err(e) => Err(e),
                }
            },
        )
        .collect();
    let lines: Vec<Option<Vec<C64>>> = lines.into_iter().collect::<Result<_, FrfError>>()?;
    let mut singular = Vec::new();
    for (k, line) in lines.iter().enumerate() {
        match line {
            Some(line) => line.iter().enumerate().for_each(|(c, &v)| set.set(c, k, v)),
            None => {
                singular.push(freqs_hz[k]);
                (0..channels.len()).for_each(|c| set.set(c, k, C64::new(f64::NAN, f64::NAN)));
            }
        }
    }
    Ok((set, singular))
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::{Dof, samples};

    /// A dynamic stiffness that overflows at every line is refused at the
    /// first line, whichever thread meets its line first.
    #[test]
    fn a_failure_names_the_first_failing_line_every_time() {
        let mut sys = DampedSystem::new(samples::cantilever(4)).unwrap();
        let alpha = sys.model().quantity("group.beam.alpha").unwrap();
        sys.set(alpha, 1e300).unwrap();
        let tip = DofRef::new(5, Dof::Uy);
        let lines: Vec<f64> = (1..=400).map(f64::from).collect();
        // more threads than cores, so that the chunks of later lines often
        // fail before the first one
        let pool = rayon::ThreadPoolBuilder::new().num_threads(8).build().unwrap();
        for _ in 0..50 {
            match pool.install(|| synthesize(&sys, &[Channel::new(tip, tip)], &lines)).unwrap_err() {
                FrfError::NonFiniteZ { freq_hz, .. } => assert_eq!(freq_hz, 1.0),
                e => panic!("{e}"),
            }
        }
    }

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

    /// An undamped spring-mass evaluated exactly on its resonance: the
    /// strict synthesis refuses the set, the lenient one leaves that line
    /// out (NaN) and agrees with the strict one everywhere else.
    #[test]
    fn only_the_singular_line_is_left_out_of_a_lenient_synthesis() {
        let mut m = fe_model::Model::new("spring-mass");
        let g = m.add_group(fe_model::Group::new("g")).unwrap();
        m.add_node(1, 0.0, 0.0).unwrap();
        let (k, mass) = (4.0e4, 1.0);
        m.add_spring("s", 1, None, [k, k, k], g).unwrap();
        m.add_mass("m", 1, mass, mass, g).unwrap();
        let sys = DampedSystem::new(m).unwrap();
        let resonance = (k / mass).sqrt() / (2.0 * std::f64::consts::PI);
        let lines = [0.5 * resonance, resonance, 1.5 * resonance];
        let ch = [Channel::new(DofRef::new(1, Dof::Uy), DofRef::new(1, Dof::Uy))];
        assert_eq!(synthesize(&sys, &ch, &lines).unwrap_err(), FrfError::Singular { freq_hz: resonance });
        let (set, singular) = synthesize_regular(&sys, &ch, &lines).unwrap();
        assert_eq!(singular, vec![resonance]);
        assert!(set.get(0, 1).re.is_nan() && set.get(0, 1).im.is_nan());
        let regular = synthesize(&sys, &ch, &[lines[0], lines[2]]).unwrap();
        assert_eq!((set.get(0, 0), set.get(0, 2)), (regular.get(0, 0), regular.get(0, 1)));
        // receptance of a spring-mass: 1 / (k - w^2 m)
        let w = 2.0 * std::f64::consts::PI * lines[0];
        assert!((set.get(0, 0).re - 1.0 / (k - w * w * mass)).abs() < 1e-12 / k);
    }
}
