//! `rfm compare`: the case's model against the measured FRFs, without
//! updating: FRF-level errors per channel and per band, the worst of them,
//! overlays and a report.
//!
//! The report is a list of sections; the FRF sections come first, and
//! further comparisons (a mode table, say) are appended as more sections
//! in [`report_sections`] without changing the others.

use std::path::{Path, PathBuf};

use damping::DampedSystem;
use fe_model::CaseFile;
use fe_model::case::Gains;
use frf::correlation::{BandSpec, Correlation};
use frf::{FrfError, FrfSet, MismatchError};
use rfm_update::comparison::{self, GainSource};
use rfm_update::gain::{self, FittedGains, GainReport};
use rfm_update::quantities::MisfitReport;
use rfm_update::study::{describe_masked, read_measured_for};
use serde::Serialize;

use super::{Result, load_case, print_masked, print_notes};
use crate::exit::Exit;
use crate::output::Outputs;
use crate::report::html::{Block, Report, Section};
use crate::report::modes::{MIN_MAC, ModesJson, mode_table_rows, rows};
use crate::report::{self, Data, MeshReading, ModelFrfs, ReportOptions, plot, sig, signed};
use crate::table::{self, Table};
use rfm_update::diagnose::MeshCheck;

/// What `--json` prints and `compare.json` holds: the library's results
/// (the correlation, the fitted gains) with what only the command knows.
#[derive(Serialize)]
struct CompareJson<'a> {
    case: String,
    title: String,
    /// Where the measured data came from.
    measured: String,
    /// The model compared (the case's initial model).
    model: String,
    /// Band choice (`auto`, `octave`, edges...).
    bands: String,
    /// The FRF kind compared: the data's, whichever way they arrive.
    kind: String,
    /// What the compared values are, in words (`accelerance per volt`).
    quantity: String,
    /// The unit of the compared values (`m/s²/V` for data per volt).
    unit: String,
    /// The model's misfit over the diagnosis's lines and the data's noise
    /// (the same numbers `rfm diagnose` and `rfm fix` give this model).
    misfit: MisfitReport,
    /// The model against itself with every element cut in two, at the
    /// same lines (`null` for a model without beams or above 10,000 DOFs).
    mesh: Option<MeshCheck>,
    correlation: &'a Correlation,
    /// The unknown gains the model's FRFs were multiplied by (`none`,
    /// `per-reference`, `per-channel`) and why.
    gain_setting: String,
    /// The fitted gains (empty without gains).
    gains: Vec<GainReport>,
    /// Measured (LSCF) against model modes; `null` when they could not be
    /// compared, with the reason in `modes_error`.
    modes: Option<ModesJson>,
    /// Why the modes could not be compared.
    modes_error: Option<String>,
    /// What the case's mask rules left out of the measured data.
    masked: Vec<String>,
    /// What reading the measured data changed or passed over.
    notes: Vec<String>,
}

/// The fitted gains, one line each.
fn print_gains(gains: &[GainReport]) -> Result<()> {
    if gains.is_empty() {
        return Ok(());
    }
    outln!("\nfitted gains (model FRFs multiplied by them before the comparison)");
    for g in gains {
        outln!("    {}", report::gain_text(g));
    }
    Ok(())
}

/// Parses `--bands`: `auto`, `resonances`, `octave`, `third-octave`, or
/// comma-separated edges in Hz.
pub(crate) fn parse_bands(s: &str) -> std::result::Result<BandSpec, String> {
    match s.trim() {
        "auto" => Ok(BandSpec::Auto),
        "resonances" | "modes" => Ok(BandSpec::Resonances),
        "octave" | "octaves" => Ok(BandSpec::Octave { fraction: 1 }),
        "third-octave" | "third-octaves" => Ok(BandSpec::Octave { fraction: 3 }),
        list => list
            .split(',')
            .map(|x| x.trim().parse::<f64>().map_err(|_| format!("`{}` is not a frequency in Hz", x.trim())))
            .collect::<std::result::Result<Vec<f64>, String>>()
            .map(BandSpec::Edges)
            .map_err(|e| {
                format!("{e}; --bands takes auto, resonances, octave, third-octave or edges like 0,50,120,400")
            }),
    }
}

