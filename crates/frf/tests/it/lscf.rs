//! LSCF / pLSCF with LSFD against the model's exact complex modes
//! (`damping::complex_modes`), on synthesised receptances with and without
//! seeded noise.

use damping::{ComplexMode, DampedSystem, complex_modes};
use fe_model::{Dof, DofRef, samples};
use frf::lscf::{LscfError, PoleStatus};
use frf::{C64, Channel, FrfKind, FrfSet, LscfOptions, ModalEstimate, NoiseModel, equation_of, lscf, synthesize};

/// Lines `lo, lo + df, ..., hi` (Hz).
fn lines(lo: f64, hi: f64, df: f64) -> Vec<f64> {
    let n = ((hi - lo) / df).round() as usize;
    (0..=n).map(|k| lo + k as f64 * df).collect()
}

fn grid(responses: &[DofRef], references: &[DofRef]) -> Vec<Channel> {
    responses.iter().flat_map(|&r| references.iter().map(move |&q| Channel::new(r, q))).collect()
}

/// The cantilever's measured channels of the paper: "2..31:uy" over "31:uy".
fn cantilever_channels() -> Vec<Channel> {
    let tip = DofRef::new(31, Dof::Uy);
    (2..=31).map(|n| Channel::new(DofRef::new(n, Dof::Uy), tip)).collect()
}

fn frame_responses() -> [DofRef; 5] {
    [
        DofRef::new(2, Dof::Ux),
        DofRef::new(2, Dof::Uy),
        DofRef::new(3, Dof::Rz),
        DofRef::new(4, Dof::Ux),
        DofRef::new(4, Dof::Uy),
    ]
}

/// The model's oscillatory modes inside `[lo, hi]` Hz.
fn truth_in(sys: &DampedSystem, lo: f64, hi: f64) -> Vec<ComplexMode> {
    complex_modes(sys).unwrap().oscillatory.into_iter().filter(|m| m.frequency_hz > lo && m.frequency_hz < hi).collect()
}

/// Asserts one estimated mode per true mode and returns the worst relative
/// frequency and damping errors.
fn compare(name: &str, est: &ModalEstimate, truth: &[ComplexMode], tol_f: f64, tol_zeta: f64) -> (f64, f64) {
    let found: Vec<f64> = est.modes.iter().map(|m| m.frequency_hz).collect();
    assert_eq!(est.modes.len(), truth.len(), "{name}: found {found:?}");
    let (mut ef, mut ez): (f64, f64) = (0.0, 0.0);
    for (m, t) in est.modes.iter().zip(truth) {
        let df = (m.frequency_hz - t.frequency_hz).abs() / t.frequency_hz;
        let dz = (m.damping_ratio - t.damping_ratio).abs() / t.damping_ratio;
        assert!(df < tol_f, "{name}: {} Hz vs {} Hz ({df:.1e})", m.frequency_hz, t.frequency_hz);
        assert!(
            dz < tol_zeta,
            "{name}: zeta {} vs {} ({dz:.1e}) at {} Hz",
            m.damping_ratio,
            t.damping_ratio,
            t.frequency_hz
        );
        ef = ef.max(df);
        ez = ez.max(dz);
    }
    eprintln!("{name}: {} modes, worst errors: frequency {ef:.1e}, damping ratio {ez:.1e}", truth.len());
    (ef, ez)
}

