//! `rfm`: compare, update and simulate FE models of damped structures against
//! measured FRFs. Run `rfm --help`.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{CommandFactory as _, FromArgMatches as _, Parser, Subcommand};

use rfm_cli::{Exit, FrequencyScale, ReportOptions};

/// FE model updating of damped structures from measured FRFs (response
/// function method with exponential non-viscous damping).
#[derive(Parser)]
#[command(name = "rfm", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Synthesise the model's FRFs (or the truth's) on the case's measurement lines.
    Simulate {
        /// Case file.
        case: PathBuf,
        /// Output file: .uff or .unv for UFF dataset 58, .csv for CSV.
        #[arg(long)]
        out: PathBuf,
        /// Use the case's truth model instead of the initial model.
        #[arg(long)]
        truth: bool,
        /// Relative complex noise level (0.01 = 1 %).
        #[arg(long, default_value_t = 0.0)]
        noise: f64,
        /// Random seed of the noise.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// FRF kind written: receptance, mobility or accelerance.
        #[arg(long, default_value = "receptance")]
        kind: String,
        /// Write UFF as binary 58b instead of ASCII.
        #[arg(long)]
        binary: bool,
        /// Print what was written as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Compare the case's model with the measured FRFs: errors per channel and band, overlays, a report.
    Compare {
        /// Case file.
        case: PathBuf,
        /// Measured FRF file(s) to use instead of the case's data (channels of several files are joined).
        #[arg(long, value_name = "FILE")]
        measured: Vec<PathBuf>,
        /// Folder for the report (report.html, compare.json, SVG figures, CSV tables).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Replace the --out folder even when another command's results are in it.
        #[arg(long)]
        replace: bool,
        /// Print machine-readable JSON instead of tables.
        #[arg(long)]
        json: bool,
        /// Frequency bands: auto, resonances, octave, third-octave, or edges in Hz such as 0,50,120,400.
        #[arg(long, default_value = "auto")]
        bands: String,
        /// Frequency axis of the report's figures: auto (logarithmic for bands of a decade or more), log or linear.
        #[arg(long, value_enum, default_value = "auto")]
        frequency_axis: FrequencyScale,
    },
    /// Find which physical effect is missing: fit every candidate effect and rank them.
    Diagnose {
        /// Case file.
        case: PathBuf,
        /// Measured FRFs (default: the case's data or truth).
        #[arg(long)]
        measured: Option<PathBuf>,
        /// Print machine-readable JSON instead of tables.
        #[arg(long)]
        json: bool,
        /// Write the case with the effect of this rank added (needs --out; with --measured, the new case reads that file).
        #[arg(long)]
        apply: Option<usize>,
        /// New case file for --apply.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Folder for a report of the ranking (report.html, the structure with the leaders marked, ranking.csv).
        #[arg(long, value_name = "DIR")]
        report: Option<PathBuf>,
        /// Replace the --report folder even when another command's results are in it.
        #[arg(long)]
        replace: bool,
        /// Frequency axis of the report's figures: auto (logarithmic for bands of a decade or more), log or linear.
        #[arg(long, value_enum, default_value = "auto")]
        frequency_axis: FrequencyScale,
        /// Rows of the ranking to print.
        #[arg(long, default_value_t = 10)]
        top: usize,
        /// Print each stage of the search with its time on standard error.
        #[arg(long)]
        verbose: bool,
    },
    /// Close the loop: diagnose, add the recommended effect, update, and again
    /// until nothing significant remains; the case after every step and a report.
    Fix {
        /// Case file.
        case: PathBuf,
        /// Folder for step-0.toml (the case's own parameters updated), step-1.toml, ..., results.json, report.html and figures.
        #[arg(long)]
        out: PathBuf,
        /// Measured FRF file to use instead of the case's data or truth (every step's case then reads it).
        #[arg(long, value_name = "FILE")]
        measured: Option<PathBuf>,
        /// Most effects to add (counting those of a resumed run).
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=20))]
        steps: u64,
        /// Go on from the steps an interrupted run left in --out.
        #[arg(long)]
        resume: bool,
        /// Replace the --out folder even when another command's results are in it.
        #[arg(long)]
        replace: bool,
        /// Print machine-readable JSON instead of tables.
        #[arg(long)]
        json: bool,
        /// Frequency axis of the report's figures: auto (logarithmic for bands of a decade or more), log or linear.
        #[arg(long, value_enum, default_value = "auto")]
        frequency_axis: FrequencyScale,
    },
    /// List what a measurement file holds (UFF dataset 58 or CSV): channels,
    /// function types, units, frequency lines, data types; skipped datasets.
    Inspect {
        /// Measurement file (.uff, .unv, .58, .csv, ...).
        file: PathBuf,
        /// Print machine-readable JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Update the model's parameters so that its FRFs match the measured ones.
    Update {
        /// Case file.
        case: PathBuf,
        /// Folder for results (results.json, updated.toml, report.html, SVG figures and CSV tables).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Measured FRF file to use instead of the case's data or truth (updated.toml then reads it).
        #[arg(long, value_name = "FILE")]
        measured: Option<PathBuf>,
        /// Replace the --out folder even when another command's results are in it.
        #[arg(long)]
        replace: bool,
        /// Print machine-readable JSON instead of tables.
        #[arg(long)]
        json: bool,
        /// Updating method (default: the case's, else rfm).
        #[arg(long, value_parser = ["rfm", "output-error"])]
        method: Option<String>,
        /// Fit this many measured lines spread over the band (overrides the case).
        #[arg(long)]
        lines: Option<usize>,
        /// Iteration limit (overrides the case).
        #[arg(long)]
        iterations: Option<usize>,
        /// Frequency axis of the report's figures: auto (logarithmic for bands of a decade or more), log or linear.
        #[arg(long, value_enum, default_value = "auto")]
        frequency_axis: FrequencyScale,
    },
}

