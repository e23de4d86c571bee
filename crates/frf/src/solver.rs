//! Sparse factorisation of `Z(w)` once per frequency.
//!
//! `Z(w) = K - w^2 M + j w G(w)` is complex symmetric, so [`ZSolver`] factorises
//! it as `P Z P^T = L D L^T` (complex, no conjugation, no pivoting): half the
//! work and memory of an LU, with a structure fixed by the pattern alone.
//!
//! [`ZSolver::new`] does the symbolic analysis once per model pattern: a
//! fill-reducing ordering (faer's approximate minimum degree), the elimination
//! tree and the pattern of `L`. It is shared, read-only, by every frequency,
//! iteration and thread. Each thread owns a [`Workspace`] with the numeric
//! factors and buffers, reused from one frequency to the next: factorising
//! and solving allocate nothing once the workspace has seen the largest
//! number of right-hand sides. faer runs sequentially inside; parallelism is
//! over frequencies (rayon) in the callers.
//!
//! Without pivoting the factorisation is only as stable as its pivots. A
//! pivot that is not finite, or tiny against the entries of its row of `Z` or
//! against the terms subtracted to form it, makes [`ZSolver::factorize`] fall
//! back, for that frequency only, to faer's sparse LU with partial pivoting
//! (its symbolic analysis is made on first need and then kept).
//! [`Workspace::factor_kind`] tells which was used. A matrix that LU cannot
//! factorise, or whose solution is not finite, is reported as
//! [`FrfError::Singular`]. So is an LU solution amplified more than
//! [`SINGULAR_AMPLIFICATION`]: faer's LU factorises a matrix that is singular
//! to working precision (an undamped model evaluated at its computed
//! resonance) without complaint and returns numbers of 1e15 times the
//! right-hand side over `|Z|`, none of whose digits can be trusted.
//!
//! # Selected inversion
//!
//! A caller that needs `H = Z^-1` only on small sets of equations `D` (one
//! element, one node, a few neighbouring elements), `H[D, D]`, would make a
//! unit solve per equation. [`ZSolver::selected_inverse`] instead computes
//! every entry of `H` on the pattern of the factor (`L + L^T` plus the
//! diagonal) from the `L D L^T` factors, by the Takahashi equations
//! (Takahashi, Fagan and Chen, 1973; Erisman and Tinney, 1975), for about
//! the cost of the numeric factorisation. With `B = P Z P^T` and `S` the
//! rows of column `j` of `L` below `j`, from the last column to the first:
//!
//! ```text
//! B^-1[S, j] = -B^-1[S, S] L[S, j]
//! B^-1[j, j] = D^-1[j] - L[S, j]^T B^-1[S, j]
//! ```
//!
//! The pattern of the factor is closed under this recurrence (the filled
//! graph is chordal), but holds a set `D` only if it happens to: build the
//! solver with [`ZSolver::with_cliques`] to add every pair of each set to the
//! pattern analysed, at the price of some fill. Read the result with
//! [`ZSolver::inverse_entry`] or [`ZSolver::inverse_block`]. After the LU
//! fallback there are no such factors: [`ZSolver::selected_inverse`] returns
//! [`FrfError::NoLdltFactors`], and the caller solves for unit right-hand
//! sides ([`ZSolver::solve_units_ordered`]) at that frequency.
//!
//! # Right-hand side layouts
//!
//! - [`ZSolver::solve_in_place`]: a column-major faer matrix, one column per
//!   right-hand side (convenient).
//! - [`ZSolver::solve_interleaved`]: a slice with the `k` right-hand sides
//!   interleaved by row, `x[i * k + j]` for equation `i`, right-hand side `j`.
//!   Each elimination step then updates `k` contiguous values.
//! - [`ZSolver::solve_ordered`]: the same, with rows in the solver's internal
//!   order ([`ZSolver::position`]), which saves two permuting copies of the
//!   whole block; for callers that build right-hand sides and read solutions
//!   at a few rows per equation, such as the sensitivity assembly.

use std::sync::OnceLock;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::lu::{LuRef, NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, Mat, MatMut, MatRef, Par};
use fe_model::Pattern;
use num_complex::Complex64 as C64;

