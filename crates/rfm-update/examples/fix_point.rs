//! The loop of `rfm fix` on test-resolution data, in its own process, for
//! `cargo xtask bench`.
//!
//! ```text
//! cargo run --release -p rfm-update --example fix_point -- --model beam|tower [--steps 3] [--write DIR] [--verbose]
//! ```
//!
//! Two workloads that users wait for (issue 35):
//!
//! - `beam`: a 1 m steel strip of 100 elements, clamped, measured as
//!   accelerance at 4 responses from one shaker over 8,000 lines (1 to
//!   800.9 Hz by 0.1 Hz), with two hidden effects: a lossy in-line joint at
//!   node 61 (a non-viscous rotational spring) and a 30 g mass at node 86;
//! - `tower`: a two-level frame in space (four columns, two levels of
//!   rails; 60 nodes, 336 free DOFs) measured as accelerance at 22 responses from two
//!   horizontal impacts (44 channels) over 461 lines, with one hidden
//!   effect: a loose, lossy corner joint where a rail meets a column at the
//!   first level.
//!
//! The truth is a case file of its own with the effect present, written
//! with explicit coincident nodes, springs and ties (not the `[[joints]]`
//! table the diagnosis's edits write), synthesised by `frf::synthesize`
//! with 1 % relative complex noise. The nominal case declares the frame's
//! own damping in `[update]`, as a user's case would. The loop runs with
//! the options `rfm fix` uses for such data ([`FixOptions::default`] with
//! `--steps` steps) and one JSON line is printed: sizes, wall and CPU time
//! of the loop, the load average before and after, the effects the loop
//! ended with, whether each hidden effect is among them (right kind at its
//! place: the beam's one node either side, the tower's at its node), how
//! many effects it ended with that are none of them, the final misfit over
//! the injected noise, whether that answer is right (every hidden effect
//! found, nothing else, and the misfit within 1.5 times the noise: a fast
//! wrong answer is a failure of the bench) and the stop. `--write
//! DIR` also writes the nominal case, its data and the truth, to run `rfm
//! fix DIR/nominal.toml` on them; `--verbose` prints the loop's progress
//! with times to stderr.

mod point;

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use damping::DampedSystem;
use fe_model::CaseFile;
use frf::{Channel, FrfKind, NoiseModel, synthesize};
use point::{arg, peak_kib};
use rfm_update::diagnose::{EffectKind, Ranked};
use rfm_update::fix::{FixOptions, FixProgress, fix};

/// The injected relative noise.
const NOISE: f64 = 0.01;

/// A hidden effect: the kind that represents it and where it is.
struct Hidden {
    kind: EffectKind,
    /// Nominal nodes at or next to which the effect sits.
    nodes: Vec<u32>,
    label: &'static str,
}

/// A workload: the nominal case (without its `data`), the truth's case,
/// the measured lines and what is hidden.
struct Workload {
    label: String,
    nominal: String,
    truth: String,
    hidden: Vec<Hidden>,
    seed: u64,
}

/// A `[measurement]` table: lines `from..=to` by `step`, the channels, the data file.
fn measurement(band: (f64, f64, f64), references: &[String], responses: &[String], data: Option<&str>) -> String {
    let quoted = |v: &[String]| v.iter().map(|s| format!("\"{s}\"")).collect::<Vec<_>>().join(", ");
    let mut s = format!(
        "\n[measurement]\nfrequencies = {{ from = {}, to = {}, step = {} }}\nreferences = [{}]\nresponses = [{}]\n",
        band.0,
        band.1,
        band.2,
        quoted(references),
        quoted(responses)
    );
    if let Some(d) = data {
        let _ = writeln!(s, "data = \"{d}\"");
    }
    s
}