fn main() -> ExitCode {
    // Without a handler the signal would end the process at once, leaving
    // its staging folder behind for the next run to clean.
    let interrupt = ctrlc::set_handler(|| {
        let (_held, written, kept) = rfm_cli::interrupt_outputs();
        if written {
            eprintln!("interrupted after this run's outputs were written");
        } else if let Some(kept) = kept {
            eprintln!("interrupted: {kept}; the rest of this run was not written");
        } else {
            eprintln!("interrupted: the outputs of this run were not written (earlier ones are untouched)");
        }
        std::process::exit(i32::from(Exit::Interrupted.code()));
    });
    if let Err(e) = interrupt {
        eprintln!(
            "warning: cannot handle Ctrl-C ({e}); an interrupt may leave a staging folder for the next run to remove"
        );
    }
    // clap exits with 2 (Exit::Usage) on a wrong command line, 0 for --help
    let matches = Cli::command().after_help(Exit::help()).get_matches();
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    // A panic is a bug; it must still end with the documented code, after
    // the default hook has printed where it happened (unwinding has removed
    // any staging folder on the way).
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(cli))).unwrap_or_else(|_| {
        Err(rfm_cli::Failure::new(
            Exit::Internal,
            "internal error (a bug in rfm): please report it with the command and its input files",
        ))
    });
    match result {
        Ok(exit) => ExitCode::from(exit.code()),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit.code())
        }
    }
}

fn run(cli: Cli) -> rfm_cli::Result<Exit> {
    match cli.command {
        Command::Simulate { case, out, truth, noise, seed, kind, binary, json } => {
            rfm_cli::simulate(&rfm_cli::SimulateArgs {
                case: &case,
                out: &out,
                truth,
                noise,
                seed,
                kind: &kind,
                binary,
                json,
            })
        }
        Command::Compare { case, measured, out, replace, json, bands, frequency_axis } => {
            rfm_cli::compare(&rfm_cli::CompareArgs {
                case: &case,
                measured: &measured,
                out: out.as_deref(),
                replace,
                json,
                bands: &bands,
                report: ReportOptions { frequency_scale: frequency_axis, ..Default::default() },
            })
        }
        Command::Diagnose {
            case,
            measured,
            json,
            apply,
            out,
            report: report_dir,
            replace,
            frequency_axis,
            top,
            verbose,
        } => rfm_cli::diagnose(&rfm_cli::DiagnoseArgs {
            case: &case,
            measured: measured.as_deref(),
            json,
            apply,
            out: out.as_deref(),
            top,
            verbose,
            report: report_dir.as_deref(),
            replace,
            report_options: ReportOptions { frequency_scale: frequency_axis, ..Default::default() },
        }),
        Command::Fix { case, out, measured, steps, resume, replace, json, frequency_axis } => {
            rfm_cli::fix(&rfm_cli::FixArgs {
                case: &case,
                out: &out,
                measured: measured.as_deref(),
                steps: steps as usize,
                json,
                replace,
                resume,
                report: ReportOptions { frequency_scale: frequency_axis, ..Default::default() },
            })
        }
        Command::Inspect { file, json } => rfm_cli::inspect(&file, json),
        Command::Update { case, out, measured, replace, json, method, lines, iterations, frequency_axis } => {
            rfm_cli::update(
                &case,
                measured.as_deref(),
                out.as_deref(),
                replace,
                json,
                &rfm_cli::UpdateOverrides { method, lines, max_iterations: iterations },
                &ReportOptions { frequency_scale: frequency_axis, ..Default::default() },
            )
        }
    }
}
