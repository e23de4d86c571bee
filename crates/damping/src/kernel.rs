//! The exponential damping kernel of one group in the frequency domain.
//!
//! Time domain: `G_g(t) = mu_g exp(-mu_g t) C_g`. Frequency domain (paper eq. 5):
//!
//! ```text
//! h_g(w) = mu_g / (mu_g + j w)          (h = 1 when mu_g = infinity: viscous)
//! Z(w)   = sum_g [ (1 + j w h_g alpha_g) K_g + (-w^2 + j w h_g beta_g) M_g ]
//! ```
//!
//! so that each group contributes a complex coefficient times its stiffness
//! terms and another times its mass terms. A group imported with a viscous
//! damping matrix `C` (times the group's damping factor, which its terms
//! carry) adds `j w C` besides: the coefficient `j w` on its damping terms.

use fe_model::{Group, MatrixKind};
use num_complex::Complex64 as C64;

const J: C64 = C64 { re: 0.0, im: 1.0 };

/// `h(w) = mu / (mu + j w)`, and 1 for a viscous kernel (`mu = None`).
pub fn relaxation_factor(mu: Option<f64>, omega: f64) -> C64 {
    match mu {
        None => C64::new(1.0, 0.0),
        Some(mu) => C64::new(mu, 0.0) / C64::new(mu, omega),
    }
}

/// The two complex coefficients of a group at one angular frequency.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroupCoefficients {
    /// Multiplies the group's stiffness terms: `1 + j w h alpha`.
    pub stiffness: C64,
    /// Multiplies the group's mass terms: `-w^2 + j w h beta`.
    pub mass: C64,
    /// Multiplies the group's (imported, viscous) damping terms: `j w`.
    pub damping: C64,
}

impl GroupCoefficients {
    /// Coefficients of group `g` at angular frequency `omega` (rad/s).
    pub fn new(g: &Group, omega: f64) -> Self {
        let jwh = J * omega * relaxation_factor(g.mu, omega);
        GroupCoefficients { stiffness: 1.0 + jwh * g.alpha, mass: -omega * omega + jwh * g.beta, damping: J * omega }
    }

    /// The coefficient for a term of the given kind.
    pub fn of(&self, kind: MatrixKind) -> C64 {
        match kind {
            MatrixKind::Stiffness => self.stiffness,
            MatrixKind::Mass => self.mass,
            MatrixKind::Damping => self.damping,
        }
    }
}

/// The place of a matrix kind's coefficient among a group's (stiffness,
/// mass, damping): the slot `3 group + kind_slot(kind)` of a table of every
/// group's coefficients, as `Z(w)` and the sensitivity assembly keep them.
pub fn kind_slot(kind: MatrixKind) -> u32 {
    match kind {
        MatrixKind::Stiffness => 0,
        MatrixKind::Mass => 1,
        MatrixKind::Damping => 2,
    }
}

/// Coefficients of the damping-parameter derivatives of one group, already
/// multiplied by the parameter (relative form `(dZ/dp) p`), per matrix kind.
/// None of alpha, beta and mu acts on an imported damping matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DampingDerivative {
    /// On stiffness terms.
    pub stiffness: C64,
    /// On mass terms.
    pub mass: C64,
}

impl DampingDerivative {
    /// The coefficient for a term of the given kind (zero on damping terms).
    pub fn of(&self, kind: MatrixKind) -> C64 {
        match kind {
            MatrixKind::Stiffness => self.stiffness,
            MatrixKind::Mass => self.mass,
            MatrixKind::Damping => C64::new(0.0, 0.0),
        }
    }
}

/// `(dZ/dalpha) alpha = j w h alpha K_g`.
pub fn d_alpha(g: &Group, omega: f64) -> DampingDerivative {
    let c = J * omega * relaxation_factor(g.mu, omega) * g.alpha;
    DampingDerivative { stiffness: c, mass: C64::new(0.0, 0.0) }
}

/// `(dZ/dbeta) beta = j w h beta M_g`.
pub fn d_beta(g: &Group, omega: f64) -> DampingDerivative {
    let c = J * omega * relaxation_factor(g.mu, omega) * g.beta;
    DampingDerivative { stiffness: C64::new(0.0, 0.0), mass: c }
}

/// `(dZ/dmu) mu = j w [j w mu / (mu + j w)^2] C_g` (zero for a viscous group,
/// the limit as `mu` goes to infinity).
pub fn d_mu(g: &Group, omega: f64) -> DampingDerivative {
    match g.mu {
        None => DampingDerivative { stiffness: C64::new(0.0, 0.0), mass: C64::new(0.0, 0.0) },
        Some(mu) => {
            let den = C64::new(mu, omega);
            let c = J * omega * (J * omega * mu) / (den * den);
            DampingDerivative { stiffness: c * g.alpha, mass: c * g.beta }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn kernel_tends_to_viscous_as_mu_grows() {
        let w = 2.0 * std::f64::consts::PI * 300.0;
        let h = relaxation_factor(Some(1e12), w);
        assert!((h - 1.0).norm() < 1e-8);
        // a slow kernel behaves like a stiffness: j w h -> mu at high frequency
        let mu = 5.0;
        let jwh = J * w * relaxation_factor(Some(mu), w);
        assert_relative_eq!(jwh.re, mu, max_relative = 1e-3);
    }

    #[test]
    fn mu_derivative_matches_finite_difference() {
        let mut g = Group::new("g").rayleigh(2e-4, 0.3).relaxation(400.0);
        let w = 700.0;
        let d = d_mu(&g, w);
        let mu = 400.0;
        let step = mu * 1e-6;
        g.mu = Some(mu + step);
        let plus = GroupCoefficients::new(&g, w);
        g.mu = Some(mu - step);
        let minus = GroupCoefficients::new(&g, w);
        let fd_k = (plus.stiffness - minus.stiffness) / (2.0 * step) * mu;
        let fd_m = (plus.mass - minus.mass) / (2.0 * step) * mu;
        assert!((fd_k - d.stiffness).norm() <= 1e-7 * d.stiffness.norm());
        assert!((fd_m - d.mass).norm() <= 1e-7 * d.mass.norm());
    }
}
