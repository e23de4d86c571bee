//! The complex-symmetric `L D L^T` solver against faer's pivoting sparse LU.

use damping::DampedSystem;
use faer::Mat;
use fe_model::{Model, Pattern, Quantity, samples};
use frf::{C64, Channel, FactorKind, FrfError, Layout, ZSolver, synthesize};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Norm-wise relative difference of two blocks of solutions.
fn rel_diff(a: &Mat<C64>, b: &Mat<C64>) -> f64 {
    let mut num = 0.0;
    let mut den = 0.0;
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            num += (a[(i, j)] - b[(i, j)]).norm_sqr();
            den += b[(i, j)].norm_sqr();
        }
    }
    (num / den).sqrt()
}

fn random_rhs(n: usize, k: usize, rng: &mut ChaCha8Rng) -> Mat<C64> {
    Mat::from_fn(n, k, |_, _| C64::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)))
}

/// Solves with `L D L^T` (asserting it was used) and with LU; returns both.
fn solve_both(pattern: &Pattern, values: &[C64], rhs: &Mat<C64>) -> (Mat<C64>, Mat<C64>) {
    let solver = ZSolver::new(pattern).unwrap();
    let mut ws = solver.workspace();
    solver.factorize(&mut ws, values, 1.0).unwrap();
    assert_eq!(ws.factor_kind(), Some(FactorKind::Ldlt));
    let mut x = rhs.clone();
    solver.solve_in_place(&mut ws, x.as_mut(), 1.0).unwrap();
    solver.factorize_lu(&mut ws, values, 1.0).unwrap();
    assert_eq!(ws.factor_kind(), Some(FactorKind::Lu));
    let mut y = rhs.clone();
    solver.solve_in_place(&mut ws, y.as_mut(), 1.0).unwrap();
    (x, y)
}

#[test]
fn ldlt_equals_lu_on_the_sample_models() {
    let models: Vec<(&str, Model)> = vec![
        ("cantilever", samples::cantilever(8)),
        ("two-material cantilever", samples::two_material_cantilever()),
        ("frame with joint", samples::frame_with_joint()),
        ("2-dof oscillator", samples::two_dof_oscillator()),
        ("long beam", samples::long_beam(120)),
        ("frame grid", samples::frame_grid(3, 4, 3)),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for (name, model) in models {
        let sys = DampedSystem::new(model).unwrap();
        let pattern = sys.assembly().pattern();
        let rhs = random_rhs(sys.n(), 3, &mut rng);
        for f in [0.5, 13.0, 170.0, 2400.0] {
            let z = sys.z_values(2.0 * std::f64::consts::PI * f);
            let (x, y) = solve_both(pattern, &z, &rhs);
            let e = rel_diff(&x, &y);
            assert!(e < 1e-10, "{name} at {f} Hz: relative difference {e:e}");
        }
    }
}

/// A random complex-symmetric matrix on a random symmetric pattern: random
/// off-diagonal entries, and a diagonal of the size of its row's
/// off-diagonal sum times a random complex factor (not diagonally dominant).
fn random_symmetric(n: usize, per_col: usize, rng: &mut ChaCha8Rng) -> (Pattern, Vec<C64>) {
    symmetric_with_diagonal(n, per_col, rng, |off, rng| {
        let phase = rng.random_range(0.0..std::f64::consts::TAU);
        let factor = rng.random_range(0.6..1.6);
        C64::from_polar(off.max(1.0) * factor, phase)
    })
}

/// A random symmetric pattern with about `per_col` random off-diagonal
/// entries per column (a pair drawn twice is merged on both sides, so the
/// values stay symmetric), and each diagonal entry `diagonal(off, rng)`,
/// `off` being the sum of the moduli of its column's other entries.
pub(crate) fn symmetric_with_diagonal(
    n: usize,
    per_col: usize,
    rng: &mut ChaCha8Rng,
    mut diagonal: impl FnMut(f64, &mut ChaCha8Rng) -> C64,
) -> (Pattern, Vec<C64>) {
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
        col.push((c, diagonal(off, rng)));
        col.sort_by_key(|&(r, _)| r);
        for &(r, v) in col.iter() {
            row_idx.push(r);
            vals.push(v);
        }
        col_ptr.push(row_idx.len());
    }
    (Pattern::new(n, col_ptr, row_idx).unwrap(), vals)
}

#[test]
fn ldlt_equals_lu_on_random_complex_symmetric_sparse_matrices() {
    let mut rng = ChaCha8Rng::seed_from_u64(2023);
    for trial in 0..40 {
        let n = rng.random_range(5..300);
        let per_col = rng.random_range(1..5);
        let (pattern, vals) = random_symmetric(n, per_col, &mut rng);
        // symmetric values, as the LDL^T reads one triangle and LU both
        for c in 0..n {
            for p in pattern.col_ptr()[c]..pattern.col_ptr()[c + 1] {
                let q = pattern.position(c, pattern.row_idx()[p]).unwrap();
                assert_eq!(vals[p], vals[q]);
            }
        }
        let rhs = random_rhs(n, 4, &mut rng);
        let (x, y) = solve_both(&pattern, &vals, &rhs);
        let e = rel_diff(&x, &y);
        assert!(e < 1e-10, "trial {trial} (n = {n}): relative difference {e:e}");
    }
}

