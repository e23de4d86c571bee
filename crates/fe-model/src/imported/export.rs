//! A model's group matrices as another finite element code exports them:
//! over the free equations (supports removed, tied DOFs shared), one DOF
//! per row, for round trips through [`super::matrix_market`] (the tests'
//! and examples' way to make an imported model equal to a native one).

use std::fmt::Write as _;

use super::SymmetricCoo;
use crate::assembly::{Assembly, MatrixKind};
use crate::dof::DofRef;
use crate::model::{Group, Model};

/// The group matrices of a model over its free equations.
#[derive(Clone, Debug)]
pub struct Exported {
    /// The DOF of each row: the owner of each equation.
    pub dofs: Vec<DofRef>,
    /// Per group with any stiffness, mass or imported damping.
    pub groups: Vec<ExportedGroup>,
}

/// One group's matrices: lower triangles, the group factors applied.
#[derive(Clone, Debug)]
pub struct ExportedGroup {
    /// The group's name.
    pub name: String,
    /// `K_g`.
    pub stiffness: SymmetricCoo,
    /// `M_g`.
    pub mass: SymmetricCoo,
    /// The group's imported viscous damping matrix (empty without one; the
    /// group's own `alpha K_g + beta M_g` is not in it).
    pub damping: SymmetricCoo,
}

/// Exports the group matrices of `model`, assembled as `assembly`.
pub fn export(model: &Model, assembly: &Assembly) -> Exported {
    let lower = |values: Vec<f64>| SymmetricCoo::lower_of(assembly.pattern(), &values);
    let groups = (0..model.groups().len())
        .map(|g| ExportedGroup {
            name: model.groups()[g].name.clone(),
            stiffness: lower(assembly.group_values(g, MatrixKind::Stiffness)),
            mass: lower(assembly.group_values(g, MatrixKind::Mass)),
            damping: lower(assembly.group_values(g, MatrixKind::Damping)),
        })
        .filter(|e| !(e.stiffness.entries.is_empty() && e.mass.entries.is_empty() && e.damping.entries.is_empty()))
        .collect();
    Exported { dofs: (0..assembly.n()).map(|eq| assembly.dofs().dof_of(eq)).collect(), groups }
}

impl Exported {
    /// The DOF table's text (`node dof` per row).
    pub fn dof_table(&self) -> String {
        let mut s = String::from("# node dof: the DOF of each row and column of the matrices\n");
        for r in &self.dofs {
            let _ = writeln!(s, "{} {}", r.node, r.dof);
        }
        s
    }
}

/// The node file's text (`id x y z` per node).
pub fn node_file(model: &Model) -> String {
    let mut s = String::from("# id x y z (m)\n");
    for n in model.nodes() {
        let _ = writeln!(s, "{} {:e} {:e} {:e}", n.id, n.x, n.y, n.z);
    }
    s
}

/// `model` as an imported model: the same nodes and groups, its group
/// matrices over its free equations as imported blocks, and every DOF
/// without an equation held (as the case reader holds what no table
/// lists). The round trip without files, for tests.
pub fn as_imported(model: &Model) -> Result<Model, crate::error::ModelError> {
    let assembly = Assembly::new(model)?;
    let exported = export(model, &assembly);
    let mut m = Model::with_dimension(&model.title, model.dimension());
    for g in model.groups() {
        // the factors are in the exported matrices: the copy's are 1
        m.add_group(Group { stiffness: 1.0, mass: 1.0, damping: 1.0, ..g.clone() })?;
    }
    for n in model.nodes() {
        m.add_node_at(n.id.0, n.position())?;
    }
    for e in &exported.groups {
        let g = m.group_index(&e.name).expect("added above");
        m.add_imported(g, super::ImportedKind::Stiffness, &exported.dofs, &e.stiffness)?;
        m.add_imported(g, super::ImportedKind::Mass, &exported.dofs, &e.mass)?;
        if !e.damping.entries.is_empty() {
            m.add_imported(g, super::ImportedKind::Damping, &exported.dofs, &e.damping)?;
        }
    }
    for n in model.nodes() {
        let held: Vec<_> = m
            .node_dofs()
            .iter()
            .copied()
            .filter(|&d| !exported.dofs.contains(&DofRef { node: n.id, dof: d }))
            .collect();
        if !held.is_empty() {
            m.add_support(n.id.0, &held)?;
        }
    }
    Ok(m)
}
