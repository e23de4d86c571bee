//! The assembly over lines: per line one factorisation and one sweep, by
//! unit solves at the measured rows or by solves with the class sums,
//! whichever is fewer; lines in parallel.

use std::sync::{Mutex, PoisonError};

use damping::DampedSystem;
use faer::Mat;
use faer::traits::pulp::Arch;
use fe_model::Quantity;
use frf::{Workspace, ZSolver};
use num_complex::Complex64 as C64;
use rayon::prelude::*;

use super::kernels::BucketProducts;
use super::plan::ChannelPlan;
use super::terms::{Coefficients, TermTable};
use super::{FrequencyBlock, Hybrid, MAX_BLOCK, NONE, ZERO};
use crate::error::UpdateError;

/// Per-thread scratch for [`assemble_one`]: the solver workspace, the
/// solutions and the per-line coefficients, reused from one frequency to
/// the next.
pub struct Scratch {
    ws: Workspace,
    z: Vec<C64>,
    /// Equations of the unit right-hand sides: references, then responses.
    eqs: Vec<usize>,
    /// Solutions, row-interleaved in the solver's order: row `position(eq)`
    /// holds `R[eq, ref]` for each reference, then `R[m, eq]` for each
    /// response `m`.
    sol: Vec<C64>,
    /// Per `(parameter, class)` pair of the term table: its coefficient.
    coef: Vec<C64>,
    /// `references x classes x responses` sums of step 4.
    acc: Vec<C64>,
    /// Class sums as right-hand sides (the class-sum strategy).
    w: Vec<C64>,
    /// Per solver row: index of its measured values in `measured`, or `NONE`.
    measured_at: Vec<u32>,
    /// Measured values per replaced row and reference (`None`: no channel).
    measured: Vec<Option<C64>>,
}

impl Scratch {
    /// Scratch for a solver.
    pub fn new(solver: &ZSolver) -> Self {
        Scratch {
            ws: solver.workspace(),
            z: Vec::new(),
            eqs: Vec::new(),
            sol: Vec::new(),
            coef: Vec::new(),
            acc: Vec::new(),
            w: Vec::new(),
            measured_at: Vec::new(),
            measured: Vec::new(),
        }
    }
}

/// How step 4 reaches the measured rows (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Strategy {
    /// Whichever needs fewer right-hand sides.
    Auto,
    /// Unit solves at the measured DOFs, products taken in the sweep.
    #[cfg_attr(not(test), allow(dead_code))] // forced in tests
    MeasuredRows,
    /// Solves with the class sums `sum value U x` as right-hand sides.
    #[cfg_attr(not(test), allow(dead_code))] // forced in tests
    ClassSums,
}

