//! The sparsity pattern K, M and every group matrix share: its invariants
//! (square, sorted, symmetric, with the diagonal) checked for a pattern
//! made elsewhere, and the pattern of an assembly's blocks.

use crate::error::ModelError;

/// Symmetric sparsity pattern in compressed sparse column form (both
/// triangles stored, rows sorted within each column, every diagonal entry
/// stored). [`Pattern::new`] checks all of it; an
/// [`Assembly`](super::Assembly)'s pattern
/// also holds every block's entries.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pattern {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
}

impl Pattern {
    /// The pattern of an `n x n` matrix with the rows `row_idx[col_ptr[c]
    /// .. col_ptr[c + 1]]` in column `c`. Refuses (`ModelError::Invalid`)
    /// column pointers that are not `n + 1` from 0 to `row_idx.len()`
    /// without decreasing, rows that are out of range or not strictly
    /// ascending within a column, a missing diagonal entry, and an entry
    /// whose mirror is not stored.
    pub fn new(n: usize, col_ptr: Vec<usize>, row_idx: Vec<usize>) -> Result<Self, ModelError> {
        let bad = |reason: String| ModelError::Invalid { what: "the sparsity pattern".into(), reason };
        if col_ptr.len() != n + 1 {
            return Err(bad(format!("has {} column pointers for {n} columns; expected {}", col_ptr.len(), n + 1)));
        }
        if col_ptr[0] != 0 || col_ptr[n] != row_idx.len() {
            return Err(bad(format!(
                "has column pointers from {} to {}; expected from 0 to {}, the number of rows stored",
                col_ptr[0],
                col_ptr[n],
                row_idx.len()
            )));
        }
        if let Some(c) = (0..n).find(|&c| col_ptr[c] > col_ptr[c + 1]) {
            return Err(bad(format!("has column pointers that decrease at column {c}")));
        }
        for c in 0..n {
            let rows = &row_idx[col_ptr[c]..col_ptr[c + 1]];
            if let Some(&r) = rows.iter().find(|&&r| r >= n) {
                return Err(bad(format!("has row {r} in column {c}, beyond its {n} rows")));
            }
            if let Some(w) = rows.windows(2).find(|w| w[0] >= w[1]) {
                return Err(bad(format!("has rows {} then {} in column {c}: not strictly ascending", w[0], w[1])));
            }
            if rows.binary_search(&c).is_err() {
                return Err(bad(format!("has no diagonal entry in column {c}")));
            }
        }
        let pattern = Pattern { n, col_ptr, row_idx };
        for c in 0..n {
            for &r in pattern.rows(c) {
                if pattern.position(c, r).is_none() {
                    return Err(bad(format!("is not symmetric: ({r}, {c}) is stored and ({c}, {r}) is not")));
                }
            }
        }
        Ok(pattern)
    }

    /// Matrix dimension.
    #[inline]
    pub fn n(&self) -> usize {
        self.n
    }

    /// Column pointers, length `n + 1`.
    #[inline]
    pub fn col_ptr(&self) -> &[usize] {
        &self.col_ptr
    }

    /// Row indices, length `nnz`.
    #[inline]
    pub fn row_idx(&self) -> &[usize] {
        &self.row_idx
    }

    /// The rows stored in column `col`, ascending.
    #[inline]
    pub fn rows(&self, col: usize) -> &[usize] {
        &self.row_idx[self.col_ptr[col]..self.col_ptr[col + 1]]
    }

    /// Number of stored entries.
    #[inline]
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Index of entry `(row, col)` in the values array.
    pub fn position(&self, row: usize, col: usize) -> Option<usize> {
        let (a, b) = (self.col_ptr[col], self.col_ptr[col + 1]);
        self.row_idx[a..b].binary_search(&row).ok().map(|k| a + k)
    }

    /// Index of each diagonal entry.
    pub fn diagonal_positions(&self) -> Vec<usize> {
        (0..self.n).map(|i| self.position(i, i).expect("diagonal is always stored")).collect()
    }

    /// The pattern of `n` equations with the diagonal and every pair of
    /// equations of each block (a block's free equations): symmetric by
    /// construction, so not checked again.
    pub(super) fn of_blocks<'a>(n: usize, blocks: impl Iterator<Item = &'a [usize]>) -> Self {
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        for i in 0..n {
            cols[i].push(i);
        }
        for eqs in blocks {
            for &c in eqs {
                cols[c].extend_from_slice(eqs);
            }
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for mut rows in cols {
            rows.sort_unstable();
            rows.dedup();
            row_idx.extend(rows);
            col_ptr.push(row_idx.len());
        }
        Pattern { n, col_ptr, row_idx }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::Assembly;
    use crate::samples;

    #[test]
    fn an_assemblys_pattern_passes_the_checks_of_a_pattern_from_outside() {
        let a = Assembly::new(&samples::frame_with_joint()).unwrap();
        let p = a.pattern();
        assert_eq!(Pattern::new(p.n(), p.col_ptr().to_vec(), p.row_idx().to_vec()).unwrap(), *p);
    }

    #[test]
    fn a_pattern_that_breaks_an_invariant_is_refused_with_the_reason() {
        let refused = |n: usize, col_ptr: Vec<usize>, row_idx: Vec<usize>| match Pattern::new(n, col_ptr, row_idx) {
            Err(ModelError::Invalid { what, reason }) => {
                assert_eq!(what, "the sparsity pattern");
                reason
            }
            other => panic!("expected ModelError::Invalid, got {other:?}"),
        };
        // [[x, x], [x, x]] is accepted
        assert!(Pattern::new(2, vec![0, 2, 4], vec![0, 1, 0, 1]).is_ok());
        assert_eq!(refused(2, vec![0, 2], vec![0, 1]), "has 2 column pointers for 2 columns; expected 3");
        assert_eq!(
            refused(2, vec![1, 2, 4], vec![0, 1, 0, 1]),
            "has column pointers from 1 to 4; expected from 0 to 4, the number of rows stored"
        );
        assert_eq!(
            refused(2, vec![0, 2, 3], vec![0, 1, 0, 1]),
            "has column pointers from 0 to 3; expected from 0 to 4, the number of rows stored"
        );
        assert_eq!(refused(2, vec![0, 3, 2], vec![0, 1]), "has column pointers that decrease at column 1");
        assert_eq!(refused(2, vec![0, 2, 4], vec![0, 2, 0, 1]), "has row 2 in column 0, beyond its 2 rows");
        assert_eq!(
            refused(2, vec![0, 2, 4], vec![1, 0, 0, 1]),
            "has rows 1 then 0 in column 0: not strictly ascending"
        );
        assert_eq!(
            refused(2, vec![0, 2, 4], vec![0, 0, 0, 1]),
            "has rows 0 then 0 in column 0: not strictly ascending"
        );
        assert_eq!(refused(2, vec![0, 1, 3], vec![1, 0, 1]), "has no diagonal entry in column 0");
        assert_eq!(refused(2, vec![0, 2, 3], vec![0, 1, 1]), "is not symmetric: (1, 0) is stored and (0, 1) is not");
        let message = Pattern::new(1, vec![0, 0], vec![]).unwrap_err().to_string();
        assert_eq!(message, "the sparsity pattern has no diagonal entry in column 0");
    }
}
