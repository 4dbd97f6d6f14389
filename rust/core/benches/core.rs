//! Criterion benches of the core: the inner loop (one RHS evaluation and one RK8 step,
//! for one member and for a batch of 4 lanes) and whole runs (a Monte Carlo ensemble and a
//! CCSP filter). Run: `cargo bench -p rhoprop-core --bench core`.

use criterion::{criterion_group, criterion_main, Criterion};
use rhoprop_core::ccsp::{ccsp, CcspConfig, Coordinates};
use rhoprop_core::density::Exponential;
use rhoprop_core::dynamics::{BatchRhs, Dynamics, Perturbation, State};
use rhoprop_core::integrators::{FixedMethod, FixedStepper};
use rhoprop_core::montecarlo::{monte_carlo, monte_carlo_on};
use rhoprop_core::progress::Progress;
use rhoprop_core::simd::SimdPath;
use std::hint::black_box;

#[path = "common/one_thread.rs"]
mod one_thread;
use one_thread::{one_day_monte_carlo, paper_problem, synthetic_field};

const PAPER: [f64; 6] = rhoprop_core::constants::PAPER_STATE;

fn batch<const W: usize>() -> State<W> {
    PAPER.map(|c| [c; W])
}

fn benches(c: &mut Criterion) {
    let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.0).unwrap();
    let drag = 3.0912 * 0.0015;

    let mut d1 = Dynamics::<_, 1>::new(&atm, 8.4e7, [drag]);
    let y1 = batch::<1>();
    let mut dy1 = [[0.0; 1]; 6];
    c.bench_function("rhs/exponential/1 member", |b| {
        b.iter(|| d1.eval(black_box(60.0), black_box(&y1), &mut dy1).unwrap())
    });

    let mut d4 = Dynamics::<_, 4>::new(&atm, 8.4e7, [drag; 4]);
    let y4 = batch::<4>();
    let mut dy4 = [[0.0; 4]; 6];
    c.bench_function("rhs/exponential/4 members", |b| {
        b.iter(|| d4.eval(black_box(60.0), black_box(&y4), &mut dy4).unwrap())
    });

    let mut d4j6 = Dynamics::<_, 4>::new(&atm, 8.4e7, [drag; 4]);
    d4j6.zonal_degree = 6;
    c.bench_function("rhs/exponential/4 members/J6", |b| {
        b.iter(|| {
            d4j6.eval(black_box(60.0), black_box(&y4), &mut dy4)
                .unwrap()
        })
    });

    let mut stepper1 = FixedStepper::<1>::default();
    c.bench_function("rk8 step/exponential/1 member", |b| {
        let mut y = batch::<1>();
        b.iter(|| {
            stepper1
                .step(FixedMethod::Rk8, &mut d1, 0.0, black_box(180.0), &mut y)
                .unwrap();
            y = batch::<1>();
        })
    });

    let mut stepper4 = FixedStepper::<4>::default();
    c.bench_function("rk8 step/exponential/4 members", |b| {
        let mut y = batch::<4>();
        b.iter(|| {
            stepper4
                .step(FixedMethod::Rk8, &mut d4, 0.0, black_box(180.0), &mut y)
                .unwrap();
            y = batch::<4>();
        })
    });
}

/// Whole runs on the paper's orbit and the benchmark exponential atmosphere (20 % sigma).
fn runs(c: &mut Criterion) {
    let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
    let problem = paper_problem();

    let mut group = c.benchmark_group("monte_carlo");
    group.sample_size(20);
    let mc = one_day_monte_carlo(problem);
    group.bench_function("exponential/64 members x 1 day", |b| {
        b.iter(|| monte_carlo(&atm, black_box(&mc), &Progress::default()).unwrap())
    });
    // The same run on every instruction-set path this CPU has (one thread, so that the
    // paths compare per core).
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let field = synthetic_field(mc.problem.epoch);
    for path in SimdPath::available() {
        group.bench_function(
            format!("exponential/64 members x 1 day/1 thread/{}", path.name()),
            |b| {
                b.iter(|| {
                    one.install(|| monte_carlo_on(path, &atm, black_box(&mc), &Progress::default()))
                        .unwrap()
                })
            },
        );
        group.bench_function(
            format!("gridded/64 members x 1 day/1 thread/{}", path.name()),
            |b| {
                b.iter(|| {
                    one.install(|| {
                        monte_carlo_on(path, &field, black_box(&mc), &Progress::default())
                    })
                    .unwrap()
                })
            },
        );
    }
    group.finish();

    let mut group = c.benchmark_group("ccsp");
    group.sample_size(20);
    // The paper's near-zero initial covariance: 1 mm and 1 um/s.
    let p0: [[f64; 6]; 6] = std::array::from_fn(|i| {
        std::array::from_fn(|j| match (i == j, i < 3) {
            (false, _) => 0.0,
            (true, true) => 1e-6,
            (true, false) => 1e-12,
        })
    });
    let cfg = CcspConfig {
        problem,
        p0,
        update_times: (1..=72).map(|i| i as f64 * 3600.0).collect(),
        output_times: vec![],
        scaling: (3.0, 3.0),
        kappa_scale: 1.0,
        perturbation: Perturbation::Additive,
        method: FixedMethod::Rk8,
        max_step: 180.0,
        drag_sigma: 0.0,
        coordinates: Coordinates::Equinoctial,
        slow: None,
    };
    group.bench_function("exponential/3 days, hourly updates", |b| {
        b.iter(|| ccsp(&atm, black_box(&cfg), &Progress::default()).unwrap())
    });
    group.finish();
}

criterion_group!(core, benches, runs);
criterion_main!(core);
