//! A case file and a measured file together through what the commands do:
//! loading, the study set-up (measured data read through the case's map and
//! mask, channels checked against the model, updating lines chosen), then
//! a compare (synthesis, correlation, modal estimation and pairing), an
//! update by each method and a diagnosis, with tiny budgets. Every input
//! must end in a value or an error, never a panic.
//!
//! The input is the case text, a line `@@@@`, then the measured file's
//! bytes. The harness writes the bytes to `m.csv` and `m.uff` beside the
//! case, so a case reads them with `data = "m.csv"` or `data = "m.uff"`.
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use frf::correlation::{BandSpec, correlate};
use libfuzzer_sys::fuzz_target;
use rfm_update::Study;
use rfm_update::diagnose::DiagnoseOptions;
use rfm_update::output_error::OeOptions;
use rfm_update::response_function::RfmOptions;

/// Larger models and data sets only cost time: the parsers and set-up are
/// exercised on small ones just as well.
const MAX_EQUATIONS: usize = 60;
const MAX_VALUES: usize = 4000;

fn folder() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("rfm-fuzz-commands-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a scratch folder");
        dir
    })
}

fuzz_target!(|bytes: &[u8]| {
    let split = bytes.windows(5).position(|w| w == b"\n@@@@");
    let (case, data) = match split {
        Some(i) => (&bytes[..i], bytes[i + 5..].strip_prefix(b"\n").unwrap_or(&bytes[i + 5..])),
        None => (bytes, &b""[..]),
    };
    let Ok(case) = std::str::from_utf8(case) else { return };
    let dir = folder();
    for name in ["m.csv", "m.uff"] {
        if std::fs::write(dir.join(name), data).is_err() {
            return;
        }
    }
    let Ok(case) = fe_model::CaseFile::parse(&dir.join("fuzz.toml"), case) else { return };
    let values =
        case.measurement.as_ref().map_or(0, |m| m.frequencies_hz.len() * m.references.len() * m.responses.len());
    if case.model.nodes().len() * 3 > MAX_EQUATIONS || values > MAX_VALUES {
        return;
    }
    let Ok(study) = Study::from_case(case) else { return };
    let measured = study.measured();
    if measured.n_freq() * measured.channels().len() > MAX_VALUES {
        return;
    }
    // compare
    if let Ok(model) = frf::synthesize(study.system(), measured.channels(), measured.frequencies_hz()) {
        let _ = correlate(measured, &model, &BandSpec::Auto);
    }
    if let (Some(&lo), Some(&hi)) = (measured.frequencies_hz().first(), measured.frequencies_hz().last()) {
        if let Ok(est) = frf::lscf(measured, &frf::LscfOptions::new(lo, hi)) {
            let modes = frf::measured_modes(&est);
            if let Ok(model) = frf::model_modes(study.system(), &est.responses, hi) {
                let _ = frf::pair_modes(&model, &modes, 0.5);
            }
        }
    }
    // update, both methods
    if !study.parameters().is_empty() {
        let _ = study.run_rfm(&RfmOptions { max_iterations: 2, ..Default::default() }, |_| {});
        if let Ok(opts) = study.output_error_options() {
            let _ = study.run_output_error(&OeOptions { max_iterations: 2, ..opts }, |_| {});
        }
    }
    // diagnose
    let opts = DiagnoseOptions {
        lines: 8,
        prescreen_lines: 4,
        prescreen_iterations: 1,
        screen_lines: 6,
        screen_iterations: 1,
        keep: 2,
        iterations: 2,
        ..Default::default()
    };
    let _ = rfm_update::diagnose::diagnose(&study.case().model, measured, &opts);
});
