//! The BMI270's and the LSM6DSO's whole paths (`qemu_bench`'s budget rows for them): raw bytes
//! read from their register models on the QEMU board as their drivers read them, then decoded
//! and run through the pipeline as a board would.

use core::hint::black_box;

use cortex_m_semihosting::hprintln;
use embedded_hal::spi::{Operation, SpiDevice};
use firmware::imu::bmi270::dma::{Decoder, BATCH, FRAME_LEN};
use firmware::imu::bmi270::{self, Bmi270};
use firmware::imu::lsm6dso::{self, regs::WORD_LEN, Lsm6dso, Pairing};
use firmware::imu::sim::{Bmi270Model, Generator, Lsm6dsoModel, Truth};
use firmware::imu::ImuSample;
use firmware::paper_unit;
use firmware::pipeline::PipelineCommand;
use firmware::pipeline::PipelineFeed;
use firmware::virtual_sensor::VirtualSensor;
use firmware::Pipeline;
use shared::wire::{StreamKind, StreamRequest};
use shared::{Compensator, LeverMode};

use super::{line, per_iter_x10, ticks};

/// The virtual unit spinning at 200 °/s about a tilted axis, sampled at `rate_hz`.
fn spinning_unit(cal: &shared::Calibration, rate_hz: u32) -> Option<VirtualSensor> {
    let mut sensor = VirtualSensor::new(cal, rate_hz, true)?;
    sensor
        .set_table(&shared::wire::VirtualTable {
            up_b: [0.6, -0.48, 0.64],
            rate_rad_s: 200f32.to_radians(),
            accel_rad_s2: 0.0,
        })
        .ok()?;
    Some(sensor)
}

/// The virtual unit for the ±4 g parts: its specific force (which spans the ICM's 18-bit codes,
/// ±16 g) a quarter, so that no sample saturates and every one takes the clean-run path.
struct Quarter(VirtualSensor);

impl Generator for Quarter {
    fn next(&mut self) -> Truth {
        let mut t = self.0.next();
        t.accel_g = t.accel_g.map(|g| g * 0.25);
        t
    }
}

/// A pipeline as the F405 runs it on its costliest route: full compensation with the temperature
/// model, compensated windows.
fn full_pipeline(cal: &shared::Calibration) -> Pipeline<8> {
    let thermal = shared::Calibration {
        temperature: Some(paper_unit::typical_thermal_model()),
        ..*cal
    };
    let mut p = Pipeline::<8>::new(1000);
    p.apply(PipelineCommand::Compensator(
        Compensator::new(&thermal, LeverMode::RateAndAcceleration).ok(),
    ));
    p.apply(PipelineCommand::Stream(StreamRequest {
        kind: StreamKind::CompensatedWindows,
        window_samples: 1000,
    }));
    p
}

/// Frames the BMI270 model gives at 1.6 kHz (STATUS … TEMPERATURE_1, read as the driver and the
/// V3's DMA burst read them: the address, the dummy byte, 33 registers), into `buf`; how many.
#[inline(never)]
fn bmi270_frames(cal: &shared::Calibration, buf: &mut [u8]) -> Option<usize> {
    let gen = Quarter(spinning_unit(cal, 1600)?);
    let mut imu = Bmi270::new(Bmi270Model::new(gen), bmi270::Config::DEFAULT).ok()?;
    let m = imu.device_mut();
    let n = buf.len() / FRAME_LEN;
    for frame in buf.chunks_exact_mut(FRAME_LEN) {
        m.advance_ns(m.until_next_sample_ns().max(1));
        let mut dummy = [0u8; 1];
        m.transaction(&mut [
            Operation::Write(&[bmi270::regs::STATUS as u8 | bmi270::regs::READ]),
            Operation::Read(&mut dummy),
            Operation::Read(frame),
        ])
        .ok()?;
    }
    Some(n)
}