/// The shape at the responses against the model's `phi` there (scale
/// included: both use `phi^T Z' phi = 1`): asserts a MAC above 0.999 and
/// returns the worst relative error.
fn shape_error(sys: &DampedSystem, est: &ModalEstimate, truth: &[ComplexMode]) -> f64 {
    let mut worst: f64 = 0.0;
    for (m, t) in est.modes.iter().zip(truth) {
        assert!(m.scaled);
        let phi: Vec<C64> = est.responses.iter().map(|&d| t.shape[equation_of(sys, d).unwrap()]).collect();
        // the sign of a shape is arbitrary
        let dot: C64 = m.shape.iter().zip(&phi).map(|(a, b)| a * b.conj()).sum();
        let sign = if dot.re < 0.0 { -1.0 } else { 1.0 };
        let num: f64 = m.shape.iter().zip(&phi).map(|(a, b)| (a * sign - b).norm_sqr()).sum();
        let den: f64 = phi.iter().map(|b| b.norm_sqr()).sum();
        worst = worst.max((num / den).sqrt());
        let mac = frf::mac(&m.shape, &phi);
        assert!(mac > 0.999, "MAC {mac} at {} Hz", t.frequency_hz);
    }
    worst
}

#[test]
fn cantilever_poles_and_shapes_from_clean_receptances() {
    let sys = DampedSystem::new(samples::two_material_cantilever()).unwrap();
    let freqs = lines(1.0, 400.0, 0.1);
    let h = synthesize(&sys, &cantilever_channels(), &freqs).unwrap();
    let mut opts = LscfOptions::new(1.0, 400.0);
    opts.orders = 4..=30;
    let est = lscf(&h, &opts).unwrap();
    let truth = truth_in(&sys, 1.0, 400.0);
    assert_eq!(truth.len(), 5);
    compare("cantilever, clean", &est, &truth, 1e-3, 2e-2);
    let e = shape_error(&sys, &est, &truth);
    eprintln!("cantilever, clean: worst scaled-shape error {e:.1e}");
    // the fifth mode (293 Hz) has the sixth (423 Hz) just above the band,
    // which the constant upper residual only approximates
    assert!(e < 3e-2, "scaled shapes differ from the model's by {e:.1e}");
    // the LSFD synthesis reproduces the data up to the real (relaxation)
    // poles it does not model
    let fit = est.fit_error.iter().copied().fold(0.0, f64::max);
    assert!(fit < 2e-2, "LSFD misfit {fit:.1e}");
}

#[test]
fn cantilever_poles_with_two_percent_noise() {
    let sys = DampedSystem::new(samples::two_material_cantilever()).unwrap();
    let freqs = lines(1.0, 400.0, 0.1);
    let clean = synthesize(&sys, &cantilever_channels(), &freqs).unwrap();
    let truth = truth_in(&sys, 1.0, 400.0);
    let mut opts = LscfOptions::new(1.0, 400.0);
    opts.orders = 4..=30;
    for seed in [11, 12] {
        let mut h = clean.clone();
        NoiseModel::relative(0.02, seed).apply(&mut h);
        let est = lscf(&h, &opts).unwrap();
        compare(&format!("cantilever, 2 % noise, seed {seed}"), &est, &truth, 5e-3, 0.10);
    }
}

#[test]
fn frame_poles_with_one_and_two_references_clean_and_noisy() {
    // The L-frame's first two modes (7.6 and 19.8 Hz, half-power bandwidths
    // of 0.06 and 0.27 Hz) are analysed in their own band with fine lines,
    // the next three in a wide band: a z-domain polynomial over 0-1000 Hz
    // cannot resolve modes in its lowest percent once there is noise.
    let sys = DampedSystem::new(samples::frame_with_joint()).unwrap();
    let tip = DofRef::new(4, Dof::Uy);
    let corner = DofRef::new(2, Dof::Ux);
    // The residues near the top of the wide band are a few percent off: the
    // sixth mode (1352 Hz, 7.6 % damping) is represented by the constant
    // upper residual only.
    for (lo, hi, df, shape_tol) in [(1.0, 40.0, 0.01, 1e-3), (40.0, 1000.0, 0.25, 5e-2)] {
        let truth = truth_in(&sys, lo, hi);
        for refs in [vec![tip], vec![tip, corner]] {
            let channels = grid(&frame_responses(), &refs);
            let clean = synthesize(&sys, &channels, &lines(lo, hi, df)).unwrap();
            let mut opts = LscfOptions::new(lo, hi);
            opts.orders = 2..=if refs.len() == 1 { 30 } else { 20 };
            let name = format!("L-frame {lo}-{hi} Hz, {} reference(s)", refs.len());
            let est = lscf(&clean, &opts).unwrap();
            compare(&format!("{name}, clean"), &est, &truth, 1e-3, 2e-2);
            assert_eq!(est.references, refs);
            for m in &est.modes {
                assert_eq!(m.participation.len(), refs.len());
            }
            let e = shape_error(&sys, &est, &truth);
            eprintln!("{name}, clean: worst scaled-shape error {e:.1e}");
            assert!(e < shape_tol, "{name}: scaled shapes differ from the model's by {e:.1e}");
            let mut noisy = clean.clone();
            NoiseModel::relative(0.02, 5).apply(&mut noisy);
            let est = lscf(&noisy, &opts).unwrap();
            compare(&format!("{name}, 2 % noise"), &est, &truth, 5e-3, 0.10);
        }
    }
}

