//! Exact low-rank evaluation of candidates that change `Z` only locally.
//!
//! A candidate (a lumped mass, a stiffness or mass change of an element or
//! region, damping of a region, a joint or support spring) changes `Z` only
//! on the few equations `D` its elements, springs or masses touch:
//! `Z(p) = Z_0 + E dZ(p) E^T` with `E` the columns of the identity at `D`.
//! A candidate that adds equations of its own (a released support, the
//! rotation of a split joint node), coupled to `D` only, has them condensed
//! out exactly: with the local matrix `[[A, B], [B^T, C]]` over `D` and the
//! added equations, `dZ = A - B C^-1 B^T`, and each parameter derivative
//! condenses the same way, `T^T (dZ_ext/dp) T` with `T = [I; -C^-1 B^T]`.
//! With `H_0 = Z_0^-1`, `S = H_0[D, D]` and `X = H_0[D, W]` (`W`: the
//! measured response and reference equations), the Woodbury identity gives
//!
//! ```text
//! Y          = (I + S dZ)^-1 X               (= H(p)[D, W])
//! H(p)[r, f] = H_0[r, f] - X[:, r]^T dZ Y[:, f]
//! (dH/dp_i) p_i [r, f] = -Y[:, r]^T ((dZ/dp_i) p_i) Y[:, f]
//!                      = -X[:, r]^T (I + S dZ)^-T ((dZ/dp_i) p_i) Y[:, f]
//! ```
//!
//! exactly (no linearisation). `Y` is needed only at the reference columns
//! `f`, and each sensitivity costs one solve with the transposed matrix.
//!
//! Everything a candidate needs is local: the part of the model it touches
//! before and after its change ([`LocalCandidate`], from
//! [`fe_model::Model::part`]), whose equations are matched to the whole
//! nominal model's by DOF, and per line `S` and `X`. These come from one
//! factorisation of the *nominal* `Z` per line, shared by every candidate:
//! `X` from unit solves at `W`, and every `S` from the selected inverse of
//! `Z_0` (the solver is analysed with each `D` as a clique, so that
//! `H_0[D, D]` lies in the factor's pattern), which costs about one more
//! factorisation, where a solve per equation of `D` would cost `N` solves
//! per line on a large model. Each evaluation then costs a few operations on
//! `d x d` matrices with small kernels written here (faer's dispatch costs
//! more than the arithmetic at this size). A candidate touching more than
//! [`MAX_LOCAL_EQS`] equations is fitted on its own model.

use std::collections::HashMap;

use damping::DampedSystem;
use faer::Mat;
use fe_model::{Assembly, Block, BlockSource, Quantity};
use frf::{Channel, SelectedInverse, ZSolver};
use num_complex::Complex64 as C64;
use rayon::prelude::*;

use super::Candidate;
use crate::error::UpdateError;
use crate::oe::{Evaluated, Response};
use crate::params::ParameterSet;

const ZERO: C64 = C64::new(0.0, 0.0);

/// Above this many local equations a candidate is fitted on its own model:
/// the low-rank update would cost more than it saves.
const MAX_LOCAL_EQS: usize = 60;

/// Unit right-hand sides solved together when gathering `H_0[D, D]`.
const CHUNK: usize = 32;

/// A candidate fitted by low-rank updates: the part of the nominal model it
/// touches, before and after its change, and where the two differ. All of
/// it is as small as the change; nothing here grows with the model.
pub(crate) struct LocalCandidate {
    /// The nominal model's part (see [`fe_model::Model::part`]).
    nominal_part: DampedSystem,
    /// The same part with the change, at its starting values.
    pub(crate) part: DampedSystem,
    /// The parameters to fit, resolved in `part`.
    pub(crate) params: ParameterSet,
    pub(crate) form: LocalForm,
}

impl LocalCandidate {
    /// The local form of `candidate` relative to `nominal` (the whole
    /// nominal system), or `None` when it has none (see [`LocalForm`]).
    pub(crate) fn new(nominal: &DampedSystem, candidate: &Candidate) -> Option<Self> {
        let nominal_part = DampedSystem::of_part(candidate.nominal_part().clone()).ok()?;
        let part = DampedSystem::of_part(candidate.part().clone()).ok()?;
        let params = ParameterSet::new(candidate.parameters_in(part.model()).ok()?);
        let form = LocalForm::of(nominal, &nominal_part, &part, &params)?;
        Some(LocalCandidate { nominal_part, part, params, form })
    }
}

/// The model item a block comes from, by id or name: block indices differ
/// between a part and the whole, and between a part before and after a
/// change.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum Item {
    Beam(u32),
    Spring(String),
    Mass(String),
    /// An imported block: group, mass (not stiffness), its two nodes.
    Imported(usize, bool, u32, u32),
}

