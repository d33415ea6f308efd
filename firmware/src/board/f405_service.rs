//! What the F405 firmware does besides sampling, the same whatever its IMU (the ICM-42688-P's
//! binary `f405`, the BMI270's `f405-bmi270`): the USB CDC-ACM device and its link-service round,
//! the independent watchdog, the request handler's boot, and a delay for an IMU driver's start.

use shared::wire::ImuStatus;
use shared::LeverMode;
use stm32f4xx_hal::flash::LockedFlash;
use stm32f4xx_hal::otg_fs::{UsbBus, UsbBusType, USB};
use stm32f4xx_hal::pac;
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::{Config, Rcc};
use stm32f4xx_hal::watchdog::IndependentWatchdog;
use usb_device::bus::UsbBusAllocator;
use usb_device::prelude::*;

use super::f405::{self as board, UsbLink};
use super::stm32_common::Store;
use super::{log_stack_growth, LockedPipeline};
use crate::health::{Counter, HealthCounters};
use crate::pipeline::{Pipeline, PipelineCommand};
use crate::protocol::{PipelineAccess, StoreMailbox};
use crate::stack::HighWater;
use crate::{BoardEvent, Controller, LinkService};

/// The link over USB.
pub type Link = UsbLink<'static, UsbBusType>;

/// Lever mode at boot and after a reset request.
pub const BOOT_LEVER_MODE: LeverMode = LeverMode::RateAndAcceleration;

/// The clocks from the board's crystal through the PLL: the F405's 168 MHz core and the 48 MHz
/// USB clock.
pub fn freeze_clocks(rcc: pac::RCC) -> Rcc {
    rcc.freeze(
        Config::hse(board::HSE_HZ.Hz())
            .sysclk(board::SYSCLK_HZ.Hz())
            .require_pll48clk(),
    )
}

/// The calibration store, its spare slot erased ahead: the erase stalls the CPU for up to half a
/// second (a 16 KiB sector on a single-bank F4, `crate::flash_layout`), so it runs at boot,
/// before the IMU's samples flow; a calibration written later only programs.
pub fn prepared_store(flash: pac::FLASH) -> Store {
    let mut store = board::store(LockedFlash::new(flash))
        .unwrap_or_else(|| defmt::panic!("calibration store geometry"));
    if store.prepare().is_err() {
        defmt::warn!("calibration store: erasing ahead failed");
    }
    store
}

/// The idle loop: the watchdog fed, a calibration write's store job run (below every interrupt:
/// the USB task only validates a write and posts its job, `crate::protocol::StoreJob`; the lock
/// moves the job, never runs it), the stack's high-water mark once per `scan_every` wakes (the
/// scan reads the whole unused stack, about 0.2 ms), then `wfi`; without an IMU, the LED blinks
/// fast (4 Hz) instead.
pub fn idle_loop<J>(
    watchdog: &mut IndependentWatchdog,
    store_job: &mut J,
    imu_found: bool,
    scan_every: u32,
) -> !
where
    J: rtic::Mutex<T = StoreMailbox<Store>>,
{
    let mut high_water = HighWater::new();
    let mut wakes = 0u32;
    loop {
        watchdog.feed();
        if let Some(mut job) = store_job.lock(|m| m.take_to_run()) {
            job.run();
            store_job.lock(|m| m.post(job));
            rtic::pend(pac::Interrupt::OTG_FS);
        }
        if wakes % scan_every == 0 {
            log_stack_growth(&mut high_water);
        }
        wakes = wakes.wrapping_add(1);
        if imu_found {
            cortex_m::asm::wfi();
        } else {
            cortex_m::asm::delay(board::SYSCLK_HZ / 8);
            board::toggle_led();
        }
    }
}

/// Why the chip reset: an independent-watchdog reset is counted for `Health` (RM0090 §7.3.21,
/// RCC_CSR: IWDGRSTF, cleared by RMVF).
pub fn count_watchdog_reset(rcc: &pac::RCC, health: &HealthCounters) {
    if rcc.csr().read().wdgrstf().bit_is_set() {
        health.add(Counter::WatchdogReset, 1);
        defmt::warn!("restarted by the independent watchdog");
    }
    rcc.csr().modify(|_, w| w.rmvf().set_bit());
}

/// The independent watchdog (its own 32 kHz LSI), started: fed by the idle loop, so a task that
/// never returns (or a stuck interrupt storm) resets the chip. Its period outlasts the longest
/// thing the idle loop does, a calibration store's sector erase (`board::WATCHDOG_MS`, from the
/// erase's datasheet maximum).
pub fn start_watchdog(iwdg: pac::IWDG) -> IndependentWatchdog {
    let mut watchdog = IndependentWatchdog::new(iwdg);
    watchdog.start(board::WATCHDOG_MS.millis());
    watchdog
}

/// What the request handler reports of the part: its start, its sensitivity (counts per g) and
/// the counters the tasks keep.
#[derive(Clone, Copy)]
pub struct ImuReport {
    /// The part and its start.
    pub status: ImuStatus,
    /// The accelerometer's counts per g at its configured range.
    pub accel_lsb_per_g: u32,
    /// The error counters.
    pub health: &'static HealthCounters,
}