use crate::error::FrfError;
pub use crate::factor_kind::{FactorKind, Layout};
pub use crate::ldlt::mul_add;
use crate::ldlt::{Analysis, Factors, InverseScratch};

const ZERO: C64 = C64 { re: 0.0, im: 0.0 };

/// Largest `max|Z_ij| max|x| / max|b|` accepted from the LU fallback: a
/// lower bound on the condition number of `Z` at which the relative error of
/// the solution may reach 1 %. An undamped model on a resonance gives 1e15 to
/// 1e19 (measured on the sample models), 1 % beside one 1e2 to 1e8, and a
/// slender 100,000-element beam's static tip compliance about 1e11.
pub const SINGULAR_AMPLIFICATION: f64 = 1e-2 / f64::EPSILON;

/// Symbolic factorisation of a model's `Z` pattern; see the module docs.
#[derive(Clone, Debug)]
pub struct ZSolver {
    pattern: SymbolicSparseColMat<usize>,
    ldlt: Analysis,
    /// Symbolic LU for the fallback, made on first need.
    lu: OnceLock<Result<SymbolicLu<usize>, String>>,
}

/// Per-thread numeric factors and scratch memory.
pub struct Workspace {
    ldlt: Factors,
    /// Row-interleaved right-hand sides in the internal order.
    buf: Vec<C64>,
    /// Internal rows of unit right-hand sides.
    buf_rows: Vec<usize>,
    lu: Option<LuWorkspace>,
    kind: Option<FactorKind>,
    /// Largest `|Z_ij|` of the matrix factorised.
    z_max: f64,
    /// Frequency of the matrix factorised, for errors.
    freq_hz: f64,
}

/// Numeric LU and its scratch, allocated only when the fallback is needed.
struct LuWorkspace {
    numeric: NumericLu<usize, C64>,
    buffer: MemBuffer,
    capacity: StackReq,
    /// Column-major copy of interleaved right-hand sides.
    cols: Mat<C64>,
}

impl ZSolver {
    /// Analyses a pattern (once per model).
    pub fn new(pattern: &Pattern) -> Result<Self, FrfError> {
        Self::with_cliques(pattern, &[])
    }

    /// As [`Self::new`], with an ordering and a factor pattern chosen so
    /// that [`Self::selected_inverse`] holds `Z^-1[D, D]` for every clique
    /// `D` (equation numbers, as in the pattern).
    ///
    /// The analysis is that of `pattern` with every pair of equations within
    /// each clique added; [`Self::factorize`] still takes values on
    /// `pattern` itself, the added pairs being structural zeros. Each added
    /// pair can bring fill, so the factor grows with the cliques
    /// ([`Self::factor_nnz`]); pairs already in `pattern` (the equations of
    /// one element) change nothing. With no cliques this is [`Self::new`].
    ///
    /// The factor's [`Layout`] is chosen from the analysis: supernodal when
    /// one factorisation needs more than 16 multiply-adds per entry of `L`
    /// (the long columns of shell and solid meshes), simplicial otherwise
    /// (beams and frames, a few per entry).
    pub fn with_cliques(pattern: &Pattern, cliques: &[Vec<usize>]) -> Result<Self, FrfError> {
        Self::analyse(pattern, cliques, None)
    }

    /// As [`Self::with_cliques`], in the given layout rather than the one
    /// the analysis would choose: for comparisons and tests.
    pub fn with_layout(pattern: &Pattern, cliques: &[Vec<usize>], layout: Layout) -> Result<Self, FrfError> {
        Self::analyse(pattern, cliques, Some(layout))
    }

    fn analyse(pattern: &Pattern, cliques: &[Vec<usize>], layout: Option<Layout>) -> Result<Self, FrfError> {
        let n = pattern.n();
        for (clique, eqs) in cliques.iter().enumerate() {
            if let Some(&eq) = eqs.iter().find(|&&eq| eq >= n) {
                return Err(FrfError::CliqueOutOfRange { clique, eq, n });
            }
        }
        let symbolic =
            SymbolicSparseColMat::new_checked(n, n, pattern.col_ptr().to_vec(), None, pattern.row_idx().to_vec());
        let ldlt = Analysis::new(pattern, cliques, layout).map_err(FrfError::Factorization)?;
        Ok(ZSolver { pattern: symbolic, ldlt, lu: OnceLock::new() })
    }

