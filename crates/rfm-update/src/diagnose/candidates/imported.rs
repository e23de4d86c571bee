//! Candidates of an imported model (matrices without element geometry):
//! a change of each imported group's stiffness, mass and damping (its
//! alpha and mu, and the factor on its own damping matrix where it has one). Masses
//! at its nodes and springs at its supports come from the usual
//! generators, which count the imported matrices in a node's stiffness
//! (`Ctx::local_stiffness`) and its nodes as places for a mass.

use fe_model::Model;
use fe_model::imported::ImportedKind;

use super::edit::Edit;
use super::{EffectKind, Fitted, Head, Role};

/// The groups with imported matrices and the nodes each one's blocks touch.
pub(super) fn imported_groups(model: &Model) -> Vec<(usize, Vec<u32>)> {
    let mut out: Vec<(usize, Vec<u32>)> = Vec::new();
    for b in model.imported() {
        let at = match out.iter().position(|(g, _)| *g == b.group) {
            Some(k) => k,
            None => {
                out.push((b.group, Vec::new()));
                out.len() - 1
            }
        };
        out[at].1.extend(b.nodes.map(|n| n.0));
    }
    for (_, nodes) in &mut out {
        nodes.sort_unstable();
        nodes.dedup();
    }
    out
}

/// The changes of an imported group, as the updating parameters the group
/// has: its stiffness and mass factors, and its damping where it has any
/// (a parameter is updated relative to its start, which must not be zero):
/// alpha (and mu), and the factor on an imported damping matrix.
/// `alpha` and `mu` make the fitted entries of damping parameters.
pub(super) fn group_changes(
    model: &Model,
    group: usize,
    nodes: &[u32],
    alpha: impl Fn(String) -> Fitted,
    mu: impl Fn(String) -> Fitted,
) -> Vec<(Head, Edit, Vec<Fitted>)> {
    let g = &model.groups()[group];
    let name = &g.name;
    let head = |kind: EffectKind, description: String| Head {
        kind,
        description,
        nodes: Vec::new(),
        elements: Vec::new(),
        dofs: Vec::new(),
        // the whole group: too large for a low-rank update, fitted on its own model
        part_nodes: nodes.to_vec(),
    };
    let mut out = vec![
        (
            head(EffectKind::StiffnessChange, format!("stiffness change of group `{name}`")),
            Edit::Set,
            vec![Fitted {
                name: format!("group.{name}.stiffness"),
                role: Role::StiffnessFactor,
                bounds: Some((1e-3, 100.0)),
                plausible: (0.05, 1.5, "a change beyond -95 % .. +50 % of the nominal stiffness"),
            }],
        ),
        (
            head(EffectKind::MassChange, format!("mass change of group `{name}`")),
            Edit::Set,
            vec![Fitted {
                name: format!("group.{name}.mass"),
                role: Role::MassFactor,
                bounds: Some((1e-3, 100.0)),
                plausible: (0.5, 2.0, "a change beyond -50 % .. +100 % of the nominal mass"),
            }],
        ),
    ];
    if g.alpha > 0.0 {
        let (kind, mut fitted) = (
            if g.mu.is_some() { EffectKind::NonViscousDamping } else { EffectKind::ViscousDamping },
            vec![alpha(format!("group.{name}.alpha"))],
        );
        if g.mu.is_some() {
            fitted.push(mu(format!("group.{name}.mu")));
        }
        out.push((head(kind, format!("{} of group `{name}`", kind.label())), Edit::Set, fitted));
    }
    if model.imported().iter().any(|b| b.group == group && b.kind == ImportedKind::Damping) {
        out.push((
            head(EffectKind::ViscousDamping, format!("change of the damping matrix of group `{name}`")),
            Edit::Set,
            vec![Fitted {
                name: format!("group.{name}.damping"),
                role: Role::DampingFactor,
                bounds: Some((1e-3, 1e3)),
                plausible: (0.02, 50.0, "a factor beyond 0.02 .. 50 on the group's damping matrix"),
            }],
        ));
    }
    out
}
