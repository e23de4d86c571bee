//! The model description: nodes, materials, sections, elements, springs,
//! lumped masses, supports, ties and groups.
//!
//! A [`Model`] is plain data with validated construction. It knows nothing of
//! frequencies or damping kernels; the damping values of a group are stored
//! here only so that a case file describes the whole structure in one place.

use std::collections::HashMap;
use std::fmt;

use crate::dof::Dof;
use crate::error::ModelError;

/// Identifier of a node as written by the user (not an index).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(pub u32);

impl fmt::Display for NodeId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// Identifier of a beam element as written by the user (not an index).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ElementId(pub u32);

impl fmt::Display for ElementId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// A node in the x-y plane.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// User id.
    pub id: NodeId,
    /// x coordinate (m).
    pub x: f64,
    /// y coordinate (m).
    pub y: f64,
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
}

/// Cross-section properties of a beam.
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    /// Name used by elements.
    pub name: String,
    /// Area A (m^2).
    pub area: f64,
    /// Second moment of area about the bending axis, I (m^4).
    pub inertia: f64,
}

impl Section {
    /// Solid rectangle of width `b` and depth `h` in the bending plane.
    pub fn rectangle(name: &str, b: f64, h: f64) -> Self {
        Section { name: name.into(), area: b * h, inertia: b * h.powi(3) / 12.0 }
    }

    /// Circular tube of outer diameter `od` and inner diameter `id`.
    pub fn tube(name: &str, od: f64, id: f64) -> Self {
        let pi = std::f64::consts::PI;
        Section {
            name: name.into(),
            area: pi / 4.0 * (od * od - id * id),
            inertia: pi / 64.0 * (od.powi(4) - id.powi(4)),
        }
    }
}

/// A two-node Euler-Bernoulli frame element (axial + bending, consistent mass).
#[derive(Clone, Debug, PartialEq)]
pub struct Beam {
    /// User id.
    pub id: ElementId,
    /// End nodes.
    pub nodes: [NodeId; 2],
    /// Index into [`Model::materials`].
    pub material: usize,
    /// Index into [`Model::sections`].
    pub section: usize,
    /// Index into [`Model::groups`].
    pub group: usize,
    /// Non-structural transverse mass per unit length (kg/m), lumped at the
    /// ends, for example the added mass of surrounding water.
    pub added_mass: f64,
    /// Stiffness factor of this element (1 = nominal).
    pub stiffness_factor: f64,
    /// Mass factor of this element (1 = nominal).
    pub mass_factor: f64,
}

/// Linear springs between two nodes, or from a node to ground, along the
/// global x, y and rotation directions. Joints and flexible supports are
/// modelled with coincident nodes joined by a spring.
#[derive(Clone, Debug, PartialEq)]
pub struct Spring {
    /// Unique name (used in parameter names such as `spring.clamp.kr`).
    pub name: String,
    /// First node.
    pub a: NodeId,
    /// Second node, or `None` for a spring to ground.
    pub b: Option<NodeId>,
    /// Stiffnesses (kx N/m, ky N/m, kr N m/rad), indexed by [`Dof::index`].
    pub k: [f64; 3],
    /// Index into [`Model::groups`].
    pub group: usize,
}

/// A lumped mass with rotary inertia at a node.
#[derive(Clone, Debug, PartialEq)]
pub struct LumpedMass {
    /// Unique name (used in parameter names such as `mass.sensor.m`).
    pub name: String,
    /// Node carrying the mass.
    pub node: NodeId,
    /// Mass (kg), acting on ux and uy.
    pub m: f64,
    /// Rotary inertia (kg m^2), acting on rz.
    pub j: f64,
    /// Index into [`Model::groups`].
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
}

