//! The test geometry of a universal file and the pairing of test nodes
//! with model nodes by position.
//!
//! Test systems export the measured points as nodes: dataset 15 (`4I10,
//! 1P3E13.5`: label, definition and displacement coordinate systems,
//! colour, x y z) or 2411 (`4I10` then `1P3D25.16`), with their coordinate
//! systems in dataset 18 (origin, a point on +x and a point in the +xz
//! plane) or 2420 (a matrix and an origin), and the length unit of the file
//! in dataset 164 (a factor: SI = file value / factor). A node's
//! *displacement* coordinate system orients its measurement directions:
//! Simcenter Test.Lab gives each node its own, so that `+Z` at node 7 may
//! point along the global -Z.
//!
//! [`pair_by_coordinates`] maps each test node an FRF uses to the model
//! node at its position and each of its directions to a model DOF by
//! direction cosines: the model's plane is spanned by two test axes
//! ([`PairingOptions::axes`], `+X` and `+Y` by default); a test direction
//! within 2.6 degrees of the model's x or y axis is `ux` or `uy`, a
//! rotation about the normal of the plane is `rz`, with the sign of the
//! cosine. The coordinate along the normal is not compared: sensors sit on
//! a surface, off the model's reference line. A 3D model's z axis is the
//! normal (`x cross y`): positions are compared in space, and every test
//! direction within 2.6 degrees of a model axis maps to the translation
//! along or the rotation about it.
//!
//! Nothing is guessed silently: a file without dataset 164 is taken in
//! metres, a coordinate system the file does not define as the global
//! one, a test node between coincident model nodes (a joint) as the lowest
//! of them, each with a note; a node far from every model node, an oblique
//! or out-of-plane direction, or a coordinate system rfm cannot read is an
//! error naming the node and the line, which an explicit
//! `[[measurement.map]]` entry resolves.

use std::collections::HashMap;

use fe_model::case::ChannelMap;
use fe_model::{Dimension, Dof, DofRef};

use super::map::map_test_dof;
use super::numbers::numbers;
use super::{Direction, RawDataset, TestDof, UffFile};

/// Datasets kept by the reader for [`UffFile::geometry`].
pub(crate) const GEOMETRY_DATASETS: [i64; 5] = [15, 2411, 18, 2420, 164];

/// Smallest direction cosine taken as parallel (2.6 degrees).
const PARALLEL: f64 = 0.999;

/// A measured point of the test geometry.
#[derive(Clone, Debug, PartialEq)]
pub struct TestNode {
    /// Node label.
    pub id: i64,
    /// Position in the global test frame (m).
    pub position: [f64; 3],
    /// The coordinate system its directions are measured in (0: global).
    pub displacement_cs: i64,
    /// Dataset (15 or 2411) and line it comes from.
    pub dataset: i64,
    /// 1-based line of its record.
    pub line: usize,
}

/// A Cartesian coordinate system of the test geometry.
#[derive(Clone, Debug, PartialEq)]
pub struct CoordinateSystem {
    /// Label.
    pub id: i64,
    /// Its x, y and z axes as unit vectors in the global frame (rows).
    pub axes: [[f64; 3]; 3],
    /// Its origin in the global frame (m).
    pub origin: [f64; 3],
    /// 1-based line of its record.
    pub line: usize,
}

/// The test geometry of a universal file.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Geometry {
    /// Nodes, in file order.
    pub nodes: Vec<TestNode>,
    /// Coordinate systems, in file order.
    pub systems: Vec<CoordinateSystem>,
    /// Metres per length unit of the file (dataset 164; 1 without it).
    pub metres_per_unit: f64,
    /// What was assumed (no dataset 164, undefined coordinate systems).
    pub notes: Vec<String>,
}

impl Geometry {
    /// The axes of coordinate system `id` (the global ones for 0), or
    /// `None` when the file does not define it.
    pub fn axes(&self, id: i64) -> Option<[[f64; 3]; 3]> {
        if id == 0 {
            return Some(IDENTITY);
        }
        self.systems.iter().find(|s| s.id == id).map(|s| s.axes)
    }
}

