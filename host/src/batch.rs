//! A production lot: every session of a directory calibrated in parallel (rayon, one session per
//! task), one summary row per unit (each parameter with its 1σ, χ², pass/fail against the limits), and
//! the units whose parameters are outliers of the lot flagged.
//!
//! Outliers: for each parameter, the robust z-score `z = (x − median) / s` over the units that
//! calibrated, with `s = max(1.4826·MAD, median of the units' own 1σ)` (the MAD scale of Iglewicz and
//! Hoaglin, 1993, never below the measurement's own uncertainty: a small lot of nearly identical units
//! has a MAD that can fall far below the noise by chance). A unit with `|z|` above the limit on any
//! parameter is flagged. Lots of fewer than [`MIN_LOT`] units are not screened; parameters with no
//! spread and no 1σ (a lever-arm component no plan determines) are skipped.

use crate::calibration_files::{now_unix_s, write_calibration_files, CALIBRATION_TOML};
use crate::estimate::{calibrate_session_stats, median, EstimateOptions};
use crate::session::{read_session, ReadOptions, PLAN_FILE};
use crate::summary::{CalibrationSummary, Limits};
use indicatif::ProgressBar;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use shared::UnitId;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Fewest calibrated units for the outlier screening.
pub const MIN_LOT: usize = 5;

/// How to run a lot.
#[derive(Clone, Debug)]
pub struct BatchOptions {
    /// The estimator's options.
    pub estimate: EstimateOptions,
    /// Pass/fail limits of each unit.
    pub limits: Limits,
    /// Robust z-score above which a parameter is an outlier of the lot.
    pub outlier_z: f64,
    /// Worker threads (`None`: one per core).
    pub jobs: Option<usize>,
    /// Replace existing calibration files in the output directory.
    pub force: bool,
}

/// One unit of the lot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UnitResult {
    /// Session directory name.
    pub session: String,
    /// Rows read.
    pub rows: u64,
    /// The calibration's summary; `None` when it failed (see `error`).
    pub summary: Option<CalibrationSummary>,
    /// Why the unit could not be calibrated.
    pub error: Option<String>,
    /// Parameters on which the unit is an outlier of the lot, with their robust z-score.
    pub outliers: Vec<(String, f64)>,
    /// Calibrated, within the limits, and not an outlier.
    pub passed: bool,
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
}

impl LotSummary {
    /// Units that did not pass.
    pub fn failed(&self) -> Vec<&UnitResult> {
        self.units.iter().filter(|u| !u.passed).collect()
    }
}

/// Why a lot could not be run at all.
#[derive(Debug)]
pub enum BatchError {
    /// The input directory cannot be listed.
    Io(PathBuf, std::io::Error),
    /// It holds no session.
    NoSessions(PathBuf),
    /// The thread pool could not start.
    Threads(String),
}

impl std::fmt::Display for BatchError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BatchError::Io(p, e) => write!(f, "cannot list {}: {e}", p.display()),
            BatchError::NoSessions(p) => write!(
                f,
                "{} holds no session directory (a subdirectory with {PLAN_FILE} and samples.csv)",
                p.display()
            ),
            BatchError::Threads(m) => write!(f, "cannot start the worker threads: {m}"),
        }
    }
}

impl std::error::Error for BatchError {}

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
        passed: false,
    };
    let out_dir = out.join(&session);
    if !opts.force && out_dir.join(CALIBRATION_TOML).exists() {
        r.error = Some(format!(
            "{} exists; allow overwriting with --force",
            out_dir.join(CALIBRATION_TOML).display()
        ));
        return r;
    }
    let result = (|| -> Result<CalibrationSummary, String> {
        let s = read_session(dir, &ReadOptions { quiet: true }).map_err(|e| e.to_string())?;
        r.rows = s.report.rows;
        let outcome = calibrate_session_stats(&s.plan, &s.stats, &opts.estimate)
            .map_err(|e| e.to_string())?;
        let unit = s.plan.unit_id.as_deref().and_then(UnitId::parse_hex);
        write_calibration_files(
            &out_dir,
            &outcome,
            unit.unwrap_or_default(),
            now_unix_s(),
            false,
        )
        .map_err(|e| e.to_string())?;
        Ok(CalibrationSummary::new(
            &outcome,
            s.plan.unit_id.clone(),
            &opts.limits,
        ))
    })();
    match result {
        Ok(s) => r.summary = Some(s),
        Err(e) => r.error = Some(e),
    }
    r
}

