//! `simulate-hand`: a simulated hand-held session (or a six-face one) as a logger would write it,
//! with the simulated unit's truth. The command line's flags and Python's keyword arguments both
//! become a [`HandSimulation`]; the units, the rate and the options that go together are checked
//! here once, and a refusal names the options as the caller spells them.

use estimator::sim::handheld::{
    logger_unit, simulate_hand, truth_toml, write_logger_csv, HandSession, HandSpec, LoggerLayout,
};
use recording::limits::SIMULATED_HAND_RATE_HZ;
use recording::output_file::{write_atomic, OutputFileError};
use recording::session::import::{gyro_unit_and_scale, parse_acc_unit, GyroUnit, GyroUnitFault};
use recording::spelling::{Spelling, UserOption};
use shared::{Calibration, OutputUnit};
use std::path::{Path, PathBuf};

/// A simulated session to make.
#[derive(Clone, Debug, PartialEq)]
pub struct HandSimulation {
    /// Seed of the session's randomness.
    pub seed: u64,
    /// Sample rate, Hz, within [`SIMULATED_HAND_RATE_HZ`].
    pub rate_hz: f64,
    /// The accelerometer's unit as written: m/s2, g or LSB (4096 per g, quantised).
    pub acc_unit: String,
    /// With LSB: counts added to every accelerometer value (an unsigned output's mid-scale).
    pub acc_offset: Option<f64>,
    /// The gyro's unit as written: deg/s, rad/s, or LSB with `gyro_lsb_per_dps`.
    pub gyro_unit: String,
    /// With a gyro in LSB: counts per °/s.
    pub gyro_lsb_per_dps: Option<f64>,
    /// A six-face session turned over this many times, instead of the hand-held one.
    pub six_face_rounds: Option<u32>,
    /// A whole turn about the vertical on the table at each position (docs/model.md §7.2).
    pub table_turns: bool,
    /// How the caller names its options, for a refusal.
    pub spelling: Spelling,
}

/// Why a simulation was refused: an option outside what it can write.
#[derive(Debug, thiserror::Error)]
pub enum HandSimulationError {
    /// An accelerometer unit it does not write.
    #[error("{}: use m/s2, g or LSB", .spelling.given(UserOption::AccUnit, .given))]
    AccUnit {
        /// The unit given.
        given: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// A gyro unit it does not write.
    #[error("{}: use deg/s, rad/s or LSB", .spelling.given(UserOption::GyroUnit, .given))]
    GyroUnit {
        /// The unit given.
        given: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// A gyro in counts without its scale, or a scale without counts.
    #[error(
        "{} and {} go together",
        .0.given(UserOption::GyroUnit, "LSB"),
        .0.given(UserOption::GyroLsbPerDps, "X")
    )]
    GyroCounts(Spelling),
    /// An accelerometer offset on values that are not counts.
    #[error("{} needs {}", .0.name(UserOption::AccOffset), .0.given(UserOption::AccUnit, "LSB"))]
    OffsetWithoutCounts(Spelling),
    /// A rate outside the simulator's range.
    #[error(
        "{}: use {} to {}",
        .spelling.given(UserOption::RateHz, .rate_hz),
        SIMULATED_HAND_RATE_HZ.0,
        SIMULATED_HAND_RATE_HZ.1
    )]
    Rate {
        /// The rate given, Hz.
        rate_hz: f64,
        /// The caller's names of the options.
        spelling: Spelling,
    },
}