#[test]
fn lsfd_residues_of_a_viscous_two_dof_system_are_phi_phi_t() {
    // With viscous damping and every mode in the band, the receptance is
    // exactly the sum of the two modes: the residual terms vanish and the
    // residues are phi_o phi_i of the model's normalisation.
    let sys = DampedSystem::new(samples::two_dof_oscillator()).unwrap();
    let (a, b) = (DofRef::new(1, Dof::Ux), DofRef::new(2, Dof::Ux));
    let channels = grid(&[a, b], &[b]);
    let h = synthesize(&sys, &channels, &lines(0.2, 20.0, 0.01)).unwrap();
    let mut opts = LscfOptions::new(0.2, 20.0);
    opts.orders = 2..=12;
    let est = lscf(&h, &opts).unwrap();
    let truth = truth_in(&sys, 0.2, 20.0);
    compare("2-DOF", &est, &truth, 1e-8, 1e-6);
    let mut worst: f64 = 0.0;
    for (m, t) in est.modes.iter().zip(&truth) {
        for (c, ch) in channels.iter().enumerate() {
            let r = t.residue(equation_of(&sys, ch.response).unwrap(), equation_of(&sys, ch.reference).unwrap());
            worst = worst.max((m.residues[c] - r).norm() / r.norm());
        }
    }
    eprintln!("2-DOF: worst residue error {worst:.1e}, fit error {:.1e}", est.fit_error[0]);
    assert!(worst < 1e-6, "residues off by {worst:.1e}");
    for c in 0..channels.len() {
        assert!(est.fit_error[c] < 1e-6);
        let scale = h.channel(c).iter().map(|v| v.norm()).fold(0.0, f64::max);
        assert!(est.upper_residuals[c].norm() < 1e-8 * scale);
    }
}

#[test]
fn the_stabilisation_data_holds_every_order_and_the_selected_poles_are_stable() {
    let sys = DampedSystem::new(samples::frame_with_joint()).unwrap();
    let channels = grid(&frame_responses(), &[DofRef::new(4, Dof::Uy)]);
    let mut h = synthesize(&sys, &channels, &lines(40.0, 1000.0, 0.25)).unwrap();
    NoiseModel::relative(0.02, 9).apply(&mut h);
    let mut opts = LscfOptions::new(40.0, 1000.0);
    opts.orders = 2..=30;
    let est = lscf(&h, &opts).unwrap();
    let orders: Vec<usize> = est.stabilisation.iter().map(|o| o.order).collect();
    assert_eq!(orders, (2..=30).collect::<Vec<_>>());
    // the first order has nothing to compare with
    assert!(est.stabilisation[0].poles.iter().all(|p| p.status == PoleStatus::New));
    // some poles of the diagram were rejected (noise poles at high orders)
    let unstable = est.stabilisation.iter().flat_map(|o| &o.poles).filter(|p| p.status != PoleStatus::Stable).count();
    assert!(unstable > 0);
    for m in &est.modes {
        assert!(m.stable_orders >= 8, "{} Hz stable in {} orders", m.frequency_hz, m.stable_orders);
        // the selected pole is in the diagram, with status Stable
        let there =
            est.stabilisation.iter().flat_map(|o| &o.poles).any(|p| p.pole == m.pole && p.status == PoleStatus::Stable);
        assert!(there);
    }
    // every pole in the diagram is physical and inside the band
    for p in est.stabilisation.iter().flat_map(|o| &o.poles) {
        assert!(p.frequency_hz >= 40.0 && p.frequency_hz <= 1000.0 && p.damping_ratio > 0.0);
        assert!(p.damping_ratio < opts.max_damping);
    }
}