/// Flags the outliers of the lot (see the module documentation) and sets `passed`.
pub fn flag_outliers(units: &mut [UnitResult], z_limit: f64) {
    let n_params = units
        .iter()
        .find_map(|u| u.summary.as_ref())
        .map_or(0, |s| s.parameters.len());
    for k in 0..=n_params {
        // k == n_params: χ²/dof (no 1σ of its own).
        let value = |u: &UnitResult| -> Option<(f64, Option<f64>)> {
            let s = u.summary.as_ref()?;
            let (v, sigma) = if k == n_params {
                (s.chi2_per_dof, None)
            } else {
                let p = s.parameters.get(k)?;
                (p.value, p.sigma)
            };
            v.is_finite().then_some((v, sigma))
        };
        let pairs: Vec<(f64, Option<f64>)> = units.iter().filter_map(value).collect();
        if pairs.len() < MIN_LOT {
            continue;
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
        if scale <= 0.0 {
            continue;
        }
        for u in units.iter_mut() {
            let Some((x, _)) = value(u) else { continue };
            let z = (x - m) / scale;
            if z.abs() > z_limit {
                let name = match &u.summary {
                    Some(s) if k < n_params => s.parameters[k].name.clone(),
                    _ => "chi2_per_dof".into(),
                };
                u.outliers.push((name, z));
            }
        }
    }
    for u in units.iter_mut() {
        u.passed = u.summary.as_ref().is_some_and(|s| s.passed) && u.outliers.is_empty();
    }
}

/// Calibrates every session in `sessions` into `out/<session name>/`, in parallel.
pub fn run_batch(
    sessions: &[PathBuf],
    out: &Path,
    opts: &BatchOptions,
    bar: &ProgressBar,
) -> Result<LotSummary, BatchError> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(j) = opts.jobs {
        builder = builder.num_threads(j);
    }
    let pool = builder
        .build()
        .map_err(|e| BatchError::Threads(e.to_string()))?;
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
    flag_outliers(&mut units, opts.outlier_z);
    Ok(LotSummary {
        rows: units.iter().map(|u| u.rows).sum(),
        units,
        seconds,
        threads: pool.current_num_threads(),
        outlier_z: opts.outlier_z,
    })
}

/// The lot as CSV: one row per unit, each parameter and its 1σ.
pub fn to_csv(lot: &LotSummary) -> String {
    let keys = crate::summary::parameter_keys();
    let mut s = String::from("session,unit_id,passed,within_limits,outliers,chi2,dof,chi2_per_dof");
    for k in &keys {
        s += &format!(",{k},{k}_sigma");
    }
    s += ",error\n";
    for u in &lot.units {
        let outl: Vec<String> = u
            .outliers
            .iter()
            .map(|(n, z)| format!("{n}(z={z:.1})"))
            .collect();
        match &u.summary {
            Some(sm) => {
                s += &format!(
                    "{},{},{},{},{},{:e},{},{:e}",
                    u.session,
                    sm.unit_id.clone().unwrap_or_default(),
                    u.passed,
                    sm.passed,
                    outl.join(" "),
                    sm.chi2,
                    sm.dof,
                    sm.chi2_per_dof
                );
                for p in &sm.parameters {
                    s += &format!(
                        ",{:e},{}",
                        p.value,
                        p.sigma.map_or("".into(), |v| format!("{v:e}"))
                    );
                }
                s += ",\n";
            }
            None => {
                s += &format!("{},,false,false,,,,", u.session);
                s += &",".repeat(2 * keys.len());
                // Commas would split the message: it is the last column, quoted.
                s += &format!(
                    ",\"{}\"\n",
                    u.error.clone().unwrap_or_default().replace('"', "'")
                );
            }
        }
    }
    s
}

#[cfg(test)]
mod tests;
