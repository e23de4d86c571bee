//! The two layouts of the `L D L^T` factorisation side by side on one
//! thread: what one line costs (a numeric factorisation and a solve for
//! `k` right-hand sides) on the sample models, and which layout the
//! analysis picks.
//!
//! ```text
//! cargo run --release -p frf --example layouts -- plate:128 frame:10x11x15 beam:34483 \
//!     [--rhs 20] [--repeat 3] [--layout simplicial|supernodal|faer]
//! ```
//!
//! `faer` is a reference, not a solver of `Z`: faer's own supernodal
//! `L D L^H` of the same pattern and values read as Hermitian (its lower
//! triangle), in the same ordering family (AMD), with the same arithmetic
//! (complex multiply-adds) as a complex-symmetric factorisation.
//!
//! Prints one line per model and layout: size, the factor's entries and
//! multiply-adds per entry, and the best times (of `--repeat`) of the
//! factorisation and of the solve, in ms: wall time, and the thread's CPU
//! time, which a machine shared with other work disturbs less over long
//! runs (the kernel accounts it by scheduler ticks of a few ms, so it means
//! nothing for short ones; NaN where it cannot be read).

use std::time::Instant;

use damping::DampedSystem;
use fe_model::{Model, samples};
use frf::{C64, Layout, ZSolver};

fn model(spec: &str) -> Option<Model> {
    let (kind, size) = spec.split_once(':')?;
    let dims: Vec<usize> = size.split('x').map(str::parse).collect::<Result<_, _>>().ok()?;
    match (kind, &dims[..]) {
        ("plate", &[n]) => Some(samples::imported_plate(n, 6)),
        ("beam", &[n]) => Some(samples::long_beam(n)),
        ("frame", &[b, s, p]) => Some(samples::frame_grid(b, s, p)),
        _ => None,
    }
}

/// CPU time of this thread so far (s), from /proc/thread-self/schedstat
/// (nanoseconds on the CPU), or NaN.
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .map_or(f64::NAN, |ns| ns as f64 * 1e-9)
}

/// Best wall and CPU times of `f(state)` over `repeat` runs (s);
/// `prepare(state)` runs before each, untimed.
fn best_of<S>(repeat: usize, state: &mut S, mut prepare: impl FnMut(&mut S), mut f: impl FnMut(&mut S)) -> (f64, f64) {
    let (mut wall, mut cpu) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..repeat.max(1) {
        prepare(state);
        let (t, c) = (Instant::now(), cpu_seconds());
        f(state);
        wall = wall.min(t.elapsed().as_secs_f64());
        cpu = cpu.min(cpu_seconds() - c);
    }
    (wall, cpu)
}

