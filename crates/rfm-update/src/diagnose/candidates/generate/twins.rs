//! Twins of leading candidates: the same effect at the same place, modelled
//! the other way a user's model may hold it, fitted from where the original
//! ended (see `search`). Each twin has as many parameters as its original;
//! it stays in the ranking only when it fits better by very strong evidence,
//! so that where the data cannot tell the two apart the plain change stands.
//!
//! - **The bending-only twin of a stiffness change**: a factor on the
//!   elements' bending stiffness alone (`element.<id>.bending`), their axial
//!   (and in space torsional) stiffness kept. A crack, a notch, a thinner
//!   wall or a bolted overlap changes the second moment of area far more
//!   than the area. In a frame whose members also stretch (an L-frame's arm
//!   loads the post axially), a factor on the whole element matrix fits such
//!   a loss by a compromise between the two: on held-out data the
//!   whole-element factor of an I-only loss was 11 standard deviations from
//!   the truth at a misfit of 1.06 times the noise, the bending-only factor
//!   0.1 sd.
//!
//! Twins are fitted for the leaders only, not tried as candidates of their
//! own around every leader: they screen like their originals, and tried so
//! they crowded the right window of another held-out stiffness loss out of
//! the full fits.

use fe_model::{ElementId, Model};

use super::{Ctx, build, window};
use crate::diagnose::candidates::{Candidate, CandidateOptions, Edit, EffectKind};

/// The twins of the given candidates, each with the index (in `of`) of its
/// original; most kinds have none.
pub(crate) fn twins(model: &Model, opts: &CandidateOptions, of: &[&Candidate]) -> Vec<(usize, Candidate)> {
    let ctx = Ctx::new(model, opts);
    let mut specs = Vec::new();
    let mut originals = Vec::new();
    for (k, c) in of.iter().enumerate() {
        let whole_stiffness = c.kind == EffectKind::StiffnessChange
            && c.edit == Edit::Set
            && c.parameters.len() == 1
            && c.parameters[0].starts_with("element.")
            && c.parameters[0].ends_with(".stiffness");
        if !whole_stiffness {
            continue;
        }
        let beams: Option<Vec<usize>> = c.elements.iter().map(|&e| model.beam_index(ElementId(e))).collect();
        let Some((mut head, edit, mut fitted)) =
            beams.and_then(|b| window(&ctx, &b, &[EffectKind::StiffnessChange]).pop())
        else {
            continue;
        };
        head.description = format!("bending {}", head.description);
        let f = &mut fitted[0];
        f.name = format!("{}.bending", f.name.strip_suffix(".stiffness").expect("a stiffness factor"));
        f.plausible.2 = "a change beyond -95 % .. +50 % of the nominal bending stiffness";
        specs.push((head, edit, fitted));
        originals.push(k);
    }
    originals.into_iter().zip(specs).filter_map(|(k, spec)| build(&ctx, vec![spec]).pop().map(|c| (k, c))).collect()
}
