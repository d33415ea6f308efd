//! `host calibrate --port sim-hand`: the hand-held procedure end to end, as with a board held in the
//! hand and no table (the F405 flight controller on its USB cable). The device is the simulated one,
//! running the firmware's own protocol, pipeline and storage code, without a table; a simulated
//! hand turns it whenever the procedure asks the operator to.

use device::operator::AutomaticOperator;
use device::procedure::{self, ProcedureError, ProcedureOptions};
use device::sim::SimDevice;
use device::sim_hand::HandOperator;
use device::{DeviceClient, LinkError};
use e2e::paper_unit;
use recording::session::builtin::load_plan;
use shared::wire::{Board, CalibrationState};
use std::time::Duration;

fn hand_client() -> DeviceClient<SimDevice> {
    let dev = SimDevice::hand_held(paper_unit()).expect("simulated device boots");
    DeviceClient::new(dev, Duration::from_millis(500))
}

fn options(out: &std::path::Path) -> ProcedureOptions {
    let mut opts = ProcedureOptions::new(
        load_plan("hand").unwrap(),
        out.to_path_buf(),
        recording::testkit::SPELLING,
    );
    opts.quiet = true;
    opts.verify_tolerance_mg = 0.1;
    opts
}

fn quiet() -> AutomaticOperator {
    AutomaticOperator {
        verbose: false,
        warnings: Vec::new(),
    }
}

/// `M·Mᵀ` (output unit² per g²): what the fit determines whatever the body frame's orientation
/// (a rotated frame gives `M·R`, and `M·R·Rᵀ·Mᵀ` is the same).
fn gram(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| m[i][k] * m[j][k]).sum()))
}

#[test]
fn the_hand_held_procedure_calibrates_stores_and_verifies_a_unit_without_a_table() {
    let out = tempfile::tempdir().unwrap();
    let mut client = hand_client();
    let cue = client.transport_mut().hand_cue().expect("held in a hand");
    let mut op = HandOperator {
        inner: quiet(),
        cue,
    };
    let result = procedure::run(&mut client, &options(out.path()), &mut op).unwrap();

    assert_eq!(result.identity.board, Board::SimulatedHand);
    assert!(result.passed, "verification: {:#?}", result.verification);
    assert!(matches!(
        result.state_after_reset,
        CalibrationState::Valid { .. }
    ));
    // Verified by the magnitude of gravity at three new positions (no reference attitude by hand).
    assert_eq!(result.verification.len(), 3);
    assert!(result
        .verification
        .iter()
        .all(|v| v.label.starts_with("hand-held check")));
    assert!(op.inner.warnings.is_empty(), "{:?}", op.inner.warnings);

    // Against the simulator's truth, in what a hand-held session determines: the biases, and M·Mᵀ
    // (scale factors and the angles between the sensing axes). The device's noise is 0.5 mg per
    // sample; each position is 5 s at 1 kHz.
    let truth = paper_unit();
    let est = result.calibrated.outcome.calibration;
    let (m_true, _) = truth.statics.to_fitted().unwrap();
    let (m_est, _) = est.statics.to_fitted().unwrap();
    let (g_true, g_est) = (gram(&m_true.m_out_per_g), gram(&m_est.m_out_per_g));
    let rel = e2e::max_abs_diff(&g_true, &g_est) / g_true[0][0];
    assert!(rel < 5e-5, "M·Mᵀ relative error {rel}");
    for i in 0..3 {
        let e = (truth.statics.zero_bias_out[i] - est.statics.zero_bias_out[i]).abs();
        assert!(e < 1e-5, "bias {i} off by {e} V");
    }
    // The body frame is the stated convention: x along accelerometer x, y in the x–y sensing plane.
    let m = m_est.m_out_per_g;
    // (Zero up to the round trip through installation angles: cos 90° is 6e-17.)
    assert!(
        [m[0][1], m[0][2], m[1][2]].iter().all(|v| v.abs() < 1e-12),
        "{m:?}"
    );
    // No rotation in a hand-held session: no lever arms are claimed.
    assert_eq!(est.lever_arms.r_m, [[0.0; 3]; 3]);

    assert!(result.recording_dir.join("samples.csv").exists());
    assert!(out.path().join("calibration.toml").exists());
}

