//! Candidate effects, generated from the model without the user listing them.
//!
//! | kind | where | parameters |
//! |---|---|---|
//! | flexible, lossy support | each supported node | a ground spring per fixed DOF, its group's alpha |
//! | flexible, lossy joint | where members meet at an angle, and existing joint springs | rotational spring, its group's alpha |
//! | lumped mass | each node | mass |
//! | stiffness change | each element (each region on large models; the leaders' locations are refined per element) | stiffness factor |
//! | mass change | each element (each region on large models, refined likewise) | mass factor |
//! | viscous damping | each region of a few elements | alpha of the region |
//! | non-viscous damping | each region | alpha and mu of the region |
//!
//! Each candidate is a change of the nominal model, the effect inserted at a
//! starting value that changes little (a very stiff spring, a tiny mass, a
//! factor of one), the parameters to fit, wide search bounds, and a
//! plausible range: a sensor mass of a quarter of the structure's mass, or a
//! joint stiffer than the member it connects, explains data only in a way
//! no engineer would accept, and the ranking says so.
//!
//! A candidate does not carry a copy of the whole model: a large model has
//! thousands of candidates. It carries the recipe of its change ([`Edit`]),
//! applied to the whole model on demand ([`Candidate::model`]), and the part
//! of the model where it acts with the change applied ([`Model::part`]),
//! which is all the diagnosis needs to fit it (module `local`).

use fe_model::{Dof, ElementId, Group, Model, ModelError, NodeId, Parameter};
use rayon::prelude::*;
use serde::Serialize;

/// The kind of a candidate effect.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectKind {
    /// A support that is flexible (and lossy) instead of rigid.
    FlexibleSupport,
    /// A flexible (and lossy) joint where members meet.
    FlexibleJoint,
    /// An unmodelled lumped mass (a sensor, added mass).
    LumpedMass,
    /// A local stiffness change (loss or gain).
    StiffnessChange,
    /// A local mass change.
    MassChange,
    /// Local viscous damping.
    ViscousDamping,
    /// Local non-viscous (exponential kernel) damping.
    NonViscousDamping,
}

impl EffectKind {
    /// Plain-language name.
    pub fn label(self) -> &'static str {
        match self {
            EffectKind::FlexibleSupport => "flexible, lossy support",
            EffectKind::FlexibleJoint => "flexible, lossy joint",
            EffectKind::LumpedMass => "lumped mass",
            EffectKind::StiffnessChange => "stiffness change",
            EffectKind::MassChange => "mass change",
            EffectKind::ViscousDamping => "viscous damping",
            EffectKind::NonViscousDamping => "non-viscous damping",
        }
    }
}

/// The change a candidate makes to the nominal model, at its starting
/// values: applied to a model by [`Edit::apply`] and written into a case
/// file by [`Candidate::case_lines`]. Names are chosen free in the whole
/// nominal model.
#[derive(Clone, Debug)]
pub(crate) enum Edit {
    /// A lumped mass `m` at a node, in an undamped group of its own.
    Mass { node: u32, name: String, group: String, m: f64 },
    /// The rigid support of a node replaced by ground springs `k` on the
    /// fixed DOFs, in a group with damping `alpha`.
    Support { node: u32, dofs: Vec<Dof>, name: String, group: String, k: [f64; 3], alpha: f64 },
    /// Members detached from a node onto a new coincident node, tied to it in
    /// translation and joined by a rotational spring `kr` with damping `alpha`.
    NewJoint { node: u32, elements: Vec<u32>, new_node: u32, name: String, group: String, kr: f64, alpha: f64 },
    /// Nothing added: the parameters exist in the nominal model.
    Set,
    /// Elements `first..=last` moved to a new group.
    Region { first: u32, last: u32, group: Group, viscous: bool },
}

