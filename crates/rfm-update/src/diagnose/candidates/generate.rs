//! Which candidates a model gets: a first pass over the whole model, and a
//! refinement around the leaders of a first ranking.
//!
//! Small models (up to [`CandidateOptions::per_element_limit`] elements) get
//! every window size at every offset and an in-line joint at every interior
//! node from the start. Large models get coarse windows first; the leaders'
//! surroundings are then tried with every window and in-line joint
//! ([`refine`]), as a region that explains a weakened element in part leads
//! to that element. On every model the refinement adds the fuller variants
//! of the leaders: translational springs for a joint, a rotary inertia for
//! a mass, and for a resonator a lumped mass with its rotary inertia at
//! its node (tuned above the band, a resonator acts there as a mass).
//!
//! A 3D model gets the same families in its own DOFs: supports release every
//! fixed DOF (that the structure there gives stiffness), a joint springs the three rotations (and in its fuller variant
//! the translations too), a mass acts on the three translations (its rotary
//! inertia is the same about every axis), and members are told apart by
//! their directions in space. An imported model (matrices without element
//! geometry) gets what needs none: its supports released, a spring to
//! ground at each of its free nodes, a mass at each node, and the changes of
//! each group (`imported.rs`).
//!
//! Resonators are candidates only at the frequencies the options name
//! ([`CandidateOptions::resonator_hz`]: measured modes the model lacks, and
//! the bands of broad residual the diagnosis reads): one tuned to each, at
//! every node that can move (`resonators.rs`). A shaker's armature and suspension is
//! a candidate at each drive point, and equal sensor masses at the
//! response nodes (`set_up.rs`), where the caller names them (the diagnosis
//! names the data's).

use std::collections::{HashMap, HashSet};

use fe_model::{Dimension, Group, Model, NodeId, PartIndex, PerDof};
use rayon::prelude::*;

mod points;
use points::{existing_joints, ground_spring, imported_stiffness_nodes, joint, mass, mass_nodes, supports};
mod resonators;
pub(crate) use resonators::RESONATOR_MASS_STARTS;
mod set_up;
pub(crate) mod twins;

use super::edit::Edit;
use super::{Candidate, CandidateOptions, EffectKind, Fitted, Head, Role};

/// Window lengths (elements) of stiffness, mass and damping changes.
const WINDOW_SIZES: [usize; 6] = [1, 2, 3, 4, 6, 8];

/// Most elements in the window of a change. A window of eight elements in
/// a row touches 27 equations, so its change is a cheap low-rank update of
/// the nominal model (module `local`, whose cost grows as the cube of that
/// number); a window of more than about twenty would be fitted on its own
/// model, a factorisation per line and iteration.
const MAX_WINDOW: usize = 8;

/// Elements on either side of a leader within which a large model's
/// refinement tries every window and in-line joint.
const REFINE_REACH: usize = 8;

/// Elements on either side of a leading window within which a small
/// model's refinement tries every window of its kind.
const WINDOW_REACH: usize = 3;

/// The first pass of windows on small models: (size, stride). Single
/// elements at every offset catch a local stiffness loss; longer windows at
/// a stride catch a patch in part, and the refinement finds its extent.
const FIRST_PASS_WINDOWS: [(usize, usize); 3] = [(1, 1), (3, 2), (6, 3)];

/// The kinds of change a window carries, in the order of [`window`].
const WINDOW_KINDS: [EffectKind; 4] =
    [EffectKind::StiffnessChange, EffectKind::MassChange, EffectKind::ViscousDamping, EffectKind::NonViscousDamping];

/// Two beams at a node within this angle (cosine) form one member.
const COLLINEAR: f64 = 0.985; // 10 degrees

/// A candidate before its part of the model is taken.
type Spec = (Head, Edit, Vec<Fitted>);

/// What the generators share: the model, its adjacency, and the scales of
/// starting values, bounds and plausible ranges.
struct Ctx<'a> {
    model: &'a Model,
    /// The items at each node, to cut each candidate's part.
    parts: PartIndex,
    dim: Dimension,
    /// Beams (indices) at each node id.
    beams_at: HashMap<u32, Vec<usize>>,
    /// Runs of consecutive elements (beam indices in id order) of one group.
    runs: Vec<Vec<usize>>,
    /// Run and position of each beam.
    run_of: Vec<(usize, usize)>,
    w_min: f64,
    w_mid: f64,
    w_max: f64,
    total_mass: f64,
    /// Largest extent of the structure (m), the scale of rotary inertias.
    size: f64,
    new_node: u32,
    opts: CandidateOptions,
}

