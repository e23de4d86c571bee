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
//! Each candidate is the nominal model with the effect inserted at a
//! starting value that changes little (a very stiff spring, a tiny mass, a
//! factor of one), the parameters to fit, wide search bounds, and a
//! plausible range: a sensor mass of a quarter of the structure's mass, or a
//! joint stiffer than the member it connects, explains data only in a way
//! no engineer would accept, and the ranking says so.

use fe_model::{Dof, ElementId, Group, Model, NodeId, Parameter};
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

/// How a candidate is written into a case file.
#[derive(Clone, Debug)]
pub(crate) enum Edit {
    Mass { node: u32, name: String, group: String },
    Support { node: u32, dofs: Vec<Dof>, name: String, group: String },
    NewJoint { node: u32, elements: Vec<u32>, name: String, group: String },
    Set,
    Region { first: u32, last: u32, group: String, base_beta: f64, viscous: bool },
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
    /// The nominal model with the effect at its starting values.
    pub model: Model,
    /// Parameters to fit (resolved in `model`).
    pub parameters: Vec<Parameter>,
    /// Search bounds per parameter.
    pub bounds: Vec<Option<(f64, f64)>>,
    /// Plausible range per parameter, with the reason shown when outside.
    pub plausible: Vec<(f64, f64, &'static str)>,
    pub(crate) edit: Edit,
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
fn change_candidates(model: &Model, unit: &[usize]) -> Vec<Candidate> {
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
        out.push(Candidate {
            kind,
            description: format!("{} of {}", kind.label(), range_name(&ids)),
            nodes: nodes_of(model, unit),
            elements: ids.clone(),
            dofs: Vec::new(),
            model: model.clone(),
            parameters: vec![p],
            bounds: vec![Some((1e-3, 100.0))],
            plausible: vec![plaus],
            edit: Edit::Set,
        });
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
    beams.iter().flat_map(|&i| change_candidates(model, &[i])).collect()
}

/// Generates every candidate for a model; see the module docs.
pub fn generate(model: &Model, opts: &CandidateOptions) -> Vec<Candidate> {
    let mut out = Vec::new();
    let w_mid = 2.0 * std::f64::consts::PI * (opts.band_hz.0 * opts.band_hz.1).sqrt();
    let w_max = 2.0 * std::f64::consts::PI * opts.band_hz.1;
    let w_min = 2.0 * std::f64::consts::PI * opts.band_hz.0;
    let total_mass = model.total_mass();
    let alpha_start = 1e-4 / w_mid; // a loss factor of 1e-4 at mid band
    let alpha_bounds = Some((1e-9 / w_max, 10.0 / w_min));
    let alpha_plausible = (0.0, 1.0 / w_max, "a loss factor above 1 in the band");

    // flexible, lossy supports
    let supported: Vec<u32> = {
        let mut v: Vec<u32> = model.supports().iter().map(|s| s.node.0).collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    for node in supported {
        let mut m = model.clone();
        let dofs = m.remove_support(node);
        let kref = local_stiffness(model, NodeId(node));
        if dofs.is_empty() || dofs.iter().any(|d| kref[d.index()] <= 0.0) {
            continue;
        }
        let group = unique_name(&m, &format!("support_{node}"));
        let g = m.add_group(Group::new(&group).rayleigh(alpha_start, 0.0)).expect("fresh group");
        let mut k = [0.0; 3];
        for d in &dofs {
            k[d.index()] = 100.0 * kref[d.index()];
        }
        let name = group.clone();
        if m.add_spring(&name, node, None, k, g).is_err() {
            continue;
        }
        let mut parameters = Vec::new();
        let mut bounds = Vec::new();
        let mut plausible = Vec::new();
        for d in &dofs {
            let field = ["kx", "ky", "kr"][d.index()];
            parameters.push(m.parameter(&format!("spring.{name}.{field}")).expect("just added"));
            let r = kref[d.index()];
            bounds.push(Some((1e-6 * r, 1e4 * r)));
            plausible.push((0.0, 10.0 * r, "stiffer than the member it holds"));
        }
        parameters.push(m.parameter(&format!("group.{group}.alpha")).expect("just added"));
        bounds.push(alpha_bounds);
        plausible.push(alpha_plausible);
        out.push(Candidate {
            kind: EffectKind::FlexibleSupport,
            description: format!("flexible, lossy support at node {node}"),
            nodes: vec![node],
            elements: Vec::new(),
            dofs: dofs.clone(),
            model: m,
            parameters,
            bounds,
            plausible,
            edit: Edit::Support { node, dofs, name, group },
        });
    }

    // flexible, lossy joints where members meet at an angle
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
            let mut m = model.clone();
            let elements = element_ids(model, member);
            let group = unique_name(&m, &format!("joint_{}_{}", node.id, elements[0]));
            let g = m.add_group(Group::new(&group).rayleigh(alpha_start, 0.0)).expect("fresh group");
            let new_id = m.max_node_id() + 1;
            if m.split_node(node.id.0, &elements, new_id).is_err() {
                continue;
            }
            m.add_tie(node.id.0, new_id, &[Dof::Ux, Dof::Uy]).expect("both nodes exist");
            let kref = local_stiffness(model, node.id)[2];
            m.add_spring(&group, node.id.0, Some(new_id), [0.0, 0.0, 100.0 * kref], g).expect("valid spring");
            let parameters = vec![
                m.parameter(&format!("spring.{group}.kr")).expect("just added"),
                m.parameter(&format!("group.{group}.alpha")).expect("just added"),
            ];
            out.push(Candidate {
                kind: EffectKind::FlexibleJoint,
                description: format!("flexible, lossy joint at node {} ({})", node.id, range_name(&elements)),
                nodes: vec![node.id.0],
                elements: elements.clone(),
                dofs: vec![Dof::Rz],
                model: m,
                parameters,
                bounds: vec![Some((1e-6 * kref, 1e4 * kref)), alpha_bounds],
                plausible: vec![(0.0, 10.0 * kref, "stiffer than the members it joins"), alpha_plausible],
                edit: Edit::NewJoint { node: node.id.0, elements, name: group.clone(), group },
            });
        }
    }
    // existing joint springs: their stiffness and damping as modelled
    for (si, sp) in model.springs().iter().enumerate() {
        let Some(b) = sp.b else { continue };
        let mut parameters = Vec::new();
        let mut bounds = Vec::new();
        let mut plausible = Vec::new();
        let kref = local_stiffness(model, sp.a);
        for d in Dof::ALL {
            if sp.k[d.index()] > 0.0 {
                let field = ["kx", "ky", "kr"][d.index()];
                parameters.push(model.parameter(&format!("spring.{}.{field}", sp.name)).expect("exists"));
                let r = kref[d.index()].max(sp.k[d.index()]);
                bounds.push(Some((1e-6 * r, 1e4 * r)));
                plausible.push((0.0, 10.0 * r, "stiffer than the members it joins"));
            }
        }
        let g = &model.groups()[sp.group];
        let group_only_this = model.springs().iter().filter(|o| o.group == sp.group).count() == 1
            && model.beams().iter().all(|o| o.group != sp.group)
            && model.masses().iter().all(|o| o.group != sp.group);
        if group_only_this && g.alpha > 0.0 {
            parameters.push(model.parameter(&format!("group.{}.alpha", g.name)).expect("exists"));
            bounds.push(alpha_bounds);
            plausible.push(alpha_plausible);
        }
        let _ = si;
        out.push(Candidate {
            kind: EffectKind::FlexibleJoint,
            description: format!("joint `{}` between nodes {} and {} (as modelled)", sp.name, sp.a, b),
            nodes: vec![sp.a.0, b.0],
            elements: Vec::new(),
            dofs: Dof::ALL.iter().copied().filter(|d| sp.k[d.index()] > 0.0).collect(),
            model: model.clone(),
            parameters,
            bounds,
            plausible,
            edit: Edit::Set,
        });
    }

    // lumped masses at free nodes
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
        let mut m = model.clone();
        let group = unique_name(&m, "added_masses");
        let g = m.add_group(Group::new(&group)).expect("fresh group");
        let name = unique_name(&m, &format!("mass_{}", node.id));
        m.add_mass(&name, node.id.0, 1e-3 * total_mass, 0.0, g).expect("valid mass");
        out.push(Candidate {
            kind: EffectKind::LumpedMass,
            description: format!("lumped mass at node {}", node.id),
            nodes: vec![node.id.0],
            elements: Vec::new(),
            dofs: vec![Dof::Ux, Dof::Uy],
            parameters: vec![m.parameter(&format!("mass.{name}.m")).expect("just added")],
            model: m,
            bounds: vec![Some((1e-7 * total_mass, 10.0 * total_mass))],
            plausible: vec![(0.0, 0.25 * total_mass, "more than a quarter of the structure's mass")],
            edit: Edit::Mass { node: node.id.0, name, group },
        });
    }

