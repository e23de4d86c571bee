//! A case's `[check]` table against what its runs produced.
//!
//! Each function returns one sentence per missed check, saying what was
//! found and what the check allows; an empty list means the run passed.
//! Anything the check needs and the results lack is a failure too, so that
//! a check never passes by having nothing to look at.

use fe_model::case::{DiagnosisCheck, RUN_STATUSES, RunCheck};
use serde_json::Value;

/// The status of a `results.json`: a plain name, or the key of a status
/// that carries a message (`{"failed": "..."}`).
pub(crate) fn status_name(results: &Value) -> String {
    match &results["status"] {
        Value::String(s) => s.clone(),
        Value::Object(o) => o.keys().next().cloned().unwrap_or_default(),
        other => other.to_string(),
    }
}

/// The number in `v`, or `NaN`.
fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// `results.json` of one `rfm update` run against its check. `noise` is the
/// truth's noise level, which the `noise` check compares with.
pub(crate) fn run_failures(check: &RunCheck, results: &Value, noise: Option<f64>) -> Vec<String> {
    let mut out = Vec::new();
    let status = status_name(results);
    if !check.status.contains(&status) {
        out.push(format!("status `{status}`, the check allows {}", check.status.join(", ")));
    }
    let empty = Vec::new();
    let params = results["parameters"].as_array().unwrap_or(&empty);
    if params.is_empty() {
        out.push("the results list no parameters".to_string());
    }
    if let Some(bound) = check.max_error {
        for p in params {
            let name = p["name"].as_str().unwrap_or("?");
            let (updated, truth) = (num(&p["updated"]), num(&p["truth"]));
            let err = ((updated - truth) / truth).abs();
            if !(err <= bound) {
                out.push(format!(
                    "{name}: updated {updated:e}, truth {truth:e}, relative error {err:.2e} above max_error {bound:e}"
                ));
            }
        }
    }
    let unc = results["uncertainty"]["parameters"].as_array();
    if (check.within_sd.is_some() || !check.weak.is_empty() || check.noise.is_some()) && unc.is_none() {
        out.push("the results carry no uncertainty to check".to_string());
    }
    let unc = unc.unwrap_or(&empty);
    if let Some(bound) = check.within_sd {
        let mut checked = 0;
        for (p, u) in params.iter().zip(unc) {
            if u["well_determined"].as_bool() != Some(true) {
                continue;
            }
            checked += 1;
            let name = p["name"].as_str().unwrap_or("?");
            let (updated, truth, s) = (num(&p["updated"]), num(&p["truth"]), num(&u["relative_std"]));
            let z = (updated / truth).ln().abs() / s;
            if !(z <= bound) {
                out.push(format!(
                    "{name}: updated {updated:e}, truth {truth:e}, {z:.2} standard deviations ({:.2e} relative) away, above within_sd {bound}",
                    s
                ));
            }
        }
        if checked == 0 {
            out.push("no parameter is reported well determined, so within_sd checks nothing".to_string());
        }
    }
    for name in &check.weak {
        match unc.iter().find(|u| u["name"].as_str() == Some(name)) {
            None => out.push(format!("{name}: not in the results' uncertainty table")),
            Some(u) if u["well_determined"].as_bool() != Some(false) => out.push(format!(
                "{name} is reported well determined (relative std {:.2e}); the check expects it flagged as weak",
                num(&u["relative_std"])
            )),
            Some(_) => {}
        }
    }
    if let Some(bound) = check.noise {
        let rms = num(&results["uncertainty"]["residual_rms"]);
        let level = noise.unwrap_or(f64::NAN);
        let off = (rms / level - 1.0).abs();
        if !(off <= bound) {
            out.push(format!(
                "residual RMS {rms:.4e} is {:.1} % from the truth's noise {level}, above noise {bound}",
                100.0 * off
            ));
        }
    }
    out
}

/// A diagnosis (`rfm diagnose --json`) and the misfit after its leader was
/// added and updated, against the case's diagnosis check.
pub(crate) fn diagnosis_failures(check: &DiagnosisCheck, diagnosis: &Value, updated_misfit: f64) -> Vec<String> {
    let mut out = Vec::new();
    match diagnosis["ranking"].as_array().and_then(|r| r.first()) {
        None => out.push("the diagnosis ranked no candidate".to_string()),
        Some(leader) => {
            let description = leader["description"].as_str().unwrap_or("?");
            if !description.contains(&check.leader) {
                out.push(format!(
                    "the diagnosis ranked \"{description}\" first; the check expects \"{}\"",
                    check.leader
                ));
            }
            if leader["significant"].as_bool() != Some(true) {
                out.push(format!("the leader \"{description}\" is not significant"));
            }
        }
    }
    if let Some(bound) = check.misfit_fall {
        let nominal = num(&diagnosis["nominal_misfit"]);
        let fall = nominal / updated_misfit;
        if !(fall >= bound) {
            out.push(format!(
                "the misfit fell {fall:.1} times (from {nominal:.3e} to {updated_misfit:.3e}), less than misfit_fall {bound}"
            ));
        }
    }
    out
}

