//! The 3D frame element against truths derived here: Gauss quadrature of
//! its shape functions, the textbook stiffness written out entry by entry,
//! the six rigid motions of a body in space, and the section constants
//! against Timoshenko and Goodier's table.

use fe_model::element::frame3d::{self, Mat12};
use fe_model::model::rectangle_torsion;
use fe_model::{Assembly, Dimension, Dof, DofRef, Group, Model, Section};
use nalgebra::{DMatrix, SVector, Vector3};

use super::elements::{assert_assembled, integrate};

/// The element's shape functions at `x` along it, as rows over the local
/// DOFs `[u1, v1, w1, tx1, ty1, tz1, u2, v2, w2, tx2, ty2, tz2]`: the axial
/// displacement and the twist (linear), and the two transverse
/// displacements (cubic Hermite), with their derivatives. In the x-z plane
/// the end rotation is `ty = -dw/dx` (a positive turn about y lifts z
/// towards x), so its Hermite functions enter with a minus sign.
struct Shapes3 {
    u: [f64; 12],
    du: [f64; 12],
    tx: [f64; 12],
    dtx: [f64; 12],
    v: [f64; 12],
    d2v: [f64; 12],
    w: [f64; 12],
    d2w: [f64; 12],
}

fn shapes3(x: f64, l: f64) -> Shapes3 {
    let s = x / l;
    let h = [
        1.0 - 3.0 * s * s + 2.0 * s.powi(3),
        l * (s - 2.0 * s * s + s.powi(3)),
        3.0 * s * s - 2.0 * s.powi(3),
        l * (s.powi(3) - s * s),
    ];
    let d2h = [(-6.0 + 12.0 * s) / (l * l), (-4.0 + 6.0 * s) / l, (6.0 - 12.0 * s) / (l * l), (6.0 * s - 2.0) / l];
    let mut f = Shapes3 {
        u: [0.0; 12],
        du: [0.0; 12],
        tx: [0.0; 12],
        dtx: [0.0; 12],
        v: [0.0; 12],
        d2v: [0.0; 12],
        w: [0.0; 12],
        d2w: [0.0; 12],
    };
    (f.u[0], f.u[6], f.du[0], f.du[6]) = (1.0 - s, s, -1.0 / l, 1.0 / l);
    (f.tx[3], f.tx[9], f.dtx[3], f.dtx[9]) = (1.0 - s, s, -1.0 / l, 1.0 / l);
    for (k, (&i, sign)) in [1, 5, 7, 11].iter().zip([1.0, 1.0, 1.0, 1.0]).enumerate() {
        f.v[i] = sign * h[k];
        f.d2v[i] = sign * d2h[k];
    }
    for (k, (&i, sign)) in [2, 4, 8, 10].iter().zip([1.0, -1.0, 1.0, -1.0]).enumerate() {
        f.w[i] = sign * h[k];
        f.d2w[i] = sign * d2h[k];
    }
    f
}

/// `K = int A u' u'^T + g J tx' tx'^T + Iz v'' v''^T + Iy w'' w''^T` and
/// `M = int A (u u^T + v v^T + w w^T) + (Iy + Iz) tx tx^T`, by four-point
/// Gauss quadrature (exact: the integrands are polynomials of degree six
/// at most).
fn by_quadrature(area: f64, iy: f64, iz: f64, j: f64, g: f64, l: f64) -> (Mat12, Mat12) {
    let (mut k, mut m) = (Mat12::zeros(), Mat12::zeros());
    for a in 0..12 {
        for b in 0..12 {
            k[(a, b)] = integrate(l, 4, |x| {
                let f = shapes3(x, l);
                area * f.du[a] * f.du[b]
                    + g * j * f.dtx[a] * f.dtx[b]
                    + iz * f.d2v[a] * f.d2v[b]
                    + iy * f.d2w[a] * f.d2w[b]
            });
            m[(a, b)] = integrate(l, 4, |x| {
                let f = shapes3(x, l);
                area * (f.u[a] * f.u[b] + f.v[a] * f.v[b] + f.w[a] * f.w[b]) + (iy + iz) * f.tx[a] * f.tx[b]
            });
        }
    }
    (k, m)
}

/// Entry by entry to `tol` of the largest entry in the row or column of `b`.
fn assert_close(a: &Mat12, b: &Mat12, tol: f64, what: &str) {
    for i in 0..12 {
        for j in 0..12 {
            let scale = (0..12).map(|k| b[(i, k)].abs().max(b[(k, j)].abs())).fold(0.0, f64::max);
            assert!((a[(i, j)] - b[(i, j)]).abs() <= tol * scale, "{what}[{i}][{j}]: {} vs {}", a[(i, j)], b[(i, j)]);
        }
    }
}

