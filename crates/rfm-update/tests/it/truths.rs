//! Truths for the hidden-effect test, written as case files by a generator
//! that shares no code with the diagnosis's candidate generator.
//!
//! A truth is a pair of case-file texts: the nominal model the user has and
//! the true structure that was measured, which differs from it by one hidden
//! effect (or two, in pair trials). Both are written explicitly, node by node
//! and element by element (`nodes = [...]`, `[[beams]]`, `[[springs]]` between
//! coincident nodes, groups with `alpha`, `beta`, `mu`), never with the
//! `[[lines]]`, `[[joints]]` or `[[assign]]` tables the tool's own edits use,
//! so that a truth reaches the model through a different road of the parser.
//!
//! The families are drawn wider than a candidate generator would propose
//! them: supports and joints with finite translational springs and their own
//! exponential (or viscous) damping, sometimes one group per spring with its
//! own relaxation parameter; splices at any interior node; damping patches of
//! any length from 1 to 6 elements at any offset; masses with or without a
//! rotary inertia; stiffness losses written as a weaker material (axial and
//! bending) or as a section of smaller second moment (bending only). Every
//! draw is checked to be physically plausible and visible above the noise,
//! and redrawn otherwise; a [`Truth`] counts its redraws.
//!
//! [`crate::lab`] builds on its structures and writer (the items it uses
//! are `pub(crate)`), for trials with set-up errors and physics outside
//! these families.
//!
//! The tests at the end check the generator itself: the texts parse and
//! assemble, the true values read back from the parsed models, every effect
//! is visible, a null truth is its nominal, draws are reproducible, and an
//! explicit splice tends to the nominal model as its springs go stiff.

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::OnceLock;

use damping::{DampedSystem, normal_modes};
use fe_model::{CaseFile, Dof, DofRef};
use frf::{Channel, FrfKind, FrfSet, NoiseModel, synthesize};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// RMS relative difference between a truth's and the nominal model's FRFs
/// (without noise) that a drawn effect must reach: ten times a 1 % noise
/// level, so that the effect stands well above the noise of the test.
pub(crate) const VISIBLE: f64 = 0.10;

/// The lowest natural frequency a truth may have (Hz): below it a support or
/// joint is so soft that the structure is close to a mechanism.
pub(crate) const LOWEST_MODE_HZ: f64 = 0.5;

/// How far, in half-power peak widths `2 zeta f` of the nominal model, a
/// joint or splice must move at least one mode in the band: its rotational
/// spring is meant to be soft enough to be seen as a stiffness, not only
/// through its damping.
const JOINT_SHIFT_WIDTHS: f64 = 3.0;

/// Redraws allowed before the generator gives up (a bug, not bad luck).
const MAX_REDRAWS: u32 = 500;

/// First id of the nodes a truth adds (above every nominal node id).
pub(crate) const FIRST_EXTRA_NODE: u32 = 101;

/// The nominal structures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Structure {
    /// A 1 m steel strip, 20 elements, clamped at node 1, horizontal.
    Cantilever,
    /// A 0.6 m column (12 elements) clamped at its base, with a 0.5 m arm
    /// (10 elements) at its top, like `cases/tutorial/l-frame.toml`.
    LFrame,
}

impl Structure {
    pub(crate) const ALL: [Structure; 2] = [Structure::Cantilever, Structure::LFrame];
}

/// The kinds of hidden effect.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Family {
    /// The clamp replaced by lossy ground springs kx, ky, kr.
    Support,
    /// The L-frame's corner: the arm detached onto a coincident node, joined
    /// by lossy springs.
    Joint,
    /// An in-line joint at an interior node of a member.
    Splice,
    /// A window of elements with larger (often non-viscous) damping.
    DampingPatch,
    /// A lumped mass, sometimes with a rotary inertia.
    Mass,
    /// A window of elements with reduced stiffness.
    StiffnessLoss,
}

impl Family {
    pub(crate) const ALL: [Family; 6] =
        [Family::Support, Family::Joint, Family::Splice, Family::DampingPatch, Family::Mass, Family::StiffnessLoss];

    /// Whether the family can be drawn on a structure (the cantilever has
    /// no corner).
    pub(crate) fn fits(self, structure: Structure) -> bool {
        !(self == Family::Joint && structure == Structure::Cantilever)
    }

    /// Whether a structure has room for only one effect of this family.
    fn unique(self) -> bool {
        matches!(self, Family::Support | Family::Joint)
    }
}

/// One trial: the nominal and true case-file texts and how they were measured.
#[derive(Clone, Debug)]
pub(crate) struct Truth {
    /// What is hidden, in words (for tables and messages).
    pub(crate) label: String,
    /// Which nominal structure the trial is on.
    pub(crate) structure: Structure,
    /// Case-file text of the nominal model (what the user has).
    pub(crate) nominal: String,
    /// Case-file text of the true structure (what was measured).
    pub(crate) truth: String,
    /// The hidden effects: none (null trial), one, or two (pair trial).
    pub(crate) effects: Vec<HiddenEffect>,
    /// Measured channels as (response, reference) DOF names, translations only.
    pub(crate) channels: Vec<(String, String)>,
    /// Measured lines (Hz).
    pub(crate) lines_hz: Vec<f64>,
    /// Measured as accelerance (else receptance).
    pub(crate) accelerance: bool,
    /// Draws rejected (implausible or not visible) before this one.
    pub(crate) redraws: u32,
}

/// A hidden effect and its true values, located by nominal ids.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct HiddenEffect {
    pub(crate) family: Family,
    /// Nominal node ids where a point effect (support, joint, splice, mass) sits.
    pub(crate) nodes: Vec<u32>,
    /// Nominal element ids of an element effect (patch, stiffness loss).
    pub(crate) elements: Vec<u32>,
    /// Stiffness-like true values: `kx`, `ky`, `kr` (global directions, the
    /// sum over the effect's springs) or `factor` (the bending stiffness
    /// EI relative to the nominal one).
    pub(crate) stiffness: Vec<(String, f64)>,
    /// Mass-like true values: `m` (kg), `j` (kg m^2).
    pub(crate) mass: Vec<(String, f64)>,
    /// Damping: `alpha` and `mu` (absent when viscous) of the effect's
    /// group, or of its rotational spring's group when each spring has its
    /// own; then `alpha.kx`, `mu.kx`, ... give every spring's group.
    pub(crate) damping: Vec<(String, f64)>,
}

impl HiddenEffect {
    /// A true value by name, from any of the three lists.
    pub(crate) fn value(&self, name: &str) -> Option<f64> {
        self.stiffness.iter().chain(&self.mass).chain(&self.damping).find(|(n, _)| n == name).map(|&(_, v)| v)
    }
}

impl Truth {
    /// The nominal case, parsed.
    pub(crate) fn nominal_case(&self) -> CaseFile {
        CaseFile::parse(Path::new("nominal.toml"), &self.nominal).expect("the nominal text parses")
    }

    /// The true structure's case, parsed.
    pub(crate) fn truth_case(&self) -> CaseFile {
        CaseFile::parse(Path::new("truth.toml"), &self.truth).expect("the truth text parses")
    }

    /// The measured channels.
    pub(crate) fn frf_channels(&self) -> Vec<Channel> {
        self.channels
            .iter()
            .map(|(r, e)| Channel::new(r.parse().expect("a DOF name"), e.parse().expect("a DOF name")))
            .collect()
    }

    /// The kind the FRFs are measured as.
    pub(crate) fn kind(&self) -> FrfKind {
        if self.accelerance { FrfKind::Accelerance } else { FrfKind::Receptance }
    }

    /// The measurement: the true structure's FRFs on the trial's channels
    /// and lines, in the trial's kind, with relative complex noise of the
    /// given level (0.01 is 1 %) from `seed`.
    pub(crate) fn measure(&self, noise: f64, seed: u64) -> FrfSet {
        let sys = DampedSystem::new(self.truth_case().model).expect("the truth assembles");
        let clean = synthesize(&sys, &self.frf_channels(), &self.lines_hz).expect("the truth's FRFs");
        let mut set = clean.converted(self.kind());
        NoiseModel::relative(noise, seed).apply(&mut set);
        set
    }

    /// A `[measurement]` table for the nominal case that reads the trial's
    /// data from `data` (a path relative to the case file), to append to
    /// [`Truth::nominal`] when the measurement is written to a file.
    pub(crate) fn measurement_table(&self, data: &str) -> String {
        let geo = Geometry::of(self.structure);
        let mut references: Vec<&str> = self.channels.iter().map(|(_, e)| e.as_str()).collect();
        references.dedup();
        let responses: Vec<&str> = self.channels.iter().map(|(r, _)| r.as_str()).collect();
        let quoted = |v: &[&str]| v.iter().map(|s| format!("\"{s}\"")).collect::<Vec<_>>().join(", ");
        let (from, to, step) = geo.band;
        format!(
            "\n[measurement]\nfrequencies = {{ from = {}, to = {}, step = {} }}\n\
             references = [{}]\nresponses = [{}]\ndata = \"{data}\"\n",
            num(from),
            num(to),
            num(step),
            quoted(&references),
            quoted(&responses)
        )
    }
}

// ------------------------------------------------------------ the structures

