//! `rfm simulate`: synthesise FRFs on the case's measurement lines, written
//! as UFF dataset 58 (`.uff`, `.unv`; ASCII, or 58b with `--binary`) or CSV
//! (`.csv`), in the kind asked for.

use std::path::Path;

use damping::DampedSystem;
use fe_model::CaseFile;
use frf::io::uff::{Encoding, UffWriteOptions};
use frf::{Channel, FrfKind, FrfSet, NoiseModel};
use serde::Serialize;

use super::{Result, load_case};
use crate::exit::{Exit, Failure};
use crate::output::Outputs;

/// Options of the simulate command.
pub struct SimulateArgs<'a> {
    /// The case file.
    pub case: &'a Path,
    /// The output file.
    pub out: &'a Path,
    /// Synthesise the truth's FRFs instead of the model's.
    pub truth: bool,
    /// Relative complex noise level.
    pub noise: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// FRF kind written.
    pub kind: &'a str,
    /// UFF 58b instead of ASCII.
    pub binary: bool,
    /// Print JSON.
    pub json: bool,
}

/// The file format of `--out`, from its extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum OutFormat {
    Uff,
    Csv,
}

fn out_format(out: &Path, binary: bool) -> std::result::Result<OutFormat, String> {
    let ext = out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let format = match ext.as_deref() {
        Some("uff" | "unv") => OutFormat::Uff,
        Some("csv") => OutFormat::Csv,
        _ => {
            return Err(format!(
                "--out {}: the extension says the format: .uff or .unv for UFF dataset 58 (--binary for 58b), .csv \
                 for CSV",
                out.display()
            ));
        }
    };
    if binary && format == OutFormat::Csv {
        return Err(format!("--binary writes UFF 58b; {} is a CSV file (.uff or .unv for UFF)", out.display()));
    }
    Ok(format)
}

/// The FRFs `rfm simulate` writes, in memory: the model's (or with
/// `truth`, the case's truth's) at the case's measurement lines and
/// channels, with `noise` (relative, seeded by `seed`), in `kind`.
pub fn synthesised(case_file: &CaseFile, truth: bool, noise: f64, seed: u64, kind: FrfKind) -> Result<FrfSet> {
    let spec =
        case_file.measurement.as_ref().ok_or("the case has no [measurement] section (which channels and lines?)")?;
    if spec.frequencies_hz.is_empty() {
        return Err(format!(
            "{}: the case's [measurement] gives no `frequencies`: simulate needs the lines to synthesise",
            case_file.path.display()
        )
        .into());
    }
    let model = if truth {
        case_file.truth.as_ref().ok_or("the case has no [truth] section")?.model.clone()
    } else {
        case_file.model.clone()
    };
    let sys = DampedSystem::new(model)?;
    let channels: Vec<Channel> =
        spec.references.iter().flat_map(|&r| spec.responses.iter().map(move |&m| Channel::new(m, r))).collect();
    let mut set = frf::synthesize(&sys, &channels, &spec.frequencies_hz)?;
    NoiseModel { relative: noise, floor: 0.0, seed }.apply(&mut set);
    Ok(set.converted(kind))
}

/// What `--json` prints.
#[derive(Serialize)]
struct SimulateJson {
    out: String,
    format: &'static str,
    kind: String,
    channels: usize,
    lines: usize,
    from_hz: f64,
    to_hz: f64,
    model: &'static str,
    noise: f64,
    seed: u64,
}

/// `rfm simulate`: writes the FRFs and says what it wrote.
pub fn simulate(args: &SimulateArgs<'_>) -> Result<Exit> {
    if !(args.noise.is_finite() && args.noise >= 0.0) {
        return Err(Failure::new(
            Exit::Usage,
            format!("--noise {}: the relative noise level must be a finite number, 0 or more (0.01 = 1 %)", args.noise),
        ));
    }
    let kind = FrfKind::parse(args.kind).ok_or_else(|| {
        Failure::new(Exit::Usage, format!("--kind {}: receptance, mobility or accelerance", args.kind))
    })?;
    let case_file = load_case(args.case)?;
    // an input named as the output is refused first, whatever its extension
    let mut output = Outputs::file(args.out, &case_file.inputs())?;
    let format = out_format(args.out, args.binary).map_err(|e| Failure::new(Exit::Usage, e))?;
    let set = synthesised(&case_file, args.truth, args.noise, args.seed, kind)?;
    let bytes = match format {
        OutFormat::Csv => frf::io::csv::to_csv_string(&set).into_bytes(),
        OutFormat::Uff => {
            let encoding = if args.binary { Encoding::BINARY } else { Encoding::Ascii };
            frf::io::uff::to_uff_bytes(&set, &UffWriteOptions { encoding, ..UffWriteOptions::default() })?
        }
    };
    output.write_file(&bytes)?;
    output.commit()?;
    let f = set.frequencies_hz();
    let format_name = match (format, args.binary) {
        (OutFormat::Csv, _) => "csv",
        (OutFormat::Uff, false) => "uff58 ascii",
        (OutFormat::Uff, true) => "uff58b binary",
    };
    if args.json {
        let doc = SimulateJson {
            out: args.out.display().to_string(),
            format: format_name,
            kind: set.kind().to_string(),
            channels: set.channels().len(),
            lines: set.n_freq(),
            from_hz: f[0],
            to_hz: f[f.len() - 1],
            model: if args.truth { "truth" } else { "initial" },
            noise: args.noise,
            seed: args.seed,
        };
        outln!("{}", serde_json::to_string_pretty(&doc)?);
    } else {
        outln!(
            "wrote {} channels x {} lines ({}, {format_name}) to {}",
            set.channels().len(),
            set.n_freq(),
            set.kind(),
            args.out.display()
        );
    }
    Ok(Exit::Success)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_extension_decides_the_format_and_binary_needs_uff() {
        assert_eq!(out_format(Path::new("a/x.uff"), false), Ok(OutFormat::Uff));
        assert_eq!(out_format(Path::new("x.UNV"), true), Ok(OutFormat::Uff));
        assert_eq!(out_format(Path::new("x.csv"), false), Ok(OutFormat::Csv));
        let e = out_format(Path::new("x.dat"), false).unwrap_err();
        assert!(e.contains("x.dat") && e.contains(".uff or .unv"), "{e}");
        let e = out_format(Path::new("x.csv"), true).unwrap_err();
        assert!(e.contains("--binary writes UFF 58b"), "{e}");
    }
}
