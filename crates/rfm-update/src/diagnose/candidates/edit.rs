//! The change a candidate makes, applied to a model and written into a case file.

use fe_model::{CaseEditor, CaseError, Dimension, Dof, ElementId, Group, Model, ModelError, PerDof};

use super::EffectKind;

/// The change a candidate makes to the nominal model, at its starting
/// values: applied to a model by [`Edit::apply`] and written into a case
/// file by [`Edit::write`]. Names are chosen free in the whole nominal model.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Edit {
    /// A lumped mass `m` (and rotary inertia `j`, when fitted: about z in a
    /// planar model, the same about every axis in space) at a node, in an
    /// undamped group of its own.
    Mass { node: u32, name: String, group: String, m: f64, j: f64, dim: Dimension },
    /// The rigid support of a node (the DOFs `fixed`) replaced, in the
    /// `released` DOFs, by ground springs `k` in a damping group of their
    /// own; the other fixed DOFs stay fixed.
    Support { node: u32, fixed: Vec<Dof>, released: Vec<Dof>, name: String, group: Group, k: PerDof, dim: Dimension },
    /// Members detached from a node onto a new coincident node, joined to it
    /// by springs `k` in the `sprung` DOFs (always the rotations), tied in
    /// the others, in a damping group of their own.
    Joint {
        node: u32,
        elements: Vec<u32>,
        new_node: u32,
        in_line: bool,
        name: String,
        group: Group,
        k: PerDof,
        sprung: Vec<Dof>,
        dim: Dimension,
    },
    /// Nothing added: the parameters exist in the nominal model.
    Set,
    /// Elements `first..=last` moved to a new group.
    Region { first: u32, last: u32, group: Group },
}

fn range_name(first: u32, last: u32) -> String {
    if first == last { format!("element {first}") } else { format!("elements {first}..{last}") }
}

