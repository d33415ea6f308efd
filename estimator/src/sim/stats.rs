//! A simulated session reduced straight to its segment statistics, without files (what
//! `host navigation-check` calibrates).

use super::session::{simulate_rows, NoiseModel, SimulateError, SimulationSummary};
use crate::session::{Plan, SegmentAccumulator, SegmentStats};
use shared::Calibration;

/// Simulates `plan` on `cal` straight into segment statistics (no files).
pub fn simulate_stats(
    cal: &Calibration,
    plan: &Plan,
    noise: &NoiseModel,
    seed: u64,
) -> Result<Vec<SegmentStats>, SimulateError> {
    simulate_stats_with_summary(cal, plan, noise, seed).map(|(stats, _)| stats)
}

/// [`simulate_stats`] with the simulation's summary (each mount's true up, the truth an oracle fit
/// is given).
pub fn simulate_stats_with_summary(
    cal: &Calibration,
    plan: &Plan,
    noise: &NoiseModel,
    seed: u64,
) -> Result<(Vec<SegmentStats>, SimulationSummary), SimulateError> {
    let mut accs: Vec<SegmentAccumulator> = Vec::new();
    let r = simulate_rows(cal, plan, noise, seed, |seg, t, u, w| {
        if accs.last().is_none_or(|a| a.name() != seg) {
            accs.push(SegmentAccumulator::new(seg));
        }
        if let Some(a) = accs.last_mut() {
            a.push(t, u, w);
        }
        Ok::<(), std::convert::Infallible>(())
    })?;
    let summary = match r {
        Ok(summary) => summary,
        Err(never) => match never {},
    };
    Ok((accs.iter().filter_map(|a| a.finish()).collect(), summary))
}
