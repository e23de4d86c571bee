//! Complex modes against independent truths: the eigen-residual of `Z(s)`,
//! the singularity of `Z` at each eigenvalue, the undamped modes under
//! proportional damping, the roots of a single-DOF characteristic cubic, and
//! the modal expansion of the receptance.

use damping::{DampedSystem, ModalError, complex_modes, normal_modes};
use faer::Mat;
use faer::linalg::solvers::DenseSolveCore;
use fe_model::{Dof, Group, MatrixKind, Model, Quantity, samples};
use num_complex::Complex64 as C64;

/// `Z(s) = K + s^2 M + s sum_g h_g(s) (alpha_g K_g + beta_g M_g)`, built here
/// from the assembly's group matrices, independently of the library's own.
fn z_dense(sys: &DampedSystem, s: C64) -> Mat<C64> {
    let a = sys.assembly();
    let n = a.n();
    let mut z = Mat::<C64>::zeros(n, n);
    let mut add = |values: &[f64], c: C64| {
        let d = a.to_dense(values);
        for i in 0..n {
            for j in 0..n {
                z[(i, j)] += c * d[(i, j)];
            }
        }
    };
    add(&a.real_values(MatrixKind::Stiffness), C64::new(1.0, 0.0));
    add(&a.real_values(MatrixKind::Mass), s * s);
    for (g, group) in sys.model().groups().iter().enumerate() {
        let h = match group.mu {
            None => C64::new(1.0, 0.0),
            Some(mu) => mu / (mu + s),
        };
        add(&a.group_values(g, MatrixKind::Stiffness), s * h * group.alpha);
        add(&a.group_values(g, MatrixKind::Mass), s * h * group.beta);
    }
    z
}

fn norm(x: &[C64]) -> f64 {
    x.iter().map(|v| v.norm_sqr()).sum::<f64>().sqrt()
}

/// `|Z(s) phi| / (|Z(s)|_2 |phi|)`.
fn relative_residual(sys: &DampedSystem, s: C64, phi: &[C64]) -> f64 {
    let z = z_dense(sys, s);
    let n = phi.len();
    let zphi: Vec<C64> = (0..n).map(|i| (0..n).map(|j| z[(i, j)] * phi[j]).sum()).collect();
    let sigma_max = z.singular_values().unwrap()[0];
    norm(&zphi) / (sigma_max * norm(phi))
}

/// The sample models, viscous and not, proportional and not.
fn models() -> Vec<(&'static str, Model)> {
    vec![
        ("two_dof_oscillator", samples::two_dof_oscillator()),
        ("cantilever(8)", samples::cantilever(8)),
        ("frame_with_joint", samples::frame_with_joint()),
        ("two_material_cantilever", samples::two_material_cantilever()),
        ("space_portal", samples::space_portal()),
    ]
}

#[test]
fn every_eigenpair_annihilates_the_dynamic_stiffness() {
    for (name, model) in models() {
        let sys = DampedSystem::new(model).unwrap();
        let modes = complex_modes(&sys).unwrap();
        assert_eq!(
            2 * modes.oscillatory.len() + modes.overdamped.len() + modes.infinite,
            modes.state_dimension,
            "{name}: every eigenvalue is accounted for"
        );
        assert!(!modes.oscillatory.is_empty());
        let mut worst: f64 = 0.0;
        for m in &modes.oscillatory {
            assert!(m.eigenvalue.im > 0.0 && m.eigenvalue.re < 0.0, "{name}: {}", m.eigenvalue);
            let r = relative_residual(&sys, m.eigenvalue, &m.shape);
            assert!(r < 1e-8, "{name}: mode at {} Hz has residual {r:e}", m.frequency_hz);
            worst = worst.max(r);
        }
        for m in &modes.overdamped {
            assert!(m.eigenvalue < 0.0, "{name}: real eigenvalue {}", m.eigenvalue);
            let phi: Vec<C64> = m.shape.iter().map(|&v| C64::new(v, 0.0)).collect();
            let r = relative_residual(&sys, C64::new(m.eigenvalue, 0.0), &phi);
            assert!(r < 1e-8, "{name}: real mode {} has residual {r:e}", m.eigenvalue);
            worst = worst.max(r);
        }
        // the frequencies are sorted and consistent with the eigenvalues
        for w in modes.oscillatory.windows(2) {
            assert!(w[0].frequency_hz <= w[1].frequency_hz);
        }
        for m in &modes.oscillatory {
            let f = m.eigenvalue.norm() / (2.0 * std::f64::consts::PI);
            assert!((m.frequency_hz - f).abs() <= 1e-14 * f);
            assert!((m.damping_ratio + m.eigenvalue.re / m.eigenvalue.norm()).abs() <= 1e-15);
        }
        eprintln!("{name}: worst relative eigen-residual {worst:.1e}");
    }
}

