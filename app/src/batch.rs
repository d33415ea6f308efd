//! A production lot: every session of a directory calibrated in parallel (rayon, one session per
//! task), one summary row per unit (each parameter with its 1σ — the accelerometer's, the gyro's and
//! the temperature model's — χ², pass/fail against the limits), the units whose parameters are
//! outliers of the lot flagged, and units that claim the same unit id failed.
//!
//! Outliers: for each parameter, the robust z-score `z = (x − median) / s` over the units that
//! calibrated, with `s = max(1.4826·MAD, median of the units' own 1σ)` (the MAD scale of Iglewicz and
//! Hoaglin, 1993, never below the measurement's own uncertainty: a small lot of nearly identical units
//! has a MAD that can fall far below the noise by chance). A unit with `|z|` above the limit on any
//! parameter is flagged. Lots of fewer than `MIN_LOT` units are not screened; a value with no 1σ
//! (a lever-arm component or gyro entry the plan did not determine, a temperature coefficient above
//! the degree the data chose) is not screened unless the parameter has no 1σ in any unit (χ²/dof),
//! and parameters with no spread and no 1σ are skipped.
//!
//! Units: a bias in volts and one in m/s² are not one population. A lot that mixes output units is
//! screened within each output unit (a group below `MIN_LOT` is not screened) and says so; each
//! summary row names its unit.

use crate::{CalibrateOptions, CalibrationDocument};
use estimator::calibration_files::now_unix_s;
use estimator::estimate::{median, EstimateOptions};
use indicatif::ProgressBar;
use outputs::summary::{all_parameter_keys, CalibrationSummary, Limits};
use rayon::prelude::*;
use recording::session::{ReadOptions, PLAN_FILE};
use serde::{Deserialize, Serialize};
use shared::{OutputUnit, UnitId};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Most worker threads `host batch --jobs` starts (a lot never uses more than it has sessions).
pub const MAX_JOBS: usize = 256;

/// Fewest calibrated units for the outlier screening.
pub(crate) const MIN_LOT: usize = 5;

/// How to run a lot.
#[derive(Clone, Debug)]
pub struct BatchOptions {
    /// The estimator's options.
    pub estimate: EstimateOptions,
    /// Pass/fail limits of each unit.
    pub limits: Limits,
    /// Robust z-score above which a parameter is an outlier of the lot.
    pub outlier_z: f64,
    /// Worker threads (`None`: one per core); never more than there are sessions.
    pub jobs: Option<usize>,
}

/// One unit of the lot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UnitResult {
    /// Session directory name.
    pub session: String,
    /// Rows read.
    pub rows: u64,
    /// The calibration's result, as `host calibrate --input --json` gives it; `None` when it
    /// failed (see `error`).
    pub summary: Option<CalibrationDocument>,
    /// Why the unit could not be calibrated.
    pub error: Option<String>,
    /// Parameters on which the unit is an outlier of the lot, with their robust z-score.
    pub outliers: Vec<(String, f64)>,
    /// The other sessions of the lot whose unit id is this unit's (a mislabelled or repeated unit).
    #[serde(default)]
    pub same_unit_id_as: Vec<String>,
    /// Calibrated, within the limits, not an outlier and its unit id not claimed twice.
    pub passed: bool,
}

impl UnitResult {
    /// The output unit of the unit's calibration (its biases' unit), when it calibrated.
    pub fn output_unit(&self) -> Option<OutputUnit> {
        let file = self.calibration()?.calibration.as_ref()?;
        Some(file.output_unit.unwrap_or(OutputUnit::Volts))
    }

    /// The calibration's summary (parameters, 1σ, checks), when the unit calibrated.
    pub fn calibration(&self) -> Option<&CalibrationSummary> {
        self.summary.as_ref().map(|d| &d.summary)
    }

    /// Why the unit did not pass, every reason in one line (empty when it passed).
    pub fn why_failed(&self) -> String {
        let mut why = Vec::new();
        if let Some(e) = &self.error {
            why.push(e.clone());
        }
        if let Some(s) = self.calibration().filter(|s| !s.passed) {
            why.push(s.failures());
        }
        if !self.outliers.is_empty() {
            let o: Vec<String> = self
                .outliers
                .iter()
                .map(|(n, z)| format!("{n} z = {z:.1}"))
                .collect();
            why.push(format!("outlier of the lot: {}", o.join(", ")));
        }
        if !self.same_unit_id_as.is_empty() {
            why.push(format!(
                "unit id {} is also the unit of {}: each unit is calibrated once per lot; check the \
                 sessions' plan.toml unit_id",
                self.calibration()
                    .and_then(|s| s.unit_id.as_deref())
                    .unwrap_or("?"),
                self.same_unit_id_as.join(", ")
            ));
        }
        why.join("; ")
    }
}

