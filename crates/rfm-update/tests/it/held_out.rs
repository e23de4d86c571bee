//! The hidden-effect test that cannot be tuned to the candidate generator:
//! truths written as case files by [`crate::truths`] (which shares no code
//! with the diagnosis), drawn from families wider than the candidates,
//! measured with 1 % noise as receptance or accelerance at translational
//! DOFs, and put through the whole loop of `rfm fix`
//! ([`rfm_update::fix::fix`]): diagnose, add the recommended effect, update,
//! again until nothing significant remains.
//!
//! Criteria (issue "Close the loop on the effects the paper is about"),
//! printed with a confusion table:
//!
//! - the first recommended effect is of the right kind at the right place
//!   (one node or element either side allowed) in at least 90 % of the
//!   trials with effects (in a pair trial, either effect counts);
//! - after the loop the misfit is within 1.5 times the noise in at least 85 %;
//! - the true stiffness and mass values lie within 3 reported standard
//!   deviations in at least 85 % of the trials that have such values and
//!   whose effect was found at exactly its place;
//! - in pair trials both effects are found in at least 80 %;
//! - in null trials (2 % noise) nothing is significant in at least 95 %.
//!
//! CI runs the study at the size the criteria ask for: 12 trials per family
//! (72), 8 pairs and 20 null trials (about 12 minutes in the test profile on
//! two cores). On 2026-11-28: right kind and place first 78/80, within 1.5
//! times the noise 79/80, true values within 3 sd 58/67, both effects of a
//! pair 8/8, null trials clean 20/20 (`cargo xtask heldout` runs the same
//! size, `RFM_STUDY=full`). `HELD_OUT_SINGLE` (per family),
//! `HELD_OUT_PAIRS` and `HELD_OUT_NULL` set the numbers of trials (a smaller
//! study checks the rates but not the counts); `HELD_OUT_ONLY=i,j,...` runs
//! those trials alone and `HELD_OUT_DUMP=DIR` writes
//! each trial as a case with its data.

use std::collections::BTreeMap;

use fe_model::{CaseFile, Model};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rfm_update::diagnose::{self, DiagnoseOptions, EffectKind, Ranked, Role};
use rfm_update::fix::{FixOptions, FixOutcome, fix};

use crate::truths::{self, Family, HiddenEffect, Truth};

/// The relative noise of the measurements.
const NOISE: f64 = 0.01;

use crate::{full_study, study_size};

/// The candidate kinds that represent a hidden family.
fn kinds_of(f: Family) -> &'static [EffectKind] {
    match f {
        Family::Support => &[EffectKind::FlexibleSupport],
        Family::Joint | Family::Splice => &[EffectKind::FlexibleJoint],
        Family::DampingPatch => &[EffectKind::ViscousDamping, EffectKind::NonViscousDamping],
        Family::Mass => &[EffectKind::LumpedMass],
        Family::StiffnessLoss => &[EffectKind::StiffnessChange],
    }
}

/// Whether a ranked effect is of the hidden effect's kind at its place (one
/// node or element of slack, through the nominal model's connectivity).
fn matches(r: &Ranked, h: &HiddenEffect, model: &Model) -> bool {
    kinds_of(h.family).contains(&r.kind) && near(r, h, model)
}

fn near(r: &Ranked, h: &HiddenEffect, model: &Model) -> bool {
    let beams_at = |n: u32| model.beams_at(fe_model::NodeId(n));
    let ends = |e: u32| model.beam_index(fe_model::ElementId(e)).map(|i| model.beams()[i].nodes.map(|n| n.0));
    // the hidden effect's nodes and elements, and their neighbours
    let mut nodes: Vec<u32> = h.nodes.clone();
    let mut elements: Vec<u32> = h.elements.clone();
    for &n in &h.nodes {
        for i in beams_at(n) {
            elements.push(model.beams()[i].id.0);
            nodes.extend(model.beams()[i].nodes.map(|x| x.0));
        }
    }
    for &e in &h.elements {
        for n in ends(e).into_iter().flatten() {
            nodes.push(n);
            elements.extend(beams_at(n).into_iter().map(|i| model.beams()[i].id.0));
        }
    }
    r.nodes.iter().any(|n| nodes.contains(n)) || r.elements.iter().any(|e| elements.contains(e))
}

/// Whether the ranked effect sits exactly where the hidden one does.
fn exact(r: &Ranked, h: &HiddenEffect) -> bool {
    if h.elements.is_empty() {
        r.nodes.first() == h.nodes.first()
    } else {
        let mut a = r.elements.clone();
        a.sort_unstable();
        a == h.elements
    }
}

