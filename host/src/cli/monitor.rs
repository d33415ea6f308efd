//! `host monitor`: a device's live compensated output, one line per window, with its flags.

use super::port::{connect, PortArgs};
use super::CliError;
use clap::Args;
use shared::wire::{SampleFlags, StreamKind};

/// `host monitor`.
#[derive(Debug, Args)]
pub struct MonitorArgs {
    /// How to reach the device.
    #[command(flatten)]
    pub port: PortArgs,
    /// Samples averaged per line.
    #[arg(long, default_value_t = 100, value_parser = crate::limits::whole_u32(1, crate::limits::MAX_WINDOW))]
    pub window: u32,
    /// Stop after this many lines (default: run until interrupted).
    #[arg(long, value_parser = crate::limits::whole_u64(1, u64::MAX))]
    pub count: Option<u64>,
}

/// `host monitor --port P [--window N] [--count N]`: live compensated output with its flags.
pub fn run(port: &PortArgs, window: u32, count: Option<u64>) -> Result<(), CliError> {
    crate::limits::count_in("--window", window, crate::limits::MAX_WINDOW)?;
    let mut client = connect(port)?;
    let identity = client.identify()?;
    let g = shared::STANDARD_GRAVITY_M_S2;
    crate::outln!(
        "unit {} ({:?}), calibration {:?}; compensated specific force in g, {} samples per line",
        identity.unit_id,
        identity.board,
        identity.calibration,
        window
    )?;
    client.start_stream(StreamKind::CompensatedWindows, window.max(1))?;
    let mut n = 0u64;
    while count.is_none_or(|c| n < c) {
        let w = client.next_compensated_window()?;
        let flags = [
            (SampleFlags::UNCALIBRATED, "UNCALIBRATED"),
            (SampleFlags::SATURATED, "SATURATED"),
            (SampleFlags::NON_FINITE, "NON-FINITE"),
            (SampleFlags::FRAMES_DROPPED, "DROPPED"),
        ]
        .iter()
        .filter(|(bit, _)| w.flags.has(*bit))
        .map(|(_, name)| *name)
        .collect::<Vec<_>>()
        .join(",");
        crate::outln!(
            "{:10.3} s  f = ({:+.6}, {:+.6}, {:+.6}) g  ω = ({:+8.2}, {:+8.2}, {:+8.2}) °/s  {}",
            w.first_sample as f64 / f64::from(identity.sample_rate_hz.max(1)),
            f64::from(w.mean_m_s2[0]) / g,
            f64::from(w.mean_m_s2[1]) / g,
            f64::from(w.mean_m_s2[2]) / g,
            f64::from(w.mean_rate_rad_s[0]).to_degrees(),
            f64::from(w.mean_rate_rad_s[1]).to_degrees(),
            f64::from(w.mean_rate_rad_s[2]).to_degrees(),
            if flags.is_empty() {
                "calibrated"
            } else {
                &flags
            }
        )?;
        n += 1;
    }
    client.stop_stream()?;
    Ok(())
}