impl Strategy {
    /// Whether to solve for the class sums, with the coefficient rules or
    /// not, `n_classes` classes, `n_ref` references and `n_resp` measured
    /// rows. `Auto` takes the fewer solves: the class sums need `n_ref (1 +
    /// n_classes)` in two rounds, the measured rows `n_ref + n_resp` in one;
    /// without the rules (the fallback's class per term) the measured rows.
    fn class_sums(self, rules: bool, n_classes: usize, n_ref: usize, n_resp: usize) -> bool {
        match self {
            Strategy::Auto => rules && n_ref * (1 + n_classes) < n_ref + n_resp,
            Strategy::MeasuredRows => false,
            Strategy::ClassSums => true,
        }
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
    assemble_line(sys, None, Strategy::Auto, solver, plan, params, freq_hz, hybrid, line, scratch)
}

/// [`assemble_one`] with an optional term table (made here for this line
/// when absent or when it does not fit).
pub(super) fn assemble_line(
    sys: &DampedSystem,
    table: Option<&TermTable>,
    strategy: Strategy,
    solver: &ZSolver,
    plan: &ChannelPlan,
    params: &[Quantity],
    freq_hz: f64,
    hybrid: Hybrid<'_>,
    line: usize,
    scratch: &mut Scratch,
) -> Result<FrequencyBlock, UpdateError> {
    let omega = 2.0 * std::f64::consts::PI * freq_hz;
    let (n_ref, n_resp) = (plan.ref_eqs.len(), plan.resp_eqs.len());
    let n_par = params.len();

    // the derivatives' coefficients at this line
    let own_table;
    let table = match table {
        Some(t) if t.coefficients(sys, params, omega, &mut scratch.coef).is_some() => t,
        _ => {
            own_table = TermTable::new(sys, solver, params, omega);
            own_table.coefficients(sys, params, omega, &mut scratch.coef).expect("a table fits its own derivatives");
            &own_table
        }
    };

    // 3 (set up): measured values replace the references' columns at
    // measured rows, on the fly in step 4, so that the solve is untouched
    let n = solver.n();
    scratch.measured_at.clear();
    scratch.measured_at.resize(n, NONE);
    scratch.measured.clear();
    if let Hybrid::Measured(meas) = hybrid {
        for (mi, &m) in plan.resp_eqs.iter().enumerate() {
            scratch.measured_at[solver.position(m)] = mi as u32;
        }
        scratch.measured.resize(n_resp * n_ref, None);
        for (c, &(ri, mi)) in plan.picks.iter().enumerate() {
            scratch.measured[mi * n_ref + ri] = Some(meas.get(c, line));
        }
    }

    // 1: one factorisation
    scratch.z.resize(sys.assembly().pattern().nnz(), ZERO);
    sys.z_values_into(omega, &mut scratch.z);
    solver.factorize(&mut scratch.ws, &scratch.z, freq_hz)?;

    let rules = matches!(table.coefficients, Coefficients::Rules(_));
    let model = if strategy.class_sums(rules, table.n_classes, n_ref, n_resp) {
        by_class_sums(table, solver, plan, freq_hz, scratch)?
    } else {
        by_measured_rows(table, solver, plan, freq_hz, scratch)?
    };
    let (acc, coef) = (&scratch.acc, &scratch.coef);

    // each parameter: its classes' sums times their coefficients
    let mut per_param = vec![ZERO; n_ref * n_par * n_resp];
    for ri in 0..n_ref {
        for (&(i, class), &c) in table.pairs.iter().zip(coef.iter()) {
            let from = (ri * table.n_classes + class as usize) * n_resp;
            let to = (ri * n_par + i as usize) * n_resp;
            for m in 0..n_resp {
                per_param[to + m] += c * acc[from + m];
            }
        }
    }
    let mut sens = Mat::<C64>::zeros(plan.channels.len(), n_par);
    for (c, &(ri, mi)) in plan.picks.iter().enumerate() {
        for i in 0..n_par {
            sens[(c, i)] = per_param[(ri * n_par + i) * n_resp + mi];
        }
    }
    Ok(FrequencyBlock { freq_hz, model, sens })
}

/// Steps 2 and 4 by unit solves at the references and measured DOFs, each
/// block's class sums taken as soon as its rows are final in the backward
/// sweep. Returns the model FRFs of the plan's channels, and leaves in
/// `scratch.acc` the class sums `R[m, :] (sum value U x)`,
/// `references x classes x responses`.
fn by_measured_rows(
    table: &TermTable,
    solver: &ZSolver,
    plan: &ChannelPlan,
    freq_hz: f64,
    scratch: &mut Scratch,
) -> Result<Vec<C64>, UpdateError> {
    let (n_ref, n_resp) = (plan.ref_eqs.len(), plan.resp_eqs.len());
    let k = n_ref + n_resp;
    scratch.eqs.clear();
    scratch.eqs.extend(plan.ref_eqs.iter().chain(&plan.resp_eqs));
    let Scratch { ws, eqs, sol, acc, measured_at, measured, .. } = scratch;
    acc.clear();
    acc.resize(n_ref * table.n_classes * n_resp, ZERO);
    let arch = Arch::new();
    solver.solve_units_ordered_with(ws, eqs, sol, freq_hz, |r, rows| {
        let (b0, b1) = (table.bucket[r] as usize, table.bucket[r + 1] as usize);
        if b0 < b1 {
            arch.dispatch(BucketProducts {
                table,
                items: &table.items[b0..b1],
                first_row: r,
                rows,
                n_ref,
                n_resp,
                measured_at,
                measured,
                acc,
            });
        }
    })?;
    Ok(plan.picks.iter().map(|&(ri, mi)| sol[solver.position(plan.resp_eqs[mi]) * k + ri]).collect())
}

/// Steps 2 and 4 the other way round: `R[m, :] w = (Z^-1 w)[m]` by symmetry,
/// so each class sum `w = sum value U x` (a sparse vector over the class's
/// blocks) is solved for once and read at the measured rows. Needs the
/// references' columns first, then `references x classes` solves: fewer
/// than the measured DOFs when the parameters act through a few groups.
/// Returns and leaves what [`by_measured_rows`] does.
fn by_class_sums(
    table: &TermTable,
    solver: &ZSolver,
    plan: &ChannelPlan,
    freq_hz: f64,
    scratch: &mut Scratch,
) -> Result<Vec<C64>, UpdateError> {
    let (n_ref, n_resp) = (plan.ref_eqs.len(), plan.resp_eqs.len());
    let n = solver.n();
    let Scratch { ws, sol, w, acc, measured_at, measured, .. } = scratch;
    // the references' columns (hybrid), and in the same backward sweep the
    // class sums, row-interleaved in solver order, one column per
    // (reference, class): a block is added when its rows of x are final; a
    // row of w is cleared when the sweep reaches it, before any block that
    // touches it (those have their smallest row at or below it)
    let kc = n_ref * table.n_classes;
    w.resize(n * kc, ZERO);
    solver.solve_units_ordered_with(ws, &plan.ref_eqs, sol, freq_hz, |r, rows| {
        w[r * kc..(r + 1) * kc].fill(ZERO);
        let (b0, b1) = (table.bucket[r] as usize, table.bucket[r + 1] as usize);
        let mut xb = [ZERO; MAX_BLOCK];
        for item in &table.items[b0..b1] {
            let nb = item.nb as usize;
            let item_rows = &item.rows[..nb];
            for ri in 0..n_ref {
                for (x, &row) in xb.iter_mut().zip(item_rows) {
                    let at = measured_at[row as usize];
                    let replaced = if at == NONE { None } else { measured[at as usize * n_ref + ri] };
                    *x = replaced.unwrap_or(rows[(row as usize - r) * n_ref + ri]);
                }
                for term in &table.terms[item.t0 as usize..item.t1 as usize] {
                    let unit = &table.units[term.unit as usize..term.unit as usize + nb * nb];
                    let col = ri * table.n_classes + term.class as usize;
                    for (l, &row) in item_rows.iter().enumerate() {
                        let urow = &unit[l * nb..(l + 1) * nb];
                        let v = urow.iter().zip(&xb[..nb]).fold(ZERO, |s, (&u, &x)| s + x * u) * term.value;
                        w[row as usize * kc + col] += v;
                    }
                }
            }
        }
    })?;
    let model = plan.picks.iter().map(|&(ri, mi)| sol[solver.position(plan.resp_eqs[mi]) * n_ref + ri]).collect();
    solver.solve_ordered(ws, w, kc, freq_hz)?;
    acc.clear();
    acc.resize(kc * n_resp, ZERO);
    for (mi, &m) in plan.resp_eqs.iter().enumerate() {
        let at = solver.position(m) * kc;
        for (col, &v) in w[at..at + kc].iter().enumerate() {
            acc[col * n_resp + mi] = v;
        }
    }
    Ok(model)
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
    let Some(&first) = freqs_hz.first() else { return Ok(Vec::new()) };
    // frequency-independent preparation, shared by the threads (and made by
    // both at once): it pays for itself from a few lines on
    let omega = 2.0 * std::f64::consts::PI * first;
    let table = TermTable::new(sys, solver, params, omega);
    // rayon's `map_init` would make a scratch per work split, not per thread;
    // a pool makes at most one per concurrently running task
    let pool = Mutex::new(Vec::new());
    freqs_hz
        .par_iter()
        .enumerate()
        .map(|(k, &f)| {
            let popped = pool.lock().unwrap_or_else(PoisonError::into_inner).pop();
            let mut scratch = popped.unwrap_or_else(|| Scratch::new(solver));
            let block =
                assemble_line(sys, Some(&table), Strategy::Auto, solver, plan, params, f, hybrid, k, &mut scratch);
            pool.lock().unwrap_or_else(PoisonError::into_inner).push(scratch);
            block
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::Strategy;

    /// `Auto` takes the class sums exactly when they need fewer solves and
    /// the rules hold; the forced strategies ignore the counts.
    #[test]
    fn auto_takes_the_fewer_solves() {
        let auto = |rules, classes, refs, rows| Strategy::Auto.class_sums(rules, classes, refs, rows);
        // one reference, three classes: 4 solves against 1 + rows
        assert!(auto(true, 3, 1, 4));
        assert!(!auto(true, 3, 1, 3), "a tie keeps the single round");
        assert!(!auto(true, 3, 1, 2));
        // two references: 8 against 2 + rows
        assert!(auto(true, 3, 2, 7));
        assert!(!auto(true, 3, 2, 6));
        // the fallback measures rows however many
        assert!(!auto(false, 3, 1, 100));
        for (rules, rows) in [(true, 1), (true, 100), (false, 100)] {
            assert!(Strategy::ClassSums.class_sums(rules, 3, 1, rows));
            assert!(!Strategy::MeasuredRows.class_sums(rules, 3, 1, rows));
        }
    }
}
