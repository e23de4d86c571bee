//! Universal File Format dataset 58 ("function at nodal DOF"), ASCII and
//! binary (58b), as written by test systems (Simcenter Test.Lab, B&K, m+p,
//! HBM catman) and by pyuff.
//!
//! Three levels:
//!
//! - [`read_uff`] / [`parse_uff`] give the file as it is: every dataset 58
//!   ([`Record58`]: header, abscissa, ordinates) of any function type, and
//!   the other datasets it skipped ([`SkippedDataset`]). [`encode`] writes
//!   such records back.
//! - [`read_uff_frfs`] / [`frfs_from_uff`] turn the FRF records (function
//!   type 4) into an [`FrfSet`](crate::FrfSet) on model DOFs, with the coherence records
//!   (type 6) attached, and explain what they did in [`UffFrfs::notes`].
//! - [`write_uff`] / [`to_uff_bytes`] write an [`FrfSet`](crate::FrfSet) as dataset 58.
//!
//! # Layout of one dataset 58
//!
//! ```text
//!     -1
//!     58                          (or `    58b     1     2          11        1600 ...` for binary)
//! record 1-5   five free-text lines (80 columns)
//! record 6     function type, id, version, load case, response entity/node/direction,
//!              reference entity/node/direction          (2(I5,I10),2(1X,10A1,I10,I4))
//! record 7     ordinate data type, number of values, spacing (1 even, 0 uneven),
//!              abscissa start, increment, z value       (3I10,3E13)
//! record 8-11  abscissa, ordinate numerator, ordinate denominator, z axis:
//!              specific data type, unit exponents, label, units ((I10,3I5,2(1X,A20))
//! record 12    the data: ASCII lines or `n bytes` of IEEE floats
//!     -1
//! ```
//!
//! Ordinate data types are 2 (real single), 4 (real double), 5 (complex
//! single) and 6 (complex double). With even spacing the data holds the
//! ordinates only; with uneven spacing each value is preceded by its
//! abscissa. ASCII fields are 13 columns for single precision and for
//! abscissas, 20 for double precision ordinates. Binary data uses the
//! ordinate precision for every number (abscissas included, as pyuff does)
//! and the byte order of the `58b` line.
//!
//! # Errors
//!
//! Nothing here panics on bad input. A malformed or truncated file gives
//! [`crate::FileError::Parse`] with the line (ASCII) or, for binary data, the byte
//! offset in the `line` field and the message, and says what was expected.

mod frfs;
mod geometry;
mod map;
mod numbers;
mod read;
pub(crate) mod units;
mod write;

use std::fmt;
use std::path::Path;

use num_complex::Complex64 as C64;

use crate::error::{FileError, FrfError};

pub use frfs::{
    ChannelSource, TestDofMapper, UffFrfs, frfs_from_uff, frfs_from_uff_mapped, frfs_from_uff_with, read_uff_frfs,
    read_uff_frfs_in, read_uff_frfs_with,
};
pub use geometry::{CoordinateSystem, Geometry, PairedNode, Pairing, PairingOptions, TestNode, pair_by_coordinates};
pub use map::{map_test_dof, map_test_dof_in, model_to_test_dof};
pub use read::{parse_uff, read_uff};
pub use units::{FrfUnits, frf_units};
pub use write::{Spacing, UffWriteOptions, encode, frf_set_to_functions, to_uff_bytes, write_uff};

/// Name of a dataset 58 function type (record 6, field 1).
pub fn function_type_name(code: i64) -> &'static str {
    match code {
        0 => "general or unknown",
        1 => "time response",
        2 => "auto spectrum",
        3 => "cross spectrum",
        4 => "frequency response function",
        5 => "transmissibility",
        6 => "coherence",
        7 => "auto correlation",
        8 => "cross correlation",
        9 => "power spectral density",
        10 => "energy spectral density",
        11 => "probability density function",
        12 => "spectrum",
        13 => "cumulative frequency distribution",
        14 => "peaks valley",
        15 => "stress/cycles",
        16 => "strain/cycles",
        17 => "orbit",
        18 => "mode indicator function",
        19 => "force pattern",
        20 => "partial power",
        21 => "partial coherence",
        22 => "eigenvalue",
        23 => "eigenvector",
        24 => "shock response spectrum",
        25 => "finite impulse response filter",
        26 => "multiple coherence",
        27 => "order function",
        _ => "unknown function type",
    }
}

/// Function type of a frequency response function.
pub const FUNCTION_FRF: i64 = 4;
/// Function type of an (ordinary) coherence.
pub const FUNCTION_COHERENCE: i64 = 6;

