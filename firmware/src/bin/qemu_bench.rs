//! Cost of the per-sample path on QEMU mps2-an386, in instructions.
//!
//! Run under `-icount shift=0,align=off,sleep=off` (scripts/bench-qemu.sh): SysTick then counts
//! executed instructions, one tick per 40 instructions (25 MHz tick, 1 ns per instruction). Each
//! measurement runs `N` iterations over 16 varied inputs, subtracts an empty loop, and divides by `N`.
//! A block of 1000 `nop`s is measured first to show the conversion. These are instruction counts, not
//! Cortex-M4F cycles (use DWT CYCCNT on a board for cycles).
//!
//! The per-sample budgets are CPU shares at the boards' real rates, with the instruction count as
//! the proxy for cycles: the F405's IMU path at 8 kHz ≤ 2 % of 168 MHz (420 instructions per
//! sample) for each IMU — the ICM-42688-P (its FIFO packets in 16-packet transfers), the BMI270
//! (one data-ready frame per transfer, as the V3 reads it by DMA) and the LSM6DSO (tagged FIFO
//! words in 48-word transfers), each at 8 kHz whatever its own top rate, so that the three compare
//! —, the Nucleo's ADC path at 1 kHz ≤ 0.5 % of 180 MHz (900). The bench prints each whole
//! path's share and exits with a failure when one is over its budget.
#![no_std]
#![no_main]

use core::hint::black_box;

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use defmt_semihosting as _;

use embedded_hal::spi::{Operation, SpiDevice};
use firmware::board::qemu;
use firmware::conversion::{gyro_word, Scaling, ADC_SR_AWD};
use firmware::imu::icm42688::{regs, Core};
use firmware::imu::ImuSample;
use firmware::paper_unit;
use firmware::pipeline::PipelineFeed;
use firmware::pipeline::{PipelineCommand, Sample};
use firmware::stats::WindowAccumulator;
use firmware::virtual_sensor::{VirtualSensor, IMU_CONFIG};
use firmware::Pipeline;
use shared::omega_dot::OmegaDotEstimator;
use shared::units::{BodyAngularAccel, BodyRate, SensorOutputs};
use shared::wire::{StreamKind, StreamRequest};
use shared::{Compensator, LeverMode};

#[path = "qemu_bench/other_imus.rs"]
mod other_imus;
use other_imus::bench_other_imus;

const N: u32 = 4096;
const INSTR_PER_TICK: u32 = 40;

/// A per-sample budget: at most `share_permille` ‰ of a `clock_hz` CPU at `rate_hz` samples per
/// second.
struct Budget {
    path: &'static str,
    rate_hz: u32,
    clock_hz: u32,
    share_permille: u32,
}

impl Budget {
    /// Instructions per sample the share allows.
    const fn instructions(&self) -> u32 {
        (self.clock_hz / 1000) * self.share_permille / self.rate_hz
    }

    /// Prints the share of `x10` (tenths of an instruction per sample) at this budget's rate and
    /// clock; false when it is over the budget.
    fn check(&self, x10: u32) -> bool {
        // Hundredths of a percent: x10/10 instructions × rate / clock × 10⁴.
        let share = (u64::from(x10) * u64::from(self.rate_hz) * 1000
            + u64::from(self.clock_hz) / 2)
            / u64::from(self.clock_hz);
        let ok = x10 <= self.instructions() * 10;
        hprintln!(
            "bench: {}: {}.{} instructions x {} Hz / {} MHz = {}.{:02} % of the CPU (budget {}.{} %, {} instructions): {}",
            self.path,
            x10 / 10,
            x10 % 10,
            self.rate_hz,
            self.clock_hz / 1_000_000,
            share / 100,
            share % 100,
            self.share_permille / 10,
            self.share_permille % 10,
            self.instructions(),
            if ok { "ok" } else { "OVER BUDGET" }
        );
        ok
    }
}

/// The F405's ICM-42688-P path: 8 kHz ODR, 168 MHz, at most 2 % of the CPU.
const F405_IMU: Budget = Budget {
    path: "F405 IMU path (its costliest route)",
    rate_hz: 8000,
    clock_hz: 168_000_000,
    share_permille: 20,
};

/// The BMI270's path (the F405 V3), held to the ICM's budget: 8 kHz, 168 MHz, at most 2 %.
const F405_BMI270: Budget = Budget {
    path: "F405 BMI270 path (one frame per transfer)",
    rate_hz: 8000,
    clock_hz: 168_000_000,
    share_permille: 20,
};

