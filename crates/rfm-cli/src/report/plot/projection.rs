//! How a model in space, or a model of imported matrices, is drawn on the
//! page: the cabinet projection of a point, a 3D beam deformed by its own
//! shape functions, and the node pairs an imported stiffness couples.

use fe_model::imported::ImportedKind;
use fe_model::{Dimension, Dof, Model, NodeId, PerDof};

/// The drawing's direction of the model's z axis: half scale, 30 degrees
/// above the x axis.
pub(super) const RECEDING: (f64, f64) = (0.433_012_701_892_219_3, 0.25);

/// A point of the model on the drawing's plane (model units): `(x, y)` of
/// a planar model, the cabinet projection `(x, y) + z RECEDING` in space.
pub(super) fn project(model: &Model, [x, y, z]: [f64; 3]) -> (f64, f64) {
    match model.dimension() {
        Dimension::Planar => (x, y),
        Dimension::Spatial => (x + RECEDING.0 * z, y + RECEDING.1 * z),
    }
}

/// The pairs of distinct nodes that imported stiffness matrices couple.
pub(super) fn imported_edges(model: &Model) -> Vec<[NodeId; 2]> {
    let mut edges: Vec<[NodeId; 2]> = model
        .imported()
        .iter()
        .filter(|b| b.kind == ImportedKind::Stiffness && b.nodes[0] != b.nodes[1])
        .map(|b| b.nodes)
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// Points along a 3D beam from `p` to `q` with local axes `axes`, deformed
/// by end displacements `up`, `uq` times `amp`: axial displacement linear,
/// each transverse one cubic (Hermite) with its plane's end rotations, as
/// the element's own shape functions ([`fe_model::element::frame3d`]).
pub(super) fn deformed_beam_3d(
    p: [f64; 3],
    q: [f64; 3],
    axes: &[[f64; 3]; 3],
    up: PerDof,
    uq: PerDof,
    amp: f64,
) -> Vec<[f64; 3]> {
    let l = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2)).sqrt();
    // local components of a global vector
    let local = |v: [f64; 3]| axes.map(|e| e[0] * v[0] + e[1] * v[1] + e[2] * v[2]);
    let (t1, t2) = (local([up[Dof::Ux], up[Dof::Uy], up[Dof::Uz]]), local([uq[Dof::Ux], uq[Dof::Uy], uq[Dof::Uz]]));
    let (r1, r2) = (local([up[Dof::Rx], up[Dof::Ry], up[Dof::Rz]]), local([uq[Dof::Rx], uq[Dof::Ry], uq[Dof::Rz]]));
    (0..=16)
        .map(|k| {
            let t = f64::from(k) / 16.0;
            let (h1, h2, h3, h4) = (
                1.0 - 3.0 * t * t + 2.0 * t.powi(3),
                (t - 2.0 * t * t + t.powi(3)) * l,
                3.0 * t * t - 2.0 * t.powi(3),
                (t.powi(3) - t * t) * l,
            );
            let u = t1[0] * (1.0 - t) + t2[0] * t;
            // v with tz = dv/dx, w with ty = -dw/dx
            let v = h1 * t1[1] + h2 * r1[2] + h3 * t2[1] + h4 * r2[2];
            let w = h1 * t1[2] - h2 * r1[1] + h3 * t2[2] - h4 * r2[1];
            [0, 1, 2].map(|c| p[c] + t * (q[c] - p[c]) + amp * (u * axes[0][c] + v * axes[1][c] + w * axes[2][c]))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small rigid rotation `w` about the first node moves every point of
    /// the beam by `w x r`: the shape functions interpolate a rigid motion
    /// exactly, in both bending planes and whatever the section's axes.
    #[test]
    fn a_rigid_rotation_moves_a_3d_beam_as_a_rigid_body() {
        let (p, q) = ([0.1, 0.2, 0.3], [0.7, -0.1, 0.9]);
        let axes = fe_model::element::frame3d::axes(p, q, Some([0.2, 1.0, 0.1]), 0.6).unwrap();
        let w = [0.01, -0.02, 0.015];
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        };
        let r = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
        let uq = cross(w, r);
        let end = PerDof([uq[0], uq[1], uq[2], w[0], w[1], w[2]]);
        let start = PerDof([0.0, 0.0, 0.0, w[0], w[1], w[2]]);
        for (k, at) in deformed_beam_3d(p, q, &axes, start, end, 1.0).iter().enumerate() {
            let t = k as f64 / 16.0;
            let x = [0, 1, 2].map(|c| p[c] + t * r[c]);
            let u = cross(w, [t * r[0], t * r[1], t * r[2]]);
            for c in 0..3 {
                assert!((at[c] - (x[c] + u[c])).abs() < 1e-15, "point {k}: {at:?}");
            }
        }
    }
}
