//! Sparse assembly that keeps every element's contribution separate.
//!
//! An [`Assembly`] is the model turned into equations: a [`DofMap`], one
//! symmetric sparsity [`Pattern`] shared by K, M and every damping matrix, and
//! one [`Block`] per element, spring and lumped mass. A block holds the local
//! equation indices and a few [`Term`]s, each a *unit* matrix times a value
//! that is the product of model quantities:
//!
//! ```text
//! beam  K:  E * f_element * f_group       * K_unit(A, I, L, angle)
//! beam  M:  rho * f_element * f_group     * M_unit(A, L, angle)   (+ added mass term)
//! spring:   k_d * f_group                 * [1 -1; -1 1] on direction d
//! mass:     m * f_group (translations),  j_a * f_group (rotation about axis a)
//! ```
//!
//! A planar model's nodes have three DOFs and its beams the planar element
//! ([`element`]); a 3D model's nodes have six and its beams the element of
//! [`element::frame3d`], whose unit stiffness holds the torsion `G J / E`.
//!
//! Any group matrix `K_g`, `M_g`, and the derivative of any of them with
//! respect to a quantity, is then a sum over a known list of terms. Nothing
//! here knows about frequencies; `damping` combines the terms into `Z(w)`.

use std::collections::HashMap;

use nalgebra::DMatrix;

use crate::dof::{Dof, DofMap, DofRef, Slot};
use crate::element;
use crate::error::ModelError;
use crate::imported::ImportedKind;
use crate::model::{Model, NodeId};
use crate::quantity::Quantity;
use crate::union_find::UnionFind;

mod pattern;
pub use pattern::Pattern;

/// Which global matrix a term belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MatrixKind {
    /// Stiffness K.
    Stiffness,
    /// Mass M.
    Mass,
    /// A viscous damping matrix C of the user's own (imported), entering
    /// `Z` as `j w C` whatever its group's kernel.
    Damping,
}

/// The model item a block comes from (index into the model's list).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BlockSource {
    /// A beam element.
    Beam(usize),
    /// A spring.
    Spring(usize),
    /// A lumped mass.
    Mass(usize),
    /// A block of an imported matrix (index into [`Model::imported`]).
    Imported(usize),
}

/// One unit matrix of a block, times a value.
///
/// Made only by [`Assembly`], from its model: the value is always the
/// product of the factors' current values ([`Assembly::refresh`]), and the
/// unit matrix is square over the block's free DOFs.
#[derive(Clone, Debug)]
pub struct Term {
    kind: MatrixKind,
    factors: Vec<Quantity>,
    value: f64,
    unit: Vec<f64>,
}

impl Term {
    /// Stiffness or mass.
    #[inline]
    pub fn kind(&self) -> MatrixKind {
        self.kind
    }

    /// Model quantities whose product is [`Self::value`].
    #[inline]
    pub fn factors(&self) -> &[Quantity] {
        &self.factors
    }

    /// Current product of the factors.
    #[inline]
    pub fn value(&self) -> f64 {
        self.value
    }

    /// Unit matrix over the block's free local DOFs, row-major `n x n`.
    #[inline]
    pub fn unit(&self) -> &[f64] {
        &self.unit
    }
}

/// The contribution of one element, spring or mass.
///
/// Made only by [`Assembly`]: its equations are the free ones of its DOFs,
/// every term's unit matrix is `len() x len()`, and its positions are in
/// the assembly's pattern.
#[derive(Clone, Debug)]
pub struct Block {
    source: BlockSource,
    group: usize,
    eqs: Vec<usize>,
    terms: Vec<Term>,
    positions: Vec<usize>,
}

impl Block {
    /// Where it comes from.
    #[inline]
    pub fn source(&self) -> BlockSource {
        self.source
    }

    /// Its group index.
    #[inline]
    pub fn group(&self) -> usize {
        self.group
    }

    /// Equation index of each free local DOF (may repeat when DOFs are tied).
    #[inline]
    pub fn eqs(&self) -> &[usize] {
        &self.eqs
    }

    /// Its terms.
    #[inline]
    pub fn terms(&self) -> &[Term] {
        &self.terms
    }

