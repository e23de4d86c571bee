//! The `[check]` table: what `cargo xtask reproduce` requires of a case's
//! runs, checked against the case's truth and update.

use toml::Spanned;

use super::raw::{RawCheck, RawRunCheck};
use super::spec::{CheckSpec, DiagnosisCheck, RUN_STATUSES, RunCheck, TruthSpec, UpdateSpec};
use super::{Ctx, hint};
use crate::error::CaseError;

pub(super) fn parse_check(
    ctx: &Ctx<'_>,
    c: &Spanned<RawCheck>,
    truth: Option<&TruthSpec>,
    update: Option<&UpdateSpec>,
) -> Result<CheckSpec, CaseError> {
    let r = c.get_ref();
    let run = |table: &Option<Spanned<RawRunCheck>>, name: &str| -> Result<Option<RunCheck>, CaseError> {
        let Some(t) = table else { return Ok(None) };
        let Some(update) = update else {
            return Err(ctx.err(t.span(), format!("[check.{name}] checks an update, and the case has no [update]")));
        };
        let r = t.get_ref();
        if r.status.is_empty() {
            return Err(ctx.err(t.span(), format!("[check.{name}] needs at least one `status`")));
        }
        for s in &r.status {
            if !RUN_STATUSES.contains(&s.get_ref().as_str()) {
                let hint = hint(s.get_ref(), &RUN_STATUSES, "available");
                return Err(ctx.err(s.span(), format!("unknown status `{}`{hint}", s.get_ref())));
            }
        }
        let bound = |v: &Option<Spanned<f64>>, key: &str, needs: &str| -> Result<Option<f64>, CaseError> {
            let Some(v) = v else { return Ok(None) };
            if !(*v.get_ref() > 0.0 && v.get_ref().is_finite()) {
                return Err(ctx.err(v.span(), format!("`{key}` must be positive and finite")));
            }
            if truth.is_none() {
                return Err(ctx.err(v.span(), format!("`{key}` compares with {needs}, and the case has no [truth]")));
            }
            Ok(Some(*v.get_ref()))
        };
        let max_error = bound(&r.max_error, "max_error", "the truth")?;
        let within_sd = bound(&r.within_sd, "within_sd", "the truth")?;
        let noise = bound(&r.noise, "noise", "the truth's noise level")?;
        if let (Some(v), Some(t)) = (&r.noise, truth)
            && !(t.noise > 0.0)
        {
            return Err(ctx.err(v.span(), "`noise` compares with the truth's noise level, and the truth has no noise"));
        }
        let names: Vec<&str> = update.parameters.iter().map(|p| p.name.as_str()).collect();
        for w in &r.weak {
            if !names.contains(&w.get_ref().as_str()) {
                let hint = hint(w.get_ref(), &names, "updated");
                return Err(ctx.err(w.span(), format!("`{}` is not an [update] parameter{hint}", w.get_ref())));
            }
        }
        Ok(Some(RunCheck {
            status: r.status.iter().map(|s| s.get_ref().clone()).collect(),
            max_error,
            within_sd,
            weak: r.weak.iter().map(|w| w.get_ref().clone()).collect(),
            noise,
        }))
    };
    let diagnosis = match &r.diagnosis {
        None => None,
        Some(d) => {
            let r = d.get_ref();
            if r.leader.get_ref().trim().is_empty() {
                return Err(ctx.err(r.leader.span(), "`leader` must name the effect the diagnosis ranks first"));
            }
            if let Some(f) = &r.misfit_fall
                && !(*f.get_ref() >= 1.0 && f.get_ref().is_finite())
            {
                return Err(ctx.err(f.span(), "`misfit_fall` is a factor of at least 1"));
            }
            // the update with the leader added, against the truth that made the data
            let needs_truth = |span: std::ops::Range<usize>, key: &str| {
                ctx.err(span, format!("`{key}` compares with the truth that made the data: name its case in `truth`"))
            };
            let positive = |v: &Option<Spanned<f64>>, key: &str| -> Result<Option<f64>, CaseError> {
                let Some(v) = v else { return Ok(None) };
                if !(*v.get_ref() > 0.0 && v.get_ref().is_finite()) {
                    return Err(ctx.err(v.span(), format!("`{key}` must be positive and finite")));
                }
                if r.truth.is_none() {
                    return Err(needs_truth(v.span(), key));
                }
                Ok(Some(*v.get_ref()))
            };
            for s in &r.status {
                if !RUN_STATUSES.contains(&s.get_ref().as_str()) {
                    let hint = hint(s.get_ref(), &RUN_STATUSES, "available");
                    return Err(ctx.err(s.span(), format!("unknown status `{}`{hint}", s.get_ref())));
                }
            }
            let within_sd = positive(&r.within_sd, "within_sd")?;
            let noise = positive(&r.noise, "noise")?;
            let compare: Vec<(String, String)> = match &r.compare {
                None => Vec::new(),
                Some(c) => {
                    if r.truth.is_none() {
                        return Err(needs_truth(c.span(), "compare"));
                    }
                    if c.get_ref().is_empty() || within_sd.is_none() {
                        return Err(ctx.err(
                            c.span(),
                            "`compare` names updated parameters and their true quantities for `within_sd`, \
                             which needs both",
                        ));
                    }
                    c.get_ref().iter().map(|(k, v)| (k.clone(), v.get_ref().clone())).collect()
                }
            };
            if let (Some(w), true) = (&r.within_sd, compare.is_empty()) {
                return Err(ctx.err(w.span(), "`within_sd` checks the parameters `compare` names, and it names none"));
            }
            let truth = r.truth.as_ref().map(|t| {
                let p = std::path::Path::new(t.get_ref());
                if p.is_absolute() {
                    p.to_path_buf()
                } else {
                    ctx.path.parent().unwrap_or(std::path::Path::new(".")).join(p)
                }
            });
            Some(DiagnosisCheck {
                leader: r.leader.get_ref().clone(),
                misfit_fall: r.misfit_fall.as_ref().map(|f| *f.get_ref()),
                status: r.status.iter().map(|s| s.get_ref().clone()).collect(),
                truth,
                compare,
                within_sd,
                noise,
            })
        }
    };
    Ok(CheckSpec { rfm: run(&r.rfm, "rfm")?, output_error: run(&r.output_error, "output-error")?, diagnosis })
}