fn item(model: &fe_model::Model, source: BlockSource) -> Item {
    match source {
        BlockSource::Beam(i) => Item::Beam(model.beams()[i].id.0),
        BlockSource::Spring(i) => Item::Spring(model.springs()[i].name.clone()),
        BlockSource::Mass(i) => Item::Mass(model.masses()[i].name.clone()),
        BlockSource::Imported(i) => {
            let b = &model.imported()[i];
            Item::Imported(b.group, b.kind == fe_model::imported::ImportedKind::Mass, b.nodes[0].0, b.nodes[1].0)
        }
    }
}

/// The equation of the whole nominal model for each equation of a part,
/// when it has one (a DOF the part frees, or a node it adds, has none).
fn whole_equations(nominal: &Assembly, part: &Assembly) -> Vec<Option<usize>> {
    (0..part.n())
        .map(|eq| {
            part.dofs.dofs_of(eq).iter().find_map(|&r| match nominal.dofs.slot(r) {
                Some(fe_model::Slot::Free(e)) => Some(e),
                _ => None,
            })
        })
        .collect()
}

/// Where a candidate's `Z` differs from the nominal one.
#[derive(Clone, Debug)]
pub(crate) struct LocalForm {
    /// The nominal equations `D` the changed blocks touch (sorted).
    pub(crate) eqs: Vec<usize>,
    /// Equations of the candidate that the nominal model lacks (a released
    /// support, the rotation of a split node), after `D` in the local order.
    new_eqs: usize,
    /// Local index of each equation of the candidate's part (`usize::MAX`
    /// where no changed block touches it).
    index: Vec<usize>,
    /// Local index of each equation of the nominal part (likewise).
    nominal_index: Vec<usize>,
    /// Blocks of the candidate's part that differ or may differ.
    blocks: Vec<usize>,
    /// The same blocks' counterparts in the nominal part.
    nominal_blocks: Vec<usize>,
}

impl LocalForm {
    /// The local form of a candidate (`cand`: its part with the change,
    /// `params` the parameters to fit in it) relative to `nominal` (the
    /// whole nominal system; `nominal_part` its part on the same nodes), or
    /// `None` when the candidate's equations do not extend the nominal ones
    /// or it touches too many.
    pub(crate) fn of(
        nominal: &DampedSystem,
        nominal_part: &DampedSystem,
        cand: &DampedSystem,
        params: &ParameterSet,
    ) -> Option<Self> {
        let (a0, a) = (nominal_part.assembly(), cand.assembly());
        let map0 = whole_equations(nominal.assembly(), a0);
        let map = whole_equations(nominal.assembly(), a);
        // two candidate equations on one nominal equation cannot be expressed
        let mut seen: Vec<usize> = map.iter().flatten().copied().collect();
        seen.sort_unstable();
        if seen.windows(2).any(|w| w[0] == w[1]) || map0.iter().any(Option::is_none) {
            return None;
        }
        // each candidate block: the nominal block of the same element, spring or mass
        let by_item: HashMap<Item, usize> =
            a0.blocks.iter().enumerate().map(|(i, b)| (item(nominal_part.model(), b.source), i)).collect();
        let counterpart: Vec<Option<usize>> =
            a.blocks.iter().map(|b| by_item.get(&item(cand.model(), b.source)).copied()).collect();
        if counterpart.iter().flatten().count() != a0.blocks.len() {
            return None;
        }
        let (g0, g) = (nominal_part.model().groups(), cand.model().groups());
        let mut touched = vec![false; a.blocks.len()];
        for &q in params.quantities() {
            match q {
                Quantity::GroupAlpha(i) | Quantity::GroupBeta(i) | Quantity::GroupMu(i) => {
                    a.group_blocks[i].iter().for_each(|&b| touched[b] = true);
                }
                _ => a.terms_of(q).iter().for_each(|&(b, _)| touched[b] = true),
            }
        }
        for (b, t) in touched.iter_mut().enumerate() {
            let Some(b0) = counterpart[b].map(|i| &a0.blocks[i]) else {
                *t = true;
                continue;
            };
            let bc = &a.blocks[b];
            let same_eqs =
                b0.eqs.len() == bc.eqs.len() && b0.eqs.iter().zip(&bc.eqs).all(|(&e0, &e)| map[e] == map0[e0]);
            let same_group = b0.group == bc.group && g0.get(b0.group) == g.get(bc.group);
            let same_terms = b0.terms.len() == bc.terms.len()
                && b0
                    .terms
                    .iter()
                    .zip(&bc.terms)
                    .all(|(x, y)| x.value == y.value && x.kind == y.kind && x.unit == y.unit);
            if !(same_eqs && same_group && same_terms) {
                *t = true;
            }
        }
        let blocks: Vec<usize> = (0..a.blocks.len()).filter(|&b| touched[b]).collect();
        let nominal_blocks: Vec<usize> = blocks.iter().filter_map(|&b| counterpart[b]).collect();
        // D: the nominal equations of the changed blocks, before and after
        let mut cand_eqs: Vec<usize> = blocks.iter().flat_map(|&b| a.blocks[b].eqs.iter().copied()).collect();
        cand_eqs.sort_unstable();
        cand_eqs.dedup();
        let mut eqs: Vec<usize> = cand_eqs.iter().filter_map(|&e| map[e]).collect();
        eqs.extend(nominal_blocks.iter().flat_map(|&b| a0.blocks[b].eqs.iter().filter_map(|&e| map0[e])));
        eqs.sort_unstable();
        eqs.dedup();
        let added: Vec<usize> = cand_eqs.iter().copied().filter(|&e| map[e].is_none()).collect();
        let mut index = vec![usize::MAX; a.n()];
        for &e in &cand_eqs {
            index[e] = match map[e] {
                Some(e0) => eqs.binary_search(&e0).expect("mapped equations are in D"),
                None => eqs.len() + added.binary_search(&e).expect("listed"),
            };
        }
        let nominal_index =
            map0.iter().map(|e| e.and_then(|e| eqs.binary_search(&e).ok()).unwrap_or(usize::MAX)).collect();
        let fits = !eqs.is_empty() && eqs.len() + added.len() <= MAX_LOCAL_EQS;
        fits.then_some(LocalForm { eqs, new_eqs: added.len(), index, nominal_index, blocks, nominal_blocks })
    }

