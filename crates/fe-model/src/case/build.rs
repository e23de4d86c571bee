//! The model a case file describes: materials, sections, groups, nodes,
//! lines of elements, beams, springs, joints, masses, supports, ties and
//! group assignments, built in that order through the checked `Model::add_*`
//! methods, each error placed at the entry that caused it.

use std::ops::Range;

use toml::Spanned;

use super::raw::{RawCase, RawGroup, RawJoint, RawLine, RawMass, RawSpring};
use super::{Ctx, hint};
use crate::dof::Dof;
use crate::error::CaseError;
use crate::model::{Group, Model, NodeId, Section};

/// Most elements one `[[lines]]` entry may generate.
pub const MAX_LINE_ELEMENTS: u32 = 100_000;

/// The index of the material, section or group a case names, or an error at
/// the name with the closest defined one suggested (or the list).
fn find<'a>(
    ctx: &Ctx<'_>,
    kind: &str,
    name: &Spanned<String>,
    defined: impl Iterator<Item = &'a str> + Clone,
) -> Result<usize, CaseError> {
    defined.clone().position(|n| n == name.get_ref()).ok_or_else(|| {
        let known: Vec<&str> = defined.collect();
        ctx.err(name.span(), format!("unknown {kind} `{}`{}", name.get_ref(), hint(name.get_ref(), &known, "defined")))
    })
}

pub(super) fn group_ref(ctx: &Ctx<'_>, model: &Model, name: &Spanned<String>) -> Result<usize, CaseError> {
    find(ctx, "group", name, model.groups.iter().map(|g| g.name.as_str()))
}

fn material_ref(ctx: &Ctx<'_>, model: &Model, name: &Spanned<String>) -> Result<usize, CaseError> {
    find(ctx, "material", name, model.materials.iter().map(|m| m.name.as_str()))
}

fn section_ref(ctx: &Ctx<'_>, model: &Model, name: &Spanned<String>) -> Result<usize, CaseError> {
    find(ctx, "section", name, model.sections.iter().map(|s| s.name.as_str()))
}

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
    })
}

pub(super) fn build_model(ctx: &Ctx<'_>, raw: &RawCase, model: &mut Model) -> Result<(), CaseError> {
    for (name, m) in &raw.materials {
        model.add_material(name, m.get_ref().e, m.get_ref().rho).map_err(|e| ctx.model_err(m.span(), e))?;
    }
    for (name, s) in &raw.sections {
        let r = s.get_ref();
        let section = match (r.area, r.inertia, r.b, r.h, r.od, r.id) {
            (Some(a), Some(i), None, None, None, None) => Section { name: name.clone(), area: a, inertia: i },
            (None, None, Some(b), Some(h), None, None) => Section::rectangle(name, b, h),
            (None, None, None, None, Some(od), id) => {
                let id = id.unwrap_or(0.0);
                if !(id >= 0.0 && id < od) {
                    return Err(
                        ctx.err(s.span(), format!("section `{name}`: need 0 <= id < od, got od = {od}, id = {id}"))
                    );
                }
                Section::tube(name, od, id)
            }
            _ => {
                return Err(ctx.err(
                    s.span(),
                    format!("section `{name}`: give either A and I, or b and h (rectangle), or od and id (tube)"),
                ));
            }
        };
        model.add_section(section).map_err(|e| ctx.model_err(s.span(), e))?;
    }
    for (name, g) in &raw.groups {
        let group = raw_group(ctx, name, g)?;
        model.add_group(group).map_err(|e| ctx.model_err(g.span(), e))?;
    }
    for n in &raw.nodes {
        let (id, x, y) = *n.get_ref();
        model.add_node(id, x, y).map_err(|e| ctx.model_err(n.span(), e))?;
    }
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
    }
    for s in &raw.springs {
        add_spring(ctx, model, s)?;
    }
    // joints before masses, supports and ties: a joint makes a node (its
    // `new_node`, or the next free id) that those may name, as a case
    // written by `rfm diagnose --apply` does for a mass at a joint
    for j in &raw.joints {
        add_joint(ctx, model, j)?;
    }
    for m in &raw.masses {
        add_mass(ctx, model, m)?;
    }
    for s in &raw.supports {
        let r = s.get_ref();
        let dofs = match &r.dofs {
            None => Dof::ALL.to_vec(),
            Some(list) => parse_dofs(ctx, list)?,
        };
        model.add_support(r.node, &dofs).map_err(|e| ctx.model_err(s.span(), e))?;
    }
    for t in &raw.ties {
        let r = t.get_ref();
        let dofs = parse_dofs(ctx, &r.dofs)?;
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
    if model.beams.is_empty() && model.springs.is_empty() {
        return Err(ctx.whole("the case defines no beams, lines or springs"));
    }
    Ok(())
}