/// A coordinate rounded to a picometre, so that a case file shows `0.15`
/// rather than `0.15000000000000002`.
pub(crate) fn round(x: f64) -> f64 {
    (x * 1e12).round() / 1e12
}

/// A straight run of elements along the chain, axis-aligned.
pub(crate) struct Member {
    /// Node ids from one end to the other.
    pub(crate) nodes: Vec<u32>,
    /// Element ids, element `elements[i]` joins `nodes[i]` and `nodes[i + 1]`.
    pub(crate) elements: Vec<u32>,
    /// Whether the member lies along x (else along y).
    pub(crate) along_x: bool,
}

/// A nominal structure: its properties, members and measurement.
pub(crate) struct Geometry {
    pub(crate) structure: Structure,
    pub(crate) title: &'static str,
    pub(crate) e: f64,
    pub(crate) rho: f64,
    pub(crate) b: f64,
    pub(crate) h: f64,
    pub(crate) alpha: f64,
    pub(crate) beta: f64,
    /// Node coordinates, in id order.
    pub(crate) nodes: Vec<(u32, f64, f64)>,
    /// Members in order along the chain from the clamp.
    pub(crate) members: Vec<Member>,
    pub(crate) clamp: u32,
    /// Response DOFs (over one reference).
    pub(crate) responses: Vec<DofRef>,
    pub(crate) reference: DofRef,
    /// Measured band: from, to, step (Hz).
    pub(crate) band: (f64, f64, f64),
    /// The frequency (Hz) at which damping effects are sized by their loss
    /// factor: the middle of the band's modes.
    pub(crate) f_ref: f64,
}

impl Geometry {
    pub(crate) fn of(structure: Structure) -> Geometry {
        match structure {
            Structure::Cantilever => {
                let n = 20;
                let nodes = (0..=n).map(|i| (i + 1, round(f64::from(i) / f64::from(n)), 0.0)).collect();
                let member = Member { nodes: (1..=n + 1).collect(), elements: (1..=n).collect(), along_x: true };
                Geometry {
                    structure,
                    title: "Steel cantilever, 20 elements",
                    e: 2.0e11,
                    rho: 7800.0,
                    b: 0.04,
                    h: 0.008,
                    alpha: 1.0e-5,
                    beta: 0.5,
                    nodes,
                    members: vec![member],
                    clamp: 1,
                    responses: (3..=n + 1).step_by(2).map(|i| DofRef::new(i, Dof::Uy)).collect(),
                    reference: DofRef::new(n + 1, Dof::Uy),
                    band: (1.0, 400.0, 0.5),
                    f_ref: 100.0,
                }
            }
            Structure::LFrame => {
                // column: nodes 1..13, elements 1..12; arm: nodes 13..23, elements 13..22
                let mut nodes: Vec<(u32, f64, f64)> =
                    (0..=12).map(|i| (i + 1, 0.0, round(0.6 * f64::from(i) / 12.0))).collect();
                nodes.extend((1..=10).map(|i| (13 + i, round(0.5 * f64::from(i) / 10.0), 0.6)));
                let column = Member { nodes: (1..=13).collect(), elements: (1..=12).collect(), along_x: false };
                let arm = Member { nodes: (13..=23).collect(), elements: (13..=22).collect(), along_x: true };
                let mut responses: Vec<DofRef> = [15, 17, 19, 21, 23].map(|i| DofRef::new(i, Dof::Uy)).to_vec();
                responses.extend([5, 9, 13].map(|i| DofRef::new(i, Dof::Ux)));
                Geometry {
                    structure,
                    title: "Steel L-frame, column 12 and arm 10 elements",
                    e: 2.1e11,
                    rho: 7850.0,
                    b: 0.02,
                    h: 0.02,
                    alpha: 2.0e-6,
                    beta: 1.0,
                    nodes,
                    members: vec![column, arm],
                    clamp: 1,
                    responses,
                    reference: DofRef::new(23, Dof::Uy),
                    band: (2.0, 800.0, 1.0),
                    f_ref: 150.0,
                }
            }
        }
    }

    pub(crate) fn area(&self) -> f64 {
        self.b * self.h
    }

    pub(crate) fn inertia(&self) -> f64 {
        self.b * self.h.powi(3) / 12.0
    }

    /// Element length of a member.
    pub(crate) fn le(&self, member: &Member) -> f64 {
        let (a, b) = (self.node(member.nodes[0]), self.node(*member.nodes.last().unwrap()));
        (b.1 - a.1).hypot(b.2 - a.2) / member.elements.len() as f64
    }

    pub(crate) fn node(&self, id: u32) -> (u32, f64, f64) {
        *self.nodes.iter().find(|n| n.0 == id).expect("a nominal node")
    }

    pub(crate) fn total_mass(&self) -> f64 {
        let length: f64 = self.members.iter().map(|m| self.le(m) * m.elements.len() as f64).sum();
        self.rho * self.area() * length
    }

    /// Position along the chain from the clamp, in elements.
    pub(crate) fn position(&self, node: u32) -> usize {
        let mut pos = 0;
        for m in &self.members {
            if let Some(i) = m.nodes.iter().position(|&n| n == node) {
                return pos + i;
            }
            pos += m.elements.len();
        }
        panic!("node {node} is not on the chain")
    }

    pub(crate) fn element_nodes(&self, element: u32) -> [u32; 2] {
        for m in &self.members {
            if let Some(i) = m.elements.iter().position(|&e| e == element) {
                return [m.nodes[i], m.nodes[i + 1]];
            }
        }
        panic!("element {element} is not on the chain")
    }

    pub(crate) fn lines(&self) -> Vec<f64> {
        let (from, to, step) = self.band;
        let n = ((to - from) / step).round() as usize;
        (0..=n).map(|k| from + step * k as f64).collect()
    }

    pub(crate) fn channels(&self) -> Vec<Channel> {
        self.responses.iter().map(|&r| Channel::new(r, self.reference)).collect()
    }

    /// The nominal model as a frame to write.
    pub(crate) fn frame(&self) -> Frame {
        let mut beams = Vec::new();
        for m in &self.members {
            for (i, &id) in m.elements.iter().enumerate() {
                beams.push(BeamText {
                    id,
                    nodes: [m.nodes[i], m.nodes[i + 1]],
                    material: "steel".into(),
                    section: "bar".into(),
                    group: "structure".into(),
                });
            }
        }
        Frame {
            comment: format!("Nominal model: {}.", self.title.to_lowercase()),
            title: self.title.into(),
            nodes: self.nodes.clone(),
            materials: vec![("steel".into(), self.e, self.rho)],
            sections: vec![("bar".into(), SectionText::Rectangle { b: self.b, h: self.h })],
            groups: vec![GroupText { name: "structure".into(), alpha: self.alpha, beta: self.beta, mu: None }],
            beams,
            springs: Vec::new(),
            masses: Vec::new(),
            supports: vec![self.clamp],
            partial_supports: Vec::new(),
            ties: Vec::new(),
        }
    }
}

// ------------------------------------------------------------- case writer

pub(crate) enum SectionText {
    Rectangle { b: f64, h: f64 },
    AreaInertia { a: f64, i: f64 },
}

pub(crate) struct GroupText {
    pub(crate) name: String,
    pub(crate) alpha: f64,
    pub(crate) beta: f64,
    pub(crate) mu: Option<f64>,
}

pub(crate) struct BeamText {
    pub(crate) id: u32,
    pub(crate) nodes: [u32; 2],
    pub(crate) material: String,
    pub(crate) section: String,
    pub(crate) group: String,
}

pub(crate) struct SpringText {
    pub(crate) name: String,
    /// Two nodes, or one node to ground (`b` is `None`).
    pub(crate) a: u32,
    pub(crate) b: Option<u32>,
    pub(crate) k: [f64; 3],
    pub(crate) group: String,
}

pub(crate) struct MassText {
    pub(crate) name: String,
    pub(crate) node: u32,
    pub(crate) m: f64,
    pub(crate) j: f64,
    pub(crate) group: String,
}

/// A float as case-file text: the shortest text that reads back to the
/// same number (so that read-back tests can compare exactly), in exponent
/// form when it is large or small.
pub(crate) fn num(x: f64) -> String {
    if x != 0.0 && !(1e-3..1e5).contains(&x.abs()) { format!("{x:e}") } else { format!("{x:?}") }
}

/// A model being written as a case file, item by item.
pub(crate) struct Frame {
    pub(crate) comment: String,
    pub(crate) title: String,
    pub(crate) nodes: Vec<(u32, f64, f64)>,
    pub(crate) materials: Vec<(String, f64, f64)>,
    pub(crate) sections: Vec<(String, SectionText)>,
    pub(crate) groups: Vec<GroupText>,
    pub(crate) beams: Vec<BeamText>,
    pub(crate) springs: Vec<SpringText>,
    pub(crate) masses: Vec<MassText>,
    pub(crate) supports: Vec<u32>,
    /// Nodes held in some DOFs only (an added node whose unused DOFs
    /// nothing else holds).
    pub(crate) partial_supports: Vec<(u32, Vec<Dof>)>,
    /// Pairs of coincident nodes that share some DOFs.
    pub(crate) ties: Vec<([u32; 2], Vec<Dof>)>,
}

impl Frame {
    pub(crate) fn beam_mut(&mut self, id: u32) -> &mut BeamText {
        self.beams.iter_mut().find(|b| b.id == id).expect("a nominal element")
    }