/// The beam: nominal as one run of 100 elements; the truth split at node
/// 61 onto a coincident node 200 (tied in ux, uy; a rotational spring with
/// its own non-viscous damping between them) with a 30 g mass at node 86.
fn beam() -> Workload {
    let head = "[materials]\nsteel = { E = 2.1e11, rho = 7850 }\n\n[sections]\nstrip = { b = 0.04, h = 0.006 }\n\n\
                [groups.beam]\nalpha = 2.0e-6\nbeta = 0.5\n";
    let band = (1.0, 800.9, 0.1);
    let references = vec!["21:uy".to_string()];
    let responses: Vec<String> = [21, 46, 71, 101].iter().map(|n| format!("{n}:uy")).collect();
    let update = "\n[update]\nparameters = [\"group.beam.alpha\", \"group.beam.beta\"]\nmethod = \"output-error\"\n";
    let nominal = format!(
        "title = \"100-element beam (fix bench)\"\n\n{head}\n[[lines]]\nfrom = [0.0, 0.0]\nto = [1.0, 0.0]\n\
         elements = 100\nmaterial = \"steel\"\nsection = \"strip\"\ngroup = \"beam\"\n\n[[supports]]\nnode = 1\n\
         {update}"
    );
    let truth = format!(
        "title = \"100-element beam, truth (fix bench)\"\nnodes = [[200, 0.6, 0.0]]\n\n{head}\n\
         [groups.lap]\nalpha = 3.0e-4\nmu = 3000\n\n\
         [[lines]]\nfrom = [0.0, 0.0]\nto = [0.6, 0.0]\nelements = 60\nfirst_node = 1\nfirst_element = 1\nmaterial = \"steel\"\nsection = \"strip\"\n\
         group = \"beam\"\n\n\
         [[lines]]\nfrom = 200\nto = [1.0, 0.0]\nelements = 40\nfirst_node = 62\nfirst_element = 61\n\
         material = \"steel\"\nsection = \"strip\"\ngroup = \"beam\"\n\n\
         [[ties]]\nnodes = [61, 200]\ndofs = [\"ux\", \"uy\"]\n\n\
         [[springs]]\nname = \"lap\"\nnodes = [61, 200]\nkr = 1.0e4\ngroup = \"lap\"\n\n\
         [[masses]]\nname = \"added\"\nnode = 86\nm = 0.03\ngroup = \"beam\"\n\n[[supports]]\nnode = 1\n{}",
        measurement(band, &references, &responses, Some("measured.csv"))
    );
    Workload {
        label: "beam, 4 channels".into(),
        nominal: format!("{nominal}{}", measurement(band, &references, &responses, Some("measured.csv"))),
        truth,
        hidden: vec![
            Hidden { kind: EffectKind::FlexibleJoint, nodes: vec![60, 61, 62], label: "joint at node 61" },
            Hidden { kind: EffectKind::LumpedMass, nodes: vec![85, 86, 87], label: "mass at node 86" },
        ],
        seed: 35,
    }
}

/// Node ids of the tower: column `c` (0..4) has nodes `9 c + 1` (its foot)
/// to `9 c + 9` (its top), the first level at `9 c + 5`.
fn column_node(c: u32, k: u32) -> u32 {
    9 * c + 1 + k
}

