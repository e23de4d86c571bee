//! Trials as a test lab makes them: the data's own set-up errors, physics
//! the nominal model lacks, and effects outside every family of the
//! diagnosis, each with the answer a tool should give (issue 32, item 7).
//!
//! The generator extends [`crate::truths`] and shares none of the
//! diagnosis's code: a trial is a pair of case-file texts written node by
//! node with truths.rs's writer (the nominal model the user has, complete
//! with its `[measurement]` and, where the family declares them, its
//! `[update]` parameters; and the structure that was measured), a list of
//! set-up errors applied to the synthesised FRFs by plain array operations,
//! an optional complex gain (data per volt) and the relative noise. What a
//! tool should conclude is an [`Expect`], written as TOML text beside the
//! data so that a test of any kind (this crate's, the CLI's) can read it
//! without knowing the tool's API.
//!
//! The families, drawn at random within the ranges of test practice
//! (`BRIEF.md` section 7):
//!
//! - set-up errors on the data ([`SetupError`]): one channel's polarity
//!   inverted; two channels' cables exchanged; a sensor that measures the
//!   other direction at its node; a sensor at a neighbouring node; one
//!   channel's calibration off by a real factor of 0.7-0.9 or 1.1-1.3. Each
//!   may come alone or with one hidden structural effect of truths.rs's
//!   families.
//! - physics the nominal lacks: an attached resonator (a mass on a spring
//!   and dashpot at a node, in one or two directions, its frequency in the
//!   band, viscous or exponential damping); a shaker's armature mass,
//!   suspension and electrical damping at the drive point (per volt, or per
//!   force taken from the coil current); accelerometer masses at the
//!   response nodes; a damping model-form error that the case's declared
//!   `[update]` parameters cover; null trials, some with declared
//!   parameters at their true values.
//! - three families outside every family the tool has or will have
//!   ([`LabFamily::outside`] says why for each): a phase lag linear in
//!   frequency on every channel, a member at another angle, and a fin whose
//!   bending modes its root's rotation drives.
//!
//! Every draw is checked and redrawn otherwise: the texts parse and
//! assemble, the truth has no mode below 0.5 Hz, each effect and each
//! set-up error stands [`VISIBLE`] above the noise on the trial's own
//! channels, and a resonator's truth has as many more modes in band than
//! the nominal model as the resonator has directions (a fin at least one).
//!
//! A study draws its trials with [`trials`] (every family, and every set-up
//! error with a structural effect), gives each nominal case the data of
//! [`LabTrial::measure`], and scores what the tool concludes against
//! [`LabTrial::expect`].
//!
//! `LAB_DUMP=DIR` writes a sample of trials (one per family and a few
//! combinations) as cases to run `rfm fix` on by hand; `LAB_CASES_WRITE=1`
//! rewrites the committed acceptance cases
//! (`crates/rfm-cli/tests/it/cases/lab/`) and the walkthrough's frame
//! (`cases/tutorial/lab-frame*`), which the tests otherwise check against
//! the generator.

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use damping::{DampedSystem, normal_modes};
use fe_model::{CaseFile, Dof, DofRef};
use frf::{C64, Channel, FrfKind, FrfSet, NoiseModel, synthesize};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::truths::{
    self, BeamText, Damp, Extra, Family, Frame, Geometry, GroupText, HiddenEffect, LOWEST_MODE_HZ, MassText, Recipe,
    SectionText, SpringText, Structure, VISIBLE, damp_for_loss, log_uniform, num, relative_rms, round, system,
};

/// The relative noise of every trial's measurement (1 %).
pub(crate) const NOISE: f64 = 0.01;

/// Redraws allowed before the generator gives up (a bug, not bad luck).
const MAX_REDRAWS: u32 = 500;

/// The data file a trial's nominal case reads, beside it.
pub(crate) const DATA_FILE: &str = "measured.csv";

// ------------------------------------------------------------------ families

/// What a trial holds besides the noise.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum LabFamily {
    /// One response channel inverted (a sensor mounted upside down, or its
    /// direction entered the wrong way).
    Polarity,
    /// Two channels' cables exchanged at the front end.
    Swap,
    /// A sensor that measures the other direction at its node, with either
    /// sign. On the L-frame only: on the straight cantilever the other
    /// direction is the axial one, which a transverse force does not move.
    Misdirected,
    /// A sensor mounted at a neighbouring node.
    WrongNode,
    /// One channel's calibration off by a real factor.
    Calibration,
    /// A mass on a spring and dashpot at a node.
    Resonator,
    /// A shaker at the drive point: armature mass, suspension stiffness and
    /// damping to ground.
    Shaker,
    /// The accelerometers' masses at the response nodes.
    SensorMasses,
    /// The structure's damping non-viscous and about three times the
    /// nominal's viscous guess; the case declares the group's `alpha`,
    /// `beta` and `mu` under `[update]`.
    DampingForm,
    /// Nothing but noise.
    Null,
    /// Outside: a phase lag linear in frequency on every channel.
    PhaseDrift,
    /// Outside: the L-frame's arm at another angle.
    SkewMember,
    /// Outside: a fin whose bending modes its root's rotation drives.
    Fin,
}

impl LabFamily {
    pub(crate) const ALL: [LabFamily; 13] = [
        LabFamily::Polarity,
        LabFamily::Swap,
        LabFamily::Misdirected,
        LabFamily::WrongNode,
        LabFamily::Calibration,
        LabFamily::Resonator,
        LabFamily::Shaker,
        LabFamily::SensorMasses,
        LabFamily::DampingForm,
        LabFamily::Null,
        LabFamily::PhaseDrift,
        LabFamily::SkewMember,
        LabFamily::Fin,
    ];

    /// Whether the family is an error of the test set-up on one or two
    /// channels (which may come with a structural effect).
    pub(crate) fn is_setup(self) -> bool {
        matches!(
            self,
            LabFamily::Polarity
                | LabFamily::Swap
                | LabFamily::Misdirected
                | LabFamily::WrongNode
                | LabFamily::Calibration
        )
    }

    /// Whether the family can be drawn on a structure.
    pub(crate) fn fits(self, structure: Structure) -> bool {
        !(matches!(self, LabFamily::Misdirected | LabFamily::SkewMember) && structure == Structure::Cantilever)
    }

    /// Why a family lies outside every family of effects the tool has or
    /// will have (issue 32: supports, joints, masses, stiffness and mass
    /// changes, damping patches, resonators, gains per reference or
    /// channel, and the data checks of item 2); `None` for the others.
    pub(crate) fn outside(self) -> Option<&'static str> {
        match self {
            LabFamily::PhaseDrift => Some(
                "every channel lags by a phase proportional to frequency (a delay between the force and \
                 response channels of the acquisition): a gain is one complex constant, and a change of the \
                 structure's stiffness, mass or damping changes channels differently and shifts their phase \
                 only near its modes",
            ),
            LabFamily::SkewMember => Some(
                "a member lies at another angle than the nominal one: every family changes stiffness, mass \
                 or damping at fixed places and keeps the geometry, and the angle sets how the arm's bending \
                 and axial motion load the column",
            ),
            LabFamily::Fin => Some(
                "a fin fixed across a member resonates when its root turns: a resonator is a mass on \
                 translational springs, which takes no moment from its node's rotation, and a lumped \
                 mass's rotary inertia does not resonate",
            ),
            _ => None,
        }
    }
}

// ----------------------------------------------------------- set-up errors

/// An error of the test set-up, applied to the synthesised FRFs by plain
/// array operations. Channels are indices into [`LabTrial::channels`], the
/// channels as the file names them.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum SetupError {
    /// The channel is negated.
    Polarity { channel: usize },
    /// The two channels' data are exchanged.
    Swap { a: usize, b: usize },
    /// The channel holds `sign` times the FRF of the other direction at its
    /// node, `measured`.
    Misdirected { channel: usize, measured: DofRef, sign: f64 },
    /// The channel holds the FRF at `measured`, a neighbouring node.
    WrongNode { channel: usize, measured: DofRef },
    /// The channel is `factor` times the true FRF.
    Calibration { channel: usize, factor: f64 },
    /// Every channel is delayed: multiplied by `exp(-j w seconds)`.
    Delay { seconds: f64 },
}

impl SetupError {
    /// The DOF a channel's sensor really measures, and the factor on it.
    fn physical(&self, i: usize, channel: Channel) -> (Channel, f64) {
        match *self {
            SetupError::Misdirected { channel: c, measured, sign } if c == i => {
                (Channel::new(measured, channel.reference), sign)
            }
            SetupError::WrongNode { channel: c, measured } if c == i => {
                (Channel::new(measured, channel.reference), 1.0)
            }
            _ => (channel, 1.0),
        }
    }

    /// Applies what happens after the sensors (cables, calibration, the
    /// acquisition's delay) to a set whose channels hold what each sensor
    /// measured.
    fn apply_after_sensors(&self, set: &mut FrfSet) {
        match *self {
            SetupError::Swap { a, b } => {
                let first = set.channel(a).to_vec();
                let second = set.channel(b).to_vec();
                set.channel_mut(a).copy_from_slice(&second);
                set.channel_mut(b).copy_from_slice(&first);
            }
            SetupError::Polarity { channel } => set.channel_mut(channel).iter_mut().for_each(|v| *v = -*v),
            SetupError::Calibration { channel, factor } => {
                set.channel_mut(channel).iter_mut().for_each(|v| *v *= factor)
            }
            SetupError::Delay { seconds } => {
                let lag: Vec<C64> =
                    set.frequencies_hz().iter().map(|&f| C64::from_polar(1.0, -2.0 * PI * f * seconds)).collect();
                for c in 0..set.channels().len() {
                    set.channel_mut(c).iter_mut().zip(&lag).for_each(|(v, l)| *v *= l);
                }
            }
            SetupError::Misdirected { .. } | SetupError::WrongNode { .. } => {}
        }
    }

    /// The channels whose data the error changes.
    fn channels(&self, n: usize) -> Vec<usize> {
        match *self {
            SetupError::Polarity { channel }
            | SetupError::Misdirected { channel, .. }
            | SetupError::WrongNode { channel, .. }
            | SetupError::Calibration { channel, .. } => vec![channel],
            SetupError::Swap { a, b } => vec![a, b],
            SetupError::Delay { .. } => (0..n).collect(),
        }
    }

    /// The error in words.
    fn describe(&self, channels: &[Channel]) -> String {
        match *self {
            SetupError::Polarity { channel } => format!("{} inverted", channels[channel]),
            SetupError::Swap { a, b } => format!("{} and {} swapped", channels[a], channels[b]),
            SetupError::Misdirected { channel, measured, sign } => {
                let s = if sign < 0.0 { "-" } else { "+" };
                format!("{} measures {s}{measured}", channels[channel])
            }
            SetupError::WrongNode { channel, measured } => {
                format!("{}'s sensor at {measured}", channels[channel])
            }
            SetupError::Calibration { channel, factor } => format!("{} reads x {factor:.3}", channels[channel]),
            SetupError::Delay { seconds } => format!("every channel delayed by {:.1} us", seconds * 1e6),
        }
    }

    /// What a tool should report about the data, in the file's channels.
    fn finding(&self, channels: &[Channel]) -> Option<Finding> {
        Some(match *self {
            SetupError::Polarity { channel } => Finding::Polarity { channel: channels[channel] },
            SetupError::Swap { a, b } => Finding::Swapped { a: channels[a], b: channels[b] },
            SetupError::Misdirected { channel, measured, sign } => {
                Finding::Misdirected { channel: channels[channel], measured, sign }
            }
            SetupError::WrongNode { channel, measured } => Finding::WrongNode { channel: channels[channel], measured },
            SetupError::Calibration { channel, factor } => Finding::Calibration { channel: channels[channel], factor },
            SetupError::Delay { .. } => return None,
        })
    }
}

// ------------------------------------------------------------ expectations

/// A finding about the data: what is wrong with a channel and the
/// correction (the inverse of the error).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Finding {
    /// Inverted: the correction is `sign = -1` for this channel.
    Polarity { channel: Channel },
    /// The two channels hold each other's data: exchange them.
    Swapped { a: Channel, b: Channel },
    /// The channel measured `sign` times `measured`, the other direction
    /// at its node: map it there, with that sign.
    Misdirected { channel: Channel, measured: DofRef, sign: f64 },
    /// The channel measured at `measured`: map it there.
    WrongNode { channel: Channel, measured: DofRef },
    /// The channel reads `factor` times the truth: divide it by `factor`.
    Calibration { channel: Channel, factor: f64 },
}

/// Named values in the order of their names, as a TOML table reads back.
fn by_name(mut values: Vec<(String, f64)>) -> Vec<(String, f64)> {
    values.sort_by(|a, b| a.0.cmp(&b.0));
    values
}

/// An effect the model lacks, in the diagnosis's words: `family` is one of
/// the kinds of `fe_model::case::EFFECT_KINDS`, or `resonator` (values `m`,
/// `kx` and/or `ky`, `alpha`, `mu` when non-viscous, and `f_hz` =
/// `sqrt(k / m) / 2 pi`), or `shaker` (a mass, a spring and a dashpot to
/// ground in the drive's direction: `m`, `kx` or `ky`, `c` in N s/m).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ExpectedEffect {
    pub(crate) family: String,
    /// Nominal node ids where it sits.
    pub(crate) nodes: Vec<u32>,
    /// Nominal element ids it covers.
    pub(crate) elements: Vec<u32>,
    /// True values, in the order of their names.
    pub(crate) values: Vec<(String, f64)>,
}

impl ExpectedEffect {
    /// A true value by name.
    pub(crate) fn value(&self, name: &str) -> Option<f64> {
        self.values.iter().find(|(n, _)| n == name).map(|&(_, v)| v)
    }

    /// A hidden effect of truths.rs in the diagnosis's words.
    fn of_hidden(h: &HiddenEffect) -> ExpectedEffect {
        let family = match h.family {
            Family::Support => "flexible_support",
            Family::Joint | Family::Splice => "flexible_joint",
            Family::DampingPatch if h.value("mu").is_some() => "non_viscous_damping",
            Family::DampingPatch => "viscous_damping",
            Family::Mass => "lumped_mass",
            Family::StiffnessLoss => "stiffness_change",
        };
        ExpectedEffect {
            family: family.into(),
            nodes: h.nodes.clone(),
            elements: h.elements.clone(),
            values: by_name(h.stiffness.iter().chain(&h.mass).chain(&h.damping).cloned().collect()),
        }
    }
}

/// What is left that no family explains, in a user's terms.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Remainder {
    /// Measured modes without a model partner, near `node`.
    ExtraModes { hz: Vec<f64>, node: u32 },
    /// A phase lag of `seconds` times `w` on every channel.
    PhaseDrift { seconds: f64 },
    /// The member of `elements` turned by `degrees` (counter-clockwise)
    /// about its first node.
    Geometry { elements: Vec<u32>, degrees: f64 },
}

impl Remainder {
    fn describe(&self) -> String {
        match self {
            Remainder::ExtraModes { hz, node } => {
                let f: Vec<String> = hz.iter().map(|f| format!("{f:.1}")).collect();
                format!("measured modes without a model partner at {} Hz, near node {node}", f.join(", "))
            }
            Remainder::PhaseDrift { seconds } => {
                format!("a phase lag growing linearly with frequency on every channel ({:.1} us)", seconds * 1e6)
            }
            Remainder::Geometry { elements, degrees } => format!(
                "the member of elements {}..{} lies {degrees:.1} degrees off its modelled direction",
                elements[0],
                elements.last().expect("a member")
            ),
        }
    }
}

/// The right answer to a trial.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Expect {
    /// Nothing is missing: no finding, no effect. The case's declared
    /// `[update]` parameters, if any, are at these true values.
    Nothing { declared: Vec<(String, f64)> },
    /// Updating the case's own `[update]` parameters explains the data;
    /// their true values.
    DeclaredOnly { values: Vec<(String, f64)> },
    /// These findings about the data and these effects, and nothing else.
    Found { findings: Vec<Finding>, effects: Vec<ExpectedEffect> },
    /// These findings (and these effects, which explain a part of the data
    /// rightly), and then the model cannot explain the data: stop and say
    /// what remains.
    Inadequate { findings: Vec<Finding>, effects: Vec<ExpectedEffect>, what: Vec<Remainder> },
    /// Several answers, each equally right: the data cannot tell them apart.
    OneOf(Vec<Expect>),
}

