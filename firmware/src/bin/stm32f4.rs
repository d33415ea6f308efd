//! Firmware for the STM32F446RE Nucleo-64 (see `firmware::board::stm32f4` for the pin map).
//! `cargo run --release` in `firmware/` flashes it with probe-rs (see README).
#![no_std]
#![no_main]

use core::cell::RefCell;

use cortex_m::interrupt::{free, Mutex};
use cortex_m_rt::entry;
use defmt_rtt as _;
use panic_probe as _;
use stm32f4xx_hal::adc::config::{AdcConfig, SampleTime};
use stm32f4xx_hal::adc::{Adc, Temperature};
use stm32f4xx_hal::flash::LockedFlash;
use stm32f4xx_hal::gpio::{Analog, Output, PushPull, PA0, PA1, PA4, PB6};
use stm32f4xx_hal::pac::{self, interrupt, Interrupt, ADC1, SPI1, TIM2};
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Config;
use stm32f4xx_hal::signature::{VtempCal110, VtempCal30};
use stm32f4xx_hal::spi::{Mode, Phase, Polarity, Spi};
use stm32f4xx_hal::timer::{CounterHz, Event};

use firmware::board::stm32f4::{self as board, OUTPUT_QUEUE, SAMPLE_RATE_HZ};
use firmware::board::{PipelineHandle, SharedPipeline};
use firmware::gyro::{CsDevice, L3gd20};
use firmware::pipeline::{PipelineCommand, RawCodes, Scaling};
use firmware::{BoardEvent, Controller, Gyro, LinkService, NbLink, Pipeline};
use shared::LeverMode;

type GyroDev = L3gd20<CsDevice<Spi<SPI1>, PB6<Output<PushPull>>>>;

/// Everything the sampling interrupt owns.
struct Sampler {
    timer: CounterHz<TIM2>,
    adc: Adc<ADC1>,
    pins: (PA0<Analog>, PA1<Analog>, PA4<Analog>),
    gyro: Option<GyroDev>,
    scaling: Scaling,
    /// Samples until the next temperature reading.
    until_temperature: u32,
}

/// Samples between on-chip temperature readings (4 per second, the pipeline's refresh rate).
const TEMPERATURE_EVERY: u32 = SAMPLE_RATE_HZ / firmware::pipeline::TEMPERATURE_REFRESH_HZ;

static PIPELINE: SharedPipeline<OUTPUT_QUEUE> = Mutex::new(RefCell::new(None));
static SAMPLER: Mutex<RefCell<Option<&'static mut Sampler>>> = Mutex::new(RefCell::new(None));

#[entry]
fn main() -> ! {
    let dp = pac::Peripherals::take().unwrap();
    // Nucleo: 8 MHz HSE from the ST-LINK's MCO.
    let mut rcc = dp.RCC.freeze(
        Config::hse(8.MHz())
            .bypass_hse_oscillator()
            .sysclk(board::SYSCLK_HZ.Hz()),
    );
    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);

    let serial = dp
        .USART2
        .serial((gpioa.pa2, gpioa.pa3), board::BAUD.bps(), &mut rcc)
        .unwrap();

    let store = board::store(LockedFlash::new(dp.FLASH)).unwrap();
    let controller = Controller::boot(board::info(), store, LeverMode::RateAndAcceleration);

    let spi = dp.SPI1.spi(
        (Some(gpioa.pa5), Some(gpioa.pa6), Some(gpioa.pa7)),
        Mode {
            polarity: Polarity::IdleHigh,
            phase: Phase::CaptureOnSecondTransition,
        },
        8.MHz(),
        &mut rcc,
    );
    let mut cs = gpiob.pb6.into_push_pull_output();
    cs.set_high();
    let gyro = match L3gd20::new(CsDevice::new(spi, cs)) {
        Ok(g) => Some(g),
        Err(_) => {
            defmt::warn!("no gyro on SPI1: rates read as 0, use LeverMode::Off");
            None
        }
    };

    let mut adc = Adc::new(dp.ADC1, true, AdcConfig::default(), &mut rcc);
    adc.enable_temperature_and_vref();
    let pins = (
        gpioa.pa0.into_analog(),
        gpioa.pa1.into_analog(),
        gpioa.pa4.into_analog(),
    );
    let mut timer = dp.TIM2.counter_hz(&mut rcc);
    timer.start(SAMPLE_RATE_HZ.Hz()).unwrap();
    timer.listen(Event::Update);

    let pipeline =
        cortex_m::singleton!(: Pipeline<OUTPUT_QUEUE> = Pipeline::new(SAMPLE_RATE_HZ)).unwrap();
    pipeline.apply(PipelineCommand::Compensator(controller.compensator()));
    let sampler = cortex_m::singleton!(: Sampler = Sampler {
        timer,
        adc,
        pins,
        gyro,
        scaling: Scaling {
            volts_per_code: board::VREF_V / 4095.0,
            adc_max: 4095,
            rad_s_per_lsb: firmware::gyro::RAD_S_PER_LSB_2000DPS,
        },
        until_temperature: 0,
    })
    .unwrap();
    free(|cs| {
        PIPELINE.borrow(cs).replace(Some(pipeline));
        SAMPLER.borrow(cs).replace(Some(sampler));
    });
    // SAFETY: the handler only touches state behind the critical-section mutexes above.
    unsafe { cortex_m::peripheral::NVIC::unmask(Interrupt::TIM2) };
    defmt::info!("accel-cal firmware on STM32F446: {=u32} Hz", SAMPLE_RATE_HZ);

    let mut link = NbLink(serial);
    let mut service = LinkService::new(controller);
    let mut shared = PipelineHandle(&PIPELINE);
    loop {
        match service.poll(&mut link, &mut shared) {
            Some(BoardEvent::Reset) => {
                service.flush(&mut link, 10_000_000);
                cortex_m::peripheral::SCB::sys_reset();
            }
            // Refused by the request handler on this board (no virtual unit).
            Some(BoardEvent::SetTable(_)) | Some(BoardEvent::SetTemperature(_)) | None => {}
        }
    }
}

#[interrupt]
fn TIM2() {
    free(|cs| {
        let mut sampler = SAMPLER.borrow(cs).borrow_mut();
        let mut pipeline = PIPELINE.borrow(cs).borrow_mut();
        let (Some(s), Some(p)) = (sampler.as_mut(), pipeline.as_mut()) else {
            return;
        };
        let _ = s.timer.wait(); // clear the update flag
        let t = SampleTime::Cycles_56;
        let adc = [
            s.adc.convert(&s.pins.0, t),
            s.adc.convert(&s.pins.1, t),
            s.adc.convert(&s.pins.2, t),
        ];
        if s.until_temperature == 0 {
            // The sensor needs ≥ 10 µs of sampling (480 ADC cycles ≈ 21 µs), 4 times a second.
            s.until_temperature = TEMPERATURE_EVERY;
            let code = s.adc.convert(&Temperature, SampleTime::Cycles_480);
            p.set_temperature(firmware::die_temperature::from_code(
                code,
                VtempCal30::get().read(),
                VtempCal110::get().read(),
                board::VREF_V,
            ));
        }
        s.until_temperature -= 1;
        let mut sample = s.scaling.sample(&RawCodes { adc, gyro: [0; 3] });
        if let Some(g) = s.gyro.as_mut() {
            match g.read_rate() {
                Ok((w, sat)) => {
                    sample.rate_rad_s = w;
                    sample.saturated |= sat;
                }
                Err(_) => sample.rate_rad_s = [f32::NAN; 3], // flagged, left out of the statistics
            }
        }
        p.on_sample(&sample);
    });
}
