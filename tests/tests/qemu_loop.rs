//! The firmware in QEMU over a pty: `host calibrate --port <pty>` works exactly as against a board.
//! Needs `qemu-system-arm` and the thumb target, which `scripts/test-all.sh` installs; it runs them with
//! `cargo test -p e2e --test qemu_loop -- --ignored`.

use device::operator::AutomaticOperator;
use device::procedure::{self, ProcedureOptions};
use device::serial::{SerialTransport, DEFAULT_BAUD};
use device::DeviceClient;
use e2e::qemu::{build_firmware, Qemu};
use e2e::{max_abs_diff, paper_unit};
use recording::session::builtin::load_plan;
use shared::wire::{CalibrationState, StreamKind, VirtualTable};
use std::time::Duration;

fn connect(qemu: &Qemu) -> DeviceClient<SerialTransport> {
    let port = SerialTransport::open(&qemu.pty, DEFAULT_BAUD).expect("open the QEMU pty");
    // QEMU polls a fresh pty about once a second: allow a generous first answer.
    DeviceClient::new(port, Duration::from_secs(5))
}

#[test]
#[ignore = "needs qemu-system-arm and the thumbv7em target: run by scripts/test-all.sh"]
fn calibrate_the_emulated_board_over_its_pty_and_survive_a_reset() {
    let elf = build_firmware().unwrap();
    let mut qemu = Qemu::start(&elf).unwrap();
    let mut client = connect(&qemu);
    let id = client.identify().unwrap();
    assert_eq!(id.calibration, CalibrationState::Missing);

    let out = tempfile::tempdir().unwrap();
    let mut opts = ProcedureOptions::new(
        load_plan("quick-oblique").unwrap(),
        out.path().to_path_buf(),
        recording::testkit::SPELLING,
    );
    opts.quiet = true;
    opts.verify_tolerance_mg = 0.1;
    let mut op = AutomaticOperator {
        verbose: true,
        warnings: Vec::new(),
    };
    let result = procedure::run(&mut client, &opts, &mut op).unwrap();
    assert!(result.passed, "verification: {:#?}", result.verification);
    assert!(result
        .verification
        .iter()
        .any(|v| v.rate_deg_s.abs() >= 200.0));

    // Against the virtual sensor's truth (the paper's unit).
    let truth = paper_unit();
    let (m_true, _) = truth.statics.to_fitted().unwrap();
    let (m_est, _) = result
        .calibrated
        .outcome
        .calibration
        .statics
        .to_fitted()
        .unwrap();
    assert!(max_abs_diff(&m_true.m_out_per_g, &m_est.m_out_per_g) < 2e-4);
    assert!(
        max_abs_diff(
            &truth.lever_arms.r_m,
            &result.calibrated.outcome.calibration.lever_arms.r_m
        ) < 3e-4
    );

    // A second reset: the calibration is still there and still applied.
    let again = client.reset().unwrap();
    assert_eq!(again.calibration, result.state_after_reset);
    client
        .set_table(VirtualTable {
            up_b: [0.0, 0.0, -1.0],
            rate_rad_s: 0.0,
            accel_rad_s2: 0.0,
        })
        .unwrap();
    client
        .start_stream(StreamKind::CompensatedWindows, 1000)
        .unwrap();
    client.next_compensated_window().unwrap();
    let w = client.next_compensated_window().unwrap();
    client.stop_stream().unwrap();
    let g = truth.gravity_m_s2;
    let err_mg = [
        w.mean_m_s2[0] as f64,
        w.mean_m_s2[1] as f64,
        w.mean_m_s2[2] as f64 + g,
    ]
    .iter()
    .map(|e| e.abs() / g * 1e3)
    .fold(0.0, f64::max);
    assert!(err_mg < 0.1, "z-down after a second reset: {err_mg} mg");
    assert!(qemu.running(), "the firmware must still be running");
}
