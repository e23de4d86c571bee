//! `Z(w)` laid out for evaluation at many lines, with each distinct unit
//! matrix stored once.

use std::hash::Hasher;

use damping::{DampedSystem, GroupCoefficients};
use fe_model::MatrixKind;
use num_complex::Complex64 as C64;

use super::ZERO;
use super::hash::{FxHasher, FxMap};

/// `Z(w)` laid out for fast evaluation at many frequencies.
///
/// [`DampedSystem::z_values_into`] walks every element's terms, unit
/// matrices and positions, each in its own heap allocation, at every
/// frequency. This is the same walk over compact arrays (positions as `u32`,
/// each distinct unit matrix stored once), with the same operations in the
/// same order, so it gives *bitwise* the same values: model FRFs from the
/// sensitivity assembly and from [`frf::synthesize_with`] then agree exactly,
/// which the response function method's step control relies on near
/// convergence. Made once per [`assemble`] call (the parameters may have
/// changed since the last).
pub(super) struct ZCache {
    /// Per block: `(first position, number of local entries, first term, end of terms)`.
    pub(super) blocks: Vec<(u32, u32, u32, u32)>,
    pub(super) positions: Vec<u32>,
    /// Per non-zero term: `(slot, value, unit offset)`; the slot is `3 g` for
    /// group `g`'s stiffness terms, `3 g + 1` for its mass terms and `3 g + 2`
    /// for its (imported) damping terms.
    pub(super) terms: Vec<(u32, f64, u32)>,
    pub(super) units: Vec<f64>,
}

impl ZCache {
    pub(super) fn new(sys: &DampedSystem) -> Self {
        let a = sys.assembly();
        let mut units = UnitStore::default();
        let (mut blocks, mut positions, mut terms) = (Vec::with_capacity(a.blocks().len()), Vec::new(), Vec::new());
        for b in a.blocks() {
            let p0 = positions.len() as u32;
            positions.extend(b.positions().iter().map(|&p| p as u32));
            let t0 = terms.len() as u32;
            // Assembly::accumulate skips terms whose value is zero
            for t in b.terms().iter().filter(|t| t.value() != 0.0) {
                let slot = 3 * b.group() as u32 + kind_index(t.kind());
                terms.push((slot, t.value(), units.offset_of(t.unit())));
            }
            blocks.push((p0, b.positions().len() as u32, t0, terms.len() as u32));
        }
        ZCache { blocks, positions, terms, units: units.values }
    }

    /// `Z(w)` into `out`, given each group's coefficients at `w`: the loop of
    /// `Assembly::accumulate` with the coefficients of `z_values_into`.
    pub(super) fn values_into(&self, coefs: &[GroupCoefficients], out: &mut [C64]) {
        let by_slot: Vec<C64> = coefs.iter().flat_map(|c| [c.stiffness, c.mass, c.damping]).collect();
        out.fill(ZERO);
        for &(p0, len, t0, t1) in &self.blocks {
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

/// 0, 1, 2 for a stiffness, mass or damping term: its place among its
/// group's coefficients.
pub(super) fn kind_index(kind: MatrixKind) -> u32 {
    match kind {
        MatrixKind::Stiffness => 0,
        MatrixKind::Mass => 1,
        MatrixKind::Damping => 2,
    }
}

/// Unit matrices stored once each: identical elements (the common case in
/// a mesh) share one copy, so that the hot loops read them from cache.
#[derive(Default)]
pub(super) struct UnitStore {
    pub(super) values: Vec<f64>,
    /// Hash of a matrix's bits to the offset of the last one stored with it.
    pub(super) by_hash: FxMap<u64, u32>,
}

impl UnitStore {
    /// Offset in `values` of a matrix equal to `unit` (bit for bit), stored
    /// now if there is none.
    pub(super) fn offset_of(&mut self, unit: &[f64]) -> u32 {
        // a sample of the entries is enough for a key: equality is checked
        let mut h = FxHasher::default();
        h.write_usize(unit.len());
        for u in unit.iter().step_by(5) {
            h.write_u64(u.to_bits());
        }
        let key = h.finish();
        if let Some(&at) = self.by_hash.get(&key) {
            let stored = &self.values[at as usize..at as usize + unit.len()];
            if stored.iter().zip(unit).all(|(a, b)| a.to_bits() == b.to_bits()) {
                return at;
            }
        }
        let at = self.values.len() as u32;
        self.values.extend_from_slice(unit);
        self.by_hash.insert(key, at);
        at
    }
}
