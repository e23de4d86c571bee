//! The error measures of one value (dB, wrapped phase) and of one FRF
//! (FRAC); formulas in the module docs of [`crate::correlation`].

use num_complex::Complex64 as C64;

/// `20 log10(|a| / |x|)`: the model's level above the measurement, in dB.
pub fn db_error(model: C64, measured: C64) -> f64 {
    20.0 * (model.norm() / measured.norm()).log10()
}

/// `arg(a conj(x))` in degrees, wrapped to `(-180, 180]`.
pub fn phase_error_deg(model: C64, measured: C64) -> f64 {
    let d = (model * measured.conj()).arg().to_degrees();
    // `arg` returns [-pi, pi]; map -180 to +180 so the interval is half-open
    if d <= -180.0 { d + 360.0 } else { d }
}

/// The frequency response assurance criterion of two FRFs over the same lines
/// (see the module docs); 0 when either is identically zero.
pub fn frac(measured: &[C64], model: &[C64]) -> f64 {
    let (mut cross, mut xx, mut aa) = (C64::new(0.0, 0.0), 0.0, 0.0);
    for (x, a) in measured.iter().zip(model) {
        cross += x.conj() * a;
        xx += x.norm_sqr();
        aa += a.norm_sqr();
    }
    if xx > 0.0 && aa > 0.0 { cross.norm_sqr() / (xx * aa) } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phase_differences_wrap_to_one_turn() {
        let x = C64::from_polar(1.0, 170f64.to_radians());
        let a = C64::from_polar(1.0, -170f64.to_radians());
        assert!((phase_error_deg(a, x) - 20.0).abs() < 1e-9);
        assert!((phase_error_deg(x, a) + 20.0).abs() < 1e-9);
        // exactly half a turn is +180, never -180
        assert_eq!(phase_error_deg(C64::new(-1.0, 0.0), C64::new(1.0, 0.0)), 180.0);
        assert_eq!(phase_error_deg(C64::new(-1.0, -0.0), C64::new(1.0, 0.0)), 180.0);
    }

    #[test]
    fn frac_of_hand_computed_vectors() {
        let one = C64::new(1.0, 0.0);
        let x = [one, one];
        assert!((frac(&x, &x) - 1.0).abs() < 1e-15);
        assert!((frac(&x, &[one * 3.0, one * 3.0]) - 1.0).abs() < 1e-15);
        // |1 + 2|^2 / (2 * 5)
        assert!((frac(&x, &[one, one * 2.0]) - 0.9).abs() < 1e-15);
        // orthogonal shapes
        assert!(frac(&x, &[one, -one]).abs() < 1e-15);
        assert_eq!(frac(&x, &[C64::new(0.0, 0.0); 2]), 0.0);
    }
}
