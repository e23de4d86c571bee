//! Modal correlation: the model's complex modes against its own FRFs, MAC
//! pairing, and the LSCF estimate paired with the model.

use damping::{DampedSystem, complex_modes};
use fe_model::{Dof, DofRef, samples};
use frf::modal::mode_mac;
use frf::{
    C64, Channel, LscfOptions, Mode, ModeError, NoiseModel, ZSolver, lscf, measured_modes, model_modes, pair_modes,
    synthesize, synthesize_with,
};

/// Frequency (Hz) of the largest `|H|` in `[a, b]`, by golden-section search.
fn peak(sys: &DampedSystem, solver: &ZSolver, ch: Channel, mut a: f64, mut b: f64) -> f64 {
    let mag = |f: f64| synthesize_with(sys, solver, &[ch], &[f]).unwrap().get(0, 0).norm();
    let g = (5.0f64.sqrt() - 1.0) / 2.0;
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    let (mut fc, mut fd) = (mag(c), mag(d));
    for _ in 0..80 {
        if fc > fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = mag(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = mag(d);
        }
    }
    0.5 * (a + b)
}

#[test]
fn receptance_peaks_lie_at_the_predicted_damped_frequencies() {
    // A lightly damped mode, R / (j w - s) + conj, peaks at Im(s) up to the
    // pull of the conjugate term and of the other modes, a small fraction of
    // the half-power half-width zeta f_d. Checked on the tip driving point of
    // the non-viscous cantilever and of the non-proportionally damped
    // L-frame; a prediction off by a bandwidth would fail by far.
    let cases = [
        (samples::two_material_cantilever(), DofRef::new(31, Dof::Uy), 4),
        (samples::frame_with_joint(), DofRef::new(4, Dof::Uy), 3),
    ];
    for (model, tip, count) in cases {
        let sys = DampedSystem::new(model).unwrap();
        let solver = ZSolver::new(sys.assembly().pattern()).unwrap();
        let modes = complex_modes(&sys).unwrap();
        // the lightly damped ones (zeta < 1 %)
        let light: Vec<_> = modes.oscillatory.iter().take_while(|m| m.damping_ratio < 0.01).collect();
        assert_eq!(light.len(), count);
        for m in light {
            let fd = m.damped_frequency_hz();
            let zeta = m.damping_ratio;
            let f = peak(&sys, &solver, Channel::new(tip, tip), fd * (1.0 - 3.0 * zeta), fd * (1.0 + 3.0 * zeta));
            let err = (f - fd).abs() / fd;
            eprintln!("peak at {f:.6} Hz, predicted {fd:.6} Hz: {err:.1e} = {:.3} zeta", err / zeta);
            assert!(err < 0.1 * zeta, "peak at {f} Hz, mode at {fd} Hz (zeta {zeta})");
        }
    }
}

#[test]
fn model_modes_take_the_complex_shapes_at_the_requested_dofs() {
    let sys = DampedSystem::new(samples::frame_with_joint()).unwrap();
    let dofs = [DofRef::new(4, Dof::Uy), DofRef::new(3, Dof::Rz), DofRef::new(2, Dof::Ux)];
    let all = complex_modes(&sys).unwrap();
    let modes = model_modes(&sys, &dofs, 300.0).unwrap();
    let expected: Vec<_> = all.oscillatory.iter().filter(|m| m.frequency_hz <= 300.0).collect();
    assert_eq!(modes.len(), expected.len());
    assert!(modes.len() >= 3 && modes.len() < all.oscillatory.len());
    for (m, e) in modes.iter().zip(expected) {
        assert_eq!(m.frequency_hz, e.frequency_hz);
        assert_eq!(m.damping_ratio, e.damping_ratio);
        assert_eq!(m.dofs, dofs);
        for (d, v) in dofs.iter().zip(&m.shape) {
            assert_eq!(*v, e.shape[frf::equation_of(&sys, *d).unwrap()]);
        }
    }
    let fixed = DofRef::new(1, Dof::Uy);
    assert_eq!(model_modes(&sys, &[fixed], 300.0).unwrap_err(), ModeError::Dof(frf::FrfError::FixedDof { dof: fixed }));
}

