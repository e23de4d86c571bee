//! The loop's story as a case carries it (`[[history]]`): the misfit after
//! each step against the noise, and where each added effect sits on the
//! structure. `rfm fix` draws its own loop from its outcome; `rfm compare`
//! and `rfm update` draw it from the case they read, so the report of a
//! case written by `rfm diagnose --apply` shows what was added and how far
//! the misfit fell.

use fe_model::{ElementId, HistoryEntry, Model, NodeId};
use rfm_update::diagnose::EffectKind;
use rfm_update::fix::CONSISTENT;

use super::html::Block;
use super::plot::structure::{Highlight, HighlightKind};
use super::{Result, plot};
use crate::output::Outputs;

/// How an effect of `kind` is marked on the structure: at its nodes for a
/// joint, a support or a mass, along its elements for a change over a
/// region (at its nodes when it has no elements, or when its kind is not
/// known).
pub(crate) fn highlight_kind(kind: Option<EffectKind>, has_elements: bool) -> HighlightKind {
    match kind {
        Some(EffectKind::FlexibleSupport) => HighlightKind::Support,
        Some(EffectKind::LumpedMass) => HighlightKind::Mass,
        Some(EffectKind::Resonator) => HighlightKind::Resonator,
        Some(
            EffectKind::StiffnessChange
            | EffectKind::MassChange
            | EffectKind::ViscousDamping
            | EffectKind::NonViscousDamping,
        ) if has_elements => HighlightKind::Patch,
        None if has_elements => HighlightKind::Patch,
        _ => HighlightKind::Joint,
    }
}

/// An effect in a few words for an axis label, numbered elsewhere as on
/// the structure: what it is and where (`joint at node 13`, `stiffness of
/// elements 4-7`).
pub(crate) fn short_effect(kind: Option<EffectKind>, nodes: &[u32], elements: &[u32]) -> String {
    let what = match kind {
        Some(EffectKind::FlexibleSupport) => "support",
        Some(EffectKind::FlexibleJoint) => "joint",
        Some(EffectKind::LumpedMass) => "mass",
        Some(EffectKind::StiffnessChange) => "stiffness",
        Some(EffectKind::MassChange) => "mass change",
        Some(EffectKind::ViscousDamping | EffectKind::NonViscousDamping) => "damping",
        Some(EffectKind::Resonator) => "resonator",
        Some(EffectKind::Shaker) => "shaker",
        Some(EffectKind::SensorMasses) => "sensor masses",
        None => "effect",
    };
    let span = |ids: &[u32], one: &str, many: &str| match (ids.iter().min(), ids.iter().max()) {
        (Some(a), Some(b)) if a == b => format!("{one} {a}"),
        (Some(a), Some(b)) => format!("{many} {a}-{b}"),
        _ => String::new(),
    };
    let at_nodes = matches!(
        kind,
        Some(
            EffectKind::FlexibleSupport
                | EffectKind::FlexibleJoint
                | EffectKind::LumpedMass
                | EffectKind::Shaker
                | EffectKind::SensorMasses
        )
    );
    let place = if at_nodes && !nodes.is_empty() {
        format!("at {}", span(nodes, "node", "nodes"))
    } else if !elements.is_empty() {
        format!("of {}", span(elements, "element", "elements"))
    } else if !nodes.is_empty() {
        format!("at {}", span(nodes, "node", "nodes"))
    } else {
        String::new()
    };
    if place.is_empty() { what.to_string() } else { format!("{what} {place}") }
}

/// Whether a step added an effect with a place (`+ ...` with nodes or
/// elements): the steps the structure figure numbers.
fn adds_a_placed_effect(h: &HistoryEntry) -> bool {
    h.step.starts_with('+') && !(h.nodes.is_empty() && h.elements.is_empty())
}

/// The effects the history says were added, marked where they sit in
/// `model`. A history records where each effect was put when it was added:
/// a node or element that `model` no longer has (the effect was later
/// taken out, or the model edited) is not marked, and an effect with
/// nothing left to mark says so in its legend.
pub(crate) fn highlights(history: &[HistoryEntry], model: &Model) -> Vec<Highlight> {
    history
        .iter()
        .filter(|h| adds_a_placed_effect(h))
        .map(|h| {
            let kind = h.effect.as_deref().and_then(EffectKind::from_name);
            let nodes: Vec<u32> = h.nodes.iter().copied().filter(|&n| model.node(NodeId(n)).is_some()).collect();
            let elements: Vec<u32> =
                h.elements.iter().copied().filter(|&e| model.beam_index(ElementId(e)).is_some()).collect();
            let mut label = h.step.trim_start_matches('+').trim().to_string();
            if nodes.is_empty() && elements.is_empty() {
                label.push_str(" (no longer in the model)");
            }
            Highlight { label, kind: highlight_kind(kind, !h.elements.is_empty()), nodes, elements, number: None }
        })
        .collect()
}

