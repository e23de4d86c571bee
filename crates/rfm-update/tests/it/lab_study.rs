//! The study of `rfm fix` on data a test lab produces ([`crate::lab`]:
//! truths written apart from the tool, with set-up errors, resonators, a
//! shaker, sensor masses, a damping model-form error with the case's
//! parameters declared, null trials, and families outside every family the
//! tool has), each trial dumped as a case with its data file and run as
//! `rfm fix` runs it (`Study::load`, the study's diagnosis options, three
//! steps), then scored against the trial's expected answer.
//!
//! Criteria (issue 32, item 7), printed with their counts:
//!
//! - the data error reported as such (the finding's kind on the right
//!   channels) in at least 90 % of the trials with one;
//! - the resonator found (a resonator at its node or the next) in at least
//!   85 % of the resonator trials;
//! - no spurious effect (every effect added is one of the answer's, at its
//!   place) in at least 95 % of all trials;
//! - where the truth is outside every family, the loop stops as
//!   inadequate (exit 9) with a description of what remains in at least
//!   95 %.
//!
//! `cargo xtask heldout` (`RFM_STUDY=full`) runs 4 trials per family (72
//! trials) and asserts the rates. `cargo test` runs one trial of each of a
//! few families that go through the other paths of the loop (a swap and a
//! miscalibration alone found and corrected, a member at another angle
//! that no family explains, a null trial; `crates/rfm-cli/tests/it/lab_cases.rs`
//! runs the inverted channel, the resonator and the declared damping) and
//! asserts each right in full. `LAB_PER` sets the trials per family (with
//! fewer than 4 the rates are printed and not asserted), `LAB_ONLY=i,j`
//! runs those trials alone, `LAB_SEED` draws another set, and `LAB_VERBOSE`
//! prints each trial's steps and findings (`LAB_KEEP` keeps its files).

use std::collections::BTreeMap;

use rfm_update::checks::FindingKind;
use rfm_update::diagnose::EffectKind;
use rfm_update::fix::{FixOptions, FixOutcome, FixStop, fix};
use rfm_update::status::Status;

use crate::lab::{self, Expect, ExpectedEffect, Finding, LabFamily, LabTrial};

use crate::{full_study, study_size};

/// Criteria of issue 32 the loop does not meet yet, with the counts of the
/// last full run. None since the run of 2026-11-28 (72 trials, `cargo
/// xtask heldout`): data errors reported as such 38/40, resonators found
/// 4/4, no spurious effect 71/72, the trials outside every family stopped
/// with exit 9 and a description 12/12, all asserted. Right in full by
/// family: polarity 8/8, swap 8/8, misdirected 6/8, wrong node 8/8,
/// calibration 8/8, resonator 4/4, shaker 4/4, sensor masses 4/4, damping
/// form 4/4, null 4/4, phase drift 4/4, skew member 4/4, fin 3/4. The two
/// heavily damped resonators that show no mode of their own (trials 22 and
/// 23) are found from the broad residual they leave between the modes
/// (`diagnose/suspects.rs`); a step chosen before a data error was found is
/// made again on the corrected data (trial 64), and a step's share of what
/// is left is read above the residual's own noise (trial 68). What is left:
/// beside a fin a damping patch lowers the misfit by more than half of its
/// excess (trial 48); two misdirected sensors beside a model error are not
/// reported (trials 61 and 63). The study prints a criterion listed here as
/// not met, and fails when one is met, so that it is asserted from then on.
const NOT_YET_MET: &[(&str, &str)] = &[];

/// The families `cargo test` runs one trial of (see the module docs).
const REDUCED: [LabFamily; 4] = [LabFamily::Swap, LabFamily::Calibration, LabFamily::SkewMember, LabFamily::Null];

