//! Unit matrices stored once each, for the term table.

use std::hash::Hasher;

use super::hash::{FxHasher, FxMap};

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
