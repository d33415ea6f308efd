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

use core::cell::RefCell;
use core::ptr::{addr_of, addr_of_mut, read_volatile, write_volatile};
use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::interrupt::{self, Mutex};
use cortex_m::peripheral::scb::SystemHandler;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::{debug, hprintln};
use defmt_semihosting as _;

use firmware::board::{self, qemu};
use firmware::pipeline::PipelineCommand;
use firmware::pipeline::PipelineFeed;
use firmware::protocol::{DeviceInfo, PipelineAccess};
use firmware::storage::{AbStore, RamNorFlash};
use firmware::testvectors::{self, Check};
use firmware::virtual_sensor::VirtualSensor;
use firmware::{paper_unit, ByteLink, Controller, LinkService, Pipeline};
use shared::blob::ParameterBlob;
use shared::wire::{
    blob_chunks, decode_frame, encode_frame, Ack, CalibrationState, DeviceToHost, HostToDevice,
    SampleFlags, StreamKind, StreamRequest, VirtualTable, DEVICE_FRAME_MAX, HOST_FRAME_MAX,
};
use shared::LeverMode;

extern "C" {
    static mut _bootmark: [u32; 4];
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

    /// Queues one request frame for the next polls (and forgets the answers so far).
    fn load(&mut self, m: &HostToDevice) {
        let mut buf = [0u8; HOST_FRAME_MAX];
        if let Ok(f) = encode_frame(m, &mut buf) {
            self.rx[..f.len()].copy_from_slice(f);
            (self.rx_len, self.rx_pos, self.tx_len) = (f.len(), 0, 0);
        }
    }

    /// The first answer frame since the last [`Self::load`].
    fn first_reply(&self) -> Option<DeviceToHost> {
        let end = self.tx[..self.tx_len].iter().position(|b| *b == 0)?;
        let mut frame = [0u8; DEVICE_FRAME_MAX];
        frame[..end].copy_from_slice(&self.tx[..end]);
        decode_frame(&mut frame[..end]).ok()
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
            // The board's main loop: a calibration write's store.
            service.run_store_here(pipeline);
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

/// The virtual unit on the virtual table seen through the ICM-42688-P model and its driver (as the
/// QEMU firmware samples it): register traffic, 20-bit FIFO decode and the pipeline on the M4F.
#[inline(never)]
fn pipeline_on_virtual_table(t: &mut Tally) {
    // 200 °/s about x with x up: full compensation returns (g, 0, 0); static-only leaves ~11 mg on y.
    let cal = paper_unit::calibration();
    let mut ok_imu = true;
    let mut errs = [0f32; 2];
    for (k, mode) in [LeverMode::RateAndAcceleration, LeverMode::Off]
        .into_iter()
        .enumerate()
    {
        let mut sensor = VirtualSensor::new(&cal, 1000, true).unwrap();
        ok_imu &= sensor
            .set_table(&VirtualTable {
                up_b: [1.0, 0.0, 0.0],
                rate_rad_s: 200f32.to_radians(),
                accel_rad_s2: 0.0,
            })
            .is_ok();
        let Some(mut imu) = qemu::imu(sensor) else {
            ok_imu = false;
            continue;
        };
        let mut feed = PipelineFeed::new(1000);
        let mut p = Pipeline::<4>::new(1000);
        p.apply(PipelineCommand::Compensator(
            shared::Compensator::new(&cal, mode).ok(),
        ));
        p.apply(PipelineCommand::Stream(StreamRequest {
            kind: StreamKind::CompensatedWindows,
            window_samples: 500,
        }));
        for _ in 0..500 {
            ok_imu &= qemu::sample_period(&mut imu, &mut feed, &mut p) == 1;
        }
        if let Some(DeviceToHost::CompensatedWindow(w)) = p.pop_output() {
            // The part marks its first sample invalid: 499 of 500 in the statistics.
            ok_imu &= w.count == 499 && w.rejected == 1;
            errs[k] = w.mean_m_s2[1].abs() / 9.80665 * 1e3; // mg
            if k == 0 {
                errs[k] = errs[k].max((w.mean_m_s2[0] - 9.80665).abs() / 9.80665 * 1e3);
            }
        } else {
            errs[k] = f32::NAN;
        }
    }
    let ok = ok_imu && errs[0] < 0.2 && (errs[1] - 11.19).abs() < 0.3;
    hprintln!(
        "test pipeline_virtual_table_200dps_through_icm42688 ... {} (full: {} mg, static-only y: {} mg)",
        if ok { "ok" } else { "FAILED" },
        errs[0],
        errs[1]
    );
    t.passed += u32::from(ok);
    t.failed += u32::from(!ok);
}

/// The virtual IMU's FIFO left undrained for 121 ms holds 102 packets and drops 19: the driver
/// flags the first sample after them, and the pipeline's sample index counts them.
#[inline(never)]
fn imu_overflow_on_target(t: &mut Tally) {
    let sensor = VirtualSensor::new(&paper_unit::calibration(), 1000, true).unwrap();
    let Some(mut imu) = qemu::imu(sensor) else {
        t.report("imu_overflow_flagged", false, "(driver refused the model)");
        return;
    };
    imu.device_mut().advance_ns(120_000_000);
    let mut feed = PipelineFeed::new(1000);
    let mut p = Pipeline::<4>::new(1000);
    p.apply(PipelineCommand::Stream(StreamRequest {
        kind: StreamKind::RawWindows,
        window_samples: 125,
    }));
    // The FIFO is still full at the next period: its sample is dropped too (19 in all); the 102
    // kept are drained.
    let first = qemu::sample_period(&mut imu, &mut feed, &mut p);
    let dropped = imu.device_mut().dropped.len();
    let ok = first == 102 && dropped == 19 && p.samples() == 102 && p.pop_output().is_none();
    // The next sample follows the gap: 19 samples of time counted, the 125-sample window closes
    // after 4 periods with the invalid first sample and the 19 lost rejected, flagged.
    for _ in 0..4 {
        qemu::sample_period(&mut imu, &mut feed, &mut p);
    }
    let closed = p.samples() == 125
        && matches!(p.pop_output(), Some(DeviceToHost::RawWindow(w))
            if w.flags.has(SampleFlags::SAMPLES_LOST) && w.rejected == 1 + 19 && w.count == 105);
    t.report(
        "imu_overflow_flagged",
        ok && closed,
        "(102 packets kept, 19 dropped, counted and flagged)",
    );
}

/// The virtual unit with gyro errors and a thermal model, heated in software, through the whole
/// pipeline on the target: within 50 µg with its temperature model, milli-g without, flagged outside
/// the calibrated range.
#[inline(never)] // its frame (sensor, pipeline) only while it runs
fn heated_board(t: &mut Tally) {
    for temp in [0.0f32, 45.0] {
        let with = testvectors::heated_unit(temp, true, 4000);
        let without = testvectors::heated_unit(temp, false, 4000);
        let ok = matches!((with, without), (Some(a), Some(b))
            if a.error_ug < 50.0 && b.error_ug > 3000.0
                && !a.flags.has(SampleFlags::TEMPERATURE));
        hprintln!(
            "test heated_board_{}C_compensated ... {} (with the model: {} ug, without: {} ug)",
            temp as i32,
            if ok { "ok" } else { "FAILED" },
            with.map_or(f32::NAN, |r| r.error_ug),
            without.map_or(f32::NAN, |r| r.error_ug)
        );
        t.passed += u32::from(ok);
        t.failed += u32::from(!ok);
    }
    let hot = testvectors::heated_unit(70.0, true, 1000);
    t.report(
        "heated_board_70C_flagged",
        hot.is_some_and(|r| r.flags.has(SampleFlags::TEMPERATURE)),
        "(outside the calibrated -20..60 C)",
    );
}

/// The sampling interrupt of the store test: the virtual IMU, its feed and a pipeline.
type Sampler = (
    &'static mut qemu::Imu,
    PipelineFeed,
    &'static mut Pipeline<4>,
);
static SAMPLER: Mutex<RefCell<Option<Sampler>>> = Mutex::new(RefCell::new(None));
/// Samples the driver handed to the pipeline (the pipeline's index also counts the lost ones).
static DELIVERED: AtomicU32 = AtomicU32::new(0);

/// Erase block of the store test's flash (its stall is a store slot's: `StallingFlash`).
const TEST_ERASE: usize = 4096;
type TestStore = AbStore<qemu::StallingFlash<TEST_ERASE>>;
static mut TEST_FLASH: [u8; 2 * TEST_ERASE] = [0; 2 * TEST_ERASE];
/// The link of the store test, polled from PendSV as the F405 polls it from its USB interrupt.
type UsbSide = (LinkService<TestStore>, MemLink, Pipeline<1>);
static USB_SIDE: Mutex<RefCell<Option<UsbSide>>> = Mutex::new(RefCell::new(None));

/// 1 kHz: one sample period of the virtual IMU, as the QEMU board's SysTick.
#[exception]
fn SysTick() {
    interrupt::free(|cs| {
        if let Some((imu, feed, p)) = SAMPLER.borrow(cs).borrow_mut().as_mut() {
            // The part sampled on through a flash stall that held this interrupt back.
            let stalled = qemu::STALLED_MS.swap(0, Ordering::Relaxed);
            imu.device_mut().advance_ns(u64::from(stalled) * 1_000_000);
            let n = qemu::sample_period(imu, feed, p);
            DELIVERED.fetch_add(n as u32, Ordering::Relaxed);
        }
    });
}

/// The F405's USB interrupt, at the lowest exception priority: the link service's poll only.
#[exception]
fn PendSV() {
    interrupt::free(|cs| {
        if let Some((service, link, p)) = USB_SIDE.borrow(cs).borrow_mut().as_mut() {
            for _ in 0..8 {
                service.poll(link, p);
            }
        }
    });
}

/// Samples the part produced, the pipeline's sample count (which counts the losses the driver
/// saw) and the samples delivered, read together.
fn counts() -> (u64, u64, u32) {
    interrupt::free(|cs| {
        let mut s = SAMPLER.borrow(cs).borrow_mut();
        let (made, index) = s.as_mut().map_or((0, 0), |(imu, _, p)| {
            (u64::from(imu.device_mut().samples), p.samples())
        });
        (made, index, DELIVERED.load(Ordering::Relaxed))
    })
}

/// Busy-waits `ms` sample periods of SysTick's interrupt.
fn wait_samples(ms: u64) {
    let (start, _, _) = counts();
    while counts().0 < start + ms {}
}

/// One calibration write as the F405 does it: each chunk's request polled from PendSV (the USB
/// interrupt), the store job run here in thread mode (the idle loop) while SysTick samples.
/// Returns the samples lost (as produced by the part less those delivered), those the driver
/// counted as lost, the samples the part produced meanwhile, and the write's answer.
fn store_while_sampling() -> (u64, u64, u64, Option<DeviceToHost>) {
    let (buf, n) = ParameterBlob {
        unit_id: paper_unit::QEMU_UNIT_ID,
        calibration: paper_unit::calibration(),
        created_unix_s: 7,
    }
    .to_bytes()
    .unwrap_or(([0; shared::blob::BLOB_MAX_LEN], 0));
    let (made0, index0, delivered0) = counts();
    for c in blob_chunks(&buf[..n]) {
        interrupt::free(|cs| {
            if let Some((_, link, _)) = USB_SIDE.borrow(cs).borrow_mut().as_mut() {
                link.load(&HostToDevice::WriteCalibration(c));
            }
        });
        cortex_m::peripheral::SCB::set_pendsv();
        cortex_m::asm::isb();
    }
    let take = || {
        interrupt::free(|cs| {
            USB_SIDE
                .borrow(cs)
                .borrow_mut()
                .as_mut()
                .and_then(|(s, _, _)| s.take_store_job())
        })
    };
    if let Some(mut job) = take() {
        job.run();
        interrupt::free(|cs| {
            if let Some((s, _, p)) = USB_SIDE.borrow(cs).borrow_mut().as_mut() {
                s.finish_store(job, p);
            }
        });
    }
    cortex_m::peripheral::SCB::set_pendsv();
    cortex_m::asm::isb();
    // A few periods more: the first sample after a gap carries it.
    wait_samples(5);
    let (made1, index1, delivered1) = counts();
    let reply = interrupt::free(|cs| {
        USB_SIDE
            .borrow(cs)
            .borrow_mut()
            .as_mut()
            .and_then(|(_, link, _)| link.first_reply())
    });
    let delivered = u64::from(delivered1 - delivered0);
    let made = made1 - made0;
    (
        made.saturating_sub(delivered),
        (index1 - index0).saturating_sub(delivered),
        made,
        reply,
    )
}

/// Sample loss while a calibration is stored, with the STM32 boards' flash stall modelled
/// (`qemu::StallingFlash`: a slot's erase masks interrupts for its longest erase, 500 ms): none
/// when the slot was erased ahead at boot (`AbStore::prepare`); when the write must erase, the
/// stall less the FIFO's depth, at most half a second of samples (1 kHz here); and no flash
/// operation from an interrupt.
#[inline(never)]
fn store_keeps_sampling(t: &mut Tally, cp: &mut cortex_m::Peripherals) {
    let sensor = VirtualSensor::new(&paper_unit::calibration(), 1000, true);
    let Some(imu) = sensor.and_then(qemu::imu) else {
        t.report("store_keeps_sampling", false, "(driver refused the model)");
        return;
    };
    let (Some(imu), Some(p)) = (
        cortex_m::singleton!(: qemu::Imu = imu),
        cortex_m::singleton!(: Pipeline<4> = Pipeline::new(1000)),
    ) else {
        return;
    };
    // SAFETY: the test flash is used by this test only, once.
    let mem: &'static mut [u8] = unsafe { &mut *addr_of_mut!(TEST_FLASH) };
    let Ok(mut store) = AbStore::new(
        qemu::StallingFlash(RamNorFlash::new(mem)),
        0,
        TEST_ERASE as u32,
    ) else {
        return;
    };
    // Power-on: erase ahead before sampling starts (SysTick not yet running: no stall).
    let prepared = store.prepare() == Ok(true);
    let service = LinkService::new(Controller::boot(
        info(),
        store,
        LeverMode::RateAndAcceleration,
    ));
    interrupt::free(|cs| {
        SAMPLER
            .borrow(cs)
            .replace(Some((imu, PipelineFeed::new(1000), p)));
        USB_SIDE
            .borrow(cs)
            .replace(Some((service, MemLink::new(), Pipeline::new(1000))));
    });
    // SAFETY: PendSV below SysTick, as the F405's USB interrupt (1) is below its sampling (2, 3).
    unsafe { cp.SCB.set_priority(SystemHandler::PendSV, 0xF0) };
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(qemu::CORE_CLOCK_HZ / 1000 - 1);
    cp.SYST.clear_current();
    cp.SYST.enable_interrupt();
    cp.SYST.enable_counter();
    wait_samples(20);
    // The first write finds slot 0 erased ahead; the second finds slot 1 never erased.
    let (lost_a, counted_a, made_a, reply_a) = store_while_sampling();
    let (lost_b, counted_b, made_b, reply_b) = store_while_sampling();
    cp.SYST.disable_interrupt();
    cp.SYST.disable_counter();
    let in_handler = qemu::FLASH_OPS_IN_HANDLER.load(Ordering::Relaxed);
    let stored = Some(DeviceToHost::Ack(Ack::CalibrationStored));
    let ok = prepared
        && reply_a == stored
        && reply_b == stored
        && lost_a == 0
        && counted_a == 0
        && lost_b > 100
        && lost_b <= 500
        && counted_b > 0
        && in_handler == 0;
    hprintln!(
        "test store_keeps_sampling ... {} (erased ahead: {} samples lost of {} during the store; erasing: {} lost of {}, {} counted lost by the driver; {} flash operations in an interrupt)",
        if ok { "ok" } else { "FAILED" },
        lost_a,
        made_a,
        lost_b,
        made_b,
        counted_b,
        in_handler
    );
    if !ok {
        hprintln!(
            "  answers: {:?}, {:?}; {} erases",
            reply_a,
            reply_b,
            qemu::FLASH_ERASES.load(Ordering::Relaxed)
        );
    }
    t.passed += u32::from(ok);
    t.failed += u32::from(!ok);
    interrupt::free(|cs| {
        SAMPLER.borrow(cs).replace(None);
        USB_SIDE.borrow(cs).replace(None);
    });
}

fn first_boot(t: &mut Tally, cp: &mut cortex_m::Peripherals) -> ! {
    board::paint_stack();
    hprintln!("qemu-target-tests: boot 1 (Cortex-M4F FPU, mps2-an386)");
    let [st, rate, full] = testvectors::check_compensation();
    t.check("compensation_static_matches_pc", st);
    t.check("compensation_rate_only_matches_pc", rate);
    t.check("compensation_full_matches_pc", full);
    t.check("omega_dot_matches_pc", testvectors::check_omega_dot());
    t.check("window_stats_match_pc", testvectors::check_window_stats());
    t.check("window_6_channels_match_pc", testvectors::check_window_6());
    t.check(
        "adc_board_conversion_matches_reference",
        testvectors::check_conversion(),
    );
    let [rate, full] = testvectors::check_gyro_temperature();
    t.check("gyro_correction_matches_pc", rate);
    t.check("compensation_after_temperature_refresh_matches_pc", full);
    pipeline_on_virtual_table(t);
    imu_overflow_on_target(t);
    heated_board(t);
    store_keeps_sampling(t, cp);

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
        board::stack_usage().1
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
        let Some(mut cp) = cortex_m::Peripherals::take() else {
            t.report("core_peripherals", false, "");
            finish(&t)
        };
        first_boot(&mut t, &mut cp)
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
