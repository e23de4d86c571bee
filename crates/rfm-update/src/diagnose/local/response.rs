//! A local candidate's receptances and sensitivities by the Woodbury
//! identity (see the module docs of `local`), as a [`Response`] the
//! output-error fit iterates on.

use std::borrow::Cow;

use damping::DampedSystem;
use faer::Mat;
use fe_model::Block;
use num_complex::Complex64 as C64;

use super::kernels::{condense, lu_in_place, lu_solve, lu_solve_transposed};
use super::{LocalCandidate, LocalData, LocalForm, ZERO};
use crate::error::UpdateError;
use crate::output_error::{Evaluated, Response};
use crate::params::ParameterSet;

impl LocalData {
    /// The model response of one candidate at `lines` (Hz, all among
    /// those gathered), starting at the values of `sys` (its part,
    /// [`LocalCandidate::part`], possibly with other values); `None` when
    /// these data do not serve it (see [`LocalData::covers`]).
    pub(crate) fn response<'a>(
        &'a self,
        local: &'a LocalCandidate,
        sys: DampedSystem,
        lines: &[f64],
    ) -> Option<LocalResponse<'a>> {
        let (form, nominal) = (&local.form, &local.nominal_part);
        let line_idx = self.line_indices(lines)?;
        let slot = self.slots.find(&form.eqs)?;
        let d = form.eqs.len();
        // S on D: the slot's S where the slot is D, else its rows and
        // columns at D (both sorted)
        let slot_eqs = &self.slots.eqs[slot];
        let at: Vec<usize> = form.eqs.iter().map(|e| slot_eqs.binary_search(e).expect("the slot holds D")).collect();
        let ds = slot_eqs.len();
        let s = line_idx
            .iter()
            .map(|&l| {
                let full = &self.per_line[l].s[self.slots.range(slot)];
                if ds == d {
                    Cow::Borrowed(full)
                } else {
                    Cow::Owned(at.iter().flat_map(|&r| at.iter().map(move |&c| full[r * ds + c])).collect())
                }
            })
            .collect();
        let a0 = nominal.assembly();
        let nominal_blocks: Vec<Placed> =
            form.nominal_blocks.iter().map(|&b| Placed::new(&a0.blocks()[b], |e| form.nominal_index(e))).collect();
        let nominal_z = lines
            .iter()
            .map(|&f| {
                let coefs = nominal.coefficients(2.0 * std::f64::consts::PI * f);
                let mut z = vec![ZERO; d * d];
                for (p, &b) in nominal_blocks.iter().zip(&form.nominal_blocks) {
                    let block = &a0.blocks()[b];
                    for t in block.terms() {
                        p.add(t.unit(), -coefs[block.group()].of(t.kind()) * t.value(), &mut z, d);
                    }
                }
                z
            })
            .collect();
        let k = self.w_eqs.len();
        let x = line_idx
            .iter()
            .map(|&l| {
                let line = &self.per_line[l];
                form.eqs
                    .iter()
                    .flat_map(|&e| {
                        let r = self.row_of[e];
                        line.w_rows[r * k..r * k + k].iter().copied()
                    })
                    .collect()
            })
            .collect();
        let a = sys.assembly();
        let mut placed: Vec<Option<Placed>> = (0..a.blocks().len()).map(|_| None).collect();
        for &b in &form.blocks {
            placed[b] = Some(Placed::new(&a.blocks()[b], |e| form.candidate_index(e)));
        }
        let mut refs: Vec<usize> = self.picks.iter().map(|&(_, f)| f).collect();
        refs.sort_unstable();
        refs.dedup();
        let n_local = d + form.new_eqs;
        Some(LocalResponse {
            data: self,
            lines: lines.to_vec(),
            line_idx,
            form,
            sys,
            params: &local.params,
            nominal_z,
            x,
            s,
            placed,
            work: Work::new(n_local, d),
            refs,
            states: (0..lines.len()).map(|_| LineState::default()).collect(),
            model: Vec::new(),
            values: None,
            fresh: false,
        })
    }
}