    /// Matrix dimension.
    pub fn n(&self) -> usize {
        self.ldlt.n()
    }

    /// The layout of the `L D L^T` factor.
    pub fn layout(&self) -> Layout {
        self.ldlt.layout()
    }

    /// Number of entries of the factor `L` below its diagonal in the
    /// elimination's pattern (the fill-in measure that sets the cost of
    /// factorising and solving), whatever the layout.
    pub fn factor_nnz(&self) -> usize {
        self.ldlt.nnz_exact()
    }

    /// Number of entries of `L` below its diagonal as stored: at least
    /// [`Self::factor_nnz`], more in the supernodal layout, which stores
    /// explicit zeros where it merged small supernodes of nearly equal
    /// patterns into one dense block. The selected inverse holds `Z^-1` on
    /// the stored pattern (and the diagonal).
    pub fn factor_stored(&self) -> usize {
        self.ldlt.nnz_stored()
    }

    /// Complex multiply-adds of one numeric `L D L^T` factorisation in the
    /// elimination's pattern: the part of a line's cost that grows with the
    /// square of the factor's column counts (a shell's factor has columns
    /// tens of times fuller than a beam's), where the solves grow with
    /// [`Self::factor_nnz`].
    pub fn factor_multiply_adds(&self) -> u64 {
        self.ldlt.multiply_adds()
    }

    /// Row of equation `eq` in the solver's internal order (the layout of
    /// [`Self::solve_ordered`]).
    pub fn position(&self, eq: usize) -> usize {
        self.ldlt.perm_inv()[eq]
    }

    /// A fresh workspace for one thread.
    pub fn workspace(&self) -> Workspace {
        Workspace {
            ldlt: self.ldlt.numeric(),
            buf: Vec::new(),
            buf_rows: Vec::new(),
            lu: None,
            kind: None,
            z_max: 0.0,
            freq_hz: f64::NAN,
        }
    }

    fn symbolic_lu(&self) -> Result<&SymbolicLu<usize>, FrfError> {
        self.lu
            .get_or_init(|| {
                factorize_symbolic_lu(self.pattern.as_ref(), Default::default()).map_err(|e| format!("{e:?}"))
            })
            .as_ref()
            .map_err(|e| FrfError::Factorization(e.clone()))
    }

    /// Factorises `Z` given as values on the pattern: `L D L^T`, or LU when a
    /// pivot is tiny (see the module docs). `freq_hz` is only used in errors.
    pub fn factorize(&self, ws: &mut Workspace, values: &[C64], freq_hz: f64) -> Result<(), FrfError> {
        ws.kind = None;
        ws.freq_hz = freq_hz;
        ws.z_max = check_values(self, values, freq_hz)?;
        match self.ldlt.factorize(&mut ws.ldlt, values) {
            Ok(()) => {
                ws.kind = Some(FactorKind::Ldlt);
                Ok(())
            }
            Err(_) => self.factorize_lu(ws, values, freq_hz),
        }
    }

    /// Factorises `Z` with the pivoting sparse LU directly, as the fallback of
    /// [`Self::factorize`] does; for cross-checks and tests.
    pub fn factorize_lu(&self, ws: &mut Workspace, values: &[C64], freq_hz: f64) -> Result<(), FrfError> {
        ws.kind = None;
        ws.freq_hz = freq_hz;
        ws.z_max = check_values(self, values, freq_hz)?;
        let lu = self.symbolic_lu()?;
        let lw = ws.lu.get_or_insert_with(|| {
            let capacity = lu
                .factorize_numeric_lu_scratch::<C64>(Par::Seq, Default::default())
                .or(lu.solve_in_place_scratch::<C64>(1, Par::Seq));
            LuWorkspace { numeric: NumericLu::new(), buffer: MemBuffer::new(capacity), capacity, cols: Mat::new() }
        });
        let mat = SparseColMatRef::new(self.pattern.as_ref(), values);
        lu.factorize_numeric_lu(&mut lw.numeric, mat, Par::Seq, MemStack::new(&mut lw.buffer), Default::default())
            .map_err(|_| FrfError::Singular { freq_hz })?;
        ws.kind = Some(FactorKind::Lu);
        Ok(())
    }

