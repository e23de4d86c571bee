//! `rfm`: compare, update and simulate FE models of damped structures against
//! measured FRFs. Run `rfm --help`.

mod commands;
mod report;
mod table;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

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
        /// Output CSV file.
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
    },
    /// Compare the case's model with the measured FRFs: errors per channel and band, overlays, a report.
    Compare {
        /// Case file.
        case: PathBuf,
        /// Measured FRF file(s) to use instead of the case's data (channels of several files are joined).
        #[arg(long, value_name = "FILE")]
        measured: Vec<PathBuf>,
        /// Folder for the report (report.html, compare.json, SVG figures).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print machine-readable JSON instead of tables.
        #[arg(long)]
        json: bool,
        /// Frequency bands: auto, resonances, octave, third-octave, or edges in Hz such as 0,50,120,400.
        #[arg(long, default_value = "auto")]
        bands: String,
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
        /// Write the case with the effect of this rank added (needs --out).
        #[arg(long)]
        apply: Option<usize>,
        /// New case file for --apply.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Rows of the ranking to print.
        #[arg(long, default_value_t = 10)]
        top: usize,
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
        /// Folder for results (results.json, updated.toml, report.html and SVG figures).
        #[arg(long)]
        out: Option<PathBuf>,
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
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Simulate { case, out, truth, noise, seed } => commands::simulate(&case, &out, truth, noise, seed),
        Command::Compare { case, measured, out, json, bands } => {
            commands::compare(&case, &measured, out.as_deref(), json, &bands)
        }
        Command::Diagnose { case, measured, json, apply, out, top } => commands::diagnose(&commands::DiagnoseArgs {
            case: &case,
            measured: measured.as_deref(),
            json,
            apply,
            out: out.as_deref(),
            top,
        }),
        Command::Inspect { file, json } => commands::inspect(&file, json),
        Command::Update { case, out, json, method, lines, iterations } => commands::update(
            &case,
            out.as_deref(),
            json,
            &commands::UpdateOverrides { method, lines, max_iterations: iterations },
        ),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
