//! `rfm update`: update the model's parameters against the measured FRFs.

use std::path::Path;

use rfm_update::rfm::RfmOptions;
use rfm_update::{Study, UpdateError};

use super::Result;
use crate::table::{Table, num};

pub(crate) fn update(case: &Path, out: Option<&Path>, json: bool, method: Option<&str>) -> Result<()> {
    let study = Study::load(case).map_err(|e| match e {
        UpdateError::Case(c) => c.render(),
        other => other.to_string(),
    })?;
    let spec = study.case.update.as_ref().ok_or("the case has no [update] section")?;
    let method =
        method.map(str::to_string).or_else(|| spec.method.as_ref().map(|m| m.0.clone())).unwrap_or("rfm".into());
    if method != "rfm" {
        return Err(study
            .case
            .error(spec.method.as_ref().map(|m| m.1.clone()), format!("unknown method `{method}` (available: rfm)"))
            .render()
            .into());
    }
    let mut opts = RfmOptions::default();
    if let Some(n) = spec.max_iterations {
        opts.max_iterations = n as usize;
    }
    if let Some(t) = spec.tolerance {
        opts.tolerance = t;
    }
    if !json {
        println!("{}", study.case.model.title);
        println!(
            "updating {} parameters with the response function method at {} lines: {}",
            study.parameters.len(),
            study.update_frequencies_hz.len(),
            study.update_frequencies_hz.iter().map(|f| num(*f)).collect::<Vec<_>>().join(", ")
        );
        println!("{:>5}  {:>12}  {:>12}", "iter", "residual", "max |du/u|");
    }
    let outcome = study.run_rfm(&opts, |r| {
        if !json {
            println!("{:>5}  {:>12.4e}  {:>12.4e}", r.iteration, r.residual, r.max_correction);
        }
    })?;
    if json {
        println!("{}", serde_json::to_string_pretty(&outcome)?);
    } else {
        println!("status: {:?}, final residual {:.3e}\n", outcome.status, outcome.residual);
        let has_truth = outcome.parameters.iter().any(|p| p.truth.is_some());
        let has_paper = outcome.parameters.iter().any(|p| p.paper.is_some());
        let mut header = vec!["parameter", "initial", "updated"];
        if has_truth {
            header.extend(["truth", "error"]);
        }
        if has_paper {
            header.push("paper");
        }
        let mut t = Table::new(&header);
        for p in &outcome.parameters {
            let mut row = vec![p.name.clone(), num(p.initial), num(p.updated)];
            if has_truth {
                row.push(p.truth.map(num).unwrap_or_default());
                row.push(p.relative_error().map(|e| format!("{e:.1e}")).unwrap_or_default());
            }
            if has_paper {
                row.push(p.paper.map(num).unwrap_or_default());
            }
            t.row(row);
        }
        println!("{}", t.render());
        let nf = &outcome.natural_frequencies_hz;
        let mut header = vec!["mode", "initial (Hz)", "updated (Hz)"];
        if nf.truth.is_some() {
            header.push("truth (Hz)");
        }
        if nf.paper.is_some() {
            header.push("paper (Hz)");
        }
        let mut t = Table::new(&header);
        let rows = nf.initial.len().max(nf.updated.len()).max(nf.paper.as_ref().map_or(0, Vec::len));
        let cell = |v: Option<&f64>| v.map(|f| format!("{f:.2}")).unwrap_or_default();
        for k in 0..rows {
            let mut row = vec![format!("{}", k + 1), cell(nf.initial.get(k)), cell(nf.updated.get(k))];
            if let Some(tr) = &nf.truth {
                row.push(cell(tr.get(k)));
            }
            if let Some(p) = &nf.paper {
                row.push(cell(p.get(k)));
            }
            t.row(row);
        }
        println!("\nundamped natural frequencies in the measured band\n{}", t.render());
    }
    if let Some(dir) = out {
        let path = dir.join("results.json");
        frf::io::atomic_write(&path, serde_json::to_string_pretty(&outcome)?.as_bytes(), &[case.to_path_buf()])?;
        if !json {
            println!("\nwrote {}", path.display());
        }
        let report = crate::report::update_report::write(&study, &outcome, dir, case)?;
        if !json {
            println!("wrote {} (figures beside it)", report.display());
        }
    }
    Ok(())
}
