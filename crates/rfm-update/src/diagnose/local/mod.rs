//! Exact low-rank evaluation of candidates that change `Z` only locally.
//!
//! A candidate (a lumped mass, a stiffness or mass change of an element or
//! region, damping of a region, a joint or support spring, a resonator)
//! changes `Z` only on the few equations `D` its elements, springs or
//! masses touch: `Z(p) = Z_0 + E dZ(p) E^T` with `E` the columns of the
//! identity at `D`. A candidate that adds equations of its own (a released
//! support, the rotation of a split joint node, a resonator's mass node),
//! coupled to `D` only, has them condensed out exactly: with the local
//! matrix `[[A, B], [B^T, C]]` over `D` and the added equations, `dZ = A -
//! B C^-1 B^T`, and each parameter derivative condenses the same way,
//! `T^T (dZ_ext/dp) T` with `T = [I; -C^-1 B^T]`.
//! With `H_0 = Z_0^-1`, `S = H_0[D, D]` and `X = H_0[D, W]` (`W`: the
//! measured response and reference equations), the Woodbury identity gives
//!
//! ```text
//! Y          = (I + S dZ)^-1 X               (= H(p)[D, W])
//! H(p)[r, f] = H_0[r, f] - X[:, r]^T dZ Y[:, f]
//! (dH/dp_i) p_i [r, f] = -Y[:, r]^T ((dZ/dp_i) p_i) Y[:, f]
//!                      = -X[:, r]^T (I + S dZ)^-T ((dZ/dp_i) p_i) Y[:, f]
//! ```
//!
//! exactly (no linearisation). `Y` is needed only at the reference columns
//! `f`, and each sensitivity costs one solve with the transposed matrix.
//!
//! Everything a candidate needs is local: the part of the model it touches
//! before and after its change ([`LocalCandidate`], from
//! [`fe_model::Model::part`]), whose equations are matched to the whole
//! nominal model's by DOF, and per line `S` and `X`. These come from one
//! factorisation of the *nominal* `Z` per line, shared by every candidate:
//! `X` from unit solves at `W`, and every `S` from the selected inverse of
//! `Z_0` (the solver is analysed with each `D` as a clique, so that
//! `H_0[D, D]` lies in the factor's pattern), which costs about one more
//! factorisation, where a solve per equation of `D` would cost `N` solves
//! per line on a large model. Each evaluation then costs a few operations on
//! `d x d` matrices with small kernels written here (faer's dispatch costs
//! more than the arithmetic at this size). A candidate touching more than
//! [`MAX_LOCAL_EQS`] equations is fitted on its own model.
//!
//! One step per file: `form.rs` finds where a candidate's `Z` differs
//! ([`LocalForm`]), `data.rs` gathers `H_0` from the nominal factorisation
//! ([`LocalData`]), `response.rs` evaluates a candidate (`LocalResponse`)
//! with the dense kernels of `kernels.rs`.

mod data;
mod form;
mod kernels;
mod response;

use damping::DampedSystem;
use num_complex::Complex64 as C64;

pub(crate) use data::{LocalData, Slots};
pub(crate) use form::LocalForm;

use super::Candidate;
use crate::params::ParameterSet;

const ZERO: C64 = C64::new(0.0, 0.0);

/// Above this many local equations a candidate is fitted on its own model:
/// the low-rank update would cost more than it saves.
const MAX_LOCAL_EQS: usize = 60;

/// A candidate fitted by low-rank updates: the part of the nominal model it
/// touches, before and after its change, and where the two differ. All of
/// it is as small as the change; nothing here grows with the model.
pub(crate) struct LocalCandidate {
    /// The nominal model's part (see [`fe_model::Model::part`]).
    nominal_part: DampedSystem,
    /// The same part with the change, at its starting values.
    pub(crate) part: DampedSystem,
    /// The parameters to fit, resolved in `part`.
    pub(crate) params: ParameterSet,
    pub(crate) form: LocalForm,
}

