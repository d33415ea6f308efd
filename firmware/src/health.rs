//! A device that tells: the error counters the sampling tasks keep ([`HealthCounters`], atomics
//! a board shares between its interrupts and the link) and the request handler's view of them
//! ([`HealthState`]: the part's identity and start, its nominal sensitivity, the link's own frame
//! errors), answered to `Health` (`shared::wire::Health`, protocol version 4).

use core::sync::atomic::{AtomicU32, Ordering};
use shared::wire::{ErrorCounters, Health, ImuInit, ImuPart, ImuStatus};

/// Which counter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Counter {
    /// A FIFO read out of step, flushed.
    FifoResync,
    /// A stalled burst chain restarted.
    Stall,
    /// The part re-initialised after a register check found a register changed.
    Reinit,
    /// Samples lost.
    LostSamples,
    /// This boot followed an independent-watchdog reset.
    WatchdogReset,
}

/// Counters a board's tasks bump (any priority: each is one atomic read-modify-write).
pub struct HealthCounters {
    fifo_resyncs: AtomicU32,
    stalls: AtomicU32,
    reinits: AtomicU32,
    lost_samples: AtomicU32,
    watchdog_resets: AtomicU32,
}

impl Default for HealthCounters {
    fn default() -> Self {
        Self::new()
    }
}

impl HealthCounters {
    /// All zero.
    pub const fn new() -> Self {
        HealthCounters {
            fifo_resyncs: AtomicU32::new(0),
            stalls: AtomicU32::new(0),
            reinits: AtomicU32::new(0),
            lost_samples: AtomicU32::new(0),
            watchdog_resets: AtomicU32::new(0),
        }
    }

    fn cell(&self, c: Counter) -> &AtomicU32 {
        match c {
            Counter::FifoResync => &self.fifo_resyncs,
            Counter::Stall => &self.stalls,
            Counter::Reinit => &self.reinits,
            Counter::LostSamples => &self.lost_samples,
            Counter::WatchdogReset => &self.watchdog_resets,
        }
    }

    /// Adds `n`, saturating at `u32::MAX`.
    pub fn add(&self, c: Counter, n: u32) {
        let _ = self
            .cell(c)
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |v| {
                Some(v.saturating_add(n))
            });
    }

    /// The current values (the link's frame errors are the request handler's: 0 here).
    pub fn snapshot(&self) -> ErrorCounters {
        let get = |c: Counter| self.cell(c).load(Ordering::Relaxed);
        ErrorCounters {
            fifo_resyncs: get(Counter::FifoResync),
            stalls: get(Counter::Stall),
            reinits: get(Counter::Reinit),
            crc_errors: 0,
            lost_samples: get(Counter::LostSamples),
            watchdog_resets: get(Counter::WatchdogReset),
        }
    }
}

/// `bytes` as lower-case hex digits in `out` (two per byte; the rest of `out` untouched), as a
/// `str` (a USB serial number from the chip's unique ID).
pub fn hex_into<'a>(bytes: &[u8], out: &'a mut [u8]) -> &'a str {
    const DIGITS: &[u8; 16] = b"0123456789abcdef";
    let n = bytes.len().min(out.len() / 2);
    for (i, b) in bytes[..n].iter().enumerate() {
        out[2 * i] = DIGITS[usize::from(b >> 4)];
        out[2 * i + 1] = DIGITS[usize::from(b & 0xF)];
    }
    // Only ASCII digits were written.
    core::str::from_utf8(&out[..2 * n]).unwrap_or("")
}

/// What the request handler reports to `Health`.
#[derive(Clone, Copy)]
pub struct HealthState {
    /// The part and its start.
    pub imu: ImuStatus,
    /// Counts per g at the configured range (0 when the outputs are not counts).
    pub accel_lsb_per_g: u32,
    /// The board's counters (`None`: a board that keeps none reports zeros).
    pub counters: Option<&'static HealthCounters>,
    /// Frames from the host that did not decode.
    pub frame_errors: u32,
}

impl HealthState {
    /// Before the board says anything: a virtual unit, nothing counted.
    pub const fn new() -> Self {
        HealthState {
            imu: ImuStatus {
                part: ImuPart::Virtual,
                who_am_i: 0,
                init: ImuInit::NotApplicable,
            },
            accel_lsb_per_g: 0,
            counters: None,
            frame_errors: 0,
        }
    }

    /// The answer to `Health`.
    pub fn report(&self) -> Health {
        let mut counters = self.counters.map(|c| c.snapshot()).unwrap_or_default();
        counters.crc_errors = self.frame_errors;
        Health {
            imu: self.imu,
            accel_lsb_per_g: self.accel_lsb_per_g,
            counters,
        }
    }
}

impl Default for HealthState {
    fn default() -> Self {
        Self::new()
    }
}

impl<S: crate::storage::CalStore> crate::protocol::Controller<S> {
    /// The board's part, its start and its sensitivity, for `Health`.
    pub fn set_imu(&mut self, imu: ImuStatus, accel_lsb_per_g: u32) {
        let h = self.health_mut();
        h.imu = imu;
        h.accel_lsb_per_g = accel_lsb_per_g;
    }

