//! Frequency lists as case files write them: numbers, or a range table.

use toml::Spanned;

use super::Ctx;
use crate::error::CaseError;

/// Parses a frequency specification: a list of numbers, or a table
/// `{ from, to, step }` / `{ from, to, count }` (Hz).
pub(super) fn parse_frequencies(ctx: &Ctx<'_>, v: &Spanned<toml::Value>) -> Result<Vec<f64>, CaseError> {
    let num = |x: &toml::Value| match x {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    };
    let freqs: Vec<f64> = match v.get_ref() {
        toml::Value::Array(a) => a
            .iter()
            .map(|x| num(x).ok_or_else(|| ctx.err(v.span(), "frequencies must be numbers (Hz)")))
            .collect::<Result<_, _>>()?,
        toml::Value::Table(t) => {
            const KEYS: [&str; 4] = ["from", "to", "step", "count"];
            for k in t.keys() {
                if !KEYS.contains(&k.as_str()) {
                    let hint = match crate::suggest::closest(k, KEYS) {
                        Some(best) => format!("did you mean `{best}`?"),
                        None => "use from, to and step or count".to_string(),
                    };
                    return Err(ctx.err(v.span(), format!("unknown key `{k}` in a frequency range; {hint}")));
                }
            }
            let get = |k: &str| t.get(k).and_then(num);
            let (from, to) = match (get("from"), get("to")) {
                (Some(a), Some(b)) => (a, b),
                _ => return Err(ctx.err(v.span(), "a frequency range needs `from` and `to` (Hz)")),
            };
            let count = match (get("step"), t.get("count")) {
                (Some(step), None) if step > 0.0 => (((to - from) / step + 1e-9).floor() as usize).saturating_add(1),
                (None, Some(toml::Value::Integer(c))) if *c >= 2 => *c as usize,
                _ => {
                    return Err(
                        ctx.err(v.span(), "a frequency range needs a positive `step` or an integer `count` >= 2")
                    );
                }
            };
            if count > 10_000_000 {
                return Err(
                    ctx.err(v.span(), format!("{count} frequency lines is more than this tool accepts (10 million)"))
                );
            }
            (0..count).map(|i| from + (to - from) * i as f64 / (count - 1).max(1) as f64).collect()
        }
        _ => return Err(ctx.err(v.span(), "expected a list of frequencies or a table { from, to, step }")),
    };
    if freqs.is_empty() {
        return Err(ctx.err(v.span(), "no frequencies given"));
    }
    for w in freqs.windows(2) {
        if !(w[1] > w[0]) {
            return Err(
                ctx.err(v.span(), format!("frequencies must increase strictly ({} is followed by {})", w[0], w[1]))
            );
        }
    }
    if let Some(f) = freqs.iter().find(|f| !(f.is_finite() && **f > 0.0)) {
        return Err(ctx.err(v.span(), format!("frequencies must be positive and finite (Hz), got {}", crate::show(*f))));
    }
    Ok(freqs)
}
