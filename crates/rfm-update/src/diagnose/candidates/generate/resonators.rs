//! Attached resonators: a mass on a spring and damper at a node, tuned to a
//! measured mode the model lacks, or to the middle of a band where the
//! nominal model's residual is broad between the modes (a heavily damped
//! resonator shows no mode of its own; see the diagnosis's `suspects`).
//!
//! A resonator adds a mode of its own near its tuning frequency, and where
//! that lies near a mode of the structure the two split; no other candidate
//! adds a mode, so none can stand in for it. The candidate starts tuned to
//! the frequency of the extra mode ([`super::CandidateOptions::resonator_hz`],
//! which a check of the data finds), though a resonator tuned near a mode of
//! the structure shows as two modes on either side of its tuning. How far
//! they split, and how strongly an extra mode shows, is the mass: the fit
//! starts at 2 % of the structure's mass, and the screening tries 0.5 % and
//! 8 % as well, each with its springs scaled so that it stays tuned
//! ([`super::super::Candidate::other_starts`]). Measured on the 20-element
//! cantilever of the diagnosis's tests (1 % noise, 1-400 Hz, resonators of
//! 0.3 % to 20 % of its mass tuned to 41, 70, 112 or 250 Hz at its tip or
//! mid-span, started at the truth's mode farthest from the model's): all 40
//! were ranked first at their node with the mass within 3 standard
//! deviations and the misfit at the noise from the three starts; 36 from
//! the 2 % start alone (two fits went to a neighbouring node, and two of
//! the heaviest at the tip, started at their shifted first mode, to a wrong
//! tuning). The two starts added a quarter to the diagnosis's time (8.7 s
//! against 6.9 s on average).

use fe_model::{Dof, PerDof};

use super::{Ctx, Spec, unique_name};
use crate::diagnose::candidates::edit::Edit;
use crate::diagnose::candidates::{EffectKind, Fitted, Head, Role};

/// The resonator's starting mass as fractions of the structure's: the
/// candidate's own (the middle one) and those the screening tries besides.
pub(crate) const RESONATOR_MASS_STARTS: [f64; 3] = [0.005, 0.02, 0.08];

/// The loss factor of a resonator's spring at its tuning frequency, to
/// start: a few percent, as a bolted or rubber mount has (a tuned-mass
/// damper's optimum is higher, and the fit finds it).
const LOSS_START: f64 = 0.05;

/// The resonators at every node that can move, tuned to `hz`: in each
/// translation the node is free in (and, in a planar model, in x and y at
/// once), viscous and non-viscous.
pub(super) fn resonators(ctx: &Ctx<'_>, hz: f64) -> Vec<Spec> {
    let model = ctx.model;
    let mut out = Vec::new();
    for node in model.nodes() {
        let id = node.id.0;
        let held: Vec<Dof> =
            model.supports().iter().filter(|s| s.node.0 == id).flat_map(|s| s.dofs.iter().copied()).collect();
        // a translation the structure gives stiffness there: a DOF of the
        // structure, not of a resonator's own mass or a bare node
        let kref = ctx.local_stiffness(id);
        let free: Vec<Dof> =
            ctx.dim.translations().iter().copied().filter(|d| !held.contains(d) && kref[*d] > 0.0).collect();
        let mut sets: Vec<Vec<Dof>> = free.iter().map(|&d| vec![d]).collect();
        if ctx.dim == fe_model::Dimension::Planar && free.len() == 2 {
            sets.push(free.clone());
        }
        for dofs in sets {
            for non_viscous in [false, true] {
                out.push(resonator(ctx, id, dofs.clone(), hz, non_viscous));
            }
        }
    }
    out
}

/// A resonator at `node` acting in `dofs`, tuned to `hz`, viscous or not.
fn resonator(ctx: &Ctx<'_>, node: u32, dofs: Vec<Dof>, hz: f64, non_viscous: bool) -> Spec {
    let model = ctx.model;
    let name = unique_name(model, &format!("resonator_{node}"));
    let w = 2.0 * std::f64::consts::PI * hz;
    let total = ctx.total_mass;
    let m = RESONATOR_MASS_STARTS[1] * total;
    let mut k = PerDof::default();
    for &d in &dofs {
        k[d] = m * w * w;
    }
    // the spring's loss factor at w: alpha w viscous; alpha w mu^2 / (mu^2
    // + w^2) with mu = w, where a kernel relaxing at the resonator's own
    // frequency differs most from a viscous one
    let mut group = ctx.damping_group(&name, non_viscous);
    group.alpha = if non_viscous { 2.0 * LOSS_START / w } else { LOSS_START / w };
    if non_viscous {
        group.mu = Some(w);
    }
    let mut fitted = vec![Fitted {
        name: format!("mass.{name}.m"),
        role: Role::Mass,
        bounds: Some((1e-7 * total, 10.0 * total)),
        plausible: (0.0, 0.25 * total, "more than a quarter of the structure's mass"),
    }];
    // springs from a tuning far below the band to far above it; their
    // plausibility is the tuning, judged with the mass. The floor is ten
    // times the structure's mass tuned a hundred times below the band's
    // lowest line (a 1 % mass at a third of it), not the mass's own floor:
    // a spring the fit runs to 1e-7 of that leaves the mass free in its
    // direction, and the case written with it is refused as a mechanism
    // (the lab frame's two-direction resonator at node 11, `apply_every`)
    let (lo, hi) = (10.0 * total * (0.01 * ctx.w_min).powi(2), 10.0 * total * (100.0 * ctx.w_max).powi(2));
    for &d in &dofs {
        fitted.push(Fitted {
            name: format!("spring.{name}.{}", ctx.dim.spring_key(d)),
            role: Role::Spring(d),
            bounds: Some((lo, hi)),
            plausible: (0.0, f64::INFINITY, ""),
        });
    }
    fitted.extend(ctx.group_damping(&name, non_viscous));
    let edit = Edit::Resonator { node, new_node: ctx.new_node, dofs: dofs.clone(), name, group, m, k, dim: ctx.dim };
    let head = Head {
        kind: EffectKind::Resonator,
        description: edit.describe(EffectKind::Resonator),
        nodes: vec![node],
        elements: Vec::new(),
        dofs,
        // it touches the node alone, as a lumped mass does
        part_nodes: vec![node],
    };
    (head, edit, fitted)
}
