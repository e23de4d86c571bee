//! The per-direction variant of a flexible support or joint.
//!
//! A support or joint found with its springs in one damping group has one
//! loss for every direction, but a real clamp or bolted joint loses energy
//! differently in bending and in shear. One group is then a compromise: it
//! can reach the noise while it puts the stiffnesses several standard
//! deviations from the truth, each spring taking up some of the others'
//! damping. The variant springs every direction in a group of its own (its
//! own alpha, and mu when the leader is non-viscous), started from the
//! leader's fit; its extra parameters pay their price in the information
//! criterion that ranks every candidate, so it wins only where the data
//! show different losses.

use fe_model::Model;

use super::edit::{Edit, direction_name};
use super::{Candidate, Fitted, Role};

/// The per-direction variant of `leader`, when it is a support or joint
/// (not already per direction) with springs in two or more DOFs, started
/// from the leader's fitted `values`: every spring at its fitted stiffness,
/// every group at the leader's fitted alpha (and mu). The variant is the
/// leader when its groups are equal, so its fit starts at the leader's
/// optimum and can only lower the misfit; whether that is worth its extra
/// parameters is for the information criterion to say.
pub(crate) fn per_direction_variant(model: &Model, leader: &Candidate, values: &[f64]) -> Option<Candidate> {
    let mut edit = leader.edit.clone();
    let (name, group, k, dofs, dim, per_direction) = match &mut edit {
        Edit::Support { name, group, k, released: dofs, dim, per_direction, .. }
        | Edit::Joint { name, group, k, sprung: dofs, dim, per_direction, .. } => {
            (name, group, k, dofs.clone(), *dim, per_direction)
        }
        _ => return None,
    };
    if *per_direction || dofs.len() < 2 {
        return None;
    }
    *per_direction = true;
    // a base name whose springs and groups are all free in the model
    let taken =
        |n: &str| model.group_index(n).is_some() || model.spring_index(n).is_some() || model.mass_index(n).is_some();
    let free = |base: &String| dofs.iter().all(|&d| !taken(&direction_name(base, dim, d)));
    let base = std::iter::once(name.clone())
        .chain((2..).map(|i| format!("{name}_{i}")))
        .find(free)
        .expect("some suffix is free");
    *name = base.clone();
    group.name = base.clone();

    // the leader's fitted value, bounds and plausible range of a role
    let like = |role: Role| {
        let i = leader.roles.iter().position(|&r| r == role)?;
        Some((values[i], leader.bounds[i], leader.plausible[i]))
    };
    let mut fitted = Vec::new();
    for &d in &dofs {
        let (v, bounds, plausible) = like(Role::Spring(d))?;
        k[d] = v;
        let key = dim.spring_key(d);
        let name = format!("spring.{}.{key}", direction_name(&base, dim, d));
        fitted.push(Fitted { name, role: Role::Spring(d), bounds, plausible });
    }
    for (role, field) in [(Role::Alpha, "alpha"), (Role::Mu, "mu")] {
        let Some((v, bounds, plausible)) = like(role) else { continue };
        match role {
            Role::Alpha => group.alpha = v,
            _ => group.mu = Some(v),
        }
        for &d in &dofs {
            let name = format!("group.{}.{field}", direction_name(&base, dim, d));
            fitted.push(Fitted { name, role, bounds, plausible });
        }
    }
    leader.variant(model, edit, fitted)
}