/// The kinds of the tool that stand for an expected effect's family (a
/// damping patch either form; a shaker is the tool's shaker, or a mass, a
/// spring to ground or a resonator at the drive point; a sensor's mass may
/// be found as the sensors' masses at every response node).
fn kinds_of(family: &str) -> &'static [EffectKind] {
    match family {
        "flexible_support" => &[EffectKind::FlexibleSupport],
        "flexible_joint" => &[EffectKind::FlexibleJoint],
        "lumped_mass" => &[EffectKind::LumpedMass, EffectKind::MassChange, EffectKind::SensorMasses],
        "stiffness_change" => &[EffectKind::StiffnessChange],
        "viscous_damping" | "non_viscous_damping" => &[EffectKind::ViscousDamping, EffectKind::NonViscousDamping],
        "resonator" => &[EffectKind::Resonator],
        "shaker" => &[EffectKind::Shaker, EffectKind::LumpedMass, EffectKind::FlexibleSupport, EffectKind::Resonator],
        _ => &[],
    }
}

/// Whether an added effect is the expected one: of its kind, within one
/// node or element of its place (nodes are numbered along members, so one
/// apart are neighbours; an element effect's nodes are its elements' ends).
fn matches(effect: &rfm_update::diagnose::Ranked, e: &ExpectedEffect) -> bool {
    if !kinds_of(&e.family).contains(&effect.kind) {
        return false;
    }
    let near = |a: u32, b: u32| a.abs_diff(b) <= 1;
    let mut places: Vec<u32> = e.nodes.clone();
    places.extend(e.elements.iter().flat_map(|&x| [x, x + 1]));
    let mine: Vec<u32> = effect.nodes.iter().copied().chain(effect.elements.iter().flat_map(|&x| [x, x + 1])).collect();
    mine.iter().any(|&m| places.iter().any(|&p| near(m, p)))
}

/// Whether a finding of the loop reports an expected finding: its kind on
/// its channels (a swap may also be reported as the two channels each at
/// the other's place).
fn reports(found: &rfm_update::checks::Finding, expected: &Finding) -> bool {
    let on = |c: &frf::Channel| found.channels.contains(&c.to_string());
    match expected {
        Finding::Polarity { channel } => found.kind == FindingKind::InvertedPolarity && on(channel),
        Finding::Swapped { a, b } => found.kind == FindingKind::SwappedChannels && on(a) && on(b),
        Finding::Misdirected { channel, measured, .. } => {
            found.kind == FindingKind::MisdirectedChannel
                && on(channel)
                && found.corrections.iter().any(|c| c.measured_at == Some(*measured))
        }
        Finding::WrongNode { channel, measured } => {
            found.kind == FindingKind::WrongNode
                && on(channel)
                && found.corrections.iter().any(|c| c.measured_at == Some(*measured))
        }
        Finding::Calibration { channel, factor } => {
            found.kind == FindingKind::Calibration
                && on(channel)
                && found.corrections.iter().any(|c| (c.scale * factor - 1.0).abs() < 0.05)
        }
    }
}

/// How a trial's outcome reads against one of its right answers.
#[derive(Debug, Default)]
struct Score {
    /// Every expected finding reported.
    findings: bool,
    /// Effects added that the answer does not hold.
    spurious: Vec<String>,
    /// Every expected effect added.
    effects: bool,
    /// The verdict is the answer's (explained; or inadequate with a description).
    verdict: bool,
}