impl LocalCandidate {
    /// The local form of `candidate` relative to `nominal` (the whole
    /// nominal system), or `None` when it has none (see [`LocalForm`]).
    pub(crate) fn new(nominal: &DampedSystem, candidate: &Candidate) -> Option<Self> {
        let nominal_part = DampedSystem::of_part(candidate.nominal_part().clone()).ok()?;
        let part = DampedSystem::of_part(candidate.part().clone()).ok()?;
        let params = ParameterSet::new(candidate.parameters_in(part.model()).ok()?);
        let form = LocalForm::of(nominal, &nominal_part, &part, &params)?;
        Some(LocalCandidate { nominal_part, part, params, form })
    }
}

#[cfg(test)]
mod tests {
    use frf::{Channel, ZSolver};

    use super::data::unit_solves;
    use super::*;
    use crate::diagnose::candidates::{self, CandidateOptions, EffectKind};
    use crate::output_error::Response;
    use crate::sensitivity::{self, ChannelPlan, Hybrid};
    use fe_model::{Dof, DofRef, samples};

    /// Every local candidate's low-rank response equals its own model's
    /// receptances and sensitivities, away from the starting values,
    /// including those that add equations (supports, joints, the mass
    /// node of a resonator in every variant).
    #[test]
    fn low_rank_updates_equal_the_candidate_models() {
        let (mut kinds, mut new_joints) = (Vec::new(), 0);
        // damped, partly non-viscous models (one with a joint spring), so
        // that every kind of local change meets damping it must replace
        for model in [samples::frame_grid(1, 2, 2), samples::frame_with_joint(), samples::space_portal()] {
            check_model(&model, &mut kinds, &mut new_joints);
        }
        // a model of imported matrices: masses at its nodes, changes of its groups
        let imported = fe_model::imported::export::as_imported(&samples::frame_grid(1, 1, 2)).unwrap();
        let mut imported_kinds = Vec::new();
        check_model(&imported, &mut imported_kinds, &mut 0);
        for kind in [EffectKind::LumpedMass, EffectKind::StiffnessChange, EffectKind::MassChange] {
            assert!(imported_kinds.contains(&kind), "no local {kind:?} candidate of an imported model was checked");
        }
        assert!(new_joints > 0, "no new joint was checked");
        for kind in [
            EffectKind::LumpedMass,
            EffectKind::StiffnessChange,
            EffectKind::MassChange,
            EffectKind::ViscousDamping,
            EffectKind::NonViscousDamping,
            EffectKind::FlexibleJoint,
            EffectKind::FlexibleSupport,
            EffectKind::Resonator,
        ] {
            assert!(kinds.contains(&kind), "no local {kind:?} candidate was checked");
        }
    }