/// The measured FRFs and what is known of them.
struct MeasuredData {
    /// The case (returned by the study that read the data).
    case: CaseFile,
    /// The FRFs.
    set: FrfSet,
    /// Where they came from.
    source: String,
    /// What the case's mask rules left out of them.
    masked: Vec<String>,
    /// What reading them changed or passed over.
    notes: Vec<String>,
    /// The gains to fit and why.
    gains: (Gains, String),
    /// The references whose data are per volt.
    per_volt: Vec<fe_model::DofRef>,
}

/// The measured FRFs: the case's data or truth, or the `--measured` files.
fn measured_data(case: CaseFile, system: &DampedSystem, files: &[PathBuf]) -> Result<MeasuredData> {
    if files.is_empty() {
        let study = super::study_of(case)?;
        let source = match (study.case().measurement.as_ref().and_then(|m| m.data.as_ref()), &study.case().truth) {
            (Some(p), _) => format!("measured file {} (from the case)", report::shown_path(p)),
            (None, Some(t)) if t.noise > 0.0 => format!(
                "synthesised from the case's truth model ({} % noise, seed {})",
                report::short(100.0 * t.noise),
                t.seed
            ),
            (None, Some(_)) => "synthesised from the case's truth model (noise-free)".into(),
            (None, None) => "the case's data".into(),
        };
        let masked = describe_masked(study.masked());
        // compared in the kind the data were measured in, as with --measured
        let set = study.measured_as_read();
        let gains = (study.gains(), study.gains_reason().to_string());
        let (case, notes, per_volt) = (study.case().clone(), study.notes().to_vec(), study.per_volt().to_vec());
        return Ok(MeasuredData { case, set, source, masked, notes, gains, per_volt });
    }
    let mut sets = Vec::new();
    let mut masked = Vec::new();
    let mut notes = Vec::new();
    let mut per_volt = Vec::new();
    for f in files {
        let read = read_measured_for(system, f, case.measurement.as_ref())
            .map_err(|e| super::mismatch(e.into(), case.measurement.as_ref(), Some(f)))?;
        per_volt.extend(read.per_volt_references());
        masked.extend(describe_masked(&read.masked).into_iter().map(|m| format!("{}: {m}", f.display())));
        notes.extend(read.notes.iter().map(|n| format!("{}: {n}", f.display())));
        sets.push((f.clone(), read.set));
    }
    let names = files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>().join(", ");
    per_volt.sort_by_key(ToString::to_string);
    per_volt.dedup();
    let gains = gain::decide(case.measurement.as_ref(), case.update.as_ref(), &per_volt)?;
    if gains.0 != Gains::None {
        notes.push(format!("model FRFs are multiplied by fitted gains ({}): {}", gains.0, gains.1));
    }
    let source = format!("measured file(s) {names}");
    Ok(MeasuredData { case, set: merge(sets)?, source, masked, notes, gains, per_volt })
}

/// Joins the channels of several measured files on the same lines, in the
/// first file's FRF kind ([`FrfSet::merge_channels`]); a refusal names the
/// files.
fn merge(sets: Vec<(PathBuf, FrfSet)>) -> Result<FrfSet> {
    let (paths, sets): (Vec<PathBuf>, Vec<FrfSet>) = sets.into_iter().unzip();
    FrfSet::merge_channels(&sets).map_err(|e| match e {
        FrfError::Mismatch(MismatchError::NothingToMerge) => "no measured file given".into(),
        FrfError::Mismatch(MismatchError::SetLinesDiffer { set, lines, first }) => format!(
            "{}: its {lines} lines differ from the {first} lines of {}; files compared together must share their lines",
            paths[set].display(),
            paths[0].display()
        )
        .into(),
        FrfError::Mismatch(MismatchError::ChannelInTwoSets { channel, set, .. }) => {
            format!("{}: channel {channel} appears in an earlier file too", paths[set].display()).into()
        }
        other => other.into(),
    })
}

