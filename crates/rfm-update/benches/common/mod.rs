//! Benchmark workloads shared by the criterion benchmarks and the
//! `bench_point` example (which `cargo xtask bench` runs once per
//! configuration, to measure each one's peak memory in its own process).

use damping::DampedSystem;
use fe_model::{Dof, Quantity, samples};
use frf::Channel;

/// A model with the parameters, channels and lines to assemble.
pub(crate) struct Workload {
    /// What it is, for labels.
    pub(crate) label: String,
    /// The model.
    pub(crate) sys: DampedSystem,
    /// Parameters to differentiate.
    pub(crate) params: Vec<Quantity>,
    /// Channels: every measured response over one reference.
    pub(crate) channels: Vec<Channel>,
    /// Lines (Hz).
    pub(crate) freqs: Vec<f64>,
}

/// The model families of the benchmarks.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Family {
    /// `samples::two_material_cantilever` with the paper's six damping
    /// parameters, 30 measured uy DOFs, the tip reference and the ten
    /// updating lines of `cases/two-material-beam.toml`.
    Paper,
    /// `samples::long_beam(elements)`.
    Beam {
        /// Number of beam elements.
        elements: usize,
    },
    /// `samples::frame_grid(bays, storeys, per)`.
    Frame {
        /// Bays.
        bays: usize,
        /// Storeys.
        storeys: usize,
        /// Elements per member.
        per: usize,
    },
    /// `samples::imported_plate(n, 6)`: imported matrices with the sparsity
    /// of a shell mesh, six groups.
    Shell {
        /// Cells along each side.
        n: usize,
    },
}

impl Family {
    /// Parses `paper`, `beam:<elements>`, `frame:<bays>x<storeys>x<per>` or `shell:<n>`.
    #[allow(dead_code)]
    pub(crate) fn parse(s: &str) -> Option<Family> {
        if s == "paper" {
            return Some(Family::Paper);
        }
        let (kind, size) = s.split_once(':')?;
        match kind {
            "beam" => Some(Family::Beam { elements: size.parse().ok()? }),
            "shell" => Some(Family::Shell { n: size.parse().ok()? }),
            "frame" => {
                let v: Vec<usize> = size.split('x').map(str::parse).collect::<Result<_, _>>().ok()?;
                match v[..] {
                    [bays, storeys, per] => Some(Family::Frame { bays, storeys, per }),
                    _ => None,
                }
            }
            _ => None,
        }
    }
}

/// `count` evenly spaced picks from `0..len` (all when `count >= len`).
fn spread(len: usize, count: usize) -> impl Iterator<Item = usize> {
    let count = count.min(len);
    (0..count).map(move |i| (2 * i + 1) * len / (2 * count))
}

/// Builds a workload. For the beam, frame and shell families the
/// parameters are first the groups' (alpha, beta, mu, stiffness and mass
/// factors of each group: they touch every element of the group), then
/// stiffness and mass factors of evenly spaced elements (one element each,
/// the diagnosis kind; the shell has none), up to `params`; the measured
/// DOFs are `measured` evenly spaced uy DOFs (uz on the shell), the
/// reference the middle one; the lines are `freqs` evenly spaced in 5-400
/// Hz. `Paper` ignores the counts.
pub(crate) fn workload(family: Family, params: usize, measured: usize, freqs: usize) -> Workload {
    let (model, label) = match family {
        Family::Paper => (samples::two_material_cantilever(), "paper beam".to_string()),
        Family::Beam { elements } => (samples::long_beam(elements), format!("long beam ({elements} elements)")),
        Family::Frame { bays, storeys, per } => {
            (samples::frame_grid(bays, storeys, per), format!("frame {bays}x{storeys}x{per}"))
        }
        Family::Shell { n } => (samples::imported_plate(n, 6), format!("imported shell {n}x{n}")),
    };
    let sys = DampedSystem::new(model).expect("sample models assemble");
    let m = sys.model();
    if let Family::Paper = family {
        let names = ["mu", "alpha", "beta"];
        let params = names
            .iter()
            .flat_map(|p| ["steel", "aluminium"].map(|g| m.quantity(&format!("group.{g}.{p}")).unwrap()))
            .collect();
        let tip = fe_model::DofRef::new(31, Dof::Uy);
        let channels = (2..=31).map(|n| Channel::new(fe_model::DofRef::new(n, Dof::Uy), tip)).collect();
        let freqs = vec![5.5, 13.5, 26.5, 48.0, 82.0, 115.5, 157.5, 209.5, 275.5, 336.0];
        return Workload { label, sys, params, channels, freqs };
    }
    let mut qs = Vec::with_capacity(params);
    for g in 0..m.groups().len() {
        qs.extend([
            Quantity::GroupAlpha(g),
            Quantity::GroupBeta(g),
            Quantity::GroupMu(g),
            Quantity::GroupStiffness(g),
            Quantity::GroupMass(g),
        ]);
    }
    qs.truncate(params);
    let rest = params - qs.len();
    for e in spread(m.beams().len(), rest.div_ceil(2)) {
        qs.push(Quantity::ElementStiffness(e));
        qs.push(Quantity::ElementMass(e));
    }
    qs.truncate(params);
    let dofs = sys.assembly().dofs();
    // the plate's normal, the beams' and frames' transverse direction
    let across = if let Family::Shell { .. } = family { Dof::Uz } else { Dof::Uy };
    let uy: Vec<_> = (0..sys.n()).map(|eq| dofs.dof_of(eq)).filter(|d| d.dof == across).collect();
    let meas: Vec<_> = spread(uy.len(), measured).map(|i| uy[i]).collect();
    let reference = meas[meas.len() / 2];
    let channels = meas.iter().map(|&r| Channel::new(r, reference)).collect();
    let freqs = (0..freqs).map(|k| 5.0 + 395.0 * (k as f64 + 0.5) / freqs as f64).collect();
    Workload { label, sys, params: qs, channels, freqs }
}
