//! Selected inversion (the Takahashi equations) against a dense inverse and
//! against unit solves.

use damping::DampedSystem;
use faer::Mat;
use faer::linalg::solvers::Solve;
use fe_model::{Assembly, BlockSource, Pattern, samples};
use frf::{C64, FactorKind, FrfError, Layout, SelectedInverse, ZSolver};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::solver::symmetric_with_diagonal;

/// A random complex-symmetric matrix on a random symmetric pattern, strictly
/// diagonally dominant (so `L D L^T` needs no pivoting and the inverse is
/// well conditioned): random off-diagonal entries, and a diagonal of random
/// phase whose modulus is 1.5 times its row's off-diagonal sum, plus one.
fn dominant_symmetric(n: usize, per_col: usize, rng: &mut ChaCha8Rng) -> (Pattern, Vec<C64>) {
    symmetric_with_diagonal(n, per_col, rng, |off, rng| {
        C64::from_polar(1.5 * off + 1.0, rng.random_range(0.0..std::f64::consts::TAU))
    })
}

/// `Z^-1` by faer's dense LU with partial pivoting, solving against the
/// identity: independent of the sparse code under test.
fn dense_inverse(pattern: &Pattern, values: &[C64]) -> Mat<C64> {
    let n = pattern.n();
    let mut z = Mat::<C64>::zeros(n, n);
    for c in 0..n {
        for p in pattern.col_ptr()[c]..pattern.col_ptr()[c + 1] {
            z[(pattern.row_idx()[p], c)] = values[p];
        }
    }
    let mut h = Mat::<C64>::identity(n, n);
    z.partial_piv_lu().solve_in_place(h.as_mut());
    h
}

/// Random cliques of 1 to 6 distinct equations.
fn random_cliques(n: usize, count: usize, rng: &mut ChaCha8Rng) -> Vec<Vec<usize>> {
    (0..count)
        .map(|_| {
            let size = rng.random_range(1..=6.min(n));
            let mut clique: Vec<usize> = Vec::with_capacity(size);
            while clique.len() < size {
                let eq = rng.random_range(0..n);
                if !clique.contains(&eq) {
                    clique.push(eq);
                }
            }
            clique
        })
        .collect()
}