/// Options of the compare command.
pub struct CompareArgs<'a> {
    /// The case file.
    pub case: &'a Path,
    /// Measured FRF files to use instead of the case's data.
    pub measured: &'a [PathBuf],
    /// The report folder.
    pub out: Option<&'a Path>,
    /// Replace a folder another command wrote.
    pub replace: bool,
    /// Print JSON instead of tables.
    pub json: bool,
    /// The bands, as `--bands` takes them.
    pub bands: &'a str,
    /// How the report draws.
    pub report: ReportOptions,
}

/// `rfm compare`: prints the tables (or `--json`) and with `--out` writes
/// the report.
pub fn compare(args: &CompareArgs<'_>) -> Result<Exit> {
    let json = args.json;
    parse_bands(args.bands)?;
    let case = load_case(args.case)?;
    let inputs = CompareRun::inputs(&case, args.measured);
    let output = args
        .out
        .map(|dir| Outputs::folder(dir, &inputs, &CompareRun::OUTPUTS)?.of_command("compare", args.replace))
        .transpose()?;
    let run = CompareRun::new(args.case, case, args.measured, args.bands)?;
    print_notes(&run.read_notes, json)?;
    print_masked(&run.masked, json)?;
    let doc = run.doc();
    if json {
        outln!("{}", serde_json::to_string_pretty(&doc)?);
    } else {
        print_tables(&run.case, &run.data(), &run.source, &run.model.correlation, &run.misfit)?;
        if let Some(line) =
            run.misfit.noise.and_then(|noise| report::mesh_sentence(run.mesh.as_ref(), noise, MeshReading::Compared))
        {
            outln!("\nnote: {line}");
        }
        print_gains(&doc.gains)?;
        match &run.comparison {
            Ok(_) => {
                let m = doc.modes.as_ref().expect("the rows of a comparison");
                let (header, rows) = mode_table_rows(m);
                let mut t = Table::new(&header);
                for r in rows {
                    t.row(r);
                }
                outln!(
                    "\nmodes (measured by LSCF, paired with the model's by MAC; each numbered in frequency order)\n{}",
                    t.render()
                );
            }
            Err(e) => outln!("\nmodes not compared: {e}"),
        }
    }
    if let Some(output) = output {
        let (path, html, written) = run.write(output, &args.report)?;
        if !json {
            let count = |ext: &str| written.iter().filter(|p| p.extension().is_some_and(|e| e == ext)).count();
            outln!(
                "\nwrote {}, {}, {} figures and {} tables (CSV)",
                path.display(),
                html.display(),
                count("svg"),
                count("csv")
            );
        }
    }
    Ok(Exit::Success)
}

/// What `rfm compare` finds, before anything is printed or written: the
/// case's model against the measured FRFs (the case's data, or files given
/// as `--measured` gives them), with what `--json` prints ([`CompareRun::json`])
/// and the files `--out` writes ([`CompareRun::save`]).
pub struct CompareRun {
    case_path: PathBuf,
    case: CaseFile,
    measured: FrfSet,
    source: String,
    bands: String,
    model: ModelFrfs,
    comparison: std::result::Result<frf::ModalComparison, String>,
    gain_setting: String,
    gains: Vec<GainReport>,
    /// The model's misfit over the diagnosis's lines, with the noise.
    misfit: MisfitReport,
    /// The model against itself meshed finer.
    mesh: Option<MeshCheck>,
    /// The references whose data are per volt.
    per_volt: Vec<fe_model::DofRef>,
    /// The data's noise level without line weights (for the noise floors).
    unweighted_noise: Option<f64>,
    masked: Vec<String>,
    /// The notes of reading the data, as printed before the tables.
    read_notes: Vec<String>,
    /// Those and what the comparison adds, as the JSON holds them.
    notes: Vec<String>,
}

