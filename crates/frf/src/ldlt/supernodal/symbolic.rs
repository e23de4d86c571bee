//! The supernodal symbolic analysis: the shared ordering, postordered; the
//! supernodes (faer's supernodal symbolic Cholesky); their elimination tree
//! and the layout of the update-matrix stack.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::SymbolicSupernodalParams;
use faer::sparse::linalg::cholesky::{simplicial, supernodal};
use fe_model::Pattern;

use super::super::symbolic::{Ordering, elimination_tree, permuted_upper};
use super::SupernodalLdlt;

const NONE: usize = usize::MAX;

impl SupernodalLdlt {
    /// The supernodal analysis of `pattern` in a given ordering (see
    /// [`super::super::symbolic::order`]), which is postordered first.
    pub(in crate::ldlt) fn from_ordering(pattern: &Pattern, ordering: Ordering) -> Result<Self, String> {
        let n = pattern.n();
        let Ordering { perm: amd_perm, perm_inv: amd_inv, augmented } = ordering;
        let analysed = augmented.as_ref().unwrap_or(pattern);

        // postorder the elimination tree, so that each subtree is a run of
        // consecutive columns: the multifrontal stack relies on it, and
        // supernodes come out larger. The fill does not change.
        let (etree, _) = {
            let (ptr, rows, _) = permuted_upper(analysed, &amd_perm, &amd_inv);
            elimination_tree(n, &ptr, &rows)
        };
        let post = postorder(&etree);
        let perm: Vec<usize> = post.iter().map(|&k| amd_perm[k]).collect();
        let mut perm_inv = vec![0usize; n];
        for (new, &old) in perm.iter().enumerate() {
            perm_inv[old] = new;
        }
        drop((amd_perm, amd_inv, etree, post));

        // supernodes and their rows (faer), on the analysed pattern
        let (up_ptr, up_rows, _) = permuted_upper(analysed, &perm, &perm_inv);
        let upper = SymbolicSparseColMatRef::new_checked(n, n, &up_ptr, None, &up_rows);
        let mut etree = vec![0isize; n];
        let mut counts = vec![0usize; n];
        let mut mem = MemBuffer::new(
            simplicial::prefactorize_symbolic_cholesky_scratch::<usize>(n, up_rows.len())
                .or(supernodal::factorize_supernodal_symbolic_cholesky_scratch::<usize>(n)),
        );
        let etree_ref =
            simplicial::prefactorize_symbolic_cholesky(&mut etree, &mut counts, upper, MemStack::new(&mut mem));
        let faer_symbolic = supernodal::factorize_supernodal_symbolic_cholesky(
            upper,
            etree_ref,
            &counts,
            MemStack::new(&mut mem),
            SymbolicSupernodalParams::default(),
        )
        .map_err(|e| format!("supernodal symbolic factorisation failed: {e:?}"))?;
        drop((mem, up_ptr, up_rows));
        let (nnz_exact, madds_exact) = counts.iter().fold((0usize, 0u64), |(nnz, madds), &c| {
            let below = c as u64 - 1;
            (nnz + c - 1, madds + below * (below + 3) / 2)
        });
        drop(counts);

        let n_super = faer_symbolic.n_supernodes();
        let mut begin = faer_symbolic.supernode_begin().to_vec();
        begin.push(n);
        let row_ptr = faer_symbolic.col_ptr_for_row_idx().to_vec();
        let rows: Vec<u32> = faer_symbolic.row_idx().iter().map(|&r| r as u32).collect();
        drop(faer_symbolic);
        let mut super_of = vec![0u32; n];
        let mut val_ptr = Vec::with_capacity(n_super + 1);
        val_ptr.push(0);
        let (mut max_rows, mut max_cols, mut max_rows_cols) = (0, 0, 0);
        for s in 0..n_super {
            let (f, e) = (begin[s], begin[s + 1]);
            let (w, r) = (e - f, row_ptr[s + 1] - row_ptr[s]);
            let s_rows = &rows[row_ptr[s]..row_ptr[s + 1]];
            if w == 0 || s_rows.windows(2).any(|p| p[0] >= p[1]) || s_rows.first().is_some_and(|&i| (i as usize) < e) {
                return Err(format!("supernode {s} is empty or its rows are not sorted below it"));
            }
            super_of[f..e].fill(s as u32);
            val_ptr.push(val_ptr[s] + (w + r) * w);
            (max_rows, max_cols, max_rows_cols) = (max_rows.max(r), max_cols.max(w), max_rows_cols.max(r * w));
        }

        // the supernodal elimination tree: a supernode's parent holds the
        // first row below its diagonal block
        let parent: Vec<usize> = (0..n_super)
            .map(|s| rows[row_ptr[s]..row_ptr[s + 1]].first().map_or(NONE, |&r| super_of[r as usize] as usize))
            .collect();
        let mut child_ptr = vec![0usize; n_super + 1];
        for &p in parent.iter().filter(|&&p| p != NONE) {
            child_ptr[p + 1] += 1;
        }
        for s in 0..n_super {
            child_ptr[s + 1] += child_ptr[s];
        }
        let mut next = child_ptr[..n_super].to_vec();
        let mut children = vec![0u32; child_ptr[n_super]];
        for (s, &p) in parent.iter().enumerate() {
            if p != NONE {
                if p <= s {
                    return Err(format!("supernode {s} has parent {p}, not above it"));
                }
                children[next[p]] = s as u32;
                next[p] += 1;
            }
        }

        // the update-matrix stack: supernode s makes its update matrix above
        // the stack, adds its children's (the top of the stack, by the
        // postorder) into its front, then moves its own down over them
        let mut update_at = vec![0usize; n_super];
        let (mut top, mut stack_len) = (0usize, 0usize);
        for s in 0..n_super {
            let kids = &children[child_ptr[s]..child_ptr[s + 1]];
            let mut at = kids.first().map_or(top, |&c| update_at[c as usize]);
            let start = at;
            for &c in kids {
                let c = c as usize;
                let rc = row_ptr[c + 1] - row_ptr[c];
                if update_at[c] != at {
                    return Err(format!("the supernodes are not postordered at {s}"));
                }
                at += rc * rc;
            }
            if at != top {
                return Err(format!("the supernodes are not postordered at {s}"));
            }
            let r = row_ptr[s + 1] - row_ptr[s];
            stack_len = stack_len.max(top + r * r);
            update_at[s] = start;
            top = start + r * r;
        }

        // the lower triangle of P Z P^T by column, for the fronts
        let (a_col_ptr, a_row_idx, a_src) = permuted_lower(pattern, &perm, &perm_inv);
        Ok(SupernodalLdlt {
            n,
            perm,
            perm_inv,
            orig_col_ptr: pattern.col_ptr().to_vec(),
            a_col_ptr,
            a_row_idx,
            a_src,
            begin,
            row_ptr,
            rows,
            val_ptr,
            super_of,
            child_ptr,
            children,
            update_at,
            stack_len,
            max_rows,
            max_cols,
            max_rows_cols,
            nnz_exact,
            madds_exact,
        })
    }
}

