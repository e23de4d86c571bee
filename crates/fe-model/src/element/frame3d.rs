//! The 3D Euler-Bernoulli frame element: axial, torsion, and bending in
//! the two principal planes of its section, with consistent mass.
//!
//! Local DOFs, length `L`, in the element's own axes (`x` from the first
//! node to the second, `y` and `z` the principal axes of the section):
//!
//! ```text
//! [u1, v1, w1, tx1, ty1, tz1,  u2, v2, w2, tx2, ty2, tz2]
//! ```
//!
//! - axial (`u`): `EA/L [1 -1; -1 1]`, mass `rho A L/6 [2 1; 1 2]`;
//! - torsion (`tx`): `GJ/L [1 -1; -1 1]`, mass `rho Ip L/6 [2 1; 1 2]` with
//!   the polar moment `Ip = Iy + Iz` (the section's rotary inertia about
//!   the axis, which equals `J` only for a circle);
//! - bending in the x-y plane (`v`, `tz = dv/dx`) with `Iz`, and in the x-z
//!   plane (`w`, `ty = -dw/dx`) with `Iy`: the planar element's Hermite
//!   matrices, with the sign of the rotation coupling terms flipped in the
//!   x-z plane because a positive `ty` turns `z` towards `x`.
//!
//! As the planar element, no shear deformation and no rotary inertia of
//! bending. The global matrices are `T^T k T` with `T` four copies of the
//! rotation `R` whose rows are the local axes in global components
//! ([`axes`]). Routines return *unit* matrices (`E = 1`, `rho = 1`); the
//! shear modulus enters as the ratio `G/E = 1 / (2 (1 + nu))`.

use nalgebra::{SMatrix, Vector3};

/// 12x12 element matrix.
pub type Mat12 = SMatrix<f64, 12, 12>;

/// Sine of the angle below which a beam counts as parallel to the reference
/// direction of its section: the default reference then changes from
/// global z to global y, and a given reference is refused.
pub const PARALLEL: f64 = 1e-6;

/// Why the axes of a beam cannot be made.
#[derive(Clone, Debug, PartialEq)]
pub enum AxesError {
    /// The beam has no length.
    ZeroLength,
    /// The orientation vector is zero, not finite, or along the beam.
    Reference,
}

/// The local axes `[x, y, z]` (rows, unit, right-handed) of a beam from
/// `p` to `q`.
///
/// `reference` is the approximate direction of the section's local `z` (the
/// axis about which `Iz` bends the beam in its x-y plane): `z` is its part
/// perpendicular to the beam, `y = z x x`. Without one, `z` is global z made
/// perpendicular to the beam (so that a beam in the x-y plane bends in that
/// plane with `Iz`, as in a planar model), or global y for a beam along z.
/// `angle` (radians) then turns `y` and `z` about `x` (right-hand rule).
pub fn axes(p: [f64; 3], q: [f64; 3], reference: Option<[f64; 3]>, angle: f64) -> Result<[[f64; 3]; 3], AxesError> {
    let d = Vector3::new(q[0] - p[0], q[1] - p[1], q[2] - p[2]);
    let l = d.norm();
    if !(l > 0.0 && l.is_finite()) {
        return Err(AxesError::ZeroLength);
    }
    let x = d / l;
    let r = match reference {
        Some(r) => {
            let r = Vector3::from(r);
            let n = r.norm();
            if !(n > 0.0 && n.is_finite()) || x.cross(&r).norm() <= PARALLEL * n {
                return Err(AxesError::Reference);
            }
            r / n
        }
        None if x.cross(&Vector3::z()).norm() > PARALLEL => Vector3::z(),
        None => Vector3::y(),
    };
    let z0 = (r - x * x.dot(&r)).normalize();
    let y0 = z0.cross(&x);
    let (s, c) = angle.sin_cos();
    let y = y0 * c + z0 * s;
    let z = z0 * c - y0 * s;
    Ok([x.into(), y.into(), z.into()])
}

/// Writes `scale * b` into the rows and columns `idx` of `k`.
fn put(k: &mut Mat12, idx: [usize; 4], scale: f64, b: [[f64; 4]; 4]) {
    for (r, &i) in idx.iter().enumerate() {
        for (c, &j) in idx.iter().enumerate() {
            k[(i, j)] = scale * b[r][c];
        }
    }
}

