//! What every local candidate needs from the nominal model: per line, from
//! one factorisation of the nominal `Z`, `H_0` at the channels and at the
//! measured equations `W`, and `S = H_0[D, D]` on every distinct `D`.

use std::collections::HashMap;

use damping::DampedSystem;
use frf::{Channel, SelectedInverse, ZSolver};
use num_complex::Complex64 as C64;
use rayon::prelude::*;

use super::{LocalForm, ZERO};
use crate::error::UpdateError;

/// Unit right-hand sides solved together when gathering `H_0[D, D]`.
const CHUNK: usize = 32;

/// What every local candidate needs from the nominal model at a set of
/// lines: `H_0` at the channels, at `W` and on each distinct `D`.
///
/// A candidate is served by any slot whose equations include its `D` (its
/// `S` is that slot's `S` on its equations), at any of the lines gathered
/// (see [`LocalData::covers`]), so that one factorisation per line serves
/// the fits of several stages on several line sets.
pub(crate) struct LocalData {
    pub(super) lines: Vec<f64>,
    /// Distinct response and reference equations.
    pub(super) w_eqs: Vec<usize>,
    /// Per channel: (index of its response, index of its reference) in `w_eqs`.
    pub(super) picks: Vec<(usize, usize)>,
    /// The distinct `D`s.
    pub(super) slots: Slots,
    /// Row of each equation in [`Line::w_rows`] (`usize::MAX`: none).
    pub(super) row_of: Vec<usize>,
    /// Per line: the nominal receptances needed.
    pub(super) per_line: Vec<Line>,
}

/// Distinct sets of equations (each sorted), found by their equations: the
/// set itself, or a set that contains it.
pub(crate) struct Slots {
    pub(super) eqs: Vec<Vec<usize>>,
    /// Where each slot's `S` starts in a line's [`Line::s`] (one more
    /// than the slots: the last is the length).
    pub(super) offsets: Vec<usize>,
    exact: HashMap<Vec<usize>, usize>,
    /// The slots holding each equation.
    by_eq: HashMap<usize, Vec<usize>>,
}

impl Slots {
    /// The sets of `forms` that no other set contains, largest first (in
    /// their first order among equal sizes). A set inside another is served
    /// by it ([`Slots::find`]) with the same values, read from the same
    /// entries of the selected inverse: keeping it too would store them
    /// twice on every line (a window inside a longer one, a mass at a
    /// node of a window: on the 100k-DOF frame's pre-screen, 46,036 sets). The
    /// factorisation is the same either way, as a contained clique adds no
    /// pair to the pattern.
    pub(crate) fn of(forms: &[&LocalForm]) -> Self {
        let mut slots = Slots { eqs: Vec::new(), offsets: vec![0], exact: HashMap::new(), by_eq: HashMap::new() };
        let mut order: Vec<&Vec<usize>> = forms.iter().map(|f| &f.eqs).collect();
        // stable: equal sizes keep their first order
        order.sort_by_key(|eqs| std::cmp::Reverse(eqs.len()));
        for eqs in order {
            if slots.find(eqs).is_none() {
                let slot = slots.eqs.len();
                slots.exact.insert(eqs.clone(), slot);
                for &e in eqs {
                    slots.by_eq.entry(e).or_default().push(slot);
                }
                slots.eqs.push(eqs.clone());
                slots.offsets.push(slots.offsets[slot] + eqs.len() * eqs.len());
            }
        }
        slots
    }

    /// The range of a line's [`Line::s`] that holds the slot's `S`.
    pub(super) fn range(&self, slot: usize) -> std::ops::Range<usize> {
        self.offsets[slot]..self.offsets[slot + 1]
    }

    /// A slot holding every equation of `eqs` (sorted): the set itself when
    /// it is a slot, else the smallest that contains it.
    pub(crate) fn find(&self, eqs: &[usize]) -> Option<usize> {
        if let Some(&slot) = self.exact.get(eqs) {
            return Some(slot);
        }
        let first = eqs.first()?;
        let contains = |slot: usize| {
            let have = &self.eqs[slot];
            eqs.iter().all(|e| have.binary_search(e).is_ok())
        };
        self.by_eq.get(first)?.iter().copied().filter(|&s| contains(s)).min_by_key(|&s| self.eqs[s].len())
    }
}

/// The nominal receptances at one line.
pub(super) struct Line {
    /// `H_0` at the channels.
    pub(super) h0: Vec<C64>,
    /// `H_0[:, W]` on the rows that some `D` needs (see
    /// [`LocalData::row_of`]), `rows x |W|` row-interleaved.
    pub(super) w_rows: Vec<C64>,
    /// Per slot: `S = H_0[D, D]`, row-major, one after the other
    /// ([`Slots::range`]): one allocation per line, where one per slot
    /// made freeing the pre-screening's data of a 100k-DOF frame (4,387
    /// slots on 20 lines) and the screening's take over a second.
    pub(super) s: Vec<C64>,
}

/// Every `S = H_0[D, D]` by unit solves, `CHUNK` equations at a time: the
/// fallback when the factorisation has no selected inverse (the LU fallback).
pub(super) fn unit_solves(
    solver: &ZSolver,
    ws: &mut frf::Workspace,
    slots: &Slots,
    x: &mut Vec<C64>,
    f: f64,
    s: &mut [C64],
) -> Result<(), frf::FrfError> {
    let (offsets, slots) = (&slots.offsets, &slots.eqs);
    // for each equation of some D: the (slot, local column) it fills
    let mut users: HashMap<usize, Vec<(usize, usize)>> = HashMap::new();
    for (slot, eqs) in slots.iter().enumerate() {
        for (j, &e) in eqs.iter().enumerate() {
            users.entry(e).or_default().push((slot, j));
        }
    }
    let mut columns: Vec<usize> = users.keys().copied().collect();
    columns.sort_unstable();
    for chunk in columns.chunks(CHUNK) {
        let k = chunk.len();
        solver.solve_units_ordered(ws, chunk, x, f)?;
        for (j, eq) in chunk.iter().enumerate() {
            for &(slot, col) in &users[eq] {
                let d = slots[slot].len();
                for (row, &e) in slots[slot].iter().enumerate() {
                    s[offsets[slot] + row * d + col] = x[solver.position(e) * k + j];
                }
            }
        }
    }
    Ok(())
}

