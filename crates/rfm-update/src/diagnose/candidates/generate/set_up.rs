//! The test's own hardware on the structure: a shaker's armature and
//! suspension at a drive point, and the sensors' masses at the response
//! nodes. Neither is a change of the structure; both change what was
//! measured, and a model of the structure alone explains them only in part
//! and in the wrong places (a lab study's shaker drew a stiffness change
//! two elements away, its sensor masses stiffness changes along the beam).

use fe_model::Dof;

use super::{Ctx, Spec, unique_name};
use crate::diagnose::candidates::edit::{Edit, SENSOR_UNIT};
use crate::diagnose::candidates::{EffectKind, Fitted, Head, Role};

/// The starting mass of a shaker's armature, as a fraction of the
/// structure's (its screening fit runs on from there: the candidate adds no
/// mode of its own, so one start finds it).
const ARMATURE_START: f64 = 0.02;

/// A shaker at `node`, driving in `dof`: its armature's mass tied to the
/// node, on a suspension tuned to the band's lowest line, with a dashpot
/// of a tenth of critical beside it.
pub(super) fn shaker(ctx: &Ctx<'_>, node: u32, dof: Dof) -> Option<Spec> {
    let model = ctx.model;
    let held = model.supports().iter().any(|s| s.node.0 == node && s.dofs.contains(&dof));
    if held || !ctx.dim.dofs().contains(&dof) || ctx.local_stiffness(node)[dof] <= 0.0 {
        return None;
    }
    let name = unique_name(model, &format!("shaker_{node}"));
    let total = ctx.total_mass;
    let m = ARMATURE_START * total;
    let k = m * ctx.w_min * ctx.w_min;
    let c = 0.2 * (k * m).sqrt();
    let mut group = ctx.damping_group(&name, false);
    group.alpha = c / k;
    let key = ctx.dim.spring_key(dof);
    let fitted = vec![
        Fitted {
            name: format!("mass.{name}.m"),
            role: Role::Mass,
            bounds: Some((1e-7 * total, 10.0 * total)),
            plausible: (0.0, total, "an armature heavier than the structure"),
        },
        Fitted {
            name: format!("spring.{name}.{key}"),
            role: Role::Spring(dof),
            bounds: Some((1e-6 * total * ctx.w_min.powi(2), 10.0 * total * ctx.w_max.powi(2))),
            plausible: (0.0, f64::INFINITY, ""),
        },
        Fitted {
            name: format!("group.{name}.alpha"),
            role: Role::Alpha,
            bounds: Some((1e-9 / ctx.w_max, 1e3 / ctx.w_min)),
            plausible: (0.0, f64::INFINITY, ""),
        },
    ];
    let edit = Edit::Shaker { node, new_node: ctx.new_node, dof, name, group, m, k, dim: ctx.dim };
    let head = Head {
        kind: EffectKind::Shaker,
        description: edit.describe(EffectKind::Shaker),
        nodes: vec![node],
        elements: Vec::new(),
        dofs: vec![dof],
        part_nodes: vec![node],
    };
    Some((head, edit, fitted))
}

/// Equal sensor masses at the response nodes `nodes` (two or more that the
/// structure gives stiffness): one parameter, each sensor's mass in grams.
pub(super) fn sensor_masses(ctx: &Ctx<'_>, nodes: &[u32]) -> Option<Spec> {
    let model = ctx.model;
    let mut nodes: Vec<u32> = nodes
        .iter()
        .copied()
        .filter(|&n| model.node(fe_model::NodeId(n)).is_some())
        .filter(|&n| ctx.dim.translations().iter().any(|&d| ctx.local_stiffness(n)[d] > 0.0))
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    if nodes.len() < 2 {
        return None;
    }
    let group = unique_name(model, "sensors");
    // together more than half the structure's mass: no sensor set an
    // engineer would put on it
    let most = 0.5 * ctx.total_mass / (nodes.len() as f64 * SENSOR_UNIT);
    let fitted = vec![Fitted {
        name: format!("group.{group}.mass"),
        role: Role::MassFactor,
        bounds: Some((1e-4, 100.0 * most)),
        plausible: (0.0, most, "sensors weighing together more than half the structure"),
    }];
    let edit = Edit::Sensors { nodes: nodes.clone(), group };
    let head = Head {
        kind: EffectKind::SensorMasses,
        description: edit.describe(EffectKind::SensorMasses),
        nodes: nodes.clone(),
        elements: Vec::new(),
        dofs: ctx.dim.translations().to_vec(),
        part_nodes: nodes,
    };
    Some((head, edit, fitted))
}
