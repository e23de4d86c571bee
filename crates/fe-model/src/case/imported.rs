//! The `[imported]` table: a model's own matrices, exported from another
//! finite element code (see `docs/imported-models.md`).
//!
//! ```toml
//! [imported]
//! nodes = "frame-nodes.txt"        # optional: id x y [z]
//!
//! [[imported.groups]]
//! group = "frame"                  # a group of [groups]: its factors and damping
//! dofs = "frame-dofs.txt"          # the DOF of each matrix row: node dof
//! stiffness = "frame-K.mtx"        # Matrix Market coordinate files
//! mass = "frame-M.mtx"
//! damping = "frame-C.mtx"          # optional: a viscous damping matrix
//! ```
//!
//! An error in one of these files names that file, its line and column.
//! A DOF table's node must be in the node file when there is one (else it
//! is made at the origin); the DOFs of a node that no table lists and no
//! beam touches are held fixed, as a solid element's node has no rotations.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use toml::Spanned;

use super::Ctx;
use super::lookup::group_ref;
use super::raw::RawImported;
use crate::dof::DofRef;
use crate::error::{CaseError, Location};
use crate::imported::matrix_market::{self, TextError};
use crate::imported::{ImportedKind, tables};
use crate::model::{Model, NodeId};

/// A path the case names, relative to its folder, with `..` taken out
/// lexically: a case written into a folder that does not exist yet (an
/// output being staged) names its files through it.
fn resolve(ctx: &Ctx<'_>, name: &str) -> PathBuf {
    let p = Path::new(name);
    let joined = if p.is_absolute() { p.to_path_buf() } else { ctx.path.parent().unwrap_or(Path::new(".")).join(p) };
    let absolute = std::path::absolute(&joined).unwrap_or(joined);
    let mut clean = PathBuf::new();
    for c in absolute.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                clean.pop();
            }
            other => clean.push(other),
        }
    }
    clean
}

/// The files `[imported]` names, resolved (inputs that no output may replace).
pub(super) fn files(ctx: &Ctx<'_>, raw: &Spanned<RawImported>) -> Vec<PathBuf> {
    let r = raw.get_ref();
    let names = r.groups.iter().flat_map(|g| {
        let g = g.get_ref();
        [Some(&g.dofs), g.stiffness.as_ref(), g.mass.as_ref(), g.damping.as_ref()]
    });
    std::iter::once(r.nodes.as_ref()).chain(names).flatten().map(|n| resolve(ctx, n.get_ref())).collect()
}

/// A file the case names, read, with its resolved path.
fn read(ctx: &Ctx<'_>, name: &Spanned<String>) -> Result<(PathBuf, String), CaseError> {
    let path = resolve(ctx, name.get_ref());
    let text = std::fs::read(&path)
        .map_err(|e| ctx.err(name.span(), format!("cannot read `{}`: {e}", name.get_ref())))
        .and_then(|bytes| {
            crate::text::decode(&bytes).map(str::to_string).map_err(|e| CaseError {
                file: path.clone(),
                location: Some(Location { line: e.line, column: e.column }),
                message: e.to_string(),
                snippet: None,
            })
        })?;
    Ok((path, text))
}

/// An error at a line and column of another file than the case.
fn in_file(path: &Path, text: &str, e: TextError) -> CaseError {
    CaseError {
        file: path.to_path_buf(),
        location: Some(Location { line: e.line, column: e.column }),
        message: e.message,
        snippet: text.lines().nth(e.line.saturating_sub(1)).map(str::to_string),
    }
}

