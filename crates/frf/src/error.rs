//! Errors of the FRF layer, by concern: [`FrfError`] is what every frf
//! function returns; its own variants are the model's DOFs and the solver
//! (a singular or non-finite `Z`, the factorisation), while the errors of
//! files ([`FileError`]) and of FRF data that do not fit together
//! ([`MismatchError`]) are types of their own inside it, so that a caller
//! matches `FrfError::File(_)` or `FrfError::Mismatch(_)` as a whole, or a
//! case of either.

use std::path::PathBuf;

use fe_model::DofRef;

use crate::channel::Channel;
use crate::factor_kind::FactorKind;
use crate::label::short;

/// An FRF computation or data error (see the module docs).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrfError {
    /// A channel names a node the model does not have.
    #[error("{dof} is not a DOF of the model (no such node)")]
    UnknownDof {
        /// The DOF.
        dof: DofRef,
    },
    /// A channel is at a supported (fixed) DOF, where the response is zero.
    #[error("{dof} is held fixed by a support; it cannot be excited or measured")]
    FixedDof {
        /// The DOF.
        dof: DofRef,
    },
    /// `Z(w)` is singular at a frequency (an undamped model on a resonance).
    #[error(
        "the dynamic stiffness is singular at {freq_hz} Hz (an undamped or very lightly damped model evaluated on a resonance?)"
    )]
    Singular {
        /// The frequency.
        freq_hz: f64,
    },
    /// A selected inverse was asked of a workspace without `L D L^T`
    /// factors: the factorisation fell back to LU at that frequency (a tiny
    /// pivot), or none succeeded. Solve for unit right-hand sides instead.
    #[error("the selected inverse needs L D L^T factors, but the workspace holds {}", held_factors(.held))]
    NoLdltFactors {
        /// The factorisation held, if any.
        held: Option<FactorKind>,
    },
    /// A clique given to [`ZSolver::with_cliques`](crate::ZSolver::with_cliques)
    /// names an equation the pattern does not have.
    #[error("clique {clique} names equation {eq}, but the pattern has {n} equations")]
    CliqueOutOfRange {
        /// Index of the clique in the list.
        clique: usize,
        /// The equation.
        eq: usize,
        /// Number of equations.
        n: usize,
    },
    /// The sparse factorisation failed for another reason.
    #[error("sparse factorisation failed: {0}")]
    Factorization(String),
    /// `Z(w)` has an entry that is not finite at a (valid) frequency: some
    /// value of the model overflows when stiffness, mass and damping are
    /// combined.
    #[error(
        "the dynamic stiffness at {freq_hz} Hz has an entry that is not a finite number (equation {equation}): a \
         value of the model (a modulus, density, stiffness, mass or damping coefficient) is so large that K, M or \
         the damping overflow; check the case's values"
    )]
    NonFiniteZ {
        /// The frequency.
        freq_hz: f64,
        /// The first equation (row of `Z`) with a non-finite entry.
        equation: usize,
    },
    /// A frequency that is not positive and finite.
    #[error("frequency {freq_hz} Hz is not positive and finite")]
    BadFrequency {
        /// The frequency.
        freq_hz: f64,
    },
    /// Reading or writing a file failed, or its content is malformed.
    #[error(transparent)]
    File(#[from] FileError),
    /// FRF data, or what is asked of them, that do not fit together.
    #[error(transparent)]
    Mismatch(#[from] MismatchError),
}

/// A file that cannot be read or written, or whose content is malformed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FileError {
    /// Reading or writing a file failed.
    #[error("{}: {message}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A data file's content is malformed.
    #[error("{}:{line}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line (or byte offset for binary data, see the message).
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// Data that cannot be written in the requested format (a number too
    /// wide for its fixed-width field, complex FRFs as a real type, ...).
    #[error("cannot write {format}: {message}")]
    Unwritable {
        /// The format (`UFF dataset 58`).
        format: &'static str,
        /// Why.
        message: String,
    },
}