#[test]
fn pairing_recovers_a_shuffled_rescaled_list_and_reports_the_leftovers() {
    let sys = DampedSystem::new(samples::two_material_cantilever()).unwrap();
    let dofs: Vec<DofRef> = (2..=31).map(|n| DofRef::new(n, Dof::Uy)).collect();
    let model = model_modes(&sys, &dofs, 1000.0).unwrap();
    assert!(model.len() >= 7);
    // "measured": modes 4, 0, 6, 2, 1, 3 (mode 5 not measured), each shape
    // times a complex factor, frequencies 1 % high, plus one noise mode
    let order = [4usize, 0, 6, 2, 1, 3];
    let mut measured: Vec<Mode> = order
        .iter()
        .enumerate()
        .map(|(i, &k)| {
            let f = C64::from_polar(0.3 + i as f64, 0.7 * i as f64);
            Mode {
                frequency_hz: model[k].frequency_hz * 1.01,
                damping_ratio: model[k].damping_ratio * 0.8,
                dofs: dofs.clone(),
                shape: model[k].shape.iter().map(|v| v * f).collect(),
            }
        })
        .collect();
    // a shape with alternating signs at every node: unlike any low mode
    measured.push(Mode {
        frequency_hz: 100.0,
        damping_ratio: 0.01,
        dofs: dofs.clone(),
        shape: (0..dofs.len()).map(|i| C64::new(if i % 2 == 0 { 1.0 } else { -1.0 }, 0.0)).collect(),
    });
    let model = &model[..7];
    let pairing = pair_modes(model, &measured, 0.8);
    assert_eq!(pairing.pairs.len(), order.len());
    for (p, &k) in pairing.pairs.iter().zip(&order) {
        assert_eq!(p.model, k);
        assert!((p.mac - 1.0).abs() < 1e-12, "MAC {}", p.mac);
        // f_model = f_measured / 1.01
        assert!((p.frequency_error_pct - 100.0 * (1.0 / 1.01 - 1.0)).abs() < 1e-9);
        assert!((p.damping_error_pct - 25.0).abs() < 1e-9);
    }
    assert_eq!(pairing.unpaired_measured, vec![order.len()]);
    assert_eq!(pairing.unpaired_model, vec![5]);
    assert_eq!(pairing.mac.len(), measured.len());
    assert_eq!(pairing.mac[0].len(), model.len());
    assert!(pairing.mac[order.len()].iter().all(|&v| v < 0.8));
}

#[test]
fn lscf_modes_pair_with_the_model_modes() {
    let sys = DampedSystem::new(samples::two_material_cantilever()).unwrap();
    let tip = DofRef::new(31, Dof::Uy);
    let channels: Vec<Channel> = (2..=31).map(|n| Channel::new(DofRef::new(n, Dof::Uy), tip)).collect();
    let freqs: Vec<f64> = (0..=3990).map(|k| 1.0 + 0.1 * f64::from(k)).collect();
    let mut h = synthesize(&sys, &channels, &freqs).unwrap();
    NoiseModel::relative(0.02, 21).apply(&mut h);
    let mut opts = LscfOptions::new(1.0, 400.0);
    opts.orders = 4..=30;
    let est = lscf(&h, &opts).unwrap();
    let measured = measured_modes(&est);
    let dofs: Vec<DofRef> = channels.iter().map(|c| c.response).collect();
    let model = model_modes(&sys, &dofs, 500.0).unwrap();
    let pairing = pair_modes(&model, &measured, 0.9);
    assert_eq!(pairing.pairs.len(), measured.len());
    assert!(pairing.unpaired_measured.is_empty());
    // the model has a sixth mode at 423 Hz, outside the measured band
    assert_eq!(pairing.unpaired_model, vec![5]);
    for (i, p) in pairing.pairs.iter().enumerate() {
        assert_eq!((p.measured, p.model), (i, i));
        assert!(p.mac > 0.99, "MAC {}", p.mac);
        assert!(p.frequency_error_pct.abs() < 0.1, "{} %", p.frequency_error_pct);
        assert!((mode_mac(&measured[i], &model[i]) - p.mac).abs() < 1e-15);
        eprintln!(
            "pair {i}: MAC {:.5}, frequency error {:+.4} %, damping error {:+.2} %",
            p.mac, p.frequency_error_pct, p.damping_error_pct
        );
    }
}
