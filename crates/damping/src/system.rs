//! The damped system: a model, its assembly, and `Z(w)` with its derivatives.

use fe_model::{Assembly, MatrixKind, Model, ModelError, Quantity, QuantityKind};
use num_complex::Complex64 as C64;
use std::sync::{Arc, OnceLock};

use crate::kernel::{self, GroupCoefficients};
use crate::units::UnitStore;

/// A model together with its assembly, kept consistent when quantities change.
///
/// `Z(w) = K - w^2 M + j w G(w)` is produced as values on the assembly's
/// sparsity pattern (see [`fe_model::Pattern`]); it is complex symmetric.
#[derive(Clone, Debug)]
pub struct DampedSystem {
    model: Model,
    assembly: Assembly,
    /// The assembly's terms laid out for `Z(w)`, made on the first `Z(w)`
    /// and dropped when a quantity changes a term.
    layout: OnceLock<Option<Arc<Layout>>>,
}

/// The assembly's terms laid out for `Z(w)` at many frequencies: per
/// block its positions, per term its group and kind's coefficient slot,
/// value and unit matrix, each distinct unit matrix stored once (identical
/// elements share it, so the loop reads it from cache). The assembly keeps
/// every term and unit matrix in its own allocation; walking those at
/// every line cost 12.6 ms on a 96k-DOF frame, this 1.6 ms. The loop is
/// [`Assembly::accumulate`]'s, in the same order, so `Z` is bitwise the
/// same: every FRF the tool synthesises, compares or writes is made from
/// it, and the response function method's step control compares model
/// FRFs from the sensitivity assembly and from synthesis bitwise.
#[derive(Debug)]
struct Layout {
    /// Per block: first position, number of entries, first term, end of terms.
    blocks: Vec<[u32; 4]>,
    positions: Vec<u32>,
    /// Per term of non-zero value: coefficient slot (`3 group + kind`),
    /// value and offset of its unit matrix.
    terms: Vec<(u32, f64, u32)>,
    units: Vec<f64>,
}

impl Layout {
    /// The layout of an assembly, or `None` when it does not fit `u32`
    /// indices (`z_values_into` then walks the assembly).
    fn new(assembly: &Assembly) -> Option<Layout> {
        let mut units = UnitStore::default();
        let (mut blocks, mut positions, mut terms) = (Vec::new(), Vec::new(), Vec::new());
        for b in assembly.blocks() {
            let p0 = u32::try_from(positions.len()).ok()?;
            for &p in b.positions() {
                positions.push(u32::try_from(p).ok()?);
            }
            let t0 = u32::try_from(terms.len()).ok()?;
            // Assembly::accumulate skips terms whose value is zero
            for t in b.terms().iter().filter(|t| t.value() != 0.0) {
                let at = units.offset_of(t.unit())?;
                let slot = 3 * u32::try_from(b.group()).ok()? + kernel::kind_slot(t.kind());
                terms.push((slot, t.value(), at));
            }
            let len = u32::try_from(b.positions().len()).ok()?;
            blocks.push([p0, len, t0, u32::try_from(terms.len()).ok()?]);
        }
        Some(Layout { blocks, positions, terms, units: units.into_values() })
    }

    /// `Z(w)` added into `out` (cleared), given each group's coefficients.
    fn z_into(&self, coefs: &[GroupCoefficients], out: &mut [C64]) {
        let by_slot: Vec<C64> = coefs.iter().flat_map(|c| [c.stiffness, c.mass, c.damping]).collect();
        out.fill(C64::new(0.0, 0.0));
        for &[p0, len, t0, t1] in &self.blocks {
            let positions = &self.positions[p0 as usize..(p0 + len) as usize];
            for &(slot, value, unit) in &self.terms[t0 as usize..t1 as usize] {
                let c = by_slot[slot as usize];
                let unit = &self.units[unit as usize..unit as usize + positions.len()];
                for (&p, &u) in positions.iter().zip(unit) {
                    if u != 0.0 {
                        out[p as usize] += c * (value * u);
                    }
                }
            }
        }
    }
}

/// `(dZ/dq) q` for one quantity at one frequency, as a list of
/// `(block, term, coefficient)`: the derivative is the sum of
/// `coefficient * term.value() * term.unit()` over the listed terms.
#[derive(Clone, Debug, Default)]
pub struct Derivative {
    /// `(block index, term index, complex coefficient)`.
    pub terms: Vec<(usize, usize, C64)>,
}