impl Group {
    /// An undamped group with unit factors.
    pub fn new(name: &str) -> Self {
        Group { name: name.into(), alpha: 0.0, beta: 0.0, mu: None, stiffness: 1.0, mass: 1.0 }
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

/// A planar frame model.
///
/// Build it with the `add_*` methods (each checks its references), or load it
/// from a case file with [`crate::case::CaseFile`]. Every element, spring and
/// mass belongs to a group.
#[derive(Clone, Debug, Default)]
pub struct Model {
    /// Title shown in reports.
    pub title: String,
    pub(crate) nodes: Vec<Node>,
    pub(crate) node_index: HashMap<NodeId, usize>,
    pub(crate) materials: Vec<Material>,
    pub(crate) sections: Vec<Section>,
    pub(crate) beams: Vec<Beam>,
    pub(crate) springs: Vec<Spring>,
    pub(crate) masses: Vec<LumpedMass>,
    pub(crate) supports: Vec<Support>,
    pub(crate) ties: Vec<Tie>,
    pub(crate) groups: Vec<Group>,
}

fn positive(what: String, v: f64) -> Result<(), ModelError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(ModelError::Invalid { what, reason: format!("must be positive and finite, got {}", crate::show(v)) })
    }
}

fn non_negative(what: String, v: f64) -> Result<(), ModelError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(ModelError::Invalid {
            what,
            reason: format!("must be zero or positive and finite, got {}", crate::show(v)),
        })
    }
}

impl Model {
    /// An empty model.
    pub fn new(title: &str) -> Self {
        Model { title: title.into(), ..Default::default() }
    }

