//! Host time per compensated sample: `cargo bench -p accel-cal-shared --bench compensate`.
//!
//! Prints nanoseconds per call of the full path (lever arms + ω̇), the static-only path and the ω̇
//! estimator, each over 10⁷ samples of the paper's unit spinning at 200 °/s. The operation count of the
//! per-sample path is in the `compensator` module docs (51 multiply-adds against MODEL.md's ~50).

use shared::forward::{ForwardModel, TableState};
use shared::omega_dot::OmegaDotEstimator;
use shared::params::{LeverArms, OutputUnit, ReferencePoint, StaticParams};
use shared::{BodyAngularAccel, BodyRate, Calibration, Compensator, LeverMode, SensorOutputs};
use std::hint::black_box;
use std::time::Instant;

fn paper_unit() -> Calibration {
    Calibration {
        statics: StaticParams {
            output_unit: OutputUnit::Volts,
            zero_bias_out: [2.405098, 2.380978, 2.435503],
            scale_out_per_g: [0.39496, 0.39808, 0.40024],
            installation_angles_deg: [
                [0.75997, 90.71425, 89.74038],
                [89.25516, 0.74486, 90.5630],
                [90.52202, 89.17706, 0.97456],
            ],
        },
        lever_arms: LeverArms {
            r_m: [
                [-0.00834, -0.00042, -0.00132],
                [-0.00256, -0.00893, -0.00026],
                [-0.00060, -0.00050, -0.00824],
            ],
        },
        reference: ReferencePoint::TableAxis,
        gravity_m_s2: shared::STANDARD_GRAVITY_M_S2,
    }
}

fn time_per_call(n: u32, mut f: impl FnMut(u32)) -> f64 {
    let start = Instant::now();
    for i in 0..n {
        f(i);
    }
    start.elapsed().as_secs_f64() * 1e9 / f64::from(n)
}

fn main() {
    let cal = paper_unit();
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
    println!("  full (lever arms + ω̇)   {ns_full:6.2} ns/sample   (51 multiply-adds; MODEL.md floor ~50)");
    println!("  static only              {ns_static:6.2} ns/sample   (12 multiply-adds)");
    println!("  ω̇ estimator update       {ns_wdot:6.2} ns/sample");
}