#[test]
fn unusable_input_is_refused_with_a_reason() {
    let sys = DampedSystem::new(samples::frame_with_joint()).unwrap();
    let (tip, corner) = (DofRef::new(4, Dof::Uy), DofRef::new(2, Dof::Ux));
    let freqs = lines(40.0, 1000.0, 0.5);
    let h = synthesize(&sys, &grid(&frame_responses(), &[tip]), &freqs).unwrap();
    let opts = LscfOptions::new(40.0, 1000.0);

    let mobility = h.converted(FrfKind::Mobility);
    assert_eq!(lscf(&mobility, &opts).unwrap_err(), LscfError::NotReceptance { kind: FrfKind::Mobility });

    // a second reference measured at one response only
    let mut channels = grid(&frame_responses(), &[tip]);
    channels.push(Channel::new(tip, corner));
    let partial = synthesize(&sys, &channels, &freqs).unwrap();
    assert_eq!(
        lscf(&partial, &opts).unwrap_err(),
        LscfError::IncompleteGrid { response: frame_responses()[0], reference: corner }
    );

    // 41 lines in the band cannot carry order 40
    let narrow = LscfOptions::new(100.0, 120.0);
    assert!(matches!(lscf(&h, &narrow).unwrap_err(), LscfError::Band { lines: 41, .. }));

    let mut bad = opts.clone();
    bad.tol_damping = f64::NAN;
    assert!(matches!(lscf(&h, &bad).unwrap_err(), LscfError::Options(_)));

    let mut nan = h.clone();
    nan.set(2, 10, C64::new(f64::NAN, 0.0));
    assert_eq!(
        lscf(&nan, &opts).unwrap_err(),
        LscfError::NotFinite { channel: nan.channels()[2], freq_hz: nan.frequencies_hz()[10] }
    );
    // a response without signal (a dead sensor) is ignored, not fatal
    let mut dead = h.clone();
    dead.channel_mut(1).fill(C64::new(0.0, 0.0));
    let mut o = opts.clone();
    o.orders = 2..=30;
    let est = lscf(&dead, &o).unwrap();
    assert_eq!(est.modes.len(), 3);
    assert_eq!(est.fit_error[1], 0.0);
    assert!(est.fit_error.iter().all(|e| e.is_finite()));
    // an empty FrfSet of the right kind but no lines in the band
    let empty = FrfSet::zeros(vec![1.0, 2.0], grid(&[tip], &[tip]), FrfKind::Receptance).unwrap();
    assert!(matches!(lscf(&empty, &opts).unwrap_err(), LscfError::Band { lines: 0, .. }));
}

/// The resident memory of this process (`VmRSS`) or its peak since the last
/// reset (`VmHWM`), in bytes.
#[cfg(target_os = "linux")]
fn resident(key: &str) -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let line = status.lines().find(|l| l.starts_with(key)).unwrap();
    line.split_whitespace().nth(1).unwrap().parse::<u64>().unwrap() * 1024
}

