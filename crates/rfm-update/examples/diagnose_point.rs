//! The whole diagnosis on a frame, in its own process, for `cargo xtask bench`.
//!
//! ```text
//! cargo run --release -p rfm-update --example diagnose_point -- --frame 10x11x15 [--lines 200]
//! ```
//!
//! Builds `samples::frame_grid(bays, storeys, per)`, hides a 40 % stiffness
//! loss in one floor-beam element, synthesises the hidden truth's FRFs with
//! 1 % noise at `--measured` translational DOFs (default 20) over `--lines`
//! lines (default 200), runs [`rfm_update::diagnose::diagnose`] with its
//! default options on the nominal frame, and prints one JSON line: sizes,
//! the number of candidates, the wall and CPU time (all threads), the peak
//! memory, and whether the
//! leader is the hidden stiffness loss at the right element (or a neighbour).
//! `--verbose` prints the stages as they end, the first six of the
//! ranking, the noise estimate and the nominal misfit to stderr.

mod point;

use std::time::Instant;

use damping::DampedSystem;
use fe_model::{Dof, samples};
use frf::{Channel, NoiseModel, synthesize};
use point::{arg, cpu_seconds, peak_kib};
use rfm_update::diagnose::{DiagnoseOptions, EffectKind, diagnose_with};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let frame: String = arg(&args, "--frame", "3x3x4".to_string());
    let size: Vec<usize> = frame.split('x').map(|v| v.parse().expect("--frame BxSxP")).collect();
    let [bays, storeys, per] = size[..] else { panic!("--frame BxSxP") };
    let (n_lines, n_measured): (usize, usize) = (arg(&args, "--lines", 200), arg(&args, "--measured", 20));

    let nominal = samples::frame_grid(bays, storeys, per);
    let sys = DampedSystem::new(nominal.clone()).expect("sample frames assemble");
    // the hidden effect: the middle element of the first floor beam of the middle bay
    let beam_member = (bays + 1) + bays / 2;
    let element = (beam_member * per + per / 2 + 1) as u32;
    let mut truth = nominal.clone();
    let q = truth.quantity(&format!("element.{element}.stiffness")).expect("element exists");
    truth.set(q, 0.6).expect("factor is valid");

    // translational DOFs spread over the frame, driven at one of them
    let dofs = sys.assembly().dofs();
    let uy: Vec<_> = (0..sys.n()).map(|eq| dofs.dof_of(eq)).filter(|d| d.dof == Dof::Uy).collect();
    let measured: Vec<_> = (0..n_measured).map(|i| uy[(2 * i + 1) * uy.len() / (2 * n_measured)]).collect();
    let reference = measured[measured.len() / 2];
    let channels: Vec<Channel> = measured.iter().map(|&r| Channel::new(r, reference)).collect();
    let top_hz = 1.2 * rfm_update::study::natural_frequencies(&sys, 1e6).0.get(5).copied().unwrap_or(100.0);
    let lines: Vec<f64> = (0..n_lines).map(|k| top_hz * (k as f64 + 1.0) / n_lines as f64).collect();
    let truth_sys = DampedSystem::new(truth).expect("truth assembles");
    let mut data = synthesize(&truth_sys, &channels, &lines).expect("synthesis");
    NoiseModel::relative(0.01, 7).apply(&mut data);

    let (t, cpu0) = (Instant::now(), cpu_seconds());
    let cpu = || cpu_seconds().zip(cpu0).map(|(b, a)| b - a);
    let verbose = args.iter().any(|a| a == "--verbose");
    let d = diagnose_with(&nominal, &data, &DiagnoseOptions::default(), |stage| {
        if verbose {
            let cpu = cpu().map_or("?".to_string(), |c| format!("{c:.2}"));
            eprintln!("{:>8.2} s (CPU {cpu:>7} s)  {stage}", t.elapsed().as_secs_f64());
        }
    })
    .expect("diagnosis runs");
    let seconds = t.elapsed().as_secs_f64();
    let cpu_seconds = cpu();
    for r in d.ranking.iter().take(if verbose { 6 } else { 0 }) {
        eprintln!("{:<50} explained {:.4} dBIC {:.1}", r.description, r.explained, r.delta_bic);
    }
    if verbose {
        let nominal_sys = DampedSystem::new(nominal.clone()).expect("assembles");
        let misfit = rfm_update::diagnose::log_misfit(&nominal_sys, &data, 200).unwrap_or(f64::NAN);
        eprintln!("noise estimate {:.4}, nominal misfit {misfit:.4}", d.noise);
    }
    let top = &d.ranking[0];
    let near = |e: &u32| e.abs_diff(element) <= 1;
    let found = top.kind == EffectKind::StiffnessChange && top.elements.iter().any(near);
    println!(
        "{{\"label\":\"diagnosis, frame {frame}\",\"dofs\":{},\"candidates\":{},\"measured\":{},\"freqs\":{},\
         \"seconds\":{seconds:e},\"cpu_seconds\":{},\"found\":{found},\"leader\":\"{}\",\"peak_kib\":{}}}",
        sys.n(),
        d.candidates.len(),
        channels.len(),
        lines.len(),
        cpu_seconds.map_or("null".to_string(), |c| format!("{c:e}")),
        top.description,
        peak_kib().map_or("null".to_string(), |k| k.to_string()),
    );
}