#[test]
fn the_dynamic_stiffness_is_singular_at_each_eigenvalue_and_not_beside_it() {
    for (name, model) in [("frame_with_joint", samples::frame_with_joint()), ("two_dof", samples::two_dof_oscillator())]
    {
        let sys = DampedSystem::new(model).unwrap();
        let modes = complex_modes(&sys).unwrap();
        let ratio = |s: C64| {
            let sv = z_dense(&sys, s).singular_values().unwrap();
            sv[sv.len() - 1] / sv[0]
        };
        let mut poles: Vec<C64> = modes.oscillatory.iter().map(|m| m.eigenvalue).collect();
        poles.extend(modes.overdamped.iter().map(|m| C64::new(m.eigenvalue, 0.0)));
        for s in poles {
            let at = ratio(s);
            let beside = ratio(s * (1.0 + 1e-3));
            assert!(at < 1e-12, "{name}: sigma_min / sigma_max = {at:e} at s = {s}");
            assert!(beside > 1e3 * at, "{name}: {beside:e} beside s = {s}, {at:e} at it");
        }
    }
}

#[test]
fn proportional_viscous_damping_keeps_the_undamped_frequencies_and_shapes() {
    // one viscous group, C = alpha K + beta M: the complex modes are the
    // undamped ones with s = -zeta w_n +- j w_n sqrt(1 - zeta^2),
    // zeta = (alpha w_n + beta / w_n) / 2; an overdamped mode gives the two
    // real roots -w_n (zeta -+ sqrt(zeta^2 - 1)).
    let model = samples::cantilever(8);
    let (alpha, beta) = (model.groups()[0].alpha, model.groups()[0].beta);
    let sys = DampedSystem::new(model).unwrap();
    let undamped = normal_modes(sys.assembly()).unwrap();
    let modes = complex_modes(&sys).unwrap();
    let two_pi = 2.0 * std::f64::consts::PI;
    let mut reals: Vec<f64> = modes.overdamped.iter().map(|m| m.eigenvalue).collect();
    let mut expected_reals = Vec::new();
    let mut k = 0;
    for (col, &f) in undamped.frequencies_hz.iter().enumerate() {
        let wn = two_pi * f;
        let zeta = 0.5 * (alpha * wn + beta / wn);
        if zeta >= 1.0 {
            let r = (zeta * zeta - 1.0).sqrt();
            expected_reals.extend([-wn * (zeta - r), -wn * (zeta + r)]);
            continue;
        }
        let m = &modes.oscillatory[k];
        k += 1;
        assert!((m.frequency_hz - f).abs() <= 1e-9 * f, "mode {col}: {} Hz vs undamped {f} Hz", m.frequency_hz);
        assert!((m.damping_ratio - zeta).abs() <= 1e-9 * zeta, "mode {col}: zeta {} vs {zeta}", m.damping_ratio);
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        assert!((m.eigenvalue.im - wd).abs() <= 1e-9 * wd, "mode {col}: w_d {} vs {wd}", m.eigenvalue.im);
        // the complex shape is the real undamped shape times one complex number
        let phi = undamped.shapes.col(col);
        let dot: C64 = m.shape.iter().enumerate().map(|(i, v)| v * phi[i]).sum();
        let mac = dot.norm_sqr() / (norm(&m.shape).powi(2) * phi.norm_l2().powi(2));
        assert!(mac > 1.0 - 1e-10, "mode {col}: MAC with the undamped shape {mac}");
    }
    assert_eq!(k, modes.oscillatory.len(), "no extra oscillatory modes");
    reals.sort_by(f64::total_cmp);
    expected_reals.sort_by(f64::total_cmp);
    assert_eq!(reals.len(), expected_reals.len());
    for (a, b) in reals.iter().zip(&expected_reals) {
        assert!((a - b).abs() <= 1e-8 * b.abs(), "real root {a} vs {b}");
    }
}

