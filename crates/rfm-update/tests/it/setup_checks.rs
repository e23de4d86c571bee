//! The checks of the data for set-up errors ([`rfm_update::checks`]) on the
//! held-out truths ([`crate::truths`]: case files written apart from the
//! tool, each with a hidden effect the nominal model lacks), with set-up
//! errors applied to the measured channels by plain array operations:
//! a model error must not pass for a set-up error, and each set-up error
//! must be found, on its channel, with the correction that removes it,
//! while the model error is still there.

use damping::DampedSystem;
use fe_model::DofRef;
use fe_model::case::Gains;
use frf::{Channel, FrfSet, NoiseModel, synthesize};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rfm_update::checks::{CheckOptions, Finding, FindingKind, check_channels};

use crate::truths::{self, Family, Truth};

const NOISE: f64 = 0.01;

fn opts() -> CheckOptions {
    CheckOptions { lines: 200, gains: Gains::None, weights: None, noise: NOISE }
}

/// The truths: two of each family, drawn as the held-out study draws them.
fn truths() -> Vec<Truth> {
    let mut rng = ChaCha8Rng::seed_from_u64(4242);
    Family::ALL
        .iter()
        .flat_map(|&f| (0..2).map(|_| truths::draw(&mut rng, Some(f), false)).collect::<Vec<_>>())
        .collect()
}

/// The truth's clean receptances on its channels.
fn clean(t: &Truth) -> FrfSet {
    let sys = DampedSystem::new(t.truth_case().model).unwrap();
    synthesize(&sys, &t.frf_channels(), &t.lines_hz).unwrap()
}

fn noisy(mut set: FrfSet, seed: u64) -> FrfSet {
    NoiseModel::relative(NOISE, seed).apply(&mut set);
    set
}

fn nominal(t: &Truth) -> DampedSystem {
    DampedSystem::new(t.nominal_case().model).unwrap()
}

fn channel_findings(f: &[Finding]) -> Vec<&Finding> {
    f.iter().filter(|f| f.kind != FindingKind::ExtraMode).collect()
}

#[test]
fn model_errors_are_not_taken_for_set_up_errors() {
    for (i, t) in truths().iter().enumerate() {
        let data = noisy(clean(t), 100 + i as u64);
        let found = check_channels(&nominal(t), &data, &opts()).unwrap();
        let wrong = channel_findings(&found);
        assert!(wrong.is_empty(), "{}: {:#?}", t.label, wrong);
    }
}

/// A truth's receptance at another DOF of a channel's reference.
fn truth_at(t: &Truth, dof: DofRef, reference: DofRef) -> Vec<num_complex::Complex64> {
    let sys = DampedSystem::new(t.truth_case().model).unwrap();
    synthesize(&sys, &[Channel::new(dof, reference)], &t.lines_hz).unwrap().channel(0).to_vec()
}

/// What the checks made of one set-up error.
#[derive(Debug, PartialEq)]
enum Outcome {
    /// Exactly one finding, of the right kind, on the right channels.
    Right,
    /// No finding.
    Nothing,
    /// Anything else.
    Wrong(Vec<String>),
}

fn outcome(found: &[Finding], kind: FindingKind, channels: &[Channel], at: Option<DofRef>) -> Outcome {
    let f = channel_findings(found);
    let names: Vec<String> = channels.iter().map(ToString::to_string).collect();
    let moved_to = |one: &Finding| at.is_none_or(|d| one.corrections.iter().any(|c| c.measured_at == Some(d)));
    match f.as_slice() {
        [] => Outcome::Nothing,
        [one] if one.kind == kind && names.iter().all(|n| one.channels.contains(n)) && moved_to(one) => Outcome::Right,
        _ => Outcome::Wrong(f.iter().map(|f| f.summary.clone()).collect()),
    }
}

