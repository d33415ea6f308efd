//! What `host segment` presents besides its table: the `--json` document and the figure of the
//! recording with the still intervals marked.

use super::SegmentArgs;
use super::SegmentOutcome;
use outputs::report::plot::{Figure, Panel, Series, SeriesStyle};
use recording::session::coverage::Coverage;
use recording::session::import::Recording;
use recording::session::plan::Attitude;
use recording::session::segment::{IntervalKind, Segmentation};
use serde::Serialize;
use shared::chain::Chain;
use shared::linalg;

/// What was written and said besides the intervals and the fit, for the JSON document.
pub(super) struct Written {
    pub(super) rows: u64,
    pub(super) advice: Option<String>,
    pub(super) warnings: Vec<String>,
    pub(super) six_faces: bool,
}

/// The `--json` document of `host segment`.
#[derive(Serialize)]
pub(super) struct SegmentDocument {
    input: String,
    sample_rate_hz: f64,
    /// The accelerometer's unit (the calibration's output unit): `acc_noise` is in it.
    acc_unit: &'static str,
    /// The gyro unit of the input; the document's rates are in rad/s and °/s as named.
    gyro_unit: &'static str,
    /// |mean accelerometer output| at rest, acc_unit.
    gravity_out: f64,
    acc_threshold_mg: f64,
    gyro_threshold_deg_s: f64,
    still_intervals: usize,
    spins: usize,
    short_dropped: usize,
    distinct_positions: usize,
    /// The positions were taken as the six faces of a cube (nominal ups with a prior).
    six_face_session: bool,
    /// Counts subtracted from each accelerometer axis on reading (added back in the session).
    acc_offset: [f64; 3],
    /// The time column's unit ("s", "ms", "µs", "ns"; null: from --rate-hz) and whether detected.
    time_unit: Option<&'static str>,
    time_unit_detected: bool,
    intervals: Vec<IntervalDocument>,
    /// Whole turns on the table found between still intervals at the same position (used or not;
    /// the refused ones are in `warnings`).
    table_turns_found: usize,
    gyro: Option<GyroDocument>,
    gyro_not_calibrated: Option<String>,
    advice: Option<String>,
    warnings: Vec<String>,
    out_dir: String,
    rows_written: u64,
}

#[derive(Serialize)]
struct IntervalDocument {
    /// 1-based, as in the table.
    index: usize,
    kind: &'static str,
    start_s: f64,
    duration_s: f64,
    /// Rough up direction from the uncalibrated outputs (unit vector, body axes).
    mean_direction: [f64; 3],
    acc_noise_mg: f64,
    gyro_noise_deg_s: f64,
    /// Spins: the mean rate.
    rate_deg_s: Option<f64>,
    /// Still intervals: the earlier interval (1-based) at the same position.
    same_position_as: Option<usize>,
    /// Still intervals: the attitude given to the session's segment.
    attitude: Option<AttitudeDocument>,
}

/// `free` (no prior, docs/model.md §7) or `axis` (set down on a face: `up_b` with a prior).
#[derive(Serialize)]
struct AttitudeDocument {
    segment: String,
    kind: &'static str,
    up_b: [f64; 3],
    prior_1sigma_deg: Option<f64>,
}

/// The gyro fit; a `null` 1σ is an entry the turns do not determine.
#[derive(Serialize)]
struct GyroDocument {
    turns: usize,
    rms_residual_deg: f64,
    /// Whole turns on the table used as known angles (docs/model.md §7.2).
    table_turns: usize,
    table_rms_residual_deg: f64,
    matrix: [[f64; 3]; 3],
    matrix_1sigma: [[f64; 3]; 3],
    bias_rad_s: [f64; 3],
    bias_rad_s_1sigma: [f64; 3],
    undetermined: Vec<String>,
}

