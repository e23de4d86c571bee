//! `rfm simulate`: synthesise FRFs on the case's measurement lines.

use std::path::Path;

use damping::DampedSystem;
use frf::{Channel, NoiseModel};

use super::{Result, load_case};
use crate::exit::Exit;
use crate::output::Outputs;

pub(crate) fn simulate(case: &Path, out: &Path, truth: bool, noise: f64, seed: u64) -> Result<Exit> {
    let case_file = load_case(case)?;
    let mut output = Outputs::file(out, &case_file.inputs())?;
    let spec =
        case_file.measurement.as_ref().ok_or("the case has no [measurement] section (which channels and lines?)")?;
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
    output.write_file(frf::io::csv::to_csv_string(&set).as_bytes())?;
    output.commit()?;
    outln!("wrote {} channels x {} lines ({}) to {}", set.channels().len(), set.n_freq(), set.kind(), out.display());
    Ok(Exit::Success)
}