/// One line of the table.
fn row(
    spec: &str,
    n: usize,
    entries: &str,
    per_entry: &str,
    layout: &str,
    factor: (f64, f64),
    solve: (f64, f64),
    chosen: bool,
) {
    println!(
        "{spec:<16} {n:>8} {entries:>11} {per_entry:>10} {layout:>11} {:>9.2} {:>9.2} {:>9.2} {:>9.2} {:>7}",
        1e3 * factor.0,
        1e3 * solve.0,
        1e3 * factor.1,
        1e3 * solve.1,
        if chosen { "yes" } else { "" }
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str, default: usize| {
        args.iter().position(|a| a == flag).and_then(|i| args.get(i + 1)).map_or(default, |v| v.parse().unwrap())
    };
    let (k, repeat) = (value("--rhs", 20), value("--repeat", 3));
    let only = args.iter().position(|a| a == "--layout").and_then(|i| args.get(i + 1)).cloned();
    let specs =
        args.iter().enumerate().filter(|&(i, a)| !a.starts_with("--") && (i == 0 || !args[i - 1].starts_with("--")));
    println!(
        "{:<16} {:>8} {:>11} {:>10} {:>11} {:>9} {:>9} {:>9} {:>9} {:>7}",
        "model", "DOFs", "L entries", "madds/ent", "layout", "factor", "solve", "CPU fac", "CPU sol", "chosen"
    );
    for (_, spec) in specs {
        let sys = DampedSystem::new(model(spec).unwrap_or_else(|| panic!("unknown model {spec}"))).unwrap();
        let pattern = sys.assembly().pattern();
        let chosen = ZSolver::new(pattern).unwrap().layout();
        let z = sys.z_values(2.0 * std::f64::consts::PI * 123.0);
        let n = sys.n();
        let rhs: Vec<C64> = (0..n * k).map(|i| C64::new((i % 7) as f64 - 3.0, (i % 5) as f64)).collect();
        if only.as_deref().is_none_or(|o| o == "faer") {
            let (factor, solve) = faer_reference(pattern, &z, &rhs, k, repeat);
            row(spec, n, "", "", "faer LDL^H", factor, solve, false);
        }
        for layout in [Layout::Simplicial, Layout::Supernodal] {
            if only.as_deref().is_some_and(|o| !format!("{layout:?}").eq_ignore_ascii_case(o)) {
                continue;
            }
            let solver = ZSolver::with_layout(pattern, &[], layout).unwrap();
            let mut ws = solver.workspace();
            let factor = best_of(repeat, &mut ws, |_| {}, |ws| solver.factorize(ws, &z, 123.0).unwrap());
            let solve = best_of(
                repeat,
                &mut (&mut ws, rhs.clone()),
                |(_, x)| x.copy_from_slice(&rhs),
                |(ws, x)| solver.solve_ordered(ws, x, k, 123.0).unwrap(),
            );
            let per_entry = solver.factor_multiply_adds() as f64 / solver.factor_nnz() as f64;
            let (entries, layout_name) = (solver.factor_nnz().to_string(), format!("{layout:?}"));
            row(spec, n, &entries, &format!("{per_entry:.1}"), &layout_name, factor, solve, layout == chosen);
        }
    }
}

/// Best CPU times of faer's supernodal `L D L^H` (factorisation, solve of
/// `k` right-hand sides) on `values` read as Hermitian; see the module docs.
fn faer_reference(
    pattern: &fe_model::Pattern,
    values: &[C64],
    rhs: &[C64],
    k: usize,
    repeat: usize,
) -> ((f64, f64), (f64, f64)) {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
    use faer::sparse::linalg::SupernodalThreshold;
    use faer::sparse::linalg::cholesky::{
        CholeskySymbolicParams, LdltRef, SymmetricOrdering, factorize_symbolic_cholesky,
    };
    use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
    use faer::{Conj, Mat, Par, Side};

    let n = pattern.n();
    let structure = SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
    let params = CholeskySymbolicParams {
        supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
        ..Default::default()
    };
    let symbolic = factorize_symbolic_cholesky(structure, Side::Lower, SymmetricOrdering::Amd, params).unwrap();
    let mut l_values = vec![C64::new(0.0, 0.0); symbolic.len_val()];
    let mut mem = MemBuffer::new(
        symbolic
            .factorize_numeric_ldlt_scratch::<C64>(Par::Seq, Default::default())
            .or(symbolic.solve_in_place_scratch::<C64>(k, Par::Seq)),
    );
    let a = SparseColMatRef::new(structure, values);
    let factor = best_of(
        repeat,
        &mut (),
        |_| {},
        |_| {
            symbolic
                .factorize_numeric_ldlt(
                    &mut l_values,
                    a,
                    Side::Lower,
                    LdltRegularization::default(),
                    Par::Seq,
                    MemStack::new(&mut mem),
                    Default::default(),
                )
                .unwrap();
        },
    );
    let b = Mat::from_fn(n, k, |i, j| rhs[i * k + j]);
    let ldlt = LdltRef::new(&symbolic, &l_values);
    let solve = best_of(
        repeat,
        &mut b.clone(),
        |x| x.copy_from(&b),
        |x| ldlt.solve_in_place_with_conj(Conj::No, x.as_mut(), Par::Seq, MemStack::new(&mut mem)),
    );
    (factor, solve)
}
