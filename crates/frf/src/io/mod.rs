//! File input and output of FRF sets. This module is the only place in the
//! crate that touches the file system.
//!
//! Measured data comes as UFF dataset 58 ([`uff`]: ASCII or binary, test
//! nodes and directions mapped to model DOFs) or CSV ([`csv`]: model DOFs);
//! [`read_measured`] picks the reader by extension or content.
//!
//! Every writer goes through [`atomic_write`]: the data is written to a
//! temporary file beside the target and renamed over it, so an interrupted
//! run never leaves a half-written file, and [`atomic_write`] refuses to
//! replace a file the caller marks as an input.

pub mod csv;
pub mod mask;
pub mod uff;

use std::io::Write;
use std::path::{Path, PathBuf};

use fe_model::DofMap;
use fe_model::case::{ChannelMap, MaskRule};

pub use mask::{Masked, Origin, check_channels};

use crate::error::{FileError, FrfError};
use crate::set::FrfSet;

/// A measured-data file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeasuredFormat {
    /// Plain CSV whose channel names are model DOFs ([`csv`]).
    Csv,
    /// Universal file, dataset 58 or 58b ([`uff`]).
    Uff,
}

/// File extensions read as universal files.
pub const UFF_EXTENSIONS: [&str; 4] = ["uff", "unv", "58", "uff58"];

/// The format of a measured-data file: by extension (`.csv`/`.txt` CSV,
/// `.uff`/`.unv`/`.58`/`.uff58` universal file), otherwise by content (a
/// universal file starts with a `-1` line; a CSV file has a header line
/// naming a frequency column).
pub fn detect_format(path: &Path) -> Result<MeasuredFormat, FrfError> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    if ext == "csv" || ext == "txt" {
        return Ok(MeasuredFormat::Csv);
    }
    if UFF_EXTENSIONS.contains(&ext.as_str()) {
        return Ok(MeasuredFormat::Uff);
    }
    let bytes = uff::read_bytes(path)?;
    if uff::looks_like_uff(&bytes) {
        return Ok(MeasuredFormat::Uff);
    }
    let looks_csv = String::from_utf8_lossy(bytes.get(..4096).unwrap_or(&bytes))
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .is_some_and(|l| l.to_ascii_lowercase().starts_with("freq"));
    if looks_csv {
        return Ok(MeasuredFormat::Csv);
    }
    Err(FrfError::File(FileError::Io {
        path: path.to_path_buf(),
        message: format!(
            "cannot tell the format of this file{}: it is neither a universal file (dataset 58, first line `-1`) \
             nor CSV (a header line starting with the frequency column); supported: .csv, .txt, {}",
            if ext.is_empty() { String::new() } else { format!(" (extension `.{ext}`)") },
            UFF_EXTENSIONS.map(|e| format!(".{e}")).join(", ")
        ),
    }))
}

/// What a measured channel's values are relative to, as read from its file.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelUnits {
    /// The values are per volt: the reference is a voltage (a shaker
    /// amplifier's drive signal, an uncalibrated force gauge), not a force.
    pub per_volt: bool,
    /// The reference as a universal file names it (`1:+Z`), so that a
    /// calibration can be given by test point; `None` for CSV.
    pub test_reference: Option<uff::TestDof>,
    /// The units as read, for messages (`` `m/s^2` / `V` ``, `` `g/N` ``).
    pub basis: String,
}

/// Measured FRFs and what reading them involved.
#[derive(Clone, Debug, PartialEq)]
pub struct Measured {
    /// The FRFs on model DOFs, in the file's kind (call
    /// [`FrfSet::to_receptance`] to compare with receptances).
    pub set: FrfSet,
    /// The format read.
    pub format: MeasuredFormat,
    /// Notes for the user (skipped datasets, dropped lines, conversions).
    pub notes: Vec<String>,
    /// Where each channel of `set` comes from in the file, in the same order.
    pub origins: Vec<Origin>,
    /// What the case's mask rules left out (empty without rules).
    pub masked: Vec<Masked>,
    /// What each channel of `set` is relative to, in the same order.
    pub units: Vec<ChannelUnits>,
    /// How test nodes were paired with model nodes by their coordinates
    /// (empty unless the case asks for it: `[measurement] pair`).
    pub pairing: Vec<uff::PairedNode>,
}