impl LocalData {
    /// Gathers the data for the given forms (deduplicated by `D`) at `lines`
    /// (Hz): per line, in parallel, one factorisation of the nominal `Z`.
    pub(crate) fn new(
        nominal: &DampedSystem,
        channels: &[Channel],
        lines: &[f64],
        forms: &[&LocalForm],
    ) -> Result<Self, UpdateError> {
        let mut w_eqs: Vec<usize> = Vec::new();
        let mut index = |eq: usize| match w_eqs.iter().position(|&e| e == eq) {
            Some(i) => i,
            None => {
                w_eqs.push(eq);
                w_eqs.len() - 1
            }
        };
        let mut picks = Vec::new();
        for c in channels {
            let r = frf::equation_of(nominal, c.response)?;
            let f = frf::equation_of(nominal, c.reference)?;
            picks.push((index(r), index(f)));
        }
        // (deduplicated by hash: the pre-screening of a 100k-DOF frame has
        // 60,000 forms, and a search through the slots so far took seconds)
        let slots = Slots::of(forms);
        // the rows of H_0[:, W] that some D needs, compactly
        let n = nominal.n();
        let mut row_of = vec![usize::MAX; n];
        // and the equation of each such row, in order
        let mut eq_of_row = Vec::new();
        for &e in slots.eqs.iter().flatten() {
            if row_of[e] == usize::MAX {
                row_of[e] = eq_of_row.len();
                eq_of_row.push(e);
            }
        }
        // The symbolic analysis makes each D a clique of the factor, so that
        // the selected inverse holds every S = H_0[D, D] (about the cost of
        // the factorisation, where a solve per equation would cost N solves).
        let solver = ZSolver::with_cliques(nominal.assembly().pattern(), &slots.eqs)?;
        // Only the rows read below are solved for (those of W and of every
        // D), and only the entries between the equations of each D inverted:
        // where the Ds lie in a few places of a large model (the screening's
        // and the full fits' candidates, around the leaders), most of the
        // factor is skipped. The numbers read are the same bit for bit.
        let slot_eqs = || slots.eqs.iter().flatten().copied();
        let solved = solver.reach(w_eqs.iter().copied().chain(slot_eqs()));
        let inverted = solver.reach(slot_eqs());
        let per_line: Vec<Line> = lines
            .par_iter()
            .with_min_len(frf::lines_per_job(lines.len()))
            .map_init(
                || (solver.workspace(), Vec::new(), Vec::new(), SelectedInverse::new()),
                |(ws, z, x, inv), &f| {
                    let omega = 2.0 * std::f64::consts::PI * f;
                    z.resize(nominal.assembly().pattern().nnz(), ZERO);
                    nominal.z_values_into(omega, z);
                    solver.factorize(ws, z, f)?;
                    let k = w_eqs.len();
                    solver.solve_units_within(ws, &w_eqs, &solved, x, f)?;
                    let h0 = picks.iter().map(|&(r, c)| x[solver.position(w_eqs[r]) * k + c]).collect();
                    // Written once each, in order, rather than zeroed first:
                    // the pre-screening of the 100k-DOF frame keeps about
                    // 200 MB of them per line, on fresh pages that a zeroing
                    // pass would go over twice (3 % of its time).
                    let mut w_rows: Vec<C64> = Vec::with_capacity(eq_of_row.len() * k);
                    for &eq in &eq_of_row {
                        let p = solver.position(eq);
                        w_rows.extend_from_slice(&x[p * k..p * k + k]);
                    }
                    let total = slots.offsets[slots.eqs.len()];
                    let mut s: Vec<C64> = Vec::with_capacity(total);
                    let selected = match solver.selected_inverse_within(ws, &inverted, inv) {
                        // each block zeroed just before it is filled, in cache
                        Ok(()) => slots.eqs.iter().all(|eqs| {
                            let start = s.len();
                            s.resize(start + eqs.len() * eqs.len(), ZERO);
                            solver.inverse_block(inv, eqs, &mut s[start..])
                        }),
                        // the LU fallback has no selected inverse
                        Err(frf::FrfError::NoLdltFactors { .. }) => false,
                        Err(e) => return Err(e),
                    };
                    if !selected {
                        s.clear();
                        s.resize(total, ZERO);
                        unit_solves(&solver, ws, &slots, x, f, &mut s)?;
                    }
                    Ok(Line { h0, w_rows, s })
                },
            )
            .collect::<Result<_, frf::FrfError>>()?;
        Ok(LocalData { lines: lines.to_vec(), w_eqs, picks, slots, row_of, per_line })
    }

    /// The index of each of `lines` among the lines gathered, or `None`
    /// when one was not gathered.
    pub(super) fn line_indices(&self, lines: &[f64]) -> Option<Vec<usize>> {
        lines.iter().map(|f| self.lines.iter().position(|g| g == f)).collect()
    }

    /// Whether these data serve every one of `forms` at every one of
    /// `lines` (the channels are those they were gathered for).
    pub(crate) fn covers(&self, lines: &[f64], forms: &[&LocalForm]) -> bool {
        lines.iter().all(|f| self.lines.contains(f)) && forms.iter().all(|form| self.slots.find(&form.eqs).is_some())
    }
}
