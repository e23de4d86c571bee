//! An imported model (its group matrices exported to Matrix Market files
//! with a DOF table and node coordinates, read back through a case file)
//! is the model built natively: the same dynamic stiffness entry for entry,
//! and the same receptances to 1e-12.
//!
//! The receptances are compared by one dense LU per model, both in the
//! native model's equation order (the sparse solver orders its elimination
//! by the sparsity pattern, and an imported matrix's pattern, its blocks by
//! node pair, differs from the beams', by element). `Z` is the same to its
//! round-off (2e-16 of its largest entry, the matrices summed in another
//! order), and a receptance can move by the condition number of `Z` times
//! that: 8e-13 on the portal in space, held to 1e-12 at every line, while
//! near the planar L-frame's lightly damped modes `Z` is so ill conditioned
//! that the native model's own sparse and dense solutions already differ
//! by 3e-12 at 6.7 Hz. Each line is therefore held to 1e-12 or, where no
//! better is possible (8 of the L-frame's 60 lines), to ten times the
//! condition number of `Z` (equilibrated by its diagonal) times the largest
//! relative difference of its entries.

use std::fmt::Write as _;
use std::path::Path;

use damping::DampedSystem;
use faer::Mat;
use faer::linalg::solvers::DenseSolveCore;
use fe_model::imported::{SymmetricCoo, export, matrix_market};
use fe_model::{Assembly, CaseFile, Dimension, Dof, DofRef, MatrixKind, Model, samples};
use frf::C64;

/// Writes `model`'s matrices into `dir` and a case that imports them, with
/// the model's groups (damping and all).
fn imported_case(model: &Model, dir: &Path) -> CaseFile {
    let assembly = Assembly::new(model).unwrap();
    let exported = export::export(model, &assembly);
    let entries: Vec<Entry<'_>> = exported
        .groups
        .iter()
        .map(|g| Entry {
            group: model.group_index(&g.name).map(|i| model.groups()[i].clone()).unwrap(),
            stiffness: &g.stiffness,
            mass: &g.mass,
            damping: None,
        })
        .collect();
    write_case(model, &exported, &entries, dir)
}

/// One `[[imported.groups]]` entry: its group (damping and factors) and
/// its matrices.
struct Entry<'a> {
    group: fe_model::Group,
    stiffness: &'a SymmetricCoo,
    mass: &'a SymmetricCoo,
    damping: Option<&'a SymmetricCoo>,
}

