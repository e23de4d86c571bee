//! Tiny canonical models shared by tests, examples, benchmarks and docs.
//!
//! Behind the `samples` feature: they are fixtures, which unwrap what a
//! user's model would return as an error, so they are not part of the
//! default API. Enable it where they are used, as a dev-dependency:
//! `fe-model = { workspace = true, features = ["samples"] }`.

use crate::dof::{Dimension, Dof, DofRef};
use crate::model::{Group, Model, Section};

/// A uniform steel cantilever, 1 m long, 50 x 10 mm, clamped at node 1,
/// `n` elements along x, nodes `1..=n+1`, one viscous group `beam`
/// (alpha = 1e-5, beta = 0.5).
pub fn cantilever(n: usize) -> Model {
    let mut m = Model::new("uniform steel cantilever");
    let g = m.add_group(Group::new("beam").rayleigh(1e-5, 0.5)).unwrap();
    let mat = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let sec = m.add_section(Section::rectangle("bar", 0.05, 0.01)).unwrap();
    for i in 0..=n {
        m.add_node(i as u32 + 1, i as f64 / n as f64, 0.0).unwrap();
    }
    for i in 0..n {
        m.add_beam(i as u32 + 1, [i as u32 + 1, i as u32 + 2], mat, sec, g).unwrap();
    }
    m.add_support(1, &Dof::PLANAR).unwrap();
    m
}

/// The paper's two-material cantilever (900 x 50 x 5 mm, 30 elements, steel
/// then aluminium, clamped at the steel end) with the *true* damping of its
/// Table 1: mu = 631.12 / 38274 rad/s, alpha = 1e-5 / 3e-5, beta = 0.1 / 0.2.
pub fn two_material_cantilever() -> Model {
    let mut m = Model::new("two-material cantilever (Arora et al. 2023, Table 1)");
    let steel_g = m.add_group(Group::new("steel").rayleigh(1e-5, 0.1).relaxation(631.12)).unwrap();
    let alu_g = m.add_group(Group::new("aluminium").rayleigh(3e-5, 0.2).relaxation(38274.0)).unwrap();
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let alu = m.add_material("aluminium", 0.69e11, 2700.0).unwrap();
    let sec = m.add_section(Section::rectangle("strip", 0.05, 0.005)).unwrap();
    let n = 30;
    for i in 0..=n {
        m.add_node(i + 1, 0.9 * f64::from(i) / f64::from(n), 0.0).unwrap();
    }
    for i in 0..n {
        let (mat, g) = if i < n / 2 { (steel, steel_g) } else { (alu, alu_g) };
        m.add_beam(i + 1, [i + 1, i + 2], mat, sec, g).unwrap();
    }
    m.add_support(1, &Dof::PLANAR).unwrap();
    m
}

/// An L-shaped frame with a flexible, lossy joint: a 1 m steel column
/// (nodes 1-2, clamped at 1) and a 1 m arm (nodes 3-4) whose first node 3
/// coincides with 2, tied to it in ux and uy and joined by a rotational
/// spring `joint` (kr = 2e5 N m/rad) in group `joint` (alpha = 1e-3,
/// mu = 300 rad/s). The members are in group `frame` (viscous Rayleigh).
pub fn frame_with_joint() -> Model {
    frame_with_joint_turned(0.0)
}