/// The tower: four 30 mm square columns of two 0.75 m storeys (four
/// elements each) at the corners of a 1.0 x 0.6 m plan, and at each level
/// four flat rails (40 x 10 mm on edge, four elements each). In the truth
/// the rail along x from column C to column D at the first level starts at
/// a node 300 coincident with column C's, tied in translation, with
/// rotational springs about the three axes in a non-viscous group.
fn tower() -> Workload {
    let corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 0.6), (0.0, 0.6)];
    let head = "[model]\ndimension = 3\n\n[materials]\nsteel = { E = 2.1e11, rho = 7850, nu = 0.3 }\n\n\
                [sections]\nleg = { b = 0.03, h = 0.03 }\nrail = { b = 0.01, h = 0.04 }\n\n\
                [groups.frame]\nalpha = 2.0e-6\nbeta = 1.0\n";
    let line = |from: &str, to: &str, first_node: u32, first_element: u32, section: &str, along_z: bool| {
        format!(
            "\n[[lines]]\nfrom = {from}\nto = {to}\nelements = {}\nfirst_node = {first_node}\n\
             first_element = {first_element}\nmaterial = \"steel\"\nsection = \"{section}\"\ngroup = \"frame\"\n{}",
            if section == "leg" { 8 } else { 4 },
            if along_z { "orientation = [1.0, 0.0, 0.0]\n" } else { "" }
        )
    };
    // columns: nodes 1..36, elements 1..32
    let mut columns = String::new();
    for (c, &(x, z)) in corners.iter().enumerate() {
        let c = c as u32;
        columns.push_str(&line(
            &format!("[{x}, 0.0, {z}]"),
            &format!("[{x}, 1.5, {z}]"),
            9 * c + 1,
            8 * c + 1,
            "leg",
            false,
        ));
    }
    // rails: level l (1, 2) at column node k = 4 l; rail r joins corner r to corner r + 1
    let rail = |l: u32, r: u32, from: String| {
        let k = 4 * l;
        let to = column_node((r + 1) % 4, k);
        let first_node = 37 + 3 * (4 * (l - 1) + r);
        let first_element = 33 + 4 * (4 * (l - 1) + r);
        line(&from, &to.to_string(), first_node, first_element, "rail", r % 2 == 1)
    };
    let mut rails = String::new();
    let mut truth_rails = String::new();
    for l in 1..=2 {
        for r in 0..4 {
            let from = column_node(r, 4 * l).to_string();
            rails.push_str(&rail(l, r, from.clone()));
            // the loose rail: level 1, C to D, from the coincident node 300
            let loose = l == 1 && r == 2;
            truth_rails.push_str(&rail(l, r, if loose { "300".into() } else { from }));
        }
    }
    let supports: String = (0..4).map(|c| format!("\n[[supports]]\nnode = {}\n", column_node(c, 0))).collect();
    // two horizontal impacts at the top of columns B and D; at every corner
    // of both levels both horizontal directions, and the rails' middles at
    // the top and two at the first level vertically
    let references = vec![format!("{}:ux", column_node(1, 8)), format!("{}:uz", column_node(3, 8))];
    let mut responses: Vec<String> = Vec::new();
    for k in [4, 8] {
        for c in 0..4 {
            responses.push(format!("{}:ux", column_node(c, k)));
            responses.push(format!("{}:uz", column_node(c, k)));
        }
    }
    for (l, r) in [(2, 0), (2, 1), (2, 2), (2, 3), (1, 0), (1, 3)] {
        responses.push(format!("{}:uy", 37 + 3 * (4 * (l - 1) + r) + 1));
    }
    let band = (2.0, 462.0, 1.0);
    let update = "\n[update]\nparameters = [\"group.frame.alpha\", \"group.frame.beta\"]\nmethod = \"output-error\"\n";
    let c1 = column_node(2, 4);
    let (x, z) = corners[2];
    let nominal =
        format!("title = \"two-level tower in space (fix bench)\"\n\n{head}{columns}{rails}{supports}{update}");
    let truth = format!(
        "title = \"two-level tower in space, truth (fix bench)\"\nnodes = [[300, {x}, 0.75, {z}]]\n\n{head}\n\
         [groups.corner]\nalpha = 4.0e-3\nmu = 400\n{columns}{truth_rails}{supports}\n\
         [[ties]]\nnodes = [{c1}, 300]\ndofs = [\"ux\", \"uy\", \"uz\"]\n\n\
         [[springs]]\nname = \"corner\"\nnodes = [{c1}, 300]\nkrx = 2.0e4\nkry = 2.0e4\nkrz = 5.0e4\n\
         group = \"corner\"\n{}",
        measurement(band, &references, &responses, Some("measured.csv"))
    );
    Workload {
        label: "tower in space, 44 channels".into(),
        nominal: format!("{nominal}{}", measurement(band, &references, &responses, Some("measured.csv"))),
        truth,
        hidden: vec![Hidden { kind: EffectKind::FlexibleJoint, nodes: vec![c1], label: "joint at node 23" }],
        seed: 36,
    }
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_default()
}

