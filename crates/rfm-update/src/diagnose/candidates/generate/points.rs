//! The candidates at a node: a flexible, lossy support in place of a rigid
//! one, a spring to ground at a free node of an imported model, a flexible,
//! lossy joint (at a corner or in line), a lumped mass, and the joints the
//! model already has, as modelled.

use std::collections::{HashMap, HashSet};

use fe_model::{Dof, PerDof};

use super::{Ctx, Spec, ids, unique_name};
use crate::diagnose::candidates::edit::Edit;
use crate::diagnose::candidates::{EffectKind, Fitted, Head, Role};

/// The stiffness in DOF `d` of spring `name` as a fitted parameter, searched
/// from 1e-6 to 1e4 times `reference` (the stiffness of the members there).
fn spring(ctx: &Ctx<'_>, name: &str, d: Dof, reference: f64) -> Fitted {
    Fitted {
        name: format!("spring.{name}.{}", ctx.dim.spring_key(d)),
        role: Role::Spring(d),
        bounds: Some((1e-6 * reference, 1e4 * reference)),
        // a spring far stiffer than the member is as good as rigid, not implausible
        plausible: (0.0, f64::INFINITY, ""),
    }
}

/// The flexible, lossy support candidates of a supported node: every fixed
/// DOF that the structure there gives stiffness released onto a ground
/// spring, viscous and non-viscous. (At a node of an imported solid, the
/// rotations are held because nothing gives them stiffness: they stay
/// held. A node whose rows the export left out has no stiffness to compete
/// with at all, and no candidate: the matrices do not say how it is held.)
pub(super) fn supports(ctx: &Ctx<'_>, node: u32) -> Vec<Spec> {
    let model = ctx.model;
    let mut fixed: Vec<Dof> =
        model.supports().iter().filter(|s| s.node.0 == node).flat_map(|s| s.dofs.iter().copied()).collect();
    fixed.sort();
    fixed.dedup();
    let kref = ctx.local_stiffness(node);
    let released: Vec<Dof> = fixed.iter().copied().filter(|&d| kref[d] > 0.0).collect();
    if released.is_empty() {
        return Vec::new();
    }
    let mut out = Vec::new();
    for non_viscous in [false, true] {
        let name = unique_name(model, &format!("support_{node}"));
        let mut k = PerDof::default();
        for &d in &released {
            k[d] = 100.0 * kref[d];
        }
        out.push(support_spec(ctx, node, name, (fixed.clone(), released.clone()), (k, &kref), non_viscous));
    }
    out
}

/// The candidate of ground springs `k` at `node` in the DOFs `released` of
/// those `fixed` (none: springs where nothing held it), each fitted from its
/// reference stiffness in `kref`, in a damping group of their own.
fn support_spec(
    ctx: &Ctx<'_>,
    node: u32,
    name: String,
    (fixed, released): (Vec<Dof>, Vec<Dof>),
    (k, kref): (PerDof, &PerDof),
    non_viscous: bool,
) -> Spec {
    let mut fitted: Vec<Fitted> = released.iter().map(|&d| spring(ctx, &name, d, kref[d])).collect();
    fitted.extend(ctx.group_damping(&name, non_viscous));
    let edit = Edit::Support {
        node,
        fixed,
        released: released.clone(),
        group: ctx.damping_group(&name, non_viscous),
        name,
        k,
        dim: ctx.dim,
        per_direction: false,
    };
    let head = Head {
        kind: EffectKind::FlexibleSupport,
        description: edit.describe(EffectKind::FlexibleSupport),
        nodes: vec![node],
        elements: Vec::new(),
        dofs: released,
        // the released DOFs enter every element at the node
        part_nodes: ctx.ring(node),
    };
    (head, edit, fitted)
}

/// A spring to ground at a node of an imported model that nothing holds in
/// some translation (an unmodelled support, mount or contact), in the
/// translations the matrices give stiffness, viscous: one of the effects
/// rfm can propose without element geometry. It starts soft (a hundredth
/// of the stiffness there), as the nominal model has none.
pub(super) fn ground_spring(ctx: &Ctx<'_>, node: u32) -> Option<Spec> {
    let model = ctx.model;
    let held: Vec<Dof> =
        model.supports().iter().filter(|s| s.node.0 == node).flat_map(|s| s.dofs.iter().copied()).collect();
    let kref = ctx.local_stiffness(node);
    let sprung: Vec<Dof> =
        ctx.dim.translations().iter().copied().filter(|d| !held.contains(d) && kref[*d] > 0.0).collect();
    if sprung.is_empty() {
        return None;
    }
    let name = unique_name(model, &format!("ground_{node}"));
    let mut k = PerDof::default();
    for &d in &sprung {
        k[d] = 1e-2 * kref[d];
    }
    // a support with nothing fixed before: the springs are all it adds
    Some(support_spec(ctx, node, name, (Vec::new(), sprung), (k, &kref), false))
}

/// The nodes of an imported model's stiffness matrices (where a spring to
/// ground is a candidate), in id order.
pub(super) fn imported_stiffness_nodes(ctx: &Ctx<'_>) -> Vec<u32> {
    let mut nodes: Vec<u32> = ctx
        .model
        .imported()
        .iter()
        .filter(|b| b.kind == fe_model::imported::ImportedKind::Stiffness)
        .flat_map(|b| b.dofs.iter().map(|r| r.node.0))
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}