impl Expect {
    /// The equally right answers.
    pub(crate) fn answers(&self) -> Vec<&Expect> {
        match self {
            Expect::OneOf(all) => all.iter().collect(),
            one => vec![one],
        }
    }

    /// The expectation as TOML: one `[[answer]]` table per equally right
    /// answer, each with a `verdict` (`nothing`, `declared_only`, `found`,
    /// `inadequate`) and its `findings`, `effects`, `declared` values and
    /// `remainders`.
    pub(crate) fn to_toml(&self) -> String {
        let mut s = String::new();
        let w = &mut s;
        let values = |v: &[(String, f64)]| {
            let inner: Vec<String> = v.iter().map(|(k, x)| format!("\"{k}\" = {}", num(*x))).collect();
            format!("{{ {} }}", inner.join(", "))
        };
        for answer in self.answers() {
            let verdict = match answer {
                Expect::Nothing { .. } => "nothing",
                Expect::DeclaredOnly { .. } => "declared_only",
                Expect::Found { .. } => "found",
                Expect::Inadequate { .. } => "inadequate",
                Expect::OneOf(_) => panic!("alternatives are not nested"),
            };
            writeln!(w, "[[answer]]\nverdict = \"{verdict}\"").unwrap();
            match answer {
                Expect::Nothing { declared } if !declared.is_empty() => {
                    writeln!(w, "declared = {}", values(declared)).unwrap()
                }
                Expect::DeclaredOnly { values: v } => writeln!(w, "declared = {}", values(v)).unwrap(),
                _ => {}
            }
            let findings = match answer {
                Expect::Found { findings, .. } | Expect::Inadequate { findings, .. } => findings.as_slice(),
                _ => &[],
            };
            for f in findings {
                writeln!(w, "\n[[answer.findings]]").unwrap();
                match f {
                    Finding::Polarity { channel } => {
                        writeln!(w, "kind = \"polarity\"\nchannel = \"{channel}\"\nsign = -1.0").unwrap()
                    }
                    Finding::Swapped { a, b } => {
                        writeln!(w, "kind = \"swapped\"\nchannel = \"{a}\"\nwith = \"{b}\"").unwrap()
                    }
                    Finding::Misdirected { channel, measured, sign } => writeln!(
                        w,
                        "kind = \"misdirected\"\nchannel = \"{channel}\"\nmeasured = \"{measured}\"\nsign = {}",
                        num(*sign)
                    )
                    .unwrap(),
                    Finding::WrongNode { channel, measured } => {
                        writeln!(w, "kind = \"wrong_node\"\nchannel = \"{channel}\"\nmeasured = \"{measured}\"")
                            .unwrap()
                    }
                    Finding::Calibration { channel, factor } => {
                        writeln!(w, "kind = \"calibration\"\nchannel = \"{channel}\"\nfactor = {}", num(*factor))
                            .unwrap()
                    }
                }
            }
            if let Expect::Found { effects, .. } | Expect::Inadequate { effects, .. } = answer {
                for e in effects {
                    let ids = |v: &[u32]| v.iter().map(u32::to_string).collect::<Vec<_>>().join(", ");
                    writeln!(
                        w,
                        "\n[[answer.effects]]\nfamily = \"{}\"\nnodes = [{}]\nelements = [{}]\nvalues = {}",
                        e.family,
                        ids(&e.nodes),
                        ids(&e.elements),
                        values(&e.values)
                    )
                    .unwrap();
                }
            }
            if let Expect::Inadequate { what, .. } = answer {
                for r in what {
                    writeln!(w, "\n[[answer.remainders]]").unwrap();
                    match r {
                        Remainder::ExtraModes { hz, node } => {
                            let f: Vec<String> = hz.iter().map(|f| num(*f)).collect();
                            writeln!(w, "kind = \"extra_modes\"\nhz = [{}]\nnode = {node}", f.join(", ")).unwrap()
                        }
                        Remainder::PhaseDrift { seconds } => {
                            writeln!(w, "kind = \"phase_drift\"\nseconds = {}", num(*seconds)).unwrap()
                        }
                        Remainder::Geometry { elements, degrees } => {
                            let ids: Vec<String> = elements.iter().map(u32::to_string).collect();
                            writeln!(
                                w,
                                "kind = \"geometry\"\nelements = [{}]\ndegrees = {}",
                                ids.join(", "),
                                num(*degrees)
                            )
                            .unwrap()
                        }
                    }
                    writeln!(w, "text = \"{}\"", r.describe()).unwrap();
                }
            }
            writeln!(w).unwrap();
        }
        s
    }

    /// Reads the text [`Expect::to_toml`] writes.
    pub(crate) fn from_toml(text: &str) -> Result<Expect, String> {
        let doc: toml::Table = text.parse().map_err(|e| format!("{e}"))?;
        let answers = doc.get("answer").and_then(|a| a.as_array()).ok_or("no [[answer]]")?;
        let mut all = Vec::new();
        for a in answers {
            let a = a.as_table().ok_or("an answer is a table")?;
            let str_of = |t: &toml::Table, k: &str| -> Result<String, String> {
                t.get(k).and_then(|v| v.as_str()).map(str::to_string).ok_or(format!("no `{k}`"))
            };
            let float_of = |t: &toml::Table, k: &str| -> Result<f64, String> {
                t.get(k).and_then(|v| v.as_float()).ok_or(format!("no float `{k}`"))
            };
            let ids_of = |t: &toml::Table, k: &str| -> Result<Vec<u32>, String> {
                let v = t.get(k).and_then(|v| v.as_array()).ok_or(format!("no `{k}`"))?;
                v.iter().map(|x| x.as_integer().map(|i| i as u32).ok_or(format!("`{k}` holds ids"))).collect()
            };
            let named = |t: &toml::Table, k: &str| -> Result<Vec<(String, f64)>, String> {
                match t.get(k) {
                    None => Ok(vec![]),
                    Some(v) => v
                        .as_table()
                        .ok_or(format!("`{k}` is a table"))?
                        .iter()
                        .map(|(n, x)| x.as_float().map(|x| (n.clone(), x)).ok_or(format!("`{k}.{n}` is a float")))
                        .collect(),
                }
            };
            let tables = |k: &str| -> Vec<&toml::Table> {
                a.get(k).and_then(|v| v.as_array()).map_or(vec![], |v| v.iter().filter_map(|x| x.as_table()).collect())
            };
            let channel = |t: &toml::Table, k: &str| -> Result<Channel, String> { parse_channel(&str_of(t, k)?) };
            let dof = |t: &toml::Table, k: &str| -> Result<DofRef, String> { str_of(t, k)?.parse() };
            let mut findings = Vec::new();
            for f in tables("findings") {
                findings.push(match str_of(f, "kind")?.as_str() {
                    "polarity" => Finding::Polarity { channel: channel(f, "channel")? },
                    "swapped" => Finding::Swapped { a: channel(f, "channel")?, b: channel(f, "with")? },
                    "misdirected" => Finding::Misdirected {
                        channel: channel(f, "channel")?,
                        measured: dof(f, "measured")?,
                        sign: float_of(f, "sign")?,
                    },
                    "wrong_node" => {
                        Finding::WrongNode { channel: channel(f, "channel")?, measured: dof(f, "measured")? }
                    }
                    "calibration" => {
                        Finding::Calibration { channel: channel(f, "channel")?, factor: float_of(f, "factor")? }
                    }
                    other => return Err(format!("unknown finding `{other}`")),
                });
            }
            let mut effects = Vec::new();
            for e in tables("effects") {
                effects.push(ExpectedEffect {
                    family: str_of(e, "family")?,
                    nodes: ids_of(e, "nodes")?,
                    elements: ids_of(e, "elements")?,
                    values: named(e, "values")?,
                });
            }
            let mut what = Vec::new();
            for r in tables("remainders") {
                what.push(match str_of(r, "kind")?.as_str() {
                    "extra_modes" => {
                        let hz = r.get("hz").and_then(|v| v.as_array()).ok_or("no `hz`")?;
                        Remainder::ExtraModes {
                            hz: hz.iter().map(|x| x.as_float().ok_or("`hz` holds floats")).collect::<Result<_, _>>()?,
                            node: r.get("node").and_then(|v| v.as_integer()).ok_or("no `node`")? as u32,
                        }
                    }
                    "phase_drift" => Remainder::PhaseDrift { seconds: float_of(r, "seconds")? },
                    "geometry" => {
                        Remainder::Geometry { elements: ids_of(r, "elements")?, degrees: float_of(r, "degrees")? }
                    }
                    other => return Err(format!("unknown remainder `{other}`")),
                });
            }
            all.push(match str_of(a, "verdict")?.as_str() {
                "nothing" => Expect::Nothing { declared: named(a, "declared")? },
                "declared_only" => Expect::DeclaredOnly { values: named(a, "declared")? },
                "found" => Expect::Found { findings, effects },
                "inadequate" => Expect::Inadequate { findings, effects, what },
                other => return Err(format!("unknown verdict `{other}`")),
            });
        }
        Ok(if all.len() == 1 { all.pop().expect("one") } else { Expect::OneOf(all) })
    }
}

/// A channel written as `H(response,reference)`.
fn parse_channel(s: &str) -> Result<Channel, String> {
    let inner = s.strip_prefix("H(").and_then(|r| r.strip_suffix(')')).ok_or(format!("`{s}` is no channel"))?;
    let (r, e) = inner.split_once(',').ok_or(format!("`{s}` is no channel"))?;
    Ok(Channel::new(r.parse()?, e.parse()?))
}

// ----------------------------------------------------------------- a trial

/// One trial: the nominal case the user has, the structure that was
/// measured, how the test went wrong, and the right answer.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct LabTrial {
    /// What the trial holds, in words.
    pub(crate) label: String,
    pub(crate) family: LabFamily,
    /// The structural effect of truths.rs that a set-up error comes with.
    pub(crate) with: Option<Family>,
    pub(crate) structure: Structure,
    /// The complete nominal case: model, `[measurement]` reading
    /// [`DATA_FILE`], and `[update]` where the family declares parameters.
    pub(crate) nominal: String,
    /// Case text of what was measured (the model only).
    pub(crate) truth: String,
    /// The channels as the data file names them.
    pub(crate) channels: Vec<Channel>,
    pub(crate) lines_hz: Vec<f64>,
    pub(crate) kind: FrfKind,
    pub(crate) setup: Vec<SetupError>,
    /// Relative noise level.
    pub(crate) noise: f64,
    /// The complex gain of data per volt (force per volt of the amplifier).
    pub(crate) gain: Option<C64>,
    pub(crate) expect: Expect,
    /// Draws rejected before this one.
    pub(crate) redraws: u32,
}

impl LabTrial {
    /// The nominal case, parsed.
    pub(crate) fn nominal_case(&self) -> CaseFile {
        CaseFile::parse(Path::new("lab/nominal.toml"), &self.nominal).expect("the nominal case parses")
    }

    /// The measured structure's case, parsed.
    pub(crate) fn truth_case(&self) -> CaseFile {
        CaseFile::parse(Path::new("lab/truth.toml"), &self.truth).expect("the truth parses")
    }

    /// What each file channel's sensor really measured, and the factor on it.
    fn physical(&self) -> Vec<(Channel, f64)> {
        self.channels
            .iter()
            .enumerate()
            .map(|(i, &c)| self.setup.iter().map(|e| e.physical(i, c)).find(|&(p, _)| p != c).unwrap_or((c, 1.0)))
            .collect()
    }

    /// The file's channels in receptance, before gain and noise: the
    /// truth's FRFs where the sensors are, then the cables, calibrations
    /// and delay of the set-up.
    pub(crate) fn clean_file(&self) -> FrfSet {
        let sys = system(&self.truth).expect("the truth assembles");
        let physical = self.physical();
        let mut unique: Vec<Channel> = physical.iter().map(|p| p.0).collect();
        unique.sort();
        unique.dedup();
        let h = synthesize(&sys, &unique, &self.lines_hz).expect("the truth's FRFs");
        let mut set = FrfSet::zeros(self.lines_hz.clone(), self.channels.clone(), FrfKind::Receptance)
            .expect("the trial's channels are distinct");
        for (i, &(p, sign)) in physical.iter().enumerate() {
            let from = h.find(p).expect("a synthesised channel");
            set.channel_mut(i).iter_mut().zip(h.channel(from)).for_each(|(v, x)| *v = sign * x);
        }
        for e in &self.setup {
            e.apply_after_sensors(&mut set);
        }
        set
    }

    /// The measurement: [`LabTrial::clean_file`] in the trial's kind, times
    /// the gain when per volt, with the trial's relative noise from `seed`.
    pub(crate) fn measure(&self, seed: u64) -> FrfSet {
        let mut set = self.clean_file().converted(self.kind);
        if let Some(g) = self.gain {
            for c in 0..set.channels().len() {
                set.channel_mut(c).iter_mut().for_each(|v| *v *= g);
            }
        }
        NoiseModel::relative(self.noise, seed).apply(&mut set);
        set
    }

    /// The expectation file: the trial in comments, then [`Expect::to_toml`].
    pub(crate) fn expect_text(&self, seed: u64) -> String {
        let mut s = format!("# Lab trial (crates/rfm-update/tests/it/lab.rs): {}\n", self.label);
        let setup: Vec<String> = self.setup.iter().map(|e| e.describe(&self.channels)).collect();
        if !setup.is_empty() {
            s.push_str(&format!("# set-up: {}\n", setup.join("; ")));
        }
        s.push_str(&format!(
            "# measured: {} channels x {} lines, {}, {} % noise (seed {seed})",
            self.channels.len(),
            self.lines_hz.len(),
            self.kind,
            self.noise * 100.0
        ));
        if let Some(g) = self.gain {
            s.push_str(&format!(", per volt (gain {:.3} N/V at {:.1} deg)", g.norm(), g.arg().to_degrees()));
        }
        s.push('\n');
        if let Some(why) = self.family.outside() {
            s.push_str(&format!("# outside every family: {why}\n"));
        }
        s.push_str("# Any one [[answer]] below is right.\n\n");
        s.push_str(&self.expect.to_toml());
        s
    }

    /// Writes the trial into `dir`: `nominal.toml` (reading
    /// `measured.csv`), `measured.csv`, `truth.toml` and `expect.txt`, so
    /// that `rfm fix dir/nominal.toml` can be run on it.
    pub(crate) fn dump(&self, dir: &Path, seed: u64) -> std::io::Result<()> {
        self.dump_as(dir, &FileNames::default(), seed)
    }

    /// As [`LabTrial::dump`], under other file names.
    pub(crate) fn dump_as(&self, dir: &Path, names: &FileNames, seed: u64) -> std::io::Result<()> {
        std::fs::create_dir_all(dir)?;
        std::fs::write(dir.join(&names.nominal), names.nominal_text(self))?;
        let data = self.measure(seed);
        let per_volt = self.gain.is_some();
        let bytes = if names.data.ends_with(".uff") {
            uff_bytes(&data, per_volt)
        } else {
            csv_text(&data, per_volt).into_bytes()
        };
        std::fs::write(dir.join(&names.data), bytes)?;
        std::fs::write(dir.join(&names.truth), &self.truth)?;
        std::fs::write(dir.join(&names.expect), self.expect_text(seed))
    }
}

/// The names of a dumped trial's four files.
pub(crate) struct FileNames {
    pub(crate) nominal: String,
    pub(crate) data: String,
    pub(crate) truth: String,
    pub(crate) expect: String,
}

impl Default for FileNames {
    fn default() -> Self {
        FileNames {
            nominal: "nominal.toml".into(),
            data: DATA_FILE.into(),
            truth: "truth.toml".into(),
            expect: "expect.txt".into(),
        }
    }
}

