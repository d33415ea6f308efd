//! `host calibrate --port sim`: the whole loop against the in-process simulated device, which runs the
//! firmware's own protocol, pipeline and storage code.

use device::operator::AutomaticOperator;
use device::procedure::{self, ProcedureOptions};
use e2e::{max_abs_diff, paper_unit, sim_client};
use recording::session::builtin::load_plan;
use shared::wire::CalibrationState;

#[test]
fn calibrate_flash_verify_against_the_simulated_device() {
    let out = tempfile::tempdir().unwrap();
    let mut client = sim_client();
    let mut opts = ProcedureOptions::new(
        load_plan("short-oblique").unwrap(),
        out.path().to_path_buf(),
        recording::testkit::SPELLING,
    );
    opts.quiet = true;
    opts.verify_tolerance_mg = 0.1;
    let mut op = AutomaticOperator {
        verbose: false,
        warnings: Vec::new(),
    };
    let result = procedure::run(&mut client, &opts, &mut op).unwrap();

    assert!(result.passed, "verification: {:#?}", result.verification);
    assert!(matches!(
        result.state_after_reset,
        CalibrationState::Valid { .. }
    ));
    assert_eq!(result.verification.len(), 5);
    assert!(result.warnings.is_empty(), "{:?}", result.warnings);

    // Recovered parameters against the simulator's truth (the device's noise is 0.5 mg per sample).
    let truth = paper_unit();
    let est = result.calibrated.outcome.calibration;
    let (m_true, _) = truth.statics.to_fitted().unwrap();
    let (m_est, _) = est.statics.to_fitted().unwrap();
    let rel = max_abs_diff(&m_true.m_out_per_g, &m_est.m_out_per_g) / 0.4;
    assert!(rel < 2e-4, "M relative error {rel}");
    for i in 0..3 {
        assert!((truth.statics.zero_bias_out[i] - est.statics.zero_bias_out[i]).abs() < 1e-4);
    }
    let r_err = max_abs_diff(&truth.lever_arms.r_m, &est.lever_arms.r_m);
    assert!(r_err < 2e-4, "lever arms off by {r_err} m");

    // Everything the procedure promised is on disk: the recording and both result files.
    assert!(result.recording_dir.join("samples.csv").exists());
    assert!(out.path().join("calibration.toml").exists());
    assert_eq!(
        std::fs::read(out.path().join("calibration.bin")).unwrap(),
        result.written.blob
    );
}