/// The LSM6DSO's path, held to the same budget.
const F405_LSM6DSO: Budget = Budget {
    path: "F405 LSM6DSO path (tagged FIFO words)",
    rate_hz: 8000,
    clock_hz: 168_000_000,
    share_permille: 20,
};

/// The Nucleo's ADC path: 1 kHz, 180 MHz, at most 0.5 % of the CPU.
const NUCLEO_ADC: Budget = Budget {
    path: "Nucleo ADC path",
    rate_hz: 1000,
    clock_hz: 180_000_000,
    share_permille: 5,
};

/// 100 `nop`s (out of line, so that no literal pool lands beyond their reach).
#[inline(never)]
fn hundred_nops() {
    // SAFETY: nops only.
    unsafe {
        core::arch::asm!(
            ".rept 100",
            "nop",
            ".endr",
            options(nomem, nostack, preserves_flags)
        )
    };
}

fn ticks<F: FnMut(usize)>(n: u32, mut f: F) -> u32 {
    let start = SYST::get_current();
    for i in 0..n as usize {
        f(i);
    }
    let end = SYST::get_current();
    start.wrapping_sub(end) & 0x00FF_FFFF
}

/// Tenths of an instruction per iteration, with the empty loop removed.
fn per_iter_x10(t: u32, empty: u32, n: u32) -> u32 {
    (t.saturating_sub(empty) * INSTR_PER_TICK * 10 + n / 2) / n
}

fn line(name: &str, x10: u32, note: &str) {
    hprintln!(
        "bench: {:<46} {:>5}.{} instructions/sample  {}",
        name,
        x10 / 10,
        x10 % 10,
        note
    );
}

/// One benchmark line: `f` over `N` iterations, less the `baseline` loop's ticks.
fn measure<F: FnMut(usize)>(name: &str, note: &str, baseline: u32, f: F) {
    line(name, per_iter_x10(ticks(N, f), baseline, N), note);
}

/// The inputs every measurement cycles through: 16 varied samples.
struct Inputs {
    u: [SensorOutputs; 16],
    w: [BodyRate; 16],
    wd: [BodyAngularAccel; 16],
    adc: [[u32; 3]; 16],
    words: [[i32; 3]; 16],
    status: [u32; 16],
}

/// The board's conversion: a 12-bit ADC on 3.3 V, and a gyro of 1 mrad/s per LSB.
const SCALING: Scaling = Scaling {
    volts_per_code: 3.3 / 4095.0,
    rad_s_per_lsb: 0.001,
};

/// An ADC board's sample as the Nucleo reads it: the ADC's status (its watchdog flag; a volatile
/// load, as of the register), then the scan's codes and the gyro's words converted.
#[inline(always)]
fn read(adc: &[u32; 3], words: &[i32; 3], status: &u32) -> Sample {
    // SAFETY: a valid reference.
    let at_end = unsafe { core::ptr::read_volatile(status) } & ADC_SR_AWD != 0;
    SCALING.convert(adc, words, at_end)
}

impl Inputs {
    fn new(sensor: &mut VirtualSensor) -> Inputs {
        let mut x = Inputs {
            u: [SensorOutputs::default(); 16],
            w: [BodyRate::default(); 16],
            wd: [BodyAngularAccel::default(); 16],
            adc: [[0; 3]; 16],
            words: [[0; 3]; 16],
            status: [0; 16],
        };
        for k in 0..16 {
            let s = sensor.sample();
            x.u[k].raw = s.raw;
            x.w[k].rad_s = [0.5 + k as f32 * 0.01, -0.2, 3.0 - k as f32 * 0.1];
            x.wd[k].rad_s2 = [1.0, k as f32, -2.5];
            x.adc[k] = s.raw.map(|v| (v / SCALING.volts_per_code) as u32);
            x.words[k] = [100 + k as i16, -300, 2000 - 10 * k as i16].map(gyro_word);
            // End of conversion and start flags as a scan leaves them; the watchdog's now and then.
            x.status[k] = 0x12 | u32::from(k % 5 == 0);
        }
        x
    }
}

/// Shows the tick-to-instruction conversion on 10 × 100 `nop`s.
fn conversion_check() {
    let nop_empty = ticks(10, |i| {
        black_box(i);
    });
    let nops = ticks(10, |i| {
        black_box(i);
        hundred_nops();
    });
    hprintln!(
        "bench: 10 calls of 100 nops measured as {} instructions (+ 2 per call) (SysTick ticks x {}; QEMU -icount shift=0)",
        nops.saturating_sub(nop_empty) * INSTR_PER_TICK,
        INSTR_PER_TICK
    );
}

