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
//!   ([`ZSolver`]), its symbolic analysis shared by every line and iteration.
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
//!   [`DampedSystem::derivative`] when the table is made, and the assembly
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
//!   row, distinct unit matrices stored once) and a streamable copy of
//!   `Z(w)`'s contributions that gives bitwise the values of
//!   [`DampedSystem::z_values_into`] are made once per [`assemble`] call and
//!   shared by the threads, which take the lines in parallel, each with its
//!   own [`Scratch`].
//!
//! Per line the cost is one factorisation, `min(measured + references,
//! references x (1 + classes))` solves and `O(measured)` work per used term;
//! the memory per thread is the factor, the `N x` (that many) solutions and
//! the per-class sums; the result is `channels x parameters` per line.
//!
//! [`naive`] is the dense textbook formulation, a reference for tests and
//! benchmarks.

pub mod naive;

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::{Mutex, PoisonError};

use damping::{DampedSystem, Derivative, GroupCoefficients, kernel};
use faer::Mat;
use faer::traits::pulp::{Arch, Simd, WithSimd};
use fe_model::{Group, MatrixKind, Quantity};
use frf::solver::mul_add;
use frf::{Channel, FrfSet, Workspace, ZSolver, equation_of};
use num_complex::Complex64 as C64;
use rayon::prelude::*;

use crate::error::UpdateError;

const ZERO: C64 = C64 { re: 0.0, im: 0.0 };

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

const NONE: u32 = u32::MAX;

/// `Z(w)` laid out for fast evaluation at many frequencies.
///
/// [`DampedSystem::z_values_into`] walks every element's terms, unit
/// matrices and positions, each in its own heap allocation, at every
/// frequency. This is the same walk over compact arrays (positions as `u32`,
/// each distinct unit matrix stored once), with the same operations in the
/// same order, so it gives *bitwise* the same values: model FRFs from the
/// sensitivity assembly and from [`frf::synthesize_with`] then agree exactly,
/// which the response function method's step control relies on near
/// convergence. Made once per [`assemble`] call (the parameters may have
/// changed since the last).
struct ZCache {
    /// Per block: `(first position, number of local entries, first term, end of terms)`.
    blocks: Vec<(u32, u32, u32, u32)>,
    positions: Vec<u32>,
    /// Per non-zero term: `(slot, value, unit offset)`; the slot is `2 g` for
    /// group `g`'s stiffness terms and `2 g + 1` for its mass terms.
    terms: Vec<(u32, f64, u32)>,
    units: Vec<f64>,
}

impl ZCache {
    fn new(sys: &DampedSystem) -> Self {
        let a = sys.assembly();
        let mut units = UnitStore::default();
        let (mut blocks, mut positions, mut terms) = (Vec::with_capacity(a.blocks.len()), Vec::new(), Vec::new());
        for b in &a.blocks {
            let p0 = positions.len() as u32;
            positions.extend(b.positions.iter().map(|&p| p as u32));
            let t0 = terms.len() as u32;
            // Assembly::accumulate skips terms whose value is zero
            for t in b.terms.iter().filter(|t| t.value != 0.0) {
                let slot = 2 * b.group as u32 + u32::from(t.kind == MatrixKind::Mass);
                terms.push((slot, t.value, units.offset_of(&t.unit)));
            }
            blocks.push((p0, b.positions.len() as u32, t0, terms.len() as u32));
        }
        ZCache { blocks, positions, terms, units: units.values }
    }

    /// `Z(w)` into `out`, given each group's coefficients at `w`: the loop of
    /// `Assembly::accumulate` with the coefficients of `z_values_into`.
    fn values_into(&self, coefs: &[GroupCoefficients], out: &mut [C64]) {
        let by_slot: Vec<C64> = coefs.iter().flat_map(|c| [c.stiffness, c.mass]).collect();
        out.fill(ZERO);
        for &(p0, len, t0, t1) in &self.blocks {
            let positions = &self.positions[p0 as usize..(p0 + len) as usize];
            for &(slot, value, unit) in &self.terms[t0 as usize..t1 as usize] {
                let c = by_slot[slot as usize];
                let unit = &self.units[unit as usize..unit as usize + positions.len()];
                for (&p, &u) in positions.iter().zip(unit) {
                    if u != 0.0 {
                        out[p as usize] += c * (value * u);
                    }
                }
            }
        }
    }
}

