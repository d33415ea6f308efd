//! Firmware for an STM32F405 flight controller with a Bosch BMI270 (the SpeedyBee F405 V3, see
//! `firmware::board::f405`). Build: `cargo build --release --no-default-features --features
//! speedybee-v3 --bin f405-bmi270`; flash with probe-rs or DFU (README "Bring-up: STM32F405").
//!
//! The BMI270 is read on data ready (`firmware::imu::bmi270`, "Data path"): each rising edge of
//! INT1 is one time-aligned accelerometer and gyro sample, read by blocking SPI transfers from the
//! interrupt itself (26 bytes and 4 for the temperature: about 50 µs at the V3 bus's 5.25 MHz, 8 %
//! of the time at 1.6 kHz), so no DMA chain is needed. RTIC 2 tasks, highest priority first:
//!
//! | task | binds | priority | does |
//! |---|---|---|---|
//! | `imu_drdy` | EXTI4 (INT1 on PC4) | 2 | reads the sample, rotates it into the board's axes, runs the pipeline on it |
//! | `register_check` | SysTick (10 Hz) | 2 | reads back one configured register (PX4's `RegisterCheck`); on a mismatch (a brown-out reset the part) starts it again |
//! | `usb` | OTG_FS | 1 | USB device, link service (requests, frames out); a calibration write's store only queued |
//! | `idle` | — | 0 | the calibration store, stack high-water mark, LED blink when the IMU is missing, `wfi` |
//!
//! The IMU's two tasks share one priority, so neither waits on the other's lock; the USB task
//! locks the pipeline (BASEPRI to 2) for one `pop_output`/`apply` at a time, and an edge of INT1
//! that comes meanwhile stays pending in the EXTI until the lock ends.
#![no_std]
#![no_main]

