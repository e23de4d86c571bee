//! The symbolic analysis, once per pattern: a fill-reducing ordering
//! (faer's approximate minimum degree) of the pattern with the cliques
//! added and the elimination tree, which both layouts share; for the
//! simplicial layout, the pattern of `L` (faer's simplicial symbolic
//! Cholesky) and the row structure of `L` that the up-looking factorisation
//! walks.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::simplicial;
use fe_model::Pattern;

use super::SymbolicLdlt;

/// A fill-reducing ordering of a pattern with its cliques added: `perm[new]
/// = old`, `perm_inv[old] = new`, and the pattern analysed (`None` when
/// there are no cliques: the pattern itself).
pub(super) struct Ordering {
    pub(super) perm: Vec<usize>,
    pub(super) perm_inv: Vec<usize>,
    pub(super) augmented: Option<Pattern>,
}

/// Orders a symmetric pattern (both triangles stored, rows sorted, diagonal
/// present) with every pair of equations within each clique added (an
/// index out of range is an error): faer's approximate minimum degree.
pub(super) fn order(pattern: &Pattern, cliques: &[Vec<usize>]) -> Result<Ordering, String> {
    let n = pattern.n();
    if u32::try_from(n).is_err() {
        return Err(format!("{n} equations exceed the solver's 32-bit row indices"));
    }
    let augmented = if cliques.is_empty() { None } else { Some(with_clique_pairs(pattern, cliques)?) };
    let analysed = augmented.as_ref().unwrap_or(pattern);

    // upper triangle of the analysed pattern, for the ordering
    let mut up_ptr = Vec::with_capacity(n + 1);
    let mut up_idx = Vec::with_capacity(analysed.nnz() / 2 + n);
    up_ptr.push(0);
    for c in 0..n {
        let rows = &analysed.row_idx()[analysed.col_ptr()[c]..analysed.col_ptr()[c + 1]];
        up_idx.extend(rows.iter().copied().take_while(|&r| r <= c));
        up_ptr.push(up_idx.len());
    }
    let mut perm = vec![0usize; n];
    let mut perm_inv = vec![0usize; n];
    let upper = SymbolicSparseColMatRef::new_checked(n, n, &up_ptr, None, &up_idx);
    let mut mem = MemBuffer::new(amd::order_scratch::<usize>(n, up_idx.len()));
    amd::order(&mut perm, &mut perm_inv, upper, amd::Control::default(), MemStack::new(&mut mem))
        .map_err(|e| format!("ordering failed: {e:?}"))?;
    Ok(Ordering { perm, perm_inv, augmented })
}

/// The elimination tree (`-1` for a root) and the column counts of `L`,
/// diagonal included, of the symmetric matrix whose upper triangle is
/// given by column (rows sorted): faer's.
pub(super) fn elimination_tree(n: usize, up_ptr: &[usize], up_rows: &[usize]) -> (Vec<isize>, Vec<usize>) {
    let upper = SymbolicSparseColMatRef::new_checked(n, n, up_ptr, None, up_rows);
    let mut etree = vec![0isize; n];
    let mut counts = vec![0usize; n];
    let mut mem = MemBuffer::new(simplicial::prefactorize_symbolic_cholesky_scratch::<usize>(n, up_rows.len()));
    simplicial::prefactorize_symbolic_cholesky(&mut etree, &mut counts, upper, MemStack::new(&mut mem));
    (etree, counts)
}

impl SymbolicLdlt {
    /// Orders and analyses a symmetric pattern (both triangles stored, rows
    /// sorted, diagonal present).
    ///
    /// The ordering and the pattern of `L` are those of the pattern with
    /// every pair of equations within each clique added (caller's numbering,
    /// an index out of range is an error), so that `L + L^T` covers each clique
    /// and the selected inverse holds every entry of `Z^-1` between its
    /// equations. The added pairs are structural zeros: values are still
    /// read on the original pattern. With no cliques this is the plain
    /// analysis of `pattern`.
    #[cfg(test)]
    pub(crate) fn new(pattern: &Pattern, cliques: &[Vec<usize>]) -> Result<Self, String> {
        Self::from_ordering(pattern, order(pattern, cliques)?)
    }

