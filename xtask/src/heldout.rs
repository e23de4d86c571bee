//! `cargo xtask heldout`: the statistical studies at the size their criteria
//! ask for.
//!
//! `cargo test` runs each study of rfm-update at a reduced size that goes
//! through every behaviour and checks the rates. This task runs the same
//! tests with `RFM_STUDY=full`: the held-out study of the loop (12 trials
//! per family, 8 pairs, 20 null trials), the hidden-effect diagnosis (13
//! trials per kind, 20 null trials) and the lab study (4 trials per family
//! of `tests/it/lab.rs`: 72), with their counts asserted, and writes every
//! effect of every diagnosis of the cases into a case file (`cargo test`
//! writes a sample of each kind of edit). Only the tests
//! whose size `RFM_STUDY` sets run here: the other tests of those modules
//! are the same either way, and CI, which runs this after `cargo test`,
//! ran them there (they took about four minutes of this task before). It
//! builds in the test profile, as `cargo test` does (opt-level 3 in this workspace), and
//! for the whole workspace (`--workspace --test it`, the filters select
//! rfm-update's studies), so that cargo resolves the dependencies' features
//! as `cargo test --workspace` did and CI, which runs it after the tests,
//! compiles nothing again (`-p rfm-update` alone would compile faer,
//! nalgebra and the workspace once more). The
//! studies' own variables (`HELD_OUT_PAIRS=16`, `LAB_PER`, ...) still set
//! their sizes. It fails when a study misses a criterion.

/// The studies: the tests of rfm-update's integration tests whose size
/// `RFM_STUDY=full` sets (`crate::study_size` and `crate::full_study` in
/// `crates/rfm-update/tests/it/main.rs`), matched exactly.
const STUDIES: [&str; 6] = [
    "apply_every::every_ranked_effect_applies_to_the_tutorial_the_papers_cases_and_samples",
    "held_out::the_loop_finds_and_fixes_held_out_effects",
    "held_out::null_trials_find_nothing_significant",
    "hidden_effects::diagnosis_names_hidden_effects_and_updating_recovers_them",
    "hidden_effects::diagnosis_finds_nothing_significant_when_nothing_is_hidden",
    "lab_study::the_loop_tells_the_test_set_up_from_the_structure_and_stops_where_nothing_explains_the_data",
];

/// Runs rfm-update's statistical studies at full size.
pub(crate) fn heldout(args: &[String]) -> Result<(), String> {
    if !args.is_empty() {
        return Err(format!("heldout takes no arguments (got {})", args.join(" ")));
    }
    let status = crate::cargo()
        .current_dir(crate::root())
        .args(["test", "--workspace", "--test", "it", "--"])
        .args(STUDIES)
        .args(["--exact", "--nocapture", "--test-threads", "2"])
        .env("RFM_STUDY", "full")
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if status.success() { Ok(()) } else { Err("a statistical study missed a criterion (see above)".into()) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every study named is a test of its module, and every test of those
    /// modules that reads the study's size is named: a renamed test would
    /// otherwise drop out of CI's full-size run without a word.
    #[test]
    fn the_studies_are_the_tests_sized_by_rfm_study() {
        let dir = crate::root().join("crates/rfm-update/tests/it");
        for module in ["apply_every", "held_out", "hidden_effects", "lab_study"] {
            let text = std::fs::read_to_string(dir.join(format!("{module}.rs"))).expect("the study's module");
            // each test function, and whether its body reads the size
            let mut tests = Vec::new();
            for part in text.split("#[test]").skip(1) {
                let name = part.split("fn ").nth(1).and_then(|r| r.split('(').next()).expect("a test function");
                let body = part.split("\n}\n").next().unwrap_or(part);
                let sized = body.contains("study_size(") || body.contains("full_study()");
                tests.push((format!("{module}::{name}"), sized));
            }
            for (name, sized) in &tests {
                assert_eq!(STUDIES.contains(&name.as_str()), *sized, "{name}: sized by RFM_STUDY {sized}");
            }
            for study in STUDIES.iter().filter(|s| s.starts_with(&format!("{module}::"))) {
                assert!(tests.iter().any(|(n, _)| n == study), "{study} is no test of {module}.rs");
            }
        }
    }
}
