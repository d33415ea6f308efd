//! Firmware for QEMU's mps2-an386: the virtual sensor sampled at 1 kHz from SysTick, the host
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
use firmware::virtual_sensor::VirtualSensor;
use firmware::{paper_unit, BoardEvent, Controller, EioLink, LinkService, Pipeline};

static PIPELINE: SharedPipeline<OUTPUT_QUEUE> = Mutex::new(RefCell::new(None));
static SENSOR: Mutex<RefCell<Option<&'static mut VirtualSensor>>> = Mutex::new(RefCell::new(None));

#[entry]
fn main() -> ! {
    let mut cp = cortex_m::Peripherals::take().unwrap_or_else(|| halt());
    // SAFETY: UART0 is used by nothing else.
    let uart = unsafe { CmsdkUart::new(UART0_BASE, 16) };
    // SAFETY: called once.
    let store = unsafe { qemu::store() }.unwrap_or_else(|| halt());
    let controller = Controller::boot(qemu::INFO, store, qemu::BOOT_LEVER_MODE);
    let pipeline = cortex_m::singleton!(: Pipeline<OUTPUT_QUEUE> = Pipeline::new(SAMPLE_RATE_HZ))
        .unwrap_or_else(|| halt());
    pipeline.apply(PipelineCommand::Compensator(controller.compensator()));
    // The paper's unit with MEMS-sized tempcos: at the virtual chamber's 25 °C it is the paper's unit.
    let sensor = VirtualSensor::new(&paper_unit::hot_calibration(), SAMPLE_RATE_HZ, true)
        .unwrap_or_else(|| halt());
    let sensor = cortex_m::singleton!(: VirtualSensor = sensor).unwrap_or_else(|| halt());
    interrupt::free(|cs| {
        PIPELINE.borrow(cs).replace(Some(pipeline));
        SENSOR.borrow(cs).replace(Some(sensor));
    });
    defmt::info!(
        "accel-cal firmware on mps2-an386: {=u32} Hz virtual sensor, UART0 protocol",
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
                if let Some(s) = SENSOR.borrow(cs).borrow_mut().as_mut() {
                    let _ = s.set_table(&t);
                }
            }),
            Some(BoardEvent::Reset) => {
                defmt::info!("reset requested by the host");
                service.flush(&mut link, 10_000_000);
                cortex_m::peripheral::SCB::sys_reset();
            }
            None => {}
        }
    }
}

/// Samples between two temperature readings: four a second (docs/model.md §9: the temperature
/// terms are refreshed a few times a second, never per sample).
const TEMPERATURE_PERIOD_SAMPLES: u32 = SAMPLE_RATE_HZ / 4;

/// One sample per SysTick: the virtual sensor, then the whole per-sample path; every
/// [`TEMPERATURE_PERIOD_SAMPLES`] the unit's temperature too.
#[exception]
fn SysTick() {
    static mut UNTIL_TEMPERATURE: u32 = 0;
    let read_temperature = *UNTIL_TEMPERATURE == 0;
    *UNTIL_TEMPERATURE = if read_temperature {
        TEMPERATURE_PERIOD_SAMPLES - 1
    } else {
        *UNTIL_TEMPERATURE - 1
    };
    interrupt::free(|cs| {
        let mut sensor = SENSOR.borrow(cs).borrow_mut();
        let mut pipeline = PIPELINE.borrow(cs).borrow_mut();
        if let (Some(s), Some(p)) = (sensor.as_mut(), pipeline.as_mut()) {
            if read_temperature {
                p.on_temperature(s.temperature_c());
            }
            let sample = s.sample();
            p.on_sample(&sample);
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
