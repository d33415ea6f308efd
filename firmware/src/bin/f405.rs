//! Firmware for an STM32F405 flight controller with an ICM-42688-P (SpeedyBee F405 V4 pins, see
//! `firmware::board::f405`). Build: `cargo build --release --no-default-features --features
//! board-f405 --bin f405`; flash with probe-rs or DFU (README "Bring-up: STM32F405").
//!
//! RTIC 2 tasks, highest priority first (README "Sampling architecture"):
//!
//! | task | binds | priority | does |
//! |---|---|---|---|
//! | `imu_int` | EXTI4 (INT1 on PC4) | 3 | FIFO watermark: CS low, starts the SPI1 TX DMA (the RX stream is armed) |
//! | `burst_done` | DMA2_STREAM2 (SPI1 RX) | 2 | CS high, re-arms RX, decodes the packets, rotates them into the board's axes, runs the pipeline on each; every 100 ms one configured register read back in the chain, the part started again if it changed |
//! | `stall_tick` | SysTick (every 10 ms) | 2 | restarts a burst chain that stalled (an interrupt lost): FIFO flushed, status read |
//! | `usb` | OTG_FS | 1 | USB device, link service (requests, frames out); a calibration write's store only queued |
//! | `idle` | — | 0 | the calibration store (sector erase and programming), stack high-water mark, LED blink when the IMU is missing, `wfi` |
//!
//! Locks: the pipeline is shared by `burst_done` and `usb`; `usb` locks it (BASEPRI to 2) for one
//! `pop_output`/`apply`, never around I/O. The watermark interrupt (3) is never masked by a lock.
//! A calibration write's store job goes from `usb` to `idle` and back through `store_job` (locked
//! only to move the job, never while it runs).
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
    use stm32f4xx_hal::timer::{SysCounterHz, SysDelay, SysEvent};
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
    use firmware::imu::icm42688::check::{check_and_heal, restart, Checked};
    use firmware::imu::icm42688::{Core, Error as IcmError, Icm42688, BATCH_PACKETS};
    use firmware::imu::ImuFlags;
    use firmware::imu::ImuSample;
    use firmware::imu_bursts::{
        BurstReader, InFlight, Mismatch, BURST_MAX, NO_SAMPLE, STALL_TICK_MS,
    };
    use firmware::pipeline::PipelineCommand;
    use firmware::pipeline::PipelineFeed;
    use firmware::protocol::StoreMailbox;
    use firmware::{LinkService, Pipeline};
    use shared::wire::ImuStatus;

    // The DMA burst chain below reads an ICM-42688-P; the V3's BMI270 is `f405-bmi270`'s.
    const _: () = assert!(
        matches!(board::BOARD.imu, ImuPart::Icm42688P),
        "this board's IMU is read by another binary: `--bin f405-bmi270` for a BMI270"
    );

    /// A burst chain is running (set by the watermark interrupt, cleared by the completion task).
    static IN_FLIGHT: InFlight = InFlight::new();
    /// The error counters the device reports to `Health`.
    static HEALTH: HealthCounters = HealthCounters::new();

    #[shared]
    struct Shared {
        pipeline: &'static mut Pipeline<OUTPUT_QUEUE>,
        /// The SPI bus during bursts: its DMA streams and the chip select.
        bus: board::ImuBus,
        /// The chain's decisions (`None`: no IMU answered at boot); the completion task and the
        /// stall timer share it at the same priority.
        reader: Option<BurstReader>,
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
        samples: &'static mut [ImuSample; BATCH_PACKETS],
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
        rx_buf: [u8; BURST_MAX] = [0; BURST_MAX],
        sample_buf: [ImuSample; BATCH_PACKETS] = [NO_SAMPLE; BATCH_PACKETS],
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

        // The IMU: configured over the blocking bus, then the bus is handed to the DMA streams.
        let mut cs = gpioa.pa4.into_push_pull_output();
        cs.set_high();
        let spi = spi1(
            dp.SPI1,
            (gpioa.pa5, gpioa.pa6, gpioa.pa7),
            &board::BOARD.imu_spi,
            &mut rcc,
        );
        let sample_rate_hz = board::IMU_CONFIG.odr.hz();
        let mut delay = cx.core.SYST.delay(&rcc.clocks);
        let (reader, imu_status) = init_imu(spi, &mut cs, &mut delay);
        let imu_found = reader.is_some();
        // SysTick, free after the IMU's set-up, ticks the stall check every STALL_TICK_MS.
        let mut tick = delay.release().counter_hz();
        tick.start((1000 / STALL_TICK_MS).Hz())
            .unwrap_or_else(|_| defmt::panic!("SysTick at the stall check's rate"));
        tick.listen(SysEvent::Update);
        let dma = SpiDma::new(StreamsTuple::new(dp.DMA2, &mut rcc));
        let rx = RxBuf::new(cx.local.rx_buf);

        let mut int1 = gpioc.pc4.into_pull_down_input();
        let mut syscfg = dp.SYSCFG.constrain(&mut rcc);
        int1.make_interrupt_source(&mut syscfg);
        int1.trigger_on_edge(&mut dp.EXTI, Edge::Rising);
        int1.enable_interrupt(&mut dp.EXTI);

        let imu = ImuReport {
            status: imu_status,
            accel_lsb_per_g: board::IMU_CONFIG.accel_range.lsb_per_g() as u32,
            health: &HEALTH,
        };
        let controller = boot_controller(store, sample_rate_hz, imu);
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

        // INT1 is latched: if the FIFO reached its watermark before EXTI4 was armed, no edge will
        // come until INT_STATUS is read. One read at start-up clears it.
        rtic::pend(pac::Interrupt::EXTI4);
        defmt::info!(
            "accel-cal firmware on STM32F405: ICM-42688-P at {=u32} Hz, USB CDC-ACM",
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
                imu_found,
                watchdog,
                samples: cx.local.sample_buf,
                feed: PipelineFeed::new(sample_rate_hz),
                led_period: sample_rate_hz / 2,
                usb: UsbTask {
                    usb_dev,
                    link,
                    service: Some(LinkService::new(controller)),
                    sample_rate_hz,
                    imu,
                },
            },
        )
    }

    /// Configures the ICM-42688-P over the blocking bus, then hands SPI1 to its DMA streams. `None`
    /// when the part does not answer.
    fn init_imu(
        mut spi: Spi<SPI1>,
        cs: &mut PA4<Output<PushPull>>,
        delay: &mut SysDelay,
    ) -> (Option<BurstReader>, ImuStatus) {
        let (configured, status) = match ExclusiveDevice::new(&mut spi, cs, delay) {
            Ok(dev) => {
                let result = Icm42688::new(dev, board::IMU_CONFIG).map(|_| ());
                (result.is_ok(), board::imu_status(&result))
            }
            Err(_) => (false, board::imu_status::<()>(&Err(IcmError::Spi(())))),
        };
        let core = configured
            .then(|| Core::new(board::IMU_CONFIG).ok())
            .flatten();
        let reader = match core {
            // The part is configured and its FIFO running; the driver's state continues in the
            // burst reader, the bus goes to the DMA streams.
            Some(core) => Some(BurstReader::new(core)),
            None => {
                defmt::error!(
                    "ICM-42688-P not answering on SPI1 (WHO_AM_I {=u8:#x}): no samples",
                    status.who_am_i
                );
                None
            }
        };
        board::spi1_to_dma(spi);
        (reader, status)
    }

    /// The calibration store, stack high-water mark (once per 1024 wakes: about a second at the
    /// watermark's 1 kHz); without an IMU, the LED blinks fast (`idle_loop`).
    #[idle(local = [imu_found, watchdog], shared = [store_job])]
    fn idle(cx: idle::Context) -> ! {
        let mut store_job = cx.shared.store_job;
        idle_loop(cx.local.watchdog, &mut store_job, *cx.local.imu_found, 1024)
    }

    /// FIFO watermark: start the chain's status burst, unless a chain runs (its status read will
    /// see the new packets).
    #[task(binds = EXTI4, priority = 3, shared = [bus], local = [int1, rx_for_int])]
    fn imu_int(mut cx: imu_int::Context) {
        cx.local.int1.clear_interrupt_pending_bit();
        if let Some(burst) = IN_FLIGHT.on_watermark() {
            let rx = *cx.local.rx_for_int;
            cx.shared.bus.lock(|bus| board::start_burst(bus, burst, rx));
        }
    }

    /// A burst ended: CS high, the driver's decision on the received bytes (next burst of the
    /// chain, decoded samples) outside any lock, then the pipeline on each sample — all preemptible
    /// by the watermark interrupt. The locks cover register writes only (the reader's is free: its
    /// other user, `stall_tick`, has the same priority).
    #[task(binds = DMA2_STREAM2, priority = 2, shared = [pipeline, bus, reader],
           local = [rx, samples, feed, led_period, packets: u32 = 0])]
    fn burst_done(mut cx: burst_done::Context) {
        let l = cx.local;
        // The stream's flags first, whatever follows: a flag left set would re-enter at once.
        let Some(end) = cx.shared.bus.lock(|(dma, cs)| {
            let end = dma.finish()?;
            cs.set_high();
            Some(end)
        }) else {
            return; // spurious: the burst is still running
        };
        let rx = *l.rx;
        let samples = &mut *l.samples;
        let Some(done) = cx.shared.reader.lock(|reader| {
            // None: no IMU answered at boot (the boot-time kick still runs one burst).
            let reader = reader.as_mut()?;
            Some(match end {
                // SAFETY: the burst ended and the next starts below, after the last use of
                // `bytes`.
                BurstEnd::Complete => {
                    let bytes = unsafe { rx.received(reader.expected_len()) };
                    reader.on_complete(bytes, samples, &IN_FLIGHT)
                }
                BurstEnd::Error => reader.abandon(&IN_FLIGHT),
            })
        }) else {
            return;
        };
        if let Some(next) = done.next {
            cx.shared.bus.lock(|bus| board::start_burst(bus, next, rx));
        }
        if let Some(m) = done.mismatch {
            // The periodic register check found the part's configuration changed: started again
            // over the polled bus (the chain still holds it), then the chain goes on.
            let core = cx.shared.bus.lock(|bus| heal(&mut bus.1, m));
            let next = cx.shared.reader.lock(|reader| {
                reader
                    .as_mut()
                    .and_then(|r| r.resume_after_heal(core, &IN_FLIGHT))
            });
            if let Some(next) = next {
                cx.shared.bus.lock(|bus| board::start_burst(bus, next, rx));
            }
            return;
        }
        if let Some(h) = done.corrupt_header {
            HEALTH.add(Counter::FifoResync, 1);
            defmt::warn!("IMU FIFO out of step (header {=u8:#x}): flushed", h);
        }
        for s in &samples[..done.samples] {
            if s.flags.has(ImuFlags::DATA_LOST) {
                HEALTH.add(Counter::LostSamples, u32::from(s.lost_before.max(1)));
            }
        }
        // Into the board's axes (the calibration's body frame), outside any lock.
        board::IMU_ALIGNMENT.apply(&mut samples[..done.samples]);
        cx.shared.pipeline.lock(|p| {
            // A FIFO overflow, a flushed FIFO or a failed burst reaches the window through the
            // sample's DATA_LOST flag.
            l.feed.push_all(&samples[..done.samples], p);
            *l.packets += done.samples as u32;
            if *l.packets >= *l.led_period {
                *l.packets = 0;
                board::show_state(p.is_calibrated());
            }
            if p.queued() > 0 {
                rtic::pend(pac::Interrupt::OTG_FS);
            }
        });
    }

    /// The part started again after the periodic register check found `m` (PX4's `Reset()` on a
    /// failed `RegisterCheck`), over the polled bus, counted as a re-init for `Health`; its fresh
    /// state, or `None` when the start failed (the next check, 100 ms on, tries again).
    fn heal(cs: &mut PA4<Output<PushPull>>, m: Mismatch) -> Option<Core> {
        HEALTH.add(Counter::Reinit, 1);
        defmt::warn!(
            "ICM-42688-P register {=u8:#x} read {=u8:#x}, not {=u8:#x}: started again",
            m.reg,
            m.read,
            m.expected
        );
        let dev = ExclusiveDevice::new(PolledSpi1, cs, CycleDelay).ok()?;
        match restart(dev, board::IMU_CONFIG) {
            Ok(core) => Some(core),
            Err(e) => {
                defmt::error!("ICM-42688-P start failed: {}", defmt::Debug2Format(&e));
                None
            }
        }
    }

    /// The register check after a stall over the polled bus: the part's fresh state where it had
    /// lost its configuration and was started again.
    fn check_after_stall(cs: &mut PA4<Output<PushPull>>) -> Option<Core> {
        let dev = ExclusiveDevice::new(PolledSpi1, cs, CycleDelay).ok()?;
        match check_and_heal(dev, board::IMU_CONFIG) {
            Ok(Checked::Intact) => None,
            Ok(Checked::Restarted {
                reg,
                expected,
                read,
                core,
            }) => {
                HEALTH.add(Counter::Reinit, 1);
                defmt::warn!(
                    "ICM-42688-P register {=u8:#x} read {=u8:#x}, not {=u8:#x}: started again",
                    reg,
                    read,
                    expected
                );
                Some(core)
            }
            Err(e) => {
                defmt::error!(
                    "ICM-42688-P register check failed: {}",
                    defmt::Debug2Format(&e)
                );
                None
            }
        }
    }

    /// Every 10 ms: when no burst completed for the reader's stall time (an interrupt of the chain
    /// was lost), restart the chain — CS high then low around the restart's flush, the streams
    /// stopped and restarted by `SpiDma::start`; the next sample is flagged as following lost
    /// data (`imu_bursts`, "A chain that stalls").
    ///
    /// Before the restart, the configured registers are read back over the polled bus (PX4's
    /// `RegisterCheck`, `imu::icm42688::check`): a part that reset under the board (a brown-out)
    /// raises no watermark again, so it is started again here, counted as a re-init for `Health`.
    #[task(binds = SysTick, priority = 2, shared = [bus, reader], local = [rx_for_tick, tick])]
    fn stall_tick(mut cx: stall_tick::Context) {
        let Some(burst) = cx
            .shared
            .reader
            .lock(|reader| reader.as_mut().and_then(|r| r.on_tick(&IN_FLIGHT)))
        else {
            return;
        };
        HEALTH.add(Counter::Stall, 1);
        defmt::warn!("IMU burst chain stalled: FIFO flushed, reading restarted");
        let rx = *cx.local.rx_for_tick;
        let restarted = cx.shared.bus.lock(|bus| {
            bus.1.set_high();
            check_after_stall(&mut bus.1)
        });
        if let Some(core) = restarted {
            cx.shared.reader.lock(|reader| {
                if let Some(r) = reader.as_mut() {
                    r.replace_core(core);
                }
            });
        }
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
