//! Data whose noise is an additive floor (a constant level per channel, as
//! an acquisition's noise floor or an independent generator's "noise at a
//! fraction of the peak" makes it), not relative to the FRF: where the FRF
//! falls to the floor, at antiresonances and above the first modes of a
//! receptance, the logarithm of the data is the noise's, and a fit that
//! weighs those lines as the others chases it. Before the floor's lines
//! were weighted down (`frf::noise::floor_weights`), a floor at 1e-6 of
//! the peak left the update of this strip at 18 times the noise, "model
//! inadequate", with its moduli 1 % off, and a floor at 3e-3 ran them to
//! 7 and 0.1 times the truth, each "well determined".

use std::path::Path;

use fe_model::CaseFile;
use num_complex::Complex64 as C64;
use rfm_update::Study;
use rfm_update::status::Status;

const CASE: &str = r#"
title = "two-material strip"
[materials]
a = { E = 2.1e11, rho = 7850 }
b = { E = 2.1e11, rho = 7850 }
[sections]
strip = { b = 0.04, h = 0.006 }
[groups.beam]
alpha = 2.0e-6
beta = 0.5
[[lines]]
from = [0.0, 0.0]
to = [0.4, 0.0]
elements = 4
material = "a"
section = "strip"
group = "beam"
[[lines]]
from = 5
to = [0.8, 0.0]
elements = 4
material = "b"
section = "strip"
group = "beam"
[[supports]]
node = 1
[measurement]
frequencies = { from = 5.0, to = 400.0, step = 0.5 }
references = ["9:uy"]
responses = ["3:uy", "5:uy", "7:uy", "9:uy"]
[truth]
noise = 0.0
[truth.set]
"material.a.E" = 2.2e11
"material.b.E" = 2.0e11
"group.beam.alpha" = 3.0e-6
"group.beam.beta" = 0.6
[update]
parameters = ["material.a.E", "material.b.E", "group.beam.alpha", "group.beam.beta"]
frequencies = { auto = 60 }
method = "output-error"
"#;

/// SplitMix64, then Box-Muller: an independent source of normal numbers.
struct Normal(u64);

