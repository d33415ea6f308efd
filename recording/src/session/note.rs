//! What a reader tells the user about a recording it read besides its samples: the rows and bytes it
//! left out, the stamps it repaired, the corrections it undid. Each is a [`Note`] carrying its
//! figures, not its text, so that a caller can tell one from another (its [`Note::code`]) without
//! matching words; its `Display` is the one wording every caller prints (a text file's notes are
//! worded beside their reader, in `import::notes`).

use super::import::time::{jumps_text, TimeJump};
use super::repair::TimeRepairs;
use crate::spelling::{Spelling, UserOption};
use std::fmt;
use std::path::PathBuf;

/// One thing a reader noticed and repaired or left out, with the figures its message states.
#[derive(Clone, Debug, PartialEq)]
pub enum Note {
    /// A session segment's stamps jump between consecutive rows.
    SegmentTimeJumps {
        /// The plan segment.
        segment: String,
        /// How many.
        count: u64,
        /// The line (1-based) of the first.
        line: u64,
        /// The first step, s.
        step_s: f64,
        /// The plan's sample period, s.
        period_s: f64,
    },
    /// A session segment's rows whose temperature jumps too fast, left out as glitches.
    SegmentTempGlitches {
        /// The plan segment.
        segment: String,
        /// How many.
        count: u64,
        /// The line (1-based) of the first.
        line: u64,
        /// The first glitch's temperature, °C.
        temp_c: f64,
    },
    /// A session segment's rows with NaN or infinite values left out.
    SegmentNonFinite {
        /// The plan segment.
        segment: String,
        /// The line (1-based) of the first.
        line: u64,
        /// Rows left out in all.
        rejected: u64,
    },
    /// A plan segment with no usable row in the samples file.
    SegmentWithoutRows {
        /// The plan segment.
        segment: String,
        /// The samples file.
        path: PathBuf,
    },
    /// A plan segment with less than half the rows its duration expects.
    SegmentShort {
        /// The plan segment.
        segment: String,
        /// Rows (or samples) in all.
        rows: u64,
        /// Rows the plan's duration expects.
        expected: f64,
        /// The plan's duration, s.
        duration_s: f64,
        /// The sample rate, Hz.
        rate_hz: f64,
    },
    /// ULog format definitions that do not parse.
    UlogBadFormats {
        /// How many.
        count: u64,
        /// Where the first is (byte or line).
        first: u64,
    },
    /// ULog format definitions beyond the fields kept.
    UlogOverFormats {
        /// How many.
        count: u64,
        /// Where the first is (byte or line).
        first: u64,
    },
    /// A ULog file ends before its appended data.
    UlogEndsBeforeAppended {
        /// The byte where reading is, or where it happened.
        offset: u64,
        /// The byte where the appended data starts.
        appended: u64,
    },
    /// A ULog file's appended data lies before where reading is.
    UlogAppendedBehind {
        /// The byte where the appended data starts.
        appended: u64,
        /// The byte where reading is, or where it happened.
        offset: u64,
    },
    /// A ULog message runs into the appended data.
    UlogRunsIntoAppended {
        /// The byte where reading is, or where it happened.
        offset: u64,
        /// The byte where the appended data starts.
        appended: u64,
    },
    /// A binary log's last message is cut short.
    LastMessageCutShort {
        /// The byte where reading is, or where it happened.
        offset: u64,
    },
    /// A ULog's raw sensor topics are sparse beside sensor_combined, which is read instead.
    UlogSparseRawTopics {
        /// Samples of the raw topics.
        raw: usize,
        /// Samples of sensor_combined.
        combined: usize,
    },
    /// A ULog's logger dropped data.
    UlogDropouts {
        /// How many.
        count: usize,
        /// All dropouts, ms.
        total_ms: u64,
        /// The byte where reading is, or where it happened.
        offset: u64,
        /// The first dropout's time, s.
        t_s: f64,
        /// The first dropout, ms.
        ms: u16,
    },
    /// DataFlash bytes that start no known message, skipped.
    DataFlashSkipped {
        /// How many.
        count: u64,
        /// Where the first is (byte or line).
        first: u64,
    },
    /// An MCAP file cut short inside a record.
    McapCutShort {
        /// The byte where reading is, or where it happened.
        offset: u64,
    },
    /// MCAP Imu messages without a header stamp, timed by the bag's log time.
    McapUnstamped {
        /// How many.
        count: u64,
    },
    /// Gyro samples with NaN or infinite values left out.
    GyroNonFinite {
        /// How many.
        count: usize,
    },
    /// Accelerometer samples with no gyro sample near enough, left out.
    Unpaired {
        /// How many.
        count: usize,
        /// The gap allowed, s.
        max_gap_s: f64,
    },
    /// Every sample re-timed at the rate given; the rate its stamps imply, if they tell.
    Retimed {
        /// The rate given, Hz.
        given_hz: f64,
        /// The rate the stamps imply, Hz, if they tell.
        implied_hz: Option<f64>,
    },
    /// No sample has a temperature reading: read as a recording without temperature.
    NoTemperature,
    /// Some samples have no temperature reading.
    SomeWithoutTemperature {
        /// Samples without a reading.
        missing: usize,
        /// Rows (or samples) in all.
        rows: usize,
    },
    /// A long log kept only its still stretches and turns.
    LongLogKept {
        /// Accelerometer samples in the log.
        read: usize,
        /// Samples kept in memory at once.
        max: usize,
        /// Samples kept.
        kept: usize,
        /// Stretches of still positions and turns.
        regions: usize,
        /// Samples of long moves left out.
        outside: usize,
    },
    /// A long log's still stretches and turns held more than the budget: the rest left out, and
    /// the option that keeps more, spelled as the caller does.
    LongLogOverBudget {
        /// Samples kept in memory at once.
        max: usize,
        /// Samples beyond the budget left out.
        over_budget: usize,
        /// The first left out sample's time, s.
        from_s: f64,
        /// Samples the stretches hold.
        needed: usize,
        /// The option that keeps more, if the caller has one.
        option: Option<UserOption>,
        /// How the caller names its options.
        spelling: Spelling,
    },
    /// Samples the window rule left out of a long log read window by window.
    WindowRule {
        /// Samples left out.
        lost: usize,
    },
    /// The stamps a reader repaired, `what` naming a sample where the places are the file's.
    TimeRepairs {
        /// What a sample is called, where the places are the file's.
        what: Option<&'static str>,
        /// The repairs.
        repairs: TimeRepairs,
    },
    /// The jumps left in the stamps, the first five named.
    TimeJumps {
        /// The first jumps (at most five).
        named: Vec<TimeJump>,
        /// How many.
        count: usize,
        /// The sample rate, Hz.
        rate_hz: f64,
    },
    /// Text rows with NaN or infinite values left out.
    SkippedRows {
        /// How many.
        count: usize,
    },
    /// Overlong text lines left out as damaged.
    OverlongLines {
        /// How many.
        count: usize,
        /// Where the first is (byte or line).
        first: u64,
    },
    /// The last line of a text file has no line end.
    Unterminated {
        /// The line (1-based) of the first.
        line: u64,
    },
    /// Lines before a text file's header skipped.
    Preamble {
        /// Lines skipped.
        lines: u64,
        /// The header's line.
        header_line: u64,
        /// How the caller names its options.
        spelling: Spelling,
    },
    /// A text file without a header: its columns taken by index.
    NoHeader {
        /// The line (1-based) of the first.
        line: u64,
    },
    /// Rows without gyro values took the gyro's rate from their neighbours.
    GyroFilled {
        /// Rows without gyro values.
        no_gyro: usize,
        /// Rows with the gyro alone.
        no_acc: usize,
        /// Rows with no gyro near enough, left out.
        unfilled: usize,
        /// How far a row looks for a gyro value, rows.
        fill_rows: usize,
    },
    /// A gyro in counts at an unsigned output's mid-scale with no offset given.
    GyroMidScale {
        /// The mid-scale count.
        mid: f64,
        /// The output's bits.
        bits: u32,
        /// The bias it reads as, °/s.
        bias_dps: f64,
        /// The offset to give, as the caller writes a number.
        offset: String,
        /// How the caller names its options.
        spelling: Spelling,
    },
    /// ArduPilot's own calibration undone sample by sample.
    ArduPilotUndone {
        /// The IMU instance.
        instance: u8,
        /// The offset parameters' prefix.
        offs: String,
        /// The scale parameters' prefix.
        scal: String,
        /// The offsets undone, m/s².
        acc_offset: [f64; 3],
        /// The scales undone.
        acc_scale: [f64; 3],
        /// AHRS_ORIENTATION.
        orientation: f64,
        /// Temperature terms undone too.
        tcal: bool,
        /// Samples without a temperature.
        no_temp: usize,
    },
}

