//! Element matrices against Gauss quadrature of their shape functions, and
//! the rotation to global axes against what a rotated element must do.

use fe_model::element::{self, Mat6};
use fe_model::{Assembly, Dof, DofRef, Group, Model, Section};
use nalgebra::{DMatrix, SVector};

/// Gauss-Legendre points and weights on [-1, 1], from Newton's method on the
/// Legendre polynomial (three-term recurrence), not from a table.
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            // Tricomi's first guess, then Newton
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    (p0, p1) = (p1, p2);
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let step = p1 / dp;
                x -= step;
                if step.abs() < 1e-16 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// `int_0^L f(x) dx` by `n`-point Gauss-Legendre quadrature.
pub(crate) fn integrate(l: f64, n: usize, f: impl Fn(f64) -> f64) -> f64 {
    gauss_legendre(n).iter().map(|&(t, w)| w * 0.5 * l * f(0.5 * l * (t + 1.0))).sum()
}

/// Shape functions of the frame element at `x` along it, as rows over the
/// local DOFs `[u1, v1, th1, u2, v2, th2]`: axial displacement (linear),
/// transverse displacement (cubic Hermite), its first and second derivatives.
struct Shapes {
    u: [f64; 6],
    du: [f64; 6],
    v: [f64; 6],
    d2v: [f64; 6],
}

fn shapes(x: f64, l: f64) -> Shapes {
    let s = x / l;
    Shapes {
        u: [1.0 - s, 0.0, 0.0, s, 0.0, 0.0],
        du: [-1.0 / l, 0.0, 0.0, 1.0 / l, 0.0, 0.0],
        v: [
            0.0,
            1.0 - 3.0 * s * s + 2.0 * s * s * s,
            l * (s - 2.0 * s * s + s * s * s),
            0.0,
            3.0 * s * s - 2.0 * s * s * s,
            l * (s * s * s - s * s),
        ],
        d2v: [
            0.0,
            (-6.0 + 12.0 * s) / (l * l),
            (-4.0 + 6.0 * s) / l,
            0.0,
            (6.0 - 12.0 * s) / (l * l),
            (6.0 * s - 2.0) / l,
        ],
    }
}

/// Local stiffness (`E = 1`) and consistent mass (`rho = 1`) by quadrature:
/// `K = int A u' u'^T + I v'' v''^T`, `M = int A (u u^T + v v^T)`.
fn by_quadrature(area: f64, inertia: f64, l: f64) -> (Mat6, Mat6) {
    // the mass integrand has degree 6: four points integrate it exactly
    let (mut k, mut m) = (Mat6::zeros(), Mat6::zeros());
    for i in 0..6 {
        for j in 0..6 {
            k[(i, j)] = integrate(l, 4, |x| {
                let f = shapes(x, l);
                area * f.du[i] * f.du[j] + inertia * f.d2v[i] * f.d2v[j]
            });
            m[(i, j)] = integrate(l, 4, |x| {
                let f = shapes(x, l);
                area * (f.u[i] * f.u[j] + f.v[i] * f.v[j])
            });
        }
    }
    (k, m)
}

/// Every entry of `a` equals that of `b` to `tol` of the largest entry of
/// its row or column in `b` (the DOFs mix lengths and rotations, so one
/// scale for the whole matrix would hide the small ones).
fn assert_entrywise(a: &Mat6, b: &Mat6, tol: f64, what: &str) {
    for i in 0..6 {
        for j in 0..6 {
            let scale = (0..6).map(|k| b[(i, k)].abs().max(b[(k, j)].abs())).fold(0.0, f64::max);
            assert!(
                (a[(i, j)] - b[(i, j)]).abs() <= tol * scale,
                "{what}[{i}][{j}]: {} vs quadrature {}",
                a[(i, j)],
                b[(i, j)]
            );
        }
    }
}

#[test]
fn gauss_legendre_integrates_polynomials_up_to_degree_2n_minus_1() {
    for n in 1..=6 {
        for degree in 0..2 * n {
            let exact = 2.0f64.powi(degree as i32 + 1) / (degree as f64 + 1.0);
            let q = integrate(2.0, n, |x| x.powi(degree as i32));
            assert!((q - exact).abs() <= 1e-13 * exact, "n {n}, x^{degree}: {q} vs {exact}");
        }
    }
}