/// Three axes as rows (unit vectors in the global frame).
type Axes = [[f64; 3]; 3];

const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

impl UffFile {
    /// Parses the test geometry (datasets 15, 2411, 18, 2420 and 164) kept by
    /// the reader. An error gives the line and what is wrong.
    pub fn geometry(&self) -> Result<Geometry, (usize, String)> {
        let mut g = Geometry { metres_per_unit: 1.0, ..Geometry::default() };
        let units: Vec<&RawDataset> = self.geometry.iter().filter(|d| d.number == 164).collect();
        match units.first() {
            Some(d) => g.metres_per_unit = length_unit(d)?,
            None if self.geometry.iter().any(|d| matches!(d.number, 15 | 2411)) => {
                g.notes.push("no dataset 164 (units): node coordinates taken in metres".into());
            }
            None => {}
        }
        let scale = g.metres_per_unit;
        for d in self.geometry.iter().filter(|d| matches!(d.number, 18 | 2420)) {
            let systems = if d.number == 18 { systems_18(d, scale)? } else { systems_2420(d, scale)? };
            g.systems.extend(systems);
        }
        let mut definition: Vec<(i64, usize)> = Vec::new();
        for d in self.geometry.iter().filter(|d| matches!(d.number, 15 | 2411)) {
            let nodes = if d.number == 15 { nodes_15(d, scale)? } else { nodes_2411(d, scale)? };
            for (node, def_cs) in nodes {
                definition.push((def_cs, node.line));
                g.nodes.push(node);
            }
        }
        // positions given in a local system: into the global frame
        for (node, &(cs, line)) in g.nodes.iter_mut().zip(&definition) {
            if cs == 0 {
                continue;
            }
            let Some(sys) = g.systems.iter().find(|s| s.id == cs) else {
                return Err((
                    line,
                    format!(
                        "node {} is defined in coordinate system {cs}, which the file does not define (datasets \
                         18 or 2420)",
                        node.id
                    ),
                ));
            };
            let p = node.position;
            node.position = std::array::from_fn(|i| sys.origin[i] + (0..3).map(|j| p[j] * sys.axes[j][i]).sum::<f64>());
        }
        let mut undefined: Vec<i64> =
            g.nodes.iter().map(|n| n.displacement_cs).filter(|&cs| cs != 0 && g.axes(cs).is_none()).collect();
        undefined.sort_unstable();
        undefined.dedup();
        if !undefined.is_empty() {
            g.notes.push(format!(
                "coordinate system(s) {} of the nodes' directions are not defined in the file; taken as the global \
                 one (pyuff writes each node's own number there)",
                list(&undefined)
            ));
        }
        Ok(g)
    }
}

fn list(v: &[i64]) -> String {
    const SHOWN: usize = 8;
    let mut s = v.iter().take(SHOWN).map(ToString::to_string).collect::<Vec<_>>().join(", ");
    if v.len() > SHOWN {
        s.push_str(&format!(" and {} more", v.len() - SHOWN));
    }
    s
}

fn nums(line: &(usize, String)) -> Result<Vec<f64>, (usize, String)> {
    numbers(line.1.as_bytes()).map_err(|m| (line.0, m))
}

fn int(x: f64, line: usize, what: &str) -> Result<i64, (usize, String)> {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        Ok(x as i64)
    } else {
        Err((line, format!("{what} `{x}` is not an integer")))
    }
}

/// Dataset 164: the length factor of record 2 (SI = file value / factor).
fn length_unit(d: &RawDataset) -> Result<f64, (usize, String)> {
    let r2 = d.lines.get(1).ok_or((d.line, "dataset 164 (units) ends before its factors (record 2)".to_string()))?;
    let v = nums(r2)?;
    match v.first() {
        Some(&f) if f.is_finite() && f > 0.0 => Ok(1.0 / f),
        Some(&f) => Err((r2.0, format!("dataset 164: length factor {f} is not positive and finite"))),
        None => Err((r2.0, "dataset 164: record 2 holds no length factor".into())),
    }
}