impl Note {
    /// A stable name of the note's kind, for a program reading the notes (the JSON document,
    /// Python), independent of its wording.
    pub fn code(&self) -> &'static str {
        match self {
            Note::SegmentTimeJumps { .. } => "segment_time_jumps",
            Note::SegmentTempGlitches { .. } => "segment_temp_glitches",
            Note::SegmentNonFinite { .. } => "segment_non_finite",
            Note::SegmentWithoutRows { .. } => "segment_without_rows",
            Note::SegmentShort { .. } => "segment_short",
            Note::UlogBadFormats { .. } => "ulog_bad_formats",
            Note::UlogOverFormats { .. } => "ulog_over_formats",
            Note::UlogEndsBeforeAppended { .. } => "ulog_ends_before_appended",
            Note::UlogAppendedBehind { .. } => "ulog_appended_behind",
            Note::UlogRunsIntoAppended { .. } => "ulog_runs_into_appended",
            Note::LastMessageCutShort { .. } => "last_message_cut_short",
            Note::UlogSparseRawTopics { .. } => "ulog_sparse_raw_topics",
            Note::UlogDropouts { .. } => "ulog_dropouts",
            Note::DataFlashSkipped { .. } => "dataflash_skipped",
            Note::McapCutShort { .. } => "mcap_cut_short",
            Note::McapUnstamped { .. } => "mcap_unstamped",
            Note::GyroNonFinite { .. } => "gyro_non_finite",
            Note::Unpaired { .. } => "unpaired",
            Note::Retimed { .. } => "retimed",
            Note::NoTemperature => "no_temperature",
            Note::SomeWithoutTemperature { .. } => "some_without_temperature",
            Note::LongLogKept { .. } => "long_log_kept",
            Note::LongLogOverBudget { .. } => "long_log_over_budget",
            Note::WindowRule { .. } => "window_rule",
            Note::TimeRepairs { .. } => "time_repairs",
            Note::TimeJumps { .. } => "time_jumps",
            Note::SkippedRows { .. } => "skipped_rows",
            Note::OverlongLines { .. } => "overlong_lines",
            Note::Unterminated { .. } => "unterminated",
            Note::Preamble { .. } => "preamble",
            Note::NoHeader { .. } => "no_header",
            Note::GyroFilled { .. } => "gyro_filled",
            Note::GyroMidScale { .. } => "gyro_mid_scale",
            Note::ArduPilotUndone { .. } => "ardupilot_undone",
        }
    }

    /// `repairs` said, `what` naming a sample where the places are the file's; none when nothing
    /// was repaired.
    pub(crate) fn time_repairs(what: Option<&'static str>, repairs: &TimeRepairs) -> Option<Note> {
        (!repairs.is_empty()).then(|| Note::TimeRepairs {
            what,
            repairs: repairs.clone(),
        })
    }

    /// The notes said as text, in order: what a caller that only prints them keeps.
    pub fn texts(notes: &[Note]) -> Vec<String> {
        notes.iter().map(ToString::to_string).collect()
    }
}

