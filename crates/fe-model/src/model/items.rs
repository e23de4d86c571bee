//! The items a model is made of, as plain data: element ids (node ids,
//! which DOFs name too, are in `dof.rs`), nodes, materials, sections (with
//! the torsion constant of a rectangle), beams, springs, lumped masses,
//! supports, ties, groups and the blocks of imported matrices (made by
//! `crate::imported`). [`super::Model`] checks them as they are added.
use std::fmt;

use crate::dof::{Dof, DofRef, NodeId, PerDof};

/// Identifier of a beam element as written by the user (not an index).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ElementId(pub u32);

impl fmt::Display for ElementId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// A node: in the x-y plane (`z = 0`) in a planar model.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// User id.
    pub id: NodeId,
    /// x coordinate (m).
    pub x: f64,
    /// y coordinate (m).
    pub y: f64,
    /// z coordinate (m); 0 in a planar model.
    pub z: f64,
}

impl Node {
    /// The position `[x, y, z]`.
    pub fn position(&self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
}

/// An isotropic linear elastic material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name used by elements.
    pub name: String,
    /// Young's modulus E (Pa).
    pub e: f64,
    /// Density rho (kg/m^3).
    pub rho: f64,
    /// Poisson's ratio, which gives the shear modulus `G = E / (2 (1 + nu))`
    /// of torsion; needed by beams of a 3D model only.
    pub nu: Option<f64>,
}

impl Material {
    /// `G / E`, the shear modulus per unit Young's modulus (0 when `nu` is not given).
    pub fn shear_ratio(&self) -> f64 {
        self.nu.map_or(0.0, |nu| 0.5 / (1.0 + nu))
    }
}

/// Cross-section properties of a beam.
///
/// A planar model bends its beams in the x-y plane with `inertia`; a 3D
/// model's beams bend in their local x-y plane with `inertia` (`Iz`), in
/// their local x-z plane with `iy`, and twist with the torsion constant
/// `torsion` (`J`).
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    /// Name used by elements.
    pub name: String,
    /// Area A (m^2).
    pub area: f64,
    /// Second moment of area about the local z axis, `I` of a planar model
    /// and `Iz` of a 3D one (m^4).
    pub inertia: f64,
    /// Second moment of area about the local y axis, `Iy` (m^4; 3D models).
    pub iy: f64,
    /// Saint-Venant torsion constant `J` (m^4; 3D models).
    pub torsion: f64,
}

impl Section {
    /// A planar section of area `area` and second moment `inertia`; its `Iy`
    /// and `J` are unknown (zero), which a 3D model refuses.
    pub fn planar(name: &str, area: f64, inertia: f64) -> Self {
        Section { name: name.into(), area, inertia, iy: 0.0, torsion: 0.0 }
    }

    /// A section of a 3D beam: area, second moments about the local y and z
    /// axes, torsion constant.
    pub fn spatial(name: &str, area: f64, iy: f64, iz: f64, torsion: f64) -> Self {
        Section { name: name.into(), area, inertia: iz, iy, torsion }
    }

    /// Solid rectangle of width `b` (along the local z axis) and depth `h`
    /// in the bending plane (along the local y axis).
    pub fn rectangle(name: &str, b: f64, h: f64) -> Self {
        Section {
            name: name.into(),
            area: b * h,
            inertia: b * h.powi(3) / 12.0,
            iy: h * b.powi(3) / 12.0,
            torsion: rectangle_torsion(b, h),
        }
    }

    /// Circular tube of outer diameter `od` and inner diameter `id`.
    pub fn tube(name: &str, od: f64, id: f64) -> Self {
        let pi = std::f64::consts::PI;
        let inertia = pi / 64.0 * (od.powi(4) - id.powi(4));
        Section {
            name: name.into(),
            area: pi / 4.0 * (od * od - id * id),
            inertia,
            iy: inertia,
            torsion: 2.0 * inertia,
        }
    }

    /// The polar moment `Iy + Iz`, the rotary inertia per unit density and
    /// length of the section about the beam's axis.
    pub fn polar(&self) -> f64 {
        self.iy + self.inertia
    }
}

