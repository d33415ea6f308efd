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
