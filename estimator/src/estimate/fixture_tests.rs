//! The imperfect fixture and free attitudes (docs/model.md §7), against the simulator's truth.
//!
//! Short runs (6 seeds, the exact distribution of the segment means, the plans' full segment
//! lengths) assert the figures in the normal tests; the full runs (20 seeds, the project's simulator
//! row by row, 1 mg and 0.05 °/s white noise at 1 kHz) are `#[ignore]`d, print every figure and
//! assert the same bounds plus the body frame's 1σ:
//!
//! ```text
//! cargo test --release -p host fixture_full -- --ignored --nocapture --test-threads 1
//! ```

use crate::estimate::EstimateOptions;
use crate::sim::montecarlo::{run, Case, CaseResult, Generator};
use crate::sim::testkit::{declared, many_mounts_plan};
use recording::session::builtin::builtin_plan;
use recording::session::Plan;

fn oblique() -> Plan {
    builtin_plan("oblique").unwrap().unwrap()
}

fn hand() -> Plan {
    builtin_plan("hand").unwrap().unwrap()
}

fn case(
    title: &str,
    plan: Plan,
    true_tilt_deg: f64,
    seeds: u64,
    generator: Generator,
) -> CaseResult {
    let r = run(&Case {
        title: title.into(),
        plan,
        true_tilt_deg,
        seeds,
        generator,
        options: EstimateOptions::default(),
        norm_only: false,
        gyro: None,
        table_rate_error: false,
    });
    r.print();
    r
}

/// 0.05° per mount, declared: static, lever-arm and dynamic bounds; with `check_frame`, the body
/// frame's error against its reported 1σ.
fn fixture_005(
    title: &str,
    plan: &Plan,
    seeds: u64,
    g: Generator,
    check_frame: bool,
    lever_bound_m: Option<f64>,
) {
    let r = case(title, declared(plan, 0.05, 1.0), 0.05, seeds, g);
    assert!(
        r.static_p95_ug() <= 15.0,
        "static {:.1} µg",
        r.static_p95_ug()
    );
    assert!(r.dyn200_ug() <= 50.0, "dynamic {:.1} µg", r.dyn200_ug());
    if let Some(b) = lever_bound_m {
        assert!(
            r.lever_worst_rms_m() <= b,
            "lever arms {:.1} µm",
            r.lever_worst_rms_m() * 1e6
        );
    }
    if check_frame {
        let q = r.body_ratio();
        assert!((0.7..=1.3).contains(&q), "body frame spread / 1σ = {q:.2}");
    }
}

fn fixture_02(title: &str, plan: &Plan, seeds: u64, g: Generator, lever_bound_m: Option<f64>) {
    let r = case(title, declared(plan, 0.2, 1.0), 0.2, seeds, g);
    assert!(
        r.static_p95_ug() <= 20.0,
        "intrinsic {:.1} µg",
        r.static_p95_ug()
    );
    if let Some(b) = lever_bound_m {
        assert!(
            r.lever_worst_rms_m() <= b,
            "lever arms {:.1} µm",
            r.lever_worst_rms_m() * 1e6
        );
    }
}

/// An exact fixture declared exact is the estimator without attitude unknowns; declared 0.05°
/// the loss is small.
fn exact(plan: &Plan, seeds: u64, g: Generator) {
    let a = case(
        "oblique, exact fixture, declared exact",
        declared(plan, 0.0, 1.0),
        0.0,
        seeds,
        g,
    );
    let b = case(
        "oblique, exact fixture, declared 0.05°",
        declared(plan, 0.05, 1.0),
        0.0,
        seeds,
        g,
    );
    eprintln!(
        "   loss from declaring 0.05° on an exact fixture: static {:.1} → {:.1} µg, dynamic {:.1} → {:.1} µg, \
         lever arms {:.1} → {:.1} µm",
        a.static_p95_ug(),
        b.static_p95_ug(),
        a.dyn200_ug(),
        b.dyn200_ug(),
        a.lever_worst_rms_m() * 1e6,
        b.lever_worst_rms_m() * 1e6
    );
    assert!(a.static_p95_ug() <= 15.0 && b.static_p95_ug() <= 15.0);
    assert!(
        b.dyn200_ug() <= 1.5 * a.dyn200_ug() + 5.0,
        "{} vs {}",
        b.dyn200_ug(),
        a.dyn200_ug()
    );
}