/// One set-up error applied to clean data: (what, data, kind, channels
/// concerned, the DOF the correction must name when it names one).
type SetUpError = (&'static str, FrfSet, FindingKind, Vec<Channel>, Option<DofRef>);

/// The set-up errors of one trial, each applied alone to its clean data.
fn set_up_errors(t: &Truth, sys: &DampedSystem, rng: &mut ChaCha8Rng) -> Option<Vec<SetUpError>> {
    let base = clean(t);
    let n = base.channels().len();
    let c = rng.random_range(0..n);
    let ch = base.channels()[c];
    // another channel, not at the driving point, for the moves
    let other = (0..n).rev().find(|&k| k != c && base.channels()[k].response != ch.reference).unwrap();
    let oc = base.channels()[other];
    // the nearest node (either side, one or two away) whose response differs
    // from the channel's by at least 10 times the noise: a sensor one node
    // off where the two move alike is no error the data can show
    let r = oc.response;
    let own = truth_at(t, r, oc.reference);
    let next = [1i64, -1, 2, -2]
        .into_iter()
        .filter_map(|k| u32::try_from(i64::from(r.node.0) + k).ok())
        .map(|n| DofRef::new(n, r.dof))
        .filter(|d| sys.model().node(d.node).is_some() && base.channels().iter().all(|c| c.response != *d))
        .find(|d| {
            let other = truth_at(t, *d, oc.reference);
            let rms =
                (own.iter().zip(&other).map(|(a, b)| (b / a).ln().norm_sqr()).sum::<f64>() / own.len() as f64).sqrt();
            rms > 10.0 * NOISE
        })?;
    // the other translation at the channel's own node, where the truth
    // moves differently by at least 10 times the noise (a sensor turned on
    // its mount, read upside down as well)
    let mine = truth_at(t, ch.response, ch.reference);
    let turned = sys
        .model()
        .node_dofs()
        .iter()
        .filter(|d| d.is_translation() && **d != ch.response.dof)
        .map(|&d| DofRef::new(ch.response.node.0, d))
        .filter(|&d| {
            matches!(sys.assembly().dofs().slot(d), Some(fe_model::Slot::Free(_)))
                && base.channels().iter().all(|c| c.response != d)
        })
        .find(|&d| {
            let other = truth_at(t, d, ch.reference);
            let rms =
                (mine.iter().zip(&other).map(|(a, b)| (b / a).ln().norm_sqr()).sum::<f64>() / mine.len() as f64).sqrt();
            other.iter().all(|v| v.norm() > 0.0) && rms > 10.0 * NOISE
        });
    let with = |f: &dyn Fn(&mut FrfSet)| {
        let mut s = base.clone();
        f(&mut s);
        s
    };
    let turned = turned.map(|d| {
        let h: Vec<_> = truth_at(t, d, ch.reference).iter().map(|v| -v).collect();
        ("turned", with(&|s| s.channel_mut(c).copy_from_slice(&h)), FindingKind::MisdirectedChannel, vec![ch], Some(d))
    });
    let mut errors = vec![
        (
            "inverted",
            with(&|s| s.channel_mut(c).iter_mut().for_each(|v| *v = -*v)),
            FindingKind::InvertedPolarity,
            vec![ch],
            None,
        ),
        (
            "swapped",
            with(&|s| {
                let (a, b) = (s.channel(c).to_vec(), s.channel(other).to_vec());
                s.channel_mut(c).copy_from_slice(&b);
                s.channel_mut(other).copy_from_slice(&a);
            }),
            FindingKind::SwappedChannels,
            vec![ch, oc],
            None,
        ),
        (
            "next node",
            with(&|s| s.channel_mut(other).copy_from_slice(&truth_at(t, next, oc.reference))),
            FindingKind::WrongNode,
            vec![oc],
            Some(next),
        ),
        (
            "scaled by 1.25",
            with(&|s| s.channel_mut(c).iter_mut().for_each(|v| *v *= 1.25)),
            FindingKind::Calibration,
            vec![ch],
            None,
        ),
    ];
    errors.extend(turned);
    Some(errors)
}

/// With the hidden model error still in the data, an inverted channel is
/// found on its channel in at least 90 % of the trials, a swapped,
/// misplaced or turned one (the other axis at its node, inverted: the
/// correction must name that DOF, also where DOFs along a member fit it
/// alike) in at least 75 % (a large model error can hide them until the
/// loop has fitted it: against the true model, the stand-in for the model
/// the loop ends with, each of the five errors is found in at least 95 %),
/// and nothing else is ever claimed. A calibration error, which a
/// model error hides, is found or nothing is said.
#[test]
fn each_set_up_error_is_found_on_its_channel_with_its_correction() {
    let mut rng = ChaCha8Rng::seed_from_u64(77);
    let mut rows = Vec::new();
    let mut tally = std::collections::BTreeMap::<String, (usize, usize, usize)>::new();
    let mut trials = truths();
    let mut null_rng = ChaCha8Rng::seed_from_u64(78);
    trials.extend((0..6).map(|_| truths::null(&mut null_rng)));
    for (i, t) in trials.iter().enumerate() {
        let nominal = nominal(t);
        let truth = DampedSystem::new(t.truth_case().model).unwrap();
        let errors = set_up_errors(t, &nominal, &mut rng).expect("a neighbour that moves differently");
        for (what, data, kind, channels, at) in errors {
            let data = noisy(data, 500 + i as u64);
            for (against, sys) in [("nominal", &nominal), ("truth", &truth)] {
                let found = check_channels(sys, &data, &opts()).unwrap();
                let o = outcome(&found, kind, &channels, at);
                let key = format!("{what}, against the {against}");
                let e = tally.entry(key).or_default();
                match &o {
                    Outcome::Right => e.0 += 1,
                    Outcome::Nothing => e.1 += 1,
                    Outcome::Wrong(_) => e.2 += 1,
                }
                if o != Outcome::Right {
                    rows.push(format!("{:<50} {what:<16} against the {against}: {o:?}", t.label));
                }
            }
        }
    }
    println!("{}", rows.join("\n"));
    for (k, (right, nothing, wrong)) in &tally {
        println!("{k:<36} right {right:>3}  nothing {nothing:>3}  wrong {wrong:>3}");
        assert_eq!(*wrong, 0, "{k}: a wrong finding");
        let rate = *right as f64 / (right + nothing) as f64;
        let bound = match k.as_str() {
            k if k.ends_with("truth") => 0.95,
            "inverted, against the nominal" => 0.90,
            "scaled by 1.25, against the nominal" => 0.0,
            _ => 0.75,
        };
        assert!(rate >= bound, "{k}: found in {right} of {}, below {bound}", right + nothing);
    }
}

/// The corrections the checks propose, written into the case as
/// `[[measurement.corrections]]`, undo the set-up errors when the case reads
/// its data again: an inverted channel, a miscalibrated one and two swapped
/// ones come back as the clean measurement, to round-off.
#[test]
fn corrections_written_into_the_case_undo_the_set_up_errors_when_read() {
    let mut rng = ChaCha8Rng::seed_from_u64(4243);
    let t = truths::null(&mut rng);
    let clean = clean(&t);
    let n = clean.channels().len();
    let (flip, scale, a, b) = (0, 1, n - 3, n - 2);
    let mut data = clean.clone();
    data.channel_mut(flip).iter_mut().for_each(|v| *v = -*v);
    data.channel_mut(scale).iter_mut().for_each(|v| *v *= 0.8);
    let (va, vb) = (data.channel(a).to_vec(), data.channel(b).to_vec());
    data.channel_mut(a).copy_from_slice(&vb);
    data.channel_mut(b).copy_from_slice(&va);
    let found = check_channels(&nominal(&t), &data, &opts()).unwrap();
    let kinds: Vec<FindingKind> = found.iter().map(|f| f.kind).collect();
    assert_eq!(
        kinds,
        vec![FindingKind::SwappedChannels, FindingKind::InvertedPolarity, FindingKind::Calibration],
        "{found:#?}"
    );

    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("measured.csv"), frf::io::csv::to_csv_string(&data)).unwrap();
    let path = dir.path().join("case.toml");
    let case =
        fe_model::CaseFile::parse(&path, &format!("{}{}", t.nominal, t.measurement_table("measured.csv"))).unwrap();
    let mut editor = case.editor().unwrap();
    for f in &found {
        f.write(&mut editor).unwrap();
    }
    let text = editor.text_at(&path).unwrap();
    assert_eq!(text.matches("[[measurement.corrections]]").count(), 4, "{text}");
    std::fs::write(&path, &text).unwrap();
    let study = rfm_update::Study::load(&path).unwrap();
    let read = study.measured();
    // in the case's order (a swapped response listed where the test named it)
    let mut names = read.channels().to_vec();
    names.sort_by_key(|c| c.response.node.0);
    assert_eq!(names, clean.channels());
    for c in 0..n {
        let r = read.find(clean.channels()[c]).unwrap();
        for (x, y) in read.channel(r).iter().zip(clean.channel(c)) {
            // the calibration's scale is estimated from the data, the rest exact
            let tol = if c == scale { 0.02 } else { 1e-12 };
            assert!((x - y).norm() <= tol * y.norm(), "channel {c}: {x} vs {y}");
        }
    }
    assert!(study.notes().iter().any(|n| n.contains("sign inverted")), "{:?}", study.notes());
}

