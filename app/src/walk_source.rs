//! The bias random walks taken from the unit's own noise figures ([`UserOption::BiasWalkFrom`],
//! docs/model.md §11.3): the Allan K of `host noise`'s `noise.json`, or a unit file's `[noise]`
//! `accel_bias_walk_mg_sqrt_s`. The accelerometers' walk must be there; the gyro's is taken too
//! where the file holds it (the gyro axes' K, or `gyro_bias_walk_deg_s_sqrt_s` or
//! `gyro_bias_walk_per_axis_deg_s_sqrt_s`; §11.6), as one strength for the three axes: the rms of
//! theirs.
//!
//! Units: the fit wants the walk per axis either in mg/√s (turned into output units with the fitted
//! scale factors) or in output unit/√s as it is. A unit file's `[noise]` is mg/√s already. A
//! `noise.json` holds K in its axes' `unit` per √s: `m/s^2` (a recording in m/s² or g, or one analysed
//! with a calibration) becomes mg/√s as `K / g₀ · 10³` with g₀ the standard gravity (a local g
//! differs by at most 0.3 %, far inside K's own uncertainty); `output unit` (V or LSB, no
//! calibration) is taken as it is, with the output unit the file records (`output_unit`), which
//! the fit checks against the session's; a file that records none is refused.

use estimator::estimate::UnitWalk;
use estimator::sim::{NoiseModel, SimulateError};
use estimator::unit_file::{UnitFile, UnitFileError};
use outputs::noise::{NoiseReport, AXES};
use recording::spelling::{Spelling, UserOption};
use std::path::{Path, PathBuf};

/// Why the walk could not be taken from the file.
#[derive(Debug, thiserror::Error)]
pub enum WalkSourceError {
    /// The file could not be read.
    #[error("{} {}", .spelling.name(UserOption::BiasWalkFrom), .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The caller's names of the options.
        spelling: Spelling,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A `.json` file that is not `host noise`'s `noise.json`. serde_json's reason is said in
    /// parentheses inside the message, so it is shown there and not also returned as `source()`.
    #[error(
        "{} {}: not a noise.json of `host noise` ({})",
        .spelling.name(UserOption::BiasWalkFrom),
        .path.display(),
        shared::chain::Chain(.cause)
    )]
    Json {
        /// The file.
        path: PathBuf,
        /// The caller's names of the options.
        spelling: Spelling,
        /// Why.
        cause: serde_json::Error,
    },
    /// A unit file that cannot be read.
    #[error(transparent)]
    Unit(#[from] UnitFileError),
    /// A unit file whose `[noise]` table is not the simulator's noise model.
    #[error("{} {}", .spelling.name(UserOption::BiasWalkFrom), .path.display())]
    Noise {
        /// The file.
        path: PathBuf,
        /// The caller's names of the options.
        spelling: Spelling,
        /// Why.
        #[source]
        source: SimulateError,
    },
    /// The file holds no accelerometer bias random walk.
    #[error(
        "{} {}: the file holds no accelerometer bias random walk ({what}); measure it with `host \
         noise {} {}` on a still recording (hours long for a walk to show) and give \
         DIR/noise.json, or give the walk in mg/√s with {}",
        .spelling.name(UserOption::BiasWalkFrom),
        .path.display(),
        .spelling.given(UserOption::Input, "STILL"),
        .spelling.given(UserOption::Out, "DIR"),
        .spelling.name(UserOption::BiasWalk)
    )]
    NoWalk {
        /// The file.
        path: PathBuf,
        /// The caller's names of the options.
        spelling: Spelling,
        /// What is missing.
        what: String,
    },
    /// A walk in raw outputs whose output unit the file does not record.
    #[error(
        "{} {}: its accelerometer figures are in the output unit of the recording analysed, and \
         the file does not say which (V, LSB, …; a bare samples.csv states none, and an older \
         `host noise` did not record it): run `host noise` again on the session directory or the \
         logger's file (or with {}, for figures in m/s²)",
        .spelling.name(UserOption::BiasWalkFrom),
        .path.display(),
        .spelling.name(UserOption::Calibration)
    )]
    UnknownUnit {
        /// The file.
        path: PathBuf,
        /// The caller's names of the options.
        spelling: Spelling,
    },
}