    pub(crate) fn coordinates(&self, id: u32) -> (f64, f64) {
        let n = self.nodes.iter().find(|n| n.0 == id).expect("a node");
        (n.1, n.2)
    }

    /// Adds a node at the place of an existing one.
    pub(crate) fn add_coincident(&mut self, of: u32, id: u32) {
        let (x, y) = self.coordinates(of);
        self.nodes.push((id, x, y));
    }

    /// The case-file text.
    pub(crate) fn to_toml(&self) -> String {
        let mut s = String::new();
        let w = &mut s;
        writeln!(w, "# {}", self.comment).unwrap();
        writeln!(w, "title = \"{}\"", self.title).unwrap();
        writeln!(w, "nodes = [").unwrap();
        for (id, x, y) in &self.nodes {
            writeln!(w, "  [{id}, {}, {}],", num(*x), num(*y)).unwrap();
        }
        writeln!(w, "]\n\n[materials]").unwrap();
        for (name, e, rho) in &self.materials {
            writeln!(w, "{name} = {{ E = {}, rho = {} }}", num(*e), num(*rho)).unwrap();
        }
        writeln!(w, "\n[sections]").unwrap();
        for (name, sec) in &self.sections {
            match sec {
                SectionText::Rectangle { b, h } => {
                    writeln!(w, "{name} = {{ b = {}, h = {} }}", num(*b), num(*h)).unwrap()
                }
                SectionText::AreaInertia { a, i } => {
                    writeln!(w, "{name} = {{ A = {}, I = {} }}", num(*a), num(*i)).unwrap()
                }
            }
        }
        for g in &self.groups {
            writeln!(w, "\n[groups.{}]\nalpha = {}\nbeta = {}", g.name, num(g.alpha), num(g.beta)).unwrap();
            if let Some(mu) = g.mu {
                writeln!(w, "mu = {}", num(mu)).unwrap();
            }
        }
        for b in &self.beams {
            writeln!(
                w,
                "\n[[beams]]\nid = {}\nnodes = [{}, {}]\nmaterial = \"{}\"\nsection = \"{}\"\ngroup = \"{}\"",
                b.id, b.nodes[0], b.nodes[1], b.material, b.section, b.group
            )
            .unwrap();
        }
        for sp in &self.springs {
            writeln!(w, "\n[[springs]]\nname = \"{}\"", sp.name).unwrap();
            match sp.b {
                Some(b) => writeln!(w, "nodes = [{}, {b}]", sp.a).unwrap(),
                None => writeln!(w, "node = {}", sp.a).unwrap(),
            }
            for (key, k) in ["kx", "ky", "kr"].iter().zip(sp.k) {
                if k != 0.0 {
                    writeln!(w, "{key} = {}", num(k)).unwrap();
                }
            }
            writeln!(w, "group = \"{}\"", sp.group).unwrap();
        }
        for m in &self.masses {
            writeln!(w, "\n[[masses]]\nname = \"{}\"\nnode = {}\nm = {}", m.name, m.node, num(m.m)).unwrap();
            if m.j != 0.0 {
                writeln!(w, "j = {}", num(m.j)).unwrap();
            }
            writeln!(w, "group = \"{}\"", m.group).unwrap();
        }
        for n in &self.supports {
            writeln!(w, "\n[[supports]]\nnode = {n}").unwrap();
        }
        for (n, dofs) in &self.partial_supports {
            let dofs: Vec<String> = dofs.iter().map(|d| format!("\"{d}\"")).collect();
            writeln!(w, "\n[[supports]]\nnode = {n}\ndofs = [{}]", dofs.join(", ")).unwrap();
        }
        for ([a, b], dofs) in &self.ties {
            let dofs: Vec<String> = dofs.iter().map(|d| format!("\"{d}\"")).collect();
            writeln!(w, "\n[[ties]]\nnodes = [{a}, {b}]\ndofs = [{}]", dofs.join(", ")).unwrap();
        }
        s
    }
}

// ------------------------------------------------------------------ effects

/// Damping of one group: `C = alpha K` with the kernel `mu / (mu + j w)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Damp {
    pub(crate) alpha: f64,
    pub(crate) mu: Option<f64>,
}

/// How the springs of a support or joint are written.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Layout {
    /// One spring with kx, ky and kr, in one group.
    Single(Damp),
    /// One spring per direction, each in its own group (x, y, r).
    PerDirection([Damp; 3]),
}

/// A drawn effect: everything needed to write it into a frame.
#[derive(Clone, Debug)]
pub(crate) enum Recipe {
    Support {
        node: u32,
        /// Global kx, ky, kr.
        k: [f64; 3],
        layout: Layout,
        /// Springs to a supported coincident node (else to ground directly).
        ground_node: bool,
    },
    /// A joint or splice: `moved` is detached from `node` onto a new
    /// coincident node joined to it by springs.
    Joint {
        family: Family,
        node: u32,
        moved: u32,
        k: [f64; 3],
        layout: Layout,
    },
    Patch {
        elements: Vec<u32>,
        damp: Damp,
    },
    Mass {
        node: u32,
        m: f64,
        j: f64,
        /// In its own undamped group (else in the structure's group).
        own_group: bool,
    },
    Loss {
        elements: Vec<u32>,
        factor: f64,
        /// A section of smaller I (bending only), else a material of smaller E.
        by_section: bool,
    },
}

pub(crate) fn log_uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    rng.random_range(lo.ln()..hi.ln()).exp()
}

/// `alpha` of a group whose loss factor at `f_ref` is `eta`: the kernel
/// contributes `j w alpha mu / (mu + j w)`, whose imaginary part is
/// `alpha w mu^2 / (mu^2 + w^2)`. A relaxation far below `f_ref` would need
/// a large alpha, which also stiffens the group by `alpha mu` at high
/// frequencies; that stiffening is capped at half of the group's stiffness.
pub(crate) fn damp_for_loss(eta: f64, mu: Option<f64>, f_ref: f64) -> Damp {
    let w = 2.0 * PI * f_ref;
    match mu {
        None => Damp { alpha: eta / w, mu: None },
        Some(mu) => Damp { alpha: (eta * (mu * mu + w * w) / (w * mu * mu)).min(0.5 / mu), mu: Some(mu) },
    }
}

/// Damping of a lossy spring: loss factor 2-30 % at `f_ref`, with a
/// relaxation between 10 Hz and 2 kHz (below to above either band) unless
/// viscous.
fn spring_damp(rng: &mut ChaCha8Rng, viscous: bool, f_ref: f64) -> Damp {
    let eta = log_uniform(rng, 0.02, 0.3);
    let mu = (!viscous).then(|| 2.0 * PI * log_uniform(rng, 10.0, 2000.0));
    damp_for_loss(eta, mu, f_ref)
}

fn layout(rng: &mut ChaCha8Rng, viscous: bool, f_ref: f64) -> Layout {
    if rng.random_bool(0.5) {
        Layout::Single(spring_damp(rng, viscous, f_ref))
    } else {
        Layout::PerDirection([0; 3].map(|_| spring_damp(rng, viscous, f_ref)))
    }
}

/// Global (kx, ky) of a spring pair given along and across a member.
fn global(along_x: bool, axial: f64, transverse: f64) -> (f64, f64) {
    if along_x { (axial, transverse) } else { (transverse, axial) }
}

/// Chain positions an effect occupies, for keeping the two of a pair apart.
fn positions(geo: &Geometry, r: &Recipe) -> Vec<usize> {
    match r {
        Recipe::Support { node, .. } | Recipe::Joint { node, .. } | Recipe::Mass { node, .. } => {
            vec![geo.position(*node)]
        }
        Recipe::Patch { elements, .. } | Recipe::Loss { elements, .. } => {
            elements.iter().flat_map(|&e| geo.element_nodes(e)).map(|n| geo.position(n)).collect()
        }
    }
}

/// Least distance, in elements, between two sets of chain positions.
fn distance(a: &[usize], b: &[usize]) -> usize {
    a.iter().flat_map(|&p| b.iter().map(move |&q| p.abs_diff(q))).min().unwrap_or(usize::MAX)
}