/// Unit matrices stored once each: identical elements (the common case in
/// a mesh) share one copy, so that the hot loops read them from cache.
#[derive(Default)]
struct UnitStore {
    values: Vec<f64>,
    /// Hash of a matrix's bits to the offset of the last one stored with it.
    by_hash: FxMap<u64, u32>,
}

impl UnitStore {
    /// Offset in `values` of a matrix equal to `unit` (bit for bit), stored
    /// now if there is none.
    fn offset_of(&mut self, unit: &[f64]) -> u32 {
        // a sample of the entries is enough for a key: equality is checked
        let mut h = FxHasher::default();
        h.write_usize(unit.len());
        for u in unit.iter().step_by(5) {
            h.write_u64(u.to_bits());
        }
        let key = h.finish();
        if let Some(&at) = self.by_hash.get(&key) {
            let stored = &self.values[at as usize..at as usize + unit.len()];
            if stored.iter().zip(unit).all(|(a, b)| a.to_bits() == b.to_bits()) {
                return at;
            }
        }
        let at = self.values.len() as u32;
        self.values.extend_from_slice(unit);
        self.by_hash.insert(key, at);
        at
    }
}

/// A block that some parameter touches, as step 4 reads it.
#[derive(Clone, Copy, Debug)]
struct Item {
    /// Solver row of each local equation.
    rows: [u32; MAX_BLOCK],
    /// Number of local equations.
    nb: u32,
    /// Its used terms, `terms[t0..t1]`.
    t0: u32,
    t1: u32,
}

/// A term that some parameter uses.
#[derive(Clone, Copy, Debug)]
struct TermRef {
    /// Offset of its unit matrix (`nb x nb`, row-major) in `units`.
    unit: u32,
    /// The class whose sum it adds to.
    class: u32,
    /// The term's current value (product of its model quantities).
    value: f64,
}

/// How the coefficient of a `(parameter, class)` pair is found at a line.
#[derive(Clone, Debug)]
enum Coefficients {
    /// From the group data, as [`DampedSystem::derivative`] computes it (this
    /// was checked when the table was made): `(rule, group, kind)` per pair.
    Rules(Vec<(Rule, usize, MatrixKind)>),
    /// From [`DampedSystem::derivative`] at each line, each term its own
    /// class: per parameter, `(block, term, pair)` for each of its terms in
    /// the derivative's order.
    Derivatives(Vec<Vec<(u32, u32, u32)>>),
}

/// Which derivative rule a parameter follows (see `damping::kernel`).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Rule {
    Alpha,
    Beta,
    Mu,
    /// A factor on terms: the group coefficient of the term's kind.
    Factor,
}

impl Rule {
    fn of(q: Quantity) -> Rule {
        match q {
            Quantity::GroupAlpha(_) => Rule::Alpha,
            Quantity::GroupBeta(_) => Rule::Beta,
            Quantity::GroupMu(_) => Rule::Mu,
            _ => Rule::Factor,
        }
    }

    /// The coefficient on a term of `kind` in group `group` at `omega`.
    fn coefficient(self, groups: &[Group], group: usize, kind: MatrixKind, omega: f64) -> C64 {
        let d = match self {
            Rule::Alpha => kernel::d_alpha(&groups[group], omega),
            Rule::Beta => kernel::d_beta(&groups[group], omega),
            Rule::Mu => kernel::d_mu(&groups[group], omega),
            Rule::Factor => return GroupCoefficients::new(&groups[group], omega).of(kind),
        };
        match kind {
            MatrixKind::Stiffness => d.stiffness,
            MatrixKind::Mass => d.mass,
        }
    }
}

