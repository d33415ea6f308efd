//! A hand-held session held in memory: `host segment`'s steps (`cli/segment.rs`) in the same order —
//! the reader's warnings, the still intervals, the coverage check, the plan, the hand-turn gyro
//! accepted or refused — without writing the session directory, and what `host calibrate --input`
//! would read back from that directory ([`SegmentedSession::stats`], [`SegmentedSession::gyro_estimate`]).
//! The Python package (`python/`) calibrates from it without files.
//!
//! The hand-held method's use case is here whole: this module (a logger's recording to a session),
//! [`gyro`] (the gyro fit from the hand turns, accepted or refused, kept as `gyro.toml`) and
//! [`table_turn`] (the whole turns on a table that the gyro fit takes as known angles). The
//! layers below hold their own parts: the recording's segmentation and coverage, the estimator's
//! hand-turn gyro fit (`estimate::handheld_gyro`) and simulated hand (`sim::handheld`); above,
//! the device's live hand-held mode (`device::handheld`, `device::sim_hand`).

pub mod gyro;
#[cfg(test)]
mod rest_detection_tests;
#[cfg(test)]
mod segmentation_tests;
pub mod table_turn;

use estimator::estimate::gyro::GyroEstimate;
use estimator::estimate::handheld_gyro::{HandGyroError, HandGyroFit};
use gyro::{HandGyroFileError, GYRO_FILE};
use recording::output_file::{write_atomic, OutputFileError};
use recording::session::coverage::{coverage, given_faces, Coverage};
use recording::session::from_recording::{
    join_table_turn_mounts, plan_for, plan_for_faces, stats_for, write_session,
};
use recording::session::import::{Places, Recording};
use recording::session::note::Note;
use recording::session::segment::{
    find_intervals, PositionSet, SegmentError, SegmentOptions, Segmentation,
};
use recording::session::{Plan, RecordingError, SegmentStats};
use recording::spelling::Spelling;
use std::path::Path;
use table_turn::{find_table_turns, FoundTableTurn};

/// What `host segment`'s options decide besides the recording.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentChoices {
    /// The interval detection (`--min-still-s`).
    pub segment: SegmentOptions,
    /// The unit's id, 24 lower-case hex digits (`--unit-id`, checked by the caller).
    pub unit_id: Option<String>,
    /// The site's gravity, m/s² (`--gravity`, `--latitude`, or standard).
    pub gravity_m_s2: f64,
    /// Fit the gyro from the hand turns (not with `--no-gyro`).
    pub fit_gyro: bool,
    /// A six-face session's prior on its faces, degrees (`--face-sigma-deg`, docs/model.md §7.1).
    pub face_sigma_deg: f64,
    /// The faces as the user labels them, one per still interval in order (`--faces`): a six-face
    /// session whatever the automatic labelling finds, checked against the data.
    pub faces: Option<Vec<(usize, f64)>>,
}

/// The first step: the recording, the reader's warnings, the intervals and their coverage, before
/// anything is refused for too few positions (so that a caller can show what was found first).
pub struct Found {
    /// The recording.
    pub recording: Recording,
    /// The intervals found.
    pub segmentation: Segmentation,
    /// Which positions repeat and which faces are missing.
    pub coverage: Coverage,
    /// The reader's warnings (rows left out, a cut-short last line, time jumps).
    pub warnings: Vec<String>,
}

/// A recording cut into still intervals, with its plan and the hand-turn gyro.
pub struct SegmentedSession {
    /// The recording.
    pub recording: Recording,
    /// The intervals found.
    pub segmentation: Segmentation,
    /// Which positions repeat and which faces are missing.
    pub coverage: Coverage,
    /// Spread positions, or the six faces of a cube.
    pub position_set: PositionSet,
    /// The session's plan (one static segment per still interval).
    pub plan: Plan,
    /// The gyro fit, or why there is none (too few turns, not asked).
    pub gyro: Result<HandGyroFit, HandGyroError>,
    /// The whole turns on a table found between still intervals at the same position, used or not
    /// (docs/model.md §7.2); empty without a gyro fit.
    pub table_turns: Vec<FoundTableTurn>,
    /// The reader's warnings (rows left out, a cut-short last line, time jumps), the turns left out
    /// of the gyro fit and the table turns not used as whole turns.
    pub warnings: Vec<String>,
    /// How to make a better session, when the positions are too few or too alike.
    pub advice: Option<String>,
    /// How the caller names its options in the gyro's refusals.
    pub spelling: Spelling,
}