impl FileNames {
    /// The trial's nominal case reading this data file.
    fn nominal_text(&self, t: &LabTrial) -> String {
        let from = format!("data = \"{DATA_FILE}\"");
        assert_eq!(t.nominal.matches(&from).count(), 1, "the nominal case reads its data once");
        t.nominal.replace(&from, &format!("data = \"{}\"", self.data))
    }
}

/// A set as a universal file (ASCII dataset 58, complex double), its
/// denominators in volts when per volt, as a test system exports it: a
/// case reads it through its `[[measurement.map]]`, whose `sign = -1`
/// corrects an inverted channel (the CSV reader names model DOFs and
/// ignores the map).
pub(crate) fn uff_bytes(set: &FrfSet, per_volt: bool) -> Vec<u8> {
    use frf::io::uff::{self, DataAxis, Encoding, UffWriteOptions};
    let mut functions =
        uff::frf_set_to_functions(set, &UffWriteOptions::default()).expect("FRFs a universal file holds");
    for f in functions.iter_mut().filter(|f| per_volt && f.header.function_type == uff::FUNCTION_FRF) {
        f.header.denominator = DataAxis::new(0, "Voltage", "V");
    }
    uff::encode(&functions, Encoding::Ascii).expect("an encodable file")
}

/// A set as CSV with eight significant digits (far below the noise, and
/// half the size of every digit a double has), per volt when asked.
pub(crate) fn csv_text(set: &FrfSet, per_volt: bool) -> String {
    let mut s = format!("# kind = {}\n# units = {}\nfrequency_hz", set.kind(), if per_volt { "SI/V" } else { "SI" });
    for c in set.channels() {
        write!(s, ",\"{c}.re\",\"{c}.im\"").unwrap();
    }
    s.push('\n');
    for (k, f) in set.frequencies_hz().iter().enumerate() {
        write!(s, "{f}").unwrap();
        for c in 0..set.channels().len() {
            let v = set.get(c, k);
            write!(s, ",{:.7e},{:.7e}", v.re, v.im).unwrap();
        }
        s.push('\n');
    }
    s
}

// --------------------------------------------------------- the physics

/// An undamped group (for masses).
fn undamped(name: &str) -> GroupText {
    GroupText { name: name.into(), alpha: 0.0, beta: 0.0, mu: None }
}

/// The index of a planar DOF in a spring's `[kx, ky, kr]`.
fn axis(d: Dof) -> usize {
    match d {
        Dof::Ux => 0,
        Dof::Uy => 1,
        Dof::Rz => 2,
        other => panic!("{other} is not a planar DOF"),
    }
}

/// The DOFs of an added node that nothing but its supports holds.
fn held_except(free: &[Dof]) -> Vec<Dof> {
    [Dof::Ux, Dof::Uy, Dof::Rz].into_iter().filter(|d| !free.contains(d)).collect()
}

/// An attached resonator: a mass `m` on a spring `k` with damping `damp`
/// (`C = alpha K`, kernel `mu / (mu + j w)`) at `node`, in each of `dofs`.
#[derive(Clone, Debug)]
pub(crate) struct Resonator {
    pub(crate) node: u32,
    pub(crate) dofs: Vec<Dof>,
    pub(crate) m: f64,
    pub(crate) k: f64,
    pub(crate) damp: Damp,
}

impl Resonator {
    /// Writes the resonator: a node at `node`'s place holding the mass,
    /// springs to `node` in `dofs`, and its other DOFs supported.
    fn add_to(&self, frame: &mut Frame, extra: &mut Extra) {
        let id = extra.node();
        frame.add_coincident(self.node, id);
        frame.groups.push(GroupText { name: "resonator".into(), alpha: self.damp.alpha, beta: 0.0, mu: self.damp.mu });
        frame.groups.push(undamped("resonator_mass"));
        let mut k = [0.0; 3];
        for &d in &self.dofs {
            k[axis(d)] = self.k;
        }
        frame.springs.push(SpringText {
            name: "resonator".into(),
            a: self.node,
            b: Some(id),
            k,
            group: "resonator".into(),
        });
        frame.masses.push(MassText {
            name: "resonator".into(),
            node: id,
            m: self.m,
            j: 0.0,
            group: "resonator_mass".into(),
        });
        frame.partial_supports.push((id, held_except(&self.dofs)));
    }

    /// Its natural frequency on a rigid base (Hz), from the static stiffness.
    pub(crate) fn f_hz(&self) -> f64 {
        (self.k / self.m).sqrt() / (2.0 * PI)
    }

    fn effect(&self) -> ExpectedEffect {
        let mut values = vec![("m".to_string(), self.m)];
        values.extend(self.dofs.iter().map(|&d| (["kx", "ky"][axis(d)].to_string(), self.k)));
        values.push(("alpha".into(), self.damp.alpha));
        values.extend(self.damp.mu.map(|mu| ("mu".to_string(), mu)));
        values.push(("f_hz".into(), self.f_hz()));
        ExpectedEffect { family: "resonator".into(), nodes: vec![self.node], elements: vec![], values: by_name(values) }
    }

    fn describe(&self) -> String {
        let dirs: Vec<String> = self.dofs.iter().map(Dof::to_string).collect();
        let damping = match self.damp.mu {
            Some(mu) => format!("non-viscous, mu = 2 pi x {:.0} Hz", mu / (2.0 * PI)),
            None => "viscous".into(),
        };
        format!(
            "resonator at node {} in {} ({:.1} g at {:.1} Hz, {damping})",
            self.node,
            dirs.join(" and "),
            self.m * 1e3,
            self.f_hz()
        )
    }

    /// Its dynamic stiffness seen from its node, per direction:
    /// `-w^2 m k* / (k* - w^2 m)` with the spring's complex stiffness
    /// `k* = k (1 + j w alpha mu / (mu + j w))`.
    pub(crate) fn z(&self, w: f64) -> C64 {
        let jw = C64::new(0.0, w);
        let kernel = self.damp.mu.map_or(C64::new(1.0, 0.0), |mu| mu / (mu + jw));
        let ks = self.k * (1.0 + jw * self.damp.alpha * kernel);
        let inertia = -w * w * self.m;
        inertia * ks / (ks + inertia)
    }
}

/// A shaker at the drive point: its armature `m` moves with the structure
/// in the drive's direction (a stiff stinger, written as a tie), held by
/// its suspension `k` and a dashpot `c` to ground (the electrical damping
/// `(Bl)^2 / R` of a voltage drive, or the suspension's own loss).
#[derive(Clone, Debug)]
pub(crate) struct Shaker {
    pub(crate) drive: DofRef,
    pub(crate) m: f64,
    pub(crate) k: f64,
    pub(crate) c: f64,
}

impl Shaker {
    fn add_to(&self, frame: &mut Frame, extra: &mut Extra) {
        let node = self.drive.node.0;
        let id = extra.node();
        frame.add_coincident(node, id);
        frame.ties.push(([node, id], vec![self.drive.dof]));
        frame.partial_supports.push((id, held_except(&[self.drive.dof])));
        frame.groups.push(undamped("shaker_armature"));
        frame.masses.push(MassText {
            name: "shaker_armature".into(),
            node: id,
            m: self.m,
            j: 0.0,
            group: "shaker_armature".into(),
        });
        // a viscous dashpot c beside the spring k is the group's alpha = c / k
        frame.groups.push(GroupText { name: "shaker_suspension".into(), alpha: self.c / self.k, beta: 0.0, mu: None });
        let mut k = [0.0; 3];
        k[axis(self.drive.dof)] = self.k;
        frame.springs.push(SpringText {
            name: "shaker_suspension".into(),
            a: id,
            b: None,
            k,
            group: "shaker_suspension".into(),
        });
    }

    /// Its dynamic stiffness at the drive point: `k - w^2 m + j w c`.
    pub(crate) fn z(&self, w: f64) -> C64 {
        C64::new(self.k - w * w * self.m, w * self.c)
    }

    fn effect(&self) -> ExpectedEffect {
        let key = ["kx", "ky"][axis(self.drive.dof)];
        ExpectedEffect {
            family: "shaker".into(),
            nodes: vec![self.drive.node.0],
            elements: vec![],
            values: by_name(vec![("m".into(), self.m), (key.into(), self.k), ("c".into(), self.c)]),
        }
    }
}

/// A fin: a steel strip of `elements` beam elements fixed rigidly at
/// `root`, along `direction` (a unit vector across the member).
#[derive(Clone, Debug)]
struct FinSpec {
    root: u32,
    direction: (f64, f64),
    length: f64,
    b: f64,
    h: f64,
    damp: Damp,
}

const FIN_ELEMENTS: u32 = 4;
const FIRST_FIN_ELEMENT: u32 = 101;

impl FinSpec {
    /// Writes the fin: its nodes, section, group and elements.
    fn add_to(&self, frame: &mut Frame, extra: &mut Extra) {
        let (x0, y0) = frame.coordinates(self.root);
        frame.sections.push(("fin".into(), SectionText::Rectangle { b: self.b, h: self.h }));
        frame.groups.push(GroupText { name: "fin".into(), alpha: self.damp.alpha, beta: 0.0, mu: self.damp.mu });
        let mut previous = self.root;
        for i in 1..=FIN_ELEMENTS {
            let id = extra.node();
            let s = self.length * f64::from(i) / f64::from(FIN_ELEMENTS);
            frame.nodes.push((id, round(x0 + s * self.direction.0), round(y0 + s * self.direction.1)));
            frame.beams.push(BeamText {
                id: FIRST_FIN_ELEMENT + i - 1,
                nodes: [previous, id],
                material: "steel".into(),
                section: "fin".into(),
                group: "fin".into(),
            });
            previous = id;
        }
    }

    /// The fin alone, clamped at its root, as a case text.
    fn alone(&self, geo: &Geometry) -> String {
        let mut frame = geo.frame();
        let (x0, y0) = frame.coordinates(self.root);
        frame.nodes = vec![(self.root, x0, y0)];
        frame.beams.clear();
        frame.supports = vec![self.root];
        self.add_to(&mut frame, &mut Extra::new());
        frame.to_toml()
    }
}

// ----------------------------------------------------------------- drawing

/// The channels and lines of a trial: the structure's own, or a compact
/// layout for files to commit (five channels at 1 Hz on the cantilever;
/// the L-frame's eight channels at 1 Hz up to 600 Hz, as the tutorial's).
fn layout(geo: &Geometry, compact: bool) -> (Vec<Channel>, Vec<f64>) {
    if !compact {
        return (geo.channels(), geo.lines());
    }
    match geo.structure {
        Structure::Cantilever => {
            let channels = geo.channels().into_iter().skip(1).step_by(2).collect();
            (channels, (1..=400).map(f64::from).collect())
        }
        Structure::LFrame => (geo.channels(), (2..=600).map(f64::from).collect()),
    }
}

/// The nodes along the structure's chain from the clamp, in order.
fn chain(geo: &Geometry) -> Vec<u32> {
    let mut nodes = geo.members[0].nodes.clone();
    for m in &geo.members[1..] {
        nodes.extend(&m.nodes[1..]);
    }
    nodes
}

/// The direction across the member at a node (for the corner, either).
fn across(rng: &mut ChaCha8Rng, geo: &Geometry, node: u32) -> Dof {
    let along: Vec<bool> = geo.members.iter().filter(|m| m.nodes.contains(&node)).map(|m| m.along_x).collect();
    let along_x = along[rng.random_range(0..along.len())];
    if along_x { Dof::Uy } else { Dof::Ux }
}

/// Natural frequencies (Hz) of a case text inside a band.
fn modes_in(text: &str, lo: f64, hi: f64) -> Result<Vec<f64>, String> {
    let sys = system(text)?;
    let modes = normal_modes(sys.assembly()).map_err(|e| e.to_string())?;
    Ok(modes.frequencies_hz.into_iter().filter(|f| (lo..=hi).contains(f)).collect())
}

/// RMS of `|a - b| / |a|` over one channel's lines.
pub(crate) fn channel_rms(a: &[C64], b: &[C64]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| ((x - y) / x.norm()).norm_sqr()).sum::<f64>() / a.len() as f64).sqrt()
}

/// Whether two models' FRFs differ by less than the noise can show: the
/// misfit the difference adds over `n` values (`n d^2 / noise^2`, a
/// chi-square) stays below one parameter's BIC penalty, `ln n`.
fn indistinguishable(d: f64, n: usize, noise: f64) -> bool {
    n as f64 * d * d <= noise * noise * (n as f64).ln()
}

/// How a draw's modes must differ from the nominal model's in the band.
#[derive(Clone, Copy, Debug)]
enum ModeCheck {
    /// Exactly this many more.
    Extra(usize),
    /// At least this many more.
    AtLeast(usize),
    /// Not checked.
    Any,
}

/// A family's draw before the checks.
struct Made {
    label: String,
    /// The nominal model's text.
    model: String,
    /// `[update]` parameters the nominal case declares.
    declared: Vec<String>,
    truth: String,
    setup: Vec<SetupError>,
    gain: Option<C64>,
    expect: Expect,
    /// Whether the truth's structure differs from the nominal one (and must
    /// be visible).
    structural: bool,
    modes: ModeCheck,
}

/// The nominal case: the model, the measurement of [`DATA_FILE`], and the
/// declared parameters.
fn nominal_case_text(model: &str, channels: &[Channel], declared: &[String]) -> String {
    let mut references: Vec<String> = channels.iter().map(|c| c.reference.to_string()).collect();
    references.dedup();
    let mut responses: Vec<String> = channels.iter().map(|c| c.response.to_string()).collect();
    responses.dedup();
    let quoted = |v: &[String]| v.iter().map(|s| format!("\"{s}\"")).collect::<Vec<_>>().join(", ");
    let mut s = format!(
        "{model}\n[measurement]\nreferences = [{}]\nresponses = [{}]\ndata = \"{DATA_FILE}\"\n",
        quoted(&references),
        quoted(&responses)
    );
    if !declared.is_empty() {
        write!(s, "\n[update]\nparameters = [{}]\nmethod = \"output-error\"\n", quoted(declared)).unwrap();
    }
    s
}

/// A set-up error of `family` on one of `channels`; `None` when the
/// structure has no place for it.
fn draw_setup(rng: &mut ChaCha8Rng, geo: &Geometry, family: LabFamily, channels: &[Channel]) -> Option<SetupError> {
    let n = channels.len();
    let channel = rng.random_range(0..n);
    let r = channels[channel].response;
    Some(match family {
        LabFamily::Polarity => SetupError::Polarity { channel },
        LabFamily::Swap => {
            let mut b = rng.random_range(0..n - 1);
            if b >= channel {
                b += 1;
            }
            SetupError::Swap { a: channel.min(b), b: channel.max(b) }
        }
        LabFamily::Misdirected => {
            let other = if r.dof == Dof::Ux { Dof::Uy } else { Dof::Ux };
            let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            SetupError::Misdirected { channel, measured: DofRef::new(r.node.0, other), sign }
        }
        LabFamily::WrongNode => {
            let chain = chain(geo);
            let p = chain.iter().position(|&x| x == r.node.0).expect("a response on the chain");
            let near: Vec<u32> =
                [p.checked_sub(1), Some(p + 1)].into_iter().flatten().filter_map(|q| chain.get(q).copied()).collect();
            let near: Vec<u32> = near.into_iter().filter(|&x| x != geo.clamp).collect();
            if near.is_empty() {
                return None;
            }
            SetupError::WrongNode { channel, measured: DofRef::new(near[rng.random_range(0..near.len())], r.dof) }
        }
        LabFamily::Calibration => {
            let factor = if rng.random_bool(0.5) { rng.random_range(0.7..0.9) } else { rng.random_range(1.1..1.3) };
            SetupError::Calibration { channel, factor }
        }
        other => panic!("{other:?} is not a set-up error"),
    })
}

/// A hidden structural effect of truths.rs's `family`, checked as
/// truths.rs checks its own (visible on the structure's full layout).
fn draw_structural(rng: &mut ChaCha8Rng, geo: &Geometry, family: Family) -> Option<(String, HiddenEffect, String)> {
    let recipe = truths::draw_recipe(rng, geo, family, &[])?;
    structural_text(geo, &recipe)
}