/// [`frame_with_joint`] with every node turned by `theta` (radians) about
/// the origin, in the plane: the same structure in another orientation.
pub fn frame_with_joint_turned(theta: f64) -> Model {
    let (c, s) = (theta.cos(), theta.sin());
    let mut m = Model::new("L-frame with a lossy joint");
    let frame = m.add_group(Group::new("frame").rayleigh(2e-5, 0.3)).unwrap();
    let joint = m.add_group(Group::new("joint").rayleigh(1e-3, 0.0).relaxation(300.0)).unwrap();
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let sec = m.add_section(Section::rectangle("square", 0.03, 0.03)).unwrap();
    for (id, x, y) in [(1, 0.0, 0.0), (2, 0.0, 1.0), (3, 0.0, 1.0), (4, 1.0, 1.0)] {
        m.add_node(id, c * x - s * y, s * x + c * y).unwrap();
    }
    m.add_beam(1, [1, 2], steel, sec, frame).unwrap();
    m.add_beam(2, [3, 4], steel, sec, frame).unwrap();
    m.add_spring("joint", 2, Some(3), [0.0, 0.0, 2.0e5], joint).unwrap();
    m.add_tie(2, 3, &[Dof::Ux, Dof::Uy]).unwrap();
    m.add_mass("tip", 4, 0.5, 1e-4, frame).unwrap();
    m.add_support(1, &Dof::PLANAR).unwrap();
    m
}

/// Two masses on springs along x (a 2-DOF oscillator): ground -k1- m1 -k2- m2,
/// with k1 = 1000 N/m, k2 = 500 N/m, m1 = 1 kg, m2 = 0.5 kg, in one viscous
/// group (alpha = 1e-3, beta = 0.1). The uy and rz DOFs are fixed.
pub fn two_dof_oscillator() -> Model {
    let mut m = Model::new("2-DOF oscillator");
    let g = m.add_group(Group::new("g").rayleigh(1e-3, 0.1)).unwrap();
    m.add_node(1, 0.0, 0.0).unwrap();
    m.add_node(2, 1.0, 0.0).unwrap();
    m.add_spring("k1", 1, None, [1000.0, 0.0, 0.0], g).unwrap();
    m.add_spring("k2", 1, Some(2), [500.0, 0.0, 0.0], g).unwrap();
    m.add_mass("m1", 1, 1.0, 0.0, g).unwrap();
    m.add_mass("m2", 2, 0.5, 0.0, g).unwrap();
    m.add_support(1, &[Dof::Uy, Dof::Rz]).unwrap();
    m.add_support(2, &[Dof::Uy, Dof::Rz]).unwrap();
    m
}

/// Number of regions (damping groups) of [`long_beam`].
pub const LONG_BEAM_REGIONS: usize = 6;

/// A long continuous steel beam for benchmarks: `n_elements` elements of
/// 50 mm (section 50 x 10 mm) along x, nodes `1..=n_elements+1`, clamped at
/// node 1 and pinned (ux, uy) every 20 elements, so that it is a chain of
/// 1 m spans whose conditioning does not grow with its length. It has
/// `3 n - 2 floor(n / 20)` equations for `n` elements (34,483 elements give
/// about 100,000).
///
/// The elements are split into [`LONG_BEAM_REGIONS`] consecutive regions
/// (fewer when there are fewer elements), each its own group `r1`, `r2`, ...
/// with its own non-viscous damping, so that each region offers five
/// parameters (alpha, beta, mu, stiffness and mass factors).
pub fn long_beam(n_elements: usize) -> Model {
    let n = n_elements.max(1);
    let mut m = Model::new("long multi-span beam");
    let regions = LONG_BEAM_REGIONS.min(n);
    let groups: Vec<usize> = (0..regions)
        .map(|r| {
            let x = r as f64;
            let g = Group::new(&format!("r{}", r + 1)).rayleigh(1e-5 * (1.0 + 0.2 * x), 0.5 + 0.1 * x);
            m.add_group(g.relaxation(500.0 * (1.0 + x))).unwrap()
        })
        .collect();
    let mat = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let sec = m.add_section(Section::rectangle("bar", 0.05, 0.01)).unwrap();
    for i in 0..=n {
        m.add_node(i as u32 + 1, 0.05 * i as f64, 0.0).unwrap();
    }
    for i in 0..n {
        let g = groups[i * regions / n];
        m.add_beam(i as u32 + 1, [i as u32 + 1, i as u32 + 2], mat, sec, g).unwrap();
    }
    m.add_support(1, &Dof::PLANAR).unwrap();
    for i in (20..=n).step_by(20) {
        m.add_support(i as u32 + 1, &[Dof::Ux, Dof::Uy]).unwrap();
    }
    m
}

