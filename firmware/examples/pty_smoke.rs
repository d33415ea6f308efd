//! End-to-end smoke test of the QEMU firmware over its serial pty (PC program, std).
//!
//! `cargo run --example pty_smoke --target x86_64-unknown-linux-gnu -- /dev/pts/N`
//! (scripts/run-qemu.sh prints N). Identify (retrying while QEMU connects the pty), set the virtual
//! table to 200 °/s about x with x up, write the paper unit's calibration in chunks, stream
//! compensated windows and check they give (g, 0, 0), reset, and check the calibration came back.
//! Exits non-zero on the first failure.

use std::io::{Read, Write};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use firmware::paper_unit::{self, QEMU_UNIT_ID};
use shared::blob::ParameterBlob;
use shared::wire::{
    blob_chunks, decode_frame, encode_frame, Ack, CalibrationState, DeviceToHost, HostToDevice,
    StreamKind, StreamRequest, VirtualTable, HOST_FRAME_MAX,
};

const CREATED: u64 = 1_800_000_123;

struct Port {
    tx: std::fs::File,
    frames: mpsc::Receiver<DeviceToHost>,
}

impl Port {
    fn open(path: &str) -> Port {
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .unwrap_or_else(|e| fail(&format!("open {path}: {e}")));
        let mut rx = file.try_clone().unwrap();
        let (send, frames) = mpsc::channel();
        std::thread::spawn(move || {
            let mut frame = Vec::new();
            let mut buf = [0u8; 256];
            while let Ok(n) = rx.read(&mut buf) {
                if n == 0 {
                    break;
                }
                for &b in &buf[..n] {
                    if b != 0 {
                        frame.push(b);
                        continue;
                    }
                    if let Ok(m) = decode_frame::<DeviceToHost>(&mut frame) {
                        if send.send(m).is_err() {
                            return;
                        }
                    }
                    frame.clear();
                }
            }
        });
        Port { tx: file, frames }
    }

    fn send(&mut self, m: &HostToDevice) {
        let mut buf = [0u8; HOST_FRAME_MAX];
        let f = encode_frame(m, &mut buf).unwrap();
        self.tx.write_all(f).unwrap();
    }

    /// The next frame that is not a stream frame.
    fn reply(&mut self, timeout: Duration) -> Option<DeviceToHost> {
        let end = Instant::now() + timeout;
        loop {
            let left = end.checked_duration_since(Instant::now())?;
            match self.frames.recv_timeout(left).ok()? {
                DeviceToHost::CompensatedWindow(_) | DeviceToHost::RawWindow(_) => continue,
                m => return Some(m),
            }
        }
    }

    fn request(&mut self, m: &HostToDevice) -> DeviceToHost {
        self.send(m);
        let r = self
            .reply(Duration::from_secs(5))
            .unwrap_or_else(|| fail(&format!("no answer to {m:?}")));
        println!("pty-smoke: {m:?} -> {r:?}");
        r
    }

    /// Identify, resending until the device answers (QEMU drops output until the pty is open).
    fn identify(&mut self) -> shared::wire::Identity {
        let end = Instant::now() + Duration::from_secs(20);
        while Instant::now() < end {
            self.send(&HostToDevice::Identify);
            if let Some(DeviceToHost::Identity(id)) = self.reply(Duration::from_millis(700)) {
                // Answers to the earlier (retried) Identify requests may still be on their way.
                std::thread::sleep(Duration::from_millis(1500));
                while self.frames.try_recv().is_ok() {}
                return id;
            }
        }
        fail("no Identity within 20 s")
    }
}

fn fail(msg: &str) -> ! {
    eprintln!("pty-smoke: FAILED: {msg}");
    std::process::exit(1);
}

fn check(ok: bool, msg: &str) {
    if !ok {
        fail(msg);
    }
    println!("pty-smoke: ok: {msg}");
}

fn main() {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| fail("usage: pty_smoke /dev/pts/N"));
    let mut port = Port::open(&path);
    let id = port.identify();
    check(
        id.unit_id == QEMU_UNIT_ID,
        "Identify reports the QEMU unit id",
    );
    println!("pty-smoke: calibration at start: {:?}", id.calibration);

    let table = VirtualTable {
        up_b: [1.0, 0.0, 0.0],
        rate_rad_s: 200f32.to_radians(),
        accel_rad_s2: 0.0,
    };
    check(
        port.request(&HostToDevice::SetVirtualTable(table)) == DeviceToHost::Ack(Ack::TableSet),
        "virtual table set to 200 deg/s about x, x up",
    );

    let (buf, n) = ParameterBlob {
        unit_id: QEMU_UNIT_ID,
        calibration: paper_unit::calibration(),
        created_unix_s: CREATED,
    }
    .to_bytes()
    .unwrap();
    let mut last = None;
    for c in blob_chunks(&buf[..n]) {
        last = Some(port.request(&HostToDevice::WriteCalibration(c)));
    }
    check(
        last == Some(DeviceToHost::Ack(Ack::CalibrationStored)),
        "calibration written and stored",
    );

    check(
        port.request(&HostToDevice::SetVirtualTemperature { temp_c: 38.5 })
            == DeviceToHost::Ack(Ack::TemperatureSet),
        "virtual unit heated to 38.5 C",
    );

    let t0 = Instant::now();
    port.send(&HostToDevice::Stream(StreamRequest {
        kind: StreamKind::CompensatedWindows,
        window_samples: 500,
    }));
    let mut windows = Vec::new();
    while windows.len() < 2 {
        match port.frames.recv_timeout(Duration::from_secs(10)) {
            Ok(DeviceToHost::CompensatedWindow(w)) => windows.push(w),
            Ok(_) => {}
            Err(_) => fail("no compensated windows"),
        }
    }
    let w = windows[1];
    println!(
        "pty-smoke: window of {} samples in {:?}: mean {:?} m/s^2, var {:?}, flags {:#04x}",
        w.count,
        t0.elapsed(),
        w.mean_m_s2,
        w.var_m2_s4,
        w.flags.0
    );
    let g = 9.80665f32;
    let err_mg = [w.mean_m_s2[0] - g, w.mean_m_s2[1], w.mean_m_s2[2]].map(|e| e.abs() / g * 1e3);
    check(
        w.flags.0 == 0 && err_mg.iter().all(|e| *e < 0.5),
        &format!("compensated window is (g, 0, 0) within 0.5 mg (errors {err_mg:?} mg)"),
    );
    // The QEMU board reads the temperature from its virtual ICM-42688-P's FIFO packets: 16 bits
    // at 132.48 LSB/°C, so the reading is 38.5 °C to half an LSB (3.8 m°C).
    check(
        (w.mean_temp_c - 38.5).abs() <= 0.5 / 132.48,
        &format!(
            "window carries the unit's temperature ({} C)",
            w.mean_temp_c
        ),
    );
    port.send(&HostToDevice::StopStream);
    check(
        port.reply(Duration::from_secs(5)) == Some(DeviceToHost::Ack(Ack::StreamStopped)),
        "stream stopped",
    );

    check(
        port.request(&HostToDevice::Reset) == DeviceToHost::Ack(Ack::Resetting),
        "reset acknowledged",
    );
    let id = port.identify();
    check(
        id.calibration
            == CalibrationState::Valid {
                created_unix_s: CREATED,
            },
        "calibration survived the reset",
    );
    println!("pty-smoke: all checks passed");
}
