//! What a report or a compensated recording says beside its numbers: each a [`Note`] carrying
//! what it is about, not its text, so that a caller can tell one from another (its [`Note::code`]) without matching
//! words; its `Display` is the one wording the terminal, `report.md` and `report.html` print. The
//! reader's notes on the session's files are carried whole.

use std::fmt;
use std::path::PathBuf;

/// One thing a report tells its reader besides its numbers.
#[derive(Clone, Debug, PartialEq)]
pub enum Note {
    /// What the reader repaired or noticed in the session's files.
    Reader(recording::session::note::Note),
    /// The session alone does not calibrate: the theoretical values are the plan's.
    SessionDoesNotCalibrate(estimator::estimate::error::EstimateError),
    /// Every position was held by hand: no navigation replay (its attitude is fitted from the
    /// outputs the replay would judge).
    ReplayHandHeld,
    /// No static segment with a known attitude: no static replay.
    NoStaticReplay,
    /// No constant-rate segment with a known attitude: no rotating replay.
    NoRateReplay,
    /// The embedded font could not be registered: an SVG without text.
    SvgWithoutText {
        /// The figure's file stem.
        stem: String,
    },
    /// The embedded font could not be registered: a PNG not written.
    PngNotWritten {
        /// The file it would have been.
        path: PathBuf,
    },
    /// Rows outside the calibration's valid temperature range (or without a reading),
    /// compensated at the range's nearest end.
    RowsOutsideTemperatureRange {
        /// How many.
        rows: u64,
    },
    /// A long log compensated window by window.
    ReadInWindows {
        /// The most samples per stream read into memory at once.
        max_samples: usize,
        /// The windows read.
        windows: usize,
    },
    /// A still segment longer than the noise analysis takes: only its first samples analysed.
    NoiseSegmentCut {
        /// The segment.
        segment: String,
        /// The samples analysed.
        max_samples: usize,
    },
    /// No calibration for the noise analysis: the accelerometer's figures in its output unit.
    NoiseUncalibrated {
        /// How the caller names its options.
        spelling: recording::spelling::Spelling,
    },
    /// What the reader said of some of a long log's windows.
    InWindows {
        /// What it said.
        note: Box<Note>,
        /// The windows' spans, s (open ends infinite).
        spans: Vec<(f64, f64)>,
        /// The log's windows in all.
        windows: usize,
    },
}

impl Note {
    /// A stable name of the note's kind, for a program reading the notes, independent of its
    /// wording (a reader's note has its own).
    pub fn code(&self) -> &'static str {
        match self {
            Note::Reader(n) => n.code(),
            Note::SessionDoesNotCalibrate(_) => "session_does_not_calibrate",
            Note::ReplayHandHeld => "replay_hand_held",
            Note::NoStaticReplay => "no_static_replay",
            Note::NoRateReplay => "no_rate_replay",
            Note::SvgWithoutText { .. } => "svg_without_text",
            Note::PngNotWritten { .. } => "png_not_written",
            Note::RowsOutsideTemperatureRange { .. } => "rows_outside_temperature_range",
            Note::ReadInWindows { .. } => "read_in_windows",
            Note::NoiseSegmentCut { .. } => "noise_segment_cut",
            Note::NoiseUncalibrated { .. } => "noise_uncalibrated",
            Note::InWindows { note, .. } => note.code(),
        }
    }

    /// The notes said as text, in order.
    pub fn texts(notes: &[Note]) -> Vec<String> {
        notes.iter().map(ToString::to_string).collect()
    }
}

impl fmt::Display for Note {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Note::Reader(n) => write!(f, "{n}"),
            Note::SessionDoesNotCalibrate(e) => write!(
                f,
                "the session alone does not calibrate ({}): the theoretical values are the plan's \
                 nominal attitudes, and free (hand-held) positions are not compared",
                shared::chain::Chain(e)
            ),
            Note::ReplayHandHeld => f.write_str(
                "the navigation replay is left out: every position was held by hand, so its \
                 attitude is fitted from the very outputs the replay would judge (it would show the \
                 fit's own residual, not a navigator's drift); the before/after table against the \
                 fitted attitudes is the check",
            ),
            Note::NoStaticReplay => f.write_str(
                "no static segment with a known attitude: the static navigation replay is left out",
            ),
            Note::NoRateReplay => f.write_str(
                "no constant-rate segment with a known attitude: the rotating navigation replay is \
                 left out",
            ),
            Note::SvgWithoutText { stem } => write!(
                f,
                "the embedded font could not be registered: {stem}.svg has no text"
            ),
            Note::PngNotWritten { path } => write!(
                f,
                "the embedded font could not be registered: {} not written",
                path.display()
            ),
            Note::RowsOutsideTemperatureRange { rows } => write!(
                f,
                "{rows} rows were recorded outside the calibration's valid temperature range (or \
                 without a temperature reading): their compensation uses the nearest end of the \
                 range, and the device flags such outputs"
            ),
            Note::ReadInWindows {
                max_samples,
                windows,
            } => write!(
                f,
                "the log holds more than {max_samples} samples per stream, the most read into \
                 memory at once: it was read and compensated in {windows} time windows, the \
                 device's state carried from each to the next"
            ),
            Note::NoiseSegmentCut {
                segment,
                max_samples,
            } => write!(
                f,
                "segment '{segment}' is longer than {max_samples} rows; only its first \
                 {max_samples} are analysed"
            ),
            Note::NoiseUncalibrated { spelling } => write!(
                f,
                "no {}: accelerometer figures are in the output unit, and Kalibr's accelerometer \
                 figures are undetermined",
                spelling.name(recording::spelling::UserOption::Calibration)
            ),
            Note::InWindows {
                note,
                spans,
                windows,
            } => match spans.as_slice() {
                _ if spans.len() == *windows => write!(f, "{note}"),
                [(lo, hi)] => write!(f, "in the window {}: {note}", SpanText(*lo, *hi)),
                _ => write!(f, "in {} of the {windows} windows: {note}", spans.len()),
            },
        }
    }
}

/// A window's times for the user: "t = 120.000 s to 245.500 s", its open ends said as such.
struct SpanText(f64, f64);

impl fmt::Display for SpanText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let SpanText(lo, hi) = *self;
        match (lo.is_finite(), hi.is_finite()) {
            (true, true) => write!(f, "t = {lo:.3} s to {hi:.3} s"),
            (false, true) => write!(f, "up to t = {hi:.3} s"),
            (true, false) => write!(f, "from t = {lo:.3} s on"),
            (false, false) => f.write_str("of the whole log"),
        }
    }
}
