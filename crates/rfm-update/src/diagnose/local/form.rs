//! Where a candidate's `Z` differs from the nominal one: the equations `D`
//! its changed blocks touch, matched to the whole nominal model's by DOF,
//! and the equations it adds.

use std::collections::HashMap;

use damping::DampedSystem;
use fe_model::{Assembly, BlockSource, Quantity};

use super::MAX_LOCAL_EQS;
use crate::params::ParameterSet;

/// The model item a block comes from, by id or name: block indices differ
/// between a part and the whole, and between a part before and after a
/// change.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum Item {
    Beam(u32),
    Spring(String),
    Mass(String),
    /// An imported block: group, matrix, its two nodes.
    Imported(usize, fe_model::imported::ImportedKind, u32, u32),
}

fn item(model: &fe_model::Model, source: BlockSource) -> Item {
    match source {
        BlockSource::Beam(i) => Item::Beam(model.beams()[i].id.0),
        BlockSource::Spring(i) => Item::Spring(model.springs()[i].name.clone()),
        BlockSource::Mass(i) => Item::Mass(model.masses()[i].name.clone()),
        BlockSource::Imported(i) => {
            let b = &model.imported()[i];
            Item::Imported(b.group, b.kind, b.nodes[0].0, b.nodes[1].0)
        }
    }
}

/// The equation of the whole nominal model for each equation of a part,
/// when it has one (a DOF the part frees, or a node it adds, has none).
fn whole_equations(nominal: &Assembly, part: &Assembly) -> Vec<Option<usize>> {
    (0..part.n())
        .map(|eq| {
            part.dofs().dofs_of(eq).iter().find_map(|&r| match nominal.dofs().slot(r) {
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
    pub(super) new_eqs: usize,
    /// Local index of each equation of the candidate's part (`usize::MAX`
    /// where no changed block touches it).
    pub(super) index: Vec<usize>,
    /// Local index of each equation of the nominal part (likewise).
    pub(super) nominal_index: Vec<usize>,
    /// Blocks of the candidate's part that differ or may differ.
    pub(super) blocks: Vec<usize>,
    /// The same blocks' counterparts in the nominal part.
    pub(super) nominal_blocks: Vec<usize>,
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
            a0.blocks().iter().enumerate().map(|(i, b)| (item(nominal_part.model(), b.source()), i)).collect();
        let counterpart: Vec<Option<usize>> =
            a.blocks().iter().map(|b| by_item.get(&item(cand.model(), b.source())).copied()).collect();
        if counterpart.iter().flatten().count() != a0.blocks().len() {
            return None;
        }
        let (g0, g) = (nominal_part.model().groups(), cand.model().groups());
        let mut touched = vec![false; a.blocks().len()];
        for &q in params.quantities() {
            match q {
                Quantity::GroupAlpha(i) | Quantity::GroupBeta(i) | Quantity::GroupMu(i) => {
                    a.group_blocks(i).iter().for_each(|&b| touched[b] = true);
                }
                _ => a.terms_of(q).iter().for_each(|&(b, _)| touched[b] = true),
            }
        }
        for (b, t) in touched.iter_mut().enumerate() {
            let Some(b0) = counterpart[b].map(|i| &a0.blocks()[i]) else {
                *t = true;
                continue;
            };
            let bc = &a.blocks()[b];
            let same_eqs =
                b0.eqs().len() == bc.eqs().len() && b0.eqs().iter().zip(bc.eqs()).all(|(&e0, &e)| map[e] == map0[e0]);
            let same_group = b0.group() == bc.group() && g0.get(b0.group()) == g.get(bc.group());
            let same_terms = b0.terms().len() == bc.terms().len()
                && b0
                    .terms()
                    .iter()
                    .zip(bc.terms())
                    .all(|(x, y)| x.value() == y.value() && x.kind() == y.kind() && x.unit() == y.unit());
            if !(same_eqs && same_group && same_terms) {
                *t = true;
            }
        }
        let blocks: Vec<usize> = (0..a.blocks().len()).filter(|&b| touched[b]).collect();
        let nominal_blocks: Vec<usize> = blocks.iter().filter_map(|&b| counterpart[b]).collect();
        // D: the nominal equations of the changed blocks, before and after
        let mut cand_eqs: Vec<usize> = blocks.iter().flat_map(|&b| a.blocks()[b].eqs().iter().copied()).collect();
        cand_eqs.sort_unstable();
        cand_eqs.dedup();
        let mut eqs: Vec<usize> = cand_eqs.iter().filter_map(|&e| map[e]).collect();
        eqs.extend(nominal_blocks.iter().flat_map(|&b| a0.blocks()[b].eqs().iter().filter_map(|&e| map0[e])));
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
    pub(super) fn nominal_index(&self, eq: usize) -> usize {
        self.nominal_index[eq]
    }

    /// Local index of an equation of the candidate's changed blocks.
    pub(super) fn candidate_index(&self, eq: usize) -> usize {
        self.index[eq]
    }
}
