//! The hidden-effect loop, randomised: a truth model is the nominal model plus
//! one hidden effect drawn at random (kind, location, size); its FRFs are
//! synthesised with 1 % noise at translational DOFs only; the diagnosis must
//! name the right kind at the right place (a neighbour counts), and adding
//! the proposed effect and updating must lower the misfit at least tenfold
//! with the true values within 3 standard deviations. Null trials (no hidden
//! effect, 2 % noise) must find nothing significant.
//!
//! A misfit cannot fall below the noise, so a tenfold fall needs an effect
//! whose own misfit is well above it. Draws whose effect changes the FRFs by
//! less than 12 times the noise level (a stiffness change in the tip
//! element, where the bending moment vanishes, say) are redrawn; the test
//! prints how many.

use damping::DampedSystem;
use fe_model::{Dof, DofRef, Group, Model, Section};
use frf::{Channel, FrfSet, NoiseModel, synthesize};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rfm_update::diagnose::{DiagnoseOptions, Diagnosis, EffectKind, diagnose};
use rfm_update::output_error::{self, OeData, OeOptions};
use rfm_update::params::ParameterSet;

const N_EL: u32 = 20;
const LENGTH: f64 = 1.0;
const B: f64 = 0.04;
const H: f64 = 0.008;
const E: f64 = 2.0e11;
const RHO: f64 = 7800.0;

fn nominal() -> Model {
    let mut m = Model::new("hidden-effect cantilever");
    let g = m.add_group(Group::new("beam").rayleigh(1e-5, 0.5)).unwrap();
    let steel = m.add_material("steel", E, RHO).unwrap();
    let sec = m.add_section(Section::rectangle("bar", B, H)).unwrap();
    for i in 0..=N_EL {
        m.add_node(i + 1, LENGTH * f64::from(i) / f64::from(N_EL), 0.0).unwrap();
    }
    for i in 0..N_EL {
        m.add_beam(i + 1, [i + 1, i + 2], steel, sec, g).unwrap();
    }
    m.add_support(1, &Dof::PLANAR).unwrap();
    m
}

/// Lines 1..400 Hz every 0.5 Hz; uy at every other node over the tip's uy.
fn channels() -> Vec<Channel> {
    let tip = DofRef::new(N_EL + 1, Dof::Uy);
    (3..=N_EL + 1).step_by(2).map(|n| Channel::new(DofRef::new(n, Dof::Uy), tip)).collect()
}

fn lines() -> Vec<f64> {
    (2..=800).map(|i| 0.5 * f64::from(i)).collect()
}