/// A block's equations placed in a local matrix.
struct Placed {
    /// Local index of each block equation.
    idx: Vec<usize>,
}

impl Placed {
    fn new(block: &Block, index: impl Fn(usize) -> usize) -> Self {
        Placed { idx: block.eqs().iter().map(|&e| index(e)).collect() }
    }

    /// `out += c * unit` with `out` row-major `n x n`.
    fn add(&self, unit: &[f64], c: C64, out: &mut [C64], n: usize) {
        let m = self.idx.len();
        for (r, &ir) in self.idx.iter().enumerate() {
            let row = &mut out[ir * n..ir * n + n];
            for (col, &ic) in self.idx.iter().enumerate() {
                let u = unit[r * m + col];
                if u != 0.0 {
                    row[ic] += c * u;
                }
            }
        }
    }
}

/// Scratch of one candidate's evaluation, allocated once.
struct Work {
    /// The local change `[[A, B], [B^T, C]]`, `(d + e)^2`.
    z: Vec<C64>,
    /// The LU of `C` (`G = C^-1 B^T` is kept per line: [`LineState`]).
    c: Vec<C64>,
    c_piv: Vec<usize>,
    /// The condensed change `dZ`, `d x d`.
    dz: Vec<C64>,
    /// The non-zeros `(column, value)` of `dZ` by row, and row pointers.
    nz: Vec<(usize, C64)>,
    nz_ptr: Vec<usize>,
    /// One parameter's derivative, `(d + e)^2`, and condensed, `d x d`.
    dzi: Vec<C64>,
    dzi_c: Vec<C64>,
    /// A column of `d` values.
    col: Vec<C64>,
}

impl Work {
    fn new(n_local: usize, d: usize) -> Self {
        let e = n_local - d;
        Work {
            z: vec![ZERO; n_local * n_local],
            c: vec![ZERO; e * e],
            c_piv: vec![0; e],
            dz: vec![ZERO; d * d],
            nz: Vec::with_capacity(d * d),
            nz_ptr: Vec::with_capacity(d + 1),
            dzi: vec![ZERO; n_local * n_local],
            dzi_c: vec![ZERO; d * d],
            col: vec![ZERO; d],
        }
    }
}

/// [`Response`] of one local candidate; see the module docs.
pub(crate) struct LocalResponse<'a> {
    data: &'a LocalData,
    /// The lines it is evaluated at, and their indices in `data`.
    lines: Vec<f64>,
    line_idx: Vec<usize>,
    form: &'a LocalForm,
    sys: DampedSystem,
    params: &'a ParameterSet,
    /// Per line: minus the nominal model's part of `Z` on `D` that the
    /// candidate replaces, row-major `d x d`.
    nominal_z: Vec<Vec<C64>>,
    /// Per line: `X = H_0[D, W]`, row-major `d x |W|`.
    x: Vec<Vec<C64>>,
    /// Per line: `S = H_0[D, D]`, row-major `d x d`: borrowed from the
    /// gathered data where the slot is `D` itself (a copy of 46 KB per
    /// line and fit for a window of 8 elements in space, a tenth of the
    /// pre-screening's time on the 100k-DOF frame), else its rows and
    /// columns at `D`.
    s: Vec<Cow<'a, [C64]>>,
    /// Each block of the candidate's part, placed locally when it changed.
    placed: Vec<Option<Placed>>,
    /// Distinct reference columns in `W`.
    refs: Vec<usize>,
    work: Work,
    /// Per line, what the sensitivities read of the last evaluation (see
    /// [`LineState`]), and its receptances.
    states: Vec<LineState>,
    model: Vec<Vec<C64>>,
    /// The values last set ([`Response::set`]; `None`: those it started with).
    values: Option<Vec<f64>>,
    /// Whether `states` and `model` hold the evaluation at those values.
    fresh: bool,
}

/// What the sensitivities at one line read of an evaluation: the LU of `I +
/// S dZ`, `Y` at the reference columns and the condensation `G`, so that
/// the sensitivities at the point of the last evaluation cost no second
/// factorisation of the local system.
#[derive(Default)]
struct LineState {
    m: Vec<C64>,
    m_piv: Vec<usize>,
    y: Vec<C64>,
    g: Vec<C64>,
}

