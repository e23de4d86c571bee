//! `element.<id>.bending`, a factor on an element's bending stiffness alone,
//! against the static deflections of cantilevers: Euler-Bernoulli beam
//! theory (moment-area) for the bending, `P L / EA` and `T L / GJ` for the
//! axial and torsional stiffness it must leave alone.

use fe_model::{Assembly, Dimension, Dof, DofRef, Group, Model, Section};
use nalgebra::DVector;

/// The static displacement of `model` under the given nodal loads.
fn deflect(model: &Model, loads: &[(u32, Dof, f64)]) -> impl Fn(u32, Dof) -> f64 + use<> {
    let a = Assembly::new(model).unwrap();
    let mut f = DVector::zeros(a.n());
    for &(node, dof, value) in loads {
        f[a.dofs().equation(DofRef::new(node, dof)).unwrap()] += value;
    }
    let u = a.stiffness_dense().cholesky().expect("a supported structure").solve(&f);
    move |node, dof| u[a.dofs().equation(DofRef::new(node, dof)).unwrap()]
}

fn scale_bending(model: &mut Model, range: &str, factor: f64) {
    let p = model.parameter(&format!("element.{range}.bending")).unwrap();
    for q in p.quantities {
        model.set(q, factor).unwrap();
    }
}

#[test]
fn a_bending_factor_over_the_root_half_bends_a_cantilever_as_moment_area_says_and_leaves_it_axially_stiff() {
    // fe_model::samples::cantilever: 1 m of 50 x 10 mm steel, 10 elements
    let (e, b, h, l) = (2.0e11, 0.05, 0.01, 1.0);
    let (area, inertia) = (b * h, b * h * h * h / 12.0);
    let f = 0.6;
    let mut model = fe_model::samples::cantilever(10);
    scale_bending(&mut model, "1..5", f);
    let (p, tip) = (10.0, 11);
    let u = deflect(&model, &[(tip, Dof::Uy, p), (tip, Dof::Ux, p)]);
    // tip deflection int_0^L M(x) (L - x) / EI(x) dx with M = P (L - x),
    // EI = f E I over 0..a
    let a: f64 = 0.5;
    let expected = p / (e * inertia) * ((l * l * l - (l - a).powi(3)) / (3.0 * f) + (l - a).powi(3) / 3.0);
    assert!((u(tip, Dof::Uy) / expected - 1.0).abs() < 1e-10, "uy {} vs {expected}", u(tip, Dof::Uy));
    let axial = p * l / (e * area);
    assert!((u(tip, Dof::Ux) / axial - 1.0).abs() < 1e-10, "ux {} vs {axial}", u(tip, Dof::Ux));
}

#[test]
fn in_space_a_bending_factor_softens_both_bending_planes_and_neither_torsion_nor_tension() {
    let (e, nu, b, h, l) = (2.0e11, 0.3, 0.04, 0.02, 0.8);
    let section = Section::rectangle("bar", b, h);
    let build = |f: f64| {
        let mut m = Model::with_dimension("3D cantilever", Dimension::Spatial);
        let g = m.add_group(Group::new("g")).unwrap();
        let steel = m.add_material("steel", e, 7800.0).unwrap();
        m.set_poisson(steel, nu).unwrap();
        let sec = m.add_section(section.clone()).unwrap();
        for i in 0..=4u32 {
            m.add_node_at(i + 1, [l * f64::from(i) / 4.0, 0.0, 0.0]).unwrap();
        }
        for i in 0..4u32 {
            m.add_beam(i + 1, [i + 1, i + 2], steel, sec, g).unwrap();
        }
        m.add_support(1, &Dof::SPATIAL).unwrap();
        if f != 1.0 {
            scale_bending(&mut m, "1..4", f);
        }
        m
    };
    let (p, t, tip) = (10.0, 3.0, 5);
    let loads = [(tip, Dof::Ux, p), (tip, Dof::Uy, p), (tip, Dof::Uz, p), (tip, Dof::Rx, t)];
    let f = 0.45;
    let u = deflect(&build(f), &loads);
    // the two bending planes: P L^3 / (3 f E I) about each axis, the larger
    // deflection about the smaller second moment
    let mut bent = [u(tip, Dof::Uy), u(tip, Dof::Uz)];
    bent.sort_by(f64::total_cmp);
    let mut expected = [section.inertia, section.iy].map(|i: f64| p * l * l * l / (3.0 * f * e * i));
    expected.sort_by(f64::total_cmp);
    for (got, want) in bent.iter().zip(expected) {
        assert!((got / want - 1.0).abs() < 1e-10, "bending {got} vs {want}");
    }
    let axial = p * l / (e * section.area);
    assert!((u(tip, Dof::Ux) / axial - 1.0).abs() < 1e-10, "ux {} vs {axial}", u(tip, Dof::Ux));
    let g = e / (2.0 * (1.0 + nu));
    let twist = t * l / (g * section.torsion);
    assert!((u(tip, Dof::Rx) / twist - 1.0).abs() < 1e-10, "twist {} vs {twist}", u(tip, Dof::Rx));
}

#[test]
fn the_bending_factor_resolves_by_name_and_refuses_what_set_refuses() {
    let mut model = fe_model::samples::cantilever(4);
    let q = model.quantity("element.3.bending").unwrap();
    assert_eq!(model.quantity_name(q).to_string(), "element.3.bending");
    assert_eq!(model.get(q), 1.0);
    model.set(q, 0.7).unwrap();
    assert_eq!(model.get(q), 0.7);
    for bad in [0.0, f64::NAN] {
        let e = model.set(q, bad).unwrap_err().to_string();
        assert!(e.contains(&format!("element.3.bending cannot be set to {bad}")), "{e}");
    }
    let e = model.quantity("element.3.bend").unwrap_err().to_string();
    assert!(e.contains("bending"), "{e}");
}
