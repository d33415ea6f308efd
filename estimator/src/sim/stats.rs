//! A simulated session reduced straight to its segment statistics, without files (what
//! `host navigation-check` calibrates).

use super::session::{
    simulate_rows, simulate_rows_with_temperature, simulated_noise, NoiseModel, SimulateError,
    SimulationSummary,
};
use super::thermal::ThermalSim;
use crate::unit_file::UnitFile;
use recording::session::{Plan, SegmentAccumulator, SegmentStats};
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
pub(crate) fn simulate_stats_with_summary(
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

/// The statistics `host simulate` would write for `unit` on `plan`, without files: its thermal
/// model (`[thermal]`, and its calibration's temperature dependence) and its `[gyro]` table, and,
/// when the plan records temperatures, each segment's temperatures, so that a temperature model is
/// fitted from them (docs/model.md §9) as from the written session.
pub fn simulate_unit_stats(
    unit: &UnitFile,
    plan: &Plan,
    noise: &NoiseModel,
    seed: u64,
) -> Result<Vec<SegmentStats>, SimulateError> {
    let cal = unit.to_calibration().map_err(SimulateError::Unit)?;
    let thermal = ThermalSim::from_unit_file(unit)?;
    let noise = simulated_noise(unit, noise);
    let with_temperature = plan.has_temperature();
    let mut accs: Vec<SegmentAccumulator> = Vec::new();
    let r = simulate_rows_with_temperature(
        &cal,
        plan,
        &noise,
        &thermal,
        seed,
        |seg, t, u, w, temp| {
            if accs.last().is_none_or(|a| a.name() != seg) {
                accs.push(SegmentAccumulator::new(seg));
            }
            if let Some(a) = accs.last_mut() {
                if with_temperature {
                    a.push_with_temperature(t, u, w, temp);
                } else {
                    a.push(t, u, w);
                }
            }
            Ok::<(), std::convert::Infallible>(())
        },
    )?;
    if let Err(never) = r {
        match never {}
    }
    Ok(accs.iter().filter_map(|a| a.finish()).collect())
}