impl CompareRun {
    /// The files `--out` writes besides the figures.
    const OUTPUTS: [&str; 2] = ["compare.json", "report.html"];

    /// The inputs of a comparison, which no output may replace.
    fn inputs(case: &CaseFile, measured_files: &[PathBuf]) -> Vec<PathBuf> {
        let mut inputs = case.inputs();
        inputs.extend(measured_files.iter().cloned());
        inputs
    }

    /// Compares the model of `case` (read from `case_path`, the path the
    /// JSON names) with its measured data, or with `measured_files`
    /// instead when any are given; `bands` as `--bands` takes them.
    pub fn new(case_path: &Path, case: CaseFile, measured_files: &[PathBuf], bands: &str) -> Result<CompareRun> {
        let spec = parse_bands(bands)?;
        let system = DampedSystem::new(case.model.clone())?;
        let MeasuredData { case, set: measured, source, masked, notes, gains, per_volt } =
            measured_data(case, &system, measured_files)?;
        let read_notes = notes.clone();
        // the model's FRFs in the data's kind, times the gains that bring them
        // closest to the data (closed form), weighted as the fits weight them:
        // by the measured coherence when the data carry it
        let weights = rfm_update::study::line_weights_for(&case, &measured)?;
        let source_of_gains = GainSource::Fit { setting: gains.0, weights: weights.as_deref() };
        let compared = comparison::compare(&system, &measured, source_of_gains, &spec)?;
        // a model singular at a line has no FRF there: the comparison is
        // refused, naming the line (the reports of updates draw around it)
        if let Some(&freq_hz) = compared.model.singular_hz.first() {
            return Err(FrfError::Singular { freq_hz }.into());
        }
        let fitted = compared.model.fitted.clone().unwrap_or_else(|| FittedGains::none(measured.channels()));
        let coherent = (0..measured.channels().len()).any(|c| measured.coherence(c).is_some());
        let mut notes = notes;
        if coherent && gains.0 != Gains::None && weights.is_some() {
            notes.push("the gains are fitted with each line weighted by its measured coherence".into());
        }
        // the misfit and the noise as the diagnosis reads them (receptances,
        // the same gains and weights), so that every command gives this model
        // one misfit
        let misfit = MisfitReport::of(&system, &measured.to_receptance(), gains.0, weights.as_deref())?;
        let mesh = rfm_update::diagnose::mesh_check(
            &case.model,
            &measured.to_receptance(),
            rfm_update::quantities::MISFIT_LINES,
            gains.0,
            weights.as_deref(),
        );
        let comparison =
            comparison::compare_modes(&system, &measured, &compared.model.gains, MIN_MAC).map_err(|e| e.to_string());
        let model = ModelFrfs {
            label: "model".into(),
            colour: plot::UPDATED,
            frfs: compared.model.frfs,
            correlation: compared.correlation,
            gains: fitted.reports(),
            misfit: Some(misfit),
        };
        let unweighted_noise = match weights {
            Some(_) => rfm_update::quantities::noise(&system, &measured.to_receptance(), None)?,
            None => misfit.noise,
        };
        Ok(CompareRun {
            case_path: case_path.to_path_buf(),
            case,
            measured,
            source,
            bands: bands.to_string(),
            model,
            comparison,
            gain_setting: format!("{} ({})", gains.0, gains.1),
            gains: fitted.reports(),
            misfit,
            mesh,
            per_volt,
            unweighted_noise,
            masked,
            read_notes,
            notes,
        })
    }