/// Writes the DOF table and node file of `exported`, each entry's matrices
/// and a case that imports them into `dir`, and reads the case.
fn write_case(model: &Model, exported: &export::Exported, entries: &[Entry<'_>], dir: &Path) -> CaseFile {
    std::fs::write(dir.join("dofs.txt"), exported.dof_table()).unwrap();
    std::fs::write(dir.join("nodes.txt"), export::node_file(model)).unwrap();
    let mut case = format!("title = \"imported {}\"\n", model.title);
    if model.dimension() == Dimension::Spatial {
        case.push_str("[model]\ndimension = 3\n");
    }
    for e in entries {
        let g = &e.group;
        write!(case, "[groups.{}]\nalpha = {:e}\nbeta = {:e}\n", g.name, g.alpha, g.beta).unwrap();
        if let Some(mu) = g.mu {
            writeln!(case, "mu = {mu:e}").unwrap();
        }
        if g.damping != 1.0 {
            writeln!(case, "damping = {:e}", g.damping).unwrap();
        }
    }
    case.push_str("[imported]\nnodes = \"nodes.txt\"\n");
    for e in entries {
        let name = &e.group.name;
        std::fs::write(dir.join(format!("{name}-K.mtx")), matrix_market::write(e.stiffness, "stiffness")).unwrap();
        std::fs::write(dir.join(format!("{name}-M.mtx")), matrix_market::write(e.mass, "mass")).unwrap();
        write!(
            case,
            "[[imported.groups]]\ngroup = \"{name}\"\ndofs = \"dofs.txt\"\nstiffness = \"{name}-K.mtx\"\nmass = \"{name}-M.mtx\"\n"
        )
        .unwrap();
        if let Some(c) = e.damping {
            std::fs::write(dir.join(format!("{name}-C.mtx")), matrix_market::write(c, "viscous damping")).unwrap();
            writeln!(case, "damping = \"{name}-C.mtx\"").unwrap();
        }
    }
    let path = dir.join("imported.toml");
    std::fs::write(&path, case).unwrap();
    CaseFile::load(&path).unwrap()
}

/// `Z(w)` of `sys` as a dense matrix in the equation order of `order`
/// (the DOF owning each equation of another model).
fn dense_z(sys: &DampedSystem, omega: f64, order: &[DofRef]) -> Mat<C64> {
    let a = sys.assembly();
    let eq: Vec<usize> = order.iter().map(|&r| a.dofs().equation(r).expect("the same free DOFs")).collect();
    let mut to = vec![usize::MAX; a.n()];
    for (k, &e) in eq.iter().enumerate() {
        to[e] = k;
    }
    let z = sys.z_values(omega);
    let mut m = Mat::<C64>::zeros(a.n(), a.n());
    for col in 0..a.n() {
        for p in a.pattern().col_ptr()[col]..a.pattern().col_ptr()[col + 1] {
            m[(to[a.pattern().row_idx()[p]], to[col])] = z[p];
        }
    }
    m
}

#[test]
fn an_imported_model_has_the_dynamic_stiffness_and_receptances_of_the_native_one() {
    let dir = tempfile::tempdir().unwrap();
    let portal_dofs = [(7, Dof::Uy), (7, Dof::Rx), (5, Dof::Uz), (6, Dof::Ry), (4, Dof::Ux)];
    let frame_dofs = [(4, Dof::Uy), (3, Dof::Rz), (2, Dof::Ux)];
    for (k, (native, dofs)) in
        [(samples::space_portal(), &portal_dofs[..]), (samples::frame_with_joint(), &frame_dofs[..])]
            .into_iter()
            .enumerate()
    {
        let sub = dir.path().join(format!("model-{k}"));
        std::fs::create_dir_all(&sub).unwrap();
        let imported = imported_case(&native, &sub).model;
        assert!(!imported.imported().is_empty() && imported.beams().is_empty(), "the matrices, not the beams");
        let (a, b) = (DampedSystem::new(native.clone()).unwrap(), DampedSystem::new(imported).unwrap());
        let worst = assert_same_receptances(&a, &b, dofs, &native.title);
        if k == 0 {
            assert!(worst <= 1e-12, "{}: receptances differ by {worst:e}", native.title);
        }
    }
}

/// Asserts that `b` has the dynamic stiffness of `a` to its round-off and
/// the receptances among `dofs` to 1e-12 (or the condition number's
/// allowance, see the module docs) at 60 lines up to 402 Hz; returns the
/// largest receptance difference relative to the channel's largest value.
fn assert_same_receptances(a: &DampedSystem, b: &DampedSystem, dofs: &[(u32, Dof)], title: &str) -> f64 {
    assert_eq!(a.n(), b.n(), "{}: the same free DOFs", title);
    let order: Vec<DofRef> = (0..a.n()).map(|e| a.assembly().dofs().dof_of(e)).collect();
    let eqs: Vec<usize> =
        dofs.iter().map(|&(n, d)| order.iter().position(|&r| r == DofRef::new(n, d)).unwrap()).collect();
    let lines: Vec<f64> = (1..=60).map(|i| 6.7 * f64::from(i)).collect();
    // receptances H[r][c] per line, and the worst differences
    let (mut h_native, mut h_imported) = (Vec::new(), Vec::new());
    let mut worst_z = 0.0f64;
    let mut allowed = Vec::new();
    for &f in &lines {
        let w = 2.0 * std::f64::consts::PI * f;
        let (za, zb) = (dense_z(a, w, &order), dense_z(b, w, &order));
        // the condition number of Z equilibrated by its diagonal (the
        // DOFs mix metres and radians), times the largest relative
        // difference of an entry: how far the receptances may move
        let d: Vec<f64> = (0..a.n()).map(|i| 1.0 / za[(i, i)].norm().sqrt()).collect();
        let scaled = Mat::<C64>::from_fn(a.n(), a.n(), |r, c| za[(r, c)] * (d[r] * d[c]));
        let sv = scaled.as_ref().singular_values().unwrap();
        let delta = (0..a.n())
            .flat_map(|r| (0..a.n()).map(move |c| (r, c)))
            .filter(|&(r, c)| za[(r, c)].norm() > 0.0)
            .map(|(r, c)| (za[(r, c)] - zb[(r, c)]).norm() / za[(r, c)].norm())
            .fold(0.0, f64::max);
        allowed.push(f64::max(1e-12, 10.0 * delta * sv[0] / sv[sv.len() - 1]));
        let scale = (0..a.n())
            .flat_map(|r| (0..a.n()).map(move |c| (r, c)))
            .map(|(r, c)| za[(r, c)].norm())
            .fold(0.0, f64::max);
        for r in 0..a.n() {
            for c in 0..a.n() {
                worst_z = worst_z.max((za[(r, c)] - zb[(r, c)]).norm() / scale);
            }
        }
        let (ra, rb) = (za.partial_piv_lu().inverse(), zb.partial_piv_lu().inverse());
        h_native.push(
            eqs.iter().flat_map(|&r| eqs.iter().map(move |&c| (r, c))).map(|(r, c)| ra[(r, c)]).collect::<Vec<_>>(),
        );
        h_imported.push(
            eqs.iter().flat_map(|&r| eqs.iter().map(move |&c| (r, c))).map(|(r, c)| rb[(r, c)]).collect::<Vec<_>>(),
        );
    }
    assert!(worst_z <= 1e-15, "{}: Z differs by {worst_z:e} of its largest entry", title);
    // each receptance relative to its largest over the lines
    let mut worst = 0.0f64;
    for ch in 0..eqs.len() * eqs.len() {
        let scale = h_native.iter().map(|h| h[ch].norm()).fold(0.0, f64::max);
        for (l, (x, y)) in h_native.iter().zip(&h_imported).enumerate() {
            let e = (x[ch] - y[ch]).norm() / scale;
            assert!(e <= allowed[l], "{}: receptance {ch} at {} Hz differs by {e:e}", title, lines[l]);
            worst = worst.max(e);
        }
    }
    worst
}

/// A viscous damping matrix that no group's `alpha K_g + beta M_g` can
/// give: the portal's frame and joint damped in their own proportions,
/// imported as one group whose stiffness, mass and damping are the sums.
/// The native portal (its joint made viscous) is the truth.
#[test]
fn an_imported_damping_matrix_gives_the_native_non_proportional_viscous_damping() {
    let dir = tempfile::tempdir().unwrap();
    let mut native = samples::space_portal();
    let joint = native.quantity("group.joint.mu").unwrap();
    native.set(joint, f64::INFINITY).unwrap();
    let a = Assembly::new(&native).unwrap();
    let exported = export::export(&native, &a);
    let sum = |kind: MatrixKind| {
        let mut v = vec![0.0; a.pattern().nnz()];
        for (g, group) in native.groups().iter().enumerate() {
            let c = match kind {
                MatrixKind::Stiffness => [1.0, 0.0],
                MatrixKind::Mass => [0.0, 1.0],
                MatrixKind::Damping => [group.alpha, group.beta],
            };
            let (k, m) = (a.group_values(g, MatrixKind::Stiffness), a.group_values(g, MatrixKind::Mass));
            v.iter_mut().zip(k.iter().zip(&m)).for_each(|(s, (k, m))| *s += c[0] * k + c[1] * m);
        }
        SymmetricCoo::lower_of(a.pattern(), &v)
    };
    let (k, m, c) = (sum(MatrixKind::Stiffness), sum(MatrixKind::Mass), sum(MatrixKind::Damping));
    let entries = [Entry { group: fe_model::Group::new("all"), stiffness: &k, mass: &m, damping: Some(&c) }];
    let imported = write_case(&native, &exported, &entries, dir.path()).model;
    assert_eq!(imported.groups().len(), 1);
    let (sa, sb) = (DampedSystem::new(native.clone()).unwrap(), DampedSystem::new(imported).unwrap());
    let dofs = [(7, Dof::Uy), (7, Dof::Rx), (5, Dof::Uz), (6, Dof::Ry), (4, Dof::Ux)];
    let worst = assert_same_receptances(&sa, &sb, &dofs, "one group with the portal's damping");
    assert!(worst <= 1e-12, "receptances differ by {worst:e}");
    // the same model without its damping matrix is another one
    let mut undamped = sb.model().clone();
    undamped.set(undamped.quantity("group.all.damping").unwrap(), 1e-9).unwrap();
    let sc = DampedSystem::new(undamped).unwrap();
    let w = 2.0 * std::f64::consts::PI * 100.0;
    let order: Vec<DofRef> = (0..sa.n()).map(|e| sa.assembly().dofs().dof_of(e)).collect();
    let (za, zc) = (dense_z(&sa, w, &order), dense_z(&sc, w, &order));
    assert!((0..sa.n()).any(|i| (za[(i, i)].im - zc[(i, i)].im).abs() > 1e-3 * za[(i, i)].im.abs()));
}

/// A damping matrix adds to its group's own damping: the portal's frame
/// imported with its beta and with its `alpha K` as a damping matrix, the
/// joint with its non-viscous kernel, equals the native portal; and the
/// group's damping factor scales the matrix (2 equals the native frame
/// with twice its alpha).
#[test]
fn an_imported_damping_matrix_adds_to_the_group_damping_and_its_factor_scales_it() {
    let dir = tempfile::tempdir().unwrap();
    for factor in [1.0, 2.0] {
        let mut native = samples::space_portal();
        let alpha = native.quantity("group.frame.alpha").unwrap();
        let frame_alpha = native.get(alpha);
        native.set(alpha, factor * frame_alpha).unwrap();
        let a = Assembly::new(&native).unwrap();
        let exported = export::export(&native, &a);
        let f = native.group_index("frame").unwrap();
        let kf = a.group_values(f, MatrixKind::Stiffness);
        let c = SymmetricCoo::lower_of(a.pattern(), &kf.iter().map(|k| frame_alpha * k).collect::<Vec<_>>());
        let entries: Vec<Entry<'_>> = exported
            .groups
            .iter()
            .map(|e| {
                let mut group = native.groups()[native.group_index(&e.name).unwrap()].clone();
                let damping = (e.name == "frame").then_some(&c);
                if damping.is_some() {
                    (group.alpha, group.damping) = (0.0, factor);
                }
                Entry { group, stiffness: &e.stiffness, mass: &e.mass, damping }
            })
            .collect();
        assert!(entries.iter().any(|e| e.group.mu.is_some()), "a non-viscous group beside");
        let sub = dir.path().join(format!("factor-{factor}"));
        std::fs::create_dir_all(&sub).unwrap();
        let imported = write_case(&native, &exported, &entries, &sub).model;
        let (sa, sb) = (DampedSystem::new(native.clone()).unwrap(), DampedSystem::new(imported).unwrap());
        let dofs = [(7, Dof::Uy), (7, Dof::Rx), (5, Dof::Uz), (6, Dof::Ry), (4, Dof::Ux)];
        let worst = assert_same_receptances(&sa, &sb, &dofs, &format!("damping factor {factor}"));
        assert!(worst <= 1e-12, "factor {factor}: receptances differ by {worst:e}");
    }
}