/// The terms of step 4, laid out for one sweep.
///
/// A parameter's derivative is `sum over its terms of c(w) x value x unit
/// matrix`, where `c` depends only on the parameter and the term's group and
/// kind. Terms used by the same set of parameters in the same group and kind
/// form a *class*: step 4 sums `value x R[m, eqs] U x` over each class once,
/// and each parameter is then a combination of a few class sums (a group's
/// `alpha`, `mu` and stiffness factor share one sum instead of three).
/// Blocks are bucketed by the solver row at which their solution rows are all
/// final in the backward substitution (the smallest of their rows), and each
/// distinct unit matrix is stored once. Depends on the parameters' values and
/// on which terms their derivatives list, not on the frequency; made once per
/// [`assemble`] call.
struct TermTable {
    /// Items of bucket `r`: `items[bucket[r]..bucket[r + 1]]`.
    bucket: Vec<u32>,
    items: Vec<Item>,
    terms: Vec<TermRef>,
    units: Vec<f64>,
    n_classes: usize,
    /// `(parameter, class)`: the parameter's sensitivity includes the class
    /// sum times the pair's coefficient.
    pairs: Vec<(u32, u32)>,
    coefficients: Coefficients,
}

/// A small fast hash for the table's keys (FxHash's mixing step).
/// Most free DOFs of one block: two nodes of a frame in space (a planar
/// model's blocks have at most six).
const MAX_BLOCK: usize = 12;

#[derive(Default)]
struct FxHasher(u64);

