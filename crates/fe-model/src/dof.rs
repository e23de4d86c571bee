//! Degrees of freedom: the three of a planar node or the six of a node in
//! space ([`Dimension`]), references to them, values per DOF ([`PerDof`]),
//! and the map from (node, dof) to equation index. Node ids ([`NodeId`])
//! are here, below the model, because a DOF names its node as the model's
//! items do; `model` re-exports them.

use std::collections::HashMap;
use std::fmt;
use std::str::FromStr;

/// Identifier of a node as written by the user (not an index).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(pub u32);

impl fmt::Display for NodeId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// A degree of freedom of a node: three translations and three rotations.
/// A planar model's nodes have `ux`, `uy` and `rz` ([`Dimension::Planar`]),
/// a 3D model's all six ([`Dimension::Spatial`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Dof {
    /// Translation along global x.
    Ux,
    /// Translation along global y.
    Uy,
    /// Translation along global z (3D models).
    Uz,
    /// Rotation about global x (3D models; right-hand rule).
    Rx,
    /// Rotation about global y (3D models; right-hand rule).
    Ry,
    /// Rotation about global z (counter-clockwise positive in the x-y plane).
    Rz,
}

impl Dof {
    /// The DOFs of a planar node, in the order they are numbered.
    pub const PLANAR: [Dof; 3] = [Dof::Ux, Dof::Uy, Dof::Rz];

    /// The DOFs of a 3D node, in the order they are numbered.
    pub const SPATIAL: [Dof; 6] = [Dof::Ux, Dof::Uy, Dof::Uz, Dof::Rx, Dof::Ry, Dof::Rz];

    /// Position among the six DOFs of a 3D node (`ux` 0 .. `rz` 5): the
    /// index of a [`PerDof`], whatever the model's dimension.
    pub fn position(self) -> usize {
        match self {
            Dof::Ux => 0,
            Dof::Uy => 1,
            Dof::Uz => 2,
            Dof::Rx => 3,
            Dof::Ry => 4,
            Dof::Rz => 5,
        }
    }

    /// The global axis (0 x, 1 y, 2 z) this DOF translates along or rotates about.
    pub fn axis(self) -> usize {
        self.position() % 3
    }

    /// Lower-case name used in case files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            Dof::Ux => "ux",
            Dof::Uy => "uy",
            Dof::Uz => "uz",
            Dof::Rx => "rx",
            Dof::Ry => "ry",
            Dof::Rz => "rz",
        }
    }

    /// True for the three translations.
    pub fn is_translation(self) -> bool {
        self.position() < 3
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
            "uz" | "z" => Ok(Dof::Uz),
            "rx" => Ok(Dof::Rx),
            "ry" => Ok(Dof::Ry),
            "rz" | "r" | "theta" => Ok(Dof::Rz),
            other => Err(format!("unknown dof `{other}` (expected ux, uy, uz, rx, ry or rz)")),
        }
    }
}

/// Whether a model is a planar frame in the x-y plane or a frame in space.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Dimension {
    /// Nodes in the x-y plane with `ux`, `uy`, `rz` (`[model] dimension = 2`, the default).
    #[default]
    Planar,
    /// Nodes in space with all six DOFs (`[model] dimension = 3`).
    Spatial,
}