fn structural_text(geo: &Geometry, recipe: &Recipe) -> Option<(String, HiddenEffect, String)> {
    let text = truths::truth_text(geo, std::slice::from_ref(recipe));
    truths::check(geo.structure, &text, matches!(recipe, Recipe::Joint { .. })).ok()?;
    Some((text, recipe.effect(), recipe.describe()))
}

/// The answer to set-up errors (with effects): a swap is also each
/// channel's sensor at the other's place.
fn setup_expect(setup: &[SetupError], channels: &[Channel], effects: Vec<ExpectedEffect>) -> Expect {
    let findings: Vec<Finding> = setup.iter().filter_map(|e| e.finding(channels)).collect();
    let swapped: Vec<Finding> = findings
        .iter()
        .flat_map(|f| match f {
            Finding::Swapped { a, b } => vec![
                Finding::WrongNode { channel: *a, measured: b.response },
                Finding::WrongNode { channel: *b, measured: a.response },
            ],
            other => vec![other.clone()],
        })
        .collect();
    let main = Expect::Found { findings, effects: effects.clone() };
    if swapped.len() > setup.len() {
        Expect::OneOf(vec![main, Expect::Found { findings: swapped, effects }])
    } else {
        main
    }
}

/// Draws what a family adds, before the checks.
fn make(
    rng: &mut ChaCha8Rng,
    geo: &Geometry,
    family: LabFamily,
    with: Option<Family>,
    channels: &[Channel],
    lines: &[f64],
) -> Option<Made> {
    let nominal = geo.frame().to_toml();
    let (lo, hi) = (lines[0], *lines.last().expect("lines"));
    let n_values = channels.len() * lines.len();
    let free: Vec<u32> = geo.nodes.iter().map(|n| n.0).filter(|&n| n != geo.clamp).collect();
    let title = geo.title.to_lowercase();
    let plain = |label: String, truth: String, expect: Expect, structural: bool| Made {
        label,
        model: nominal.clone(),
        declared: vec![],
        truth,
        setup: vec![],
        gain: None,
        expect,
        structural,
        modes: ModeCheck::Any,
    };
    Some(match family {
        f if f.is_setup() => {
            let e = draw_setup(rng, geo, f, channels)?;
            let (truth, effects, what) = match with {
                None => (nominal.clone(), vec![], String::new()),
                Some(s) => {
                    let (text, hidden, what) = draw_structural(rng, geo, s)?;
                    (text, vec![ExpectedEffect::of_hidden(&hidden)], format!(" + {what}"))
                }
            };
            let expect = setup_expect(std::slice::from_ref(&e), channels, effects);
            Made {
                setup: vec![e.clone()],
                ..plain(format!("{}{what}", e.describe(channels)), truth, expect, with.is_some())
            }
        }
        LabFamily::Resonator => {
            let node = free[rng.random_range(0..free.len())];
            let main = across(rng, geo, node);
            let dofs = if rng.random_bool(0.4) { vec![Dof::Ux, Dof::Uy] } else { vec![main] };
            let f_r = log_uniform(rng, (2.0 * lo).max(3.0), 0.85 * hi);
            let m = log_uniform(rng, 0.01, 0.05) * geo.total_mass();
            let w_r = 2.0 * PI * f_r;
            let zeta = log_uniform(rng, 0.01, 0.15);
            let damp = if rng.random_bool(0.4) {
                Damp { alpha: 2.0 * zeta / w_r, mu: None }
            } else {
                damp_for_loss(2.0 * zeta, Some(w_r * log_uniform(rng, 0.3, 3.0)), f_r)
            };
            let r = Resonator { node, dofs, m, k: m * w_r * w_r, damp };
            resonator_made(geo, &r, channels, lines, n_values)?
        }
        LabFamily::Shaker => {
            let per_volt = rng.random_bool(0.5);
            let s = Shaker {
                drive: geo.reference,
                m: log_uniform(rng, 0.02, 0.2),
                k: log_uniform(rng, 500.0, 1e4),
                // electrical damping of a voltage drive, or the suspension's own loss
                c: if per_volt { log_uniform(rng, 0.5, 20.0) } else { log_uniform(rng, 0.05, 1.0) },
            };
            let gain = per_volt
                .then(|| C64::from_polar(log_uniform(rng, 5.0, 50.0), rng.random_range(-40.0f64..0.0).to_radians()));
            let mut frame = geo.frame();
            s.add_to(&mut frame, &mut Extra::new());
            let how = if per_volt { "per volt" } else { "force from the coil current" };
            let label = format!("shaker at {} ({:.0} g, {:.0} N/m, {:.2} N s/m; {how})", s.drive, s.m * 1e3, s.k, s.c);
            frame.comment = format!("True structure: {title}, with a {label}.");
            let expect = Expect::Found { findings: vec![], effects: vec![s.effect()] };
            Made { gain, ..plain(label, frame.to_toml(), expect, true) }
        }
        LabFamily::SensorMasses => {
            let m = log_uniform(rng, 0.0005, 0.03);
            let r = log_uniform(rng, 0.003, 0.01);
            let j = m * r * r;
            let mut nodes: Vec<u32> = channels.iter().map(|c| c.response.node.0).collect();
            nodes.sort_unstable();
            nodes.dedup();
            let mut frame = geo.frame();
            frame.groups.push(undamped("sensors"));
            for &n in &nodes {
                frame.masses.push(MassText { name: format!("sensor_{n}"), node: n, m, j, group: "sensors".into() });
            }
            let label = format!("{} accelerometers of {:.1} g (j = {j:.2e} kg m^2)", nodes.len(), m * 1e3);
            frame.comment = format!("True structure: {title}, with {label}.");
            let effects = nodes
                .iter()
                .map(|&n| ExpectedEffect {
                    family: "lumped_mass".into(),
                    nodes: vec![n],
                    elements: vec![],
                    values: by_name(vec![("m".into(), m), ("j".into(), j)]),
                })
                .collect();
            plain(label, frame.to_toml(), Expect::Found { findings: vec![], effects }, true)
        }
        LabFamily::DampingForm => {
            let factor = 3.0 * rng.random_range(0.85..1.15);
            damping_form(rng, geo, factor)
        }
        LabFamily::Null => {
            let declared: Vec<String> = match rng.random_range(0..4) {
                0 => vec!["group.structure.alpha".into(), "group.structure.beta".into()],
                1 => vec!["material.steel.E".into()],
                _ => vec![],
            };
            let model = CaseFile::parse(Path::new("nominal.toml"), &nominal).expect("the nominal parses").model;
            let values = by_name(
                declared
                    .iter()
                    .map(|n| (n.clone(), model.get(model.quantity(n).expect("a quantity of the nominal"))))
                    .collect(),
            );
            let label =
                if declared.is_empty() { "null".into() } else { format!("null, declaring {}", declared.join(", ")) };
            Made { declared, ..plain(label, nominal.clone(), Expect::Nothing { declared: values }, false) }
        }
        LabFamily::PhaseDrift => {
            let degrees = rng.random_range(10.0..40.0);
            let seconds = degrees / 360.0 / hi;
            let e = SetupError::Delay { seconds };
            let expect =
                Expect::Inadequate { findings: vec![], effects: vec![], what: vec![Remainder::PhaseDrift { seconds }] };
            Made {
                setup: vec![e.clone()],
                ..plain(
                    format!("{} ({degrees:.0} degrees at {hi} Hz)", e.describe(channels)),
                    nominal.clone(),
                    expect,
                    false,
                )
            }
        }
        LabFamily::SkewMember => {
            let arm = &geo.members[1];
            let degrees = rng.random_range(5.0..15.0) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            let (c, s) = (f64::to_radians(degrees).cos(), f64::to_radians(degrees).sin());
            let mut frame = geo.frame();
            let (x0, y0) = frame.coordinates(arm.nodes[0]);
            for n in frame.nodes.iter_mut().filter(|n| arm.nodes[1..].contains(&n.0)) {
                let (dx, dy) = (n.1 - x0, n.2 - y0);
                (n.1, n.2) = (round(x0 + c * dx - s * dy), round(y0 + s * dx + c * dy));
            }
            let label = format!("the arm turned by {degrees:.1} degrees at node {}", arm.nodes[0]);
            frame.comment = format!("True structure: {title}, with {label}.");
            let what = vec![Remainder::Geometry { elements: arm.elements.clone(), degrees }];
            plain(label, frame.to_toml(), Expect::Inadequate { findings: vec![], effects: vec![], what }, true)
        }
        LabFamily::Fin => {
            let root = free[rng.random_range(0..free.len())];
            let along_x = geo.members.iter().find(|m| m.nodes.contains(&root)).expect("a member").along_x;
            let direction = if along_x { (0.0, 1.0) } else { (1.0, 0.0) };
            let (b, h) = (rng.random_range(0.015..0.03), rng.random_range(0.002..0.004));
            // its first clamped-free mode (1.875^2 / 2 pi) sqrt(EI / rho A) / L^2 in the band
            let f1 = log_uniform(rng, 0.15, 0.8) * hi;
            let reach = 1.875f64.powi(2) / (2.0 * PI) * h * (geo.e / (12.0 * geo.rho)).sqrt();
            let length = (reach / f1).sqrt();
            let damp = damp_for_loss(log_uniform(rng, 0.005, 0.03), None, f1);
            let fin = FinSpec { root, direction, length, b, h, damp };
            let own = modes_in(&fin.alone(geo), lo, hi).ok()?;
            let mut frame = geo.frame();
            fin.add_to(&mut frame, &mut Extra::new());
            let truth = frame.to_toml();
            let coupled = modes_in(&truth, lo, hi).ok()?;
            let nearest = |f: f64| coupled.iter().copied().min_by(|a, b| (a - f).abs().total_cmp(&(b - f).abs()));
            let hz: Vec<f64> = own.iter().filter_map(|&f| nearest(f)).collect();
            let label = format!(
                "fin at node {root} ({:.0} x {:.0} x {:.1} mm, own modes {:?} Hz)",
                length * 1e3,
                b * 1e3,
                h * 1e3,
                own.iter().map(|f| f.round()).collect::<Vec<_>>()
            );
            let truth = truth.replacen(
                &format!("# Nominal model: {title}."),
                &format!("# True structure: {title}, with a {label}."),
                1,
            );
            let what = vec![Remainder::ExtraModes { hz, node: root }];
            // below its own modes the fin moves as a rigid body: its mass on the
            // root's translations and m L^2 / 3 on its rotation, a lumped mass
            // with a rotary inertia, which a tool may rightly add before it stops
            let m = geo.rho * b * h * length;
            let rigid = ExpectedEffect {
                family: "lumped_mass".into(),
                nodes: vec![root],
                elements: vec![],
                values: by_name(vec![("m".into(), m), ("j".into(), m * length * length / 3.0)]),
            };
            let expect = Expect::OneOf(vec![
                Expect::Inadequate { findings: vec![], effects: vec![], what: what.clone() },
                Expect::Inadequate { findings: vec![], effects: vec![rigid], what },
            ]);
            Made { modes: ModeCheck::AtLeast(own.len().max(1)), ..plain(label, truth, expect, true) }
        }
        other => panic!("{other:?} has no draw"),
    })
}

/// A resonator's draw: its truth, and the answer (a resonator in one
/// direction is as right as one in two when the data cannot see the other).
fn resonator_made(geo: &Geometry, r: &Resonator, channels: &[Channel], lines: &[f64], n_values: usize) -> Option<Made> {
    let text = |r: &Resonator| {
        let mut frame = geo.frame();
        r.add_to(&mut frame, &mut Extra::new());
        frame.comment = format!("True structure: {}, with a {}.", geo.title.to_lowercase(), r.describe());
        frame.to_toml()
    };
    let truth = text(r);
    let mut answers = vec![Expect::Found { findings: vec![], effects: vec![r.effect()] }];
    for &d in &r.dofs {
        if r.dofs.len() < 2 {
            break;
        }
        let one = Resonator { dofs: vec![d], ..r.clone() };
        let h = |t: &str| synthesize(&system(t).ok()?, channels, lines).ok();
        let d = relative_rms(&h(&truth)?, &h(&text(&one))?);
        if indistinguishable(d, n_values, NOISE) {
            answers.push(Expect::Found { findings: vec![], effects: vec![one.effect()] });
        }
    }
    let expect = if answers.len() == 1 { answers.pop().expect("one") } else { Expect::OneOf(answers) };
    Some(Made {
        label: r.describe(),
        model: geo.frame().to_toml(),
        declared: vec![],
        truth,
        setup: vec![],
        gain: None,
        expect,
        structural: true,
        modes: ModeCheck::Extra(r.dofs.len()),
    })
}

/// The damping model-form error: the nominal case guesses the structure's
/// damping viscous (its `mu` written far above the band, so that it can be
/// updated) and declares `alpha`, `beta` and `mu`; the truth's damping is
/// exponential with its relaxation near the band's middle and `factor`
/// times the guess's loss factor at the reference frequency.
fn damping_form(rng: &mut ChaCha8Rng, geo: &Geometry, factor: f64) -> Made {
    let w_ref = 2.0 * PI * geo.f_ref;
    let mu_guess = 2.0 * PI * 100.0 * geo.band.1;
    let mu = w_ref * log_uniform(rng, 0.3, 3.0);
    let truth_damp = damp_for_loss(factor * geo.alpha * w_ref, Some(mu), geo.f_ref);
    let (alpha, beta) = (truth_damp.alpha, factor * geo.beta);
    let title = geo.title.to_lowercase();
    let mut model = geo.frame();
    model.groups[0].mu = Some(mu_guess);
    let mut truth = geo.frame();
    truth.groups[0] = GroupText { name: "structure".into(), alpha, beta, mu: Some(mu) };
    let label = format!("damping non-viscous (mu = 2 pi x {:.0} Hz), {factor:.2} x the viscous guess", mu / (2.0 * PI));
    truth.comment = format!("True structure: {title}, with its {label}.");
    let declared: Vec<String> = ["alpha", "beta", "mu"].iter().map(|p| format!("group.structure.{p}")).collect();
    let values = by_name(declared.iter().cloned().zip([alpha, beta, mu]).collect());
    Made {
        label,
        model: model.to_toml(),
        declared,
        truth: truth.to_toml(),
        setup: vec![],
        gain: None,
        expect: Expect::DeclaredOnly { values },
        structural: true,
        modes: ModeCheck::Any,
    }
}

/// The checks every draw passes, or why it is refused.
fn vet(t: &LabTrial, structural: bool, modes: ModeCheck) -> Result<(), String> {
    let truth = system(&t.truth)?;
    let nominal_case = CaseFile::parse(Path::new("lab/nominal.toml"), &t.nominal).map_err(|e| e.to_string())?;
    let nominal = DampedSystem::new(nominal_case.model).map_err(|e| e.to_string())?;
    let lowest = normal_modes(truth.assembly()).map_err(|e| e.to_string())?.frequencies_hz[0];
    if !(lowest >= LOWEST_MODE_HZ) {
        return Err(format!("lowest mode {lowest:.3} Hz"));
    }
    let clean = synthesize(&truth, &t.channels, &t.lines_hz).map_err(|e| e.to_string())?;
    if structural {
        let h = synthesize(&nominal, &t.channels, &t.lines_hz).map_err(|e| e.to_string())?;
        let v = relative_rms(&clean, &h);
        if v < VISIBLE {
            return Err(format!("the structure's change is visible at {v:.3}, below {VISIBLE}"));
        }
    }
    let file = t.clean_file();
    for e in &t.setup {
        let touched = e.channels(t.channels.len());
        let v = (touched.iter().map(|&c| channel_rms(clean.channel(c), file.channel(c)).powi(2)).sum::<f64>()
            / touched.len() as f64)
            .sqrt();
        if v < VISIBLE {
            return Err(format!("{} is visible at {v:.3}, below {VISIBLE}", e.describe(&t.channels)));
        }
    }
    let (lo, hi) = (t.lines_hz[0], *t.lines_hz.last().expect("lines"));
    let extra = modes_in(&t.truth, lo, hi)?.len() as i64 - modes_in(&t.nominal, lo, hi)?.len() as i64;
    match modes {
        ModeCheck::Extra(n) if extra != n as i64 => Err(format!("{extra} more modes in band, not {n}")),
        ModeCheck::AtLeast(n) if extra < n as i64 => Err(format!("{extra} more modes in band, not {n} or more")),
        _ => Ok(()),
    }
}