/// Saint-Venant torsion constant of a solid `b` x `h` rectangle, from the
/// series solution of the Prandtl stress function (Timoshenko and Goodier,
/// Theory of Elasticity, sect. 109): with `a >= c` the longer and shorter
/// sides, `J = a c^3 / 3 (1 - 192 c / (pi^5 a) sum_{n odd} tanh(n pi a / 2c) / n^5)`.
pub fn rectangle_torsion(b: f64, h: f64) -> f64 {
    let (a, c) = if b >= h { (b, h) } else { (h, b) };
    let pi = std::f64::consts::PI;
    // the terms fall as n^-5: 200 of them leave less than 1e-13 of the sum
    let sum: f64 = (0..200).map(|k| f64::from(2 * k + 1)).map(|n| (n * pi * a / (2.0 * c)).tanh() / n.powi(5)).sum();
    a * c.powi(3) / 3.0 * (1.0 - 192.0 * c / (pi.powi(5) * a) * sum)
}

/// A two-node Euler-Bernoulli frame element (axial + bending, consistent mass).
#[derive(Clone, Debug, PartialEq)]
pub struct Beam {
    /// User id.
    pub id: ElementId,
    /// End nodes.
    pub nodes: [NodeId; 2],
    /// Index into [`Model::materials`](crate::Model::materials).
    pub material: usize,
    /// Index into [`Model::sections`](crate::Model::sections).
    pub section: usize,
    /// Index into [`Model::groups`](crate::Model::groups).
    pub group: usize,
    /// Non-structural transverse mass per unit length (kg/m), lumped at the
    /// ends, for example the added mass of surrounding water.
    pub added_mass: f64,
    /// Stiffness factor of this element (1 = nominal).
    pub stiffness_factor: f64,
    /// Factor on this element's bending stiffness alone (1 = nominal): a
    /// smaller second moment of area (a notch, a crack, a thinner wall),
    /// where the axial and torsional stiffness keep their values.
    pub bending_factor: f64,
    /// Mass factor of this element (1 = nominal).
    pub mass_factor: f64,
    /// 3D models: the approximate direction of the section's local z axis
    /// (`None`: global z, or global y for a beam along z); see
    /// [`crate::element::frame3d::axes`].
    pub reference: Option<[f64; 3]>,
    /// 3D models: the turn of the section about the beam's axis (radians).
    pub angle: f64,
}

/// Linear springs between two nodes, or from a node to ground, along and
/// about the global axes, one per DOF of the model's nodes. Joints and
/// flexible supports are modelled with coincident nodes joined by a spring.
#[derive(Clone, Debug, PartialEq)]
pub struct Spring {
    /// Unique name (used in parameter names such as `spring.clamp.kr`).
    pub name: String,
    /// First node.
    pub a: NodeId,
    /// Second node, or `None` for a spring to ground.
    pub b: Option<NodeId>,
    /// Stiffnesses per DOF (N/m along, N m/rad about the global axes, or
    /// the spring's own axes when it has them); zero in the DOFs the spring
    /// does not join.
    pub k: PerDof,
    /// Index into [`Model::groups`](crate::Model::groups).
    pub group: usize,
    /// The spring's own axes (rows: local x, y, z in global components) in
    /// a 3D model, set by [`Model::orient_spring`](crate::Model::orient_spring); `None`: the global axes.
    pub axes: Option<[[f64; 3]; 3]>,
}

/// A lumped mass with rotary inertia at a node.
#[derive(Clone, Debug, PartialEq)]
pub struct LumpedMass {
    /// Unique name (used in parameter names such as `mass.sensor.m`).
    pub name: String,
    /// Node carrying the mass.
    pub node: NodeId,
    /// Mass (kg), acting on every translation.
    pub m: f64,
    /// Rotary inertias about the global x, y and z axes (kg m^2), acting on
    /// `rx`, `ry`, `rz`; a planar model has only the last.
    pub j: [f64; 3],
    /// Index into [`Model::groups`](crate::Model::groups).
    pub group: usize,
}

/// DOFs of a node held fixed.
#[derive(Clone, Debug, PartialEq)]
pub struct Support {
    /// The node.
    pub node: NodeId,
    /// Its fixed DOFs.
    pub dofs: Vec<Dof>,
}