    // stiffness and mass changes per element or per region
    let units: Vec<Vec<usize>> = if model.beams().len() <= opts.per_element_limit {
        let mut v: Vec<usize> = (0..model.beams().len()).collect();
        v.sort_by_key(|&i| model.beams()[i].id);
        v.into_iter().map(|i| vec![i]).collect()
    } else {
        regions(model, model.beams().len().div_ceil(opts.per_element_limit / 2).max(opts.region_size))
    };
    for unit in &units {
        out.extend(change_candidates(model, unit));
    }

    // damping per region
    for region in regions(model, opts.region_size) {
        let ids = element_ids(model, &region);
        let base = model.groups()[model.beams()[region[0]].group].clone();
        for viscous in [true, false] {
            let mut m = model.clone();
            let group = unique_name(&m, &format!("damping_{}_{}", ids[0], ids[ids.len() - 1]));
            let alpha0 = if base.alpha > 0.0 { base.alpha } else { alpha_start };
            let mut g = Group::new(&group).rayleigh(alpha0, base.beta);
            g.mu = if viscous { base.mu } else { Some(w_mid) };
            g.stiffness = base.stiffness;
            g.mass = base.mass;
            let gi = m.add_group(g).expect("fresh group");
            for &i in &region {
                m.set_beam_group(i, gi).expect("group exists");
            }
            let mut parameters = vec![m.parameter(&format!("group.{group}.alpha")).expect("just added")];
            let mut bounds = vec![alpha_bounds];
            let mut plausible = vec![alpha_plausible];
            if !viscous {
                parameters.push(m.parameter(&format!("group.{group}.mu")).expect("just added"));
                bounds.push(Some((1e-3 * w_min, 1e3 * w_max)));
                plausible.push((0.0, f64::INFINITY, ""));
            }
            let kind = if viscous { EffectKind::ViscousDamping } else { EffectKind::NonViscousDamping };
            out.push(Candidate {
                kind,
                description: format!("{} in {}", kind.label(), range_name(&ids)),
                nodes: nodes_of(model, &region),
                elements: ids.clone(),
                dofs: Vec::new(),
                model: m,
                parameters,
                bounds,
                plausible,
                edit: Edit::Region { first: ids[0], last: ids[ids.len() - 1], group, base_beta: base.beta, viscous },
            });
        }
    }
    out.retain(|c| fe_model::Assembly::new(&c.model).is_ok());
    out
}