#[test]
fn frame_stiffness_and_consistent_mass_equal_quadrature_of_the_shape_functions() {
    for (area, inertia, l) in [(2.5e-4, 5.2e-10, 0.03), (0.01, 2e-5, 0.7), (0.0313, 7.6e-3, 3.6)] {
        let (k, m) = by_quadrature(area, inertia, l);
        assert_entrywise(&element::frame_stiffness_local(area, inertia, l), &k, 1e-13, "K");
        assert_entrywise(&element::frame_mass_local(area, l), &m, 1e-13, "M");
        // more points change nothing: the integrands are polynomials
        let (k6, m6) = {
            let (mut k6, mut m6) = (Mat6::zeros(), Mat6::zeros());
            for i in 0..6 {
                for j in 0..6 {
                    k6[(i, j)] = integrate(l, 6, |x| {
                        let f = shapes(x, l);
                        area * f.du[i] * f.du[j] + inertia * f.d2v[i] * f.d2v[j]
                    });
                    m6[(i, j)] = integrate(l, 6, |x| {
                        let f = shapes(x, l);
                        area * (f.u[i] * f.u[j] + f.v[i] * f.v[j])
                    });
                }
            }
            (k6, m6)
        };
        assert_entrywise(&k6, &k, 1e-13, "K (6 points)");
        assert_entrywise(&m6, &m, 1e-13, "M (6 points)");
    }
}

#[test]
fn lumped_added_mass_puts_half_of_each_length_on_its_ends_across_the_axis() {
    let l = 0.8;
    let local = element::transverse_lumped_mass_local(l);
    let mut expect = Mat6::zeros();
    expect[(1, 1)] = l / 2.0;
    expect[(4, 4)] = l / 2.0;
    assert_eq!(local, expect);
    // in global axes: nothing along the element, all of it across
    let theta: f64 = 0.9;
    let (c, s) = (theta.cos(), theta.sin());
    let m = element::transverse_lumped_mass(l, c, s);
    let along = SVector::<f64, 6>::from_row_slice(&[c, s, 0.0, c, s, 0.0]);
    let across = SVector::<f64, 6>::from_row_slice(&[-s, c, 0.0, -s, c, 0.0]);
    assert!((along.transpose() * m * along)[0].abs() < 1e-15);
    assert!(((across.transpose() * m * across)[0] - l).abs() < 1e-15);
}

/// A displacement `d` of node 2 (node 1 held) in global axes, as a vector of
/// the element's global DOFs.
fn node2(dx: f64, dy: f64, rz: f64) -> SVector<f64, 6> {
    SVector::<f64, 6>::from_row_slice(&[0.0, 0.0, 0.0, dx, dy, rz])
}

#[test]
fn global_matrices_act_along_and_across_the_rotated_element() {
    let (area, inertia, l) = (0.01, 2e-5, 0.7);
    for theta in [0.0f64, 0.4, 1.3, 2.0, -2.8] {
        let (c, s) = (theta.cos(), theta.sin());
        let k = element::frame_stiffness(area, inertia, l, c, s);
        // pulling node 2 along the axis loads both ends along the axis with EA/L
        let f = k * node2(c, s, 0.0);
        let expect = area / l * SVector::<f64, 6>::from_row_slice(&[-c, -s, 0.0, c, s, 0.0]);
        assert!((f - expect).norm() <= 1e-12 * expect.norm(), "theta {theta}: {f} vs {expect}");
        // moving it across the axis (no rotation) needs 12 EI / L^3 and end moments 6 EI / L^2
        let f = k * node2(-s, c, 0.0);
        let (t, mo) = (12.0 * inertia / l.powi(3), 6.0 * inertia / l.powi(2));
        let expect = SVector::<f64, 6>::from_row_slice(&[s * t, -c * t, -mo, -s * t, c * t, -mo]);
        assert!((f - expect).norm() <= 1e-12 * expect.norm(), "theta {theta}: {f} vs {expect}");
        // rotating the element changes none of its stiffnesses or masses
        let m = element::frame_mass(area, l, c, s);
        let sorted = |a: Mat6| {
            let mut e: Vec<f64> = a.symmetric_eigen().eigenvalues.iter().copied().collect();
            e.sort_by(f64::total_cmp);
            e
        };
        let (k0, m0) =
            (sorted(element::frame_stiffness_local(area, inertia, l)), sorted(element::frame_mass_local(area, l)));
        for (a, b) in sorted(k).iter().zip(&k0).chain(sorted(m).iter().zip(&m0)) {
            assert!((a - b).abs() <= 1e-12 * k0[5].max(m0[5]), "theta {theta}: {a} vs {b}");
        }
    }
}