impl Derivative {
    /// The derivative as values on the sparsity pattern.
    pub fn values(&self, assembly: &Assembly) -> Vec<C64> {
        let mut out = vec![C64::new(0.0, 0.0); assembly.pattern().nnz()];
        for &(b, t, c) in &self.terms {
            let block = &assembly.blocks()[b];
            let term = &block.terms()[t];
            for (k, &p) in block.positions().iter().enumerate() {
                out[p] += c * (term.value() * term.unit()[k]);
            }
        }
        out
    }

    /// Appends `((dZ/dq) q x)` as sparse `(equation, value)` pairs to `out`
    /// (an equation may appear more than once; entries add).
    pub fn apply(&self, assembly: &Assembly, x: &[C64], out: &mut Vec<(usize, C64)>) {
        for &(b, t, c) in &self.terms {
            let block = &assembly.blocks()[b];
            let term = &block.terms()[t];
            let n = block.eqs().len();
            let scale = c * term.value();
            for r in 0..n {
                let mut acc = C64::new(0.0, 0.0);
                for col in 0..n {
                    let u = term.unit()[r * n + col];
                    if u != 0.0 {
                        acc += x[block.eqs()[col]] * u;
                    }
                }
                if acc != C64::new(0.0, 0.0) {
                    out.push((block.eqs()[r], scale * acc));
                }
            }
        }
    }

    /// True when the quantity does not affect `Z` at this frequency.
    pub fn is_zero(&self) -> bool {
        self.terms.iter().all(|&(_, _, c)| c == C64::new(0.0, 0.0))
    }
}

impl DampedSystem {
    /// Assembles a model.
    pub fn new(model: Model) -> Result<Self, ModelError> {
        let assembly = Assembly::new(&model)?;
        Ok(DampedSystem { model, assembly, layout: OnceLock::new() })
    }

    /// Assembles a part of a model ([`Model::part`]), which may float free;
    /// see [`Assembly::of_part`].
    pub fn of_part(model: Model) -> Result<Self, ModelError> {
        let assembly = Assembly::of_part(&model)?;
        Ok(DampedSystem { model, assembly, layout: OnceLock::new() })
    }

    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The assembly.
    pub fn assembly(&self) -> &Assembly {
        &self.assembly
    }

    /// Number of equations.
    pub fn n(&self) -> usize {
        self.assembly.n()
    }

    /// Sets a quantity and refreshes the terms it multiplies.
    pub fn set(&mut self, q: Quantity, value: f64) -> Result<(), ModelError> {
        self.model.set(q, value)?;
        if q.kind() == QuantityKind::Factor {
            self.assembly.refresh_quantity(&self.model, q);
            self.layout = OnceLock::new();
        }
        Ok(())
    }

    /// Current value of a quantity.
    pub fn get(&self, q: Quantity) -> f64 {
        self.model.get(q)
    }

    /// Per-group coefficients at angular frequency `omega` (rad/s).
    pub fn coefficients(&self, omega: f64) -> Vec<GroupCoefficients> {
        self.model.groups().iter().map(|g| GroupCoefficients::new(g, omega)).collect()
    }

    /// Writes `Z(w)` on the pattern into `out` (overwritten).
    pub fn z_values_into(&self, omega: f64, out: &mut [C64]) {
        let coefs = self.coefficients(omega);
        match self.layout.get_or_init(|| Layout::new(&self.assembly).map(Arc::new)) {
            Some(layout) => layout.z_into(&coefs, out),
            None => {
                out.fill(C64::new(0.0, 0.0));
                self.assembly.accumulate(|b, t| Some(coefs[b.group()].of(t.kind())), out);
            }
        }
    }

    /// `Z(w)` on the pattern.
    pub fn z_values(&self, omega: f64) -> Vec<C64> {
        let mut v = vec![C64::new(0.0, 0.0); self.assembly.pattern().nnz()];
        self.z_values_into(omega, &mut v);
        v
    }