impl Edit {
    /// Applies the change to `m`: the whole nominal model, or a part of it
    /// that holds the nodes and elements the change touches.
    pub(crate) fn apply(&self, m: &mut Model) -> Result<(), ModelError> {
        match self {
            Edit::Mass { node, name, group, m: mass } => {
                let g = m.add_group(Group::new(group))?;
                m.add_mass(name, *node, *mass, 0.0, g)?;
            }
            Edit::Support { node, name, group, k, alpha, .. } => {
                m.remove_support(*node);
                let g = m.add_group(Group::new(group).rayleigh(*alpha, 0.0))?;
                m.add_spring(name, *node, None, *k, g)?;
            }
            Edit::NewJoint { node, elements, new_node, name, group, kr, alpha } => {
                let g = m.add_group(Group::new(group).rayleigh(*alpha, 0.0))?;
                m.split_node(*node, elements, *new_node)?;
                m.add_tie(*node, *new_node, &[Dof::Ux, Dof::Uy])?;
                m.add_spring(name, *node, Some(*new_node), [0.0, 0.0, *kr], g)?;
            }
            Edit::Set => {}
            Edit::Region { first, last, group, .. } => {
                let g = m.add_group(group.clone())?;
                for id in *first..=*last {
                    if let Some(i) = m.beam_index(ElementId(id)) {
                        m.set_beam_group(i, g)?;
                    }
                }
            }
        }
        Ok(())
    }
}

/// A candidate effect; see the module docs.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// Kind.
    pub kind: EffectKind,
    /// Plain-language description with its location.
    pub description: String,
    /// Nodes where it acts.
    pub nodes: Vec<u32>,
    /// Elements where it acts.
    pub elements: Vec<u32>,
    /// DOFs it acts on, where that applies.
    pub dofs: Vec<Dof>,
    /// Names of the parameters to fit (resolved in [`Candidate::model`]).
    pub parameters: Vec<String>,
    /// Search bounds per parameter.
    pub bounds: Vec<Option<(f64, f64)>>,
    /// Plausible range per parameter, with the reason shown when outside.
    pub plausible: Vec<(f64, f64, &'static str)>,
    pub(crate) edit: Edit,
    /// The part of the nominal model the change touches, before and after it.
    nominal_part: Model,
    part: Model,
}

/// Options of candidate generation.
#[derive(Clone, Debug)]
pub struct CandidateOptions {
    /// Elements per damping region.
    pub region_size: usize,
    /// Above this many elements, stiffness and mass changes are per region.
    pub per_element_limit: usize,
    /// Band of the data (Hz), to scale damping starting values.
    pub band_hz: (f64, f64),
}

impl Default for CandidateOptions {
    fn default() -> Self {
        CandidateOptions { region_size: 4, per_element_limit: 40, band_hz: (1.0, 1000.0) }
    }
}

fn unique_name(model: &Model, base: &str) -> String {
    let taken =
        |n: &str| model.group_index(n).is_some() || model.spring_index(n).is_some() || model.mass_index(n).is_some();
    if !taken(base) {
        return base.to_string();
    }
    (2..).map(|i| format!("{base}_{i}")).find(|n| !taken(n)).expect("some suffix is free")
}

/// Diagonal stiffness (for `E` and factors as modelled) of the beams at a
/// node, per global DOF: the scale a spring at that node competes with.
fn local_stiffness(model: &Model, node: NodeId) -> [f64; 3] {
    let mut k = [0.0; 3];
    for i in model.beams_at(node) {
        let b = &model.beams()[i];
        let (l, c, s) = model.beam_geometry(i);
        let sec = &model.sections()[b.section];
        let e = model.materials()[b.material].e * b.stiffness_factor * model.groups()[b.group].stiffness;
        let ke = fe_model::element::frame_stiffness(sec.area, sec.inertia, l, c, s) * e;
        let o = if b.nodes[0] == node { 0 } else { 3 };
        for d in 0..3 {
            k[d] += ke[(o + d, o + d)];
        }
    }
    k
}