/// Dataset 15: one line per node (label, definition and displacement
/// systems, colour, x, y, z).
fn nodes_15(d: &RawDataset, scale: f64) -> Result<Vec<(TestNode, i64)>, (usize, String)> {
    let mut out = Vec::new();
    for l in &d.lines {
        let v = nums(l)?;
        if v.is_empty() {
            continue;
        }
        if v.len() != 7 {
            return Err((
                l.0,
                format!("dataset 15 (nodes): {} numbers; a node has 7 (label, 3 integers, x y z)", v.len()),
            ));
        }
        out.push(node(d.number, l.0, &v[..4], &v[4..], scale)?);
    }
    Ok(out)
}

/// Dataset 2411: two lines per node (label, export and displacement
/// systems, colour; then x, y, z).
fn nodes_2411(d: &RawDataset, scale: f64) -> Result<Vec<(TestNode, i64)>, (usize, String)> {
    let lines: Vec<&(usize, String)> = d.lines.iter().filter(|l| !l.1.trim().is_empty()).collect();
    if !lines.len().is_multiple_of(2) {
        let last = lines.last().map_or(d.line, |l| l.0);
        return Err((last, "dataset 2411 (nodes): a node's record 1 has no coordinates (record 2) after it".into()));
    }
    let mut out = Vec::new();
    for pair in lines.chunks_exact(2) {
        let (a, b) = (nums(pair[0])?, nums(pair[1])?);
        if a.len() != 4 || b.len() != 3 {
            return Err((
                pair[0].0,
                format!(
                    "dataset 2411 (nodes): expected 4 integers then 3 coordinates, found {} and {}",
                    a.len(),
                    b.len()
                ),
            ));
        }
        out.push(node(d.number, pair[0].0, &a, &b, scale)?);
    }
    Ok(out)
}

fn node(dataset: i64, line: usize, ints: &[f64], xyz: &[f64], scale: f64) -> Result<(TestNode, i64), (usize, String)> {
    let id = int(ints[0], line, "node label")?;
    let def_cs = int(ints[1], line, "definition coordinate system")?;
    let disp_cs = int(ints[2], line, "displacement coordinate system")?;
    if let Some(x) = xyz.iter().find(|x| !x.is_finite()) {
        return Err((line, format!("node {id}: coordinate {x} is not finite")));
    }
    let position = [xyz[0] * scale, xyz[1] * scale, xyz[2] * scale];
    Ok((TestNode { id, position, displacement_cs: disp_cs, dataset, line }, def_cs))
}

/// Dataset 18: per system, record 1 (number, type, reference system,
/// colour, method), a name, and 9 numbers: origin, a point on +x, a point
/// in the +xz plane.
fn systems_18(d: &RawDataset, scale: f64) -> Result<Vec<CoordinateSystem>, (usize, String)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < d.lines.len() {
        if d.lines[i].1.trim().is_empty() {
            i += 1;
            continue;
        }
        let head = &d.lines[i];
        let r1 = nums(head)?;
        if r1.len() != 5 {
            return Err((head.0, format!("dataset 18 (coordinate systems): record 1 has {} numbers, not 5", r1.len())));
        }
        let id = int(r1[0], head.0, "coordinate system number")?;
        let (kind, reference, method) =
            (int(r1[1], head.0, "type")?, int(r1[2], head.0, "reference system")?, int(r1[4], head.0, "method")?);
        let mut p: Vec<f64> = Vec::new();
        for l in d.lines.iter().skip(i + 2).take(2) {
            p.extend(nums(l)?);
        }
        if p.len() != 9 {
            return Err((
                head.0,
                format!("dataset 18: coordinate system {id} has {} of its 9 definition numbers", p.len()),
            ));
        }
        if kind != 0 || reference != 0 || method != 1 {
            return Err((
                head.0,
                format!(
                    "dataset 18: coordinate system {id} is of type {kind}, relative to system {reference}, defined by \
                     method {method}; rfm reads Cartesian systems (type 0) given in the global one (0) by three \
                     points (method 1)"
                ),
            ));
        }
        let o = [p[0], p[1], p[2]];
        let ex = unit(sub([p[3], p[4], p[5]], o));
        let v = sub([p[6], p[7], p[8]], o);
        let ez = ex.and_then(|ex| unit(sub(v, scaled(ex, dot(v, ex)))));
        let (Some(ex), Some(ez)) = (ex, ez) else {
            return Err((
                head.0,
                format!("dataset 18: the three points of coordinate system {id} do not span a plane"),
            ));
        };
        out.push(CoordinateSystem { id, axes: [ex, cross(ez, ex), ez], origin: scaled(o, scale), line: head.0 });
        i += 4;
    }
    Ok(out)
}

