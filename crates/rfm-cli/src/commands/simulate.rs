//! `rfm simulate`: synthesise FRFs on the case's measurement lines.

use std::path::Path;

use damping::DampedSystem;
use frf::{Channel, NoiseModel};

use super::{Result, load_case};

pub(crate) fn simulate(case: &Path, out: &Path, truth: bool, noise: f64, seed: u64) -> Result<()> {
    crate::files_to_write();
    let case_file = load_case(case)?;
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
    let _writing = crate::writing();
    frf::io::atomic_write(out, frf::io::csv::to_csv_string(&set).as_bytes(), &case_file.inputs())?;
    outln!("wrote {} channels x {} lines ({}) to {}", set.channels().len(), set.n_freq(), set.kind(), out.display());
    Ok(())
}