/// Draws an effect of a family on a structure, at least 3 elements from the
/// positions in `avoid`; `None` when no place is far enough.
pub(crate) fn draw_recipe(rng: &mut ChaCha8Rng, geo: &Geometry, family: Family, avoid: &[usize]) -> Option<Recipe> {
    let far = |p: &[usize]| avoid.is_empty() || distance(p, avoid) >= 3;
    let ei = geo.e * geo.inertia();
    let ea = geo.e * geo.area();
    match family {
        Family::Support => {
            if !far(&[geo.position(geo.clamp)]) {
                return None;
            }
            // sized on the member the clamp holds: kr against the root
            // element's bending stiffness 4EI/Le, ky against its shear-like
            // 12EI/Le^3, the axial spring stiff against EA/Le
            let member = &geo.members[0];
            let le = geo.le(member);
            let kr = log_uniform(rng, 0.05, 2.0) * 4.0 * ei / le;
            let transverse = 10f64.powf(rng.random_range(0.0..2.0)) * 12.0 * ei / le.powi(3);
            let axial = 10f64.powf(rng.random_range(0.0..2.0)) * ea / le;
            let (kx, ky) = global(member.along_x, axial, transverse);
            let viscous = rng.random_bool(0.25);
            Some(Recipe::Support {
                node: geo.clamp,
                k: [kx, ky, kr],
                layout: layout(rng, viscous, geo.f_ref),
                ground_node: rng.random_bool(0.5),
            })
        }
        Family::Joint | Family::Splice => {
            // (node, moved element, member) of every place the family fits
            let places: Vec<(u32, u32, usize)> = if family == Family::Joint {
                if geo.members.len() < 2 {
                    return None;
                }
                // the corner: the arm's first element moves
                vec![(geo.members[1].nodes[0], geo.members[1].elements[0], 1)]
            } else {
                geo.members
                    .iter()
                    .enumerate()
                    .flat_map(|(mi, m)| {
                        (1..m.nodes.len() - 1)
                            .flat_map(move |i| [(m.nodes[i], m.elements[i - 1], mi), (m.nodes[i], m.elements[i], mi)])
                    })
                    .collect()
            };
            let places: Vec<_> = places.into_iter().filter(|p| far(&[geo.position(p.0)])).collect();
            if places.is_empty() {
                return None;
            }
            let (node, moved, mi) = places[rng.random_range(0..places.len())];
            let member = &geo.members[mi];
            let le = geo.le(member);
            // The joint's rotational compliance 1/kr adds to the member's
            // bending compliance, L/EI = 10 to 20 Le/EI here: kr = 0.2 EI/Le
            // adds 25-50 % to it, 8 EI/Le 0.6-1.3 %, against peak widths
            // 2 zeta of about 1 %. A splice near the free end bends little
            // in every mode, so it gets the softer part of the range;
            // draws that move no mode by JOINT_SHIFT_WIDTHS are redrawn.
            let stiffest = if family == Family::Joint { 8.0 } else { 3.0 };
            let kr = log_uniform(rng, 0.2, stiffest) * ei / le;
            let transverse = 10f64.powf(rng.random_range(0.0..2.0)) * 12.0 * ei / le.powi(3);
            let axial = 10f64.powf(rng.random_range(0.0..2.0)) * ea / le;
            let (kx, ky) = global(member.along_x, axial, transverse);
            Some(Recipe::Joint { family, node, moved, k: [kx, ky, kr], layout: layout(rng, false, geo.f_ref) })
        }
        Family::DampingPatch | Family::StiffnessLoss => {
            let longest = if family == Family::DampingPatch { 6 } else { 3 };
            let len = rng.random_range(1..=longest);
            let windows: Vec<Vec<u32>> = geo
                .members
                .iter()
                .flat_map(|m| m.elements.windows(len).map(|w| w.to_vec()))
                .filter(|w| {
                    let p: Vec<usize> = w.iter().flat_map(|&e| geo.element_nodes(e)).map(|n| geo.position(n)).collect();
                    far(&p)
                })
                .collect();
            if windows.is_empty() {
                return None;
            }
            let elements = windows[rng.random_range(0..windows.len())].clone();
            if family == Family::StiffnessLoss {
                return Some(Recipe::Loss {
                    elements,
                    factor: rng.random_range(0.4..0.8),
                    by_section: rng.random_bool(0.5),
                });
            }
            // a loss factor of 2-20 % in the patch at f_ref (the structure's
            // own is 0.7 % on the cantilever, 0.3 % on the L-frame), with a
            // relaxation from a twentieth of the band's top to 1.5 times it
            let eta = log_uniform(rng, 0.02, 0.2);
            let mu = (!rng.random_bool(0.25)).then(|| 2.0 * PI * log_uniform(rng, 0.05, 1.5) * geo.band.1);
            Some(Recipe::Patch { elements, damp: damp_for_loss(eta, mu, geo.f_ref) })
        }
        Family::Mass => {
            let free: Vec<u32> =
                geo.nodes.iter().map(|n| n.0).filter(|&n| n != geo.clamp && far(&[geo.position(n)])).collect();
            if free.is_empty() {
                return None;
            }
            let node = free[rng.random_range(0..free.len())];
            let m = rng.random_range(0.02..0.10) * geo.total_mass();
            let j = if rng.random_bool(0.5) {
                let r: f64 = rng.random_range(0.005..0.04);
                m * r * r
            } else {
                0.0
            };
            Some(Recipe::Mass { node, m, j, own_group: rng.random_bool(0.5) })
        }
    }
}

/// The ids of the nodes a truth adds, in the order it adds them.
pub(crate) struct Extra {
    next_node: u32,
}

impl Extra {
    pub(crate) fn new() -> Self {
        Extra { next_node: FIRST_EXTRA_NODE }
    }

    pub(crate) fn node(&mut self) -> u32 {
        self.next_node += 1;
        self.next_node - 1
    }
}

const AXES: [&str; 3] = ["x", "y", "r"];

/// Writes the springs `k` between `a` and `b` (or `a` and ground) with
/// their groups, named after `name`.
fn add_springs(frame: &mut Frame, name: &str, a: u32, b: Option<u32>, k: [f64; 3], layout: Layout) {
    match layout {
        Layout::Single(d) => {
            frame.groups.push(GroupText { name: name.into(), alpha: d.alpha, beta: 0.0, mu: d.mu });
            frame.springs.push(SpringText { name: name.into(), a, b, k, group: name.into() });
        }
        Layout::PerDirection(ds) => {
            for (i, d) in ds.iter().enumerate() {
                let n = format!("{name}_{}", AXES[i]);
                let mut ki = [0.0; 3];
                ki[i] = k[i];
                frame.groups.push(GroupText { name: n.clone(), alpha: d.alpha, beta: 0.0, mu: d.mu });
                frame.springs.push(SpringText { name: n.clone(), a, b, k: ki, group: n });
            }
        }
    }
}

impl Recipe {
    /// Writes the effect into a frame that holds the nominal model (and
    /// possibly another effect at least 3 elements away).
    pub(crate) fn apply(&self, frame: &mut Frame, extra: &mut Extra) {
        match self {
            &Recipe::Support { node, k, layout, ground_node } => {
                frame.supports.retain(|&n| n != node);
                let name = format!("support_{node}");
                if ground_node {
                    let g = extra.node();
                    frame.add_coincident(node, g);
                    frame.supports.push(g);
                    add_springs(frame, &name, g, Some(node), k, layout);
                } else {
                    add_springs(frame, &name, node, None, k, layout);
                }
            }
            &Recipe::Joint { family, node, moved, k, layout } => {
                let new = extra.node();
                frame.add_coincident(node, new);
                let beam = frame.beam_mut(moved);
                for n in beam.nodes.iter_mut().filter(|n| **n == node) {
                    *n = new;
                }
                let prefix = if family == Family::Joint { "joint" } else { "splice" };
                add_springs(frame, &format!("{prefix}_{node}"), node, Some(new), k, layout);
            }
            Recipe::Patch { elements, damp } => {
                let name = format!("patch_{}", elements[0]);
                let beta = frame.groups[0].beta;
                frame.groups.push(GroupText { name: name.clone(), alpha: damp.alpha, beta, mu: damp.mu });
                for &e in elements {
                    frame.beam_mut(e).group = name.clone();
                }
            }
            &Recipe::Mass { node, m, j, own_group } => {
                let name = format!("mass_{node}");
                let group = if own_group {
                    frame.groups.push(GroupText { name: name.clone(), alpha: 0.0, beta: 0.0, mu: None });
                    name.clone()
                } else {
                    frame.groups[0].name.clone()
                };
                frame.masses.push(MassText { name, node, m, j, group });
            }
            Recipe::Loss { elements, factor, by_section } => {
                let name = format!("loss_{}", elements[0]);
                let (e, rho) = (frame.materials[0].1, frame.materials[0].2);
                if *by_section {
                    // the same area (so the same mass and axial stiffness),
                    // a smaller second moment: a loss in bending only
                    let SectionText::Rectangle { b, h } = frame.sections[0].1 else {
                        panic!("the nominal section is a rectangle")
                    };
                    let sec = SectionText::AreaInertia { a: b * h, i: factor * b * h.powi(3) / 12.0 };
                    frame.sections.push((name.clone(), sec));
                    for &el in elements {
                        frame.beam_mut(el).section = name.clone();
                    }
                } else {
                    frame.materials.push((name.clone(), factor * e, rho));
                    for &el in elements {
                        frame.beam_mut(el).material = name.clone();
                    }
                }
            }
        }
    }

    pub(crate) fn family(&self) -> Family {
        match self {
            Recipe::Support { .. } => Family::Support,
            Recipe::Joint { family, .. } => *family,
            Recipe::Patch { .. } => Family::DampingPatch,
            Recipe::Mass { .. } => Family::Mass,
            Recipe::Loss { .. } => Family::StiffnessLoss,
        }
    }