impl Response for LocalResponse<'_> {
    fn set(&mut self, values: &[f64]) -> Result<(), UpdateError> {
        if self.values.as_deref() != Some(values) {
            self.fresh = false;
            self.values = Some(values.to_vec());
        }
        self.params.set_values(&mut self.sys, values)
    }

    /// Not cheap beside the receptances (on a damping window the
    /// sensitivities cost about what the receptances do), but an
    /// evaluation keeps the factorisations its sensitivities read: a trial
    /// step is evaluated without them, and an accepted one adds only the
    /// sensitivities, with the same numbers as one evaluation of both.
    /// The brief fits of the pre-screening reject about half their trial
    /// steps on damping windows.
    fn cheap_jacobian(&self) -> bool {
        false
    }

    fn evaluate(&mut self, lines: &[f64], jacobian: bool) -> Option<Evaluated> {
        if lines != self.lines.as_slice() {
            return None;
        }
        if !self.fresh {
            self.model = self.receptances()?;
            self.fresh = true;
        }
        let sens = jacobian.then(|| self.sensitivities());
        Some((self.model.clone(), sens))
    }
}

impl LocalResponse<'_> {
    /// The receptances at the current values, keeping per line what the
    /// sensitivities read ([`LineState`]); `None` when the local system is
    /// singular at a line or a receptance is not finite.
    fn receptances(&mut self) -> Option<Vec<Vec<C64>>> {
        let (d, e) = (self.form.eqs.len(), self.form.new_eqs);
        let (n, k) = (d + e, self.data.w_eqs.len());
        let a = self.sys.assembly();
        let w = &mut self.work;
        let mut model = Vec::with_capacity(self.lines.len());
        for (li, &f) in self.lines.iter().enumerate() {
            let omega = 2.0 * std::f64::consts::PI * f;
            let coefs = self.sys.coefficients(omega);
            let state = &mut self.states[li];
            // the change on D and the candidate's own equations, [[A, B], [B^T, C]]
            w.z.fill(ZERO);
            for (i, row) in self.nominal_z[li].chunks_exact(d).enumerate() {
                w.z[i * n..i * n + d].copy_from_slice(row);
            }
            for &b in &self.form.blocks {
                let (block, p) = (&a.blocks()[b], self.placed[b].as_ref().expect("changed blocks are placed"));
                for t in block.terms().iter().filter(|t| t.value() != 0.0) {
                    p.add(t.unit(), coefs[block.group()].of(t.kind()) * t.value(), &mut w.z, n);
                }
            }
            // condensed onto D: dZ = A - B C^-1 B^T, with G = C^-1 B^T
            state.g.clear();
            state.g.resize(e * d, ZERO);
            if e > 0 {
                for m in 0..e {
                    w.c[m * e..m * e + e].copy_from_slice(&w.z[(d + m) * n + d..(d + m) * n + n]);
                    state.g[m * d..m * d + d].copy_from_slice(&w.z[(d + m) * n..(d + m) * n + d]);
                }
                if !lu_in_place(&mut w.c, e, &mut w.c_piv) {
                    return None;
                }
                lu_solve(&w.c, e, &w.c_piv, &mut state.g, d);
            }
            condense(&w.z, &state.g, d, e, &mut w.dz);
            // I + S dZ over the non-zeros of dZ: a row of dZ couples a DOF
            // only to the DOFs of its elements, so this costs d nnz(dZ), not d^3
            w.nz.clear();
            w.nz_ptr.clear();
            w.nz_ptr.push(0);
            for row in w.dz.chunks_exact(d) {
                w.nz.extend(row.iter().enumerate().filter(|(_, v)| **v != ZERO).map(|(j, &v)| (j, v)));
                w.nz_ptr.push(w.nz.len());
            }
            let s = &self.s[li];
            state.m.clear();
            state.m.resize(d * d, ZERO);
            state.m_piv.resize(d, 0);
            for i in 0..d {
                state.m[i * d + i] = C64::new(1.0, 0.0);
                let (s_row, m_row) = (&s[i * d..i * d + d], &mut state.m[i * d..i * d + d]);
                for (kk, &sik) in s_row.iter().enumerate() {
                    for &(j, v) in &w.nz[w.nz_ptr[kk]..w.nz_ptr[kk + 1]] {
                        m_row[j] += sik * v;
                    }
                }
            }
            if !lu_in_place(&mut state.m, d, &mut state.m_piv) {
                return None;
            }
            // Y = (I + S dZ)^-1 X, needed only at the reference columns:
            // the sensitivities use the transposed system instead (below)
            let x = &self.x[li];
            let nr = self.refs.len();
            state.y.clear();
            state.y.resize(d * nr, ZERO);
            for i in 0..d {
                for (a, &fr) in self.refs.iter().enumerate() {
                    state.y[i * nr + a] = x[i * k + fr];
                }
            }
            lu_solve(&state.m, d, &state.m_piv, &mut state.y, nr);
            // H = H_0 - X^T dZ Y on the channels
            let line = &self.data.per_line[self.line_idx[li]];
            let mut h = line.h0.clone();
            for (a, &fr) in self.refs.iter().enumerate() {
                // over the non-zeros of dZ's rows (the zeros add nothing)
                for i in 0..d {
                    w.col[i] = w.nz[w.nz_ptr[i]..w.nz_ptr[i + 1]].iter().map(|&(j, v)| v * state.y[j * nr + a]).sum();
                }
                for (c, &(r, fi)) in self.data.picks.iter().enumerate() {
                    if fi == fr {
                        h[c] -= (0..d).map(|i| x[i * k + r] * w.col[i]).sum::<C64>();
                    }
                }
            }
            if h.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
                return None;
            }
            model.push(h);
        }
        Some(model)
    }

    /// The sensitivities at the values of the last evaluation, from what it
    /// kept per line: `(dH/dp_i) p_i [r, f] = -Y[:, r]^T dZ_i Y[:, f]` with
    /// `Y[:, r]^T = X[:, r]^T (I + S dZ)^-T`, one transposed solve per
    /// parameter and reference, not one solve per response.
    fn sensitivities(&mut self) -> Vec<Mat<C64>> {
        let (d, e) = (self.form.eqs.len(), self.form.new_eqs);
        let (n, k) = (d + e, self.data.w_eqs.len());
        let a = self.sys.assembly();
        let n_par = self.params.len();
        let nr = self.refs.len();
        let w = &mut self.work;
        let mut sens = Vec::with_capacity(self.lines.len());
        for (li, &f) in self.lines.iter().enumerate() {
            let omega = 2.0 * std::f64::consts::PI * f;
            let state = &self.states[li];
            let x = &self.x[li];
            let mut block = Mat::<C64>::zeros(self.data.picks.len(), n_par);
            for (pi, p) in self.params.params().iter().enumerate() {
                w.dzi.fill(ZERO);
                for &q in &p.quantities {
                    for (b, t, c) in self.sys.derivative(q, omega).terms {
                        let term = &a.blocks()[b].terms()[t];
                        let p = self.placed[b].as_ref().expect("a parameter's blocks are changed blocks");
                        p.add(term.unit(), c * term.value(), &mut w.dzi, n);
                    }
                }
                condense(&w.dzi, &state.g, d, e, &mut w.dzi_c);
                for (a, &fr) in self.refs.iter().enumerate() {
                    for i in 0..d {
                        w.col[i] = (0..d).map(|j| w.dzi_c[i * d + j] * state.y[j * nr + a]).sum();
                    }
                    lu_solve_transposed(&state.m, d, &state.m_piv, &mut w.col);
                    for (c, &(r, fi)) in self.data.picks.iter().enumerate() {
                        if fi == fr {
                            block[(c, pi)] = (0..d).map(|i| x[i * k + r] * w.col[i]).sum();
                        }
                    }
                }
            }
            sens.push(block);
        }
        sens
    }
}