/// The lot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LotSummary {
    /// Per unit, in session-name order.
    pub units: Vec<UnitResult>,
    /// Rows read in all.
    pub rows: u64,
    /// Wall time, s.
    pub seconds: f64,
    /// Worker threads used.
    pub threads: usize,
    /// The outlier limit used.
    pub outlier_z: f64,
    /// What the reader must know about the lot as a whole (a mix of output units).
    #[serde(default)]
    pub warnings: Vec<String>,
}

impl LotSummary {
    /// Units that did not pass.
    pub fn failed(&self) -> Vec<&UnitResult> {
        self.units.iter().filter(|u| !u.passed).collect()
    }
}

/// Why a lot could not be run at all.
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    /// The input directory cannot be listed.
    #[error("cannot list {}", .0.display())]
    Io(PathBuf, #[source] std::io::Error),
    /// It holds no session.
    #[error(
        "{} holds no session directory (a subdirectory with {PLAN_FILE} and samples.csv)",
        .0.display()
    )]
    NoSessions(PathBuf),
    /// The thread pool could not start.
    #[error("cannot start the worker threads")]
    Threads(#[source] rayon::ThreadPoolBuildError),
}

/// The session directories directly under `dir`, sorted by name.
pub fn find_sessions(dir: &Path) -> Result<Vec<PathBuf>, BatchError> {
    let io = |e| BatchError::Io(dir.to_path_buf(), e);
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.join(PLAN_FILE).is_file())
        .collect();
    v.sort();
    if v.is_empty() {
        return Err(BatchError::NoSessions(dir.to_path_buf()));
    }
    Ok(v)
}