/// The true value of a fitted parameter's role, when the hidden effect has one.
fn truth_of(role: Role, h: &HiddenEffect) -> Option<f64> {
    match role {
        Role::Spring(d) => h.value(fe_model::Dimension::Planar.spring_key(d)),
        Role::Mass => h.value("m"),
        Role::Inertia => h.value("j"),
        Role::StiffnessFactor => h.value("factor"),
        Role::MassFactor | Role::Alpha | Role::Mu | Role::DampingFactor => None,
    }
}

struct Trial {
    label: String,
    family: String,
    first: Option<Ranked>,
    first_ok: bool,
    outcome: FixOutcome,
    found: Vec<bool>,
    /// `None`: no comparable stiffness or mass value.
    values_ok: Option<bool>,
    detail: String,
}

fn run(truth: &Truth, seed: u64, opts: &FixOptions) -> Trial {
    let case_text = format!("{}{}", truth.nominal, truth.measurement_table("measured.csv"));
    let case = CaseFile::parse(std::path::Path::new("held-out/nominal.toml"), &case_text).expect("nominal case");
    let data = truth.measure(NOISE, seed);
    // HELD_OUT_DUMP=DIR writes each trial as a case with its data, to run rfm on
    if let Ok(dir) = std::env::var("HELD_OUT_DUMP") {
        let dir = std::path::Path::new(&dir).join(format!("trial-{seed}"));
        std::fs::create_dir_all(&dir).expect("dump folder");
        std::fs::write(dir.join("nominal.toml"), &case_text).expect("dump");
        std::fs::write(dir.join("truth.toml"), &truth.truth).expect("dump");
        std::fs::write(dir.join("measured.csv"), frf::io::csv::to_csv_string(&data)).expect("dump");
    }
    let measured = data.to_receptance();
    let mut first: Option<Ranked> = None;
    // every finished step as the loop hands it out, to keep (rfm fix writes
    // each one as it comes, so that an interrupted loop keeps them)
    let mut done: Vec<(usize, String)> = Vec::new();
    let outcome = fix(&case, &measured, opts, |p| match p {
        rfm_update::fix::FixProgress::Diagnosed { step: 0, diagnosis } => first = diagnosis.leader().cloned(),
        rfm_update::fix::FixProgress::StepDone { index, done: step } => {
            done.push((index, step.case.text_at(&case.path).expect("the step's case")));
        }
        _ => {}
    })
    .expect("the loop runs");
    // each step of the outcome was handed out in order, as it is in the
    // outcome when last handed out (a step updated again from a better
    // start is handed out again)
    assert!(done.windows(2).all(|w| w[1].0 == w[0].0 || w[1].0 == w[0].0 + 1), "{:?}", done.iter().map(|d| d.0));
    done.dedup_by(|later, earlier| {
        let same = later.0 == earlier.0;
        if same {
            std::mem::swap(later, earlier);
        }
        same
    });
    assert_eq!(done.iter().map(|d| d.0).collect::<Vec<_>>(), (0..outcome.steps.len()).collect::<Vec<_>>());
    for ((_, text), step) in done.iter().zip(&outcome.steps) {
        assert_eq!(text, &step.case.text_at(&case.path).expect("the step's case"), "{}", truth.label);
    }
    let model = &case.model;
    // the loop's first effect (it may look one step ahead past the first
    // diagnosis's leader), else what the first diagnosis recommended
    if let Some(s) = outcome.steps.first() {
        first = Some(s.effect.clone());
    }
    let first_ok = first.as_ref().is_some_and(|r| truth.effects.iter().any(|h| matches(r, h, model)));
    let found: Vec<bool> = truth.effects.iter().map(|h| outcome.effects.iter().any(|e| matches(e, h, model))).collect();
    // true stiffness and mass values against the final update's, for the
    // effects found at exactly their place
    let mut values_ok: Option<bool> = None;
    let mut detail = String::new();
    if let Some(last) = outcome.steps.last() {
        for h in &truth.effects {
            let Some(effect) = outcome.effects.iter().find(|e| matches(e, h, model) && exact(e, h)) else {
                continue;
            };
            for p in effect.parameters.iter().filter(|p| p.role.is_stiffness_or_mass()) {
                let Some(t) = truth_of(p.role, h) else { continue };
                let Some(i) = last.parameters.iter().position(|q| q.name == p.name) else { continue };
                let value = last.parameters[i].updated;
                let sd = last.uncertainty.as_ref().map_or(f64::NAN, |u| u.parameters[i].relative_std);
                let z = (value / t).ln().abs() / sd;
                let ok = z <= 3.0;
                values_ok = Some(values_ok.unwrap_or(true) && ok);
                detail.push_str(&format!(" {}: {value:.4e} vs {t:.4e} ({z:.1} sd)", p.name));
            }
        }
    }
    Trial {
        label: truth.label.clone(),
        family: if truth.effects.len() == 2 { "pair".into() } else { format!("{:?}", truth.effects[0].family) },
        first,
        first_ok,
        outcome,
        found,
        values_ok,
        detail,
    }
}

