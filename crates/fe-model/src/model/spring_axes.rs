//! Springs in their own axes (3D models): a spring's six stiffnesses act
//! along and about a local x, y and z, given as a local x axis and a vector
//! in the local x-y plane, the convention of Abaqus's `*ORIENTATION` and of
//! Nastran's `CBUSH` orientation vector.
//!
//! With `R` the rotation whose rows are the local axes in global
//! components, the spring's stiffness over a node's translations is `R^T
//! diag(kx, ky, kz) R`, and over its rotations `R^T diag(krx, kry, krz) R`:
//! each stiffness `k_d` multiplies the unit matrix `r r^T` of its local
//! axis `r` (row `d` of `R`), so that `spring.<name>.kx` keeps meaning the
//! stiffness along the local x axis and its derivative stays one term.

use nalgebra::Vector3;

use super::{Model, Spring};
use crate::dof::{Dimension, Dof};
use crate::element::frame3d::PARALLEL;
use crate::error::ModelError;

/// Why a spring's axes cannot be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpringAxesError {
    /// The local x axis is zero or not finite.
    XAxis,
    /// The vector in the local x-y plane is zero or not finite.
    XyVector,
    /// The vector in the x-y plane lies along the x axis: it does not say
    /// where y points.
    Parallel,
}

/// The local axes `[x, y, z]` (rows, unit, right-handed) of a spring from
/// its local x axis and a vector `xy` in its local x-y plane: `x` is the
/// axis made unit, `z = x × xy` made unit, `y = z × x`.
pub fn spring_axes(x: [f64; 3], xy: [f64; 3]) -> Result<[[f64; 3]; 3], SpringAxesError> {
    let (x, v) = (Vector3::from(x), Vector3::from(xy));
    let (nx, nv) = (x.norm(), v.norm());
    if !(nx > 0.0 && nx.is_finite()) {
        return Err(SpringAxesError::XAxis);
    }
    if !(nv > 0.0 && nv.is_finite()) {
        return Err(SpringAxesError::XyVector);
    }
    let x = x / nx;
    let z = x.cross(&v);
    if z.norm() <= PARALLEL * nv {
        return Err(SpringAxesError::Parallel);
    }
    let z = z.normalize();
    let y = z.cross(&x);
    Ok([x.into(), y.into(), z.into()])
}

impl Spring {
    /// The global DOFs (of one node) that the spring's stiffness `d` acts
    /// along or about, with the components of its axis: `d` itself with 1
    /// in global axes, else the three translations (or rotations) with the
    /// components of the local axis of `d`.
    pub fn direction(&self, dim: Dimension, d: Dof) -> Vec<(Dof, f64)> {
        match self.axes {
            None => vec![(d, 1.0)],
            Some(r) => {
                let global = if d.is_translation() { dim.translations() } else { dim.rotations() };
                global.iter().map(|&g| (g, r[d.axis()][g.axis()])).filter(|&(_, c)| c != 0.0).collect()
            }
        }
    }
}

impl Model {
    /// Turns spring `spring`'s stiffnesses to its own axes: `x` its local x
    /// axis, `xy` a vector in its local x-y plane (see [`spring_axes`]).
    /// Only a spring of a 3D model has axes of its own.
    pub fn orient_spring(&mut self, spring: usize, x: [f64; 3], xy: [f64; 3]) -> Result<(), ModelError> {
        let what = format!("spring `{}`", self.springs[spring].name);
        if self.dimension == Dimension::Planar {
            return Err(ModelError::Invalid {
                what,
                reason: "has axes of its own, which only a spring of a 3D model has (`[model] dimension = 3`)".into(),
            });
        }
        let reason = match spring_axes(x, xy) {
            Ok(axes) => {
                self.springs[spring].axes = Some(axes);
                return Ok(());
            }
            Err(SpringAxesError::XAxis) => format!("has the local x axis {x:?}, which is zero or not finite"),
            Err(SpringAxesError::XyVector) => {
                format!("has the x-y plane vector {xy:?}, which is zero or not finite")
            }
            Err(SpringAxesError::Parallel) => format!(
                "has the x-y plane vector {xy:?} along its local x axis {x:?}: give a vector across the x axis, \
                 in the plane of the local x and y axes"
            ),
        };
        Err(ModelError::Invalid { what, reason })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_are_right_handed_and_orthonormal_and_bad_vectors_are_refused() {
        let [x, y, z] = spring_axes([1.0, 1.0, 0.0], [0.0, 0.0, 2.0]).unwrap();
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(&b).all(|(p, q)| (p - q).abs() < 1e-15);
        assert!(close(x, [s, s, 0.0]) && close(y, [0.0, 0.0, 1.0]) && close(z, [s, -s, 0.0]), "{x:?} {y:?} {z:?}");
        assert_eq!(spring_axes([0.0; 3], [0.0, 1.0, 0.0]), Err(SpringAxesError::XAxis));
        assert_eq!(spring_axes([f64::NAN, 1.0, 0.0], [0.0, 1.0, 0.0]), Err(SpringAxesError::XAxis));
        assert_eq!(spring_axes([1.0, 0.0, 0.0], [0.0; 3]), Err(SpringAxesError::XyVector));
        assert_eq!(spring_axes([1.0, 2.0, 3.0], [-2.0, -4.0, -6.0]), Err(SpringAxesError::Parallel));
    }
}