/// Each per-sample piece on its own. `empty`: the empty loop's ticks.
fn bench_parts(cal: &shared::Calibration, x: &Inputs, empty: u32) {
    let c_off = Compensator::new(cal, LeverMode::Off).unwrap();
    let c_full = Compensator::new(cal, LeverMode::RateAndAcceleration).unwrap();
    measure(
        "compensation, static only",
        "(floor: 12 multiply-adds)",
        empty,
        |i| {
            black_box(c_off.compensate_static(black_box(&x.u[i & 15])));
        },
    );
    measure(
        "compensation, static + lever arms + omega-dot",
        "(floor: 51 multiply-adds)",
        empty,
        |i| {
            black_box(c_full.compensate(
                black_box(&x.u[i & 15]),
                black_box(&x.w[i & 15]),
                black_box(&x.wd[i & 15]),
            ));
        },
    );
    // The same loop passing `w` through unchanged: what remains is what the correction adds.
    let pass = ticks(N, |i| {
        black_box(*black_box(&x.w[i & 15].rad_s));
    });
    measure(
        "gyro correction, c + G^-1 w",
        "(over passing w through; 9 multiply-adds)",
        pass,
        |i| {
            black_box(c_full.correct_rate(black_box(&x.w[i & 15].rad_s)));
        },
    );
    let mut est = OmegaDotEstimator::new(1000.0, 20.0).unwrap();
    measure("omega-dot estimator update", "", empty, |i| {
        black_box(est.update(black_box(&x.w[i & 15].rad_s)));
    });
    let mut acc = WindowAccumulator::<6>::new();
    let ac = ticks(N, |i| {
        let u = black_box(&x.u[i & 15].raw);
        let r = &x.w[i & 15].rad_s;
        acc.add(&[u[0], u[1], u[2], r[0], r[1], r[2]]);
    });
    black_box(acc.finish());
    line(
        "window accumulation (6 channels)",
        per_iter_x10(ac, empty, N),
        "",
    );
    bench_conversion(x, empty);
}

/// The ADC board's sample conversion, in a function of its own: in the large frame of the other
/// measurements the loop recomputes stack addresses beyond an instruction's offset range, which
/// would be counted as the conversion's.
#[inline(never)]
fn bench_conversion(x: &Inputs, empty: u32) {
    let inputs = |i: usize| black_box((&x.adc[i & 15], &x.words[i & 15], &x.status[i & 15]));
    measure(
        "sample conversion (ADC codes + gyro words -> f32, range ends)",
        "(with the loop's 16 inputs' addresses)",
        empty,
        |i| {
            let (adc, words, status) = inputs(i);
            black_box(read(adc, words, status));
        },
    );
    // The same loop passing its inputs through unchanged: what remains is the conversion's own.
    let pass = ticks(N, |i| {
        black_box(inputs(i));
    });
    measure(
        "sample conversion in place",
        "(over passing the inputs through)",
        pass,
        |i| {
            let (adc, words, status) = inputs(i);
            black_box(read(adc, words, status));
        },
    );
}