impl<'a> Ctx<'a> {
    fn new(model: &'a Model, opts: &CandidateOptions) -> Self {
        let mut beams_at: HashMap<u32, Vec<usize>> = HashMap::new();
        for (i, b) in model.beams().iter().enumerate() {
            for n in b.nodes {
                beams_at.entry(n.0).or_default().push(i);
            }
        }
        let runs = runs(model);
        let mut run_of = vec![(0, 0); model.beams().len()];
        for (r, run) in runs.iter().enumerate() {
            for (p, &b) in run.iter().enumerate() {
                run_of[b] = (r, p);
            }
        }
        let extent = |c: usize| {
            let v = model.nodes().iter().map(|n| n.position()[c]);
            v.clone().fold(f64::NEG_INFINITY, f64::max) - v.fold(f64::INFINITY, f64::min)
        };
        let size = extent(0).max(extent(1)).max(extent(2)).max(1e-3);
        let two_pi = 2.0 * std::f64::consts::PI;
        Ctx {
            model,
            parts: PartIndex::new(model),
            dim: model.dimension(),
            beams_at,
            runs,
            run_of,
            w_min: two_pi * opts.band_hz.0,
            w_mid: two_pi * (opts.band_hz.0 * opts.band_hz.1).sqrt(),
            w_max: two_pi * opts.band_hz.1,
            total_mass: model.total_mass(),
            size,
            new_node: model.max_node_id() + 1,
            opts: opts.clone(),
        }
    }

    fn at(&self, node: u32) -> &[usize] {
        self.beams_at.get(&node).map_or(&[], Vec::as_slice)
    }

    fn small(&self) -> bool {
        self.model.beams().len() <= self.opts.per_element_limit
    }

    /// A loss factor of 1e-4 at mid band.
    fn alpha_start(&self) -> f64 {
        1e-4 / self.w_mid
    }

    fn alpha(&self, name: String) -> Fitted {
        Fitted {
            name,
            role: Role::Alpha,
            bounds: Some((1e-9 / self.w_max, 10.0 / self.w_min)),
            // judged with mu by `Candidate::implausible`
            plausible: (0.0, f64::INFINITY, ""),
        }
    }

    /// The damping parameters of group `group`: alpha, and mu when
    /// non-viscous.
    fn group_damping(&self, group: &str, non_viscous: bool) -> Vec<Fitted> {
        let mut fitted = vec![self.alpha(format!("group.{group}.alpha"))];
        if non_viscous {
            fitted.push(self.mu(format!("group.{group}.mu")));
        }
        fitted
    }

    fn mu(&self, name: String) -> Fitted {
        Fitted {
            name,
            role: Role::Mu,
            bounds: Some((1e-3 * self.w_min, 1e3 * self.w_max)),
            plausible: (0.0, f64::INFINITY, ""),
        }
    }

    /// A damping group of an effect's own: viscous, or non-viscous with the
    /// relaxation parameter at mid band.
    fn damping_group(&self, name: &str, non_viscous: bool) -> Group {
        let mut g = Group::new(name).rayleigh(self.alpha_start(), 0.0);
        if non_viscous {
            g.mu = Some(self.w_mid);
        }
        g
    }

    /// The nodes of the beams at `node`, of the imported blocks that couple
    /// it to others, and the node itself.
    fn ring(&self, node: u32) -> Vec<u32> {
        let mut v: Vec<u32> = self.at(node).iter().flat_map(|&i| self.model.beams()[i].nodes.map(|n| n.0)).collect();
        let coupled = self.model.imported().iter().filter(|b| b.nodes.contains(&NodeId(node)));
        v.extend(coupled.flat_map(|b| b.nodes.map(|n| n.0)));
        v.push(node);
        v.sort_unstable();
        v.dedup();
        v
    }

