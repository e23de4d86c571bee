//! The other damping form of a leading support, joint, damping window or
//! resonator.
//!
//! Each of these effects is a candidate in both forms, viscous and
//! non-viscous, and each form is screened from its own start. The
//! non-viscous form has a relaxation parameter whose misfit has local
//! minima, and its screening fit can stop in one of them: on a portal
//! frame whose clamp is flexible and lossy with an exponential kernel, the
//! viscous support led at 8.4 times the noise, while its non-viscous form
//! was screened 66th, at a misfit twelve times higher, and never fitted
//! fully; the loop then piled a joint and a damping window beside the
//! support to make up for the wrong form. Its supports also differ in
//! which springs the data determine, so the leader (a variant holding an
//! undetermined spring) had no other form in the pool at all.
//!
//! So the other form of each leader is fitted fully from the leader's own
//! fit: a non-viscous form starts from a kernel relaxing ten times faster
//! than the highest line, which damps as the leader's viscous group does
//! over the band, and so starts at the leader's misfit; a viscous form
//! starts from the leader's alpha. Whether its fit is worth its parameters
//! is for the information criterion that ranks every candidate to say.

use fe_model::Model;

use super::edit::Edit;
use super::{Candidate, Fitted, Role};

/// A non-viscous form starts with its kernel relaxing this many times
/// faster than the highest line (rad/s): viscous over the band.
pub(crate) const FAST: f64 = 10.0;

/// The other damping form of `leader` (a support or joint, with one damping
/// group or one per direction, a damping window or a resonator), with the leader's parameters,
/// its held ones held (see [`Candidate::holding`]), and a relaxation
/// parameter added or dropped; `band_hz` is the band of the data. The new
/// relaxation parameter starts at [`FAST`] times the highest line, bounded
/// as the generated candidates' are. `None` for other kinds.
pub(crate) fn other_form(model: &Model, leader: &Candidate, band_hz: (f64, f64)) -> Option<Candidate> {
    let mut edit = leader.edit.clone();
    let group = match &mut edit {
        Edit::Support { group, .. }
        | Edit::Joint { group, .. }
        | Edit::Region { group, .. }
        | Edit::Resonator { group, .. } => group,
        _ => return None,
    };
    let (w_min, w_max) = (std::f64::consts::TAU * band_hz.0, std::f64::consts::TAU * band_hz.1);
    let mut fitted: Vec<Fitted> = (0..leader.parameters.len())
        .map(|i| Fitted {
            name: leader.parameters[i].clone(),
            role: leader.roles[i],
            bounds: leader.bounds[i],
            plausible: leader.plausible[i],
        })
        .collect();
    if group.mu.is_some() {
        group.mu = None;
        fitted.retain(|f| f.role != Role::Mu);
    } else {
        // a relaxation parameter beside each group's alpha (one group, or
        // one per direction, all starting as the edit's group)
        let mus: Vec<Fitted> = fitted
            .iter()
            .filter(|f| f.role == Role::Alpha)
            .filter_map(|f| f.name.strip_suffix(".alpha"))
            .map(|g| Fitted {
                name: format!("{g}.mu"),
                role: Role::Mu,
                bounds: Some((1e-3 * w_min, 1e3 * w_max)),
                plausible: (0.0, f64::INFINITY, ""),
            })
            .collect();
        if mus.is_empty() {
            return None;
        }
        group.mu = Some(FAST * w_max);
        fitted.extend(mus);
    }
    let mut c = leader.variant(model, edit, fitted)?;
    c.held = leader.held.clone();
    Some(c)
}