/// A postorder of the forest `parent` (`-1` for a root): `post[new] = old`,
/// children visited in ascending order.
fn postorder(parent: &[isize]) -> Vec<usize> {
    let n = parent.len();
    let mut head = vec![NONE; n];
    let mut next = vec![NONE; n];
    // built from the last node down, so that each list is ascending
    for j in (0..n).rev() {
        if let Ok(p) = usize::try_from(parent[j]) {
            next[j] = head[p];
            head[p] = j;
        }
    }
    let mut post = Vec::with_capacity(n);
    let mut path = Vec::new();
    for root in (0..n).filter(|&j| parent[j] < 0) {
        path.push(root);
        while let Some(&top) = path.last() {
            let child = head[top];
            if child == NONE {
                post.push(top);
                path.pop();
            } else {
                head[top] = next[child];
                path.push(child);
            }
        }
    }
    post
}

/// Lower triangle of `P A P^T` by column, for a symmetric pattern `A` with
/// both triangles stored: column pointers, rows (`>= j`) and the position of
/// each entry in `A`'s values.
fn permuted_lower(pattern: &Pattern, perm: &[usize], perm_inv: &[usize]) -> (Vec<usize>, Vec<u32>, Vec<usize>) {
    let n = pattern.n();
    let mut col_ptr = vec![0usize; n + 1];
    for j in 0..n {
        let c = perm[j];
        col_ptr[j + 1] = col_ptr[j] + pattern.rows(c).iter().filter(|&&r| perm_inv[r] >= j).count();
    }
    let mut rows = Vec::with_capacity(col_ptr[n]);
    let mut src = Vec::with_capacity(col_ptr[n]);
    for j in 0..n {
        let c = perm[j];
        for p in pattern.col_ptr()[c]..pattern.col_ptr()[c + 1] {
            let i = perm_inv[pattern.row_idx()[p]];
            if i >= j {
                rows.push(i as u32);
                src.push(p);
            }
        }
    }
    (col_ptr, rows, src)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn postorder_visits_children_before_parents_and_subtrees_together() {
        //      6
        //    /   \
        //   2     5
        //  / \    |
        // 4   0   1     3 (a root of its own)
        let parent = [2, 5, 6, -1, 2, 6, -1];
        let post = postorder(&parent);
        assert_eq!(post, vec![3, 0, 4, 2, 1, 5, 6]);
    }
}
