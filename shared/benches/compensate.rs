//! Host time per compensated sample: `cargo bench -p shared --bench compensate`.
//!
//! Prints nanoseconds per call of the full path (lever arms + ω̇), the static-only path and the ω̇
//! estimator, each over 10⁷ samples of the paper's unit spinning at 200 °/s. The operation count of the
//! per-sample path is in the `compensator` module docs (51 multiply-adds against docs/model.md §10's ~50).

use shared::forward::{ForwardModel, TableState};
use shared::omega_dot::OmegaDotEstimator;
use shared::{BodyAngularAccel, BodyRate, Compensator, LeverMode, SensorOutputs};
use std::hint::black_box;
use std::time::Instant;

fn time_per_call(n: u32, mut f: impl FnMut(u32)) -> f64 {
    let start = Instant::now();
    for i in 0..n {
        f(i);
    }
    start.elapsed().as_secs_f64() * 1e9 / f64::from(n)
}

fn main() {
    let cal = shared::params::PAPER_UNIT;
    let mut t = TableState::at_rest([1.0, 0.0, 0.0]);
    t.rate_rad_s = 200f64.to_radians();
    let motion = t.motion(cal.gravity_m_s2);
    let u = ForwardModel::new(&cal).unwrap().outputs(&motion);
    let u = SensorOutputs {
        raw: u.raw.map(|v| v as f32),
    };
    let w = BodyRate {
        rad_s: motion.omega.rad_s.map(|v| v as f32),
    };
    let full = Compensator::new(&cal, LeverMode::RateAndAcceleration).unwrap();
    let n = 10_000_000;
    // Vary the input slightly per call so the optimiser cannot hoist the work out of the loop.
    let ns_full = time_per_call(n, |i| {
        let mut ui = u;
        ui.raw[0] += (i & 7) as f32 * 1e-6;
        black_box(full.compensate(
            black_box(&ui),
            black_box(&w),
            black_box(&BodyAngularAccel::default()),
        ));
    });
    let ns_static = time_per_call(n, |i| {
        let mut ui = u;
        ui.raw[0] += (i & 7) as f32 * 1e-6;
        black_box(full.compensate_static(black_box(&ui)));
    });
    let mut est = OmegaDotEstimator::new(1000.0, 20.0).unwrap();
    let ns_wdot = time_per_call(n, |i| {
        let mut wi = w.rad_s;
        wi[0] += (i & 7) as f32 * 1e-6;
        black_box(est.update(black_box(&wi)));
    });
    println!("host time per compensated sample (paper unit, 200 °/s, 10^7 samples):");
    println!("  full (lever arms + ω̇)   {ns_full:6.2} ns/sample   (51 multiply-adds; docs/model.md §10 floor ~50)");
    println!("  static only              {ns_static:6.2} ns/sample   (12 multiply-adds)");
    println!("  ω̇ estimator update       {ns_wdot:6.2} ns/sample");
}