/// The estimator holds what it needs a line at a time and the residue fit
/// a block of lines: on 500,000 lines of two channels it adds less than
/// the data's own size to what the process holds (the dense fit held its
/// design matrix twice and a copy of the data, some six times the data).
/// Measured in a process of its own, this test binary run again for this
/// test alone, so that no other test's memory counts; its peak is reset
/// (`/proc/self/clear_refs`) once the data are made.
#[cfg(target_os = "linux")]
#[test]
fn lscf_on_many_lines_holds_less_than_a_copy_of_the_data() {
    const NAME: &str = "lscf::lscf_on_many_lines_holds_less_than_a_copy_of_the_data";
    if std::env::var_os("FRF_MEASURE_LSCF").is_none() {
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args([NAME, "--exact", "--nocapture", "--test-threads=1"])
            .env("FRF_MEASURE_LSCF", "1")
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{text}");
        let field = |key: &str| -> f64 {
            let at = text.find(key).unwrap_or_else(|| panic!("no `{key}` in {text}")) + key.len();
            text[at..].split_whitespace().next().unwrap().parse().unwrap()
        };
        let (data, added) = (field("data bytes:"), field("added bytes:"));
        assert!(added < data, "lscf added {added} bytes to {data} bytes of data");
        return;
    }
    // two modes (12 and 31 Hz, 2 % damping) at responses 1 and 2 over reference 1
    let n = 500_000;
    let freqs: Vec<f64> = (0..n).map(|k| 2.0 + 48.0 * k as f64 / (n - 1) as f64).collect();
    let reference = DofRef::new(1, Dof::Uy);
    let channels = vec![Channel::new(reference, reference), Channel::new(DofRef::new(2, Dof::Uy), reference)];
    let mut h = FrfSet::zeros(freqs.clone(), channels, FrfKind::Receptance).unwrap();
    let modes = [(12.0, [1.0, 0.6]), (31.0, [0.8, -0.9])];
    for (k, &f) in freqs.iter().enumerate() {
        let w = 2.0 * std::f64::consts::PI * f;
        for c in 0..2 {
            let v: C64 = modes
                .iter()
                .map(|&(fk, phi)| {
                    let wk = 2.0 * std::f64::consts::PI * fk;
                    C64::new(phi[c] * phi[0], 0.0) / C64::new(wk * wk - w * w, 0.04 * wk * w)
                })
                .sum();
            h.set(c, k, v);
        }
    }
    let mut opts = LscfOptions::new(2.0, 50.0);
    opts.orders = 4..=12;
    std::fs::write("/proc/self/clear_refs", "5").unwrap();
    let before = resident("VmRSS:");
    let est = lscf(&h, &opts).unwrap();
    let added = resident("VmHWM:").saturating_sub(before);
    // the fit ran: both modes found
    assert_eq!(est.modes.len(), 2, "{:?}", est.modes.iter().map(|m| m.frequency_hz).collect::<Vec<_>>());
    println!("data bytes: {} added bytes: {added}", n * 2 * 16);
}

