//! Modal physics of 3D frames against independent truths: a shaft's torsion
//! (the exact solution of the discretised equations and the continuum), a
//! cantilever bending in its two planes with different second moments
//! (Euler-Bernoulli), and a frame turned in space. A planar frame built in
//! space is compared with the planar one in `frf`'s tests (its receptances
//! too).

use damping::normal_modes;
use fe_model::{Assembly, Dimension, Dof, DofRef, Group, Model, Section};

use super::modal_physics::BETA_L;

const E: f64 = 2.0e11;
const RHO: f64 = 7800.0;
const NU: f64 = 0.3;

/// A straight 3D beam of `n` elements from the origin along `dir` (unit),
/// length `l`, node 1 clamped.
fn straight_beam(n: u32, l: f64, dir: [f64; 3], section: Section) -> Model {
    let mut m = Model::with_dimension("3D beam", Dimension::Spatial);
    let g = m.add_group(Group::new("g")).unwrap();
    let mat = m.add_material("steel", E, RHO).unwrap();
    m.set_poisson(mat, NU).unwrap();
    let sec = m.add_section(section).unwrap();
    for i in 0..=n {
        let t = l * f64::from(i) / f64::from(n);
        m.add_node_at(i + 1, dir.map(|d| d * t)).unwrap();
    }
    for i in 1..=n {
        m.add_beam(i, [i, i + 1], mat, sec, g).unwrap();
    }
    m.add_support(1, &Dof::SPATIAL).unwrap();
    m
}

/// A clamped-free circular shaft twisting only (every other DOF held):
/// the consistent-mass bar's frequencies solve the discretised wave
/// equation exactly, `w^2 = (G / rho) (6 / h^2) (1 - cos t) / (2 + cos t)`
/// with `t = (2 k - 1) pi / (2 N)` (the interior equations are satisfied by
/// `sin(j t)` and the free end by the symmetry of that `t`), and approach
/// the continuum's `(2 k - 1) pi / (2 L) sqrt(G / rho)` from above by
/// `t^2 / 24` relative.
#[test]
fn shaft_torsion_frequencies_match_the_discrete_and_continuous_solutions() {
    let (n, l) = (20u32, 1.2);
    let mut m = straight_beam(n, l, [1.0, 0.0, 0.0], Section::tube("shaft", 0.03, 0.0));
    for node in 2..=n + 1 {
        m.add_support(node, &[Dof::Ux, Dof::Uy, Dof::Uz, Dof::Ry, Dof::Rz]).unwrap();
    }
    let modes = normal_modes(&Assembly::new(&m).unwrap()).unwrap();
    assert_eq!(modes.frequencies_hz.len(), n as usize);
    let g = E / (2.0 * (1.0 + NU));
    let c = (g / RHO).sqrt();
    let h = l / f64::from(n);
    let pi = std::f64::consts::PI;
    for k in 1..=6 {
        let t = (2.0 * f64::from(k) - 1.0) * pi / (2.0 * f64::from(n));
        let discrete = c * (6.0 / (h * h) * (1.0 - t.cos()) / (2.0 + t.cos())).sqrt() / (2.0 * pi);
        let fe = modes.frequencies_hz[k as usize - 1];
        assert!((fe - discrete).abs() <= 1e-10 * discrete, "mode {k}: FE {fe} Hz, discrete solution {discrete} Hz");
        let continuum = (2.0 * f64::from(k) - 1.0) * pi / (2.0 * l) * c / (2.0 * pi);
        let err = (fe - continuum) / continuum;
        assert!(
            (err / (t * t / 24.0) - 1.0).abs() < 0.05,
            "mode {k}: error {err:.3e} vs t^2/24 = {:.3e}",
            t * t / 24.0
        );
    }
}

/// `v / |v|`.
fn unit(v: [f64; 3]) -> [f64; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|c| c / n)
}

/// The rotation by `angle` about `axis` (Rodrigues' formula), as a map of points.
pub(super) fn rotation(axis: [f64; 3], angle: f64) -> impl Fn([f64; 3]) -> [f64; 3] {
    let [x, y, z] = unit(axis);
    let (s, c) = angle.sin_cos();
    let r = [
        [c + x * x * (1.0 - c), x * y * (1.0 - c) - z * s, x * z * (1.0 - c) + y * s],
        [y * x * (1.0 - c) + z * s, c + y * y * (1.0 - c), y * z * (1.0 - c) - x * s],
        [z * x * (1.0 - c) - y * s, z * y * (1.0 - c) + x * s, c + z * z * (1.0 - c)],
    ];
    move |p: [f64; 3]| r.map(|row| row[0] * p[0] + row[1] * p[1] + row[2] * p[2])
}