struct Hidden {
    kind: EffectKind,
    nodes: Vec<u32>,
    elements: Vec<u32>,
    /// True values of the candidate's parameters, by a fragment of their name.
    truth: Vec<(&'static str, f64)>,
    model: Model,
}

fn draw(kind: EffectKind, rng: &mut ChaCha8Rng) -> Hidden {
    let mut m = nominal();
    let le = LENGTH / f64::from(N_EL);
    let ei = E * B * H.powi(3) / 12.0;
    match kind {
        EffectKind::LumpedMass => {
            let node = rng.random_range(3..=N_EL + 1);
            let mass = m.total_mass() * rng.random_range(0.02..0.10);
            let g = m.add_group(Group::new("sensor")).unwrap();
            m.add_mass("sensor", node, mass, 0.0, g).unwrap();
            Hidden { kind, nodes: vec![node], elements: vec![], truth: vec![(".m", mass)], model: m }
        }
        EffectKind::StiffnessChange => {
            let e = rng.random_range(1..=N_EL);
            let f = rng.random_range(0.5..0.8);
            let q = m.quantity(&format!("element.{e}.stiffness")).unwrap();
            m.set(q, f).unwrap();
            Hidden { kind, nodes: vec![], elements: vec![e], truth: vec![("stiffness", f)], model: m }
        }
        EffectKind::FlexibleSupport => {
            let kr = rng.random_range(0.1..1.0) * 4.0 * ei / le;
            let alpha = rng.random_range(1e-4..1e-3);
            m.remove_support(1);
            let g = m.add_group(Group::new("clamp").rayleigh(alpha, 0.0)).unwrap();
            let area = B * H;
            m.add_spring("clamp", 1, None, [1e3 * E * area / le, 1e3 * 12.0 * ei / le.powi(3), kr], g).unwrap();
            Hidden { kind, nodes: vec![1], elements: vec![], truth: vec![(".kr", kr), (".alpha", alpha)], model: m }
        }
        EffectKind::NonViscousDamping => {
            let r = rng.random_range(0..N_EL / 4);
            let alpha = rng.random_range(2e-4..1e-3);
            let mu = 2.0 * std::f64::consts::PI * rng.random_range(20.0..150.0);
            let g = m.add_group(Group::new("patch").rayleigh(alpha, 0.5).relaxation(mu)).unwrap();
            let elements: Vec<u32> = (4 * r + 1..=4 * r + 4).collect();
            for &e in &elements {
                let i = m.beam_index(fe_model::ElementId(e)).unwrap();
                m.set_beam_group(i, g).unwrap();
            }
            Hidden { kind, nodes: vec![], elements, truth: vec![(".alpha", alpha), (".mu", mu)], model: m }
        }
        _ => unreachable!("not drawn"),
    }
}

fn measure(truth: &Model, noise: f64, seed: u64) -> FrfSet {
    let sys = DampedSystem::new(truth.clone()).unwrap();
    let mut set = synthesize(&sys, &channels(), &lines()).unwrap();
    NoiseModel::relative(noise, seed).apply(&mut set);
    set
}

/// RMS relative difference between the nominal model's and a truth's FRFs
/// (no noise).
fn systematic_misfit(truth: &Model) -> f64 {
    let clean = measure(truth, 0.0, 0);
    misfit(&DampedSystem::new(nominal()).unwrap(), &clean)
}

/// RMS relative misfit of a system against data.
fn misfit(sys: &DampedSystem, measured: &FrfSet) -> f64 {
    let h = synthesize(sys, measured.channels(), measured.frequencies_hz()).unwrap();
    let n = measured.values().len() as f64;
    (h.values().iter().zip(measured.values()).map(|(a, b)| ((a - b) / b.norm()).norm_sqr()).sum::<f64>() / n).sqrt()
}

struct Outcome {
    right_kind: bool,
    right_place: bool,
    predicted: String,
    misfit_ratio: f64,
    within_3sd: bool,
    detail: String,
}

fn run_trial(h: &Hidden, measured: &FrfSet, opts: &DiagnoseOptions) -> Outcome {
    let model = nominal();
    let d: Diagnosis = diagnose(&model, measured, opts).unwrap();
    let top = &d.ranking[0];
    let cand = &d.candidates[top.candidate];
    let right_kind = top.kind == h.kind;
    let right_place = cand.near(&model, &h.nodes, &h.elements);
    // add the proposed effect, starting from its diagnosed values, and update
    let mut sys = DampedSystem::new(cand.model(&model).unwrap()).unwrap();
    let params = ParameterSet::new(cand.parameters_in(sys.model()).unwrap());
    let start: Vec<f64> = top.parameters.iter().map(|p| p.value).collect();
    params.set_values(&mut sys, &start).unwrap();
    let fit_lines: Vec<f64> = lines().into_iter().step_by(4).collect();
    let data_lines = measured.at_frequencies(&fit_lines).unwrap();
    let before = misfit(&DampedSystem::new(model).unwrap(), &data_lines);
    let r = output_error::run(
        &mut sys,
        &params,
        &OeData { measured: &data_lines, weights: None },
        &OeOptions::default(),
        |_| {},
    )
    .unwrap();
    let after = misfit(&sys, &data_lines);
    let mut within = right_kind;
    let mut detail = String::new();
    if right_kind {
        for (frag, truth) in &h.truth {
            let i = params.params().iter().position(|p| p.name.ends_with(frag)).expect("parameter with truth");
            let sd = r.covariance[(i, i)].sqrt();
            let z = (r.values[i] / truth).ln().abs() / sd;
            detail.push_str(&format!(" {frag}: {:.4e} vs {truth:.4e} ({z:.1} sd)", r.values[i]));
            within &= z <= 3.0;
        }
    }
    Outcome {
        right_kind,
        right_place,
        predicted: format!("{} (dBIC {:.0})", top.description, top.delta_bic),
        misfit_ratio: before / after,
        within_3sd: within,
        detail,
    }
}

#[test]
fn diagnosis_names_hidden_effects_and_updating_recovers_them() {
    let kinds = [
        EffectKind::LumpedMass,
        EffectKind::StiffnessChange,
        EffectKind::FlexibleSupport,
        EffectKind::NonViscousDamping,
    ];
    let per_kind = crate::study_size("HIDDEN_TRIALS_PER_KIND", 3, 13);
    let opts = DiagnoseOptions::default();
    let mut rng = ChaCha8Rng::seed_from_u64(2026);
    let mut table: Vec<(EffectKind, Vec<Outcome>)> = Vec::new();
    for (k, &kind) in kinds.iter().enumerate() {
        let mut outcomes = Vec::new();
        let mut redrawn = 0;
        for t in 0..per_kind {
            let h = loop {
                let h = draw(kind, &mut rng);
                if systematic_misfit(&h.model) >= 12.0 * 0.01 {
                    break h;
                }
                redrawn += 1;
            };
            let measured = measure(&h.model, 0.01, 1000 * k as u64 + t as u64);
            let o = run_trial(&h, &measured, &opts);
            println!(
                "{:<22} trial {t:>2}: top = {:<55} kind {} place {} misfit /{:.1} 3sd {}{}",
                kind.label(),
                o.predicted,
                o.right_kind,
                o.right_place,
                o.misfit_ratio,
                o.within_3sd,
                o.detail
            );
            outcomes.push(o);
        }
        println!("{}: {redrawn} draws too small to lift the misfit tenfold above the noise were redrawn", kind.label());
        table.push((kind, outcomes));
    }
    println!(
        "\nconfusion (rows: hidden kind; columns: correct kind and place / kind only / wrong; misfit fell 10x; truth within 3 sd)"
    );
    let mut correct = 0;
    let mut total = 0;
    let mut loop_ok = 0;
    for (kind, o) in &table {
        let kp = o.iter().filter(|x| x.right_kind && x.right_place).count();
        let k_only = o.iter().filter(|x| x.right_kind && !x.right_place).count();
        let fell = o.iter().filter(|x| x.misfit_ratio >= 10.0).count();
        let w3 = o.iter().filter(|x| x.within_3sd).count();
        println!("{:<24} {kp:>3} {k_only:>3} {:>3}   {fell:>3}   {w3:>3}", kind.label(), o.len() - kp - k_only);
        correct += kp;
        total += o.len();
        loop_ok += o.iter().filter(|x| x.right_kind && x.right_place && x.misfit_ratio >= 10.0 && x.within_3sd).count();
    }
    let rate = correct as f64 / total as f64;
    println!("named first: {correct}/{total} ({:.0} %); full loop succeeded: {loop_ok}/{total}", 100.0 * rate);
    assert!(rate >= 0.9, "the hidden effect ranked first in only {:.0} % of trials", 100.0 * rate);
    for (kind, o) in &table {
        for (t, x) in o.iter().enumerate() {
            if x.right_kind && x.right_place {
                assert!(x.misfit_ratio >= 10.0, "{} trial {t}: misfit fell only {:.1}x", kind.label(), x.misfit_ratio);
                assert!(x.within_3sd, "{} trial {t}: truth outside 3 sd:{}", kind.label(), x.detail);
            }
        }
    }
}

#[test]
fn diagnosis_finds_nothing_significant_when_nothing_is_hidden() {
    let trials = crate::study_size("NULL_TRIALS", 5, 20) as u64;
    let opts = DiagnoseOptions::default();
    let mut false_alarms = 0;
    for t in 0..trials {
        let measured = measure(&nominal(), 0.02, 5000 + t);
        let d = diagnose(&nominal(), &measured, &opts).unwrap();
        let top = &d.ranking[0];
        println!(
            "null trial {t:>2}: noise estimate {:.4}, top = {} (dBIC {:.1}), consistent: {}",
            d.noise,
            top.description,
            top.delta_bic,
            d.consistent()
        );
        assert!((d.noise / 0.02 - 1.0).abs() < 0.15, "noise estimate {} for 2 % noise", d.noise);
        if !d.consistent() {
            false_alarms += 1;
        }
    }
    let rate = 1.0 - false_alarms as f64 / trials as f64;
    println!("null trials without a significant candidate: {}/{trials}", trials as usize - false_alarms);
    assert!(rate >= 0.95, "false alarms in {false_alarms} of {trials} null trials");
}

/// On large models stiffness and mass changes are first tried per region;
/// the leaders' locations are then refined per element. With regions of
/// five elements forced on the cantilever, a 40 % stiffness loss in element
/// 7 must be named at element 7 itself, not as its region (which explains
/// it only in part) nor as a mass at one of its nodes (which leads without
/// the refinement).
#[test]
fn a_leading_region_is_refined_to_the_element_that_changed() {
    let mut truth = nominal();
    let q = truth.quantity("element.7.stiffness").unwrap();
    truth.set(q, 0.6).unwrap();
    let measured = measure(&truth, 0.01, 5);
    let mut opts = DiagnoseOptions::default();
    opts.candidates.per_element_limit = 8;
    let d = diagnose(&nominal(), &measured, &opts).unwrap();
    assert!(
        d.ranking.iter().any(|r| r.kind == EffectKind::StiffnessChange && r.elements.len() == 5),
        "the candidates should be per region"
    );
    let top = &d.ranking[0];
    assert_eq!((top.kind, top.elements.as_slice()), (EffectKind::StiffnessChange, &[7][..]), "{}", top.description);
    assert!(top.significant && top.explained > 0.95, "{} explains {}", top.description, top.explained);
    let factor = top.parameters[0].value;
    assert!((factor / 0.6 - 1.0).abs() < 3.0 * top.parameters[0].relative_std, "fitted factor {factor}");
}

/// Large models pre-screen their many candidates on a few lines and screen
/// only the best. Forced on the cantilever (pre-screening all, screening
/// a fifth), each kind of hidden effect must still lead, with the same full
/// fit as without pre-screening, and no candidate may drop out of the
/// ranking (each is ranked, superseded by a variant, or counted as
/// unfitted).
#[test]
fn pre_screening_keeps_the_leader() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for kind in [
        EffectKind::StiffnessChange,
        EffectKind::LumpedMass,
        EffectKind::FlexibleSupport,
        EffectKind::NonViscousDamping,
    ] {
        let h = draw(kind, &mut rng);
        let measured = measure(&h.model, 0.01, 3);
        let plain = diagnose(&nominal(), &measured, &DiagnoseOptions::default()).unwrap();
        let n = plain.candidates.len();
        let opts = DiagnoseOptions { prescreen_above: 0, prescreen_keep: n / 5, ..DiagnoseOptions::default() };
        assert!(n > opts.prescreen_keep + opts.keep, "too few candidates ({n}) to test pre-screening");
        let pre = diagnose(&nominal(), &measured, &opts).unwrap();
        let (a, b) = (&plain.ranking[0], &pre.ranking[0]);
        assert_eq!(a.kind, kind, "{}", a.description);
        assert_eq!(a.description, b.description);
        assert!((a.delta_bic - b.delta_bic).abs() <= 1e-6 * a.delta_bic.abs(), "{} vs {}", a.delta_bic, b.delta_bic);
        // every candidate the pre-screened diagnosis tried is ranked, but
        // for those a variant superseded and those no fit served (the two
        // runs' refinements differ where their second and third leaders do:
        // resonators tuned to a band of broad residual lead beside a
        // support, so their counts are compared within each run)
        for d in [&plain, &pre] {
            let unranked = d.unfitted.iter().filter(|u| !u.ranked).count();
            assert_eq!(
                d.ranking.len() + d.superseded + unranked + d.deferred,
                d.tried,
                "candidates lost by pre-screening"
            );
        }
    }
}