impl Measured {
    /// Checks the channels against a model's DOFs (see [`check_channels`]):
    /// a channel at a node the model lacks or at a supported DOF is refused,
    /// naming the file, its record or columns and the DOF, or left out when
    /// `rules` hold [`MaskRule::UnmodelledChannels`].
    pub fn check_channels(self, path: &Path, dofs: &DofMap, rules: &[MaskRule]) -> Result<Measured, FrfError> {
        let by_channel: std::collections::HashMap<crate::Channel, ChannelUnits> =
            self.set.channels().iter().copied().zip(self.units).collect();
        let (set, origins, masked) = check_channels(path, self.set, &self.origins, dofs, rules)?;
        let units = set.channels().iter().filter_map(|c| by_channel.get(c).cloned()).collect();
        if set.channels().is_empty() {
            return Err(FrfError::File(FileError::Parse {
                path: path.to_path_buf(),
                line: 1,
                message: "no channel is left: every channel is at a node the model lacks or at a supported DOF".into(),
            }));
        }
        let mut all = self.masked;
        all.extend(masked);
        Ok(Measured { set, format: self.format, notes: self.notes, origins, masked: all, units, pairing: self.pairing })
    }

    /// The references whose values are per volt (see [`ChannelUnits::per_volt`]).
    pub fn per_volt_references(&self) -> Vec<fe_model::DofRef> {
        let mut out: Vec<fe_model::DofRef> = Vec::new();
        for (c, u) in self.set.channels().iter().zip(&self.units) {
            if u.per_volt && !out.contains(&c.reference) {
                out.push(c.reference);
            }
        }
        out
    }
}

/// How to read a measured file: the case's channel map and mask rules, and
/// the channel of a CSV file whose columns name none.
#[derive(Clone, Copy, Debug, Default)]
pub struct ReadOptions<'a> {
    /// Test (node, direction) to model DOF entries (`[[measurement.map]]`).
    pub map: &'a [ChannelMap],
    /// What to leave out instead of refusing (`[measurement] mask`).
    pub mask: &'a [MaskRule],
    /// The channel of a single-channel CSV file with columns `freq,re,im`
    /// and no `# channel` line: the one channel a case measures.
    pub channel: Option<crate::Channel>,
    /// The model's dimension: which test directions map to model DOFs
    /// without a map entry ([`uff::map_test_dof_in`]).
    pub dimension: fe_model::Dimension,
}

/// Reads a measured FRF file (see [`detect_format`]) and maps its channels
/// to model DOFs. CSV files name model DOFs directly (the map is not used);
/// universal files name test nodes and directions, mapped through `map`
/// (see [`uff::map_test_dof`] and `docs/measured-data.md`). Defects are
/// refused; see [`load_measured_with`] to leave some out.
pub fn load_measured(path: &Path, map: &[ChannelMap]) -> Result<Measured, FrfError> {
    load_measured_with(path, map, &[])
}

/// Reads a measured FRF file like [`load_measured`], leaving out what the
/// mask rules allow (non-finite values, repeated lines) instead of refusing
/// the file; [`Measured::masked`] lists what was left out. Channel rules
/// need the model: see [`Measured::check_channels`].
pub fn load_measured_with(path: &Path, map: &[ChannelMap], rules: &[MaskRule]) -> Result<Measured, FrfError> {
    load_measured_opts(path, &ReadOptions { map, mask: rules, channel: None, dimension: fe_model::Dimension::Planar })
}

/// Reads a measured FRF file with [`ReadOptions`] (see [`load_measured_with`]).
pub fn load_measured_opts(path: &Path, opts: &ReadOptions<'_>) -> Result<Measured, FrfError> {
    let measured = read_format(path, opts)?;
    check_not_empty(path, measured)
}

/// The last guard of every reader: no command ever indexes an empty set.
pub fn check_not_empty(path: &Path, measured: Measured) -> Result<Measured, FrfError> {
    // The readers refuse an empty record or table where they see it; this
    // is the last guard, so that no command ever indexes an empty set.
    if measured.set.n_freq() == 0 || measured.set.channels().is_empty() {
        return Err(FrfError::File(FileError::Parse {
            path: path.to_path_buf(),
            line: 1,
            message: format!(
                "the file holds {} frequency lines and {} channels: nothing to compare",
                measured.set.n_freq(),
                measured.set.channels().len()
            ),
        }));
    }
    Ok(measured)
}

fn read_format(path: &Path, opts: &ReadOptions<'_>) -> Result<Measured, FrfError> {
    match detect_format(path)? {
        MeasuredFormat::Csv => {
            let c = csv::read_csv_opts(path, &csv::CsvOptions { rules: opts.mask, channel: opts.channel })?;
            let unit = ChannelUnits { per_volt: c.per_volt, test_reference: None, basis: c.units.clone() };
            Ok(Measured {
                units: vec![unit; c.set.channels().len()],
                set: c.set,
                format: MeasuredFormat::Csv,
                notes: c.notes,
                origins: c.origins,
                masked: c.masked,
                pairing: Vec::new(),
            })
        }
        MeasuredFormat::Uff => Ok(uff::read_uff_frfs_in(path, opts.map, opts.mask, opts.dimension)?.into_measured()),
    }
}

/// Reads a measured FRF file like [`load_measured`], keeping only the FRFs.
pub fn read_measured(path: &Path, map: &[ChannelMap]) -> Result<FrfSet, FrfError> {
    load_measured(path, map).map(|m| m.set)
}