/// Dataset 2420: a part id and name, then per system its label, type and
/// colour, a name, and four rows of three numbers (a matrix and the
/// origin). Writers differ on whether the matrix holds the axes in its rows
/// or its columns, so only systems parallel to the global one are read.
fn systems_2420(d: &RawDataset, scale: f64) -> Result<Vec<CoordinateSystem>, (usize, String)> {
    let lines: Vec<&(usize, String)> = d.lines.iter().skip(2).collect();
    let mut out = Vec::new();
    for block in lines.chunks(6) {
        let head = block[0];
        if block.len() < 6 {
            return Err((head.0, "dataset 2420 (coordinate systems): a system has fewer than 6 lines".into()));
        }
        let r = nums(head)?;
        let id = int(*r.first().unwrap_or(&f64::NAN), head.0, "coordinate system label")?;
        let kind = int(*r.get(1).unwrap_or(&0.0), head.0, "type")?;
        let mut rows = [[0.0; 3]; 4];
        for (k, l) in block[2..6].iter().enumerate() {
            let v = nums(l)?;
            if v.len() != 3 {
                return Err((
                    l.0,
                    format!("dataset 2420: coordinate system {id}: a matrix row has {} numbers, not 3", v.len()),
                ));
            }
            rows[k] = [v[0], v[1], v[2]];
        }
        let parallel = (0..3).all(|a| (0..3).all(|b| (rows[a][b] - IDENTITY[a][b]).abs() < 1e-6));
        if kind != 0 || !parallel {
            return Err((
                head.0,
                format!(
                    "dataset 2420: coordinate system {id} is {}; rfm reads only Cartesian systems parallel to the \
                     global one from dataset 2420 (define rotated systems in dataset 18, or map the nodes with \
                     [[measurement.map]])",
                    if kind != 0 { format!("of type {kind}") } else { "rotated from the global one".to_string() }
                ),
            ));
        }
        out.push(CoordinateSystem { id, axes: IDENTITY, origin: scaled(rows[3], scale), line: head.0 });
    }
    Ok(out)
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn scaled(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(a, a).sqrt();
    (n > 0.0 && n.is_finite()).then(|| scaled(a, 1.0 / n))
}

/// How test nodes are paired with model nodes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairingOptions {
    /// Largest distance (m) in the model's plane between a test node and
    /// its model node.
    pub tolerance_m: f64,
    /// The test directions (global `+X`, `-Z`, ...) along the model's x and
    /// y axes.
    pub axes: [Direction; 2],
    /// Planar (the coordinate along the plane's normal is not compared) or
    /// in space.
    pub dimension: Dimension,
}

/// A test node paired with a model node, as written into the results.
#[derive(Clone, Debug, PartialEq)]
pub struct PairedNode {
    /// Test node label.
    pub test_node: i64,
    /// Model node.
    pub model_node: u32,
    /// Distance in the model's plane (m).
    pub distance_m: f64,
    /// The test node's directions as model DOFs (`+Z -> -uy`), those that
    /// have one.
    pub directions: Vec<String>,
}