    /// The effect as the test sees it.
    pub(crate) fn effect(&self) -> HiddenEffect {
        let named = |v: &[(&str, f64)]| v.iter().map(|&(n, x)| (n.to_string(), x)).collect::<Vec<_>>();
        let spring_damping = |layout: &Layout| {
            let mut d = Vec::new();
            let push = |d: &mut Vec<(String, f64)>, suffix: &str, damp: &Damp| {
                d.push((format!("alpha{suffix}"), damp.alpha));
                if let Some(mu) = damp.mu {
                    d.push((format!("mu{suffix}"), mu));
                }
            };
            match layout {
                Layout::Single(damp) => push(&mut d, "", damp),
                Layout::PerDirection(ds) => {
                    push(&mut d, "", &ds[2]);
                    for (i, key) in ["kx", "ky", "kr"].iter().enumerate() {
                        push(&mut d, &format!(".{key}"), &ds[i]);
                    }
                }
            }
            d
        };
        let mut e = HiddenEffect {
            family: self.family(),
            nodes: vec![],
            elements: vec![],
            stiffness: vec![],
            mass: vec![],
            damping: vec![],
        };
        match self {
            Recipe::Support { node, k, layout, .. } | Recipe::Joint { node, k, layout, .. } => {
                e.nodes = vec![*node];
                e.stiffness = named(&[("kx", k[0]), ("ky", k[1]), ("kr", k[2])]);
                e.damping = spring_damping(layout);
            }
            Recipe::Patch { elements, damp } => {
                e.elements = elements.clone();
                e.damping = named(&[("alpha", damp.alpha)]);
                e.damping.extend(damp.mu.map(|mu| ("mu".to_string(), mu)));
            }
            Recipe::Mass { node, m, j, .. } => {
                e.nodes = vec![*node];
                e.mass = named(&[("m", *m)]);
                if *j > 0.0 {
                    e.mass.push(("j".into(), *j));
                }
            }
            Recipe::Loss { elements, factor, .. } => {
                e.elements = elements.clone();
                e.stiffness = named(&[("factor", *factor)]);
            }
        }
        e
    }

    /// The effect in words.
    pub(crate) fn describe(&self) -> String {
        let damp = |d: &Damp| match d.mu {
            Some(mu) => format!("non-viscous, mu = 2 pi x {:.0} Hz", mu / (2.0 * PI)),
            None => "viscous".into(),
        };
        let springs = |l: &Layout| match l {
            Layout::Single(d) => damp(d),
            Layout::PerDirection(ds) => format!("one group per spring, kr's {}", damp(&ds[2])),
        };
        match self {
            Recipe::Support { node, k, layout, .. } => {
                let [kx, ky, kr] = k;
                format!(
                    "lossy support at node {node} (kr = {kr:.3e}, kx = {kx:.3e}, ky = {ky:.3e}; {})",
                    springs(layout)
                )
            }
            Recipe::Joint { family, node, k, layout, .. } => {
                let what = if *family == Family::Joint { "corner joint" } else { "splice" };
                format!("{what} at node {node} (kr = {:.3e}; {})", k[2], springs(layout))
            }
            Recipe::Patch { elements, damp: d } => format!(
                "damping patch on elements {}..{} (alpha = {:.2e}, {})",
                elements[0],
                elements.last().unwrap(),
                d.alpha,
                damp(d)
            ),
            Recipe::Mass { node, m, j, .. } if *j > 0.0 => {
                format!("mass at node {node} (m = {m:.4} kg, j = {j:.2e} kg m^2)")
            }
            Recipe::Mass { node, m, .. } => format!("mass at node {node} (m = {m:.4} kg)"),
            Recipe::Loss { elements, factor, by_section } => format!(
                "stiffness loss on elements {}..{} (x {factor:.3} of {})",
                elements[0],
                elements.last().unwrap(),
                if *by_section { "I" } else { "E" }
            ),
        }
    }
}

// ------------------------------------------------------------------ drawing

/// The nominal model's FRFs (receptance, no noise) on a structure's channels
/// and lines, computed once.
fn nominal_frfs(structure: Structure) -> &'static FrfSet {
    static CACHE: [OnceLock<FrfSet>; 2] = [OnceLock::new(), OnceLock::new()];
    let i = Structure::ALL.iter().position(|&s| s == structure).unwrap();
    CACHE[i].get_or_init(|| {
        let geo = Geometry::of(structure);
        let text = geo.frame().to_toml();
        let case = CaseFile::parse(Path::new("nominal.toml"), &text).expect("the nominal text parses");
        let sys = DampedSystem::new(case.model).expect("the nominal model assembles");
        synthesize(&sys, &geo.channels(), &geo.lines()).expect("the nominal FRFs")
    })
}

/// The damped system of a case-file text.
pub(crate) fn system(text: &str) -> Result<DampedSystem, String> {
    let case = CaseFile::parse(Path::new("truth.toml"), text).map_err(|e| e.to_string())?;
    DampedSystem::new(case.model).map_err(|e| e.to_string())
}

/// RMS over lines and channels of `|H - H_nominal| / |H|`: how far a case's
/// FRFs are from the nominal model's, relative to the case's own, which is
/// how relative measurement noise scales. The measured kind does not matter:
/// converting both sets multiplies both by the same factor.
pub(crate) fn misfit_to_nominal(structure: Structure, text: &str) -> Result<f64, String> {
    misfit_of(structure, &system(text)?)
}

fn misfit_of(structure: Structure, sys: &DampedSystem) -> Result<f64, String> {
    let geo = Geometry::of(structure);
    let h = synthesize(sys, &geo.channels(), &geo.lines()).map_err(|e| e.to_string())?;
    Ok(relative_rms(&h, nominal_frfs(structure)))
}

/// RMS of `|a - b| / |a|` over every value.
pub(crate) fn relative_rms(a: &FrfSet, b: &FrfSet) -> f64 {
    let n = a.values().len() as f64;
    (a.values().iter().zip(b.values()).map(|(x, y)| ((x - y) / x.norm()).norm_sqr()).sum::<f64>() / n).sqrt()
}

/// The largest shift of a mode in the band between the nominal model and a
/// truth, in half-power peak widths of the nominal mode (the modes are
/// paired in order; the nominal damping is Rayleigh, `zeta = (alpha w +
/// beta / w) / 2`).
fn largest_shift_in_widths(geo: &Geometry, truth_hz: &[f64]) -> f64 {
    let nominal = normal_modes(system(&geo.frame().to_toml()).unwrap().assembly()).unwrap().frequencies_hz;
    let (lo, hi) = (geo.band.0, geo.band.1);
    nominal
        .iter()
        .zip(truth_hz)
        .filter(|(f, _)| (lo..=hi).contains(*f))
        .map(|(&f, &t)| {
            let w = 2.0 * PI * f;
            let zeta = (geo.alpha * w + geo.beta / w) / 2.0;
            (t - f).abs() / (2.0 * zeta * f)
        })
        .fold(0.0, f64::max)
}

/// A drawn truth's misfit to the nominal model, or why it is refused: it
/// does not assemble, is not positive definite, has a mode below
/// [`LOWEST_MODE_HZ`], is not visible above the noise, or (when `joint`)
/// moves no mode by [`JOINT_SHIFT_WIDTHS`] peak widths.
pub(crate) fn check(structure: Structure, text: &str, joint: bool) -> Result<f64, String> {
    let sys = system(text)?;
    let modes = normal_modes(sys.assembly()).map_err(|e| e.to_string())?;
    let lowest = modes.frequencies_hz.first().copied().unwrap_or(0.0);
    if !(lowest >= LOWEST_MODE_HZ) {
        return Err(format!("lowest mode {lowest:.3} Hz"));
    }
    if joint {
        let shift = largest_shift_in_widths(&Geometry::of(structure), &modes.frequencies_hz);
        if shift < JOINT_SHIFT_WIDTHS {
            return Err(format!("a joint that moves the modes by {shift:.1} peak widths at most"));
        }
    }
    let misfit = misfit_of(structure, &sys)?;
    if misfit < VISIBLE {
        return Err(format!("misfit {misfit:.3} below {VISIBLE}"));
    }
    Ok(misfit)
}

pub(crate) fn truth_text(geo: &Geometry, recipes: &[Recipe]) -> String {
    let mut frame = geo.frame();
    let mut extra = Extra::new();
    for r in recipes {
        r.apply(&mut frame, &mut extra);
    }
    let what: Vec<String> = recipes.iter().map(Recipe::describe).collect();
    frame.comment = format!("True structure: {}, with {}.", geo.title.to_lowercase(), what.join(" and "));
    frame.to_toml()
}

fn random_family(rng: &mut ChaCha8Rng, structure: Structure) -> Family {
    let fitting: Vec<Family> = Family::ALL.into_iter().filter(|f| f.fits(structure)).collect();
    fitting[rng.random_range(0..fitting.len())]
}

fn random_structure(rng: &mut ChaCha8Rng, family: Option<Family>) -> Structure {
    match family {
        Some(f) if !f.fits(Structure::Cantilever) => Structure::LFrame,
        _ => Structure::ALL[rng.random_range(0..Structure::ALL.len())],
    }
}

fn trial(
    geo: &Geometry,
    label: String,
    truth: String,
    effects: Vec<HiddenEffect>,
    accelerance: bool,
    redraws: u32,
) -> Truth {
    Truth {
        label,
        structure: geo.structure,
        nominal: geo.frame().to_toml(),
        truth,
        effects,
        channels: geo.responses.iter().map(|r| (r.to_string(), geo.reference.to_string())).collect(),
        lines_hz: geo.lines(),
        accelerance,
        redraws,
    }
}