/// `NaN`, `inf` or `infinity` (any case, with an optional sign) as a
/// number. The readers keep such values so that the checks of the FRF set
/// refuse or mask them with their place in the file ([`mask`]).
pub(crate) fn non_finite_word(token: &str) -> Option<f64> {
    let bare = token.trim_start_matches(['+', '-']).to_ascii_lowercase();
    if matches!(bare.as_str(), "nan" | "inf" | "infinity") { token.to_ascii_lowercase().parse().ok() } else { None }
}

/// What makes a file the same file however it is reached: its device and
/// inode on unix, so that a second mount point, a hard link or a symlink
/// to an input is still recognised as that input (comparing resolved paths
/// misses the first two); elsewhere its canonical path, the best std offers.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct FileId {
    #[cfg(unix)]
    dev: u64,
    #[cfg(unix)]
    ino: u64,
    #[cfg(not(unix))]
    path: PathBuf,
}

impl FileId {
    /// The identity of the file at `path` (following symlinks), or `None`
    /// when there is no such file.
    pub fn of(path: &Path) -> Option<FileId> {
        let meta = std::fs::metadata(path).ok()?;
        Some(FileId::from_metadata(path, &meta))
    }

    /// The identity of an open file.
    pub fn of_file(file: &std::fs::File, path: &Path) -> Option<FileId> {
        let meta = file.metadata().ok()?;
        Some(FileId::from_metadata(path, &meta))
    }

    #[cfg(unix)]
    fn from_metadata(_path: &Path, meta: &std::fs::Metadata) -> FileId {
        use std::os::unix::fs::MetadataExt;
        FileId { dev: meta.dev(), ino: meta.ino() }
    }

    #[cfg(not(unix))]
    fn from_metadata(path: &Path, _meta: &std::fs::Metadata) -> FileId {
        FileId { path: path.canonicalize().unwrap_or_else(|_| path.to_path_buf()) }
    }
}

/// Fails if one of `outputs` is one of `inputs` (the same file, however
/// named: see [`FileId`]), so that a command can refuse before it does any
/// work. Outputs that do not exist yet cannot be inputs.
pub fn refuse_inputs(outputs: &[PathBuf], inputs: &[PathBuf]) -> Result<(), FrfError> {
    let inputs: Vec<FileId> = inputs.iter().filter_map(|p| FileId::of(p)).collect();
    for path in outputs {
        if FileId::of(path).is_some_and(|id| inputs.contains(&id)) {
            return Err(FrfError::File(FileError::Io {
                path: path.to_path_buf(),
                message: "refusing to overwrite an input file; choose another output path".into(),
            }));
        }
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically (temporary file in the same folder,
/// flushed and synced, then renamed). Fails if `path` is one of `inputs`.
pub fn atomic_write(path: &Path, bytes: &[u8], inputs: &[PathBuf]) -> Result<(), FrfError> {
    let io = |message: String| FrfError::File(FileError::Io { path: path.to_path_buf(), message });
    refuse_inputs(&[path.to_path_buf()], inputs)?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(|e| io(format!("cannot create folder {}: {e}", dir.display())))?;
    let name = path.file_name().ok_or_else(|| io("not a file path".into()))?;
    let tmp = dir.join(format!(".{}.tmp-{}", name.to_string_lossy(), std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(io(format!("cannot write: {e}")));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_outputs_but_never_inputs() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.txt");
        atomic_write(&out, b"one", &[]).unwrap();
        atomic_write(&out, b"two", &[]).unwrap();
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "two");
        let e = atomic_write(&out, b"three", std::slice::from_ref(&out)).unwrap_err();
        assert!(e.to_string().contains("refusing to overwrite an input"), "{e}");
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "two");
        // no temporary files are left behind
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    /// A hard link is another path to the same file: comparing resolved
    /// paths would let an output replace the input through it (as a second
    /// mount point of the same folder would); device and inode do not.
    #[test]
    fn an_input_reached_through_a_hard_link_is_recognised() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("case.toml");
        std::fs::write(&input, "x").unwrap();
        let link = dir.path().join("other-name.toml");
        std::fs::hard_link(&input, &link).unwrap();
        assert_ne!(link.canonicalize().unwrap(), input.canonicalize().unwrap());
        let e = refuse_inputs(std::slice::from_ref(&link), std::slice::from_ref(&input)).unwrap_err();
        assert!(e.to_string().contains("other-name.toml: refusing to overwrite an input"), "{e}");
        let e = atomic_write(&link, b"y", std::slice::from_ref(&input)).unwrap_err();
        assert!(e.to_string().contains("refusing to overwrite an input"), "{e}");
        assert_eq!(std::fs::read_to_string(&input).unwrap(), "x");
        refuse_inputs(&[dir.path().join("new.toml")], std::slice::from_ref(&input)).unwrap();
    }
}
