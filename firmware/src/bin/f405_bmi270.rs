//! Firmware for an STM32F405 flight controller with a Bosch BMI270 (the SpeedyBee F405 V3, see
//! `firmware::board::f405`). Build: `cargo build --release --no-default-features --features
//! speedybee-v3 --bin f405-bmi270`; flash with probe-rs or DFU (README "Bring-up: STM32F405").
//!
//! The BMI270 is read on data ready without the CPU (`firmware::imu::bmi270::dma`, Betaflight's
//! way: one DMA burst per data-ready edge): each rising edge of INT1 starts one 35-byte burst on
//! SPI1's DMA2 streams (the ones the ICM-42688-P's chain uses), and the burst's completion decodes
//! the sample and runs the pipeline. The CPU spends two short interrupts per sample instead of the
//! ~50 µs blocking read (8 % of the CPU at 1.6 kHz) this replaced. RTIC 2 tasks, highest priority
//! first:
//!
//! | task | binds | priority | does |
//! |---|---|---|---|
//! | `imu_drdy` | EXTI4 (INT1 on PC4) | 3 | data ready: CS low, starts the sample burst (or notes it while a burst runs) |
//! | `burst_done` | DMA2_STREAM2 (SPI1 RX) | 2 | CS high; decodes the frame, rotates the sample into the board's axes, runs the pipeline; every 100 ms the next burst reads one configured register back (PX4's `RegisterCheck`), and a changed one starts the part again over the polled bus |
//! | `stall_tick` | SysTick (every 10 ms) | 2 | times the register check; after 80 ms without a completed burst (a DMA completion lost, or a part whose data ready stopped: a brown-out) reads a frame again, the check following it |
//! | `usb` | OTG_FS | 1 | USB device, link service (requests, frames out); a calibration write's store only queued |
//! | `idle` | — | 0 | the calibration store, stack high-water mark, LED blink when the IMU is missing, `wfi` |
//!
//! The "burst under way" state is an atomic (`imu_bursts::InFlight`, made with the BMI270's sample
//! burst), so the data-ready interrupt never waits; the bus lock covers a few register writes (and
//! a re-init after a failed check). The USB task locks the pipeline (BASEPRI to 2) for one
//! `pop_output`/`apply` at a time.
#![no_std]
#![no_main]