pub(super) fn document(
    a: &SegmentArgs,
    gyro_unit: &'static str,
    o: &SegmentOutcome,
    cov: &Coverage,
    w: &Written,
) -> SegmentDocument {
    let (rec, seg) = (&o.recording, &o.segmentation);
    let intervals = seg
        .stills
        .iter()
        .chain(&seg.spins)
        .enumerate()
        .map(|(k, iv)| {
            let sp = o.plan.segments.get(k).filter(|_| k < seg.stills.len());
            IntervalDocument {
                index: k + 1,
                kind: match iv.kind {
                    IntervalKind::Still => "static",
                    IntervalKind::Spin => "spin",
                },
                start_s: iv.start_s,
                duration_s: iv.duration_s,
                mean_direction: iv.direction,
                acc_noise_mg: linalg::norm(&iv.std_acc) / seg.gravity_out * 1e3,
                gyro_noise_deg_s: linalg::norm(&iv.std_gyro_rad_s).to_degrees(),
                rate_deg_s: (iv.kind == IntervalKind::Spin)
                    .then(|| linalg::norm(&iv.mean_gyro_rad_s).to_degrees()),
                same_position_as: cov.repeats.get(k).copied().flatten().map(|r| r + 1),
                attitude: sp.map(|sp| AttitudeDocument {
                    segment: sp.name.clone(),
                    kind: match sp.attitude {
                        Attitude::Free => "free",
                        Attitude::Fixture | Attitude::Face => "axis",
                    },
                    up_b: sp.up_b,
                    prior_1sigma_deg: sp.attitude_sigma_deg,
                }),
            }
        })
        .collect();
    SegmentDocument {
        input: a.input.display().to_string(),
        sample_rate_hz: rec.rate_hz,
        acc_unit: rec.acc_unit.map_or("", |u| u.symbol()),
        gyro_unit,
        gravity_out: seg.gravity_out,
        acc_threshold_mg: seg.acc_threshold / seg.gravity_out * 1e3,
        gyro_threshold_deg_s: seg.gyro_threshold_rad_s.to_degrees(),
        still_intervals: seg.stills.len(),
        spins: seg.spins.len(),
        short_dropped: seg.short_dropped,
        distinct_positions: cov.distinct,
        six_face_session: w.six_faces,
        acc_offset: rec.acc_offset,
        time_unit: rec.time_unit.map(|u| u.0.symbol()),
        time_unit_detected: rec.time_unit.is_some_and(|u| u.1),
        intervals,
        table_turns_found: o.table_turns.len(),
        gyro: o.gyro.as_ref().ok().map(|f| GyroDocument {
            turns: f.turns,
            rms_residual_deg: f.rms_residual_deg,
            table_turns: f.table_turns,
            table_rms_residual_deg: f.table_rms_residual_deg,
            matrix: f.matrix,
            matrix_1sigma: f.matrix_1sigma,
            bias_rad_s: f.bias_rad_s,
            bias_rad_s_1sigma: f.bias_1sigma_rad_s,
            undetermined: f.undetermined(),
        }),
        gyro_not_calibrated: o.gyro.as_ref().err().map(|e| Chain(e).to_string()),
        advice: w.advice.clone(),
        warnings: w.warnings.clone(),
        out_dir: a.out.display().to_string(),
        rows_written: w.rows,
    }
}

/// The recording (|acc| and |gyro|) with the still intervals marked.
pub(super) fn figure(rec: &Recording, seg: &Segmentation) -> Figure {
    let step = (rec.len() / 4000).max(1);
    let series = |label: &str, f: &dyn Fn(usize) -> f64, colour| Series {
        label: label.into(),
        points: (0..rec.len())
            .step_by(step)
            .map(|i| (rec.t_s[i], f(i)))
            .collect(),
        error: None,
        style: SeriesStyle::Line,
        colour,
    };
    let marks = |y: f64| Series {
        label: "still intervals".into(),
        points: seg
            .stills
            .iter()
            .flat_map(|iv| {
                (iv.start..iv.end)
                    .step_by(step.max(10))
                    .map(move |i| (i, y))
            })
            .map(|(i, y)| (rec.t_s[i], y))
            .collect(),
        error: None,
        style: SeriesStyle::Markers,
        colour: 4,
    };
    let unit = rec.acc_unit.map_or("", |u| u.symbol());
    let g = seg.gravity_out;
    Figure {
        stem: "segments".into(),
        title: "Recording and the still intervals found".into(),
        grid: (2, 1),
        size: (1400, 900),
        panels: vec![
            Panel {
                title: "accelerometer magnitude".into(),
                x_desc: "t (s)".into(),
                y_desc: format!("|a| ({unit})"),
                x_categories: None,
                log_x: false,
                log_y: false,
                series: vec![
                    series("|a|", &|i| linalg::norm(&rec.acc[i]), 2),
                    marks(g * 1.05),
                ],
            },
            Panel {
                title: "gyro magnitude".into(),
                x_desc: "t (s)".into(),
                y_desc: "|w| (°/s)".into(),
                x_categories: None,
                log_x: false,
                log_y: false,
                series: vec![
                    series("|w|", &|i| linalg::norm(&rec.gyro_rad_s[i]).to_degrees(), 0),
                    marks(0.0),
                ],
            },
        ],
    }
}
