//! DOF lists as case files write them: `31:uy`, and ranges `2..31:uy`.

use toml::Spanned;

use super::Ctx;
use crate::dof::{Dof, DofRef};
use crate::error::CaseError;
use crate::model::{Model, NodeId};

/// Parses `31:uy` or a range `2..31:uy` (inclusive) into DOF references.
/// The range is expanded here, so a caller that knows the model should use
/// [`parse_dof_range`] and check each node as it goes, before a range of
/// four billion nodes is allocated.
pub fn parse_dof_list(text: &str) -> Result<Vec<DofRef>, String> {
    let (a, b, dof) = parse_dof_range(text)?;
    Ok((a..=b).map(|n| DofRef::new(n, dof)).collect())
}

/// Parses `31:uy` (the range `31..31`) or `2..31:uy` into its first and
/// last node and its DOF, without expanding it.
pub fn parse_dof_range(text: &str) -> Result<(u32, u32, Dof), String> {
    let (nodes, dof) = text
        .split_once(':')
        .ok_or_else(|| format!("`{text}` is not of the form node:dof or first..last:dof (for example 2..31:uy)"))?;
    let dof: Dof = dof.parse()?;
    if let Some((a, b)) = nodes.split_once("..") {
        let a: u32 = a.trim().parse().map_err(|_| format!("`{a}` in `{text}` is not a node id"))?;
        let b: u32 = b.trim().parse().map_err(|_| format!("`{b}` in `{text}` is not a node id"))?;
        if b < a {
            return Err(format!("range `{text}` is empty (last node before first)"));
        }
        Ok((a, b, dof))
    } else {
        let n: u32 = nodes.trim().parse().map_err(|_| format!("`{nodes}` in `{text}` is not a node id"))?;
        Ok((n, n, dof))
    }
}
pub(super) fn parse_dof_refs(ctx: &Ctx<'_>, list: &[Spanned<String>], model: &Model) -> Result<Vec<DofRef>, CaseError> {
    let mut out = Vec::new();
    // a set, so that listing a hundred thousand DOFs stays linear
    let mut seen = std::collections::HashSet::new();
    for s in list {
        let (first, last, dof) = parse_dof_range(s.get_ref()).map_err(|e| ctx.err(s.span(), e))?;
        model.dimension().check(dof).map_err(|e| ctx.err(s.span(), e))?;
        // Every node of the range must exist, so the walk stops at the first
        // missing one: it never goes further than the model has nodes.
        for node in first..=last {
            let r = DofRef::new(node, dof);
            if model.node(NodeId(node)).is_none() {
                return Err(ctx.err(s.span(), format!("node {node} does not exist in the model")));
            }
            if !seen.insert(r) {
                return Err(ctx.err(s.span(), format!("{r} is listed twice")));
            }
            out.push(r);
        }
    }
    Ok(out)
}