use defmt_rtt as _;
use panic_probe as _;

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use embedded_hal_bus::spi::ExclusiveDevice;
    use stm32f4xx_hal::dma::StreamsTuple;
    use stm32f4xx_hal::gpio::{Edge, Input, Output, PushPull, PA4, PC4};
    use stm32f4xx_hal::otg_fs::{UsbBusType, USB};
    use stm32f4xx_hal::pac::{self, SPI1};
    use stm32f4xx_hal::prelude::*;
    use stm32f4xx_hal::spi::Spi;
    use stm32f4xx_hal::timer::{SysCounterHz, SysEvent};
    use stm32f4xx_hal::watchdog::IndependentWatchdog;
    use usb_device::bus::UsbBusAllocator;

    use firmware::board::f405::{self as board, BurstEnd, PolledSpi1, RxBuf, SpiDma, OUTPUT_QUEUE};
    use firmware::board::f405_service::{
        boot_controller, count_watchdog_reset, freeze_clocks, idle_loop, init_usb, prepared_store,
        start_watchdog, CycleDelay, ImuReport, UsbTask,
    };
    use firmware::board::paint_stack;
    use firmware::board::stm32_common::{spi1, Store};
    use firmware::boards::ImuPart;
    use firmware::health::{Counter, HealthCounters};
    use firmware::imu::bmi270::dma::{Bmi270Bursts, Completed, BATCH, BURST_LEN, SAMPLE_CMD};
    use firmware::imu::bmi270::Bmi270;
    use firmware::imu::{ImuFlags, ImuSample};
    use firmware::imu_bursts::NO_SAMPLE;
    use firmware::imu_bursts::{InFlight, Mismatch, STALL_TICK_MS};
    use firmware::pipeline::PipelineCommand;
    use firmware::pipeline::PipelineFeed;
    use firmware::protocol::StoreMailbox;
    use firmware::{LinkService, Pipeline};

    // This binary reads a BMI270 on data ready; an ICM-42688-P board is `f405`'s.
    const _: () = assert!(
        matches!(board::BOARD.imu, ImuPart::Bmi270),
        "this board's IMU is read by another binary: `--bin f405` for an ICM-42688-P"
    );

    /// A sample burst is under way (set by the data-ready interrupt, ended by the completion
    /// task); a data-ready edge meanwhile gets its own burst when it ends.
    static IN_FLIGHT: InFlight = InFlight::with_command(&SAMPLE_CMD);
    /// The error counters the device reports to `Health`.
    static HEALTH: HealthCounters = HealthCounters::new();

    #[shared]
    struct Shared {
        pipeline: &'static mut Pipeline<OUTPUT_QUEUE>,
        /// The SPI bus during bursts: its DMA streams and the chip select.
        bus: board::ImuBus,
        /// The bursts' decisions (`None`: the part did not answer at boot); the completion task
        /// and the stall timer share it at the same priority.
        reader: Option<Bmi270Bursts>,
        /// A calibration write's store job, between the USB task and the idle loop.
        store_job: StoreMailbox<Store>,
    }

    #[local]
    struct Local {
        int1: PC4<Input>,
        rx_for_int: RxBuf,
        rx_for_tick: RxBuf,
        rx: RxBuf,
        /// SysTick, counting the stall timer's period (kept so that it keeps running).
        tick: SysCounterHz,
        feed: PipelineFeed,
        /// Samples between two LED updates (half a second).
        led_period: u32,
        usb: UsbTask,
        imu_found: bool,
        watchdog: IndependentWatchdog,
    }

    #[init(local = [
        ep_memory: [u32; 1024] = [0; 1024],
        usb_bus: Option<UsbBusAllocator<UsbBusType>> = None,
        rx_buf: [u8; BURST_LEN] = [0; BURST_LEN],
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        board::enter_bootloader_if_requested();
        paint_stack();
        let mut dp = cx.device;
        count_watchdog_reset(&dp.RCC, &HEALTH);
        let mut rcc = freeze_clocks(dp.RCC);
        let gpioa = dp.GPIOA.split(&mut rcc);
        let gpioc = dp.GPIOC.split(&mut rcc);
        board::init_led(); // `BOARD.led`, dark; its port's clock is on (split above)

        // The store first (`prepared_store`): its erase ahead stalls the CPU before samples flow.
        let store = prepared_store(dp.FLASH);

        let mut cs = gpioa.pa4.into_push_pull_output();
        cs.set_high();
        let spi = spi1(
            dp.SPI1,
            (gpioa.pa5, gpioa.pa6, gpioa.pa7),
            &board::BOARD.imu_spi,
            &mut rcc,
        );
        let sample_rate_hz = board::BMI270_CONFIG.odr.hz();
        let (reader, status) = init_imu(spi, &mut cs);
        let imu_found = reader.is_some();
        let dma = SpiDma::new(StreamsTuple::new(dp.DMA2, &mut rcc));
        let rx = RxBuf::new(cx.local.rx_buf);

        let mut tick = cx.core.SYST.counter_hz(&rcc.clocks);
        tick.start((1000 / STALL_TICK_MS).Hz())
            .unwrap_or_else(|_| defmt::panic!("SysTick at the stall check's rate"));
        tick.listen(SysEvent::Update);

        let mut int1 = gpioc.pc4.into_pull_down_input();
        let mut syscfg = dp.SYSCFG.constrain(&mut rcc);
        int1.make_interrupt_source(&mut syscfg);
        int1.trigger_on_edge(&mut dp.EXTI, Edge::Rising);
        int1.enable_interrupt(&mut dp.EXTI);

        let report = ImuReport {
            status,
            accel_lsb_per_g: board::BMI270_CONFIG.accel_range.lsb_per_g(),
            health: &HEALTH,
        };
        let controller = boot_controller(store, sample_rate_hz, report);
        let pipeline =
            cortex_m::singleton!(: Pipeline<OUTPUT_QUEUE> = Pipeline::new(sample_rate_hz))
                .unwrap_or_else(|| defmt::panic!("pipeline singleton"));
        pipeline.apply(PipelineCommand::Compensator(controller.compensator()));

        let watchdog = start_watchdog(dp.IWDG);
        let (usb_dev, link) = init_usb(
            USB::new(
                (dp.OTG_FS_GLOBAL, dp.OTG_FS_DEVICE, dp.OTG_FS_PWRCLK),
                (gpioa.pa11, gpioa.pa12),
                &rcc.clocks,
            ),
            cx.local.usb_bus,
            cx.local.ep_memory,
        );
        // A data-ready edge that came before EXTI4 was armed is not seen again if INT1 holds its
        // level until the data are read: one burst at start-up reads them.
        rtic::pend(pac::Interrupt::EXTI4);
        defmt::info!(
            "accel-cal firmware on STM32F405: BMI270 at {=u32} Hz, USB CDC-ACM",
            sample_rate_hz
        );
        (
            Shared {
                pipeline,
                bus: (dma, cs),
                reader,
                store_job: StoreMailbox::new(),
            },
            Local {
                int1,
                rx_for_int: rx,
                rx_for_tick: rx,
                rx,
                tick,
                feed: PipelineFeed::new(sample_rate_hz),
                led_period: sample_rate_hz / 2,
                usb: UsbTask {
                    usb_dev,
                    link,
                    service: Some(LinkService::new(controller)),
                    sample_rate_hz,
                    imu: report,
                },
                imu_found,
                watchdog,
            },
        )
    }

    /// Starts the BMI270 over the blocking bus (`firmware::imu::bmi270`, steps 1–6: its
    /// configuration file uploaded, data ready on INT1), then hands SPI1 to its DMA streams. `None`
    /// when it does not answer, with its start for `Health`.
    fn init_imu(
        mut spi: Spi<SPI1>,
        cs: &mut PA4<Output<PushPull>>,
    ) -> (Option<Bmi270Bursts>, shared::wire::ImuStatus) {
        // The chip select cannot fail (`Infallible`): the device is always made.
        let Ok(dev) = ExclusiveDevice::new(&mut spi, cs, CycleDelay);
        let result = Bmi270::new(dev, board::BMI270_CONFIG).map(|_| ());
        let status = board::bmi270_status(&result);
        let reader = match result {
            Ok(()) => Some(Bmi270Bursts::new(&board::BMI270_CONFIG)),
            Err(_) => {
                defmt::error!(
                    "BMI270 not answering on SPI1 (CHIP_ID {=u8:#x}): no samples",
                    status.who_am_i
                );
                None
            }
        };
        board::spi1_to_dma(spi);
        (reader, status)
    }

    /// The calibration store, stack high-water mark (once per 2048 wakes: about 0.6 s with a
    /// data-ready and a DMA interrupt per sample at 1.6 kHz and the 100 Hz tick); without an IMU,
    /// the LED blinks fast (`idle_loop`).
    #[idle(local = [imu_found, watchdog], shared = [store_job])]
    fn idle(cx: idle::Context) -> ! {
        let mut store_job = cx.shared.store_job;
        idle_loop(cx.local.watchdog, &mut store_job, *cx.local.imu_found, 2048)
    }

    /// Data ready: start the sample burst, unless one runs (it ends with this edge's burst).
    #[task(binds = EXTI4, priority = 3, shared = [bus], local = [int1, rx_for_int])]
    fn imu_drdy(mut cx: imu_drdy::Context) {
        cx.local.int1.clear_interrupt_pending_bit();
        if let Some(burst) = IN_FLIGHT.on_watermark() {
            let rx = *cx.local.rx_for_int;
            cx.shared.bus.lock(|bus| board::start_burst(bus, burst, rx));
        }
    }

    /// A burst ended: CS high, the reader's decision on the bytes (the sample into the batch,
    /// the next burst), then, every [`BATCH`] samples (5 ms), the pipeline on the batch — all
    /// preemptible by the data-ready interrupt. After a register check that found the part
    /// changed, it is started again here over the polled bus.
    #[task(binds = DMA2_STREAM2, priority = 2, shared = [pipeline, bus, reader],
           local = [rx, feed, led_period, samples: u32 = 0,
                    batch: [ImuSample; BATCH] = [NO_SAMPLE; BATCH], held: usize = 0])]
    fn burst_done(mut cx: burst_done::Context) {
        let l = cx.local;
        let Some(end) = cx.shared.bus.lock(|(dma, cs)| {
            let end = dma.finish()?;
            cs.set_high();
            Some(end)
        }) else {
            return; // spurious: the burst is still running
        };
        let rx = *l.rx;
        // `held` < BATCH always (reset when the batch is full, below).
        let slot = (*l.held).min(BATCH - 1);
        let out = &mut l.batch[slot];
        let Some(done) = cx.shared.reader.lock(|reader| {
            let reader = reader.as_mut()?;
            Some(match end {
                // SAFETY: the burst ended and the next starts below, after the last use of
                // the bytes.
                BurstEnd::Complete => {
                    let bytes = unsafe { rx.received(reader.expected_len()) };
                    reader.on_complete(bytes, out, &IN_FLIGHT)
                }
                BurstEnd::Error => Completed {
                    sample: false,
                    next: reader.abandon(&IN_FLIGHT),
                    mismatch: None,
                },
            })
        }) else {
            return;
        };
        let mut next = done.next;
        if let Some(m) = done.mismatch {
            let started = cx.shared.bus.lock(|bus| heal(&mut bus.1, m));
            next = cx.shared.reader.lock(|reader| {
                reader
                    .as_mut()
                    .and_then(|r| r.resume_after_heal(started, &IN_FLIGHT))
            });
        }
        if let Some(next) = next {
            cx.shared.bus.lock(|bus| board::start_burst(bus, next, rx));
        }
        if !done.sample {
            return;
        }
        let s = &l.batch[slot];
        if s.flags.has(ImuFlags::DATA_LOST) {
            HEALTH.add(Counter::LostSamples, u32::from(s.lost_before.max(1)));
        }
        *l.held = slot + 1;
        if *l.held < BATCH {
            return;
        }
        *l.held = 0;
        let batch = &mut *l.batch;
        board::IMU_ALIGNMENT.apply(batch);
        cx.shared.pipeline.lock(|p| {
            l.feed.push_all(batch, p);
            *l.samples += BATCH as u32;
            if *l.samples >= *l.led_period {
                *l.samples = 0;
                board::show_state(p.is_calibrated());
            }
            if p.queued() > 0 {
                rtic::pend(pac::Interrupt::OTG_FS);
            }
        });
    }

    /// The part started again after the register check found `m` changed (a brown-out, a
    /// flipped bit), over the polled bus while the reader holds it; counted as a re-init for
    /// `Health`. Whether it answered and took its configuration.
    fn heal(cs: &mut PA4<Output<PushPull>>, m: Mismatch) -> bool {
        HEALTH.add(Counter::Reinit, 1);
        defmt::warn!(
            "BMI270 register {=u8:#x} read {=u8:#x}, not {=u8:#x}: started again",
            m.reg,
            m.read,
            m.expected
        );
        let Ok(dev) = ExclusiveDevice::new(PolledSpi1, cs, CycleDelay);
        let started = Bmi270::new(dev, board::BMI270_CONFIG).is_ok();
        if !started {
            defmt::error!("BMI270 start failed: retried at the next check");
        }
        started
    }

    /// Every 10 ms: times the register check; after 80 ms without a completed burst, a frame read
    /// again (CS high then low, the streams restarted), the check following it.
    #[task(binds = SysTick, priority = 2, shared = [bus, reader], local = [rx_for_tick, tick])]
    fn stall_tick(mut cx: stall_tick::Context) {
        let _ = cx.local.tick.wait();
        let Some(burst) = cx
            .shared
            .reader
            .lock(|reader| reader.as_mut().and_then(|r| r.on_tick(&IN_FLIGHT)))
        else {
            return;
        };
        HEALTH.add(Counter::Stall, 1);
        let rx = *cx.local.rx_for_tick;
        cx.shared.bus.lock(|bus| {
            bus.1.set_high();
            board::drain_spi1_receiver();
            board::start_burst(bus, burst, rx);
        });
    }

    /// USB events and the link service: requests in, answers and frames out (`UsbTask::round`).
    /// Also pended by `burst_done` when frames are queued.
    #[task(binds = OTG_FS, priority = 1, shared = [pipeline, store_job], local = [usb])]
    fn usb(cx: usb::Context) {
        let mut store_job = cx.shared.store_job;
        cx.local.usb.round(cx.shared.pipeline, &mut store_job);
    }
}
