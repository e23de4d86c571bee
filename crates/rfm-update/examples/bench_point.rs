//! One benchmark configuration in its own process, for `cargo xtask bench`.
//!
//! ```text
//! cargo run --release -p rfm-update --example bench_point -- \
//!     --model beam:34483 --params 30 --measured 20 --freqs 10 [--naive] [--repeat 3] [--threads 1]
//! ```
//!
//! Models: `paper`, `beam:<elements>`, `frame:<bays>x<storeys>x<per>`, `shell:<n>` (see
//! `benches/common`). Assembles the sensitivities (`Hybrid::Model`) over all
//! lines `--repeat` times, on `--threads` threads (default: rayon's, one per
//! CPU), and prints one JSON line:
//!
//! - sizes: DOFs, parameters, measured DOFs, lines, threads; the factor's
//!   `layout`, its entries in the elimination's pattern (`factor_nnz`) and
//!   as stored (`factor_stored`), and the multiply-adds of one numeric
//!   factorisation (`factor_madds`);
//! - `seconds`, `ms_per_freq`: the best wall time of the whole assembly, and
//!   per line (with several threads, lines run side by side: wall time
//!   divided by lines); `cpu_ms_per_freq`: that run's CPU time summed over
//!   threads, per line;
//! - `factor_ms_per_freq` and `z_ms_per_freq`: in a second pass over the
//!   same lines and threads, the mean time of one call of the numeric
//!   factorisation alone, and of making `Z`'s values alone (the best pass);
//!   so on one thread they are the parts of `ms_per_freq` they name;
//! - `setup_s`, and the process's peak resident memory (`peak_kib`,
//!   VmHWM), so that each configuration's memory is its own.
//!
//! Both passes keep at most one workspace per running task, made in the
//! pass and reused across its lines, as the assembly does. (An earlier
//! version made one per rayon work split, on one thread one per line, each
//! a fresh allocation of the factor's size, and timed the making of `Z`'s
//! values as part of the factorisation: on the 100k-DOF beam on one thread
//! its factorisation read 16 to 20 ms per line where the factorisation
//! alone takes 10 to 11 ms and `Z`'s values 5 to 6 ms, measured side by
//! side on 2026-11-28 at a load average of 5.)

#[path = "../benches/common/mod.rs"]
mod common;

mod point;

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};
use std::time::Instant;

use point::{arg, cpu_seconds, peak_kib};
use rayon::prelude::*;
use rfm_update::sensitivity::{self, ChannelPlan, Hybrid};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let threads: usize = arg(&args, "--threads", 0);
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool").install(|| run(&args));
}

fn run(args: &[String]) {
    let args = args.to_vec();
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
    // beam's); and apart, the making of Z's values, which the line includes
    let (factor, z_time) = if naive {
        (f64::NAN, f64::NAN)
    } else {
        let mut best = (f64::INFINITY, f64::INFINITY);
        for _ in 0..repeat.max(1) {
            let pool = Mutex::new(Vec::new());
            let (factor_ns, z_ns) = (AtomicU64::new(0), AtomicU64::new(0));
            let nanos = |t: Instant| u64::try_from(t.elapsed().as_nanos()).unwrap_or(u64::MAX);
            w.freqs.par_iter().for_each(|&f| {
                let popped = pool.lock().unwrap_or_else(PoisonError::into_inner).pop();
                let (mut ws, mut z) = popped.unwrap_or_else(|| (solver.workspace(), Vec::new()));
                let t = Instant::now();
                z.resize(w.sys.assembly().pattern().nnz(), num_complex::Complex64::ZERO);
                w.sys.z_values_into(2.0 * std::f64::consts::PI * f, &mut z);
                z_ns.fetch_add(nanos(t), Ordering::Relaxed);
                let t = Instant::now();
                solver.factorize(&mut ws, &z, f).expect("Z factorises");
                factor_ns.fetch_add(nanos(t), Ordering::Relaxed);
                pool.lock().unwrap_or_else(PoisonError::into_inner).push((ws, z));
            });
            let per_call = |ns: AtomicU64| ns.into_inner() as f64 * 1e-9 / w.freqs.len() as f64;
            best = (best.0.min(per_call(factor_ns)), best.1.min(per_call(z_ns)));
        }
        best
    };
    // one JSON object per line; labels never contain quotes or backslashes
    let json = format!(
        concat!(
            "{{\"label\":\"{}\",\"method\":\"{}\",\"dofs\":{},\"layout\":\"{:?}\",\"factor_nnz\":{},",
            "\"factor_stored\":{},\"factor_madds\":{},\"params\":{},",
            "\"measured\":{},\"freqs\":{},\"threads\":{},\"seconds\":{:e},\"ms_per_freq\":{:e},",
            "\"cpu_ms_per_freq\":{},\"factor_ms_per_freq\":{},\"z_ms_per_freq\":{},\"setup_s\":{:e},",
            "\"peak_kib\":{}}}"
        ),
        w.label,
        if naive { "dense" } else { "sparse" },
        w.sys.n(),
        solver.layout(),
        solver.factor_nnz(),
        solver.factor_stored(),
        solver.factor_multiply_adds(),
        w.params.len(),
        w.channels.len(),
        w.freqs.len(),
        rayon::current_num_threads(),
        best,
        1e3 * best / w.freqs.len() as f64,
        if best_cpu.is_finite() { format!("{:e}", 1e3 * best_cpu / w.freqs.len() as f64) } else { "null".into() },
        if factor.is_finite() { format!("{:e}", 1e3 * factor) } else { "null".into() },
        if z_time.is_finite() { format!("{:e}", 1e3 * z_time) } else { "null".into() },
        setup,
        peak_kib().map_or("null".to_string(), |k| k.to_string()),
    );
    println!("{json}");
}