/// Cliques of runs of `run` elements consecutive by id: the equations of
/// beam `i` to beam `i + run - 1`, for every `i`.
fn element_run_cliques(asm: &Assembly, run: usize) -> Vec<Vec<usize>> {
    let beams: Vec<&[usize]> =
        asm.blocks().iter().filter(|b| matches!(b.source(), BlockSource::Beam(_))).map(|b| b.eqs()).collect();
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

#[test]
fn selected_inverse_equals_the_dense_inverse_on_random_sparse_matrices() {
    let mut rng = ChaCha8Rng::seed_from_u64(947);
    let mut worst: f64 = 0.0;
    for trial in 0..24 {
        let n = [1, 2, 7, 30, 80, 160][trial % 6];
        let per_col = rng.random_range(1..4);
        let (pattern, values) = dominant_symmetric(n, per_col, &mut rng);
        let cliques = if trial % 2 == 0 { Vec::new() } else { random_cliques(n, n / 4 + 1, &mut rng) };
        let solver = ZSolver::with_cliques(&pattern, &cliques).unwrap();
        let mut ws = solver.workspace();
        solver.factorize(&mut ws, &values, 10.0).unwrap();
        assert_eq!(ws.factor_kind(), Some(FactorKind::Ldlt));
        let mut inv = SelectedInverse::new();
        solver.selected_inverse(&ws, &mut inv).unwrap();
        let h = dense_inverse(&pattern, &values);

        // every entry in the pattern, in both triangles, against the dense one
        let mut found = 0;
        for i in 0..n {
            for j in 0..n {
                let Some(got) = solver.inverse_entry(&inv, i, j) else { continue };
                found += 1;
                // a pair joining two disconnected parts of the matrix (a
                // clique can make one) is exactly zero, and so is its entry
                let exact = h[(i, j)];
                let diff = (got - exact).norm();
                if exact != C64::new(0.0, 0.0) {
                    worst = worst.max(diff / exact.norm());
                }
                assert!(
                    diff <= 1e-10 * exact.norm(),
                    "trial {trial} (n = {n}), entry ({i}, {j}): {got} against {exact}"
                );
            }
        }
        // as stored: the supernodal layout, which the denser trials get,
        // holds explicit zeros of merged supernodes too
        assert_eq!(found, n + 2 * solver.factor_stored(), "trial {trial}: the diagonal and both triangles of L");

        // every clique pair is there, and a whole block reads the same
        for clique in &cliques {
            let m = clique.len();
            let mut block = vec![C64::new(0.0, 0.0); m * m];
            assert!(solver.inverse_block(&inv, clique, &mut block), "trial {trial}: clique {clique:?}");
            for a in 0..m {
                for b in 0..m {
                    let exact = h[(clique[a], clique[b])];
                    assert!((block[a * m + b] - exact).norm() <= 1e-10 * exact.norm(), "trial {trial}");
                }
            }
        }
    }
    assert!(worst > 0.0 && worst < 1e-10, "worst relative difference {worst:e}");
}

/// A frame's `Z(w)` is neither diagonally dominant nor definite; entries of
/// the selected inverse must match columns of `Z^-1` from unit solves, on
/// the factor's pattern and on every clique of consecutive elements.
#[test]
fn selected_inverse_of_a_frame_equals_unit_solves() {
    let sys = DampedSystem::new(samples::frame_grid(2, 3, 3)).unwrap();
    let n = sys.n();
    let cliques = element_run_cliques(sys.assembly(), 4);
    for (name, cliques) in [("no cliques", Vec::new()), ("runs of 4 elements", cliques)] {
        let solver = ZSolver::with_cliques(sys.assembly().pattern(), &cliques).unwrap();
        let mut ws = solver.workspace();
        let mut inv = SelectedInverse::new();
        let all: Vec<usize> = (0..n).collect();
        let mut x = Vec::new();
        for f in [3.0, 170.0, 900.0] {
            let z = sys.z_values(2.0 * std::f64::consts::PI * f);
            solver.factorize(&mut ws, &z, f).unwrap();
            assert_eq!(ws.factor_kind(), Some(FactorKind::Ldlt), "{name} at {f} Hz");
            solver.selected_inverse(&ws, &mut inv).unwrap();
            solver.solve_units_ordered(&mut ws, &all, &mut x, f).unwrap();
            // x[position(i) * n + j] = Z^-1[i, j]; entries are compared
            // against the largest of their column, as the solves are accurate
            // norm-wise, not entry by entry
            let col_max: Vec<f64> =
                (0..n).map(|j| (0..n).fold(0.0, |m: f64, i| m.max(x[solver.position(i) * n + j].norm()))).collect();
            let mut found = 0;
            for i in 0..n {
                for j in 0..n {
                    let Some(got) = solver.inverse_entry(&inv, i, j) else { continue };
                    found += 1;
                    let solved = x[solver.position(i) * n + j];
                    let err = (got - solved).norm() / col_max[j];
                    assert!(err < 1e-10, "{name} at {f} Hz, entry ({i}, {j}): {got} against {solved}");
                }
            }
            assert_eq!(found, n + 2 * solver.factor_stored());
            for clique in &cliques {
                for &i in clique {
                    for &j in clique {
                        assert!(solver.inverse_entry(&inv, i, j).is_some(), "{name}: pair ({i}, {j})");
                    }
                }
            }
        }
    }
}

/// Solves and selected inversions restricted to the reach of a few places
/// of a frame (the measured equations and a few runs of elements, as the
/// diagnosis gathers them around its leaders) give the rows and entries
/// read there bit for bit as the whole ones, while skipping most of the
/// simplicial factor; in the supernodal layout, which has no such
/// restriction, they are the whole ones.
#[test]
fn solves_and_inversions_within_a_reach_equal_the_whole_ones() {
    let sys = DampedSystem::new(samples::frame_grid(6, 6, 4)).unwrap();
    let n = sys.n();
    let runs = element_run_cliques(sys.assembly(), 3);
    // three places along the members, and four measured equations elsewhere
    let cliques: Vec<Vec<usize>> = [5, 6, runs.len() / 2].iter().map(|&i| runs[i].clone()).collect();
    let measured = [n / 7, n / 3, n / 2 + 1, n - 4];
    let read: Vec<usize> = measured.iter().copied().chain(cliques.iter().flatten().copied()).collect();
    for layout in [Layout::Simplicial, Layout::Supernodal] {
        let solver = ZSolver::with_layout(sys.assembly().pattern(), &cliques, layout).unwrap();
        let solved = solver.reach(read.iter().copied());
        let inverted = solver.reach(cliques.iter().flatten().copied());
        match layout {
            Layout::Simplicial => {
                let (s, i) = (solved.rows().unwrap(), inverted.rows().unwrap());
                assert!(i < s && s < n / 2, "{layout:?}: the reaches hold {i} and {s} of {n} rows");
            }
            Layout::Supernodal => assert_eq!((solved.rows(), inverted.rows()), (None, None)),
        }
        let mut ws = solver.workspace();
        let (mut whole, mut part) = (SelectedInverse::new(), SelectedInverse::new());
        let (mut x_whole, mut x_part) = (Vec::new(), Vec::new());
        for f in [3.0, 170.0, 900.0] {
            let z = sys.z_values(2.0 * std::f64::consts::PI * f);
            solver.factorize(&mut ws, &z, f).unwrap();
            solver.solve_units_ordered(&mut ws, &measured, &mut x_whole, f).unwrap();
            solver.solve_units_within(&mut ws, &measured, &solved, &mut x_part, f).unwrap();
            let k = measured.len();
            for &eq in &read {
                let row = solver.position(eq) * k;
                for j in 0..k {
                    let (a, b) = (x_whole[row + j], x_part[row + j]);
                    assert!(a.re.to_bits() == b.re.to_bits() && a.im.to_bits() == b.im.to_bits(), "row of {eq}");
                }
            }
            solver.selected_inverse(&ws, &mut whole).unwrap();
            solver.selected_inverse_within(&ws, &inverted, &mut part).unwrap();
            for clique in &cliques {
                let m = clique.len();
                let (mut a, mut b) = (vec![C64::new(0.0, 0.0); m * m], vec![C64::new(0.0, 0.0); m * m]);
                assert!(solver.inverse_block(&whole, clique, &mut a) && solver.inverse_block(&part, clique, &mut b));
                assert!(
                    a.iter().zip(&b).all(|(a, b)| a.re.to_bits() == b.re.to_bits() && a.im.to_bits() == b.im.to_bits())
                );
            }
        }
    }
}

/// No cliques is [`ZSolver::new`]; cliques the pattern already holds (the
/// equations of one element) change nothing; runs of elements add fill.
#[test]
fn cliques_change_the_factor_only_where_the_pattern_lacks_them() {
    let sys = DampedSystem::new(samples::frame_grid(3, 4, 4)).unwrap();
    let pattern = sys.assembly().pattern();
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

/// After the LU fallback there are no `L D L^T` factors to invert: the
/// error says so, instead of an inverse of stale factors.
#[test]
fn selected_inverse_is_refused_without_ldlt_factors() {
    let (pattern, values) = dominant_symmetric(40, 2, &mut ChaCha8Rng::seed_from_u64(3));
    let solver = ZSolver::new(&pattern).unwrap();
    let mut ws = solver.workspace();
    let mut inv = SelectedInverse::new();
    assert_eq!(solver.selected_inverse(&ws, &mut inv), Err(FrfError::NoLdltFactors { held: None }));
    solver.factorize(&mut ws, &values, 5.0).unwrap();
    solver.selected_inverse(&ws, &mut inv).unwrap();
    solver.factorize_lu(&mut ws, &values, 5.0).unwrap();
    assert_eq!(solver.selected_inverse(&ws, &mut inv), Err(FrfError::NoLdltFactors { held: Some(FactorKind::Lu) }));

    // [[0, 1], [1, 0]] blocks: every pivot is zero, so factorize falls back
    let zero = C64::new(0.0, 0.0);
    let one = C64::new(1.0, 0.0);
    let pattern = Pattern::new(4, vec![0, 2, 4, 6, 8], vec![0, 1, 0, 1, 2, 3, 2, 3]).unwrap();
    let values = [zero, one, one, zero, zero, one, one, zero];
    let solver = ZSolver::new(&pattern).unwrap();
    let mut ws = solver.workspace();
    solver.factorize(&mut ws, &values, 7.0).unwrap();
    assert_eq!(ws.factor_kind(), Some(FactorKind::Lu));
    assert_eq!(solver.selected_inverse(&ws, &mut inv), Err(FrfError::NoLdltFactors { held: Some(FactorKind::Lu) }));
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
