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

/// CPU time used so far by all threads of this process (s), those that
/// have ended included (the diagnosis frees its working data on threads of
/// their own): user and system time from /proc/self/stat, in the kernel's
/// clock ticks of 1/100 s (`USER_HZ`, fixed at 100 in Linux's ABI).
pub(crate) fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // the fields after the command name, which may hold spaces: the state
    // first, user time the twelfth, system time the thirteenth
    let rest: Vec<&str> = stat[stat.rfind(')')? + 1..].split_whitespace().collect();
    let ticks = rest.get(11)?.parse::<u64>().ok()? + rest.get(12)?.parse::<u64>().ok()?;
    Some(ticks as f64 / 100.0)
}
