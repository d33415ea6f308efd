//! `host bringup`'s checks of the device's health report (protocol version 4): the part and its
//! WHO_AM_I with the start's result, and the error counters over the measurement.

use crate::bringup::{names, Check};
use shared::wire::{ErrorCounters, Health, ImuInit};

/// The part the firmware drives, the identity register's value against the part's, the start's
/// result. A version 3 device has no report: skipped.
pub(crate) fn part_check(health: Option<&Health>) -> Check {
    let Some(h) = health else {
        return Check::skipped(
            names::PART,
            "the device speaks protocol version 3: no health report (flash a current build)",
        );
    };
    let s = h.imu;
    let expected = s.part.expected_id();
    let id = match expected {
        Some(e) => format!("WHO_AM_I 0x{:02X} (expected 0x{e:02X})", s.who_am_i),
        None => "no identity register".to_string(),
    };
    let detail = format!("{:?}, {id}, start {:?}", s.part, s.init);
    let ok = matches!(s.init, ImuInit::Ok | ImuInit::NotApplicable)
        && expected.is_none_or(|e| e == s.who_am_i);
    let cause = match s.init {
        ImuInit::WrongDevice => format!(
            "the part answered 0x{:02X}: another part than the board's description says (a board \
             variant: build for the board you have), or a bus fault (0x00/0xFF: no answer; one bit \
             off: SPI pins too slow)",
            s.who_am_i
        ),
        ImuInit::BusError => "the SPI bus failed at start: check the board's IMU wiring".into(),
        ImuInit::ConfigRejected => "the part refused its configuration upload (BMI270: \
             INTERNAL_STATUS not 'init OK'): power-cycle the board; if it persists the part is damaged"
            .into(),
        ImuInit::RegisterMismatch => "a configured register did not read back: a bus fault or a \
             part that reset itself (brown-out)"
            .into(),
        ImuInit::Ok | ImuInit::NotApplicable => "the identity register does not match".into(),
    };
    Check::new(names::PART, ok, detail, cause)
}

/// The counters' growth over the measurement (a board at rest should add nothing), with the
/// totals since boot.
pub(crate) fn counters_check(before: Option<&Health>, after: &Health) -> Check {
    let b = before.map(|h| h.counters).unwrap_or_default();
    let a = after.counters;
    let grew = |f: fn(&ErrorCounters) -> u32| f(&a).saturating_sub(f(&b));
    let rows: [(&str, u32, u32, &str); 6] = [
        (
            "FIFO resyncs",
            grew(|c| c.fifo_resyncs),
            a.fifo_resyncs,
            "the FIFO read went out of step: SPI errors (a loose connector, interference)",
        ),
        (
            "stall restarts",
            grew(|c| c.stalls),
            a.stalls,
            "the interrupt or DMA completion was lost: check the INT pin",
        ),
        (
            "re-inits",
            grew(|c| c.reinits),
            a.reinits,
            "the part lost its configuration (brown-out): check the board's 3.3 V supply",
        ),
        (
            "frame errors",
            grew(|c| c.crc_errors),
            a.crc_errors,
            "frames from this computer arrived damaged: the USB cable or hub",
        ),
        (
            "lost samples",
            grew(|c| c.lost_samples),
            a.lost_samples,
            "the FIFO overflowed: sampling was held up (a flash write, a stalled chain)",
        ),
        (
            "watchdog resets",
            0,
            a.watchdog_resets,
            "the firmware hung and the watchdog restarted it: report it with the board's log",
        ),
    ];
    let detail = rows
        .iter()
        .map(|(n, d, t, _)| format!("{n} +{d} ({t} since boot)"))
        .collect::<Vec<_>>()
        .join(", ");
    let bad: Vec<&str> = rows
        .iter()
        .filter(|(n, d, t, _)| *d > 0 || (*n == "watchdog resets" && *t > 0))
        .map(|r| r.3)
        .collect();
    Check::new(names::COUNTERS, bad.is_empty(), detail, bad.join("; "))
}
