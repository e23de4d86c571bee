//! The model description: nodes, materials, sections, elements, springs,
//! lumped masses, supports, ties and groups.
//!
//! A [`Model`] is plain data with validated construction. It knows nothing of
//! frequencies or damping kernels; the damping values of a group are stored
//! here only so that a case file describes the whole structure in one place.
//! A model is planar (nodes in the x-y plane with `ux`, `uy`, `rz`) or a
//! frame in space (six DOFs per node), fixed when it is made
//! ([`Model::with_dimension`]); every `add_*` refuses a DOF, coordinate or
//! value the dimension does not have. The items themselves are in `items.rs`,
//! the parts and the geometry the model derives in `geometry.rs`, springs in
//! their own axes in `spring_axes.rs`.

use std::collections::HashMap;

use crate::dof::{Dimension, Dof, PerDof};
use crate::element::frame3d;
use crate::error::ModelError;

mod geometry;
pub use geometry::PartIndex;
mod items;
mod spring_axes;

pub use crate::dof::NodeId;
pub use items::{
    Beam, ElementId, Group, ImportedBlock, ImportedKind, LumpedMass, Material, Node, RotaryInertia, Section, Spring,
    Support, Tie, rectangle_torsion,
};
pub use spring_axes::{SpringAxesError, spring_axes};

/// A frame model, planar or in space.
///
/// Build it with the `add_*` methods (each checks its references), or load it
/// from a case file with [`crate::case::CaseFile`]. Every element, spring and
/// mass belongs to a group.
#[derive(Clone, Debug, Default)]
pub struct Model {
    /// Title shown in reports.
    pub title: String,
    pub(crate) dimension: Dimension,
    pub(crate) nodes: Vec<Node>,
    pub(crate) node_index: HashMap<NodeId, usize>,
    pub(crate) materials: Vec<Material>,
    pub(crate) sections: Vec<Section>,
    pub(crate) beams: Vec<Beam>,
    /// Index in `beams` of each element id: a model of 100k elements
    /// checked each new id against all before it (quadratic: seconds when
    /// loading a large imported frame).
    pub(crate) beam_ids: HashMap<ElementId, usize>,
    pub(crate) springs: Vec<Spring>,
    pub(crate) masses: Vec<LumpedMass>,
    pub(crate) supports: Vec<Support>,
    pub(crate) ties: Vec<Tie>,
    pub(crate) groups: Vec<Group>,
    pub(crate) imported: Vec<ImportedBlock>,
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
    /// An empty planar model.
    pub fn new(title: &str) -> Self {
        Model { title: title.into(), ..Default::default() }
    }

    /// An empty model of the given dimension.
    pub fn with_dimension(title: &str, dimension: Dimension) -> Self {
        Model { title: title.into(), dimension, ..Default::default() }
    }

    /// Planar or in space.
    pub fn dimension(&self) -> Dimension {
        self.dimension
    }