const SECTIONS: [(f64, f64, f64, f64, f64, f64); 3] = [
    // area, Iy, Iz, J, G/E, L
    (8e-4, 1.07e-8, 4.27e-8, 2.9e-8, 0.3846, 0.45),
    (2.5e-3, 5.2e-7, 1.3e-6, 1.1e-6, 0.375, 1.7),
    (1.2e-2, 9.0e-5, 2.0e-5, 6.0e-5, 0.4, 0.08),
];

#[test]
fn local_stiffness_and_mass_equal_quadrature_of_the_shape_functions() {
    for (area, iy, iz, j, g, l) in SECTIONS {
        let (k, m) = by_quadrature(area, iy, iz, j, g, l);
        assert_close(&frame3d::stiffness_local(area, iy, iz, j, g, l), &k, 1e-13, "K");
        assert_close(&frame3d::mass_local(area, iy + iz, l), &m, 1e-13, "M");
    }
}

/// The local stiffness as the textbooks print it (Przemieniecki, Theory of
/// Matrix Structural Analysis, 1968, eq. 5.117, with `E = 1`), entry by
/// entry in the upper triangle; every other entry of the triangle is zero.
#[test]
fn local_stiffness_is_the_textbook_matrix() {
    let (area, iy, iz, j, g, l) = SECTIONS[1];
    let (l2, l3) = (l * l, l * l * l);
    let mut want = Mat12::zeros();
    let entries = [
        ((0, 0), area / l),
        ((0, 6), -area / l),
        ((1, 1), 12.0 * iz / l3),
        ((1, 5), 6.0 * iz / l2),
        ((1, 7), -12.0 * iz / l3),
        ((1, 11), 6.0 * iz / l2),
        ((2, 2), 12.0 * iy / l3),
        ((2, 4), -6.0 * iy / l2),
        ((2, 8), -12.0 * iy / l3),
        ((2, 10), -6.0 * iy / l2),
        ((3, 3), g * j / l),
        ((3, 9), -g * j / l),
        ((4, 4), 4.0 * iy / l),
        ((4, 8), 6.0 * iy / l2),
        ((4, 10), 2.0 * iy / l),
        ((5, 5), 4.0 * iz / l),
        ((5, 7), -6.0 * iz / l2),
        ((5, 11), 2.0 * iz / l),
        ((6, 6), area / l),
        ((7, 7), 12.0 * iz / l3),
        ((7, 11), -6.0 * iz / l2),
        ((8, 8), 12.0 * iy / l3),
        ((8, 10), 6.0 * iy / l2),
        ((9, 9), g * j / l),
        ((10, 10), 4.0 * iy / l),
        ((11, 11), 4.0 * iz / l),
    ];
    for ((r, c), v) in entries {
        want[(r, c)] = v;
        want[(c, r)] = v;
    }
    assert_close(&frame3d::stiffness_local(area, iy, iz, j, g, l), &want, 1e-15, "K");
}

/// The rigid motion of translation `t` and small rotation `w` about the
/// origin, at the element's two end nodes: `u = t + w x r`, `theta = w`.
fn rigid(t: [f64; 3], w: [f64; 3], p: [f64; 3], q: [f64; 3]) -> SVector<f64, 12> {
    let (t, w) = (Vector3::from(t), Vector3::from(w));
    let mut x = SVector::<f64, 12>::zeros();
    for (o, r) in [(0, p), (6, q)] {
        let u = t + w.cross(&Vector3::from(r));
        x.fixed_rows_mut::<3>(o).copy_from(&u);
        x.fixed_rows_mut::<3>(o + 3).copy_from(&w);
    }
    x
}

