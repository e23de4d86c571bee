//! `rfm diagnose --apply` for every candidate of every kind: on the
//! tutorials (the lab frame's resonators among them), the paper's case
//! studies and small sample models, every ranked effect is written into a
//! new case file in another folder; the written
//! case loads, reads its measured data through a path relative to itself,
//! and its misfit with the fitted values equals the diagnosis's to 1e-6.
//! Its `[update]` holds the effect's determined parameters and all its
//! damping parameters, determined or not.
//! The per-direction variants of supports and joints (a spring and a group
//! per direction) are among them.
//!
//! `cargo test` applies, on each case, the first two and the last effect of
//! every class of the ranking (kind, damping form, per-direction or not,
//! held parameters, each parameter's role and whether it is determined):
//! every kind of edit the diagnosis can ask for, on every case, at a
//! fifth of the cost. `cargo xtask heldout` (`RFM_STUDY=full`) applies
//! every ranked effect, about 5,300.

use damping::DampedSystem;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use fe_model::CaseFile;
use rfm_update::Study;
use rfm_update::diagnose::{DiagnoseOptions, EffectKind, Ranked, diagnose, log_misfit};

fn cases_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases")
}

/// Small sample models as case files, each with a truth that differs from
/// it so that the diagnosis has something to find.
const SAMPLES: [(&str, &str); 2] = [
    ("portal.toml", include_str!("cases/apply-every-portal.toml")),
    ("beam.toml", include_str!("cases/apply-every-beam.toml")),
];

/// What makes two ranked effects the same edit of a case, whatever their
/// place: the kind, the damping form, the per-direction variant, whether
/// parameters are held, and each parameter's role and whether the data
/// determine it.
fn class(r: &Ranked) -> String {
    let mut roles: Vec<String> = r.parameters.iter().map(|p| format!("{:?}/{}", p.role, p.determined)).collect();
    roles.sort();
    format!(
        "{:?} {:?} per-direction {} held {} {roles:?}",
        r.kind,
        r.damping,
        r.description.contains("one group per direction"),
        !r.held.is_empty()
    )
}

/// The ranks (from 0) to apply: all of them when `every`, else the first
/// two and the last of each [`class`].
fn chosen(ranking: &[Ranked], every: bool) -> Vec<usize> {
    if every {
        return (0..ranking.len()).collect();
    }
    let mut members: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for (i, r) in ranking.iter().enumerate() {
        members.entry(class(r)).or_default().push(i);
    }
    let mut ranks: Vec<usize> =
        members.values().flat_map(|m| m.iter().take(2).chain(m.last()).copied().collect::<Vec<_>>()).collect();
    ranks.sort_unstable();
    ranks.dedup();
    ranks
}