/// The update of a diagnosis loop (`results.json` with the leader added)
/// against the check's `status` and the truth that made the data: each
/// parameter the check's `compare` names within `within_sd` of its true
/// value (`truths`, one per entry of `compare`, `Err` saying why there is
/// none), and the residual RMS within `noise` of the truth's noise level
/// (`None` without a truth).
pub(crate) fn loop_update_failures(
    check: &DiagnosisCheck,
    results: &Value,
    truths: &[Result<f64, String>],
    noise: Option<f64>,
) -> Vec<String> {
    let mut out = Vec::new();
    let empty = Vec::new();
    let params = results["parameters"].as_array().unwrap_or(&empty);
    let unc = results["uncertainty"]["parameters"].as_array().unwrap_or(&empty);
    // the compared parameters alone, each with its truth, in the order of `compare`
    let (mut compared, mut compared_unc) = (Vec::new(), Vec::new());
    for ((name, truth_name), truth) in check.compare.iter().zip(truths) {
        let by_name = |list: &Vec<Value>| list.iter().find(|p| p["name"].as_str() == Some(name)).cloned();
        let (Some(mut p), Some(u)) = (by_name(params), by_name(unc)) else {
            out.push(format!("{name}: not among the updated parameters and their uncertainty"));
            continue;
        };
        match truth {
            Ok(t) => p["truth"] = Value::from(*t),
            Err(why) => out.push(format!("{name}: no true value from {truth_name} ({why})")),
        }
        compared.push(p);
        compared_unc.push(u);
    }
    let mut narrowed = results.clone();
    if !check.compare.is_empty() {
        narrowed["parameters"] = Value::Array(compared);
        narrowed["uncertainty"]["parameters"] = Value::Array(compared_unc);
    }
    let run = RunCheck {
        status: if check.status.is_empty() {
            RUN_STATUSES.iter().map(|s| s.to_string()).collect()
        } else {
            check.status.clone()
        },
        max_error: None,
        within_sd: check.within_sd,
        weak: Vec::new(),
        noise: check.noise,
    };
    out.extend(run_failures(&run, &narrowed, noise));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn check() -> RunCheck {
        RunCheck { status: vec!["converged".into()], max_error: None, within_sd: None, weak: Vec::new(), noise: None }
    }

    fn results(updated: f64, relative_std: f64, well_determined: bool) -> Value {
        json!({
            "status": "converged",
            "parameters": [{ "name": "group.steel.mu", "updated": updated, "truth": 631.12 }],
            "uncertainty": {
                "parameters": [{ "name": "group.steel.mu", "relative_std": relative_std, "well_determined": well_determined }],
                "residual_rms": 0.0612,
            },
        })
    }

    #[test]
    fn a_result_moved_past_max_error_fails_and_says_by_how_much() {
        let c = RunCheck { max_error: Some(1e-8), ..check() };
        assert!(run_failures(&c, &results(631.12 * (1.0 + 5e-9), 0.01, true), None).is_empty());
        let f = run_failures(&c, &results(631.12 * (1.0 + 2e-8), 0.01, true), None);
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(
            f[0].starts_with("group.steel.mu:") && f[0].contains("relative error 2.00e-8 above max_error 1e-8"),
            "{f:?}"
        );
        // a missing truth is a failure, not a pass
        let mut r = results(631.12, 0.01, true);
        r["parameters"][0]["truth"] = Value::Null;
        assert_eq!(run_failures(&c, &r, None).len(), 1);
    }

    #[test]
    fn within_sd_counts_the_run_own_standard_deviations() {
        let c = RunCheck { within_sd: Some(3.0), ..check() };
        // 2 % off with a 1 % standard deviation: 2 sd
        assert!(run_failures(&c, &results(631.12 * 1.02, 0.01, true), None).is_empty());
        let f = run_failures(&c, &results(631.12 * 1.04, 0.01, true), None);
        assert!(f.len() == 1 && f[0].contains("3.92 standard deviations"), "{f:?}");
        // an over-estimated (doubled) standard deviation hides nothing from the noise check
        let c = RunCheck { noise: Some(0.1), ..check() };
        assert!(run_failures(&c, &results(631.12, 0.01, true), Some(0.06)).is_empty());
        let f = run_failures(&c, &results(631.12, 0.01, true), Some(0.03));
        assert!(f.len() == 1 && f[0].contains("104.0 % from the truth's noise 0.03"), "{f:?}");
        // nothing well determined: within_sd has nothing to check, which fails
        let c = RunCheck { within_sd: Some(3.0), ..check() };
        let f = run_failures(&c, &results(631.12, 0.01, false), None);
        assert!(f.len() == 1 && f[0].contains("checks nothing"), "{f:?}");
    }

    #[test]
    fn weak_parameters_must_be_flagged_and_statuses_listed() {
        let c = RunCheck { weak: vec!["group.steel.mu".into()], ..check() };
        assert!(run_failures(&c, &results(631.12, 0.5, false), None).is_empty());
        let f = run_failures(&c, &results(631.12, 0.01, true), None);
        assert!(f.len() == 1 && f[0].contains("expects it flagged as weak"), "{f:?}");
        let mut r = results(631.12, 0.01, true);
        r["status"] = json!({ "failed": "singular" });
        assert_eq!(status_name(&r), "failed");
        assert_eq!(run_failures(&check(), &r, None), vec!["status `failed`, the check allows converged".to_string()]);
        // a check of the uncertainty on a run without one fails
        r.as_object_mut().unwrap().remove("uncertainty");
        r["status"] = json!("converged");
        let f = run_failures(&c, &r, None);
        assert!(f.iter().any(|f| f.contains("no uncertainty")), "{f:?}");
    }

    #[test]
    fn the_diagnosis_must_name_its_leader_and_lower_the_misfit() {
        let c = DiagnosisCheck {
            leader: "joint at node 13".into(),
            misfit_fall: Some(10.0),
            status: Vec::new(),
            truth: None,
            compare: Vec::new(),
            within_sd: None,
            noise: None,
        };
        let d = json!({
            "nominal_misfit": 1.39,
            "ranking": [{ "description": "flexible, lossy joint at node 13 (element 13)", "significant": true }],
        });
        assert!(diagnosis_failures(&c, &d, 0.0099).is_empty());
        let f = diagnosis_failures(&c, &d, 0.2);
        assert!(f.len() == 1 && f[0].contains("fell 6.9 times"), "{f:?}");
        let wrong = json!({
            "nominal_misfit": 1.39,
            "ranking": [{ "description": "lumped mass at node 19", "significant": false }],
        });
        assert_eq!(diagnosis_failures(&c, &wrong, 0.0099).len(), 2);
        assert_eq!(diagnosis_failures(&c, &json!({ "ranking": [] }), 0.0099).len(), 2);
    }

    #[test]
    fn the_loop_update_is_held_to_the_truth_that_made_the_data() {
        let c = DiagnosisCheck {
            leader: "in-line joint at node 9".into(),
            misfit_fall: None,
            status: vec!["converged".into()],
            truth: Some("lap-joint-truth.toml".into()),
            compare: vec![("spring.joint_9_9.kr".into(), "spring.lap.kr".into())],
            within_sd: Some(3.0),
            noise: None,
        };
        let results = |kr: f64, status: &str| {
            json!({
                "status": status,
                "parameters": [
                    { "name": "spring.joint_9_9.kr", "updated": kr },
                    { "name": "group.joint_9_9.alpha", "updated": 2.1e-4 },
                ],
                "uncertainty": {
                    "parameters": [
                        { "name": "spring.joint_9_9.kr", "relative_std": 0.001, "well_determined": true },
                        { "name": "group.joint_9_9.alpha", "relative_std": 0.001, "well_determined": true },
                    ],
                    "residual_rms": 0.0047,
                },
            })
        };
        // 2 sd from the truth passes; the alpha the check does not compare is not judged
        assert!(loop_update_failures(&c, &results(2000.0 * 1.002, "converged"), &[Ok(2000.0)], Some(0.01)).is_empty());
        let f = loop_update_failures(&c, &results(2000.0 * 1.004, "converged"), &[Ok(2000.0)], Some(0.01));
        assert!(f.len() == 1 && f[0].starts_with("spring.joint_9_9.kr:") && f[0].contains("3.99 standard deviations"));
        let f = loop_update_failures(&c, &results(2000.0, "model_inadequate"), &[Ok(2000.0)], Some(0.01));
        assert_eq!(f, vec!["status `model_inadequate`, the check allows converged".to_string()]);
        // a truth the truth's model lacks, or a parameter the update lacks, is a failure
        let f = loop_update_failures(&c, &results(2000.0, "converged"), &[Err("no spring `lap`".into())], Some(0.01));
        assert!(f.iter().any(|f| f.contains("no true value from spring.lap.kr (no spring `lap`)")), "{f:?}");
        let mut renamed = results(2000.0, "converged");
        renamed["parameters"][0]["name"] = json!("spring.joint_9_10.kr");
        let f = loop_update_failures(&c, &renamed, &[Ok(2000.0)], Some(0.01));
        assert!(f.iter().any(|f| f.contains("not among the updated parameters")), "{f:?}");
        // the residual against the truth's noise level
        let noisy = DiagnosisCheck { noise: Some(0.2), ..c.clone() };
        let f = loop_update_failures(&noisy, &results(2000.0, "converged"), &[Ok(2000.0)], Some(0.01));
        assert!(f.len() == 1 && f[0].contains("53.0 % from the truth's noise 0.01"), "{f:?}");
    }
}