    /// LU solve of a column-major block, with the factors in `lw`.
    fn lu_solve(&self, lw: &mut LuWorkspace, rhs: MatMut<'_, C64>) {
        let lu = self.symbolic_lu().expect("an LU factorisation exists, so does its symbolic part");
        let need = lu.solve_in_place_scratch::<C64>(rhs.ncols(), Par::Seq);
        if need.size_bytes() > lw.capacity.size_bytes() {
            lw.capacity = lw.capacity.or(need);
            lw.buffer = MemBuffer::new(lw.capacity);
        }
        LuRef::new_unchecked(lu, &lw.numeric).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut lw.buffer),
        );
    }

    /// Solves `Z x = b` in place for every column of `rhs`, with the factors in
    /// `ws`. Returns [`FrfError::Singular`] when the solution is not finite.
    pub fn solve_in_place(&self, ws: &mut Workspace, mut rhs: MatMut<'_, C64>, freq_hz: f64) -> Result<(), FrfError> {
        let n = self.n();
        assert_eq!(rhs.nrows(), n, "right-hand sides must have one row per equation");
        match ws.kind.expect("solve called before a successful factorize") {
            FactorKind::Ldlt => {
                let k = rhs.ncols();
                let perm = self.ldlt.perm();
                let mut buf = std::mem::take(&mut ws.buf);
                buf.clear();
                buf.resize(n * k, ZERO);
                for j in 0..k {
                    let col = rhs.as_ref().col(j);
                    for (new, &old) in perm.iter().enumerate() {
                        buf[new * k + j] = col[old];
                    }
                }
                let finite = self.ldlt.solve_in_place(&mut ws.ldlt, &mut buf, k);
                for j in 0..k {
                    let mut col = rhs.as_mut().col_mut(j);
                    for (new, &old) in perm.iter().enumerate() {
                        col[old] = buf[new * k + j];
                    }
                }
                ws.buf = buf;
                if finite { Ok(()) } else { Err(FrfError::Singular { freq_hz }) }
            }
            FactorKind::Lu => {
                let b_max = largest_entry(rhs.as_ref());
                let lw = ws.lu.as_mut().expect("LU factors exist");
                self.lu_solve(lw, rhs.as_mut());
                for j in 0..rhs.ncols() {
                    if !rhs.as_ref().col(j).iter().all(|v| is_finite(*v)) {
                        return Err(FrfError::Singular { freq_hz });
                    }
                }
                check_amplification(ws.z_max, b_max, largest_entry(rhs.as_ref()), freq_hz)
            }
        }
    }

    /// Solves `Z X = B` in place for `k` right-hand sides stored
    /// row-interleaved in equation order: `x[i * k + j]` is equation `i` of
    /// right-hand side `j` (`x.len() == n * k`).
    pub fn solve_interleaved(&self, ws: &mut Workspace, x: &mut [C64], k: usize, freq_hz: f64) -> Result<(), FrfError> {
        let n = self.n();
        assert_eq!(x.len(), n * k, "right-hand sides must be n x k, row-interleaved");
        if ws.kind == Some(FactorKind::Ldlt) {
            let perm = self.ldlt.perm();
            let mut buf = std::mem::take(&mut ws.buf);
            buf.clear();
            buf.reserve(n * k);
            for &old in perm {
                buf.extend_from_slice(&x[old * k..old * k + k]);
            }
            let finite = self.ldlt.solve_in_place(&mut ws.ldlt, &mut buf, k);
            for (new, &old) in perm.iter().enumerate() {
                x[old * k..old * k + k].copy_from_slice(&buf[new * k..new * k + k]);
            }
            ws.buf = buf;
            return if finite { Ok(()) } else { Err(FrfError::Singular { freq_hz }) };
        }
        self.solve_lu_interleaved(ws, x, k, |i| i, freq_hz)
    }

    /// As [`Self::solve_interleaved`], with rows in the solver's internal
    /// order: row [`Self::position`]`(eq)` holds equation `eq`.
    pub fn solve_ordered(&self, ws: &mut Workspace, x: &mut [C64], k: usize, freq_hz: f64) -> Result<(), FrfError> {
        assert_eq!(x.len(), self.n() * k, "right-hand sides must be n x k, row-interleaved");
        if ws.kind == Some(FactorKind::Ldlt) {
            let finite = self.ldlt.solve_in_place(&mut ws.ldlt, x, k);
            return if finite { Ok(()) } else { Err(FrfError::Singular { freq_hz }) };
        }
        let perm_inv = self.ldlt.perm_inv();
        self.solve_lu_interleaved(ws, x, k, |eq| perm_inv[eq], freq_hz)
    }

    /// Columns of `R = Z^-1` for the equations `eqs`: `x` is resized to
    /// `n x eqs.len()` and receives them row-interleaved in the solver's
    /// internal order, `x[position(i) * k + j] = R[i, eqs[j]]`. The unit
    /// right-hand sides are made on the fly, so `x` needs no clearing; by
    /// symmetry of `R` the same numbers are the rows `R[eqs[j], i]`.
    pub fn solve_units_ordered(
        &self,
        ws: &mut Workspace,
        eqs: &[usize],
        x: &mut Vec<C64>,
        freq_hz: f64,
    ) -> Result<(), FrfError> {
        self.solve_units_ordered_with(ws, eqs, x, freq_hz, |_, _| {})
    }

    /// As [`Self::solve_units_ordered`], calling `visit(r, &x[r * k..])` for
    /// each internal row `r` from the last to the first, as soon as rows
    /// `r..n` of the solution are final: a caller that consumes the solution
    /// a few rows at a time does so while they are still in cache, instead
    /// of in another pass over the whole block. The rows passed may not be
    /// the final answer if the solve then reports an error.
    pub fn solve_units_ordered_with(
        &self,
        ws: &mut Workspace,
        eqs: &[usize],
        x: &mut Vec<C64>,
        freq_hz: f64,
        visit: impl FnMut(usize, &[C64]),
    ) -> Result<(), FrfError> {
        self.solve_units_in(ws, eqs, x, freq_hz, None, visit)
    }

    /// As [`Self::solve_units_ordered`], where only the rows of `within`
    /// (from [`Self::reach`] of the equations whose rows are read, which
    /// must include `eqs`) are wanted: the rows outside it are left
    /// undefined, and the substitutions skip what they do not need. The
    /// rows of `within` are bit for bit those of the whole solve. Where the
    /// factorisation held is not a simplicial `L D L^T` every row is solved.
    pub fn solve_units_within(
        &self,
        ws: &mut Workspace,
        eqs: &[usize],
        within: &Reach,
        x: &mut Vec<C64>,
        freq_hz: f64,
    ) -> Result<(), FrfError> {
        self.solve_units_in(ws, eqs, x, freq_hz, within.rows.as_deref(), |_, _| {})
    }

    fn solve_units_in(
        &self,
        ws: &mut Workspace,
        eqs: &[usize],
        x: &mut Vec<C64>,
        freq_hz: f64,
        within: Option<&[bool]>,
        mut visit: impl FnMut(usize, &[C64]),
    ) -> Result<(), FrfError> {
        let (n, k) = (self.n(), eqs.len());
        x.resize(n * k, ZERO);
        if ws.kind == Some(FactorKind::Ldlt) {
            let mut rows = std::mem::take(&mut ws.buf_rows);
            rows.clear();
            rows.extend(eqs.iter().map(|&e| self.position(e)));
            let finite = self.ldlt.solve_units(&mut ws.ldlt, &rows, x, within, visit);
            ws.buf_rows = rows;
            return if finite { Ok(()) } else { Err(FrfError::Singular { freq_hz }) };
        }
        x.fill(ZERO);
        for (j, &e) in eqs.iter().enumerate() {
            x[self.position(e) * k + j] = C64::new(1.0, 0.0);
        }
        self.solve_ordered(ws, x, k, freq_hz)?;
        for r in (0..n).rev() {
            visit(r, &x[r * k..]);
        }
        Ok(())
    }

    /// The LU path of the interleaved solves: `row(eq)` is the row of `x`
    /// that holds equation `eq`.
    fn solve_lu_interleaved(
        &self,
        ws: &mut Workspace,
        x: &mut [C64],
        k: usize,
        row: impl Fn(usize) -> usize,
        freq_hz: f64,
    ) -> Result<(), FrfError> {
        assert_eq!(ws.kind, Some(FactorKind::Lu), "solve called before a successful factorize");
        let n = self.n();
        let b_max = largest_norm(x);
        let z_max = ws.z_max;
        let lw = ws.lu.as_mut().expect("LU factors exist");
        let mut cols = std::mem::replace(&mut lw.cols, Mat::new());
        cols.resize_with(n, k, |_, _| ZERO);
        for eq in 0..n {
            let r = row(eq);
            for j in 0..k {
                cols[(eq, j)] = x[r * k + j];
            }
        }
        self.lu_solve(lw, cols.as_mut());
        for eq in 0..n {
            let r = row(eq);
            for j in 0..k {
                x[r * k + j] = cols[(eq, j)];
            }
        }
        lw.cols = cols;
        check_solution(x, freq_hz)?;
        check_amplification(z_max, b_max, largest_norm(x), freq_hz)
    }
}

