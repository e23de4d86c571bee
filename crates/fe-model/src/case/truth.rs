//! The `[truth]` table: the model that synthesises a simulated study's
//! "measured" data, with its noise.

use std::collections::BTreeMap;

use toml::Spanned;

use super::Ctx;
use super::build::{add_joints, add_mass, add_resonator, add_shaker, add_spring, raw_group};
use super::raw::RawTruth;
use super::spec::TruthSpec;
use crate::error::CaseError;
use crate::model::Model;
use crate::quantity::Quantity;

pub(super) fn resolve_values(
    ctx: &Ctx<'_>,
    values: &BTreeMap<String, Spanned<f64>>,
    model: &Model,
) -> Result<Vec<(Quantity, f64)>, CaseError> {
    values
        .iter()
        .map(|(name, v)| {
            let q = model.quantity(name).map_err(|e| ctx.model_err(v.span(), e))?;
            Ok((q, *v.get_ref()))
        })
        .collect()
}

pub(super) fn parse_truth(ctx: &Ctx<'_>, t: &Spanned<RawTruth>, base: &Model) -> Result<TruthSpec, CaseError> {
    let r = t.get_ref();
    if !(r.noise >= 0.0 && r.noise.is_finite() && r.floor >= 0.0 && r.floor.is_finite()) {
        return Err(ctx.err(t.span(), "noise and floor must be zero or positive"));
    }
    let mut model = base.clone();
    for (name, g) in &r.groups {
        let group = raw_group(ctx, name, g)?;
        match model.group_index(name) {
            Some(i) => model.replace_group(i, group),
            None => model.add_group(group).map(|_| ()),
        }
        .map_err(|e| ctx.model_err(g.span(), e))?;
    }
    for s in &r.springs {
        add_spring(ctx, &mut model, s)?;
    }
    for m in &r.masses {
        add_mass(ctx, &mut model, m)?;
    }
    add_joints(ctx, &mut model, &r.joints)?;
    for s in &r.resonators {
        add_resonator(ctx, &mut model, s)?;
    }
    for s in &r.shakers {
        add_shaker(ctx, &mut model, s)?;
    }
    // Values may name items the truth adds, so resolve them on the truth model.
    for (name, v) in &r.set {
        let q = model.quantity(name).map_err(|e| ctx.model_err(v.span(), e))?;
        model.set(q, *v.get_ref()).map_err(|e| ctx.model_err(v.span(), e))?;
    }
    crate::assembly::Assembly::new(&model).map_err(|e| ctx.err(t.span(), format!("the truth model: {e}")))?;
    let values = r.set.iter().filter_map(|(name, v)| base.quantity(name).ok().map(|q| (q, *v.get_ref()))).collect();
    Ok(TruthSpec { model, values, noise: r.noise, floor: r.floor, seed: r.seed })
}