/// Draws a trial on a random structure (the L-frame for a joint): one effect
/// of `family` (any family when `None`), or with `pair` two effects, the
/// first of `family`, at least 3 elements apart.
pub(crate) fn draw(rng: &mut ChaCha8Rng, family: Option<Family>, pair: bool) -> Truth {
    let structure = random_structure(rng, family);
    draw_on(rng, structure, family, pair)
}

/// As [`draw`], on a given structure.
pub(crate) fn draw_on(rng: &mut ChaCha8Rng, structure: Structure, family: Option<Family>, pair: bool) -> Truth {
    let geo = Geometry::of(structure);
    if let Some(f) = family {
        assert!(f.fits(structure), "{f:?} does not fit the {structure:?}");
    }
    let accelerance = rng.random_bool(0.5);
    let mut redraws = 0;
    loop {
        assert!(redraws < MAX_REDRAWS, "{redraws} draws of {family:?} on the {structure:?} were all refused");
        let first = family.unwrap_or_else(|| random_family(rng, structure));
        let mut recipes = vec![draw_recipe(rng, &geo, first, &[]).expect("a place for a first effect")];
        if pair {
            let avoid = positions(&geo, &recipes[0]);
            let second = loop {
                let f = random_family(rng, structure);
                if f.unique() && f == first {
                    continue;
                }
                if let Some(r) = draw_recipe(rng, &geo, f, &avoid) {
                    break r;
                }
            };
            recipes.push(second);
        }
        let truth = truth_text(&geo, &recipes);
        // each effect of a pair must pass on its own, or "both found" could
        // not be asked of the diagnosis
        let is_joint = |r: &Recipe| matches!(r, Recipe::Joint { .. });
        let alone = |r: &Recipe| check(structure, &truth_text(&geo, std::slice::from_ref(r)), is_joint(r)).is_ok();
        let passes = match recipes.as_slice() {
            [single] => check(structure, &truth, is_joint(single)).is_ok(),
            _ => check(structure, &truth, false).is_ok() && recipes.iter().all(alone),
        };
        if !passes {
            redraws += 1;
            continue;
        }
        let label = recipes.iter().map(Recipe::describe).collect::<Vec<_>>().join(" + ");
        let effects = recipes.iter().map(Recipe::effect).collect();
        return trial(&geo, format!("{label} ({structure:?})"), truth, effects, accelerance, redraws);
    }
}

/// A null trial: the truth is the nominal model.
pub(crate) fn null(rng: &mut ChaCha8Rng) -> Truth {
    let geo = Geometry::of(random_structure(rng, None));
    let accelerance = rng.random_bool(0.5);
    let text = geo.frame().to_toml();
    trial(&geo, format!("null ({:?})", geo.structure), text, vec![], accelerance, 0)
}

// -------------------------------------------------------------------- tests

/// The tests of the generator itself. They read what a truth claims back
/// from the parsed case files, not from the generator's own records.
mod tests {
    use super::*;
    use fe_model::{Model, NodeId, Spring};
    use rand::SeedableRng;

    fn rng(seed: u64) -> ChaCha8Rng {
        ChaCha8Rng::seed_from_u64(seed)
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
    }

    /// Bending stiffness EI of a beam as the model assembles it.
    fn bending(m: &Model, beam: usize) -> f64 {
        let b = &m.beams()[beam];
        m.materials()[b.material].e
            * m.sections()[b.section].inertia
            * b.stiffness_factor
            * m.groups()[b.group].stiffness
    }

    /// Mass per length of a beam as the model assembles it.
    fn mass_per_length(m: &Model, beam: usize) -> f64 {
        let b = &m.beams()[beam];
        (m.materials()[b.material].rho * m.sections()[b.section].area + b.added_mass)
            * b.mass_factor
            * m.groups()[b.group].mass
    }

    fn beam_by_id(m: &Model, id: u32) -> usize {
        m.beam_index(fe_model::ElementId(id)).expect("the element exists")
    }

    fn springs_at(m: &Model, node: u32) -> Vec<&Spring> {
        m.springs().iter().filter(|s| s.a.0 == node || s.b.map(|b| b.0) == Some(node)).collect()
    }

    fn xy(m: &Model, node: u32) -> (f64, f64) {
        let n = m.node(NodeId(node)).expect("the node exists");
        (n.x, n.y)
    }

    /// Each spring's group has the effect's damping: `alpha.kx`, `mu.kx`,
    /// ... when each spring has its own group, else `alpha` and `mu`; and
    /// `alpha`, `mu` are always the rotational spring's.
    fn check_spring_damping(truth: &Model, springs: &[&Spring], e: &HiddenEffect, label: &str) {
        let per_spring = e.value("alpha.kr").is_some();
        for (i, (key, d)) in [("kx", Dof::Ux), ("ky", Dof::Uy), ("kr", Dof::Rz)].into_iter().enumerate() {
            for s in springs.iter().filter(|s| s.k[d] > 0.0) {
                let g = &truth.groups()[s.group];
                let suffixes = if per_spring { vec![format!(".{key}")] } else { vec![String::new()] };
                let suffixes = if i == 2 { [suffixes, vec![String::new()]].concat() } else { suffixes };
                for suffix in suffixes {
                    let alpha = e.value(&format!("alpha{suffix}")).expect("alpha");
                    assert!(close(g.alpha, alpha), "{label}: {key}'s group alpha {} vs alpha{suffix} {alpha}", g.alpha);
                    assert_eq!(g.mu, e.value(&format!("mu{suffix}")), "{label}: {key}'s group mu vs mu{suffix}");
                }
                assert!(g.alpha > 0.0 && g.beta == 0.0, "{label}: the {key} spring is lossy");
            }
        }
    }

    /// The sums of kx, ky, kr over the springs equal the effect's values.
    fn check_spring_stiffness(springs: &[&Spring], e: &HiddenEffect, label: &str) {
        for (key, d) in [("kx", Dof::Ux), ("ky", Dof::Uy), ("kr", Dof::Rz)] {
            let sum: f64 = springs.iter().map(|s| s.k[d]).sum();
            let want = e.value(key).expect("a spring stiffness");
            assert!(close(sum, want), "{label}: {key} reads back as {sum}, the effect says {want}");
            assert!(sum > 0.0, "{label}: {key} is finite, not absent");
        }
    }