/// The whole path as the sampling interrupt runs it. The first two differ only in the gyro: the
/// difference is the correction's cost in place (with the addresses and loads it adds there).
/// Returns the first (the Nucleo's per-sample path), tenths of an instruction.
fn bench_whole_paths(cal: &shared::Calibration, x: &Inputs, empty: u32) -> u32 {
    let perfect_gyro = paper_unit::calibration();
    let mut first_two = [0u32; 2];
    for (k, (name, kind, mode, unit, goal)) in [
        (
            "whole path: read + gyro corr. + omega-dot + full comp. + window",
            StreamKind::CompensatedWindows,
            LeverMode::RateAndAcceleration,
            cal,
            "(Nucleo per-sample path; its CPU share below)",
        ),
        (
            "whole path as above, perfect gyro (correction skipped)",
            StreamKind::CompensatedWindows,
            LeverMode::RateAndAcceleration,
            &perfect_gyro,
            "",
        ),
        (
            "whole path: read + gyro corr. + omega-dot + static comp. + window",
            StreamKind::CompensatedWindows,
            LeverMode::Off,
            cal,
            "",
        ),
        (
            "whole path: read + gyro corr. + omega-dot + raw window",
            StreamKind::RawWindows,
            LeverMode::RateAndAcceleration,
            cal,
            "",
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let mut p = Pipeline::<8>::new(1000);
        p.apply(PipelineCommand::Compensator(
            Compensator::new(unit, mode).ok(),
        ));
        p.apply(PipelineCommand::Stream(StreamRequest {
            kind,
            window_samples: 1000,
        }));
        let t = ticks(N, |i| {
            let (adc, words, status) =
                black_box((&x.adc[i & 15], &x.words[i & 15], &x.status[i & 15]));
            let s = read(adc, words, status);
            p.on_sample(&s);
        });
        black_box(p.pop_output());
        line(name, per_iter_x10(t, empty, N), goal);
        if let Some(slot) = first_two.get_mut(k) {
            *slot = t;
        }
    }
    line(
        "gyro correction in place (first minus second)",
        per_iter_x10(first_two[0], first_two[1], N),
        "",
    );
    per_iter_x10(first_two[0], empty, N)
}

/// Packets of the IMU benchmark (64 FIFO transfers of 16).
const IMU_SAMPLES: usize = 1024;
const PACKET: usize = 20;

/// `IMU_SAMPLES` consecutive FIFO packets (20-bit packet 4) of the QEMU board's virtual IMU, the
/// unit spinning at 200 °/s about a tilted axis, read raw from the model's FIFO over SPI.
fn imu_stream(cal: &shared::Calibration) -> Option<&'static mut [u8; IMU_SAMPLES * PACKET]> {
    let stream = cortex_m::singleton!(: [u8; IMU_SAMPLES * PACKET] = [0; IMU_SAMPLES * PACKET])?;
    let mut sensor = VirtualSensor::new(cal, 1000, true)?;
    sensor
        .set_table(&shared::wire::VirtualTable {
            up_b: [0.6, -0.48, 0.64],
            rate_rad_s: 200f32.to_radians(),
            accel_rad_s2: 0.0,
        })
        .ok()?;
    let mut imu = qemu::imu(sensor)?;
    let m = imu.device_mut();
    let mut filled = 0;
    let mut skip = PACKET; // the part marks its first packet invalid
    while filled < stream.len() {
        m.advance_ns(50_000_000);
        let mut status = [0u8; 3];
        m.transaction(&mut [
            Operation::Write(&[regs::INT_STATUS as u8 | regs::READ]),
            Operation::Read(&mut status),
        ])
        .ok()?;
        let mut bytes = usize::from(u16::from_be_bytes([status[1], status[2]])) * PACKET;
        while bytes > 0 {
            let mut chunk = [0u8; PACKET];
            m.transaction(&mut [
                Operation::Write(&[regs::FIFO_DATA as u8 | regs::READ]),
                Operation::Read(&mut chunk),
            ])
            .ok()?;
            bytes -= PACKET;
            if skip > 0 {
                skip -= PACKET;
            } else if filled < stream.len() {
                stream[filled..filled + PACKET].copy_from_slice(&chunk);
                filled += PACKET;
            }
        }
    }
    Some(stream)
}

