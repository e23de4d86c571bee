//! The user's own finite element model: per-group stiffness and mass
//! matrices exported from another code (as Matrix Market files with a DOF
//! table), optionally a viscous damping matrix per group, taken into a
//! [`Model`] beside or instead of its beams.
//!
//! An imported matrix is kept as blocks, one per pair of nodes it couples
//! (and one per node for the entries among its own DOFs), so that it
//! assembles, differentiates and cuts into parts ([`Model::part`]) as
//! beams do: a block of group `g` is a unit matrix times `group.g.stiffness`
//! (or `.mass`), and the group's damping acts on it as on any element
//! (`C_g = alpha K_g + beta M_g` through the group's kernel). A damping
//! block is a unit matrix times `group.g.damping` and adds `j w C` to `Z`,
//! viscous whatever the group's kernel. Without
//! element geometry the model knows no zero-energy motions of its own, so
//! the kinematic check of a mechanism passes over a model with imported
//! matrices; a DOF without stiffness is still refused, and a singular `Z`
//! at a line is reported by the solver.
//!
//! `matrix_market.rs` reads (and writes) the matrices, `tables.rs` the DOF
//! table and the node coordinates; `crate::case` reads the `[imported]`
//! table of a case. See `docs/imported-models.md`.

use std::collections::{BTreeMap, HashMap};

use crate::dof::{DofRef, NodeId};
use crate::error::ModelError;
use crate::model::Model;

pub mod export;
pub mod matrix_market;
pub mod tables;

// The blocks are items of the model (`model/items.rs`, so that the model
// holds them without importing this module); named here too, where they
// are made.
pub use crate::model::{ImportedBlock, ImportedKind};
pub use matrix_market::SymmetricCoo;

/// An entry of a matrix: row, column, value.
type Entry = (usize, usize, f64);

impl Model {
    /// The blocks of the imported matrices.
    pub fn imported(&self) -> &[ImportedBlock] {
        &self.imported
    }

    /// Adds the matrix `m` of `kind` to group `group`: row `i` of `m` is
    /// the DOF `table[i]`, whose node must exist and whose direction the
    /// model's dimension must have. The matrix is cut into blocks by node
    /// pair (see [`ImportedBlock`]).
    pub fn add_imported(
        &mut self,
        group: usize,
        kind: ImportedKind,
        table: &[DofRef],
        m: &SymmetricCoo,
    ) -> Result<(), ModelError> {
        let what = || format!("the imported {} of group #{group}", kind.key());
        if group >= self.groups.len() {
            return Err(ModelError::UnknownGroup { name: format!("#{group}"), context: what() });
        }
        if m.n != table.len() {
            return Err(ModelError::Invalid {
                what: what(),
                reason: format!("is {} x {}, and its DOF table has {} rows", m.n, m.n, table.len()),
            });
        }
        for r in table {
            if self.node(r.node).is_none() {
                return Err(ModelError::UnknownNode { id: r.node.0, context: what() });
            }
            self.dimension.check(r.dof).map_err(|reason| ModelError::Invalid { what: what(), reason })?;
        }
        // each node's rows, in table order
        let mut rows_of: HashMap<NodeId, Vec<usize>> = HashMap::new();
        for (i, r) in table.iter().enumerate() {
            rows_of.entry(r.node).or_default().push(i);
        }
        let mut pairs: BTreeMap<(NodeId, NodeId), Vec<Entry>> = BTreeMap::new();
        for &(r, c, v) in &m.entries {
            if v == 0.0 {
                continue;
            }
            let (a, b) = (table[r].node, table[c].node);
            pairs.entry((a.min(b), a.max(b))).or_default().push((r, c, v));
        }
        for ((a, b), entries) in pairs {
            // the rows with an entry in this block, first node's first, in
            // table order: a block holds no DOF it does not couple, so the
            // sparsity pattern is no fuller than the matrix
            let used: std::collections::HashSet<usize> = entries.iter().flat_map(|&(r, c, _)| [r, c]).collect();
            let mut rows: Vec<usize> = rows_of[&a].iter().copied().filter(|r| used.contains(r)).collect();
            if b != a {
                rows.extend(rows_of[&b].iter().copied().filter(|r| used.contains(r)));
            }
            let local: HashMap<usize, usize> = rows.iter().enumerate().map(|(k, &r)| (r, k)).collect();
            let n = rows.len();
            let mut values = vec![0.0; n * n];
            for (r, c, v) in entries {
                let (i, j) = (local[&r], local[&c]);
                values[i * n + j] = v;
                values[j * n + i] = v;
            }
            self.imported.push(ImportedBlock {
                group,
                kind,
                nodes: [a, b],
                dofs: rows.iter().map(|&r| table[r]).collect(),
                values,
            });
        }
        Ok(())
    }