    /// For each local pair `(r, c)` (row-major), the index in the pattern's values.
    #[inline]
    pub fn positions(&self) -> &[usize] {
        &self.positions
    }

    /// Number of free local DOFs.
    #[inline]
    pub fn len(&self) -> usize {
        self.eqs.len()
    }

    /// True when every local DOF is fixed.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.eqs.is_empty()
    }
}

/// A model assembled into equations; see the module docs.
///
/// Made only from a [`Model`] ([`Assembly::new`], [`Assembly::of_part`]),
/// so that its blocks, pattern and DOF map agree; its term values follow
/// the model through [`Assembly::refresh`] and [`Assembly::refresh_quantity`].
#[derive(Clone, Debug)]
pub struct Assembly {
    dofs: DofMap,
    pattern: Pattern,
    blocks: Vec<Block>,
    group_blocks: Vec<Vec<usize>>,
    /// For each factor quantity, the `(block, term)` pairs it multiplies.
    by_quantity: HashMap<Quantity, Vec<(usize, usize)>>,
}

fn build_dof_map(model: &Model) -> DofMap {
    let n = model.nodes.len();
    let dim = model.dimension;
    let nd = dim.dofs_per_node();
    let slot_of = |id: NodeId, d: Dof| nd * model.node_index[&id] + dim.local(d).expect("checked when added");
    let mut uf = UnionFind::new(nd * n);
    for tie in &model.ties {
        for &d in &tie.dofs {
            uf.union(slot_of(tie.nodes[0], d), slot_of(tie.nodes[1], d));
        }
    }
    let mut fixed = vec![false; nd * n];
    for s in &model.supports {
        for &d in &s.dofs {
            let root = uf.find(slot_of(s.node, d));
            fixed[root] = true;
        }
    }
    let mut map = DofMap::default();
    let mut eq_of_root: HashMap<usize, usize> = HashMap::new();
    for (i, node) in model.nodes.iter().enumerate() {
        for (k, &d) in dim.dofs().iter().enumerate() {
            let r = DofRef { node: node.id, dof: d };
            let root = uf.find(nd * i + k);
            if fixed[root] {
                map.insert_fixed(r);
            } else if let Some(&eq) = eq_of_root.get(&root) {
                map.insert_alias(r, eq);
            } else {
                let eq = map.insert_free(r);
                eq_of_root.insert(root, eq);
            }
        }
    }
    map
}

/// A term before fixed DOFs are removed: kind, factors, full local matrix.
type RawTerm = (MatrixKind, Vec<Quantity>, LocalMatrix);

/// A block before fixed DOFs are removed: source, group, local DOFs, terms.
type RawBlock = (BlockSource, usize, Vec<DofRef>, Vec<RawTerm>);