/// A cantilever in space whose section is three times as wide as deep bends
/// in its local x-y plane with `Iz` and in its x-z plane with `Iy`: each
/// family of modes has the Euler-Bernoulli frequencies of its own second
/// moment, to the discretisation error `(beta_n h)^4 / 1440` (5 %), as the
/// planar cantilever. The beam lies along an oblique direction with a
/// turned section, so that the rotation to global axes is exercised too.
#[test]
fn cantilever_bends_in_two_planes_with_its_two_second_moments() {
    let (n, l, b, h) = (30u32, 1.0, 0.03, 0.01);
    let dir = unit([1.0, 2.0, -0.5]);
    let mut m = straight_beam(n, l, dir, Section::rectangle("bar", b, h));
    for i in 0..m.beams().len() {
        m.orient_beam(i, Some([0.3, -0.1, 1.0]), 0.4).unwrap();
    }
    let a = Assembly::new(&m).unwrap();
    let modes = normal_modes(&a).unwrap();
    let axes = m.beam_axes(0);
    let area = b * h;
    let (iz, iy) = (b * h.powi(3) / 12.0, h * b.powi(3) / 12.0);
    // a mode's family by the direction its translations take
    let along = |k: usize, axis: [f64; 3]| {
        let col = modes.shapes.col(k);
        let mut sum = 0.0;
        let mut total = 0.0;
        for node in 2..=n + 1 {
            let u: Vec<f64> = [Dof::Ux, Dof::Uy, Dof::Uz]
                .iter()
                .map(|&d| col[a.dofs().equation(DofRef::new(node, d)).unwrap()])
                .collect();
            let p = u[0] * axis[0] + u[1] * axis[1] + u[2] * axis[2];
            sum += p * p;
            total += u.iter().map(|v| v * v).sum::<f64>();
        }
        sum / total
    };
    for (axis, inertia, plane) in [(axes[1], iz, "x-y (Iz)"), (axes[2], iy, "x-z (Iy)")] {
        let family: Vec<f64> = (0..modes.frequencies_hz.len())
            .filter(|&k| along(k, axis) > 0.99)
            .map(|k| modes.frequencies_hz[k])
            .collect();
        for (k, bl) in BETA_L.iter().enumerate() {
            let exact = bl * bl / (2.0 * std::f64::consts::PI * l * l) * (E * inertia / (RHO * area)).sqrt();
            let fe = family[k];
            let err = (fe - exact) / exact;
            let expected = (bl / f64::from(n)).powi(4) / 1440.0;
            assert!(
                (err / expected - 1.0).abs() < 0.05,
                "{plane} mode {}: FE {fe:.9} Hz, analytic {exact:.9} Hz, error {err:.3e}, expected {expected:.3e}",
                k + 1
            );
        }
    }
}

/// A table in space: four legs clamped at the floor, a frame of four
/// rails at the top with one corner a lossy joint (springs the same in
/// every direction, so that turning the table turns nothing else), a mass
/// at another corner; sections with unequal second moments, each oriented
/// by a reference vector, all turned by `rot` about the origin.
fn table(rot: &dyn Fn([f64; 3]) -> [f64; 3]) -> Model {
    let mut m = Model::with_dimension("table", Dimension::Spatial);
    let frame = m.add_group(Group::new("frame").rayleigh(2e-5, 0.3)).unwrap();
    let joint = m.add_group(Group::new("joint").rayleigh(1e-3, 0.0).relaxation(300.0)).unwrap();
    let steel = m.add_material("steel", E, RHO).unwrap();
    m.set_poisson(steel, NU).unwrap();
    let leg = m.add_section(Section::rectangle("leg", 0.03, 0.02)).unwrap();
    let rail = m.add_section(Section::spatial("rail", 6e-4, 2e-8, 9e-8, 4e-8)).unwrap();
    let at = |p: [f64; 3]| rot(p);
    let (w, d, h) = (0.8, 0.5, 0.7);
    let corners = [[0.0, 0.0], [w, 0.0], [w, d], [0.0, d]];
    for (i, c) in corners.iter().enumerate() {
        let i = i as u32;
        m.add_node_at(10 + i, at([c[0], c[1], 0.0])).unwrap();
        m.add_node_at(20 + i, at([c[0], c[1], h])).unwrap();
        m.add_support(10 + i, &Dof::SPATIAL).unwrap();
        let b = m.add_beam(1 + i, [10 + i, 20 + i], steel, leg, frame).unwrap();
        m.orient_beam(b, Some(at([1.0, 0.3, 0.0])), 0.0).unwrap();
    }
    // the first rail ends on node 30, a joint at corner 21
    m.add_node_at(30, at([w, 0.0, h])).unwrap();
    m.add_spring("joint", 21, Some(30), [4e6, 4e6, 4e6, 3e3, 3e3, 3e3], joint).unwrap();
    for (k, (a, b)) in [(20, 30), (21, 22), (22, 23), (23, 20)].into_iter().enumerate() {
        let e = m.add_beam(5 + k as u32, [a, b], steel, rail, frame).unwrap();
        m.orient_beam(e, Some(at([0.0, 0.0, 1.0])), 0.3).unwrap();
    }
    m.add_mass("sensor", 22, 0.4, [2e-4, 2e-4, 2e-4], frame).unwrap();
    m
}

#[test]
fn a_frame_turned_in_space_keeps_its_frequencies() {
    let reference = normal_modes(&Assembly::new(&table(&|p| p)).unwrap()).unwrap();
    assert!(reference.frequencies_hz.len() > 20);
    for (axis, angle) in [([1.0, 2.0, 3.0], 0.7), ([0.0, 0.0, 1.0], 2.1), ([-1.0, 0.5, 0.2], -1.3)] {
        let turned = normal_modes(&Assembly::new(&table(&rotation(axis, angle))).unwrap()).unwrap();
        assert_eq!(turned.frequencies_hz.len(), reference.frequencies_hz.len());
        for (a, b) in reference.frequencies_hz.iter().zip(&turned.frequencies_hz) {
            assert!((a - b).abs() <= 1e-9 * a, "axis {axis:?}, angle {angle}: {a} Hz vs {b} Hz");
        }
    }
}