/// Why the simulated session's files were not written.
#[derive(Debug, thiserror::Error)]
pub enum HandWriteError {
    /// A file is there and replacing it was not asked for.
    #[error("{} exists", .0.display())]
    Exists(PathBuf),
    /// The CSV could not be written.
    #[error("cannot write {}", .0.display())]
    Csv(PathBuf, #[source] std::io::Error),
    /// The truth file could not be written.
    #[error(transparent)]
    Truth(#[from] OutputFileError),
}

/// A simulated session: its rows and holds, the unit's truth, and how a logger writes them.
#[derive(Clone, Debug)]
pub struct SimulatedHand {
    /// The rows (t, acc in the unit's output, gyro rad/s) and the holds.
    pub session: HandSession,
    /// The simulated unit, its biases in the written file's counts (the offset included).
    pub truth: Calibration,
    /// What was simulated (its gyro's truth included).
    pub spec: HandSpec,
    /// How the logger's file holds the rows.
    pub layout: LoggerLayout,
    /// The accelerometer's unit written.
    pub acc_unit: OutputUnit,
    /// The gyro's unit written: its symbol (`deg/s`, `rad/s` or `LSB`).
    pub gyro_symbol: &'static str,
}

impl HandSimulation {
    /// The session, or why these options cannot make one.
    pub fn run(&self) -> Result<SimulatedHand, HandSimulationError> {
        let sp = self.spelling;
        let acc_unit = parse_acc_unit(&self.acc_unit)
            .filter(|u| *u != OutputUnit::Volts)
            .ok_or_else(|| HandSimulationError::AccUnit {
                given: self.acc_unit.clone(),
                spelling: sp,
            })?;
        let (gyro_unit, _) = gyro_unit_and_scale(&self.gyro_unit, self.gyro_lsb_per_dps).map_err(
            |fault| match fault {
                GyroUnitFault::Unknown => HandSimulationError::GyroUnit {
                    given: self.gyro_unit.clone(),
                    spelling: sp,
                },
                GyroUnitFault::NeedsScale | GyroUnitFault::ScaleNotCounts => {
                    HandSimulationError::GyroCounts(sp)
                }
            },
        )?;
        let counts = self.gyro_lsb_per_dps.is_some();
        if self.acc_offset.is_some() && acc_unit != OutputUnit::Lsb {
            return Err(HandSimulationError::OffsetWithoutCounts(sp));
        }
        let (lo, hi) = SIMULATED_HAND_RATE_HZ;
        if !(lo..=hi).contains(&self.rate_hz) {
            return Err(HandSimulationError::Rate {
                rate_hz: self.rate_hz,
                spelling: sp,
            });
        }
        let spec = HandSpec {
            rate_hz: self.rate_hz,
            acc_step: if acc_unit == OutputUnit::Lsb {
                1.0
            } else {
                0.0
            },
            table_turns: self.table_turns,
            ..match self.six_face_rounds {
                Some(rounds) => HandSpec::six_faces(self.seed, 1.0, rounds as usize),
                None => HandSpec::standard(self.seed),
            }
        };
        let mut truth = logger_unit(acc_unit);
        let session = simulate_hand(&truth, &spec);
        let acc_offset = self.acc_offset.unwrap_or(0.0);
        // The file's zero force is at the offset: so is the truth's bias.
        truth.statics.zero_bias_out = truth.statics.zero_bias_out.map(|b| b + acc_offset);
        let layout = LoggerLayout {
            gyro_deg_s: gyro_unit == GyroUnit::DegPerS,
            acc_offset,
            gyro_lsb_per_dps: self.gyro_lsb_per_dps,
            ..LoggerLayout::default()
        };
        Ok(SimulatedHand {
            session,
            truth,
            spec,
            layout,
            acc_unit,
            gyro_symbol: if counts { "LSB" } else { gyro_unit.symbol() },
        })
    }
}

impl SimulatedHand {
    /// The unit's truth as unit-file TOML with its `[gyro]`.
    pub fn truth_toml(&self) -> String {
        truth_toml(&self.truth, &self.spec.gyro)
    }

    /// Where the truth of a session written to `csv` goes: beside it, `.truth.toml`.
    pub fn truth_path(csv: &Path) -> PathBuf {
        csv.with_extension("truth.toml")
    }

    /// Writes the logger's CSV to `csv` and the truth beside it ([`SimulatedHand::truth_path`]);
    /// an existing file is replaced only with `force`, and neither is touched when one is there.
    pub fn write(&self, csv: &Path, force: bool) -> Result<PathBuf, HandWriteError> {
        let truth_path = Self::truth_path(csv);
        for p in [csv, truth_path.as_path()] {
            if p.exists() && !force {
                return Err(HandWriteError::Exists(p.to_path_buf()));
            }
        }
        write_logger_csv(csv, &self.session.rows, &self.layout)
            .map_err(|e| HandWriteError::Csv(csv.to_path_buf(), e))?;
        write_atomic(&truth_path, self.truth_toml().as_bytes(), force)?;
        Ok(truth_path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use recording::testkit::{KEYWORD_SPELLING, SPELLING};

    fn request() -> HandSimulation {
        HandSimulation {
            seed: 1,
            rate_hz: 200.0,
            acc_unit: "m/s2".into(),
            acc_offset: None,
            gyro_unit: "deg/s".into(),
            gyro_lsb_per_dps: None,
            six_face_rounds: None,
            table_turns: false,
            spelling: SPELLING,
        }
    }

    /// Each refusal names the options as the caller spells them, and the rate's range is the
    /// limits' own.
    #[test]
    fn refusals_name_the_callers_options() {
        let refused = |change: &dyn Fn(&mut HandSimulation), spelling| {
            let mut r = request();
            change(&mut r);
            r.spelling = spelling;
            r.run().unwrap_err().to_string()
        };
        let rate = |r: &mut HandSimulation| r.rate_hz = 5.0;
        let (lo, hi) = SIMULATED_HAND_RATE_HZ;
        assert_eq!(
            refused(&rate, SPELLING),
            format!("<RateHz> 5: use {lo} to {hi}")
        );
        assert_eq!(
            refused(&rate, KEYWORD_SPELLING),
            format!("<RateHz>=5: use {lo} to {hi}")
        );
        let volts = |r: &mut HandSimulation| r.acc_unit = "V".into();
        assert_eq!(
            refused(&volts, KEYWORD_SPELLING),
            "<AccUnit>=\"V\": use m/s2, g or LSB"
        );
        let counts = |r: &mut HandSimulation| r.gyro_unit = "LSB".into();
        assert_eq!(
            refused(&counts, SPELLING),
            "<GyroUnit> LSB and <GyroLsbPerDps> X go together"
        );
        let offset = |r: &mut HandSimulation| r.acc_offset = Some(32768.0);
        assert_eq!(
            refused(&offset, KEYWORD_SPELLING),
            "<AccOffset> needs <AccUnit>=\"LSB\""
        );
    }

    /// The truth's biases are in the written file's counts: the offset added to each.
    #[test]
    fn an_offset_is_in_the_truths_biases() {
        let mut r = request();
        r.acc_unit = "LSB".into();
        let plain = r.run().unwrap();
        r.acc_offset = Some(32768.0);
        let shifted = r.run().unwrap();
        for i in 0..3 {
            let d = shifted.truth.statics.zero_bias_out[i] - plain.truth.statics.zero_bias_out[i];
            assert_eq!(d, 32768.0);
        }
        assert_eq!(shifted.layout.acc_offset, 32768.0);
        assert_eq!(shifted.session.rows, plain.session.rows);
    }
}
