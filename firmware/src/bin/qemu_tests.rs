//! On-target tests for QEMU mps2-an386 (Cortex-M4F): the compensation on the target's FPU against
//! the PC-computed table (bit for bit), the pipeline on the virtual sensor, the protocol handler on
//! the real storage region, and the calibration surviving a system reset.
//!
//! Output goes to semihosting stdout as plain text; the last line is
//! `qemu-target-tests: N passed, M failed` and the exit code is 0 only when M is 0.
//!
//! Two boots: the first runs the tests, stores a calibration through the protocol and writes a marker
//! (with its results) to the `BOOTMARK` region — outside the ELF image like the store — then resets
//! the system. The second boot finds the marker, checks that the calibration came back and that the
//! image's RAM was re-initialised (a real reset), prints the summary and exits.
#![no_std]
#![no_main]

use core::ptr::{addr_of, addr_of_mut, read_volatile, write_volatile};

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use defmt_semihosting as _;

use firmware::board::qemu;
use firmware::pipeline::{PipelineCommand, Sample};
use firmware::protocol::{DeviceInfo, PipelineAccess};
use firmware::testvectors::{self, Check};
use firmware::virtual_sensor::VirtualSensor;
use firmware::{paper_unit, ByteLink, Controller, LinkService, Pipeline};
use shared::blob::ParameterBlob;
use shared::wire::{
    blob_chunks, decode_frame, encode_frame, Ack, CalibrationState, DeviceToHost, HostToDevice,
    StreamKind, StreamRequest, VirtualTable, DEVICE_FRAME_MAX, HOST_FRAME_MAX,
};
use shared::LeverMode;

extern "C" {
    static mut _bootmark: [u32; 4];
    /// End of .bss/.uninit (cortex-m-rt): the stack grows down towards it.
    static mut __sheap: u32;
    /// Top of the stack (cortex-m-rt).
    static _stack_start: u32;
}
const PAINT: u32 = 0xA5A5_A5A5;

