//! What the one-configuration-per-process examples (`bench_point`,
//! `diagnose_point`) share: their argument parsing and the peak memory they
//! report to `cargo xtask bench`.

/// The value after `--name`, or `default` when the flag is absent.
pub(crate) fn arg<T: std::str::FromStr>(args: &[String], name: &str, default: T) -> T {
    match args.iter().position(|a| a == name) {
        Some(i) => args.get(i + 1).and_then(|v| v.parse().ok()).unwrap_or_else(|| panic!("{name} needs a value")),
        None => default,
    }
}

/// Peak resident set size of this process (KiB), from /proc/self/status.
pub(crate) fn peak_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}
