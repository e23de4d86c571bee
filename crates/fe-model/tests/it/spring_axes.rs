//! `[[springs]]` in their own axes (`x_axis`, `xy_vector`) in a 3D case:
//! the assembled stiffness is the diagonal of the spring's stiffnesses
//! turned to global axes by hand, `spring.<name>.kx` is the stiffness along
//! the local x axis, and bad axes are refused at their line and column.

use std::path::Path;

use approx::assert_relative_eq;
use fe_model::{Assembly, CaseFile, Dof, DofRef};
use nalgebra::{Matrix3, Vector3};

/// A 3D case: a foot node on a ground spring with the given lines, a
/// clamped node beside it (so that the case has a beam), and the spring
/// between node 2 and the ground.
fn case(spring: &str) -> String {
    format!(
        "title = \"spring axes\"\n\
         [model]\ndimension = 3\n\
         [materials]\nsteel = {{ E = 2e11, rho = 7800, nu = 0.3 }}\n\
         [sections]\nbar = {{ b = 0.02, h = 0.03 }}\n\
         [groups.g]\n\
         [[lines]]\nfrom = [0.0, 0.0, 0.0]\nto = [0.0, 0.0, 0.5]\nelements = 1\nmaterial = \"steel\"\nsection = \"bar\"\ngroup = \"g\"\n\
         [[supports]]\nnode = 1\n\
         [[springs]]\nname = \"mount\"\nnode = 2\ngroup = \"g\"\n{spring}"
    )
}

fn parse(text: &str) -> Result<CaseFile, fe_model::CaseError> {
    CaseFile::parse(Path::new("axes.toml"), text)
}

/// The spring's global stiffness over node 2's translations and rotations,
/// taken out of the assembly (the beam's own subtracted).
fn spring_blocks(text: &str) -> (Matrix3<f64>, Matrix3<f64>) {
    let with = Assembly::new(&parse(text).unwrap().model).unwrap();
    let k = with.stiffness_dense();
    let beam_only = {
        let mut m = parse(text).unwrap().model;
        for key in ["kx", "ky", "kz", "krx", "kry", "krz"] {
            let q = m.quantity(&format!("spring.mount.{key}")).unwrap();
            m.set(q, 0.0).unwrap();
        }
        m
    };
    // the beam alone, with the same equations: the spring's stiffnesses
    // zero (which only the assembly of a part, without the whole model's
    // checks, accepts)
    let kb = Assembly::of_part(&beam_only).unwrap().stiffness_dense();
    let eq = |d: Dof| with.dofs().equation(DofRef::new(2, d)).unwrap();
    let block =
        |dofs: [Dof; 3]| Matrix3::from_fn(|r, c| k[(eq(dofs[r]), eq(dofs[c]))] - kb[(eq(dofs[r]), eq(dofs[c]))]);
    (block([Dof::Ux, Dof::Uy, Dof::Uz]), block([Dof::Rx, Dof::Ry, Dof::Rz]))
}

#[test]
fn a_spring_in_its_own_axes_is_its_diagonal_turned_by_hand() {
    let text = case(
        "kx = 4e6\nky = 1e6\nkz = 2.5e5\nkrx = 300.0\nkry = 120.0\nkrz = 60.0\n\
         x_axis = [1.0, 1.0, 0.0]\nxy_vector = [0.0, 0.0, 1.0]\n",
    );
    let (kt, kr) = spring_blocks(&text);
    // local x along (1, 1, 0), local y along z (the x-y plane holds z), local z = x × y = (1, -1, 0) / sqrt 2
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let r = Matrix3::new(s, s, 0.0, 0.0, 0.0, 1.0, s, -s, 0.0);
    let by_hand = |k: [f64; 3]| r.transpose() * Matrix3::from_diagonal(&Vector3::from(k)) * r;
    assert_relative_eq!(kt, by_hand([4e6, 1e6, 2.5e5]), max_relative = 1e-12, epsilon = 1e-6);
    assert_relative_eq!(kr, by_hand([300.0, 120.0, 60.0]), max_relative = 1e-12, epsilon = 1e-9);
    // written out: kx and kz share the x-y diagonal, ky is along global z
    assert_relative_eq!(kt[(0, 0)], (4e6 + 2.5e5) / 2.0, max_relative = 1e-12);
    assert_relative_eq!(kt[(0, 1)], (4e6 - 2.5e5) / 2.0, max_relative = 1e-12);
    assert_relative_eq!(kt[(2, 2)], 1e6, max_relative = 1e-12);
    // without axes the same lines give the diagonal in global axes
    let (kt, _) = spring_blocks(&case("kx = 4e6\nky = 1e6\nkz = 2.5e5\nkrx = 300.0\n"));
    assert_relative_eq!(kt, Matrix3::from_diagonal(&Vector3::new(4e6, 1e6, 2.5e5)), epsilon = 1e-6);
}

