//! Degrees of freedom: the three per node, references to them, and the map
//! from (node, dof) to equation index.

use std::collections::HashMap;
use std::fmt;
use std::str::FromStr;

use crate::model::NodeId;

/// One of the three planar degrees of freedom of a node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Dof {
    /// Translation along global x.
    Ux,
    /// Translation along global y.
    Uy,
    /// Rotation about global z (counter-clockwise positive).
    Rz,
}

impl Dof {
    /// All three DOFs in the order they are numbered within a node.
    pub const ALL: [Dof; 3] = [Dof::Ux, Dof::Uy, Dof::Rz];

    /// Position of this DOF within a node's block of three.
    pub fn index(self) -> usize {
        match self {
            Dof::Ux => 0,
            Dof::Uy => 1,
            Dof::Rz => 2,
        }
    }

    /// The DOF at position `i` (0, 1, 2) within a node.
    pub fn from_index(i: usize) -> Option<Dof> {
        Dof::ALL.get(i).copied()
    }

    /// Lower-case name used in case files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            Dof::Ux => "ux",
            Dof::Uy => "uy",
            Dof::Rz => "rz",
        }
    }

    /// True for the two translations.
    pub fn is_translation(self) -> bool {
        !matches!(self, Dof::Rz)
    }
}

impl fmt::Display for Dof {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Dof {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "ux" | "x" => Ok(Dof::Ux),
            "uy" | "y" => Ok(Dof::Uy),
            "rz" | "r" | "theta" => Ok(Dof::Rz),
            other => Err(format!("unknown dof `{other}` (expected ux, uy or rz)")),
        }
    }
}

/// A degree of freedom of a given node, written `node:dof` (for example `31:uy`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct DofRef {
    /// The node.
    pub node: NodeId,
    /// Which of its DOFs.
    pub dof: Dof,
}

impl DofRef {
    /// Shorthand constructor.
    pub fn new(node: u32, dof: Dof) -> Self {
        DofRef { node: NodeId(node), dof }
    }
}

impl fmt::Display for DofRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.node.0, self.dof)
    }
}

impl FromStr for DofRef {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let (node, dof) =
            s.split_once(':').ok_or_else(|| format!("`{s}` is not of the form node:dof, for example 31:uy"))?;
        let node: u32 = node.trim().parse().map_err(|_| format!("`{node}` in `{s}` is not a node id"))?;
        Ok(DofRef { node: NodeId(node), dof: dof.parse()? })
    }
}

/// Where a model DOF ends up in the global system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    /// Free: equation index in the assembled matrices.
    Free(usize),
    /// Held fixed by a support: no equation.
    Fixed,
}

/// Map between (node, dof) and equation indices of the assembled system.
///
/// Supported DOFs have no equation. Tied DOFs (rigid couplings between
/// coincident nodes) share the equation of the first node of the tie.
#[derive(Clone, Debug, Default)]
pub struct DofMap {
    slots: HashMap<DofRef, Slot>,
    /// For each equation, the DOFs that map to it (the first is the owner).
    owners: Vec<Vec<DofRef>>,
}

impl DofMap {
    pub(crate) fn insert_free(&mut self, r: DofRef) -> usize {
        let eq = self.owners.len();
        self.owners.push(vec![r]);
        self.slots.insert(r, Slot::Free(eq));
        eq
    }

    pub(crate) fn insert_alias(&mut self, r: DofRef, eq: usize) {
        self.owners[eq].push(r);
        self.slots.insert(r, Slot::Free(eq));
    }

    pub(crate) fn insert_fixed(&mut self, r: DofRef) {
        self.slots.insert(r, Slot::Fixed);
    }

    /// Number of equations (free DOFs).
    pub fn len(&self) -> usize {
        self.owners.len()
    }

    /// True when the model has no free DOF.
    pub fn is_empty(&self) -> bool {
        self.owners.is_empty()
    }

    /// Slot of a DOF, or `None` if the node does not exist.
    pub fn slot(&self, r: DofRef) -> Option<Slot> {
        self.slots.get(&r).copied()
    }

    /// Equation index of a free DOF (`None` if fixed or unknown).
    pub fn equation(&self, r: DofRef) -> Option<usize> {
        match self.slots.get(&r) {
            Some(Slot::Free(eq)) => Some(*eq),
            _ => None,
        }
    }

    /// The DOF that owns equation `eq` (the first of a tie).
    pub fn dof_of(&self, eq: usize) -> DofRef {
        self.owners[eq][0]
    }

    /// All DOFs sharing equation `eq`.
    pub fn dofs_of(&self, eq: usize) -> &[DofRef] {
        &self.owners[eq]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dof_ref_round_trips_through_text() {
        let r: DofRef = "31:uy".parse().unwrap();
        assert_eq!(r, DofRef::new(31, Dof::Uy));
        assert_eq!(r.to_string(), "31:uy");
        assert!("31".parse::<DofRef>().unwrap_err().contains("`31` is not of the form node:dof"));
        assert!("a:uy".parse::<DofRef>().unwrap_err().contains("`a` in `a:uy` is not a node id"));
        assert!("3:uz".parse::<DofRef>().unwrap_err().contains("uz"));
    }
}
