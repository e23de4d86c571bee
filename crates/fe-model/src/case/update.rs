//! The `[update]` table: the parameters, their bounds, the frequency lines
//! and the options of the fit.

use toml::Spanned;

use super::Ctx;
use super::frequencies::parse_frequencies;
use super::raw::RawUpdate;
use super::spec::{BandWeight, FrequencyChoice, UpdateSpec};
use crate::error::CaseError;
use crate::model::Model;
use crate::quantity::Parameter;

pub(super) fn parse_update(ctx: &Ctx<'_>, u: &Spanned<RawUpdate>, model: &Model) -> Result<UpdateSpec, CaseError> {
    let r = u.get_ref();
    let mut parameters: Vec<Parameter> = Vec::new();
    for p in &r.parameters {
        let param = model.parameter(p.get_ref()).map_err(|e| ctx.model_err(p.span(), e))?;
        if let Some(q) = param.quantities.iter().find(|q| parameters.iter().any(|o| o.quantities.contains(q))) {
            return Err(ctx.err(
                p.span(),
                format!("`{}` is already updated by another parameter in the list", model.quantity_name(*q)),
            ));
        }
        for &q in &param.quantities {
            let v = model.get(q);
            if !(v > 0.0 && v.is_finite()) {
                return Err(ctx.err(
                    p.span(),
                    format!(
                        "`{}` starts at {v}; updating works on relative changes and needs a positive, finite starting value",
                        model.quantity_name(q)
                    ),
                ));
            }
        }
        parameters.push(param);
    }
    if parameters.is_empty() {
        return Err(ctx.err(u.span(), "no parameters to update"));
    }
    let mut bounds = vec![None; parameters.len()];
    for (name, b) in &r.bounds {
        let i = parameters.iter().position(|p| &p.name == name).ok_or_else(|| {
            ctx.err(b.span(), format!("bounds given for `{name}`, which is not in the parameters list"))
        })?;
        let [lo, hi] = *b.get_ref();
        if !(lo > 0.0 && hi > lo && hi.is_finite()) {
            return Err(
                ctx.err(b.span(), format!("bounds of `{name}` must satisfy 0 < lower < upper < inf, got [{lo}, {hi}]"))
            );
        }
        let v = model.get(parameters[i].quantities[0]);
        if !(lo <= v && v <= hi) {
            return Err(ctx.err(b.span(), format!("`{name}` starts at {v}, outside its bounds [{lo}, {hi}]")));
        }
        bounds[i] = Some((lo, hi));
    }
    let frequencies = match &r.frequencies {
        None => None,
        Some(v) => Some(match v.get_ref() {
            toml::Value::String(s) if s == "all" => FrequencyChoice::All,
            toml::Value::Table(t) if t.len() == 1 && (t.contains_key("auto") || t.contains_key("lines")) => {
                let (key, n) = t.iter().next().expect("one entry");
                match n {
                    toml::Value::Integer(n) if *n > 0 => {
                        if key == "auto" {
                            FrequencyChoice::Auto(*n as usize)
                        } else {
                            FrequencyChoice::Lines(*n as usize)
                        }
                    }
                    _ => return Err(ctx.err(v.span(), format!("`{key}` needs a positive number of lines"))),
                }
            }
            _ => FrequencyChoice::List(parse_frequencies(ctx, v)?),
        }),
    };
    if let Some(tol) = r.tolerance
        && !(tol > 0.0)
    {
        return Err(ctx.err(u.span(), "tolerance must be positive"));
    }
    if let Some(reg) = &r.regularization
        && !(*reg.get_ref() >= 0.0 && reg.get_ref().is_finite())
    {
        return Err(ctx.err(reg.span(), "regularization must be zero or positive"));
    }
    let weights = r
        .weights
        .iter()
        .map(|w| {
            let b = w.get_ref();
            if !(b.to > b.from && b.weight >= 0.0 && b.weight.is_finite()) {
                return Err(ctx.err(w.span(), "a band weight needs from < to and a weight >= 0"));
            }
            Ok(BandWeight { from: b.from, to: b.to, weight: b.weight })
        })
        .collect::<Result<_, _>>()?;
    Ok(UpdateSpec {
        parameters,
        bounds,
        frequencies,
        method: r.method.as_ref().map(|m| (m.get_ref().clone(), m.span())),
        max_iterations: r.max_iterations,
        tolerance: r.tolerance,
        regularization: r.regularization.as_ref().map(|r| *r.get_ref()),
        gains: r.gains,
        misfit: r.misfit.as_ref().map(|m| (m.get_ref().clone(), m.span())),
        coherence: r.coherence,
        weights,
    })
}