/// The part of a factorisation that the solution at some equations, and the
/// entries of `Z^-1` between them, depend on ([`ZSolver::reach`]): the
/// equations and their ancestors in the elimination tree. A solve or a
/// selected inversion restricted to it ([`ZSolver::solve_units_within`],
/// [`ZSolver::selected_inverse_within`]) skips the rest of the factor.
#[derive(Clone, Debug)]
pub struct Reach {
    /// Per internal row, whether it is in the reach; `None`: every row (the
    /// supernodal layout).
    rows: Option<Vec<bool>>,
}

impl Reach {
    /// How many of the factor's rows it holds; `None` where it holds every
    /// row (the supernodal layout).
    pub fn rows(&self) -> Option<usize> {
        self.rows.as_ref().map(|r| r.iter().filter(|&&b| b).count())
    }
}

/// Entries of `Z^-1` on the pattern of the factor (`L + L^T` plus the
/// diagonal), made by [`ZSolver::selected_inverse`] and read with
/// [`ZSolver::inverse_entry`] and [`ZSolver::inverse_block`].
///
/// Make one per thread with [`SelectedInverse::new`] and reuse it from one
/// frequency to the next: its storage is allocated on first use only.
#[derive(Clone, Debug, Default)]
pub struct SelectedInverse {
    /// The entries, in the layout of the factor (the solver's internal
    /// order; see `Analysis::inverse_position`).
    values: Vec<C64>,
    /// Scratch of the recurrence.
    scratch: InverseScratch,
    /// Whether the values are those of the last successful inversion.
    ready: bool,
}