    fn check_model(model: &fe_model::Model, kinds: &mut Vec<EffectKind>, new_joints: &mut usize) {
        let nominal = DampedSystem::new(model.clone()).unwrap();
        let uy: Vec<DofRef> =
            (0..nominal.n()).map(|eq| nominal.assembly().dofs().dof_of(eq)).filter(|d| d.dof == Dof::Uy).collect();
        // two references, so that the update's columns per reference are seen
        let mut channels: Vec<Channel> = uy.iter().step_by(2).map(|&r| Channel::new(r, uy[uy.len() - 1])).collect();
        channels.push(Channel::new(uy[uy.len() - 1], uy[0]));
        let lines = [3.0, 17.0, 41.0, 88.0];
        // resonators tuned between two lines, whose values below keep the tuning
        let opts = CandidateOptions { band_hz: (1.0, 100.0), resonator_hz: vec![40.0], ..CandidateOptions::default() };
        let mut all = candidates::generate(model, &opts);
        // the fuller variants (a joint's translational springs, a mass's
        // rotary inertia) and those that hold a spring rigid
        let tried = all.iter().map(|c| c.description.clone()).collect();
        let leaders: Vec<&candidates::Candidate> = all
            .iter()
            .filter(|c| matches!(c.edit, candidates::Edit::Joint { .. }))
            .chain(all.iter().filter(|c| c.kind == EffectKind::LumpedMass).take(2))
            .collect();
        let refined = candidates::refine(model, &opts, &leaders, &tried);
        let held: Vec<candidates::Candidate> = all
            .iter()
            .chain(&refined)
            .filter_map(|c| {
                let springs: Vec<usize> = (0..c.roles.len())
                    .filter(|&i| matches!(c.roles[i], candidates::Role::Spring(d) if d.is_translation()))
                    .collect();
                c.holding(model, &springs[..springs.len().min(1)])
            })
            .collect();
        if leaders.iter().any(|c| matches!(c.edit, candidates::Edit::Joint { .. })) {
            assert!(
                refined
                    .iter()
                    .any(|c| c.kind == EffectKind::FlexibleJoint && c.dofs.iter().any(|d| d.is_translation())),
                "{}",
                model.title
            );
        }
        assert!(refined.iter().any(|c| c.roles.contains(&candidates::Role::Inertia)), "{}", model.title);
        // (an imported model's supports hold DOFs no matrix has: nothing to release)
        assert!(!held.is_empty() || !model.imported().is_empty(), "{}", model.title);
        all.extend(refined);
        all.extend(held);
        let locals: Vec<Option<LocalCandidate>> = all.iter().map(|c| LocalCandidate::new(&nominal, c)).collect();
        let forms: Vec<&LocalForm> = locals.iter().flatten().map(|l| &l.form).collect();
        let data = LocalData::new(&nominal, &channels, &lines, &forms).unwrap();
        // S from the selected inverse equals S from unit solves (the fallback)
        let solver = ZSolver::with_cliques(nominal.assembly().pattern(), &data.slots.eqs).unwrap();
        let mut ws = solver.workspace();
        let z = nominal.z_values(2.0 * std::f64::consts::PI * lines[1]);
        solver.factorize(&mut ws, &z, lines[1]).unwrap();
        let mut s = vec![ZERO; data.per_line[1].s.len()];
        unit_solves(&solver, &mut ws, &data.slots, &mut Vec::new(), lines[1], &mut s).unwrap();
        for k in 0..data.slots.eqs.len() {
            let (got, want) = (&data.per_line[1].s[data.slots.range(k)], &s[data.slots.range(k)]);
            let scale = want.iter().map(|v| v.norm()).fold(0.0, f64::max);
            assert!(got.iter().zip(want).all(|(g, w)| (g - w).norm() <= 1e-10 * scale), "S differs from unit solves");
        }
        for (c, local) in all.iter().zip(&locals) {
            let Some(local) = local else { panic!("{} has no local form", c.description) };
            kinds.push(c.kind);
            // a joint the model lacks, not only one it has
            *new_joints += usize::from(matches!(c.edit, candidates::Edit::Joint { .. }));
            // the truth: the candidate's whole model
            let sys = DampedSystem::new(c.model(model).unwrap()).unwrap();
            let params = ParameterSet::new(c.parameters_in(sys.model()).unwrap());
            // away from the start: masses and damping grow, stiffness falls
            let values: Vec<f64> = params.values(&sys).iter().map(|v| v * 1.7).collect();
            let mut response = data.response(local, local.part.clone(), &lines).unwrap();
            response.set(&values).unwrap();
            let (h, sens) = response.evaluate(&lines, true).unwrap();
            let mut truth = sys;
            params.set_values(&mut truth, &values).unwrap();
            let solver = ZSolver::new(truth.assembly().pattern()).unwrap();
            let plan = ChannelPlan::new(&truth, &channels).unwrap();
            let blocks =
                sensitivity::assemble(&truth, &solver, &plan, params.quantities(), &lines, Hybrid::Model).unwrap();
            let sens = sens.unwrap();
            for (k, b) in blocks.iter().enumerate() {
                let scale = b.model.iter().map(|v| v.norm()).fold(0.0, f64::max);
                for (ch, v) in b.model.iter().enumerate() {
                    assert!((h[k][ch] - v).norm() <= 1e-9 * scale, "{}: H at line {k}", c.description);
                }
                let want = params.combine(b);
                // Relative to each sensitivity, with a floor relative to the
                // response itself: a spring a hundred times stiffer than the
                // member (a joint's translational spring at its rigid start)
                // has a sensitivity 1e-8 of H, which the low-rank update and
                // the whole model's factorisation each resolve only to about
                // 1e-15 of H.
                let h_scale = b.model.iter().map(|v| v.norm()).fold(0.0, f64::max);
                for i in 0..params.len() {
                    let scale = (0..channels.len()).map(|ch| want[(ch, i)].norm()).fold(0.0, f64::max);
                    for ch in 0..channels.len() {
                        assert!(
                            (sens[k][(ch, i)] - want[(ch, i)]).norm() <= 1e-9 * scale + 1e-12 * h_scale,
                            "{}: sensitivity {i} at line {k}: {} vs {} (scale {scale:e}, H scale {h_scale:e})",
                            c.description,
                            sens[k][(ch, i)],
                            want[(ch, i)],
                        );
                    }
                }
            }
        }
    }