/// Fills the unused stack with a pattern (from the end of the statics to 256 bytes below SP).
fn paint_stack() {
    let sp = cortex_m::register::msp::read() as usize;
    let mut p = addr_of_mut!(__sheap) as usize;
    while p + 4 <= sp - 256 {
        // SAFETY: memory between the statics and the live stack, unused.
        unsafe { write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
}

/// Deepest stack use since [`paint_stack`], bytes.
fn stack_high_water() -> usize {
    let mut p = addr_of_mut!(__sheap) as usize;
    // SAFETY: as above; reads only.
    while unsafe { read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    addr_of!(_stack_start) as usize - p
}
const MARK: u32 = 0xB007_1E57;
const CREATED: u64 = 1_800_000_042;

/// A RAM variable of the image: set in boot 1; a real reset re-initialises it.
static mut IMAGE_WORD: u32 = 0;

struct Tally {
    passed: u32,
    failed: u32,
}

impl Tally {
    fn report(&mut self, name: &str, ok: bool, detail: &str) {
        if ok {
            self.passed += 1;
        } else {
            self.failed += 1;
        }
        hprintln!(
            "test {} ... {} {}",
            name,
            if ok { "ok" } else { "FAILED" },
            detail
        );
    }

    fn check(&mut self, name: &str, c: Check) {
        let ok = c.passed();
        self.passed += u32::from(ok);
        self.failed += u32::from(!ok);
        hprintln!(
            "test {} ... {} ({}/{} values bit-exact, max {} ulp)",
            name,
            if ok { "ok" } else { "FAILED" },
            c.exact,
            c.values,
            c.max_ulp
        );
    }
}

/// An in-memory link: the test writes request frames into `rx`, the device's bytes land in `tx`.
struct MemLink {
    rx: [u8; 256],
    rx_len: usize,
    rx_pos: usize,
    tx: [u8; 512],
    tx_len: usize,
}

impl ByteLink for MemLink {
    fn try_read(&mut self) -> Option<u8> {
        (self.rx_pos < self.rx_len).then(|| {
            self.rx_pos += 1;
            self.rx[self.rx_pos - 1]
        })
    }
    fn try_write(&mut self, b: u8) -> bool {
        if self.tx_len == self.tx.len() {
            return false;
        }
        self.tx[self.tx_len] = b;
        self.tx_len += 1;
        true
    }
}

impl MemLink {
    const fn new() -> Self {
        MemLink {
            rx: [0; 256],
            rx_len: 0,
            rx_pos: 0,
            tx: [0; 512],
            tx_len: 0,
        }
    }

    /// Sends one request through the service and returns the first answer frame.
    fn request<S: firmware::CalStore, P: PipelineAccess>(
        &mut self,
        service: &mut LinkService<S>,
        pipeline: &mut P,
        m: &HostToDevice,
    ) -> Option<DeviceToHost> {
        let mut buf = [0u8; HOST_FRAME_MAX];
        let f = encode_frame(m, &mut buf).ok()?;
        self.rx[..f.len()].copy_from_slice(f);
        (self.rx_len, self.rx_pos, self.tx_len) = (f.len(), 0, 0);
        for _ in 0..8 {
            service.poll(self, pipeline);
        }
        let end = self.tx[..self.tx_len].iter().position(|b| *b == 0)?;
        let mut frame = [0u8; DEVICE_FRAME_MAX];
        frame[..end].copy_from_slice(&self.tx[..end]);
        decode_frame(&mut frame[..end]).ok()
    }
}

fn info() -> DeviceInfo {
    qemu::INFO
}

fn pipeline_on_virtual_table(t: &mut Tally) {
    // 200 °/s about x with x up: full compensation returns (g, 0, 0); static-only leaves ~11 mg on y.
    let cal = paper_unit::calibration();
    let mut sensor = VirtualSensor::new(&cal, 1000, true).unwrap();
    let ok_table = sensor
        .set_table(&VirtualTable {
            up_b: [1.0, 0.0, 0.0],
            rate_rad_s: 200f32.to_radians(),
            accel_rad_s2: 0.0,
        })
        .is_ok();
    let mut errs = [0f32; 2];
    for (k, mode) in [LeverMode::RateAndAcceleration, LeverMode::Off]
        .into_iter()
        .enumerate()
    {
        let mut p = Pipeline::<4>::new(1000);
        p.apply(PipelineCommand::Compensator(
            shared::Compensator::new(&cal, mode).ok(),
        ));
        p.apply(PipelineCommand::Stream(StreamRequest {
            kind: StreamKind::CompensatedWindows,
            window_samples: 500,
        }));
        for _ in 0..500 {
            let s: Sample = sensor.sample();
            p.on_sample(&s);
        }
        if let Some(DeviceToHost::CompensatedWindow(w)) = p.pop_output() {
            errs[k] = w.mean_m_s2[1].abs() / 9.80665 * 1e3; // mg
            if k == 0 {
                errs[k] = errs[k].max((w.mean_m_s2[0] - 9.80665).abs() / 9.80665 * 1e3);
            }
        } else {
            errs[k] = f32::NAN;
        }
    }
    let ok = ok_table && errs[0] < 0.2 && (errs[1] - 11.19).abs() < 0.3;
    hprintln!(
        "test pipeline_virtual_table_200dps ... {} (full: {} mg, static-only y: {} mg)",
        if ok { "ok" } else { "FAILED" },
        errs[0],
        errs[1]
    );
    t.passed += u32::from(ok);
    t.failed += u32::from(!ok);
}

/// The heated unit (docs/model.md §9): the paper's unit with MEMS tempcos in a virtual chamber
/// heated in software, its temperature read four times a second; the compensated window mean is
/// within 50 µg of gravity at 45 °C and 0 °C, and flagged at 70 °C, outside the calibrated range.
fn pipeline_heated_unit(t: &mut Tally) {
    let cal = paper_unit::hot_calibration();
    let mut sensor = VirtualSensor::new(&cal, 1000, true).unwrap();
    let up = [0.6f32, 0.0, -0.8];
    let table_ok = sensor
        .set_table(&VirtualTable {
            up_b: up,
            rate_rad_s: 0.0,
            accel_rad_s2: 0.0,
        })
        .is_ok();
    let mut p = Pipeline::<4>::new(1000);
    p.apply(PipelineCommand::Compensator(
        shared::Compensator::new(&cal, LeverMode::RateOnly).ok(),
    ));
    p.apply(PipelineCommand::Stream(StreamRequest {
        kind: StreamKind::CompensatedWindows,
        window_samples: 4000,
    }));
    for (ambient, in_range) in [(45.0f32, true), (0.0, true), (70.0, false)] {
        let mut ok = table_ok && sensor.set_ambient_c(ambient).is_ok();
        let mut last = None;
        for k in 0..20_000u32 {
            if k % 250 == 0 {
                p.on_temperature(sensor.temperature_c());
            }
            p.on_sample(&sensor.sample());
            while let Some(m) = p.pop_output() {
                if let DeviceToHost::CompensatedWindow(w) = m {
                    last = Some(w);
                }
            }
        }
        let (error_ug, flagged, temp) = match last {
            Some(w) => {
                let e: [f32; 3] = core::array::from_fn(|j| w.mean_m_s2[j] / 9.80665 - up[j]);
                (
                    libm::sqrtf(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) * 1e6,
                    w.flags.has(shared::wire::SampleFlags::TEMPERATURE),
                    w.mean_temp_c,
                )
            }
            None => (f32::NAN, false, f32::NAN),
        };
        ok &= flagged != in_range && (temp - ambient).abs() < 0.05;
        if in_range {
            ok &= error_ug < 50.0;
        }
        hprintln!(
            "test pipeline_heated_unit_{}c ... {} (error {} µg, die {} °C, flagged {})",
            ambient as i32,
            if ok { "ok" } else { "FAILED" },
            error_ug,
            temp,
            flagged
        );
        t.passed += u32::from(ok);
        t.failed += u32::from(!ok);
    }
}

fn first_boot(t: &mut Tally) -> ! {
    paint_stack();
    hprintln!("qemu-target-tests: boot 1 (Cortex-M4F FPU, mps2-an386)");
    let [st, rate, full] = testvectors::check_compensation();
    t.check("compensation_static_matches_pc", st);
    t.check("compensation_rate_only_matches_pc", rate);
    t.check("compensation_full_matches_pc", full);
    t.check("omega_dot_matches_pc", testvectors::check_omega_dot());
    t.check("window_stats_match_pc", testvectors::check_window_stats());
    pipeline_on_virtual_table(t);
    pipeline_heated_unit(t);

    // The protocol handler on the board's real storage region: write the paper unit's calibration.
    // SAFETY: only place the store is created in this binary.
    let store = unsafe { qemu::store() };
    let ok = store.is_some();
    t.report("storage_region_geometry", ok, "");
    let Some(store) = store else { finish(t) };
    let controller = Controller::boot(info(), store, LeverMode::RateAndAcceleration);
    let fresh = controller.calibration_state() == CalibrationState::Missing;
    t.report("fresh_qemu_boots_uncalibrated", fresh, "");
    let mut service = LinkService::new(controller);
    let mut pipeline = Pipeline::<4>::new(1000);
    let mut link = MemLink::new();
    let (buf, n) = ParameterBlob {
        unit_id: paper_unit::QEMU_UNIT_ID,
        calibration: paper_unit::calibration(),
        created_unix_s: CREATED,
    }
    .to_bytes()
    .unwrap();
    let mut last = None;
    for c in blob_chunks(&buf[..n]) {
        last = link.request(
            &mut service,
            &mut pipeline,
            &HostToDevice::WriteCalibration(c),
        );
    }
    let stored = last == Some(DeviceToHost::Ack(Ack::CalibrationStored));
    t.report("write_calibration_over_protocol", stored, "");
    let foreign = ParameterBlob {
        unit_id: shared::UnitId(*b"SOMEONE-ELSE"),
        ..ParameterBlob {
            unit_id: paper_unit::QEMU_UNIT_ID,
            calibration: paper_unit::calibration(),
            created_unix_s: 1,
        }
    }
    .to_bytes()
    .unwrap();
    for c in blob_chunks(&foreign.0[..foreign.1]) {
        last = link.request(
            &mut service,
            &mut pipeline,
            &HostToDevice::WriteCalibration(c),
        );
    }
    let refused = matches!(last, Some(DeviceToHost::Error(_)));
    t.report("foreign_blob_refused", refused, "");
    let reset = link.request(&mut service, &mut pipeline, &HostToDevice::Reset);
    t.report(
        "reset_is_acknowledged",
        reset == Some(DeviceToHost::Ack(Ack::Resetting)),
        "",
    );

    hprintln!(
        "qemu-target-tests: stack high-water mark {} bytes (boot, calibration write, tests)",
        stack_high_water()
    );

    // Marker + results, then a real system reset.
    // SAFETY: the marker region is reserved for this binary; the image variable is ours.
    unsafe {
        write_volatile(addr_of_mut!(IMAGE_WORD), 0xDEAD_BEEF);
        let m = addr_of_mut!(_bootmark) as *mut u32;
        write_volatile(m, MARK);
        write_volatile(m.add(1), t.passed);
        write_volatile(m.add(2), t.failed);
    }
    hprintln!("qemu-target-tests: resetting the system (SCB::sys_reset)");
    cortex_m::peripheral::SCB::sys_reset();
}

fn second_boot(t: &mut Tally) -> ! {
    hprintln!("qemu-target-tests: boot 2 (after SCB::sys_reset)");
    // SAFETY: as above.
    let image_word = unsafe { read_volatile(addr_of!(IMAGE_WORD)) };
    t.report(
        "reset_reinitialised_the_image",
        image_word == 0,
        "(a RAM variable set before the reset is back to its initial value)",
    );
    // SAFETY: called once in this boot.
    let Some(store) = (unsafe { qemu::store() }) else {
        t.report("storage_region_geometry", false, "");
        finish(t)
    };
    let controller = Controller::boot(info(), store, LeverMode::RateAndAcceleration);
    let state = controller.calibration_state();
    t.report(
        "calibration_survives_system_reset",
        state
            == CalibrationState::Valid {
                created_unix_s: CREATED,
            },
        "",
    );
    t.report(
        "compensator_rebuilt_at_boot",
        controller.compensator().is_some(),
        "",
    );
    finish(t)
}

fn finish(t: &Tally) -> ! {
    // SAFETY: reserved region.
    unsafe { write_volatile(addr_of_mut!(_bootmark) as *mut u32, 0) };
    hprintln!(
        "qemu-target-tests: {} passed, {} failed",
        t.passed,
        t.failed
    );
    debug::exit(if t.failed == 0 {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}

#[entry]
fn main() -> ! {
    // SAFETY: reserved region, read once.
    let (mark, passed, failed) = unsafe {
        let m = addr_of!(_bootmark) as *const u32;
        (
            read_volatile(m),
            read_volatile(m.add(1)),
            read_volatile(m.add(2)),
        )
    };
    if mark == MARK {
        let mut t = Tally { passed, failed };
        second_boot(&mut t)
    } else {
        let mut t = Tally {
            passed: 0,
            failed: 0,
        };
        first_boot(&mut t)
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("qemu-target-tests: PANIC {}", info);
    hprintln!("qemu-target-tests: 0 passed, 1 failed");
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}
