//! Solvers analysed with cliques of equations.

use damping::DampedSystem;
use fe_model::{Assembly, BlockSource, Pattern, samples};
use frf::{C64, FrfError, ZSolver};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A random complex-symmetric matrix on a random symmetric pattern, strictly
/// diagonally dominant (so `L D L^T` needs no pivoting and the inverse is
/// well conditioned): random off-diagonal entries, and a diagonal of random
/// phase whose modulus is 1.5 times its row's off-diagonal sum, plus one.
fn dominant_symmetric(n: usize, per_col: usize, rng: &mut ChaCha8Rng) -> (Pattern, Vec<C64>) {
    let mut cols: Vec<Vec<(usize, C64)>> = vec![Vec::new(); n];
    for c in 0..n {
        for _ in 0..per_col {
            let r = rng.random_range(0..n);
            if r != c {
                let v = C64::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
                cols[c].push((r, v));
                cols[r].push((c, v));
            }
        }
    }
    let mut col_ptr = vec![0];
    let mut row_idx = Vec::new();
    let mut vals = Vec::new();
    for (c, col) in cols.iter_mut().enumerate() {
        // a pair drawn twice is merged; both columns see the same two values,
        // so the sum stays symmetric
        col.sort_by_key(|&(r, _)| r);
        col.dedup_by(|a, b| {
            if a.0 == b.0 {
                b.1 += a.1;
                true
            } else {
                false
            }
        });
        let off: f64 = col.iter().map(|&(_, v)| v.norm()).sum();
        col.push((c, C64::from_polar(1.5 * off + 1.0, rng.random_range(0.0..std::f64::consts::TAU))));
        col.sort_by_key(|&(r, _)| r);
        for &(r, v) in col.iter() {
            row_idx.push(r);
            vals.push(v);
        }
        col_ptr.push(row_idx.len());
    }
    (Pattern { n, col_ptr, row_idx }, vals)
}

/// Cliques of runs of `run` elements consecutive by id: the equations of
/// beam `i` to beam `i + run - 1`, for every `i`.
fn element_run_cliques(asm: &Assembly, run: usize) -> Vec<Vec<usize>> {
    let beams: Vec<&[usize]> =
        asm.blocks.iter().filter(|b| matches!(b.source, BlockSource::Beam(_))).map(|b| b.eqs.as_slice()).collect();
    beams
        .windows(run)
        .map(|w| {
            let mut eqs: Vec<usize> = w.iter().flat_map(|e| e.iter().copied()).collect();
            eqs.sort_unstable();
            eqs.dedup();
            eqs
        })
        .collect()
}

/// No cliques is [`ZSolver::new`]; cliques the pattern already holds (the
/// equations of one element) change nothing; runs of elements add fill.
#[test]
fn cliques_change_the_factor_only_where_the_pattern_lacks_them() {
    let sys = DampedSystem::new(samples::frame_grid(3, 4, 4)).unwrap();
    let pattern = &sys.assembly().pattern;
    let plain = ZSolver::new(pattern).unwrap();
    let same = ZSolver::with_cliques(pattern, &[]).unwrap();
    let elements = ZSolver::with_cliques(pattern, &element_run_cliques(sys.assembly(), 1)).unwrap();
    for other in [&same, &elements] {
        assert_eq!(other.factor_nnz(), plain.factor_nnz());
        assert!((0..sys.n()).all(|eq| other.position(eq) == plain.position(eq)));
    }
    let runs = ZSolver::with_cliques(pattern, &element_run_cliques(sys.assembly(), 4)).unwrap();
    assert!(runs.factor_nnz() > plain.factor_nnz());
}

#[test]
fn a_clique_naming_an_unknown_equation_is_refused() {
    let (pattern, _) = dominant_symmetric(10, 2, &mut ChaCha8Rng::seed_from_u64(4));
    let cliques = vec![vec![0, 1], vec![3, 10, 2]];
    assert_eq!(
        ZSolver::with_cliques(&pattern, &cliques).unwrap_err(),
        FrfError::CliqueOutOfRange { clique: 1, eq: 10, n: 10 }
    );
}
