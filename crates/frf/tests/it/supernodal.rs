//! The supernodal layout of the `L D L^T` factorisation against the
//! simplicial one and against a dense LU with partial pivoting (faer's,
//! independent of the sparse code): solutions, unit solves, the selected
//! inverse and the fallback to LU.

use damping::DampedSystem;
use faer::Mat;
use faer::linalg::solvers::Solve;
use fe_model::{Dof, Group, Model, Pattern, Quantity, Section, samples};
use frf::{C64, Channel, FactorKind, FrfError, Layout, SelectedInverse, ZSolver, synthesize};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::solver::symmetric_with_diagonal;

/// `Z` as a dense matrix.
fn dense(pattern: &Pattern, values: &[C64]) -> Mat<C64> {
    let n = pattern.n();
    let mut z = Mat::<C64>::zeros(n, n);
    for c in 0..n {
        for p in pattern.col_ptr()[c]..pattern.col_ptr()[c + 1] {
            z[(pattern.row_idx()[p], c)] = values[p];
        }
    }
    z
}

/// Norm-wise relative difference of two blocks.
fn rel_diff(a: &Mat<C64>, b: &Mat<C64>) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            num += (a[(i, j)] - b[(i, j)]).norm_sqr();
            den += b[(i, j)].norm_sqr();
        }
    }
    (num / den).sqrt()
}

/// Backward error of each column of `x`: `|Z x - b| / (|Z| |x| + |b|)` in
/// the max norm, the largest over the columns. A backward-stable solver
/// gives a small multiple of the unit round-off, however ill conditioned
/// `Z` is.
fn backward_error(z: &Mat<C64>, x: &Mat<C64>, b: &Mat<C64>) -> f64 {
    let z_max = (0..z.ncols())
        .flat_map(|j| (0..z.nrows()).map(move |i| (i, j)))
        .fold(0.0, |m: f64, (i, j)| m.max(z[(i, j)].norm()));
    let r = z * x - b;
    (0..x.ncols())
        .map(|j| {
            let col_max = |m: &Mat<C64>| (0..m.nrows()).fold(0.0, |a: f64, i| a.max(m[(i, j)].norm()));
            col_max(&r) / (z_max * col_max(x) * z.nrows() as f64 + col_max(b))
        })
        .fold(0.0, f64::max)
}

/// Solves with `L D L^T` in the given layout, asserting that it was used.
fn solve_with(pattern: &Pattern, values: &[C64], rhs: &Mat<C64>, layout: Layout) -> Mat<C64> {
    let solver = ZSolver::with_layout(pattern, &[], layout).unwrap();
    assert_eq!(solver.layout(), layout);
    let mut ws = solver.workspace();
    solver.factorize(&mut ws, values, 1.0).unwrap();
    assert_eq!(ws.factor_kind(), Some(FactorKind::Ldlt), "{layout:?}");
    let mut x = rhs.clone();
    solver.solve_in_place(&mut ws, x.as_mut(), 1.0).unwrap();
    x
}

fn random_rhs(n: usize, k: usize, rng: &mut ChaCha8Rng) -> Mat<C64> {
    Mat::from_fn(n, k, |_, _| C64::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)))
}

/// Both layouts and a dense LU on one matrix: each backward stable, and the
/// two layouts within `tol` of the dense solution (norm-wise).
fn check_layouts(name: &str, pattern: &Pattern, values: &[C64], rng: &mut ChaCha8Rng, tol: f64) {
    let rhs = random_rhs(pattern.n(), 3, rng);
    let z = dense(pattern, values);
    let lu = z.partial_piv_lu().solve(&rhs);
    let simplicial = solve_with(pattern, values, &rhs, Layout::Simplicial);
    let supernodal = solve_with(pattern, values, &rhs, Layout::Supernodal);
    for (what, x) in [("dense LU", &lu), ("simplicial", &simplicial), ("supernodal", &supernodal)] {
        let e = backward_error(&z, x, &rhs);
        assert!(e < 1e-16, "{name}: {what} has backward error {e:e}");
    }
    for (what, x) in [("simplicial", &simplicial), ("supernodal", &supernodal)] {
        let e = rel_diff(x, &lu);
        assert!(e < tol, "{name}: {what} differs from the dense LU by {e:e}");
    }
}