    /// Local index of an equation of the nominal part's changed blocks.
    fn nominal_index(&self, eq: usize) -> usize {
        self.nominal_index[eq]
    }

    /// Local index of an equation of the candidate's changed blocks.
    fn candidate_index(&self, eq: usize) -> usize {
        self.index[eq]
    }
}

/// What every local candidate needs from the nominal model at a set of
/// lines: `H_0` at the channels, at `W` and on each distinct `D`.
pub(crate) struct LocalData {
    lines: Vec<f64>,
    /// Distinct response and reference equations.
    w_eqs: Vec<usize>,
    /// Per channel: (index of its response, index of its reference) in `w_eqs`.
    picks: Vec<(usize, usize)>,
    /// The distinct `D`s.
    slots: Vec<Vec<usize>>,
    /// Row of each equation in [`Line::w_rows`] (`usize::MAX`: none).
    row_of: Vec<usize>,
    /// Per line: the nominal receptances needed.
    per_line: Vec<Line>,
}

/// The nominal receptances at one line.
struct Line {
    /// `H_0` at the channels.
    h0: Vec<C64>,
    /// `H_0[:, W]` on the rows that some `D` needs (see
    /// [`LocalData::row_of`]), `rows x |W|` row-interleaved.
    w_rows: Vec<C64>,
    /// Per slot: `S = H_0[D, D]`, row-major.
    s: Vec<Vec<C64>>,
}

