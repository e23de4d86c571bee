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
/// update converges within the verdict's 1.5 times the noise (seen: 0.99
/// to 1.13, against the noise read for each value on the fitted lines;
/// 0.84 to 1.39 against one level read as a median over the lines, and
/// 1.26 to 1.79 before the floor's level was read over `|H|` on every
/// line, 3 of the 4 "model inadequate").
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
        alike
            .set_floor_weights(vec![1.0; n * alike.n_freq()], vec![f64::NAN; n * alike.n_freq()], vec![1.0; n])
            .unwrap();
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

/// The noise level read from data at a floor over most lines of every
/// channel (and no coherence) is the noise they carry: the truth's
/// weighted misfit over the diagnosis's lines reads within 0.75 and 1.33
/// times it, read against the truth or against the nominal model, from a
/// floor at 3e-3 of each channel's peak to one at 3e-2 (the first
/// resonances alone stand above it). Before the noise of each value was
/// read from the floor, a single level read as a median over lines whose
/// weighted noise ranges from the threshold's down to a hundredth of it
/// put the truth at 6 times the noise at 3e-3 (seen: 0.0257 against
/// 0.0041), "model inadequate" for the right model.
#[test]
fn the_truth_reads_at_the_noise_read_from_data_at_a_floor() {
    for (floor, seed) in [(3e-3, 1), (3e-3, 2), (3e-2, 1), (3e-2, 2)] {
        let case = case();
        let data = measured(&case, floor, seed);
        let truth = damping::DampedSystem::new(case.truth.as_ref().unwrap().model.clone()).unwrap();
        let study = Study::with_measured(case, data).unwrap();
        let weights = study.line_weights(study.measured()).unwrap();
        let (m, w) = (study.measured(), weights.as_deref());
        let misfit = rfm_update::quantities::misfit(&truth, m, study.gains(), w).unwrap();
        let noise = rfm_update::quantities::noise(&truth, m, w).unwrap().unwrap();
        let against_nominal = rfm_update::quantities::noise(study.system(), m, w).unwrap().unwrap();
        println!(
            "{floor}/{seed}: the truth's misfit {misfit:.4}, noise {noise:.4} ({:.2} x; {against_nominal:.4} read against the nominal)",
            misfit / noise
        );
        assert!(w.is_some(), "{floor}/{seed}: no floor found");
        for n in [noise, against_nominal] {
            assert!(
                (0.75..=1.0 / 0.75).contains(&(misfit / n)),
                "{floor}/{seed}: the truth at {:.2} x the noise {n:.4}",
                misfit / n
            );
        }
    }
}

/// `rfm fix` on a floor over most lines: the case's own four parameters
/// are updated (step 0), found within 1 % of the truth, nothing is added,
/// and the loop ends at the noise (seen: 1.07 and 1.18 times it). Before
/// the noise of each value was read from the floor, the same loop ended
/// "model inadequate" at 6.3 times a noise level read low.
#[test]
fn the_loop_on_a_floor_over_most_lines_ends_at_the_noise_with_nothing_added() {
    use rfm_update::fix::{CONSISTENT, FixOptions, FixStop, fix};
    for seed in [1, 2] {
        let study = Study::with_measured(case(), measured(&case(), 3e-3, seed)).unwrap();
        let opts = FixOptions {
            max_steps: 2,
            diagnose: study.diagnose_options(study.measured()).unwrap(),
            ..FixOptions::default()
        };
        let outcome = fix(study.case(), study.measured(), &opts, |_| {}).unwrap();
        let d = outcome.declared.as_ref().expect("step 0");
        let ratio = outcome.final_misfit() / outcome.noise;
        println!("seed {seed}: {:.4} x the noise {:.4}, {:?}", ratio, outcome.noise, outcome.stop);
        for p in &d.parameters {
            // the moduli as the update's test holds them; the damping, read
            // on the resonances alone, within 5 % (seen: up to 1.8 %)
            let bound = if p.name.ends_with(".E") { 0.01 } else { 0.05 };
            let err = (p.updated / truth_of(&p.name) - 1.0).abs();
            assert!(err < bound, "{seed}: {} {:.2} % off", p.name, 100.0 * err);
        }
        assert!(
            outcome.effects.is_empty(),
            "{seed}: added {:?}",
            outcome.effects.iter().map(|e| &e.description).collect::<Vec<_>>()
        );
        assert!(ratio <= CONSISTENT, "{seed}: final misfit {ratio:.2} x the noise");
        assert_eq!(outcome.stop, FixStop::NothingSignificant, "{seed}");
    }
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
/// not asserted: on the update's 60 lines few values weigh above 0 (the
/// rest lie at the floor), and one of them 2.3 times its noise moves it
/// (seen: the fit leaves 0.99 and 1.56 times the noise on its lines, the
/// truth 1.36 and 1.45; against a single level read as a median over
/// the lines, 2.9 and 3.7).
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
