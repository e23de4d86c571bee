//! The term table: the terms of the parameters' derivatives grouped into
//! classes, bucketed by solver row for the sweep, with the coefficient of
//! each `(parameter, class)` pair from the group data (or from
//! `DampedSystem::derivative` as a fallback).

use std::hash::Hasher;

use damping::{DampedSystem, Derivative, GroupCoefficients, UnitStore, kernel};
use fe_model::{Group, MatrixKind, Quantity};
use frf::ZSolver;
use num_complex::Complex64 as C64;

use rustc_hash::{FxHashMap, FxHasher};

use super::{MAX_BLOCK, NONE, ZERO};

/// A block that some parameter touches, as step 4 reads it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Item {
    /// Solver row of each local equation.
    pub(super) rows: [u32; MAX_BLOCK],
    /// Number of local equations.
    pub(super) nb: u32,
    /// Its used terms, `terms[t0..t1]`.
    pub(super) t0: u32,
    pub(super) t1: u32,
}

/// A term that some parameter uses.
#[derive(Clone, Copy, Debug)]
pub(super) struct TermRef {
    /// Offset of its unit matrix (`nb x nb`, row-major) in `units`.
    pub(super) unit: u32,
    /// The class whose sum it adds to.
    pub(super) class: u32,
    /// The term's current value (product of its model quantities).
    pub(super) value: f64,
}

/// How the coefficient of a `(parameter, class)` pair is found at a line.
#[derive(Clone, Debug)]
pub(super) enum Coefficients {
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
pub(super) enum Rule {
    Alpha,
    Beta,
    Mu,
    /// A factor on terms: the group coefficient of the term's kind.
    Factor,
}

impl Rule {
    pub(super) fn of(q: Quantity) -> Rule {
        match q {
            Quantity::GroupAlpha(_) => Rule::Alpha,
            Quantity::GroupBeta(_) => Rule::Beta,
            Quantity::GroupMu(_) => Rule::Mu,
            _ => Rule::Factor,
        }
    }