impl WalkSourceError {
    /// Whether the file was read but says nothing usable about the walk: a usage error (exit 2).
    pub fn is_usage(&self) -> bool {
        matches!(
            self,
            WalkSourceError::NoWalk { .. } | WalkSourceError::UnknownUnit { .. }
        )
    }
}

/// The walks a file gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FileWalks {
    /// The accelerometers' walk, per axis.
    pub accel: UnitWalk,
    /// The gyro's walk, °/s/√s, where the file holds one for all three axes.
    pub gyro_deg_s_sqrt_s: Option<f64>,
}

/// The walks from `path`: a `noise.json` (by its `.json` name) or a unit file; a refusal names the
/// options as `spelling` does.
pub fn walk_from_file(path: &Path, spelling: Spelling) -> Result<FileWalks, WalkSourceError> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
    {
        let text = std::fs::read_to_string(path).map_err(|source| WalkSourceError::Io {
            path: path.into(),
            spelling,
            source,
        })?;
        let report: NoiseReport =
            serde_json::from_str(&text).map_err(|source| WalkSourceError::Json {
                path: path.into(),
                spelling,
                cause: source,
            })?;
        return Ok(FileWalks {
            accel: walk_from_noise(&report, path, spelling)?,
            gyro_deg_s_sqrt_s: gyro_walk_from_noise(&report),
        });
    }
    let unit = UnitFile::load(path)?;
    let noise = NoiseModel::from_unit_file(&unit).map_err(|source| WalkSourceError::Noise {
        path: path.into(),
        spelling,
        source,
    })?;
    match noise {
        Some(n) if n.accel_bias_walk_mg_sqrt_s > 0.0 => Ok(FileWalks {
            accel: UnitWalk::MgSqrtS([n.accel_bias_walk_mg_sqrt_s; 3]),
            gyro_deg_s_sqrt_s: Some(n.gyro_bias_walk_one()).filter(|&k| k > 0.0),
        }),
        Some(_) => Err(WalkSourceError::NoWalk {
            path: path.into(),
            spelling,
            what: "its [noise] table has no accel_bias_walk_mg_sqrt_s above 0".into(),
        }),
        None => Err(WalkSourceError::NoWalk {
            path: path.into(),
            spelling,
            what: "it has no [noise] table".into(),
        }),
    }
}

/// The gyro axes' Allan K of `host noise` (rad/s/√s) as one strength in °/s/√s, the rms of the
/// three; none unless all three are determined.
fn gyro_walk_from_noise(r: &NoiseReport) -> Option<f64> {
    let mut sum_sq = 0.0;
    for name in &AXES[3..] {
        let axis = r
            .axes
            .iter()
            .find(|x| x.axis == *name && x.unit == "rad/s")?;
        let k = axis
            .terms
            .random_walk
            .filter(|k| k.is_finite() && *k > 0.0)?;
        sum_sq += k * k;
    }
    Some((sum_sq / 3.0).sqrt().to_degrees())
}