    /// Diagonal stiffness (for `E` and factors as modelled) of the beams at a
    /// node, per global DOF: the scale a spring at that node competes with.
    fn local_stiffness(&self, node: u32) -> PerDof {
        let m = self.model;
        let dofs = self.dim.dofs();
        let mut k = PerDof::default();
        for &i in self.at(node) {
            let b = &m.beams()[i];
            let e = m.materials()[b.material].e * b.stiffness_factor * m.groups()[b.group].stiffness;
            let [ke, ..] = fe_model::element::beam_units(m, i);
            let o = if b.nodes[0] == NodeId(node) { 0 } else { dofs.len() };
            for (p, &d) in dofs.iter().enumerate() {
                k[d] += ke[(o + p, o + p)] * e;
            }
        }
        // and the imported stiffness matrices' diagonal there
        for b in m.imported().iter().filter(|b| b.kind == fe_model::imported::ImportedKind::Stiffness) {
            let n = b.dofs.len();
            for (p, r) in b.dofs.iter().enumerate().filter(|(_, r)| r.node == NodeId(node)) {
                k[r.dof] += b.values[p * n + p] * m.groups()[b.group].stiffness;
            }
        }
        k
    }

    /// The direction of beam `i` pointing away from `node`.
    fn direction(&self, i: usize, node: u32) -> [f64; 3] {
        let (_, d) = self.model.beam_axis(i);
        if self.model.beams()[i].nodes[0] == NodeId(node) { d } else { d.map(|v| -v) }
    }

    /// The cosine of the angle between the directions of beams `a` and `b`
    /// away from `node`.
    fn cosine(&self, a: usize, b: usize, node: u32) -> f64 {
        let (p, q) = (self.direction(a, node), self.direction(b, node));
        p[0] * q[0] + p[1] * q[1] + p[2] * q[2]
    }

    /// The beams at `node` grouped by direction: collinear beams form one member.
    fn members_at(&self, node: u32) -> Vec<Vec<usize>> {
        let mut members: Vec<Vec<usize>> = Vec::new();
        for &i in self.at(node) {
            match members.iter_mut().find(|m| self.cosine(i, m[0], node).abs() > COLLINEAR) {
                Some(m) => m.push(i),
                None => members.push(vec![i]),
            }
        }
        members
    }

