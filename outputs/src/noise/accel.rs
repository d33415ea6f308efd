//! The accelerometer's outputs in m/s² for the noise analysis: through a calibration
//! (`f = g·K_A·(U − u0)`, paper eq. 6), or as they are when the recording is already in m/s² or
//! g; otherwise they stay in the output unit, and a note says so.

use super::{NoiseError, Signals};
use crate::export::PlainMatrices;
use crate::note::Note;
use recording::spelling::Spelling;
use shared::OutputUnit;

/// Turns the accelerometer signals of `s` into m/s² where they can be (a calibration, or an input
/// already in m/s² or g); the unit they end in.
pub(super) fn accel_to_m_s2(
    s: &mut Signals,
    calibration: Option<&PlainMatrices>,
    spelling: Spelling,
    warnings: &mut Vec<Note>,
) -> Result<&'static str, NoiseError> {
    let n = s.data[0].len();
    Ok(match calibration {
        Some(pm) => {
            let g = pm.gravity_m_s2;
            let mut sum = [0.0; 3];
            for k in 0..n {
                let u = [s.data[0][k], s.data[1][k], s.data[2][k]];
                let f = shared::linalg::mat_vec(&pm.k_a_g_per_out, &u);
                for j in 0..3 {
                    s.data[j][k] = (f[j] - pm.nabla_b_g[j]) * g;
                    sum[j] += s.data[j][k];
                }
            }
            // The physical check: a still recording is at 1 g (docs/robustness.md).
            let f_g = shared::linalg::norm(&sum.map(|v| v / n as f64)) / g;
            if f_g.is_nan() || (f_g - 1.0).abs() > crate::apply::MAX_STILL_G_ERROR {
                return Err(NoiseError::NotOneG { f_g });
            }
            "m/s^2"
        }
        // An input already in m/s² (or g) needs no calibration for Kalibr's figures: they are
        // its own noise, and a calibration's scale errors change them by parts per thousand.
        None => match s.acc_unit.and_then(metres_per_second_squared_per) {
            Some(k) => {
                for axis in s.data.iter_mut().take(3) {
                    axis.iter_mut().for_each(|v| *v *= k);
                }
                "m/s^2"
            }
            None => {
                warnings.push(Note::NoiseUncalibrated { spelling });
                "output unit"
            }
        },
    })
}

/// m/s² per unit of an output that has a physical unit (m/s², g); `None` for volts and counts.
fn metres_per_second_squared_per(unit: OutputUnit) -> Option<f64> {
    match unit {
        OutputUnit::MetresPerSecondSquared => Some(1.0),
        OutputUnit::StandardGravity => Some(shared::STANDARD_GRAVITY_M_S2),
        _ => None,
    }
}