/// Runs of consecutive elements (by id) of the same group that share nodes,
/// split into chunks of at most `size`.
fn regions(model: &Model, size: usize) -> Vec<Vec<usize>> {
    let mut order: Vec<usize> = (0..model.beams().len()).collect();
    order.sort_by_key(|&i| model.beams()[i].id);
    let mut runs: Vec<Vec<usize>> = Vec::new();
    for i in order {
        let b = &model.beams()[i];
        let continues = runs.last().and_then(|r| r.last()).is_some_and(|&j| {
            let a = &model.beams()[j];
            a.group == b.group && a.id.0 + 1 == b.id.0 && a.nodes.iter().any(|n| b.nodes.contains(n))
        });
        if continues {
            runs.last_mut().expect("checked").push(i);
        } else {
            runs.push(vec![i]);
        }
    }
    let mut out = Vec::new();
    for run in runs {
        let n_chunks = run.len().div_ceil(size.max(1));
        let per = run.len().div_ceil(n_chunks);
        out.extend(run.chunks(per).map(<[usize]>::to_vec));
    }
    out
}

/// Most elements in the region of a stiffness or mass change. A region of
/// eight elements in a row touches 27 equations, so its change is a cheap
/// low-rank update of the nominal model (module `local`, whose cost grows as
/// the cube of that number); a region of more than about twenty would be
/// fitted on its own model, a factorisation per line and iteration.
const MAX_CHANGE_REGION: usize = 8;

/// Elements per region of stiffness and mass changes on a model with more
/// than [`CandidateOptions::per_element_limit`] elements: about half that
/// many regions, each no larger than [`MAX_CHANGE_REGION`].
fn change_region_size(elements: usize, opts: &CandidateOptions) -> usize {
    elements.div_ceil((opts.per_element_limit / 2).max(1)).min(MAX_CHANGE_REGION).max(opts.region_size)
}

fn element_ids(model: &Model, idx: &[usize]) -> Vec<u32> {
    idx.iter().map(|&i| model.beams()[i].id.0).collect()
}

fn range_name(ids: &[u32]) -> String {
    match ids {
        [one] => format!("element {one}"),
        _ => format!("elements {}..{}", ids[0], ids[ids.len() - 1]),
    }
}

fn nodes_of(model: &Model, idx: &[usize]) -> Vec<u32> {
    let mut n: Vec<u32> = idx.iter().flat_map(|&i| model.beams()[i].nodes.map(|n| n.0)).collect();
    n.sort_unstable();
    n.dedup();
    n
}

/// Stiffness-change and mass-change candidates of one element or one
/// contiguous run of elements (`unit`: beam indices).
fn change_candidates(model: &Model, unit: &[usize]) -> Vec<Spec> {
    let ids = element_ids(model, unit);
    let field_name = |f: &str| {
        if ids.len() == 1 {
            format!("element.{}.{f}", ids[0])
        } else {
            format!("element.{}..{}.{f}", ids[0], ids[ids.len() - 1])
        }
    };
    let contiguous = ids.windows(2).all(|w| w[1] == w[0] + 1);
    if !contiguous {
        return Vec::new();
    }
    let mut out = Vec::new();
    for (kind, field, plaus) in [
        (
            EffectKind::StiffnessChange,
            "stiffness",
            (0.05, 1.5, "a change beyond -95 % .. +50 % of the nominal stiffness"),
        ),
        (EffectKind::MassChange, "mass", (0.5, 2.0, "a change beyond -50 % .. +100 % of the nominal mass")),
    ] {
        let Ok(p) = model.parameter(&field_name(field)) else { continue };
        let nodes = nodes_of(model, unit);
        out.push((
            Head {
                kind,
                description: format!("{} of {}", kind.label(), range_name(&ids)),
                part_nodes: nodes.clone(),
                nodes,
                elements: ids.clone(),
                dofs: Vec::new(),
            },
            Edit::Set,
            vec![(p.name, Some((1e-3, 100.0)), plaus)],
        ));
    }
    out
}