/// Local DOFs and terms (full, before removing fixed DOFs) of every block.
fn raw_blocks(model: &Model) -> Vec<RawBlock> {
    let mut out = Vec::new();
    let dim = model.dimension;
    let nd = dim.dofs_per_node();
    let node_dofs = |id: NodeId| dim.dofs().iter().map(move |&d| DofRef { node: id, dof: d });
    for (i, b) in model.beams.iter().enumerate() {
        let dofs: Vec<DofRef> = node_dofs(b.nodes[0]).chain(node_dofs(b.nodes[1])).collect();
        let g = b.group;
        // unit stiffness (axial with torsion, and bending, apart so that the
        // bending alone can change), unit consistent mass, unit added
        // (lumped transverse) mass
        let [_, m, added] = element::beam_units(model, i).map(|u| LocalMatrix::from_dense(&u));
        let [axial, bending] = element::beam_stiffness_parts(model, i).map(|u| LocalMatrix::from_dense(&u));
        let stiffness = [Quantity::MaterialE(b.material), Quantity::ElementStiffness(i), Quantity::GroupStiffness(g)];
        let terms = vec![
            (MatrixKind::Stiffness, stiffness.to_vec(), axial),
            (MatrixKind::Stiffness, [stiffness.as_slice(), &[Quantity::ElementBending(i)]].concat(), bending),
            (
                MatrixKind::Mass,
                vec![Quantity::MaterialRho(b.material), Quantity::ElementMass(i), Quantity::GroupMass(g)],
                m,
            ),
            // The added-mass term always exists so that it can be updated from zero.
            (
                MatrixKind::Mass,
                vec![Quantity::ElementAddedMass(i), Quantity::ElementMass(i), Quantity::GroupMass(g)],
                added,
            ),
        ];
        out.push((BlockSource::Beam(i), g, dofs, terms));
    }
    for (i, sp) in model.springs.iter().enumerate() {
        let mut dofs: Vec<DofRef> = node_dofs(sp.a).collect();
        if let Some(b) = sp.b {
            dofs.extend(node_dofs(b));
        }
        let n = dofs.len();
        let terms = dim
            .dofs()
            .iter()
            .map(|&d| {
                // r r^T on the node's DOFs along (or about) the axis of d,
                // and -r r^T to the other node: in global axes r is e_d
                let r: Vec<(usize, f64)> = sp
                    .direction(dim, d)
                    .into_iter()
                    .map(|(g, c)| (dim.local(g).expect("of the dimension"), c))
                    .collect();
                let mut u = vec![0.0; n * n];
                for &(i, ci) in &r {
                    for &(j, cj) in &r {
                        u[i * n + j] = ci * cj;
                        if n == 2 * nd {
                            u[(nd + i) * n + nd + j] = ci * cj;
                            u[i * n + nd + j] = -(ci * cj);
                            u[(nd + i) * n + j] = -(ci * cj);
                        }
                    }
                }
                (
                    MatrixKind::Stiffness,
                    vec![Quantity::SpringK(i, d), Quantity::GroupStiffness(sp.group)],
                    LocalMatrix(u),
                )
            })
            .collect();
        out.push((BlockSource::Spring(i), sp.group, dofs, terms));
    }
    for (i, m) in model.masses.iter().enumerate() {
        let dofs: Vec<DofRef> = node_dofs(m.node).collect();
        // the unit matrix on the given DOFs of the node
        let on = |which: &[Dof]| {
            let mut u = vec![0.0; nd * nd];
            for &d in which {
                let k = dim.local(d).expect("a DOF of the dimension");
                u[k * nd + k] = 1.0;
            }
            LocalMatrix(u)
        };
        let mut terms =
            vec![(MatrixKind::Mass, vec![Quantity::MassM(i), Quantity::GroupMass(m.group)], on(dim.translations()))];
        for &r in dim.rotations() {
            terms.push((MatrixKind::Mass, vec![Quantity::MassJ(i, r), Quantity::GroupMass(m.group)], on(&[r])));
        }
        out.push((BlockSource::Mass(i), m.group, dofs, terms));
    }
    for (i, b) in model.imported.iter().enumerate() {
        let factor = match b.kind {
            ImportedKind::Stiffness => (MatrixKind::Stiffness, Quantity::GroupStiffness(b.group)),
            ImportedKind::Mass => (MatrixKind::Mass, Quantity::GroupMass(b.group)),
            ImportedKind::Damping => (MatrixKind::Damping, Quantity::GroupDamping(b.group)),
        };
        let terms = vec![(factor.0, vec![factor.1], LocalMatrix(b.values.clone()))];
        out.push((BlockSource::Imported(i), b.group, b.dofs.clone(), terms));
    }
    out
}

/// A full local matrix, row-major, of a block's local DOFs.
struct LocalMatrix(Vec<f64>);

impl LocalMatrix {
    fn from_dense(m: &DMatrix<f64>) -> Self {
        let n = m.nrows();
        LocalMatrix((0..n * n).map(|k| m[(k / n, k % n)]).collect())
    }

    fn get(&self, n: usize, r: usize, c: usize) -> f64 {
        self.0[r * n + c]
    }
}

impl Assembly {
    /// Assembles a model. Fails when no DOF is free, when a node with free
    /// DOFs touches nothing, or when a free DOF has no stiffness at all.
    pub fn new(model: &Model) -> Result<Self, ModelError> {
        let assembly = Self::build(model, true)?;
        crate::kinematics::check(model)?;
        assembly.check_stiffness_diagonal()?;
        Ok(assembly)
    }

