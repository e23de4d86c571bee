//! Zero-energy motions found from the model's kinematics: the check behind
//! [`crate::ModelError::Mechanism`].
//!
//! A singular stiffness matrix cannot be told from a badly conditioned one by
//! its pivots: a free 3,000-element beam leaves pivots of `1e-6 K_ii` where a
//! well-supported 5-element frame has `2e-5 K_ii`. The kinematics give an
//! exact answer instead. The zero-energy motions of a set of beams joined at
//! shared nodes are the rigid motions of the set (each beam's only
//! zero-energy motions are its own rigid motions, and a shared node shares
//! its translations and rotations), so every beam-connected part, and every
//! node touched by no beam, is a *body* with three coordinates in a planar
//! model, a translation `(a, b)` and a rotation `t` about a reference point,
//! and six in space, a translation `(a, b, c)` and a rotation `(tx, ty, tz)`
//! (a 3D beam, with its torsion and both bending stiffnesses, has exactly
//! the six rigid motions). Supports,
//! ties and the non-zero stiffnesses of springs then each ask for one
//! combination of these coordinates to be zero. The motions left free, the
//! null space of that small, well-scaled constraint matrix, are exactly the
//! null space of `K`, whatever the stiffness values.
//!
//! Bodies joined by springs or ties are solved together, with a dense SVD;
//! a part with more than [`MAX_BODIES`] bodies (a long chain of springs and
//! masses) is skipped, and the diagonal check of the assembly remains.

use std::collections::HashMap;

use nalgebra::DMatrix;

use crate::dof::{Dimension, Dof, DofRef, PerDof};
use crate::error::ModelError;
use crate::model::{Model, NodeId};
use crate::union_find::UnionFind;

/// Most bodies (beam-connected parts and lone nodes) solved together.
pub const MAX_BODIES: usize = 200;

/// Singular values below this (rows of the constraint matrix have unit
/// norm) count as zero: a motion that no support, tie or spring resists.
const RANK_TOLERANCE: f64 = 1e-9;

/// The zero-energy motions of a model (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct ZeroEnergy {
    /// Number of independent zero-energy motions (the rank deficiency of K).
    pub modes: usize,
    /// The first motion, one value per DOF per node (model order); empty
    /// when `modes` is 0.
    pub first: Vec<PerDof>,
    /// True when some part was too large to check (its motions are not counted).
    pub skipped: bool,
}

/// A rigid body: its reference point and length scale.
struct Body {
    origin: [f64; 3],
    /// The rotation coordinates are `t * scale` so that all coordinates
    /// are lengths of similar size.
    scale: f64,
}

/// One homogeneous constraint: `sum coef * coordinate = 0`, coordinates
/// numbered `nc * body + k` with `nc` coordinates per body: `(a, b, t *
/// scale)` in a planar model, `(a, b, c, tx * scale, ty * scale, tz *
/// scale)` in space.
type Row = Vec<(usize, f64)>;