impl Dimension {
    /// The DOFs of a node, in the order they are numbered.
    pub fn dofs(self) -> &'static [Dof] {
        match self {
            Dimension::Planar => &Dof::PLANAR,
            Dimension::Spatial => &Dof::SPATIAL,
        }
    }

    /// The translations of a node.
    pub fn translations(self) -> &'static [Dof] {
        match self {
            Dimension::Planar => &[Dof::Ux, Dof::Uy],
            Dimension::Spatial => &[Dof::Ux, Dof::Uy, Dof::Uz],
        }
    }

    /// The rotations of a node.
    pub fn rotations(self) -> &'static [Dof] {
        match self {
            Dimension::Planar => &[Dof::Rz],
            Dimension::Spatial => &[Dof::Rx, Dof::Ry, Dof::Rz],
        }
    }

    /// DOFs per node (3 or 6).
    pub fn dofs_per_node(self) -> usize {
        self.dofs().len()
    }

    /// Position of `d` within a node's block of DOFs, `None` when the
    /// dimension has no such DOF.
    pub fn local(self, d: Dof) -> Option<usize> {
        self.dofs().iter().position(|&x| x == d)
    }

    /// 2 or 3, as case files write it.
    pub fn number(self) -> u8 {
        match self {
            Dimension::Planar => 2,
            Dimension::Spatial => 3,
        }
    }

    /// The dimension a case file's number names.
    pub fn from_number(n: i64) -> Option<Self> {
        match n {
            2 => Some(Dimension::Planar),
            3 => Some(Dimension::Spatial),
            _ => None,
        }
    }

    /// Refuses a DOF the dimension does not have, saying what to do.
    pub fn check(self, d: Dof) -> Result<(), String> {
        match self.local(d) {
            Some(_) => Ok(()),
            None => Err(format!(
                "`{d}` is not a DOF of a planar model (its nodes have ux, uy and rz); a frame in space needs \
                 `[model] dimension = 3`"
            )),
        }
    }

    /// The key of a spring stiffness along or about `d`, as case files and
    /// parameter names write it: `kx`, `ky`, `kz`, `krx`, `kry`, `krz`, and
    /// `kr` for the rotation of a planar model.
    pub fn spring_key(self, d: Dof) -> &'static str {
        match (self, d) {
            (_, Dof::Ux) => "kx",
            (_, Dof::Uy) => "ky",
            (_, Dof::Uz) => "kz",
            (_, Dof::Rx) => "krx",
            (_, Dof::Ry) => "kry",
            (Dimension::Planar, Dof::Rz) => "kr",
            (Dimension::Spatial, Dof::Rz) => "krz",
        }
    }

    /// The DOF a spring key names (see [`Dimension::spring_key`]).
    pub fn spring_dof(self, key: &str) -> Option<Dof> {
        self.dofs().iter().copied().find(|&d| self.spring_key(d) == key)
    }

    /// The key of a lumped mass's rotary inertia about the axis of `d` (a
    /// rotation): `j` in a planar model, `jx`, `jy`, `jz` in space.
    pub fn inertia_key(self, d: Dof) -> &'static str {
        match (self, d.axis()) {
            (Dimension::Planar, _) => "j",
            (Dimension::Spatial, 0) => "jx",
            (Dimension::Spatial, 1) => "jy",
            (Dimension::Spatial, _) => "jz",
        }
    }

    /// The rotation whose inertia a key names (see [`Dimension::inertia_key`]).
    pub fn inertia_dof(self, key: &str) -> Option<Dof> {
        self.rotations().iter().copied().find(|&d| self.inertia_key(d) == key)
    }
}

/// One value per DOF of a node (a spring's stiffnesses, a motion), indexed
/// by [`Dof`]; a planar model leaves `uz`, `rx` and `ry` at zero.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PerDof(pub [f64; 6]);

impl PerDof {
    /// The DOFs with a non-zero value, among `dofs`.
    pub fn non_zero(&self, dofs: &[Dof]) -> Vec<Dof> {
        dofs.iter().copied().filter(|&d| self[d] != 0.0).collect()
    }
}

/// The planar `(ux, uy, rz)` values.
impl From<[f64; 3]> for PerDof {
    fn from([x, y, r]: [f64; 3]) -> Self {
        PerDof([x, y, 0.0, 0.0, 0.0, r])
    }
}

/// The six `(ux, uy, uz, rx, ry, rz)` values.
impl From<[f64; 6]> for PerDof {
    fn from(v: [f64; 6]) -> Self {
        PerDof(v)
    }
}

impl std::ops::Index<Dof> for PerDof {
    type Output = f64;
    fn index(&self, d: Dof) -> &f64 {
        &self.0[d.position()]
    }
}

impl std::ops::IndexMut<Dof> for PerDof {
    fn index_mut(&mut self, d: Dof) -> &mut f64 {
        &mut self.0[d.position()]
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
        // every DOF name parses; whether the model has it is checked against its dimension
        assert_eq!("3:uz".parse::<DofRef>(), Ok(DofRef::new(3, Dof::Uz)));
        assert!("3:uw".parse::<DofRef>().unwrap_err().contains("expected ux, uy, uz, rx, ry or rz"));
        assert!(Dimension::Planar.check(Dof::Uz).unwrap_err().contains("dimension = 3"));
        assert_eq!(Dimension::Spatial.check(Dof::Rz), Ok(()));
    }

    #[test]
    fn spring_and_inertia_keys_name_their_dofs_in_each_dimension() {
        for dim in [Dimension::Planar, Dimension::Spatial] {
            for &d in dim.dofs() {
                assert_eq!(dim.spring_dof(dim.spring_key(d)), Some(d));
            }
            for &d in dim.rotations() {
                assert_eq!(dim.inertia_dof(dim.inertia_key(d)), Some(d));
            }
        }
        assert_eq!(Dimension::Planar.spring_key(Dof::Rz), "kr");
        assert_eq!(Dimension::Spatial.spring_dof("kr"), None);
        let k = PerDof::from([1.0, 2.0, 3.0]);
        assert_eq!((k[Dof::Ux], k[Dof::Uy], k[Dof::Rz], k[Dof::Uz]), (1.0, 2.0, 3.0, 0.0));
    }
}