    /// The analysis of `pattern` in a given ordering (see [`order`]).
    pub(super) fn from_ordering(pattern: &Pattern, ordering: Ordering) -> Result<Self, String> {
        let n = pattern.n();
        let Ordering { perm, perm_inv, augmented } = ordering;

        // the numeric factorisation reads the values of the original pattern
        let (a_col_ptr, a_row_usize, a_src) = permuted_upper(pattern, &perm, &perm_inv);
        let a_row_idx: Vec<u32> = a_row_usize.iter().map(|&i| i as u32).collect();
        // while the elimination tree and L come from the analysed one
        let (e_col_ptr, e_row_idx) = match &augmented {
            Some(aug) => {
                let (ptr, rows, _) = permuted_upper(aug, &perm, &perm_inv);
                (ptr, rows)
            }
            None => (a_col_ptr.clone(), a_row_usize),
        };
        drop(augmented);
        let nnz_e = e_row_idx.len();

        // elimination tree, column counts and the pattern of L (faer)
        let l_symbolic = {
            let upper = SymbolicSparseColMatRef::new_checked(n, n, &e_col_ptr, None, &e_row_idx);
            let mut etree = vec![0isize; n];
            let mut counts = vec![0usize; n];
            let mut mem = MemBuffer::new(
                simplicial::prefactorize_symbolic_cholesky_scratch::<usize>(n, nnz_e)
                    .or(simplicial::factorize_simplicial_symbolic_cholesky_scratch::<usize>(n)),
            );
            let etree_ref =
                simplicial::prefactorize_symbolic_cholesky(&mut etree, &mut counts, upper, MemStack::new(&mut mem));
            simplicial::factorize_simplicial_symbolic_cholesky(upper, etree_ref, &counts, MemStack::new(&mut mem))
                .map_err(|e| format!("symbolic factorisation failed: {e:?}"))?
        };
        drop((e_col_ptr, e_row_idx));

        // strictly lower part (faer stores the diagonal first in each column)
        let (f_ptr, f_idx) = (l_symbolic.col_ptr(), l_symbolic.row_idx());
        let mut l_col_ptr = Vec::with_capacity(n + 1);
        let mut l_row_idx = Vec::with_capacity(f_idx.len() - n);
        l_col_ptr.push(0);
        for j in 0..n {
            let col = &f_idx[f_ptr[j]..f_ptr[j + 1]];
            if col.first() != Some(&j) {
                return Err("symbolic factor without its diagonal".into());
            }
            let below = &col[1..];
            if below.windows(2).any(|w| w[0] >= w[1]) || below.first().is_some_and(|&r| r <= j) {
                return Err("symbolic factor rows are not sorted".into());
            }
            l_row_idx.extend(below.iter().map(|&r| r as u32));
            l_col_ptr.push(l_row_idx.len());
        }
        drop(l_symbolic);

        // row structure by a counting transpose: columns visited in ascending
        // order, so each row lists its columns ascending
        let nnz_l = l_row_idx.len();
        let mut lt_row_ptr = vec![0usize; n + 1];
        for &r in &l_row_idx {
            lt_row_ptr[r as usize + 1] += 1;
        }
        for k in 0..n {
            lt_row_ptr[k + 1] += lt_row_ptr[k];
        }
        let mut next = lt_row_ptr[..n].to_vec();
        let mut lt_col = vec![0u32; nnz_l];
        let mut lt_pos = vec![0usize; nnz_l];
        for i in 0..n {
            for p in l_col_ptr[i]..l_col_ptr[i + 1] {
                let k = l_row_idx[p] as usize;
                let q = next[k];
                next[k] += 1;
                lt_col[q] = i as u32;
                lt_pos[q] = p;
            }
        }

        Ok(SymbolicLdlt {
            n,
            perm,
            perm_inv,
            orig_col_ptr: pattern.col_ptr().to_vec(),
            a_col_ptr,
            a_row_idx,
            a_src,
            l_col_ptr,
            l_row_idx,
            lt_row_ptr,
            lt_col,
            lt_pos,
        })
    }
}