fn calibrate_one(dir: &Path, out: &Path, opts: &BatchOptions) -> UnitResult {
    let session = dir.file_name().map_or_else(
        || dir.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let mut r = UnitResult {
        session: session.clone(),
        rows: 0,
        summary: None,
        error: None,
        outliers: Vec::new(),
        same_unit_id_as: Vec::new(),
        passed: false,
    };
    let out_dir = out.join(&session);
    let options = CalibrateOptions {
        estimate: opts.estimate.clone(),
        limits: opts.limits,
    };
    // The one calibrate use case, as `host calibrate` on a recording; the unit's error is kept as its
    // message in the lot's summary (a row of summary.csv and summary.json).
    match crate::calibrate_session_dir(dir, &options, &ReadOptions { quiet: true }) {
        Err(e) => r.error = Some(shared::chain::Chain(&e).to_string()),
        Ok((s, mut calibrated)) => {
            r.rows = s.report.rows;
            match crate::write_result(&out_dir, &mut calibrated, now_unix_s(), false) {
                Ok(_) => r.summary = Some(calibrated.document),
                Err(e) => r.error = Some(shared::chain::Chain(&e).to_string()),
            }
        }
    }
    r
}

/// Flags the outliers of the lot (see the module documentation) and the units whose id another
/// session claims too, and sets `passed`.
pub(crate) fn flag_outliers(units: &mut [UnitResult], z_limit: f64) -> Vec<String> {
    let mut groups: Vec<(Option<OutputUnit>, usize)> = Vec::new();
    for unit in units
        .iter()
        .filter(|u| u.calibration().is_some())
        .map(UnitResult::output_unit)
    {
        match groups.iter_mut().find(|(u, _)| *u == unit) {
            Some((_, n)) => *n += 1,
            None => groups.push((unit, 1)),
        }
    }
    for (unit, _) in &groups {
        flag_outliers_of(units, z_limit, *unit);
    }
    flag_same_unit_ids(units);
    for u in units.iter_mut() {
        u.passed = u.calibration().is_some_and(|s| s.passed)
            && u.outliers.is_empty()
            && u.same_unit_id_as.is_empty();
    }
    if groups.len() < 2 {
        // A lot too small to screen leaves every outlier cell empty: say why.
        return groups
            .first()
            .filter(|(_, n)| *n < MIN_LOT)
            .map(|(_, n)| {
                format!(
                    "no unit is screened for outliers: the lot has {n} calibrated unit(s), fewer \
                     than the {MIN_LOT} a robust spread needs, so the outliers column is empty"
                )
            })
            .into_iter()
            .collect();
    }
    let counts: Vec<String> = groups
        .iter()
        .map(|(u, n)| format!("{n} in {}", u.map_or("an unknown unit", OutputUnit::symbol)))
        .collect();
    vec![format!(
        "the lot mixes output units ({}): each unit is screened against the units of its own \
         output unit only (fewer than {MIN_LOT} are not screened); check that every session is of \
         this lot",
        counts.join(", ")
    )]
}

/// [`flag_outliers`] among the units whose output unit is `unit` (`None`: a summary without its
/// calibration file).
fn flag_outliers_of(units: &mut [UnitResult], z_limit: f64, unit: Option<OutputUnit>) {
    let mut names = all_parameter_keys();
    for p in units.iter().filter_map(UnitResult::calibration) {
        for q in &p.parameters {
            if !names.contains(&q.name) {
                names.push(q.name.clone());
            }
        }
    }
    // `None`: χ²/dof (no 1σ of its own).
    for name in names.iter().map(Some).chain([None]) {
        let value = |u: &UnitResult| -> Option<(f64, Option<f64>)> {
            if u.output_unit() != unit {
                return None;
            }
            let s = u.calibration()?;
            let (v, sigma) = match name {
                None => (s.chi2_per_dof, None),
                Some(n) => {
                    let p = s.parameters.iter().find(|p| &p.name == n)?;
                    (p.value, p.sigma)
                }
            };
            v.is_finite().then_some((v, sigma))
        };
        let any_sigma = units.iter().filter_map(value).any(|p| p.1.is_some());
        // A value without its 1σ (not determined, not in the model) is not screened.
        let screened = |u: &UnitResult| value(u).filter(|p| !any_sigma || p.1.is_some());
        let pairs: Vec<(f64, Option<f64>)> = units.iter().filter_map(screened).collect();
        let Some((m, scale)) = robust_centre_and_scale(&pairs) else {
            continue;
        };
        for u in units.iter_mut() {
            let Some((x, _)) = screened(u) else { continue };
            let z = (x - m) / scale;
            if z.abs() > z_limit {
                let label = name.map_or_else(|| "chi2_per_dof".to_string(), Clone::clone);
                u.outliers.push((label, z));
            }
        }
    }
}

/// The median and the scale `max(1.4826·MAD, median 1σ)` of a parameter's values and 1σ; `None`
/// for fewer than [`MIN_LOT`] values or no spread and no 1σ.
fn robust_centre_and_scale(pairs: &[(f64, Option<f64>)]) -> Option<(f64, f64)> {
    if pairs.len() < MIN_LOT {
        return None;
    }
    let xs: Vec<f64> = pairs.iter().map(|p| p.0).collect();
    let m = median(xs.clone());
    let dev: Vec<f64> = xs.iter().map(|x| (x - m).abs()).collect();
    let mad_scale = 1.4826 * median(dev);
    let sigmas: Vec<f64> = pairs
        .iter()
        .filter_map(|p| p.1)
        .filter(|s| s.is_finite())
        .collect();
    let sigma = if sigmas.is_empty() {
        0.0
    } else {
        median(sigmas)
    };
    let scale = mad_scale.max(sigma);
    (scale > 0.0).then_some((m, scale))
}

/// Records, on each unit, the other sessions whose calibration has its unit id (an absent or
/// all-zero id, a session recorded without one, matches nothing).
fn flag_same_unit_ids(units: &mut [UnitResult]) {
    let id = |u: &UnitResult| {
        u.calibration()
            .and_then(|s| s.unit_id.as_deref())
            .and_then(UnitId::parse_hex)
            .filter(|id| *id != UnitId::default())
    };
    let ids: Vec<(Option<UnitId>, String)> =
        units.iter().map(|u| (id(u), u.session.clone())).collect();
    for (k, u) in units.iter_mut().enumerate() {
        let Some(mine) = ids[k].0 else { continue };
        u.same_unit_id_as = ids
            .iter()
            .enumerate()
            .filter(|(j, (other, _))| *j != k && *other == Some(mine))
            .map(|(_, (_, session))| session.clone())
            .collect();
    }
}

/// Calibrates every session in `sessions` into `out/<session name>/`, in parallel.
pub fn run_batch(
    sessions: &[PathBuf],
    out: &Path,
    opts: &BatchOptions,
    bar: &ProgressBar,
) -> Result<LotSummary, BatchError> {
    // One thread per session at most: more would only wait (and each one costs a stack).
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    let threads = opts.jobs.unwrap_or(cores).clamp(1, sessions.len().max(1));
    let builder = rayon::ThreadPoolBuilder::new().num_threads(threads);
    let pool = builder.build().map_err(BatchError::Threads)?;
    bar.set_length(sessions.len() as u64);
    let started = Instant::now();
    let mut units: Vec<UnitResult> = pool.install(|| {
        sessions
            .par_iter()
            .map(|dir| {
                let r = calibrate_one(dir, out, opts);
                bar.inc(1);
                r
            })
            .collect()
    });
    let seconds = started.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let warnings = flag_outliers(&mut units, opts.outlier_z);
    // A unit that did not pass keeps its files under names that say so (README, "Output and exit
    // status"); one that could not be renamed says why.
    for u in units
        .iter_mut()
        .filter(|u| !u.passed && u.summary.is_some())
    {
        let dir = out.join(&u.session);
        if let Some(Err(e)) = u
            .summary
            .as_mut()
            .map(|d| crate::calibrate::mark_failed(d, &dir, false))
        {
            u.error = Some(shared::chain::Chain(&e).to_string());
        }
    }
    Ok(LotSummary {
        rows: units.iter().map(|u| u.rows).sum(),
        units,
        seconds,
        threads: pool.current_num_threads(),
        outlier_z: opts.outlier_z,
        warnings,
    })
}

/// A CSV cell: quoted when it holds a comma, a quote or a line end.
fn csv_cell(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// The lot as CSV: one row per unit, every parameter ([`all_parameter_keys`]: the accelerometer's,
/// the gyro's, the temperature model's) and its 1σ, the temperature model's reference and range and
/// its fit's worst χ²/dof (the figure the verdict checks, docs/model.md §9); a unit without a gyro
/// or a temperature model leaves those cells empty.
pub fn to_csv(lot: &LotSummary) -> String {
    let keys = all_parameter_keys();
    let mut header: Vec<String> = [
        "session",
        "unit_id",
        "output_unit",
        "passed",
        "within_limits",
        "outliers",
        "same_unit_id_as",
        "chi2",
        "dof",
        "chi2_per_dof",
        "thermal_chi2_per_dof",
    ]
    .map(String::from)
    .into();
    for k in &keys {
        header.push(k.clone());
        header.push(format!("{k}_sigma"));
    }
    header.extend(
        [
            "temp_reference_c",
            "temp_valid_min_c",
            "temp_valid_max_c",
            "error",
        ]
        .map(String::from),
    );
    let mut s = header.join(",") + "\n";
    let num = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:e}"));
    for u in &lot.units {
        let outl: Vec<String> = u
            .outliers
            .iter()
            .map(|(n, z)| format!("{n}(z={z:.1})"))
            .collect();
        let sm = u.calibration();
        let mut row = vec![
            csv_cell(&u.session),
            sm.and_then(|m| m.unit_id.clone()).unwrap_or_default(),
            u.output_unit().map_or("", OutputUnit::symbol).to_string(),
            u.passed.to_string(),
            sm.is_some_and(|m| m.passed).to_string(),
            csv_cell(&outl.join(" ")),
            csv_cell(&u.same_unit_id_as.join(" ")),
            num(sm.map(|m| m.chi2)),
            sm.map_or(String::new(), |m| m.dof.to_string()),
            num(sm.map(|m| m.chi2_per_dof)),
            num(sm
                .and_then(|m| m.thermal_fit.as_ref())
                .map(|t| t.worst_chi2_per_dof)),
        ];
        for k in &keys {
            let p = sm.and_then(|m| m.parameters.iter().find(|p| &p.name == k));
            row.push(num(p.map(|p| p.value)));
            row.push(num(p.and_then(|p| p.sigma)));
        }
        let t = sm.and_then(|m| m.temperature.as_ref());
        row.push(num(t.map(|t| t.reference_c)));
        row.push(num(t.map(|t| t.valid_range_c[0])));
        row.push(num(t.map(|t| t.valid_range_c[1])));
        row.push(csv_cell(u.error.as_deref().unwrap_or_default()));
        s += &(row.join(",") + "\n");
    }
    s
}

#[cfg(test)]
mod tests;
