//! Frequencies as labels and messages print them.

/// A frequency in a short form for labels (`12.5`, `1000`, `0.25`).
pub(crate) fn short(f: f64) -> String {
    if f >= 100.0 {
        format!("{f:.0}")
    } else if f >= 10.0 {
        trim(format!("{f:.1}"))
    } else {
        trim(format!("{f:.2}"))
    }
}

fn trim(s: String) -> String {
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
}