    /// Assembles a part of a model ([`Model::part`]) without the checks that
    /// only a whole structure passes: a part may float free, and its nodes
    /// may touch nothing. Fails only when no DOF is free or a stiffness or
    /// mass is not finite.
    pub fn of_part(model: &Model) -> Result<Self, ModelError> {
        Self::build(model, false)
    }

    fn build(model: &Model, whole: bool) -> Result<Self, ModelError> {
        let dofs = build_dof_map(model);
        if dofs.is_empty() {
            return Err(ModelError::NoFreeDof);
        }
        let mut touched = vec![false; model.nodes.len()];
        let mut blocks = Vec::new();
        for (source, group, local, terms) in raw_blocks(model) {
            for r in &local {
                touched[model.node_index[&r.node]] = true;
            }
            let free: Vec<(usize, usize)> = local
                .iter()
                .enumerate()
                .filter_map(|(k, r)| match dofs.slot(*r) {
                    Some(Slot::Free(eq)) => Some((k, eq)),
                    _ => None,
                })
                .collect();
            if free.is_empty() {
                continue;
            }
            let n_full = local.len();
            let n = free.len();
            let terms = terms
                .into_iter()
                .map(|(kind, factors, m)| {
                    let mut unit = vec![0.0; n * n];
                    for (r, &(kr, _)) in free.iter().enumerate() {
                        for (c, &(kc, _)) in free.iter().enumerate() {
                            unit[r * n + c] = m.get(n_full, kr, kc);
                        }
                    }
                    let value = factors.iter().map(|&q| model.get(q)).product();
                    Term { kind, factors, value, unit }
                })
                .collect();
            blocks.push(Block {
                source,
                group,
                eqs: free.iter().map(|&(_, eq)| eq).collect(),
                terms,
                positions: Vec::new(),
            });
        }
        if let Some(b) =
            blocks.iter().find(|b| b.terms.iter().any(|t| !t.unit.iter().all(|u| (u * t.value).is_finite())))
        {
            return Err(ModelError::Invalid {
                what: describe_source(model, b.source),
                reason: "has a stiffness or mass that is not finite (values or geometry too large)".into(),
            });
        }
        for (i, node) in model.nodes.iter().enumerate() {
            let has_free =
                model.dimension.dofs().iter().any(|&d| dofs.equation(DofRef { node: node.id, dof: d }).is_some());
            if whole && !touched[i] && has_free {
                return Err(ModelError::DanglingNode { id: node.id.0 });
            }
        }
        let pattern = Pattern::of_blocks(dofs.len(), blocks.iter().map(|b| b.eqs.as_slice()));
        for b in &mut blocks {
            let n = b.eqs.len();
            b.positions = (0..n * n)
                .map(|k| pattern.position(b.eqs[k / n], b.eqs[k % n]).expect("pattern covers every block"))
                .collect();
        }
        let mut group_blocks = vec![Vec::new(); model.groups.len()];
        let mut by_quantity: HashMap<Quantity, Vec<(usize, usize)>> = HashMap::new();
        for (bi, b) in blocks.iter().enumerate() {
            group_blocks[b.group].push(bi);
            for (ti, t) in b.terms.iter().enumerate() {
                for &q in &t.factors {
                    by_quantity.entry(q).or_default().push((bi, ti));
                }
            }
        }
        Ok(Assembly { dofs, pattern, blocks, group_blocks, by_quantity })
    }

    /// Every free DOF needs some stiffness: a zero diagonal in K means a DOF
    /// that nothing restrains (a free rotation at a pin, a spring-less joint).
    fn check_stiffness_diagonal(&self) -> Result<(), ModelError> {
        let k = self.real_values(MatrixKind::Stiffness);
        let diag = self.pattern.diagonal_positions();
        let scale = diag.iter().map(|&p| k[p].abs()).fold(0.0, f64::max);
        for (eq, &p) in diag.iter().enumerate() {
            if k[p] <= 1e-14 * scale {
                let dof = self.dofs.dof_of(eq);
                let mut nodes: Vec<u32> = self.dofs.dofs_of(eq).iter().map(|r| r.node.0).collect();
                nodes.sort_unstable();
                nodes.dedup();
                return Err(ModelError::Mechanism { hint: dof.to_string(), modes: 1, nodes });
            }
        }
        Ok(())
    }