impl Hasher for FxHasher {
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            self.write_u64(u64::from_le_bytes(c.try_into().expect("chunks of eight bytes")));
        }
        for &b in chunks.remainder() {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }

    fn write_u32(&mut self, x: u32) {
        self.write_u64(u64::from(x));
    }

    fn write_usize(&mut self, x: usize) {
        self.write_u64(x as u64);
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

type FxMap<K, V> = HashMap<K, V, BuildHasherDefault<FxHasher>>;

impl TermTable {
    /// A table for the parameters' derivatives at `omega`.
    fn new(sys: &DampedSystem, solver: &ZSolver, params: &[Quantity], omega: f64) -> Self {
        Self::build(sys, solver, params, omega, true)
    }

    /// As [`Self::new`]; `use_rules = false` forces the fallback (tests).
    fn build(sys: &DampedSystem, solver: &ZSolver, params: &[Quantity], omega: f64, use_rules: bool) -> Self {
        let derivs: Vec<Derivative> = params.iter().map(|&q| sys.derivative(q, omega)).collect();
        let groups = sys.model().groups();
        let blocks = &sys.assembly().blocks;
        // do the rules reproduce every coefficient of the derivatives?
        let rules_hold = use_rules
            && params.iter().zip(&derivs).all(|(&q, d)| {
                d.terms.iter().all(|&(b, t, c)| {
                    let group = rule_group(q, blocks[b].group);
                    Rule::of(q).coefficient(groups, group, blocks[b].terms[t].kind, omega) == c
                })
            });
        let mut term_offset = Vec::with_capacity(blocks.len() + 1);
        term_offset.push(0usize);
        for b in blocks {
            term_offset.push(term_offset.last().copied().unwrap_or(0) + b.terms.len());
        }
        let total = term_offset[blocks.len()];
        // the parameters using each assembly term (ascending, as pushed)
        let mut users_ptr = vec![0u32; total + 1];
        for d in &derivs {
            for &(b, t, _) in &d.terms {
                users_ptr[term_offset[b] + t + 1] += 1;
            }
        }
        for f in 0..total {
            users_ptr[f + 1] += users_ptr[f];
        }
        let mut fill = users_ptr[..total].to_vec();
        let mut users = vec![0u32; users_ptr[total] as usize];
        for (i, d) in derivs.iter().enumerate() {
            for &(b, t, _) in &d.terms {
                let f = term_offset[b] + t;
                users[fill[f] as usize] = i as u32;
                fill[f] += 1;
            }
        }
        drop(fill);
        let used = |f: usize| users_ptr[f] < users_ptr[f + 1];
        let used_blocks: Vec<usize> =
            (0..blocks.len()).filter(|&b| (term_offset[b]..term_offset[b + 1]).any(used)).collect();
        // bucket the used blocks by their smallest solver row (counting sort)
        let n = solver.n();
        let first_row = |b: usize| blocks[b].eqs.iter().map(|&e| solver.position(e)).min().unwrap_or(0);
        let mut bucket = vec![0u32; n + 1];
        for &b in &used_blocks {
            bucket[first_row(b) + 1] += 1;
        }
        for r in 0..n {
            bucket[r + 1] += bucket[r];
        }
        let mut order = vec![0usize; used_blocks.len()];
        let mut next: Vec<u32> = bucket[..n].to_vec();
        for &b in &used_blocks {
            let r = first_row(b);
            order[next[r] as usize] = b;
            next[r] += 1;
        }
        // items and terms in sweep order; unit matrices stored once; classes
        // by (group, kind, users) under the rules, else one per term
        let mut items = Vec::with_capacity(order.len());
        let mut terms = Vec::new();
        let mut units = UnitStore::default();
        // classes by hash of (group, kind, users), checked against the first
        // term of the class: (group, kind, its users' range in `users`)
        let mut class_of: FxMap<u64, u32> = FxMap::default();
        let mut classes: Vec<(usize, MatrixKind, usize)> = Vec::new();
        let mut class_of_term = vec![NONE; total];
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        let mut pair_rules = Vec::new();
        for &b in &order {
            let block = &blocks[b];
            let nb = block.eqs.len();
            assert!(nb <= MAX_BLOCK, "blocks have at most two nodes of six DOFs");
            let mut rows = [0u32; MAX_BLOCK];
            for (r, &e) in rows.iter_mut().zip(&block.eqs) {
                *r = solver.position(e) as u32;
            }
            let t0 = terms.len() as u32;
            for (t, term) in block.terms.iter().enumerate() {
                let f = term_offset[b] + t;
                if !used(f) {
                    continue;
                }
                let unit = units.offset_of(&term.unit);
                let who = &users[users_ptr[f] as usize..users_ptr[f + 1] as usize];
                let mut new_class = || {
                    let class = if rules_hold { classes.len() } else { terms.len() } as u32;
                    for &i in who {
                        pairs.push((i, class));
                        let q = params[i as usize];
                        pair_rules.push((Rule::of(q), rule_group(q, block.group), term.kind));
                    }
                    class
                };
                let class = if rules_hold {
                    let mut h = FxHasher::default();
                    h.write_usize(block.group);
                    h.write_u32(u32::from(term.kind == MatrixKind::Mass));
                    for &i in who {
                        h.write_u32(i);
                    }
                    let key = h.finish();
                    let same = |c: u32| {
                        let (g, kind, f0) = classes[c as usize];
                        let them = &users[users_ptr[f0] as usize..users_ptr[f0 + 1] as usize];
                        g == block.group && kind == term.kind && them == who
                    };
                    match class_of.get(&key).copied().filter(|&c| same(c)) {
                        Some(c) => c,
                        None => {
                            let c = new_class();
                            classes.push((block.group, term.kind, f));
                            class_of.insert(key, c);
                            c
                        }
                    }
                } else {
                    new_class()
                };
                class_of_term[f] = class;
                terms.push(TermRef { unit, class, value: term.value });
            }
            items.push(Item { rows, nb: nb as u32, t0, t1: terms.len() as u32 });
        }
        let n_classes = if rules_hold { classes.len() } else { terms.len() };
        let coefficients = if rules_hold {
            Coefficients::Rules(pair_rules)
        } else {
            // one class per term, so each (parameter, term) is one pair
            let mut pair_at: FxMap<(u32, u32), u32> = FxMap::default();
            for (p, &pair) in pairs.iter().enumerate() {
                pair_at.insert(pair, p as u32);
            }
            Coefficients::Derivatives(
                derivs
                    .iter()
                    .enumerate()
                    .map(|(i, d)| {
                        d.terms
                            .iter()
                            .map(|&(b, t, _)| {
                                let class = class_of_term[term_offset[b] + t];
                                (b as u32, t as u32, pair_at[&(i as u32, class)])
                            })
                            .collect()
                    })
                    .collect(),
            )
        };
        TermTable { bucket, items, terms, units: units.values, n_classes, pairs, coefficients }
    }

    /// Each pair's coefficient at `omega` into `coef`. `None` when the
    /// derivatives now list other terms than the table was made from.
    fn coefficients(&self, sys: &DampedSystem, params: &[Quantity], omega: f64, coef: &mut Vec<C64>) -> Option<()> {
        coef.clear();
        coef.resize(self.pairs.len(), ZERO);
        match &self.coefficients {
            Coefficients::Rules(rules) => {
                let groups = sys.model().groups();
                for (c, &(rule, group, kind)) in coef.iter_mut().zip(rules) {
                    *c = rule.coefficient(groups, group, kind, omega);
                }
            }
            Coefficients::Derivatives(lists) => {
                for (&q, list) in params.iter().zip(lists) {
                    let d = sys.derivative(q, omega);
                    if d.terms.len() != list.len() {
                        return None;
                    }
                    for (&(b, t, c), &(tb, tt, pair)) in d.terms.iter().zip(list) {
                        if (b, t) != (tb as usize, tt as usize) {
                            return None;
                        }
                        coef[pair as usize] = c;
                    }
                }
            }
        }
        Some(())
    }
}

/// The group whose data a parameter's rule reads for a term of `term_group`:
/// a damping parameter's own group, or the term's group for a factor.
fn rule_group(q: Quantity, term_group: usize) -> usize {
    match q {
        Quantity::GroupAlpha(g) | Quantity::GroupBeta(g) | Quantity::GroupMu(g) => g,
        _ => term_group,
    }
}

/// How step 4 reaches the measured rows (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Strategy {
    /// Whichever needs fewer right-hand sides.
    Auto,
    /// Unit solves at the measured DOFs, products taken in the sweep.
    #[cfg_attr(not(test), allow(dead_code))] // forced in tests
    MeasuredRows,
    /// Solves with the class sums `sum value U x` as right-hand sides.
    #[cfg_attr(not(test), allow(dead_code))] // forced in tests
    ClassSums,
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
    assemble_line(sys, None, None, Strategy::Auto, solver, plan, params, freq_hz, hybrid, line, scratch)
}

