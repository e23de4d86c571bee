//! Writes `cases/tutorial/lap-joint-measured.uff`, the tutorial's test data
//! as a test system would export them: the accelerances of
//! `lap-joint-truth.toml` referenced to a shaker amplifier's voltage (an
//! unknown gain of 42 N/V at -30 degrees, units `(m/s^2)/V`), with 1 %
//! noise that grows where the coherence falls (below 20 Hz), the coherence
//! records attached, and the test's `+Z` for the model's `y`.
//!
//! `cargo run -p rfm-update --example lap_joint_data`

use std::error::Error;
use std::path::Path;

use damping::DampedSystem;
use fe_model::CaseFile;
use frf::io::uff::{self, DataAxis, Direction, Encoding, UffWriteOptions};
use frf::{Channel, FrfKind, NoiseModel};
use num_complex::Complex64 as C64;

/// Coherence of a line: near 1 above 40 Hz, falling to 0.3 at 2 Hz, as
/// with a shaker that hardly drives the beam at low frequency.
fn coherence(f: f64) -> f64 {
    0.995 - 0.7 * (-(f - 2.0) / 8.0).exp()
}

fn main() -> Result<(), Box<dyn Error>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases/tutorial");
    let case = CaseFile::load(dir.join("lap-joint-truth.toml"))?;
    let spec = case.measurement.as_ref().ok_or("no [measurement]")?;
    let truth = case.truth.as_ref().ok_or("no [truth]")?;
    let sys = DampedSystem::new(truth.model.clone())?;
    let channels: Vec<Channel> =
        spec.references.iter().flat_map(|&r| spec.responses.iter().map(move |&m| Channel::new(m, r))).collect();
    let clean = frf::synthesize(&sys, &channels, &spec.frequencies_hz)?.converted(FrfKind::Accelerance);
    // two independent 1 % realisations: the second scaled up where the coherence is low, so
    // that the relative noise is 1 % times sqrt((1 - g) / g) over its value at g = 0.995
    let (mut a, mut b) = (clean.clone(), clean.clone());
    NoiseModel { relative: truth.noise, floor: 0.0, seed: truth.seed }.apply(&mut a);
    NoiseModel { relative: truth.noise, floor: 0.0, seed: truth.seed + 1 }.apply(&mut b);
    let gain = C64::from_polar(42.0, (-30f64).to_radians());
    let ratio = |g: f64| ((1.0 - g) / g).sqrt() / ((1.0f64 - 0.995) / 0.995).sqrt();
    let mut set = clean.clone();
    let mut coh = Vec::new();
    let lines = clean.frequencies_hz().to_vec();
    for c in 0..channels.len() {
        for (k, &f) in lines.iter().enumerate() {
            let g = coherence(f);
            let extra = (ratio(g).powi(2) - 1.0).max(0.0).sqrt();
            let h = clean.get(c, k);
            set.set(c, k, gain * (h + (a.get(c, k) - h) + extra * (b.get(c, k) - h)));
            coh.push(g);
        }
    }
    set.set_coherence(coh)?;
    let mut functions = uff::frf_set_to_functions(&set, &UffWriteOptions::default())?;
    for f in &mut functions {
        f.header.ids[0] = "lap-joint beam, shaker test (rfm tutorial)".into();
        f.header.response.direction = Direction::Z;
        f.header.reference.direction = Direction::Z;
        if f.header.function_type == uff::FUNCTION_FRF {
            f.header.denominator = DataAxis::new(0, "Voltage", "V");
        }
    }
    let path = dir.join("lap-joint-measured.uff");
    std::fs::write(&path, uff::encode(&functions, Encoding::Ascii)?)?;
    println!("wrote {} ({} channels x {} lines)", path.display(), channels.len(), lines.len());
    Ok(())
}