    /// The measured data as the report draws them: their kind and unit.
    fn data(&self) -> Data<'_> {
        Data::new(&self.measured, &self.per_volt, self.unweighted_noise)
    }

    /// The document `--json` prints and `compare.json` holds.
    fn doc(&self) -> CompareJson<'_> {
        let consistent = self.misfit.consistent();
        let (modes, modes_error) = match self.comparison.as_ref().map(|c| rows(c, consistent)) {
            Ok(m) => (Some(m), None),
            Err(e) => (None, Some(e.clone())),
        };
        let data = self.data();
        CompareJson {
            case: self.case_path.display().to_string(),
            title: self.case.model.title.clone(),
            measured: self.source.clone(),
            model: "the case's model (initial values)".into(),
            bands: self.bands.clone(),
            kind: self.measured.kind().to_string(),
            quantity: data.quantity(),
            unit: data.unit(),
            misfit: self.misfit,
            mesh: self.mesh.clone(),
            correlation: &self.model.correlation,
            gain_setting: self.gain_setting.clone(),
            gains: self.gains.clone(),
            modes,
            modes_error,
            masked: self.masked.clone(),
            notes: self.notes.clone(),
        }
    }

    /// The measured FRFs compared, in the kind they were measured in.
    pub fn measured(&self) -> &FrfSet {
        &self.measured
    }

    /// The model's FRFs on the measured channels and lines, in the same
    /// kind, times the fitted gains.
    pub fn model_frfs(&self) -> &FrfSet {
        &self.model.frfs
    }

    /// The measured modes against the model's (with the MAC matrix), or
    /// why they could not be compared.
    pub fn modes(&self) -> std::result::Result<&frf::ModalComparison, &str> {
        self.comparison.as_ref().map_err(String::as_str)
    }

    /// What `rfm compare --json` prints.
    pub fn json(&self) -> Result<String> {
        Ok(serde_json::to_string_pretty(&self.doc())?)
    }

    /// Writes what `rfm compare --out DIR` writes (`compare.json`,
    /// `report.html`, the figures and the tables as CSV), all or nothing;
    /// returns the files. A folder another command wrote is refused, as
    /// `rfm compare` without `--replace` refuses it.
    pub fn save(&self, dir: &Path, opts: &ReportOptions) -> Result<Vec<PathBuf>> {
        let inputs = CompareRun::inputs(&self.case, &[]);
        let output = Outputs::folder(dir, &inputs, &CompareRun::OUTPUTS)?.of_command("compare", false)?;
        Ok(self.write(output, opts)?.2)
    }

    /// Writes the outputs and commits them: the JSON's and the report's
    /// paths, and every file written.
    fn write(&self, mut output: Outputs, opts: &ReportOptions) -> Result<(PathBuf, PathBuf, Vec<PathBuf>)> {
        let doc = self.doc();
        let case = &self.case;
        let path = output.write("compare.json", serde_json::to_string_pretty(&doc)?.as_bytes())?;
        let mut report = Report::new(format!("{}: model against measurement", case.model.title));
        report.subtitle = Some(format!("rfm compare, case file {}", self.case_path.display()));
        report.sections = report_sections(
            case,
            &self.data(),
            &self.source,
            &self.model,
            self.comparison.as_ref(),
            &doc,
            &opts.for_case(case),
            &mut output,
        )?;
        let html = output.write("report.html", report.render().as_bytes())?;
        let written = output.commit()?;
        Ok((path, html, written))
    }
}