    /// The kernel matrix `G(w) = sum_g h_g(w) C_g` on the pattern (with
    /// the imported viscous damping matrices, `h = 1`).
    pub fn g_values(&self, omega: f64) -> Vec<C64> {
        let groups = self.model.groups();
        let mut v = vec![C64::new(0.0, 0.0); self.assembly.pattern().nnz()];
        self.assembly.accumulate(
            |b, t| {
                let g = &groups[b.group()];
                let h = kernel::relaxation_factor(g.mu, omega);
                Some(match t.kind() {
                    MatrixKind::Stiffness => h * g.alpha,
                    MatrixKind::Mass => h * g.beta,
                    // viscous: j w C
                    MatrixKind::Damping => C64::new(1.0, 0.0),
                })
            },
            &mut v,
        );
        v
    }

    /// `(dZ/dq) q` at angular frequency `omega`, for any quantity kind.
    pub fn derivative(&self, q: Quantity, omega: f64) -> Derivative {
        let groups = self.model.groups();
        let mut terms = Vec::new();
        match q {
            Quantity::GroupAlpha(g) | Quantity::GroupBeta(g) | Quantity::GroupMu(g) => {
                let d = match q {
                    Quantity::GroupAlpha(_) => kernel::d_alpha(&groups[g], omega),
                    Quantity::GroupBeta(_) => kernel::d_beta(&groups[g], omega),
                    _ => kernel::d_mu(&groups[g], omega),
                };
                for &b in self.assembly.group_blocks(g) {
                    for (t, term) in self.assembly.blocks()[b].terms().iter().enumerate() {
                        let c = d.of(term.kind());
                        if c != C64::new(0.0, 0.0) && term.value() != 0.0 {
                            terms.push((b, t, c));
                        }
                    }
                }
            }
            _ => {
                let coefs: Vec<GroupCoefficients> = groups.iter().map(|g| GroupCoefficients::new(g, omega)).collect();
                for &(b, t) in self.assembly.terms_of(q) {
                    let block = &self.assembly.blocks()[b];
                    let term = &block.terms()[t];
                    if term.value() != 0.0 {
                        terms.push((b, t, coefs[block.group()].of(term.kind())));
                    }
                }
            }
        }
        Derivative { terms }
    }

    /// Consumes the system and returns its model.
    pub fn into_model(self) -> Model {
        self.model
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::samples;

    fn max_rel_diff(a: &[C64], b: &[C64]) -> f64 {
        // a zip would pass over a missing vector (an empty G or Z) as equal
        assert_eq!(a.len(), b.len(), "the vectors compared differ in length");
        let scale = b.iter().map(|v| v.norm()).fold(0.0, f64::max);
        a.iter().zip(b).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max) / scale
    }

    /// `Z` from the layout is bitwise `Z` added up block by block, and
    /// follows a quantity changed after `Z` was first made (the layout is
    /// made once and must be dropped then).
    #[test]
    fn z_is_the_blockwise_sum_and_follows_a_change() {
        let portal = samples::space_portal();
        for (model, name) in [(samples::frame_with_joint(), "material.steel.E"), (portal, "element.5.stiffness")] {
            let mut sys = DampedSystem::new(model).unwrap();
            let blockwise = |s: &DampedSystem, omega: f64| {
                let coefs = s.coefficients(omega);
                let mut out = vec![C64::new(0.0, 0.0); s.assembly().pattern().nnz()];
                s.assembly().accumulate(|b, t| Some(coefs[b.group()].of(t.kind())), &mut out);
                out
            };
            let before = sys.z_values(900.0);
            for omega in [30.0, 900.0, 5000.0] {
                assert_eq!(sys.z_values(omega), blockwise(&sys, omega), "{name}");
            }
            let q = sys.model().quantity(name).unwrap();
            sys.set(q, 1.3 * sys.get(q)).unwrap();
            let after = sys.z_values(900.0);
            assert!(max_rel_diff(&after, &before) > 1e-3, "{name}: Z did not change");
            assert_eq!(after, blockwise(&sys, 900.0), "{name}");
        }
    }

