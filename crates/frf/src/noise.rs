//! Seeded measurement noise for synthesised FRFs.
//!
//! Model, for each channel `c` and line `k`:
//!
//! ```text
//! H_noisy = H (1 + s e1) + f * rms_c * e2
//! ```
//!
//! with `e1`, `e2` independent complex Gaussian numbers of unit mean square
//! (real and imaginary parts each N(0, 1/2)), `s` the relative level (0.06 is
//! "6 % noise": the RMS of the relative error is 6 %), `f` the additive floor
//! relative to `rms_c`, the RMS magnitude of channel `c`. The generator is
//! ChaCha8 seeded with `seed`, so the same seed gives the same data on every
//! platform.

use num_complex::Complex64 as C64;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::set::FrfSet;

/// Noise model parameters; see the module docs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseModel {
    /// Relative (multiplicative) level.
    pub relative: f64,
    /// Additive floor relative to each channel's RMS magnitude.
    pub floor: f64,
    /// Random seed.
    pub seed: u64,
}

impl NoiseModel {
    /// Multiplicative noise only.
    pub fn relative(level: f64, seed: u64) -> Self {
        NoiseModel { relative: level, floor: 0.0, seed }
    }

    /// True when the model adds nothing.
    pub fn is_zero(&self) -> bool {
        self.relative == 0.0 && self.floor == 0.0
    }

    /// Adds noise to every value of a set, in channel-major order.
    pub fn apply(&self, set: &mut FrfSet) {
        if self.is_zero() {
            return;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut gauss = || {
            let re: f64 = StandardNormal.sample(&mut rng);
            let im: f64 = StandardNormal.sample(&mut rng);
            C64::new(re, im) * std::f64::consts::FRAC_1_SQRT_2
        };
        for c in 0..set.channels().len() {
            let values = set.channel_mut(c);
            let rms = (values.iter().map(|v| v.norm_sqr()).sum::<f64>() / values.len().max(1) as f64).sqrt();
            for v in values.iter_mut() {
                let e1 = gauss();
                let e2 = gauss();
                *v = *v * (1.0 + self.relative * e1) + self.floor * rms * e2;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::set::{Channel, FrfKind};
    use fe_model::{Dof, DofRef};

    fn ones(n: usize) -> FrfSet {
        let c = Channel::new(DofRef::new(2, Dof::Uy), DofRef::new(2, Dof::Uy));
        let f: Vec<f64> = (1..=n).map(|i| i as f64).collect();
        let mut s = FrfSet::zeros(f, vec![c], FrfKind::Receptance).unwrap();
        s.channel_mut(0).fill(C64::new(1.0, 0.0));
        s
    }

    #[test]
    fn relative_level_is_the_rms_of_the_relative_error_and_seeds_repeat() {
        let mut a = ones(20000);
        NoiseModel::relative(0.06, 7).apply(&mut a);
        let rms = (a.channel(0).iter().map(|v| (v - 1.0).norm_sqr()).sum::<f64>() / 20000.0).sqrt();
        assert!((rms - 0.06).abs() < 0.002, "rms relative error {rms}");
        let mut b = ones(20000);
        NoiseModel::relative(0.06, 7).apply(&mut b);
        assert_eq!(a, b);
        let mut c = ones(20000);
        NoiseModel::relative(0.06, 8).apply(&mut c);
        assert_ne!(a, c);
    }
}