/// The digital IMU's path: the FIFO packet decode alone, and the whole per-sample path from FIFO
/// bytes (decode, gap and saturation checks, the temperature mean of `PipelineFeed`, gyro
/// correction, ω̇, full compensation with the temperature model, window) as the QEMU board runs it,
/// in transfers of 16 packets (what one DMA read brings). Returns the costliest of its routes (the
/// F405's per-sample path: the whole path with full compensation, unless another is dearer),
/// tenths of an instruction.
fn bench_imu_path(cal: &shared::Calibration, stream: &[u8; IMU_SAMPLES * PACKET]) -> Option<u32> {
    let batches = (IMU_SAMPLES / 16) as u32;
    let b_empty = ticks(batches, |b| {
        black_box(&stream[b * 320..(b + 1) * 320]);
    });
    let mut core = Core::new(IMU_CONFIG).ok()?;
    let mut out = [ImuSample::default(); 16];
    let dec = ticks(batches, |b| {
        black_box(core.decode(black_box(&stream[b * 320..(b + 1) * 320]), &mut out)).ok();
        black_box(&out);
    });
    line(
        "FIFO packet decode (packet 4: 20-bit, checks)",
        per_iter_x10(dec, b_empty, IMU_SAMPLES as u32),
        "(20 bytes to a sample, checks included)",
    );
    let thermal = shared::Calibration {
        temperature: Some(paper_unit::typical_thermal_model()),
        ..*cal
    };
    // The same loop with less of the pipeline on, for the per-stage table (README "Per-sample
    // budgets"): the differences are each stage's cost in place.
    let mut costliest = 0;
    for (name, kind, mode, goal) in [
        (
            "whole IMU path: decode + gyro corr. + omega-dot + full comp. (thermal) + window",
            Some(StreamKind::CompensatedWindows),
            LeverMode::RateAndAcceleration,
            "(F405 per-sample path; its CPU share below)",
        ),
        (
            "IMU path as above, static comp. (thermal) + window",
            Some(StreamKind::CompensatedWindows),
            LeverMode::Off,
            "",
        ),
        (
            "IMU path as above, raw window",
            Some(StreamKind::RawWindows),
            LeverMode::RateAndAcceleration,
            "",
        ),
        (
            "IMU path as above, not streaming (decode + feed + gyro corr. + omega-dot)",
            None,
            LeverMode::RateAndAcceleration,
            "",
        ),
    ] {
        let mut core = Core::new(IMU_CONFIG).ok()?;
        let mut p = Pipeline::<8>::new(1000);
        p.apply(PipelineCommand::Compensator(
            Compensator::new(&thermal, mode).ok(),
        ));
        if let Some(kind) = kind {
            p.apply(PipelineCommand::Stream(StreamRequest {
                kind,
                window_samples: 1000,
            }));
        }
        let mut feed = PipelineFeed::new(1000);
        let t = ticks(batches, |b| {
            if let Ok(n) = core.decode(black_box(&stream[b * 320..(b + 1) * 320]), &mut out) {
                feed.push_all(&out[..n], &mut p);
            }
        });
        black_box(p.pop_output());
        let x10 = per_iter_x10(t, b_empty, IMU_SAMPLES as u32);
        line(name, x10, goal);
        costliest = costliest.max(x10);
    }
    Some(costliest)
}

/// What does not run per sample: a temperature refresh (4 per second) and the QEMU board's virtual
/// sensor (which replaces the read there).
fn bench_occasional(cal: &shared::Calibration, sensor: &mut VirtualSensor) {
    let thermal = shared::Calibration {
        temperature: Some(paper_unit::typical_thermal_model()),
        ..*cal
    };
    let r_empty = ticks(256, |i| {
        black_box(i);
    });
    if let Ok(mut c) = Compensator::new(&thermal, LeverMode::RateAndAcceleration) {
        let r = ticks(256, |i| {
            black_box(c.refresh(black_box(20.0 + (i & 15) as f32)));
        });
        line(
            "temperature refresh (u0, K_A columns, lever terms, gyro bias)",
            per_iter_x10(r, r_empty, 256),
            "(per refresh, 4 per second: not per sample)",
        );
    }
    let vs = ticks(256, |_| {
        black_box(sensor.sample());
    });
    line(
        "QEMU virtual sensor sample (f64 soft-float model)",
        per_iter_x10(vs, r_empty, 256),
        "(QEMU board only; replaces the read)",
    );
}

#[entry]
fn main() -> ! {
    let mut cp = cortex_m::Peripherals::take().unwrap();
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(0x00FF_FFFF);
    cp.SYST.clear_current();
    cp.SYST.enable_counter();

    // The paper's unit with a typical MEMS gyro's errors (0.5 % scale, 0.5° misalignment, 0.5 °/s
    // bias): the correction runs on every sample either way; this makes its constants non-trivial.
    let cal = shared::Calibration {
        gyro: Some(paper_unit::typical_gyro()),
        ..paper_unit::calibration()
    };
    let mut sensor = VirtualSensor::new(&cal, 1000, true).unwrap();
    let inputs = Inputs::new(&mut sensor);
    conversion_check();
    let empty = ticks(N, |i| {
        black_box(i);
    });
    bench_parts(&cal, &inputs, empty);
    let adc = bench_whole_paths(&cal, &inputs, empty);
    let imu = imu_stream(&cal).and_then(|stream| bench_imu_path(&cal, stream));
    if imu.is_none() {
        hprintln!("bench: FAILED to read the virtual IMU's FIFO or build its driver");
    }
    let (bmi, lsm) = bench_other_imus(&cal);
    bench_occasional(&cal, &mut sensor);
    let imu_ok = imu.is_some_and(|x10| F405_IMU.check(x10));
    let bmi_ok = bmi.is_some_and(|x10| F405_BMI270.check(x10));
    let lsm_ok = lsm.is_some_and(|x10| F405_LSM6DSO.check(x10));
    let adc_ok = NUCLEO_ADC.check(adc);
    debug::exit(if imu_ok && bmi_ok && lsm_ok && adc_ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("bench: PANIC {}", info);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}
