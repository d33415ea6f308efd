//! The fit under an accelerometer bias random walk (docs/model.md §11), against the simulator's
//! truth and against an oracle: the generalised least squares given the true attitudes and the true
//! walk.
//!
//! `DRIFT_SEEDS=N cargo test -p estimator --lib drift_against_the_oracle -- --nocapture` runs N seeds
//! per walk strength (default 2) on both fixtures and prints every figure; `DRIFT_SEEDS=10` is the
//! documented run (about 10 minutes on two busy cores: the default fit estimates the gyro's walk
//! too).

use super::*;
use crate::sim::montecarlo::{rms, static_errors};
use crate::sim::testkit;
use crate::sim::NoiseModel;
use recording::session::SegmentStats;
use shared::rng::Rng;
use std::collections::BTreeMap;

/// A fixture: how far each mount's true up is from the plan's, and what the plan declares.
#[derive(Clone, Copy, Debug)]
struct Fixture {
    name: &'static str,
    /// 1σ per tilt axis of each mount's true up, and the plan's declared attitude prior, degrees.
    tilt_deg: f64,
}

const FIXTURES: [Fixture; 2] = [
    Fixture {
        name: "exact fixture",
        tilt_deg: 0.0,
    },
    Fixture {
        name: "0.05° fixture",
        tilt_deg: 0.05,
    },
];

/// The 16-mount plan (27 segments of 30 s, 810 s) with the fixture's attitude prior declared.
fn plan(fixture: Fixture) -> Plan {
    testkit::declared(&testkit::many_mounts_plan(), fixture.tilt_deg, 1.0)
}

/// A simulated session's statistics and the true up of every mount.
struct Session {
    stats: Vec<SegmentStats>,
    ups: BTreeMap<String, [f64; 3]>,
}

/// `plan` simulated row by row with 1 mg white noise, mounts tilted by `tilt_deg` and a bias walk
/// of `walk_mg` mg/√s.
fn simulate(plan: &Plan, truth: &Calibration, tilt_deg: f64, walk_mg: f64, seed: u64) -> Session {
    let noise = NoiseModel {
        accel_white_mg: 1.0,
        gyro_white_deg_s: 0.05,
        table_tilt_deg: tilt_deg,
        accel_bias_walk_mg_sqrt_s: walk_mg,
        ..NoiseModel::none()
    };
    let (stats, summary) =
        crate::sim::stats::simulate_stats_with_summary(truth, plan, &noise, seed).unwrap();
    Session {
        stats,
        ups: summary.mount_up_b,
    }
}

/// `plan` with every mount at its true up, exactly (the oracle's attitudes).
fn true_attitudes(plan: &Plan, ups: &BTreeMap<String, [f64; 3]>) -> Plan {
    let mut p = plan.clone();
    p.attitude_sigma_deg = Some(0.0);
    for s in &mut p.segments {
        let name = s.mount_name();
        s.up_b = ups[&name];
        s.mount = Some(name);
    }
    p
}

fn fit(plan: &Plan, stats: &[SegmentStats], walk: BiasWalk) -> CalibrationOutcome {
    let options = match walk {
        // The walk estimated is the tools' default: both walks estimated from the session and
        // used where it determines them.
        BiasWalk::Estimate => EstimateOptions::default().drift_aware(),
        walk => EstimateOptions {
            bias_walk: walk,
            ..EstimateOptions::default()
        },
    };
    calibrate_session_stats(plan, stats, &options).unwrap()
}

/// One fit's figures against the truth.
#[derive(Clone, Copy, Debug, Default)]
struct Figures {
    /// Worst static error on held-out attitudes after the best common rotation, µg.
    static_ug: f64,
    /// RMS lever-arm error, µm.
    lever_um: f64,
    /// Σ (error/σ)² and the count, for biases, scale factors, lever arms.
    z2: [(f64, usize); 3],
}