/// Applies the ranked effects of the case's diagnosis ([`chosen`]) and
/// checks each written case; returns the kinds applied.
fn apply_every(case: CaseFile, dir: &Path, every: bool) -> BTreeSet<String> {
    let title = case.model.title.clone();
    let study = Study::from_case(case).unwrap_or_else(|e| panic!("{title}: {e}"));
    let mut opts = DiagnoseOptions::default();
    // resonators are offered at the measured modes the model lacks, as
    // `rfm diagnose` and `rfm fix` offer them (the lab frame has one)
    let sys = DampedSystem::new(study.case().model.clone()).unwrap();
    opts.candidates.resonator_hz = rfm_update::checks::extra_modes(&sys, study.measured())
        .unwrap_or_else(|e| panic!("{title}: {e}"))
        .iter()
        .filter_map(|f| f.frequency_hz)
        .collect();
    let d = diagnose(&study.case().model, study.measured(), &opts).unwrap_or_else(|e| panic!("{title}: {e}"));
    // the new cases go into another folder than the case's
    let out = dir.join("written");
    std::fs::create_dir_all(&out).unwrap();
    let synthesised = study.case().measurement.as_ref().and_then(|m| m.data.as_ref()).is_none();
    let data = out.join("measured.csv");
    if synthesised {
        std::fs::write(&data, frf::io::csv::to_csv_string(study.measured())).unwrap();
    }
    let target = out.join("applied.toml");
    let mut kinds = BTreeSet::new();
    // the case's own [update] parameters stay, whatever an effect says of them
    let own: Vec<String> =
        study.case().update.iter().flat_map(|u| u.parameters.iter().map(|p| p.name.clone())).collect();
    let ranks = chosen(&d.ranking, every);
    for &i in &ranks {
        let (r, rank) = (&d.ranking[i], i + 1);
        let editor = d
            .apply_with_data(study.case(), rank, synthesised.then_some(data.as_path()))
            .unwrap_or_else(|e| panic!("{title}, rank {rank} ({}): {e}", r.description));
        let text = editor.text_at(&target).unwrap_or_else(|e| panic!("{title}, rank {rank}: {e}"));
        // the data path is relative to the new file and names the same data
        let table: toml::Table = text.parse().unwrap();
        let written = table["measurement"]["data"].as_str().expect("a data path");
        assert!(Path::new(written).is_relative(), "{title}, rank {rank}: data path {written}");
        // the effect's determined parameters and all its damping parameters
        // are updated next; an undetermined stiffness or mass is not
        let updated: Vec<&str> =
            table["update"]["parameters"].as_array().unwrap().iter().filter_map(|v| v.as_str()).collect();
        for p in r.parameters.iter().filter(|p| !own.contains(&p.name)) {
            let damping = !p.role.is_stiffness_or_mass();
            assert_eq!(
                updated.contains(&p.name.as_str()),
                p.determined || damping,
                "{title}, rank {rank}: {} (determined {}) in [update] {updated:?}",
                p.name,
                p.determined
            );
            if damping && !p.determined {
                kinds.insert("undetermined damping updated".into());
            }
        }
        std::fs::write(&target, &text).unwrap();
        let applied = Study::load(&target).unwrap_or_else(|e| panic!("{title}, rank {rank} ({}): {e}", r.description));
        let misfit = log_misfit(applied.system(), applied.measured(), r.lines).unwrap();
        // the written case is the fitted candidate: the same misfit on the
        // same lines as the candidate's model with its fitted values, built
        // in memory
        let c = &d.candidates[r.candidate];
        let mut fitted = c.model(&study.case().model).unwrap();
        for p in &r.parameters {
            let param = fitted.parameter(&p.name).unwrap_or_else(|e| panic!("{title}, rank {rank}: {e}"));
            for &q in &param.quantities {
                fitted.set(q, p.value).unwrap();
            }
        }
        let expected = log_misfit(&DampedSystem::new(fitted).unwrap(), study.measured(), r.lines).unwrap();
        assert!(
            (misfit - expected).abs() <= 1e-9 * expected.max(1e-3),
            "{title}, rank {rank} ({}): misfit {misfit} of the written case, {expected} of the fitted candidate",
            r.description
        );
        // the case records the fall from the nominal model
        let history: Vec<f64> = applied.case().history.iter().map(|h| h.misfit).collect();
        assert_eq!(history, vec![d.nominal_misfit, r.misfit], "{title}, rank {rank}");
        kinds.insert(format!("{:?}", r.kind));
        if r.description.contains("one group per direction") {
            kinds.insert(format!("{:?} per direction", r.kind));
        }
    }
    println!("{title}: {} of {} ranked effects applied ({:?})", ranks.len(), d.ranking.len(), kinds);
    kinds
}

#[test]
fn every_ranked_effect_applies_to_the_tutorial_the_papers_cases_and_samples() {
    let every = crate::full_study();
    let tmp = tempfile::tempdir().unwrap();
    let mut kinds = BTreeSet::new();
    let mut paths: Vec<PathBuf> = std::fs::read_dir(cases_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    paths.push(cases_dir().join("tutorial/l-frame.toml"));
    // a frame that carries a resonator (and an inverted channel)
    paths.push(cases_dir().join("tutorial/lab-frame.toml"));
    assert!(paths.len() >= 9, "the six paper cases, the frame in space and the tutorials");
    for (k, path) in paths.iter().enumerate() {
        let case = CaseFile::load(path).unwrap();
        kinds.extend(apply_every(case, &tmp.path().join(format!("case-{k}")), every));
    }
    for (k, (name, text)) in SAMPLES.iter().enumerate() {
        let path = tmp.path().join(format!("sample-{k}")).join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, text).unwrap();
        kinds.extend(apply_every(CaseFile::load(&path).unwrap(), &tmp.path().join(format!("sample-{k}")), every));
    }
    // a support with a loss per direction, whose per-direction variant is written
    let dir = tmp.path().join("per-direction");
    kinds.extend(apply_every(
        crate::per_direction::nominal_case(&crate::per_direction::lossy_rotation(), &dir),
        &dir,
        every,
    ));
    println!("applied: {kinds:?}");
    for kind in ["FlexibleSupport per direction", "FlexibleJoint per direction", "undetermined damping updated"] {
        assert!(kinds.contains(kind), "no {kind} was applied");
    }
    for kind in EffectKind::ALL {
        assert!(kinds.contains(&format!("{kind:?}")), "no {kind:?} was applied");
    }
}