/// The accelerometer axes' Allan K of `host noise`, in the unit the fit takes (module docs).
pub(crate) fn walk_from_noise(
    r: &NoiseReport,
    path: &Path,
    spelling: Spelling,
) -> Result<UnitWalk, WalkSourceError> {
    let no_walk = |what: String| WalkSourceError::NoWalk {
        path: path.into(),
        spelling,
        what,
    };
    let mut k = [0.0; 3];
    let mut unit = None;
    for (a, name) in AXES.iter().take(3).enumerate() {
        let axis = r
            .axes
            .iter()
            .find(|x| x.axis == *name)
            .ok_or_else(|| no_walk(format!("no {name} axis")))?;
        k[a] = match axis.terms.random_walk {
            Some(v) if v.is_finite() && v > 0.0 => v,
            _ => {
                let needs = axis.terms.fits[2]
                    .needs_recording_s
                    .map_or(String::new(), |s| {
                        format!(", at least {s:.0} s of still recording would")
                    });
                return Err(no_walk(format!(
                    "{name}'s random walk K is not determined by that recording{needs}"
                )));
            }
        };
        if unit.is_some_and(|u: &str| u != axis.unit) {
            return Err(no_walk(
                "the accelerometer axes are in different units".into(),
            ));
        }
        unit = Some(axis.unit.as_str());
    }
    match unit {
        Some("m/s^2") => Ok(UnitWalk::MgSqrtS(
            k.map(|k| k / shared::STANDARD_GRAVITY_M_S2 * 1e3),
        )),
        Some("output unit") => match r.output_unit {
            Some(u) => Ok(UnitWalk::OutputPerSqrtS(k, u)),
            None => Err(WalkSourceError::UnknownUnit {
                path: path.into(),
                spelling,
            }),
        },
        other => Err(no_walk(format!(
            "its accelerometer unit {other:?} is neither m/s^2 nor the output unit"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use outputs::noise::allan::{NoiseTerms, TermFit};
    use outputs::noise::AxisNoise;
    use recording::testkit::SPELLING;

    fn report(unit: &str, k: [Option<f64>; 3]) -> NoiseReport {
        with_gyro(unit, k, [None; 3])
    }

    /// A report whose accelerometer axes have K `k` (in `unit`) and gyro axes `gyro` (rad/s/√s).
    fn with_gyro(unit: &str, k: [Option<f64>; 3], gyro: [Option<f64>; 3]) -> NoiseReport {
        let axes = AXES
            .iter()
            .enumerate()
            .map(|(j, name)| AxisNoise {
                axis: (*name).into(),
                unit: if j < 3 { unit.into() } else { "rad/s".into() },
                points: Vec::new(),
                terms: NoiseTerms {
                    white_density: Some(1e-3),
                    bias_instability: None,
                    random_walk: if j < 3 { k[j] } else { gyro[j - 3] },
                    fits: [
                        TermFit::default(),
                        TermFit::default(),
                        TermFit {
                            needs_recording_s: Some(7200.0),
                            ..TermFit::default()
                        },
                    ],
                    curve: None,
                },
            })
            .collect();
        NoiseReport {
            source: "still".into(),
            segment: "still".into(),
            sample_rate_hz: 200.0,
            samples: 1000,
            axes,
            kalibr: Default::default(),
            warnings: Vec::new(),
            output_unit: Some(shared::OutputUnit::Volts),
        }
    }

    /// By hand: K = 9.80665·10⁻⁵ m/s²/√s is 10⁻⁵ g/√s, 0.01 mg/√s; 1.961 33·10⁻⁵ m/s²/√s is
    /// 2·10⁻⁶ g/√s, 0.002 mg/√s. An Allan K of the raw outputs (V/√s) is taken as it is.
    #[test]
    fn an_allan_k_is_turned_into_mg_by_hand() {
        let p = Path::new("noise.json");
        let r = report(
            "m/s^2",
            [Some(9.80665e-5), Some(1.96133e-5), Some(9.80665e-6)],
        );
        let UnitWalk::MgSqrtS(mg) = walk_from_noise(&r, p, SPELLING).unwrap() else {
            panic!("not in mg")
        };
        for (got, want) in mg.iter().zip([0.01, 0.002, 0.001]) {
            assert!((got - want).abs() < 1e-15, "{mg:?}");
        }
        let raw = report("output unit", [Some(4e-6), Some(5e-6), Some(6e-6)]);
        assert_eq!(
            walk_from_noise(&raw, p, SPELLING).unwrap(),
            UnitWalk::OutputPerSqrtS([4e-6, 5e-6, 6e-6], shared::OutputUnit::Volts)
        );
    }

    /// A walk in raw outputs carries the output unit the file records; a file that records none
    /// (an older noise.json) is refused as a usage error naming the file.
    #[test]
    fn a_raw_output_walk_carries_its_unit_or_is_refused() {
        let p = Path::new("noise.json");
        let mut raw = report("output unit", [Some(8.2); 3]);
        raw.output_unit = Some(shared::OutputUnit::Lsb);
        assert_eq!(
            walk_from_noise(&raw, p, SPELLING).unwrap(),
            UnitWalk::OutputPerSqrtS([8.2; 3], shared::OutputUnit::Lsb)
        );
        raw.output_unit = None;
        let e = walk_from_noise(&raw, p, SPELLING).unwrap_err();
        assert!(e.is_usage() && e.to_string().contains("noise.json"), "{e}");
        // A noise.json without the field reads as one that records none.
        let mut v = serde_json::to_value(report("output unit", [Some(8.2); 3])).unwrap();
        v.as_object_mut().unwrap().remove("output_unit");
        let old: NoiseReport = serde_json::from_value(v).unwrap();
        assert_eq!(old.output_unit, None);
    }

    /// An axis whose K the recording did not determine refuses, naming the axis, how long a
    /// recording would determine it, and `host noise`.
    #[test]
    fn an_undetermined_k_is_refused() {
        let r = report("m/s^2", [Some(1e-5), None, Some(1e-5)]);
        let e = walk_from_noise(&r, Path::new("noise.json"), SPELLING).unwrap_err();
        assert!(e.is_usage());
        let m = e.to_string();
        assert!(
            m.contains("accel_y") && m.contains("7200 s") && m.contains("host noise"),
            "{m}"
        );
    }

    /// The file itself: a noise.json written as `host noise` writes it, and a unit file's `[noise]`.
    #[test]
    fn the_walk_is_read_from_either_file() {
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("noise.json");
        let r = report("m/s^2", [Some(9.80665e-5); 3]);
        std::fs::write(&json, serde_json::to_string_pretty(&r).unwrap()).unwrap();
        let walks = walk_from_file(&json, SPELLING).unwrap();
        assert_eq!(walks.accel, UnitWalk::MgSqrtS([0.01; 3]));
        assert_eq!(walks.gyro_deg_s_sqrt_s, None);
        let unit = dir.path().join("unit.toml");
        let text = format!(
            "{}\n[noise]\naccel_bias_walk_mg_sqrt_s = 0.003\n",
            estimator::unit_file::PAPER_UNIT_TOML
        );
        std::fs::write(&unit, text).unwrap();
        let walks = walk_from_file(&unit, SPELLING).unwrap();
        assert_eq!(walks.accel, UnitWalk::MgSqrtS([0.003; 3]));
        assert_eq!(walks.gyro_deg_s_sqrt_s, None);
        // A unit file's gyro walk comes with it.
        let text = format!(
            "{}\n[noise]\naccel_bias_walk_mg_sqrt_s = 0.003\ngyro_bias_walk_deg_s_sqrt_s = 0.0004\n",
            estimator::unit_file::PAPER_UNIT_TOML
        );
        std::fs::write(&unit, text).unwrap();
        assert_eq!(
            walk_from_file(&unit, SPELLING).unwrap().gyro_deg_s_sqrt_s,
            Some(0.0004)
        );
        // Per axis, their rms: 1, 2 and 2 ·10⁻⁴ give √3·10⁻⁴ (by hand).
        let text = format!(
            "{}\n[noise]\naccel_bias_walk_mg_sqrt_s = 0.003\n\
             gyro_bias_walk_per_axis_deg_s_sqrt_s = [0.0001, 0.0002, 0.0002]\n",
            estimator::unit_file::PAPER_UNIT_TOML
        );
        std::fs::write(&unit, text).unwrap();
        let got = walk_from_file(&unit, SPELLING)
            .unwrap()
            .gyro_deg_s_sqrt_s
            .unwrap();
        assert!((got - 1.7320508e-4).abs() < 1e-11, "{got}");
    }

    /// By hand: gyro K of 1, 2 and 2 ·10⁻⁵ rad/s/√s have the rms √(9/3)·10⁻⁵ = 1.732 05·10⁻⁵
    /// rad/s/√s, 9.9240·10⁻⁴ °/s/√s; one axis undetermined gives no gyro walk (the accelerometers'
    /// is still taken).
    #[test]
    fn the_gyro_axes_k_is_one_strength_in_degrees() {
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("noise.json");
        let r = with_gyro(
            "m/s^2",
            [Some(9.80665e-5); 3],
            [Some(1e-5), Some(2e-5), Some(2e-5)],
        );
        std::fs::write(&json, serde_json::to_string_pretty(&r).unwrap()).unwrap();
        let got = walk_from_file(&json, SPELLING)
            .unwrap()
            .gyro_deg_s_sqrt_s
            .unwrap();
        assert!((got - 9.9240e-4).abs() < 1e-7, "{got}");
        let r = with_gyro(
            "m/s^2",
            [Some(9.80665e-5); 3],
            [Some(1e-5), None, Some(2e-5)],
        );
        std::fs::write(&json, serde_json::to_string_pretty(&r).unwrap()).unwrap();
        let walks = walk_from_file(&json, SPELLING).unwrap();
        assert_eq!(
            (walks.accel, walks.gyro_deg_s_sqrt_s),
            (UnitWalk::MgSqrtS([0.01; 3]), None)
        );
    }
}