/// The pairing of the test nodes an FRF file uses; maps their directions
/// to model DOFs ([`Pairing::map`]).
#[derive(Clone, Debug)]
pub struct Pairing {
    /// Explicit entries, which take precedence.
    explicit: Vec<ChannelMap>,
    /// Per used test node: its model node and the axes of its directions,
    /// or why it has none.
    nodes: HashMap<i64, Result<(u32, Axes), String>>,
    /// Model x, y and the plane's normal in the test frame.
    frame: [[f64; 3]; 3],
    axes: [Direction; 2],
    dimension: Dimension,
}

fn axis_vector(d: Direction) -> [f64; 3] {
    let s = d.sign();
    match d.axis() {
        Direction::X => [s, 0.0, 0.0],
        Direction::Y => [0.0, s, 0.0],
        _ => [0.0, 0.0, s],
    }
}

impl Pairing {
    /// The model DOF and sign of a test direction: by an explicit map entry
    /// when one names its node and axis, else by the pairing.
    pub fn map(&self, dof: TestDof) -> Result<(DofRef, f64), String> {
        let explicit = self
            .explicit
            .iter()
            .any(|e| e.test_point().is_ok_and(|(n, c)| n == dof.node && c.abs() == dof.direction.code().abs()));
        if explicit {
            return map_test_dof(dof, &self.explicit);
        }
        let entry = self
            .nodes
            .get(&dof.node)
            .ok_or_else(|| format!("test node {} was not paired (it is not a node of the FRF records)", dof.node))?;
        let (model, axes) = entry.clone()?;
        let code = dof.direction.code().unsigned_abs();
        if code == 0 {
            return Err(format!("test DOF {dof} is a scalar channel; map it with [[measurement.map]]"));
        }
        let u = axes[usize::from((code - 1) % 3)];
        let [ex, ey, ez] = self.frame;
        let plane = format!("the model's x along {} and y along {} of the test", self.axes[0], self.axes[1]);
        let hint = format!(
            "map it with a [[measurement.map]] entry, e.g.\n    [[measurement.map]]\n    test = \"{}:{}\"\n    model = \
             \"{model}:uy\"\n    sign = 1",
            dof.node,
            dof.direction.axis()
        );
        if self.dimension == Dimension::Spatial {
            // the model axis the test direction lies along, translation or rotation
            let along = [ex, ey, ez].iter().map(|&e| dot(u, e)).enumerate().find(|(_, c)| c.abs() >= PARALLEL);
            let Some((axis, c)) = along else {
                return Err(format!(
                    "test DOF {dof} is oblique to the model's axes ({plane}, z their cross product); {hint}"
                ));
            };
            let dofs = if code <= 3 { [Dof::Ux, Dof::Uy, Dof::Uz] } else { [Dof::Rx, Dof::Ry, Dof::Rz] };
            return Ok((DofRef::new(model, dofs[axis]), dof.direction.sign() * c.signum()));
        }
        let (dof_model, c) = if code <= 3 {
            let (cx, cy) = (dot(u, ex), dot(u, ey));
            if cx.abs() >= PARALLEL {
                (Dof::Ux, cx)
            } else if cy.abs() >= PARALLEL {
                (Dof::Uy, cy)
            } else if dot(u, ez).abs() >= PARALLEL {
                return Err(format!("test DOF {dof} is perpendicular to the model's plane ({plane}); {hint}"));
            } else {
                return Err(format!(
                    "test DOF {dof} is oblique to the model's axes (direction cosines {cx:.3} with x and {cy:.3} with \
                     y, {plane}); {hint}"
                ));
            }
        } else {
            let c = dot(u, ez);
            if c.abs() < PARALLEL {
                return Err(format!(
                    "test DOF {dof} is a rotation about an axis in the model's plane ({plane}), which a planar model \
                     does not have; {hint}"
                ));
            }
            (Dof::Rz, c)
        };
        Ok((DofRef::new(model, dof_model), dof.direction.sign() * c.signum()))
    }
}