/// The report's sections, in order.
fn report_sections(
    case: &CaseFile,
    data: &Data<'_>,
    source: &str,
    model: &ModelFrfs,
    modes: std::result::Result<&frf::ModalComparison, &String>,
    doc: &CompareJson<'_>,
    opts: &ReportOptions,
    out: &mut Outputs,
) -> Result<Vec<Section>> {
    let c = &model.correlation;
    let measured = data.set;
    let mut first = summary(case, data, source, c, &doc.misfit, &doc.gains);
    if let Some(b) =
        doc.misfit.noise.and_then(|noise| report::mesh_text(doc.mesh.as_ref(), noise, MeshReading::Compared))
    {
        first.push(b);
    }
    // the loop so far, when the case was written by an earlier step
    if let Some(fall) = report::loop_story::fall_figure(&case.history, false, out)? {
        first.push(fall);
    }
    let added = report::loop_story::highlights(&case.history, &case.model);
    let caption = if added.is_empty() {
        "The case's model."
    } else {
        "The case's model, each effect its history records as added numbered and marked where it sits (a ring at a \
         joint, a support or a mass, a broad band along the elements of a changed region)."
    };
    first.push(report::structure_figure(&case.model, measured, &added, caption, out)?);
    let mut sections = vec![first];
    let mut notes = vec!["The case's model with its initial parameter values against the measured FRFs.".to_string()];
    if !doc.gains.is_empty() {
        notes.push(format!(
            "The model's FRFs are multiplied by unknown complex gains fitted in closed form ({}): {}.",
            doc.gain_setting,
            report::gains_text(&doc.gains)
        ));
    }
    sections.push(report::correlation_section(data, std::slice::from_ref(model), opts, out, notes)?);
    sections.push(report::modes::section(
        modes,
        "the model",
        &case.model,
        measured,
        doc.misfit.consistent(),
        opts,
        out,
    )?);
    sections.push(report::overlay_section(data, std::slice::from_ref(model), &[], opts, out)?);
    sections.push(report::definitions_section());
    Ok(sections)
}

/// The model's misfit in words: `0.4325, 86.67 x the noise (0.00499), over
/// the 200 lines the diagnosis reads, each value weighted by its coherence`.
pub(crate) fn misfit_text(m: &MisfitReport) -> String {
    let noise = match (m.noise, m.times_noise) {
        (Some(n), Some(t)) => format!(", {} x the noise ({})", table::times(t), table::misfit(n)),
        _ => String::new(),
    };
    format!(
        "{}{noise}, over the {} lines the diagnosis reads{}",
        table::misfit(m.misfit),
        m.lines,
        if m.weighted { ", each value weighted by its coherence" } else { "" }
    )
}

fn summary(
    case: &CaseFile,
    data: &Data<'_>,
    source: &str,
    c: &Correlation,
    misfit: &MisfitReport,
    gains: &[GainReport],
) -> Section {
    let measured = data.set;
    let f = measured.frequencies_hz();
    let t = &c.total;
    let mut s = Section::new("Summary");
    let mut facts = vec![
        ("case".into(), case.path.display().to_string()),
        ("data".into(), source.to_string()),
        (
            "measurement".into(),
            format!(
                "{} channels x {} lines, {} to {} Hz, {} ({})",
                measured.channels().len(),
                f.len(),
                report::short(f.first().copied().unwrap_or(0.0)),
                report::short(f.last().copied().unwrap_or(0.0)),
                data.quantity(),
                data.unit()
            ),
        ),
        ("misfit".into(), misfit_text(misfit)),
        ("RMS dB error".into(), format!("{} dB (mean {} dB), all lines", sig(t.rms_db, 3), signed(t.mean_db, 3))),
        ("RMS phase error".into(), format!("{} deg", sig(t.rms_phase_deg, 3))),
        ("FRAC".into(), format!("mean {:.4}, lowest {:.4}", t.mean_frac, t.min_frac)),
    ];
    if !gains.is_empty() {
        facts.push(("fitted gain".into(), report::gains_text(gains)));
    }
    s.push(Block::Facts(facts));
    let bands: Vec<String> = report::notable_bands(c, 3)
        .into_iter()
        .map(|i| format!("{} ({} of the misfit)", c.bands[i].band.label(), report::percent(c.bands[i].share)))
        .collect();
    let channels: Vec<String> = report::notable_channels(c, 3)
        .into_iter()
        .map(|i| {
            format!("{} ({} dB, FRAC {:.3})", c.channels[i].channel, sig(c.channels[i].rms_db, 3), c.channels[i].frac)
        })
        .collect();
    if bands.is_empty() && channels.is_empty() {
        s.push(Block::Text(format!(
            "The model matches the measured FRFs in every band and channel (misfit below {}).",
            report::NOTABLE_MISFIT
        )));
    }
    if !bands.is_empty() {
        s.push(Block::Text(format!("Worst bands: {}.", bands.join("; "))));
    }
    if !channels.is_empty() {
        s.push(Block::Text(format!("Worst channels: {}.", channels.join("; "))));
    }
    s
}