/// Frames and beams: the analysis picks the simplicial layout (short
/// columns), and the supernodal one, forced, gives the same solutions.
#[test]
fn supernodal_equals_simplicial_and_dense_lu_on_frames() {
    let models: Vec<(&str, Model)> = vec![
        ("frame with joint", samples::frame_with_joint()),
        ("long beam", samples::long_beam(60)),
        ("frame grid", samples::frame_grid(3, 4, 3)),
        ("portal in space", samples::space_portal()),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for (name, model) in models {
        let sys = DampedSystem::new(model).unwrap();
        let pattern = sys.assembly().pattern();
        assert_eq!(ZSolver::new(pattern).unwrap().layout(), Layout::Simplicial, "{name}");
        for f in [0.5, 13.0, 170.0, 2400.0] {
            let z = sys.z_values(2.0 * std::f64::consts::PI * f);
            check_layouts(&format!("{name} at {f} Hz"), pattern, &z, &mut rng, 1e-10);
        }
    }
}

/// An imported shell's pattern: the analysis picks the supernodal layout,
/// whose solutions are the simplicial layout's and the dense LU's. The
/// postorder does not change the fill: both layouts count the same entries
/// and multiply-adds, and the supernodal one stores at least those.
#[test]
fn supernodal_equals_simplicial_and_dense_lu_on_an_imported_shell() {
    let sys = DampedSystem::new(samples::imported_plate(9, 3)).unwrap();
    let pattern = sys.assembly().pattern();
    let auto = ZSolver::new(pattern).unwrap();
    assert_eq!(auto.layout(), Layout::Supernodal);
    let simplicial = ZSolver::with_layout(pattern, &[], Layout::Simplicial).unwrap();
    assert_eq!(auto.factor_nnz(), simplicial.factor_nnz());
    assert_eq!(auto.factor_multiply_adds(), simplicial.factor_multiply_adds());
    assert!(auto.factor_stored() >= auto.factor_nnz());
    assert_eq!(simplicial.factor_stored(), simplicial.factor_nnz());
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for f in [3.0, 61.0, 390.0] {
        let z = sys.z_values(2.0 * std::f64::consts::PI * f);
        check_layouts(&format!("plate at {f} Hz"), pattern, &z, &mut rng, 1e-10);
    }
}

/// A frame whose joints are near-rigid springs (1e12) beside soft ones
/// (1e3) and light members: entries of `Z` span about fifteen orders of
/// magnitude. Every solution is backward stable, and the layouts agree with
/// the dense LU to what the conditioning allows.
#[test]
fn supernodal_equals_simplicial_and_dense_lu_on_a_badly_scaled_joint_model() {
    let mut m = Model::new("frame with stiff and soft joints");
    let frame = m.add_group(Group::new("frame").rayleigh(2e-5, 0.3)).unwrap();
    let joints = m.add_group(Group::new("joints").rayleigh(1e-4, 0.0).relaxation(200.0)).unwrap();
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let sec = m.add_section(Section::rectangle("square", 0.02, 0.02)).unwrap();
    // three members of six elements: a column, a beam and a hanger, each
    // its own chain of nodes, joined end to end by springs in all DOFs
    let per = 6;
    let ends = [([0.0, 0.0], [0.0, 1.0]), ([0.0, 1.0], [1.0, 1.0]), ([1.0, 1.0], [1.0, 0.3])];
    let mut node = 0u32;
    let mut beam = 0u32;
    let mut firsts = Vec::new();
    for (a, b) in ends {
        firsts.push(node + 1);
        for i in 0..=per {
            let t = i as f64 / per as f64;
            node += 1;
            m.add_node(node, a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])).unwrap();
            if i > 0 {
                beam += 1;
                m.add_beam(beam, [node - 1, node], steel, sec, frame).unwrap();
            }
        }
    }
    let last = |member: usize| firsts[member] + per as u32;
    m.add_spring("stiff joint", last(0), Some(firsts[1]), [1e12, 1e12, 1e12], joints).unwrap();
    m.add_spring("soft joint", last(1), Some(firsts[2]), [1e3, 1e3, 1e3], joints).unwrap();
    m.add_spring("soft ground", last(2), None, [1e3, 1e3, 0.0], joints).unwrap();
    m.add_support(1, &Dof::PLANAR).unwrap();
    let sys = DampedSystem::new(m).unwrap();
    let pattern = sys.assembly().pattern();
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    for f in [0.2, 9.0, 140.0, 1800.0] {
        let z = sys.z_values(2.0 * std::f64::consts::PI * f);
        let (lo, hi) = z
            .iter()
            .filter(|v| v.norm() > 0.0)
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| (lo.min(v.norm()), hi.max(v.norm())));
        assert!(hi / lo > 1e12, "at {f} Hz the entries span only {:e}", hi / lo);
        check_layouts(&format!("joint model at {f} Hz"), pattern, &z, &mut rng, 1e-6);
    }
}