    /// Recomputes every term value from the model's current quantities.
    pub fn refresh(&mut self, model: &Model) {
        for b in &mut self.blocks {
            for t in &mut b.terms {
                t.value = t.factors.iter().map(|&q| model.get(q)).product();
            }
        }
    }

    /// Recomputes the values of the terms that quantity `q` multiplies.
    pub fn refresh_quantity(&mut self, model: &Model, q: Quantity) {
        if let Some(list) = self.by_quantity.get(&q) {
            for &(b, t) in list {
                let term = &mut self.blocks[b].terms[t];
                term.value = term.factors.iter().map(|&f| model.get(f)).product();
            }
        }
    }

    /// The `(block, term)` pairs that a factor quantity multiplies (empty for
    /// damping quantities, which act through whole groups).
    pub fn terms_of(&self, q: Quantity) -> &[(usize, usize)] {
        self.by_quantity.get(&q).map_or(&[], Vec::as_slice)
    }

    /// Number of equations.
    #[inline]
    pub fn n(&self) -> usize {
        self.dofs.len()
    }

    /// DOF numbering.
    #[inline]
    pub fn dofs(&self) -> &DofMap {
        &self.dofs
    }

    /// Shared sparsity pattern of K, M and every group matrix.
    #[inline]
    pub fn pattern(&self) -> &Pattern {
        &self.pattern
    }

    /// One block per beam, spring, lumped mass and imported block with a
    /// free DOF, in that order.
    #[inline]
    pub fn blocks(&self) -> &[Block] {
        &self.blocks
    }

    /// The blocks of group `group` (indices into [`Self::blocks`]).
    #[inline]
    pub fn group_blocks(&self, group: usize) -> &[usize] {
        &self.group_blocks[group]
    }

    /// Accumulates `sum over blocks and terms of coef(block, term) * value * unit`
    /// into `out`, a values array on [`Self::pattern`]. `out` is not cleared.
    pub fn accumulate<T>(&self, mut coef: impl FnMut(&Block, &Term) -> Option<T>, out: &mut [T])
    where
        T: Copy + std::ops::AddAssign + std::ops::Mul<f64, Output = T>,
    {
        for b in &self.blocks {
            for t in &b.terms {
                if t.value == 0.0 {
                    continue;
                }
                if let Some(c) = coef(b, t) {
                    for (k, &p) in b.positions.iter().enumerate() {
                        let u = t.unit[k];
                        if u != 0.0 {
                            out[p] += c * (t.value * u);
                        }
                    }
                }
            }
        }
    }

    /// Values of the whole K, M or (imported) C on the pattern.
    pub fn real_values(&self, kind: MatrixKind) -> Vec<f64> {
        let mut v = vec![0.0; self.pattern.nnz()];
        self.accumulate(|_, t| (t.kind == kind).then_some(1.0), &mut v);
        v
    }

    /// Values of `K_g`, `M_g` or the imported `C_g` of one group.
    pub fn group_values(&self, group: usize, kind: MatrixKind) -> Vec<f64> {
        let mut v = vec![0.0; self.pattern.nnz()];
        self.accumulate(|b, t| (b.group == group && t.kind == kind).then_some(1.0), &mut v);
        v
    }

    /// A values array on the pattern as a dense matrix (for small models).
    pub fn to_dense(&self, values: &[f64]) -> DMatrix<f64> {
        let n = self.n();
        let mut m = DMatrix::zeros(n, n);
        for c in 0..n {
            for p in self.pattern.col_ptr()[c]..self.pattern.col_ptr()[c + 1] {
                m[(self.pattern.row_idx()[p], c)] = values[p];
            }
        }
        m
    }

    /// Dense K (for small models and tests).
    pub fn stiffness_dense(&self) -> DMatrix<f64> {
        self.to_dense(&self.real_values(MatrixKind::Stiffness))
    }

