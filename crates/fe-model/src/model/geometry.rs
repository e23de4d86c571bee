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
    /// Each call indexes the whole model; for many parts of one model, see
    /// [`Self::part_indexed`].
    pub fn part(&self, nodes: &[NodeId]) -> Model {
        self.part_indexed(&PartIndex::new(self), nodes)
    }

    /// [`Self::part`], cut through an index of the items at each node made
    /// beforehand ([`PartIndex::new`]): it touches only what lies on the
    /// part's nodes. A diagnosis cuts one part per candidate (60,000 on a
    /// 100k-DOF frame, where a scan of the whole model for each took 40 s of
    /// CPU); it builds the index once.
    pub fn part_indexed(&self, index: &PartIndex, nodes: &[NodeId]) -> Model {
        let mut keep: Vec<usize> = nodes.iter().filter_map(|id| self.node_index.get(id).copied()).collect();
        keep.sort_unstable();
        keep.dedup();
        // closure over ties (a chain can reach further than one step), by a
        // walk along the ties at kept nodes
        let mut queue = keep.clone();
        while let Some(i) = queue.pop() {
            for &t in &index.ties[i] {
                for n in self.ties[t].nodes {
                    let j = self.node_index[&n];
                    if let Err(at) = keep.binary_search(&j) {
                        keep.insert(at, j);
                        queue.push(j);
                    }
                }
            }
        }
        let kept = |id: &NodeId| keep.binary_search(&self.node_index[id]).is_ok();
        // the items at kept nodes, in model order, with every node kept
        let at = |lists: &[Vec<usize>]| -> Vec<usize> {
            let mut items: Vec<usize> = keep.iter().flat_map(|&i| lists[i].iter().copied()).collect();
            items.sort_unstable();
            items.dedup();
            items
        };
        let nodes: Vec<Node> = keep.iter().map(|&i| self.nodes[i].clone()).collect();
        let node_index = nodes.iter().enumerate().map(|(i, n)| (n.id, i)).collect();
        let beams = cut(&self.beams, at(&index.beams), |b| b.nodes.iter().all(kept));
        let beam_ids = beams.iter().enumerate().map(|(i, b)| (b.id, i)).collect();
        Model {
            title: self.title.clone(),
            dimension: self.dimension,
            nodes,
            node_index,
            materials: self.materials.clone(),
            sections: self.sections.clone(),
            beams,
            beam_ids,
            springs: cut(&self.springs, at(&index.springs), |s| kept(&s.a) && s.b.as_ref().is_none_or(kept)),
            masses: cut(&self.masses, at(&index.masses), |_| true),
            supports: cut(&self.supports, at(&index.supports), |_| true),
            ties: cut(&self.ties, at(&index.ties), |t| t.nodes.iter().all(kept)),
            groups: self.groups.clone(),
            imported: cut(&self.imported, at(&index.imported), |b| b.nodes.iter().all(kept)),
        }
    }

    /// The same structure with every beam split into `parts` equal
    /// elements (h-refinement): the first keeps the beam's id, the others and
    /// the nodes between them take ids above every id of the model, in beam
    /// order. Each piece keeps its beam's material, section, group, factors,
    /// added mass per length and section orientation; springs, masses,
    /// supports, ties and imported blocks are unchanged. What a model's
    /// FRFs move by when so refined is the part of them its mesh decides
    /// (the Hermite elements are exact in statics: the difference is in how
    /// finely the inertia is spread).
    pub fn refined(&self, parts: usize) -> Result<Model, crate::ModelError> {
        if parts <= 1 {
            return Ok(self.clone());
        }
        let mut m = Model { beams: Vec::new(), beam_ids: Default::default(), ..self.clone() };
        let mut next_node = self.max_node_id() + 1;
        let mut next_beam = self.beams.iter().map(|b| b.id.0).max().unwrap_or(0) + 1;
        for b in &self.beams {
            let [p, q] = b.nodes.map(|n| self.node(n).expect("checked when added").position());
            let mut prev = b.nodes[0];
            for k in 1..=parts {
                let end = if k == parts {
                    b.nodes[1]
                } else {
                    let t = k as f64 / parts as f64;
                    let id = m.add_node_at(next_node, [0, 1, 2].map(|i| p[i] + t * (q[i] - p[i])))?;
                    next_node += 1;
                    id
                };
                let id = if k == 1 {
                    b.id.0
                } else {
                    next_beam += 1;
                    next_beam - 1
                };
                let i = m.add_beam(id, [prev.0, end.0], b.material, b.section, b.group)?;
                if self.dimension == super::Dimension::Spatial {
                    m.orient_beam(i, b.reference, b.angle)?;
                }
                let piece = &mut m.beams[i];
                piece.added_mass = b.added_mass;
                piece.stiffness_factor = b.stiffness_factor;
                piece.bending_factor = b.bending_factor;
                piece.mass_factor = b.mass_factor;
                prev = end;
            }
        }
        Ok(m)
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

/// The items of `items` at the indices `at` that `keep` keeps, in order.
fn cut<T: Clone>(items: &[T], at: Vec<usize>, keep: impl Fn(&T) -> bool) -> Vec<T> {
    at.into_iter().map(|i| &items[i]).filter(|x| keep(x)).cloned().collect()
}

/// The items at each node of a model (by node index), for
/// [`Model::part_indexed`]. It belongs to the model it was built from, as
/// that model stands: an index of another model, or of this one before an
/// item was added or removed, cuts wrong parts.
pub struct PartIndex {
    beams: Vec<Vec<usize>>,
    springs: Vec<Vec<usize>>,
    masses: Vec<Vec<usize>>,
    supports: Vec<Vec<usize>>,
    ties: Vec<Vec<usize>>,
    imported: Vec<Vec<usize>>,
}

impl PartIndex {
    /// The index of `model`.
    pub fn new(model: &Model) -> PartIndex {
        let lists = |nodes: &mut dyn Iterator<Item = (usize, NodeId)>| {
            let mut at = vec![Vec::new(); model.nodes.len()];
            for (item, node) in nodes {
                let list: &mut Vec<usize> = &mut at[model.node_index[&node]];
                if list.last() != Some(&item) {
                    list.push(item);
                }
            }
            at
        };
        PartIndex {
            beams: lists(&mut model.beams.iter().enumerate().flat_map(|(i, b)| b.nodes.map(|n| (i, n)))),
            springs: lists(
                &mut model
                    .springs
                    .iter()
                    .enumerate()
                    .flat_map(|(i, s)| std::iter::once((i, s.a)).chain(s.b.map(|b| (i, b)))),
            ),
            masses: lists(&mut model.masses.iter().enumerate().map(|(i, m)| (i, m.node))),
            supports: lists(&mut model.supports.iter().enumerate().map(|(i, s)| (i, s.node))),
            ties: lists(&mut model.ties.iter().enumerate().flat_map(|(i, t)| t.nodes.map(|n| (i, n)))),
            imported: lists(&mut model.imported.iter().enumerate().flat_map(|(i, b)| b.nodes.map(|n| (i, n)))),
        }
    }
}