/// [`assemble_one`] with optional prepared parts: a Z cache, and a term
/// table (made here for this line when absent or when it does not fit).
fn assemble_line(
    sys: &DampedSystem,
    cache: Option<&ZCache>,
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
    scratch.z.resize(sys.assembly().pattern.nnz(), ZERO);
    match cache {
        None => sys.z_values_into(omega, &mut scratch.z),
        Some(cache) => cache.values_into(&sys.coefficients(omega), &mut scratch.z),
    }
    solver.factorize(&mut scratch.ws, &scratch.z, freq_hz)?;

    // class sums as right-hand sides need n_ref (1 + classes) solves in two
    // rounds, the measured rows n_ref + n_resp in one
    let class_sums = match strategy {
        Strategy::Auto => {
            matches!(table.coefficients, Coefficients::Rules(_)) && n_ref * (1 + table.n_classes) < n_ref + n_resp
        }
        Strategy::MeasuredRows => false,
        Strategy::ClassSums => true,
    };
    let model = if class_sums {
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

/// Step 4 for the blocks of one bucket, every reference: for each used term,
/// `acc[ref, class, m] += R[m, eqs] (value U x)` over the block's equations.
/// Vectorised over the responses `m`, contiguous in each row.
struct BucketProducts<'a> {
    table: &'a TermTable,
    items: &'a [Item],
    /// The solver row of `rows[0..k]`.
    first_row: usize,
    /// Final solution rows `first_row..`, `k` values each.
    rows: &'a [C64],
    n_ref: usize,
    n_resp: usize,
    measured_at: &'a [u32],
    measured: &'a [Option<C64>],
    /// `references x classes x responses`.
    acc: &'a mut [C64],
}

impl WithSimd for BucketProducts<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let BucketProducts { table, items, first_row, rows, n_ref, n_resp, measured_at, measured, acc } = self;
        let k = n_ref + n_resp;
        let mut off = [0usize; MAX_BLOCK];
        let mut xb = [ZERO; MAX_BLOCK];
        let mut v = [ZERO; MAX_BLOCK];
        for item in items {
            let nb = item.nb as usize;
            for (o, &r) in off[..nb].iter_mut().zip(&item.rows[..nb]) {
                *o = (r as usize - first_row) * k;
            }
            for ri in 0..n_ref {
                // x at the block's equations: the hybrid or the model column
                for l in 0..nb {
                    let at = measured_at.get(item.rows[l] as usize).copied().unwrap_or(NONE);
                    let replaced = if at == NONE { None } else { measured[at as usize * n_ref + ri] };
                    xb[l] = replaced.unwrap_or(rows[off[l] + ri]);
                }
                for term in &table.terms[item.t0 as usize..item.t1 as usize] {
                    let unit = &table.units[term.unit as usize..term.unit as usize + nb * nb];
                    for (r, vr) in v[..nb].iter_mut().enumerate() {
                        let urow = &unit[r * nb..(r + 1) * nb];
                        *vr = urow.iter().zip(&xb[..nb]).fold(ZERO, |s, (&u, &x)| s + x * u) * term.value;
                    }
                    let at = (ri * table.n_classes + term.class as usize) * n_resp;
                    let sum = &mut acc[at..at + n_resp];
                    for (&o, &vr) in off[..nb].iter().zip(&v[..nb]) {
                        if vr != ZERO {
                            mul_add(simd, sum, vr, &rows[o + n_ref..o + k]);
                        }
                    }
                }
            }
        }
    }
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
    let (table, cache) =
        rayon::join(|| TermTable::new(sys, solver, params, omega), || (freqs_hz.len() >= 3).then(|| ZCache::new(sys)));
    // rayon's `map_init` would make a scratch per work split, not per thread;
    // a pool makes at most one per concurrently running task
    let pool = Mutex::new(Vec::new());
    freqs_hz
        .par_iter()
        .enumerate()
        .map(|(k, &f)| {
            let popped = pool.lock().unwrap_or_else(PoisonError::into_inner).pop();
            let mut scratch = popped.unwrap_or_else(|| Scratch::new(solver));
            let block = assemble_line(
                sys,
                cache.as_ref(),
                Some(&table),
                Strategy::Auto,
                solver,
                plan,
                params,
                f,
                hybrid,
                k,
                &mut scratch,
            );
            pool.lock().unwrap_or_else(PoisonError::into_inner).push(scratch);
            block
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::{Dof, DofRef, samples};

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

    #[test]
    fn z_cache_gives_bitwise_the_system_values() {
        let (sys, _) = every_kind();
        let cache = ZCache::new(&sys);
        for f in [3.0, 170.0] {
            let omega = 2.0 * std::f64::consts::PI * f;
            let mut fast = vec![ZERO; sys.assembly().pattern.nnz()];
            cache.values_into(&sys.coefficients(omega), &mut fast);
            assert_eq!(fast, sys.z_values(omega));
        }
    }

    /// The class sums with coefficient rules, and the fallback with one class
    /// per term and coefficients from `DampedSystem::derivative` at every
    /// line, give the same sensitivities.
    #[test]
    fn coefficient_rules_and_the_derivative_fallback_agree() {
        let (sys, params) = every_kind();
        let solver = ZSolver::new(&sys.assembly().pattern).unwrap();
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
            assemble_line(&sys, None, Some(table), strategy, &solver, &plan, &params, f, Hybrid::Model, 0, &mut scratch)
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

    /// Solving for each class sum and reading the measured rows gives what
    /// the unit solves at the measured rows give, for both hybrid modes.
    #[test]
    fn class_sums_and_measured_rows_agree() {
        let (truth, params) = every_kind();
        let mut sys = truth.clone();
        sys.set(params[0], 1.7 * sys.get(params[0])).unwrap();
        let solver = ZSolver::new(&sys.assembly().pattern).unwrap();
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
                    assemble_line(&sys, None, t, strategy, &solver, &plan, &params, f, hybrid, line, &mut scratch)
                        .unwrap()
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