/// Name of a specific data type of records 8-11.
pub fn specific_data_type_name(code: i64) -> &'static str {
    match code {
        0 => "unknown",
        1 => "general",
        2 => "stress",
        3 => "strain",
        5 => "temperature",
        6 => "heat flux",
        8 => "displacement",
        9 => "reaction force",
        11 => "velocity",
        12 => "acceleration",
        13 => "excitation force",
        15 => "pressure",
        16 => "mass",
        17 => "time",
        18 => "frequency",
        19 => "rpm",
        20 => "order",
        21 => "sound pressure",
        22 => "sound intensity",
        23 => "sound power",
        _ => "other",
    }
}

/// A measurement direction of record 6: `+X`, `-Z`, `+RZ`, ... or scalar.
///
/// The code is the file's: 1 to 6 for X, Y, Z, RX, RY, RZ, negative for the
/// negative direction, 0 for a scalar (no direction).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Direction(i8);

impl Direction {
    /// No direction (a scalar such as a pressure).
    pub const SCALAR: Direction = Direction(0);
    /// +X translation.
    pub const X: Direction = Direction(1);
    /// +Y translation.
    pub const Y: Direction = Direction(2);
    /// +Z translation.
    pub const Z: Direction = Direction(3);
    /// +X rotation.
    pub const RX: Direction = Direction(4);
    /// +Y rotation.
    pub const RY: Direction = Direction(5);
    /// +Z rotation.
    pub const RZ: Direction = Direction(6);

    /// The direction with this file code, if it is one (-6 to 6).
    pub fn from_code(code: i64) -> Option<Direction> {
        i8::try_from(code).ok().filter(|c| (-6..=6).contains(c)).map(Direction)
    }

    /// The file code.
    pub fn code(self) -> i8 {
        self.0
    }

    /// -1 for a negative direction, +1 otherwise (scalar included).
    pub fn sign(self) -> f64 {
        if self.0 < 0 { -1.0 } else { 1.0 }
    }

    /// The positive direction along the same axis.
    pub fn axis(self) -> Direction {
        Direction(self.0.abs())
    }

    /// The opposite direction (a scalar stays scalar).
    pub fn negated(self) -> Direction {
        Direction(-self.0)
    }

    /// Axis name without sign: `X`, `Y`, `Z`, `RX`, `RY`, `RZ` or `S`.
    pub fn axis_name(self) -> &'static str {
        match self.0.abs() {
            1 => "X",
            2 => "Y",
            3 => "Z",
            4 => "RX",
            5 => "RY",
            6 => "RZ",
            _ => "S",
        }
    }
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            0 => f.write_str("S"),
            c if c < 0 => write!(f, "-{}", self.axis_name()),
            _ => write!(f, "+{}", self.axis_name()),
        }
    }
}

/// A test point and direction, e.g. `101:+Z`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TestDof {
    /// Test node (the file's node number; may be 0 or negative in some files).
    pub node: i64,
    /// Direction.
    pub direction: Direction,
}

impl TestDof {
    /// Shorthand constructor.
    pub fn new(node: i64, direction: Direction) -> Self {
        TestDof { node, direction }
    }
}

impl fmt::Display for TestDof {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.node, self.direction)
    }
}

impl std::str::FromStr for TestDof {
    type Err = String;

    /// Parses `node:direction` as in case files (`101:+Z`, `7:-rz`, `3:S`).
    fn from_str(s: &str) -> Result<Self, String> {
        let (node, code) = fe_model::case::ChannelMap::parse_test_point(s)?;
        Ok(TestDof::new(node, Direction(code)))
    }
}

/// Ordinate data type (record 7, field 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum OrdinateType {
    /// 2: real, single precision.
    RealSingle,
    /// 4: real, double precision.
    RealDouble,
    /// 5: complex, single precision.
    ComplexSingle,
    /// 6: complex, double precision.
    ComplexDouble,
}

impl OrdinateType {
    /// Every type, in code order.
    pub const ALL: [OrdinateType; 4] =
        [OrdinateType::RealSingle, OrdinateType::RealDouble, OrdinateType::ComplexSingle, OrdinateType::ComplexDouble];

    /// The type with this file code (2, 4, 5 or 6).
    pub fn from_code(code: i64) -> Option<Self> {
        match code {
            2 => Some(OrdinateType::RealSingle),
            4 => Some(OrdinateType::RealDouble),
            5 => Some(OrdinateType::ComplexSingle),
            6 => Some(OrdinateType::ComplexDouble),
            _ => None,
        }
    }

    /// The file code.
    pub fn code(self) -> i64 {
        match self {
            OrdinateType::RealSingle => 2,
            OrdinateType::RealDouble => 4,
            OrdinateType::ComplexSingle => 5,
            OrdinateType::ComplexDouble => 6,
        }
    }