/// The BMI270's path as the F405 V3 runs it: each transfer one frame, decoded in place
/// (`bmi270::dma::Decoder`: data-ready bits, six values, time stamp and gap, temperature,
/// saturation), the pipeline on every `BATCH` samples (`PipelineFeed::push_all`). Tenths of an
/// instruction per sample for the whole path.
#[inline(never)]
fn bench_bmi270_path(cal: &shared::Calibration, frames: &[u8], n: usize) -> Option<u32> {
    let frame = |k: usize| <&[u8; FRAME_LEN]>::try_from(&frames[k * FRAME_LEN..][..FRAME_LEN]);
    let empty = ticks(n as u32, |k| {
        black_box(frame(k)).ok();
    });
    let mut dec = Decoder::new(&bmi270::Config::DEFAULT);
    let mut flagged = 0u32;
    let mut s = ImuSample::default();
    let d = ticks(n as u32, |k| {
        if let Ok(f) = frame(k) {
            let got = dec.decode_into(black_box(f), &mut s);
            flagged += u32::from(!got || black_box(&s).flags.0 != 0);
        }
    });
    line(
        "BMI270 frame decode (33 registers: DRDY, 6 values, time, temp)",
        per_iter_x10(d, empty, n as u32),
        "(one data-ready frame to a sample)",
    );
    if flagged > 1 {
        hprintln!(
            "bench: BMI270: {} of {} frames flagged or empty",
            flagged,
            n
        );
        return None;
    }
    let mut dec = Decoder::new(&bmi270::Config::DEFAULT);
    let mut p = full_pipeline(cal);
    let mut feed = PipelineFeed::new(1000);
    let mut batch = [ImuSample::default(); BATCH];
    let mut held = 0;
    let t = ticks(n as u32, |k| {
        if let (Ok(f), Some(slot)) = (frame(k), batch.get_mut(held)) {
            held += usize::from(dec.decode_into(black_box(f), slot));
        }
        if held == BATCH {
            feed.push_all(&batch, &mut p);
            held = 0;
        }
    });
    black_box(p.pop_output());
    let x10 = per_iter_x10(t, empty, n as u32);
    line(
        "whole BMI270 path: frame decode + feed (runs of 8) + full comp. (thermal) + window",
        x10,
        "(F405 V3 per-sample path; its CPU share below)",
    );
    Some(x10)
}

/// Tagged words the LSM6DSO model gives at 1.666 kHz (both sensors, a time stamp every slot, the
/// temperature at 52 Hz), read as the driver reads them (FIFO_STATUS1/2, then the counted words
/// from FIFO_DATA_OUT_TAG), into `buf`; how many words.
#[inline(never)]
fn lsm6dso_words(cal: &shared::Calibration, buf: &mut [u8]) -> Option<usize> {
    let cfg = lsm6dso::Config {
        odr: lsm6dso::Odr::Hz1666,
        accel_range: lsm6dso::AccelRange::G4,
        ..lsm6dso::Config::DEFAULT
    };
    let gen = Quarter(spinning_unit(cal, 1666)?);
    let mut imu = Lsm6dso::new(Lsm6dsoModel::new(gen), cfg).ok()?;
    let m = imu.device_mut();
    let mut filled = 0;
    while filled + WORD_LEN <= buf.len() {
        m.advance_ns(5_000_000);
        let mut status = [0u8; 2];
        m.transaction(&mut [
            Operation::Write(&[lsm6dso::regs::FIFO_STATUS1 as u8 | lsm6dso::regs::READ]),
            Operation::Read(&mut status),
        ])
        .ok()?;
        let count = usize::from(u16::from_le_bytes([status[0], status[1] & 0x03]));
        let words = count.min((buf.len() - filled) / WORD_LEN);
        m.transaction(&mut [
            Operation::Write(&[lsm6dso::regs::FIFO_DATA_OUT_TAG as u8 | lsm6dso::regs::READ]),
            Operation::Read(&mut buf[filled..filled + words * WORD_LEN]),
        ])
        .ok()?;
        filled += words * WORD_LEN;
        if words < count {
            break;
        }
    }
    Some(filled / WORD_LEN)
}