fn kind_name(r: &Option<Ranked>) -> String {
    r.as_ref().map_or("none".into(), |r| format!("{:?}", r.kind))
}

/// The trials: `singles` per family, then `pairs` with two effects.
fn draws(singles: usize, pairs: usize) -> Vec<Truth> {
    let mut rng = ChaCha8Rng::seed_from_u64(2611);
    let mut draws: Vec<Truth> = Vec::new();
    for family in Family::ALL {
        for _ in 0..singles {
            draws.push(truths::draw(&mut rng, Some(family), false));
        }
    }
    for _ in 0..pairs {
        draws.push(truths::draw(&mut rng, None, true));
    }
    draws
}

/// Trial `index` of a study of `singles` per family and `pairs` pairs, run
/// through the loop of three steps as the study runs it (its seed too).
fn trial_of(singles: usize, pairs: usize, index: usize) -> Trial {
    let opts = FixOptions { max_steps: 3, ..FixOptions::default() };
    run(&draws(singles, pairs)[index], 7000 + index as u64, &opts)
}

/// Trial 25 of a study at 4 trials per family and 6 pairs: a non-viscous corner joint and a mass with
/// rotary inertia on the column of an L-frame. With the mass missing, the
/// joint is chosen viscous, and the mass is then added without its rotary
/// inertia: the loop's three steps leave 3.9 times the noise. Revised with
/// the other in place, each takes the form the data call for (the joint
/// non-viscous, the mass with its inertia), and the model reaches the
/// noise. Fails when the revision is left out or tries only the effect's
/// own diagnosis's neighbours.
#[test]
fn the_revision_mends_forms_chosen_while_another_effect_was_missing() {
    let trial = trial_of(4, 6, 25);
    let o = &trial.outcome;
    let revised: Vec<String> = o
        .steps
        .iter()
        .filter_map(|s| s.replaced.as_ref().map(|r| format!("{} instead of {r}", s.effect.description)))
        .collect();
    println!("{}: {revised:?}, ends {:.2} x noise", trial.label, o.final_misfit() / NOISE);
    assert!(
        o.effects.iter().any(|e| e.nodes.contains(&13) && e.damping == Some("non-viscous")),
        "the corner joint ends non-viscous: {:?}",
        o.effects.iter().map(|e| &e.description).collect::<Vec<_>>()
    );
    assert!(
        o.effects.iter().any(|e| e.nodes.contains(&10) && e.parameters.iter().any(|p| p.role == Role::Inertia)),
        "the mass ends with its rotary inertia"
    );
    assert!(o.final_misfit() < 1.5 * NOISE, "the loop ends {:.2} times the noise", o.final_misfit() / NOISE);
    assert!(trial.found.iter().all(|&f| f), "both effects found: {:?}", trial.found);
}

/// Trial 74 of the full study: a soft splice near a cantilever's tip and a
/// damping patch over elements 5..8. The splice is found first; then, with
/// the patch still missing, a mass change of element 2 leads by a small
/// margin and damping over elements 5..7 follows: the loop ends 2.6 times
/// the noise. Leaving the mass change out and diagnosing again adds damping
/// in element 8, which completes the patch: 1.0 times the noise.
#[test]
fn the_swap_undoes_an_early_effect_and_what_made_up_for_it() {
    let trial = trial_of(12, 16, 74);
    let o = &trial.outcome;
    let swapped = o.steps.iter().find(|s| s.replaced.is_some()).expect("a step that replaced earlier ones");
    println!("{}: {} instead of {:?}", trial.label, swapped.effect.description, swapped.replaced);
    assert!(o.final_misfit() < 2.0 * NOISE, "the loop ends {:.2} times the noise", o.final_misfit() / NOISE);
    assert!(trial.found.iter().all(|&f| f), "both effects found: {:?}", trial.found);
}