    /// Reads every effect of a truth back from the parsed nominal and true
    /// models, and checks that nothing else changed.
    fn check_truth(t: &Truth) {
        let label = &t.label;
        assert!(!label.is_empty());
        for table in ["[[lines]]", "[[joints]]", "[[assign]]", "[set]", "[truth"] {
            assert!(!t.truth.contains(table) && !t.nominal.contains(table), "{label}: {table} is not used");
        }
        let (nominal, truth) = (t.nominal_case().model, t.truth_case().model);
        DampedSystem::new(truth.clone()).expect("the truth assembles");
        let modes = normal_modes(DampedSystem::new(truth.clone()).unwrap().assembly()).expect("K is positive definite");
        assert!(modes.frequencies_hz[0] >= LOWEST_MODE_HZ, "{label}: lowest mode {}", modes.frequencies_hz[0]);
        // every nominal node and element is still there, in place
        for n in nominal.nodes() {
            assert_eq!(xy(&truth, n.id.0), (n.x, n.y), "{label}: node {}", n.id);
        }
        for n in truth.nodes().iter().filter(|n| nominal.node(n.id).is_none()) {
            assert!(n.id.0 >= FIRST_EXTRA_NODE, "{label}: an added node has id {}", n.id);
        }
        let ids = |m: &Model| m.beams().iter().map(|b| b.id.0).collect::<Vec<_>>();
        assert_eq!(ids(&nominal), ids(&truth), "{label}: the same elements");
        for (r, e) in t.frf_channels().iter().map(|c| (c.response, c.reference)) {
            assert!(r.dof.is_translation() && e.dof.is_translation(), "{label}: translations only");
            assert!(nominal.node(r.node).is_some() && nominal.node(e.node).is_some());
        }

        let of = |f: Family| t.effects.iter().filter(move |e| e.family == f);
        let lossy: Vec<u32> = of(Family::StiffnessLoss).flat_map(|e| e.elements.clone()).collect();
        let patched: Vec<u32> = of(Family::DampingPatch).flat_map(|e| e.elements.clone()).collect();
        for (i, b) in truth.beams().iter().enumerate() {
            let n = beam_by_id(&nominal, b.id.0);
            assert!(close(mass_per_length(&truth, i), mass_per_length(&nominal, n)), "{label}: element {} mass", b.id);
            if !lossy.contains(&b.id.0) {
                assert!(close(bending(&truth, i), bending(&nominal, n)), "{label}: element {} EI", b.id);
            }
            if !patched.contains(&b.id.0) {
                assert_eq!(
                    truth.groups()[b.group],
                    nominal.groups()[nominal.beams()[n].group],
                    "{label}: element {}",
                    b.id
                );
            }
        }

        for e in &t.effects {
            for &n in &e.nodes {
                assert!(nominal.node(NodeId(n)).is_some(), "{label}: node {n} is a nominal node");
            }
            match e.family {
                Family::Support => {
                    let node = e.nodes[0];
                    assert!(nominal.supports().iter().any(|s| s.node.0 == node), "{label}: the nominal clamp");
                    assert!(truth.supports().iter().all(|s| s.node.0 != node), "{label}: the clamp is gone");
                    let springs = springs_at(&truth, node);
                    for s in &springs {
                        // to ground, or to a clamped node at the same place
                        let other = [Some(s.a.0), s.b.map(|b| b.0)].into_iter().flatten().find(|&n| n != node);
                        if let Some(g) = other {
                            assert!(nominal.node(NodeId(g)).is_none() && xy(&truth, g) == xy(&truth, node));
                            let held = truth.supports().iter().find(|s| s.node.0 == g).expect("a clamped ground node");
                            assert_eq!(held.dofs.len(), 3, "{label}: the ground node is clamped");
                        }
                    }
                    check_spring_stiffness(&springs, e, label);
                    check_spring_damping(&truth, &springs, e, label);
                }
                Family::Joint | Family::Splice => {
                    let node = e.nodes[0];
                    let springs = springs_at(&truth, node);
                    let others: Vec<u32> = springs
                        .iter()
                        .map(|s| if s.a.0 == node { s.b.expect("between two nodes").0 } else { s.a.0 })
                        .collect();
                    let new = others[0];
                    assert!(others.iter().all(|&o| o == new), "{label}: one coincident node");
                    assert!(nominal.node(NodeId(new)).is_none() && xy(&truth, new) == xy(&truth, node));
                    // exactly one element moved from the node to the new one
                    let moved: Vec<u32> = truth.beams_at(NodeId(new)).iter().map(|&i| truth.beams()[i].id.0).collect();
                    assert_eq!(moved.len(), 1, "{label}: one element on the new node");
                    let before = &nominal.beams()[beam_by_id(&nominal, moved[0])];
                    assert!(before.nodes.contains(&NodeId(node)), "{label}: the moved element was on node {node}");
                    let stay = nominal.beams_at(NodeId(node)).len() - 1;
                    assert_eq!(truth.beams_at(NodeId(node)).len(), stay, "{label}: the others stay");
                    assert!(stay >= 1, "{label}: a joint joins two members");
                    if e.family == Family::Joint {
                        // the arm (along x) is detached from the column's top
                        let b = beam_by_id(&nominal, moved[0]);
                        let (_, c, _) = nominal.beam_geometry(b);
                        assert!(c.abs() > 0.99 && nominal.beams_at(NodeId(node)).len() == 2, "{label}: the corner");
                    } else {
                        let (_, c0, s0) = nominal.beam_geometry(nominal.beams_at(NodeId(node))[0]);
                        let (_, c1, s1) = nominal.beam_geometry(nominal.beams_at(NodeId(node))[1]);
                        assert!(close(c0 * c1 + s0 * s1, 1.0), "{label}: a splice is in line");
                    }
                    check_spring_stiffness(&springs, e, label);
                    check_spring_damping(&truth, &springs, e, label);
                }
                Family::Mass => {
                    let node = NodeId(e.nodes[0]);
                    let here: Vec<_> = truth.masses().iter().filter(|m| m.node == node).collect();
                    let m: f64 = here.iter().map(|m| m.m).sum();
                    let j: f64 = here.iter().map(|m| m.j[2]).sum();
                    assert!(close(m, e.value("m").unwrap()), "{label}: m reads back as {m}");
                    assert!(close(j, e.value("j").unwrap_or(0.0)), "{label}: j reads back as {j}");
                    let share = m / nominal.total_mass();
                    assert!((0.02..=0.10).contains(&share), "{label}: {share} of the structure's mass");
                    assert!(nominal.supports().iter().all(|s| s.node != node), "{label}: at a free node");
                }
                Family::StiffnessLoss => {
                    let f = e.value("factor").unwrap();
                    assert!((0.4..=0.8).contains(&f) && (1..=3).contains(&e.elements.len()), "{label}");
                    for &id in &e.elements {
                        let ratio =
                            bending(&truth, beam_by_id(&truth, id)) / bending(&nominal, beam_by_id(&nominal, id));
                        assert!(close(ratio, f), "{label}: element {id}'s EI is {ratio} of nominal, not {f}");
                    }
                }
                Family::DampingPatch => {
                    assert!((1..=6).contains(&e.elements.len()), "{label}");
                    let nominal_group = &nominal.groups()[nominal.beams()[0].group];
                    for &id in &e.elements {
                        let g = &truth.groups()[truth.beams()[beam_by_id(&truth, id)].group];
                        assert!(close(g.alpha, e.value("alpha").unwrap()), "{label}: element {id}'s alpha");
                        assert!(g.alpha > 2.0 * nominal_group.alpha, "{label}: the patch damps more");
                        assert_eq!(g.mu, e.value("mu"), "{label}: element {id}'s mu");
                        assert_eq!(g.beta, nominal_group.beta, "{label}: the same beta");
                    }
                }
            }
        }
    }

    /// RMS relative difference between the truth's clean measurement and
    /// the nominal model's FRFs in the same kind, computed from the texts
    /// through the measurement helper.
    fn visibility(t: &Truth) -> f64 {
        let clean = t.measure(0.0, 0);
        assert_eq!(clean.kind(), t.kind());
        let sys = DampedSystem::new(t.nominal_case().model).unwrap();
        let nominal = synthesize(&sys, &t.frf_channels(), &t.lines_hz).unwrap().converted(t.kind());
        relative_rms(&clean, &nominal)
    }

    /// The Euler-Bernoulli cantilever's frequencies: (lambda_i)^2 / (2 pi)
    /// sqrt(EI / (rho A L^4)).
    #[test]
    fn nominal_structures_are_as_described_with_five_modes_in_band() {
        for s in Structure::ALL {
            let geo = Geometry::of(s);
            let t = trial(&geo, "nominal".into(), geo.frame().to_toml(), vec![], false, 0);
            let model = t.nominal_case().model;
            let (nodes, elements) = if s == Structure::Cantilever { (21, 20) } else { (23, 22) };
            assert_eq!((model.nodes().len(), model.beams().len()), (nodes, elements), "{s:?}");
            assert_eq!(model.supports().len(), 1);
            let modes = normal_modes(DampedSystem::new(model).unwrap().assembly()).unwrap();
            let (lo, hi) = (t.lines_hz[0], *t.lines_hz.last().unwrap());
            let inside = modes.frequencies_hz.iter().filter(|&&f| f > lo && f < hi).count();
            assert_eq!(inside, 5, "{s:?}: {:?}", &modes.frequencies_hz[..6]);
            // the band edges keep a margin of a few per cent to the nearest modes
            assert!(modes.frequencies_hz[0] > 3.0 * lo && modes.frequencies_hz[5] > 1.05 * hi);
            assert!(modes.frequencies_hz[4] < 0.95 * hi);
            assert!((6..=10).contains(&t.channels.len()));
            if s == Structure::Cantilever {
                let ei = 2.0e11 * 0.04 * 0.008f64.powi(3) / 12.0;
                let scale = (ei / (7800.0 * 0.04 * 0.008)).sqrt() / (2.0 * PI);
                for (f, lambda) in modes.frequencies_hz.iter().zip([1.875104, 4.694091, 7.854757, 10.995541, 14.137168])
                {
                    let exact = lambda * lambda * scale;
                    assert!((f / exact - 1.0).abs() < 2e-3, "{f} Hz against Euler-Bernoulli {exact} Hz");
                }
            }
        }
    }

    /// The largest shift of a mode in the band from the nominal model to the
    /// truth, in peak widths, from the parsed models: the nominal
    /// structure's group is Rayleigh-damped, so `zeta = (alpha w + beta / w) / 2`.
    fn shift_in_widths(t: &Truth) -> f64 {
        let nominal = t.nominal_case().model;
        let g = nominal.groups()[nominal.beams()[0].group].clone();
        let modes = |m: Model| normal_modes(DampedSystem::new(m).unwrap().assembly()).unwrap().frequencies_hz;
        let (before, after) = (modes(nominal), modes(t.truth_case().model));
        let band = t.lines_hz[0]..=*t.lines_hz.last().unwrap();
        let widths = before.iter().zip(&after).filter(|(f, _)| band.contains(*f)).map(|(&f, &a)| {
            let w = 2.0 * PI * f;
            (a - f).abs() / ((g.alpha * w + g.beta / w) * f)
        });
        widths.fold(0.0, f64::max)
    }

    /// Draws `per` truths of every family on a structure, checks each, and
    /// returns them.
    fn family_truths(structure: Structure, seed: u64, per: usize) -> Vec<Truth> {
        let mut r = rng(seed);
        let mut all = Vec::new();
        for f in Family::ALL.into_iter().filter(|f| f.fits(structure)) {
            let mut redraws = 0;
            for _ in 0..per {
                let t = draw_on(&mut r, structure, Some(f), false);
                assert_eq!(t.effects.len(), 1);
                assert_eq!(t.effects[0].family, f);
                check_truth(&t);
                let v = visibility(&t);
                assert!(v >= VISIBLE, "{}: visible at {v}, below {VISIBLE}", t.label);
                if matches!(f, Family::Joint | Family::Splice) {
                    let shift = shift_in_widths(&t);
                    assert!(shift >= JOINT_SHIFT_WIDTHS, "{}: modes move by {shift} peak widths", t.label);
                }
                redraws += t.redraws;
                all.push(t);
            }
            // the ranges are meant to give visible effects in most draws
            assert!(redraws as usize <= per, "{structure:?} {f:?}: {redraws} redraws for {per} truths");
        }
        all
    }