/// A planar multi-storey steel frame for benchmarks: `bays` bays of 2 m and
/// `storeys` storeys of 1.5 m, every column and floor beam divided into
/// `elements_per_member` elements, columns clamped at the base. Columns
/// (80 x 80 mm) are in group `columns` (non-viscous, mu = 800 rad/s), floor
/// beams (60 x 120 mm) in group `beams` (viscous).
///
/// The joints are nodes `1..=(bays+1)(storeys+1)`, numbered along each floor
/// from the ground up; member-interior nodes follow. There are
/// `3 [(bays+1) storeys + members (elements_per_member - 1)]` equations with
/// `members = (2 bays + 1) storeys`: `frame_grid(10, 10, 16)` has 9,780.
pub fn frame_grid(bays: usize, storeys: usize, elements_per_member: usize) -> Model {
    let (bays, storeys, per) = (bays.max(1), storeys.max(1), elements_per_member.max(1));
    let mut m = Model::new("multi-storey frame");
    let columns = m.add_group(Group::new("columns").rayleigh(2e-5, 0.2).relaxation(800.0)).unwrap();
    let beams = m.add_group(Group::new("beams").rayleigh(3e-5, 0.3)).unwrap();
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let col_sec = m.add_section(Section::rectangle("column", 0.08, 0.08)).unwrap();
    let beam_sec = m.add_section(Section::rectangle("beam", 0.06, 0.12)).unwrap();
    let (width, height) = (2.0, 1.5);
    let joint = |bay: usize, floor: usize| (floor * (bays + 1) + bay + 1) as u32;
    for floor in 0..=storeys {
        for bay in 0..=bays {
            m.add_node(joint(bay, floor), width * bay as f64, height * floor as f64).unwrap();
        }
    }
    let mut next_node = joint(bays, storeys) + 1;
    let mut next_element = 1u32;
    let mut member = |m: &mut Model, a: (usize, usize), b: (usize, usize), sec: usize, group: usize| {
        let (xa, ya) = (width * a.0 as f64, height * a.1 as f64);
        let (xb, yb) = (width * b.0 as f64, height * b.1 as f64);
        let mut prev = joint(a.0, a.1);
        for e in 1..=per {
            let node = if e == per {
                joint(b.0, b.1)
            } else {
                let t = e as f64 / per as f64;
                let id = next_node;
                next_node += 1;
                m.add_node(id, xa + t * (xb - xa), ya + t * (yb - ya)).unwrap();
                id
            };
            m.add_beam(next_element, [prev, node], steel, sec, group).unwrap();
            next_element += 1;
            prev = node;
        }
    };
    for floor in 0..storeys {
        for bay in 0..=bays {
            member(&mut m, (bay, floor), (bay, floor + 1), col_sec, columns);
        }
        for bay in 0..bays {
            member(&mut m, (bay, floor + 1), (bay + 1, floor + 1), beam_sec, beams);
        }
    }
    for bay in 0..=bays {
        m.add_support(joint(bay, 0), &Dof::PLANAR).unwrap();
    }
    m
}

/// One member of a [`tree_frame`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TreeMember {
    /// Node it starts at: an earlier node (1-based).
    pub from: u32,
    /// Length (m).
    pub length: f64,
    /// Direction from the x axis (rad).
    pub angle: f64,
    /// Depth of its 50 mm wide rectangular section (m).
    pub depth: f64,
}

