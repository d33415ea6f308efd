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
use crate::sim::montecarlo::{run, Case, CaseResult, Generator};
use crate::sim::session::gyro_matrix;
use crate::sim::testkit::declared;
use recording::session::builtin::builtin_plan;

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
    table_rate_error: bool,
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
        table_rate_error,
    });
    r.print();
    r
}

fn gyro_figures(seeds: u64, g: Generator) {
    let perfect = run_case(
        "oblique, perfect gyro",
        None,
        GyroModel::Estimate,
        seeds,
        g,
        false,
    );
    let mems = run_case(
        "oblique, gyro 0.5 % scale, 0.5° misalignment, 0.5 °/s bias, estimated",
        Some(mems_gyro()),
        GyroModel::Estimate,
        seeds,
        g,
        false,
    );
    let ignored = run_case(
        "oblique, the same gyro taken as perfect",
        Some(mems_gyro()),
        GyroModel::Perfect,
        seeds,
        g,
        false,
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

/// The reported 1σ against the spread, with the table's rate error drawn from the plan's own
/// accuracy (the default, 10 ppm): the gyro's scale factors cannot be better than the table's rate.
fn gyro_sigma(seeds: u64, g: Generator) -> [(f64, f64); 3] {
    let r = run_case(
        "oblique, the same gyro, table rate error drawn with the plan's 1σ",
        Some(mems_gyro()),
        GyroModel::Estimate,
        seeds,
        g,
        true,
    );
    r.gyro_figures().unwrap()
}

#[test]
#[ignore = "Monte Carlo, 20 seeds through the simulator: run with --release (see the module docs)"]
fn gyro_full() {
    gyro_figures(20, Generator::Rows);
    let [s, m, b] = gyro_sigma(20, Generator::Rows);
    for (name, (_, ratio)) in [("scale", s), ("misalignment", m), ("bias", b)] {
        assert!((0.7..=1.3).contains(&ratio), "{name}: spread/σ {ratio:.2}");
    }
}

#[test]
fn gyro_short() {
    gyro_figures(6, Generator::Stats);
}

/// A dynamic model that misfits (the spin-ups' tangential term `ω̇ × r` left out) must not move the
/// static parameters beyond their 1σ: their information comes from the rest segments, and a spin
/// whose mount has a rest segment enters as its difference from it.
#[test]
fn a_dynamic_misfit_does_not_move_the_static_parameters() {
    use crate::estimate::{calibrate_session_stats, paper_labels, paper_values};
    use crate::sim::testkit::{self, TableErrors};
    // The oblique plan plus a spin-up of 20 → 200 °/s in 3 s on each oblique mount (ω̇ ≈ 1 rad/s²,
    // a tangential term of about 1 mg), which has a rest segment.
    let mut plan = declared(&builtin_plan("oblique").unwrap().unwrap(), 0.05, 1.0);
    let obliques: Vec<recording::session::SegmentPlan> = plan
        .segments
        .iter()
        .filter(|s| s.is_static() && s.up_b.iter().filter(|c| c.abs() > 0.5).count() == 2)
        .cloned()
        .collect();
    assert_eq!(obliques.len(), 3);
    for o in obliques {
        plan.segments.push(recording::session::SegmentPlan {
            name: format!("{} ramp", o.name),
            rate_deg_s: 20.0,
            rate_end_deg_s: Some(200.0),
            duration_s: Some(3.0),
            ..o
        });
    }
    let truth = testkit::paper_unit();
    let moved = |options: &EstimateOptions| {
        let mut worst = 0.0f64;
        for seed in 0..4 {
            let errors = TableErrors {
                attitude_deg: 0.05,
                gyro_noise_rad_s: 0.05f64.to_radians(),
                gyro: Some(mems_gyro()),
                ..TableErrors::default()
            };
            let mut rng = shared::rng::Rng::new(500 + seed, 0);
            let noise = 1e-3 * truth.statics.scale_out_per_g[0];
            let stats = testkit::noisy_stats(&plan, &truth, noise, errors, &mut rng);
            let good = calibrate_session_stats(&plan, &stats, options).unwrap();
            let misfit = EstimateOptions {
                use_omega_dot: false,
                ..options.clone()
            };
            let bad = calibrate_session_stats(&plan, &stats, &misfit).unwrap();
            assert!(
                bad.fit.reduced_chi2 > 1.5,
                "the misfit is visible: {:?}",
                bad.fit
            );
            let a = paper_values(&good.calibration).unwrap();
            let b = paper_values(&bad.calibration).unwrap();
            for p in 0..15 {
                let z = (a[p] - b[p]).abs() / good.covariance[p][p].sqrt();
                if z > worst {
                    eprintln!("seed {seed} {}: moved {z:.2}σ", paper_labels()[p]);
                }
                worst = worst.max(z);
            }
        }
        worst
    };
    let joint = moved(&EstimateOptions::default());
    let rest = moved(&EstimateOptions {
        static_from_rest: true,
        ..EstimateOptions::default()
    });
    eprintln!(
        "worst static move: joint fit (default) {joint:.2}σ, static from rest segments {rest:.2}σ"
    );
    assert!(joint <= 1.0, "{joint}");
    assert!(rest <= 1.0, "{rest}");
}