/// Random complex-symmetric matrices that are not diagonally dominant, on
/// random patterns, some dense enough for wide supernodes.
#[test]
fn supernodal_equals_dense_lu_on_random_complex_symmetric_matrices() {
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    for (trial, (n, per_col)) in [(30, 2), (80, 3), (150, 6), (60, 25)].into_iter().enumerate() {
        let (pattern, values) = symmetric_with_diagonal(n, per_col, &mut rng, |off, rng| {
            C64::from_polar(off.max(1.0) * rng.random_range(0.6..1.6), rng.random_range(0.0..std::f64::consts::TAU))
        });
        check_layouts(&format!("trial {trial}"), &pattern, &values, &mut rng, 1e-9);
    }
}

/// Unit solves in the internal order, with the rows handed to `visit` as
/// they become final: the same columns of `Z^-1` in both layouts, every
/// row visited once, from the last to the first, with its final values.
#[test]
fn supernodal_unit_solves_visit_final_rows_in_order() {
    let sys = DampedSystem::new(samples::imported_plate(6, 2)).unwrap();
    let pattern = sys.assembly().pattern();
    let z = sys.z_values(2.0 * std::f64::consts::PI * 45.0);
    let n = sys.n();
    let eqs = [n - 1, 0, n / 2, 7];
    let k = eqs.len();
    let mut columns = Vec::new();
    for layout in [Layout::Simplicial, Layout::Supernodal] {
        let solver = ZSolver::with_layout(pattern, &[], layout).unwrap();
        let mut ws = solver.workspace();
        solver.factorize(&mut ws, &z, 45.0).unwrap();
        let mut x = vec![C64::new(f64::NAN, 0.0); n * k];
        let mut seen = Vec::new();
        let mut visited = vec![C64::new(0.0, 0.0); n * k];
        solver
            .solve_units_ordered_with(&mut ws, &eqs, &mut x, 45.0, |r, rows| {
                seen.push(r);
                visited[r * k..(r + 1) * k].copy_from_slice(&rows[..k]);
            })
            .unwrap();
        assert_eq!(seen, (0..n).rev().collect::<Vec<_>>(), "{layout:?}");
        assert_eq!(visited, x, "{layout:?}: the rows visited are final");
        columns.push(Mat::from_fn(n, k, |i, j| x[solver.position(i) * k + j]));
    }
    let mut unit = Mat::<C64>::zeros(n, k);
    for (j, &e) in eqs.iter().enumerate() {
        unit[(e, j)] = C64::new(1.0, 0.0);
    }
    let want = dense(pattern, &z).partial_piv_lu().solve(&unit);
    for (layout, got) in ["simplicial", "supernodal"].iter().zip(&columns) {
        let e = rel_diff(got, &want);
        assert!(e < 1e-10, "{layout}: unit solves differ from the dense inverse by {e:e}");
    }
}

/// The selected inverse on supernodes against a dense inverse: every entry
/// stored (the diagonal and both triangles of the stored factor, explicit
/// zeros of merged supernodes included), and every clique's block.
#[test]
fn supernodal_selected_inverse_equals_the_dense_inverse() {
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    let sys = DampedSystem::new(samples::imported_plate(5, 2)).unwrap();
    let plate = (sys.assembly().pattern().clone(), sys.z_values(2.0 * std::f64::consts::PI * 120.0));
    let mut cases = vec![("plate".to_string(), plate.0, plate.1)];
    for (trial, (n, per_col)) in [(40, 2), (90, 4), (70, 20)].into_iter().enumerate() {
        let (pattern, values) = symmetric_with_diagonal(n, per_col, &mut rng, |off, rng| {
            C64::from_polar(1.5 * off + 1.0, rng.random_range(0.0..std::f64::consts::TAU))
        });
        cases.push((format!("trial {trial}"), pattern, values));
    }
    for (name, pattern, values) in cases {
        let n = pattern.n();
        let cliques: Vec<Vec<usize>> = (0..5)
            .map(|c| {
                let mut eqs: Vec<usize> = (0..4).map(|i| (c * 37 + i * 101) % n).collect();
                eqs.sort_unstable();
                eqs.dedup();
                eqs
            })
            .collect();
        let solver = ZSolver::with_layout(&pattern, &cliques, Layout::Supernodal).unwrap();
        let mut ws = solver.workspace();
        solver.factorize(&mut ws, &values, 1.0).unwrap();
        assert_eq!(ws.factor_kind(), Some(FactorKind::Ldlt));
        let mut inv = SelectedInverse::new();
        solver.selected_inverse(&ws, &mut inv).unwrap();
        let want = {
            let mut h = Mat::<C64>::identity(n, n);
            h = dense(&pattern, &values).partial_piv_lu().solve(&h);
            h
        };
        let scale =
            (0..n).flat_map(|j| (0..n).map(move |i| (i, j))).fold(0.0, |m: f64, (i, j)| m.max(want[(i, j)].norm()));
        let mut found = 0;
        for i in 0..n {
            for j in 0..n {
                let Some(got) = solver.inverse_entry(&inv, i, j) else { continue };
                found += 1;
                let e = (got - want[(i, j)]).norm() / scale;
                assert!(e < 1e-12, "{name}: Z^-1[{i}, {j}] = {got} against {} ({e:e})", want[(i, j)]);
            }
        }
        assert_eq!(found, n + 2 * solver.factor_stored(), "{name}: the diagonal and both triangles of L as stored");
        for clique in &cliques {
            let m = clique.len();
            let mut block = vec![C64::new(0.0, 0.0); m * m];
            assert!(solver.inverse_block(&inv, clique, &mut block), "{name}: clique {clique:?}");
            for a in 0..m {
                for b in 0..m {
                    assert_eq!(block[a * m + b], solver.inverse_entry(&inv, clique[a], clique[b]).unwrap());
                }
            }
        }
    }
}