/// Why a recording gives no session.
#[derive(Debug, thiserror::Error)]
pub enum InMemoryError {
    /// No usable still intervals, or too few distinct positions.
    #[error(transparent)]
    Segment(#[from] SegmentError),
    /// The gyro fit failed in a way that says the input is wrong (its unit).
    #[error(transparent)]
    HandGyro(#[from] HandGyroFileError),
    /// A gyro fit that no real gyro gives: its problems (`gyro::problems`).
    #[error("the gyro fit is refused:\n  - {}", .0.join("\n  - "))]
    GyroRefused(Vec<String>),
}

/// `host segment` on a recording in memory, up to (not including) writing the session; a gyro fit
/// that no real gyro gives is refused ([`SegmentedSession::gyro_problems`]).
pub fn segment_recording(
    recording: Recording,
    choices: &SegmentChoices,
) -> Result<SegmentedSession, InMemoryError> {
    let session = find(recording, choices)?.session(choices)?;
    match session.gyro_problems() {
        Some(problems) => Err(InMemoryError::GyroRefused(problems)),
        None => Ok(session),
    }
}

/// The first step of [`segment_recording`]: the intervals and their coverage.
pub fn find(recording: Recording, choices: &SegmentChoices) -> Result<Found, SegmentError> {
    if let Some(stream) = recording.corrected_by {
        return Err(SegmentError::AlreadyCorrected(stream));
    }
    let warnings = Note::texts(&recording.reader_warnings(Places::InFile));
    let segmentation = find_intervals(&recording, &choices.segment)?;
    let coverage = coverage(&segmentation.stills, choices.segment.same_position_deg);
    Ok(Found {
        recording,
        segmentation,
        coverage,
        warnings,
    })
}

impl Found {
    /// The second step: enough positions (spread, or a cube's six faces), the plan, and the gyro
    /// from the turns that no time jump cuts (those left out are said in the warnings).
    pub fn session(self, choices: &SegmentChoices) -> Result<SegmentedSession, InMemoryError> {
        let Found {
            recording,
            segmentation,
            mut coverage,
            mut warnings,
        } = self;
        let position_set = match &choices.faces {
            Some(labels) => {
                coverage.faces = Some(given_faces(&segmentation.stills, labels)?);
                PositionSet::SixFaces
            }
            None => coverage.check(segmentation.stills.len(), choices.segment.same_position_deg)?,
        };
        let (advice, mut plan) = match position_set {
            PositionSet::Spread => (coverage.advice(), plan_for(&recording, &segmentation)),
            PositionSet::SixFaces => (
                None,
                plan_for_faces(
                    &recording,
                    &segmentation,
                    coverage.faces.as_deref().unwrap_or_default(),
                    choices.face_sigma_deg,
                ),
            ),
        };
        plan.unit_id = choices.unit_id.clone();
        plan.gravity_m_s2 = choices.gravity_m_s2;
        let (gyro, table_turns) = if choices.fit_gyro {
            let table_turns = find_table_turns(&recording, &segmentation);
            join_table_turn_mounts(
                &mut plan,
                table_turns
                    .iter()
                    .filter(|t| t.used().is_some())
                    .map(|t| t.after_still),
            );
            let dropped = gyro::dropped_turns(&recording, &segmentation);
            warnings.extend(dropped.iter().map(ToString::to_string));
            warnings.extend(
                table_turns
                    .iter()
                    .filter(|t| t.used().is_none())
                    .map(ToString::to_string),
            );
            let spelling = choices.segment.spelling;
            let fit = gyro::fit(&recording, &segmentation, &plan, &dropped, spelling)?;
            let max_misfit_deg = gyro::plausible_misfit_deg(position_set, &plan);
            (
                fit.and_then(|f| gyro::undetermined(f, max_misfit_deg, spelling)),
                table_turns,
            )
        } else {
            (Err(HandGyroError::NotAsked), Vec::new())
        };
        if let Ok(fit) = &gyro {
            warnings.extend(gyro::common_scale_note(
                fit,
                &recording,
                choices.segment.spelling,
            ));
        }
        Ok(SegmentedSession {
            recording,
            segmentation,
            coverage,
            position_set,
            plan,
            gyro,
            table_turns,
            warnings,
            advice,
            spelling: choices.segment.spelling,
        })
    }
}

impl SegmentedSession {
    /// Why the gyro fit is not one a real gyro gives (`gyro::problems`), if it is not.
    pub fn gyro_problems(&self) -> Option<Vec<String>> {
        let max_misfit_deg = gyro::plausible_misfit_deg(self.position_set, &self.plan);
        let problems = gyro::problems(self.gyro.as_ref().ok()?, max_misfit_deg, self.spelling);
        (!problems.is_empty()).then_some(problems)
    }

    /// The per-segment statistics, as `host calibrate --input` reads them from the written session.
    pub fn stats(&self) -> Vec<SegmentStats> {
        stats_for(&self.recording, &self.segmentation, &self.plan)
    }

    /// The gyro estimate `host calibrate --input` takes from the session's `gyro.toml`: parsed from
    /// the same text, so that the calibration is the same to the last bit.
    pub fn gyro_estimate(&self) -> Result<Option<GyroEstimate>, HandGyroFileError> {
        match &self.gyro {
            Ok(fit) => gyro::parse(&gyro::file_text(fit), Path::new(GYRO_FILE)).map(Some),
            Err(_) => Ok(None),
        }
    }

    /// Writes the session into `dir` as `host segment` does (`plan.toml`, `samples.csv` and, with a
    /// gyro fit, `gyro.toml`), refusing an existing session unless `overwrite`; the rows written.
    pub fn write(&self, dir: &Path, overwrite: bool) -> Result<u64, WriteError> {
        let rows = write_session(
            dir,
            &self.recording,
            &self.segmentation,
            &self.plan,
            overwrite,
        )?;
        if let Ok(fit) = &self.gyro {
            let text = gyro::file_text(fit);
            write_atomic(&dir.join(GYRO_FILE), text.as_bytes(), overwrite)?;
        }
        Ok(rows)
    }
}

/// Why [`SegmentedSession::write`] failed.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The session files.
    #[error(transparent)]
    Session(#[from] RecordingError),
    /// `gyro.toml`.
    #[error(transparent)]
    Gyro(#[from] OutputFileError),
}