    /// An evaluation asked for its sensitivities after one without them, at
    /// the same values, gives what one evaluation of both gives, bit for
    /// bit (the sensitivities read the factorisations kept); after other
    /// values are set, everything is evaluated again at those.
    #[test]
    fn sensitivities_after_an_evaluation_equal_those_of_one_evaluation() {
        let model = samples::frame_with_joint();
        let nominal = DampedSystem::new(model.clone()).unwrap();
        let uy: Vec<DofRef> =
            (0..nominal.n()).map(|eq| nominal.assembly().dofs().dof_of(eq)).filter(|d| d.dof == Dof::Uy).collect();
        let channels: Vec<Channel> = uy.iter().map(|&r| Channel::new(r, uy[0])).collect();
        let lines = [3.0, 17.0, 41.0];
        let opts = CandidateOptions { band_hz: (1.0, 100.0), ..CandidateOptions::default() };
        let locals: Vec<LocalCandidate> =
            candidates::generate(&model, &opts).iter().filter_map(|c| LocalCandidate::new(&nominal, c)).collect();
        // with equations of their own (condensed) and without
        assert!(locals.iter().any(|l| l.form.new_eqs > 0) && locals.iter().any(|l| l.form.new_eqs == 0));
        let forms: Vec<&LocalForm> = locals.iter().map(|l| &l.form).collect();
        let data = LocalData::new(&nominal, &channels, &lines, &forms).unwrap();
        let bits = |e: &crate::output_error::Evaluated| {
            let h = e.0.iter().flatten().flat_map(|v| [v.re.to_bits(), v.im.to_bits()]);
            let s = e.1.iter().flatten().flat_map(|m| {
                (0..m.nrows()).flat_map(move |i| {
                    (0..m.ncols()).flat_map(move |j| [m[(i, j)].re.to_bits(), m[(i, j)].im.to_bits()])
                })
            });
            h.chain(s).collect::<Vec<u64>>()
        };
        for local in &locals {
            let start = local.params.values(&local.part);
            let away: Vec<f64> = start.iter().map(|v| v * 1.7).collect();
            let once = |values: &[f64]| {
                let mut r = data.response(local, local.part.clone(), &lines).unwrap();
                r.set(values).unwrap();
                r.evaluate(&lines, true).unwrap()
            };
            let mut r = data.response(local, local.part.clone(), &lines).unwrap();
            r.set(&start).unwrap();
            let plain = r.evaluate(&lines, false).unwrap();
            assert!(plain.1.is_none());
            r.set(&start).unwrap();
            let both = r.evaluate(&lines, true).unwrap();
            assert_eq!(bits(&both), bits(&once(&start)));
            r.set(&away).unwrap();
            let moved = r.evaluate(&lines, true).unwrap();
            assert_eq!(bits(&moved), bits(&once(&away)));
            assert_ne!(bits(&moved), bits(&both), "the values moved nothing");
        }
    }