    /// The mass of the imported mass matrices: `r^T M r` for the rigid
    /// translation `r` along the first translation they have (1 on every
    /// DOF along it), which is the total mass of any consistent mass matrix.
    pub(crate) fn imported_mass(&self) -> f64 {
        let Some(d) =
            self.dimension.translations().iter().copied().find(|&d| {
                self.imported.iter().any(|b| b.kind == ImportedKind::Mass && b.dofs.iter().any(|r| r.dof == d))
            })
        else {
            return 0.0;
        };
        self.imported
            .iter()
            .filter(|b| b.kind == ImportedKind::Mass)
            .map(|b| {
                let n = b.dofs.len();
                let along: Vec<usize> = (0..n).filter(|&k| b.dofs[k].dof == d).collect();
                let g = self.groups[b.group].mass;
                along
                    .iter()
                    .flat_map(|&i| along.iter().map(move |&j| (i, j)))
                    .map(|(i, j)| b.values[i * n + j])
                    .sum::<f64>()
                    * g
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dof::{Dimension, Dof};
    use crate::model::Group;

    #[test]
    fn a_matrix_is_cut_by_node_pairs_and_keeps_every_entry() {
        let mut m = Model::with_dimension("imported", Dimension::Spatial);
        let g = m.add_group(Group::new("g")).unwrap();
        for id in [1, 2, 3] {
            m.add_node_at(id, [f64::from(id), 0.0, 0.0]).unwrap();
        }
        let table =
            [DofRef::new(2, Dof::Ux), DofRef::new(1, Dof::Ux), DofRef::new(2, Dof::Rz), DofRef::new(3, Dof::Uy)];
        let k = SymmetricCoo {
            n: 4,
            entries: vec![(0, 0, 5.0), (1, 0, -1.0), (2, 0, 0.5), (1, 1, 4.0), (2, 2, 3.0), (3, 2, -2.0), (3, 3, 6.0)],
        };
        m.add_imported(g, ImportedKind::Stiffness, &table, &k).unwrap();
        // node 2's own block, 1-2 and 2-3 (no entries between 1 and 3, and node 1's and 3's own entries sit in their pair blocks)
        let total: f64 = m.imported().iter().map(|b| b.values.iter().sum::<f64>()).sum();
        let expect: f64 = k.entries.iter().map(|&(r, c, v)| if r == c { v } else { 2.0 * v }).sum();
        assert_eq!(total, expect);
        let e = m.add_imported(g, ImportedKind::Mass, &table[..3], &k).unwrap_err();
        assert!(e.to_string().contains("is 4 x 4, and its DOF table has 3 rows"), "{e}");
        let mut planar = Model::new("p");
        let g = planar.add_group(Group::new("g")).unwrap();
        planar.add_node(1, 0.0, 0.0).unwrap();
        let e = planar
            .add_imported(
                g,
                ImportedKind::Mass,
                &[DofRef::new(1, Dof::Uz)],
                &SymmetricCoo { n: 1, entries: vec![(0, 0, 1.0)] },
            )
            .unwrap_err();
        assert!(e.to_string().contains("`uz` is not a DOF of a planar model"), "{e}");
        let e = planar
            .add_imported(
                g,
                ImportedKind::Mass,
                &[DofRef::new(9, Dof::Ux)],
                &SymmetricCoo { n: 1, entries: vec![(0, 0, 1.0)] },
            )
            .unwrap_err();
        assert_eq!(e, ModelError::UnknownNode { id: 9, context: "the imported mass of group #0".into() });
    }
}