/// Draws a trial of `family` on a random structure it fits (a set-up error
/// with the structural effect `with`, when given).
pub(crate) fn draw(rng: &mut ChaCha8Rng, family: LabFamily, with: Option<Family>) -> LabTrial {
    let fitting: Vec<Structure> =
        Structure::ALL.into_iter().filter(|&s| family.fits(s) && with.is_none_or(|f| f.fits(s))).collect();
    let structure = fitting[rng.random_range(0..fitting.len())];
    draw_on(rng, structure, family, with, false)
}

/// As [`draw`], on a given structure, at its full layout or the compact one.
pub(crate) fn draw_on(
    rng: &mut ChaCha8Rng,
    structure: Structure,
    family: LabFamily,
    with: Option<Family>,
    compact: bool,
) -> LabTrial {
    assert!(family.fits(structure), "{family:?} does not fit the {structure:?}");
    assert!(with.is_none() || family.is_setup(), "only set-up errors come with a structural effect");
    let geo = Geometry::of(structure);
    let (channels, lines) = layout(&geo, compact);
    let kind = if rng.random_bool(0.5) { FrfKind::Accelerance } else { FrfKind::Receptance };
    let mut redraws = 0;
    loop {
        assert!(redraws < MAX_REDRAWS, "{redraws} draws of {family:?} on the {structure:?} were all refused");
        let Some(made) = make(rng, &geo, family, with, &channels, &lines) else {
            redraws += 1;
            continue;
        };
        let (structural, modes) = (made.structural, made.modes);
        let t = finish(family, with, structure, made, channels.clone(), lines.clone(), kind, redraws);
        match vet(&t, structural, modes) {
            Ok(()) => return t,
            Err(_) => redraws += 1,
        }
    }
}

/// A trial from a draw.
#[allow(clippy::too_many_arguments)]
fn finish(
    family: LabFamily,
    with: Option<Family>,
    structure: Structure,
    made: Made,
    channels: Vec<Channel>,
    lines_hz: Vec<f64>,
    kind: FrfKind,
    redraws: u32,
) -> LabTrial {
    LabTrial {
        label: format!("{} ({structure:?})", made.label),
        family,
        with,
        structure,
        nominal: nominal_case_text(&made.model, &channels, &made.declared),
        truth: made.truth,
        channels,
        lines_hz,
        kind,
        setup: made.setup,
        noise: NOISE,
        gain: made.gain,
        expect: made.expect,
        redraws,
    }
}

/// A study's trials from `seed`: `per` of every family, each on a structure
/// it fits, then `per` of every set-up error with a structural effect of a
/// family drawn from truths.rs's (13 x per + 5 x per trials: 72 at 4).
pub(crate) fn trials(per: usize, seed: u64) -> Vec<LabTrial> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut all = Vec::new();
    for family in LabFamily::ALL {
        all.extend((0..per).map(|_| draw(&mut rng, family, None)));
    }
    for family in LabFamily::ALL.into_iter().filter(|f| f.is_setup()) {
        for _ in 0..per {
            let structural = Family::ALL[rng.random_range(0..Family::ALL.len())];
            all.push(draw(&mut rng, family, Some(structural)));
        }
    }
    all
}

// ------------------------------------------------------- the fixed trials

/// The acceptance trials of issue 32, committed under
/// `crates/rfm-cli/tests/it/cases/lab/<name>/`.
pub(crate) const ACCEPTANCE: [&str; 3] = ["flipped-channel", "tip-resonator", "damping-form"];

/// The noise seed of a fixed trial's committed data.
const FIXED_SEED: u64 = 3200;

/// An acceptance trial, on the cantilever at the compact layout:
/// `flipped-channel` (one channel inverted and a hidden 40 g mass),
/// `tip-resonator` (a tuned-mass damper at the tip, tuned to the second
/// mode by Den Hartog's rules) or `damping-form` (the damping three times
/// the guess and non-viscous, with `alpha`, `beta`, `mu` declared).
pub(crate) fn acceptance(name: &str) -> LabTrial {
    let geo = Geometry::of(Structure::Cantilever);
    let (channels, lines) = layout(&geo, true);
    let n_values = channels.len() * lines.len();
    let mut rng =
        ChaCha8Rng::seed_from_u64(FIXED_SEED + ACCEPTANCE.iter().position(|&n| n == name).expect("a name") as u64);
    let kind = FrfKind::Accelerance;
    let mut redraws = 0;
    loop {
        assert!(redraws < MAX_REDRAWS, "{name}: every draw refused");
        let (family, with, made) = match name {
            "flipped-channel" => {
                let free: Vec<u32> = geo.nodes.iter().map(|n| n.0).filter(|&n| n != geo.clamp).collect();
                let node = free[rng.random_range(0..free.len())];
                let recipe = Recipe::Mass { node, m: 0.04, j: 0.0, own_group: true };
                let e = draw_setup(&mut rng, &geo, LabFamily::Polarity, &channels).expect("a channel");
                let Some((truth, hidden, what)) = structural_text(&geo, &recipe) else {
                    redraws += 1;
                    continue;
                };
                let expect =
                    setup_expect(std::slice::from_ref(&e), &channels, vec![ExpectedEffect::of_hidden(&hidden)]);
                let made = Made {
                    label: format!("{} + {what}", e.describe(&channels)),
                    model: geo.frame().to_toml(),
                    declared: vec![],
                    truth,
                    setup: vec![e],
                    gain: None,
                    expect,
                    structural: true,
                    modes: ModeCheck::Any,
                };
                (LabFamily::Polarity, Some(Family::Mass), made)
            }
            "tip-resonator" => {
                let tip = *chain(&geo).last().expect("a tip");
                let second = modes_in(&geo.frame().to_toml(), 10.0, 100.0).expect("modes")[0];
                // Den Hartog: mass ratio to the tip's modal mass (a quarter of the beam's),
                // tuning f / (1 + ratio) and damping sqrt(3 ratio / (8 (1 + ratio)^3))
                let m = 0.05;
                let ratio = m / (geo.total_mass() / 4.0);
                let f_r = second / (1.0 + ratio);
                let zeta = (3.0 * ratio / (8.0 * (1.0 + ratio).powi(3))).sqrt();
                let w_r = 2.0 * PI * f_r;
                let r = Resonator {
                    node: tip,
                    dofs: vec![Dof::Uy],
                    m,
                    k: m * w_r * w_r,
                    damp: Damp { alpha: 2.0 * zeta / w_r, mu: None },
                };
                (
                    LabFamily::Resonator,
                    None,
                    resonator_made(&geo, &r, &channels, &lines, n_values).expect("a resonator"),
                )
            }
            "damping-form" => (LabFamily::DampingForm, None, damping_form(&mut rng, &geo, 3.0)),
            other => panic!("no acceptance trial `{other}`"),
        };
        let (structural, modes) = (made.structural, made.modes);
        let t = finish(family, with, Structure::Cantilever, made, channels.clone(), lines.clone(), kind, redraws);
        if vet(&t, structural, modes).is_ok() {
            return t;
        }
        redraws += 1;
    }
}

/// Where the committed acceptance cases live.
pub(crate) fn acceptance_dir(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../rfm-cli/tests/it/cases/lab").join(name)
}

/// The walkthrough's frame (issue 32, item 8): the L-frame at the
/// tutorial's layout, measured as accelerance, one channel inverted and a
/// resonator on the arm, across it, between the frame's second and third
/// modes; with the resonator, to write the tutorial's files.
pub(crate) fn walkthrough_frame() -> (LabTrial, Resonator) {
    let geo = Geometry::of(Structure::LFrame);
    let (channels, lines) = layout(&geo, true);
    let n_values = channels.len() * lines.len();
    let mut rng = ChaCha8Rng::seed_from_u64(FIXED_SEED + 8);
    let nominal_modes = modes_in(&geo.frame().to_toml(), lines[0], *lines.last().expect("lines")).expect("modes");
    let mut redraws = 0;
    loop {
        assert!(redraws < MAX_REDRAWS, "the walkthrough's frame: every draw refused");
        let arm = &geo.members[1];
        let node = arm.nodes[rng.random_range(3..arm.nodes.len())];
        let f_r = log_uniform(&mut rng, 1.2 * nominal_modes[1], 0.8 * nominal_modes[2]);
        let m = log_uniform(&mut rng, 0.02, 0.04) * geo.total_mass();
        let w_r = 2.0 * PI * f_r;
        let damp = damp_for_loss(log_uniform(&mut rng, 0.04, 0.1), Some(w_r * log_uniform(&mut rng, 0.5, 2.0)), f_r);
        let r = Resonator { node, dofs: vec![Dof::Uy], m, k: m * w_r * w_r, damp };
        let e = draw_setup(&mut rng, &geo, LabFamily::Polarity, &channels).expect("a channel");
        let made = resonator_made(&geo, &r, &channels, &lines, n_values).expect("a resonator's truth");
        let Expect::Found { effects, .. } = made.expect else { panic!("a resonator in one direction has one answer") };
        let made = Made {
            label: format!("{} + {}", e.describe(&channels), made.label),
            expect: setup_expect(std::slice::from_ref(&e), &channels, effects),
            setup: vec![e],
            ..made
        };
        let (structural, modes) = (made.structural, made.modes);
        let kind = FrfKind::Accelerance;
        let t =
            finish(LabFamily::Resonator, None, Structure::LFrame, made, channels.clone(), lines.clone(), kind, redraws);
        if vet(&t, structural, modes).is_ok() {
            return (t, r);
        }
        redraws += 1;
    }
}

/// The walkthrough's files in `cases/tutorial/`.
pub(crate) fn walkthrough_names() -> FileNames {
    FileNames {
        nominal: "lab-frame.toml".into(),
        data: "lab-frame-measured.csv".into(),
        truth: "lab-frame-truth.toml".into(),
        expect: "lab-frame-expect.txt".into(),
    }
}

/// The L-frame as a reader writes it, by `[[lines]]` (as
/// `cases/tutorial/l-frame.toml`); the tests hold it equal to the
/// generator's node-by-node text.
fn lframe_by_lines(geo: &Geometry) -> String {
    let (b, h) = (geo.b, geo.h);
    format!(
        "[materials]\nsteel = {{ E = {}, rho = {} }}\n\n[sections]\nbar = {{ b = {}, h = {} }}\n\n\
         [groups.structure]        # light material damping\nalpha = {}\nbeta = {}\n\n\
         [[lines]]                 # column: nodes 1..13, elements 1..12\nfrom = [0.0, 0.0]\nto = [0.0, 0.6]\n\
         elements = 12\nfirst_node = 1\nfirst_element = 1\nmaterial = \"steel\"\nsection = \"bar\"\ngroup = \"structure\"\n\n\
         [[lines]]                 # arm: nodes 14..23, elements 13..22\nfrom = 13\nto = [0.5, 0.6]\n\
         elements = 10\nfirst_node = 14\nfirst_element = 13\nmaterial = \"steel\"\nsection = \"bar\"\ngroup = \"structure\"\n\n\
         [[supports]]\nnode = 1\n",
        num(geo.e),
        num(geo.rho),
        num(b),
        num(h),
        num(geo.alpha),
        num(geo.beta)
    )
}

/// The walkthrough's nominal case, docs-ready.
pub(crate) fn walkthrough_nominal(t: &LabTrial) -> String {
    let geo = Geometry::of(Structure::LFrame);
    let names = walkthrough_names();
    let references: Vec<String> = {
        let mut r: Vec<String> = t.channels.iter().map(|c| format!("\"{}\"", c.reference)).collect();
        r.dedup();
        r
    };
    let responses: Vec<String> = t.channels.iter().map(|c| format!("\"{}\"", c.response)).collect();
    format!(
        "# Walkthrough on test-like data: a steel L-frame and its impact test.\n#\n\
         # A 0.6 m column (20 x 20 mm), clamped at its base, carries a 0.5 m arm.\n\
         # The hammer struck the arm's tip ({reference}); eight accelerometers measured\n\
         # accelerances at the arm and the column ({data}). The model\n\
         # below does not match them. Run `rfm fix` on this file and read what it\n\
         # says about the data and about the model; the answer is in\n\
         # {truth} and {expect}.\n\n\
         title = \"Steel L-frame (lab walkthrough)\"\n\n{body}\n\
         [measurement]\nreferences = [{refs}]\nresponses = [{resp}]\ndata = \"{data}\"\n",
        reference = t.channels[0].reference,
        data = names.data,
        truth = names.truth,
        expect = names.expect,
        body = lframe_by_lines(&geo),
        refs = references.join(", "),
        resp = responses.join(", "),
    )
}

/// The walkthrough's truth, docs-ready: the frame by `[[lines]]` and the
/// resonator written out, item by item; the channel's polarity is in the
/// data, not in the structure.
pub(crate) fn walkthrough_truth(t: &LabTrial, r: &Resonator) -> String {
    let geo = Geometry::of(Structure::LFrame);
    let (x, y) = {
        let n = geo.node(r.node);
        (n.1, n.2)
    };
    let id = truths::FIRST_EXTRA_NODE;
    let setup: Vec<String> = t.setup.iter().map(|e| e.describe(&t.channels)).collect();
    let mu = r.damp.mu.map_or(String::new(), |mu| format!("mu = {}                 # rad/s: non-viscous\n", num(mu)));
    format!(
        "# The answer to the lab walkthrough (do not read it before you have tried!).\n#\n\
         # The frame that was measured: the model of lab-frame.toml with a\n\
         # {res}.\n\
         # The test set-up also went wrong: {setup} (in the data,\n\
         # not in this file). Written by crates/rfm-update/tests/it/lab.rs\n\
         # (LAB_CASES_WRITE=1 rewrites it).\n\n\
         title = \"Steel L-frame with a resonator (lab walkthrough truth)\"\n\
         nodes = [[{id}, {x}, {y}]]      # the resonator's mass, at node {node}'s place\n\n{body}\n\
         [groups.resonator]\nalpha = {alpha}\n{mu}\n\
         [groups.resonator_mass]\nalpha = 0.0\nbeta = 0.0\n\n\
         [[springs]]\nname = \"resonator\"\nnodes = [{node}, {id}]\nky = {k}\ngroup = \"resonator\"\n\n\
         [[masses]]\nname = \"resonator\"\nnode = {id}\nm = {m}\ngroup = \"resonator_mass\"\n\n\
         [[supports]]              # the mass moves in y only\nnode = {id}\ndofs = [\"ux\", \"rz\"]\n",
        res = r.describe(),
        setup = setup.join("; "),
        x = num(x),
        y = num(y),
        node = r.node,
        body = lframe_by_lines(&geo),
        alpha = num(r.damp.alpha),
        k = num(r.k),
        m = num(r.m),
    )
}

/// Where the tutorial's files live.
pub(crate) fn tutorial_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases/tutorial")
}

// -------------------------------------------------------------------- tests

/// The tests of the generator itself: each set-up error against the clean
/// FRFs, the shaker and the resonator against the coupling formula applied
/// to the bare structure's FRFs, every family's expectation read back from
/// the parsed truth, and the committed files against the generator.
mod tests {
    use super::*;
    use fe_model::{Model, NodeId};

    fn rng(seed: u64) -> ChaCha8Rng {
        ChaCha8Rng::seed_from_u64(seed)
    }

    /// The first draw (of up to 200) that `pick` accepts.
    fn find(seed: u64, structure: Structure, family: LabFamily, pick: impl Fn(&LabTrial) -> bool) -> LabTrial {
        let mut r = rng(seed);
        (0..200)
            .map(|_| draw_on(&mut r, structure, family, None, false))
            .find(|t| pick(t))
            .unwrap_or_else(|| panic!("no {family:?} draw on the {structure:?} of the kind asked for"))
    }