fn figures(truth: &Calibration, out: &CalibrationOutcome, seed: u64) -> Figures {
    let st = static_errors(truth, &out.fitted, &mut Rng::new(77 + seed, 0));
    let (c, u) = (&out.calibration, &out.uncertainty);
    let mut z2 = [(0.0, 0); 3];
    let mut lever = Vec::new();
    for i in 0..3 {
        let zb =
            (c.statics.zero_bias_out[i] - truth.statics.zero_bias_out[i]) / u.zero_bias_1sigma[i];
        let zk = (c.statics.scale_out_per_g[i] - truth.statics.scale_out_per_g[i])
            / u.scale_per_g_1sigma[i];
        z2[0] = (z2[0].0 + zb * zb, z2[0].1 + 1);
        z2[1] = (z2[1].0 + zk * zk, z2[1].1 + 1);
        for j in 0..3 {
            let e = c.lever_arms.r_m[i][j] - truth.lever_arms.r_m[i][j];
            lever.push(e * 1e6);
            if u.lever_arms_observable[i][j] {
                let z = e / u.lever_arms_m_1sigma[i][j];
                z2[2] = (z2[2].0 + z * z, z2[2].1 + 1);
            }
        }
    }
    Figures {
        static_ug: st.worst_ug,
        lever_um: rms(lever.into_iter()),
        z2,
    }
}