/// A flexible, lossy joint detaching `beams` from `node`: rotational
/// springs (and translational springs when `translational`), viscous or not.
pub(super) fn joint(
    ctx: &Ctx<'_>,
    node: u32,
    beams: &[usize],
    in_line: bool,
    translational: bool,
    non_viscous: bool,
) -> Spec {
    let model = ctx.model;
    let elements = ids(model, beams);
    let name = unique_name(model, &format!("joint_{node}_{}", elements[0]));
    let kref = ctx.local_stiffness(node);
    let sprung: Vec<Dof> = if translational { ctx.dim.dofs().to_vec() } else { ctx.dim.rotations().to_vec() };
    let mut k = PerDof::default();
    let mut fitted = Vec::new();
    for &d in &sprung {
        let r = kref[d].max(f64::MIN_POSITIVE);
        k[d] = 100.0 * r;
        fitted.push(spring(ctx, &name, d, r));
    }
    fitted.extend(ctx.group_damping(&name, non_viscous));
    let edit = Edit::Joint {
        node,
        elements: elements.clone(),
        new_node: ctx.new_node,
        in_line,
        name: name.clone(),
        group: ctx.damping_group(&name, non_viscous),
        k,
        sprung: sprung.clone(),
        dim: ctx.dim,
        per_direction: false,
    };
    let head = Head {
        kind: EffectKind::FlexibleJoint,
        description: edit.describe(EffectKind::FlexibleJoint),
        nodes: vec![node],
        elements,
        dofs: sprung,
        // every element at the node: splitting it checks that one stays
        part_nodes: ctx.ring(node),
    };
    (head, edit, fitted)
}

/// A lumped mass at a node, with a rotary inertia when `inertia`.
pub(super) fn mass(ctx: &Ctx<'_>, node: u32, inertia: bool) -> Spec {
    let model = ctx.model;
    let name = unique_name(model, &format!("mass_{node}"));
    let group = unique_name(model, "added_masses");
    let m0 = 1e-3 * ctx.total_mass;
    // a radius of gyration of a hundredth of the structure to start
    let j0 = if inertia { m0 * (0.01 * ctx.size).powi(2) } else { 0.0 };
    let mut fitted = vec![Fitted {
        name: format!("mass.{name}.m"),
        role: Role::Mass,
        bounds: Some((1e-7 * ctx.total_mass, 10.0 * ctx.total_mass)),
        plausible: (0.0, 0.25 * ctx.total_mass, "more than a quarter of the structure's mass"),
    }];
    let mut dofs = ctx.dim.translations().to_vec();
    if inertia {
        let j_scale = ctx.total_mass * ctx.size * ctx.size;
        fitted.push(Fitted {
            name: format!("mass.{name}.j"),
            role: Role::Inertia,
            bounds: Some((1e-12 * j_scale, 10.0 * j_scale)),
            plausible: (
                0.0,
                0.25 * ctx.total_mass * (0.1 * ctx.size).powi(2),
                "a quarter of the structure's mass at a tenth of its size",
            ),
        });
        dofs.extend(ctx.dim.rotations());
    }
    let edit = Edit::Mass { node, name, group, m: m0, j: j0, dim: ctx.dim };
    let head = Head {
        kind: EffectKind::LumpedMass,
        description: edit.describe(EffectKind::LumpedMass),
        nodes: vec![node],
        elements: Vec::new(),
        dofs,
        part_nodes: vec![node],
    };
    (head, edit, fitted)
}

/// The existing joint springs, with their stiffness and damping as modelled.
pub(super) fn existing_joints(ctx: &Ctx<'_>) -> Vec<Spec> {
    let model = ctx.model;
    let mut out = Vec::new();
    for sp in model.springs() {
        let Some(b) = sp.b else { continue };
        let kref = ctx.local_stiffness(sp.a.0);
        let mut fitted: Vec<Fitted> =
            sp.k.non_zero(ctx.dim.dofs()).into_iter().map(|d| spring(ctx, &sp.name, d, kref[d].max(sp.k[d]))).collect();
        let g = &model.groups()[sp.group];
        let group_only_this = model.springs().iter().filter(|o| o.group == sp.group).count() == 1
            && model.beams().iter().all(|o| o.group != sp.group)
            && model.masses().iter().all(|o| o.group != sp.group);
        if group_only_this && g.alpha > 0.0 {
            fitted.extend(ctx.group_damping(&g.name, g.mu.is_some()));
        }
        let head = Head {
            kind: EffectKind::FlexibleJoint,
            description: format!("joint `{}` between nodes {} and {} (as modelled)", sp.name, sp.a, b),
            nodes: vec![sp.a.0, b.0],
            elements: Vec::new(),
            dofs: sp.k.non_zero(ctx.dim.dofs()),
            part_nodes: vec![sp.a.0, b.0],
        };
        out.push((head, Edit::Set, fitted));
    }
    out
}

/// Nodes where a lumped mass is a candidate: free in some translation, on a beam.
pub(super) fn mass_nodes(ctx: &Ctx<'_>) -> Vec<u32> {
    let model = ctx.model;
    let mut fixed: HashMap<u32, usize> = HashMap::new();
    for s in model.supports() {
        *fixed.entry(s.node.0).or_default() += s.dofs.iter().filter(|d| d.is_translation()).count();
    }
    let translations = ctx.dim.translations().len();
    // nodes of imported mass matrices carry structure as a beam's do
    let imported: HashSet<u32> = model
        .imported()
        .iter()
        .filter(|b| b.kind == fe_model::imported::ImportedKind::Mass)
        .flat_map(|b| b.dofs.iter().filter(|r| r.dof.is_translation()).map(|r| r.node.0))
        .collect();
    model
        .nodes()
        .iter()
        .map(|n| n.id.0)
        .filter(|n| {
            fixed.get(n).copied().unwrap_or(0) < translations && (!ctx.at(*n).is_empty() || imported.contains(n))
        })
        .collect()
}