#[test]
fn global_stiffness_is_symmetric_with_exactly_the_six_rigid_motions_as_null_space() {
    let (area, iy, iz, j, g, _) = SECTIONS[0];
    let ends = [([0.1, -0.2, 0.3], [0.5, 0.1, -0.1]), ([0.0; 3], [0.0, 0.0, 0.7]), ([1.0, 2.0, 0.0], [1.0, 2.6, 0.0])];
    for (p, q) in ends {
        let l = Vector3::from(q).metric_distance(&Vector3::from(p));
        for (reference, angle) in [(None, 0.0), (Some([0.3, -0.5, 0.8]), 0.0), (None, 0.7)] {
            let Ok(axes) = frame3d::axes(p, q, reference, angle) else { continue };
            let k = frame3d::to_global(&frame3d::stiffness_local(area, iy, iz, j, g, l), &axes);
            let m = frame3d::to_global(&frame3d::mass_local(area, iy + iz, l), &axes);
            assert!((k - k.transpose()).norm() <= 1e-14 * k.norm(), "K symmetric");
            assert!((m - m.transpose()).norm() <= 1e-15 * m.norm(), "M symmetric");
            for (t, w) in [([1.0, 0.0, 0.0], [0.0; 3]), ([0.0, 1.0, 0.0], [0.0; 3]), ([0.0, 0.0, 1.0], [0.0; 3])]
                .into_iter()
                .chain([([0.0; 3], [1.0, 0.0, 0.0]), ([0.0; 3], [0.0, 1.0, 0.0]), ([0.0; 3], [0.0, 0.0, 1.0])])
            {
                let x = rigid(t, w, p, q);
                assert!((k * x).norm() <= 1e-12 * k.norm() * x.norm(), "rigid motion {t:?} {w:?} strains the element");
            }
            let eig = k.symmetric_eigen().eigenvalues;
            let zero = eig.iter().filter(|e| e.abs() <= 1e-10 * k.norm()).count();
            assert_eq!(zero, 6, "{eig}");
            assert!(eig.iter().all(|&e| e > -1e-10 * k.norm()));
            assert!(m.symmetric_eigen().eigenvalues.iter().all(|&e| e > 0.0), "M positive definite");
        }
    }
}

#[test]
fn local_axes_are_right_handed_and_follow_the_reference_and_the_angle() {
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let check = |axes: [[f64; 3]; 3]| {
        for i in 0..3 {
            for j in 0..3 {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((dot(axes[i], axes[j]) - want).abs() < 1e-15, "{axes:?}");
            }
        }
        let z = Vector3::from(axes[0]).cross(&Vector3::from(axes[1]));
        assert!((z - Vector3::from(axes[2])).norm() < 1e-15, "right-handed: {axes:?}");
    };
    // a beam in the x-y plane: z is global z, as in a planar model
    let (c, s) = (0.6, 0.8);
    let a = frame3d::axes([1.0, 1.0, 0.0], [1.0 + c, 1.0 + s, 0.0], None, 0.0).unwrap();
    check(a);
    assert_eq!(a[2], [0.0, 0.0, 1.0]);
    assert!((a[1][0] + s).abs() < 1e-15 && (a[1][1] - c).abs() < 1e-15);
    // a beam along z: z is global y
    let a = frame3d::axes([0.0; 3], [0.0, 0.0, 2.0], None, 0.0).unwrap();
    check(a);
    assert_eq!((a[0], a[2]), ([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]));
    // a reference: its part across the beam
    let a = frame3d::axes([0.0; 3], [1.0, 0.0, 0.0], Some([0.5, 2.0, 0.0]), 0.0).unwrap();
    check(a);
    assert!((a[2][1] - 1.0).abs() < 1e-15, "{a:?}");
    // an angle turns y towards z
    let a = frame3d::axes([0.0; 3], [1.0, 0.0, 0.0], None, std::f64::consts::FRAC_PI_2).unwrap();
    check(a);
    assert!((a[1][2] - 1.0).abs() < 1e-15 && (a[2][1] + 1.0).abs() < 1e-15, "{a:?}");
    // a reference along the beam, or none at all, says nothing
    assert_eq!(
        frame3d::axes([0.0; 3], [1.0, 0.0, 0.0], Some([-2.0, 0.0, 0.0]), 0.0),
        Err(frame3d::AxesError::Reference)
    );
    assert_eq!(frame3d::axes([0.0; 3], [1.0, 0.0, 0.0], Some([0.0; 3]), 0.0), Err(frame3d::AxesError::Reference));
    // a reference that is not a number says nothing either
    for r in [[0.0, f64::INFINITY, 0.0], [f64::NAN, 1.0, 0.0]] {
        assert_eq!(frame3d::axes([0.0; 3], [1.0, 0.0, 0.0], Some(r), 0.0), Err(frame3d::AxesError::Reference), "{r:?}");
    }
    // along the beam is an angle, whatever the reference's length: a long
    // reference within the angle is refused, a short one beyond it taken
    let sine = frame3d::PARALLEL / 10.0;
    let near = frame3d::axes([0.0; 3], [1.0, 0.0, 0.0], Some([1e3, 1e3 * sine, 0.0]), 0.0);
    assert_eq!(near, Err(frame3d::AxesError::Reference));
    let sine = frame3d::PARALLEL * 10.0;
    let off = frame3d::axes([0.0; 3], [1.0, 0.0, 0.0], Some([1e-3, 1e-3 * sine, 0.0]), 0.0).unwrap();
    check(off);
    assert!((off[2][1] - 1.0).abs() < 1e-12, "{off:?}");
    // a beam without length, or with one that is not a number, has no axes
    for q in [[0.0; 3], [f64::INFINITY, 0.0, 0.0], [f64::NAN, 1.0, 0.0]] {
        assert_eq!(frame3d::axes([0.0; 3], q, None, 0.0), Err(frame3d::AxesError::ZeroLength), "{q:?}");
    }
}

