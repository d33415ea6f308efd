//! The gyro model estimated from the same session (docs/model.md §8), against the simulator's truth.
//!
//! Short runs (6 seeds, the exact distribution of the segment means) in the normal tests; the full run
//! (20 seeds through the project's simulator, 1 mg and 0.05 °/s white noise at 1 kHz) is ignored and
//! prints every figure:
//!
//! ```text
//! cargo test --release -p host gyro_full -- --ignored --nocapture --test-threads 1
//! ```

use crate::estimate::{EstimateOptions, GyroModel};
use crate::session::builtin::builtin_plan;
use crate::sim::montecarlo::{declared, run, Case, CaseResult, Generator};
use crate::sim::session::gyro_matrix;

/// 0.5 % scale (signs differ per axis), 0.5° misalignment, 0.5 °/s bias.
fn mems_gyro() -> ([[f64; 3]; 3], [f64; 3]) {
    (
        gyro_matrix([5e-3, -5e-3, 5e-3], 0.5f64.to_radians()),
        [
            0.5f64.to_radians(),
            -0.5f64.to_radians(),
            0.5f64.to_radians(),
        ],
    )
}

fn run_case(
    title: &str,
    gyro: Option<([[f64; 3]; 3], [f64; 3])>,
    model: GyroModel,
    seeds: u64,
    g: Generator,
) -> CaseResult {
    let r = run(&Case {
        title: title.into(),
        plan: declared(&builtin_plan("oblique").unwrap().unwrap(), 0.05, 1.0),
        true_tilt_deg: 0.05,
        seeds,
        generator: g,
        options: EstimateOptions {
            gyro_model: model,
            ..EstimateOptions::default()
        },
        norm_only: false,
        gyro,
    });
    r.print();
    r
}

fn gyro_figures(seeds: u64, g: Generator) {
    let perfect = run_case("oblique, perfect gyro", None, GyroModel::Estimate, seeds, g);
    let mems = run_case(
        "oblique, gyro 0.5 % scale, 0.5° misalignment, 0.5 °/s bias, estimated",
        Some(mems_gyro()),
        GyroModel::Estimate,
        seeds,
        g,
    );
    let ignored = run_case(
        "oblique, the same gyro taken as perfect",
        Some(mems_gyro()),
        GyroModel::Perfect,
        seeds,
        g,
    );
    let [s, m, b] = mems.gyro_figures().unwrap();
    let (si, mi) = mems.gyro_intrinsic().unwrap();
    eprintln!(
        "   static: {:.1} µg (perfect gyro {:.1} µg, ratio {:.3}); dynamic: {:.1} µg (perfect gyro {:.1} µg, \
         ratio {:.3}); gyro taken as perfect: static {:.1} µg, dynamic {:.1} µg",
        mems.static_p95_ug(),
        perfect.static_p95_ug(),
        mems.static_p95_ug() / perfect.static_p95_ug(),
        mems.dyn300_ug(),
        perfect.dyn300_ug(),
        mems.dyn300_ug() / perfect.dyn300_ug(),
        ignored.static_p95_ug(),
        ignored.dyn300_ug()
    );
    assert!(si <= 50.0, "scale {si}");
    assert!(mi <= 50.0, "misalignment {mi}");
    assert!(b.0 <= 0.005, "bias {b:?}");
    let _ = (s, m);
    assert!(mems.static_p95_ug() <= 1.1 * perfect.static_p95_ug());
    assert!(mems.dyn300_ug() <= 1.2 * perfect.dyn300_ug());
}

#[test]
fn gyro_short() {
    gyro_figures(6, Generator::Stats);
}
