//! What the one-configuration-per-process examples (`bench_point`,
//! `diagnose_point`) share: their argument parsing, and the CPU time and
//! peak memory they report to `cargo xtask bench`.

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

/// CPU time used so far by all threads of this process (s), from
/// /proc/self/task/*/schedstat (nanoseconds on the CPU). Rayon's threads
/// live as long as the process, so none of their time is lost.
pub(crate) fn cpu_seconds() -> Option<f64> {
    let mut total = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let stat = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        total += stat.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(total as f64 * 1e-9)
}