/// `pattern` with every pair of equations within each clique added: both
/// triangles, rows sorted and unique. Clique indices must be below `n`.
pub(super) fn with_clique_pairs(pattern: &Pattern, cliques: &[Vec<usize>]) -> Result<Pattern, String> {
    let n = pattern.n();
    if let Some(eq) = cliques.iter().flatten().copied().find(|&eq| eq >= n) {
        return Err(format!("clique equation {eq} is not below {n}"));
    }
    // room for the original rows and every clique row (duplicates included),
    // then each column sorted and compacted in place
    let mut room: Vec<usize> = (0..n).map(|c| pattern.col_ptr()[c + 1] - pattern.col_ptr()[c]).collect();
    for clique in cliques {
        for &c in clique {
            room[c] += clique.len();
        }
    }
    let mut start = Vec::with_capacity(n + 1);
    start.push(0);
    for c in 0..n {
        start.push(start[c] + room[c]);
    }
    drop(room);
    let mut rows = vec![0usize; start[n]];
    let mut next = start[..n].to_vec();
    for c in 0..n {
        let col = &pattern.row_idx()[pattern.col_ptr()[c]..pattern.col_ptr()[c + 1]];
        rows[next[c]..next[c] + col.len()].copy_from_slice(col);
        next[c] += col.len();
    }
    for clique in cliques {
        for &c in clique {
            rows[next[c]..next[c] + clique.len()].copy_from_slice(clique);
            next[c] += clique.len();
        }
    }
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0);
    let mut kept = 0;
    for c in 0..n {
        rows[start[c]..next[c]].sort_unstable();
        let mut last = None;
        // kept <= p throughout, so the compaction never overwrites a row
        // that is still to be read
        for p in start[c]..next[c] {
            let r = rows[p];
            if last != Some(r) {
                rows[kept] = r;
                kept += 1;
                last = Some(r);
            }
        }
        col_ptr.push(kept);
    }
    rows.truncate(kept);
    // symmetric with its diagonal, as the given pattern was (a clique adds
    // both triangles of its pairs); `Pattern::new` checks it, once per analysis
    Pattern::new(n, col_ptr, rows).map_err(|e| e.to_string())
}

/// Upper triangle of `P A P^T` by column, rows ascending, for a symmetric
/// pattern `A` with both triangles stored: column pointers, rows, and the
/// position of each entry in `A`'s values.
///
/// New rows `i` are walked in order; each entry `(r, perm[i])` of `A` with
/// `j = perm_inv[r] >= i` is `B[j, i] = B[i, j]` by symmetry, appended to
/// column `j`, so every column receives its rows in ascending order.
pub(super) fn permuted_upper(
    pattern: &Pattern,
    perm: &[usize],
    perm_inv: &[usize],
) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let n = pattern.n();
    let mut col_ptr = vec![0usize; n + 1];
    for i in 0..n {
        let c = perm[i];
        for &r in &pattern.row_idx()[pattern.col_ptr()[c]..pattern.col_ptr()[c + 1]] {
            let j = perm_inv[r];
            if j >= i {
                col_ptr[j + 1] += 1;
            }
        }
    }
    for j in 0..n {
        col_ptr[j + 1] += col_ptr[j];
    }
    let nnz = col_ptr[n];
    let mut next = col_ptr[..n].to_vec();
    let mut rows = vec![0usize; nnz];
    let mut src = vec![0usize; nnz];
    for i in 0..n {
        let c = perm[i];
        for p in pattern.col_ptr()[c]..pattern.col_ptr()[c + 1] {
            let j = perm_inv[pattern.row_idx()[p]];
            if j >= i {
                rows[next[j]] = i;
                src[next[j]] = p;
                next[j] += 1;
            }
        }
    }
    (col_ptr, rows, src)
}