/// Trial 34 of the full study: a splice found and fixed at the first step;
/// the third step's update drives the joint's ky (which the data hardly
/// see) to 4e14 N/m, and the diagnosis of that model calls a line singular.
/// The loop must keep its steps and say that what remains is unknown,
/// not fail as a whole.
#[test]
fn the_loop_keeps_its_steps_when_the_last_diagnosis_fails() {
    let trial = trial_of(12, 16, 34);
    let o = &trial.outcome;
    println!("{}: {} steps, diagnosis error {:?}", trial.label, o.steps.len(), o.diagnosis_error);
    assert!(trial.found.iter().all(|&f| f), "the splice is found: {:?}", trial.found);
    assert!(o.final_misfit() < 1.5 * NOISE, "the loop ends {:.2} times the noise", o.final_misfit() / NOISE);
    if o.diagnosis_error.is_some() {
        assert!(o.significant_remains && o.remaining.is_empty(), "an unknown remainder is not called consistent");
    }
}

/// Trial 76 of the full study: a splice near the arm's end and a mass on
/// the column. One at a time, a flexible support at the base once explained
/// most of both and neither right effect led (the mass ranked eleventh, the
/// splice twentieth): the loop ended 22 times above the noise until pairs of
/// leaders were fitted together. Diagnosed with the lack-of-fit variance,
/// the mass beside its node now leads, and the splice follows. Whichever
/// way the loop goes (alone or as a pair), both effects are found, and
/// every step it keeps passes the rule on its own: a dBIC below the
/// diagnosis's significance against the model before it, so that no
/// partner rides along with a strong effect; an effect the revisions take
/// out is one that, added back, would not be significant (its removal's
/// dBIC above minus the significance).
#[test]
fn two_effects_that_mislead_one_at_a_time_are_both_found() {
    let trial = trial_of(12, 16, 76);
    let o = &trial.outcome;
    for s in &o.steps {
        println!(
            "{}: {} (dBIC {:.3e}, {:.2} x noise)",
            trial.label,
            s.effect.description,
            s.delta_bic,
            s.misfit_updated / NOISE
        );
        let significance = DiagnoseOptions::default().significance;
        if s.removed {
            assert!(s.removed_because.is_some(), "{} taken out without a reason", s.effect.description);
            assert!(
                -s.delta_bic >= significance,
                "{} taken out though its own dBIC is {:.3e}",
                s.effect.description,
                -s.delta_bic
            );
        } else if s.replaced.is_none() {
            assert!(s.delta_bic < significance, "{} kept with dBIC {:.3e}", s.effect.description, s.delta_bic);
        }
    }
    assert!(trial.found.iter().all(|&f| f), "both effects found: {:?}", trial.found);
    assert!(o.final_misfit() < 4.0 * NOISE, "the loop ends {:.2} times the noise", o.final_misfit() / NOISE);
}

