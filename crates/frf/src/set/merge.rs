//! Several measured sets on the same lines joined into one, as when a test's
//! channels come in several files (one per reference, or per sensor group).

use super::FrfSet;
use crate::error::{FrfError, MismatchError};

impl FrfSet {
    /// The channels of `sets`, in order, joined into one set on the first
    /// set's lines and in its kind (the others converted to it by powers of
    /// `j w`). Every set must hold the same lines (to 1e-6 relative) and no
    /// channel may appear in two sets.
    ///
    /// Coherence is kept: when any set carries it, the merged set does, and
    /// the channels of a set without it get coherence 1 (what a channel
    /// without coherence is weighted as by the fits).
    pub fn merge_channels(sets: &[FrfSet]) -> Result<FrfSet, FrfError> {
        let Some(first) = sets.first() else {
            return Err(MismatchError::NothingToMerge.into());
        };
        let lines = first.frequencies_hz();
        let mut channels = Vec::with_capacity(sets.iter().map(|s| s.channels().len()).sum());
        let mut seen = std::collections::HashMap::new();
        for (i, set) in sets.iter().enumerate() {
            let same = set.n_freq() == lines.len()
                && set.frequencies_hz().iter().zip(lines).all(|(a, b)| (a - b).abs() <= 1e-6 * b.abs());
            if !same {
                return Err(MismatchError::SetLinesDiffer { set: i, lines: set.n_freq(), first: lines.len() }.into());
            }
            for &c in set.channels() {
                if let Some(&earlier) = seen.get(&c) {
                    return Err(MismatchError::ChannelInTwoSets { channel: c, earlier, set: i }.into());
                }
                seen.insert(c, i);
                channels.push(c);
            }
        }
        if sets.len() == 1 {
            return Ok(first.clone());
        }
        let mut out = FrfSet::zeros(lines.to_vec(), channels, first.kind())?;
        let has_coherence = sets.iter().any(|s| s.coherence.is_some());
        let mut coherence = Vec::new();
        let mut c_out = 0;
        for set in sets {
            let set = if set.kind() == first.kind() { set.clone() } else { set.converted(first.kind()) };
            for c in 0..set.channels().len() {
                out.channel_mut(c_out).copy_from_slice(set.channel(c));
                c_out += 1;
            }
            if has_coherence {
                match &set.coherence {
                    Some(values) => coherence.extend_from_slice(values),
                    None => coherence.resize(coherence.len() + set.values().len(), 1.0),
                }
            }
        }
        if has_coherence {
            out.set_coherence(coherence)?;
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use fe_model::{Dof, DofRef};
    use num_complex::Complex64 as C64;

    use crate::error::{FrfError, MismatchError};
    use crate::set::{Channel, FrfKind, FrfSet};

    fn channel(response: u32, reference: u32) -> Channel {
        Channel::new(DofRef::new(response, Dof::Uy), DofRef::new(reference, Dof::Uy))
    }

    /// A set of one channel with `value * (k + 1)` at line `k`.
    fn one(c: Channel, lines: &[f64], kind: FrfKind, value: C64) -> FrfSet {
        let mut s = FrfSet::zeros(lines.to_vec(), vec![c], kind).unwrap();
        for k in 0..lines.len() {
            s.set(0, k, value * (k as f64 + 1.0));
        }
        s
    }

    #[test]
    fn merged_channels_keep_their_values_in_the_first_sets_kind_and_their_coherence() {
        let lines = [2.0, 5.0, 9.0];
        let a = one(channel(2, 1), &lines, FrfKind::Accelerance, C64::new(1.0, -2.0));
        let mut b = one(channel(3, 1), &lines, FrfKind::Receptance, C64::new(0.5, 0.25));
        b.set_coherence(vec![0.9, 0.8, 0.7]).unwrap();
        let merged = FrfSet::merge_channels(&[a.clone(), b.clone()]).unwrap();
        assert_eq!(merged.kind(), FrfKind::Accelerance);
        assert_eq!(merged.channels(), &[channel(2, 1), channel(3, 1)]);
        assert_eq!(merged.channel(0), a.channel(0));
        // the second set's receptance times -w^2 at each line
        for (k, &f) in lines.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * f;
            let want = b.get(0, k) * -(w * w);
            assert!((merged.get(1, k) - want).norm() <= 1e-12 * want.norm(), "line {k}");
        }
        // the first set had no coherence: 1 there, the second's kept
        assert_eq!(merged.coherence(0), Some(&[1.0, 1.0, 1.0][..]));
        assert_eq!(merged.coherence(1), Some(&[0.9, 0.8, 0.7][..]));
        // without coherence anywhere, none is made up
        let plain = FrfSet::merge_channels(&[a.clone(), one(channel(4, 1), &lines, FrfKind::Mobility, C64::ONE)]);
        assert_eq!(plain.unwrap().coherence(1), None);
        // one set is itself
        assert_eq!(FrfSet::merge_channels(std::slice::from_ref(&b)).unwrap(), b);
    }

    #[test]
    fn sets_on_other_lines_or_with_a_channel_twice_are_refused_by_index() {
        let lines = [2.0, 5.0, 9.0];
        let a = one(channel(2, 1), &lines, FrfKind::Receptance, C64::ONE);
        let other_lines = one(channel(3, 1), &[2.0, 5.0, 9.5], FrfKind::Receptance, C64::ONE);
        let shorter = one(channel(3, 1), &[2.0, 5.0], FrfKind::Receptance, C64::ONE);
        let again = one(channel(2, 1), &lines, FrfKind::Mobility, C64::ONE);
        let near = one(channel(3, 1), &[2.0, 5.0, 9.0 * (1.0 + 5e-7)], FrfKind::Receptance, C64::ONE);
        let b = one(channel(3, 1), &lines, FrfKind::Receptance, C64::ONE);
        let mismatch = |r: Result<FrfSet, FrfError>| match r {
            Err(FrfError::Mismatch(m)) => m,
            other => panic!("expected a mismatch, got {other:?}"),
        };
        assert_eq!(
            mismatch(FrfSet::merge_channels(&[a.clone(), other_lines])),
            MismatchError::SetLinesDiffer { set: 1, lines: 3, first: 3 }
        );
        assert_eq!(
            mismatch(FrfSet::merge_channels(&[a.clone(), shorter])),
            MismatchError::SetLinesDiffer { set: 1, lines: 2, first: 3 }
        );
        let twice = mismatch(FrfSet::merge_channels(&[a.clone(), b, again]));
        assert_eq!(twice, MismatchError::ChannelInTwoSets { channel: channel(2, 1), earlier: 0, set: 2 });
        assert!(twice.to_string().contains("channel H(2:uy,1:uy) of set 2 is in set 0 too"), "{twice}");
        assert_eq!(mismatch(FrfSet::merge_channels(&[])), MismatchError::NothingToMerge);
        // lines within 1e-6 are the same lines
        assert!(FrfSet::merge_channels(&[a, near]).is_ok());
    }
}