/// A beam 1-2 at an angle, a node 3 on node 2 joined to it by springs in
/// every direction, and a lumped mass at node 3; node 1 clamped.
fn beam_spring_mass(theta: f64) -> Model {
    let mut m = Model::new("beam, spring, mass");
    let g = m.add_group(Group::new("g")).unwrap();
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let sec = m.add_section(Section::rectangle("bar", 0.04, 0.02)).unwrap();
    m.add_node(1, 0.0, 0.0).unwrap();
    m.add_node(2, 0.9 * theta.cos(), 0.9 * theta.sin()).unwrap();
    m.add_node(3, 0.9 * theta.cos(), 0.9 * theta.sin()).unwrap();
    m.add_beam(1, [1, 2], steel, sec, g).unwrap();
    m.add_spring("joint", 2, Some(3), [3e7, 5e6, 2e4], g).unwrap();
    m.add_mass("tip", 3, 1.5, 2e-3, g).unwrap();
    m.add_support(1, &Dof::PLANAR).unwrap();
    m
}

#[test]
fn assembled_stiffness_and_mass_equal_an_independent_assembly_of_every_item_type() {
    let theta: f64 = 0.6;
    let model = beam_spring_mass(theta);
    let a = Assembly::new(&model).unwrap();
    let eq = |node: u32, dof: Dof| a.dofs().equation(DofRef::new(node, dof));
    let n = a.n();
    let (mut k, mut m) = (DMatrix::<f64>::zeros(n, n), DMatrix::<f64>::zeros(n, n));
    // the beam: quadrature matrices turned by the rotation written out here
    let (area, inertia, l) = (0.04 * 0.02, 0.04 * 0.02f64.powi(3) / 12.0, 0.9);
    let (kq, mq) = by_quadrature(area, inertia, l);
    let (c, s) = (theta.cos(), theta.sin());
    let mut t = Mat6::zeros();
    for o in [0, 3] {
        t[(o, o)] = c;
        t[(o, o + 1)] = s;
        t[(o + 1, o)] = -s;
        t[(o + 1, o + 1)] = c;
        t[(o + 2, o + 2)] = 1.0;
    }
    let (kg, mg) = (t.transpose() * kq * t * 2.0e11, t.transpose() * mq * t * 7800.0);
    let beam_dofs = [(1, Dof::Ux), (1, Dof::Uy), (1, Dof::Rz), (2, Dof::Ux), (2, Dof::Uy), (2, Dof::Rz)];
    for (i, &(ni, di)) in beam_dofs.iter().enumerate() {
        for (j, &(nj, dj)) in beam_dofs.iter().enumerate() {
            if let (Some(r), Some(col)) = (eq(ni, di), eq(nj, dj)) {
                k[(r, col)] += kg[(i, j)];
                m[(r, col)] += mg[(i, j)];
            }
        }
    }
    // the springs: k on each DOF pair, -k between them
    for (dof, ks) in [(Dof::Ux, 3e7), (Dof::Uy, 5e6), (Dof::Rz, 2e4)] {
        let (p, q) = (eq(2, dof).unwrap(), eq(3, dof).unwrap());
        k[(p, p)] += ks;
        k[(q, q)] += ks;
        k[(p, q)] -= ks;
        k[(q, p)] -= ks;
    }
    // the mass: m on both translations, j on the rotation
    for (dof, v) in [(Dof::Ux, 1.5), (Dof::Uy, 1.5), (Dof::Rz, 2e-3)] {
        let p = eq(3, dof).unwrap();
        m[(p, p)] += v;
    }
    assert_assembled(&a, &k, &m);
}

/// The assembled stiffness and mass of `a` against `k` and `m` assembled
/// independently, entry by entry to 1e-12 of the larger diagonal of its row
/// and column.
pub(crate) fn assert_assembled(a: &Assembly, k: &DMatrix<f64>, m: &DMatrix<f64>) {
    let (ka, ma) = (a.stiffness_dense(), a.mass_dense());
    assert_eq!((ka.nrows(), ma.nrows()), (k.nrows(), m.nrows()), "sizes");
    let n = k.nrows();
    for r in 0..n {
        for col in 0..n {
            let (ks, ms) = (k[(r, r)].abs().max(k[(col, col)].abs()), m[(r, r)].abs().max(m[(col, col)].abs()));
            let (dk, dm) = ((ka[(r, col)] - k[(r, col)]).abs(), (ma[(r, col)] - m[(r, col)]).abs());
            assert!(dk <= 1e-12 * ks, "K[{r}][{col}]: {} vs {}", ka[(r, col)], k[(r, col)]);
            assert!(dm <= 1e-12 * ms, "M[{r}][{col}]: {} vs {}", ma[(r, col)], m[(r, col)]);
        }
    }
}
