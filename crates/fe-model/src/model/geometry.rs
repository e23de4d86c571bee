//! What a model derives from its items: the part of it around some nodes
//! (for local computations), the beams at a node, each beam's axis, local
//! axes and planar geometry, and the total mass.

use super::{Model, Node, NodeId};
use crate::element::frame3d;

impl Model {
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
            dimension: self.dimension,
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
            imported: self.imported.iter().filter(|b| b.nodes.iter().all(kept)).cloned().collect(),
        }
    }

    /// Indices of the beams with an end at `node`.
    pub fn beams_at(&self, node: NodeId) -> Vec<usize> {
        self.beams.iter().enumerate().filter(|(_, b)| b.nodes.contains(&node)).map(|(i, _)| i).collect()
    }

    /// Length and unit direction (first node to second) of a beam.
    pub fn beam_axis(&self, beam: usize) -> (f64, [f64; 3]) {
        let b = &self.beams[beam];
        let (p, q) = (self.node(b.nodes[0]).unwrap(), self.node(b.nodes[1]).unwrap());
        let d = [q.x - p.x, q.y - p.y, q.z - p.z];
        let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        (l, d.map(|v| v / l))
    }

    /// The local axes `[x, y, z]` of a beam (rows, in global components):
    /// along the beam, and the section's principal axes (in a planar
    /// model, `y` in the plane and `z` the global z).
    pub fn beam_axes(&self, beam: usize) -> [[f64; 3]; 3] {
        let b = &self.beams[beam];
        let [p, q] = b.nodes.map(|n| self.node(n).expect("checked when added").position());
        frame3d::axes(p, q, b.reference, b.angle).expect("checked when added and oriented")
    }

    /// Length and direction cosines (c, s) of a beam in the x-y plane (a
    /// planar model's beams).
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
                let (l, _) = self.beam_axis(i);
                let g = &self.groups[b.group];
                let rho_a = self.materials[b.material].rho * self.sections[b.section].area;
                (rho_a + b.added_mass) * l * b.mass_factor * g.mass
            })
            .sum();
        let lumped: f64 = self.masses.iter().map(|m| m.m * self.groups[m.group].mass).sum();
        beams + lumped + self.imported_mass()
    }
}