impl SelectedInverse {
    /// Empty storage, sized on first use.
    pub fn new() -> Self {
        Self::default()
    }
}

/// Selected inversion: entries of `Z^-1` without a solve per equation.
impl ZSolver {
    /// The part of the factorisation that the solution at the equations
    /// `eqs`, and the entries of `Z^-1` between them, depend on (see
    /// [`Reach`]).
    ///
    /// # Panics
    ///
    /// When an equation is out of range.
    pub fn reach(&self, eqs: impl IntoIterator<Item = usize>) -> Reach {
        Reach { rows: self.ldlt.reach(eqs.into_iter().map(|e| self.position(e))) }
    }

    /// `Z^-1` on the pattern of the factor, from the `L D L^T` factors in
    /// `ws`, by the Takahashi equations (see the module docs): about the
    /// cost of the numeric factorisation, whatever the number of entries
    /// then read. Allocates nothing once `out` has been used with this
    /// solver.
    ///
    /// Returns [`FrfError::NoLdltFactors`] when `ws` holds the LU fallback
    /// or no factorisation (solve for unit right-hand sides instead), and
    /// [`FrfError::Singular`] when an entry is not finite. On error `out`
    /// holds nothing that can be read.
    pub fn selected_inverse(&self, ws: &Workspace, out: &mut SelectedInverse) -> Result<(), FrfError> {
        self.selected_inverse_in(ws, out, None)
    }

    /// As [`Self::selected_inverse`], where only the entries between the
    /// equations of `within` (from [`Self::reach`]) are read afterwards:
    /// only the columns of the factor they depend on are inverted (about
    /// the cost of the factorisation when they lie in a few places of a
    /// large model), bit for bit as the whole inversion makes them. Other
    /// entries are left undefined. The supernodal layout inverts every
    /// column.
    pub fn selected_inverse_within(
        &self,
        ws: &Workspace,
        within: &Reach,
        out: &mut SelectedInverse,
    ) -> Result<(), FrfError> {
        self.selected_inverse_in(ws, out, within.rows.as_deref())
    }

