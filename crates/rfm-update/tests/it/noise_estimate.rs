//! The noise level read from the data, on a line grid coarse against the
//! structure's peaks: a frame with many modes in its band, 1 % relative
//! noise injected (the independent truth), lines a few per mode.

use damping::DampedSystem;
use fe_model::{Dof, Model, samples};
use frf::{Channel, FrfSet, NoiseModel, synthesize};
use rfm_update::diagnose::{estimate_noise, estimate_noise_against};

const NOISE: f64 = 0.01;

/// The frame, and its FRFs at 12 translational DOFs on 120 lines up to
/// 1.2 times its 40th natural frequency, with `NOISE` injected.
fn frame_and_data() -> (Model, FrfSet) {
    let model = samples::frame_grid(4, 4, 4);
    let sys = DampedSystem::new(model.clone()).unwrap();
    let dofs = sys.assembly().dofs();
    let uy: Vec<_> = (0..sys.n()).map(|eq| dofs.dof_of(eq)).filter(|d| d.dof == Dof::Uy).collect();
    let measured: Vec<_> = (0..12).map(|i| uy[(2 * i + 1) * uy.len() / 24]).collect();
    let channels: Vec<Channel> = measured.iter().map(|&r| Channel::new(r, measured[5])).collect();
    let top = 1.2 * rfm_update::study::natural_frequencies(&sys, 1e6).0[39];
    let lines: Vec<f64> = (1..=120).map(|k| top * k as f64 / 120.0).collect();
    let mut data = synthesize(&sys, &channels, &lines).unwrap();
    NoiseModel::relative(NOISE, 11).apply(&mut data);
    (model, data)
}

#[test]
fn the_noise_is_read_against_the_model_where_lines_are_coarse_against_the_peaks() {
    let (model, data) = frame_and_data();
    let own = estimate_noise(&data).unwrap();
    let sys = DampedSystem::new(model.clone()).unwrap();
    let against = estimate_noise_against(&sys, &data).unwrap().unwrap();
    println!("injected {NOISE}, from the data alone {own:.4}, against the model {against:.4}");
    // the premise: the data's own roughness is mostly the dynamics here
    assert!(own > 3.0 * NOISE, "the lines are not coarse against the peaks ({own:.4})");
    assert!((against / NOISE - 1.0).abs() < 0.15, "{against:.4} against {NOISE} injected");

    // a model far from the data leaves a rougher residual: the data's own
    // roughness stands, never a level below the noise
    let mut far = model;
    let q = far.quantity("material.steel.E").unwrap();
    far.set(q, 1.3 * far.get(q)).unwrap();
    let far = estimate_noise_against(&DampedSystem::new(far).unwrap(), &data).unwrap().unwrap();
    println!("against a model 30 % too stiff: {far:.4}");
    assert!(far > 0.9 * NOISE, "{far:.4} against {NOISE} injected");
}
