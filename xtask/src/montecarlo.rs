//! `cargo xtask montecarlo [N]`: how often the output-error fit reaches the
//! global minimum. For each twin (the flexible clamp and the f-frame, 1 %
//! noise), `N` seeds (100 by default) of its `[truth]` noise, each updated
//! with `rfm update --method output-error --json`; a seed counts as
//! converged when the residual RMS it leaves is within 1.2 times the
//! injected noise. Prints the count, the statuses and the time per seed.
//! Not part of the CI tests (it takes minutes).

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// Residual within this many times the injected noise: the global minimum.
const WITHIN: f64 = 1.2;

const TWINS: [&str; 2] = ["cantilever-flexible-clamp", "f-frame"];

/// The case text with its `[truth]` seed replaced.
fn with_seed(text: &str, seed: u64) -> String {
    text.lines()
        .map(|l| if l.starts_with("seed = ") { format!("seed = {seed}") } else { l.to_string() })
        .collect::<Vec<_>>()
        .join("\n")
}

pub(crate) fn montecarlo(args: &[String]) -> Result<(), String> {
    let n: u64 = match args.first() {
        Some(a) => a.parse().map_err(|_| format!("montecarlo: `{a}` is not a number of seeds"))?,
        None => 100,
    };
    let rfm = crate::release_build(&["-p", "rfm-cli", "--bin", "rfm"], "rfm")?;
    let dir = crate::target_dir()?.join("montecarlo");
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    println!("{:<28} {:>10} {:>10}  statuses", "twin", "converged", "s / seed");
    for name in TWINS {
        let path = crate::root().join("cases").join(format!("{name}.toml"));
        let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let case = fe_model::CaseFile::load(&path).map_err(|e| e.to_string())?;
        let noise = case.truth.as_ref().map(|t| t.noise).ok_or_else(|| format!("{name} has no [truth]"))?;
        let (mut converged, mut statuses) = (0, BTreeMap::<String, usize>::new());
        let start = Instant::now();
        for seed in 1..=n {
            let file = dir.join(format!("{name}-{seed}.toml"));
            std::fs::write(&file, with_seed(&text, seed)).map_err(|e| format!("{}: {e}", file.display()))?;
            let json = run(&rfm, &file)?;
            let rms = json["uncertainty"]["residual_rms"].as_f64().unwrap_or(f64::INFINITY);
            if rms <= WITHIN * noise {
                converged += 1;
            }
            *statuses.entry(crate::check::status_name(&json)).or_default() += 1;
        }
        let per = start.elapsed().as_secs_f64() / n as f64;
        let list: Vec<String> = statuses.iter().map(|(s, k)| format!("{s} {k}")).collect();
        println!("{name:<28} {:>10} {per:>10.2}  {}", format!("{converged}/{n}"), list.join(", "));
    }
    Ok(())
}

fn run(rfm: &Path, case: &Path) -> Result<serde_json::Value, String> {
    let out = Command::new(rfm)
        .args(["update", case.to_str().unwrap_or_default(), "--method", "output-error", "--json"])
        .output()
        .map_err(|e| format!("cannot run {}: {e}", rfm.display()))?;
    serde_json::from_slice(&out.stdout)
        .map_err(|e| format!("{}: no JSON result ({e}): {}", case.display(), String::from_utf8_lossy(&out.stderr)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_seed_line_changes() {
        let text = "[truth]\nnoise = 0.01\nseed = 5\n[truth.set]\n\"a.seed\" = 1";
        assert_eq!(with_seed(text, 42), "[truth]\nnoise = 0.01\nseed = 42\n[truth.set]\n\"a.seed\" = 1");
    }
}