/// Writes the two-node bar matrix `scale [a b; b a]` on DOFs `i` and `j`.
fn put_bar(k: &mut Mat12, i: usize, j: usize, scale: f64, a: f64, b: f64) {
    k[(i, i)] = scale * a;
    k[(j, j)] = scale * a;
    k[(i, j)] = scale * b;
    k[(j, i)] = scale * b;
}

/// Local stiffness for `E = 1`: section area, second moments `iy`, `iz`,
/// torsion constant `j`, shear-to-Young's ratio `g`, length `l`.
pub fn stiffness_local(area: f64, iy: f64, iz: f64, j: f64, g: f64, l: f64) -> Mat12 {
    let mut k = Mat12::zeros();
    put_bar(&mut k, 0, 6, area / l, 1.0, -1.0);
    put_bar(&mut k, 3, 9, g * j / l, 1.0, -1.0);
    let (l2, l3) = (l * l, l * l * l);
    // x-y plane: v and tz = dv/dx
    put(
        &mut k,
        [1, 5, 7, 11],
        iz / l3,
        [
            [12.0, 6.0 * l, -12.0, 6.0 * l],
            [6.0 * l, 4.0 * l2, -6.0 * l, 2.0 * l2],
            [-12.0, -6.0 * l, 12.0, -6.0 * l],
            [6.0 * l, 2.0 * l2, -6.0 * l, 4.0 * l2],
        ],
    );
    // x-z plane: w and ty = -dw/dx
    put(
        &mut k,
        [2, 4, 8, 10],
        iy / l3,
        [
            [12.0, -6.0 * l, -12.0, -6.0 * l],
            [-6.0 * l, 4.0 * l2, 6.0 * l, 2.0 * l2],
            [-12.0, 6.0 * l, 12.0, 6.0 * l],
            [-6.0 * l, 2.0 * l2, 6.0 * l, 4.0 * l2],
        ],
    );
    k
}

/// Local consistent mass for `rho = 1`: area, polar moment `ip` (for the
/// rotary inertia in torsion), length `l`.
pub fn mass_local(area: f64, ip: f64, l: f64) -> Mat12 {
    let mut m = Mat12::zeros();
    put_bar(&mut m, 0, 6, area * l / 6.0, 2.0, 1.0);
    put_bar(&mut m, 3, 9, ip * l / 6.0, 2.0, 1.0);
    let l2 = l * l;
    let t = area * l / 420.0;
    put(
        &mut m,
        [1, 5, 7, 11],
        t,
        [
            [156.0, 22.0 * l, 54.0, -13.0 * l],
            [22.0 * l, 4.0 * l2, 13.0 * l, -3.0 * l2],
            [54.0, 13.0 * l, 156.0, -22.0 * l],
            [-13.0 * l, -3.0 * l2, -22.0 * l, 4.0 * l2],
        ],
    );
    put(
        &mut m,
        [2, 4, 8, 10],
        t,
        [
            [156.0, -22.0 * l, 54.0, 13.0 * l],
            [-22.0 * l, 4.0 * l2, -13.0 * l, -3.0 * l2],
            [54.0, -13.0 * l, 156.0, 22.0 * l],
            [13.0 * l, -3.0 * l2, 22.0 * l, 4.0 * l2],
        ],
    );
    m
}

/// Local lumped transverse mass for a unit mass per length: `L/2` on each
/// end's two transverse translations (`v`, `w`).
pub fn transverse_lumped_mass_local(l: f64) -> Mat12 {
    let mut m = Mat12::zeros();
    for i in [1, 2, 7, 8] {
        m[(i, i)] = l / 2.0;
    }
    m
}

/// Rotates a local 12x12 matrix to global axes, for local axes `axes`
/// (rows: the local x, y, z in global components).
pub fn to_global(local: &Mat12, axes: &[[f64; 3]; 3]) -> Mat12 {
    let mut t = Mat12::zeros();
    for block in 0..4 {
        let o = 3 * block;
        for (r, row) in axes.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                t[(o + r, o + c)] = *v;
            }
        }
    }
    t.transpose() * local * t
}