    /// A case text's receptances on channels and lines.
    fn receptance(text: &str, channels: &[Channel], lines: &[f64]) -> FrfSet {
        let mut unique = channels.to_vec();
        unique.sort();
        unique.dedup();
        synthesize(&system(text).expect("the text assembles"), &unique, lines).expect("FRFs")
    }

    /// One channel of a set by its name.
    fn of(set: &FrfSet, response: DofRef, reference: DofRef) -> &[C64] {
        set.channel(set.find(Channel::new(response, reference)).expect("a synthesised channel"))
    }

    /// The largest `|a - b|` over a channel, relative to the channel's RMS.
    fn worst(a: &[C64], b: &[C64]) -> f64 {
        let rms = (a.iter().map(|v| v.norm_sqr()).sum::<f64>() / a.len() as f64).sqrt();
        a.iter().zip(b).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max) / rms
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
    }

    /// A trial without noise, to compare with synthesised FRFs.
    fn clean(t: &LabTrial) -> LabTrial {
        LabTrial { noise: 0.0, ..t.clone() }
    }

    fn xy(m: &Model, node: u32) -> (f64, f64) {
        let n = m.node(NodeId(node)).expect("the node exists");
        (n.x, n.y)
    }

    /// The first answer's effects (the fullest one).
    fn effects(t: &LabTrial) -> &[ExpectedEffect] {
        match t.expect.answers()[0] {
            Expect::Found { effects, .. } => effects,
            other => panic!("{}: expected effects, got {other:?}", t.label),
        }
    }

    /// Reads a trial's expectation back from its parsed cases: what the
    /// answer names is what the truth holds, and nothing else differs.
    fn check_expect(t: &LabTrial) {
        let label = &t.label;
        let case = t.nominal_case();
        let spec = case.measurement.as_ref().expect("a [measurement]");
        assert_eq!(spec.data.as_deref(), Some(Path::new("lab").join(DATA_FILE).as_path()), "{label}");
        let listed: Vec<Channel> =
            spec.responses.iter().flat_map(|&r| spec.references.iter().map(move |&e| Channel::new(r, e))).collect();
        assert_eq!(listed, t.channels, "{label}: the case lists the file's channels");
        let declared: Vec<String> =
            case.update.as_ref().map_or(vec![], |u| u.parameters.iter().map(|p| p.name.clone()).collect());
        let nominal = &case.model;
        let truth = t.truth_case().model;
        let same_structure = t.nominal.starts_with(&t.truth);
        let answers = t.expect.answers();
        assert!(!answers.is_empty() && t.redraws < MAX_REDRAWS, "{label}");
        assert!(t.gain.is_none() || t.family == LabFamily::Shaker, "{label}: only a shaker's data are per volt");
        // every set-up error is a finding of the first answer, on the channel it touches
        let findings: Vec<Finding> = t.setup.iter().filter_map(|e| e.finding(&t.channels)).collect();
        if t.family.is_setup() {
            assert_eq!(t.setup.len(), 1, "{label}");
            let Expect::Found { findings: named, effects } = answers[0] else { panic!("{label}: {:?}", t.expect) };
            assert_eq!(named, &findings, "{label}");
            match t.with {
                None => assert!(same_structure && effects.is_empty(), "{label}: the structure is the nominal"),
                Some(f) => {
                    assert!(!same_structure && effects.len() == 1, "{label}");
                    let family = ExpectedEffect::of_hidden(&HiddenEffect {
                        family: f,
                        nodes: vec![],
                        elements: vec![],
                        stiffness: vec![],
                        mass: vec![],
                        damping: effects[0].values.iter().filter(|(n, _)| n == "mu").cloned().collect(),
                    })
                    .family;
                    assert_eq!(effects[0].family, family, "{label}");
                }
            }
            for e in &t.setup {
                match *e {
                    SetupError::Polarity { channel } | SetupError::Calibration { channel, .. } => {
                        assert!(channel < t.channels.len())
                    }
                    SetupError::Swap { a, b } => {
                        assert!(a < b && b < t.channels.len(), "{label}");
                        assert_eq!(answers.len(), 2, "{label}: a swap is also two sensors at each other's places");
                    }
                    SetupError::Misdirected { channel, measured, sign } => {
                        let r = t.channels[channel].response;
                        assert!(measured.node == r.node && measured.dof != r.dof && sign.abs() == 1.0, "{label}");
                    }
                    SetupError::WrongNode { channel, measured } => {
                        let r = t.channels[channel].response;
                        let geo = Geometry::of(t.structure);
                        let apart = geo.position(r.node.0).abs_diff(geo.position(measured.node.0));
                        assert!(apart == 1 && measured.dof == r.dof, "{label}: a neighbour's {}", r.dof);
                    }
                    SetupError::Delay { .. } => panic!("{label}: a delay is no set-up family's"),
                }
            }
            if let SetupError::Calibration { factor, .. } = t.setup[0] {
                assert!((0.7..=0.9).contains(&factor) || (1.1..=1.3).contains(&factor), "{label}: {factor}");
            }
            return;
        }
        // the walkthrough's frame adds an inverted channel to a resonator
        let delay_only = t.setup.iter().all(|e| matches!(e, SetupError::Delay { .. }));
        assert!(delay_only || t.family == LabFamily::Resonator, "{label}: {:?}", t.setup);
        let added_node = |name: &str| -> u32 {
            let m = &truth.masses()[truth.mass_index(name).unwrap_or_else(|| panic!("{label}: no mass `{name}`"))];
            m.node.0
        };
        match t.family {
            LabFamily::Resonator => {
                let id = added_node("resonator");
                let mass = &truth.masses()[truth.mass_index("resonator").unwrap()];
                let spring = &truth.springs()[truth.spring_index("resonator").unwrap()];
                let group = &truth.groups()[spring.group];
                assert!(nominal.node(NodeId(id)).is_none(), "{label}: the resonator's node is added");
                assert_eq!(truth.groups()[mass.group].alpha + truth.groups()[mass.group].beta, 0.0, "{label}");
                for (i, answer) in answers.iter().enumerate() {
                    let Expect::Found { findings: named, effects } = answer else { panic!("{label}") };
                    assert!(named == &findings && effects.len() == 1, "{label}");
                    let e = &effects[0];
                    assert_eq!(e.family, "resonator");
                    assert_eq!(xy(&truth, id), xy(nominal, e.nodes[0]), "{label}: at its node's place");
                    assert_eq!(spring.a.0, e.nodes[0], "{label}");
                    assert_eq!(spring.b, Some(NodeId(id)), "{label}");
                    assert!(close(mass.m, e.value("m").unwrap()), "{label}");
                    assert!(close(group.alpha, e.value("alpha").unwrap()) && group.mu == e.value("mu"), "{label}");
                    let mut free = 0;
                    for (key, d) in [("kx", Dof::Ux), ("ky", Dof::Uy)] {
                        match e.value(key) {
                            Some(k) => {
                                assert!(close(spring.k[d], k), "{label}: {key}");
                                free += 1;
                            }
                            // an alternative leaves out a direction the data cannot see
                            None if i > 0 => {}
                            None => assert_eq!(spring.k[d], 0.0, "{label}: {key}"),
                        }
                    }
                    let k = e.value("ky").or(e.value("kx")).unwrap();
                    assert!(close(e.value("f_hz").unwrap(), (k / mass.m).sqrt() / (2.0 * PI)), "{label}");
                    if i == 0 {
                        let held = &truth.supports().iter().find(|s| s.node.0 == id).expect("held DOFs").dofs;
                        assert_eq!(held.len(), 3 - free, "{label}: the resonator's other DOFs are held");
                        let (lo, hi) = (t.lines_hz[0], *t.lines_hz.last().unwrap());
                        assert!((lo..=hi).contains(&e.value("f_hz").unwrap()), "{label}: tuned in the band");
                    }
                }
            }
            LabFamily::Shaker => {
                let e = &effects(t)[0];
                let id = added_node("shaker_armature");
                let drive = t.channels[0].reference;
                assert_eq!(e.nodes, [drive.node.0], "{label}");
                let tie = truth.ties().iter().find(|x| x.nodes.contains(&NodeId(id))).expect("the stinger");
                assert!(tie.nodes.contains(&drive.node) && tie.dofs == [drive.dof], "{label}: tied in the drive's DOF");
                let mass = &truth.masses()[truth.mass_index("shaker_armature").unwrap()];
                assert!(close(mass.m, e.value("m").unwrap()), "{label}");
                let spring = &truth.springs()[truth.spring_index("shaker_suspension").unwrap()];
                assert!(spring.a.0 == id && spring.b.is_none(), "{label}: to ground");
                let key = if drive.dof == Dof::Ux { "kx" } else { "ky" };
                assert!(close(spring.k[drive.dof], e.value(key).unwrap()), "{label}");
                let g = &truth.groups()[spring.group];
                assert!(g.mu.is_none() && close(g.alpha * spring.k[drive.dof], e.value("c").unwrap()), "{label}");
            }
            LabFamily::SensorMasses => {
                let mut nodes: Vec<u32> = t.channels.iter().map(|c| c.response.node.0).collect();
                nodes.sort_unstable();
                nodes.dedup();
                let named: Vec<u32> = effects(t).iter().map(|e| e.nodes[0]).collect();
                assert_eq!(named, nodes, "{label}: a sensor at every response node");
                assert_eq!(truth.masses().len(), nodes.len(), "{label}");
                for (e, m) in effects(t).iter().zip(truth.masses()) {
                    assert_eq!(m.node.0, e.nodes[0]);
                    assert!(close(m.m, e.value("m").unwrap()) && close(m.j[2], e.value("j").unwrap()), "{label}");
                    assert!((0.0005..=0.03).contains(&m.m), "{label}: {} kg", m.m);
                }
            }
            LabFamily::DampingForm => {
                let Expect::DeclaredOnly { values } = answers[0] else { panic!("{label}") };
                let names: Vec<&String> = values.iter().map(|(n, _)| n).collect();
                assert_eq!(names, declared.iter().collect::<Vec<_>>(), "{label}: the case declares what explains it");
                for (name, v) in values {
                    assert!(close(truth.get(truth.quantity(name).unwrap()), *v), "{label}: {name}");
                }
                let (g0, g1) = (&nominal.groups()[0], &truth.groups()[0]);
                assert!(g0.mu.unwrap() > 2.0 * PI * 50.0 * t.lines_hz.last().unwrap(), "{label}: a viscous guess");
                assert!(g1.mu.unwrap() < 2.0 * PI * t.lines_hz.last().unwrap(), "{label}: relaxing in the band");
                assert!((2.5..3.5).contains(&(g1.beta / g0.beta)), "{label}: about three times the guess");
            }
            LabFamily::Null => {
                assert!(same_structure && answers.len() == 1, "{label}");
                let Expect::Nothing { declared: values } = answers[0] else { panic!("{label}") };
                assert_eq!(values.iter().map(|(n, _)| n).collect::<Vec<_>>(), declared.iter().collect::<Vec<_>>());
                for (name, v) in values {
                    assert_eq!(truth.get(truth.quantity(name).unwrap()), *v, "{label}: at the true value");
                }
            }
            LabFamily::PhaseDrift => {
                let [SetupError::Delay { seconds }] = t.setup[..] else { panic!("{label}") };
                let Expect::Inadequate { what, .. } = answers[0] else { panic!("{label}") };
                assert_eq!(what, &[Remainder::PhaseDrift { seconds }], "{label}");
                assert!(same_structure, "{label}");
            }
            LabFamily::SkewMember => {
                let Expect::Inadequate { what, .. } = answers[0] else { panic!("{label}") };
                let [Remainder::Geometry { elements, degrees }] = &what[..] else { panic!("{label}") };
                let (a, b) = (xy(&truth, 13), xy(&truth, 23));
                let turned = (b.1 - a.1).atan2(b.0 - a.0).to_degrees();
                assert!((turned - degrees).abs() < 1e-6, "{label}: the arm at {turned} degrees");
                assert_eq!(elements, &(13..=22).collect::<Vec<_>>(), "{label}");
                assert_eq!(xy(&truth, 12), xy(nominal, 12), "{label}: the column stays");
            }
            LabFamily::Fin => {
                let Expect::Inadequate { what, .. } = answers[0] else { panic!("{label}") };
                let [Remainder::ExtraModes { hz, node }] = &what[..] else { panic!("{label}") };
                let fin: Vec<_> = truth.beams().iter().filter(|b| b.id.0 >= FIRST_FIN_ELEMENT).collect();
                assert_eq!(fin.len() as u32, FIN_ELEMENTS, "{label}");
                assert!(fin[0].nodes.contains(&NodeId(*node)), "{label}: the fin's root is its node");
                let (lo, hi) = (t.lines_hz[0], *t.lines_hz.last().unwrap());
                assert!(!hz.is_empty() && hz.iter().all(|f| (lo..=hi).contains(f)), "{label}: {hz:?}");
                // the rigid fin's mass is the mass of its elements in the parsed truth
                let Expect::Inadequate { effects, what: same, .. } = answers[1] else { panic!("{label}") };
                assert_eq!(same, what, "{label}");
                let mass: f64 = fin
                    .iter()
                    .map(|b| {
                        let (length, _, _) = truth.beam_geometry(truth.beam_index(b.id).unwrap());
                        truth.materials()[b.material].rho * truth.sections()[b.section].area * length
                    })
                    .sum();
                assert!((effects[0].value("m").unwrap() / mass - 1.0).abs() < 1e-9, "{label}: the fin's mass");
                assert_eq!(effects[0].nodes, [*node], "{label}");
            }
            other => panic!("{other:?} is checked above"),
        }
    }

    /// Draws `per` trials of every family on both structures where it fits,
    /// and checks each: its draw passed the checks (drawn again here), its
    /// expectation reads back from the parsed truth, and the redraws stay few.
    #[test]
    fn every_family_draws_on_both_structures_and_its_answer_is_its_truth() {
        let per = 3;
        let mut r = rng(32);
        let mut count = 0;
        for family in LabFamily::ALL {
            for structure in Structure::ALL.into_iter().filter(|&s| family.fits(s)) {
                let mut redraws = 0;
                for _ in 0..per {
                    let t = draw_on(&mut r, structure, family, None, false);
                    assert_eq!((t.family, t.structure), (family, structure));
                    check_expect(&t);
                    redraws += t.redraws;
                    count += 1;
                    println!("{:<14} {} redraws {}", format!("{family:?}"), t.label, t.redraws);
                }
                // a family whose ranges give mostly invisible draws is drawn wrong
                assert!(redraws as usize <= 4 * per, "{family:?} on the {structure:?}: {redraws} redraws");
            }
        }
        assert_eq!(count, per * (2 * LabFamily::ALL.len() - 2));
    }

    /// A set-up error comes with a hidden effect of each of truths.rs's
    /// families; both stand above the noise.
    #[test]
    fn set_up_errors_combine_with_every_structural_family() {
        let mut r = rng(33);
        let setups = [LabFamily::Polarity, LabFamily::Swap, LabFamily::WrongNode, LabFamily::Calibration];
        for (k, family) in Family::ALL.into_iter().enumerate() {
            let t = draw(&mut r, setups[k % setups.len()], Some(family));
            check_expect(&t);
            assert_eq!(t.with, Some(family));
            println!("{}", t.label);
        }
        let t = draw(&mut r, LabFamily::Misdirected, Some(Family::Joint));
        assert_eq!(t.structure, Structure::LFrame);
        check_expect(&t);
    }

    /// The independent roads: the truth's FRFs synthesised directly, and
    /// the file's channels.
    fn file_and_truth(t: &LabTrial) -> (FrfSet, FrfSet) {
        (clean(t).measure(0).to_receptance(), receptance(&t.truth, &t.channels, &t.lines_hz))
    }

    #[test]
    fn a_flipped_channel_is_exactly_the_negated_clean_channel() {
        for s in Structure::ALL {
            let t = find(34, s, LabFamily::Polarity, |_| true);
            let [SetupError::Polarity { channel }] = t.setup[..] else { panic!() };
            let (file, h) = file_and_truth(&t);
            for c in 0..t.channels.len() {
                let want: Vec<C64> = of(&h, t.channels[c].response, t.channels[c].reference).to_vec();
                let want: Vec<C64> = if c == channel { want.iter().map(|v| -v).collect() } else { want };
                assert!(worst(&want, file.channel(c)) < 1e-12, "{}: channel {c}", t.label);
            }
            assert!(
                channel_rms(of(&h, t.channels[channel].response, t.channels[channel].reference), file.channel(channel))
                    > 1.99
            );
        }
    }

    #[test]
    fn a_swap_exchanges_exactly_two_channels() {
        let t = find(35, Structure::LFrame, LabFamily::Swap, |_| true);
        let [SetupError::Swap { a, b }] = t.setup[..] else { panic!() };
        let (file, h) = file_and_truth(&t);
        for c in 0..t.channels.len() {
            let from = if c == a {
                b
            } else if c == b {
                a
            } else {
                c
            };
            let ch = t.channels[from];
            assert!(worst(of(&h, ch.response, ch.reference), file.channel(c)) < 1e-12, "{}: channel {c}", t.label);
        }
    }

    /// A sensor at a neighbouring node reads the neighbour's FRF, and one
    /// turned to the other direction that direction's, both synthesised
    /// alone as a channel of their own.
    #[test]
    fn a_misplaced_or_misdirected_sensor_reads_the_frf_where_it_is() {
        for (family, s) in [
            (LabFamily::WrongNode, Structure::Cantilever),
            (LabFamily::WrongNode, Structure::LFrame),
            (LabFamily::Misdirected, Structure::LFrame),
        ] {
            let t = find(36, s, family, |_| true);
            let (channel, measured, sign) = match t.setup[0] {
                SetupError::WrongNode { channel, measured } => (channel, measured, 1.0),
                SetupError::Misdirected { channel, measured, sign } => (channel, measured, sign),
                _ => panic!(),
            };
            let file = clean(&t).measure(0).to_receptance();
            let reference = t.channels[channel].reference;
            let alone = receptance(&t.truth, &[Channel::new(measured, reference)], &t.lines_hz);
            let want: Vec<C64> = alone.channel(0).iter().map(|v| sign * v).collect();
            assert!(worst(&want, file.channel(channel)) < 1e-12, "{}", t.label);
            let h = receptance(&t.truth, &t.channels, &t.lines_hz);
            for c in (0..t.channels.len()).filter(|&c| c != channel) {
                assert!(worst(of(&h, t.channels[c].response, reference), file.channel(c)) < 1e-12, "{}", t.label);
            }
        }
    }

    /// The relative RMS misfit to a truth's clean FRFs left by the best
    /// single translational resonator added to the model of `base` (a case
    /// text): at a node within five of `around` along the chain, across or
    /// along the member, from a grid of masses, tunings near `near_hz` and
    /// losses, refined by a pattern search; each candidate by the coupling
    /// formula from `base`'s FRFs. With the candidate in words.
    fn best_resonator(t: &LabTrial, base: &str, around: u32, near_hz: f64) -> (f64, String) {
        let geo = Geometry::of(t.structure);
        let d = t.channels[0].reference;
        let target = receptance(&t.truth, &t.channels, &t.lines_hz);
        let chain = chain(&geo);
        let p = chain.iter().position(|&n| n == around).unwrap();
        let nodes: Vec<u32> =
            chain[p.saturating_sub(5)..(p + 6).min(chain.len())].iter().copied().filter(|&n| n != geo.clamp).collect();
        let mut pairs = t.channels.clone();
        for &n in &nodes {
            for dof in [Dof::Ux, Dof::Uy] {
                let a = DofRef::new(n, dof);
                pairs.push(Channel::new(a, a));
                pairs.push(Channel::new(a, d));
                pairs.extend(t.channels.iter().map(|c| Channel::new(c.response, a)));
            }
        }
        let bare = receptance(base, &pairs, &t.lines_hz);
        let w: Vec<f64> = t.lines_hz.iter().map(|f| 2.0 * PI * f).collect();
        let misfit = |a: DofRef, m: f64, f: f64, zeta: f64| -> f64 {
            let wr = 2.0 * PI * f;
            let damp = Damp { alpha: 2.0 * zeta / wr, mu: None };
            let r = Resonator { node: a.node.0, dofs: vec![a.dof], m, k: m * wr * wr, damp };
            let (haa, had) = (of(&bare, a, a), of(&bare, a, d));
            let mut sum = 0.0;
            for ch in &t.channels {
                let (hrd, hra) = (of(&bare, ch.response, d), of(&bare, ch.response, a));
                let want = of(&target, ch.response, d);
                for k in 0..w.len() {
                    let z = r.z(w[k]);
                    let v = hrd[k] - hra[k] * z / (1.0 + z * haa[k]) * had[k];
                    sum += ((v - want[k]) / want[k].norm()).norm_sqr();
                }
            }
            (sum / (w.len() * t.channels.len()) as f64).sqrt()
        };
        let mut best = (f64::INFINITY, DofRef::new(nodes[0], Dof::Uy), 0.0, 0.0, 0.0);
        for &n in &nodes {
            for dof in [Dof::Ux, Dof::Uy] {
                let a = DofRef::new(n, dof);
                for i in 0..9 {
                    let f = near_hz * 0.7f64.powf(1.0 - f64::from(i) / 6.0);
                    for j in 0..10 {
                        let m = 1e-3 * 300f64.powf(f64::from(j) / 9.0);
                        for zeta in [0.003, 0.01, 0.03, 0.1] {
                            let e = misfit(a, m, f, zeta);
                            if e < best.0 {
                                best = (e, a, m, f, zeta);
                            }
                        }
                    }
                }
            }
        }
        // a pattern search on the logarithms of m, f and zeta
        let (mut e, a, mut m, mut f, mut zeta) = best;
        let mut step: f64 = 0.3;
        while step > 1e-3 {
            let mut moved = false;
            for (dm, df, dz) in [
                (1.0, 0.0, 0.0),
                (-1.0, 0.0, 0.0),
                (0.0, 1.0, 0.0),
                (0.0, -1.0, 0.0),
                (0.0, 0.0, 1.0),
                (0.0, 0.0, -1.0),
            ] {
                let (m2, f2, z2) = (m * (step * dm).exp(), f * (0.1 * step * df).exp(), zeta * (step * dz).exp());
                let e2 = misfit(a, m2, f2, z2);
                if e2 < e {
                    (e, m, f, zeta, moved) = (e2, m2, f2, z2, true);
                }
            }
            if !moved {
                step /= 2.0;
            }
        }
        (e, format!("{:.1} g at {a} tuned to {f:.1} Hz, zeta {zeta:.4}", m * 1e3))
    }

    /// The fin is outside the resonator family: with its rigid mass added
    /// (the alternative answer's lumped mass), the best single resonator
    /// near it leaves several times the noise; the same search matches a
    /// resonator's own truth to well within the noise (the search works).
    #[test]
    fn a_fin_is_no_single_resonator() {
        for s in Structure::ALL {
            let viscous =
                |t: &LabTrial| matches!(t.expect, Expect::Found { .. }) && effects(t)[0].value("mu").is_none();
            let t = find(45, s, LabFamily::Resonator, viscous);
            let e = &effects(&t)[0];
            let (misfit, what) = best_resonator(&t, &t.nominal, e.nodes[0], e.value("f_hz").unwrap());
            println!("{}: best resonator {what}: {:.3} x noise", t.label, misfit / NOISE);
            assert!(misfit < 0.3 * NOISE, "{}: the search finds the resonator", t.label);
        }
        let mut r = rng(46);
        for s in Structure::ALL {
            for _ in 0..2 {
                let t = draw_on(&mut r, s, LabFamily::Fin, None, false);
                let Expect::Inadequate { effects, what, .. } = t.expect.answers()[1] else { panic!() };
                let [Remainder::ExtraModes { hz, node }] = &what[..] else { panic!() };
                let (m, j) = (effects[0].value("m").unwrap(), effects[0].value("j").unwrap());
                let mut frame = Geometry::of(s).frame();
                frame.groups.push(undamped("rigid_fin"));
                frame.masses.push(MassText { name: "rigid_fin".into(), node: *node, m, j, group: "rigid_fin".into() });
                let base = frame.to_toml();
                let with_mass = relative_rms(
                    &receptance(&t.truth, &t.channels, &t.lines_hz),
                    &receptance(&base, &t.channels, &t.lines_hz),
                );
                let (misfit, what) = best_resonator(&t, &base, *node, hz[0]);
                println!(
                    "{}: {:.1} x noise with its rigid mass; best resonator then {what}: {:.1} x noise",
                    t.label,
                    with_mass / NOISE,
                    misfit / NOISE
                );
                assert!(
                    misfit > 3.0 * NOISE,
                    "{}: a resonator explains the fin to {:.2} x noise",
                    t.label,
                    misfit / NOISE
                );
            }
        }
    }

    /// A calibration scales one channel by its factor, a delay turns every
    /// channel by `-w tau`, and data per volt are the gain times the FRFs.
    #[test]
    fn a_calibration_a_delay_and_a_gain_act_as_drawn() {
        let t = find(37, Structure::Cantilever, LabFamily::Calibration, |_| true);
        let [SetupError::Calibration { channel, factor }] = t.setup[..] else { panic!() };
        let (file, h) = file_and_truth(&t);
        let ch = t.channels[channel];
        let want: Vec<C64> = of(&h, ch.response, ch.reference).iter().map(|v| factor * v).collect();
        assert!(worst(&want, file.channel(channel)) < 1e-12);

        let t = find(37, Structure::LFrame, LabFamily::PhaseDrift, |_| true);
        let [SetupError::Delay { seconds }] = t.setup[..] else { panic!() };
        let (file, h) = file_and_truth(&t);
        for (c, ch) in t.channels.iter().enumerate() {
            for (k, &f) in t.lines_hz.iter().enumerate() {
                let turn = file.get(c, k) / of(&h, ch.response, ch.reference)[k];
                assert!((turn - C64::from_polar(1.0, -2.0 * PI * f * seconds)).norm() < 1e-12, "{f} Hz");
            }
        }
        let top = 2.0 * PI * t.lines_hz.last().unwrap() * seconds;
        assert!((10f64.to_radians()..40f64.to_radians()).contains(&top), "{} degrees at the top", top.to_degrees());
        // no gain absorbs it: after each channel's best complex gain in the
        // log misfit (the mean of ln(file / truth)), the drift's spread about
        // its mean is left, top / sqrt(12) over an even band
        let mut left = 0.0;
        for (c, ch) in t.channels.iter().enumerate() {
            let logs: Vec<C64> =
                (0..t.lines_hz.len()).map(|k| (file.get(c, k) / of(&h, ch.response, ch.reference)[k]).ln()).collect();
            let mean = logs.iter().sum::<C64>() / logs.len() as f64;
            left += logs.iter().map(|l| (l - mean).norm_sqr()).sum::<f64>();
        }
        let left = (left / (t.channels.len() * t.lines_hz.len()) as f64).sqrt();
        assert!((left / (top / 12f64.sqrt()) - 1.0).abs() < 0.01 && left > 3.0 * NOISE, "{left} left after the gains");

        let t = find(37, Structure::Cantilever, LabFamily::Shaker, |t| t.gain.is_some());
        let g = t.gain.unwrap();
        let per_volt = clean(&t).measure(0);
        let force = clean(&t).clean_file().converted(t.kind);
        assert_eq!(per_volt.kind(), t.kind);
        for c in 0..t.channels.len() {
            let want: Vec<C64> = force.channel(c).iter().map(|v| g * v).collect();
            assert!(worst(&want, per_volt.channel(c)) < 1e-14);
        }
        assert!((5.0..=50.0).contains(&g.norm()) && (-40.0..=0.0).contains(&g.arg().to_degrees()));
    }

    /// The shaker's truth, synthesised from its case text, against the
    /// coupling formula with one reference at the drive point:
    /// `H'_rd = H_rd / (1 + z H_dd)`, `z = k - w^2 m + j w c` from the
    /// expectation's values and `H` the bare (nominal) structure's.
    #[test]
    fn the_shaker_truth_is_the_bare_structure_coupled_to_the_shaker() {
        for s in Structure::ALL {
            let t = find(38, s, LabFamily::Shaker, |_| true);
            let e = &effects(&t)[0];
            let drive = t.channels[0].reference;
            let key = if drive.dof == Dof::Ux { "kx" } else { "ky" };
            let shaker = Shaker { drive, m: e.value("m").unwrap(), k: e.value(key).unwrap(), c: e.value("c").unwrap() };
            let bare = receptance(&t.nominal, &t.channels, &t.lines_hz);
            let coupled = receptance(&t.truth, &t.channels, &t.lines_hz);
            let h_dd = of(&bare, drive, drive);
            for ch in &t.channels {
                let want: Vec<C64> = t
                    .lines_hz
                    .iter()
                    .enumerate()
                    .map(|(k, &f)| of(&bare, ch.response, drive)[k] / (1.0 + shaker.z(2.0 * PI * f) * h_dd[k]))
                    .collect();
                let got = of(&coupled, ch.response, drive);
                // round-off of the formula's cancellation near a lightly damped peak
                assert!(worst(&want, got) < 1e-6, "{}: {ch} off by {:.2e}", t.label, worst(&want, got));
                assert!(worst(of(&bare, ch.response, drive), got) > 0.05, "{}: the shaker changes {ch}", t.label);
            }
        }
    }

    /// A resonator's truth against the structure coupled to its single-DOF
    /// dynamic stiffness `z` at its node's DOFs `N` (one or two):
    /// `H' = H - H[:, N] z (I + z H[N, N])^-1 H[N, d]`, from the bare
    /// structure's FRFs and the expectation's values.
    #[test]
    fn a_resonator_truth_is_the_structure_coupled_to_its_sdof() {
        let cases = [
            find(39, Structure::Cantilever, LabFamily::Resonator, |t| effects(t)[0].value("kx").is_none()),
            find(39, Structure::LFrame, LabFamily::Resonator, |t| effects(t)[0].value("kx").is_some()),
            find(39, Structure::LFrame, LabFamily::Resonator, |t| effects(t)[0].value("mu").is_some()),
        ];
        for t in &cases {
            let e = &effects(t)[0];
            let dofs: Vec<Dof> = [("kx", Dof::Ux), ("ky", Dof::Uy)]
                .into_iter()
                .filter(|(k, _)| e.value(k).is_some())
                .map(|x| x.1)
                .collect();
            let k = e.value("ky").or(e.value("kx")).unwrap();
            let mu = e.value("mu");
            let r = Resonator {
                node: e.nodes[0],
                dofs: dofs.clone(),
                m: e.value("m").unwrap(),
                k,
                damp: Damp { alpha: e.value("alpha").unwrap(), mu },
            };
            let d = t.channels[0].reference;
            let at: Vec<DofRef> = dofs.iter().map(|&x| DofRef::new(r.node, x)).collect();
            let mut pairs: Vec<Channel> = t.channels.clone();
            for &a in &at {
                pairs.push(Channel::new(a, d));
                for &b in &at {
                    pairs.push(Channel::new(a, b));
                }
                for ch in &t.channels {
                    pairs.push(Channel::new(ch.response, a));
                }
            }
            let bare = receptance(&t.nominal, &pairs, &t.lines_hz);
            let coupled = receptance(&t.truth, &t.channels, &t.lines_hz);
            for ch in &t.channels {
                let want: Vec<C64> = t
                    .lines_hz
                    .iter()
                    .enumerate()
                    .map(|(k, &f)| {
                        let z = r.z(2.0 * PI * f);
                        let h = |a: DofRef, b: DofRef| of(&bare, a, b)[k];
                        // B = z (I + z H_NN)^-1, one or two DOFs
                        let b: Vec<Vec<C64>> = if at.len() == 1 {
                            vec![vec![z / (1.0 + z * h(at[0], at[0]))]]
                        } else {
                            let (p, q, s, u) = (
                                1.0 + z * h(at[0], at[0]),
                                z * h(at[0], at[1]),
                                z * h(at[1], at[0]),
                                1.0 + z * h(at[1], at[1]),
                            );
                            let det = p * u - q * s;
                            vec![vec![z * u / det, -z * q / det], vec![-z * s / det, z * p / det]]
                        };
                        let mut v = h(ch.response, d);
                        for i in 0..at.len() {
                            for j in 0..at.len() {
                                v -= h(ch.response, at[i]) * b[i][j] * h(at[j], d);
                            }
                        }
                        v
                    })
                    .collect();
                let got = of(&coupled, ch.response, d);
                // round-off of the formula's cancellation near a lightly damped peak
                assert!(worst(&want, got) < 1e-6, "{}: {ch} off by {:.2e}", t.label, worst(&want, got));
            }
            // one more mode in band per direction
            let (lo, hi) = (t.lines_hz[0], *t.lines_hz.last().unwrap());
            let extra = modes_in(&t.truth, lo, hi).unwrap().len() - modes_in(&t.nominal, lo, hi).unwrap().len();
            assert_eq!(extra, dofs.len(), "{}", t.label);
        }
    }

    #[test]
    fn draws_are_reproducible_from_the_seed() {
        let run = |seed| {
            let mut r = rng(seed);
            let mut trials: Vec<LabTrial> =
                [LabFamily::Polarity, LabFamily::Resonator, LabFamily::Shaker, LabFamily::Fin]
                    .into_iter()
                    .map(|f| draw(&mut r, f, None))
                    .collect();
            trials.push(draw(&mut r, LabFamily::Swap, Some(Family::Mass)));
            let data: Vec<Vec<C64>> = trials.iter().map(|t| t.measure(5).values().to_vec()).collect();
            (trials, data)
        };
        let (a, b) = (run(40), run(40));
        assert_eq!(a.0, b.0);
        assert_eq!(a.1, b.1);
        assert_ne!(run(41).0[0].label, a.0[0].label);
        assert_eq!(acceptance("tip-resonator"), acceptance("tip-resonator"));
        assert_eq!(walkthrough_frame().0, walkthrough_frame().0);
    }

    /// Every answer's text reads back as the same answer.
    #[test]
    fn expectations_round_trip_through_their_text() {
        let mut r = rng(42);
        let mut verdicts = std::collections::BTreeSet::new();
        let mut trials: Vec<LabTrial> = LabFamily::ALL.into_iter().map(|f| draw(&mut r, f, None)).collect();
        trials.push(draw(&mut r, LabFamily::Calibration, Some(Family::Support)));
        for t in &trials {
            let text = t.expect_text(7);
            let back = Expect::from_toml(&text).unwrap_or_else(|e| panic!("{}: {e}\n{text}", t.label));
            assert_eq!(back, t.expect, "{}", t.label);
            for a in t.expect.answers() {
                verdicts.insert(a.to_toml().lines().nth(1).unwrap().to_string());
            }
        }
        assert_eq!(verdicts.len(), 4, "every verdict is written: {verdicts:?}");
        assert!(Expect::from_toml("[[answer]]\nverdict = \"maybe\"\n").unwrap_err().contains("maybe"));
    }

    /// A dumped trial is a case rfm reads: the study loads it, and its data
    /// are the trial's measurement (to the eight digits written).
    #[test]
    fn a_dumped_trial_is_a_case_rfm_reads() {
        let mut r = rng(43);
        let tmp = tempfile::tempdir().unwrap();
        let per_volt = find(43, Structure::LFrame, LabFamily::Shaker, |t| t.gain.is_some());
        for (k, t) in [draw(&mut r, LabFamily::DampingForm, None), per_volt].iter().enumerate() {
            let dir = tmp.path().join(format!("trial-{k}"));
            t.dump(&dir, 11).unwrap();
            let study = rfm_update::Study::load(&dir.join("nominal.toml")).unwrap();
            let want = t.measure(11).to_receptance();
            let got = study.measured();
            assert_eq!(got.channels(), want.channels(), "{}", t.label);
            assert_eq!(got.frequencies_hz(), want.frequencies_hz(), "{}", t.label);
            for c in 0..want.channels().len() {
                assert!(worst(want.channel(c), got.channel(c)) < 1e-6, "{}", t.label);
            }
            assert_eq!(study.case().update.is_some(), t.family == LabFamily::DampingForm);
            let text = std::fs::read_to_string(dir.join("expect.txt")).unwrap();
            assert_eq!(Expect::from_toml(&text).unwrap(), t.expect);
            assert_eq!(std::fs::read_to_string(dir.join("truth.toml")).unwrap(), t.truth);
        }
    }

    /// A trial dumped with a universal file reads as its CSV does, and the
    /// polarity finding's correction, `sign = -1` in the case's map for the
    /// channel's test point, restores the channel; on the driving point the
    /// same entry would also turn the reference, and every channel with it.
    #[test]
    fn a_universal_file_reads_as_the_csv_and_its_map_corrects_the_polarity() {
        let t = find(
            48,
            Structure::LFrame,
            LabFamily::Polarity,
            |t| matches!(t.setup[..], [SetupError::Polarity { channel }] if t.channels[channel].response != t.channels[channel].reference),
        );
        let [SetupError::Polarity { channel }] = t.setup[..] else { panic!() };
        let tmp = tempfile::tempdir().unwrap();
        let names = FileNames { data: "measured.uff".into(), ..FileNames::default() };
        t.dump_as(tmp.path(), &names, 12).unwrap();
        let load = |text: &str| {
            std::fs::write(tmp.path().join("nominal.toml"), text).unwrap();
            rfm_update::Study::load(&tmp.path().join("nominal.toml")).unwrap().measured().clone()
        };
        let as_written = load(&names.nominal_text(&t));
        let want = t.measure(12).to_receptance();
        for c in 0..want.channels().len() {
            assert!(worst(want.channel(c), as_written.channel(c)) < 1e-9, "{}", want.channels()[c]);
        }
        let r = t.channels[channel].response;
        let axis = if r.dof == Dof::Ux { "X" } else { "Y" };
        let entry = format!("\n[[measurement.map]]\ntest = \"{}:+{axis}\"\nmodel = \"{r}\"\nsign = -1\n", r.node.0);
        let corrected = load(&format!("{}{entry}", names.nominal_text(&t)));
        let truth = receptance(&t.truth, &t.channels, &t.lines_hz);
        for (c, ch) in t.channels.iter().enumerate() {
            let flipped: Vec<C64> = as_written.channel(c).iter().map(|v| -v).collect();
            let expected = if c == channel { flipped } else { as_written.channel(c).to_vec() };
            assert!(worst(&expected, corrected.channel(c)) < 1e-12, "{ch}");
            // the corrected data are the truth's with the trial's 1 % noise
            let error = channel_rms(of(&truth, ch.response, ch.reference), corrected.channel(c));
            assert!(error < 2.0 * NOISE, "{ch}: {error} from the truth");
        }
    }

    /// Whether two texts agree but for the last digits of their numbers
    /// (another platform's libm may round a drawn value differently).
    fn same_text(a: &str, b: &str) -> bool {
        let split = |s: &str| -> Vec<String> {
            s.split(|c: char| c.is_whitespace() || "[],={}\"()".contains(c))
                .filter(|x| !x.is_empty())
                .map(String::from)
                .collect()
        };
        let (x, y) = (split(a), split(b));
        x.len() == y.len()
            && x.iter().zip(&y).all(|(p, q)| match (p.parse::<f64>(), q.parse::<f64>()) {
                (Ok(u), Ok(v)) => (u - v).abs() <= 1e-9 * u.abs().max(v.abs()),
                _ => p == q,
            })
    }

    /// Checks (or with `LAB_CASES_WRITE` set, first writes) a trial's
    /// committed files: the texts, the data to their digits, the case loads
    /// as rfm loads it.
    fn check_committed(t: &LabTrial, dir: &Path, names: &FileNames, nominal: &str, truth: &str) {
        if std::env::var_os("LAB_CASES_WRITE").is_some() {
            t.dump_as(dir, names, FIXED_SEED).unwrap();
            std::fs::write(dir.join(&names.nominal), nominal).unwrap();
            std::fs::write(dir.join(&names.truth), truth).unwrap();
        }
        let read = |name: &str| {
            std::fs::read_to_string(dir.join(name))
                .unwrap_or_else(|e| panic!("{}: {e} (LAB_CASES_WRITE=1 writes it)", dir.join(name).display()))
        };
        let stale = |name: &str| {
            format!("{} is not what the generator writes (LAB_CASES_WRITE=1 rewrites it)", dir.join(name).display())
        };
        assert!(same_text(&read(&names.nominal), nominal), "{}", stale(&names.nominal));
        assert!(same_text(&read(&names.truth), truth), "{}", stale(&names.truth));
        assert!(same_text(&read(&names.expect), &t.expect_text(FIXED_SEED)), "{}", stale(&names.expect));
        let committed = frf::io::csv::parse_csv(&dir.join(&names.data), &read(&names.data)).unwrap();
        let fresh = t.measure(FIXED_SEED);
        assert_eq!(
            (committed.kind(), committed.channels()),
            (fresh.kind(), fresh.channels()),
            "{}",
            stale(&names.data)
        );
        assert_eq!(committed.frequencies_hz(), fresh.frequencies_hz(), "{}", stale(&names.data));
        for c in 0..fresh.channels().len() {
            assert!(worst(fresh.channel(c), committed.channel(c)) < 1e-6, "{}", stale(&names.data));
        }
        let study = rfm_update::Study::load(&dir.join(&names.nominal)).unwrap();
        assert_eq!(study.measured().channels(), t.channels.as_slice());
        assert_eq!(Expect::from_toml(&read(&names.expect)).unwrap(), t.expect);
        let bytes = std::fs::metadata(dir.join(&names.data)).unwrap().len();
        assert!(bytes < 160_000, "{}: {bytes} bytes", names.data);
    }

    /// The three acceptance cases of issue 32 are committed as the
    /// generator writes them, and each is what its name says.
    #[test]
    fn the_committed_acceptance_cases_are_the_generators() {
        for name in ACCEPTANCE {
            let t = acceptance(name);
            println!("{name}: {} ({} redraws)", t.label, t.redraws);
            let nominal = FileNames::default().nominal_text(&t);
            check_committed(&t, &acceptance_dir(name), &FileNames::default(), &nominal, &t.truth);
            assert_eq!(t.structure, Structure::Cantilever);
            assert!(t.channels.len() <= 5 && t.lines_hz.len() <= 400, "{name}: small files");
            match name {
                "flipped-channel" => {
                    check_expect(&t);
                    let e = &effects(&t)[0];
                    assert_eq!((e.family.as_str(), e.value("m")), ("lumped_mass", Some(0.04)));
                    assert!(matches!(t.setup[..], [SetupError::Polarity { .. }]));
                }
                "tip-resonator" => {
                    check_expect(&t);
                    let e = &effects(&t)[0];
                    assert_eq!((e.nodes[0], e.value("kx")), (21, None), "at the tip, across the beam");
                    // Den Hartog's tuning to the second mode, whose frequency is read here from the model
                    let geo = Geometry::of(Structure::Cantilever);
                    let second = modes_in(&geo.frame().to_toml(), 10.0, 100.0).unwrap()[0];
                    let ratio = 0.05 / (geo.total_mass() / 4.0);
                    assert!((e.value("f_hz").unwrap() * (1.0 + ratio) / second - 1.0).abs() < 1e-12);
                }
                _ => {
                    check_expect(&t);
                    let Expect::DeclaredOnly { values } = &t.expect else { panic!() };
                    let nominal = t.nominal_case().model;
                    let beta = nominal.get(nominal.quantity("group.structure.beta").unwrap());
                    assert!(close(values[1].1, 3.0 * beta), "beta three times the guess");
                }
            }
        }
    }

    /// The walkthrough's frame in `cases/tutorial/`: its docs-ready texts
    /// (by `[[lines]]`) are the generator's models, and its files are the
    /// generator's.
    #[test]
    fn the_walkthrough_frame_files_are_the_generators() {
        let (t, r) = walkthrough_frame();
        println!("{} ({} redraws)", t.label, t.redraws);
        let names = walkthrough_names();
        let (nominal, truth) = (walkthrough_nominal(&t), walkthrough_truth(&t, &r));
        // the same models as the node-by-node texts
        let pairs: Vec<Channel> = t.channels.clone();
        for (mine, theirs) in [(&nominal, &t.nominal), (&truth, &t.truth)] {
            let case = CaseFile::parse(Path::new("x.toml"), mine).unwrap();
            let reference = CaseFile::parse(Path::new("x.toml"), theirs).unwrap();
            assert_eq!(case.model.nodes().len(), reference.model.nodes().len());
            let (a, b) = (receptance(mine, &pairs, &t.lines_hz), receptance(theirs, &pairs, &t.lines_hz));
            for c in 0..pairs.len() {
                // the two roads round the nodes' coordinates apart by 1e-16, which a
                // peak of the lightly damped frame (zeta about 1e-3) amplifies
                let d = worst(a.channel(c), b.channel(c));
                assert!(d < 1e-6, "{}: {d:.2e}\n{mine}", pairs[c]);
            }
        }
        check_committed(&t, &tutorial_dir(), &names, &nominal, &truth);
        assert!(matches!(t.setup[..], [SetupError::Polarity { .. }]));
        let e = &effects(&t)[0];
        assert_eq!(e.family, "resonator");
        assert!((12..=23).contains(&e.nodes[0]), "on the arm");
    }

    /// A study's trials: every family and every pairing of a set-up error
    /// with a structural effect, all distinct.
    #[test]
    fn a_study_draws_every_family_and_pairing() {
        let all = trials(2, 47);
        assert_eq!(all.len(), 2 * 13 + 2 * 5);
        for family in LabFamily::ALL {
            assert_eq!(all.iter().filter(|t| t.family == family && t.with.is_none()).count(), 2, "{family:?}");
        }
        assert!(all.iter().filter(|t| t.with.is_some()).all(|t| t.family.is_setup()));
        let mut labels: Vec<&String> = all.iter().map(|t| &t.label).collect();
        labels.sort();
        labels.dedup();
        assert_eq!(labels.len(), all.len());
        assert!(Structure::ALL.iter().all(|&s| all.iter().any(|t| t.structure == s)), "both structures");
    }

    /// A sample of every family and of set-up errors with structural
    /// effects, each drawn and checked; `LAB_DUMP=DIR` writes them as
    /// cases to run `rfm fix` on.
    #[test]
    fn a_sample_of_every_family_dumps_when_asked() {
        let mut r = rng(44);
        let mut sample: Vec<LabTrial> = LabFamily::ALL.into_iter().map(|f| draw(&mut r, f, None)).collect();
        for (setup, family) in [
            (LabFamily::Polarity, Family::Mass),
            (LabFamily::Swap, Family::Support),
            (LabFamily::WrongNode, Family::StiffnessLoss),
            (LabFamily::Calibration, Family::DampingPatch),
            (LabFamily::Misdirected, Family::Joint),
        ] {
            sample.push(draw(&mut r, setup, Some(family)));
        }
        sample.extend(ACCEPTANCE.map(acceptance));
        sample.push(walkthrough_frame().0);
        let mut labels: Vec<&String> = sample.iter().map(|t| &t.label).collect();
        labels.sort();
        labels.dedup();
        assert_eq!(labels.len(), sample.len(), "every trial of the sample differs");
        for t in &sample {
            check_expect(t);
        }
        if let Some(dir) = std::env::var_os("LAB_DUMP") {
            for (k, t) in sample.iter().enumerate() {
                let name = format!("{k:02}-{:?}{}", t.family, t.with.map_or(String::new(), |f| format!("-{f:?}")));
                t.dump(&Path::new(&dir).join(name.to_lowercase()), 7000 + k as u64).unwrap();
                println!("{name}: {}", t.label);
            }
        }
    }
}