    /// The board's counters, for `Health`.
    pub fn set_counters(&mut self, counters: &'static HealthCounters) {
        self.health_mut().counters = Some(counters);
    }

    /// A frame from the host did not decode (or was too long).
    pub(crate) fn count_frame_error(&mut self) {
        let h = self.health_mut();
        h.frame_errors = h.frame_errors.saturating_add(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper_unit::QEMU_UNIT_ID;
    use crate::pipeline::Pipeline;
    use crate::protocol::{Controller, DeviceInfo, LinkService};
    use crate::storage::{AbStore, RamNorFlash};
    use crate::ByteLink;
    use shared::wire::{
        decode_frame, encode_frame, Board, DeviceToHost, HostToDevice, HOST_FRAME_MAX,
    };
    use shared::{LeverMode, OutputUnit};
    use std::collections::VecDeque;
    use std::vec::Vec;

    struct Link {
        rx: VecDeque<u8>,
        tx: Vec<u8>,
    }

    impl ByteLink for Link {
        fn try_read(&mut self) -> Option<u8> {
            self.rx.pop_front()
        }
        fn try_write(&mut self, b: u8) -> bool {
            self.tx.push(b);
            true
        }
    }

    const INFO: DeviceInfo = DeviceInfo {
        unit_id: QEMU_UNIT_ID,
        board: Board::Stm32f4,
        sample_rate_hz: 1600,
        virtual_table: false,
        output_unit: OutputUnit::Lsb,
    };

    /// Sends `bytes` and returns the answers.
    fn exchange(
        service: &mut LinkService<AbStore<RamNorFlash<'static, 1024>>>,
        bytes: &[u8],
    ) -> Vec<DeviceToHost> {
        let mut link = Link {
            rx: bytes.iter().copied().collect(),
            tx: Vec::new(),
        };
        let mut pipeline = Pipeline::<16>::new(INFO.sample_rate_hz);
        for _ in 0..8 {
            service.poll(&mut link, &mut pipeline);
        }
        link.tx
            .split(|b| *b == 0)
            .filter(|f| !f.is_empty())
            .map(|f| decode_frame::<DeviceToHost>(&mut f.to_vec()).unwrap())
            .collect()
    }

    fn health(service: &mut LinkService<AbStore<RamNorFlash<'static, 1024>>>) -> Health {
        let mut buf = [0u8; HOST_FRAME_MAX];
        let frame = encode_frame(&HostToDevice::Health, &mut buf)
            .unwrap()
            .to_vec();
        match exchange(service, &frame).as_slice() {
            [DeviceToHost::Health(h)] => *h,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_unique_id_in_hex() {
        let mut out = [0u8; 24];
        let id = [0x00, 0x1f, 0xa0, 0xff, 1, 2, 3, 4, 5, 6, 7, 0x8e];
        assert_eq!(hex_into(&id, &mut out), "001fa0ff010203040506078e");
        let mut short = [0u8; 5];
        assert_eq!(hex_into(&id, &mut short), "001f");
    }

    /// The board's part and start, its counts per g, its counters and the link's own frame
    /// errors, as `Health` answers them.
    #[test]
    fn health_reports_the_part_the_counters_and_the_frame_errors() {
        static COUNTERS: HealthCounters = HealthCounters::new();
        let mem: &'static mut [u8] = Vec::leak(std::vec![0u8; 2048]);
        let store = AbStore::new(RamNorFlash::<1024>::new(mem), 0, 1024).unwrap();
        let mut controller = Controller::boot(INFO, store, LeverMode::Off);
        controller.set_imu(
            ImuStatus {
                part: ImuPart::Bmi270,
                who_am_i: 0x24,
                init: ImuInit::Ok,
            },
            8192,
        );
        controller.set_counters(&COUNTERS);
        let mut service = LinkService::new(controller);
        let h = health(&mut service);
        assert_eq!(h.imu.part, ImuPart::Bmi270);
        assert_eq!((h.imu.who_am_i, h.imu.init), (0x24, ImuInit::Ok));
        assert_eq!(h.accel_lsb_per_g, 8192);
        assert_eq!(h.counters, ErrorCounters::default());
        COUNTERS.add(Counter::FifoResync, 2);
        COUNTERS.add(Counter::Stall, 1);
        COUNTERS.add(Counter::Reinit, 1);
        COUNTERS.add(Counter::LostSamples, 5);
        COUNTERS.add(Counter::LostSamples, u32::MAX);
        COUNTERS.add(Counter::WatchdogReset, 1);
        // Two damaged frames from the host: each answered MalformedFrame and counted.
        let answers = exchange(&mut service, &[0x05, 0xFF, 0x13, 0x00, 0x02, 0x77, 0x00]);
        assert_eq!(answers.len(), 2, "{answers:?}");
        let h = health(&mut service);
        assert_eq!(
            h.counters,
            ErrorCounters {
                fifo_resyncs: 2,
                stalls: 1,
                reinits: 1,
                crc_errors: 2,
                lost_samples: u32::MAX,
                watchdog_resets: 1,
            }
        );
    }
}