    /// `Z(w) - j w G(w)` is `K - w^2 M`: real, and on a straight line in
    /// `w^2` through three frequencies, for non-viscous groups (the beam's
    /// and the frame's joint, where `G` depends on `w`) and viscous ones.
    #[test]
    fn z_less_its_damping_is_k_minus_w2_m() {
        for model in [samples::two_material_cantilever(), samples::frame_with_joint(), samples::space_portal()] {
            let sys = DampedSystem::new(model).unwrap();
            let undamped = |omega: f64| -> Vec<C64> {
                let (z, g) = (sys.z_values(omega), sys.g_values(omega));
                assert_eq!(z.len(), g.len());
                z.iter().zip(&g).map(|(z, g)| z - C64::new(0.0, omega) * g).collect()
            };
            let (w1, w2, w3) = (100.0, 700.0, 3000.0);
            let (a, b, c) = (undamped(w1), undamped(w2), undamped(w3));
            // the damping is not nothing: j w G moves Z by more than round-off
            let z = sys.z_values(w2);
            assert!(max_rel_diff(&b, &z) > 1e-6, "{}: G(w) is missing", sys.model().title);
            let scale = c.iter().map(|v| v.norm()).fold(0.0, f64::max);
            for ((a, b), c) in a.iter().zip(&b).zip(&c) {
                // b on the line through a and c in w^2
                let t = (w2 * w2 - w1 * w1) / (w3 * w3 - w1 * w1);
                let line = a + (c - a) * t;
                assert!((b - line).norm() < 1e-10 * scale, "{}: {b} off the line {line}", sys.model().title);
                assert!(b.im.abs() < 1e-10 * scale, "{}: K - w^2 M has an imaginary part {b}", sys.model().title);
            }
        }
    }

    #[test]
    fn apply_equals_dense_product() {
        let sys = DampedSystem::new(samples::frame_with_joint()).unwrap();
        let n = sys.n();
        let x: Vec<C64> = (0..n).map(|i| C64::new(1.0 + i as f64, 0.5 - i as f64)).collect();
        for name in ["group.joint.mu", "material.steel.E", "mass.tip.m"] {
            let q = sys.model().quantity(name).unwrap();
            let d = sys.derivative(q, 400.0);
            let dense = d.values(sys.assembly());
            let mut expect = vec![C64::new(0.0, 0.0); n];
            let pat = sys.assembly().pattern();
            for c in 0..n {
                for p in pat.col_ptr()[c]..pat.col_ptr()[c + 1] {
                    expect[pat.row_idx()[p]] += dense[p] * x[c];
                }
            }
            let mut sparse = Vec::new();
            d.apply(sys.assembly(), &x, &mut sparse);
            let mut got = vec![C64::new(0.0, 0.0); n];
            for (i, v) in sparse {
                got[i] += v;
            }
            assert!(max_rel_diff(&got, &expect) < 1e-13, "{name}");
        }
    }

    /// A derivative is zero exactly when the parameter touches nothing at
    /// that frequency: the joint group of the frame has no mass terms and
    /// beta = 0, its alpha acts on the joint spring.
    #[test]
    fn a_derivative_that_changes_nothing_is_zero() {
        let sys = DampedSystem::new(samples::frame_with_joint()).unwrap();
        let d = |name: &str| sys.derivative(sys.model().quantity(name).unwrap(), 300.0);
        assert!(d("group.joint.beta").is_zero());
        assert!(d("group.joint.beta").values(sys.assembly()).iter().all(|v| *v == C64::new(0.0, 0.0)));
        assert!(!d("group.joint.alpha").is_zero());
        assert!(!d("mass.tip.m").is_zero());
        // only the terms a quantity changes are listed (the sensitivity
        // assembly loops over them): none for the joint's beta, and the
        // frame's alpha lists its stiffness terms, not its mass terms
        assert!(d("group.joint.beta").terms.is_empty());
        let alpha = d("group.frame.alpha");
        assert!(!alpha.terms.is_empty());
        for &(b, t, c) in &alpha.terms {
            let term = &sys.assembly().blocks()[b].terms()[t];
            assert!(c != C64::new(0.0, 0.0) && term.value() != 0.0, "{:?} term listed", term.kind());
        }
    }

    #[test]
    fn into_model_gives_back_the_model_with_its_current_values() {
        let mut sys = DampedSystem::new(samples::frame_with_joint()).unwrap();
        let q = sys.model().quantity("spring.joint.kr").unwrap();
        sys.set(q, 1234.5).unwrap();
        let model = sys.into_model();
        assert_eq!(model.title, "L-frame with a lossy joint");
        assert_eq!(model.get(q), 1234.5);
    }
}
