//! The model a case file describes: materials, sections, groups, nodes,
//! lines of elements, beams, springs, joints, masses, supports, ties, group
//! assignments, resonators and shakers, built in that order through the checked
//! `Model::add_*` methods, each error placed at the entry that caused it.

use std::ops::Range;

use toml::Spanned;

use super::Ctx;
use super::lookup::{group_ref, material_ref, section_ref};
use super::raw::{
    RawCase, RawGroup, RawJoint, RawLine, RawMass, RawMaterial, RawResonator, RawSection, RawShaker, RawSpring,
};
use crate::dof::{Dimension, Dof, PerDof};
use crate::error::CaseError;
use crate::model::{Group, Model, NodeId, Section};

/// Most elements one `[[lines]]` entry may generate.
pub const MAX_LINE_ELEMENTS: u32 = 100_000;

pub(super) fn raw_group(ctx: &Ctx<'_>, name: &str, g: &Spanned<RawGroup>) -> Result<Group, CaseError> {
    let r = g.get_ref();
    if let Some(mu) = r.mu
        && !(mu > 0.0)
    {
        return Err(ctx.err(
            g.span(),
            format!(
                "group `{name}`: mu must be positive (use `inf` or omit it for viscous damping), got {}",
                crate::show(mu)
            ),
        ));
    }
    Ok(Group {
        name: name.into(),
        alpha: r.alpha,
        beta: r.beta,
        mu: r.mu.filter(|m| m.is_finite()),
        stiffness: r.stiffness,
        mass: r.mass,
        damping: r.damping,
    })
}

/// The dimension `[model] dimension` names (2, the default, or 3).
pub(super) fn dimension(ctx: &Ctx<'_>, raw: &RawCase) -> Result<Dimension, CaseError> {
    let Some(d) = raw.model.as_ref().and_then(|m| m.get_ref().dimension.as_ref()) else {
        return Ok(Dimension::Planar);
    };
    Dimension::from_number(*d.get_ref()).ok_or_else(|| {
        ctx.err(
            d.span(),
            format!("`dimension` is 2 (a frame in the x-y plane) or 3 (a frame in space), not {}", d.get_ref()),
        )
    })
}

fn add_material(ctx: &Ctx<'_>, model: &mut Model, name: &str, m: &Spanned<RawMaterial>) -> Result<(), CaseError> {
    let r = m.get_ref();
    let i = model.add_material(name, r.e, r.rho).map_err(|e| ctx.model_err(m.span(), e))?;
    let nu = match (&r.nu, &r.g) {
        (None, None) => return Ok(()),
        (Some(nu), None) => nu.clone(),
        (None, Some(g)) => {
            // an isotropic material: nu from E and G
            if !(*g.get_ref() > 0.0 && g.get_ref().is_finite()) {
                return Err(ctx.err(g.span(), format!("material `{name}`: G must be positive and finite")));
            }
            Spanned::new(g.span(), r.e / (2.0 * g.get_ref()) - 1.0)
        }
        (Some(nu), Some(_)) => {
            return Err(ctx.err(nu.span(), format!("material `{name}`: give `nu` or `G`, not both")));
        }
    };
    model.set_poisson(i, *nu.get_ref()).map_err(|e| ctx.model_err(nu.span(), e))
}