/// The axis label of each step: `nominal`, `+ 1: joint at node 13` (the
/// number as on the structure), `updated`, or the step's own words.
fn labels(history: &[HistoryEntry]) -> Vec<String> {
    let mut k = 0;
    history
        .iter()
        .map(|h| {
            if adds_a_placed_effect(h) {
                k += 1;
                let kind = h.effect.as_deref().and_then(EffectKind::from_name);
                format!("+ {k}: {}", short_effect(kind, &h.nodes, &h.elements))
            } else if h.step.starts_with("updated") {
                "updated".to_string()
            } else {
                let words: String = h.step.chars().take(24).collect();
                if words.len() < h.step.len() { format!("{words}...") } else { words }
            }
        })
        .collect()
}

/// The misfit after each step of `history` (the case's, with this run's
/// step appended when `this_run`) against the latest noise level it
/// records, as a report figure; `None` for a history of fewer than two steps.
pub(crate) fn fall_figure(history: &[HistoryEntry], this_run: bool, out: &mut Outputs) -> Result<Option<Block>> {
    if history.len() < 2 {
        return Ok(None);
    }
    let noise = history.iter().rev().find_map(|h| h.noise).unwrap_or(0.0);
    let misfits: Vec<f64> = history.iter().map(|h| h.misfit).collect();
    let svg = plot::misfit_steps(&labels(history), &misfits, noise, CONSISTENT)?;
    let band = if noise > 0.0 {
        format!(
            " The green band runs from the latest noise level the history records to {CONSISTENT} times it: a \
             misfit inside it is consistent with the noise."
        )
    } else {
        " The history records no noise level.".to_string()
    };
    let caption = format!(
        "The misfit (RMS of |ln(model / measured)| per complex value, weighted as the fits weigh the lines) after \
         each step that led to this case, as its [[history]] records them (written by rfm diagnose --apply, rfm \
         fix and rfm update){}; added effects are numbered as on the structure.{band}",
        if this_run { ", and after this run" } else { "" }
    );
    Ok(Some(out.figure("misfit-steps", svg, caption)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(step: &str, misfit: f64, effect: Option<&str>, nodes: &[u32], elements: &[u32]) -> HistoryEntry {
        HistoryEntry {
            step: step.into(),
            misfit,
            noise: Some(0.01),
            effect: effect.map(str::to_string),
            nodes: nodes.to_vec(),
            elements: elements.to_vec(),
        }
    }

    /// Added effects are numbered in order and marked by their kind; steps
    /// that add nothing with a place (the nominal, updates, an older case's
    /// step without a place) are not marked.
    #[test]
    fn added_effects_are_numbered_and_marked_by_kind() {
        let history = [
            entry("nominal", 1.4, None, &[], &[]),
            entry("+ flexible, lossy joint at node 13", 0.1, Some("flexible_joint"), &[13], &[13]),
            entry("updated (output-error)", 0.09, None, &[], &[]),
            entry("+ a mass written by an older rfm", 0.05, None, &[], &[]),
            entry("+ stiffness change of elements 4..7", 0.02, Some("stiffness_change"), &[4, 5, 6, 7, 8], &[4, 7]),
            entry("+ lumped mass at node 9", 0.011, Some("lumped_mass"), &[9], &[]),
        ];
        let h = highlights(&history, &fe_model::samples::cantilever(20));
        let kinds: Vec<HighlightKind> = h.iter().map(|h| h.kind).collect();
        assert_eq!(kinds, [HighlightKind::Joint, HighlightKind::Patch, HighlightKind::Mass]);
        assert_eq!(h[0].label, "flexible, lossy joint at node 13");
        assert_eq!(
            labels(&history),
            [
                "nominal",
                "+ 1: joint at node 13",
                "updated",
                "+ a mass written by an o...",
                "+ 2: stiffness of elements 4-7",
                "+ 3: mass at node 9"
            ]
        );
    }

    /// A place the model no longer has (the effect was taken out later, or
    /// the model edited) is not marked, and an effect with nothing left to
    /// mark says so; the case loads all the same.
    #[test]
    fn a_place_the_model_no_longer_has_is_left_unmarked_and_said() {
        let history = [
            entry("+ in-line joint at node 30", 0.1, Some("flexible_joint"), &[30], &[30]),
            entry("+ damping in elements 19..22", 0.05, Some("viscous_damping"), &[19, 20, 21, 22, 23], &[19, 22]),
        ];
        let h = highlights(&history, &fe_model::samples::cantilever(20));
        assert_eq!(h[0].label, "in-line joint at node 30 (no longer in the model)");
        assert!(h[0].nodes.is_empty() && h[0].elements.is_empty(), "{:?}", h[0].nodes);
        assert_eq!(
            (h[1].label.as_str(), &h[1].nodes[..], &h[1].elements[..]),
            ("damping in elements 19..22", &[19, 20, 21][..], &[19][..])
        );
    }

    /// A kind the report does not know is still marked: along its elements
    /// when it has some, else at its nodes.
    #[test]
    fn an_unknown_kind_is_marked_where_it_sits() {
        assert_eq!(highlight_kind(None, true), HighlightKind::Patch);
        assert_eq!(highlight_kind(None, false), HighlightKind::Joint);
        assert_eq!(highlight_kind(Some(EffectKind::StiffnessChange), false), HighlightKind::Joint);
        assert_eq!(highlight_kind(Some(EffectKind::FlexibleJoint), true), HighlightKind::Joint);
    }
}