/// Receptances of a cantilever's first five bending modes, summed from
/// exact poles: the analytic mode shapes at the quarter points (the first
/// response, a quarter of the way out, is the driving point), natural
/// frequencies in the ratios of the Euler-Bernoulli roots from `f1`, unit
/// modal masses. Returns the set and the poles `(frequency Hz, damping ratio)`.
fn cantilever_modal_sum(f1: f64, zetas: [f64; 5], lines: &[f64]) -> (FrfSet, Vec<(f64, f64)>) {
    const BETA_L: [f64; 5] = [1.875104, 4.694091, 7.854757, 10.995541, 14.137168];
    let shape = |k: usize, x: f64| {
        let b = BETA_L[k];
        let sigma = (b.cosh() + b.cos()) / (b.sinh() + b.sin());
        (b * x).cosh() - (b * x).cos() - sigma * ((b * x).sinh() - (b * x).sin())
    };
    let points = [0.25, 0.5, 0.75, 1.0];
    let responses: Vec<DofRef> = (0..4).map(|i| DofRef::new(5 + 4 * i, Dof::Uy)).collect();
    let channels = grid(&responses, &responses[..1]);
    let mut set = FrfSet::zeros(lines.to_vec(), channels, FrfKind::Receptance).unwrap();
    let mut poles = Vec::new();
    for (k, &zeta) in zetas.iter().enumerate() {
        let f = f1 * (BETA_L[k] / BETA_L[0]).powi(2);
        let w = 2.0 * std::f64::consts::PI * f;
        let lambda = C64::new(-zeta * w, w * (1.0 - zeta * zeta).sqrt());
        poles.push((f, zeta));
        for (c, &x) in points.iter().enumerate() {
            // phi_o phi_i / (2 j w_d) with unit modal mass
            let r = C64::new(0.0, -1.0) * shape(k, x) * shape(k, points[0]) / (2.0 * lambda.im);
            for (l, &fl) in lines.iter().enumerate() {
                let jw = C64::new(0.0, 2.0 * std::f64::consts::PI * fl);
                let h = set.get(c, l) + r / (jw - lambda) + r.conj() / (jw - lambda.conj());
                set.set(c, l, h);
            }
        }
    }
    (set, poles)
}

/// The lap joint's case (cases/tutorial/lap-joint.toml): a cantilever whose
/// first mode, at 7.4 Hz, is a fiftieth of a 5 to 400 Hz band of 0.5 Hz
/// lines, its half-power bandwidth (0.07 Hz) a seventh of the line
/// spacing, weakly driven from a quarter of the span, measured per volt of
/// a shaker amplifier (42 at -30 degrees) with 1 % noise. The estimator
/// fits rational functions with real coefficients, which a constant phase
/// is not: the FRFs are divided by a gain fitted against a model first
/// (`rfm compare` does), here one 7 degrees off, as the nominal lap-joint
/// model's fit is. Every mode is found, and nothing else.
#[test]
fn a_weak_low_mode_near_the_band_edge_is_found_in_frfs_per_volt_divided_by_a_fitted_gain() {
    let freqs = lines(5.0, 400.0, 0.5);
    let zetas = [0.005, 0.005, 0.002, 0.01, 0.01];
    let (clean, poles) = cantilever_modal_sum(7.4, zetas, &freqs);
    // the fifth mode (457 Hz) is above the band
    let in_band: Vec<(f64, f64)> = poles.iter().copied().filter(|p| p.0 < 400.0).collect();
    assert_eq!(in_band.len(), 4);
    let amplifier = C64::from_polar(42.0, -30f64.to_radians());
    let fitted = C64::from_polar(40.0, -37f64.to_radians());
    let opts = LscfOptions::new(5.0, 400.0);
    for seed in 1..=6 {
        let mut h = clean.clone();
        for c in 0..h.channels().len() {
            h.channel_mut(c).iter_mut().for_each(|v| *v *= amplifier);
        }
        NoiseModel::relative(0.01, seed).apply(&mut h);
        for c in 0..h.channels().len() {
            h.channel_mut(c).iter_mut().for_each(|v| *v /= fitted);
        }
        let est = lscf(&h, &opts).unwrap();
        let found: Vec<(f64, f64)> = est.modes.iter().map(|m| (m.frequency_hz, m.damping_ratio)).collect();
        assert_eq!(found.len(), in_band.len(), "seed {seed}: found {found:?}, exact {in_band:?}");
        for (m, t) in found.iter().zip(&in_band) {
            let df = (m.0 - t.0).abs() / t.0;
            let dz = (m.1 - t.1).abs() / t.1;
            eprintln!("seed {seed}: {:.4} Hz ({df:.1e}), zeta {:.5} ({dz:.1e})", m.0, m.1);
            assert!(df < 5e-4, "seed {seed}: {} Hz against {} Hz", m.0, t.0);
            assert!(dz < 0.05, "seed {seed}: zeta {} against {} at {} Hz", m.1, t.1, t.0);
        }
    }
}
