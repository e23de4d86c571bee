//! Error types of the model layer.

use std::path::PathBuf;

/// A model that cannot be built or assembled.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A node id used twice.
    #[error("node {id} is defined twice")]
    DuplicateNode {
        /// The node id.
        id: u32,
    },
    /// Something (a material, an element, ...) defined twice.
    #[error("{what} is defined twice")]
    Duplicate {
        /// What was duplicated.
        what: String,
    },
    /// A reference to a node that does not exist.
    #[error("{context} refers to node {id}, which does not exist")]
    UnknownNode {
        /// The missing node id.
        id: u32,
        /// Who referred to it.
        context: String,
    },
    /// A reference to a group that does not exist.
    #[error("{context} refers to group `{name}`, which does not exist")]
    UnknownGroup {
        /// The missing group.
        name: String,
        /// Who referred to it.
        context: String,
    },
    /// A reference to a material that does not exist.
    #[error("{context} refers to material `{name}`, which does not exist")]
    UnknownMaterial {
        /// The missing material.
        name: String,
        /// Who referred to it.
        context: String,
    },
    /// A reference to a section that does not exist.
    #[error("{context} refers to section `{name}`, which does not exist")]
    UnknownSection {
        /// The missing section.
        name: String,
        /// Who referred to it.
        context: String,
    },
    /// An element whose two nodes coincide.
    #[error("element {element} has zero length (its two nodes coincide)")]
    ZeroLength {
        /// The element id.
        element: u32,
    },
    /// A physically invalid value.
    #[error("{what} {reason}")]
    Invalid {
        /// The offending item and field.
        what: String,
        /// Why it is invalid.
        reason: String,
    },
    /// A parameter name that does not resolve.
    #[error("unknown parameter `{name}`: {reason}")]
    UnknownQuantity {
        /// The name as written.
        name: String,
        /// Why it does not resolve, with the valid forms.
        reason: String,
    },
    /// No free DOF remains.
    #[error("the model has no free degree of freedom")]
    NoFreeDof,
    /// A node no element, spring or mass touches while some of its DOFs are free.
    #[error("node {id} is not connected to any element, spring or mass; support it or remove it")]
    DanglingNode {
        /// The node id.
        id: u32,
    },
    /// Stiffness is singular: a mechanism or an unsupported body.
    #[error("{}", mechanism_message(*modes, hint, nodes))]
    Mechanism {
        /// Where the (first) zero-energy motion is largest, as `node:dof`.
        hint: String,
        /// Number of independent zero-energy motions found.
        modes: usize,
        /// Nodes the first zero-energy motion moves, in increasing id order.
        nodes: Vec<u32>,
    },
}

/// `1-4, 7, 9-10`: node ids (sorted) as ranges, at most about 12 items.
pub(crate) fn id_ranges(ids: &[u32]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < ids.len() {
        let mut j = i;
        while j + 1 < ids.len() && ids[j + 1] == ids[j].saturating_add(1) {
            j += 1;
        }
        parts.push(if j > i { format!("{}-{}", ids[i], ids[j]) } else { ids[i].to_string() });
        i = j + 1;
    }
    if parts.len() > 12 {
        let more = parts.len() - 10;
        parts.truncate(10);
        parts.push(format!("and {more} more"));
    }
    parts.join(", ")
}

fn mechanism_message(modes: usize, hint: &str, nodes: &[u32]) -> String {
    let what = if modes > 1 {
        format!("{modes} independent zero-energy motions; the first")
    } else {
        "a zero-energy motion that".to_string()
    };
    let moving = match nodes.len() {
        0 => String::new(),
        1 => format!(" (node {})", nodes[0]),
        _ => format!(" (nodes {})", id_ranges(nodes)),
    };
    format!(
        "the stiffness matrix is singular: the structure is a mechanism or a body without enough supports; it has \
         {what} moves it without deforming it, largest at {hint}{moving}; check the supports, ties, joints and \
         springs there (a free-free test is modelled with soft suspension springs)"
    )
}

/// Line and column (1-based) in a text file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Location {
    /// 1-based line.
    pub line: usize,
    /// 1-based column (in characters).
    pub column: usize,
}

impl Location {
    /// Location of byte offset `offset` in `source`.
    pub fn of(source: &str, offset: usize) -> Self {
        let offset = offset.min(source.len());
        let before = &source[..floor_char_boundary(source, offset)];
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().map_or(0, |s| s.chars().count()) + 1;
        Location { line, column }
    }
}

fn floor_char_boundary(s: &str, mut i: usize) -> usize {
    while i > 0 && !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// An error in a case file, located in the file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}{}: {message}", file.display(), location.map(|l| format!(":{}:{}", l.line, l.column)).unwrap_or_default())]
pub struct CaseError {
    /// The case file.
    pub file: PathBuf,
    /// Where in the file, when known.
    pub location: Option<Location>,
    /// What is wrong, in words a user can act on.
    pub message: String,
    /// The offending source line, for display under the message.
    pub snippet: Option<String>,
}

impl CaseError {
    pub(crate) fn at(
        file: &std::path::Path,
        source: &str,
        span: Option<std::ops::Range<usize>>,
        message: String,
    ) -> Self {
        let location = span.as_ref().map(|s| Location::of(source, s.start));
        let snippet = location.and_then(|l| source.lines().nth(l.line - 1).map(str::to_string));
        CaseError { file: file.to_path_buf(), location, message, snippet }
    }

    /// The same place in the file with another message: a spec keeps the
    /// place of a value (with an empty message) so that a higher layer can
    /// refuse it where it is written.
    pub fn with_message(&self, message: impl Into<String>) -> CaseError {
        CaseError { message: message.into(), ..self.clone() }
    }

    /// The message with the source line and a caret under the column, for terminals.
    pub fn render(&self) -> String {
        let mut out = self.to_string();
        if let (Some(loc), Some(line)) = (self.location, &self.snippet) {
            out.push_str(&format!("\n{:>5} | {line}\n      | {}^", loc.line, " ".repeat(loc.column.saturating_sub(1))));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn location_counts_lines_and_columns_from_one() {
        let s = "a = 1\nbb = 2\n";
        assert_eq!(Location::of(s, 0), Location { line: 1, column: 1 });
        assert_eq!(Location::of(s, 6), Location { line: 2, column: 1 });
        assert_eq!(Location::of(s, 9), Location { line: 2, column: 4 });
        assert_eq!(Location::of(s, 999), Location { line: 3, column: 1 });
    }

    #[test]
    fn a_mechanism_names_its_dof_its_count_and_the_moving_nodes_as_ranges() {
        let e = ModelError::Mechanism { hint: "31:uy".into(), modes: 3, nodes: (1..=31).chain([40, 42, 43]).collect() };
        let m = e.to_string();
        assert!(m.contains("3 independent zero-energy motions"), "{m}");
        assert!(m.contains("largest at 31:uy (nodes 1-31, 40, 42-43)"), "{m}");
        let many: Vec<u32> = (0..20).map(|i| 3 * i).collect();
        assert_eq!(id_ranges(&many), "0, 3, 6, 9, 12, 15, 18, 21, 24, 27, and 10 more");
    }
}