/// 24 free hand positions, 5 s each: the intrinsic error (rms after the best rotation) and the
/// norm-only method on the same data.
fn hand_positions(seeds: u64, g: Generator) {
    let r = run(&Case {
        title: "hand-held, 24 free positions, 5 s each".into(),
        plan: hand(),
        true_tilt_deg: 0.0,
        seeds,
        generator: g,
        options: EstimateOptions::default(),
        norm_only: true,
        gyro: None,
        table_rate_error: false,
    });
    r.print();
    assert!(
        r.static_rms_ug() <= 15.0,
        "intrinsic rms {:.1} µg",
        r.static_rms_ug()
    );
    let (_, norm_rms) = r.norm_only_ug().unwrap();
    // Same information, same estimator when the noise is isotropic in g: not worse.
    assert!(
        r.static_rms_ug() <= 1.02 * norm_rms,
        "{} vs {norm_rms}",
        r.static_rms_ug()
    );
}

fn wrongly_declared(seeds: u64, g: Generator) {
    let r = case(
        "oblique, true 0.2°, declared 0.01°",
        declared(&oblique(), 0.01, 1.0),
        0.2,
        seeds,
        g,
    );
    assert_eq!(r.warned(), r.seeds.len());
}

#[test]
fn fixture_short_tilt_005_oblique() {
    fixture_005(
        "short: oblique, 0.05° per mount, declared",
        &oblique(),
        6,
        Generator::Stats,
        false,
        Some(30e-6),
    );
}

#[test]
fn fixture_short_tilt_02_oblique() {
    fixture_02(
        "short: oblique, 0.2° per mount, declared",
        &oblique(),
        6,
        Generator::Stats,
        Some(40e-6),
    );
}

#[test]
fn fixture_short_exact() {
    exact(&oblique(), 6, Generator::Stats);
}

#[test]
fn fixture_short_hand() {
    hand_positions(6, Generator::Stats);
}

#[test]
fn fixture_short_wrongly_declared() {
    wrongly_declared(6, Generator::Stats);
}

#[test]
fn fixture_short_rows() {
    // The simulator row by row, two seeds, 2 s segments: the whole chain (shared tilt per mount in
    // the simulator, statistics, estimator). Noise is √30 larger than the 60 s plan's, so the bounds
    // are the full run's × √30 on the noise-driven figures.
    let r = case(
        "short rows: oblique at 2 s per segment, 0.05°",
        declared(&oblique(), 0.05, 1.0 / 30.0),
        0.05,
        2,
        Generator::Rows,
    );
    let k = 30f64.sqrt();
    assert!(r.static_p95_ug() <= 15.0 * k, "{}", r.static_p95_ug());
    assert!(r.dyn200_ug() <= 50.0 * k, "{}", r.dyn200_ug());
}

#[test]
#[ignore = "Monte Carlo, 20 seeds through the simulator: run with --release (see the module docs)"]
fn fixture_full() {
    let g = Generator::Rows;
    let n = 20;
    fixture_005(
        "oblique, 0.05° per mount, declared",
        &oblique(),
        n,
        g,
        true,
        Some(30e-6),
    );
    fixture_005(
        "16 mounts, 0.05° per mount, declared",
        &many_mounts_plan(),
        n,
        g,
        true,
        None,
    );
    fixture_02(
        "oblique, 0.2° per mount, declared",
        &oblique(),
        n,
        g,
        Some(40e-6),
    );
    fixture_02(
        "16 mounts, 0.2° per mount, declared",
        &many_mounts_plan(),
        n,
        g,
        None,
    );
    exact(&oblique(), n, g);
    hand_positions(n, g);
    wrongly_declared(n, g);
}

#[test]
#[ignore = "Monte Carlo, the fixture-error table of docs/model.md §7: run with --release"]
fn fixture_full_table() {
    let g = Generator::Rows;
    let plan = many_mounts_plan();
    let mut rows = Vec::new();
    for tilt in [0.0, 0.01, 0.05, 0.2] {
        let exact = case(
            &format!("16 mounts, tilt {tilt}°, declared exact (the old estimator)"),
            declared(&plan, 0.0, 1.0),
            tilt,
            20,
            g,
        );
        let prior = case(
            &format!("16 mounts, tilt {tilt}°, default prior 0.05°"),
            declared(&plan, 0.05, 1.0),
            tilt,
            20,
            g,
        );
        rows.push((tilt, exact.static_p95_ug(), prior.static_p95_ug()));
    }
    // docs/model.md §7: with attitude unknowns the static error does not grow with the tilt (11.3
    // µg at every tilt); taken as exact, a tilt of 0.01° already costs it twenty-fold.
    let untilted = rows[0].2;
    for &(tilt, exact, prior) in &rows {
        assert!(
            prior <= 1.1 * untilted,
            "{tilt}°: {prior} µg against {untilted}"
        );
        if tilt > 0.0 {
            assert!(exact >= 10.0 * prior, "{tilt}°: {exact} µg against {prior}");
        }
    }
}
