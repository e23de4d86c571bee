//! `cargo xtask heldout`: the held-out study of the diagnosis loop, larger.
//!
//! The test `held_out` of rfm-update runs on CI at the size the criteria ask
//! for (12 trials per family, 8 pairs, 20 null trials). This task runs the
//! same test, with the same criteria, with twice the pairs (16, the first 8
//! CI's), in the release profile (about 17 minutes on two cores), and fails
//! when the test does.

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