fn seeds() -> u64 {
    std::env::var("DRIFT_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2)
}

/// √(mean z²) over the pooled (Σ z², count) pairs.
fn rms_z(parts: impl Iterator<Item = (f64, usize)>) -> f64 {
    let (s, n) = parts.fold((0.0, 0), |a, p| (a.0 + p.0, a.1 + p.1));
    (s / n.max(1) as f64).sqrt()
}

/// The fits of each walk strength over the seeds: the constant-bias one, the walk given, the
/// walk estimated, the oracle; and the estimated walks.
struct WalkRun {
    walk: f64,
    rows: Vec<[Figures; 4]>,
    estimated: Vec<WalkEstimate>,
}

const FITS: [&str; 4] = ["constant bias", "walk given", "walk estimated", "oracle"];

fn run(fixture: Fixture, walk: f64, seeds: u64) -> WalkRun {
    let truth = testkit::paper_unit();
    let plan = plan(fixture);
    let mut rows = Vec::new();
    let mut estimated = Vec::new();
    for seed in 0..seeds {
        // Each strength its own seeds: the walk's draws scale with its strength, so shared seeds
        // would repeat one walk three times.
        let seed = seed + (walk * 1e6) as u64;
        let s = simulate(&plan, &truth, fixture.tilt_deg, walk, seed);
        let constant = fit(&plan, &s.stats, BiasWalk::Off);
        let given = fit(&plan, &s.stats, BiasWalk::Given(walk));
        let est = fit(&plan, &s.stats, BiasWalk::Estimate);
        let oracle = fit(
            &true_attitudes(&plan, &s.ups),
            &s.stats,
            BiasWalk::Given(walk),
        );
        estimated.push(est.bias_walk.expect("asked for"));
        rows.push([constant, given, est, oracle].map(|o| figures(&truth, &o, seed)));
    }
    WalkRun {
        walk,
        rows,
        estimated,
    }
}

impl WalkRun {
    /// RMS over the seeds of fit `k`'s static error, µg.
    fn static_ug(&self, k: usize) -> f64 {
        rms(self.rows.iter().map(|r| r[k].static_ug))
    }

    /// RMS over the seeds of fit `k`'s lever-arm error, µm.
    fn lever_um(&self, k: usize) -> f64 {
        rms(self.rows.iter().map(|r| r[k].lever_um))
    }

    fn print(&self, fixture: Fixture) {
        println!(
            "{}, walk {} mg/√s, {} seeds: static µg (worst of 26 held-out attitudes, common \
             rotation removed; rms over seeds) | lever arms µm rms | rms error/σ of biases, scales, \
             lever arms",
            fixture.name,
            self.walk,
            self.rows.len()
        );
        for (k, name) in FITS.iter().enumerate() {
            let z: Vec<f64> = (0..3)
                .map(|c| rms_z(self.rows.iter().map(|r| r[k].z2[c])))
                .collect();
            println!(
                "  {name:15} {:7.1} {:7.1}   {:.2} {:.2} {:.2}",
                self.static_ug(k),
                self.lever_um(k),
                z[0],
                z[1],
                z[2]
            );
        }
        let est: Vec<String> = self
            .estimated
            .iter()
            .map(|e| {
                format!(
                    "{:.5}±{:.5}",
                    e.mg_sqrt_s,
                    e.sigma_mg_sqrt_s.unwrap_or(f64::NAN)
                )
            })
            .collect();
        println!("  estimated walk, mg/√s: {}", est.join(" "));
    }
}

/// The estimated walk's error over the side of its likelihood interval the truth lies on.
fn walk_z(e: &WalkEstimate, truth: f64) -> f64 {
    let [lo, hi] = e.interval_mg_sqrt_s.expect("estimated");
    let d = e.mg_sqrt_s - truth;
    d / if d < 0.0 {
        hi - e.mg_sqrt_s
    } else {
        e.mg_sqrt_s - lo
    }
}

/// By default (both walks estimated from the session, used where it determines them), the fit's
/// static error is within 1.2× the oracle's
/// (the fit given the true attitudes and the true walk) where the constant-bias fit reaches its
/// oracle without a walk (the exact fixture); on a 0.05° fixture the fitted attitudes cost a gap to
/// the oracle even without a walk, and the walk may widen that gap by at most 1.2×. The lever arms
/// are no worse than the constant-bias fit's, and the static error with the walk estimated is within
/// 1.1× the fit's given the true walk (which estimates the attitudes as it does); under the walk the 1σ of biases, scale factors and
/// lever arms stay honest (rms error/σ within 30 % of 1, pooled over the seeds and walks); every
/// estimated walk is within 4σ of the simulated one and, over ten seeds or more, its likelihood
/// interval is honest too (rms of (estimated − simulated) over the interval's half on the truth's
/// side within 30 % of 1).
#[test]
fn drift_against_the_oracle() {
    let n = seeds();
    for fixture in FIXTURES {
        let still = run(fixture, 0.0, n);
        still.print(fixture);
        // The fit's own gap to the oracle without a walk: 1 on the exact fixture.
        let gap = still.static_ug(0) / still.static_ug(3);
        let runs: Vec<WalkRun> = [0.001, 0.002, 0.005]
            .iter()
            .map(|&w| run(fixture, w, n))
            .collect();
        for r in &runs {
            r.print(fixture);
            let (est, oracle) = (r.static_ug(2), r.static_ug(3));
            // The fair reference on a tilted fixture: the fit given the true walk, which also
            // estimates the attitudes. Estimating the walk costs at most 10 % over it.
            assert!(
                r.static_ug(2) <= 1.1 * r.static_ug(1),
                "{}: walk estimated {} against given {}",
                r.walk,
                r.static_ug(2),
                r.static_ug(1)
            );
            assert!(
                est <= 1.2 * gap * oracle,
                "{}: {est} against the oracle's {oracle} (gap without a walk {gap})",
                r.walk
            );
            assert!(
                r.lever_um(2) <= r.lever_um(0),
                "{}: lever arms {} against {}",
                r.walk,
                r.lever_um(2),
                r.lever_um(0)
            );
            for e in &r.estimated {
                assert!(walk_z(e, r.walk).abs() < 4.0, "{e:?} against {}", r.walk);
            }
        }
        let z = rms(runs
            .iter()
            .flat_map(|r| r.estimated.iter().map(|e| walk_z(e, r.walk))));
        let sym = rms(runs.iter().flat_map(|r| {
            r.estimated
                .iter()
                .map(|e| (e.mg_sqrt_s - r.walk) / e.sigma_mg_sqrt_s.expect("estimated"))
        }));
        println!(
            "{} (without a walk, the constant-bias fit at {gap:.2}× the oracle's static error): \
             estimated walk − simulated, rms over the likelihood interval's side {z:.2}, over its \
             half-width {sym:.2}",
            fixture.name
        );
        // Ten seeds and more (the documented run) make the rms of the walk's own z a measure.
        if n >= 10 {
            assert!((z - 1.0).abs() < 0.3, "{}: walk: {z}", fixture.name);
        }
        for (c, what) in ["biases", "scale factors", "lever arms"].iter().enumerate() {
            let z = rms_z(
                runs.iter()
                    .flat_map(|r| r.rows.iter().map(|row| row[2].z2[c])),
            );
            println!(
                "{}: rms error/σ of {what}, walk estimated: {z:.2}",
                fixture.name
            );
            assert!((z - 1.0).abs() < 0.3, "{}: {what}: {z}", fixture.name);
        }
    }
}

/// No walk is the constant-bias fit: a zero walk takes the constant-bias path, and the fit is the
/// constant-bias fit bit for bit (the dense path's algebra at no walk is checked in `drift`'s own
/// tests, at one θ, where no iteration can differ).
#[test]
fn a_zero_walk_is_the_constant_bias_fit() {
    let truth = testkit::paper_unit();
    for fixture in FIXTURES {
        let plan = plan(fixture);
        let s = simulate(&plan, &truth, fixture.tilt_deg, 0.0, 7);
        let constant = fit(&plan, &s.stats, BiasWalk::Off);
        let zero = fit(&plan, &s.stats, BiasWalk::Given(0.0));
        assert_eq!(constant.calibration, zero.calibration);
        assert_eq!(constant.uncertainty, zero.uncertainty);
        assert_eq!(constant.covariance, zero.covariance);
        assert_eq!(constant.parameters, zero.parameters);
        assert_eq!(constant.fit, zero.fit);
    }
}

/// The paper's eq. 24 has no weights for a walk: asked for one, it refuses (and without one it
/// runs).
#[test]
fn the_paper_method_refuses_a_walk() {
    let truth = testkit::paper_unit();
    let plan = plan(FIXTURES[0]);
    let s = simulate(&plan, &truth, 0.0, 0.002, 11);
    let paper = EstimateOptions {
        method: Method::Paper,
        ..EstimateOptions::default()
    };
    for walk in [BiasWalk::Given(0.002), BiasWalk::Estimate] {
        let r = calibrate_session_stats(&plan, &s.stats, &paper.with_bias_walk(walk));
        assert!(
            matches!(r, Err(EstimateError::BiasWalkWithPaperMethod)),
            "{walk:?}: {r:?}"
        );
    }
    assert!(calibrate_session_stats(&plan, &s.stats, &paper).is_ok());
}

/// The report's fitted bias per segment follows the simulated walk: its truth is the difference of
/// each segment's mean outputs simulated with and without the walk (the walk has its own random
/// stream, so every other draw is the same). Over eight seeds of a 0.005 mg/√s walk the fitted track
/// leaves less than half of the walk's rms, and its error is the size its 1σ says.
#[test]
fn the_fitted_bias_track_follows_the_simulated_walk() {
    let truth = testkit::paper_unit();
    let plan = plan(FIXTURES[0]);
    let k = truth.statics.scale_out_per_g;
    let (mut err, mut size, mut z) = (Vec::new(), Vec::new(), Vec::new());
    for seed in 0..8 {
        let with = simulate(&plan, &truth, 0.0, 0.005, 900 + seed);
        let without = simulate(&plan, &truth, 0.0, 0.0, 900 + seed);
        let out = fit(&plan, &with.stats, BiasWalk::Given(0.005));
        assert_eq!(out.bias_track.len(), plan.segments.len());
        for p in &out.bias_track {
            let w = with.stats.iter().find(|s| s.name == p.name).unwrap();
            let c = without.stats.iter().find(|s| s.name == p.name).unwrap();
            for a in 0..3 {
                let walk_mg = (w.mean_u[a] - c.mean_u[a]) / k[a] * 1e3;
                err.push(p.bias_mg[a] - walk_mg);
                z.push((p.bias_mg[a] - walk_mg) / p.sigma_mg[a]);
                size.push(walk_mg);
            }
        }
    }
    let (e, s) = (rms(err.into_iter()), rms(size.into_iter()));
    println!("fitted bias track: rms error {e:.4} mg against the walk's rms {s:.4} mg");
    assert!(e < 0.5 * s, "{e} against {s}");
    // The 1σ bars are the error's size: error over 1σ has an rms near 1 (648 points, correlated
    // within a seed, so a wide band; 1σ bars of half or twice the error's spread fail it).
    let zr = rms(z.into_iter());
    println!("fitted bias track: rms of error over its 1σ {zr:.3}");
    assert!((0.7..1.4).contains(&zr), "{zr}");
    let none = fit(
        &plan,
        &simulate(&plan, &truth, 0.0, 0.0, 900).stats,
        BiasWalk::Off,
    );
    assert!(none.bias_track.is_empty());
}

/// The prediction of a plan under a walk (`host plan --check --bias-walk`) is the 1σ a session of
/// it reports with the walk given: the biases' and scale factors' within 2 % over two simulated
/// sessions, and well above the prediction without the walk.
#[test]
fn the_prediction_with_a_walk_is_what_a_session_reports() {
    let truth = testkit::paper_unit();
    let plan = plan(FIXTURES[0]);
    let walk = 0.002;
    let settings = |w: BiasWalk| PredictSettings {
        noise_out_per_sample_1sigma: truth.statics.scale_out_per_g.map(|k| 1e-3 * k),
        gyro_noise_rad_s: 0.05f64.to_radians(),
        options: EstimateOptions::default().with_bias_walk(w),
        ..PredictSettings::white(0.0, recording::testkit::SPELLING)
    };
    let predicted = |w: BiasWalk| {
        let s = settings(w);
        let stats = crate::sim::synth::prediction_stats(&plan, &truth, &s).unwrap();
        predict(&plan, &truth, &stats, &s).unwrap().sigma
    };
    let (with, without) = (predicted(BiasWalk::Given(walk)), predicted(BiasWalk::Off));
    for seed in 0..2 {
        let s = simulate(&plan, &truth, 0.0, walk, 700 + seed);
        let u = fit(&plan, &s.stats, BiasWalk::Given(walk)).uncertainty;
        for i in 0..3 {
            // The paper's order: the zero biases first, then the scale factors.
            let (b, k) = (with[i], with[3 + i]);
            println!(
                "axis {i}: bias 1σ predicted {b:.3e} reported {:.3e}; scale {k:.3e} {:.3e}",
                u.zero_bias_1sigma[i], u.scale_per_g_1sigma[i]
            );
            assert!((u.zero_bias_1sigma[i] / b - 1.0).abs() < 0.02, "bias {i}");
            assert!(
                (u.scale_per_g_1sigma[i] / k - 1.0).abs() < 0.02,
                "scale {i}"
            );
            assert!(b > 2.0 * without[i], "bias {i}: {b} against {}", without[i]);
        }
    }
}

/// A walk taken from the unit is the given walk: in mg/√s per axis it is the same fit bit for bit
/// (only its origin differs); in output unit/√s, `K_i = K_mg · 10⁻³ · k_i` with the true scale
/// factors, it differs only by the fitted against the true `k_i` (parts in 10⁴ of the walk), and
/// its reported strength is that K back in mg/√s.
#[test]
fn a_walk_from_the_unit_is_the_given_walk() {
    let truth = testkit::paper_unit();
    let plan = plan(FIXTURES[0]);
    let s = simulate(&plan, &truth, 0.0, 0.002, 31);
    let given = fit(&plan, &s.stats, BiasWalk::Given(0.002));
    let mg = fit(
        &plan,
        &s.stats,
        BiasWalk::FromUnit(UnitWalk::MgSqrtS([0.002; 3])),
    );
    assert_eq!(given.calibration, mg.calibration);
    assert_eq!(given.uncertainty, mg.uncertainty);
    let (gw, mw) = (given.bias_walk.unwrap(), mg.bias_walk.unwrap());
    assert_eq!(
        (gw.origin, mw.origin),
        (WalkOrigin::Given, WalkOrigin::Unit)
    );
    assert_eq!(mw.axes_mg_sqrt_s, [0.002; 3]);
    let k = truth.statics.scale_out_per_g;
    let out = fit(
        &plan,
        &s.stats,
        BiasWalk::FromUnit(UnitWalk::OutputPerSqrtS(
            k.map(|k| 0.002e-3 * k),
            plan.output_unit,
        )),
    );
    let ow = out.bias_walk.unwrap();
    for a in 0..3 {
        assert!((ow.axes_mg_sqrt_s[a] / 0.002 - 1.0).abs() < 1e-3, "{ow:?}");
        let (b, c) = (
            given.uncertainty.zero_bias_1sigma[a],
            out.uncertainty.zero_bias_1sigma[a],
        );
        assert!((b / c - 1.0).abs() < 1e-3, "{b} {c}");
    }
    // Per axis: a walk assumed on x alone leaves y's and z's biases as precise as a constant bias
    // would (the session's walk on them then shows in χ², which scales every 1σ up, x's too).
    let x_only = fit(
        &plan,
        &s.stats,
        BiasWalk::FromUnit(UnitWalk::MgSqrtS([0.002, 0.0, 0.0])),
    );
    let u = &x_only.uncertainty.zero_bias_1sigma;
    let g = &given.uncertainty.zero_bias_1sigma;
    assert!(
        u[1] < 0.5 * g[1] && u[2] < 0.5 * g[2],
        "{u:?} against {g:?}"
    );
    assert!(u[0] > 2.0 * u[1], "{u:?}");
}

/// A walk of raw outputs is a strength in its own output unit: one in LSB/√s on a session in volts
/// (8.2 LSB/√s would read as 8.2 V/√s) is refused naming both units, not fitted.
#[test]
fn a_walk_in_another_output_unit_is_refused() {
    let truth = testkit::paper_unit();
    let plan = plan(FIXTURES[0]);
    assert_eq!(plan.output_unit, shared::OutputUnit::Volts);
    let s = simulate(&plan, &truth, 0.0, 0.0, 32);
    let options = EstimateOptions {
        bias_walk: BiasWalk::FromUnit(UnitWalk::OutputPerSqrtS([8.2; 3], shared::OutputUnit::Lsb)),
        ..EstimateOptions::default()
    };
    let e = calibrate_session_stats(&plan, &s.stats, &options).unwrap_err();
    assert!(
        matches!(
            e,
            EstimateError::BiasWalkUnit {
                walk: "LSB",
                session: "V"
            }
        ),
        "{e}"
    );
    let m = e.to_string();
    assert!(m.contains("LSB/√s") && m.contains("in V"), "{m}");
}

/// Where the 0.05° fixture's gap to the oracle comes from (docs/model.md §11.5), without a walk:
/// the fit with the plan's prior at the truth's 0.05°, at half and twice it, with the nominal ups
/// taken as exact, and with the true ups as the prior's centres (the attitudes still estimated);
/// the oracle takes the true ups as exact. `DRIFT_SEEDS=48 cargo test -p estimator --lib
/// tilted_fixture_gap -- --ignored --nocapture` prints the figures (`DRIFT_SEED0` the first seed)
/// and checks the comparisons the document draws from them; 48 seeds unless `DRIFT_SEEDS` says.
#[test]
#[ignore]
fn tilted_fixture_gap() {
    let truth = testkit::paper_unit();
    let base = testkit::many_mounts_plan();
    let n = std::env::var("DRIFT_SEEDS").map_or(48, |_| seeds());
    let first: u64 = std::env::var("DRIFT_SEED0")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let names = [
        "prior 0.05° (the fit)",
        "prior 0.025°",
        "prior 0.1°",
        "nominal ups as exact",
        "true ups, prior 0.05°",
        "oracle: true ups exact",
    ];
    let mut rows: Vec<Vec<Figures>> = Vec::new();
    for seed in first..first + n {
        let plan = testkit::declared(&base, 0.05, 1.0);
        let s = simulate(&plan, &truth, 0.05, 0.0, seed);
        let mut centred = true_attitudes(&plan, &s.ups);
        centred.attitude_sigma_deg = Some(0.05);
        let plans = [
            plan.clone(),
            testkit::declared(&base, 0.025, 1.0),
            testkit::declared(&base, 0.1, 1.0),
            testkit::declared(&base, 0.0, 1.0),
            centred,
            true_attitudes(&plan, &s.ups),
        ];
        rows.push(
            plans
                .iter()
                .map(|p| figures(&truth, &fit(p, &s.stats, BiasWalk::Off), seed))
                .collect(),
        );
    }
    let oracle = rms(rows.iter().map(|r| r[5].static_ug));
    let statics: Vec<f64> = (0..names.len())
        .map(|k| rms(rows.iter().map(|r| r[k].static_ug)))
        .collect();
    for (k, name) in names.iter().enumerate() {
        let st = statics[k];
        let z: Vec<f64> = (0..3)
            .map(|c| rms_z(rows.iter().map(|r| r[k].z2[c])))
            .collect();
        println!(
            "{name:24} static {st:6.2} µg ({:.2}× the oracle)  lever {:6.1} µm  error/σ {:.2} {:.2} {:.2}",
            st / oracle,
            rms(rows.iter().map(|r| r[k].lever_um)),
            z[0],
            z[1],
            z[2]
        );
    }
    // docs/model.md §11.5 (48 seeds): halving the prior, doubling it or centring it on the truth
    // moves the static error by under 0.5 %; the nominal ups taken as exact cost it a hundred-fold; the
    // oracle, handed the true ups, is the lower bound.
    for k in [1, 2, 4] {
        let moved = (statics[k] / statics[0] - 1.0).abs();
        assert!(moved < 0.005, "{}: {moved}", names[k]);
    }
    assert!(statics[3] > 10.0 * statics[0], "{statics:?}");
    assert!(statics.iter().all(|&st| st >= oracle), "{statics:?}");
}