/// A MEMS gyro's typical errors (0.5 % scale, 0.5° misalignment, 0.5 °/s bias; docs/model.md §8).
fn typical_gyro() -> shared::sensor_models::GyroCorrection {
    let m = 0.5f64.to_radians();
    let b = 0.5f64.to_radians();
    shared::sensor_models::GyroCorrection {
        matrix: [[1.005, m, -m], [-m, 0.995, m], [m, -m, 1.005]],
        bias_rad_s: [b, -b, 0.6 * b],
    }
}

fn mat_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// The live session fits the gyro from the hand's turns, from every window it logged: `G` and `b`
/// are the simulator's, seen in the calibration's body frame (which the accelerometers fix: the
/// frame turned by `R = M_true⁻¹·M_est` from the simulator's), each within 5σ of its own 1σ.
#[test]
fn the_live_hand_held_session_fits_the_gyro_from_its_turns() {
    let out = tempfile::tempdir().unwrap();
    let mut truth = paper_unit();
    truth.gyro = Some(typical_gyro());
    let dev = SimDevice::hand_held(truth).expect("simulated device boots");
    let mut client = DeviceClient::new(dev, Duration::from_millis(500));
    let cue = client.transport_mut().hand_cue().expect("held in a hand");
    let mut op = HandOperator {
        inner: quiet(),
        cue,
    };
    let result = procedure::run(&mut client, &options(out.path()), &mut op).unwrap();
    assert!(result.passed, "verification: {:#?}", result.verification);
    assert!(
        out.path().join("stream.csv").exists(),
        "every window is kept"
    );
    assert_eq!(result.recording_dir, out.path().join("segmented"));

    let outcome = &result.calibrated.outcome;
    let fitted = outcome
        .gyro
        .as_ref()
        .expect("the gyro is fitted from the turns");
    let g_est = outcome.calibration.gyro.expect("[gyro] in the calibration");
    let (m_true, _) = truth.statics.to_fitted().unwrap();
    let (m_est, _) = outcome.calibration.statics.to_fitted().unwrap();
    let m_true_inv = shared::linalg::inverse(&m_true.m_out_per_g).unwrap();
    let r = mat_mul(&m_true_inv, &m_est.m_out_per_g);
    let want = mat_mul(&typical_gyro().matrix, &r);
    for i in 0..3 {
        for j in 0..3 {
            let (got, sigma) = (g_est.matrix[i][j], fitted.matrix_1sigma[i][j]);
            assert!(
                (got - want[i][j]).abs() < 5.0 * sigma,
                "G[{i}][{j}] = {got}, the simulator's {} (1σ {sigma})",
                want[i][j]
            );
        }
        let (got, sigma) = (g_est.bias_rad_s[i], fitted.bias_rad_s_1sigma[i]);
        let b = typical_gyro().bias_rad_s[i];
        assert!(
            (got - b).abs() < 5.0 * sigma,
            "b[{i}] = {got}, the simulator's {b} (1σ {sigma})"
        );
    }
    // A fit, not a copy: G is determined to about 10⁻⁴.
    assert!(fitted
        .matrix_1sigma
        .iter()
        .flatten()
        .all(|s| *s > 0.0 && *s < 5e-4));
}

/// Nobody turns the unit: the procedure says what it waited for, and the recording so far is kept.
#[test]
fn a_unit_nobody_turns_stops_the_procedure_with_what_it_waited_for() {
    let out = tempfile::tempdir().unwrap();
    let mut client = hand_client();
    let mut op = quiet();
    let e = procedure::run(&mut client, &options(out.path()), &mut op).unwrap_err();
    let ProcedureError::Link { cause, recording } = &e else {
        panic!("{e}");
    };
    assert!(
        matches!(cause, LinkError::Unexpected { waiting_for, .. } if waiting_for.contains("still at a new position")),
        "{e}"
    );
    assert!(e.to_string().contains("no new still position"), "{e}");
    assert!(recording.is_some(), "the recording so far is named");
}