/// `J / (a b^3)` of a solid `a x b` rectangle (`a >= b`), as tabulated by
/// Timoshenko and Goodier (Theory of Elasticity, 3rd ed., table 8) to three
/// digits.
#[test]
fn rectangle_torsion_constants_match_timoshenko_and_goodier() {
    for (ratio, beta) in [(1.0, 0.141), (1.5, 0.196), (2.0, 0.229), (3.0, 0.263), (5.0, 0.291), (10.0, 0.312)] {
        let (a, b) = (0.02 * ratio, 0.02);
        let got = rectangle_torsion(a, b) / (a * b.powi(3));
        assert!((got - beta).abs() <= 0.0005, "a/b = {ratio}: {got:.4} vs {beta}");
        assert_eq!(rectangle_torsion(a, b), rectangle_torsion(b, a));
    }
    // a thin strip: b^3 a / 3 less the ends' share, 0.63 b^4 (Saint-Venant)
    let (a, b): (f64, f64) = (1.0, 0.01);
    let thin = a * b.powi(3) / 3.0 - 0.21 * b.powi(4);
    assert!((rectangle_torsion(a, b) / thin - 1.0).abs() < 1e-5);
    // a tube: the polar moment
    let t = Section::tube("t", 0.05, 0.04);
    assert!((t.torsion - std::f64::consts::PI / 32.0 * (0.05f64.powi(4) - 0.04f64.powi(4))).abs() < 1e-20);
}

#[test]
fn lumped_added_mass_acts_on_both_transverse_directions_only() {
    let l = 0.6;
    let axes = frame3d::axes([0.0; 3], [0.3, 0.4, 0.2], Some([0.1, 0.0, 1.0]), 0.4).unwrap();
    let m = frame3d::to_global(&frame3d::transverse_lumped_mass_local(l), &axes);
    let at_both = |d: [f64; 3]| {
        let mut x = SVector::<f64, 12>::zeros();
        for o in [0, 6] {
            x.fixed_rows_mut::<3>(o).copy_from(&Vector3::from(d));
        }
        (x.transpose() * m * x)[0]
    };
    assert!(at_both(axes[0]).abs() < 1e-15, "nothing along the beam");
    assert!((at_both(axes[1]) - l).abs() < 1e-15 && (at_both(axes[2]) - l).abs() < 1e-15);
}

/// A 3D cantilever: a beam 1-2 in space, a node 3 on node 2 joined by six
/// springs, a mass with three rotary inertias on node 3; node 1 clamped.
fn beam_spring_mass_3d() -> Model {
    let mut m = Model::with_dimension("3D beam, spring, mass", Dimension::Spatial);
    let g = m.add_group(Group::new("g")).unwrap();
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    m.set_poisson(steel, 0.3).unwrap();
    let sec = m.add_section(Section::rectangle("bar", 0.04, 0.02)).unwrap();
    m.add_node_at(1, [0.0; 3]).unwrap();
    m.add_node_at(2, [0.3, 0.5, 0.6]).unwrap();
    m.add_node_at(3, [0.3, 0.5, 0.6]).unwrap();
    let b = m.add_beam(1, [1, 2], steel, sec, g).unwrap();
    m.orient_beam(b, Some([1.0, 0.0, 0.0]), 0.2).unwrap();
    m.add_spring("joint", 2, Some(3), [3e7, 5e6, 4e6, 2e4, 3e4, 1e4], g).unwrap();
    m.add_mass("tip", 3, 1.5, [2e-3, 3e-3, 4e-3], g).unwrap();
    m.add_support(1, &Dof::SPATIAL).unwrap();
    m
}