    /// Nodes in definition order.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }
    /// Materials.
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }
    /// Sections.
    pub fn sections(&self) -> &[Section] {
        &self.sections
    }
    /// Beam elements.
    pub fn beams(&self) -> &[Beam] {
        &self.beams
    }
    /// Springs.
    pub fn springs(&self) -> &[Spring] {
        &self.springs
    }
    /// Lumped masses.
    pub fn masses(&self) -> &[LumpedMass] {
        &self.masses
    }
    /// Supports.
    pub fn supports(&self) -> &[Support] {
        &self.supports
    }
    /// Ties.
    pub fn ties(&self) -> &[Tie] {
        &self.ties
    }
    /// Groups.
    pub fn groups(&self) -> &[Group] {
        &self.groups
    }
    /// Mutable group (damping values and factors are plain data).
    pub fn group_mut(&mut self, index: usize) -> &mut Group {
        &mut self.groups[index]
    }

    /// The node with this id.
    pub fn node(&self, id: NodeId) -> Option<&Node> {
        self.node_index.get(&id).map(|&i| &self.nodes[i])
    }

    /// Index of a group by name.
    pub fn group_index(&self, name: &str) -> Option<usize> {
        self.groups.iter().position(|g| g.name == name)
    }
    /// Index of a material by name.
    pub fn material_index(&self, name: &str) -> Option<usize> {
        self.materials.iter().position(|m| m.name == name)
    }
    /// Index of a section by name.
    pub fn section_index(&self, name: &str) -> Option<usize> {
        self.sections.iter().position(|s| s.name == name)
    }
    /// Index of a beam by id.
    pub fn beam_index(&self, id: ElementId) -> Option<usize> {
        self.beams.iter().position(|b| b.id == id)
    }
    /// Index of a spring by name.
    pub fn spring_index(&self, name: &str) -> Option<usize> {
        self.springs.iter().position(|s| s.name == name)
    }
    /// Index of a lumped mass by name.
    pub fn mass_index(&self, name: &str) -> Option<usize> {
        self.masses.iter().position(|m| m.name == name)
    }

    /// Largest node id in use (0 for an empty model).
    pub fn max_node_id(&self) -> u32 {
        self.nodes.iter().map(|n| n.id.0).max().unwrap_or(0)
    }

    /// Largest element id in use (0 for an empty model).
    pub fn max_element_id(&self) -> u32 {
        self.beams.iter().map(|b| b.id.0).max().unwrap_or(0)
    }

    fn require_node(&self, id: NodeId, context: &str) -> Result<(), ModelError> {
        if self.node_index.contains_key(&id) {
            Ok(())
        } else {
            Err(ModelError::UnknownNode { id: id.0, context: context.into() })
        }
    }

    fn require_group(&self, group: usize, context: &str) -> Result<(), ModelError> {
        if group < self.groups.len() {
            Ok(())
        } else {
            Err(ModelError::UnknownGroup { name: format!("#{group}"), context: context.into() })
        }
    }

    /// Adds a node; ids must be unique and coordinates finite.
    pub fn add_node(&mut self, id: u32, x: f64, y: f64) -> Result<NodeId, ModelError> {
        let id = NodeId(id);
        if self.node_index.contains_key(&id) {
            return Err(ModelError::DuplicateNode { id: id.0 });
        }
        if !(x.is_finite() && y.is_finite()) {
            return Err(ModelError::Invalid {
                what: format!("node {id}"),
                reason: format!("coordinates must be finite, got ({x}, {y})"),
            });
        }
        self.node_index.insert(id, self.nodes.len());
        self.nodes.push(Node { id, x, y });
        Ok(id)
    }

    /// Adds a material (E > 0, rho > 0) and returns its index.
    pub fn add_material(&mut self, name: &str, e: f64, rho: f64) -> Result<usize, ModelError> {
        if self.material_index(name).is_some() {
            return Err(ModelError::Duplicate { what: format!("material `{name}`") });
        }
        positive(format!("material `{name}`: E"), e)?;
        positive(format!("material `{name}`: rho"), rho)?;
        self.materials.push(Material { name: name.into(), e, rho });
        Ok(self.materials.len() - 1)
    }

    /// Adds a section (A > 0, I > 0) and returns its index.
    pub fn add_section(&mut self, section: Section) -> Result<usize, ModelError> {
        if self.section_index(&section.name).is_some() {
            return Err(ModelError::Duplicate { what: format!("section `{}`", section.name) });
        }
        positive(format!("section `{}`: A", section.name), section.area)?;
        positive(format!("section `{}`: I", section.name), section.inertia)?;
        self.sections.push(section);
        Ok(self.sections.len() - 1)
    }

    /// Adds a group and returns its index.
    pub fn add_group(&mut self, group: Group) -> Result<usize, ModelError> {
        if self.group_index(&group.name).is_some() {
            return Err(ModelError::Duplicate { what: format!("group `{}`", group.name) });
        }
        let g = &group.name;
        non_negative(format!("group `{g}`: alpha"), group.alpha)?;
        non_negative(format!("group `{g}`: beta"), group.beta)?;
        if let Some(mu) = group.mu {
            positive(format!("group `{g}`: mu"), mu)?;
        }
        positive(format!("group `{g}`: stiffness"), group.stiffness)?;
        positive(format!("group `{g}`: mass"), group.mass)?;
        self.groups.push(group);
        Ok(self.groups.len() - 1)
    }

    /// Returns the index of the group named `name`, creating an undamped
    /// group of that name if there is none.
    pub fn group_or_default(&mut self, name: &str) -> usize {
        match self.group_index(name) {
            Some(g) => g,
            None => {
                self.groups.push(Group::new(name));
                self.groups.len() - 1
            }
        }
    }

    /// Adds a beam element between two existing nodes.
    pub fn add_beam(
        &mut self,
        id: u32,
        nodes: [u32; 2],
        material: usize,
        section: usize,
        group: usize,
    ) -> Result<usize, ModelError> {
        let id = ElementId(id);
        let ctx = format!("element {id}");
        if self.beams.iter().any(|b| b.id == id) {
            return Err(ModelError::Duplicate { what: ctx });
        }
        let nodes = [NodeId(nodes[0]), NodeId(nodes[1])];
        for n in nodes {
            self.require_node(n, &ctx)?;
        }
        if material >= self.materials.len() {
            return Err(ModelError::UnknownMaterial { name: format!("#{material}"), context: ctx });
        }
        if section >= self.sections.len() {
            return Err(ModelError::UnknownSection { name: format!("#{section}"), context: ctx });
        }
        self.require_group(group, &ctx)?;
        let (a, b) = (self.node(nodes[0]).unwrap(), self.node(nodes[1]).unwrap());
        let length = (b.x - a.x).hypot(b.y - a.y);
        if nodes[0] == nodes[1] || length <= 1e-12 {
            return Err(ModelError::ZeroLength { element: id.0 });
        }
        if !length.is_finite() {
            return Err(ModelError::Invalid {
                what: ctx,
                reason: format!("is too long: its length between nodes {} and {} overflows", nodes[0], nodes[1]),
            });
        }
        self.beams.push(Beam {
            id,
            nodes,
            material,
            section,
            group,
            added_mass: 0.0,
            stiffness_factor: 1.0,
            mass_factor: 1.0,
        });
        Ok(self.beams.len() - 1)
    }

    /// Sets the non-structural transverse mass per length of a beam (kg/m).
    pub fn set_added_mass(&mut self, beam: usize, per_length: f64) -> Result<(), ModelError> {
        non_negative(format!("element {}: added_mass", self.beams[beam].id), per_length)?;
        self.beams[beam].added_mass = per_length;
        Ok(())
    }

    /// Adds springs `k = [kx, ky, kr]` between `a` and `b` (or to ground when
    /// `b` is `None`).
    pub fn add_spring(
        &mut self,
        name: &str,
        a: u32,
        b: Option<u32>,
        k: [f64; 3],
        group: usize,
    ) -> Result<usize, ModelError> {
        let ctx = format!("spring `{name}`");
        if self.spring_index(name).is_some() {
            return Err(ModelError::Duplicate { what: ctx });
        }
        self.require_node(NodeId(a), &ctx)?;
        if let Some(b) = b {
            self.require_node(NodeId(b), &ctx)?;
            if a == b {
                return Err(ModelError::Invalid {
                    what: ctx,
                    reason: "joins a node to itself; use two coincident nodes".into(),
                });
            }
        }
        for (d, v) in Dof::ALL.iter().zip(k) {
            non_negative(format!("{ctx}: k{}", &d.name()[d.name().len() - 1..]), v)?;
        }
        if k.iter().all(|&v| v == 0.0) {
            return Err(ModelError::Invalid { what: ctx, reason: "has no non-zero stiffness".into() });
        }
        self.require_group(group, &ctx)?;
        self.springs.push(Spring { name: name.into(), a: NodeId(a), b: b.map(NodeId), k, group });
        Ok(self.springs.len() - 1)
    }

    /// Adds a lumped mass `m` (kg) with rotary inertia `j` (kg m^2) at a node.
    pub fn add_mass(&mut self, name: &str, node: u32, m: f64, j: f64, group: usize) -> Result<usize, ModelError> {
        let ctx = format!("mass `{name}`");
        if self.mass_index(name).is_some() {
            return Err(ModelError::Duplicate { what: ctx });
        }
        self.require_node(NodeId(node), &ctx)?;
        non_negative(format!("{ctx}: m"), m)?;
        non_negative(format!("{ctx}: j"), j)?;
        if m == 0.0 && j == 0.0 {
            return Err(ModelError::Invalid { what: ctx, reason: "has neither mass nor inertia".into() });
        }
        self.require_group(group, &ctx)?;
        self.masses.push(LumpedMass { name: name.into(), node: NodeId(node), m, j, group });
        Ok(self.masses.len() - 1)
    }

    /// Fixes DOFs of a node.
    pub fn add_support(&mut self, node: u32, dofs: &[Dof]) -> Result<(), ModelError> {
        self.require_node(NodeId(node), "support")?;
        self.supports.push(Support { node: NodeId(node), dofs: dofs.to_vec() });
        Ok(())
    }

    /// Rigidly couples DOFs of two nodes.
    pub fn add_tie(&mut self, a: u32, b: u32, dofs: &[Dof]) -> Result<(), ModelError> {
        self.require_node(NodeId(a), "tie")?;
        self.require_node(NodeId(b), "tie")?;
        if a == b {
            return Err(ModelError::Invalid { what: format!("tie {a}-{b}"), reason: "ties a node to itself".into() });
        }
        // A tie makes two nodes share displacements and rotation, which is
        // only kinematically sound where they coincide (a joint, as in the
        // paper); between distant nodes it silently makes a wrong model.
        let (p, q) = (&self.nodes[self.node_index[&NodeId(a)]], &self.nodes[self.node_index[&NodeId(b)]]);
        let gap = (p.x - q.x).hypot(p.y - q.y);
        let extent = self.nodes.iter().map(|n| n.x.abs().max(n.y.abs())).fold(0.0, f64::max);
        if !(gap <= 1e-9 * extent.max(1e-300)) {
            return Err(ModelError::Invalid {
                what: format!("tie {a}-{b}"),
                reason: format!(
                    "joins nodes {gap:.6e} m apart; a tie couples coincident nodes (a joint), \
                     join distant nodes with a beam or a spring"
                ),
            });
        }
        self.ties.push(Tie { nodes: [NodeId(a), NodeId(b)], dofs: dofs.to_vec() });
        Ok(())
    }

    /// Splits `node` in two: a new coincident node `new_id` takes over the
    /// ends of the listed elements. Used to insert a joint where members meet
    /// (the caller then ties and springs the pair). Returns the new node id.
    pub fn split_node(&mut self, node: u32, elements: &[u32], new_id: u32) -> Result<u32, ModelError> {
        let ctx = format!("joint at node {node}");
        self.require_node(NodeId(node), &ctx)?;
        if elements.is_empty() {
            return Err(ModelError::Invalid { what: ctx, reason: "lists no elements to detach".into() });
        }
        let mut idx = Vec::new();
        for &e in elements {
            let i = self.beam_index(ElementId(e)).ok_or_else(|| ModelError::Invalid {
                what: ctx.clone(),
                reason: format!("element {e} does not exist"),
            })?;
            if !self.beams[i].nodes.contains(&NodeId(node)) {
                return Err(ModelError::Invalid {
                    what: ctx,
                    reason: format!("element {e} does not end at node {node}"),
                });
            }
            idx.push(i);
        }
        let attached = self.beams.iter().filter(|b| b.nodes.contains(&NodeId(node))).count();
        if attached <= idx.len() {
            return Err(ModelError::Invalid {
                what: ctx,
                reason: "would detach every element at the node; leave at least one on each side".into(),
            });
        }
        let (x, y) = {
            let n = self.node(NodeId(node)).expect("checked above");
            (n.x, n.y)
        };
        self.add_node(new_id, x, y)?;
        for i in idx {
            for end in &mut self.beams[i].nodes {
                if *end == NodeId(node) {
                    *end = NodeId(new_id);
                }
            }
        }
        Ok(new_id)
    }

    /// Removes the supports of a node; returns the DOFs that were fixed.
    pub fn remove_support(&mut self, node: u32) -> Vec<Dof> {
        let mut dofs = Vec::new();
        self.supports.retain(|s| {
            if s.node == NodeId(node) {
                dofs.extend(s.dofs.iter().copied());
                false
            } else {
                true
            }
        });
        dofs.sort();
        dofs.dedup();
        dofs
    }

    /// Moves a beam (by index) to another group.
    pub fn set_beam_group(&mut self, beam: usize, group: usize) -> Result<(), ModelError> {
        self.require_group(group, &format!("element {}", self.beams[beam].id))?;
        self.beams[beam].group = group;
        Ok(())
    }

    /// Moves a spring (by index) to another group.
    pub fn set_spring_group(&mut self, spring: usize, group: usize) -> Result<(), ModelError> {
        self.require_group(group, &format!("spring `{}`", self.springs[spring].name))?;
        self.springs[spring].group = group;
        Ok(())
    }

    /// The part of the model on the given nodes, for local computations: the
    /// beams with both ends among them, the springs, masses and supports on
    /// them, and the ties between them. A node tied to one of them is taken
    /// in too (with its supports), so that every DOF of the part is free or
    /// fixed as in the whole model. Materials, sections and groups are kept
    /// whole, at the same indices; beams, springs and masses keep their ids
    /// and names but not their indices. A part usually floats free, so it is
    /// assembled with [`crate::Assembly::of_part`], not [`crate::Assembly::new`].
    pub fn part(&self, nodes: &[NodeId]) -> Model {
        let mut keep = vec![false; self.nodes.len()];
        for id in nodes {
            if let Some(&i) = self.node_index.get(id) {
                keep[i] = true;
            }
        }
        // closure over ties: a tie chain can reach further than one step
        loop {
            let mut grew = false;
            for t in &self.ties {
                let [a, b] = t.nodes.map(|n| self.node_index[&n]);
                if keep[a] != keep[b] {
                    keep[a] = true;
                    keep[b] = true;
                    grew = true;
                }
            }
            if !grew {
                break;
            }
        }
        let kept = |id: &NodeId| keep[self.node_index[id]];
        let nodes: Vec<Node> = self.nodes.iter().filter(|n| kept(&n.id)).cloned().collect();
        let node_index = nodes.iter().enumerate().map(|(i, n)| (n.id, i)).collect();
        Model {
            title: self.title.clone(),
            nodes,
            node_index,
            materials: self.materials.clone(),
            sections: self.sections.clone(),
            beams: self.beams.iter().filter(|b| b.nodes.iter().all(kept)).cloned().collect(),
            springs: self.springs.iter().filter(|s| kept(&s.a) && s.b.as_ref().is_none_or(kept)).cloned().collect(),
            masses: self.masses.iter().filter(|m| kept(&m.node)).cloned().collect(),
            supports: self.supports.iter().filter(|s| kept(&s.node)).cloned().collect(),
            ties: self.ties.iter().filter(|t| t.nodes.iter().all(kept)).cloned().collect(),
            groups: self.groups.clone(),
        }
    }

    /// Indices of the beams with an end at `node`.
    pub fn beams_at(&self, node: NodeId) -> Vec<usize> {
        self.beams.iter().enumerate().filter(|(_, b)| b.nodes.contains(&node)).map(|(i, _)| i).collect()
    }

    /// Length and direction cosines (c, s) of a beam.
    pub fn beam_geometry(&self, beam: usize) -> (f64, f64, f64) {
        let b = &self.beams[beam];
        let (p, q) = (self.node(b.nodes[0]).unwrap(), self.node(b.nodes[1]).unwrap());
        let (dx, dy) = (q.x - p.x, q.y - p.y);
        let l = (dx * dx + dy * dy).sqrt();
        (l, dx / l, dy / l)
    }

    /// Total mass of the structure (kg), counting beams, added and lumped mass.
    pub fn total_mass(&self) -> f64 {
        let beams: f64 = self
            .beams
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let (l, _, _) = self.beam_geometry(i);
                let g = &self.groups[b.group];
                let rho_a = self.materials[b.material].rho * self.sections[b.section].area;
                (rho_a + b.added_mass) * l * b.mass_factor * g.mass
            })
            .sum();
        let lumped: f64 = self.masses.iter().map(|m| m.m * self.groups[m.group].mass).sum();
        beams + lumped
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::{Assembly, BlockSource};
    use crate::samples;

    /// A part keeps what lies on its nodes, pulls in tied nodes, and
    /// assembles the same blocks as the whole model, though it floats free.
    #[test]
    fn a_part_holds_the_blocks_on_its_nodes() {
        let whole = samples::frame_with_joint();
        let part = whole.part(&[NodeId(3), NodeId(4)]);
        // node 2 is tied to node 3, so it belongs to the part
        let ids: Vec<u32> = part.nodes().iter().map(|n| n.id.0).collect();
        assert_eq!(ids, [2, 3, 4]);
        assert_eq!(part.beams().iter().map(|b| b.id.0).collect::<Vec<_>>(), [2]);
        assert_eq!(part.springs().len(), 1);
        assert_eq!(part.masses().len(), 1);
        assert_eq!(part.ties().len(), 1);
        assert!(part.supports().is_empty());
        assert_eq!(part.groups(), whole.groups());
        // the arm alone is a mechanism: only a part assembly accepts it
        assert_eq!(
            Assembly::new(&part).unwrap_err(),
            ModelError::Mechanism { hint: "3:ux".into(), modes: 3, nodes: vec![2, 3, 4] }
        );
        let (a, w) = (Assembly::of_part(&part).unwrap(), Assembly::new(&whole).unwrap());
        assert_eq!(a.n(), 7, "ux, uy shared by nodes 2 and 3, three rotations, node 4's ux, uy");
        let beam = |asm: &Assembly, m: &Model| {
            asm.blocks
                .iter()
                .find(|b| matches!(b.source, BlockSource::Beam(i) if m.beams()[i].id.0 == 2))
                .cloned()
                .unwrap()
        };
        let (bp, bw) = (beam(&a, &part), beam(&w, &whole));
        for (tp, tw) in bp.terms.iter().zip(&bw.terms) {
            assert_eq!(tp.unit, tw.unit);
            assert_eq!(tp.value, tw.value);
        }
        // the same DOFs in both numberings
        for (&ep, &ew) in bp.eqs.iter().zip(&bw.eqs) {
            assert_eq!(a.dofs.dof_of(ep), w.dofs.dof_of(ew));
        }
    }
}