    #[test]
    fn every_family_parses_reads_back_and_stands_above_the_noise() {
        let truths: Vec<Truth> = [(Structure::Cantilever, 11), (Structure::LFrame, 12)]
            .into_iter()
            .flat_map(|(s, seed)| family_truths(s, seed, 4))
            .collect();
        assert_eq!(truths.len(), 4 * 11);
        let joints = truths.iter().filter(|t| t.effects[0].family == Family::Joint);
        assert!(joints.clone().all(|t| t.effects[0].nodes == [13]), "the joint is at the corner");
        // every way of writing an effect was read back at least once
        let of = |f: Family| truths.iter().filter(move |t| t.effects[0].family == f);
        let both = |f: Family, variant: &dyn Fn(&Truth) -> bool| of(f).any(variant) && !of(f).all(variant);
        let per_spring = |t: &Truth| t.effects[0].value("alpha.kr").is_some();
        assert!(
            both(Family::Support, &per_spring) && both(Family::Joint, &per_spring) && both(Family::Splice, &per_spring)
        );
        assert!(both(Family::Support, &|t| t.truth.contains("[[supports]]\nnode = 101")), "springs to a clamped node");
        assert!(both(Family::Support, &|t| t.effects[0].value("mu").is_some()), "viscous and non-viscous supports");
        assert!(both(Family::DampingPatch, &|t| t.effects[0].value("mu").is_some()), "viscous and non-viscous patches");
        assert!(both(Family::Mass, &|t| t.effects[0].value("j").is_some()), "masses with and without inertia");
        assert!(both(Family::StiffnessLoss, &|t| t.truth.contains("I = ")), "losses in I and in E");
        assert!(both(Family::Splice, &|t| t.structure == Structure::Cantilever), "splices on both structures");
    }

    #[test]
    fn pairs_hold_two_effects_apart_each_read_back() {
        let mut r = rng(13);
        for k in 0..6 {
            let first = [None, Some(Family::Support), Some(Family::Splice)][k % 3];
            let t = draw(&mut r, first, true);
            assert_eq!(t.effects.len(), 2, "{}", t.label);
            if let Some(f) = first {
                assert_eq!(t.effects[0].family, f);
            }
            check_truth(&t);
            let geo = Geometry::of(t.structure);
            let place = |e: &HiddenEffect| -> Vec<usize> {
                let ends = e.elements.iter().flat_map(|&el| geo.element_nodes(el));
                e.nodes.iter().copied().chain(ends).map(|n| geo.position(n)).collect()
            };
            let d = distance(&place(&t.effects[0]), &place(&t.effects[1]));
            assert!(d >= 3, "{}: {d} elements apart", t.label);
            assert!(visibility(&t) >= VISIBLE, "{}", t.label);
        }
    }

    /// Measured data are the truth's FRFs with the requested relative noise,
    /// in the requested kind.
    #[test]
    fn measurement_adds_the_requested_noise_in_the_requested_kind() {
        let mut r = rng(14);
        let t = draw_on(&mut r, Structure::Cantilever, Some(Family::Mass), false);
        let clean = t.measure(0.0, 0);
        let noisy = t.measure(0.01, 3);
        let level = relative_rms(&clean, &noisy);
        assert!((level / 0.01 - 1.0).abs() < 0.05, "relative noise {level}");
        assert_eq!(noisy.values(), t.measure(0.01, 3).values(), "the same seed, the same noise");
        let mut other = t.clone();
        other.accelerance = !t.accelerance;
        let (acc, rec) = if t.accelerance { (clean, other.measure(0.0, 0)) } else { (other.measure(0.0, 0), clean) };
        assert_eq!((acc.kind(), rec.kind()), (FrfKind::Accelerance, FrfKind::Receptance));
        for (k, &f) in t.lines_hz.iter().enumerate() {
            let w = 2.0 * PI * f;
            let (a, h) = (acc.get(0, k), rec.get(0, k));
            assert!((a + w * w * h).norm() <= 1e-12 * a.norm(), "accelerance is -w^2 receptance at {f} Hz");
        }
    }

    #[test]
    fn a_null_truth_is_its_nominal() {
        let mut r = rng(15);
        let kinds: Vec<(Structure, bool)> = (0..40)
            .map(|_| {
                let t = null(&mut r);
                assert!(t.effects.is_empty() && t.redraws == 0);
                assert_eq!(t.truth, t.nominal);
                (t.structure, t.accelerance)
            })
            .collect();
        assert!(Structure::ALL.iter().all(|s| kinds.iter().any(|k| k.0 == *s)), "both structures are drawn");
        assert!(kinds.iter().any(|k| k.1) && kinds.iter().any(|k| !k.1), "both kinds are drawn: {kinds:?}");
        let t = null(&mut r);
        assert_eq!(visibility(&t), 0.0);
    }

    #[test]
    fn draws_are_reproducible_from_the_seed() {
        let run = |seed| {
            let mut r = rng(seed);
            let single = draw(&mut r, None, false);
            let pair = draw(&mut r, None, true);
            let nothing = null(&mut r);
            [single, pair, nothing]
                .map(|t| (t.label, t.truth, t.nominal, t.effects, t.channels, t.lines_hz, t.accelerance, t.redraws))
        };
        assert_eq!(run(16), run(16));
        assert_ne!(run(16)[0].1, run(17)[0].1);
    }

    /// The nominal case with a `[measurement]` table is a case the tool loads.
    #[test]
    fn the_measurement_table_completes_the_nominal_case() {
        let t = draw(&mut rng(18), None, false);
        let text = format!("{}{}", t.nominal, t.measurement_table("measured.csv"));
        let case = CaseFile::parse(Path::new("dir/case.toml"), &text).unwrap();
        let m = case.measurement.unwrap();
        assert_eq!(m.frequencies_hz, t.lines_hz);
        assert_eq!(m.data.unwrap(), Path::new("dir/measured.csv"));
        let channels: Vec<(String, String)> =
            m.responses.iter().flat_map(|r| m.references.iter().map(move |e| (r.to_string(), e.to_string()))).collect();
        assert_eq!(channels, t.channels);
    }

    /// An explicit splice at a cantilever node, with springs `scale` times
    /// the element's axial, shear-like and bending stiffness.
    fn splice_text(scale: f64) -> String {
        let geo = Geometry::of(Structure::Cantilever);
        let le = geo.le(&geo.members[0]);
        let (ei, ea) = (geo.e * geo.inertia(), geo.e * geo.area());
        let k = [scale * ea / le, scale * 12.0 * ei / le.powi(3), scale * ei / le];
        let damp = Damp { alpha: 1e-4, mu: Some(2.0 * PI * 200.0) };
        let splice = Recipe::Joint { family: Family::Splice, node: 8, moved: 8, k, layout: Layout::Single(damp) };
        truth_text(&geo, &[splice])
    }

    /// Coincident nodes joined by springs become the continuous beam as the
    /// springs stiffen: the FRFs' difference falls like the springs'
    /// compliance, 1/scale.
    #[test]
    fn an_explicit_splice_tends_to_the_nominal_model_as_its_springs_stiffen() {
        let m: Vec<f64> = [1e2, 1e4, 1e6]
            .iter()
            .map(|&s| misfit_to_nominal(Structure::Cantilever, &splice_text(s)).unwrap())
            .collect();
        for w in m.windows(2) {
            let ratio = w[1] / w[0];
            assert!((0.5e-2..2e-2).contains(&ratio), "misfits {m:?}: each step of 100 should divide by 100");
        }
        assert!(m[2] < 1e-4, "misfits {m:?}");
    }

    /// The explicit splice is the same structure as the parser's own joint
    /// (`[[joints]]` with kx and ky, which splits the node and moves the
    /// element): the two roads give the same FRFs.
    #[test]
    fn an_explicit_splice_equals_the_parsers_joint() {
        let geo = Geometry::of(Structure::Cantilever);
        let explicit = splice_text(1.0);
        let case = CaseFile::parse(Path::new("explicit.toml"), &explicit).unwrap();
        let spring = &case.model.springs()[0];
        let g = &case.model.groups()[spring.group];
        let joint = format!(
            "{}\n[groups.j]\nalpha = {:?}\nmu = {:?}\n\n[[joints]]\nname = \"j\"\nnode = 8\nelements = [8]\n\
             kx = {:?}\nky = {:?}\nkr = {:?}\ngroup = \"j\"\n",
            geo.frame().to_toml(),
            g.alpha,
            g.mu.unwrap(),
            spring.k[Dof::Ux],
            spring.k[Dof::Uy],
            spring.k[Dof::Rz]
        );
        let other = CaseFile::parse(Path::new("joint.toml"), &joint).unwrap();
        let h = |m: Model| synthesize(&DampedSystem::new(m).unwrap(), &geo.channels(), &geo.lines()).unwrap();
        let (a, b) = (h(case.model), h(other.model));
        let d = relative_rms(&a, &b);
        assert!(d < 1e-9, "the explicit splice and the parser's joint differ by {d}");
        assert!(relative_rms(&a, nominal_frfs(Structure::Cantilever)) > VISIBLE, "and the splice is not rigid");
    }
}