/// Roots of a monic polynomial (coefficients from the highest power down,
/// leading 1 omitted) by the Durand-Kerner iteration.
fn durand_kerner(coefs: &[f64]) -> Vec<C64> {
    let deg = coefs.len();
    let p = |z: C64| coefs.iter().fold(C64::new(1.0, 0.0), |acc, &c| acc * z + c);
    let radius = 1.0 + coefs.iter().map(|c| c.abs()).fold(0.0, f64::max);
    let mut z: Vec<C64> = (0..deg).map(|k| C64::new(0.4, 0.9).powu(k as u32) * radius).collect();
    for _ in 0..2000 {
        for i in 0..deg {
            let den: C64 = (0..deg).filter(|&j| j != i).map(|j| z[i] - z[j]).product();
            let step = p(z[i]) / den;
            z[i] -= step;
        }
    }
    z
}

#[test]
fn single_dof_exponential_damping_matches_the_roots_of_its_cubic() {
    // m x'' + k x + c (mu e^{-mu t} * x') = 0:
    // m s^3 + m mu s^2 + (k + mu c) s + k mu = 0
    let (m, k, alpha, mu) = (2.0, 8.0e3, 1.6e-3, 50.0);
    let c = alpha * k;
    let mut model = Model::new("single DOF");
    let g = model.add_group(Group::new("g").rayleigh(alpha, 0.0).relaxation(mu)).unwrap();
    model.add_node(1, 0.0, 0.0).unwrap();
    model.add_spring("k", 1, None, [k, 0.0, 0.0], g).unwrap();
    model.add_mass("m", 1, m, 0.0, g).unwrap();
    model.add_support(1, &[Dof::Uy, Dof::Rz]).unwrap();
    let sys = DampedSystem::new(model).unwrap();
    assert_eq!(sys.n(), 1);
    let modes = complex_modes(&sys).unwrap();
    assert_eq!(modes.internal_variables, 1);
    assert_eq!(modes.oscillatory.len(), 1);
    assert_eq!(modes.overdamped.len(), 1);

    let roots = durand_kerner(&[mu, (k + mu * c) / m, k * mu / m]);
    let pair = roots.iter().find(|r| r.im > 1e-6).unwrap();
    let real = roots.iter().find(|r| r.im.abs() < 1e-6).unwrap();
    let s = modes.oscillatory[0].eigenvalue;
    assert!((s - pair).norm() <= 1e-10 * pair.norm(), "{s} vs cubic root {pair}");
    let r = modes.overdamped[0].eigenvalue;
    assert!((r - real.re).abs() <= 1e-10 * real.re.abs(), "{r} vs cubic root {real}");
    // the real root is the kernel's relaxation, moved by the coupling
    assert!(r < 0.0 && r > -mu * 2.0);
}

#[test]
fn a_massless_damped_dof_gives_a_finite_real_root_and_infinite_ones() {
    // ux: m s^2 + k + s h(s) alpha k = 0 (the cubic of the previous test);
    // rz has stiffness kr and damping alpha kr but no inertia:
    // kr + s h(s) alpha kr = 0  ->  s = -mu / (1 + alpha mu).
    // M is singular, so the pencil path (QZ) is taken.
    let (m, k, kr, alpha, mu) = (2.0, 8.0e3, 300.0, 1.6e-3, 50.0);
    let mut model = Model::new("massless rotation");
    let g = model.add_group(Group::new("g").rayleigh(alpha, 0.0).relaxation(mu)).unwrap();
    model.add_node(1, 0.0, 0.0).unwrap();
    model.add_spring("k", 1, None, [k, 0.0, kr], g).unwrap();
    model.add_mass("m", 1, m, 0.0, g).unwrap();
    model.add_support(1, &[Dof::Uy]).unwrap();
    let sys = DampedSystem::new(model).unwrap();
    assert_eq!(sys.n(), 2);
    let modes = complex_modes(&sys).unwrap();
    assert_eq!(modes.internal_variables, 2);
    assert_eq!((modes.oscillatory.len(), modes.overdamped.len(), modes.infinite), (1, 2, 2));
    let c = alpha * k;
    let roots = durand_kerner(&[mu, (k + mu * c) / m, k * mu / m]);
    let pair = roots.iter().find(|r| r.im > 1e-6).unwrap();
    let s = modes.oscillatory[0].eigenvalue;
    assert!((s - pair).norm() <= 1e-10 * pair.norm(), "{s} vs cubic root {pair}");
    let mut reals: Vec<f64> = modes.overdamped.iter().map(|m| m.eigenvalue).collect();
    let mut expected = vec![roots.iter().find(|r| r.im.abs() < 1e-6).unwrap().re, -mu / (1.0 + alpha * mu)];
    reals.sort_by(f64::total_cmp);
    expected.sort_by(f64::total_cmp);
    for (a, b) in reals.iter().zip(&expected) {
        assert!((a - b).abs() <= 1e-10 * b.abs(), "real root {a} vs {b}");
    }
    for m in &modes.overdamped {
        let phi: Vec<C64> = m.shape.iter().map(|&v| C64::new(v, 0.0)).collect();
        assert!(relative_residual(&sys, C64::new(m.eigenvalue, 0.0), &phi) < 1e-12);
    }
}

