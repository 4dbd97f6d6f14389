//! Field / exponential cost ratio of the Monte Carlo engine per SIMD path, timed in the
//! thread's own CPU time (Linux `/proc/thread-self/schedstat`), so that other work on a
//! shared machine inflates it far less than wall time: the A/B tool for the field lookup.
//! The runs are the criterion bench's (`benches/core.rs`, "1 thread"): 64 members x 1 day,
//! GaussMarkov 18 min, RK8 180 s, the exponential atmosphere and a synthetic field of the
//! same shape as a sampled NRLMSIS one; rounds alternate the two, the minimum counts.
//!
//! Run: `cargo run --release -p rhoprop-core --example field_ratio [-- ROUNDS [PATH]]`
//! (PATH: avx512f, avx2+fma or portable; default every path this CPU has).

use rhoprop_core::density::{Atmosphere, Exponential};
use rhoprop_core::montecarlo::{monte_carlo_on, MonteCarloConfig};
use rhoprop_core::progress::Progress;
use rhoprop_core::simd::SimdPath;

#[path = "../benches/common/one_thread.rs"]
mod one_thread;
use one_thread::{one_day_monte_carlo, paper_problem, synthetic_field};

/// CPU time of the calling thread, s (Linux).
fn thread_cpu() -> f64 {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").expect("Linux schedstat");
    let ns: f64 = s.split_whitespace().next().unwrap().parse().unwrap();
    ns * 1e-9
}

/// Thread CPU time of one Monte Carlo (s), the mean of 10 runs (about 0.1 s).
fn time<A: Atmosphere + Sync>(
    pool: &rayon::ThreadPool,
    path: SimdPath,
    atm: &A,
    mc: &MonteCarloConfig,
) -> f64 {
    const REPS: usize = 10;
    pool.install(|| {
        let t0 = thread_cpu();
        for _ in 0..REPS {
            std::hint::black_box(monte_carlo_on(path, atm, mc, &Progress::default()).unwrap());
        }
        (thread_cpu() - t0) / REPS as f64
    })
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rounds: usize = args.get(1).map_or(7, |a| a.parse().expect("ROUNDS"));
    let paths: Vec<SimdPath> = SimdPath::available()
        .into_iter()
        .filter(|p| args.get(2).is_none_or(|want| want == p.name()))
        .collect();
    let mc = one_day_monte_carlo(paper_problem());
    let exponential = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
    let field = synthetic_field(mc.problem.epoch);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    for path in paths {
        let (mut e, mut f) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..rounds {
            e = e.min(time(&one, path, &exponential, &mc));
            f = f.min(time(&one, path, &field, &mc));
        }
        println!(
            "{:<9} exponential {:.3} ms  field {:.3} ms  field/exponential speed {:.3}",
            path.name(),
            e * 1e3,
            f * 1e3,
            e / f
        );
    }
}