/// Every `S = H_0[D, D]` by unit solves, `CHUNK` equations at a time: the
/// fallback when the factorisation has no selected inverse (the LU fallback).
fn unit_solves(
    solver: &ZSolver,
    ws: &mut frf::Workspace,
    slots: &[Vec<usize>],
    x: &mut Vec<C64>,
    f: f64,
    s: &mut [Vec<C64>],
) -> Result<(), frf::FrfError> {
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
                    s[slot][row * d + col] = x[solver.position(e) * k + j];
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
        let mut slots: Vec<Vec<usize>> = Vec::new();
        for f in forms {
            if !slots.contains(&f.eqs) {
                slots.push(f.eqs.clone());
            }
        }
        // the rows of H_0[:, W] that some D needs, compactly
        let n = nominal.n();
        let mut row_of = vec![usize::MAX; n];
        let mut rows = 0;
        for &e in slots.iter().flatten() {
            if row_of[e] == usize::MAX {
                row_of[e] = rows;
                rows += 1;
            }
        }
        // The symbolic analysis makes each D a clique of the factor, so that
        // the selected inverse holds every S = H_0[D, D] (about the cost of
        // the factorisation, where a solve per equation would cost N solves).
        let solver = ZSolver::with_cliques(&nominal.assembly().pattern, &slots)?;
        let per_line: Vec<Line> = lines
            .par_iter()
            .map_init(
                || (solver.workspace(), Vec::new(), Vec::new(), SelectedInverse::new()),
                |(ws, z, x, inv), &f| {
                    let omega = 2.0 * std::f64::consts::PI * f;
                    z.resize(nominal.assembly().pattern.nnz(), ZERO);
                    nominal.z_values_into(omega, z);
                    solver.factorize(ws, z, f)?;
                    let k = w_eqs.len();
                    solver.solve_units_ordered(ws, &w_eqs, x, f)?;
                    let h0 = picks.iter().map(|&(r, c)| x[solver.position(w_eqs[r]) * k + c]).collect();
                    let mut w_rows = vec![ZERO; rows * k];
                    for (eq, &row) in row_of.iter().enumerate().filter(|(_, r)| **r != usize::MAX) {
                        let p = solver.position(eq);
                        w_rows[row * k..row * k + k].copy_from_slice(&x[p * k..p * k + k]);
                    }
                    let mut s: Vec<Vec<C64>> = slots.iter().map(|e| vec![ZERO; e.len() * e.len()]).collect();
                    let selected = match solver.selected_inverse(ws, inv) {
                        Ok(()) => slots.iter().zip(&mut s).all(|(eqs, s)| solver.inverse_block(inv, eqs, s)),
                        // the LU fallback has no selected inverse
                        Err(frf::FrfError::NoLdltFactors { .. }) => false,
                        Err(e) => return Err(e),
                    };
                    if !selected {
                        unit_solves(&solver, ws, &slots, x, f, &mut s)?;
                    }
                    Ok(Line { h0, w_rows, s })
                },
            )
            .collect::<Result<_, frf::FrfError>>()?;
        Ok(LocalData { lines: lines.to_vec(), w_eqs, picks, slots, row_of, per_line })
    }

    /// The model response of one candidate, starting at the values of
    /// `sys` (its part, [`LocalCandidate::part`], possibly with other values).
    pub(crate) fn response<'a>(&'a self, local: &'a LocalCandidate, sys: DampedSystem) -> LocalResponse<'a> {
        let (form, nominal) = (&local.form, &local.nominal_part);
        let slot = self.slots.iter().position(|e| *e == form.eqs).expect("the form was given to LocalData::new");
        let d = form.eqs.len();
        let a0 = nominal.assembly();
        let nominal_blocks: Vec<Placed> =
            form.nominal_blocks.iter().map(|&b| Placed::new(&a0.blocks[b], |e| form.nominal_index(e))).collect();
        let nominal_z = self
            .lines
            .iter()
            .map(|&f| {
                let coefs = nominal.coefficients(2.0 * std::f64::consts::PI * f);
                let mut z = vec![ZERO; d * d];
                for (p, &b) in nominal_blocks.iter().zip(&form.nominal_blocks) {
                    let block = &a0.blocks[b];
                    for t in &block.terms {
                        p.add(&t.unit, -coefs[block.group].of(t.kind) * t.value, &mut z, d);
                    }
                }
                z
            })
            .collect();
        let k = self.w_eqs.len();
        let x = self
            .per_line
            .iter()
            .map(|line| {
                form.eqs
                    .iter()
                    .flat_map(|&e| {
                        let r = self.row_of[e];
                        line.w_rows[r * k..r * k + k].iter().copied()
                    })
                    .collect()
            })
            .collect();
        let a = sys.assembly();
        let mut placed: Vec<Option<Placed>> = (0..a.blocks.len()).map(|_| None).collect();
        for &b in &form.blocks {
            placed[b] = Some(Placed::new(&a.blocks[b], |e| form.candidate_index(e)));
        }
        let mut refs: Vec<usize> = self.picks.iter().map(|&(_, f)| f).collect();
        refs.sort_unstable();
        refs.dedup();
        let n_local = d + form.new_eqs;
        LocalResponse {
            data: self,
            slot,
            form,
            sys,
            params: &local.params,
            nominal_z,
            x,
            placed,
            work: Work::new(n_local, d, refs.len()),
            refs,
        }
    }
}

/// A block's equations placed in a local matrix.
struct Placed {
    /// Local index of each block equation.
    idx: Vec<usize>,
}

impl Placed {
    fn new(block: &Block, index: impl Fn(usize) -> usize) -> Self {
        Placed { idx: block.eqs.iter().map(|&e| index(e)).collect() }
    }

    /// `out += c * unit` with `out` row-major `n x n`.
    fn add(&self, unit: &[f64], c: C64, out: &mut [C64], n: usize) {
        let m = self.idx.len();
        for (r, &ir) in self.idx.iter().enumerate() {
            let row = &mut out[ir * n..ir * n + n];
            for (col, &ic) in self.idx.iter().enumerate() {
                let u = unit[r * m + col];
                if u != 0.0 {
                    row[ic] += c * u;
                }
            }
        }
    }
}

/// Scratch of one candidate's evaluation, allocated once.
struct Work {
    /// The local change `[[A, B], [B^T, C]]`, `(d + e)^2`.
    z: Vec<C64>,
    /// `G = C^-1 B^T`, `e x d`, and the LU of `C`.
    g: Vec<C64>,
    c: Vec<C64>,
    c_piv: Vec<usize>,
    /// The condensed change `dZ`, `d x d`.
    dz: Vec<C64>,
    /// The non-zeros `(column, value)` of `dZ` by row, and row pointers.
    nz: Vec<(usize, C64)>,
    nz_ptr: Vec<usize>,
    /// `I + S dZ` and its LU.
    m: Vec<C64>,
    m_piv: Vec<usize>,
    /// `Y = (I + S dZ)^-1 X` at the reference columns, `d x refs`.
    y: Vec<C64>,
    /// One parameter's derivative, `(d + e)^2`, and condensed, `d x d`.
    dzi: Vec<C64>,
    dzi_c: Vec<C64>,
    /// A column of `d` values.
    col: Vec<C64>,
}