/// The request handler from the store, with the part's start and the counters for `Health`.
pub fn boot_controller(store: Store, sample_rate_hz: u32, imu: ImuReport) -> Controller<Store> {
    let mut controller = Controller::boot(board::info(sample_rate_hz), store, BOOT_LEVER_MODE);
    controller.set_imu(imu.status, imu.accel_lsb_per_g);
    controller.set_counters(imu.health);
    controller
}

/// The USB serial number: the chip's 96-bit unique ID in hex (24 characters), so that two boards
/// on one computer are told apart (udev's `/dev/serial/by-id/`).
fn serial_number() -> &'static str {
    let text = cortex_m::singleton!(: [u8; 24] = [0; 24]);
    match text {
        Some(text) => board::unique_id_hex(text),
        None => "F405",
    }
}

/// The USB device with its CDC-ACM class (the link).
pub fn init_usb(
    usb: USB,
    bus: &'static mut Option<UsbBusAllocator<UsbBusType>>,
    ep_memory: &'static mut [u32; 1024],
) -> (UsbDevice<'static, UsbBusType>, Link) {
    let bus: &'static UsbBusAllocator<UsbBusType> = bus.insert(UsbBus::new(usb, ep_memory));
    let link = UsbLink::new(usbd_serial::SerialPort::new(bus));
    let usb_dev = UsbDeviceBuilder::new(bus, UsbVidPid(board::USB_VID_PID.0, board::USB_VID_PID.1))
        .device_class(usbd_serial::USB_CLASS_CDC)
        .strings(&[StringDescriptors::default()
            .manufacturer("accel-cal")
            .product("accel-cal F405 IMU")
            .serial_number(serial_number())])
        .unwrap_or_else(|_| defmt::panic!("USB strings"))
        .build();
    (usb_dev, link)
}

/// The USB task's own state: the device, the link, the request handler (taken out and rebuilt on
/// a reset request) and what a rebuilt handler reports.
pub struct UsbTask {
    /// The USB device.
    pub usb_dev: UsbDevice<'static, UsbBusType>,
    /// Its CDC-ACM class as the link.
    pub link: Link,
    /// The link service (`None` only while a reset rebuilds it).
    pub service: Option<LinkService<Store>>,
    /// The IMU's rate, Hz.
    pub sample_rate_hz: u32,
    /// What the handler reports of the part.
    pub imu: ImuReport,
}

impl UsbTask {
    /// One round of the USB task: USB events, requests in, answers and frames out, a calibration
    /// write's store job handed to the idle loop (`store_job`) and its answer sent once done, and
    /// a reset request served by a soft restart (a hardware reset would re-enumerate USB and close
    /// the host's port).
    pub fn round<P, J, const Q: usize>(&mut self, pipeline: P, store_job: &mut J)
    where
        P: rtic::Mutex<T = &'static mut Pipeline<Q>>,
        J: rtic::Mutex<T = StoreMailbox<Store>>,
    {
        self.usb_dev.poll(&mut [&mut self.link.serial]);
        if board::bootloader_requested(&self.link.serial) {
            board::reboot_into_bootloader();
        }
        let Some(service) = self.service.as_mut() else {
            return;
        };
        let mut pipeline = LockedPipeline(pipeline);
        // A store the idle loop finished: its answer goes out with this poll.
        if let Some(job) = store_job.lock(|m| m.take_done()) {
            service.finish_store(job, &mut pipeline);
        }
        let event = service.poll(&mut self.link, &mut pipeline);
        if let Some(job) = service.take_store_job() {
            store_job.lock(|m| m.post(job));
        }
        self.link.flush();
        if let Some(BoardEvent::Reset) = event {
            for _ in 0..100_000 {
                self.usb_dev.poll(&mut [&mut self.link.serial]);
                service.flush(&mut self.link, 1);
                self.link.flush();
                if self.link.is_drained() {
                    break;
                }
            }
            // The reset request was read, so no store job is out: the store is home.
            let Some(store) = self.service.take().and_then(|s| s.controller.into_store()) else {
                return;
            };
            let controller = boot_controller(store, self.sample_rate_hz, self.imu);
            pipeline.apply(PipelineCommand::StopStream);
            pipeline.apply(PipelineCommand::Compensator(controller.compensator()));
            self.service = Some(LinkService::new(controller));
            defmt::info!("restarted on the host's request");
        }
    }
}

/// A delay by counting the core's cycles (`cortex_m::asm::delay`), for an IMU driver's start (its
/// resets and configuration waits): SysTick stays free for a task's tick.
pub struct CycleDelay;

impl embedded_hal::delay::DelayNs for CycleDelay {
    fn delay_ns(&mut self, ns: u32) {
        // At least `ns`: the cycles rounded up (168 cycles per µs).
        let cycles = (u64::from(ns) * u64::from(board::SYSCLK_HZ)).div_ceil(1_000_000_000);
        cortex_m::asm::delay(cycles.min(u64::from(u32::MAX)) as u32);
    }
}
