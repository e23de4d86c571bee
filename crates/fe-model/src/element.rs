//! Element matrices in global coordinates.
//!
//! Frame element (Euler-Bernoulli, axial + bending), local DOFs
//! `[u1, v1, th1, u2, v2, th2]`, length `L`:
//!
//! - axial stiffness `EA/L [1 -1; -1 1]`, consistent axial mass `rho A L/6 [2 1; 1 2]`;
//! - bending stiffness `EI/L^3 [12 6L -12 6L; 6L 4L^2 -6L 2L^2; ...]` and the
//!   consistent bending mass `rho A L/420 [156 22L 54 -13L; ...]`;
//! - global matrices `T^T k T` with `T` the rotation by the element angle.
//!
//! The routines return *unit* matrices: stiffness for `E = 1`, mass for
//! `rho = 1`, so that a physical value multiplies them (see [`crate::assembly`]).
//!
//! This file is the planar element; [`frame3d`] is the element of a frame
//! in space.

use nalgebra::{DMatrix, SMatrix};

use crate::dof::Dimension;
use crate::model::Model;

pub mod frame3d;

/// 6x6 element matrix.
pub type Mat6 = SMatrix<f64, 6, 6>;

fn rotation(c: f64, s: f64) -> Mat6 {
    let mut t = Mat6::zeros();
    for n in 0..2 {
        let o = 3 * n;
        t[(o, o)] = c;
        t[(o, o + 1)] = s;
        t[(o + 1, o)] = -s;
        t[(o + 1, o + 1)] = c;
        t[(o + 2, o + 2)] = 1.0;
    }
    t
}

/// Local frame stiffness for `E = 1`.
pub fn frame_stiffness_local(area: f64, inertia: f64, l: f64) -> Mat6 {
    let mut k = Mat6::zeros();
    let ea = area / l;
    k[(0, 0)] = ea;
    k[(0, 3)] = -ea;
    k[(3, 0)] = -ea;
    k[(3, 3)] = ea;
    let ei = inertia / l.powi(3);
    let b = [
        [12.0, 6.0 * l, -12.0, 6.0 * l],
        [6.0 * l, 4.0 * l * l, -6.0 * l, 2.0 * l * l],
        [-12.0, -6.0 * l, 12.0, -6.0 * l],
        [6.0 * l, 2.0 * l * l, -6.0 * l, 4.0 * l * l],
    ];
    let idx = [1, 2, 4, 5];
    for (r, &i) in idx.iter().enumerate() {
        for (c, &j) in idx.iter().enumerate() {
            k[(i, j)] = ei * b[r][c];
        }
    }
    k
}

/// Local consistent frame mass for `rho = 1`.
pub fn frame_mass_local(area: f64, l: f64) -> Mat6 {
    let mut m = Mat6::zeros();
    let a = area * l / 6.0;
    m[(0, 0)] = 2.0 * a;
    m[(0, 3)] = a;
    m[(3, 0)] = a;
    m[(3, 3)] = 2.0 * a;
    let t = area * l / 420.0;
    let b = [
        [156.0, 22.0 * l, 54.0, -13.0 * l],
        [22.0 * l, 4.0 * l * l, 13.0 * l, -3.0 * l * l],
        [54.0, 13.0 * l, 156.0, -22.0 * l],
        [-13.0 * l, -3.0 * l * l, -22.0 * l, 4.0 * l * l],
    ];
    let idx = [1, 2, 4, 5];
    for (r, &i) in idx.iter().enumerate() {
        for (c, &j) in idx.iter().enumerate() {
            m[(i, j)] = t * b[r][c];
        }
    }
    m
}

/// Local lumped transverse mass for a unit mass per length: `L/2` on each
/// end's transverse DOF (`v1`, `v2`).
pub fn transverse_lumped_mass_local(l: f64) -> Mat6 {
    let mut m = Mat6::zeros();
    m[(1, 1)] = l / 2.0;
    m[(4, 4)] = l / 2.0;
    m
}

/// Rotates a local 6x6 matrix to global axes, for an element with direction
/// cosines `(c, s)`.
pub fn to_global(local: &Mat6, c: f64, s: f64) -> Mat6 {
    let t = rotation(c, s);
    t.transpose() * local * t
}

/// Frame stiffness in global axes for `E = 1`.
pub fn frame_stiffness(area: f64, inertia: f64, l: f64, c: f64, s: f64) -> Mat6 {
    to_global(&frame_stiffness_local(area, inertia, l), c, s)
}

/// Consistent frame mass in global axes for `rho = 1`.
pub fn frame_mass(area: f64, l: f64, c: f64, s: f64) -> Mat6 {
    to_global(&frame_mass_local(area, l), c, s)
}

/// Lumped transverse mass in global axes for a unit mass per length.
pub fn transverse_lumped_mass(l: f64, c: f64, s: f64) -> Mat6 {
    to_global(&transverse_lumped_mass_local(l), c, s)
}