fn score(o: &FixOutcome, answer: &Expect) -> Score {
    let channel_findings: Vec<&rfm_update::checks::Finding> =
        o.findings.iter().filter(|f| f.kind != FindingKind::ExtraMode).collect();
    let (findings, effects, inadequate): (&[Finding], &[ExpectedEffect], bool) = match answer {
        Expect::Nothing { .. } | Expect::DeclaredOnly { .. } => (&[], &[], false),
        Expect::Found { findings, effects } => (findings, effects, false),
        Expect::Inadequate { findings, effects, .. } => (findings, effects, true),
        Expect::OneOf(_) => unreachable!("answers are flat"),
    };
    let reported = findings.iter().all(|e| channel_findings.iter().any(|f| reports(f, e)))
        && channel_findings.iter().all(|f| findings.iter().any(|e| reports(f, e)));
    let spurious: Vec<String> =
        o.effects.iter().filter(|x| !effects.iter().any(|e| matches(x, e))).map(|x| x.description.clone()).collect();
    let all_found = effects.iter().all(|e| o.effects.iter().any(|x| matches(x, e)));
    let verdict = if inadequate {
        matches!(o.stop, FixStop::ModelInadequate | FixStop::Ambiguous) && !o.remains.is_empty()
    } else {
        o.explained()
    };
    Score { findings: reported, spurious, effects: all_found, verdict }
}

struct Trial {
    family: LabFamily,
    label: String,
    /// The best-scoring answer's score.
    score: Score,
    outcome: FixOutcome,
    exit9: bool,
    /// The steps undone ([`rfm_update::fix::FixProgress::Redone`]).
    redone: Vec<(usize, Vec<String>)>,
}

fn run(t: &LabTrial, seed: u64) -> Trial {
    let dir = tempfile::tempdir().expect("a folder");
    t.dump(dir.path(), seed).expect("the trial written");
    let study = rfm_update::Study::load(&dir.path().join("nominal.toml")).expect("the trial's case loads");
    let opts = FixOptions {
        max_steps: 3,
        diagnose: study.diagnose_options(study.measured()).expect("options"),
        ..FixOptions::default()
    };
    let mut redone = Vec::new();
    let progress = |p: rfm_update::fix::FixProgress<'_>| {
        if let rfm_update::fix::FixProgress::Redone { step, effects } = p {
            redone.push((step, effects));
        }
    };
    let outcome = match fix(study.case(), study.measured(), &opts, progress) {
        Ok(o) => o,
        Err(e) => {
            let kept = dir.keep();
            panic!("{}: the loop failed: {e} (the trial's files are in {})", t.label, kept.display())
        }
    };
    let key = |s: &Score| {
        usize::from(s.findings) + usize::from(s.spurious.is_empty()) + usize::from(s.effects) + usize::from(s.verdict)
    };
    let score = t.expect.answers().into_iter().map(|a| score(&outcome, a)).max_by_key(key).expect("an answer");
    let exit9 = matches!(outcome.stop, FixStop::ModelInadequate | FixStop::Ambiguous) && !outcome.explained();
    if std::env::var("LAB_KEEP").is_ok() {
        println!("      the trial's files: {}", dir.keep().display());
    }
    Trial { family: t.family, label: t.label.clone(), score, outcome, exit9, redone }
}