/// The LSM6DSO's path as its driver's drain runs it: transfers of 48 tagged words
/// (`lsm6dso::BATCH_WORDS`), each word through `Pairing::word` (tag, slot counter, the pair, time
/// stamp and temperature words, gaps), the transfer's samples through the pipeline. Tenths of an
/// instruction per sample for the whole path.
#[inline(never)]
fn bench_lsm6dso_path(cal: &shared::Calibration, words: &[u8], n_words: usize) -> Option<u32> {
    let cfg = lsm6dso::Config {
        odr: lsm6dso::Odr::Hz1666,
        accel_range: lsm6dso::AccelRange::G4,
        ..lsm6dso::Config::DEFAULT
    };
    let batch = lsm6dso::BATCH_WORDS * WORD_LEN;
    let transfers = (n_words / lsm6dso::BATCH_WORDS) as u32;
    let chunk = |b: usize| &words[b * batch..(b + 1) * batch];
    let empty = ticks(transfers, |b| {
        black_box(chunk(b));
    });
    // The samples the words hold (each transfer's pairs).
    let mut pairing = Pairing::new(&cfg);
    let mut samples = 0u32;
    let mut flagged = 0u32;
    for b in 0..transfers as usize {
        for w in chunk(b).chunks_exact(WORD_LEN) {
            if let Some(s) = <&[u8; WORD_LEN]>::try_from(w)
                .ok()
                .and_then(|w| pairing.word(w))
            {
                samples += 1;
                flagged += u32::from(s.flags.0 != 0);
            }
        }
    }
    if flagged > 1 || samples == 0 {
        hprintln!("bench: LSM6DSO: {} of {} samples flagged", flagged, samples);
        return None;
    }
    let mut pairing = Pairing::new(&cfg);
    let mut out = [ImuSample::default(); lsm6dso::BATCH_WORDS / 2];
    let d = ticks(transfers, |b| {
        let mut n = 0;
        for w in black_box(chunk(b)).chunks_exact(WORD_LEN) {
            if let (Ok(w), Some(slot)) = (<&[u8; WORD_LEN]>::try_from(w), out.get_mut(n)) {
                n += usize::from(pairing.word_into(w, slot));
            }
        }
        black_box(&out[..n]);
    });
    line(
        "LSM6DSO word pairing (tagged words: gyro, accel, time stamp)",
        per_iter_x10(d, empty, samples),
        "(per sample: about 3 words)",
    );
    let mut pairing = Pairing::new(&cfg);
    let mut p = full_pipeline(cal);
    let mut feed = PipelineFeed::new(1000);
    let t = ticks(transfers, |b| {
        let mut n = 0;
        for w in black_box(chunk(b)).chunks_exact(WORD_LEN) {
            if let (Ok(w), Some(slot)) = (<&[u8; WORD_LEN]>::try_from(w), out.get_mut(n)) {
                n += usize::from(pairing.word_into(w, slot));
            }
        }
        feed.push_all(&out[..n], &mut p);
    });
    black_box(p.pop_output());
    let x10 = per_iter_x10(t, empty, samples);
    line(
        "whole LSM6DSO path: word pairing + feed + full comp. (thermal) + window",
        x10,
        "(per sample: about 3 words; its CPU share below)",
    );
    Some(x10)
}

/// The BMI270's and the LSM6DSO's whole paths, over one scratch buffer in turn. Each step is a
/// function of its own (`inline(never)`): the models' 8 KiB stay out of the measuring loops'
/// frames, whose state would otherwise sit beyond an instruction's stack offset (as for the
/// conversion, `bench_conversion`).
pub(super) fn bench_other_imus(cal: &shared::Calibration) -> (Option<u32>, Option<u32>) {
    let Some(buf) = cortex_m::singleton!(: [u8; 1024 * FRAME_LEN] = [0; 1024 * FRAME_LEN]) else {
        return (None, None);
    };
    let bmi = bmi270_frames(cal, buf).and_then(|n| bench_bmi270_path(cal, buf, n));
    let lsm = lsm6dso_words(cal, buf).and_then(|n| bench_lsm6dso_path(cal, buf, n));
    if bmi.is_none() || lsm.is_none() {
        hprintln!("bench: FAILED to read the BMI270's or the LSM6DSO's model");
    }
    (bmi, lsm)
}