/// Finds the zero-energy motions of `model` (see the module docs).
pub fn zero_energy_motions(model: &Model) -> ZeroEnergy {
    let nodes = &model.nodes;
    let dim = model.dimension;
    let nc = dim.dofs_per_node();
    let index = |id: NodeId| model.node_index[&id];
    let mut parts = UnionFind::new(nodes.len());
    for b in &model.beams {
        parts.union(index(b.nodes[0]), index(b.nodes[1]));
    }
    // bodies in order of their first node
    let mut body_of = vec![0usize; nodes.len()];
    let mut bodies: Vec<Body> = Vec::new();
    let mut body_of_root: HashMap<usize, usize> = HashMap::new();
    for i in 0..nodes.len() {
        let root = parts.find(i);
        let b = *body_of_root.entry(root).or_insert_with(|| {
            bodies.push(Body { origin: nodes[root].position(), scale: 0.0 });
            bodies.len() - 1
        });
        body_of[i] = b;
        let body = &mut bodies[b];
        let [x0, y0, z0] = body.origin;
        body.scale = body.scale.max((nodes[i].x - x0).hypot(nodes[i].y - y0).hypot(nodes[i].z - z0));
    }
    for body in &mut bodies {
        if !(body.scale > 0.0 && body.scale.is_finite()) {
            body.scale = 1.0;
        }
    }
    // the motion of one DOF of a node in body coordinates: `u = a + t x r`
    // for the translations, `t` for the rotations
    let motion = |node: usize, d: Dof| -> Row {
        let b = body_of[node];
        let body = &bodies[b];
        let [x0, y0, z0] = body.origin;
        let (dx, dy, dz) =
            ((nodes[node].x - x0) / body.scale, (nodes[node].y - y0) / body.scale, (nodes[node].z - z0) / body.scale);
        let o = nc * b;
        match (dim, d) {
            (Dimension::Planar, Dof::Ux) => vec![(o, 1.0), (o + 2, -dy)],
            (Dimension::Planar, Dof::Uy) => vec![(o + 1, 1.0), (o + 2, dx)],
            (Dimension::Planar, _) => vec![(o + 2, 1.0 / body.scale)],
            (Dimension::Spatial, Dof::Ux) => vec![(o, 1.0), (o + 4, dz), (o + 5, -dy)],
            (Dimension::Spatial, Dof::Uy) => vec![(o + 1, 1.0), (o + 5, dx), (o + 3, -dz)],
            (Dimension::Spatial, Dof::Uz) => vec![(o + 2, 1.0), (o + 3, dy), (o + 4, -dx)],
            (Dimension::Spatial, r) => vec![(o + 3 + r.axis(), 1.0 / body.scale)],
        }
    };
    let difference = |p: usize, q: usize, d: Dof| -> Row {
        let mut row = motion(p, d);
        row.extend(motion(q, d).into_iter().map(|(c, v)| (c, -v)));
        row
    };
    let mut rows: Vec<Row> = Vec::new();
    for s in &model.supports {
        rows.extend(s.dofs.iter().map(|&d| motion(index(s.node), d)));
    }
    for t in &model.ties {
        rows.extend(t.dofs.iter().map(|&d| difference(index(t.nodes[0]), index(t.nodes[1]), d)));
    }
    for sp in &model.springs {
        for &d in dim.dofs().iter().filter(|&&d| sp.k[d] > 0.0) {
            // along (or about) the spring's axis of d: the global DOFs
            // weighted by its components
            let mut row = Row::new();
            for (g, c) in sp.direction(dim, d) {
                let part = match sp.b {
                    Some(b) => difference(index(sp.a), index(b), g),
                    None => motion(index(sp.a), g),
                };
                row.extend(part.into_iter().map(|(k, v)| (k, c * v)));
            }
            rows.push(row);
        }
    }

    // bodies coupled by a constraint are solved together
    let mut coupled = UnionFind::new(bodies.len());
    for row in &rows {
        for w in row.windows(2) {
            coupled.union(w[0].0 / nc, w[1].0 / nc);
        }
    }
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); bodies.len()];
    for b in 0..bodies.len() {
        members[coupled.find(b)].push(b);
    }
    let mut rows_of: Vec<Vec<usize>> = vec![Vec::new(); bodies.len()];
    for (r, row) in rows.iter().enumerate() {
        if let Some(&(c, _)) = row.first() {
            rows_of[coupled.find(c / nc)].push(r);
        }
    }

    let mut found = ZeroEnergy { modes: 0, first: Vec::new(), skipped: false };
    for (root, part) in members.iter().enumerate().filter(|(_, m)| !m.is_empty()) {
        if part.len() > MAX_BODIES {
            found.skipped = true;
            continue;
        }
        let column: HashMap<usize, usize> = part.iter().enumerate().map(|(k, &b)| (b, k)).collect();
        let n = nc * part.len();
        let m = rows_of[root].len().max(n);
        let mut c = DMatrix::<f64>::zeros(m, n);
        for (i, &r) in rows_of[root].iter().enumerate() {
            for &(coord, v) in &rows[r] {
                c[(i, nc * column[&(coord / nc)] + coord % nc)] += v;
            }
            let norm = c.row(i).norm();
            if norm > 0.0 {
                c.row_mut(i).unscale_mut(norm);
            }
        }
        let svd = c.svd(false, true);
        let v_t = svd.v_t.expect("requested");
        let null: Vec<usize> = (0..n).filter(|&k| svd.singular_values[k] <= RANK_TOLERANCE).collect();
        if null.is_empty() {
            continue;
        }
        if found.modes == 0 {
            let coords = v_t.row(null[0]);
            found.first = vec![PerDof::default(); nodes.len()];
            for (i, node_motion) in found.first.iter_mut().enumerate() {
                let Some(&k) = column.get(&body_of[i]) else { continue };
                for &d in dim.dofs() {
                    node_motion[d] =
                        motion(i, d).iter().map(|&(coord, v)| v * coords[nc * k + coord % nc]).sum::<f64>();
                }
            }
        }
        found.modes += null.len();
    }
    found
}

