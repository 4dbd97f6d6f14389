//! Criterion benches of the inner loop: one RHS evaluation and one RK8 step, for one
//! member and for a batch of 4 lanes. Run: `cargo bench -p rhoprop-core --bench core`.

use criterion::{criterion_group, criterion_main, Criterion};
use rhoprop_core::density::Exponential;
use rhoprop_core::dynamics::{BatchRhs, Dynamics, State};
use rhoprop_core::integrators::{FixedMethod, FixedStepper};
use std::hint::black_box;

const PAPER: [f64; 6] = [
    3782900.7032,
    -5441600.6779,
    -1420075.1327,
    -606.6600,
    1539.2559,
    -7488.3946,
];

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

criterion_group!(core, benches);
criterion_main!(core);
