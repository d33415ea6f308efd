//! Estimator tests against the generator's known truth (`testkit`).

use super::testkit::{self, Rng, TableErrors};
use super::*;
use crate::recording::OutputUnitName;

const MG: f64 = 1e-3;

fn paper_noise(truth: &Calibration) -> f64 {
    // 1 mg per sample in the output unit (scale of the x axis).
    MG * truth.statics.scale_out_per_g[0]
}

#[test]
fn noise_free_paper_session_recovers_the_unit_exactly() {
    let truth = testkit::paper_unit();
    let plan = testkit::paper_plan(OutputUnitName::V);
    let unit = shared::forward::ForwardModel::new(&truth).unwrap();
    let noise = synth::SynthNoise {
        out_1sigma: [paper_noise(&truth); 3],
        gyro_1sigma_rad_s: 0.0,
        sample_rate_hz: 1000.0,
    };
    let stats = synth::plan_stats(&plan, &unit, &noise, 60.0);
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    let want = paper_values(&truth).unwrap();
    let got = paper_values(&out.calibration).unwrap();
    for p in 0..PAPER_LEN {
        assert!(
            (want[p] - got[p]).abs() < 1e-9 * want[p].abs().max(1e-3),
            "{}: {} vs {}",
            paper_labels()[p],
            got[p],
            want[p]
        );
    }
    assert!(out.excluded.is_empty(), "{:?}", out.excluded);
    // The paper's plan leaves the across-axis components undetermined to 200 µm.
    for i in 0..3 {
        for j in 0..3 {
            assert_eq!(out.observability.observable[i][j], i == j, "r{i}{j}");
        }
    }
    let text = crate::report::render(&out);
    assert!(text.contains("Table 1") && text.contains("n.d."), "{text}");
}

/// Results of a Monte Carlo over seeds.
struct Mc {
    /// Estimate − truth, paper form.
    err: Vec<[f64; PAPER_LEN]>,
    /// Reported 1σ.
    sigma: Vec<[f64; PAPER_LEN]>,
    /// Max static error over 26 held-out attitudes and 3 axes, µg.
    static_ug: Vec<f64>,
    /// The other method's lever-arm errors (when compared).
    other_lever_err: Vec<[[f64; 3]; 3]>,
    outcomes: Vec<CalibrationOutcome>,
}

/// Worst static error on 26 random attitudes, compensated with the estimate's static part, µg.
fn held_out_static_error_ug(truth: &Calibration, est: &FittedStatic, rng: &mut Rng) -> f64 {
    let unit = shared::forward::ForwardModel::new(truth).unwrap();
    let minv = shared::linalg::inverse(&est.m_out_per_g).unwrap();
    let mut worst = 0.0f64;
    for _ in 0..26 {
        let up = rng.unit_vector();
        let st = shared::forward::TableState::at_rest(up);
        let u = unit.outputs(&st.motion(truth.gravity_m_s2)).raw;
        let du: [f64; 3] = core::array::from_fn(|i| u[i] - est.zero_bias_out[i]);
        let f = shared::linalg::mat_vec(&minv, &du);
        for i in 0..3 {
            worst = worst.max((f[i] - up[i]).abs() * 1e6);
        }
    }
    worst
}

fn monte_carlo(
    seeds: u64,
    plan: &Plan,
    truth_of: &dyn Fn(&mut Rng) -> Calibration,
    noise_mg: f64,
    errors: TableErrors,
    options: &EstimateOptions,
) -> Mc {
    let mut mc = Mc {
        err: Vec::new(),
        sigma: Vec::new(),
        static_ug: Vec::new(),
        other_lever_err: Vec::new(),
        outcomes: Vec::new(),
    };
    for seed in 0..seeds {
        let mut rng = Rng::new(seed);
        let truth = truth_of(&mut rng);
        let noise = noise_mg * MG * truth.statics.scale_out_per_g[0];
        let stats = testkit::noisy_stats(plan, &truth, noise, errors, &mut rng);
        let out = calibrate_session_stats(plan, &stats, options).unwrap();
        let want = paper_values(&truth).unwrap();
        let got = paper_values(&out.calibration).unwrap();
        mc.err.push(core::array::from_fn(|p| got[p] - want[p]));
        mc.sigma.push(core::array::from_fn(|p| out.covariance[p][p].sqrt()));
        mc.static_ug
            .push(held_out_static_error_ug(&truth, &out.fitted, &mut rng));
        if let Some(c) = &out.comparison {
            mc.other_lever_err.push(core::array::from_fn(|i| {
                core::array::from_fn(|j| c.lever_arms.r_m[i][j] - truth.lever_arms.r_m[i][j])
            }));
        }
        mc.outcomes.push(out);
    }
    mc
}