/// A pivot that vanishes sends the supernodal factorisation to LU, which
/// still solves; on an undamped model's resonance, LU refuses the line as
/// singular, as the simplicial path does.
#[test]
fn supernodal_falls_back_to_lu_on_a_zero_pivot_and_refuses_a_resonance() {
    // 2 x 2 blocks [[0, a], [a, 0]] coupled to their neighbours: every
    // leading pivot is zero whatever the ordering
    let blocks = 8;
    let n = 2 * blocks;
    let (mut col_ptr, mut row_idx, mut vals) = (vec![0], Vec::new(), Vec::new());
    for c in 0..n {
        let base = c - c % 2;
        for r in base..base + 2 {
            row_idx.push(r);
            vals.push(if r == c { C64::new(0.0, 0.0) } else { C64::new(1.0 + base as f64, 0.5) });
        }
        col_ptr.push(row_idx.len());
    }
    let pattern = Pattern::new(n, col_ptr, row_idx).unwrap();
    let solver = ZSolver::with_layout(&pattern, &[], Layout::Supernodal).unwrap();
    let mut ws = solver.workspace();
    solver.factorize(&mut ws, &vals, 3.0).unwrap();
    assert_eq!(ws.factor_kind(), Some(FactorKind::Lu));
    let b = Mat::from_fn(n, 1, |i, _| C64::new(i as f64 + 1.0, -1.0));
    let mut x = b.clone();
    solver.solve_in_place(&mut ws, x.as_mut(), 3.0).unwrap();
    assert!(backward_error(&dense(&pattern, &vals), &x, &b) < 1e-16);
    let mut inv = SelectedInverse::new();
    assert_eq!(solver.selected_inverse(&ws, &mut inv), Err(FrfError::NoLdltFactors { held: Some(FactorKind::Lu) }));

    // an undamped plate at its computed natural frequencies
    let mut model = samples::imported_plate(4, 1);
    model.set(Quantity::GroupAlpha(0), 0.0).unwrap();
    model.set(Quantity::GroupBeta(0), 0.0).unwrap();
    let sys = DampedSystem::new(model).unwrap();
    let modes = damping::normal_modes(sys.assembly()).unwrap();
    let solver = ZSolver::with_layout(sys.assembly().pattern(), &[], Layout::Supernodal).unwrap();
    let mut ws = solver.workspace();
    let dof = sys.assembly().dofs().dof_of(sys.n() - 1);
    for &f in modes.frequencies_hz.iter().take(3) {
        let z = sys.z_values(2.0 * std::f64::consts::PI * f);
        let result = solver.factorize(&mut ws, &z, f).and_then(|()| {
            let mut x = Mat::from_fn(sys.n(), 1, |i, _| C64::new((i == sys.n() - 1) as u8 as f64, 0.0));
            solver.solve_in_place(&mut ws, x.as_mut(), f)
        });
        assert_eq!(result, Err(FrfError::Singular { freq_hz: f }), "at {f} Hz");
        assert_ne!(ws.factor_kind(), Some(FactorKind::Ldlt), "at {f} Hz the pivot test must send the line to LU");
        // and through the public synthesis, which picks the layout itself
        assert_eq!(synthesize(&sys, &[Channel::new(dof, dof)], &[f]).unwrap_err(), FrfError::Singular { freq_hz: f });
        solver.factorize(&mut ws, &sys.z_values(2.0 * std::f64::consts::PI * 1.01 * f), 1.01 * f).unwrap();
        assert_eq!(ws.factor_kind(), Some(FactorKind::Ldlt), "1 % beside {f} Hz");
    }
}
