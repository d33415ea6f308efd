//! Kalibr's noise figures (`imu.yaml`) from an Allan analysis: each sensor's worst axis, from
//! `host noise`'s result, its `noise.json`, or the Python package's `allan()`.

use super::{NoiseError, NoiseReport};
use crate::export::kalibr::KalibrNoise;
use std::path::Path;

/// One axis's white noise density N and random walk K (`None`: not determined).
pub type WhiteAndWalk = (Option<f64>, Option<f64>);

/// Kalibr's figures from the six axes' white noise density N and random walk K, in [`AXES`](super::AXES) order
/// (accelerometer in m/s², gyro in rad/s): each sensor's worst axis, undetermined where any of its
/// axes is; the accelerometer's are undetermined unless `accel_in_m_s2`. `host noise` and the
/// Python package's `export(noise=allan(…))` both take their figures from here.
pub fn kalibr_figures(
    rate_hz: f64,
    white_and_walk: &[WhiteAndWalk; 6],
    accel_in_m_s2: bool,
) -> KalibrNoise {
    let worst = |r: std::ops::Range<usize>, f: fn(&WhiteAndWalk) -> Option<f64>| {
        let v: Option<Vec<f64>> = white_and_walk[r].iter().map(f).collect();
        v.map(|v| v.into_iter().fold(0.0, f64::max))
    };
    KalibrNoise {
        update_rate_hz: Some(rate_hz),
        accelerometer_noise_density: worst(0..3, |t| t.0).filter(|_| accel_in_m_s2),
        accelerometer_random_walk: worst(0..3, |t| t.1).filter(|_| accel_in_m_s2),
        gyroscope_noise_density: worst(3..6, |t| t.0),
        gyroscope_random_walk: worst(3..6, |t| t.1),
    }
}

/// Kalibr's figures from a `noise.json` written by `host noise`.
pub fn load_kalibr_noise(path: &Path) -> Result<KalibrNoise, NoiseError> {
    let text =
        recording::limits::read_text_bounded(path).map_err(|e| NoiseError::File(path.into(), e))?;
    let report: NoiseReport =
        serde_json::from_str(&text).map_err(|e| NoiseError::NotNoiseJson(path.into(), e))?;
    Ok(report.kalibr)
}
