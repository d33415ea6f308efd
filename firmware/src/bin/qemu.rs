//! Firmware for QEMU's mps2-an386: the virtual sensor, seen through the ICM-42688-P model and
//! driver, sampled at 1 kHz from SysTick, the host
//! protocol on UART0, the calibration store in a RAM region that survives a system reset.
//!
//! Run with `scripts/run-qemu.sh` (prints the serial pty). Logs are defmt over semihosting.
#![no_std]
#![no_main]

use core::cell::RefCell;

use cortex_m::interrupt::{self, Mutex};
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::{entry, exception};
use defmt_semihosting as _;

use firmware::board::cmsdk_uart::{CmsdkUart, UART0_BASE};
use firmware::board::qemu::{self, OUTPUT_QUEUE, SAMPLE_RATE_HZ};
use firmware::board::{PipelineHandle, SharedPipeline};
use firmware::pipeline::PipelineCommand;
use firmware::pipeline::PipelineFeed;
use firmware::virtual_sensor::VirtualSensor;
use firmware::{paper_unit, BoardEvent, Controller, EioLink, LinkService, Pipeline};

static PIPELINE: SharedPipeline<OUTPUT_QUEUE> = Mutex::new(RefCell::new(None));
static IMU: Mutex<RefCell<Option<(&'static mut qemu::Imu, PipelineFeed)>>> =
    Mutex::new(RefCell::new(None));

#[entry]
fn main() -> ! {
    let mut cp = cortex_m::Peripherals::take().unwrap_or_else(|| halt());
    // SAFETY: UART0 is used by nothing else.
    let uart = unsafe { CmsdkUart::new(UART0_BASE, 16) };
    // SAFETY: called once.
    let mut store = unsafe { qemu::store() }.unwrap_or_else(|| halt());
    // Erase ahead, before sampling starts, as the STM32 boards do.
    if store.prepare().is_err() {
        defmt::warn!("calibration store: erasing ahead failed");
    }
    let controller = Controller::boot(qemu::INFO, store, qemu::BOOT_LEVER_MODE);
    let pipeline = cortex_m::singleton!(: Pipeline<OUTPUT_QUEUE> = Pipeline::new(SAMPLE_RATE_HZ))
        .unwrap_or_else(|| halt());
    pipeline.apply(PipelineCommand::Compensator(controller.compensator()));
    let sensor = VirtualSensor::new(&paper_unit::calibration(), SAMPLE_RATE_HZ, true)
        .unwrap_or_else(|| halt());
    let imu = qemu::imu(sensor).unwrap_or_else(|| halt());
    let imu = cortex_m::singleton!(: qemu::Imu = imu).unwrap_or_else(|| halt());
    interrupt::free(|cs| {
        PIPELINE.borrow(cs).replace(Some(pipeline));
        IMU.borrow(cs)
            .replace(Some((imu, PipelineFeed::new(SAMPLE_RATE_HZ))));
    });
    defmt::info!(
        "accel-cal firmware on mps2-an386: {=u32} Hz virtual sensor behind an ICM-42688-P model, UART0 protocol",
        SAMPLE_RATE_HZ
    );

    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(qemu::CORE_CLOCK_HZ / SAMPLE_RATE_HZ - 1);
    cp.SYST.clear_current();
    cp.SYST.enable_interrupt();
    cp.SYST.enable_counter();

    let mut link = EioLink(uart);
    let mut service = LinkService::new(controller);
    let mut shared = PipelineHandle(&PIPELINE);
    loop {
        match service.poll(&mut link, &mut shared) {
            Some(BoardEvent::SetTable(t)) => interrupt::free(|cs| {
                if let Some((imu, _)) = IMU.borrow(cs).borrow_mut().as_mut() {
                    let _ = imu.device_mut().generator().set_table(&t);
                }
            }),
            Some(BoardEvent::SetTemperature(t)) => interrupt::free(|cs| {
                if let Some((imu, _)) = IMU.borrow(cs).borrow_mut().as_mut() {
                    imu.device_mut().generator().set_temperature(t);
                }
            }),
            Some(BoardEvent::Reset) => {
                defmt::info!("reset requested by the host");
                service.flush(&mut link, 10_000_000);
                cortex_m::peripheral::SCB::sys_reset();
            }
            None => {}
        }
        // A calibration write's store, here in thread mode: SysTick keeps sampling through it.
        service.run_store_here(&mut shared);
    }
}

/// One sample per SysTick: the virtual IMU's next packet, the driver's FIFO drain, then the whole
/// per-sample path (with the packet's temperature a few times a second).
#[exception]
fn SysTick() {
    interrupt::free(|cs| {
        let mut imu = IMU.borrow(cs).borrow_mut();
        let mut pipeline = PIPELINE.borrow(cs).borrow_mut();
        if let (Some((imu, feed)), Some(p)) = (imu.as_mut(), pipeline.as_mut()) {
            qemu::sample_period(imu, feed, p);
        }
    });
}

fn halt() -> ! {
    defmt::error!("initialisation failed");
    cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic");
    cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}
