//! One benchmark configuration in its own process, for `cargo xtask bench`.
//!
//! ```text
//! cargo run --release -p rfm-update --example bench_point -- \
//!     --model beam:34483 --params 30 --measured 20 --freqs 10 [--naive] [--repeat 3]
//! ```
//!
//! Models: `paper`, `beam:<elements>`, `frame:<bays>x<storeys>x<per>`, `shell:<n>` (see
//! `benches/common`). Assembles the sensitivities (`Hybrid::Model`) over all
//! lines `--repeat` times and prints one JSON line: sizes (with the
//! factor's entries and the multiply-adds of one factorisation), the best wall
//! time per frequency line and the CPU time of that run (all threads), the
//! best wall time per line of the numeric factorisations of `Z` alone (over
//! the same lines and threads), the setup time and the process's peak
//! resident memory (VmHWM), so that each configuration's memory is its own.

#[path = "../benches/common/mod.rs"]
mod common;

mod point;

use std::time::Instant;

use point::{arg, peak_kib};
use rayon::prelude::*;
use rfm_update::sensitivity::{self, ChannelPlan, Hybrid};

/// CPU time used so far by all threads of this process (s), from
/// /proc/self/task/*/schedstat (nanoseconds on the CPU).
fn cpu_seconds() -> Option<f64> {
    let mut total = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let stat = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        total += stat.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(total as f64 * 1e-9)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let model: String = arg(&args, "--model", "paper".to_string());
    let family = common::Family::parse(&model).unwrap_or_else(|| panic!("unknown model {model}"));
    let (params, measured, freqs) =
        (arg(&args, "--params", 30), arg(&args, "--measured", 20), arg(&args, "--freqs", 10));
    let repeat: usize = arg(&args, "--repeat", 3);
    let naive = args.iter().any(|a| a == "--naive");

    let t0 = Instant::now();
    let w = common::workload(family, params, measured, freqs);
    let solver = frf::ZSolver::new(w.sys.assembly().pattern()).expect("pattern analyses");
    let plan = ChannelPlan::new(&w.sys, &w.channels).expect("channels resolve");
    let setup = t0.elapsed().as_secs_f64();

    let mut best = f64::INFINITY;
    let mut best_cpu = f64::NAN;
    for _ in 0..repeat.max(1) {
        let cpu0 = cpu_seconds();
        let t = Instant::now();
        let blocks = if naive {
            sensitivity::naive::assemble(&w.sys, &plan, &w.params, &w.freqs, Hybrid::Model)
        } else {
            sensitivity::assemble(&w.sys, &solver, &plan, &w.params, &w.freqs, Hybrid::Model)
        }
        .expect("assembly succeeds");
        let wall = t.elapsed().as_secs_f64();
        if wall < best {
            best = wall;
            best_cpu = match (cpu0, cpu_seconds()) {
                (Some(a), Some(b)) => b - a,
                _ => f64::NAN,
            };
        }
        std::hint::black_box(blocks);
    }
    // the numeric factorisations alone, over the same lines and threads:
    // the part of a line's cost that grows with the factor's flops, not
    // only with its entries (a shell's columns are 30 times fuller than a
    // beam's)
    let factor = if naive {
        f64::NAN
    } else {
        let mut best = f64::INFINITY;
        for _ in 0..repeat.max(1) {
            let t = Instant::now();
            w.freqs.par_iter().for_each_init(
                || (solver.workspace(), Vec::new()),
                |(ws, z), &f| {
                    z.resize(w.sys.assembly().pattern().nnz(), num_complex::Complex64::ZERO);
                    w.sys.z_values_into(2.0 * std::f64::consts::PI * f, z);
                    solver.factorize(ws, z, f).expect("Z factorises");
                },
            );
            best = best.min(t.elapsed().as_secs_f64());
        }
        best
    };
    // one JSON object per line; labels never contain quotes or backslashes
    let json = format!(
        concat!(
            "{{\"label\":\"{}\",\"method\":\"{}\",\"dofs\":{},\"factor_nnz\":{},\"factor_madds\":{},\"params\":{},",
            "\"measured\":{},\"freqs\":{},\"threads\":{},\"seconds\":{:e},\"ms_per_freq\":{:e},",
            "\"cpu_ms_per_freq\":{},\"factor_ms_per_freq\":{},\"setup_s\":{:e},\"peak_kib\":{}}}"
        ),
        w.label,
        if naive { "dense" } else { "sparse" },
        w.sys.n(),
        solver.factor_nnz(),
        solver.factor_multiply_adds(),
        w.params.len(),
        w.channels.len(),
        w.freqs.len(),
        rayon::current_num_threads(),
        best,
        1e3 * best / w.freqs.len() as f64,
        if best_cpu.is_finite() { format!("{:e}", 1e3 * best_cpu / w.freqs.len() as f64) } else { "null".into() },
        if factor.is_finite() { format!("{:e}", 1e3 * factor / w.freqs.len() as f64) } else { "null".into() },
        setup,
        peak_kib().map_or("null".to_string(), |k| k.to_string()),
    );
    println!("{json}");
}