/// Refuses a model with a zero-energy motion, naming where the first one
/// moves most: its largest translation (a rotation when nothing translates)
/// and the nodes it moves.
pub(crate) fn check(model: &Model) -> Result<(), ModelError> {
    // imported matrices come without the geometry that says which motions
    // they leave free: only the diagonal check of the assembly applies
    if !model.imported.is_empty() {
        return Ok(());
    }
    let found = zero_energy_motions(model);
    if found.modes == 0 {
        return Ok(());
    }
    let x = &found.first;
    let largest = |dofs: &[Dof]| {
        let mut best = (0.0f64, 0usize, Dof::Ux);
        for (i, m) in x.iter().enumerate() {
            for &d in dofs {
                if m[d].abs() > best.0 {
                    best = (m[d].abs(), i, d);
                }
            }
        }
        best
    };
    let translation = largest(model.dimension.translations());
    let (size, node, dof) = if translation.0 > 1e-9 { translation } else { largest(model.dimension.rotations()) };
    let mut nodes: Vec<u32> = x
        .iter()
        .zip(&model.nodes)
        .filter(|(m, _)| m.0.iter().any(|v| v.abs() > 1e-6 * size))
        .map(|(_, n)| n.id.0)
        .collect();
    nodes.sort_unstable();
    let hint = DofRef { node: model.nodes[node].id, dof }.to_string();
    Err(ModelError::Mechanism { hint, modes: found.modes, nodes })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Group, Section};

    fn beam(n: u32, shape: impl Fn(f64) -> (f64, f64)) -> Model {
        let mut m = Model::new("b");
        let g = m.add_group(Group::new("g")).unwrap();
        let mat = m.add_material("s", 2e11, 7800.0).unwrap();
        let sec = m.add_section(Section::rectangle("r", 0.05, 0.005)).unwrap();
        for i in 0..=n {
            let (x, y) = shape(f64::from(i) / f64::from(n));
            m.add_node(i + 1, x, y).unwrap();
        }
        for i in 1..=n {
            m.add_beam(i, [i, i + 1], mat, sec, g).unwrap();
        }
        m
    }

    fn straight(t: f64) -> (f64, f64) {
        (0.9 * t, 0.0)
    }

    fn curved(t: f64) -> (f64, f64) {
        (0.9 * t, 0.3 * (7.0 * t).sin())
    }

    /// The cases where the pivots of K cannot tell (see the module docs):
    /// long chains with and without supports, straight and curved.
    #[test]
    fn rigid_motions_are_counted_exactly_however_long_the_beam() {
        for n in [5, 3000] {
            for shape in [straight, curved] {
                let free = beam(n, shape);
                assert_eq!(zero_energy_motions(&free).modes, 3, "free, {n} elements");
                let mut pinned = beam(n, shape);
                pinned.add_support(1, &[Dof::Ux, Dof::Uy]).unwrap();
                let z = zero_energy_motions(&pinned);
                assert_eq!(z.modes, 1, "pinned, {n} elements");
                // a rotation about node 1: the far end moves, node 1 does not
                assert!(z.first[0][Dof::Ux].abs() < 1e-12 && z.first[0][Dof::Uy].abs() < 1e-12, "{:?}", z.first[0]);
                assert!(z.first[n as usize][Dof::Uy].abs() > 0.1, "{:?}", z.first[n as usize]);
                let mut clamped = beam(n, shape);
                clamped.add_support(1, &Dof::PLANAR).unwrap();
                assert_eq!(zero_energy_motions(&clamped).modes, 0, "clamped, {n} elements");
                let mut two_pins = beam(n, shape);
                two_pins.add_support(1, &[Dof::Ux, Dof::Uy]).unwrap();
                two_pins.add_support(n + 1, &[Dof::Uy]).unwrap();
                assert_eq!(zero_energy_motions(&two_pins).modes, 0, "pinned and roller, {n} elements");
            }
        }
    }

    #[test]
    fn a_hinge_between_two_cantilevers_is_a_mechanism_only_without_a_rotational_spring() {
        for (kr, modes) in [(0.0, 1), (1e3, 0)] {
            let mut m = beam(4, straight);
            // split the beam at node 3 into two bodies joined by a spring
            m.split_node(3, &[3], 100).unwrap();
            let g = m.group_index("g").unwrap();
            m.add_spring("hinge", 3, Some(100), [1e9, 1e9, kr], g).unwrap();
            m.add_support(1, &Dof::PLANAR).unwrap();
            assert_eq!(zero_energy_motions(&m).modes, modes, "kr = {kr}");
        }
    }

    #[test]
    fn a_roller_in_line_with_a_pin_does_not_stop_the_rotation_about_it_but_a_tie_can() {
        // a vertical roller at x = 0.9 restrains the rotation about the pin at x = 0;
        // a horizontal one at the same point does not (the motion there is vertical)
        let mut m = beam(6, straight);
        m.add_support(1, &[Dof::Ux, Dof::Uy]).unwrap();
        m.add_support(7, &[Dof::Ux]).unwrap();
        assert_eq!(zero_energy_motions(&m).modes, 1);
        // a lone node tied to the tip in all three DOFs moves with it
        m.add_node(50, 0.9, 0.0).unwrap();
        m.add_tie(7, 50, &Dof::PLANAR).unwrap();
        m.add_support(50, &[Dof::Uy]).unwrap();
        assert_eq!(zero_energy_motions(&m).modes, 0);
    }

    #[test]
    fn springs_to_ground_restrain_a_spring_mass_chain_one_direction_each() {
        let mut m = Model::new("chain");
        let g = m.add_group(Group::new("g")).unwrap();
        for i in 1..=3 {
            m.add_node(i, f64::from(i), 0.0).unwrap();
        }
        m.add_spring("ground", 1, None, [1e3, 1e3, 1e3], g).unwrap();
        m.add_spring("s12", 1, Some(2), [1e3, 1e3, 1e3], g).unwrap();
        m.add_spring("s23", 2, Some(3), [1e3, 0.0, 1e3], g).unwrap();
        let z = zero_energy_motions(&m);
        assert_eq!(z.modes, 1);
        assert!((z.first[2][Dof::Uy].abs() - 1.0).abs() < 1e-12, "{:?}", z.first);
        assert!(z.first[0].0.iter().chain(&z.first[1].0).all(|v| v.abs() < 1e-12), "{:?}", z.first);
    }

    /// A bent bar in space (not in any plane), of `n` elements.
    fn space_beam(n: u32) -> Model {
        let mut m = Model::with_dimension("b", crate::dof::Dimension::Spatial);
        let g = m.add_group(Group::new("g")).unwrap();
        let mat = m.add_material("s", 2e11, 7800.0).unwrap();
        m.set_poisson(mat, 0.3).unwrap();
        let sec = m.add_section(Section::rectangle("r", 0.03, 0.02)).unwrap();
        for i in 0..=n {
            let t = f64::from(i) / f64::from(n);
            m.add_node_at(i + 1, [t, 0.3 * (3.0 * t).sin(), 0.2 * t * t]).unwrap();
        }
        for i in 1..=n {
            m.add_beam(i, [i, i + 1], mat, sec, g).unwrap();
        }
        m
    }

    /// In space a body has six rigid motions: a pin leaves the three
    /// rotations about it, two pins the rotation about the line through
    /// them, which a third support off that line stops.
    #[test]
    fn rigid_motions_in_space_are_six_per_body() {
        let translations = [Dof::Ux, Dof::Uy, Dof::Uz];
        assert_eq!(zero_energy_motions(&space_beam(40)).modes, 6);
        let mut pinned = space_beam(40);
        pinned.add_support(1, &translations).unwrap();
        assert_eq!(zero_energy_motions(&pinned).modes, 3);
        pinned.add_support(41, &translations).unwrap();
        let z = zero_energy_motions(&pinned);
        assert_eq!(z.modes, 1, "the turn about the line through the pins");
        // the turn moves the middle of the bent bar, not the pins
        assert!(
            z.first[0].0.iter().take(3).chain(z.first[40].0.iter().take(3)).all(|v| v.abs() < 1e-12),
            "{:?}",
            z.first[0]
        );
        assert!(z.first[20][Dof::Uy].abs() + z.first[20][Dof::Uz].abs() > 1e-3, "{:?}", z.first[20]);
        pinned.add_support(21, &[Dof::Uz]).unwrap();
        assert_eq!(zero_energy_motions(&pinned).modes, 0);
        let mut clamped = space_beam(40);
        clamped.add_support(1, &Dof::SPATIAL).unwrap();
        assert_eq!(zero_energy_motions(&clamped).modes, 0);
        // a ball joint (translations tied) between two clamped-free bars turns freely about three axes
        let mut m = space_beam(4);
        m.split_node(3, &[3], 100).unwrap();
        m.add_tie(3, 100, &translations).unwrap();
        m.add_support(1, &Dof::SPATIAL).unwrap();
        assert_eq!(zero_energy_motions(&m).modes, 3);
        // named at the free end's largest translation (its direction is the
        // first null vector's, any of the three turns)
        match crate::Assembly::new(&m).unwrap_err() {
            ModelError::Mechanism { hint, modes: 3, nodes } if nodes == [4, 5, 100] => {
                assert!(["5:ux", "5:uy", "5:uz"].contains(&hint.as_str()), "{hint}");
            }
            other => panic!("expected a mechanism of three motions, got {other:?}"),
        }
    }
}
