//! The change a candidate makes, applied to a model and written into a case file.

use fe_model::{CaseEditor, CaseError, Dimension, Dof, ElementId, Group, Model, ModelError, NodeId, PerDof};

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
    /// own; the other fixed DOFs stay fixed. With nothing `fixed`, springs
    /// to ground at a free node. With `per_direction`, one
    /// spring per released DOF, each in a group of its own (see
    /// [`direction_name`]), all starting as `group`.
    Support {
        node: u32,
        fixed: Vec<Dof>,
        released: Vec<Dof>,
        name: String,
        group: Group,
        k: PerDof,
        dim: Dimension,
        per_direction: bool,
    },
    /// Members detached from a node onto a new coincident node, joined to it
    /// by springs `k` in the `sprung` DOFs (always the rotations), tied in
    /// the others, in a damping group of their own; with `per_direction`,
    /// one spring per sprung DOF in a group of its own, as for supports.
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
        per_direction: bool,
    },
    /// A resonator: a new node `new_node` coincident with `node`, joined
    /// to it by a spring `k` in the translations `dofs`, carrying a lumped
    /// mass `m`, held in its other DOFs; the spring and the mass are named
    /// `name` and are in `group` of their own, whose alpha (and mu) damp
    /// the spring. Written as a case's `[[resonators]]` entry.
    Resonator {
        node: u32,
        new_node: u32,
        dofs: Vec<Dof>,
        name: String,
        group: Group,
        m: f64,
        k: PerDof,
        dim: Dimension,
    },
    /// A shaker at its drive point: a new node `new_node` coincident with
    /// `node`, tied to it in `dof` (the stinger) and held in its other
    /// DOFs, carrying the armature's mass `m`, on a spring `k` in `dof` to
    /// ground (the suspension); mass and spring are named `name` and are in
    /// `group` of their own, whose alpha is the dashpot beside the spring
    /// over its stiffness. Written as a case's `[[shakers]]` entry.
    Shaker { node: u32, new_node: u32, dof: Dof, name: String, group: Group, m: f64, k: f64, dim: Dimension },
    /// The sensors' masses: a lumped mass of [`SENSOR_UNIT`] at each of
    /// `nodes` (named `<group>_<node>`), all in the undamped `group`, whose
    /// mass factor is then each sensor's mass in grams.
    Sensors { nodes: Vec<u32>, group: String },
    /// Nothing added: the parameters exist in the nominal model.
    Set,
    /// Elements `first..=last` moved to a new group.
    Region { first: u32, last: u32, group: Group },
}

/// The name of the spring, and of its group, in DOF `d` of a support or
/// joint `base` with one group per direction: `support_1_r` for its `kr`,
/// `joint_5_4_x` for its `kx`, `support_1_rx` for a `krx` in space.
pub(crate) fn direction_name(base: &str, dim: Dimension, d: Dof) -> String {
    format!("{base}_{}", &dim.spring_key(d)[1..])
}

/// The springs of a support or joint: one `(name, stiffness, group)` with
/// every DOF of `dofs`, or with `per_direction` one per DOF, its group a
/// copy of `group` named as the spring.
fn springs(
    name: &str,
    group: &Group,
    k: &PerDof,
    dofs: &[Dof],
    dim: Dimension,
    per_direction: bool,
) -> Vec<(String, PerDof, Group)> {
    if !per_direction {
        return vec![(name.to_string(), *k, group.clone())];
    }
    dofs.iter()
        .map(|&d| {
            let n = direction_name(name, dim, d);
            let mut kd = PerDof::default();
            kd[d] = k[d];
            let mut g = group.clone();
            g.name = direction_name(&group.name, dim, d);
            (n, kd, g)
        })
        .collect()
}

/// The mass (kg) of each sensor of [`Edit::Sensors`] before its group's
/// mass factor: 1 g, so that the factor reads as grams.
pub(crate) const SENSOR_UNIT: f64 = 1e-3;