    /// The coefficient on a term of `kind` in group `group` at `omega`.
    pub(super) fn coefficient(self, groups: &[Group], group: usize, kind: MatrixKind, omega: f64) -> C64 {
        let d = match self {
            Rule::Alpha => kernel::d_alpha(&groups[group], omega),
            Rule::Beta => kernel::d_beta(&groups[group], omega),
            Rule::Mu => kernel::d_mu(&groups[group], omega),
            Rule::Factor => return GroupCoefficients::new(&groups[group], omega).of(kind),
        };
        d.of(kind)
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
pub(super) struct TermTable {
    /// Items of bucket `r`: `items[bucket[r]..bucket[r + 1]]`.
    pub(super) bucket: Vec<u32>,
    pub(super) items: Vec<Item>,
    pub(super) terms: Vec<TermRef>,
    pub(super) units: Vec<f64>,
    pub(super) n_classes: usize,
    /// `(parameter, class)`: the parameter's sensitivity includes the class
    /// sum times the pair's coefficient.
    pub(super) pairs: Vec<(u32, u32)>,
    pub(super) coefficients: Coefficients,
}

impl TermTable {
    /// A table for the parameters' derivatives at `omega`.
    pub(super) fn new(sys: &DampedSystem, solver: &ZSolver, params: &[Quantity], omega: f64) -> Self {
        Self::build(sys, solver, params, omega, true)
    }

    /// As [`Self::new`]; `use_rules = false` forces the fallback (tests).
    pub(super) fn build(
        sys: &DampedSystem,
        solver: &ZSolver,
        params: &[Quantity],
        omega: f64,
        use_rules: bool,
    ) -> Self {
        let derivs: Vec<Derivative> = params.iter().map(|&q| sys.derivative(q, omega)).collect();
        let groups = sys.model().groups();
        let blocks = sys.assembly().blocks();
        // do the rules reproduce every coefficient of the derivatives?
        let rules_hold = use_rules
            && params.iter().zip(&derivs).all(|(&q, d)| {
                d.terms.iter().all(|&(b, t, c)| {
                    let group = rule_group(q, blocks[b].group());
                    Rule::of(q).coefficient(groups, group, blocks[b].terms()[t].kind(), omega) == c
                })
            });
        let mut term_offset = Vec::with_capacity(blocks.len() + 1);
        term_offset.push(0usize);
        for b in blocks {
            term_offset.push(term_offset.last().copied().unwrap_or(0) + b.terms().len());
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
        let first_row = |b: usize| blocks[b].eqs().iter().map(|&e| solver.position(e)).min().unwrap_or(0);
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
        let mut class_of: FxHashMap<u64, u32> = FxHashMap::default();
        let mut classes: Vec<(usize, MatrixKind, usize)> = Vec::new();
        let mut class_of_term = vec![NONE; total];
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        let mut pair_rules = Vec::new();
        for &b in &order {
            let block = &blocks[b];
            let nb = block.eqs().len();
            assert!(nb <= MAX_BLOCK, "blocks have at most two nodes of six DOFs");
            let mut rows = [0u32; MAX_BLOCK];
            for (r, &e) in rows.iter_mut().zip(block.eqs()) {
                *r = solver.position(e) as u32;
            }
            let t0 = terms.len() as u32;
            for (t, term) in block.terms().iter().enumerate() {
                let f = term_offset[b] + t;
                if !used(f) {
                    continue;
                }
                let unit = units.offset_of(term.unit()).expect("unit matrices within u32 offsets");
                let who = &users[users_ptr[f] as usize..users_ptr[f + 1] as usize];
                let mut new_class = || {
                    let class = if rules_hold { classes.len() } else { terms.len() } as u32;
                    for &i in who {
                        pairs.push((i, class));
                        let q = params[i as usize];
                        pair_rules.push((Rule::of(q), rule_group(q, block.group()), term.kind()));
                    }
                    class
                };
                let class = if rules_hold {
                    let mut h = FxHasher::default();
                    h.write_usize(block.group());
                    h.write_u32(damping::kernel::kind_slot(term.kind()));
                    for &i in who {
                        h.write_u32(i);
                    }
                    let key = h.finish();
                    let same = |c: u32| {
                        let (g, kind, f0) = classes[c as usize];
                        let them = &users[users_ptr[f0] as usize..users_ptr[f0 + 1] as usize];
                        g == block.group() && kind == term.kind() && them == who
                    };
                    match class_of.get(&key).copied().filter(|&c| same(c)) {
                        Some(c) => c,
                        None => {
                            let c = new_class();
                            classes.push((block.group(), term.kind(), f));
                            class_of.insert(key, c);
                            c
                        }
                    }
                } else {
                    new_class()
                };
                class_of_term[f] = class;
                terms.push(TermRef { unit, class, value: term.value() });
            }
            items.push(Item { rows, nb: nb as u32, t0, t1: terms.len() as u32 });
        }
        let n_classes = if rules_hold { classes.len() } else { terms.len() };
        let coefficients = if rules_hold {
            Coefficients::Rules(pair_rules)
        } else {
            // one class per term, so each (parameter, term) is one pair
            let mut pair_at: FxHashMap<(u32, u32), u32> = FxHashMap::default();
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
        TermTable { bucket, items, terms, units: units.into_values(), n_classes, pairs, coefficients }
    }

    /// Each pair's coefficient at `omega` into `coef`. `None` when the
    /// derivatives now list other terms than the table was made from.
    pub(super) fn coefficients(
        &self,
        sys: &DampedSystem,
        params: &[Quantity],
        omega: f64,
        coef: &mut Vec<C64>,
    ) -> Option<()> {
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
pub(super) fn rule_group(q: Quantity, term_group: usize) -> usize {
    match q {
        Quantity::GroupAlpha(g) | Quantity::GroupBeta(g) | Quantity::GroupMu(g) => g,
        _ => term_group,
    }
}