    /// Whether values are complex.
    pub fn is_complex(self) -> bool {
        matches!(self, OrdinateType::ComplexSingle | OrdinateType::ComplexDouble)
    }

    /// Whether values are double precision.
    pub fn is_double(self) -> bool {
        matches!(self, OrdinateType::RealDouble | OrdinateType::ComplexDouble)
    }

    /// Bytes per number in binary data (4 or 8).
    pub fn number_size(self) -> usize {
        if self.is_double() { 8 } else { 4 }
    }

    /// Lower-case name, e.g. `complex double`.
    pub fn name(self) -> &'static str {
        match self {
            OrdinateType::RealSingle => "real single",
            OrdinateType::RealDouble => "real double",
            OrdinateType::ComplexSingle => "complex single",
            OrdinateType::ComplexDouble => "complex double",
        }
    }
}

impl fmt::Display for OrdinateType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", self.name(), self.code())
    }
}

/// How a dataset is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// Text (dataset `58`).
    Ascii,
    /// Binary IEEE 754 data (dataset `58b`) in the given byte order.
    Binary {
        /// Big-endian (byte ordering 2) rather than little-endian (1).
        big_endian: bool,
    },
}

impl Encoding {
    /// Binary, little-endian (what current test systems and pyuff on x86 write).
    pub const BINARY: Encoding = Encoding::Binary { big_endian: false };

    /// `ASCII` or `binary`.
    pub fn name(self) -> &'static str {
        match self {
            Encoding::Ascii => "ASCII",
            Encoding::Binary { .. } => "binary",
        }
    }
}

/// One of records 8-11: what an axis holds and in which units.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct DataAxis {
    /// Specific data type (8 displacement, 11 velocity, 12 acceleration,
    /// 13 excitation force, 18 frequency, ...; see [`specific_data_type_name`]).
    pub specific_type: i64,
    /// Length units exponent.
    pub length_exp: i64,
    /// Force units exponent.
    pub force_exp: i64,
    /// Temperature units exponent.
    pub temperature_exp: i64,
    /// Axis label (`NONE` when unused).
    pub label: String,
    /// Units label (`NONE` when unused), e.g. `m/s^2` or `(1/N)*(m/s²)`.
    pub units: String,
}

impl DataAxis {
    /// An axis with a type, a label and units, and zero unit exponents.
    pub fn new(specific_type: i64, label: &str, units: &str) -> Self {
        DataAxis { specific_type, label: label.into(), units: units.into(), ..Default::default() }
    }

    /// The unused axis (`0 ... NONE NONE`).
    pub fn none() -> Self {
        DataAxis::new(0, "NONE", "NONE")
    }
}

/// Records 1-11 of a dataset 58.
#[derive(Clone, Debug, PartialEq)]
pub struct Header58 {
    /// Records 1-5: free text (id line 1 is usually a description, line 3 the date).
    pub ids: [String; 5],
    /// Function type (1 time response, 4 FRF, 6 coherence, 9 PSD, ...).
    pub function_type: i64,
    /// Function identification number.
    pub function_id: i64,
    /// Version number or sequence number.
    pub version: i64,
    /// Load case identification number.
    pub load_case: i64,
    /// Response entity name (`NONE` when unused).
    pub response_entity: String,
    /// Response node and direction.
    pub response: TestDof,
    /// Reference entity name (`NONE` when unused).
    pub reference_entity: String,
    /// Reference (excitation) node and direction.
    pub reference: TestDof,
    /// Ordinate data type.
    pub ordinate_type: OrdinateType,
    /// Z-axis value (record 7, field 6).
    pub z_value: f64,
    /// Record 8.
    pub abscissa_axis: DataAxis,
    /// Record 9.
    pub numerator: DataAxis,
    /// Record 10.
    pub denominator: DataAxis,
    /// Record 11.
    pub z_axis: DataAxis,
}

/// Abscissa values of a function.
#[derive(Clone, Debug, PartialEq)]
pub enum Abscissa {
    /// `min + k step` (record 7).
    Even {
        /// First value.
        min: f64,
        /// Increment.
        step: f64,
    },
    /// One value per ordinate, stored with the data.
    Uneven(Vec<f64>),
}

/// Ordinate values of a function.
#[derive(Clone, Debug, PartialEq)]
pub enum Ordinates {
    /// Real data (types 2 and 4).
    Real(Vec<f64>),
    /// Complex data (types 5 and 6).
    Complex(Vec<C64>),
}