use defmt_rtt as _;
use panic_probe as _;

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use embedded_hal_bus::spi::ExclusiveDevice;
    use stm32f4xx_hal::gpio::{Edge, Input, Output, PushPull, PA4, PC4};
    use stm32f4xx_hal::otg_fs::{UsbBusType, USB};
    use stm32f4xx_hal::pac::{self, SPI1};
    use stm32f4xx_hal::prelude::*;
    use stm32f4xx_hal::spi::Spi;
    use stm32f4xx_hal::timer::{SysCounterHz, SysEvent};
    use stm32f4xx_hal::watchdog::IndependentWatchdog;
    use usb_device::bus::UsbBusAllocator;

    use firmware::board::f405::{self as board, OUTPUT_QUEUE};
    use firmware::board::f405_service::{
        boot_controller, count_watchdog_reset, freeze_clocks, idle_loop, init_usb, prepared_store,
        start_watchdog, CycleDelay, ImuReport, UsbTask,
    };
    use firmware::board::paint_stack;
    use firmware::board::stm32_common::{spi1, Store};
    use firmware::boards::ImuPart;
    use firmware::health::{Counter, HealthCounters};
    use firmware::imu::bmi270::Bmi270;
    use firmware::imu::{ImuFlags, ImuSample, ImuSource, PipelineFeed};
    use firmware::imu_bursts::NO_SAMPLE;
    use firmware::pipeline::PipelineCommand;
    use firmware::protocol::StoreMailbox;
    use firmware::{LinkService, Pipeline};

    // This binary reads a BMI270 on data ready; an ICM-42688-P board is `f405`'s.
    const _: () = assert!(
        matches!(board::BOARD.imu, ImuPart::Bmi270),
        "this board's IMU is read by another binary: `--bin f405` for an ICM-42688-P"
    );

    /// The IMU on SPI1: the bus, its chip select and the driver's delay.
    type Imu = Bmi270<ExclusiveDevice<Spi<SPI1>, PA4<Output<PushPull>>, CycleDelay>>;

    /// The register check's rate, Hz: eight registers, each read back within a second.
    const CHECK_HZ: u32 = 10;

    /// The error counters the device reports to `Health`.
    static HEALTH: HealthCounters = HealthCounters::new();

    #[shared]
    struct Shared {
        pipeline: &'static mut Pipeline<OUTPUT_QUEUE>,
        /// The part (`None`: it did not answer at boot).
        imu: Option<Imu>,
        /// A calibration write's store job, between the USB task and the idle loop.
        store_job: StoreMailbox<Store>,
    }

    #[local]
    struct Local {
        int1: PC4<Input>,
        /// SysTick, counting the register check's period (kept so that it keeps running).
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
        let (imu, status) = init_imu(spi, cs);
        let imu_found = imu.is_some();

        let mut tick = cx.core.SYST.counter_hz(&rcc.clocks);
        tick.start(CHECK_HZ.Hz())
            .unwrap_or_else(|_| defmt::panic!("SysTick at the register check's rate"));
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
        defmt::info!(
            "accel-cal firmware on STM32F405: BMI270 at {=u32} Hz, USB CDC-ACM",
            sample_rate_hz
        );
        (
            Shared {
                pipeline,
                imu,
                store_job: StoreMailbox::new(),
            },
            Local {
                int1,
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

    /// Starts the BMI270 (`firmware::imu::bmi270`, steps 1–6: its configuration file uploaded,
    /// data ready on INT1); `None` when it does not answer, with its start for `Health`.
    fn init_imu(
        spi: Spi<SPI1>,
        cs: PA4<Output<PushPull>>,
    ) -> (Option<Imu>, shared::wire::ImuStatus) {
        // The chip select cannot fail (`Infallible`): the device is always made.
        let Ok(dev) = ExclusiveDevice::new(spi, cs, CycleDelay);
        match Bmi270::new(dev, board::BMI270_CONFIG) {
            Ok(imu) => (Some(imu), board::bmi270_status::<()>(&Ok(()))),
            Err(e) => {
                let status = board::bmi270_status(&Err(e));
                defmt::error!(
                    "BMI270 not answering on SPI1 (CHIP_ID {=u8:#x}): no samples",
                    status.who_am_i
                );
                (None, status)
            }
        }
    }

    /// The calibration store, stack high-water mark (once per 2048 wakes: about a second at
    /// 1.6 kHz and the check's 10 Hz); without an IMU, the LED blinks fast (`idle_loop`).
    #[idle(local = [imu_found, watchdog], shared = [store_job])]
    fn idle(cx: idle::Context) -> ! {
        let mut store_job = cx.shared.store_job;
        idle_loop(cx.local.watchdog, &mut store_job, *cx.local.imu_found, 2048)
    }

    /// Data ready: the sample read, counted where it follows lost ones, rotated into the board's
    /// axes and run through the pipeline.
    #[task(binds = EXTI4, priority = 2, shared = [pipeline, imu],
           local = [int1, feed, led_period, samples: u32 = 0])]
    fn imu_drdy(mut cx: imu_drdy::Context) {
        let l = cx.local;
        l.int1.clear_interrupt_pending_bit();
        let mut buf = [NO_SAMPLE; 1];
        let drained = cx
            .shared
            .imu
            .lock(|imu| imu.as_mut().map(|i| i.drain(&mut buf)));
        let n = match drained {
            Some(Ok(d)) => d.samples,
            Some(Err(_)) | None => return,
        };
        let samples = &mut buf[..n];
        for s in samples.iter() {
            if s.flags.has(ImuFlags::DATA_LOST) {
                HEALTH.add(Counter::LostSamples, u32::from(s.lost_before.max(1)));
            }
        }
        board::IMU_ALIGNMENT.apply(samples);
        let samples: &[ImuSample] = samples;
        cx.shared.pipeline.lock(|p| {
            l.feed.push_all(samples, p);
            *l.samples += n as u32;
            if *l.samples >= *l.led_period {
                *l.samples = 0;
                board::show_state(p.is_calibrated());
            }
            if p.queued() > 0 {
                rtic::pend(pac::Interrupt::OTG_FS);
            }
        });
    }

    /// Ten times a second: one configured register read back; a mismatch (the part lost its
    /// configuration, as after a brown-out) starts it again, counted for `Health`.
    #[task(binds = SysTick, priority = 2, shared = [imu], local = [tick])]
    fn register_check(mut cx: register_check::Context) {
        let _ = cx.local.tick.wait();
        cx.shared.imu.lock(|imu| {
            let Some(imu) = imu.as_mut() else {
                return;
            };
            if imu.check_next_register().is_ok() {
                return;
            }
            HEALTH.add(Counter::Reinit, 1);
            defmt::warn!("BMI270 lost its configuration: starting it again");
            if imu.reinit().is_err() {
                defmt::error!("BMI270 start failed: retried at the next check");
            }
        });
    }

    /// USB events and the link service: requests in, answers and frames out (`UsbTask::round`).
    /// Also pended by `imu_drdy` when frames are queued.
    #[task(binds = OTG_FS, priority = 1, shared = [pipeline, store_job], local = [usb])]
    fn usb(cx: usb::Context) {
        let mut store_job = cx.shared.store_job;
        cx.local.usb.round(cx.shared.pipeline, &mut store_job);
    }
}
