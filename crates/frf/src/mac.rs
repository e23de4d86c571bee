//! The modal assurance criterion, one definition for the stabilisation check
//! of the modal estimator and the comparison of modes.

use num_complex::Complex64 as C64;

/// Modal assurance criterion `|a^H b|^2 / ((a^H a)(b^H b))`: 1 for vectors
/// that are complex multiples of each other, 0 for orthogonal ones (or
/// when either is zero).
pub fn mac(a: &[C64], b: &[C64]) -> f64 {
    assert_eq!(a.len(), b.len(), "MAC of vectors of different lengths");
    let dot: C64 = a.iter().zip(b).map(|(x, y)| x.conj() * y).sum();
    let na: f64 = a.iter().map(|x| x.norm_sqr()).sum();
    let nb: f64 = b.iter().map(|x| x.norm_sqr()).sum();
    if na == 0.0 || nb == 0.0 { 0.0 } else { dot.norm_sqr() / (na * nb) }
}
