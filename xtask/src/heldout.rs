//! `cargo xtask heldout`: the statistical studies at the size their criteria
//! ask for.
//!
//! `cargo test` runs each study of rfm-update at a reduced size that goes
//! through every behaviour and checks the rates. This task runs the same
//! tests with `RFM_STUDY=full`: the held-out study of the loop (12 trials
//! per family, 8 pairs, 20 null trials), the hidden-effect diagnosis (13
//! trials per kind, 20 null trials) and the lab study (4 trials per family
//! of `tests/it/lab.rs`: 72), with their counts asserted. It builds in the
//! test profile, as `cargo test` does (opt-level 3 in this workspace), and
//! for the whole workspace (`--workspace --test it`, the filters select
//! rfm-update's studies), so that cargo resolves the dependencies' features
//! as `cargo test --workspace` did and CI, which runs it after the tests,
//! compiles nothing again (`-p rfm-update` alone would compile faer,
//! nalgebra and the workspace once more). The
//! studies' own variables (`HELD_OUT_PAIRS=16`, `LAB_PER`, ...) still set
//! their sizes. It fails when a study misses a criterion.

/// The studies' test filters in rfm-update's integration tests.
const STUDIES: [&str; 3] = ["held_out::", "hidden_effects::", "lab_study::"];

/// Runs rfm-update's statistical studies at full size.
pub(crate) fn heldout(args: &[String]) -> Result<(), String> {
    if !args.is_empty() {
        return Err(format!("heldout takes no arguments (got {})", args.join(" ")));
    }
    let status = crate::cargo()
        .current_dir(crate::root())
        .args(["test", "--workspace", "--test", "it", "--"])
        .args(STUDIES)
        .args(["--nocapture", "--test-threads", "2"])
        .env("RFM_STUDY", "full")
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if status.success() { Ok(()) } else { Err("a statistical study missed a criterion (see above)".into()) }
}