#[test]
fn the_loop_tells_the_test_set_up_from_the_structure_and_stops_where_nothing_explains_the_data() {
    let per = study_size("LAB_PER", 1, 4);
    let seed = study_size("LAB_SEED", 2711, 2711) as u64;
    let reduced = !full_study() && std::env::var("LAB_PER").is_err();
    let only: Option<Vec<usize>> =
        std::env::var("LAB_ONLY").ok().map(|v| v.split(',').filter_map(|k| k.trim().parse().ok()).collect());
    let draws = lab::trials(per, seed);
    let mut trials: Vec<Trial> = Vec::new();
    for (i, t) in draws.iter().enumerate() {
        if only.as_ref().is_some_and(|k| !k.contains(&i))
            || (reduced && !(REDUCED.contains(&t.family) && t.with.is_none()))
        {
            continue;
        }
        let trial = run(t, 8000 + i as u64);
        let o = &trial.outcome;
        let s = &trial.score;
        println!(
            "{i:>3} {:<70} | findings {} effects {} verdict {} | {:?} {:.2} x noise | added {:?}{}",
            trial.label,
            s.findings,
            s.effects,
            s.verdict,
            o.stop,
            o.final_misfit() / o.noise,
            o.effects.iter().map(|e| e.description.as_str()).collect::<Vec<_>>(),
            if s.spurious.is_empty() { String::new() } else { format!(" | spurious {:?}", s.spurious) }
        );
        // the loop keeps only updates that reached a stationary point: no
        // kept step reads as stalled, whatever it leaves
        for st in &o.steps {
            assert!(st.status != Status::Stalled, "{}: step {} shows stalled", trial.label, st.effect.description);
        }
        if std::env::var("LAB_VERBOSE").is_ok() {
            for (k, st) in o.steps.iter().enumerate() {
                println!(
                    "      step {k}: {} | added {:.2} updated {:.2} corrected {:?} x noise | dBIC {:.3e} | {:?}",
                    st.effect.description,
                    st.misfit_added / o.noise,
                    st.misfit_updated / o.noise,
                    st.corrected_misfit.map(|m| m / o.noise),
                    st.delta_bic,
                    st.status
                );
            }
            for f in &o.findings {
                println!("      finding after step {}: {:?} {:?}", f.found_after_step, f.kind, f.channels);
            }
        }
        trials.push(trial);
    }
    let mut table: BTreeMap<String, (usize, usize)> = BTreeMap::new();
    let mut tally = |key: &str, ok: bool| {
        let e = table.entry(key.to_string()).or_default();
        e.0 += usize::from(ok);
        e.1 += 1;
    };
    for t in &trials {
        if t.family.is_setup() {
            tally("data error reported as such", t.score.findings);
        }
        if t.family == LabFamily::Resonator {
            tally("resonator found", t.score.effects);
        }
        tally("no spurious effect", t.score.spurious.is_empty());
        if t.family.outside().is_some() {
            tally("outside every family: exit 9 with a description", t.exit9 && !t.outcome.remains.is_empty());
        }
        tally(
            &format!("right in full: {:?}", t.family),
            t.score.findings && t.score.effects && t.score.spurious.is_empty() && t.score.verdict,
        );
    }
    println!();
    for (k, (ok, n)) in &table {
        println!("{k:<50} {ok:>3}/{n}");
    }
    if reduced && only.is_none() {
        for t in &trials {
            let s = &t.score;
            assert!(
                s.findings && s.effects && s.spurious.is_empty() && s.verdict,
                "{}: {s:?}, {:?} at {:.2} x noise",
                t.label,
                t.outcome.stop,
                t.outcome.final_misfit() / t.outcome.noise
            );
        }
        assert_eq!(trials.len(), REDUCED.len(), "one trial of each reduced family");
        return;
    }
    if only.is_some() || per < 4 {
        return;
    }
    let rate = |k: &str| table.get(k).map_or(1.0, |&(ok, n)| ok as f64 / n as f64);
    assert!(trials.len() >= 60, "at least 60 trials, not {}", trials.len());
    for (k, bound) in [
        ("data error reported as such", 0.90),
        ("resonator found", 0.85),
        ("no spurious effect", 0.95),
        ("outside every family: exit 9 with a description", 0.95),
    ] {
        if let Some((_, last)) = NOT_YET_MET.iter().find(|(name, _)| *name == k) {
            // a criterion met now is asserted from now on: take it off the list
            assert!(rate(k) < bound, "{k}: {:?} meets {bound}; take it off NOT_YET_MET", table.get(k));
            println!("NOT MET (issue 32): {k}: {:?} below {bound} (last full run: {last})", table.get(k));
        } else {
            assert!(rate(k) >= bound, "{k}: {:?} below {bound}", table.get(k));
        }
    }
}