impl Work {
    fn new(n_local: usize, d: usize, refs: usize) -> Self {
        let e = n_local - d;
        Work {
            z: vec![ZERO; n_local * n_local],
            g: vec![ZERO; e * d],
            c: vec![ZERO; e * e],
            c_piv: vec![0; e],
            dz: vec![ZERO; d * d],
            nz: Vec::with_capacity(d * d),
            nz_ptr: Vec::with_capacity(d + 1),
            m: vec![ZERO; d * d],
            m_piv: vec![0; d],
            y: vec![ZERO; d * refs],
            dzi: vec![ZERO; n_local * n_local],
            dzi_c: vec![ZERO; d * d],
            col: vec![ZERO; d],
        }
    }
}

/// LU factorisation with partial pivoting of a row-major `n x n` matrix in
/// place (unit lower and upper triangles share the storage). Returns false
/// when a pivot is zero or not finite.
fn lu_in_place(a: &mut [C64], n: usize, piv: &mut [usize]) -> bool {
    for k in 0..n {
        let p = (k..n).max_by(|&i, &j| a[i * n + k].norm_sqr().total_cmp(&a[j * n + k].norm_sqr())).expect("k < n");
        piv[k] = p;
        if p != k {
            for j in 0..n {
                a.swap(k * n + j, p * n + j);
            }
        }
        let pivot = a[k * n + k];
        if pivot.norm_sqr() == 0.0 || !(pivot.re.is_finite() && pivot.im.is_finite()) {
            return false;
        }
        let inv = pivot.inv();
        let (head, tail) = a.split_at_mut((k + 1) * n);
        let row_k = &head[k * n..];
        for row in tail.chunks_exact_mut(n) {
            let l = row[k] * inv;
            row[k] = l;
            if l != ZERO {
                for j in k + 1..n {
                    row[j] -= l * row_k[j];
                }
            }
        }
    }
    true
}

/// Solves `A X = B` with the LU of [`lu_in_place`]; `b` is row-major `n x k`
/// and is overwritten by `X`.
fn lu_solve(a: &[C64], n: usize, piv: &[usize], b: &mut [C64], k: usize) {
    for i in 0..n {
        if piv[i] != i {
            for j in 0..k {
                b.swap(i * k + j, piv[i] * k + j);
            }
        }
    }
    for i in 0..n {
        let (head, tail) = b.split_at_mut(i * k);
        let bi = &mut tail[..k];
        for m in 0..i {
            let l = a[i * n + m];
            if l != ZERO {
                for (v, &u) in bi.iter_mut().zip(&head[m * k..m * k + k]) {
                    *v -= l * u;
                }
            }
        }
    }
    for i in (0..n).rev() {
        let (head, tail) = b.split_at_mut((i + 1) * k);
        let bi = &mut head[i * k..];
        for m in i + 1..n {
            let u = a[i * n + m];
            if u != ZERO {
                let off = (m - i - 1) * k;
                for (v, &w) in bi.iter_mut().zip(&tail[off..off + k]) {
                    *v -= u * w;
                }
            }
        }
        let inv = a[i * n + i].inv();
        bi.iter_mut().for_each(|v| *v *= inv);
    }
}

/// Solves `A^T x = b` for one column with the LU of [`lu_in_place`]
/// (`P A = L U`, so `A^T = U^T L^T P`); `b` is overwritten by `x`.
fn lu_solve_transposed(a: &[C64], n: usize, piv: &[usize], b: &mut [C64]) {
    for i in 0..n {
        let mut v = b[i];
        for m in 0..i {
            v -= a[m * n + i] * b[m];
        }
        b[i] = v / a[i * n + i];
    }
    for i in (0..n).rev() {
        let mut v = b[i];
        for m in i + 1..n {
            v -= a[m * n + i] * b[m];
        }
        b[i] = v;
    }
    for i in (0..n).rev() {
        b.swap(i, piv[i]);
    }
}

/// Condenses a local matrix `q` (`(d + e)^2`, row-major) onto `D`:
/// `T^T q T` with `T = [I; -G]`, written to `out` (`d x d`).
fn condense(q: &[C64], g: &[C64], d: usize, e: usize, out: &mut [C64]) {
    let n = d + e;
    for i in 0..d {
        for j in 0..d {
            out[i * d + j] = q[i * n + j];
        }
    }
    if e == 0 {
        return;
    }
    // out -= Q_AB G + G^T Q_BA, then out += G^T Q_BB G
    for i in 0..d {
        for m in 0..e {
            let (qab, gmi) = (q[i * n + d + m], g[m * d + i]);
            let (g_row, qba_row) = (&g[m * d..m * d + d], &q[(d + m) * n..(d + m) * n + d]);
            for ((o, &gj), &qj) in out[i * d..i * d + d].iter_mut().zip(g_row).zip(qba_row) {
                *o -= qab * gj + gmi * qj;
            }
        }
    }
    for m in 0..e {
        for l in 0..e {
            let qbb = q[(d + m) * n + d + l];
            if qbb == ZERO {
                continue;
            }
            for i in 0..d {
                let gi = g[m * d + i] * qbb;
                for j in 0..d {
                    out[i * d + j] += gi * g[l * d + j];
                }
            }
        }
    }
}