fn print_tables(case: &CaseFile, data: &Data<'_>, source: &str, c: &Correlation, misfit: &MisfitReport) -> Result<()> {
    let measured = data.set;
    let f = measured.frequencies_hz();
    let t = &c.total;
    outln!("{}", case.model.title);
    outln!(
        "model against {source}: {} channels x {} lines, {} to {} Hz, {} ({})",
        measured.channels().len(),
        f.len(),
        report::short(f.first().copied().unwrap_or(0.0)),
        report::short(f.last().copied().unwrap_or(0.0)),
        data.quantity(),
        data.unit()
    );
    outln!("misfit {}", misfit_text(misfit));
    outln!(
        "all lines: RMS dB error {} (mean {}), RMS phase error {} deg, FRAC mean {:.4} / lowest {:.4}",
        sig(t.rms_db, 3),
        signed(t.mean_db, 3),
        sig(t.rms_phase_deg, 3),
        t.mean_frac,
        t.min_frac,
    );
    if t.lines_excluded > 0 {
        outln!("({} values left out: zero or not finite)", t.lines_excluded);
    }
    let worst = c.worst_channels(3);
    let mut table = Table::new(&[
        "channel",
        "RMS dB error",
        "mean dB error",
        "max |dB error| at Hz",
        "RMS phase error",
        "FRAC",
        "misfit",
        "share",
        "",
    ]);
    for (i, ch) in c.channels.iter().enumerate() {
        table.row(vec![
            ch.channel.to_string(),
            sig(ch.rms_db, 3),
            signed(ch.mean_db, 3),
            format!("{} @ {}", sig(ch.max_abs_db.0, 3), report::short(ch.max_abs_db.1)),
            sig(ch.rms_phase_deg, 3),
            format!("{:.4}", ch.frac),
            table::misfit(ch.log_misfit),
            report::percent(ch.share),
            if worst.contains(&i) { "<- worst".into() } else { String::new() },
        ]);
    }
    outln!("\nper channel (all its lines; worst by misfit)\n{}", table.render());
    let worst = c.worst_bands(3);
    let mut table =
        Table::new(&["band", "lines", "RMS dB error", "mean dB error", "RMS phase error", "misfit", "share", ""]);
    for (i, b) in c.bands.iter().enumerate() {
        table.row(vec![
            format!("{}: {}", i + 1, b.band.label()),
            b.lines.to_string(),
            sig(b.rms_db, 3),
            signed(b.mean_db, 3),
            sig(b.rms_phase_deg, 3),
            table::misfit(b.log_misfit),
            report::percent(b.share),
            if worst.contains(&i) { "<- worst".into() } else { String::new() },
        ]);
    }
    outln!("\nper band (worst by misfit)\n{}", table.render());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_options_parse_and_bad_ones_say_what_is_accepted() {
        assert_eq!(parse_bands("auto").unwrap(), BandSpec::Auto);
        assert_eq!(parse_bands("third-octave").unwrap(), BandSpec::Octave { fraction: 3 });
        assert_eq!(parse_bands("0, 50,120.5").unwrap(), BandSpec::Edges(vec![0.0, 50.0, 120.5]));
        let e = parse_bands("0,fifty").unwrap_err();
        assert!(e.contains("`fifty`") && e.contains("third-octave"), "{e}");
    }
}