impl fmt::Display for Note {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Note::SegmentTimeJumps { .. }
            | Note::SegmentTempGlitches { .. }
            | Note::SegmentNonFinite { .. }
            | Note::SegmentWithoutRows { .. }
            | Note::SegmentShort { .. } => self.fmt_session(f),
            Note::UlogBadFormats { .. }
            | Note::UlogOverFormats { .. }
            | Note::UlogEndsBeforeAppended { .. }
            | Note::UlogAppendedBehind { .. }
            | Note::UlogRunsIntoAppended { .. }
            | Note::LastMessageCutShort { .. }
            | Note::UlogSparseRawTopics { .. }
            | Note::UlogDropouts { .. }
            | Note::DataFlashSkipped { .. }
            | Note::McapCutShort { .. }
            | Note::McapUnstamped { .. }
            | Note::ArduPilotUndone { .. } => self.fmt_binary(f),
            Note::GyroNonFinite { .. }
            | Note::Unpaired { .. }
            | Note::Retimed { .. }
            | Note::NoTemperature
            | Note::SomeWithoutTemperature { .. }
            | Note::LongLogKept { .. }
            | Note::LongLogOverBudget { .. }
            | Note::WindowRule { .. }
            | Note::TimeRepairs { .. }
            | Note::TimeJumps { .. } => self.fmt_stream(f),
            _ => self.fmt_text(f),
        }
    }
}