/// Whether a ranked effect is the hidden one: its kind, at one of its nodes.
fn is(e: &Ranked, h: &Hidden) -> bool {
    e.kind == h.kind && e.nodes.iter().any(|n| h.nodes.contains(n))
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let model: String = arg(&args, "--model", "beam".to_string());
    let steps: usize = arg(&args, "--steps", 3);
    let verbose = args.iter().any(|a| a == "--verbose");
    let w = match model.as_str() {
        "beam" => beam(),
        "tower" => tower(),
        _ => panic!("--model beam or tower"),
    };
    let case = CaseFile::parse(Path::new("fix-bench/nominal.toml"), &w.nominal).expect("the nominal case parses");
    let truth = CaseFile::parse(Path::new("fix-bench/truth.toml"), &w.truth).expect("the truth parses");
    let spec = truth.measurement.as_ref().expect("a measurement");
    let channels: Vec<Channel> = spec.channels().into_iter().map(|(r, e)| Channel::new(r, e)).collect();
    let truth_sys = DampedSystem::new(truth.model.clone()).expect("the truth assembles");
    let mut data = synthesize(&truth_sys, &channels, &spec.frequencies_hz)
        .expect("the truth's FRFs")
        .converted(FrfKind::Accelerance);
    NoiseModel::relative(NOISE, w.seed).apply(&mut data);
    if let Some(i) = args.iter().position(|a| a == "--write") {
        let dir = Path::new(args.get(i + 1).expect("--write DIR"));
        std::fs::create_dir_all(dir).expect("the folder");
        std::fs::write(dir.join("nominal.toml"), &w.nominal).expect("write");
        std::fs::write(dir.join("truth.toml"), &w.truth).expect("write");
        std::fs::write(dir.join("measured.csv"), frf::io::csv::to_csv_string(&data)).expect("write");
    }
    let measured = data.to_receptance();
    let opts = FixOptions { max_steps: steps, ..FixOptions::default() };

    let load_before = load_average();
    let (t, cpu0) = (Instant::now(), point::cpu_seconds());
    let outcome = fix(&case, &measured, &opts, |p| {
        if !verbose {
            return;
        }
        let s = t.elapsed().as_secs_f64();
        match p {
            FixProgress::Checked { findings } => eprintln!("{s:>8.2} s  checked: {} findings", findings.len()),
            FixProgress::Declared { step } => eprintln!("{s:>8.2} s  step 0: misfit {:.4}", step.misfit_updated),
            FixProgress::Diagnosed { step, diagnosis } => eprintln!(
                "{s:>8.2} s  diagnosed after {step} steps: {}",
                diagnosis.leader().map_or("nothing".into(), |r| r.description.clone())
            ),
            FixProgress::LookedAhead { ahead, .. } => eprintln!(
                "{s:>8.2} s    tried {}{}: misfit {:.4} {}",
                ahead.effect,
                ahead.with.as_ref().map_or(String::new(), |w| format!(" with {w}")),
                ahead.misfit_ahead,
                ahead.rejected.as_deref().unwrap_or("(kept)")
            ),
            FixProgress::Updated { effect, misfit, status, .. } => {
                eprintln!("{s:>8.2} s  kept {effect}: misfit {misfit:.4} ({status:?})")
            }
            FixProgress::StepDone { index, .. } => eprintln!("{s:>8.2} s  step {} done", index + 1),
            FixProgress::Redone { step, .. } => eprintln!("{s:>8.2} s  steps from {} undone", step + 1),
            FixProgress::Refitted { refit, misfit, .. } => eprintln!(
                "{s:>8.2} s  {} not needed at its own fit: the stage before updated again, misfit {:.4} -> {misfit:.4}",
                refit.found_by, refit.first_misfit
            ),
        }
    })
    .expect("the loop runs");
    let seconds = t.elapsed().as_secs_f64();
    let cpu = match (cpu0, point::cpu_seconds()) {
        (Some(a), Some(b)) => format!("{:e}", b - a),
        _ => "null".into(),
    };
    let found: Vec<bool> = w.hidden.iter().map(|h| outcome.effects.iter().any(|e| is(e, h))).collect();
    let ratio = outcome.final_misfit() / NOISE;
    // an effect that is none of the hidden ones: the loop added what the
    // data did not hold
    let spurious = outcome.effects.iter().filter(|e| !w.hidden.iter().any(|h| is(e, h))).count();
    let right = found.iter().all(|&f| f) && spurious == 0 && ratio <= rfm_update::fix::CONSISTENT;
    let quoted =
        |v: Vec<String>| v.iter().map(|s| format!("\"{}\"", s.replace('"', "'"))).collect::<Vec<_>>().join(",");
    if verbose {
        eprintln!(
            "noise estimate {:.4}, final misfit {:.4}, stop: {}",
            outcome.noise,
            outcome.final_misfit(),
            outcome.stop_reason
        );
    }
    println!(
        "{{\"label\":\"{}\",\"dofs\":{},\"channels\":{},\"freqs\":{},\"steps\":{},\"seconds\":{seconds:e},\
         \"cpu_seconds\":{cpu},\"load_before\":\"{load_before}\",\"load_after\":\"{}\",\"effects\":[{}],\
         \"hidden\":[{}],\"found\":[{}],\"spurious\":{spurious},\"misfit_over_noise\":{ratio:e},\"right\":{right},\"stop\":\"{:?}\",\
         \"peak_kib\":{}}}",
        w.label,
        DampedSystem::new(case.model.clone()).expect("assembles").n(),
        channels.len(),
        measured.n_freq(),
        outcome.steps.len(),
        load_average(),
        quoted(outcome.effects.iter().map(|e| e.description.clone()).collect()),
        quoted(w.hidden.iter().map(|h| h.label.to_string()).collect()),
        found.iter().map(|f| f.to_string()).collect::<Vec<_>>().join(","),
        outcome.stop,
        peak_kib().map_or("null".to_string(), |k| k.to_string()),
    );
}