    /// The DOFs of every node, in the order they are numbered.
    pub fn node_dofs(&self) -> &'static [Dof] {
        self.dimension.dofs()
    }

    fn check_dofs(&self, dofs: &[Dof], what: &str) -> Result<(), ModelError> {
        for &d in dofs {
            self.dimension.check(d).map_err(|reason| ModelError::Invalid { what: what.into(), reason })?;
        }
        Ok(())
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
        self.beam_ids.get(&id).copied()
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

    /// Adds a node in the x-y plane; ids must be unique and coordinates finite.
    pub fn add_node(&mut self, id: u32, x: f64, y: f64) -> Result<NodeId, ModelError> {
        self.add_node_at(id, [x, y, 0.0])
    }

    /// Adds a node at `[x, y, z]`; a planar model refuses `z != 0`.
    pub fn add_node_at(&mut self, id: u32, [x, y, z]: [f64; 3]) -> Result<NodeId, ModelError> {
        let id = NodeId(id);
        if self.node_index.contains_key(&id) {
            return Err(ModelError::DuplicateNode { id: id.0 });
        }
        if !(x.is_finite() && y.is_finite() && z.is_finite()) {
            let shown =
                if self.dimension == Dimension::Planar { format!("({x}, {y})") } else { format!("({x}, {y}, {z})") };
            return Err(ModelError::Invalid {
                what: format!("node {id}"),
                reason: format!("coordinates must be finite, got {shown}"),
            });
        }
        if self.dimension == Dimension::Planar && z != 0.0 {
            return Err(ModelError::Invalid {
                what: format!("node {id}"),
                reason: format!(
                    "has z = {z}, and a planar model lies in the x-y plane; a frame in space needs `[model] dimension = 3`"
                ),
            });
        }
        self.node_index.insert(id, self.nodes.len());
        self.nodes.push(Node { id, x, y, z });
        Ok(id)
    }

    /// Adds a material (E > 0, rho > 0) and returns its index.
    pub fn add_material(&mut self, name: &str, e: f64, rho: f64) -> Result<usize, ModelError> {
        if self.material_index(name).is_some() {
            return Err(ModelError::Duplicate { what: format!("material `{name}`") });
        }
        positive(format!("material `{name}`: E"), e)?;
        positive(format!("material `{name}`: rho"), rho)?;
        self.materials.push(Material { name: name.into(), e, rho, nu: None });
        Ok(self.materials.len() - 1)
    }

    /// Sets the Poisson's ratio of a material (`-1 < nu <= 0.5`), which gives
    /// the shear modulus of a 3D beam's torsion.
    pub fn set_poisson(&mut self, material: usize, nu: f64) -> Result<(), ModelError> {
        if !(nu > -1.0 && nu <= 0.5) {
            return Err(ModelError::Invalid {
                what: format!("material `{}`: nu", self.materials[material].name),
                reason: format!("must lie in (-1, 0.5], got {}", crate::show(nu)),
            });
        }
        self.materials[material].nu = Some(nu);
        Ok(())
    }

    /// Adds a section (A > 0, I > 0; in a 3D model also Iy > 0 and J > 0)
    /// and returns its index.
    pub fn add_section(&mut self, section: Section) -> Result<usize, ModelError> {
        if self.section_index(&section.name).is_some() {
            return Err(ModelError::Duplicate { what: format!("section `{}`", section.name) });
        }
        positive(format!("section `{}`: A", section.name), section.area)?;
        if self.dimension == Dimension::Spatial {
            positive(format!("section `{}`: Iz", section.name), section.inertia)?;
            positive(format!("section `{}`: Iy", section.name), section.iy)?;
            positive(format!("section `{}`: J", section.name), section.torsion)?;
        } else {
            positive(format!("section `{}`: I", section.name), section.inertia)?;
        }
        self.sections.push(section);
        Ok(self.sections.len() - 1)
    }

    /// Adds a group and returns its index.
    pub fn add_group(&mut self, group: Group) -> Result<usize, ModelError> {
        self.check_group(&group, None)?;
        self.groups.push(group);
        Ok(self.groups.len() - 1)
    }

    /// Replaces group `index` (its damping and factors, or its name) with
    /// `group`, checked as [`Self::add_group`] checks a new one; the items
    /// of the group stay in it. To change one value, [`Self::set`] its
    /// quantity.
    pub fn replace_group(&mut self, index: usize, group: Group) -> Result<(), ModelError> {
        if index >= self.groups.len() {
            return Err(ModelError::UnknownGroup { name: format!("#{index}"), context: "a replaced group".into() });
        }
        self.check_group(&group, Some(index))?;
        self.groups[index] = group;
        Ok(())
    }

    /// The checks of a group's values, and of its name against the other
    /// groups (all but `replacing`).
    fn check_group(&self, group: &Group, replacing: Option<usize>) -> Result<(), ModelError> {
        if self.group_index(&group.name).is_some_and(|i| Some(i) != replacing) {
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
        positive(format!("group `{g}`: damping"), group.damping)?;
        Ok(())
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
        if self.beam_ids.contains_key(&id) {
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
        if self.dimension == Dimension::Spatial && self.materials[material].nu.is_none() {
            return Err(ModelError::Invalid {
                what: ctx,
                reason: format!(
                    "is a 3D beam of material `{}`, which has no Poisson's ratio `nu` (or shear modulus `G`) for its torsion",
                    self.materials[material].name
                ),
            });
        }
        let (a, b) = (self.node(nodes[0]).unwrap(), self.node(nodes[1]).unwrap());
        let length = if self.dimension == Dimension::Planar {
            (b.x - a.x).hypot(b.y - a.y)
        } else {
            ((b.x - a.x).powi(2) + (b.y - a.y).powi(2) + (b.z - a.z).powi(2)).sqrt()
        };
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
            bending_factor: 1.0,
            mass_factor: 1.0,
            reference: None,
            angle: 0.0,
        });
        if self.dimension == Dimension::Spatial
            && let Err(e) = self.orient_beam(self.beams.len() - 1, None, 0.0)
        {
            self.beams.pop();
            return Err(e);
        }
        self.beam_ids.insert(id, self.beams.len() - 1);
        Ok(self.beams.len() - 1)
    }

    /// Orients the section of a 3D beam: `reference` is the approximate
    /// direction of its local z axis (`None`: the default), `angle` turns the
    /// section about the beam's axis (radians). See [`frame3d::axes`].
    pub fn orient_beam(&mut self, beam: usize, reference: Option<[f64; 3]>, angle: f64) -> Result<(), ModelError> {
        let ctx = format!("element {}", self.beams[beam].id);
        if self.dimension == Dimension::Planar && (reference.is_some() || angle != 0.0) {
            return Err(ModelError::Invalid {
                what: ctx,
                reason: "has an orientation, which only a beam of a 3D model has (`[model] dimension = 3`)".into(),
            });
        }
        if !angle.is_finite() {
            return Err(ModelError::Invalid { what: ctx, reason: format!("has a turn angle of {angle}") });
        }
        let [p, q] = self.beams[beam].nodes.map(|n| self.node(n).expect("checked when added").position());
        match frame3d::axes(p, q, reference, angle) {
            Ok(_) => {
                self.beams[beam].reference = reference;
                self.beams[beam].angle = angle;
                Ok(())
            }
            Err(frame3d::AxesError::ZeroLength) => Err(ModelError::ZeroLength { element: self.beams[beam].id.0 }),
            Err(frame3d::AxesError::Reference) => Err(ModelError::Invalid {
                what: ctx,
                reason: format!(
                    "has the orientation {:?}, which is zero or along the beam; give a direction across it for the section's local z axis",
                    reference.unwrap_or_default()
                ),
            }),
        }
    }

    /// Sets the non-structural transverse mass per length of a beam (kg/m).
    pub fn set_added_mass(&mut self, beam: usize, per_length: f64) -> Result<(), ModelError> {
        non_negative(format!("element {}: added_mass", self.beams[beam].id), per_length)?;
        self.beams[beam].added_mass = per_length;
        Ok(())
    }

    /// Adds springs `k` between `a` and `b` (or to ground when `b` is
    /// `None`): `[kx, ky, kr]` in a planar model, or a stiffness per DOF
    /// ([`PerDof`]); a DOF the model does not have must get none.
    pub fn add_spring(
        &mut self,
        name: &str,
        a: u32,
        b: Option<u32>,
        k: impl Into<PerDof>,
        group: usize,
    ) -> Result<usize, ModelError> {
        let k = k.into();
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
        for &d in &Dof::SPATIAL {
            if self.dimension.local(d).is_none() && k[d] != 0.0 {
                self.dimension.check(d).map_err(|reason| ModelError::Invalid { what: ctx.clone(), reason })?;
            }
        }
        for &d in self.dimension.dofs() {
            non_negative(format!("{ctx}: {}", self.dimension.spring_key(d)), k[d])?;
        }
        if k.0.iter().all(|&v| v == 0.0) {
            return Err(ModelError::Invalid { what: ctx, reason: "has no non-zero stiffness".into() });
        }
        self.require_group(group, &ctx)?;
        self.springs.push(Spring { name: name.into(), a: NodeId(a), b: b.map(NodeId), k, group, axes: None });
        Ok(self.springs.len() - 1)
    }

    /// Adds a lumped mass `m` (kg) with rotary inertia `j` (kg m^2: about
    /// z, or about x, y and z in a 3D model) at a node.
    pub fn add_mass(
        &mut self,
        name: &str,
        node: u32,
        m: f64,
        j: impl Into<RotaryInertia>,
        group: usize,
    ) -> Result<usize, ModelError> {
        let j = j.into().0;
        let ctx = format!("mass `{name}`");
        if self.mass_index(name).is_some() {
            return Err(ModelError::Duplicate { what: ctx });
        }
        self.require_node(NodeId(node), &ctx)?;
        non_negative(format!("{ctx}: m"), m)?;
        if self.dimension == Dimension::Planar && (j[0] != 0.0 || j[1] != 0.0) {
            return Err(ModelError::Invalid {
                what: ctx,
                reason:
                    "has a rotary inertia about x or y, which a planar model does not have (`[model] dimension = 3`)"
                        .into(),
            });
        }
        for &d in self.dimension.rotations() {
            non_negative(format!("{ctx}: {}", self.dimension.inertia_key(d)), j[d.axis()])?;
        }
        if m == 0.0 && j.iter().all(|&v| v == 0.0) {
            return Err(ModelError::Invalid { what: ctx, reason: "has neither mass nor inertia".into() });
        }
        self.require_group(group, &ctx)?;
        self.masses.push(LumpedMass { name: name.into(), node: NodeId(node), m, j, group });
        Ok(self.masses.len() - 1)
    }

    /// Fixes DOFs of a node.
    pub fn add_support(&mut self, node: u32, dofs: &[Dof]) -> Result<(), ModelError> {
        self.require_node(NodeId(node), "support")?;
        self.check_dofs(dofs, &format!("support at node {node}"))?;
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
        self.check_dofs(dofs, &format!("tie {a}-{b}"))?;
        // A tie makes two nodes share displacements and rotation, which is
        // only kinematically sound where they coincide (a joint, as in the
        // paper); between distant nodes it silently makes a wrong model.
        let (p, q) = (&self.nodes[self.node_index[&NodeId(a)]], &self.nodes[self.node_index[&NodeId(b)]]);
        let gap = (p.x - q.x).hypot(p.y - q.y).hypot(p.z - q.z);
        let extent = self.nodes.iter().map(|n| n.x.abs().max(n.y.abs()).max(n.z.abs())).fold(0.0, f64::max);
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
        let at = self.node(NodeId(node)).expect("checked above").position();
        self.add_node_at(new_id, at)?;
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::{Assembly, BlockSource};
    use crate::samples;

    /// The part by a scan of the whole model, as `Model::part` once cut it:
    /// the indexed cut's independent truth.
    fn scanned_part(m: &Model, nodes: &[NodeId]) -> Model {
        let mut keep = vec![false; m.nodes.len()];
        for id in nodes {
            if let Some(&i) = m.node_index.get(id) {
                keep[i] = true;
            }
        }
        // closure over ties: a tie chain can reach further than one step
        loop {
            let mut grew = false;
            for t in &m.ties {
                let [a, b] = t.nodes.map(|n| m.node_index[&n]);
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
        let kept = |id: &NodeId| keep[m.node_index[id]];
        let nodes: Vec<Node> = m.nodes.iter().filter(|n| kept(&n.id)).cloned().collect();
        let node_index = nodes.iter().enumerate().map(|(i, n)| (n.id, i)).collect();
        Model {
            title: m.title.clone(),
            dimension: m.dimension,
            nodes,
            node_index,
            materials: m.materials.clone(),
            sections: m.sections.clone(),
            beam_ids: m.beams.iter().filter(|b| b.nodes.iter().all(kept)).enumerate().map(|(i, b)| (b.id, i)).collect(),
            beams: m.beams.iter().filter(|b| b.nodes.iter().all(kept)).cloned().collect(),
            springs: m.springs.iter().filter(|s| kept(&s.a) && s.b.as_ref().is_none_or(kept)).cloned().collect(),
            masses: m.masses.iter().filter(|m| kept(&m.node)).cloned().collect(),
            supports: m.supports.iter().filter(|s| kept(&s.node)).cloned().collect(),
            ties: m.ties.iter().filter(|t| t.nodes.iter().all(kept)).cloned().collect(),
            groups: m.groups.clone(),
            imported: m.imported.iter().filter(|b| b.nodes.iter().all(kept)).cloned().collect(),
        }
    }

    /// The indexed cut gives the same part as the whole-model scan, for
    /// every one and every two nodes of a model with a chain of ties,
    /// springs to ground and between nodes, masses, supports and an
    /// imported block.
    #[test]
    fn the_indexed_part_is_the_scanned_part() {
        use crate::dof::DofRef;
        use crate::imported::{ImportedKind, SymmetricCoo};
        let mut m = samples::frame_with_joint();
        m.add_node(5, 1.0, 1.0).unwrap();
        m.add_node(6, 1.0, 1.0).unwrap();
        m.add_node(7, 2.0, 1.0).unwrap();
        m.add_tie(4, 5, &[Dof::Ux]).unwrap();
        m.add_tie(5, 6, &[Dof::Uy]).unwrap();
        let (steel, sec, frame) = (0, 0, 0);
        m.add_beam(3, [6, 7], steel, sec, frame).unwrap();
        m.add_spring("ground", 6, None, [1e5, 0.0, 0.0], frame).unwrap();
        m.add_mass("end", 7, 0.2, 0.0, frame).unwrap();
        m.add_support(7, &[Dof::Uy]).unwrap();
        let table = [DofRef::new(4, Dof::Rz), DofRef::new(7, Dof::Rz)];
        let k = SymmetricCoo { n: 2, entries: vec![(0, 0, 10.0), (1, 0, -10.0), (1, 1, 10.0)] };
        m.add_imported(frame, ImportedKind::Stiffness, &table, &k).unwrap();
        let index = PartIndex::new(&m);
        let ids: Vec<u32> = m.nodes().iter().map(|n| n.id.0).collect();
        let mut sets: Vec<Vec<NodeId>> = ids.iter().map(|&a| vec![NodeId(a)]).collect();
        for &a in &ids {
            for &b in &ids {
                sets.push(vec![NodeId(a), NodeId(b)]);
            }
        }
        let mut nonempty = 0;
        for nodes in &sets {
            let (scanned, indexed) = (scanned_part(&m, nodes), m.part_indexed(&index, nodes));
            let show = |p: &Model| {
                format!(
                    "{:?} {:?} {:?} {:?} {:?} {:?} {:?}",
                    p.nodes(),
                    p.beams(),
                    p.springs(),
                    p.masses(),
                    p.supports(),
                    p.ties(),
                    p.imported()
                )
            };
            assert_eq!(show(&indexed), show(&scanned), "nodes {nodes:?}");
            assert_eq!(indexed.node_index, scanned.node_index, "nodes {nodes:?}");
            nonempty += usize::from(!scanned.imported().is_empty() && !scanned.ties().is_empty());
        }
        assert!(nonempty > 0, "no part held both a tie and the imported block");
        // the tie chain 4-5-6 is followed from either end
        let ids = |p: &Model| p.nodes().iter().map(|n| n.id.0).collect::<Vec<_>>();
        assert_eq!(ids(&m.part_indexed(&index, &[NodeId(6)])), [4, 5, 6]);
    }

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
            asm.blocks()
                .iter()
                .find(|b| matches!(b.source(), BlockSource::Beam(i) if m.beams()[i].id.0 == 2))
                .cloned()
                .unwrap()
        };
        let (bp, bw) = (beam(&a, &part), beam(&w, &whole));
        for (tp, tw) in bp.terms().iter().zip(bw.terms()) {
            assert_eq!(tp.unit(), tw.unit());
            assert_eq!(tp.value(), tw.value());
        }
        // the same DOFs in both numberings
        for (&ep, &ew) in bp.eqs().iter().zip(bw.eqs()) {
            assert_eq!(a.dofs().dof_of(ep), w.dofs().dof_of(ew));
        }
    }

    #[test]
    fn a_replaced_group_is_checked_as_an_added_one() {
        let mut m = samples::frame_with_joint();
        let joint = m.group_index("joint").unwrap();
        assert_eq!(
            m.replace_group(joint, Group::new("joint").rayleigh(-1.0, 0.0)).unwrap_err(),
            ModelError::Invalid {
                what: "group `joint`: alpha".into(),
                reason: "must be zero or positive and finite, got -1".into()
            }
        );
        assert_eq!(
            m.replace_group(joint, Group::new("joint").relaxation(0.0)).unwrap_err(),
            ModelError::Invalid {
                what: "group `joint`: mu".into(),
                reason: "must be positive and finite, got 0".into()
            }
        );
        assert_eq!(
            m.replace_group(joint, Group::new("frame")).unwrap_err(),
            ModelError::Duplicate { what: "group `frame`".into() }
        );
        assert_eq!(
            m.replace_group(9, Group::new("joint")).unwrap_err(),
            ModelError::UnknownGroup { name: "#9".into(), context: "a replaced group".into() }
        );
        // nothing refused changed the group; a valid replacement does
        assert_eq!(m.groups()[joint], samples::frame_with_joint().groups()[joint]);
        m.replace_group(joint, Group::new("joint").rayleigh(2e-3, 0.0)).unwrap();
        assert_eq!((m.groups()[joint].alpha, m.groups()[joint].mu), (2e-3, None));
    }

    /// Element ids are looked up by index, not by a scan: a repeated id is
    /// refused, an element refused for another reason leaves no id behind,
    /// and a part knows its own elements' ids.
    #[test]
    fn element_ids_are_unique_and_found() {
        let mut m = samples::cantilever(4);
        let n = m.beams().len();
        for (i, b) in m.beams().iter().enumerate() {
            assert_eq!(m.beam_index(b.id), Some(i));
        }
        let first = m.beams()[0].clone();
        assert_eq!(
            m.add_beam(first.id.0, [first.nodes[0].0, first.nodes[1].0], first.material, first.section, first.group)
                .unwrap_err(),
            ModelError::Duplicate { what: format!("element {}", first.id) }
        );
        // a zero-length element with a new id is refused and leaves no id
        let a = first.nodes[0].0;
        assert!(m.add_beam(9_999, [a, a], first.material, first.section, first.group).is_err());
        assert_eq!((m.beam_index(ElementId(9_999)), m.beams().len()), (None, n));
        let added = m.add_beam(9_999, [first.nodes[0].0, first.nodes[1].0], 0, 0, first.group).unwrap();
        assert_eq!(m.beam_index(ElementId(9_999)), Some(added));
        // a part around the last element: its ids index its own list
        let last = m.beams()[n - 1].clone();
        let part = m.part(&last.nodes);
        assert_eq!(part.beams().len(), 1);
        assert_eq!(part.beam_index(last.id), Some(0));
        assert_eq!(part.beam_index(first.id), None);
    }
}