    fn selected_inverse_in(
        &self,
        ws: &Workspace,
        out: &mut SelectedInverse,
        within: Option<&[bool]>,
    ) -> Result<(), FrfError> {
        out.ready = false;
        if ws.kind != Some(FactorKind::Ldlt) {
            return Err(FrfError::NoLdltFactors { held: ws.kind });
        }
        // every value is overwritten by the recurrence, so storage of the
        // right size is reused as it is
        let len = self.ldlt.inverse_len();
        if out.values.len() != len {
            out.values = vec![ZERO; len];
        }
        if !self.ldlt.selected_inverse(&ws.ldlt, &mut out.values, &mut out.scratch, within) {
            return Err(FrfError::Singular { freq_hz: ws.freq_hz });
        }
        out.ready = true;
        Ok(())
    }

    /// `Z^-1[i, j]` (equation numbers; `Z^-1` is symmetric) from a selected
    /// inverse of this solver, or `None` when `(i, j)` is not in the factor's
    /// pattern (see [`Self::with_cliques`]). Costs a binary search in one
    /// column of the factor.
    ///
    /// # Panics
    ///
    /// If `inv` was not made by a successful [`Self::selected_inverse`] of
    /// this solver, or an equation is out of range.
    pub fn inverse_entry(&self, inv: &SelectedInverse, i: usize, j: usize) -> Option<C64> {
        self.check_inverse(inv);
        self.entry(inv, i, j)
    }

    /// [`Self::inverse_entry`] once `inv` is known to be of this solver.
    fn entry(&self, inv: &SelectedInverse, i: usize, j: usize) -> Option<C64> {
        self.ldlt.inverse_position(self.position(i), self.position(j)).map(|pos| inv.values[pos])
    }

    /// The dense block `Z^-1[D, D]` for the equations `D = eqs`, row-major
    /// (`out[a * eqs.len() + b] = Z^-1[eqs[a], eqs[b]]`, `out.len() ==
    /// eqs.len()^2`). Returns `false`, with `out` partly written, when a pair
    /// is not in the factor's pattern. Allocates nothing.
    ///
    /// # Panics
    ///
    /// As [`Self::inverse_entry`], or when `out` has the wrong length.
    pub fn inverse_block(&self, inv: &SelectedInverse, eqs: &[usize], out: &mut [C64]) -> bool {
        let m = eqs.len();
        assert_eq!(out.len(), m * m, "the block must be eqs.len() x eqs.len()");
        self.check_inverse(inv);
        for a in 0..m {
            for b in a..m {
                let Some(v) = self.entry(inv, eqs[a], eqs[b]) else {
                    return false;
                };
                out[a * m + b] = v;
                out[b * m + a] = v;
            }
        }
        true
    }

    /// Panics unless `inv` holds a successful selected inversion of a solver
    /// of this size (one of another solver of the same size cannot be told
    /// apart).
    fn check_inverse(&self, inv: &SelectedInverse) {
        assert!(
            inv.ready && inv.values.len() == self.ldlt.inverse_len(),
            "no selected inverse of this solver (none made, or the last one failed)"
        );
    }
}

impl Workspace {
    /// The factorisation held, or `None` before a successful
    /// [`ZSolver::factorize`].
    pub fn factor_kind(&self) -> Option<FactorKind> {
        self.kind
    }
}

fn is_finite(v: C64) -> bool {
    v.re.is_finite() && v.im.is_finite()
}

/// Checks that every value is finite; returns the largest `|Z_ij|`.
fn check_values(solver: &ZSolver, values: &[C64], freq_hz: f64) -> Result<f64, FrfError> {
    assert_eq!(values.len(), solver.pattern.row_idx().len(), "values must lie on the solver's pattern");
    // one pass for both the check and the largest squared modulus (a pass
    // over a 100,000-DOF frame's values is a fiftieth of its factorisation)
    let (m2, finite) = largest_square(values);
    if finite {
        return Ok(norm_from_square(m2, values));
    }
    if !(freq_hz.is_finite() && freq_hz > 0.0) {
        return Err(FrfError::BadFrequency { freq_hz });
    }
    let i = values.iter().position(|&v| !is_finite(v)).expect("a value is not finite");
    // the column of entry i (the pattern is symmetric: its row too)
    let col_ptr = solver.pattern.col_ptr();
    let equation = col_ptr.partition_point(|&p| p <= i).saturating_sub(1);
    Err(FrfError::NonFiniteZ { freq_hz, equation })
}