impl Edit {
    /// Applies the change to `m`: the whole nominal model, or a part of it
    /// that holds the nodes and elements the change touches.
    pub(crate) fn apply(&self, m: &mut Model) -> Result<(), ModelError> {
        match self {
            Edit::Mass { node, name, group, m: mass, j, dim } => {
                let g = match m.group_index(group) {
                    Some(g) => g,
                    None => m.add_group(Group::new(group))?,
                };
                let j = match dim {
                    Dimension::Planar => [0.0, 0.0, *j],
                    Dimension::Spatial => [*j; 3],
                };
                m.add_mass(name, *node, *mass, j, g)?;
            }
            Edit::Support { node, released, name, group, k, .. } => {
                let fixed = m.remove_support(*node);
                let kept: Vec<Dof> = fixed.iter().copied().filter(|d| !released.contains(d)).collect();
                if !kept.is_empty() {
                    m.add_support(*node, &kept)?;
                }
                let g = m.add_group(group.clone())?;
                m.add_spring(name, *node, None, *k, g)?;
            }
            Edit::Joint { node, elements, new_node, name, group, k, sprung, dim, .. } => {
                let g = m.add_group(group.clone())?;
                m.split_node(*node, elements, *new_node)?;
                let tied: Vec<Dof> = dim.dofs().iter().copied().filter(|d| !sprung.contains(d)).collect();
                if !tied.is_empty() {
                    m.add_tie(*node, *new_node, &tied)?;
                }
                m.add_spring(name, *node, Some(*new_node), *k, g)?;
            }
            Edit::Set => {}
            Edit::Region { first, last, group } => {
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

    /// True when the change acts on DOF `d` (springs of supports and joints).
    pub(crate) fn acts_on(&self, d: Dof) -> bool {
        match self {
            Edit::Support { released, .. } => released.contains(&d),
            Edit::Joint { sprung, .. } => sprung.contains(&d),
            Edit::Mass { j, .. } => d.is_translation() || *j > 0.0,
            _ => true,
        }
    }

    /// Plain-language description with the location and the variant.
    pub(crate) fn describe(&self, kind: EffectKind) -> String {
        let damping = |g: &Group| if g.mu.is_some() { "non-viscous" } else { "viscous" };
        let springs = |dofs: &[Dof], dim: &Dimension| {
            let mut v: Vec<&str> = dofs.iter().map(|&d| dim.spring_key(d)).collect();
            v.sort_unstable();
            v.join(", ")
        };
        match self {
            Edit::Mass { node, j, .. } => {
                if *j > 0.0 {
                    format!("lumped mass with rotary inertia at node {node}")
                } else {
                    format!("lumped mass at node {node}")
                }
            }
            Edit::Support { node, released, group, dim, .. } => {
                format!("flexible, lossy support at node {node} ({}; {})", springs(released, dim), damping(group))
            }
            Edit::Joint { node, elements, in_line, group, sprung, dim, .. } => {
                let ids: Vec<u32> = elements.clone();
                let which = match ids.as_slice() {
                    [one] => format!("element {one}"),
                    _ => format!("elements {ids:?}"),
                };
                let what = if *in_line { "flexible, lossy in-line joint" } else { "flexible, lossy joint" };
                format!("{what} at node {node} ({which}; {}; {})", springs(sprung, dim), damping(group))
            }
            Edit::Region { first, last, .. } => format!("{} in {}", kind.label(), range_name(*first, *last)),
            Edit::Set => kind.label().to_string(),
        }
    }

    /// Writes the change into a case being edited, with the parameters at
    /// `values` (`names`: the candidate's parameters, in the same order);
    /// `comment` heads the added lines. A change of quantities the model
    /// has ([`Edit::Set`]) adds nothing: the caller merges their values
    /// into `[set]`.
    pub(crate) fn write(
        &self,
        editor: &mut CaseEditor,
        names: &[String],
        values: &[f64],
        comment: &str,
    ) -> Result<(), CaseError> {
        if let Edit::Support { node, .. } = self
            && editor.remove_supports_at(*node) == 0
        {
            return Err(editor.error(format!("node {node} has no support entry to replace by springs")));
        }
        match self.snippet(names, values) {
            Some(text) => editor.append(comment, &text),
            None => Ok(()),
        }
    }

    /// The case-file lines that add the change with the parameters at
    /// `values` (see [`Edit::write`]); `None` for [`Edit::Set`]. A support
    /// replaces the node's `[[supports]]` entries, which the user deletes.
    pub(crate) fn snippet(&self, names: &[String], values: &[f64]) -> Option<String> {
        // the fitted value of a parameter by its last name component
        let fitted = |field: &str| names.iter().zip(values).find(|(n, _)| n.ends_with(field)).map(|(_, &v)| v);
        let group_table = |g: &Group| {
            let mut s = format!("[groups.{}]\n", g.name);
            let alpha = fitted(".alpha").unwrap_or(g.alpha);
            if alpha != 0.0 {
                s.push_str(&format!("alpha = {alpha:e}\n"));
            }
            if g.beta != 0.0 {
                s.push_str(&format!("beta = {:e}\n", g.beta));
            }
            if g.mu.is_some() {
                s.push_str(&format!("mu = {:e}\n", fitted(".mu").or(g.mu).expect("non-viscous")));
            }
            if g.stiffness != 1.0 {
                s.push_str(&format!("stiffness = {:e}\n", g.stiffness));
            }
            if g.mass != 1.0 {
                s.push_str(&format!("mass = {:e}\n", g.mass));
            }
            s
        };
        let spring_lines = |k: &PerDof, dofs: &[Dof], dim: &Dimension| {
            dofs.iter()
                .map(|&d| {
                    let key = dim.spring_key(d);
                    format!("{key} = {:e}\n", fitted(&format!(".{key}")).unwrap_or(k[d]))
                })
                .collect::<String>()
        };
        let text = match self {
            Edit::Mass { node, name, group, m, j, dim } => {
                let mut s = format!(
                    "[groups.{group}]                # an undamped group for added masses\n\n[[masses]]\nname = \"{name}\"\nnode = {node}\nm = {:e}\n",
                    fitted(".m").unwrap_or(*m)
                );
                if *j > 0.0 {
                    let j = fitted(".j").unwrap_or(*j);
                    match dim {
                        Dimension::Planar => s.push_str(&format!("j = {j:e}\n")),
                        Dimension::Spatial => s.push_str(&format!("jx = {j:e}\njy = {j:e}\njz = {j:e}\n")),
                    }
                }
                s.push_str(&format!("group = \"{group}\"\n"));
                s
            }
            Edit::Support { node, fixed, released, name, group, k, dim } => {
                let mut s = group_table(group);
                s.push('\n');
                let kept: Vec<&str> = fixed.iter().filter(|d| !released.contains(d)).map(|d| d.name()).collect();
                if !kept.is_empty() {
                    let list: Vec<String> = kept.iter().map(|d| format!("\"{d}\"")).collect();
                    s.push_str(&format!(
                        "[[supports]]                # the DOFs the data did not show flexible stay rigid\nnode = {node}\ndofs = [{}]\n\n",
                        list.join(", ")
                    ));
                }
                s.push_str(&format!(
                    "[[springs]]\nname = \"{name}\"\nnode = {node}                      # to ground\n"
                ));
                s.push_str(&spring_lines(k, released, dim));
                s.push_str(&format!("group = \"{}\"\n", group.name));
                s
            }
            Edit::Joint { node, elements, new_node, name, group, k, sprung, dim, .. } => {
                let mut s = group_table(group);
                s.push_str(&format!(
                    "\n[[joints]]\nname = \"{name}\"\nnode = {node}\nelements = {elements:?}\nnew_node = {new_node}\n"
                ));
                s.push_str(&spring_lines(k, sprung, dim));
                s.push_str(&format!("group = \"{}\"\n", group.name));
                s
            }
            Edit::Region { first, last, group } => {
                format!(
                    "{}\n[[assign]]\nelements = \"{first}..{last}\"\ngroup = \"{}\"\n",
                    group_table(group),
                    group.name
                )
            }
            Edit::Set => return None,
        };
        Some(text)
    }
}
