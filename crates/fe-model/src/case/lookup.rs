//! The material, section or group a case names, found by one `find`
//! (used by `build.rs` and by `imported.rs`, which names groups too).

use toml::Spanned;

use super::{Ctx, hint};
use crate::error::CaseError;
use crate::model::Model;

/// The index of the material, section or group a case names, or an error at
/// the name with the closest defined one suggested (or the list).
fn find<'a>(
    ctx: &Ctx<'_>,
    kind: &str,
    name: &Spanned<String>,
    defined: impl Iterator<Item = &'a str> + Clone,
) -> Result<usize, CaseError> {
    defined.clone().position(|n| n == name.get_ref()).ok_or_else(|| {
        let known: Vec<&str> = defined.collect();
        ctx.err(name.span(), format!("unknown {kind} `{}`{}", name.get_ref(), hint(name.get_ref(), &known, "defined")))
    })
}

pub(super) fn group_ref(ctx: &Ctx<'_>, model: &Model, name: &Spanned<String>) -> Result<usize, CaseError> {
    find(ctx, "group", name, model.groups.iter().map(|g| g.name.as_str()))
}

pub(super) fn material_ref(ctx: &Ctx<'_>, model: &Model, name: &Spanned<String>) -> Result<usize, CaseError> {
    find(ctx, "material", name, model.materials.iter().map(|m| m.name.as_str()))
}

pub(super) fn section_ref(ctx: &Ctx<'_>, model: &Model, name: &Spanned<String>) -> Result<usize, CaseError> {
    find(ctx, "section", name, model.sections.iter().map(|s| s.name.as_str()))
}
