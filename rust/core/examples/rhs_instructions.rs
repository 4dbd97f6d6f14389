//! A fixed workload for instruction counting: the Monte Carlo engine on the benchmark
//! exponential atmosphere, 64 members x 1 day, RK8 at 240 s (12 RHS evaluations per step).
//! Run: `cargo build --release --example rhs_instructions -p rhoprop-core &&
//! valgrind --tool=callgrind target/release/examples/rhs_instructions` and divide the
//! instruction total by the member-RHS count it prints.

use rhoprop_core::density::Exponential;
use rhoprop_core::dynamics::Perturbation;
use rhoprop_core::integrators::FixedMethod;
use rhoprop_core::kappa::KappaProcess;
use rhoprop_core::montecarlo::{monte_carlo, MonteCarloConfig};
use rhoprop_core::problem::Problem;
use rhoprop_core::progress::Progress;

fn main() {
    let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).expect("valid atmosphere");
    // RHOPROP_MEMBERS scales the workload (e.g. for perf record).
    let members = std::env::var("RHOPROP_MEMBERS")
        .ok()
        .and_then(|m| m.parse().ok())
        .unwrap_or(64);
    let cfg = MonteCarloConfig {
        problem: Problem {
            epoch: 8.4e7,
            y0: [
                3782900.7032,
                -5441600.6779,
                -1420075.1327,
                -606.66,
                1539.2559,
                -7488.3946,
            ],
            drag: 3.0912 * 0.0015,
            floor_altitude: 120e3,
            zonal_degree: 2,
            forces: rhoprop_core::problem::Forces::AUTO,
        },
        initial_factor: None,
        kappa: KappaProcess::Constant,
        perturbation: Perturbation::Additive,
        method: FixedMethod::Rk8,
        max_step: 240.0,
        output_times: vec![86400.0],
        members,
        seed: 1,
        record_density: false,
        drag_sigma: 0.0,
    };
    let out = monte_carlo(&atm, &cfg, &Progress::default()).expect("run");
    let member_rhs = members as u64 * (86400.0 / 240.0) as u64 * 12;
    println!(
        "member-RHS evaluations: {member_rhs}; x[0] = {}",
        out.positions[0]
    );
}