/// FRF data, or what is asked of them, that do not fit together: the lines
/// and channels of a set, two sets compared, the bands of a correlation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MismatchError {
    /// A channel is listed twice in one set.
    #[error("channel {channel} appears twice")]
    RepeatedChannel {
        /// The channel.
        channel: Channel,
    },
    /// Coherence values that do not match the FRF values one to one.
    #[error("coherence has {values} values, the FRFs {frfs}")]
    CoherenceLength {
        /// Number of coherence values given.
        values: usize,
        /// Number of FRF values (channels x lines).
        frfs: usize,
    },
    /// Per-line weights that do not match the FRF values one to one.
    #[error("{values} line weights given for {frfs} FRF values")]
    WeightsLength {
        /// Number of weights given.
        values: usize,
        /// Number of FRF values (channels x lines).
        frfs: usize,
    },
    /// A line asked for that the data does not have.
    #[error("the data has no line at {freq_hz} Hz (nearest lines must match to 1e-6)")]
    NoLine {
        /// The line asked for.
        freq_hz: f64,
    },
    /// Frequency lines that do not increase strictly.
    #[error("frequencies must increase strictly, but {before} Hz is followed by {after} Hz")]
    NotIncreasing {
        /// The first line out of order.
        before: f64,
        /// The line after it.
        after: f64,
    },
    /// Fractional-octave bands with no band per octave.
    #[error("octave bands need at least one band per octave")]
    NoOctaveFraction,
    /// Band edges that do not make a band.
    #[error("band edges: give at least two frequencies")]
    TooFewBandEdges,
    /// A band edge that is not a frequency.
    #[error("band edge {edge_hz} Hz is not a finite, non-negative frequency")]
    BadBandEdge {
        /// The edge.
        edge_hz: f64,
    },
    /// Band edges that do not increase strictly.
    #[error("band edges must increase strictly, but {before} Hz is followed by {after} Hz")]
    BandEdgesNotIncreasing {
        /// The first edge out of order.
        before: f64,
        /// The edge after it.
        after: f64,
    },
    /// A band between given edges that holds no measured line.
    #[error(
        "band {}-{} Hz has no measured line (the data spans {} to {} Hz)",
        short(*lo_hz),
        short(*hi_hz),
        short(*data_lo_hz),
        short(*data_hi_hz)
    )]
    EmptyBand {
        /// Lower edge of the band.
        lo_hz: f64,
        /// Upper edge of the band.
        hi_hz: f64,
        /// The lowest measured line.
        data_lo_hz: f64,
        /// The highest measured line.
        data_hi_hz: f64,
    },
    /// Model FRFs on other lines than the measured ones.
    #[error("the model FRFs have {model} lines, the measured {measured}; they must be on the same lines")]
    LinesDiffer {
        /// Number of model lines.
        model: usize,
        /// Number of measured lines.
        measured: usize,
    },
    /// A measured channel the model FRFs do not have.
    #[error("the model FRFs have no channel {channel}")]
    MissingChannel {
        /// The channel.
        channel: Channel,
    },
    /// [`FrfSet::rename_channels`](crate::FrfSet::rename_channels) given another
    /// number of names than the set has channels.
    #[error("{names} channel names for a set of {channels} channels")]
    ChannelCount {
        /// Names given.
        names: usize,
        /// Channels of the set.
        channels: usize,
    },
    /// [`FrfSet::merge_channels`](crate::FrfSet::merge_channels) was given no set.
    #[error("no FRF set to merge")]
    NothingToMerge,
    /// A set to merge on other lines than the first set's.
    #[error(
        "set {set} has {lines} lines that differ from the {first} lines of set 0; merged sets must share their lines"
    )]
    SetLinesDiffer {
        /// Index of the set in the list.
        set: usize,
        /// Its number of lines.
        lines: usize,
        /// The first set's number of lines.
        first: usize,
    },
    /// A channel in two of the sets to merge.
    #[error("channel {channel} of set {set} is in set {earlier} too")]
    ChannelInTwoSets {
        /// The channel.
        channel: Channel,
        /// The first set that holds it.
        earlier: usize,
        /// The set that holds it again.
        set: usize,
    },
}

fn held_factors(held: &Option<FactorKind>) -> &'static str {
    match held {
        Some(FactorKind::Lu) => "an LU factorisation (the fallback after a tiny pivot)",
        Some(FactorKind::Ldlt) => "L D L^T factors",
        None => "no factorisation",
    }
}