/// Pairs the test nodes `used` (those the FRF records name) with the model
/// nodes `model` (`(id, [x, y, z])`) by position (see the module docs). Returns
/// the pairing (whose [`Pairing::map`] maps test directions), what it did
/// per node, and notes. A used node without coordinates, or farther than
/// the tolerance from every model node, is not an error here: mapping one
/// of its directions is, unless an explicit entry maps it.
pub fn pair_by_coordinates(
    geometry: &Geometry,
    used: &[i64],
    model: &[(u32, [f64; 3])],
    opts: &PairingOptions,
    explicit: &[ChannelMap],
) -> (Pairing, Vec<PairedNode>, Vec<String>) {
    let ex = axis_vector(opts.axes[0]);
    let ey = axis_vector(opts.axes[1]);
    let frame = [ex, ey, cross(ex, ey)];
    let mut pairing = Pairing {
        explicit: explicit.to_vec(),
        nodes: HashMap::new(),
        frame,
        axes: opts.axes,
        dimension: opts.dimension,
    };
    let mut paired = Vec::new();
    let mut notes = Vec::new();
    let by_id: HashMap<i64, &TestNode> = geometry.nodes.iter().map(|n| (n.id, n)).collect();
    let mm = |d: f64| format!("{:.1} mm", d * 1e3);
    for &id in used {
        if pairing.nodes.contains_key(&id) {
            continue;
        }
        let Some(node) = by_id.get(&id) else {
            pairing
                .nodes
                .insert(id, Err(format!("test node {id} has no coordinates in the geometry (datasets 15 or 2411)")));
            continue;
        };
        let (x, y) = (dot(node.position, ex), dot(node.position, ey));
        // the coordinate along a planar model's normal is not compared
        let z = if opts.dimension == Dimension::Spatial { dot(node.position, frame[2]) } else { 0.0 };
        let mut near: Vec<(f64, u32)> = model
            .iter()
            .map(|&(m, [mx, my, mz])| (((mx - x).powi(2) + (my - y).powi(2) + (mz - z).powi(2)).sqrt(), m))
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let Some(&(d, m)) = near.first() else {
            pairing.nodes.insert(id, Err("the model has no nodes".into()));
            continue;
        };
        if d > opts.tolerance_m {
            pairing.nodes.insert(
                id,
                Err(format!(
                    "test node {id} (line {}) at x = {x:.4} m, y = {y:.4} m in the model's plane is {} from the \
                     nearest model node {m}, beyond the pairing tolerance of {}",
                    node.line,
                    mm(d),
                    mm(opts.tolerance_m)
                )),
            );
            continue;
        }
        // coincident model nodes (a joint): the lowest id, said
        let together: Vec<u32> = near.iter().filter(|(e, _)| (e - d).abs() <= 1e-9).map(|&(_, n)| n).collect();
        if together.len() > 1 {
            notes.push(format!(
                "test node {id} lies at coincident model nodes {}; paired with {m}, the lowest (map it with \
                 [[measurement.map]] to choose another)",
                together.iter().map(ToString::to_string).collect::<Vec<_>>().join(", ")
            ));
        }
        let axes = geometry.axes(node.displacement_cs).unwrap_or(IDENTITY);
        pairing.nodes.insert(id, Ok((m, axes)));
        let directions = [Direction::X, Direction::Y, Direction::Z, Direction::RX, Direction::RY, Direction::RZ]
            .into_iter()
            .filter_map(|dir| {
                let (dof, s) = pairing.map(TestDof::new(id, dir)).ok()?;
                Some(format!("{dir} -> {}{}", if s < 0.0 { "-" } else { "" }, dof.dof.name()))
            })
            .collect();
        paired.push(PairedNode { test_node: id, model_node: m, distance_m: d, directions });
    }
    (pairing, paired, notes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn raw(number: i64, lines: &[&str]) -> RawDataset {
        RawDataset { number, line: 1, lines: lines.iter().enumerate().map(|(i, l)| (i + 2, l.to_string())).collect() }
    }

    #[test]
    fn a_system_of_three_points_gives_orthonormal_axes() {
        // Test.Lab's systems: origin, a point on +x, a point in the +xz plane
        let d = raw(
            18,
            &[
                "         1         0         0         8         1",
                "SYS1",
                " -2.40000e+00 -9.50000e-01  0.00000e+00 -3.40000e+00 -9.50000e-01 -8.74228e-08",
                " -3.40000e+00 -9.50000e-01 -1.00000e+00",
            ],
        );
        let s = &systems_18(&d, 1.0).unwrap()[0];
        let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|i| (a[i] - b[i]).abs() < 1e-6);
        assert!(close(s.axes[0], [-1.0, 0.0, 0.0]), "{:?}", s.axes);
        assert!(close(s.axes[1], [0.0, 1.0, 0.0]), "{:?}", s.axes);
        assert!(close(s.axes[2], [0.0, 0.0, -1.0]), "{:?}", s.axes);
        assert_eq!(s.origin, [-2.4, -0.95, 0.0]);
    }

    #[test]
    fn directions_map_by_cosines_with_their_signs() {
        let g = Geometry {
            nodes: vec![
                TestNode { id: 101, position: [0.5, 0.004, 0.0], displacement_cs: 0, dataset: 15, line: 3 },
                TestNode { id: 102, position: [0.25, 0.0, 0.0], displacement_cs: 7, dataset: 15, line: 4 },
            ],
            systems: vec![CoordinateSystem {
                id: 7,
                axes: [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]],
                origin: [0.0; 3],
                line: 9,
            }],
            metres_per_unit: 1.0,
            notes: Vec::new(),
        };
        let model = [(1, [0.0; 3]), (3, [0.25, 0.0, 0.0]), (5, [0.5, 0.0, 0.0])];
        // a beam along X bending in the test's XZ plane: model y along test +Z; the sensor sits 4 mm off
        // the plane (along Y), which is not compared
        let opts =
            PairingOptions { tolerance_m: 0.002, axes: [Direction::X, Direction::Z], dimension: Dimension::Planar };
        let (p, paired, notes) = pair_by_coordinates(&g, &[101, 102], &model, &opts, &[]);
        assert!(notes.is_empty(), "{notes:?}");
        assert_eq!((paired[0].model_node, paired[1].model_node), (5, 3));
        let m = |s: &str| p.map(s.parse().unwrap());
        assert_eq!(m("101:+Z"), Ok((DofRef::new(5, Dof::Uy), 1.0)));
        assert_eq!(m("101:-Z"), Ok((DofRef::new(5, Dof::Uy), -1.0)));
        assert_eq!(m("101:+X"), Ok((DofRef::new(5, Dof::Ux), 1.0)));
        // node 102 measures along its own system: local +Z is global -Z
        assert_eq!(m("102:+Z"), Ok((DofRef::new(3, Dof::Uy), -1.0)));
        assert_eq!(m("102:+X"), Ok((DofRef::new(3, Dof::Ux), -1.0)));
        // the model's rz is about X x Z = -Y
        assert_eq!(m("101:+RY"), Ok((DofRef::new(5, Dof::Rz), -1.0)));
        let e = m("101:+Y").unwrap_err();
        assert!(e.contains("perpendicular to the model's plane") && e.contains("test = \"101:+Y\""), "{e}");
        let e = m("101:+RX").unwrap_err();
        assert!(e.contains("rotation about an axis in the model's plane"), "{e}");
        // far from every model node
        let opts =
            PairingOptions { tolerance_m: 0.002, axes: [Direction::X, Direction::Y], dimension: Dimension::Planar };
        let far = Geometry {
            nodes: vec![TestNode { id: 9, position: [0.1, 0.0, 0.0], displacement_cs: 0, dataset: 2411, line: 5 }],
            ..g.clone()
        };
        let (p, paired, _) = pair_by_coordinates(&far, &[9], &model, &opts, &[]);
        assert!(paired.is_empty());
        let e = p.map("9:+Y".parse().unwrap()).unwrap_err();
        assert!(e.contains("test node 9 (line 5)") && e.contains("100.0 mm from the nearest model node 1"), "{e}");
        // an explicit entry wins
        let explicit = [ChannelMap { test: "9:+Y".into(), model: DofRef::new(3, Dof::Uy), sign: -1.0 }];
        let (p, _, _) = pair_by_coordinates(&far, &[9], &model, &opts, &explicit);
        assert_eq!(p.map("9:+Y".parse().unwrap()), Ok((DofRef::new(3, Dof::Uy), -1.0)));
    }

    #[test]
    fn coincident_model_nodes_take_the_lowest_with_a_note() {
        let g = Geometry {
            nodes: vec![TestNode { id: 4, position: [0.5, 0.0, 0.0], displacement_cs: 0, dataset: 15, line: 3 }],
            metres_per_unit: 1.0,
            ..Geometry::default()
        };
        let model = [(41, [0.5, 0.0, 0.0]), (6, [0.5, 0.0, 0.0])];
        let opts =
            PairingOptions { tolerance_m: 0.001, axes: [Direction::X, Direction::Y], dimension: Dimension::Planar };
        let (p, _, notes) = pair_by_coordinates(&g, &[4], &model, &opts, &[]);
        assert_eq!(p.map("4:+Y".parse().unwrap()), Ok((DofRef::new(6, Dof::Uy), 1.0)));
        assert!(notes[0].contains("coincident model nodes 6, 41; paired with 6"), "{notes:?}");
    }

    #[test]
    fn a_3d_model_pairs_in_space_and_maps_every_axis() {
        let node = |id, position| TestNode { id, position, displacement_cs: 0, dataset: 15, line: 3 };
        let g = Geometry {
            nodes: vec![node(7, [0.5, 0.0, 0.3]), node(8, [0.5, 0.0, 0.0]), node(9, [0.5, 0.1, 0.0])],
            metres_per_unit: 1.0,
            ..Geometry::default()
        };
        // model x along test +X, model y along test +Z, so model z = X x Z = -Y
        let model = [(1, [0.5, 0.0, 0.0]), (2, [0.5, 0.3, 0.0])];
        let opts =
            PairingOptions { tolerance_m: 0.002, axes: [Direction::X, Direction::Z], dimension: Dimension::Spatial };
        let (p, paired, _) = pair_by_coordinates(&g, &[7, 8, 9], &model, &opts, &[]);
        assert_eq!(paired.iter().map(|n| (n.test_node, n.model_node)).collect::<Vec<_>>(), [(7, 2), (8, 1)]);
        let m = |s: &str| p.map(s.parse().unwrap());
        assert_eq!(m("7:+Y"), Ok((DofRef::new(2, Dof::Uz), -1.0)));
        assert_eq!(m("7:+Z"), Ok((DofRef::new(2, Dof::Uy), 1.0)));
        assert_eq!(m("8:-X"), Ok((DofRef::new(1, Dof::Ux), -1.0)));
        assert_eq!(m("8:+RX"), Ok((DofRef::new(1, Dof::Rx), 1.0)));
        assert_eq!(m("8:+RZ"), Ok((DofRef::new(1, Dof::Ry), 1.0)));
        assert_eq!(m("8:+RY"), Ok((DofRef::new(1, Dof::Rz), -1.0)));
        // 100 mm off the model along its z: compared in space, so not paired
        let e = m("9:+X").unwrap_err();
        assert!(e.contains("test node 9") && e.contains("100.0 mm"), "{e}");
    }
}