/// Two channels exchanged at the front end (the tutorial's 9:ux and
/// 13:ux), against a model that lacks the truth's corner joint and leaves
/// the median channel at about 140 times the noise: exchanged, the two
/// fit like the other channels, not four times better than before (no
/// exchange fits below what the model error leaves), and the swap is
/// found, on its own, with the inverted channel beside it.
#[test]
fn a_swap_is_found_beside_a_large_model_error() {
    let case = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/tutorial/l-frame-truth.toml");
    let study = rfm_update::Study::load(&case).unwrap();
    let truth = study.truth().expect("the case's truth");
    let channels = study.measured().channels().to_vec();
    let mut data = synthesize(truth, &channels, study.measured().frequencies_hz()).unwrap();
    let at =
        |node: u32, dof: fe_model::Dof| channels.iter().position(|c| c.response == DofRef::new(node, dof)).unwrap();
    let (a, b, c) = (at(9, fe_model::Dof::Ux), at(13, fe_model::Dof::Ux), at(17, fe_model::Dof::Uy));
    let (ha, hb) = (data.channel(a).to_vec(), data.channel(b).to_vec());
    data.channel_mut(a).copy_from_slice(&hb);
    data.channel_mut(b).copy_from_slice(&ha);
    data.channel_mut(c).iter_mut().for_each(|v| *v = -*v);
    let data = noisy(data, 31);
    let found = check_channels(study.system(), &data, &opts()).unwrap();
    let kinds: Vec<_> = found.iter().map(|f| (f.kind, f.channels.clone())).collect();
    assert_eq!(found.len(), 2, "{kinds:?}");
    let swap = found.iter().find(|f| f.kind == FindingKind::SwappedChannels).expect("the swap found");
    for ch in [channels[a], channels[b]] {
        assert!(swap.channels.contains(&ch.to_string()), "{kinds:?}");
    }
    assert!(found.iter().any(|f| f.kind == FindingKind::InvertedPolarity && f.channels == [channels[c].to_string()]));
    // the model error is as large as said: the median channel far above the noise
    assert!(swap.misfit_after > 50.0 * NOISE, "{}", swap.misfit_after);
}