    /// Whether `node` is an interior node of a straight member: exactly two
    /// beams meet there, in line. Returns the beam to detach (the one of
    /// larger id).
    fn in_line(&self, node: u32) -> Option<usize> {
        let at = self.at(node);
        let [a, b] = at[..] else { return None };
        // opposite directions away from the node
        (self.cosine(a, b, node) < -COLLINEAR)
            .then(|| if self.model.beams()[a].id > self.model.beams()[b].id { a } else { b })
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

/// Runs of consecutive elements (by id) of the same group that share nodes.
fn runs(model: &Model) -> Vec<Vec<usize>> {
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
    runs
}

/// `run` cut into chunks of at most `size`, of nearly equal length.
fn tiles(run: &[usize], size: usize) -> Vec<Vec<usize>> {
    let n_chunks = run.len().div_ceil(size.max(1));
    let per = run.len().div_ceil(n_chunks.max(1)).max(1);
    run.chunks(per).map(<[usize]>::to_vec).collect()
}

/// Elements per coarse stiffness and mass window on a model with more than
/// [`CandidateOptions::per_element_limit`] elements: about half that many
/// windows, each no longer than [`MAX_WINDOW`].
fn coarse_change_size(elements: usize, opts: &CandidateOptions) -> usize {
    elements.div_ceil((opts.per_element_limit / 2).max(1)).min(MAX_WINDOW).max(opts.region_size)
}

fn ids(model: &Model, idx: &[usize]) -> Vec<u32> {
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

/// The changes of a window of consecutive elements (beam indices) of the
/// given kinds (stiffness, mass, viscous and non-viscous damping).
fn window(ctx: &Ctx<'_>, w: &[usize], kinds: &[EffectKind]) -> Vec<Spec> {
    let model = ctx.model;
    let ids = ids(model, w);
    if ids.windows(2).any(|p| p[1] != p[0] + 1) {
        return Vec::new();
    }
    let (first, last) = (ids[0], ids[ids.len() - 1]);
    let field = |f: &str| {
        if first == last { format!("element.{first}.{f}") } else { format!("element.{first}..{last}.{f}") }
    };
    let nodes = nodes_of(model, w);
    let head = |kind: EffectKind| Head {
        kind,
        description: format!("{} of {}", kind.label(), range_name(&ids)),
        nodes: nodes.clone(),
        elements: ids.clone(),
        dofs: Vec::new(),
        part_nodes: nodes.clone(),
    };
    let mut out: Vec<Spec> = vec![
        (
            head(EffectKind::StiffnessChange),
            Edit::Set,
            vec![Fitted {
                name: field("stiffness"),
                role: Role::StiffnessFactor,
                bounds: Some((1e-3, 100.0)),
                plausible: (0.05, 1.5, "a change beyond -95 % .. +50 % of the nominal stiffness"),
            }],
        ),
        (
            head(EffectKind::MassChange),
            Edit::Set,
            vec![Fitted {
                name: field("mass"),
                role: Role::MassFactor,
                bounds: Some((1e-3, 100.0)),
                plausible: (0.5, 2.0, "a change beyond -50 % .. +100 % of the nominal mass"),
            }],
        ),
    ];
    out.retain(|(h, ..)| kinds.contains(&h.kind));
    let base = &model.groups()[model.beams()[w[0]].group];
    for non_viscous in [false, true] {
        let name = unique_name(model, &format!("damping_{first}_{last}"));
        let mut g = ctx.damping_group(&name, non_viscous);
        if base.alpha > 0.0 {
            g.alpha = base.alpha;
        }
        g.beta = base.beta;
        g.stiffness = base.stiffness;
        g.mass = base.mass;
        let kind = if non_viscous { EffectKind::NonViscousDamping } else { EffectKind::ViscousDamping };
        if !kinds.contains(&kind) {
            continue;
        }
        let fitted = ctx.group_damping(&name, non_viscous);
        let mut h = head(kind);
        h.description = format!("{} in {}", kind.label(), range_name(&ids));
        out.push((h, Edit::Region { first, last, group: g }, fitted));
    }
    out
}

/// Windows of `size` elements within `range` of a run, every `stride`
/// elements, the last one flush with the end of the range.
fn strided(run: &[usize], range: std::ops::Range<usize>, size: usize, stride: usize) -> Vec<&[usize]> {
    if size > range.len() {
        return Vec::new();
    }
    let last = range.end - size;
    let mut starts: Vec<usize> = (range.start..=last).step_by(stride.max(1)).collect();
    if starts.last() != Some(&last) {
        starts.push(last);
    }
    starts.into_iter().map(|s| &run[s..s + size]).collect()
}

/// Every window of every size at every offset within `range` of a run, of
/// the given kinds.
fn all_windows(ctx: &Ctx<'_>, run: &[usize], range: std::ops::Range<usize>, kinds: &[EffectKind]) -> Vec<Spec> {
    WINDOW_SIZES
        .iter()
        .flat_map(|&size| strided(run, range.clone(), size, 1))
        .flat_map(|w| window(ctx, w, kinds))
        .collect()
}

/// Makes the candidates of `specs`, in parallel and in order: each takes its
/// part of the model.
fn build(ctx: &Ctx<'_>, specs: Vec<Spec>) -> Vec<Candidate> {
    let band = (ctx.w_min, ctx.w_max);
    specs
        .into_par_iter()
        .filter_map(|(head, edit, fitted)| {
            let mut c = Candidate::indexed(ctx.model, &ctx.parts, head, edit, fitted)?;
            c.band_rad = band;
            Some(c)
        })
        .collect()
}

/// Generates the first pass of candidates for a model; see the module docs.
pub fn generate(model: &Model, opts: &CandidateOptions) -> Vec<Candidate> {
    let ctx = Ctx::new(model, opts);
    let mut specs: Vec<Spec> = Vec::new();

    let mut supported: Vec<u32> = model.supports().iter().map(|s| s.node.0).collect();
    supported.sort_unstable();
    supported.dedup();
    for node in supported {
        specs.extend(supports(&ctx, node));
    }
    specs.extend(imported_stiffness_nodes(&ctx).into_iter().filter_map(|node| ground_spring(&ctx, node)));

    // joints where members meet at an angle: each member but the first (the
    // through-member keeps the node) detached
    for node in model.nodes() {
        let members = ctx.members_at(node.id.0);
        if members.len() < 2 {
            continue;
        }
        for member in members.iter().skip(1) {
            for non_viscous in [false, true] {
                specs.push(joint(&ctx, node.id.0, member, false, false, non_viscous));
            }
        }
    }
    // in-line joints at every interior node of a member (small models; on
    // large ones around the leaders)
    if ctx.small() {
        for node in model.nodes() {
            if let Some(b) = ctx.in_line(node.id.0) {
                for non_viscous in [false, true] {
                    specs.push(joint(&ctx, node.id.0, &[b], true, false, non_viscous));
                }
            }
        }
    }
    specs.extend(existing_joints(&ctx));

    for node in mass_nodes(&ctx) {
        specs.push(mass(&ctx, node, false));
    }
    for (group, nodes) in super::imported::imported_groups(model) {
        specs.extend(super::imported::group_changes(model, group, &nodes, |n| ctx.alpha(n), |n| ctx.mu(n)));
    }
    // resonators tuned to each extra mode; two frequencies that a
    // description cannot tell apart are one
    let mut tuned: Vec<String> = Vec::new();
    for &hz in &opts.resonator_hz {
        let shown = format!("{hz:.1}");
        if !tuned.contains(&shown) {
            tuned.push(shown);
            specs.extend(resonators::resonators(&ctx, hz));
        }
    }

    // the test's own hardware: a shaker at each drive point, the sensors' masses
    for &(node, dof) in &opts.drive_points {
        specs.extend(set_up::shaker(&ctx, node, dof));
    }
    specs.extend(set_up::sensor_masses(&ctx, &opts.sensor_nodes));

    // windows: on small models single elements at every offset and longer
    // windows at a stride (every size at every offset follows around the
    // leaders, see `refine`); coarse tiles on large models
    for run in &ctx.runs {
        if ctx.small() {
            for (size, stride) in FIRST_PASS_WINDOWS {
                for w in strided(run, 0..run.len(), size, stride) {
                    specs.extend(window(&ctx, w, &WINDOW_KINDS));
                }
            }
        } else {
            let change = coarse_change_size(model.beams().len(), opts);
            for t in tiles(run, change) {
                specs.extend(window(&ctx, &t, &WINDOW_KINDS[..2]));
            }
            for t in tiles(run, opts.region_size) {
                specs.extend(window(&ctx, &t, &WINDOW_KINDS[2..]));
            }
        }
    }
    build(&ctx, specs)
}

/// The in-line joints (viscous and non-viscous) at those of `nodes` that
/// join two collinear members.
fn in_line_joints(ctx: &Ctx<'_>, nodes: impl IntoIterator<Item = u32>) -> Vec<Spec> {
    let mut out = Vec::new();
    for node in nodes {
        if let Some(d) = ctx.in_line(node) {
            for non_viscous in [false, true] {
                out.push(joint(ctx, node, &[d], true, false, non_viscous));
            }
        }
    }
    out
}

/// Candidates around the given leaders that the first pass did not try
/// (`tried`: descriptions of the candidates already made):
///
/// - around a window: every window of its kind (damping: viscous and
///   non-viscous) of every size at every offset within reach of it;
/// - around a mass change: lumped masses, with and without rotary inertia,
///   at the nodes of its window;
/// - around a joint, support or mass: single-element stiffness and mass
///   changes of the elements at its nodes and their neighbours, and on large
///   models the in-line joints there; around a joint, every stiffness
///   window within reach as well;
/// - the fuller variants of a joint (translational springs) and a mass
///   (rotary inertia), and for a resonator a lumped mass with its rotary
///   inertia at its node.
pub(crate) fn refine(
    model: &Model,
    opts: &CandidateOptions,
    leaders: &[&Candidate],
    tried: &HashSet<String>,
) -> Vec<Candidate> {
    let ctx = Ctx::new(model, opts);
    let reach = if ctx.small() { WINDOW_REACH } else { REFINE_REACH };
    let mut specs: Vec<Spec> = Vec::new();
    for c in leaders {
        match &c.edit {
            Edit::Joint { node, elements, in_line, group, sprung, .. }
                if !sprung.iter().any(|d| d.is_translation()) =>
            {
                let beams: Vec<usize> =
                    elements.iter().filter_map(|&e| model.beam_index(fe_model::ElementId(e))).collect();
                specs.push(joint(&ctx, *node, &beams, *in_line, true, group.mu.is_some()));
            }
            Edit::Mass { node, j, .. } if *j == 0.0 => specs.push(mass(&ctx, *node, true)),
            // a resonator tuned above the band acts there as a mass at its
            // node, and where resonators lead they may stand for a lumped
            // mass with its rotary inertia, which none has (lab study,
            // trial 53: resonators at a 172 g mass's node took the first
            // places, and its fuller variant was never tried)
            Edit::Resonator { node, .. } => specs.push(mass(&ctx, *node, true)),
            _ => {}
        }
        let kinds: &[EffectKind] = match c.kind {
            EffectKind::StiffnessChange => &WINDOW_KINDS[..1],
            EffectKind::MassChange => &WINDOW_KINDS[1..2],
            EffectKind::ViscousDamping | EffectKind::NonViscousDamping => &WINDOW_KINDS[2..],
            _ => &[],
        };
        let beams: Vec<usize> = c.elements.iter().filter_map(|&e| model.beam_index(fe_model::ElementId(e))).collect();
        if !kinds.is_empty() && !beams.is_empty() {
            // every window of the leader's kind within reach of it
            let (r, _) = ctx.run_of[beams[0]];
            let pos: Vec<usize> = beams.iter().map(|&b| ctx.run_of[b].1).collect();
            let (lo, hi) = (pos.iter().min().expect("some"), pos.iter().max().expect("some"));
            let run = &ctx.runs[r];
            let range = lo.saturating_sub(reach)..(hi + reach + 1).min(run.len());
            specs.extend(all_windows(&ctx, run, range, kinds));
            // a stiffness loss and a mass gain over the same elements both
            // lower the frequencies there, and on a large model with few
            // sensors the first pass can lead with either: there the other
            // kind is tried too, over the windows within one element of the
            // leader's (the 100k-DOF bench frame led with a mass change over
            // its hidden stiffness loss); a small model's first pass has
            // tried both at every element
            let other: &[EffectKind] = match c.kind {
                EffectKind::StiffnessChange => &WINDOW_KINDS[1..2],
                EffectKind::MassChange => &WINDOW_KINDS[..1],
                _ => &[],
            };
            if !ctx.small() && !other.is_empty() {
                let near = lo.saturating_sub(1)..(hi + 2).min(run.len());
                specs.extend(all_windows(&ctx, run, near, other));
            }
            // a mass spread over a window may be a lumped mass (with its
            // rotary inertia) at one of its nodes
            if c.kind == EffectKind::MassChange {
                for n in nodes_of(model, &beams) {
                    specs.push(mass(&ctx, n, false));
                    specs.push(mass(&ctx, n, true));
                }
            }
            // a lossy joint in a large model first shows as a stiffness loss
            // around it (small models try every in-line joint at once)
            if !ctx.small() && c.kind == EffectKind::StiffnessChange {
                for &b in &beams {
                    specs.extend(in_line_joints(&ctx, model.beams()[b].nodes.map(|n| n.0)));
                }
            }
            continue;
        }
        // around a point effect: single elements nearby, and in-line joints;
        // around a joint, every stiffness window within reach (a stiffness
        // loss over a few elements and a rotational spring at their middle
        // look alike, and the first pass tries long windows only at strides)
        for &n in &c.nodes {
            for &b in ctx.at(n) {
                let (r, p) = ctx.run_of[b];
                let run = &ctx.runs[r];
                let range = p.saturating_sub(1)..(p + 2).min(run.len());
                specs.extend(
                    strided(run, range.clone(), 1, 1).into_iter().flat_map(|w| window(&ctx, w, &WINDOW_KINDS[..2])),
                );
                if c.kind == EffectKind::FlexibleJoint {
                    let around = p.saturating_sub(reach)..(p + reach + 1).min(run.len());
                    specs.extend(all_windows(&ctx, run, around, &WINDOW_KINDS[..1]));
                }
                if !ctx.small() {
                    for &b in &run[range] {
                        specs.extend(in_line_joints(&ctx, model.beams()[b].nodes.map(|n| n.0)));
                    }
                }
            }
        }
    }
    let mut seen = tried.clone();
    specs.retain(|(h, ..)| seen.insert(h.description.clone()));
    build(&ctx, specs)
}