fn section(ctx: &Ctx<'_>, dim: Dimension, name: &str, s: &Spanned<RawSection>) -> Result<Section, CaseError> {
    let r = s.get_ref();
    let given_3d = r.iy.is_some() || r.iz.is_some() || r.torsion.is_some();
    match dim {
        Dimension::Planar if given_3d => {
            return Err(ctx.err(
                s.span(),
                format!(
                    "section `{name}`: Iy, Iz and J describe the section of a beam in space; a planar one has A and I \
                     (or set `[model] dimension = 3`)"
                ),
            ));
        }
        Dimension::Spatial if r.inertia.is_some() => {
            return Err(ctx.err(
                s.span(),
                format!("section `{name}`: a beam in space bends about two axes; give Iy, Iz and J instead of I"),
            ));
        }
        _ => {}
    }
    Ok(match (r.area, r.inertia, r.iy, r.iz, r.torsion, r.b, r.h, r.od, r.id) {
        (Some(a), Some(i), None, None, None, None, None, None, None) => Section::planar(name, a, i),
        (Some(a), None, Some(iy), Some(iz), Some(j), None, None, None, None) => Section::spatial(name, a, iy, iz, j),
        (None, None, None, None, None, Some(b), Some(h), None, None) => Section::rectangle(name, b, h),
        (None, None, None, None, None, None, None, Some(od), id) => {
            let id = id.unwrap_or(0.0);
            if !(id >= 0.0 && id < od) {
                return Err(ctx.err(s.span(), format!("section `{name}`: need 0 <= id < od, got od = {od}, id = {id}")));
            }
            Section::tube(name, od, id)
        }
        _ => {
            let own = if dim == Dimension::Planar { "A and I" } else { "A, Iy, Iz and J" };
            return Err(ctx.err(
                s.span(),
                format!("section `{name}`: give either {own}, or b and h (rectangle), or od and id (tube)"),
            ));
        }
    })
}

pub(super) fn build_model(ctx: &Ctx<'_>, raw: &RawCase, model: &mut Model) -> Result<(), CaseError> {
    let dim = model.dimension();
    for (name, m) in &raw.materials {
        add_material(ctx, model, name, m)?;
    }
    for (name, s) in &raw.sections {
        let section = section(ctx, dim, name, s)?;
        model.add_section(section).map_err(|e| ctx.model_err(s.span(), e))?;
    }
    for (name, g) in &raw.groups {
        let group = raw_group(ctx, name, g)?;
        model.add_group(group).map_err(|e| ctx.model_err(g.span(), e))?;
    }
    for n in &raw.nodes {
        let r = n.get_ref();
        if dim == Dimension::Planar && r.with_z {
            return Err(ctx.err(
                n.span(),
                format!(
                    "node {} has a z coordinate, and a planar model's nodes are [id, x, y]; a frame in space needs \
                     `[model] dimension = 3`",
                    r.id
                ),
            ));
        }
        model.add_node_at(r.id, r.at).map_err(|e| ctx.model_err(n.span(), e))?;
    }
    let (listed, node_file) = match &raw.imported {
        Some(imported) => super::imported::add_imported(ctx, imported, model)?,
        None => Default::default(),
    };
    for line in &raw.lines {
        add_line(ctx, model, line)?;
    }
    for b in &raw.beams {
        let r = b.get_ref();
        let mat = material_ref(ctx, model, &r.material)?;
        let sec = section_ref(ctx, model, &r.section)?;
        let g = group_ref(ctx, model, &r.group)?;
        let i = model.add_beam(r.id, r.nodes, mat, sec, g).map_err(|e| ctx.model_err(b.span(), e))?;
        model.set_added_mass(i, r.added_mass).map_err(|e| ctx.model_err(b.span(), e))?;
        orient(ctx, model, i, &r.orientation, &r.angle)?;
    }
    for s in &raw.springs {
        add_spring(ctx, model, s)?;
    }
    // joints before masses, supports and ties: a joint makes a node (its
    // `new_node`, or the next free id) that those may name, as a case
    // written by `rfm diagnose --apply` does for a mass at a joint
    add_joints(ctx, model, &raw.joints)?;
    for m in &raw.masses {
        add_mass(ctx, model, m)?;
    }
    for s in &raw.supports {
        let r = s.get_ref();
        let dofs = match &r.dofs {
            None => dim.dofs().to_vec(),
            Some(list) => parse_dofs(ctx, dim, list)?,
        };
        model.add_support(r.node, &dofs).map_err(|e| ctx.model_err(s.span(), e))?;
    }
    for t in &raw.ties {
        let r = t.get_ref();
        let dofs = parse_dofs(ctx, dim, &r.dofs)?;
        model.add_tie(r.nodes[0], r.nodes[1], &dofs).map_err(|e| ctx.model_err(t.span(), e))?;
    }
    for a in &raw.assign {
        let r = a.get_ref();
        let g = group_ref(ctx, model, &r.group)?;
        let text = r.elements.get_ref();
        let (first, last) = match text.split_once("..") {
            Some((x, y)) => (x.trim().parse::<u32>(), y.trim().parse::<u32>()),
            None => (text.trim().parse::<u32>(), text.trim().parse::<u32>()),
        };
        let (Ok(first), Ok(last)) = (first, last) else {
            return Err(ctx.err(r.elements.span(), format!("`{text}` is not an element id or a range first..last")));
        };
        if last < first {
            return Err(ctx.err(r.elements.span(), format!("the range `{text}` is empty")));
        }
        for id in first..=last {
            let i = model
                .beam_index(crate::model::ElementId(id))
                .ok_or_else(|| ctx.err(r.elements.span(), format!("element {id} does not exist")))?;
            model.set_beam_group(i, g).map_err(|e| ctx.model_err(a.span(), e))?;
        }
    }
    if let Some(imported) = &raw.imported {
        super::imported::hold_unlisted(model, &listed, &node_file).map_err(|e| ctx.model_err(imported.span(), e))?;
    }
    // resonators last: the node each makes (by default the largest id + 1)
    // then shifts no id that a line or joint without its own takes
    for r in &raw.resonators {
        add_resonator(ctx, model, r)?;
    }
    for s in &raw.shakers {
        add_shaker(ctx, model, s)?;
    }
    if model.beams.is_empty() && model.springs.is_empty() && model.imported().is_empty() {
        return Err(ctx.whole("the case defines no beams, lines, springs or imported matrices"));
    }
    Ok(())
}