fn parse_dofs(ctx: &Ctx<'_>, list: &[Spanned<String>]) -> Result<Vec<Dof>, CaseError> {
    list.iter()
        .map(|d| {
            if d.get_ref() == "all" {
                return Err(ctx.err(d.span(), "write all DOFs as [\"ux\", \"uy\", \"rz\"] or omit `dofs`"));
            }
            d.get_ref().parse::<Dof>().map_err(|e| ctx.err(d.span(), e))
        })
        .collect()
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
    let g = group_ref(ctx, model, &r.group)?;
    model.add_spring(&r.name, a, b, [r.kx, r.ky, r.kr], g).map_err(|e| ctx.model_err(s.span(), e))
}

/// A joint: the node is split, the listed elements move to a new coincident
/// node, the translations without a spring are tied and a spring (always kr,
/// and kx, ky when given) joins the pair.
pub(super) fn add_joint(ctx: &Ctx<'_>, model: &mut Model, j: &Spanned<RawJoint>) -> Result<(), CaseError> {
    let r = j.get_ref();
    let g = group_ref(ctx, model, &r.group)?;
    let new_id = match r.new_node {
        Some(id) => id,
        None => model
            .max_node_id()
            .checked_add(1)
            .ok_or_else(|| ctx.err(j.span(), format!("joint `{}`: no node id left above {}", r.name, u32::MAX)))?,
    };
    model.split_node(r.node, &r.elements, new_id).map_err(|e| ctx.model_err(j.span(), e))?;
    let tied: Vec<Dof> =
        [(Dof::Ux, r.kx), (Dof::Uy, r.ky)].iter().filter(|(_, k)| k.is_none()).map(|(d, _)| *d).collect();
    if !tied.is_empty() {
        model.add_tie(r.node, new_id, &tied).map_err(|e| ctx.model_err(j.span(), e))?;
    }
    let k = [r.kx.unwrap_or(0.0), r.ky.unwrap_or(0.0), r.kr];
    model.add_spring(&r.name, r.node, Some(new_id), k, g).map_err(|e| ctx.model_err(j.span(), e))?;
    Ok(())
}

pub(super) fn add_mass(ctx: &Ctx<'_>, model: &mut Model, m: &Spanned<RawMass>) -> Result<usize, CaseError> {
    let r = m.get_ref();
    let g = group_ref(ctx, model, &r.group)?;
    model.add_mass(&r.name, r.node, r.m, r.j, g).map_err(|e| ctx.model_err(m.span(), e))
}

enum End {
    Node(u32),
    Point(f64, f64),
}

fn parse_end(ctx: &Ctx<'_>, v: &Spanned<toml::Value>) -> Result<End, CaseError> {
    let bad = || ctx.err(v.span(), "expected an existing node id or a point [x, y]");
    match v.get_ref() {
        toml::Value::Integer(i) => u32::try_from(*i).map(End::Node).map_err(|_| bad()),
        toml::Value::Array(a) if a.len() == 2 => {
            let num = |x: &toml::Value| match x {
                toml::Value::Float(f) => Some(*f),
                toml::Value::Integer(i) => Some(*i as f64),
                _ => None,
            };
            match (num(&a[0]), num(&a[1])) {
                (Some(x), Some(y)) => Ok(End::Point(x, y)),
                _ => Err(bad()),
            }
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
    let point = |model: &Model, end: &End, span: Range<usize>| -> Result<(f64, f64), CaseError> {
        match *end {
            End::Point(x, y) => Ok((x, y)),
            End::Node(id) => model
                .node(NodeId(id))
                .map(|n| (n.x, n.y))
                .ok_or_else(|| ctx.err(span, format!("node {id} does not exist (define it before this line)"))),
        }
    };
    let from = parse_end(ctx, &r.from)?;
    let to = parse_end(ctx, &r.to)?;
    let (x0, y0) = point(model, &from, r.from.span())?;
    let (x1, y1) = point(model, &to, r.to.span())?;
    let mut add = |model: &mut Model, x: f64, y: f64| -> Result<u32, CaseError> {
        let id = next_node.ok_or_else(|| exhausted("node"))?;
        next_node = id.checked_add(1);
        model.add_node(id, x, y).map_err(|e| ctx.model_err(line.span(), e))?;
        Ok(id)
    };
    let start = match from {
        End::Node(id) => id,
        End::Point(x, y) => add(model, x, y)?,
    };
    let mut ids = vec![start];
    for i in 1..n {
        let t = f64::from(i) / f64::from(n);
        ids.push(add(model, x0 + t * (x1 - x0), y0 + t * (y1 - y0))?);
    }
    ids.push(match to {
        End::Node(id) => id,
        End::Point(x, y) => add(model, x, y)?,
    });
    for w in ids.windows(2) {
        let id = next_elem.ok_or_else(|| exhausted("element"))?;
        next_elem = id.checked_add(1);
        let i = model.add_beam(id, [w[0], w[1]], mat, sec, g).map_err(|e| ctx.model_err(line.span(), e))?;
        model.set_added_mass(i, r.added_mass).map_err(|e| ctx.model_err(line.span(), e))?;
    }
    Ok(())
}
