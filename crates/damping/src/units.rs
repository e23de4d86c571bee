//! Unit matrices stored once each: the identical elements of a mesh share
//! one copy, so that the loops over every term of `Z(w)` (the compact
//! layout of [`DampedSystem`](crate::DampedSystem)) and of the parameters'
//! derivatives (the sensitivity assembly's term table) read them from
//! cache.

use std::hash::Hasher;

use rustc_hash::{FxHashMap, FxHasher};

/// Unit matrices (an assembly term's entries per unit value), each distinct
/// one stored once, bit for bit, in one array.
#[derive(Debug, Default)]
pub struct UnitStore {
    values: Vec<f64>,
    /// Hash of a matrix's bits to the offset of the last one stored with it.
    by_hash: FxHashMap<u64, u32>,
}

impl UnitStore {
    /// The offset in [`UnitStore::values`] of a matrix equal to `unit` bit
    /// for bit, stored now if there is none; `None` when the store would
    /// pass `u32` offsets.
    pub fn offset_of(&mut self, unit: &[f64]) -> Option<u32> {
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
                return Some(at);
            }
        }
        let at = u32::try_from(self.values.len()).ok()?;
        u32::try_from(self.values.len() + unit.len()).ok()?;
        self.values.extend_from_slice(unit);
        self.by_hash.insert(key, at);
        Some(at)
    }

    /// The stored matrices, one after another.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The stored matrices, one after another, without the index.
    pub fn into_values(self) -> Vec<f64> {
        self.values
    }
}

#[cfg(test)]
mod tests {
    use super::UnitStore;

    #[test]
    fn equal_matrices_share_one_copy_and_different_ones_do_not() {
        let mut s = UnitStore::default();
        let a = [1.0, -2.0, 0.5, 0.0, 3.0, 4.0];
        // equal to `a` at every entry the key samples (0 and 5), not at 1
        let b = [1.0, -2.5, 0.5, 0.0, 3.0, 4.0];
        let c = [1.0, -2.0, 0.5];
        assert_eq!(s.offset_of(&a), Some(0));
        assert_eq!(s.offset_of(&b), Some(6));
        assert_eq!(s.offset_of(&c), Some(12));
        assert_eq!(s.offset_of(&b), Some(6));
        // `a` again: its key now leads to `b`, so it is stored again, never confused
        let again = s.offset_of(&a).unwrap() as usize;
        assert_eq!(&s.values()[again..again + 6], &a);
        // -0.0 is not 0.0 bit for bit
        let z = s.offset_of(&[0.0]).unwrap();
        assert_ne!(s.offset_of(&[-0.0]).unwrap(), z);
        assert_eq!(s.into_values().len(), 6 + 6 + 3 + 6 + 1 + 1);
    }
}