impl Normal {
    fn next_u(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn complex(&mut self) -> C64 {
        let (u, v) = (self.next_u(), self.next_u());
        let r = (-2.0 * u.ln()).sqrt() * std::f64::consts::FRAC_1_SQRT_2;
        C64::from_polar(r, 2.0 * std::f64::consts::PI * v)
    }
}

/// The truth's values (the case's `[truth.set]`).
fn truth_of(name: &str) -> f64 {
    match name {
        "material.a.E" => 2.2e11,
        "material.b.E" => 2.0e11,
        "group.beam.alpha" => 3.0e-6,
        "group.beam.beta" => 0.6,
        _ => panic!("{name} is not updated"),
    }
}

fn case() -> CaseFile {
    CaseFile::parse(Path::new("strip.toml"), CASE).unwrap()
}

/// The truth's receptances plus complex Gaussian noise of RMS `floor`
/// times each channel's peak modulus, of seed `seed`.
fn measured(case: &CaseFile, floor: f64, seed: u64) -> frf::FrfSet {
    let clean = crate::truth_receptances(case);
    let mut rng = Normal(seed * 7919);
    let mut measured = clean.clone();
    for c in 0..clean.channels().len() {
        let peak = clean.channel(c).iter().map(|h| h.norm()).fold(0.0, f64::max);
        for k in 0..clean.n_freq() {
            measured.set(c, k, clean.get(c, k) + floor * peak * rng.complex());
        }
    }
    measured
}

/// What an update of the strip's four parameters makes of `data`.
struct Fit {
    /// `ln(updated / truth)` over the reported standard deviation, and
    /// the relative error, of each well-determined parameter.
    z: Vec<(String, f64, f64)>,
    ratio: f64,
    status: Status,
    notes: Vec<String>,
}

fn fit(data: frf::FrfSet) -> Fit {
    let study = Study::with_measured(case(), data).unwrap();
    let o = study.run_output_error(&study.output_error_options().unwrap(), |_| {}).unwrap();
    let unc = o.uncertainty.as_ref().unwrap();
    let z = o
        .parameters
        .iter()
        .zip(&unc.parameters)
        .filter(|(_, u)| u.well_determined)
        .map(|(p, u)| {
            let t = truth_of(&p.name);
            (p.name.clone(), (p.updated / t).ln() / u.relative_std, (p.updated / t - 1.0).abs())
        })
        .collect();
    Fit { z, ratio: o.noise_ratio.unwrap(), status: o.status, notes: study.notes().to_vec() }
}

/// A floor at 1e-6 and 1e-5 of each channel's peak (two seeds each): the
/// lines at it are found and weighed down, the moduli come within 0.5 %
/// (1 % at 1e-5; seen: up to 0.54 %) of the truth and within 3 of their standard deviations
/// (and every other parameter the data determine within 3), and the
/// update converges within the verdict's 1.5 times the noise (seen: 0.84
/// to 1.39; before the floor's level was read over `|H|` on every line,
/// 1.26 to 1.79, 3 of the 4 "model inadequate").
/// The same data fitted with every line weighted alike (floor weights of
/// 1 attached beforehand, which the study then keeps) end "model
/// inadequate" at over 5 times the noise (seen: 7.6 to 22), the
/// difference between the right model and the floor's lines: the test
/// tells the weighting from its absence.
#[test]
fn the_lines_at_a_noise_floor_are_weighed_down_and_the_update_finds_the_truth() {
    for (floor, seed) in [(1e-6, 1), (1e-6, 2), (1e-5, 1), (1e-5, 2)] {
        // the moduli's error, as the floor's lines carry less
        let bound = if floor < 5e-6 { 0.005 } else { 0.01 };
        let data = measured(&case(), floor, seed);
        let f = fit(data.clone());
        println!("{floor}/{seed}: {:?}, {:.2} x noise ({:?})", f.z, f.ratio, f.status);
        assert!(f.notes.iter().any(|n| n.contains("noise floor")), "{floor}/{seed}: notes {:?}", f.notes);
        for (name, z, err) in &f.z {
            assert!(z.abs() <= 3.0, "{floor}/{seed}: {name} {z:.2} standard deviations off");
            if name.ends_with(".E") {
                assert!(*err < bound, "{floor}/{seed}: {name} {:.2} % off", 100.0 * err);
            }
        }
        assert!(f.z.iter().filter(|(n, ..)| n.ends_with(".E")).count() == 2, "{floor}/{seed}: {:?}", f.z);
        assert!(f.ratio <= 1.5, "{floor}/{seed}: {:.2} times the noise ({:?})", f.ratio, f.status);
        assert_eq!(f.status, Status::Converged, "{floor}/{seed}");
        let mut alike = data;
        let n = alike.channels().len();
        alike.set_floor_weights(vec![1.0; n * alike.n_freq()], vec![1.0; n]).unwrap();
        let g = fit(alike);
        assert!(g.ratio > 5.0, "{floor}/{seed}: weighted alike, {:.2} times the noise", g.ratio);
        assert_ne!(g.status, Status::Converged);
    }
}

/// Relative noise alone (1 %, the project's own generator): no line is
/// at a floor, and the study weighs every line alike.
#[test]
fn relative_noise_has_no_floor_weights() {
    let case = case();
    let mut data = crate::truth_receptances(&case);
    frf::NoiseModel::relative(0.01, 5).apply(&mut data);
    let study = Study::with_measured(case, data).unwrap();
    assert!((0..study.measured().channels().len()).all(|c| study.measured().floor_weights(c).is_none()));
    assert!(study.weights(study.measured()).unwrap().is_none());
}

/// A floor at 3e-3 of each channel's peak, as a generator that adds noise
/// at a fraction of the peak makes it: the strip's receptance falls below
/// it on 85 to 96 % of the lines, and only the first resonances stand out.
/// Before the floor's level was read over `|H|` on every line (the lines
/// beside the resonances, and those a scattered local reading left at
/// weight 1, kept the noise's logarithm in the fit), the update ran the
/// moduli to 7.2 and 0.16 times the truth (seed 1), 12 and 9 standard
/// deviations off. The moduli now come within 1 %
/// of the truth and within 3 of their standard deviations. The misfit is
/// not asserted: the noise level read beside so many weighted lines is
/// low (seen: the fit leaves 2.9 and 3.7 times it, "model inadequate"), a known
/// shortfall the docs name.
#[test]
fn a_floor_over_most_lines_leaves_the_moduli_to_the_resonances() {
    for seed in [1, 2] {
        let f = fit(measured(&case(), 3e-3, seed));
        assert!(f.notes.iter().any(|n| n.contains("noise floor")), "{seed}: notes {:?}", f.notes);
        let moduli: Vec<&(String, f64, f64)> = f.z.iter().filter(|(n, ..)| n.ends_with(".E")).collect();
        println!("seed {seed}: {moduli:?}, {:.2} x noise ({:?})", f.ratio, f.status);
        assert_eq!(moduli.len(), 2, "{seed}: {:?}", f.z);
        for (name, z, err) in moduli {
            assert!(z.abs() <= 3.0 && *err < 0.01, "{seed}: {name} {z:.2} sd and {:.2} % off", 100.0 * err);
        }
    }
}
