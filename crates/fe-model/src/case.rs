//! TOML case files: the model, where the measured data comes from, the truth
//! of a simulated study, and what to update.
//!
//! The format is described with an annotated example in `docs/case-files.md`;
//! every case under `cases/` is a working example. Errors name the file, the
//! line and the column.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;

use crate::dof::{Dof, DofRef};
use crate::error::{CaseError, ModelError};
use crate::model::{Group, Model, NodeId, Section};
use crate::quantity::{Parameter, Quantity};

mod edit;
mod measurement;
pub use edit::CaseEditor;
pub use measurement::{
    Calibration, CalibrationTarget, ChannelMap, DEFAULT_COHERENCE_THRESHOLD, FittedGain, GainKey, Gains, MaskRule,
    MeasurementSpec, PairingSpec,
};
use measurement::{RawMeasurement, parse_measurement};

// ---------------------------------------------------------------- raw schema

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCase {
    title: Option<String>,
    description: Option<String>,
    #[serde(default)]
    materials: BTreeMap<String, Spanned<RawMaterial>>,
    #[serde(default)]
    sections: BTreeMap<String, Spanned<RawSection>>,
    #[serde(default)]
    groups: BTreeMap<String, Spanned<RawGroup>>,
    #[serde(default)]
    nodes: Vec<Spanned<(u32, f64, f64)>>,
    #[serde(default)]
    lines: Vec<Spanned<RawLine>>,
    #[serde(default)]
    beams: Vec<Spanned<RawBeam>>,
    #[serde(default)]
    springs: Vec<Spanned<RawSpring>>,
    #[serde(default)]
    masses: Vec<Spanned<RawMass>>,
    #[serde(default)]
    supports: Vec<Spanned<RawSupport>>,
    #[serde(default)]
    ties: Vec<Spanned<RawTie>>,
    #[serde(default)]
    joints: Vec<Spanned<RawJoint>>,
    #[serde(default)]
    assign: Vec<Spanned<RawAssign>>,
    #[serde(default)]
    set: BTreeMap<String, Spanned<f64>>,
    measurement: Option<Spanned<RawMeasurement>>,
    truth: Option<Spanned<RawTruth>>,
    update: Option<Spanned<RawUpdate>>,
    paper: Option<Spanned<RawPaper>>,
    #[serde(default)]
    history: Vec<Spanned<RawHistory>>,
    check: Option<Spanned<RawCheck>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    #[serde(rename = "E")]
    e: f64,
    rho: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSection {
    #[serde(rename = "A")]
    area: Option<f64>,
    #[serde(rename = "I")]
    inertia: Option<f64>,
    b: Option<f64>,
    h: Option<f64>,
    od: Option<f64>,
    id: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGroup {
    #[serde(default)]
    alpha: f64,
    #[serde(default)]
    beta: f64,
    mu: Option<f64>,
    #[serde(default = "one")]
    stiffness: f64,
    #[serde(default = "one")]
    mass: f64,
}

fn one() -> f64 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLine {
    from: Spanned<toml::Value>,
    to: Spanned<toml::Value>,
    elements: Spanned<u32>,
    material: Spanned<String>,
    section: Spanned<String>,
    group: Spanned<String>,
    first_node: Option<u32>,
    first_element: Option<u32>,
    #[serde(default)]
    added_mass: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBeam {
    id: u32,
    nodes: [u32; 2],
    material: Spanned<String>,
    section: Spanned<String>,
    group: Spanned<String>,
    #[serde(default)]
    added_mass: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSpring {
    name: String,
    nodes: Option<[u32; 2]>,
    node: Option<u32>,
    #[serde(default)]
    kx: f64,
    #[serde(default)]
    ky: f64,
    #[serde(default)]
    kr: f64,
    group: Spanned<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMass {
    name: String,
    node: u32,
    #[serde(default)]
    m: f64,
    #[serde(default)]
    j: f64,
    group: Spanned<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSupport {
    node: u32,
    dofs: Option<Vec<Spanned<String>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTie {
    nodes: [u32; 2],
    dofs: Vec<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAssign {
    elements: Spanned<String>,
    group: Spanned<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawJoint {
    name: String,
    node: u32,
    elements: Vec<u32>,
    new_node: Option<u32>,
    kx: Option<f64>,
    ky: Option<f64>,
    kr: f64,
    group: Spanned<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTruth {
    #[serde(default)]
    noise: f64,
    #[serde(default)]
    floor: f64,
    #[serde(default)]
    seed: u64,
    #[serde(default)]
    set: BTreeMap<String, Spanned<f64>>,
    #[serde(default)]
    springs: Vec<Spanned<RawSpring>>,
    #[serde(default)]
    masses: Vec<Spanned<RawMass>>,
    #[serde(default)]
    joints: Vec<Spanned<RawJoint>>,
    #[serde(default)]
    groups: BTreeMap<String, Spanned<RawGroup>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawUpdate {
    parameters: Vec<Spanned<String>>,
    frequencies: Option<Spanned<toml::Value>>,
    method: Option<Spanned<String>>,
    max_iterations: Option<u32>,
    tolerance: Option<f64>,
    #[serde(default)]
    bounds: BTreeMap<String, Spanned<[f64; 2]>>,
    regularization: Option<Spanned<f64>>,
    #[serde(default)]
    gains: bool,
    misfit: Option<Spanned<String>>,
    coherence: Option<bool>,
    #[serde(default)]
    weights: Vec<Spanned<RawBandWeight>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBandWeight {
    from: f64,
    to: f64,
    weight: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHistory {
    step: String,
    misfit: f64,
    noise: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPaper {
    source: String,
    #[serde(default)]
    values: BTreeMap<String, Spanned<f64>>,
    #[serde(default)]
    frequencies_hz: Vec<f64>,
    note: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCheck {
    rfm: Option<Spanned<RawRunCheck>>,
    #[serde(rename = "output-error")]
    output_error: Option<Spanned<RawRunCheck>>,
    diagnosis: Option<Spanned<RawDiagnosisCheck>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRunCheck {
    status: Vec<Spanned<String>>,
    max_error: Option<Spanned<f64>>,
    within_sd: Option<Spanned<f64>>,
    #[serde(default)]
    weak: Vec<Spanned<String>>,
    noise: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDiagnosisCheck {
    leader: Spanned<String>,
    misfit_fall: Option<Spanned<f64>>,
}

// ------------------------------------------------------------- public specs

/// The truth of a simulated study: the model that generates "measured" data.
#[derive(Clone, Debug)]
pub struct TruthSpec {
    /// The truth model (the case's model with the truth's values and extra items).
    pub model: Model,
    /// Quantities set by the truth, in the *case model's* indexing, with values.
    pub values: Vec<(Quantity, f64)>,
    /// Relative complex noise level (0.01 = 1 %).
    pub noise: f64,
    /// Additive noise floor relative to each channel's RMS magnitude.
    pub floor: f64,
    /// Random seed.
    pub seed: u64,
}

/// Frequency points for updating.
#[derive(Clone, Debug, PartialEq)]
pub enum FrequencyChoice {
    /// This many lines spread evenly over the measured band.
    Lines(usize),
    /// Explicit points (Hz).
    List(Vec<f64>),
    /// Choose this many points automatically, away from resonances and anti-resonances.
    Auto(usize),
    /// Every measured line.
    All,
}

/// A weight on the measured lines of a frequency band (0 masks the band).
#[derive(Clone, Debug, PartialEq)]
pub struct BandWeight {
    /// Lower edge (Hz).
    pub from: f64,
    /// Upper edge (Hz).
    pub to: f64,
    /// Weight of the band's lines (1 is neutral).
    pub weight: f64,
}

/// What to update and how.
#[derive(Clone, Debug)]
pub struct UpdateSpec {
    /// Parameters to update.
    pub parameters: Vec<Parameter>,
    /// Optional bounds per parameter (same order), in physical units.
    pub bounds: Vec<Option<(f64, f64)>>,
    /// Frequency points (`None`: the method's default).
    pub frequencies: Option<FrequencyChoice>,
    /// Method name as written (checked by the solver crate).
    pub method: Option<(String, Range<usize>)>,
    /// Iteration limit.
    pub max_iterations: Option<u32>,
    /// Convergence tolerance on the largest relative correction.
    pub tolerance: Option<f64>,
    /// Tikhonov regularisation weight on the log-parameter changes.
    pub regularization: Option<f64>,
    /// Estimate an unknown complex gain per reference.
    pub gains: bool,
    /// Misfit form as written (`relative` or `log`), checked by the solver crate.
    pub misfit: Option<(String, Range<usize>)>,
    /// Weight lines by the measured coherence: `Some(false)` turns off the
    /// default (on whenever the data carry coherence), `Some(true)` requires
    /// coherence in the data.
    pub coherence: Option<bool>,
    /// Weights per frequency band.
    pub weights: Vec<BandWeight>,
}

/// Published values to print beside the tool's (for reproducing a paper).
#[derive(Clone, Debug)]
pub struct PaperSpec {
    /// Which table or figure.
    pub source: String,
    /// Published parameter values.
    pub values: Vec<(Quantity, f64)>,
    /// Published natural frequencies (Hz).
    pub frequencies_hz: Vec<f64>,
    /// A remark printed with the table.
    pub note: Option<String>,
}

/// One step of a case's history, written by rfm when it adds an effect or
/// updates (`[[history]]`): what the model was and how far it was from the
/// data, so that a later run can show the fall of the misfit from the
/// nominal model.
#[derive(Clone, Debug, PartialEq)]
pub struct HistoryEntry {
    /// What the step did (`nominal`, `+ flexible, lossy joint at node 13`, `updated`).
    pub step: String,
    /// RMS of `ln(model / measured)` per complex value after the step.
    pub misfit: f64,
    /// The data's estimated relative noise level, when known.
    pub noise: Option<f64>,
}

/// How an updating run may end, as its results name it (the statuses of
/// `rfm_update::rfm::Status`, whose tests keep the two lists equal).
pub const RUN_STATUSES: [&str; 6] =
    ["converged", "model_inadequate", "local_minimum", "stalled", "max_iterations", "failed"];

/// What `cargo xtask reproduce` requires of a case's results (`[check]`):
/// the case's acceptance, as data. See `docs/case-files.md`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CheckSpec {
    /// Of the run with the response function method (`[check.rfm]`).
    pub rfm: Option<RunCheck>,
    /// Of the run with the output-error estimator (`[check.output-error]`);
    /// its presence also asks `reproduce` to make that run.
    pub output_error: Option<RunCheck>,
    /// Of the diagnosis loop (`[check.diagnosis]`).
    pub diagnosis: Option<DiagnosisCheck>,
}

/// What one updating run must achieve.
#[derive(Clone, Debug, PartialEq)]
pub struct RunCheck {
    /// The statuses it may end with (names of [`RUN_STATUSES`]).
    pub status: Vec<String>,
    /// Largest `|updated - truth| / |truth|` allowed over the parameters.
    pub max_error: Option<f64>,
    /// Largest `|ln(updated / truth)|` allowed, in the run's own standard
    /// deviations of `ln p`, over the parameters it reports as well
    /// determined.
    pub within_sd: Option<f64>,
    /// Parameters the run must report as weakly determined.
    pub weak: Vec<String>,
    /// Largest relative distance allowed between the residual RMS the fit
    /// leaves and the truth's noise level: the check that its standard
    /// deviations are scaled honestly.
    pub noise: Option<f64>,
}

/// What the diagnosis of the case must find.
#[derive(Clone, Debug, PartialEq)]
pub struct DiagnosisCheck {
    /// Text the leading candidate's description must contain.
    pub leader: String,
    /// How many times at least the misfit must fall once the leading
    /// candidate is added and updated.
    pub misfit_fall: Option<f64>,
}

/// A loaded, validated case file.
#[derive(Clone, Debug)]
pub struct CaseFile {
    /// Path it was read from.
    pub path: PathBuf,
    /// Its text.
    pub source: String,
    /// Free-text description.
    pub description: Option<String>,
    /// The (initial) model.
    pub model: Model,
    /// Measurement description.
    pub measurement: Option<MeasurementSpec>,
    /// Truth of a simulated study.
    pub truth: Option<TruthSpec>,
    /// Updating setup.
    pub update: Option<UpdateSpec>,
    /// Published values.
    pub paper: Option<PaperSpec>,
    /// The misfit after each step that led to this case (`[[history]]`).
    pub history: Vec<HistoryEntry>,
    /// Acceptance of the case's results (`[check]`).
    pub check: Option<CheckSpec>,
}

// ------------------------------------------------------------------ loading

/// Most elements one `[[lines]]` entry may generate.
pub const MAX_LINE_ELEMENTS: u32 = 100_000;

struct Ctx<'a> {
    path: &'a Path,
    source: &'a str,
}

impl Ctx<'_> {
    fn err(&self, span: Range<usize>, message: impl Into<String>) -> CaseError {
        CaseError::at(self.path, self.source, Some(span), message.into())
    }
    fn model_err(&self, span: Range<usize>, e: ModelError) -> CaseError {
        self.err(span, e.to_string())
    }
    /// An error about the file as a whole (no line to point at).
    fn whole(&self, message: impl Into<String>) -> CaseError {
        CaseError::at(self.path, self.source, None, message.into())
    }
}

impl CaseFile {
    /// Reads and validates a case file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, CaseError> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|e| CaseError {
            file: path.to_path_buf(),
            location: None,
            message: format!("cannot read the case file: {e}"),
            snippet: None,
        })?;
        let source = crate::text::decode(&bytes).map_err(|e| CaseError {
            file: path.to_path_buf(),
            location: Some(crate::error::Location { line: e.line, column: e.column }),
            message: e.to_string(),
            snippet: None,
        })?;
        Self::parse(path, source)
    }

    /// The files a run of this case reads: the case file itself and its
    /// measured data file. Outputs must never be written over them.
    pub fn inputs(&self) -> Vec<PathBuf> {
        let data = self.measurement.as_ref().and_then(|m| m.data.clone());
        let geometry = self.measurement.as_ref().and_then(|m| m.geometry.clone());
        std::iter::once(self.path.clone()).chain(data).chain(geometry).collect()
    }

    /// Parses case-file text; `path` is used in messages and to resolve data files.
    pub fn parse(path: &Path, source: &str) -> Result<Self, CaseError> {
        let ctx = Ctx { path, source };
        let raw: RawCase = toml::from_str(source)
            .map_err(|e| CaseError::at(path, source, e.span(), with_suggestion(e.message().trim_end())))?;
        let mut model = Model::new(raw.title.as_deref().unwrap_or("untitled"));
        build_model(&ctx, &raw, &mut model)?;
        for (name, v) in &raw.set {
            let q = model.quantity(name).map_err(|e| ctx.model_err(v.span(), e))?;
            model.set(q, *v.get_ref()).map_err(|e| ctx.model_err(v.span(), e))?;
        }
        // Assemble once so that structural errors are reported at load time.
        crate::assembly::Assembly::new(&model).map_err(|e| ctx.whole(e.to_string()))?;

        let measurement = raw.measurement.as_ref().map(|m| parse_measurement(&ctx, m, &model)).transpose()?;
        let truth = raw.truth.as_ref().map(|t| parse_truth(&ctx, t, &model)).transpose()?;
        let update = raw.update.as_ref().map(|u| parse_update(&ctx, u, &model)).transpose()?;
        let paper = raw
            .paper
            .as_ref()
            .map(|p| {
                let p = p.get_ref();
                let values = resolve_values(&ctx, &p.values, &model)?;
                Ok::<_, CaseError>(PaperSpec {
                    source: p.source.clone(),
                    values,
                    frequencies_hz: p.frequencies_hz.clone(),
                    note: p.note.clone(),
                })
            })
            .transpose()?;
        let history = raw
            .history
            .iter()
            .map(|h| {
                let r = h.get_ref();
                let bad = |v: f64| !(v.is_finite() && v >= 0.0);
                if bad(r.misfit) || r.noise.is_some_and(bad) {
                    return Err(ctx.err(h.span(), "a history entry's misfit and noise must be finite and not negative"));
                }
                Ok(HistoryEntry { step: r.step.clone(), misfit: r.misfit, noise: r.noise })
            })
            .collect::<Result<Vec<_>, CaseError>>()?;
        let check = raw.check.as_ref().map(|c| parse_check(&ctx, c, truth.as_ref(), update.as_ref())).transpose()?;
        if let (Some(m), None) = (&measurement, &truth)
            && m.data.is_none()
        {
            return Err(ctx.err(
                raw.measurement.as_ref().unwrap().span(),
                "the measurement has no `data` file and the case has no [truth] to synthesise it from",
            ));
        }
        Ok(CaseFile {
            path: path.to_path_buf(),
            source: source.to_string(),
            description: raw.description,
            model,
            measurement,
            truth,
            update,
            paper,
            history,
            check,
        })
    }

    /// A located error about this file (for checks done by higher layers).
    pub fn error(&self, span: Option<Range<usize>>, message: impl Into<String>) -> CaseError {
        CaseError::at(&self.path, &self.source, span, message.into())
    }
}

/// A serde message about an unknown key (`unknown field `alpah`, expected
/// one of `alpha`, `beta`, ...`) with the closest valid key suggested.
fn with_suggestion(message: &str) -> String {
    let Some(rest) = message.strip_prefix("unknown field `") else { return message.to_string() };
    let Some((word, expected)) = rest.split_once('`') else { return message.to_string() };
    // the valid keys are the backquoted names after the unknown one
    let valid: Vec<&str> = expected.split('`').skip(1).step_by(2).collect();
    match crate::suggest::closest(word, valid.iter().copied()) {
        Some(best) => format!("{message}; did you mean `{best}`?"),
        None => message.to_string(),
    }
}

fn lookup(
    ctx: &Ctx<'_>,
    kind: &str,
    name: &Spanned<String>,
    found: Option<usize>,
    known: Vec<&str>,
) -> Result<usize, CaseError> {
    found.ok_or_else(|| {
        let hint = crate::suggest::closest(name.get_ref(), known.iter().copied())
            .map(|s| format!("; did you mean `{s}`?"))
            .unwrap_or_else(|| {
                format!(" (defined: {})", if known.is_empty() { "none".into() } else { known.join(", ") })
            });
        ctx.err(name.span(), format!("unknown {kind} `{}`{hint}", name.get_ref()))
    })
}

fn group_ref(ctx: &Ctx<'_>, model: &Model, name: &Spanned<String>) -> Result<usize, CaseError> {
    lookup(
        ctx,
        "group",
        name,
        model.group_index(name.get_ref()),
        model.groups.iter().map(|g| g.name.as_str()).collect(),
    )
}

fn raw_group(ctx: &Ctx<'_>, name: &str, g: &Spanned<RawGroup>) -> Result<Group, CaseError> {
    let r = g.get_ref();
    if let Some(mu) = r.mu
        && !(mu > 0.0)
    {
        return Err(ctx.err(
            g.span(),
            format!(
                "group `{name}`: mu must be positive (use `inf` or omit it for viscous damping), got {}",
                crate::show(mu)
            ),
        ));
    }
    Ok(Group {
        name: name.into(),
        alpha: r.alpha,
        beta: r.beta,
        mu: r.mu.filter(|m| m.is_finite()),
        stiffness: r.stiffness,
        mass: r.mass,
    })
}

fn build_model(ctx: &Ctx<'_>, raw: &RawCase, model: &mut Model) -> Result<(), CaseError> {
    for (name, m) in &raw.materials {
        model.add_material(name, m.get_ref().e, m.get_ref().rho).map_err(|e| ctx.model_err(m.span(), e))?;
    }
    for (name, s) in &raw.sections {
        let r = s.get_ref();
        let section = match (r.area, r.inertia, r.b, r.h, r.od, r.id) {
            (Some(a), Some(i), None, None, None, None) => Section { name: name.clone(), area: a, inertia: i },
            (None, None, Some(b), Some(h), None, None) => Section::rectangle(name, b, h),
            (None, None, None, None, Some(od), id) => {
                let id = id.unwrap_or(0.0);
                if !(id >= 0.0 && id < od) {
                    return Err(
                        ctx.err(s.span(), format!("section `{name}`: need 0 <= id < od, got od = {od}, id = {id}"))
                    );
                }
                Section::tube(name, od, id)
            }
            _ => {
                return Err(ctx.err(
                    s.span(),
                    format!("section `{name}`: give either A and I, or b and h (rectangle), or od and id (tube)"),
                ));
            }
        };
        model.add_section(section).map_err(|e| ctx.model_err(s.span(), e))?;
    }
    for (name, g) in &raw.groups {
        let group = raw_group(ctx, name, g)?;
        model.add_group(group).map_err(|e| ctx.model_err(g.span(), e))?;
    }
    for n in &raw.nodes {
        let (id, x, y) = *n.get_ref();
        model.add_node(id, x, y).map_err(|e| ctx.model_err(n.span(), e))?;
    }
    for line in &raw.lines {
        add_line(ctx, model, line)?;
    }
    for b in &raw.beams {
        let r = b.get_ref();
        let mat = lookup(
            ctx,
            "material",
            &r.material,
            model.material_index(r.material.get_ref()),
            model.materials.iter().map(|m| m.name.as_str()).collect(),
        )?;
        let sec = lookup(
            ctx,
            "section",
            &r.section,
            model.section_index(r.section.get_ref()),
            model.sections.iter().map(|m| m.name.as_str()).collect(),
        )?;
        let g = group_ref(ctx, model, &r.group)?;
        let i = model.add_beam(r.id, r.nodes, mat, sec, g).map_err(|e| ctx.model_err(b.span(), e))?;
        model.set_added_mass(i, r.added_mass).map_err(|e| ctx.model_err(b.span(), e))?;
    }
    for s in &raw.springs {
        add_spring(ctx, model, s)?;
    }
    // joints before masses, supports and ties: a joint makes a node (its
    // `new_node`, or the next free id) that those may name, as a case
    // written by `rfm diagnose --apply` does for a mass at a joint
    for j in &raw.joints {
        add_joint(ctx, model, j)?;
    }
    for m in &raw.masses {
        add_mass(ctx, model, m)?;
    }
    for s in &raw.supports {
        let r = s.get_ref();
        let dofs = match &r.dofs {
            None => Dof::ALL.to_vec(),
            Some(list) => parse_dofs(ctx, list)?,
        };
        model.add_support(r.node, &dofs).map_err(|e| ctx.model_err(s.span(), e))?;
    }
    for t in &raw.ties {
        let r = t.get_ref();
        let dofs = parse_dofs(ctx, &r.dofs)?;
        model.add_tie(r.nodes[0], r.nodes[1], &dofs).map_err(|e| ctx.model_err(t.span(), e))?;
    }
    for a in &raw.assign {
        let r = a.get_ref();
        let g = group_ref(ctx, model, &r.group)?;
        let text = r.elements.get_ref();
        let (first, last) = match text.split_once("..") {
            Some((x, y)) => (x.trim().parse::<u32>(), y.trim().parse::<u32>()),
            None => (text.trim().parse::<u32>(), text.trim().parse::<u32>()),
        };
        let (Ok(first), Ok(last)) = (first, last) else {
            return Err(ctx.err(r.elements.span(), format!("`{text}` is not an element id or a range first..last")));
        };
        if last < first {
            return Err(ctx.err(r.elements.span(), format!("the range `{text}` is empty")));
        }
        for id in first..=last {
            let i = model
                .beam_index(crate::model::ElementId(id))
                .ok_or_else(|| ctx.err(r.elements.span(), format!("element {id} does not exist")))?;
            model.set_beam_group(i, g).map_err(|e| ctx.model_err(a.span(), e))?;
        }
    }
    if model.beams.is_empty() && model.springs.is_empty() {
        return Err(ctx.whole("the case defines no beams, lines or springs"));
    }
    Ok(())
}

fn parse_dofs(ctx: &Ctx<'_>, list: &[Spanned<String>]) -> Result<Vec<Dof>, CaseError> {
    list.iter()
        .map(|d| {
            if d.get_ref() == "all" {
                return Err(ctx.err(d.span(), "write all DOFs as [\"ux\", \"uy\", \"rz\"] or omit `dofs`"));
            }
            d.get_ref().parse::<Dof>().map_err(|e| ctx.err(d.span(), e))
        })
        .collect()
}

fn add_spring(ctx: &Ctx<'_>, model: &mut Model, s: &Spanned<RawSpring>) -> Result<usize, CaseError> {
    let r = s.get_ref();
    let (a, b) = match (r.nodes, r.node) {
        (Some([a, b]), None) => (a, Some(b)),
        (None, Some(a)) => (a, None),
        _ => {
            return Err(ctx.err(
                s.span(),
                format!("spring `{}`: give `nodes = [a, b]` (between two nodes) or `node = a` (to ground)", r.name),
            ));
        }
    };
    let g = group_ref(ctx, model, &r.group)?;
    model.add_spring(&r.name, a, b, [r.kx, r.ky, r.kr], g).map_err(|e| ctx.model_err(s.span(), e))
}

/// A joint: the node is split, the listed elements move to a new coincident
/// node, the translations without a spring are tied and a spring (always kr,
/// and kx, ky when given) joins the pair.
fn add_joint(ctx: &Ctx<'_>, model: &mut Model, j: &Spanned<RawJoint>) -> Result<(), CaseError> {
    let r = j.get_ref();
    let g = group_ref(ctx, model, &r.group)?;
    let new_id = match r.new_node {
        Some(id) => id,
        None => model
            .max_node_id()
            .checked_add(1)
            .ok_or_else(|| ctx.err(j.span(), format!("joint `{}`: no node id left above {}", r.name, u32::MAX)))?,
    };
    model.split_node(r.node, &r.elements, new_id).map_err(|e| ctx.model_err(j.span(), e))?;
    let tied: Vec<Dof> =
        [(Dof::Ux, r.kx), (Dof::Uy, r.ky)].iter().filter(|(_, k)| k.is_none()).map(|(d, _)| *d).collect();
    if !tied.is_empty() {
        model.add_tie(r.node, new_id, &tied).map_err(|e| ctx.model_err(j.span(), e))?;
    }
    let k = [r.kx.unwrap_or(0.0), r.ky.unwrap_or(0.0), r.kr];
    model.add_spring(&r.name, r.node, Some(new_id), k, g).map_err(|e| ctx.model_err(j.span(), e))?;
    Ok(())
}

fn add_mass(ctx: &Ctx<'_>, model: &mut Model, m: &Spanned<RawMass>) -> Result<usize, CaseError> {
    let r = m.get_ref();
    let g = group_ref(ctx, model, &r.group)?;
    model.add_mass(&r.name, r.node, r.m, r.j, g).map_err(|e| ctx.model_err(m.span(), e))
}

enum End {
    Node(u32),
    Point(f64, f64),
}

fn parse_end(ctx: &Ctx<'_>, v: &Spanned<toml::Value>) -> Result<End, CaseError> {
    let bad = || ctx.err(v.span(), "expected an existing node id or a point [x, y]");
    match v.get_ref() {
        toml::Value::Integer(i) => u32::try_from(*i).map(End::Node).map_err(|_| bad()),
        toml::Value::Array(a) if a.len() == 2 => {
            let num = |x: &toml::Value| match x {
                toml::Value::Float(f) => Some(*f),
                toml::Value::Integer(i) => Some(*i as f64),
                _ => None,
            };
            match (num(&a[0]), num(&a[1])) {
                (Some(x), Some(y)) => Ok(End::Point(x, y)),
                _ => Err(bad()),
            }
        }
        _ => Err(bad()),
    }
}

fn add_line(ctx: &Ctx<'_>, model: &mut Model, line: &Spanned<RawLine>) -> Result<(), CaseError> {
    let r = line.get_ref();
    let n = *r.elements.get_ref();
    if n == 0 {
        return Err(ctx.err(r.elements.span(), "a line needs at least one element"));
    }
    if n > MAX_LINE_ELEMENTS {
        return Err(ctx.err(
            r.elements.span(),
            format!("{n} elements in one line is more than this tool accepts ({MAX_LINE_ELEMENTS})"),
        ));
    }
    let mat = lookup(
        ctx,
        "material",
        &r.material,
        model.material_index(r.material.get_ref()),
        model.materials.iter().map(|m| m.name.as_str()).collect(),
    )?;
    let sec = lookup(
        ctx,
        "section",
        &r.section,
        model.section_index(r.section.get_ref()),
        model.sections.iter().map(|m| m.name.as_str()).collect(),
    )?;
    let g = group_ref(ctx, model, &r.group)?;
    let exhausted = |what: &str| ctx.err(line.span(), format!("{what} ids of this line would pass {}", u32::MAX));
    let mut next_node = match r.first_node {
        Some(id) => Some(id),
        None => model.max_node_id().checked_add(1),
    };
    let mut next_elem = match r.first_element {
        Some(id) => Some(id),
        None => model.max_element_id().checked_add(1),
    };
    let point = |model: &Model, end: &End, span: Range<usize>| -> Result<(f64, f64), CaseError> {
        match *end {
            End::Point(x, y) => Ok((x, y)),
            End::Node(id) => model
                .node(NodeId(id))
                .map(|n| (n.x, n.y))
                .ok_or_else(|| ctx.err(span, format!("node {id} does not exist (define it before this line)"))),
        }
    };
    let from = parse_end(ctx, &r.from)?;
    let to = parse_end(ctx, &r.to)?;
    let (x0, y0) = point(model, &from, r.from.span())?;
    let (x1, y1) = point(model, &to, r.to.span())?;
    let mut add = |model: &mut Model, x: f64, y: f64| -> Result<u32, CaseError> {
        let id = next_node.ok_or_else(|| exhausted("node"))?;
        next_node = id.checked_add(1);
        model.add_node(id, x, y).map_err(|e| ctx.model_err(line.span(), e))?;
        Ok(id)
    };
    let start = match from {
        End::Node(id) => id,
        End::Point(x, y) => add(model, x, y)?,
    };
    let mut ids = vec![start];
    for i in 1..n {
        let t = f64::from(i) / f64::from(n);
        ids.push(add(model, x0 + t * (x1 - x0), y0 + t * (y1 - y0))?);
    }
    ids.push(match to {
        End::Node(id) => id,
        End::Point(x, y) => add(model, x, y)?,
    });
    for w in ids.windows(2) {
        let id = next_elem.ok_or_else(|| exhausted("element"))?;
        next_elem = id.checked_add(1);
        let i = model.add_beam(id, [w[0], w[1]], mat, sec, g).map_err(|e| ctx.model_err(line.span(), e))?;
        model.set_added_mass(i, r.added_mass).map_err(|e| ctx.model_err(line.span(), e))?;
    }
    Ok(())
}

/// Parses `31:uy` or a range `2..31:uy` (inclusive) into DOF references.
/// The range is expanded here, so a caller that knows the model should use
/// [`parse_dof_range`] and check each node as it goes, before a range of
/// four billion nodes is allocated.
pub fn parse_dof_list(text: &str) -> Result<Vec<DofRef>, String> {
    let (a, b, dof) = parse_dof_range(text)?;
    Ok((a..=b).map(|n| DofRef::new(n, dof)).collect())
}

/// Parses `31:uy` (the range `31..31`) or `2..31:uy` into its first and
/// last node and its DOF, without expanding it.
pub fn parse_dof_range(text: &str) -> Result<(u32, u32, Dof), String> {
    let (nodes, dof) = text
        .split_once(':')
        .ok_or_else(|| format!("`{text}` is not of the form node:dof or first..last:dof (for example 2..31:uy)"))?;
    let dof: Dof = dof.parse()?;
    if let Some((a, b)) = nodes.split_once("..") {
        let a: u32 = a.trim().parse().map_err(|_| format!("`{a}` in `{text}` is not a node id"))?;
        let b: u32 = b.trim().parse().map_err(|_| format!("`{b}` in `{text}` is not a node id"))?;
        if b < a {
            return Err(format!("range `{text}` is empty (last node before first)"));
        }
        Ok((a, b, dof))
    } else {
        let n: u32 = nodes.trim().parse().map_err(|_| format!("`{nodes}` in `{text}` is not a node id"))?;
        Ok((n, n, dof))
    }
}

/// Parses a frequency specification: a list of numbers, or a table
/// `{ from, to, step }` / `{ from, to, count }` (Hz).
fn parse_frequencies(ctx: &Ctx<'_>, v: &Spanned<toml::Value>) -> Result<Vec<f64>, CaseError> {
    let num = |x: &toml::Value| match x {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    };
    let freqs: Vec<f64> = match v.get_ref() {
        toml::Value::Array(a) => a
            .iter()
            .map(|x| num(x).ok_or_else(|| ctx.err(v.span(), "frequencies must be numbers (Hz)")))
            .collect::<Result<_, _>>()?,
        toml::Value::Table(t) => {
            const KEYS: [&str; 4] = ["from", "to", "step", "count"];
            for k in t.keys() {
                if !KEYS.contains(&k.as_str()) {
                    let hint = match crate::suggest::closest(k, KEYS) {
                        Some(best) => format!("did you mean `{best}`?"),
                        None => "use from, to and step or count".to_string(),
                    };
                    return Err(ctx.err(v.span(), format!("unknown key `{k}` in a frequency range; {hint}")));
                }
            }
            let get = |k: &str| t.get(k).and_then(num);
            let (from, to) = match (get("from"), get("to")) {
                (Some(a), Some(b)) => (a, b),
                _ => return Err(ctx.err(v.span(), "a frequency range needs `from` and `to` (Hz)")),
            };
            let count = match (get("step"), t.get("count")) {
                (Some(step), None) if step > 0.0 => (((to - from) / step + 1e-9).floor() as usize).saturating_add(1),
                (None, Some(toml::Value::Integer(c))) if *c >= 2 => *c as usize,
                _ => {
                    return Err(
                        ctx.err(v.span(), "a frequency range needs a positive `step` or an integer `count` >= 2")
                    );
                }
            };
            if count > 10_000_000 {
                return Err(
                    ctx.err(v.span(), format!("{count} frequency lines is more than this tool accepts (10 million)"))
                );
            }
            (0..count).map(|i| from + (to - from) * i as f64 / (count - 1).max(1) as f64).collect()
        }
        _ => return Err(ctx.err(v.span(), "expected a list of frequencies or a table { from, to, step }")),
    };
    if freqs.is_empty() {
        return Err(ctx.err(v.span(), "no frequencies given"));
    }
    for w in freqs.windows(2) {
        if !(w[1] > w[0]) {
            return Err(
                ctx.err(v.span(), format!("frequencies must increase strictly ({} is followed by {})", w[0], w[1]))
            );
        }
    }
    if let Some(f) = freqs.iter().find(|f| !(f.is_finite() && **f > 0.0)) {
        return Err(ctx.err(v.span(), format!("frequencies must be positive and finite (Hz), got {}", crate::show(*f))));
    }
    Ok(freqs)
}

fn parse_dof_refs(ctx: &Ctx<'_>, list: &[Spanned<String>], model: &Model) -> Result<Vec<DofRef>, CaseError> {
    let mut out = Vec::new();
    // a set, so that listing a hundred thousand DOFs stays linear
    let mut seen = std::collections::HashSet::new();
    for s in list {
        let (first, last, dof) = parse_dof_range(s.get_ref()).map_err(|e| ctx.err(s.span(), e))?;
        // Every node of the range must exist, so the walk stops at the first
        // missing one: it never goes further than the model has nodes.
        for node in first..=last {
            let r = DofRef::new(node, dof);
            if model.node(NodeId(node)).is_none() {
                return Err(ctx.err(s.span(), format!("node {node} does not exist in the model")));
            }
            if !seen.insert(r) {
                return Err(ctx.err(s.span(), format!("{r} is listed twice")));
            }
            out.push(r);
        }
    }
    Ok(out)
}

fn resolve_values(
    ctx: &Ctx<'_>,
    values: &BTreeMap<String, Spanned<f64>>,
    model: &Model,
) -> Result<Vec<(Quantity, f64)>, CaseError> {
    values
        .iter()
        .map(|(name, v)| {
            let q = model.quantity(name).map_err(|e| ctx.model_err(v.span(), e))?;
            Ok((q, *v.get_ref()))
        })
        .collect()
}

fn parse_truth(ctx: &Ctx<'_>, t: &Spanned<RawTruth>, base: &Model) -> Result<TruthSpec, CaseError> {
    let r = t.get_ref();
    if !(r.noise >= 0.0 && r.noise.is_finite() && r.floor >= 0.0 && r.floor.is_finite()) {
        return Err(ctx.err(t.span(), "noise and floor must be zero or positive"));
    }
    let mut model = base.clone();
    for (name, g) in &r.groups {
        let group = raw_group(ctx, name, g)?;
        match model.group_index(name) {
            Some(i) => *model.group_mut(i) = group,
            None => {
                model.add_group(group).map_err(|e| ctx.model_err(g.span(), e))?;
            }
        }
    }
    for s in &r.springs {
        add_spring(ctx, &mut model, s)?;
    }
    for m in &r.masses {
        add_mass(ctx, &mut model, m)?;
    }
    for j in &r.joints {
        add_joint(ctx, &mut model, j)?;
    }
    // Values may name items the truth adds, so resolve them on the truth model.
    for (name, v) in &r.set {
        let q = model.quantity(name).map_err(|e| ctx.model_err(v.span(), e))?;
        model.set(q, *v.get_ref()).map_err(|e| ctx.model_err(v.span(), e))?;
    }
    crate::assembly::Assembly::new(&model).map_err(|e| ctx.err(t.span(), format!("the truth model: {e}")))?;
    let values = r.set.iter().filter_map(|(name, v)| base.quantity(name).ok().map(|q| (q, *v.get_ref()))).collect();
    Ok(TruthSpec { model, values, noise: r.noise, floor: r.floor, seed: r.seed })
}

fn parse_update(ctx: &Ctx<'_>, u: &Spanned<RawUpdate>, model: &Model) -> Result<UpdateSpec, CaseError> {
    let r = u.get_ref();
    let mut parameters: Vec<Parameter> = Vec::new();
    for p in &r.parameters {
        let param = model.parameter(p.get_ref()).map_err(|e| ctx.model_err(p.span(), e))?;
        if let Some(q) = param.quantities.iter().find(|q| parameters.iter().any(|o| o.quantities.contains(q))) {
            return Err(ctx.err(
                p.span(),
                format!("`{}` is already updated by another parameter in the list", model.quantity_name(*q)),
            ));
        }
        for &q in &param.quantities {
            let v = model.get(q);
            if !(v > 0.0 && v.is_finite()) {
                return Err(ctx.err(
                    p.span(),
                    format!(
                        "`{}` starts at {v}; updating works on relative changes and needs a positive, finite starting value",
                        model.quantity_name(q)
                    ),
                ));
            }
        }
        parameters.push(param);
    }
    if parameters.is_empty() {
        return Err(ctx.err(u.span(), "no parameters to update"));
    }
    let mut bounds = vec![None; parameters.len()];
    for (name, b) in &r.bounds {
        let i = parameters.iter().position(|p| &p.name == name).ok_or_else(|| {
            ctx.err(b.span(), format!("bounds given for `{name}`, which is not in the parameters list"))
        })?;
        let [lo, hi] = *b.get_ref();
        if !(lo > 0.0 && hi > lo && hi.is_finite()) {
            return Err(
                ctx.err(b.span(), format!("bounds of `{name}` must satisfy 0 < lower < upper < inf, got [{lo}, {hi}]"))
            );
        }
        let v = model.get(parameters[i].quantities[0]);
        if !(lo <= v && v <= hi) {
            return Err(ctx.err(b.span(), format!("`{name}` starts at {v}, outside its bounds [{lo}, {hi}]")));
        }
        bounds[i] = Some((lo, hi));
    }
    let frequencies = match &r.frequencies {
        None => None,
        Some(v) => Some(match v.get_ref() {
            toml::Value::String(s) if s == "all" => FrequencyChoice::All,
            toml::Value::Table(t) if t.len() == 1 && (t.contains_key("auto") || t.contains_key("lines")) => {
                let (key, n) = t.iter().next().expect("one entry");
                match n {
                    toml::Value::Integer(n) if *n > 0 => {
                        if key == "auto" {
                            FrequencyChoice::Auto(*n as usize)
                        } else {
                            FrequencyChoice::Lines(*n as usize)
                        }
                    }
                    _ => return Err(ctx.err(v.span(), format!("`{key}` needs a positive number of lines"))),
                }
            }
            _ => FrequencyChoice::List(parse_frequencies(ctx, v)?),
        }),
    };
    if let Some(tol) = r.tolerance
        && !(tol > 0.0)
    {
        return Err(ctx.err(u.span(), "tolerance must be positive"));
    }
    if let Some(reg) = &r.regularization
        && !(*reg.get_ref() >= 0.0 && reg.get_ref().is_finite())
    {
        return Err(ctx.err(reg.span(), "regularization must be zero or positive"));
    }
    let weights = r
        .weights
        .iter()
        .map(|w| {
            let b = w.get_ref();
            if !(b.to > b.from && b.weight >= 0.0 && b.weight.is_finite()) {
                return Err(ctx.err(w.span(), "a band weight needs from < to and a weight >= 0"));
            }
            Ok(BandWeight { from: b.from, to: b.to, weight: b.weight })
        })
        .collect::<Result<_, _>>()?;
    Ok(UpdateSpec {
        parameters,
        bounds,
        frequencies,
        method: r.method.as_ref().map(|m| (m.get_ref().clone(), m.span())),
        max_iterations: r.max_iterations,
        tolerance: r.tolerance,
        regularization: r.regularization.as_ref().map(|r| *r.get_ref()),
        gains: r.gains,
        misfit: r.misfit.as_ref().map(|m| (m.get_ref().clone(), m.span())),
        coherence: r.coherence,
        weights,
    })
}

fn parse_check(
    ctx: &Ctx<'_>,
    c: &Spanned<RawCheck>,
    truth: Option<&TruthSpec>,
    update: Option<&UpdateSpec>,
) -> Result<CheckSpec, CaseError> {
    let r = c.get_ref();
    let run = |table: &Option<Spanned<RawRunCheck>>, name: &str| -> Result<Option<RunCheck>, CaseError> {
        let Some(t) = table else { return Ok(None) };
        let Some(update) = update else {
            return Err(ctx.err(t.span(), format!("[check.{name}] checks an update, and the case has no [update]")));
        };
        let r = t.get_ref();
        if r.status.is_empty() {
            return Err(ctx.err(t.span(), format!("[check.{name}] needs at least one `status`")));
        }
        for s in &r.status {
            if !RUN_STATUSES.contains(&s.get_ref().as_str()) {
                let hint = crate::suggest::closest(s.get_ref(), RUN_STATUSES)
                    .map(|b| format!("; did you mean `{b}`?"))
                    .unwrap_or_else(|| format!(" (available: {})", RUN_STATUSES.join(", ")));
                return Err(ctx.err(s.span(), format!("unknown status `{}`{hint}", s.get_ref())));
            }
        }
        let bound = |v: &Option<Spanned<f64>>, key: &str, needs: &str| -> Result<Option<f64>, CaseError> {
            let Some(v) = v else { return Ok(None) };
            if !(*v.get_ref() > 0.0 && v.get_ref().is_finite()) {
                return Err(ctx.err(v.span(), format!("`{key}` must be positive and finite")));
            }
            if truth.is_none() {
                return Err(ctx.err(v.span(), format!("`{key}` compares with {needs}, and the case has no [truth]")));
            }
            Ok(Some(*v.get_ref()))
        };
        let max_error = bound(&r.max_error, "max_error", "the truth")?;
        let within_sd = bound(&r.within_sd, "within_sd", "the truth")?;
        let noise = bound(&r.noise, "noise", "the truth's noise level")?;
        if let (Some(v), Some(t)) = (&r.noise, truth)
            && !(t.noise > 0.0)
        {
            return Err(ctx.err(v.span(), "`noise` compares with the truth's noise level, and the truth has no noise"));
        }
        let names: Vec<&str> = update.parameters.iter().map(|p| p.name.as_str()).collect();
        for w in &r.weak {
            if !names.contains(&w.get_ref().as_str()) {
                let hint = crate::suggest::closest(w.get_ref(), names.iter().copied())
                    .map(|b| format!("; did you mean `{b}`?"))
                    .unwrap_or_else(|| format!(" (updated: {})", names.join(", ")));
                return Err(ctx.err(w.span(), format!("`{}` is not an [update] parameter{hint}", w.get_ref())));
            }
        }
        Ok(Some(RunCheck {
            status: r.status.iter().map(|s| s.get_ref().clone()).collect(),
            max_error,
            within_sd,
            weak: r.weak.iter().map(|w| w.get_ref().clone()).collect(),
            noise,
        }))
    };
    let diagnosis = match &r.diagnosis {
        None => None,
        Some(d) => {
            let r = d.get_ref();
            if r.leader.get_ref().trim().is_empty() {
                return Err(ctx.err(r.leader.span(), "`leader` must name the effect the diagnosis ranks first"));
            }
            if let Some(f) = &r.misfit_fall
                && !(*f.get_ref() >= 1.0 && f.get_ref().is_finite())
            {
                return Err(ctx.err(f.span(), "`misfit_fall` is a factor of at least 1"));
            }
            Some(DiagnosisCheck {
                leader: r.leader.get_ref().clone(),
                misfit_fall: r.misfit_fall.as_ref().map(|f| *f.get_ref()),
            })
        }
    };
    Ok(CheckSpec { rfm: run(&r.rfm, "rfm")?, output_error: run(&r.output_error, "output-error")?, diagnosis })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<CaseFile, CaseError> {
        CaseFile::parse(Path::new("test.toml"), text)
    }

    const BEAM: &str = r#"
title = "beam"
[materials.steel]
E = 2e11
rho = 7800
[sections.bar]
b = 0.05
h = 0.01
[groups.beam]
alpha = 1e-5
[[lines]]
from = [0.0, 0.0]
to = [1.0, 0.0]
elements = 4
material = "steel"
section = "bar"
group = "beam"
[[supports]]
node = 1
"#;

    #[test]
    fn a_line_generates_nodes_and_elements() {
        let c = parse(BEAM).unwrap();
        assert_eq!(c.model.nodes().len(), 5);
        assert_eq!(c.model.beams().len(), 4);
        assert_eq!(c.model.node(NodeId(5)).unwrap().x, 1.0);
    }

    #[test]
    fn unknown_group_is_reported_with_line_column_and_suggestion() {
        let text = BEAM.replace("group = \"beam\"", "group = \"bean\"");
        let e = parse(&text).unwrap_err();
        assert!(e.message.contains("unknown group `bean`; did you mean `beam`?"), "{e}");
        let loc = e.location.unwrap();
        assert_eq!(text.lines().nth(loc.line - 1).unwrap().trim(), "group = \"bean\"");
    }

    #[test]
    fn toml_syntax_errors_are_located() {
        let e = parse("title = \n").unwrap_err();
        assert_eq!(e.location.unwrap().line, 1);
        assert!(e.to_string().starts_with("test.toml:1:"), "{e}");
    }

    #[test]
    fn a_joint_splits_a_node_ties_translations_and_adds_a_rotational_spring() {
        let text = format!(
            "{BEAM}\n[groups.j]\nalpha = 1e-3\n[[joints]]\nname = \"j3\"\nnode = 3\nelements = [3]\nkr = 5e3\ngroup = \"j\"\n"
        );
        let c = parse(&text).unwrap();
        assert_eq!(c.model.nodes().len(), 6);
        let e3 = &c.model.beams()[c.model.beam_index(crate::model::ElementId(3)).unwrap()];
        assert_eq!(e3.nodes[0], NodeId(6));
        assert_eq!(c.model.springs()[0].k, [0.0, 0.0, 5e3]);
        assert_eq!(c.model.ties()[0].dofs, vec![Dof::Ux, Dof::Uy]);
        let bad = text.replace("elements = [3]", "elements = [1]");
        assert!(parse(&bad).unwrap_err().message.contains("does not end at node 3"));
    }

    /// A mass may sit at the node a joint makes (as `rfm diagnose --apply`
    /// writes it), wherever the joint comes in the file.
    #[test]
    fn a_mass_may_sit_at_the_node_a_joint_makes() {
        let text = format!(
            "{BEAM}\n[[masses]]\nname = \"m\"\nnode = 6\nm = 0.2\ngroup = \"j\"\n\
             [groups.j]\nalpha = 1e-3\n[[joints]]\nname = \"j3\"\nnode = 3\nelements = [3]\nkr = 5e3\ngroup = \"j\"\n"
        );
        let c = parse(&text).unwrap();
        assert_eq!(c.model.masses()[0].node, NodeId(6));
        let e3 = &c.model.beams()[c.model.beam_index(crate::model::ElementId(3)).unwrap()];
        assert_eq!(e3.nodes[0], NodeId(6));
    }

    #[test]
    fn assign_moves_a_range_of_elements_to_a_group() {
        let text =
            format!("{BEAM}\n[groups.patch]\nalpha = 1e-3\n[[assign]]\nelements = \"2..3\"\ngroup = \"patch\"\n");
        let c = parse(&text).unwrap();
        let g = c.model.group_index("patch").unwrap();
        let groups: Vec<usize> = c.model.beams().iter().map(|b| b.group).collect();
        assert_eq!(groups, vec![0, g, g, 0]);
        let e = parse(&text.replace("2..3", "3..9")).unwrap_err();
        assert!(e.message.contains("element 5 does not exist"), "{e}");
    }

    #[test]
    fn update_bounds_must_hold_the_start_and_name_a_parameter() {
        let text = format!(
            "{BEAM}\n[measurement]\nfrequencies = [10.0, 20.0]\nreferences = [\"5:uy\"]\nresponses = [\"2..5:uy\"]\n[truth]\n[update]\nparameters = [\"group.beam.alpha\", \"element.1..2.stiffness\"]\nbounds = {{ \"group.beam.alpha\" = [1e-6, 1e-4] }}\n"
        );
        let c = parse(&text).unwrap();
        let u = c.update.unwrap();
        assert_eq!(u.bounds, vec![Some((1e-6, 1e-4)), None]);
        assert_eq!(u.parameters[1].quantities.len(), 2);
        let e = parse(&text.replace("[1e-6, 1e-4]", "[1e-4, 1e-3]")).unwrap_err();
        assert!(e.message.contains("outside its bounds"), "{e}");
        let e = parse(&text.replace("bounds = { \"group.beam.alpha\"", "bounds = { \"group.beam.beta\"")).unwrap_err();
        assert!(e.message.contains("not in the parameters list"), "{e}");
    }

    #[test]
    fn test_points_parse_with_signs_and_codes() {
        assert_eq!(ChannelMap::parse_test_point("101:+Z"), Ok((101, 3)));
        assert_eq!(ChannelMap::parse_test_point(" 7 : -rz "), Ok((7, -6)));
        assert_eq!(ChannelMap::parse_test_point("5:Y"), Ok((5, 2)));
        assert_eq!(ChannelMap::parse_test_point("5:-4"), Ok((5, -4)));
        assert_eq!(ChannelMap::parse_test_point("-1:S"), Ok((-1, 0)));
        for bad in ["101", "101:W", "x:+Z", "101:7", "101:+-Z"] {
            assert!(ChannelMap::parse_test_point(bad).unwrap_err().contains("is not a test point"), "{bad}");
        }
    }

    #[test]
    fn measurement_map_errors_are_located() {
        let base = format!(
            "{BEAM}[measurement]\nfrequencies = [10.0]\nreferences = [\"5:uy\"]\nresponses = [\"5:uy\"]\ndata = \"m.uff\"\n"
        );
        let ok = format!("{base}[[measurement.map]]\ntest = \"105:-Z\"\nmodel = \"5:uy\"\nsign = -1\n");
        let c = parse(&ok).unwrap();
        let m = &c.measurement.unwrap().map[0];
        assert_eq!((m.test_point(), m.model, m.sign), (Ok((105, -3)), DofRef::new(5, Dof::Uy), -1.0));

        let text = format!("{base}[[measurement.map]]\ntest = \"105:Q\"\nmodel = \"5:uy\"\n");
        let e = parse(&text).unwrap_err();
        assert!(e.message.contains("`105:Q` is not a test point"), "{e}");
        assert_eq!(text.lines().nth(e.location.unwrap().line - 1).unwrap(), "test = \"105:Q\"");

        let text = format!(
            "{base}[[measurement.map]]\ntest = \"105:+Z\"\nmodel = \"5:uy\"\n\
             [[measurement.map]]\ntest = \"105:-z\"\nmodel = \"4:uy\"\n"
        );
        let e = parse(&text).unwrap_err();
        assert!(e.message.contains("`105:-z` is already mapped by `105:+Z`"), "{e}");
        assert_eq!(text.lines().nth(e.location.unwrap().line - 1).unwrap(), "test = \"105:-z\"");
    }

    #[test]
    fn unknown_keys_get_the_closest_valid_key_of_their_table() {
        for (good, bad, table_line) in [
            ("alpha = 1e-5", "alpah = 1e-5", "alpah = 1e-5"),
            ("elements = 4", "elemnts = 4", "elemnts = 4"),
            ("rho = 7800", "rh0 = 7800", "rh0 = 7800"),
        ] {
            let text = BEAM.replace(good, bad);
            let e = parse(&text).unwrap_err();
            let want = good.split(' ').next().unwrap();
            assert!(e.message.contains(&format!("did you mean `{want}`?")), "{e}");
            assert_eq!(text.lines().nth(e.location.unwrap().line - 1).unwrap(), table_line);
        }
        // a key far from every valid one gets the list, not a guess
        let e = parse(&BEAM.replace("alpha = 1e-5", "zzzzzz = 1")).unwrap_err();
        assert!(e.message.contains("unknown field `zzzzzz`") && !e.message.contains("did you mean"), "{e}");
    }

    #[test]
    fn mask_rules_are_named_checked_and_need_a_data_file() {
        let base =
            format!("{BEAM}[measurement]\nfrequencies = [10.0]\nreferences = [\"5:uy\"]\nresponses = [\"5:uy\"]\n");
        let with_data = format!("{base}data = \"m.csv\"\n");
        let c = parse(&format!("{with_data}mask = [\"non-finite\", \"unmodelled-channels\"]\n")).unwrap();
        assert_eq!(c.measurement.unwrap().mask, vec![MaskRule::NonFinite, MaskRule::UnmodelledChannels]);
        let e = parse(&format!("{with_data}mask = [\"non-finit\"]\n")).unwrap_err();
        assert!(e.message.contains("unknown mask `non-finit`; did you mean `non-finite`?"), "{e}");
        let e = parse(&format!("{with_data}mask = [\"nan\", \"x\"]\n")).unwrap_err();
        assert!(
            e.message.contains("(available: non-finite, duplicate-lines, unmodelled-channels, bad-coherence)"),
            "{e}"
        );
        let e = parse(&format!("{with_data}mask = [\"non-finite\", \"non-finite\"]\n")).unwrap_err();
        assert!(e.message.contains("listed twice"), "{e}");
        let e = parse(&format!("{base}mask = [\"non-finite\"]\n")).unwrap_err();
        assert!(e.message.contains("has none"), "{e}");
        assert_eq!(e.location.unwrap().line, base.lines().count() + 1);
    }

    /// The beam with a truth and an update, for the `[check]` tests.
    fn checked(check: &str) -> String {
        format!(
            "{BEAM}[measurement]\nfrequencies = [10.0, 20.0]\nreferences = [\"5:uy\"]\nresponses = [\"2..5:uy\"]\n\
             [truth]\nnoise = 0.01\n[update]\nparameters = [\"group.beam.alpha\", \"group.beam.stiffness\"]\n{check}"
        )
    }

    /// The line of `text` an error points at.
    fn line_of<'a>(text: &'a str, e: &CaseError) -> &'a str {
        text.lines().nth(e.location.as_ref().expect("a located error").line - 1).unwrap().trim()
    }

    #[test]
    fn check_tables_are_read_per_run() {
        let text = checked(
            "[check.rfm]\nstatus = [\"converged\"]\nmax_error = 1e-8\n\
             [check.output-error]\nstatus = [\"converged\", \"model_inadequate\"]\nwithin_sd = 3\nweak = [\"group.beam.stiffness\"]\nnoise = 0.1\n\
             [check.diagnosis]\nleader = \"joint at node 3\"\nmisfit_fall = 10\n",
        );
        let c = parse(&text).unwrap().check.unwrap();
        let rfm = c.rfm.unwrap();
        assert_eq!(
            (rfm.status, rfm.max_error, rfm.within_sd, rfm.noise),
            (vec!["converged".into()], Some(1e-8), None, None)
        );
        let oe = c.output_error.unwrap();
        assert_eq!(oe.status, vec!["converged".to_string(), "model_inadequate".into()]);
        assert_eq!((oe.within_sd, oe.noise, oe.weak), (Some(3.0), Some(0.1), vec!["group.beam.stiffness".to_string()]));
        let d = c.diagnosis.unwrap();
        assert_eq!((d.leader.as_str(), d.misfit_fall), ("joint at node 3", Some(10.0)));
        assert!(parse(&checked("")).unwrap().check.is_none());
    }

    #[test]
    fn check_errors_name_the_key_and_its_line() {
        let cases = [
            // a misspelt key of a run check
            (
                "[check.rfm]\nstatus = [\"converged\"]\nmax_eror = 1e-8\n",
                "max_eror = 1e-8",
                "did you mean `max_error`?",
            ),
            // a misspelt run
            ("[check.rfn]\nstatus = [\"converged\"]\n", "[check.rfn]", "unknown field `rfn`"),
            (
                "[check.rfm]\nstatus = [\"convergd\"]\n",
                "status = [\"convergd\"]",
                "unknown status `convergd`; did you mean `converged`?",
            ),
            (
                "[check.rfm]\nstatus = [\"ok\"]\n",
                "status = [\"ok\"]",
                "(available: converged, model_inadequate, local_minimum, stalled, max_iterations, failed)",
            ),
            ("[check.rfm]\nstatus = []\n", "[check.rfm]", "needs at least one `status`"),
            ("[check.rfm]\nmax_error = 1e-8\n", "[check.rfm]", "missing field `status`"),
            (
                "[check.rfm]\nstatus = [\"converged\"]\nmax_error = -1\n",
                "max_error = -1",
                "`max_error` must be positive and finite",
            ),
            (
                "[check.rfm]\nstatus = [\"converged\"]\nwithin_sd = 0\n",
                "within_sd = 0",
                "`within_sd` must be positive and finite",
            ),
            (
                "[check.output-error]\nstatus = [\"converged\"]\nweak = [\"group.beam.stifness\"]\n",
                "weak = [\"group.beam.stifness\"]",
                "`group.beam.stifness` is not an [update] parameter; did you mean `group.beam.stiffness`?",
            ),
            ("[check.diagnosis]\nleader = \" \"\n", "leader = \" \"", "`leader` must name the effect"),
            (
                "[check.diagnosis]\nleader = \"joint\"\nmisfit_fall = 0.5\n",
                "misfit_fall = 0.5",
                "a factor of at least 1",
            ),
        ];
        for (check, line, words) in cases {
            let text = checked(check);
            let e = parse(&text).unwrap_err();
            assert!(e.message.contains(words), "{check}: {e}");
            assert_eq!(line_of(&text, &e), line, "{check}: {e}");
        }
        // checks against the truth need one, and checks of an update need an update
        let no_truth =
            checked("[check.rfm]\nstatus = [\"converged\"]\nnoise = 0.1\n").replace("[truth]\nnoise = 0.01\n", "");
        let no_truth = no_truth.replace("frequencies = [10.0, 20.0]", "frequencies = [10.0, 20.0]\ndata = \"m.csv\"");
        let e = parse(&no_truth).unwrap_err();
        assert!(
            e.message.contains("`noise` compares with the truth's noise level, and the case has no [truth]"),
            "{e}"
        );
        assert_eq!(line_of(&no_truth, &e), "noise = 0.1");
        let silent = checked("[check.output-error]\nstatus = [\"converged\"]\nnoise = 0.1\n")
            .replace("noise = 0.01", "noise = 0.0");
        let e = parse(&silent).unwrap_err();
        assert!(e.message.contains("the truth has no noise"), "{e}");
        let no_update = format!("{BEAM}[check.rfm]\nstatus = [\"converged\"]\n");
        let e = parse(&no_update).unwrap_err();
        assert!(e.message.contains("[check.rfm] checks an update, and the case has no [update]"), "{e}");
        assert_eq!(line_of(&no_update, &e), "[check.rfm]");
    }

    #[test]
    fn dof_lists_expand_ranges() {
        let v = parse_dof_list("2..4:uy").unwrap();
        assert_eq!(v, vec![DofRef::new(2, Dof::Uy), DofRef::new(3, Dof::Uy), DofRef::new(4, Dof::Uy)]);
        let e = parse_dof_list("4..2:uy").unwrap_err();
        assert!(e.contains("range `4..2:uy` is empty (last node before first)"), "{e}");
        let e = parse_dof_list("4").unwrap_err();
        assert!(e.contains("`4` is not of the form node:dof"), "{e}");
    }
}