    /// Dense M (for small models and tests).
    pub fn mass_dense(&self) -> DMatrix<f64> {
        self.to_dense(&self.real_values(MatrixKind::Mass))
    }
}

/// `element 3`, `spring `clamp``, `mass `sensor``: a block's model item, for messages.
fn describe_source(model: &Model, source: BlockSource) -> String {
    match source {
        BlockSource::Beam(i) => format!("element {}", model.beams[i].id),
        BlockSource::Spring(i) => format!("spring `{}`", model.springs[i].name),
        BlockSource::Mass(i) => format!("mass `{}`", model.masses[i].name),
        BlockSource::Imported(i) => {
            let b = &model.imported[i];
            format!(
                "the imported matrix of group `{}` at nodes {} and {}",
                model.groups[b.group].name, b.nodes[0], b.nodes[1]
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::samples;
    use approx::assert_relative_eq;

    #[test]
    fn assembled_matrices_are_symmetric_and_pattern_is_symmetric() {
        let model = samples::frame_with_joint();
        let a = Assembly::new(&model).unwrap();
        let k = a.stiffness_dense();
        let m = a.mass_dense();
        assert_relative_eq!(k, k.transpose(), epsilon = 1e-6);
        assert_relative_eq!(m, m.transpose(), epsilon = 1e-12);
        for c in 0..a.n() {
            for &r in a.pattern.rows(c) {
                assert!(a.pattern.position(c, r).is_some());
            }
        }
    }

    #[test]
    fn group_matrices_sum_to_the_whole() {
        let model = samples::frame_with_joint();
        let a = Assembly::new(&model).unwrap();
        let total = a.real_values(MatrixKind::Stiffness);
        let mut sum = vec![0.0; total.len()];
        for g in 0..model.groups().len() {
            for (s, v) in sum.iter_mut().zip(a.group_values(g, MatrixKind::Stiffness)) {
                *s += v;
            }
        }
        for (s, t) in sum.iter().zip(&total) {
            assert_relative_eq!(*s, *t, max_relative = 1e-12);
        }
    }

    #[test]
    fn a_pinned_rotation_with_nothing_restraining_it_is_a_mechanism() {
        let mut m = Model::new("loose");
        let g = m.add_group(crate::model::Group::new("g")).unwrap();
        m.add_node(1, 0.0, 0.0).unwrap();
        m.add_node(2, 1.0, 0.0).unwrap();
        m.add_node(3, 1.0, 0.0).unwrap();
        let mat = m.add_material("s", 2e11, 7800.0).unwrap();
        let sec = m.add_section(crate::model::Section::rectangle("r", 0.05, 0.01)).unwrap();
        m.add_beam(1, [1, 2], mat, sec, g).unwrap();
        m.add_spring("j", 2, Some(3), [1e6, 1e6, 0.0], g).unwrap();
        m.add_mass("tip", 3, 1.0, 0.0, g).unwrap();
        m.add_support(1, &Dof::PLANAR).unwrap();
        let e = Assembly::new(&m).unwrap_err();
        assert_eq!(e, ModelError::Mechanism { hint: "3:rz".into(), modes: 1, nodes: vec![3] });
    }

    #[test]
    fn ties_share_equations_and_supports_remove_them() {
        let model = samples::frame_with_joint();
        let a = Assembly::new(&model).unwrap();
        // 4 nodes x 3 dofs, node 1 clamped, nodes 2 and 3 tied in ux, uy
        assert_eq!(a.n(), 12 - 3 - 2);
        let e2 = a.dofs.equation(DofRef::new(2, Dof::Ux)).unwrap();
        let e3 = a.dofs.equation(DofRef::new(3, Dof::Ux)).unwrap();
        assert_eq!(e2, e3);
        assert_ne!(a.dofs.equation(DofRef::new(2, Dof::Rz)), a.dofs.equation(DofRef::new(3, Dof::Rz)));
        assert_eq!(a.dofs.slot(DofRef::new(1, Dof::Rz)), Some(Slot::Fixed));
    }
}