#[test]
fn the_loop_finds_and_fixes_held_out_effects() {
    let singles = study_size("HELD_OUT_SINGLE", 2, 12);
    // one pair in `cargo test` (the second took a quarter of its time, 36
    // of 155 s); the pairs' own behaviour is tested above
    let pairs = study_size("HELD_OUT_PAIRS", 1, 8);
    let opts = FixOptions { max_steps: 3, ..FixOptions::default() };
    let mut trials: Vec<Trial> = Vec::new();
    let draws = draws(singles, pairs);
    // HELD_OUT_ONLY=i,j,... runs those trials alone (to look into them)
    let only: Option<Vec<usize>> =
        std::env::var("HELD_OUT_ONLY").ok().map(|v| v.split(',').filter_map(|k| k.trim().parse().ok()).collect());
    // reduced: the first trial of each family (of the two drawn per family,
    // so that the trials and their seeds are those the reduced study ran
    // before) and the pair; the second of each family took 38 % of the
    // reduced study's time (a mass with its rotary inertia, 36 of 123 s)
    let resized = std::env::var("HELD_OUT_SINGLE").is_ok() || std::env::var("HELD_OUT_PAIRS").is_ok();
    let reduced = !full_study() && !resized;
    for (i, t) in draws.iter().enumerate() {
        if only.as_ref().is_some_and(|k| !k.contains(&i)) {
            continue;
        }
        if reduced && i < singles * Family::ALL.len() && i % singles != 0 {
            continue;
        }
        let trial = run(t, 7000 + i as u64, &opts);
        let o = &trial.outcome;
        println!(
            "{:>3} {:<60} first: {:<58} ok {} | steps {} misfit {:.2} x noise | found {:?} | values {:?}{}",
            i,
            trial.label,
            trial.first.as_ref().map_or("none".into(), |r| r.description.clone()),
            trial.first_ok,
            o.steps.len(),
            o.final_misfit() / NOISE,
            trial.found,
            trial.values_ok,
            trial.detail
        );
        trials.push(trial);
    }

    // the confusion table: hidden family against the first recommended kind
    let mut table: BTreeMap<String, BTreeMap<String, usize>> = BTreeMap::new();
    for t in &trials {
        *table.entry(t.family.clone()).or_default().entry(kind_name(&t.first)).or_default() += 1;
    }
    let columns: Vec<String> = {
        let mut c: Vec<String> = table.values().flat_map(|r| r.keys().cloned()).collect();
        c.sort();
        c.dedup();
        c
    };
    println!("\nfirst recommendation by hidden family (rows) and recommended kind (columns):");
    println!("{:<14}{}", "", columns.iter().map(|c| format!("{c:>20}")).collect::<String>());
    for (f, row) in &table {
        println!(
            "{f:<14}{}",
            columns.iter().map(|c| format!("{:>20}", row.get(c).copied().unwrap_or(0))).collect::<String>()
        );
    }

    let n = trials.len();
    let first_ok = trials.iter().filter(|t| t.first_ok).count();
    let fixed = trials.iter().filter(|t| t.outcome.final_misfit() <= 1.5 * NOISE).count();
    let with_values: Vec<bool> = trials.iter().filter_map(|t| t.values_ok).collect();
    let values_ok = with_values.iter().filter(|&&v| v).count();
    let pair_trials: Vec<&Trial> = trials.iter().filter(|t| t.found.len() == 2).collect();
    let both = pair_trials.iter().filter(|t| t.found.iter().all(|&f| f)).count();
    println!("\nright kind at the right place first: {first_ok}/{n}");
    println!("misfit within 1.5 x noise after the loop: {fixed}/{n}");
    println!("true stiffness and mass within 3 sd: {values_ok}/{}", with_values.len());
    println!("both effects found in pair trials: {both}/{}", pair_trials.len());
    let rate = |k: usize, n: usize| k as f64 / n.max(1) as f64;
    if only.is_some() {
        return;
    }
    assert!(n >= 80 || resized || !full_study(), "at least 80 trials with effects, not {n}");
    assert!(rate(first_ok, n) >= 0.90, "right kind and place first in {first_ok}/{n}");
    assert!(rate(fixed, n) >= 0.85, "misfit within 1.5 x noise in {fixed}/{n}");
    // the coverage of the values and the pairs found are rates over many
    // trials (67 with values, 8 pairs): the reduced run (6 with values, 1
    // pair) prints them, and the study at
    // full size asserts them; the pairs' own behaviour is tested above
    if full_study() || resized {
        assert!(rate(values_ok, with_values.len()) >= 0.85, "values within 3 sd in {values_ok}/{}", with_values.len());
        assert!(rate(both, pair_trials.len()) >= 0.80, "both effects found in {both}/{}", pair_trials.len());
    }
}

#[test]
fn null_trials_find_nothing_significant() {
    let trials = study_size("HELD_OUT_NULL", 5, 20);
    assert!(
        trials >= 20 || std::env::var("HELD_OUT_NULL").is_ok() || !full_study(),
        "at least 20 null trials, not {trials}"
    );
    let mut rng = ChaCha8Rng::seed_from_u64(2612);
    let mut quiet = 0;
    for i in 0..trials {
        let t = truths::null(&mut rng);
        let measured = t.measure(2.0 * NOISE, 9000 + i as u64).to_receptance();
        let d = diagnose::diagnose(&t.nominal_case().model, &measured, &DiagnoseOptions::default()).unwrap();
        let top = &d.ranking[0];
        println!(
            "null {i:>2} ({:?}): noise estimate {:.4}, top {} (dBIC {:.1}), consistent {}",
            t.structure,
            d.noise,
            top.description,
            top.delta_bic,
            d.consistent()
        );
        quiet += usize::from(d.consistent());
    }
    println!("null trials without a significant candidate: {quiet}/{trials}");
    assert!(quiet as f64 >= 0.95 * trials as f64, "false alarms in {} of {trials} null trials", trials - quiet);
}