/// Per-element stiffness and mass changes around where a candidate acts: the
/// elements of a regional change, or the elements meeting at the node of a
/// mass, joint or support. On large models stiffness and mass changes are
/// first tried per region, and one weakened element is neither a weakened
/// region (of which it explains a part) nor a mass at its node (which can
/// rank first when the regions are coarse); refining the leaders' locations
/// lets the data choose. Beam indices; the caller drops those already tried.
pub(crate) fn neighbourhood(model: &Model, c: &Candidate) -> Vec<usize> {
    let mut out: Vec<usize> = c.elements.iter().filter_map(|&e| model.beam_index(ElementId(e))).collect();
    for &n in &c.nodes {
        if c.elements.is_empty() || c.kind == EffectKind::FlexibleJoint {
            out.extend(model.beams_at(NodeId(n)));
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Stiffness-change and mass-change candidates of one element each.
pub(crate) fn per_element(model: &Model, beams: &[usize]) -> Vec<Candidate> {
    build(model, beams.iter().flat_map(|&i| change_candidates(model, &[i])).collect())
}

/// Makes the candidates of `specs`, in parallel and in order: each takes its
/// part of the model, a scan of the whole model.
fn build(model: &Model, specs: Vec<Spec>) -> Vec<Candidate> {
    specs.into_par_iter().filter_map(|(head, edit, fitted)| Candidate::new(model, head, edit, fitted)).collect()
}

/// What a candidate is, apart from its change and parameters.
struct Head {
    kind: EffectKind,
    description: String,
    nodes: Vec<u32>,
    elements: Vec<u32>,
    dofs: Vec<Dof>,
    /// Nominal nodes of every element, spring and mass the change touches.
    part_nodes: Vec<u32>,
}

/// A parameter to fit: name, search bounds, plausible range.
type Fitted = (String, Option<(f64, f64)>, (f64, f64, &'static str));

/// A candidate before its part of the model is taken.
type Spec = (Head, Edit, Vec<Fitted>);

impl Candidate {
    /// Builds a candidate: the part of `model` it touches, with the change
    /// applied. `None` when the change does not apply (it then would not
    /// apply to the whole model either).
    fn new(model: &Model, head: Head, edit: Edit, fitted: Vec<Fitted>) -> Option<Candidate> {
        let part_nodes: Vec<NodeId> = head.part_nodes.iter().map(|&n| NodeId(n)).collect();
        let nominal_part = model.part(&part_nodes);
        let mut part = nominal_part.clone();
        edit.apply(&mut part).ok()?;
        if fitted.iter().any(|(name, ..)| part.parameter(name).is_err()) {
            return None;
        }
        Some(Candidate {
            kind: head.kind,
            description: head.description,
            nodes: head.nodes,
            elements: head.elements,
            dofs: head.dofs,
            parameters: fitted.iter().map(|(n, ..)| n.clone()).collect(),
            bounds: fitted.iter().map(|f| f.1).collect(),
            plausible: fitted.iter().map(|f| f.2).collect(),
            edit,
            nominal_part,
            part,
        })
    }

    /// The whole nominal model with this effect inserted at its starting values.
    pub fn model(&self, nominal: &Model) -> Result<Model, ModelError> {
        let mut m = nominal.clone();
        self.edit.apply(&mut m)?;
        Ok(m)
    }

    /// The parameters to fit, resolved in `model` ([`Self::model`] or a part of it).
    pub fn parameters_in(&self, model: &Model) -> Result<Vec<Parameter>, ModelError> {
        self.parameters.iter().map(|n| model.parameter(n)).collect()
    }

    /// The part of the nominal model that the effect touches, with the
    /// effect inserted (see [`Model::part`]).
    pub(crate) fn part(&self) -> &Model {
        &self.part
    }

    /// The part of the nominal model on the same nodes as [`Self::part`].
    pub(crate) fn nominal_part(&self) -> &Model {
        &self.nominal_part
    }
}

/// Generates every candidate for a model; see the module docs.
pub fn generate(model: &Model, opts: &CandidateOptions) -> Vec<Candidate> {
    let mut specs: Vec<Spec> = Vec::new();
    let w_mid = 2.0 * std::f64::consts::PI * (opts.band_hz.0 * opts.band_hz.1).sqrt();
    let w_max = 2.0 * std::f64::consts::PI * opts.band_hz.1;
    let w_min = 2.0 * std::f64::consts::PI * opts.band_hz.0;
    let total_mass = model.total_mass();
    let alpha_start = 1e-4 / w_mid; // a loss factor of 1e-4 at mid band
    let alpha_bounds = Some((1e-9 / w_max, 10.0 / w_min));
    let alpha_plausible = (0.0, 1.0 / w_max, "a loss factor above 1 in the band");
    let ring = |node: NodeId| -> Vec<u32> {
        let mut v: Vec<u32> =
            model.beams_at(node).into_iter().flat_map(|i| model.beams()[i].nodes.map(|n| n.0)).collect();
        v.push(node.0);
        v.sort_unstable();
        v.dedup();
        v
    };

    // flexible, lossy supports
    let supported: Vec<u32> = {
        let mut v: Vec<u32> = model.supports().iter().map(|s| s.node.0).collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    for node in supported {
        let mut dofs: Vec<Dof> =
            model.supports().iter().filter(|s| s.node.0 == node).flat_map(|s| s.dofs.iter().copied()).collect();
        dofs.sort();
        dofs.dedup();
        let kref = local_stiffness(model, NodeId(node));
        if dofs.is_empty() || dofs.iter().any(|d| kref[d.index()] <= 0.0) {
            continue;
        }
        let group = unique_name(model, &format!("support_{node}"));
        let mut k = [0.0; 3];
        for d in &dofs {
            k[d.index()] = 100.0 * kref[d.index()];
        }
        let name = group.clone();
        let mut fitted: Vec<Fitted> = dofs
            .iter()
            .map(|d| {
                let r = kref[d.index()];
                (
                    format!("spring.{name}.{}", ["kx", "ky", "kr"][d.index()]),
                    Some((1e-6 * r, 1e4 * r)),
                    (0.0, 10.0 * r, "stiffer than the member it holds"),
                )
            })
            .collect();
        fitted.push((format!("group.{group}.alpha"), alpha_bounds, alpha_plausible));
        let head = Head {
            kind: EffectKind::FlexibleSupport,
            description: format!("flexible, lossy support at node {node}"),
            nodes: vec![node],
            elements: Vec::new(),
            dofs: dofs.clone(),
            // the released DOFs enter every element at the node
            part_nodes: ring(NodeId(node)),
        };
        let edit = Edit::Support { node, dofs, name, group, k, alpha: alpha_start };
        specs.push((head, edit, fitted));
    }

    // flexible, lossy joints where members meet at an angle
    let new_node = model.max_node_id() + 1;
    for node in model.nodes() {
        let at = model.beams_at(node.id);
        if at.len() < 2 {
            continue;
        }
        // members: beams grouped by direction (collinear beams form one member)
        let dir = |i: usize| {
            let (_, c, s) = model.beam_geometry(i);
            // direction pointing away from the node
            if model.beams()[i].nodes[0] == node.id { (c, s) } else { (-c, -s) }
        };
        let mut members: Vec<Vec<usize>> = Vec::new();
        for &i in &at {
            let (c, s) = dir(i);
            match members.iter_mut().find(|m| {
                let (c2, s2) = dir(m[0]);
                (c * c2 + s * s2).abs() > 0.985 // within 10 degrees of collinear
            }) {
                Some(m) => m.push(i),
                None => members.push(vec![i]),
            }
        }
        if members.len() < 2 {
            continue;
        }
        // detach each member except the first (the through-member keeps the node)
        for member in members.iter().skip(1) {
            let elements = element_ids(model, member);
            let group = unique_name(model, &format!("joint_{}_{}", node.id, elements[0]));
            let kref = local_stiffness(model, node.id)[2];
            let fitted: Vec<Fitted> = vec![
                (
                    format!("spring.{group}.kr"),
                    Some((1e-6 * kref, 1e4 * kref)),
                    (0.0, 10.0 * kref, "stiffer than the members it joins"),
                ),
                (format!("group.{group}.alpha"), alpha_bounds, alpha_plausible),
            ];
            // every element at the node: splitting it checks that one stays
            let part_nodes = ring(node.id);
            let head = Head {
                kind: EffectKind::FlexibleJoint,
                description: format!("flexible, lossy joint at node {} ({})", node.id, range_name(&elements)),
                nodes: vec![node.id.0],
                elements: elements.clone(),
                dofs: vec![Dof::Rz],
                part_nodes,
            };
            let edit = Edit::NewJoint {
                node: node.id.0,
                elements,
                new_node,
                name: group.clone(),
                group,
                kr: 100.0 * kref,
                alpha: alpha_start,
            };
            specs.push((head, edit, fitted));
        }
    }
    // existing joint springs: their stiffness and damping as modelled
    for sp in model.springs() {
        let Some(b) = sp.b else { continue };
        let kref = local_stiffness(model, sp.a);
        let mut fitted: Vec<Fitted> = Dof::ALL
            .iter()
            .filter(|d| sp.k[d.index()] > 0.0)
            .map(|d| {
                let r = kref[d.index()].max(sp.k[d.index()]);
                (
                    format!("spring.{}.{}", sp.name, ["kx", "ky", "kr"][d.index()]),
                    Some((1e-6 * r, 1e4 * r)),
                    (0.0, 10.0 * r, "stiffer than the members it joins"),
                )
            })
            .collect();
        let g = &model.groups()[sp.group];
        let group_only_this = model.springs().iter().filter(|o| o.group == sp.group).count() == 1
            && model.beams().iter().all(|o| o.group != sp.group)
            && model.masses().iter().all(|o| o.group != sp.group);
        if group_only_this && g.alpha > 0.0 {
            fitted.push((format!("group.{}.alpha", g.name), alpha_bounds, alpha_plausible));
        }
        let head = Head {
            kind: EffectKind::FlexibleJoint,
            description: format!("joint `{}` between nodes {} and {} (as modelled)", sp.name, sp.a, b),
            nodes: vec![sp.a.0, b.0],
            elements: Vec::new(),
            dofs: Dof::ALL.iter().copied().filter(|d| sp.k[d.index()] > 0.0).collect(),
            part_nodes: vec![sp.a.0, b.0],
        };
        specs.push((head, Edit::Set, fitted));
    }

    // lumped masses at free nodes
    let mass_group = unique_name(model, "added_masses");
    for node in model.nodes() {
        let fully_fixed = model
            .supports()
            .iter()
            .filter(|s| s.node == node.id)
            .flat_map(|s| s.dofs.iter())
            .filter(|d| d.is_translation())
            .count()
            >= 2;
        if fully_fixed || model.beams_at(node.id).is_empty() {
            continue;
        }
        let name = unique_name(model, &format!("mass_{}", node.id));
        let fitted: Vec<Fitted> = vec![(
            format!("mass.{name}.m"),
            Some((1e-7 * total_mass, 10.0 * total_mass)),
            (0.0, 0.25 * total_mass, "more than a quarter of the structure's mass"),
        )];
        let head = Head {
            kind: EffectKind::LumpedMass,
            description: format!("lumped mass at node {}", node.id),
            nodes: vec![node.id.0],
            elements: Vec::new(),
            dofs: vec![Dof::Ux, Dof::Uy],
            part_nodes: vec![node.id.0],
        };
        let edit = Edit::Mass { node: node.id.0, name, group: mass_group.clone(), m: 1e-3 * total_mass };
        specs.push((head, edit, fitted));
    }

    // stiffness and mass changes per element or per region
    let units: Vec<Vec<usize>> = if model.beams().len() <= opts.per_element_limit {
        let mut v: Vec<usize> = (0..model.beams().len()).collect();
        v.sort_by_key(|&i| model.beams()[i].id);
        v.into_iter().map(|i| vec![i]).collect()
    } else {
        regions(model, change_region_size(model.beams().len(), opts))
    };
    for unit in &units {
        specs.extend(change_candidates(model, unit));
    }

    // damping per region
    for region in regions(model, opts.region_size) {
        let ids = element_ids(model, &region);
        let base = model.groups()[model.beams()[region[0]].group].clone();
        for viscous in [true, false] {
            let name = unique_name(model, &format!("damping_{}_{}", ids[0], ids[ids.len() - 1]));
            let alpha0 = if base.alpha > 0.0 { base.alpha } else { alpha_start };
            let mut g = Group::new(&name).rayleigh(alpha0, base.beta);
            g.mu = if viscous { base.mu } else { Some(w_mid) };
            g.stiffness = base.stiffness;
            g.mass = base.mass;
            let mut fitted: Vec<Fitted> = vec![(format!("group.{name}.alpha"), alpha_bounds, alpha_plausible)];
            if !viscous {
                fitted.push((format!("group.{name}.mu"), Some((1e-3 * w_min, 1e3 * w_max)), (0.0, f64::INFINITY, "")));
            }
            let kind = if viscous { EffectKind::ViscousDamping } else { EffectKind::NonViscousDamping };
            let nodes = nodes_of(model, &region);
            let head = Head {
                kind,
                description: format!("{} in {}", kind.label(), range_name(&ids)),
                part_nodes: nodes.clone(),
                nodes,
                elements: ids.clone(),
                dofs: Vec::new(),
            };
            let edit = Edit::Region { first: ids[0], last: ids[ids.len() - 1], group: g, viscous };
            specs.push((head, edit, fitted));
        }
    }
    build(model, specs)
}

impl Candidate {
    /// The case-file lines that add this effect with the given parameter
    /// values, and the `[set]` entries (quantity names and values) to merge.
    pub fn case_lines(&self, values: &[f64]) -> (String, Vec<(String, f64)>) {
        let mut set = Vec::new();
        let text = match &self.edit {
            Edit::Mass { node, name, group, .. } => format!(
                "[groups.{group}]                # an undamped group for added masses\n\n[[masses]]\nname = \"{name}\"\nnode = {node}\nm = {:e}\ngroup = \"{group}\"\n",
                values[0]
            ),
            Edit::Support { node, dofs, name, group, .. } => {
                let mut s = format!(
                    "# replaces the rigid support of node {node}: delete its [[supports]] entry\n[groups.{group}]\nalpha = {:e}\n\n[[springs]]\nname = \"{name}\"\nnode = {node}                      # to ground\n",
                    values[dofs.len()]
                );
                for (d, v) in dofs.iter().zip(values) {
                    s.push_str(&format!("{} = {v:e}\n", ["kx", "ky", "kr"][d.index()]));
                }
                s.push_str(&format!("group = \"{group}\"\n"));
                s
            }
            Edit::NewJoint { node, elements, name, group, .. } => format!(
                "[groups.{group}]\nalpha = {:e}\n\n[[joints]]\nname = \"{name}\"\nnode = {node}\nelements = {elements:?}\nkr = {:e}\ngroup = \"{group}\"\n",
                values[1], values[0]
            ),
            Edit::Set => {
                let params = self.parameters_in(&self.part).expect("resolved when the candidate was made");
                for (p, &v) in params.iter().zip(values) {
                    for &q in &p.quantities {
                        set.push((self.part.quantity_name(q).to_string(), v));
                    }
                }
                String::new()
            }
            Edit::Region { first, last, group, viscous } => {
                let mu = if *viscous { String::new() } else { format!("mu = {:e}\n", values[1]) };
                format!(
                    "[groups.{}]\nalpha = {:e}\nbeta = {:e}\n{mu}\n[[assign]]\nelements = \"{first}..{last}\"\ngroup = \"{}\"\n",
                    group.name, values[0], group.beta, group.name
                )
            }
        };
        (text, set)
    }

    /// The first plausibility problem of the given values, if any.
    pub fn implausible(&self, values: &[f64]) -> Option<String> {
        self.parameters.iter().zip(values).zip(&self.plausible).find_map(|((name, &v), &(lo, hi, why))| {
            (v < lo || v > hi).then(|| format!("{name} = {v:.4e} is not plausible: {why}"))
        })
    }

    /// True when this candidate acts at or next to the given nodes or
    /// elements (one element or node of slack).
    pub fn near(&self, model: &Model, nodes: &[u32], elements: &[u32]) -> bool {
        let neighbour_nodes: Vec<u32> = nodes
            .iter()
            .flat_map(|&n| {
                let mut v = vec![n];
                for i in model.beams_at(NodeId(n)) {
                    v.extend(model.beams()[i].nodes.map(|x| x.0));
                }
                v
            })
            .collect();
        let neighbour_elements: Vec<u32> = elements
            .iter()
            .flat_map(|&e| {
                let mut v = vec![e];
                if let Some(i) = model.beam_index(ElementId(e)) {
                    for n in model.beams()[i].nodes {
                        v.extend(model.beams_at(n).into_iter().map(|j| model.beams()[j].id.0));
                    }
                }
                v
            })
            .collect();
        self.nodes.iter().any(|n| neighbour_nodes.contains(n))
            || self.elements.iter().any(|e| neighbour_elements.contains(e))
            || self
                .nodes
                .iter()
                .any(|&n| model.beams_at(NodeId(n)).into_iter().any(|i| elements.contains(&model.beams()[i].id.0)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::{Assembly, samples};

    /// Two members meeting at a right angle at node 3, clamped at node 1.
    fn l_frame() -> Model {
        let mut m = Model::new("L-frame");
        let g = m.add_group(Group::new("frame").rayleigh(1e-5, 0.5)).unwrap();
        let steel = m.add_material("steel", 2.1e11, 7850.0).unwrap();
        let sec = m.add_section(fe_model::Section::rectangle("bar", 0.02, 0.02)).unwrap();
        for (id, x, y) in [(1, 0.0, 0.0), (2, 0.0, 0.3), (3, 0.0, 0.6), (4, 0.25, 0.6), (5, 0.5, 0.6)] {
            m.add_node(id, x, y).unwrap();
        }
        for (id, a, b) in [(1, 1, 2), (2, 2, 3), (3, 3, 4), (4, 4, 5)] {
            m.add_beam(id, [a, b], steel, sec, g).unwrap();
        }
        m.add_support(1, &Dof::ALL).unwrap();
        m
    }

    /// Every candidate's change applies to the whole model, which still
    /// assembles (a candidate carries no whole model that could be checked
    /// beforehand), and its parameters start at the same values there as in
    /// its part.
    #[test]
    fn every_candidate_applies_to_the_whole_model() {
        for model in [samples::frame_grid(2, 2, 3), samples::frame_with_joint(), samples::cantilever(6), l_frame()] {
            let all = generate(&model, &CandidateOptions { per_element_limit: 8, ..CandidateOptions::default() });
            assert!(all.iter().any(|c| c.kind == EffectKind::FlexibleSupport));
            // a change that fails on its part drops its candidate: none may
            let new_joints = all.iter().filter(|c| matches!(c.edit, Edit::NewJoint { .. })).count();
            let corners = model
                .nodes()
                .iter()
                .filter(|n| {
                    let at = model.beams_at(n.id);
                    at.len() == 2 && {
                        let (_, c0, s0) = model.beam_geometry(at[0]);
                        let (_, c1, s1) = model.beam_geometry(at[1]);
                        (c0 * c1 + s0 * s1).abs() < 0.5
                    }
                })
                .count();
            assert!(new_joints >= corners, "{new_joints} new joints for {corners} corners in {}", model.title);
            for c in &all {
                let whole = c.model(&model).unwrap();
                assert!(Assembly::new(&whole).is_ok(), "{} breaks the model", c.description);
                let (pw, pp) = (c.parameters_in(&whole).unwrap(), c.parameters_in(c.part()).unwrap());
                for (w, p) in pw.iter().zip(&pp) {
                    assert_eq!(whole.get(w.quantities[0]), c.part().get(p.quantities[0]), "{}", w.name);
                }
            }
        }
    }
}