/// [`Response`] of one local candidate; see the module docs.
pub(crate) struct LocalResponse<'a> {
    data: &'a LocalData,
    slot: usize,
    form: &'a LocalForm,
    sys: DampedSystem,
    params: &'a ParameterSet,
    /// Per line: minus the nominal model's part of `Z` on `D` that the
    /// candidate replaces, row-major `d x d`.
    nominal_z: Vec<Vec<C64>>,
    /// Per line: `X = H_0[D, W]`, row-major `d x |W|`.
    x: Vec<Vec<C64>>,
    /// Each block of the candidate's part, placed locally when it changed.
    placed: Vec<Option<Placed>>,
    /// Distinct reference columns in `W`.
    refs: Vec<usize>,
    work: Work,
}

impl Response for LocalResponse<'_> {
    fn set(&mut self, values: &[f64]) -> Result<(), UpdateError> {
        self.params.set_values(&mut self.sys, values)
    }

    /// A sensitivity costs one transposed solve of a `d x d` system per
    /// parameter, beside the factorisation the receptances need anyway.
    fn cheap_jacobian(&self) -> bool {
        true
    }

    fn evaluate(&mut self, lines: &[f64], jacobian: bool) -> Option<Evaluated> {
        if lines != self.data.lines.as_slice() {
            return None;
        }
        let (d, e) = (self.form.eqs.len(), self.form.new_eqs);
        let (n, k) = (d + e, self.data.w_eqs.len());
        let a = self.sys.assembly();
        let n_par = self.params.len();
        let w = &mut self.work;
        let mut model = Vec::with_capacity(lines.len());
        let mut sens = jacobian.then(|| Vec::with_capacity(lines.len()));
        for (li, &f) in lines.iter().enumerate() {
            let omega = 2.0 * std::f64::consts::PI * f;
            let coefs = self.sys.coefficients(omega);
            // the change on D and the candidate's own equations, [[A, B], [B^T, C]]
            w.z.fill(ZERO);
            for (i, row) in self.nominal_z[li].chunks_exact(d).enumerate() {
                w.z[i * n..i * n + d].copy_from_slice(row);
            }
            for &b in &self.form.blocks {
                let (block, p) = (&a.blocks[b], self.placed[b].as_ref().expect("changed blocks are placed"));
                for t in block.terms.iter().filter(|t| t.value != 0.0) {
                    p.add(&t.unit, coefs[block.group].of(t.kind) * t.value, &mut w.z, n);
                }
            }
            // condensed onto D: dZ = A - B C^-1 B^T, with G = C^-1 B^T
            if e > 0 {
                for m in 0..e {
                    w.c[m * e..m * e + e].copy_from_slice(&w.z[(d + m) * n + d..(d + m) * n + n]);
                    w.g[m * d..m * d + d].copy_from_slice(&w.z[(d + m) * n..(d + m) * n + d]);
                }
                if !lu_in_place(&mut w.c, e, &mut w.c_piv) {
                    return None;
                }
                lu_solve(&w.c, e, &w.c_piv, &mut w.g, d);
            }
            condense(&w.z, &w.g, d, e, &mut w.dz);
            // I + S dZ over the non-zeros of dZ: a row of dZ couples a DOF
            // only to the DOFs of its elements, so this costs d nnz(dZ), not d^3
            w.nz.clear();
            w.nz_ptr.clear();
            w.nz_ptr.push(0);
            for row in w.dz.chunks_exact(d) {
                w.nz.extend(row.iter().enumerate().filter(|(_, v)| **v != ZERO).map(|(j, &v)| (j, v)));
                w.nz_ptr.push(w.nz.len());
            }
            let s = &self.data.per_line[li].s[self.slot];
            w.m.fill(ZERO);
            for i in 0..d {
                w.m[i * d + i] = C64::new(1.0, 0.0);
                let (s_row, m_row) = (&s[i * d..i * d + d], &mut w.m[i * d..i * d + d]);
                for (kk, &sik) in s_row.iter().enumerate() {
                    for &(j, v) in &w.nz[w.nz_ptr[kk]..w.nz_ptr[kk + 1]] {
                        m_row[j] += sik * v;
                    }
                }
            }
            if !lu_in_place(&mut w.m, d, &mut w.m_piv) {
                return None;
            }
            // Y = (I + S dZ)^-1 X, needed only at the reference columns:
            // the sensitivities use the transposed system instead (below)
            let x = &self.x[li];
            let nr = self.refs.len();
            for i in 0..d {
                for (a, &fr) in self.refs.iter().enumerate() {
                    w.y[i * nr + a] = x[i * k + fr];
                }
            }
            lu_solve(&w.m, d, &w.m_piv, &mut w.y, nr);
            // H = H_0 - X^T dZ Y on the channels
            let line = &self.data.per_line[li];
            let mut h = line.h0.clone();
            for (a, &fr) in self.refs.iter().enumerate() {
                for i in 0..d {
                    w.col[i] = (0..d).map(|j| w.dz[i * d + j] * w.y[j * nr + a]).sum();
                }
                for (c, &(r, fi)) in self.data.picks.iter().enumerate() {
                    if fi == fr {
                        h[c] -= (0..d).map(|i| x[i * k + r] * w.col[i]).sum::<C64>();
                    }
                }
            }
            if h.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
                return None;
            }
            // (dH/dp_i) p_i [r, f] = -Y[:, r]^T dZ_i Y[:, f] with
            // Y[:, r]^T = X[:, r]^T (I + S dZ)^-T: one transposed solve per
            // parameter and reference, not one solve per response
            if let Some(sens) = sens.as_mut() {
                let mut block = Mat::<C64>::zeros(h.len(), n_par);
                for (pi, p) in self.params.params().iter().enumerate() {
                    w.dzi.fill(ZERO);
                    for &q in &p.quantities {
                        for (b, t, c) in self.sys.derivative(q, omega).terms {
                            let term = &a.blocks[b].terms[t];
                            let p = self.placed[b].as_ref().expect("a parameter's blocks are changed blocks");
                            p.add(&term.unit, c * term.value, &mut w.dzi, n);
                        }
                    }
                    condense(&w.dzi, &w.g, d, e, &mut w.dzi_c);
                    for (a, &fr) in self.refs.iter().enumerate() {
                        for i in 0..d {
                            w.col[i] = (0..d).map(|j| w.dzi_c[i * d + j] * w.y[j * nr + a]).sum();
                        }
                        lu_solve_transposed(&w.m, d, &w.m_piv, &mut w.col);
                        for (c, &(r, fi)) in self.data.picks.iter().enumerate() {
                            if fi == fr {
                                block[(c, pi)] = (0..d).map(|i| x[i * k + r] * w.col[i]).sum();
                            }
                        }
                    }
                }
                sens.push(block);
            }
            model.push(h);
        }
        Some((model, sens))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::candidates::{self, CandidateOptions, EffectKind};
    use crate::sensitivity::{self, ChannelPlan, Hybrid};
    use fe_model::{Dof, DofRef, samples};

    /// Every local candidate's low-rank response equals its own model's
    /// receptances and sensitivities, away from the starting values,
    /// including those that add equations (supports, joints).
    #[test]
    fn low_rank_updates_equal_the_candidate_models() {
        let (mut kinds, mut new_joints) = (Vec::new(), 0);
        // damped, partly non-viscous models (one with a joint spring), so
        // that every kind of local change meets damping it must replace
        for model in [samples::frame_grid(1, 2, 2), samples::frame_with_joint(), samples::space_portal()] {
            check_model(&model, &mut kinds, &mut new_joints);
        }
        // a model of imported matrices: masses at its nodes, changes of its groups
        let imported = fe_model::imported::export::as_imported(&samples::frame_grid(1, 1, 2)).unwrap();
        let mut imported_kinds = Vec::new();
        check_model(&imported, &mut imported_kinds, &mut 0);
        for kind in [EffectKind::LumpedMass, EffectKind::StiffnessChange, EffectKind::MassChange] {
            assert!(imported_kinds.contains(&kind), "no local {kind:?} candidate of an imported model was checked");
        }
        assert!(new_joints > 0, "no new joint was checked");
        for kind in [
            EffectKind::LumpedMass,
            EffectKind::StiffnessChange,
            EffectKind::MassChange,
            EffectKind::ViscousDamping,
            EffectKind::NonViscousDamping,
            EffectKind::FlexibleJoint,
            EffectKind::FlexibleSupport,
        ] {
            assert!(kinds.contains(&kind), "no local {kind:?} candidate was checked");
        }
    }

    fn check_model(model: &fe_model::Model, kinds: &mut Vec<EffectKind>, new_joints: &mut usize) {
        let nominal = DampedSystem::new(model.clone()).unwrap();
        let uy: Vec<DofRef> =
            (0..nominal.n()).map(|eq| nominal.assembly().dofs.dof_of(eq)).filter(|d| d.dof == Dof::Uy).collect();
        let channels: Vec<Channel> = uy.iter().step_by(2).map(|&r| Channel::new(r, uy[uy.len() - 1])).collect();
        let lines = [3.0, 17.0, 41.0, 88.0];
        let opts = CandidateOptions { band_hz: (1.0, 100.0), ..CandidateOptions::default() };
        let mut all = candidates::generate(model, &opts);
        // the fuller variants (a joint's translational springs, a mass's
        // rotary inertia) and those that hold a spring rigid
        let tried = all.iter().map(|c| c.description.clone()).collect();
        let leaders: Vec<&candidates::Candidate> = all
            .iter()
            .filter(|c| matches!(c.edit, candidates::Edit::Joint { .. }))
            .chain(all.iter().filter(|c| c.kind == EffectKind::LumpedMass).take(2))
            .collect();
        let refined = candidates::refine(model, &opts, &leaders, &tried);
        let held: Vec<candidates::Candidate> = all
            .iter()
            .chain(&refined)
            .filter_map(|c| {
                let springs: Vec<usize> = (0..c.roles.len())
                    .filter(|&i| matches!(c.roles[i], candidates::Role::Spring(d) if d.is_translation()))
                    .collect();
                c.holding(model, &springs[..springs.len().min(1)])
            })
            .collect();
        if leaders.iter().any(|c| matches!(c.edit, candidates::Edit::Joint { .. })) {
            assert!(
                refined
                    .iter()
                    .any(|c| c.kind == EffectKind::FlexibleJoint && c.dofs.iter().any(|d| d.is_translation())),
                "{}",
                model.title
            );
        }
        assert!(refined.iter().any(|c| c.roles.contains(&candidates::Role::Inertia)), "{}", model.title);
        // (an imported model's supports hold DOFs no matrix has: nothing to release)
        assert!(!held.is_empty() || !model.imported().is_empty(), "{}", model.title);
        all.extend(refined);
        all.extend(held);
        let locals: Vec<Option<LocalCandidate>> = all.iter().map(|c| LocalCandidate::new(&nominal, c)).collect();
        let forms: Vec<&LocalForm> = locals.iter().flatten().map(|l| &l.form).collect();
        let data = LocalData::new(&nominal, &channels, &lines, &forms).unwrap();
        // S from the selected inverse equals S from unit solves (the fallback)
        let solver = ZSolver::with_cliques(&nominal.assembly().pattern, &data.slots).unwrap();
        let mut ws = solver.workspace();
        let z = nominal.z_values(2.0 * std::f64::consts::PI * lines[1]);
        solver.factorize(&mut ws, &z, lines[1]).unwrap();
        let mut s: Vec<Vec<C64>> = data.slots.iter().map(|e| vec![ZERO; e.len() * e.len()]).collect();
        unit_solves(&solver, &mut ws, &data.slots, &mut Vec::new(), lines[1], &mut s).unwrap();
        for (got, want) in data.per_line[1].s.iter().zip(&s) {
            let scale = want.iter().map(|v| v.norm()).fold(0.0, f64::max);
            assert!(got.iter().zip(want).all(|(g, w)| (g - w).norm() <= 1e-10 * scale), "S differs from unit solves");
        }
        for (c, local) in all.iter().zip(&locals) {
            let Some(local) = local else { panic!("{} has no local form", c.description) };
            kinds.push(c.kind);
            // a joint the model lacks, not only one it has
            *new_joints += usize::from(matches!(c.edit, candidates::Edit::Joint { .. }));
            // the truth: the candidate's whole model
            let sys = DampedSystem::new(c.model(model).unwrap()).unwrap();
            let params = ParameterSet::new(c.parameters_in(sys.model()).unwrap());
            // away from the start: masses and damping grow, stiffness falls
            let values: Vec<f64> = params.values(&sys).iter().map(|v| v * 1.7).collect();
            let mut response = data.response(local, local.part.clone());
            response.set(&values).unwrap();
            let (h, sens) = response.evaluate(&lines, true).unwrap();
            let mut truth = sys;
            params.set_values(&mut truth, &values).unwrap();
            let solver = ZSolver::new(&truth.assembly().pattern).unwrap();
            let plan = ChannelPlan::new(&truth, &channels).unwrap();
            let blocks =
                sensitivity::assemble(&truth, &solver, &plan, params.quantities(), &lines, Hybrid::Model).unwrap();
            let sens = sens.unwrap();
            for (k, b) in blocks.iter().enumerate() {
                let scale = b.model.iter().map(|v| v.norm()).fold(0.0, f64::max);
                for (ch, v) in b.model.iter().enumerate() {
                    assert!((h[k][ch] - v).norm() <= 1e-9 * scale, "{}: H at line {k}", c.description);
                }
                let want = params.combine(b);
                // Relative to each sensitivity, with a floor relative to the
                // response itself: a spring a hundred times stiffer than the
                // member (a joint's translational spring at its rigid start)
                // has a sensitivity 1e-8 of H, which the low-rank update and
                // the whole model's factorisation each resolve only to about
                // 1e-15 of H.
                let h_scale = b.model.iter().map(|v| v.norm()).fold(0.0, f64::max);
                for i in 0..params.len() {
                    let scale = (0..channels.len()).map(|ch| want[(ch, i)].norm()).fold(0.0, f64::max);
                    for ch in 0..channels.len() {
                        assert!(
                            (sens[k][(ch, i)] - want[(ch, i)]).norm() <= 1e-9 * scale + 1e-12 * h_scale,
                            "{}: sensitivity {i} at line {k}: {} vs {} (scale {scale:e}, H scale {h_scale:e})",
                            c.description,
                            sens[k][(ch, i)],
                            want[(ch, i)],
                        );
                    }
                }
            }
        }
    }
}