impl Note {
    /// The notes of a session's `samples.csv`, by plan segment.
    fn fmt_session(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Note::SegmentTimeJumps { segment, count, line, step_s, period_s } => write!(
                f,
                "segment '{segment}': the time stamps jump {count} time(s) between consecutive rows \
                 (a gap, a repeat or a step back; first at line {line}: {step_s:+.6} s, the period \
                 is {period_s:.6} s)"
            ),
            Note::SegmentTempGlitches { segment, count, line, temp_c } => write!(
                f,
                "segment '{segment}': {count} row(s) whose temperature jumps faster than \
                 {} °C/s from the readings around it left out as glitches \
                 (first at line {line}: {temp_c} °C)",
                super::thermal::MAX_TEMP_RATE_C_PER_S
            ),
            Note::SegmentNonFinite { segment, line, rejected } => {
                write!(
                    f,
                    "segment '{segment}': rows with NaN or infinite values left out (first at line \
                     {line}"
                )?;
                if *rejected > 0 {
                    write!(f, ", {rejected} in all")?;
                }
                f.write_str(")")
            }
            Note::SegmentWithoutRows { segment, path } => write!(
                f,
                "segment '{segment}' of the plan has no usable rows in {}: it is left out",
                path.display()
            ),
            Note::SegmentShort { segment, rows, expected, duration_s, rate_hz } => write!(
                f,
                "segment '{segment}' has {rows} usable rows; the plan expects about {expected:.0} \
                 ({duration_s} s at {rate_hz} Hz): was it cut short?"
            ),
            _ => Ok(()),
        }
    }

    /// The notes of a binary log's reader (ULog, DataFlash, MCAP).
    fn fmt_binary(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Note::UlogBadFormats { count, first } => write!(
                f,
                "{count} format definition(s) that do not parse left out (the first at byte \
                 {first}); they define no IMU topic, and the topics they define are not read"
            ),
            Note::UlogOverFormats { count, first } => write!(
                f,
                "{count} format definition(s) beyond the {} fields or {} bytes of fields kept left \
                 out (the first at byte {first}); they define no IMU topic, and the topics they \
                 define are not read",
                super::logs::ulog::MAX_FIELDS,
                super::logs::ulog::MAX_FIELD_BYTES
            ),
            Note::UlogEndsBeforeAppended { offset, appended } => write!(
                f,
                "the log ends at byte {offset} before its appended data at byte {appended}"
            ),
            Note::UlogAppendedBehind { appended, offset } => write!(
                f,
                "the log's appended data at byte {appended} lies before byte {offset}, where \
                 reading is: ignored"
            ),
            Note::UlogRunsIntoAppended { offset, appended } => write!(
                f,
                "the message at byte {offset} runs into the data appended at byte {appended} (the \
                 logger stopped while writing it): left out"
            ),
            Note::LastMessageCutShort { offset } => write!(
                f,
                "the log's last message (at byte {offset}) is cut short: it is left out"
            ),
            Note::UlogSparseRawTopics { raw, combined } => write!(
                f,
                "sensor_accel/sensor_gyro hold only {raw} samples against sensor_combined's \
                 {combined}: reading sensor_combined (already corrected by PX4's calibration, no \
                 temperature), which a calibration cannot be made from; to calibrate the sensor \
                 itself, log sensor_accel and sensor_gyro at the sensor's rate (PX4's \
                 logger_topics.txt or SDLOG_PROFILE)"
            ),
            Note::UlogDropouts {
                count,
                total_ms,
                offset,
                t_s,
                ms,
            } => write!(
                f,
                "the logger dropped data {count} time(s), {total_ms} ms in all; the first at byte \
                 {offset} (t = {t_s:.3} s), {ms} ms: no still interval or turn should span a \
                 dropout"
            ),
            Note::DataFlashSkipped { count, first } => write!(
                f,
                "{count} byte(s) that start no known message were skipped, the first at byte \
                 {first} (damage or padding in the log, as pymavlink skips them)"
            ),
            Note::McapCutShort { offset } => write!(
                f,
                "the file is cut short: it ends at byte {offset} inside a record; the messages \
                 before that record are read, those in it (a whole chunk, if the bag is chunked) \
                 are lost"
            ),
            Note::McapUnstamped { count } => write!(
                f,
                "the {count} Imu messages have no header stamp (all 0): timed by the bag's log \
                 time, when the recorder received them"
            ),
            Note::ArduPilotUndone { .. } => self.fmt_ardupilot(f),
            _ => Ok(()),
        }
    }

    /// [`Note::ArduPilotUndone`]'s text: the parameters undone, and the samples that had no
    /// temperature for INS_TCAL.
    fn fmt_ardupilot(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Note::ArduPilotUndone {
            instance,
            offs,
            scal,
            acc_offset,
            acc_scale,
            orientation,
            tcal,
            no_temp,
        } = self
        else {
            return Ok(());
        };
        write!(
            f,
            "IMU instance {instance} is logged after ArduPilot's own calibration: undone \
             sample by sample ({offs}_* = {acc_offset:?} m/s², {scal}_* = {acc_scale:?}, \
             AHRS_ORIENTATION = {orientation}"
        )?;
        if *tcal {
            write!(f, ", INS_TCAL{}_*", instance + 1)?;
        }
        f.write_str("), so that what is read is the sensor's own output")?;
        if *no_temp > 0 {
            write!(
                f,
                "; {no_temp} sample(s) without a temperature took the one before for \
                 INS_TCAL"
            )?;
        }
        Ok(())
    }

    /// The notes of a recording's streams, the same for every format.
    fn fmt_stream(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Note::GyroNonFinite { count } => write!(
                f,
                "{count} gyro sample(s) with NaN or infinite values left out (the rate \
                 interpolated between their neighbours)"
            ),
            Note::Unpaired { count, max_gap_s } => write!(
                f,
                "{count} accelerometer sample(s) with no gyro sample within {:.0} ms left out",
                max_gap_s * 1e3
            ),
            Note::Retimed {
                given_hz,
                implied_hz: Some(hz),
            } => write!(
                f,
                "every sample re-timed at {given_hz} Hz as given, not at its stamp; the stamps \
                 imply {hz:.4} Hz ({:+.2} % from the rate given)",
                (hz / given_hz - 1.0) * 100.0
            ),
            Note::Retimed {
                given_hz,
                implied_hz: None,
            } => write!(
                f,
                "every sample re-timed at {given_hz} Hz as given; too few stamps to say what rate \
                 they imply"
            ),
            Note::NoTemperature => f.write_str(
                "the temperature is NaN in every sample (a driver without a temperature \
                     reading): read as a log without temperature",
            ),
            Note::SomeWithoutTemperature { missing, rows } => write!(
                f,
                "{missing} of {rows} samples have no temperature reading (NaN): those rows are \
                 kept, and only the readings enter the temperature statistics"
            ),
            Note::LongLogKept {
                read,
                max,
                kept,
                regions,
                outside,
            } => write!(
                f,
                "the log holds {read} accelerometer samples, more than the {max} kept in memory at \
                 once: {kept} are kept, those of its {regions} stretch(es) of still positions and \
                 turns, and the {outside} of moves longer than {:.0} s between them (flights, \
                 walks) are left out",
                super::logs::keep::MAX_MOVE_S
            ),
            Note::LongLogOverBudget {
                max,
                over_budget,
                from_s,
                ..
            } => {
                write!(
                    f,
                    "the still positions and turns hold more than {max} samples: the \
                     {over_budget} from t = {from_s:.3} s on are left out; "
                )?;
                self.fmt_budget_advice(f)
            }
            Note::WindowRule { lost } => write!(
                f,
                "{lost} sample(s) left out by the window rule: a stamp damaged so far that it lies \
                 outside its own window's reach (its times and {:.0} periods either side) is not \
                 re-timed from its neighbours, as a whole read does, but left out",
                super::logs::MARGIN_PERIODS
            ),
            Note::TimeRepairs { what, repairs } => {
                f.write_str(&repairs.said(*what).unwrap_or_default())
            }
            Note::TimeJumps {
                named,
                count,
                rate_hz,
            } => f.write_str(&jumps_text(named, *count, *rate_hz)),
            _ => Ok(()),
        }
    }

    /// What a long log's over-budget note advises: the option that keeps more, if any.
    fn fmt_budget_advice(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Note::LongLogOverBudget {
            needed,
            option,
            spelling,
            ..
        } = self
        else {
            return Ok(());
        };
        let max_rows = super::import::MAX_ROWS;
        match option {
            None => f.write_str("the most one analysis takes"),
            Some(o) if *needed <= max_rows => {
                write!(f, "give {} to keep them", spelling.given(*o, needed))
            }
            Some(o) => write!(
                f,
                "at most {max_rows} can be kept ({}), about 200 bytes of memory each",
                spelling.given(*o, max_rows)
            ),
        }
    }
}