#[test]
fn assembled_3d_matrices_equal_an_independent_assembly_of_every_item_type() {
    let model = beam_spring_mass_3d();
    let a = Assembly::new(&model).unwrap();
    assert_eq!(a.n(), 12);
    let eq = |node: u32, dof: Dof| a.dofs().equation(DofRef::new(node, dof));
    let n = a.n();
    let (mut k, mut m) = (DMatrix::<f64>::zeros(n, n), DMatrix::<f64>::zeros(n, n));
    // the beam: quadrature matrices turned by the rotation built here from its axes
    let (e, rho, nu) = (2.0e11, 7800.0, 0.3);
    let (b, h): (f64, f64) = (0.04, 0.02);
    let (area, iz, iy) = (b * h, b * h.powi(3) / 12.0, h * b.powi(3) / 12.0);
    let l = (0.3f64 * 0.3 + 0.5 * 0.5 + 0.6 * 0.6).sqrt();
    let (kq, mq) = by_quadrature(area, iy, iz, rectangle_torsion(b, h), 0.5 / (1.0 + nu), l);
    let axes = frame3d::axes([0.0; 3], [0.3, 0.5, 0.6], Some([1.0, 0.0, 0.0]), 0.2).unwrap();
    let mut t = Mat12::zeros();
    for block in 0..4 {
        for r in 0..3 {
            for c in 0..3 {
                t[(3 * block + r, 3 * block + c)] = axes[r][c];
            }
        }
    }
    let (kg, mg) = (t.transpose() * kq * t * e, t.transpose() * mq * t * rho);
    let beam_dofs: Vec<(u32, Dof)> = [1, 2].iter().flat_map(|&n| Dof::SPATIAL.map(|d| (n, d))).collect();
    for (i, &(ni, di)) in beam_dofs.iter().enumerate() {
        for (j, &(nj, dj)) in beam_dofs.iter().enumerate() {
            if let (Some(r), Some(col)) = (eq(ni, di), eq(nj, dj)) {
                k[(r, col)] += kg[(i, j)];
                m[(r, col)] += mg[(i, j)];
            }
        }
    }
    for (dof, ks) in Dof::SPATIAL.into_iter().zip([3e7, 5e6, 4e6, 2e4, 3e4, 1e4]) {
        let (p, q) = (eq(2, dof).unwrap(), eq(3, dof).unwrap());
        k[(p, p)] += ks;
        k[(q, q)] += ks;
        k[(p, q)] -= ks;
        k[(q, p)] -= ks;
    }
    for (dof, v) in Dof::SPATIAL.into_iter().zip([1.5, 1.5, 1.5, 2e-3, 3e-3, 4e-3]) {
        let p = eq(3, dof).unwrap();
        m[(p, p)] += v;
    }
    assert_assembled(&a, &k, &m);
}

#[test]
fn a_3d_model_refuses_what_only_a_planar_one_has_and_the_reverse() {
    let mut planar = Model::new("p");
    let g = planar.add_group(Group::new("g")).unwrap();
    planar.add_node(1, 0.0, 0.0).unwrap();
    assert!(planar.add_node_at(2, [0.0, 0.0, 0.1]).unwrap_err().to_string().contains("dimension = 3"));
    assert!(planar.add_support(1, &[Dof::Uz]).unwrap_err().to_string().contains("`uz` is not a DOF of a planar model"));
    let e = planar.add_spring("s", 1, None, [0.0, 0.0, 1.0, 0.0, 0.0, 0.0], g).unwrap_err().to_string();
    assert!(e.contains("`uz` is not a DOF of a planar model"), "{e}");
    let e = planar.add_mass("m", 1, 1.0, [1.0, 0.0, 0.0], g).unwrap_err().to_string();
    assert!(e.contains("rotary inertia about x or y"), "{e}");
    let mut spatial = Model::with_dimension("s", Dimension::Spatial);
    let steel = spatial.add_material("steel", 2e11, 7800.0).unwrap();
    assert!(spatial.add_section(Section::planar("p", 1e-4, 1e-8)).unwrap_err().to_string().contains("Iy"));
    let sec = spatial.add_section(Section::rectangle("r", 0.01, 0.02)).unwrap();
    let g = spatial.add_group(Group::new("g")).unwrap();
    spatial.add_node_at(1, [0.0; 3]).unwrap();
    spatial.add_node_at(2, [0.0, 0.0, 1.0]).unwrap();
    // a 3D beam twists: its material needs a shear modulus
    assert!(spatial.add_beam(1, [1, 2], steel, sec, g).unwrap_err().to_string().contains("`nu`"));
    spatial.set_poisson(steel, 0.3).unwrap();
    let b = spatial.add_beam(1, [1, 2], steel, sec, g).unwrap();
    assert!(spatial.orient_beam(b, Some([0.0, 0.0, 3.0]), 0.0).unwrap_err().to_string().contains("along the beam"));
}
