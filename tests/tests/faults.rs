//! Faults on the way: a device that dies mid-segment, garbage and truncated frames in both directions,
//! a reset in the middle of a calibration write, and a blob made for another unit.

use device::operator::AutomaticOperator;
use device::procedure::{self, ProcedureError, ProcedureOptions};
use device::LinkError;
use e2e::{paper_unit, sim_client};
use recording::session::builtin::load_plan;
use recording::session::{read_session, ReadOptions};
use shared::blob::{BlobError, ParameterBlob};
use shared::wire::{self, CalibrationState, DeviceError, HostToDevice, StreamKind, HOST_FRAME_MAX};
use shared::UnitId;

fn blob_for(unit: UnitId, created: u64) -> Vec<u8> {
    let b = ParameterBlob {
        unit_id: unit,
        calibration: paper_unit(),
        created_unix_s: created,
    };
    let (bytes, n) = b.to_bytes().unwrap();
    bytes[..n].to_vec()
}

#[test]
fn a_device_that_stops_answering_mid_segment_leaves_the_recording_saved() {
    let out = tempfile::tempdir().unwrap();
    let mut client = sim_client();
    // short-oblique: 2 s segments at 1 kHz plus 0.5 s settling; die in the middle of the 4th segment.
    client
        .transport_mut()
        .stop_answering_after_samples(3 * 2500 + 1200);
    let mut opts = ProcedureOptions::new(
        load_plan("short-oblique").unwrap(),
        out.path().to_path_buf(),
        recording::testkit::SPELLING,
    );
    opts.quiet = true;
    let mut op = AutomaticOperator {
        verbose: false,
        warnings: Vec::new(),
    };
    let err = procedure::run(&mut client, &opts, &mut op).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("stopped answering"), "{msg}");
    assert!(msg.contains("saved in"), "{msg}");
    let ProcedureError::Link {
        recording: Some((dir, rows)),
        ..
    } = err
    else {
        panic!("{err:?}")
    };
    assert!(rows > 0);
    // What was collected reads back: the three finished segments and part of the fourth.
    let session = read_session(&dir, &ReadOptions { quiet: true }).unwrap();
    let names: Vec<_> = session.stats.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["x+", "x-", "y+", "y-"]);
    assert!(session.stats[3].count < session.stats[0].count);
}

#[test]
fn garbage_and_truncated_frames_are_survived_in_both_directions() {
    let mut client = sim_client();
    client.identify().unwrap();

    // Host → device: noise, an over-long frame, a truncated frame, then real requests.
    let mut frame = [0u8; HOST_FRAME_MAX];
    let identify = wire::encode_frame(&HostToDevice::Identify, &mut frame)
        .unwrap()
        .to_vec();
    let dev = client.transport_mut();
    use device::Transport;
    dev.send(&[0x13, 0x37, 0x00, 0xFF, 0xFE, 0x00]).unwrap();
    dev.send(&[0x42; 3 * HOST_FRAME_MAX]).unwrap();
    dev.send(&[0x00]).unwrap();
    dev.send(&identify[..identify.len() / 2]).unwrap();
    dev.send(&[0x00]).unwrap();
    // The device answered each bad frame with a typed error and keeps working.
    let id = client.identify().unwrap();
    assert_eq!(id.calibration, CalibrationState::Missing);
    assert!(
        client.garbage_frames >= 2,
        "typed errors seen: {}",
        client.garbage_frames
    );

    // Device → host: garbage and a truncated frame in the middle of a stream.
    client.start_stream(StreamKind::RawWindows, 50).unwrap();
    client.next_raw_window().unwrap();
    let before = client.garbage_frames;
    client
        .transport_mut()
        .inject_line_garbage(&[0x01, 0x02, 0x03, 0x00, 0x07, 0x09]);
    let mut ok = 0;
    for _ in 0..20 {
        if client.next_raw_window().is_ok() {
            ok += 1;
        }
    }
    assert!(ok >= 19, "windows after garbage: {ok}");
    assert!(client.garbage_frames > before);
    client.stop_stream().unwrap();
    assert!(client.identify().is_ok());
}

#[test]
fn a_reset_during_a_calibration_write_keeps_the_old_calibration() {
    let mut client = sim_client();
    let id = client.identify().unwrap();
    let old = blob_for(id.unit_id, 1000);
    client.write_calibration(&old).unwrap();
    assert_eq!(
        client.reset().unwrap().calibration,
        CalibrationState::Valid {
            created_unix_s: 1000
        }
    );

    // Half of a new blob, then a reset.
    let new = blob_for(id.unit_id, 2000);
    let chunks: Vec<_> = wire::blob_chunks(&new).collect();
    for c in &chunks[..chunks.len() / 2] {
        client.send(&HostToDevice::WriteCalibration(*c)).unwrap();
    }
    let after = client.reset().unwrap();
    assert_eq!(
        after.calibration,
        CalibrationState::Valid {
            created_unix_s: 1000
        }
    );
    assert_eq!(client.read_calibration().unwrap(), old);

    // And the complete new one still goes through afterwards.
    client.write_calibration(&new).unwrap();
    assert_eq!(
        client.reset().unwrap().calibration,
        CalibrationState::Valid {
            created_unix_s: 2000
        }
    );
}

#[test]
fn a_blob_made_for_another_unit_is_refused_and_the_old_one_stays() {
    let mut client = sim_client();
    let id = client.identify().unwrap();
    client.write_calibration(&blob_for(id.unit_id, 7)).unwrap();
    let foreign = blob_for(UnitId(*b"SOMEONE-ELSE"), 8);
    match client.write_calibration(&foreign) {
        Err(LinkError::Device(DeviceError::BlobRejected(BlobError::ForeignUnit))) => {}
        other => panic!("expected a foreign-unit refusal, got {other:?}"),
    }
    assert_eq!(
        client.reset().unwrap().calibration,
        CalibrationState::Valid { created_unix_s: 7 }
    );
}