/// Tree members from raw numbers, as a property test draws them: member
/// `k` starts at node `from % (k + 1) + 1` (always an earlier node) and
/// takes `length`, `angle` and `depth` as they are.
pub fn tree_members(raw: &[(usize, f64, f64, f64)]) -> Vec<TreeMember> {
    raw.iter()
        .enumerate()
        .map(|(k, &(from, length, angle, depth))| TreeMember {
            from: (from % (k + 1)) as u32 + 1,
            length,
            angle,
            depth,
        })
        .collect()
}

/// A steel frame shaped as a tree, for property tests: node 1 at the
/// origin, and member `k` (0-based, element id `k + 1`) from node
/// `members[k].from` to a new node `k + 2`. Members alternate between the
/// undamped groups `a` and `b`. The elements are added in `order` (a
/// permutation of the member indices), so that two orders give the same
/// structure. Clamped at node 1 when `clamped`; otherwise free.
pub fn tree_frame(members: &[TreeMember], order: &[usize], clamped: bool) -> Model {
    let mut m = Model::new("tree frame");
    let groups = [m.add_group(Group::new("a")).unwrap(), m.add_group(Group::new("b")).unwrap()];
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let sections: Vec<usize> = members
        .iter()
        .enumerate()
        .map(|(k, t)| m.add_section(Section::rectangle(&format!("s{}", k + 1), 0.05, t.depth)).unwrap())
        .collect();
    m.add_node(1, 0.0, 0.0).unwrap();
    for (k, t) in members.iter().enumerate() {
        let start = m.node(crate::NodeId(t.from)).expect("members start at an earlier node");
        let (x, y) = (start.x + t.length * t.angle.cos(), start.y + t.length * t.angle.sin());
        m.add_node(k as u32 + 2, x, y).unwrap();
    }
    for &k in order {
        let t = &members[k];
        m.add_beam(k as u32 + 1, [t.from, k as u32 + 2], steel, sections[k], groups[k % 2]).unwrap();
    }
    if clamped {
        m.add_support(1, &Dof::PLANAR).unwrap();
    }
    m
}

/// A small frame in space with every kind of 3D item: a portal of two
/// 0.6 m columns along y (nodes 1-2 and 3-4, clamped at 1 and 3) and a
/// 0.8 m beam along x between their tops (2-5), an arm along z from node 5
/// (6-7) joined to it by rotational springs `joint` (krx, kry, krz; the
/// translations tied) in a non-viscous group, a ground spring `foot` in
/// every DOF at node 4 (the second column's top), and a lumped mass `tip`
/// with three rotary inertias at node 7. Members in group `frame` (viscous
/// Rayleigh), rectangular steel sections with unequal second moments, the
/// arm's section turned by 20 degrees.
pub fn space_portal() -> Model {
    let mut m = Model::with_dimension("portal in space with a lossy joint", Dimension::Spatial);
    let frame = m.add_group(Group::new("frame").rayleigh(2e-5, 0.3)).unwrap();
    let joint = m.add_group(Group::new("joint").rayleigh(1e-3, 0.0).relaxation(300.0)).unwrap();
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    m.set_poisson(steel, 0.3).unwrap();
    let sec = m.add_section(Section::rectangle("bar", 0.03, 0.02)).unwrap();
    for (id, p) in [
        (1, [0.0, 0.0, 0.0]),
        (2, [0.0, 0.6, 0.0]),
        (3, [0.8, 0.0, 0.0]),
        (4, [0.8, 0.6, 0.0]),
        (5, [0.4, 0.6, 0.0]),
        (6, [0.4, 0.6, 0.0]),
        (7, [0.4, 0.6, 0.5]),
    ] {
        m.add_node_at(id, p).unwrap();
    }
    m.add_beam(1, [1, 2], steel, sec, frame).unwrap();
    m.add_beam(2, [3, 4], steel, sec, frame).unwrap();
    m.add_beam(3, [2, 5], steel, sec, frame).unwrap();
    m.add_beam(4, [5, 4], steel, sec, frame).unwrap();
    let arm = m.add_beam(5, [6, 7], steel, sec, frame).unwrap();
    m.orient_beam(arm, None, 20f64.to_radians()).unwrap();
    m.add_spring("joint", 5, Some(6), [0.0, 0.0, 0.0, 3e4, 5e4, 2e4], joint).unwrap();
    m.add_tie(5, 6, &[Dof::Ux, Dof::Uy, Dof::Uz]).unwrap();
    m.add_spring("foot", 4, None, [2e6, 3e6, 4e6, 1e3, 2e3, 3e3], joint).unwrap();
    m.add_mass("tip", 7, 0.5, [1e-4, 2e-4, 3e-4], frame).unwrap();
    m.add_support(1, &Dof::SPATIAL).unwrap();
    m.add_support(3, &Dof::SPATIAL).unwrap();
    m
}