/// A rigid coupling of some DOFs of two (usually coincident) nodes: the
/// second node's DOFs share the equations of the first's.
#[derive(Clone, Debug, PartialEq)]
pub struct Tie {
    /// The two nodes; the first owns the shared equations.
    pub nodes: [NodeId; 2],
    /// The coupled DOFs.
    pub dofs: Vec<Dof>,
}

/// A named group of elements, springs and masses sharing damping parameters.
///
/// Damping of group g: `C_g = alpha K_g + beta M_g` (alpha multiplies K, as in
/// the paper), acting through the kernel `mu / (mu + j w)`; `mu = None` is
/// viscous. `stiffness` and `mass` are factors on `K_g` and `M_g` (1 nominal).
#[derive(Clone, Debug, PartialEq)]
pub struct Group {
    /// Name.
    pub name: String,
    /// Stiffness-proportional damping coefficient alpha (s).
    pub alpha: f64,
    /// Mass-proportional damping coefficient beta (1/s).
    pub beta: f64,
    /// Relaxation parameter mu (rad/s); `None` means viscous (mu = infinity).
    pub mu: Option<f64>,
    /// Stiffness factor of the whole group.
    pub stiffness: f64,
    /// Mass factor of the whole group.
    pub mass: f64,
    /// Factor on the group's imported viscous damping matrices (nominal 1;
    /// nothing to scale in a group without one).
    pub damping: f64,
}

impl Group {
    /// An undamped group with unit factors.
    pub fn new(name: &str) -> Self {
        Group { name: name.into(), alpha: 0.0, beta: 0.0, mu: None, stiffness: 1.0, mass: 1.0, damping: 1.0 }
    }

    /// Builder: Rayleigh coefficients.
    pub fn rayleigh(mut self, alpha: f64, beta: f64) -> Self {
        self.alpha = alpha;
        self.beta = beta;
        self
    }

    /// Builder: relaxation parameter (`f64::INFINITY` for viscous).
    pub fn relaxation(mut self, mu: f64) -> Self {
        self.mu = if mu.is_infinite() { None } else { Some(mu) };
        self
    }
}

/// The rotary inertia of a lumped mass: about z only (`f64`, a planar
/// model's `j`), or about x, y and z (`[f64; 3]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotaryInertia(pub [f64; 3]);

impl From<f64> for RotaryInertia {
    fn from(j: f64) -> Self {
        RotaryInertia([0.0, 0.0, j])
    }
}

impl From<[f64; 3]> for RotaryInertia {
    fn from(j: [f64; 3]) -> Self {
        RotaryInertia(j)
    }
}

/// Which matrix an imported block belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ImportedKind {
    /// A stiffness matrix, scaled by the group's stiffness factor.
    Stiffness,
    /// A mass matrix, scaled by the group's mass factor.
    Mass,
    /// A viscous damping matrix, scaled by the group's damping factor: it
    /// enters `Z(w)` as `j w C`, beside the group's own damping
    /// (`alpha K_g + beta M_g` through its kernel).
    Damping,
}

impl ImportedKind {
    /// `stiffness`, `mass` or `damping`: the key of its file in a case.
    pub fn key(self) -> &'static str {
        match self {
            ImportedKind::Stiffness => "stiffness",
            ImportedKind::Mass => "mass",
            ImportedKind::Damping => "damping",
        }
    }
}

/// The entries of an imported group matrix between the DOFs of one node,
/// or between the DOFs of two nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportedBlock {
    /// Index into [`Model::groups`](crate::Model::groups)(super::Model::groups).
    pub group: usize,
    /// Stiffness, mass or damping.
    pub kind: ImportedKind,
    /// The node, twice, or the two nodes (smaller id first).
    pub nodes: [NodeId; 2],
    /// Its DOFs: those of the first node, then of the second, that have an
    /// entry in the block, in table order.
    pub dofs: Vec<DofRef>,
    /// The values, row-major `dofs.len()` squared, symmetric; the entries
    /// among one node's own DOFs are zero in a block of two nodes.
    pub values: Vec<f64>,
}
