//! `host monitor`: a device's live compensated output, one line per window, with its flags.

use super::port::{connect, PortArgs};
use super::CliError;
use clap::Args;
use shared::wire::{SampleFlags, StreamKind};

/// `host monitor`.
#[derive(Debug, Args)]
pub(crate) struct MonitorArgs {
    /// How to reach the device.
    #[command(flatten)]
    pub port: PortArgs,
    /// Samples averaged per line.
    #[arg(long, default_value_t = 100, value_parser = recording::limits::whole_u32(1, crate::limits::MAX_WINDOW))]
    pub window: u32,
    /// Stop after this many lines (default: run until interrupted).
    #[arg(long, value_parser = recording::limits::whole_u64(1, u64::MAX))]
    pub count: Option<u64>,
    /// With `--port sim`: run the simulated device as fast as it goes instead of at its real
    /// sampling rate (needs --count, so that the output stays bounded).
    #[arg(long)]
    pub fast: bool,
}

/// `host monitor --port P [--window N] [--count N]`: live compensated output with its flags. The
/// simulated device runs at its real rate (one line per window's duration), as a board does, unless
/// `--fast`; a board is paced by its own ADC.
pub(crate) fn run(a: &MonitorArgs, quiet: bool) -> Result<(), CliError> {
    let (window, count) = (a.window, a.count);
    recording::limits::count_in("--window", window, crate::limits::MAX_WINDOW)?;
    let sim = a.port.port == super::port::SIM_PORT;
    if a.fast && !sim {
        return Err(CliError::Usage(
            "--fast only applies to --port sim (a board samples at its own rate): leave it out"
                .into(),
        ));
    }
    if a.fast && count.is_none() {
        return Err(CliError::Usage(
            "--fast without --count writes lines without end as fast as the PC can: give --count N"
                .into(),
        ));
    }
    let mut client = connect(&a.port)?;
    let identity = client.identify()?;
    if let (device::AnyTransport::Sim(dev), false) = (client.transport_mut(), a.fast) {
        dev.pace_real_time();
    }
    // A window takes its own duration to arrive, on top of the answer timeout.
    let window_s = f64::from(window) / f64::from(identity.sample_rate_hz.max(1));
    client.set_timeout(std::time::Duration::from_secs_f64(
        a.port.timeout_s() + window_s,
    ));
    let g = shared::STANDARD_GRAVITY_M_S2;
    if !quiet {
        crate::outln!(
            "unit {} ({:?}), calibration {:?}; compensated specific force in g, {} samples per line",
            identity.unit_id,
            identity.board,
            identity.calibration,
            window
        )?;
    }
    client.start_stream(StreamKind::CompensatedWindows, window.max(1))?;
    let mut n = 0u64;
    while count.is_none_or(|c| n < c) {
        let w = client.next_compensated_window()?;
        let flags = [
            (SampleFlags::UNCALIBRATED, "UNCALIBRATED"),
            (SampleFlags::SATURATED, "SATURATED"),
            (SampleFlags::NON_FINITE, "NON-FINITE"),
            (SampleFlags::FRAMES_DROPPED, "DROPPED"),
            (SampleFlags::SAMPLES_LOST, "SAMPLES-LOST"),
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