#[test]
fn spring_stiffness_names_keep_meaning_the_local_directions() {
    let text = case("kx = 4e6\nky = 1e6\nkz = 2.5e5\nx_axis = [0.0, 3.0, 4.0]\nxy_vector = [1.0, 0.0, 0.0]\n");
    let mut c = parse(&text).unwrap();
    let q = c.model.quantity("spring.mount.kx").unwrap();
    assert_eq!(c.model.get(q), 4e6);
    c.model.set(q, 7e6).unwrap();
    let a = Assembly::new(&c.model).unwrap();
    let k = a.stiffness_dense();
    let eq = |d: Dof| a.dofs().equation(DofRef::new(2, d)).unwrap();
    let kt = Matrix3::from_fn(|r, col| k[(eq([Dof::Ux, Dof::Uy, Dof::Uz][r]), eq([Dof::Ux, Dof::Uy, Dof::Uz][col]))]);
    let x = Vector3::new(0.0, 0.6, 0.8);
    let y = Vector3::new(1.0, 0.0, 0.0);
    // the beam along z adds its own stiffness; the spring's along its local
    // axes is what changes with kx: the x axis carries 7e6 more than before
    let before = Assembly::new(&parse(&text).unwrap().model).unwrap().stiffness_dense();
    let kt0 =
        Matrix3::from_fn(|r, col| before[(eq([Dof::Ux, Dof::Uy, Dof::Uz][r]), eq([Dof::Ux, Dof::Uy, Dof::Uz][col]))]);
    let d = kt - kt0;
    assert_relative_eq!(x.dot(&(d * x)), 3e6, max_relative = 1e-9);
    assert_relative_eq!((d * y).norm(), 0.0, epsilon = 1e-6);
}

#[test]
fn bad_spring_axes_are_refused_at_their_line_and_column() {
    let cases = [
        (
            "kx = 1e6\nx_axis = [1.0, 2.0, 3.0]\nxy_vector = [-2.0, -4.0, -6.0]\n",
            "axes.toml:24:13: spring `mount` has the x-y plane vector [-2.0, -4.0, -6.0] along its local x axis",
        ),
        (
            "kx = 1e6\nx_axis = [0.0, 0.0, 0.0]\nxy_vector = [0.0, 1.0, 0.0]\n",
            "axes.toml:23:10: spring `mount` has the local x axis [0.0, 0.0, 0.0], which is zero",
        ),
        (
            "kx = 1e6\nx_axis = [1.0, 0.0, 0.0]\nxy_vector = [0.0, 0.0, 0.0]\n",
            "axes.toml:24:13: spring `mount` has the x-y plane vector [0.0, 0.0, 0.0], which is zero",
        ),
        ("kx = 1e6\nxy_vector = [0.0, 1.0, 0.0]\n", "axes.toml:23:13: spring `mount`: give both `x_axis`"),
        ("kx = 1e6\nx_axis = [1.0, 0.0]\nxy_vector = [0.0, 1.0, 0.0]\n", "axes.toml:23:10:"),
    ];
    for (lines, want) in cases {
        let e = parse(&case(lines)).unwrap_err().to_string();
        assert!(e.starts_with(want), "{lines}: {e}");
    }
    // a planar case has no spring axes
    let planar = case("kx = 1e6\nx_axis = [1.0, 0.0, 0.0]\nxy_vector = [0.0, 1.0, 0.0]\n")
        .replace("dimension = 3", "dimension = 2")
        .replace(", nu = 0.3", "")
        .replace("to = [0.0, 0.0, 0.5]", "to = [0.0, 0.5]")
        .replace("from = [0.0, 0.0, 0.0]", "from = [0.0, 0.0]");
    let e = parse(&planar).unwrap_err().to_string();
    assert!(
        e.starts_with("axes.toml:23:10: spring `mount` has axes of its own, which only a spring of a 3D model has"),
        "{e}"
    );
}

/// The kinematic check follows a spring's axes: a node hung on an oblique
/// spring without a stiffness about its local z axis turns freely about
/// that axis, which no global DOF's diagonal shows (each has stiffness from
/// the other local directions), and is refused as a mechanism; with the
/// sixth stiffness it is not.
#[test]
fn a_spring_missing_one_local_stiffness_leaves_a_mechanism_along_that_axis() {
    let lines = "kx = 4e6\nky = 1e6\nkz = 2.5e5\nkrx = 300.0\nkry = 120.0\nkrz = 60.0\n\
                 x_axis = [1.0, 1.0, 0.3]\nxy_vector = [0.0, 0.2, 1.0]\n";
    let joint = |lines: &str| {
        // node 100 beside node 2, joined to it by the spring instead of to the ground
        case(lines)
            .replace("node = 2\ngroup", "nodes = [2, 100]\ngroup")
            .replace("title", "nodes = [[100, 0.0, 0.0, 0.5]]\ntitle")
            .replace("[[supports]]", "first_node = 1\n[[supports]]")
    };
    // the case reader assembles the model, and refuses a mechanism
    Assembly::new(&parse(&joint(lines)).unwrap().model).unwrap();
    let e = parse(&joint(&lines.replace("krz = 60.0\n", ""))).unwrap_err().to_string();
    // the local z axis is (0.94, -1, 0.2) (x_axis × xy_vector): the turn
    // about it is largest about global y
    assert!(e.contains("is a mechanism") && e.contains("largest at 100:ry (node 100)"), "{e}");
}
