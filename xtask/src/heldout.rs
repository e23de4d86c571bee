//! `cargo xtask heldout`: the full held-out study of the diagnosis loop.
//!
//! The test `held_out` of rfm-update runs a reduced study on CI (4 trials
//! per family, 6 pairs, 10 null trials). This task runs the same test, with
//! the same criteria, at the study's full size: 12 trials per family, 16
//! pairs and 20 null trials (about 15 minutes on two cores), in the release
//! profile, and fails when the test does.

/// Runs the held-out tests of rfm-update at full size.
pub(crate) fn heldout(args: &[String]) -> Result<(), String> {
    if !args.is_empty() {
        return Err(format!("heldout takes no arguments (got {})", args.join(" ")));
    }
    let status = crate::cargo()
        .current_dir(crate::root())
        .args([
            "test",
            "--release",
            "-p",
            "rfm-update",
            "--test",
            "it",
            "held_out",
            "--",
            "--nocapture",
            "--include-ignored",
        ])
        .env("HELD_OUT_SINGLE", "12")
        .env("HELD_OUT_PAIRS", "16")
        .env("HELD_OUT_NULL", "20")
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if status.success() { Ok(()) } else { Err("the held-out study missed a criterion (see above)".into()) }
}