/// `max |x_i|`. The squared moduli are compared first (`hypot` on every
/// entry of `Z` cost about a twentieth of a 100,000-DOF line); only when the
/// largest square overflows or underflows is the maximum taken by `hypot`.
fn largest_norm(x: &[C64]) -> f64 {
    norm_from_square(largest_square(x).0, x)
}

/// The largest squared modulus of `x` (a value that is not finite left
/// out) and whether every value is finite, in one pass. Four maxima run
/// side by side: one running maximum is a chain of dependent operations
/// that no vector unit shortens (on a 300-DOF beam, whose factorisation
/// is cheap, the check took half as long as the factorisation).
fn largest_square(x: &[C64]) -> (f64, bool) {
    let mut m = [0.0f64; 4];
    let mut finite = true;
    let chunks = x.chunks_exact(4);
    let rest = chunks.remainder();
    for c in chunks {
        for (m, v) in m.iter_mut().zip(c) {
            *m = m.max(v.norm_sqr());
            finite &= v.re.is_finite() & v.im.is_finite();
        }
    }
    for v in rest {
        m[0] = m[0].max(v.norm_sqr());
        finite &= is_finite(*v);
    }
    (m.into_iter().fold(0.0, f64::max), finite)
}

/// `max |x_i|` from the largest squared modulus `m2` of `x`, or by `hypot`
/// where that square overflowed or underflowed.
fn norm_from_square(m2: f64, x: &[C64]) -> f64 {
    if m2.is_normal() { m2.sqrt() } else { x.iter().fold(0.0, |m, v| m.max(v.norm())) }
}

fn largest_entry(m: MatRef<'_, C64>) -> f64 {
    (0..m.ncols()).map(|j| m.col(j).iter().fold(0.0, |a: f64, v| a.max(v.norm()))).fold(0.0, f64::max)
}

/// See [`SINGULAR_AMPLIFICATION`].
fn check_amplification(z_max: f64, b_max: f64, x_max: f64, freq_hz: f64) -> Result<(), FrfError> {
    if z_max * x_max > SINGULAR_AMPLIFICATION * b_max { Err(FrfError::Singular { freq_hz }) } else { Ok(()) }
}

/// faer signals a numerically singular LU only through NaN or inf in the
/// solution; a huge but finite `L D L^T` solution passed the pivot test.
fn check_solution(x: &[C64], freq_hz: f64) -> Result<(), FrfError> {
    if x.iter().all(|&v| is_finite(v)) { Ok(()) } else { Err(FrfError::Singular { freq_hz }) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The largest modulus is exact wherever its square would leave the
    /// range of doubles.
    #[test]
    fn largest_norm_survives_overflow_and_underflow() {
        for scale in [1e-300, 1e-160, 1e-3, 1.0, 1e150, 1e200, 1e300] {
            let x = [C64::new(3.0 * scale, -4.0 * scale), C64::new(-scale, scale), C64::new(0.0, 0.0)];
            let want = 5.0 * scale;
            assert!((largest_norm(&x) - want).abs() <= 1e-15 * want, "scale {scale}: {}", largest_norm(&x));
        }
        assert_eq!(largest_norm(&[C64::new(0.0, 0.0)]), 0.0);
        // the four maxima side by side and the tail, against one running maximum
        for n in 0..11 {
            let x: Vec<C64> = (0..n).map(|i| C64::new((i * 7 % 5) as f64 - 2.0, (i * 3 % 4) as f64)).collect();
            let want = x.iter().fold(0.0, |m: f64, v| m.max(v.norm_sqr()));
            assert_eq!(largest_square(&x), (want, true), "n {n}");
            for bad in [f64::NAN, f64::INFINITY, -f64::INFINITY] {
                for at in 0..n {
                    let mut y = x.clone();
                    y[at].im = bad;
                    assert!(!largest_square(&y).1, "n {n}, {bad} at {at}");
                }
            }
        }
    }
}