/// Orients a 3D beam's section as its entry (or its line) says; the angle
/// is written in degrees.
fn orient(
    ctx: &Ctx<'_>,
    model: &mut Model,
    beam: usize,
    orientation: &Option<Spanned<[f64; 3]>>,
    angle: &Option<Spanned<f64>>,
) -> Result<(), CaseError> {
    if orientation.is_none() && angle.is_none() {
        return Ok(());
    }
    let span =
        orientation.as_ref().map(Spanned::span).or_else(|| angle.as_ref().map(Spanned::span)).expect("one given");
    let reference = orientation.as_ref().map(|o| *o.get_ref());
    let degrees = angle.as_ref().map_or(0.0, |a| *a.get_ref());
    model.orient_beam(beam, reference, degrees.to_radians()).map_err(|e| ctx.model_err(span, e))
}

/// DOF names of a support or tie, each checked against the model's
/// dimension where it is written.
fn parse_dofs(ctx: &Ctx<'_>, dim: Dimension, list: &[Spanned<String>]) -> Result<Vec<Dof>, CaseError> {
    list.iter()
        .map(|d| {
            if d.get_ref() == "all" {
                let names: Vec<String> = dim.dofs().iter().map(|d| format!("\"{d}\"")).collect();
                return Err(ctx.err(d.span(), format!("write all DOFs as [{}] or omit `dofs`", names.join(", "))));
            }
            let dof = d.get_ref().parse::<Dof>().map_err(|e| ctx.err(d.span(), e))?;
            dim.check(dof).map_err(|e| ctx.err(d.span(), e))?;
            Ok(dof)
        })
        .collect()
}