/// In both layouts of the factor.
#[test]
fn the_three_right_hand_side_layouts_agree() {
    let sys = DampedSystem::new(samples::frame_grid(2, 3, 2)).unwrap();
    let n = sys.n();
    for layout in [Layout::Simplicial, Layout::Supernodal] {
        let solver = ZSolver::with_layout(sys.assembly().pattern(), &[], layout).unwrap();
        let mut ws = solver.workspace();
        let z = sys.z_values(2.0 * std::f64::consts::PI * 40.0);
        solver.factorize(&mut ws, &z, 40.0).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let k = 5;
        let rhs = random_rhs(n, k, &mut rng);
        let mut cols = rhs.clone();
        solver.solve_in_place(&mut ws, cols.as_mut(), 40.0).unwrap();
        let mut inter: Vec<C64> = (0..n * k).map(|t| rhs[(t / k, t % k)]).collect();
        solver.solve_interleaved(&mut ws, &mut inter, k, 40.0).unwrap();
        let mut ordered = vec![C64::new(0.0, 0.0); n * k];
        for eq in 0..n {
            for j in 0..k {
                ordered[solver.position(eq) * k + j] = rhs[(eq, j)];
            }
        }
        solver.solve_ordered(&mut ws, &mut ordered, k, 40.0).unwrap();
        for eq in 0..n {
            for j in 0..k {
                assert_eq!(inter[eq * k + j], cols[(eq, j)], "{layout:?}");
                assert_eq!(ordered[solver.position(eq) * k + j], cols[(eq, j)], "{layout:?}");
            }
        }
    }
}

/// Nonsingular, but every leading pivot is zero whatever the ordering:
/// 2 x 2 blocks `[[0, a], [a, 0]]` on the diagonal. `factorize` must fall
/// back to LU and still solve exactly, through every layout.
#[test]
fn a_zero_pivot_falls_back_to_lu_and_still_solves() {
    let blocks = 6;
    let n = 2 * blocks;
    let mut col_ptr = vec![0];
    let mut row_idx = Vec::new();
    let mut vals = Vec::new();
    for c in 0..n {
        let base = c - c % 2;
        for r in base..base + 2 {
            row_idx.push(r);
            vals.push(if r == c { C64::new(0.0, 0.0) } else { C64::new(1.0 + base as f64, 0.5) });
        }
        col_ptr.push(row_idx.len());
    }
    let pattern = Pattern::new(n, col_ptr, row_idx).unwrap();
    let solver = ZSolver::new(&pattern).unwrap();
    let mut ws = solver.workspace();
    solver.factorize(&mut ws, &vals, 3.0).unwrap();
    assert_eq!(ws.factor_kind(), Some(FactorKind::Lu));
    let b: Vec<C64> = (0..n).map(|i| C64::new(i as f64 + 1.0, -1.0)).collect();
    let mut x = Mat::from_fn(n, 1, |i, _| b[i]);
    solver.solve_in_place(&mut ws, x.as_mut(), 3.0).unwrap();
    let mut inter = b.clone();
    solver.solve_interleaved(&mut ws, &mut inter, 1, 3.0).unwrap();
    let mut ordered = vec![C64::new(0.0, 0.0); n];
    for eq in 0..n {
        ordered[solver.position(eq)] = b[eq];
    }
    solver.solve_ordered(&mut ws, &mut ordered, 1, 3.0).unwrap();
    for c in 0..n {
        // row c of Z x: the partner of c times x[partner]
        let partner = c ^ 1;
        let a = vals[pattern.position(c, partner).unwrap()];
        for got in [x[(partner, 0)], inter[partner], ordered[solver.position(partner)]] {
            assert!((a * got - b[c]).norm() < 1e-14 * b[c].norm(), "row {c}");
        }
    }
}

/// `[[1, 1], [1, 1]]` (and a copy of it beside a regular block) is exactly
/// singular: the `L D L^T` meets a zero pivot, LU fails too, and the error
/// names the frequency.
#[test]
fn a_singular_matrix_is_reported_with_its_frequency() {
    let one = C64::new(1.0, 0.0);
    let pattern = Pattern::new(3, vec![0, 2, 4, 5], vec![0, 1, 0, 1, 2]).unwrap();
    let vals = [one, one, one, one, C64::new(2.0, 1.0)];
    let solver = ZSolver::new(&pattern).unwrap();
    let mut ws = solver.workspace();
    let result = solver.factorize(&mut ws, &vals, 42.0).and_then(|()| {
        let mut x = Mat::from_fn(3, 1, |i, _| C64::new(i as f64 + 1.0, 0.0));
        solver.solve_in_place(&mut ws, x.as_mut(), 42.0)
    });
    assert_eq!(result, Err(FrfError::Singular { freq_hz: 42.0 }));
}

/// faer's LU factorises a matrix singular to working precision and returns
/// huge finite numbers; an undamped model at each of its computed natural
/// frequencies must be refused with that frequency, and 1 % beside it must not.
#[test]
fn an_undamped_model_on_a_resonance_is_singular_at_that_frequency() {
    for mut model in [samples::two_dof_oscillator(), samples::cantilever(30), samples::frame_with_joint()] {
        for g in 0..model.groups().len() {
            model.set(Quantity::GroupAlpha(g), 0.0).unwrap();
            model.set(Quantity::GroupBeta(g), 0.0).unwrap();
        }
        let sys = DampedSystem::new(model).unwrap();
        let modes = damping::normal_modes(sys.assembly()).unwrap();
        let dof = sys.assembly().dofs().dof_of(sys.n() - 1);
        let channels = [Channel::new(dof, dof)];
        for &f in modes.frequencies_hz.iter().take(3) {
            assert_eq!(synthesize(&sys, &channels, &[f]).unwrap_err(), FrfError::Singular { freq_hz: f });
            let beside = synthesize(&sys, &channels, &[1.01 * f]).unwrap();
            assert!(beside.get(0, 0).norm().is_finite());
        }
    }
}