/// The sparsity of a shell mesh, imported: a square 1 m plate of `n x n`
/// cells, its `(n + 1)^2` nodes in the x-y plane with all six DOFs,
/// clamped along x = 0, each node coupled to its four neighbours by full
/// 6 x 6 blocks (30 non-zeros in an inner row of `K` and `M`, as in a
/// shell model exported from another code). The matrices are imported
/// ([`Model::add_imported`]), one stiffness and one mass per group; the
/// plate is cut into `strips` groups along x (a cell edge belongs to the
/// strip of its midpoint), each non-viscous with its own relaxation
/// parameter.
///
/// It has the sparsity of a shell, not its physics: the couplings are
/// springs along the grid lines (a membrane for every DOF), scaled so that
/// the lowest modes lie near 20 Hz and the band 5-400 Hz holds many.
pub fn imported_plate(n: usize, strips: usize) -> Model {
    use crate::imported::{ImportedKind, SymmetricCoo};
    use std::collections::BTreeMap;

    let mut m = Model::with_dimension("plate-like imported model", Dimension::Spatial);
    let groups: Vec<usize> = (0..strips)
        .map(|g| {
            let group = Group::new(&format!("strip{}", g + 1)).rayleigh(1e-5, 0.5).relaxation(400.0 + 100.0 * g as f64);
            m.add_group(group).unwrap()
        })
        .collect();
    let side = n + 1;
    let h = 1.0 / n as f64;
    for j in 0..side {
        for i in 0..side {
            m.add_node_at((j * side + i + 1) as u32, [i as f64 * h, j as f64 * h, 0.0]).unwrap();
        }
    }
    for j in 0..side {
        m.add_support((j * side + 1) as u32, &Dof::SPATIAL).unwrap();
    }
    // a node's block: the six DOFs coupled (I + c J, J the all-ones matrix
    // over 6, positive definite), the rotations scaled by h^2 so that every
    // DOF has the same stiffness-to-mass ratio
    let scale = |d: usize| if d < 3 { 1.0 } else { h };
    let block = |c: f64| {
        let mut b = [[0.0; 6]; 6];
        for (r, row) in b.iter_mut().enumerate() {
            for (col, v) in row.iter_mut().enumerate() {
                *v = scale(r) * scale(col) * (f64::from(u8::from(r == col)) + c / 6.0);
            }
        }
        b
    };
    let (plate_mass, c) = (10.0, 80.0); // kg; wave speed (m/s), lowest mode c / 4 m
    let (kb, mb) = (block(0.2), block(0.1));
    // each of the 2 n (n + 1) edges carries the same share of the mass; an
    // inner node has 4/3 of an edge's, and a chain of nodes m apart joined
    // by springs k carries waves at h sqrt(k / m)
    let m_edge = plate_mass / (2 * n * side) as f64 / mb[0][0];
    let k_edge = 4.0 / 3.0 * m_edge * (c / h).powi(2);
    let table: Vec<DofRef> =
        (0..side * side).flat_map(|node| Dof::SPATIAL.map(|d| DofRef::new((node + 1) as u32, d))).collect();
    let mut stiffness = vec![BTreeMap::<(usize, usize), f64>::new(); strips];
    let mut mass = stiffness.clone();
    let add = |map: &mut BTreeMap<(usize, usize), f64>, a: usize, b: usize, f: f64, blk: &[[f64; 6]; 6]| {
        for (r, row) in blk.iter().enumerate() {
            for (col, v) in row.iter().enumerate() {
                let (i, j) = (6 * a + r, 6 * b + col);
                if i >= j {
                    *map.entry((i, j)).or_default() += f * v;
                }
            }
        }
    };
    for j in 0..side {
        for i in 0..side {
            let a = j * side + i;
            for (b, x_mid) in [
                (i + 1 < side).then(|| (a + 1, (i as f64 + 0.5) * h)),
                (j + 1 < side).then(|| (a + side, i as f64 * h)),
            ]
            .into_iter()
            .flatten()
            {
                let g = ((x_mid * strips as f64) as usize).min(strips - 1);
                for (x, y, sign) in [(a, a, 1.0), (b, b, 1.0), (b, a, -1.0), (a, b, -1.0)] {
                    add(&mut stiffness[g], x, y, sign * k_edge, &kb);
                    // consistent, as a bar's: 2/6 on the nodes, 1/6 between
                    add(&mut mass[g], x, y, m_edge * if x == y { 2.0 } else { 1.0 } / 6.0, &mb);
                }
            }
        }
    }
    for (g, (k, mm)) in groups.into_iter().zip(stiffness.into_iter().zip(mass)) {
        for (kind, map) in [(ImportedKind::Stiffness, k), (ImportedKind::Mass, mm)] {
            let mut entries: Vec<_> = map.into_iter().map(|((i, j), v)| (i, j, v)).collect();
            entries.sort_by_key(|&(i, j, _)| (j, i));
            m.add_imported(g, kind, &table, &SymmetricCoo { n: table.len(), entries }).unwrap();
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Assembly;

    #[test]
    fn generators_have_the_documented_sizes() {
        for n in [1, 19, 20, 41, 200] {
            let a = Assembly::new(&long_beam(n)).unwrap();
            assert_eq!(a.n(), 3 * n - 2 * (n / 20), "long_beam({n})");
        }
        let (bays, storeys, per) = (3, 2, 4);
        let a = Assembly::new(&frame_grid(bays, storeys, per)).unwrap();
        let members = (2 * bays + 1) * storeys;
        assert_eq!(a.n(), 3 * ((bays + 1) * storeys + members * (per - 1)));
        assert_eq!(frame_grid(bays, storeys, per).beams().len(), members * per);
    }

    #[test]
    fn the_imported_plate_has_the_sparsity_of_a_shell() {
        let (n, strips) = (4, 3);
        let model = imported_plate(n, strips);
        let a = Assembly::new(&model).unwrap();
        // six DOFs at each node but the clamped column's
        assert_eq!(a.n(), 6 * (n + 1) * n);
        assert_eq!(model.groups().len(), strips);
        // an inner node's row couples its own six DOFs and its four
        // neighbours' (an edge node's fewer)
        let p = a.pattern();
        let per_row: Vec<usize> = (0..a.n()).map(|c| p.rows(c).len()).collect();
        assert_eq!(per_row.iter().max(), Some(&30));
        assert!(per_row.iter().all(|&k| (12..=30).contains(&k)), "{per_row:?}");
        let dofs = a.dofs();
        let inner = (0..a.n()).find(|&eq| dofs.dof_of(eq).node.0 == (2 * (n + 1) + 3) as u32).unwrap();
        assert_eq!(p.rows(inner).len(), 30);
        // the mass is the plate's 10 kg, the clamped column's share included
        assert!((model.imported_mass() - 10.0).abs() < 1e-9, "{}", model.imported_mass());
    }
}