/// The stiffnesses a spring or joint writes, by DOF, each key checked
/// against the model's dimension where it is written.
fn stiffnesses(
    ctx: &Ctx<'_>,
    dim: Dimension,
    what: &str,
    written: [(&'static str, Option<&Spanned<f64>>); 7],
) -> Result<Vec<(Dof, f64)>, CaseError> {
    let mut out = Vec::new();
    for (key, v) in written {
        let Some(v) = v else { continue };
        let Some(d) = dim.spring_dof(key) else {
            let message = match dim {
                Dimension::Planar => format!(
                    "{what}: `{key}` is a stiffness of a frame in space; a planar model's are kx, ky and kr (or set \
                     `[model] dimension = 3`)"
                ),
                Dimension::Spatial => format!(
                    "{what}: a 3D model's rotational stiffnesses are krx, kry and krz (`{key}` does not say about \
                     which axis)"
                ),
            };
            return Err(ctx.err(v.span(), message));
        };
        out.push((d, *v.get_ref()));
    }
    Ok(out)
}

pub(super) fn add_spring(ctx: &Ctx<'_>, model: &mut Model, s: &Spanned<RawSpring>) -> Result<usize, CaseError> {
    let r = s.get_ref();
    let (a, b) = match (r.nodes, r.node) {
        (Some([a, b]), None) => (a, Some(b)),
        (None, Some(a)) => (a, None),
        _ => {
            return Err(ctx.err(
                s.span(),
                format!("spring `{}`: give `nodes = [a, b]` (between two nodes) or `node = a` (to ground)", r.name),
            ));
        }
    };
    let mut k = PerDof::default();
    for (d, v) in stiffnesses(ctx, model.dimension(), &format!("spring `{}`", r.name), r.stiffnesses())? {
        k[d] = v;
    }
    let g = group_ref(ctx, model, &r.group)?;
    let i = model.add_spring(&r.name, a, b, k, g).map_err(|e| ctx.model_err(s.span(), e))?;
    super::spring_axes::orient(ctx, model, i, r)?;
    Ok(i)
}

/// The joints of a case: each node is split, the listed elements move to a
/// new coincident node, a spring joins the pair in the DOFs given a
/// stiffness (in a planar model always kr, and kx, ky when given) and the
/// other DOFs are tied. Entries with the same `node` and `new_node` are one
/// joint whose springs are in groups of their own (a joint with a different
/// loss in each direction): the node is split once, each entry adds its
/// spring, and the DOFs none of them springs are tied.
pub(super) fn add_joints(ctx: &Ctx<'_>, model: &mut Model, joints: &[Spanned<RawJoint>]) -> Result<(), CaseError> {
    let mut done = vec![false; joints.len()];
    for i in 0..joints.len() {
        if done[i] {
            continue;
        }
        let r = joints[i].get_ref();
        let same: Vec<usize> = (i..joints.len())
            .filter(|&k| {
                let o = joints[k].get_ref();
                k == i || (r.new_node.is_some() && o.node == r.node && o.new_node == r.new_node)
            })
            .collect();
        for &k in &same {
            done[k] = true;
        }
        add_joint(ctx, model, &same.iter().map(|&k| &joints[k]).collect::<Vec<_>>())?;
    }
    Ok(())
}

/// One joint, written as one entry or as several on the same node pair
/// (see [`add_joints`]).
fn add_joint(ctx: &Ctx<'_>, model: &mut Model, entries: &[&Spanned<RawJoint>]) -> Result<(), CaseError> {
    let (j, r) = (entries[0], entries[0].get_ref());
    let dim = model.dimension();
    let what = |o: &RawJoint| format!("joint `{}`", o.name);
    let mut given = Vec::new();
    for &e in entries {
        given.push(stiffnesses(ctx, dim, &what(e.get_ref()), e.get_ref().stiffnesses())?);
    }
    if dim == Dimension::Planar && !given.iter().flatten().any(|&(d, _)| d == Dof::Rz) {
        let whose = if entries.len() == 1 { what(r) } else { format!("the joint at node {}", r.node) };
        return Err(ctx.err(j.span(), format!("{whose} needs `kr`, the rotational stiffness of the joint")));
    }
    let mut springs: Vec<(&Spanned<RawJoint>, PerDof, usize)> = Vec::new();
    let mut sprung: Vec<Dof> = Vec::new();
    for (&e, given) in entries.iter().zip(given) {
        let o = e.get_ref();
        if given.is_empty() {
            return Err(ctx.err(
                e.span(),
                format!("{} needs a stiffness in at least one DOF (krx, kry, krz for a rotational joint)", what(o)),
            ));
        }
        if o.elements != r.elements {
            return Err(ctx.err(
                e.span(),
                format!(
                    "{} is on the node pair {} and {} of joint `{}`, which detaches elements {:?}: an entry on the \
                     same pair lists the same elements",
                    what(o),
                    r.node,
                    r.new_node.unwrap_or_default(),
                    r.name,
                    r.elements
                ),
            ));
        }
        let mut k = PerDof::default();
        for (d, v) in given {
            if sprung.contains(&d) {
                return Err(ctx.err(
                    e.span(),
                    format!(
                        "{}: `{}` of the joint at node {} is given by an earlier entry on the same node pair",
                        what(o),
                        dim.spring_key(d),
                        r.node
                    ),
                ));
            }
            sprung.push(d);
            k[d] = v;
        }
        springs.push((e, k, group_ref(ctx, model, &o.group)?));
    }
    let new_id = match r.new_node {
        Some(id) => id,
        None => model
            .max_node_id()
            .checked_add(1)
            .ok_or_else(|| ctx.err(j.span(), format!("joint `{}`: no node id left above {}", r.name, u32::MAX)))?,
    };
    model.split_node(r.node, &r.elements, new_id).map_err(|e| ctx.model_err(j.span(), e))?;
    let tied: Vec<Dof> = dim.dofs().iter().copied().filter(|d| !sprung.contains(d)).collect();
    if !tied.is_empty() {
        model.add_tie(r.node, new_id, &tied).map_err(|e| ctx.model_err(j.span(), e))?;
    }
    for (e, k, g) in springs {
        model.add_spring(&e.get_ref().name, r.node, Some(new_id), k, g).map_err(|err| ctx.model_err(e.span(), err))?;
    }
    Ok(())
}

/// The spring keys of the translations (`kx`, `ky`, and `kz` in space).
fn translation_keys(dim: Dimension) -> Vec<&'static str> {
    dim.translations().iter().map(|&d| dim.spring_key(d)).collect()
}

/// The stiffnesses of a resonator's or shaker's spring (`r`), which act in
/// translations only: a rotational one is refused where written, saying
/// `why`.
fn translational_springs(
    ctx: &Ctx<'_>,
    dim: Dimension,
    r: &RawResonator,
    what: &str,
    why: &str,
) -> Result<PerDof, CaseError> {
    if let Some((key, v)) = r.stiffnesses().into_iter().skip(3).find_map(|(key, v)| Some((key, v?))) {
        let keys = translation_keys(dim).join(", ");
        return Err(ctx.err(v.span(), format!("{what}: `{key}`: {why} ({keys})")));
    }
    let mut k = PerDof::default();
    for (d, v) in stiffnesses(ctx, dim, what, r.stiffnesses())? {
        k[d] = v;
    }
    Ok(k)
}

/// Where the new node of a resonator or shaker entry `s` goes (its node's
/// position) and its id (`new_node`, or the largest id + 1).
fn new_node_at(
    ctx: &Ctx<'_>,
    model: &Model,
    s: &Spanned<RawResonator>,
    what: &str,
) -> Result<([f64; 3], u32), CaseError> {
    let r = s.get_ref();
    let at = model
        .node(NodeId(r.node))
        .map(|n| n.position())
        .ok_or_else(|| ctx.err(s.span(), format!("{what}: node {} does not exist", r.node)))?;
    let id = match r.new_node {
        Some(id) => id,
        None => model.max_node_id().checked_add(1).ok_or_else(|| ctx.err(s.span(), "node ids are exhausted"))?,
    };
    Ok((at, id))
}

/// A resonator (`[[resonators]]`): a new node coincident with `node`, a
/// spring named as the entry between the two in the translations given a
/// stiffness, a lumped mass `m` of the same name on the new node, both in
/// the entry's group (whose alpha, and mu, damp the spring), and a support
/// of the new node's other DOFs, so that the mass moves only where its
/// spring holds it and no DOF is left without stiffness.
pub(super) fn add_resonator(ctx: &Ctx<'_>, model: &mut Model, s: &Spanned<RawResonator>) -> Result<(), CaseError> {
    let r = s.get_ref();
    let dim = model.dimension();
    let what = format!("resonator `{}`", r.name);
    let keys = translation_keys(dim);
    // a mass without rotary inertia on a rotational spring would move in
    // no direction: a resonator acts in translations
    let k = translational_springs(ctx, dim, r, &what, "a resonator's spring acts in translations")?;
    let acts = k.non_zero(dim.translations());
    if acts.is_empty() {
        return Err(ctx.err(
            s.span(),
            format!("{what}: give the stiffness of its spring in the directions it acts in ({})", keys.join(", ")),
        ));
    }
    let (at, id) = new_node_at(ctx, model, s, &what)?;
    let g = group_ref(ctx, model, &r.group)?;
    let held: Vec<Dof> = dim.dofs().iter().copied().filter(|d| !acts.contains(d)).collect();
    let err = |e| ctx.model_err(s.span(), e);
    model.add_node_at(id, at).map_err(err)?;
    model.add_spring(&r.name, r.node, Some(id), k, g).map_err(err)?;
    model.add_mass(&r.name, id, r.m, [0.0; 3], g).map_err(err)?;
    model.add_support(id, &held).map_err(err)
}

/// A shaker at its drive point (`[[shakers]]`): its armature, a lumped
/// mass `m` on a new node coincident with `node`, moves with the node in
/// the one direction given a stiffness (a stiff stinger, a tie) and is
/// held in the others (the stinger's bending passes little across), and
/// its suspension, a spring of that stiffness from the new node to ground,
/// is damped by the entry's group (alpha = c / k for a dashpot `c` beside
/// it: the suspension's loss, or the back-EMF damping of a voltage drive).
/// Mass and spring are named as the entry.
pub(super) fn add_shaker(ctx: &Ctx<'_>, model: &mut Model, s: &Spanned<RawShaker>) -> Result<(), CaseError> {
    let r = s.get_ref();
    let dim = model.dimension();
    let what = format!("shaker `{}`", r.name);
    let keys = translation_keys(dim);
    let k = translational_springs(ctx, dim, r, &what, "a shaker drives in a translation")?;
    let acts = k.non_zero(dim.translations());
    let [drive] = acts[..] else {
        return Err(ctx.err(
            s.span(),
            format!(
                "{what}: give the stiffness of its suspension in the one direction it drives ({})",
                keys.join(" or ")
            ),
        ));
    };
    let (at, id) = new_node_at(ctx, model, s, &what)?;
    let g = group_ref(ctx, model, &r.group)?;
    let held: Vec<Dof> = dim.dofs().iter().copied().filter(|&d| d != drive).collect();
    let err = |e| ctx.model_err(s.span(), e);
    model.add_node_at(id, at).map_err(err)?;
    model.add_tie(r.node, id, &[drive]).map_err(err)?;
    model.add_support(id, &held).map_err(err)?;
    model.add_mass(&r.name, id, r.m, [0.0; 3], g).map_err(err)?;
    model.add_spring(&r.name, id, None, k, g).map_err(err)?;
    Ok(())
}

pub(super) fn add_mass(ctx: &Ctx<'_>, model: &mut Model, m: &Spanned<RawMass>) -> Result<usize, CaseError> {
    let r = m.get_ref();
    let dim = model.dimension();
    let what = format!("mass `{}`", r.name);
    let mut j = [0.0; 3];
    for (key, v) in [("j", &r.j), ("jx", &r.jx), ("jy", &r.jy), ("jz", &r.jz)] {
        let Some(v) = v else { continue };
        let Some(d) = dim.inertia_dof(key) else {
            let message = match dim {
                Dimension::Planar => format!(
                    "{what}: `{key}` is a rotary inertia of a frame in space; a planar model's mass has `j` (about z)"
                ),
                Dimension::Spatial => {
                    format!("{what}: a 3D model's mass has jx, jy and jz (`j` does not say about which axis)")
                }
            };
            return Err(ctx.err(v.span(), message));
        };
        j[d.axis()] = *v.get_ref();
    }
    let g = group_ref(ctx, model, &r.group)?;
    model.add_mass(&r.name, r.node, r.m, j, g).map_err(|e| ctx.model_err(m.span(), e))
}

enum End {
    Node(u32),
    Point([f64; 3]),
}

fn parse_end(ctx: &Ctx<'_>, dim: Dimension, v: &Spanned<toml::Value>) -> Result<End, CaseError> {
    let shape = if dim == Dimension::Planar { "[x, y]" } else { "[x, y, z]" };
    let bad = || ctx.err(v.span(), format!("expected an existing node id or a point {shape}"));
    match v.get_ref() {
        toml::Value::Integer(i) => u32::try_from(*i).map(End::Node).map_err(|_| bad()),
        toml::Value::Array(a) if a.len() == 2 || (a.len() == 3 && dim == Dimension::Spatial) => {
            let num = |x: &toml::Value| match x {
                toml::Value::Float(f) => Some(*f),
                toml::Value::Integer(i) => Some(*i as f64),
                _ => None,
            };
            let mut p = [0.0; 3];
            for (c, x) in p.iter_mut().zip(a) {
                *c = num(x).ok_or_else(bad)?;
            }
            Ok(End::Point(p))
        }
        _ => Err(bad()),
    }
}

fn add_line(ctx: &Ctx<'_>, model: &mut Model, line: &Spanned<RawLine>) -> Result<(), CaseError> {
    let r = line.get_ref();
    let n = *r.elements.get_ref();
    if n == 0 {
        return Err(ctx.err(r.elements.span(), "a line needs at least one element"));
    }
    if n > MAX_LINE_ELEMENTS {
        return Err(ctx.err(
            r.elements.span(),
            format!("{n} elements in one line is more than this tool accepts ({MAX_LINE_ELEMENTS})"),
        ));
    }
    let mat = material_ref(ctx, model, &r.material)?;
    let sec = section_ref(ctx, model, &r.section)?;
    let g = group_ref(ctx, model, &r.group)?;
    let exhausted = |what: &str| ctx.err(line.span(), format!("{what} ids of this line would pass {}", u32::MAX));
    let mut next_node = match r.first_node {
        Some(id) => Some(id),
        None => model.max_node_id().checked_add(1),
    };
    let mut next_elem = match r.first_element {
        Some(id) => Some(id),
        None => model.max_element_id().checked_add(1),
    };
    let point = |model: &Model, end: &End, span: Range<usize>| -> Result<[f64; 3], CaseError> {
        match *end {
            End::Point(p) => Ok(p),
            End::Node(id) => model
                .node(NodeId(id))
                .map(|n| n.position())
                .ok_or_else(|| ctx.err(span, format!("node {id} does not exist (define it before this line)"))),
        }
    };
    let dim = model.dimension();
    let from = parse_end(ctx, dim, &r.from)?;
    let to = parse_end(ctx, dim, &r.to)?;
    let p0 = point(model, &from, r.from.span())?;
    let p1 = point(model, &to, r.to.span())?;
    let mut add = |model: &mut Model, p: [f64; 3]| -> Result<u32, CaseError> {
        let id = next_node.ok_or_else(|| exhausted("node"))?;
        next_node = id.checked_add(1);
        model.add_node_at(id, p).map_err(|e| ctx.model_err(line.span(), e))?;
        Ok(id)
    };
    let start = match from {
        End::Node(id) => id,
        End::Point(p) => add(model, p)?,
    };
    let mut ids = vec![start];
    for i in 1..n {
        let t = f64::from(i) / f64::from(n);
        ids.push(add(model, [0, 1, 2].map(|c| p0[c] + t * (p1[c] - p0[c])))?);
    }
    ids.push(match to {
        End::Node(id) => id,
        End::Point(p) => add(model, p)?,
    });
    for w in ids.windows(2) {
        let id = next_elem.ok_or_else(|| exhausted("element"))?;
        next_elem = id.checked_add(1);
        let i = model.add_beam(id, [w[0], w[1]], mat, sec, g).map_err(|e| ctx.model_err(line.span(), e))?;
        model.set_added_mass(i, r.added_mass).map_err(|e| ctx.model_err(line.span(), e))?;
        orient(ctx, model, i, &r.orientation, &r.angle)?;
    }
    Ok(())
}