/// The rule that tells a resonator which explains the mode it was offered
/// for from one that bends toward a mode of another form
/// (`fix/explains.rs`), on both, as the full study draws them: trial 20, a
/// 77 g resonator with 3.4 % damping between the cantilever's first two
/// modes, is found, alone, and the data explained; trial 49, a fin across
/// the cantilever whose bending its root's rotation drives, draws
/// resonators tuned to its mode that leave that mode's lines far above the
/// noise: none is kept, the loop stops as inadequate, and what remains
/// names the mode.
#[test]
fn a_resonator_that_explains_its_mode_is_kept_and_one_bent_toward_a_fin_is_not() {
    let draws = lab::trials(4, 2711);
    let (res, fin) = (&draws[20], &draws[49]);
    assert_eq!((res.family, fin.family), (LabFamily::Resonator, LabFamily::Fin), "the full study's draws");
    let r = run(res, 8020);
    let o = &r.outcome;
    println!(
        "{}: {:?} {:?} at {:.2} x noise",
        r.label,
        o.effects.iter().map(|e| &e.description).collect::<Vec<_>>(),
        o.stop,
        o.final_misfit() / o.noise
    );
    assert!(r.score.effects && r.score.spurious.is_empty() && o.explained(), "{}: {:?}", r.label, r.score);
    let f = run(fin, 8049);
    let o = &f.outcome;
    println!(
        "{}: {:?} {:?}; {}; remains {:?}",
        f.label,
        o.effects.iter().map(|e| &e.description).collect::<Vec<_>>(),
        o.stop,
        o.stop_reason,
        o.remains
    );
    assert!(!o.effects.iter().any(|e| e.kind == EffectKind::Resonator), "{}: {:?}", f.label, o.effects);
    assert!(f.exit9 && f.score.spurious.is_empty(), "{}: {:?} {:?}", f.label, o.stop, f.score);
    assert!(o.stop_reason.contains("the wrong form for the data's mode at"), "{}", o.stop_reason);
    assert!(o.remains.iter().any(|s| s.contains("which no candidate explains")), "{:?}", o.remains);
}

/// Two rules of a step beside a data error (`fix.rs`), on the full study's
/// draws. Trial 64: a sensor at the next node beside a lumped mass with its
/// rotary inertia, which the checks find only once a mass is fitted; the
/// step chosen on the wrong data (a mass change of two elements, which
/// then drew a stiffness change and a mass to make up for its form) is
/// made again on the corrected data, and the lumped mass alone explains
/// them. Trial 68: a channel 15 % low beside a lumped mass that the data
/// hold with the structure's damping (the tool's lumped mass has none);
/// after the mass the model leaves 8 % above the noise its residual reads,
/// 2 % above the data's own reading, and a shaker at the drive point that
/// takes up a third of that excess is not added.
#[test]
fn a_step_is_made_on_the_corrected_data_and_takes_nothing_that_explains_a_third_of_what_is_left() {
    let draws = lab::trials(4, 2711);
    for (i, family) in [(64, LabFamily::WrongNode), (68, LabFamily::Calibration)] {
        let t = &draws[i];
        assert_eq!(t.family, family, "the full study's draws");
        let r = run(t, 8000 + i as u64);
        let o = &r.outcome;
        let added: Vec<&str> = o.effects.iter().map(|e| e.description.as_str()).collect();
        println!("{}: {added:?} {:?} at {:.3} x noise", r.label, o.stop, o.final_misfit() / o.noise);
        let s = &r.score;
        assert!(s.findings && s.effects && s.spurious.is_empty() && s.verdict, "{}: {s:?}, added {added:?}", r.label);
        assert_eq!(o.steps.len(), 1, "{}: {added:?}", r.label);
        // the data error was found after the first step, which was made again
        assert!(o.findings.iter().any(|f| !f.corrections.is_empty() && f.found_after_step == 1), "{}", r.label);
        assert!(o.steps[0].corrected_misfit.is_none(), "{}: the step was kept, not made again", r.label);
        // and the loop said so, naming the step it undid
        assert!(matches!(r.redone.first(), Some((0, undone)) if !undone.is_empty()), "{}: {:?}", r.label, r.redone);
    }
}