#[test]
fn modal_expansion_over_all_modes_reproduces_the_receptance() {
    // Z(s)^-1 = sum over every finite eigenvalue of phi phi^T / (a (s - s_k)),
    // the oscillatory ones with their conjugates: checks the normalisation
    // a = phi^T Z'(s_k) phi and that no eigenvalue is missing.
    for (name, model) in [
        ("frame_with_joint", samples::frame_with_joint()),
        ("two_dof", samples::two_dof_oscillator()),
        ("two_material_cantilever", samples::two_material_cantilever()),
        ("space_portal", samples::space_portal()),
    ] {
        let sys = DampedSystem::new(model).unwrap();
        let modes = complex_modes(&sys).unwrap();
        assert_eq!(modes.infinite, 0);
        let n = sys.n();
        for w in [3.0, 70.0, 450.0, 2500.0] {
            let s = C64::new(0.0, w);
            let exact = z_dense(&sys, s).partial_piv_lu().inverse();
            let mut sum = Mat::<C64>::zeros(n, n);
            for m in &modes.oscillatory {
                for i in 0..n {
                    for j in 0..n {
                        let r = m.residue(i, j);
                        sum[(i, j)] += r / (s - m.eigenvalue) + r.conj() / (s - m.eigenvalue.conj());
                    }
                }
            }
            for m in &modes.overdamped {
                for i in 0..n {
                    for j in 0..n {
                        sum[(i, j)] += m.shape[i] * m.shape[j] / m.modal_a / (s - m.eigenvalue);
                    }
                }
            }
            let err = (&sum - &exact).norm_l2() / exact.norm_l2();
            assert!(err < 1e-8, "{name} at w = {w}: relative error {err:e}");
        }
    }
}

#[test]
fn a_large_viscous_mu_gives_the_viscous_modes() {
    let base = samples::frame_with_joint();
    let joint = base.group_index("joint").unwrap();
    let mut viscous = base.clone();
    // an infinite mu is the viscous group
    viscous.set(Quantity::GroupMu(joint), f64::INFINITY).unwrap();
    let mut nearly = base;
    nearly.set(Quantity::GroupMu(joint), 1e9).unwrap();
    let a = complex_modes(&DampedSystem::new(viscous).unwrap()).unwrap();
    let b = complex_modes(&DampedSystem::new(nearly).unwrap()).unwrap();
    assert_eq!(a.internal_variables, 0);
    assert_eq!(b.internal_variables, 1);
    assert_eq!(a.oscillatory.len(), b.oscillatory.len());
    for (x, y) in a.oscillatory.iter().zip(&b.oscillatory) {
        assert!((x.eigenvalue - y.eigenvalue).norm() <= 1e-6 * x.eigenvalue.norm());
    }
}

#[test]
fn models_beyond_the_dense_limit_are_refused_with_their_size() {
    let max = damping::complex_modes::MAX_STATE_DIMENSION;
    let sys = DampedSystem::new(samples::cantilever(300)).unwrap();
    let e = complex_modes(&sys).unwrap_err();
    assert_eq!(e, ModalError::TooLarge { dofs: 900, state_dimension: 1800, max });
    // 699 DOFs fit as a viscous model but not with an exponential kernel on
    // every element: the internal variables push the state past the limit
    let mut model = samples::cantilever(233);
    model.set(Quantity::GroupMu(0), 500.0).unwrap();
    let sys = DampedSystem::new(model).unwrap();
    match complex_modes(&sys).unwrap_err() {
        ModalError::TooLarge { dofs, state_dimension, max: m } => {
            assert_eq!((dofs, m), (699, max));
            assert!(state_dimension > max && state_dimension <= 3 * 699, "{state_dimension}");
        }
        other => panic!("expected TooLarge, got {other:?}"),
    }
}