/// The unit matrices of beam `beam` of `model` in global axes, over the
/// DOFs of its two end nodes (the model's DOFs per node, first node
/// first): stiffness for `E = 1` (in 3D with the torsion `G J / E`),
/// consistent mass for `rho = 1`, and the lumped transverse mass of a unit
/// added mass per length.
pub fn beam_units(model: &Model, beam: usize) -> [DMatrix<f64>; 3] {
    let b = &model.beams()[beam];
    let sec = &model.sections()[b.section];
    match model.dimension() {
        Dimension::Planar => {
            let (l, c, s) = model.beam_geometry(beam);
            [
                frame_stiffness(sec.area, sec.inertia, l, c, s),
                frame_mass(sec.area, l, c, s),
                transverse_lumped_mass(l, c, s),
            ]
            .map(|m| DMatrix::from_iterator(6, 6, m.iter().copied()))
        }
        Dimension::Spatial => {
            let (l, _) = model.beam_axis(beam);
            let axes = model.beam_axes(beam);
            let g = model.materials()[b.material].shear_ratio();
            [
                frame3d::stiffness_local(sec.area, sec.iy, sec.inertia, sec.torsion, g, l),
                frame3d::mass_local(sec.area, sec.polar(), l),
                frame3d::transverse_lumped_mass_local(l),
            ]
            .map(|local| {
                let m = frame3d::to_global(&local, &axes);
                DMatrix::from_iterator(12, 12, m.iter().copied())
            })
        }
    }
}

/// The unit stiffness of beam `beam` of `model` (as in [`beam_units`])
/// split into its axial part (in 3D with the torsion) and its bending part;
/// their sum is the unit stiffness. The element matrices are linear in the
/// area, the second moments and the torsion constant, so each part is the
/// element's matrix with the other's section properties set to zero.
pub fn beam_stiffness_parts(model: &Model, beam: usize) -> [DMatrix<f64>; 2] {
    let b = &model.beams()[beam];
    let sec = &model.sections()[b.section];
    match model.dimension() {
        Dimension::Planar => {
            let (l, c, s) = model.beam_geometry(beam);
            [frame_stiffness(sec.area, 0.0, l, c, s), frame_stiffness(0.0, sec.inertia, l, c, s)]
                .map(|m| DMatrix::from_iterator(6, 6, m.iter().copied()))
        }
        Dimension::Spatial => {
            let (l, _) = model.beam_axis(beam);
            let axes = model.beam_axes(beam);
            let g = model.materials()[b.material].shear_ratio();
            [
                frame3d::stiffness_local(sec.area, 0.0, 0.0, sec.torsion, g, l),
                frame3d::stiffness_local(0.0, sec.iy, sec.inertia, 0.0, g, l),
            ]
            .map(|local| {
                let m = frame3d::to_global(&local, &axes);
                DMatrix::from_iterator(12, 12, m.iter().copied())
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn element_matrices_are_symmetric_after_rotation() {
        let k = frame_stiffness(0.01, 2e-5, 0.7, 0.6, 0.8);
        let m = frame_mass(0.01, 0.7, 0.6, 0.8);
        assert_relative_eq!(k, k.transpose(), epsilon = 1e-12);
        assert_relative_eq!(m, m.transpose(), epsilon = 1e-15);
    }

    #[test]
    fn stiffness_has_exactly_three_rigid_body_modes() {
        let (c, s) = (0.28f64.cos(), 0.28f64.sin());
        let k = frame_stiffness(0.01, 2e-5, 0.7, c, s);
        let (x1, y1, x2, y2) = (0.0, 0.0, 0.7 * c, 0.7 * s);
        // translations in x and y, and a rotation about the origin
        let modes = [[1.0, 0.0, 0.0, 1.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0, 1.0, 0.0], [-y1, x1, 1.0, -y2, x2, 1.0]];
        for mode in modes {
            let v = nalgebra::SVector::<f64, 6>::from_row_slice(&mode);
            assert!((k * v).norm() < 1e-12 * k.norm(), "rigid mode {mode:?} strains the element");
        }
        let eig = k.symmetric_eigen();
        let zero = eig.eigenvalues.iter().filter(|e| e.abs() < 1e-10 * k.norm()).count();
        assert_eq!(zero, 3);
        assert!(eig.eigenvalues.iter().all(|&e| e > -1e-10 * k.norm()));
    }

    #[test]
    fn consistent_mass_sums_to_element_mass_in_each_translation() {
        let (area, l) = (0.02, 1.3);
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let m = frame_mass(area, l, c, s);
        let ex = nalgebra::SVector::<f64, 6>::from_row_slice(&[1.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
        let ey = nalgebra::SVector::<f64, 6>::from_row_slice(&[0.0, 1.0, 0.0, 0.0, 1.0, 0.0]);
        assert_relative_eq!((ex.transpose() * m * ex)[0], area * l, max_relative = 1e-14);
        assert_relative_eq!((ey.transpose() * m * ey)[0], area * l, max_relative = 1e-14);
        assert!(m.symmetric_eigen().eigenvalues.iter().all(|&e| e > 0.0));
    }
}