/// Adds the imported nodes and matrices to `model` (after its groups and
/// nodes, before its lines and beams). Returns the DOFs the tables list
/// and the nodes of the node file.
pub(super) fn add_imported(
    ctx: &Ctx<'_>,
    raw: &Spanned<RawImported>,
    model: &mut Model,
) -> Result<(HashSet<DofRef>, HashSet<u32>), CaseError> {
    let r = raw.get_ref();
    let dim = model.dimension();
    let mut from_file: Option<(PathBuf, HashSet<u32>)> = None;
    if let Some(name) = &r.nodes {
        let (path, text) = read(ctx, name)?;
        let nodes = tables::read_nodes(&text, dim).map_err(|e| in_file(&path, &text, e))?;
        let mut ids = HashSet::new();
        for (id, p, line) in nodes {
            model.add_node_at(id, p).map_err(|e| in_file(&path, &text, TextError::at(line, 1, e.to_string())))?;
            ids.insert(id);
        }
        from_file = Some((path, ids));
    }
    if r.groups.is_empty() {
        return Err(ctx.err(raw.span(), "[imported] names no matrices: add [[imported.groups]] entries"));
    }
    let mut listed = HashSet::new();
    for entry in &r.groups {
        let e = entry.get_ref();
        let g = group_ref(ctx, model, &e.group)?;
        let (table_path, table_text) = read(ctx, &e.dofs)?;
        let table = tables::read_dof_table(&table_text, dim).map_err(|x| in_file(&table_path, &table_text, x))?;
        for (r, &line) in table.dofs.iter().zip(&table.lines) {
            if model.node(r.node).is_some() {
                continue;
            }
            match &from_file {
                Some((nodes_path, _)) => {
                    let col = table_text.lines().nth(line - 1).map_or(1, |l| l.len() - l.trim_start().len() + 1);
                    return Err(in_file(
                        &table_path,
                        &table_text,
                        TextError::at(
                            line,
                            col,
                            format!(
                                "node {} is not in the node file {}, nor among the case's nodes",
                                r.node,
                                nodes_path.display()
                            ),
                        ),
                    ));
                }
                None => {
                    // without coordinates the node sits at the origin: the
                    // matrices do not need them, the figures do
                    model.add_node_at(r.node.0, [0.0; 3]).map_err(|x| ctx.model_err(e.dofs.span(), x))?;
                }
            }
        }
        listed.extend(table.dofs.iter().copied());
        if e.stiffness.is_none() && e.mass.is_none() && e.damping.is_none() {
            return Err(ctx.err(
                entry.span(),
                "an imported group needs a `stiffness`, a `mass` or a `damping` matrix (or several)",
            ));
        }
        let kinds = [
            (ImportedKind::Stiffness, &e.stiffness),
            (ImportedKind::Mass, &e.mass),
            (ImportedKind::Damping, &e.damping),
        ];
        for (kind, file) in kinds {
            let Some(file) = file else { continue };
            let (path, text) = read(ctx, file)?;
            let m = matrix_market::read(&text).map_err(|x| in_file(&path, &text, x))?;
            if m.n != table.dofs.len() {
                let size_line = text
                    .lines()
                    .enumerate()
                    .skip(1)
                    .find(|(_, l)| !(l.trim().is_empty() || l.trim_start().starts_with('%')))
                    .map_or(1, |(i, _)| i + 1);
                return Err(in_file(
                    &path,
                    &text,
                    TextError::at(
                        size_line,
                        1,
                        format!(
                            "the matrix is {} x {}, and its DOF table {} has {} rows",
                            m.n,
                            m.n,
                            table_path.display(),
                            table.dofs.len()
                        ),
                    ),
                ));
            }
            model.add_imported(g, kind, &table.dofs, &m).map_err(|x| ctx.model_err(file.span(), x))?;
        }
    }
    Ok((listed, from_file.map(|(_, ids)| ids).unwrap_or_default()))
}

/// Holds the DOFs of the imported nodes (of the tables and of the node
/// file) that no beam touches and that no imported table lists: the
/// rotations of a solid element's node, or every DOF of a node whose rows
/// the export left out (a clamped node). Nothing gives them stiffness, and
/// a mass or a spring there would make a mechanism of them.
pub(super) fn hold_unlisted(
    model: &mut Model,
    listed: &HashSet<DofRef>,
    node_file: &HashSet<u32>,
) -> Result<(), crate::error::ModelError> {
    let nodes: HashSet<NodeId> = listed.iter().map(|r| r.node).chain(node_file.iter().map(|&id| NodeId(id))).collect();
    let on_beams: HashSet<NodeId> = model.beams().iter().flat_map(|b| b.nodes).collect();
    let mut held: HashMap<u32, Vec<crate::dof::Dof>> = HashMap::new();
    for &n in &nodes {
        if on_beams.contains(&n) {
            continue;
        }
        let dofs: Vec<_> =
            model.node_dofs().iter().copied().filter(|&d| !listed.contains(&DofRef { node: n, dof: d })).collect();
        if !dofs.is_empty() {
            held.insert(n.0, dofs);
        }
    }
    let mut ids: Vec<u32> = held.keys().copied().collect();
    ids.sort_unstable();
    for id in ids {
        model.add_support(id, &held[&id])?;
    }
    Ok(())
}
