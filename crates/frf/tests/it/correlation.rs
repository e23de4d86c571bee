//! FRF correlation on synthesised models against known truths: a uniform
//! gain, resonance bands at the natural frequencies, and where a frequency
//! shift shows.

use damping::DampedSystem;
use fe_model::{Dof, DofRef, samples};
use frf::correlation::{BandSpec, bands, correlate, resonances};
use frf::{Channel, FrfKind, synthesize};

fn channels() -> Vec<Channel> {
    let tip = DofRef::new(11, Dof::Uy);
    vec![Channel::new(tip, tip), Channel::new(DofRef::new(6, Dof::Uy), tip), Channel::new(DofRef::new(3, Dof::Uy), tip)]
}

fn lines() -> Vec<f64> {
    (1..=1600).map(|k| 0.25 * f64::from(k)).collect()
}

#[test]
fn scaling_stiffness_and_mass_together_is_a_uniform_gain_error() {
    // K, M and C = alpha K + beta M all scale by s, so Z scales by s and every
    // FRF by 1/s: -20 log10(s) dB at every line, no phase error, FRAC 1.
    let truth = DampedSystem::new(samples::cantilever(10)).unwrap();
    let mut model = truth.clone();
    let s = 1.25;
    for name in ["group.beam.stiffness", "group.beam.mass"] {
        let q = model.model().quantity(name).unwrap();
        model.set(q, model.get(q) * s).unwrap();
    }
    let f = lines();
    let x = synthesize(&truth, &channels(), &f).unwrap().converted(FrfKind::Accelerance);
    let a = synthesize(&model, &channels(), &f).unwrap();
    let r = correlate(&x, &a, &BandSpec::Auto).unwrap();
    let gain_db = -20.0 * s.log10();
    for (c, ch) in r.channels.iter().enumerate() {
        assert!((ch.mean_db - gain_db).abs() < 1e-6, "{}: {}", ch.channel, ch.mean_db);
        assert!((ch.rms_db - gain_db.abs()).abs() < 1e-6);
        assert!(ch.rms_phase_deg < 1e-6);
        assert!((ch.frac - 1.0).abs() < 1e-9);
        assert!(r.db_error(c).iter().all(|e| (e - gain_db).abs() < 1e-6));
    }
    assert_eq!(r.kind(), FrfKind::Accelerance);
    for b in &r.bands {
        assert!((b.mean_db - gain_db).abs() < 1e-6);
    }
}

#[test]
fn resonance_bands_are_centred_on_the_natural_frequencies() {
    let sys = DampedSystem::new(samples::cantilever(10)).unwrap();
    let f = lines();
    let h = synthesize(&sys, &channels(), &f).unwrap();
    let natural: Vec<f64> = damping::normal_modes(sys.assembly())
        .unwrap()
        .frequencies_hz
        .into_iter()
        .filter(|&x| x > f[0] && x < f[f.len() - 1])
        .collect();
    assert!(natural.len() >= 4, "{natural:?}");
    let peaks = resonances(&h);
    assert_eq!(peaks.len(), natural.len(), "peaks {peaks:?}, natural {natural:?}");
    for (p, n) in peaks.iter().zip(&natural) {
        // light damping: the peak is within a line or two of the undamped frequency
        assert!((p - n).abs() <= 0.6, "peak {p} Hz vs natural {n} Hz");
    }
    let b = bands(&BandSpec::Auto, &h).unwrap();
    assert_eq!(b.len(), natural.len());
    for (band, n) in b.iter().zip(&natural) {
        assert!(band.lo_hz < *n && *n < band.hi_hz, "{} does not hold {n} Hz", band.label());
    }
}

#[test]
fn a_stiffness_error_shows_at_the_shifted_resonances() {
    let truth = DampedSystem::new(samples::cantilever(10)).unwrap();
    let mut model = truth.clone();
    let q = model.model().quantity("material.steel.E").unwrap();
    model.set(q, model.get(q) * 1.1).unwrap();
    let f = lines();
    let x = synthesize(&truth, &channels(), &f).unwrap();
    let a = synthesize(&model, &channels(), &f).unwrap();
    let r = correlate(&x, &a, &BandSpec::Auto).unwrap();
    let natural = |s: &DampedSystem| damping::normal_modes(s.assembly()).unwrap().frequencies_hz;
    let marks: Vec<f64> = natural(&truth).into_iter().chain(natural(&model)).filter(|&v| v < 400.0).collect();
    // the ten lines with the largest error all lie at a resonance of the truth or of the model
    let mut order: Vec<usize> = (0..f.len()).collect();
    order.sort_by(|&i, &j| r.lines[j].rms_db.total_cmp(&r.lines[i].rms_db));
    for &k in &order[..10] {
        let near = marks.iter().map(|m| (m - f[k]).abs() / m).fold(f64::INFINITY, f64::min);
        assert!(near < 0.03, "large error at {} Hz, away from every resonance {marks:?}", f[k]);
    }
    // shifted peaks change the shape: FRAC well below 1; identical data: 1
    assert!(r.total.min_frac < 0.9, "{}", r.total.min_frac);
    let same = correlate(&x, &x, &BandSpec::Auto).unwrap();
    assert!((same.total.min_frac - 1.0).abs() < 1e-12 && same.total.log_misfit == 0.0);
}
