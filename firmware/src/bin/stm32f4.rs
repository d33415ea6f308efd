//! Firmware for the STM32F446RE Nucleo-64 (see `firmware::board::stm32f4` for the pin map and the
//! clock tree). `cargo run --release` in `firmware/` flashes it with probe-rs (see README).
//!
//! RTIC 2 tasks, highest priority first (README "Sampling architecture"):
//!
//! | task | binds | priority | does |
//! |---|---|---|---|
//! | `usart2_rx` | USART2 | 3 | moves each received byte into the receive queue |
//! | `scan_done` | DMA2_STREAM0 | 2 | re-arms the ADC DMA, reads the gyro, runs the pipeline |
//! | `adc_overrun` | ADC | 2 | recovers the scan after an overrun (a flash erase stalled the CPU) |
//! | `idle` | — | 0 | link service (requests, calibration store, frames out), stack high-water mark |
//!
//! TIM2's update event triggers each ADC scan in hardware (no software start, no jitter from
//! interrupt latency); only the pipeline is shared (sampling task ↔ link), and the link's accesses
//! are RTIC locks that raise BASEPRI to priority 2 for one `pop_output`/`apply` — the receive
//! interrupt is never masked, and nothing waits inside a lock.
#![no_std]
#![no_main]

use defmt_rtt as _;
use panic_probe as _;

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use core::sync::atomic::{AtomicBool, Ordering};

    use embedded_hal_bus::spi::{ExclusiveDevice, NoDelay};
    use heapless::spsc::{Producer, Queue};
    use stm32f4xx_hal::adc::config::{
        AdcConfig, Clock, Continuous, Dma, ExternalTrigger, SampleTime, Scan, Sequence, TriggerMode,
    };
    use stm32f4xx_hal::adc::{Adc, Temperature};
    use stm32f4xx_hal::dma::config::DmaConfig;
    use stm32f4xx_hal::dma::{PeripheralToMemory, Stream0, StreamsTuple, Transfer};
    use stm32f4xx_hal::flash::LockedFlash;
    use stm32f4xx_hal::gpio::{Output, PushPull, PA0, PA1, PA4, PB6};
    use stm32f4xx_hal::pac::{self, ADC1, DMA2, SPI1, TIM2, USART2};
    use stm32f4xx_hal::prelude::*;
    use stm32f4xx_hal::rcc::{Config, Rcc};
    use stm32f4xx_hal::serial::{Rx, Tx};
    use stm32f4xx_hal::signature::{VtempCal110, VtempCal30};
    use stm32f4xx_hal::spi::Spi;
    use stm32f4xx_hal::timer::CounterHz;

    use firmware::board::stm32_common::{spi1, Store};
    use firmware::board::stm32f4::{self as board, AdcWords, OUTPUT_QUEUE, SAMPLE_RATE_HZ};
    use firmware::board::{log_stack_growth, paint_stack, LockedPipeline};
    use firmware::clock_start::{self, ClockSource};
    use firmware::clock_tree::nucleo::GYRO_SPI;
    use firmware::conversion::Scaling;
    use firmware::imu::l3gd20h::L3gd20;
    use firmware::link::{on_rx_byte, RxQueueLink, RX_QUEUE};
    use firmware::pipeline::PipelineCommand;
    use firmware::sampling::{split_scan, TemperatureMean, ADC_SCAN_LEN};
    use firmware::stack::HighWater;
    use firmware::{BoardEvent, Controller, Gyro, LinkService, Pipeline};
    use shared::LeverMode;

    /// Scans were lost to an ADC overrun: the next sample says so (set by `adc_overrun`).
    static SCAN_GAP: AtomicBool = AtomicBool::new(false);

    type ScanBuf = &'static mut [u32; ADC_SCAN_LEN];
    type ScanDma = Transfer<Stream0<DMA2>, 0, AdcWords, PeripheralToMemory, ScanBuf>;
    type GyroDev = L3gd20<ExclusiveDevice<Spi<SPI1>, PB6<Output<PushPull>>, NoDelay>>;
    type Link = RxQueueLink<'static, Tx<USART2>>;

    #[shared]
    struct Shared {
        pipeline: &'static mut Pipeline<OUTPUT_QUEUE>,
        scan: ScanDma,
    }

    #[local]
    struct Local {
        gyro: Option<GyroDev>,
        scaling: Scaling,
        temperature: TemperatureMean,
        vtemp_cal: (u16, u16),
        rx: Rx<USART2>,
        rx_queue: Producer<'static, u8>,
        link: Link,
        service: LinkService<Store>,
        // Owned so that TIM2 keeps running (its TRGO triggers the scans).
        _timer: CounterHz<TIM2>,
    }

    /// Nucleo: 8 MHz HSE from the ST-LINK's MCO, where the solder bridges route it; else the HSI
    /// after a bounded wait (`clock_start`), not the HAL's endless one. PCLK2 is asked for
    /// explicitly: the ADC clock derives from it (board::ADC_CLOCK_HZ).
    fn freeze_clocks(rcc: pac::RCC) -> Rcc {
        rcc.cr().modify(|_, w| {
            w.hsebyp().bypassed();
            w.hseon().set_bit()
        });
        let source = clock_start::settle(
            || {
                let ready = rcc.cr().read().hserdy().bit_is_set();
                if !ready {
                    cortex_m::asm::delay(clock_start::CYCLES_PER_POLL);
                }
                ready
            },
            clock_start::HSE_POLLS,
        );
        let config = match source {
            ClockSource::Hse => Config::hse(8.MHz()).bypass_hse_oscillator(),
            ClockSource::Hsi => {
                // HSEBYP can be written only with the HSE off (RM0390, RCC_CR).
                rcc.cr().modify(|_, w| w.hseon().clear_bit());
                rcc.cr().modify(|_, w| w.hsebyp().not_bypassed());
                Config::hsi()
            }
        };
        let rcc = rcc.freeze(
            config
                .sysclk(board::SYSCLK_HZ.Hz())
                .pclk2(board::PCLK2_HZ.Hz()),
        );
        if source == ClockSource::Hsi {
            defmt::warn!(
                "no 8 MHz clock on OSC_IN within {=u32} ms (the ST-LINK's MCO not routed by the \
                 board's solder bridges): running on the 16 MHz HSI, ±1 % at 25 °C",
                clock_start::HSE_STARTUP_TIMEOUT_MS
            );
        }
        rcc
    }

    #[init(local = [
        rx_bytes: Queue<u8, RX_QUEUE> = Queue::new(),
        scan_buf: [u32; ADC_SCAN_LEN] = [0; ADC_SCAN_LEN],
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        paint_stack();
        let dp = cx.device;
        let mut rcc = freeze_clocks(dp.RCC);
        if rcc.clocks.pclk2().raw() != board::PCLK2_HZ {
            defmt::error!(
                "PCLK2 is {=u32} Hz, not {=u32}: the ADC clock is not {=u32} Hz",
                rcc.clocks.pclk2().raw(),
                board::PCLK2_HZ,
                board::ADC_CLOCK_HZ
            );
        }
        let gpioa = dp.GPIOA.split(&mut rcc);
        let gpiob = dp.GPIOB.split(&mut rcc);

        let mut serial = dp
            .USART2
            .serial((gpioa.pa2, gpioa.pa3), board::BAUD.bps(), &mut rcc)
            .unwrap_or_else(|_| defmt::panic!("USART2 configuration"));
        serial.listen(stm32f4xx_hal::serial::Event::RxNotEmpty);
        let (tx, rx) = serial.split();
        let (rx_queue, rx_consumer) = cx.local.rx_bytes.split();

        let mut store = board::store(LockedFlash::new(dp.FLASH))
            .unwrap_or_else(|| defmt::panic!("calibration store geometry"));
        // Erase ahead, before sampling starts: a calibration written later only programs.
        if store.prepare().is_err() {
            defmt::warn!("calibration store: erasing ahead failed");
        }
        let mut controller = Controller::boot(board::info(), store, LeverMode::RateAndAcceleration);
        controller.set_imu(board::ANALOG_ACCELEROMETERS, 0);

        let gyro = init_gyro(
            spi1(
                dp.SPI1,
                (gpioa.pa5, gpioa.pa6, gpioa.pa7),
                &GYRO_SPI,
                &mut rcc,
            ),
            gpiob.pb6.into_push_pull_output(),
        );

        let mut scan = init_scan(
            dp.ADC1,
            (gpioa.pa0, gpioa.pa1, gpioa.pa4),
            dp.DMA2,
            &mut rcc,
            cx.local.scan_buf,
        );
        scan.start(|_| {});

        let pipeline =
            cortex_m::singleton!(: Pipeline<OUTPUT_QUEUE> = Pipeline::new(SAMPLE_RATE_HZ))
                .unwrap_or_else(|| defmt::panic!("pipeline singleton"));
        pipeline.apply(PipelineCommand::Compensator(controller.compensator()));

        // TIM2 update → TRGO (CR2.MMS = update) → ADC external trigger. Started last.
        let mut timer = dp.TIM2.counter_hz(&mut rcc);
        // SAFETY: only the master mode selection, which the HAL's counter does not use.
        unsafe { (*TIM2::ptr()).cr2().modify(|_, w| w.mms().update()) };
        timer
            .start(SAMPLE_RATE_HZ.Hz())
            .unwrap_or_else(|_| defmt::panic!("TIM2 at the sample rate"));
        defmt::info!(
            "accel-cal firmware on STM32F446: {=u32} Hz, ADC clock {=u32} Hz",
            SAMPLE_RATE_HZ,
            board::ADC_CLOCK_HZ
        );
        (
            Shared { pipeline, scan },
            Local {
                gyro,
                scaling: Scaling {
                    volts_per_code: board::VREF_V / f32::from(board::ADC_MAX),
                    rad_s_per_lsb: firmware::imu::l3gd20h::RAD_S_PER_LSB_2000DPS,
                },
                temperature: TemperatureMean::new(SAMPLE_RATE_HZ),
                vtemp_cal: (VtempCal30::get().read(), VtempCal110::get().read()),
                rx,
                rx_queue,
                link: RxQueueLink::new(rx_consumer, tx),
                service: LinkService::new(controller),
                _timer: timer,
            },
        )
    }

    /// ADC1 scanning x, y, z and the temperature sensor on each TIM2 trigger, into `buf` by DMA2
    /// stream 0 (transfer-complete and overrun interrupts on).
    fn init_scan(
        adc1: ADC1,
        pins: (PA0, PA1, PA4),
        dma2: DMA2,
        rcc: &mut Rcc,
        buf: ScanBuf,
    ) -> ScanDma {
        // One scan per TIM2 update: x, y, z, then the temperature sensor.
        let mut adc = Adc::new(
            adc1,
            true,
            AdcConfig::default()
                .clock(Clock::Pclk2_div_4)
                .scan(Scan::Enabled)
                .continuous(Continuous::Single)
                .dma(Dma::Continuous)
                .external_trigger(TriggerMode::RisingEdge, ExternalTrigger::Tim_2_trgo),
            rcc,
        );
        adc.configure_channel(&pins.0.into_analog(), Sequence::One, SampleTime::Cycles_56);
        adc.configure_channel(&pins.1.into_analog(), Sequence::Two, SampleTime::Cycles_56);
        adc.configure_channel(
            &pins.2.into_analog(),
            Sequence::Three,
            SampleTime::Cycles_56,
        );
        // The temperature sensor needs ≥ 10 µs of sampling: 480 cycles at 22.5 MHz = 21 µs.
        adc.configure_channel(&Temperature, Sequence::Four, SampleTime::Cycles_480);
        adc.enable_temperature_and_vref();
        // SAFETY: sets only the overrun interrupt enable of ADC1, which the HAL leaves alone.
        unsafe { (*ADC1::ptr()).cr1().modify(|_, w| w.ovrie().set_bit()) };
        board::guard_range_ends();
        let streams = StreamsTuple::new(dma2, rcc);
        Transfer::init_peripheral_to_memory(
            streams.0,
            AdcWords(adc),
            buf,
            None,
            DmaConfig::default()
                .transfer_complete_interrupt(true)
                .memory_increment(true)
                .double_buffer(false),
        )
    }

    fn init_gyro(spi: Spi<SPI1>, cs: PB6<Output<PushPull>>) -> Option<GyroDev> {
        // The L3GD20H driver issues no delay operations, so the device needs no delay source.
        let dev = ExclusiveDevice::new_no_delay(spi, cs).ok()?;
        match L3gd20::new(dev) {
            Ok(g) => Some(g),
            Err(_) => {
                defmt::warn!("no gyro on SPI1: rates read as 0, use LeverMode::Off");
                None
            }
        }
    }

    /// The link service and the stack measurement, whenever nothing else runs.
    #[idle(shared = [pipeline], local = [link, service])]
    fn idle(cx: idle::Context) -> ! {
        let (link, service) = (cx.local.link, cx.local.service);
        let mut pipeline = LockedPipeline(cx.shared.pipeline);
        let mut high_water = HighWater::new();
        let mut rounds = 0u32;
        loop {
            match service.poll(link, &mut pipeline) {
                Some(BoardEvent::Reset) => {
                    service.flush(link, 10_000_000);
                    cortex_m::peripheral::SCB::sys_reset();
                }
                // Refused by the request handler on this board (no virtual unit).
                Some(BoardEvent::SetTable(_)) | Some(BoardEvent::SetTemperature(_)) | None => {}
            }
            // A calibration write's store, here at the lowest priority.
            service.run_store_here(&mut pipeline);
            rounds = rounds.wrapping_add(1);
            if rounds % 65_536 == 0 {
                log_stack_growth(&mut high_water);
            }
        }
    }

    /// One scan finished: re-arm the DMA at once (the next trigger is a sample period away), then
    /// the gyro and the pipeline, preemptible by the receive interrupt.
    #[task(binds = DMA2_STREAM0, priority = 2, shared = [pipeline, scan],
           local = [gyro, scaling, temperature, vtemp_cal])]
    fn scan_done(mut cx: scan_done::Context) {
        let scan = cx.shared.scan.lock(|t| {
            // SAFETY: not double-buffered: the closure copies the finished scan before the stream is
            // re-enabled on the same buffer.
            unsafe {
                t.next_transfer_with(|buf, _| {
                    let copy = *buf;
                    (buf, copy)
                })
            }
            .ok()
        });
        let Some(scan) = scan else {
            return;
        };
        let l = cx.local;
        let (codes, temp_code) = split_scan(&scan);
        let adc_at_end = board::take_watchdog_flag();
        // No gyro: rates read as 0. A failed read: NaN, flagged and left out of the statistics.
        let words = l.gyro.as_mut().map_or(Ok([0; 3]), Gyro::read_words);
        let mut sample = l
            .scaling
            .convert(&codes, words.as_ref().unwrap_or(&[0; 3]), adc_at_end);
        if words.is_err() {
            sample.rate_rad_s = [f32::NAN; 3];
        }
        let temp_c = firmware::die_temperature::from_code(
            temp_code,
            l.vtemp_cal.0,
            l.vtemp_cal.1,
            board::VREF_V,
        );
        let refresh = l.temperature.push(temp_c);
        let gap = SCAN_GAP.swap(false, Ordering::Relaxed);
        cx.shared.pipeline.lock(|p| {
            if gap {
                // Scans were missed while the CPU stalled (how many is not known).
                p.on_samples_lost(0);
            }
            if let Some(t) = refresh {
                p.set_temperature(t);
            }
            p.on_sample(&sample);
        });
    }

    /// A scan's result was not read in time (the CPU stalled on a flash erase while the timer kept
    /// triggering): the ADC stops its DMA requests. Re-arm both; sampling resumes at the next trigger.
    #[task(binds = ADC, priority = 2, shared = [scan], local = [overruns: u32 = 0])]
    fn adc_overrun(mut cx: adc_overrun::Context) {
        // SAFETY: ADC1's DMA and overrun bits; the HAL owns the rest of the ADC through `scan`,
        // which this task holds locked.
        let adc = unsafe { &*ADC1::ptr() };
        cx.shared.scan.lock(|t| {
            adc.cr2().modify(|_, w| w.dma().clear_bit());
            // One write, not `modify`: a read-modify-write would also clear the watchdog's or
            // the next scan's flag raised between its read and its write.
            board::clear_adc_flags(firmware::conversion::ADC_SR_OVR);
            // SAFETY: not double-buffered: restarts the stream on its own buffer.
            let _ = unsafe { t.next_transfer_with(|buf, _| (buf, ())) };
            adc.cr2().modify(|_, w| w.dma().set_bit());
        });
        SCAN_GAP.store(true, Ordering::Relaxed);
        *cx.local.overruns += 1;
        defmt::warn!("ADC overrun #{=u32}: scan re-armed", *cx.local.overruns);
    }

    /// Each received byte into the queue; the link service reads it at its own pace.
    #[task(binds = USART2, priority = 3, local = [rx, rx_queue])]
    fn usart2_rx(cx: usart2_rx::Context) {
        use embedded_hal_nb::serial::Read;
        // The HAL clears a receive error (overrun, framing, noise) by reading the data register:
        // that byte is lost and the frame it belonged to is answered as malformed. Bounded: the
        // USART holds one byte, so a few reads always empty it.
        for _ in 0..4 {
            match cx.local.rx.read() {
                Ok(b) => on_rx_byte(cx.local.rx_queue, b),
                Err(embedded_hal_nb::nb::Error::WouldBlock) => break,
                Err(embedded_hal_nb::nb::Error::Other(_)) => {}
            }
        }
    }
}