/// The natural frequency (Hz) of a mass `m` on a spring `k`.
fn tuned_hz(k: f64, m: f64) -> f64 {
    (k / m).sqrt() / (2.0 * std::f64::consts::PI)
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
            Edit::Support { node, released, name, group, k, dim, per_direction, .. } => {
                let fixed = m.remove_support(*node);
                let kept: Vec<Dof> = fixed.iter().copied().filter(|d| !released.contains(d)).collect();
                if !kept.is_empty() {
                    m.add_support(*node, &kept)?;
                }
                for (name, k, group) in springs(name, group, k, released, *dim, *per_direction) {
                    let g = m.add_group(group)?;
                    m.add_spring(&name, *node, None, k, g)?;
                }
            }
            Edit::Joint { node, elements, new_node, name, group, k, sprung, dim, per_direction, .. } => {
                let springs = springs(name, group, k, sprung, *dim, *per_direction);
                let mut groups = Vec::new();
                for (_, _, group) in &springs {
                    groups.push(m.add_group(group.clone())?);
                }
                m.split_node(*node, elements, *new_node)?;
                let tied: Vec<Dof> = dim.dofs().iter().copied().filter(|d| !sprung.contains(d)).collect();
                if !tied.is_empty() {
                    m.add_tie(*node, *new_node, &tied)?;
                }
                for ((name, k, _), g) in springs.into_iter().zip(groups) {
                    m.add_spring(&name, *node, Some(*new_node), k, g)?;
                }
            }
            Edit::Resonator { node, new_node, dofs, name, group, m: mass, k, dim } => {
                let at = m
                    .node(NodeId(*node))
                    .ok_or_else(|| ModelError::UnknownNode { id: *node, context: format!("resonator `{name}`") })?
                    .position();
                let g = m.add_group(group.clone())?;
                m.add_node_at(*new_node, at)?;
                let mut acting = PerDof::default();
                for &d in dofs {
                    acting[d] = k[d];
                }
                m.add_spring(name, *node, Some(*new_node), acting, g)?;
                m.add_mass(name, *new_node, *mass, [0.0; 3], g)?;
                // held where it does not act: no DOF of the new node is left without stiffness
                let held: Vec<Dof> = dim.dofs().iter().copied().filter(|d| !dofs.contains(d)).collect();
                m.add_support(*new_node, &held)?;
            }
            Edit::Shaker { node, new_node, dof, name, group, m: mass, k, dim } => {
                let at = m
                    .node(NodeId(*node))
                    .ok_or_else(|| ModelError::UnknownNode { id: *node, context: format!("shaker `{name}`") })?
                    .position();
                let g = m.add_group(group.clone())?;
                m.add_node_at(*new_node, at)?;
                m.add_tie(*node, *new_node, &[*dof])?;
                let held: Vec<Dof> = dim.dofs().iter().copied().filter(|d| d != dof).collect();
                m.add_support(*new_node, &held)?;
                m.add_mass(name, *new_node, *mass, [0.0; 3], g)?;
                let mut spring = PerDof::default();
                spring[*dof] = *k;
                m.add_spring(name, *new_node, None, spring, g)?;
            }
            Edit::Sensors { nodes, group } => {
                let g = m.add_group(Group::new(group))?;
                for node in nodes {
                    m.add_mass(&format!("{group}_{node}"), *node, SENSOR_UNIT, [0.0; 3], g)?;
                }
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
            Edit::Resonator { dofs, .. } => dofs.contains(&d),
            Edit::Shaker { dof, .. } => *dof == d,
            Edit::Sensors { .. } => d.is_translation(),
            _ => true,
        }
    }

    /// Plain-language description with the location and the variant.
    pub(crate) fn describe(&self, kind: EffectKind) -> String {
        let damping = |g: &Group, per_direction: bool| {
            let form = if g.mu.is_some() { "non-viscous" } else { "viscous" };
            if per_direction { format!("{form}, one group per direction") } else { form.to_string() }
        };
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
            Edit::Support { node, fixed, released, group, dim, per_direction, .. } if fixed.is_empty() => {
                format!(
                    "spring to ground at node {node} ({}; {})",
                    springs(released, dim),
                    damping(group, *per_direction)
                )
            }
            Edit::Support { node, released, group, dim, per_direction, .. } => {
                format!(
                    "flexible, lossy support at node {node} ({}; {})",
                    springs(released, dim),
                    damping(group, *per_direction)
                )
            }
            Edit::Joint { node, elements, in_line, group, sprung, dim, per_direction, .. } => {
                let ids: Vec<u32> = elements.clone();
                let which = match ids.as_slice() {
                    [one] => format!("element {one}"),
                    _ => format!("elements {ids:?}"),
                };
                let what = if *in_line { "flexible, lossy in-line joint" } else { "flexible, lossy joint" };
                format!("{what} at node {node} ({which}; {}; {})", springs(sprung, dim), damping(group, *per_direction))
            }
            Edit::Resonator { node, dofs, group, m, k, .. } => {
                let tuned: Vec<f64> = dofs.iter().map(|&d| tuned_hz(k[d], *m)).collect();
                let names: Vec<&str> = dofs.iter().map(|d| d.name()).collect();
                // one frequency when its springs are tuned alike (to a tenth of a hertz)
                let shown: Vec<String> = tuned.iter().map(|f| format!("{f:.1} Hz")).collect();
                let tuning = if shown.iter().all(|f| *f == shown[0]) {
                    format!("{}; {}", names.join(", "), shown[0])
                } else {
                    names.iter().zip(&shown).map(|(d, f)| format!("{d} {f}")).collect::<Vec<_>>().join(", ")
                };
                format!("resonator at node {node} ({tuning}; {})", damping(group, false))
            }
            Edit::Shaker { node, dof, .. } => {
                format!("shaker's armature and suspension at the drive point, node {node} ({})", dof.name())
            }
            Edit::Sensors { nodes, .. } => {
                let list: Vec<String> = nodes.iter().map(u32::to_string).collect();
                format!("equal sensor masses at the {} response nodes ({})", nodes.len(), list.join(", "))
            }
            Edit::Region { first, last, .. } => format!("{} in {}", kind.label(), range_name(*first, *last)),
            Edit::Set => kind.label().to_string(),
        }
    }

    /// The change with the fitted `values` of its parameters (`names`, as
    /// [`Edit::write`] takes them) in place of its starting values, for
    /// the quantities a description shows (a resonator's mass and springs,
    /// which make its frequency); other changes as they are.
    pub(crate) fn at_values(&self, names: &[String], values: &[f64]) -> Edit {
        let fitted = |name: String| names.iter().zip(values).find(|(n, _)| **n == name).map(|(_, &v)| v);
        let mut edit = self.clone();
        if let Edit::Resonator { name, m, k, dofs, dim, .. } = &mut edit {
            *m = fitted(format!("mass.{name}.m")).unwrap_or(*m);
            for &d in dofs.iter() {
                k[d] = fitted(format!("spring.{name}.{}", dim.spring_key(d))).unwrap_or(k[d]);
            }
        }
        edit
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
        if let Edit::Support { node, fixed, .. } = self
            && !fixed.is_empty()
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
        // the fitted value of a parameter by its name
        let fitted = |name: String| names.iter().zip(values).find(|(n, _)| **n == name).map(|(_, &v)| v);
        let group_table = |g: &Group| {
            let mut s = format!("[groups.{}]\n", g.name);
            let alpha = fitted(format!("group.{}.alpha", g.name)).unwrap_or(g.alpha);
            if alpha != 0.0 {
                s.push_str(&format!("alpha = {alpha:e}\n"));
            }
            if g.beta != 0.0 {
                s.push_str(&format!("beta = {:e}\n", g.beta));
            }
            if g.mu.is_some() {
                let mu = fitted(format!("group.{}.mu", g.name)).or(g.mu).expect("non-viscous");
                s.push_str(&format!("mu = {mu:e}\n"));
            }
            if g.stiffness != 1.0 {
                s.push_str(&format!("stiffness = {:e}\n", g.stiffness));
            }
            if g.mass != 1.0 {
                s.push_str(&format!("mass = {:e}\n", g.mass));
            }
            s
        };
        // the stiffness lines of spring `name`, and its group's
        let spring_lines = |name: &str, k: &PerDof, g: &Group, dim: &Dimension| {
            let mut s: String = k
                .non_zero(dim.dofs())
                .into_iter()
                .map(|d| {
                    let key = dim.spring_key(d);
                    format!("{key} = {:e}\n", fitted(format!("spring.{name}.{key}")).unwrap_or(k[d]))
                })
                .collect();
            s.push_str(&format!("group = \"{}\"\n", g.name));
            s
        };
        let text = match self {
            Edit::Mass { node, name, group, m, j, dim } => {
                let mut s = format!(
                    "[groups.{group}]                # an undamped group for added masses\n\n[[masses]]\nname = \"{name}\"\nnode = {node}\nm = {:e}\n",
                    fitted(format!("mass.{name}.m")).unwrap_or(*m)
                );
                if *j > 0.0 {
                    let j = fitted(format!("mass.{name}.j")).unwrap_or(*j);
                    match dim {
                        Dimension::Planar => s.push_str(&format!("j = {j:e}\n")),
                        Dimension::Spatial => s.push_str(&format!("jx = {j:e}\njy = {j:e}\njz = {j:e}\n")),
                    }
                }
                s.push_str(&format!("group = \"{group}\"\n"));
                s
            }
            Edit::Support { node, fixed, released, name, group, k, dim, per_direction } => {
                let springs = springs(name, group, k, released, *dim, *per_direction);
                let mut s: String = springs.iter().map(|(_, _, g)| group_table(g) + "\n").collect();
                let kept: Vec<&str> = fixed.iter().filter(|d| !released.contains(d)).map(|d| d.name()).collect();
                if !kept.is_empty() {
                    let list: Vec<String> = kept.iter().map(|d| format!("\"{d}\"")).collect();
                    s.push_str(&format!(
                        "[[supports]]                # the DOFs the data did not show flexible stay rigid\nnode = {node}\ndofs = [{}]\n\n",
                        list.join(", ")
                    ));
                }
                let entries: Vec<String> = springs
                    .iter()
                    .map(|(name, k, g)| {
                        format!(
                            "[[springs]]\nname = \"{name}\"\nnode = {node}                      # to ground\n{}",
                            spring_lines(name, k, g, dim)
                        )
                    })
                    .collect();
                s.push_str(&entries.join("\n"));
                s
            }
            Edit::Joint { node, elements, new_node, name, group, k, sprung, dim, per_direction, .. } => {
                // one entry per spring; entries on the same node pair are one joint
                let springs = springs(name, group, k, sprung, *dim, *per_direction);
                let mut s: String = springs.iter().map(|(_, _, g)| group_table(g) + "\n").collect();
                let entries: Vec<String> = springs
                    .iter()
                    .map(|(name, k, g)| {
                        format!(
                            "[[joints]]\nname = \"{name}\"\nnode = {node}\nelements = {elements:?}\nnew_node = {new_node}\n{}",
                            spring_lines(name, k, g, dim)
                        )
                    })
                    .collect();
                s.push_str(&entries.join("\n"));
                s
            }
            Edit::Resonator { node, new_node, dofs, name, group, m, k, dim } => {
                let mut acting = PerDof::default();
                for &d in dofs {
                    acting[d] = k[d];
                }
                format!(
                    "{}\n[[resonators]]\nname = \"{name}\"\nnode = {node}\nnew_node = {new_node}                 # its mass's node, coincident with node {node}\nm = {:e}\n{}",
                    group_table(group),
                    fitted(format!("mass.{name}.m")).unwrap_or(*m),
                    spring_lines(name, &acting, group, dim)
                )
            }
            Edit::Shaker { node, new_node, dof, name, group, m, k, dim } => {
                let key = dim.spring_key(*dof);
                format!(
                    "{}\n[[shakers]]\nname = \"{name}\"\nnode = {node}                      # the drive point\nnew_node = {new_node}                 # the armature's node, coincident with node {node}\nm = {:e}\n{key} = {:e}\ngroup = \"{}\"\n",
                    group_table(group),
                    fitted(format!("mass.{name}.m")).unwrap_or(*m),
                    fitted(format!("spring.{name}.{key}")).unwrap_or(*k),
                    group.name
                )
            }
            Edit::Sensors { nodes, group } => {
                let grams = fitted(format!("group.{group}.mass")).unwrap_or(1.0);
                let mut s = format!(
                    "[groups.{group}]                # undamped; its mass factor is each sensor's mass in grams\nmass = {grams:e}\n"
                );
                for node in nodes {
                    s.push_str(&format!(
                        "\n[[masses]]\nname = \"{group}_{node}\"\nnode = {node}\nm = {SENSOR_UNIT:e}                   # 1 g, times the group's factor\ngroup = \"{group}\"\n"
                    ));
                }
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
