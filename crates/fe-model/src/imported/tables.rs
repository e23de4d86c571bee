//! The text tables that come with exported matrices: the DOF table (which
//! node and direction each row of the matrices is) and the node
//! coordinates.
//!
//! A DOF table has one line per matrix row, in row order: `node dof`, the
//! DOF a name (`ux` .. `rz`) or the number that Nastran, Abaqus and ANSYS
//! use (1 `ux`, 2 `uy`, 3 `uz`, 4 `rx`, 5 `ry`, 6 `rz`). A node file has one
//! line per node: `id x y`, or `id x y z`. Fields are separated by blanks
//! or commas; lines starting with `#` or `%`, and blank lines, are skipped.

use std::collections::HashSet;

use super::matrix_market::{TextError, fields, number};
use crate::dof::{Dimension, Dof, DofRef};

/// The (non-comment) lines of a table with their line numbers.
fn rows(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines().enumerate().map(|(i, l)| (i + 1, l.trim_end_matches('\r'))).filter(|(_, l)| {
        let t = l.trim_start();
        !(t.is_empty() || t.starts_with('#') || t.starts_with('%'))
    })
}

/// A DOF by its name or its number (1 to 6).
fn dof(text: &str) -> Option<Dof> {
    match text.parse::<usize>() {
        Ok(k) => Dof::SPATIAL.get(k.checked_sub(1)?).copied(),
        Err(_) => text.parse().ok(),
    }
}

/// A DOF table and where each of its rows is written.
#[derive(Clone, Debug, PartialEq)]
pub struct DofTable {
    /// The DOF of each matrix row, in row order.
    pub dofs: Vec<DofRef>,
    /// The line of each row in the file (for messages).
    pub lines: Vec<usize>,
}

/// Reads a DOF table (see the module docs) for a model of dimension `dim`.
pub fn read_dof_table(text: &str, dim: Dimension) -> Result<DofTable, TextError> {
    let mut table = DofTable { dofs: Vec::new(), lines: Vec::new() };
    let mut seen = HashSet::new();
    for (no, line) in rows(text) {
        let f = fields(line);
        if f.len() != 2 {
            let col = f.get(2).map_or(1, |x| x.0);
            return Err(TextError::at(
                no,
                col,
                format!("a DOF table's line is `node dof`; this one has {} fields", f.len()),
            ));
        }
        let (nc, nt) = f[0];
        let node: u32 = nt.parse().map_err(|_| TextError::at(no, nc, format!("`{nt}` is not a node id")))?;
        let (dc, dt) = f[1];
        let d = dof(dt).ok_or_else(|| {
            TextError::at(
                no,
                dc,
                format!("`{dt}` is not a DOF: a name (ux, uy, uz, rx, ry, rz) or a number from 1 to 6"),
            )
        })?;
        dim.check(d).map_err(|e| TextError::at(no, dc, e))?;
        let r = DofRef::new(node, d);
        if !seen.insert(r) {
            return Err(TextError::at(no, nc, format!("{r} is listed twice")));
        }
        table.dofs.push(r);
        table.lines.push(no);
    }
    if table.dofs.is_empty() {
        return Err(TextError::at(1, 1, "the DOF table lists no DOF"));
    }
    Ok(table)
}

/// A node of a node file: id, position, and its line.
pub type NodeRow = (u32, [f64; 3], usize);

/// Reads a node file (see the module docs); a planar model's nodes lie at
/// `z = 0`.
pub fn read_nodes(text: &str, dim: Dimension) -> Result<Vec<NodeRow>, TextError> {
    let mut out = Vec::new();
    let mut seen = HashSet::new();
    for (no, line) in rows(text) {
        let f = fields(line);
        if !(3..=4).contains(&f.len()) {
            let col = f.get(4).map_or(1, |x| x.0);
            return Err(TextError::at(
                no,
                col,
                format!("a node's line is `id x y` or `id x y z`; this one has {} fields", f.len()),
            ));
        }
        let (ic, it) = f[0];
        let id: u32 = it.parse().map_err(|_| TextError::at(no, ic, format!("`{it}` is not a node id")))?;
        if !seen.insert(id) {
            return Err(TextError::at(no, ic, format!("node {id} is listed twice")));
        }
        let mut p = [0.0; 3];
        for (k, &(col, t)) in f[1..].iter().enumerate() {
            p[k] = number(t)
                .filter(|v| v.is_finite())
                .ok_or_else(|| TextError::at(no, col, format!("`{t}` is not a coordinate")))?;
        }
        if dim == Dimension::Planar && p[2] != 0.0 {
            return Err(TextError::at(
                no,
                f[3].0,
                format!(
                    "node {id} has z = {}, and a planar model lies in the x-y plane (`[model] dimension = 3`)",
                    p[2]
                ),
            ));
        }
        out.push((id, p, no));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dof_tables_take_names_and_numbers_and_refuse_with_their_place() {
        let t = read_dof_table("# node dof\n7 uy\n7, 6\n\n12 3\n", Dimension::Spatial).unwrap();
        assert_eq!(t.dofs, vec![DofRef::new(7, Dof::Uy), DofRef::new(7, Dof::Rz), DofRef::new(12, Dof::Uz)]);
        assert_eq!(t.lines, vec![2, 3, 5]);
        for (text, dim, line, column, words) in [
            ("7 uz\n", Dimension::Planar, 1, 3, "`uz` is not a DOF of a planar model"),
            ("7 3\n", Dimension::Planar, 1, 3, "`uz` is not a DOF of a planar model"),
            ("7 ux\n7 7\n", Dimension::Spatial, 2, 3, "`7` is not a DOF"),
            ("x ux\n", Dimension::Spatial, 1, 1, "`x` is not a node id"),
            ("7 ux\n 7 ux\n", Dimension::Spatial, 2, 2, "7:ux is listed twice"),
            ("7 ux 1\n", Dimension::Spatial, 1, 6, "has 3 fields"),
            ("# nothing\n", Dimension::Spatial, 1, 1, "lists no DOF"),
        ] {
            let e = read_dof_table(text, dim).unwrap_err();
            assert!(e.message.contains(words), "{text:?}: {e:?}");
            assert_eq!((e.line, e.column), (line, column), "{text:?}: {e:?}");
        }
    }

    #[test]
    fn node_files_give_positions_and_refuse_with_their_place() {
        let n = read_nodes("1 0 0\n2, 0.5, 1.0, 2e-1\n", Dimension::Spatial).unwrap();
        assert_eq!(n, vec![(1, [0.0; 3], 1), (2, [0.5, 1.0, 0.2], 2)]);
        for (text, dim, line, column, words) in [
            ("1 0 0 1\n", Dimension::Planar, 1, 7, "has z = 1"),
            ("1 0 q\n", Dimension::Spatial, 1, 5, "`q` is not a coordinate"),
            ("1 0\n", Dimension::Spatial, 1, 1, "has 2 fields"),
            ("1 0 0\n1 1 1\n", Dimension::Spatial, 2, 1, "node 1 is listed twice"),
        ] {
            let e = read_nodes(text, dim).unwrap_err();
            assert!(e.message.contains(words), "{text:?}: {e:?}");
            assert_eq!((e.line, e.column), (line, column), "{text:?}: {e:?}");
        }
    }
}