impl Candidate {
    /// The case-file lines that add this effect with the given parameter
    /// values, and the `[set]` entries (quantity names and values) to merge.
    pub fn case_lines(&self, values: &[f64]) -> (String, Vec<(String, f64)>) {
        let mut set = Vec::new();
        let text = match &self.edit {
            Edit::Mass { node, name, group } => format!(
                "[groups.{group}]                # an undamped group for added masses\n\n[[masses]]\nname = \"{name}\"\nnode = {node}\nm = {:e}\ngroup = \"{group}\"\n",
                values[0]
            ),
            Edit::Support { node, dofs, name, group } => {
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
            Edit::NewJoint { node, elements, name, group } => format!(
                "[groups.{group}]\nalpha = {:e}\n\n[[joints]]\nname = \"{name}\"\nnode = {node}\nelements = {elements:?}\nkr = {:e}\ngroup = \"{group}\"\n",
                values[1], values[0]
            ),
            Edit::Set => {
                for (p, &v) in self.parameters.iter().zip(values) {
                    for &q in &p.quantities {
                        set.push((self.model.quantity_name(q).to_string(), v));
                    }
                }
                String::new()
            }
            Edit::Region { first, last, group, base_beta, viscous } => {
                let mu = if *viscous { String::new() } else { format!("mu = {:e}\n", values[1]) };
                format!(
                    "[groups.{group}]\nalpha = {:e}\nbeta = {base_beta:e}\n{mu}\n[[assign]]\nelements = \"{first}..{last}\"\ngroup = \"{group}\"\n",
                    values[0]
                )
            }
        };
        (text, set)
    }

    /// The first plausibility problem of the given values, if any.
    pub fn implausible(&self, values: &[f64]) -> Option<String> {
        self.parameters.iter().zip(values).zip(&self.plausible).find_map(|((p, &v), &(lo, hi, why))| {
            (v < lo || v > hi).then(|| format!("{} = {v:.4e} is not plausible: {why}", p.name))
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