    /// Data gathered on more lines and for larger sets of equations serve
    /// a candidate exactly as data gathered for it alone: its `S` is the
    /// larger set's on its own equations, its lines picked among the others.
    /// Lines or equations not gathered serve nothing.
    #[test]
    fn data_for_more_lines_and_larger_sets_serve_a_candidate_exactly() {
        let model = samples::frame_grid(1, 2, 2);
        let nominal = DampedSystem::new(model.clone()).unwrap();
        let uy: Vec<DofRef> =
            (0..nominal.n()).map(|eq| nominal.assembly().dofs().dof_of(eq)).filter(|d| d.dof == Dof::Uy).collect();
        let channels: Vec<Channel> = uy.iter().map(|&r| Channel::new(r, uy[uy.len() - 1])).collect();
        let opts = CandidateOptions { band_hz: (1.0, 100.0), ..CandidateOptions::default() };
        let all = candidates::generate(&model, &opts);
        let locals: Vec<LocalCandidate> = all.iter().filter_map(|c| LocalCandidate::new(&nominal, c)).collect();
        // the sets no other set contains, gathered on more lines than the fit's
        let within = |a: &[usize], b: &[usize]| a.len() < b.len() && a.iter().all(|e| b.contains(e));
        let largest: Vec<&LocalForm> =
            locals.iter().map(|l| &l.form).filter(|f| !locals.iter().any(|o| within(&f.eqs, &o.form.eqs))).collect();
        let lines = [17.0, 88.0];
        let more = LocalData::new(&nominal, &channels, &[3.0, 17.0, 41.0, 88.0], &largest).unwrap();
        let mut served_by_larger = 0;
        for local in &locals {
            let own = LocalData::new(&nominal, &channels, &lines, &[&local.form]).unwrap();
            assert!(more.covers(&lines, &[&local.form]));
            assert!(!more.covers(&[17.0, 50.0], &[&local.form]), "a line not gathered");
            assert!(more.response(local, local.part.clone(), &[17.0, 50.0]).is_none());
            served_by_larger += usize::from(largest.iter().all(|f| f.eqs != local.form.eqs));
            let values: Vec<f64> = local.params.values(&local.part).iter().map(|v| v * 1.7).collect();
            let mut evaluated = [&own, &more].map(|data| {
                let mut r = data.response(local, local.part.clone(), &lines).unwrap();
                r.set(&values).unwrap();
                r.evaluate(&lines, true).unwrap()
            });
            let (h_more, s_more) = evaluated[1].clone();
            let (h_own, s_own) = std::mem::take(&mut evaluated[0]);
            for k in 0..lines.len() {
                let scale = h_own[k].iter().map(|v| v.norm()).fold(0.0, f64::max);
                for (a, b) in h_own[k].iter().zip(&h_more[k]) {
                    assert!((a - b).norm() <= 1e-10 * scale, "H at line {k}");
                }
                let (a, b) = (&s_own.as_ref().unwrap()[k], &s_more.as_ref().unwrap()[k]);
                assert!((a - b).norm_max() <= 1e-10 * a.norm_max(), "sensitivities at line {k}");
            }
        }
        // candidates whose own set is not gathered, served by one containing it
        assert!(served_by_larger > 0, "no candidate was served by a larger set");
        // gathered for every candidate, only the sets no other contains are
        // kept, and each candidate is served by one that holds its equations
        let all_forms: Vec<&LocalForm> = locals.iter().map(|l| &l.form).collect();
        let slots = Slots::of(&all_forms);
        let mut maximal: Vec<&Vec<usize>> = largest.iter().map(|f| &f.eqs).collect();
        maximal.sort();
        maximal.dedup();
        let mut kept: Vec<&Vec<usize>> = slots.eqs.iter().collect();
        kept.sort();
        assert_eq!(kept, maximal, "the slots are the sets no other contains");
        assert!(kept.len() < all_forms.len(), "no candidate's set lies inside another's");
        for f in &all_forms {
            let slot = slots.find(&f.eqs).expect("every candidate is served");
            assert!(f.eqs.iter().all(|e| slots.eqs[slot].binary_search(e).is_ok()));
        }
        // a set of equations no gathered set contains serves nothing
        let first = &locals[0];
        let alone = LocalData::new(&nominal, &channels, &lines, &[&first.form]).unwrap();
        let other = locals.iter().find(|l| l.form.eqs.iter().any(|e| !first.form.eqs.contains(e))).unwrap();
        assert!(!alone.covers(&lines, &[&other.form]));
        assert!(alone.response(other, other.part.clone(), &lines).is_none());
    }
}