fn percentile(mut v: Vec<f64>, q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    let k = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1;
    v[k]
}

fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0.0);
    for x in v {
        s += x * x;
        n += 1.0;
    }
    (s / n).sqrt()
}

impl Mc {
    /// Std of (error / reported σ) per value: 1 when the reported σ matches the spread.
    fn z_std(&self, p: usize) -> f64 {
        rms(self.err.iter().zip(&self.sigma).map(|(e, s)| e[p] / s[p]))
    }
    /// Observed spread / mean reported σ.
    fn sigma_ratio(&self, p: usize) -> f64 {
        let spread = rms(self.err.iter().map(|e| e[p]));
        let mean_sigma = self.sigma.iter().map(|s| s[p]).sum::<f64>() / self.sigma.len() as f64;
        spread / mean_sigma
    }
    fn lever_err(&self, i: usize, j: usize) -> Vec<f64> {
        self.err.iter().map(|e| e[15 + 3 * i + j].abs()).collect()
    }
    fn print(&self, title: &str) {
        let labels = paper_labels();
        eprintln!("== {title}: {} seeds", self.err.len());
        eprintln!(
            "   static held-out error: 95th percentile {:.2} µg, max {:.2} µg",
            percentile(self.static_ug.clone(), 0.95),
            percentile(self.static_ug.clone(), 1.0)
        );
        for p in 0..PAPER_LEN {
            let scale = if p >= 15 { 1e6 } else { 1.0 };
            eprintln!(
                "   {:<8} rms err {:>12.4e}  mean σ {:>12.4e}  spread/σ {:.3}  std(z) {:.3}{}",
                labels[p],
                rms(self.err.iter().map(|e| e[p])) * scale,
                self.sigma.iter().map(|s| s[p]).sum::<f64>() / self.sigma.len() as f64 * scale,
                self.sigma_ratio(p),
                self.z_std(p),
                if p >= 15 { "  (µm)" } else { "" }
            );
        }
    }
}

#[test]
fn paper_unit_paper_plan_monte_carlo() {
    let plan = testkit::paper_plan(OutputUnitName::V);
    let truth = testkit::paper_unit();
    let mc = monte_carlo(
        120,
        &plan,
        &|_| truth,
        1.0,
        TableErrors::default(),
        &EstimateOptions::default(),
    );
    mc.print("paper unit, paper plan, 1 mg at 1 kHz");
    let p95 = percentile(mc.static_ug.clone(), 0.95);
    assert!(p95 <= 15.0, "static held-out error 95th percentile {p95:.2} µg");
    for i in 0..3 {
        let e = percentile(mc.lever_err(i, i), 0.95);
        assert!(e <= 10e-6, "r{}{} 95th percentile error {:.2} µm", i + 1, i, e * 1e6);
    }
    for p in 0..PAPER_LEN {
        let z = mc.z_std(p);
        let r = mc.sigma_ratio(p);
        assert!((0.7..=1.3).contains(&z), "{}: std(err/σ) = {z:.3}", paper_labels()[p]);
        assert!((0.7..=1.3).contains(&r), "{}: spread/σ = {r:.3}", paper_labels()[p]);
    }
    // No segment is flagged or excluded on clean data (beyond chance).
    let flagged: usize = mc.outcomes.iter().map(|o| o.excluded.len()).sum();
    assert_eq!(flagged, 0);
}