impl Ordinates {
    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            Ordinates::Real(v) => v.len(),
            Ordinates::Complex(v) => v.len(),
        }
    }

    /// Whether there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Value `k` as a complex number (imaginary part 0 for real data).
    pub fn get(&self, k: usize) -> Option<C64> {
        match self {
            Ordinates::Real(v) => v.get(k).map(|&x| C64::new(x, 0.0)),
            Ordinates::Complex(v) => v.get(k).copied(),
        }
    }
}

/// One function of a dataset 58: header and data.
#[derive(Clone, Debug, PartialEq)]
pub struct Function58 {
    /// Records 1-11.
    pub header: Header58,
    /// Abscissa (frequency in Hz for FRFs).
    pub abscissa: Abscissa,
    /// Ordinates.
    pub ordinates: Ordinates,
}

impl Function58 {
    /// Number of values.
    pub fn len(&self) -> usize {
        self.ordinates.len()
    }

    /// Whether the function has no values.
    pub fn is_empty(&self) -> bool {
        self.ordinates.is_empty()
    }

    /// Abscissa value `k`.
    pub fn abscissa_at(&self, k: usize) -> Option<f64> {
        match &self.abscissa {
            Abscissa::Even { min, step } => (k < self.len()).then(|| min + k as f64 * step),
            Abscissa::Uneven(x) => x.get(k).copied(),
        }
    }

    /// All abscissa values.
    pub fn abscissa_values(&self) -> Vec<f64> {
        (0..self.len()).filter_map(|k| self.abscissa_at(k)).collect()
    }

    /// Whether the abscissa is evenly spaced.
    pub fn is_even(&self) -> bool {
        matches!(self.abscissa, Abscissa::Even { .. })
    }
}

/// A dataset 58 as found in a file.
#[derive(Clone, Debug, PartialEq)]
pub struct Record58 {
    /// 1-based number among the file's datasets 58 ("record 2").
    pub index: usize,
    /// 1-based line of its `58`/`58b` line.
    pub line: usize,
    /// ASCII or binary.
    pub encoding: Encoding,
    /// Header and data.
    pub function: Function58,
}

impl Record58 {
    /// `record N (line L)`, the prefix of messages about this record.
    pub fn label(&self) -> String {
        format!("record {} (line {})", self.index, self.line)
    }
}

/// A dataset of another type, skipped.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SkippedDataset {
    /// Dataset number (151, 164, 2411, 55, ...).
    pub number: i64,
    /// 1-based line of its number.
    pub line: usize,
}

impl SkippedDataset {
    /// What the dataset usually holds, when it is a common one.
    pub fn description(&self) -> &'static str {
        match self.number {
            15 | 2411 | 781 => "nodes",
            18 | 2420 => "coordinate systems",
            55 | 2414 => "data at nodes (modes or responses)",
            82 => "trace lines",
            151 => "header",
            164 => "units",
            2400 => "model header",
            2412 => "elements",
            2429 | 2467 => "groups",
            1858 => "qualifiers of a dataset 58",
            _ => "another dataset",
        }
    }
}

/// A dataset kept as text lines, to be parsed when asked for (the test
/// geometry: see [`UffFile::geometry`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RawDataset {
    /// Dataset number (15, 2411, 18, 2420, 164).
    pub number: i64,
    /// 1-based line of its number.
    pub line: usize,
    /// Its lines between the number and the closing `-1`: line number and text.
    pub lines: Vec<(usize, String)>,
}

/// The datasets of a universal file.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct UffFile {
    /// Datasets 58, in file order.
    pub records: Vec<Record58>,
    /// Datasets of other types, in file order.
    pub skipped: Vec<SkippedDataset>,
    /// The datasets of the test geometry (nodes 15 and 2411, coordinate
    /// systems 18 and 2420, units 164) as text, in file order; they are
    /// listed in `skipped` too, since the FRFs do not use them.
    pub geometry: Vec<RawDataset>,
    /// Irregularities the reader worked around (an empty dataset, a wrong
    /// byte count in a `58b` line that the data's end confirms).
    pub notes: Vec<String>,
}

/// Whether `bytes` look like a universal file: the first non-blank line is `-1`.
pub fn looks_like_uff(bytes: &[u8]) -> bool {
    bytes.split(|&b| b == b'\n').map(|l| l.trim_ascii()).find(|l| !l.is_empty()).is_some_and(|l| l == b"-1")
}

/// Reads and parses `path` as a universal file (the caller already checked
/// the extension or the content).
pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>, FrfError> {
    std::fs::read(path)
        .map_err(|e| FrfError::File(FileError::Io { path: path.to_path_buf(), message: format!("cannot read: {e}") }))
}
