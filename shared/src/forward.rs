//! The forward model: what an accelerometer unit outputs for a given motion (paper eq. 11–15,
//! `docs/model.md` §2). Every simulator (the host's virtual unit, the firmware's virtual
//! sensor, the tests) uses this one implementation.

use crate::linalg::{self, RowMajor3};
use crate::params::{Calibration, FittedStatic, LeverArms, ParamsError};
use crate::units::{BodyAngularAccel, BodyRate, BodySpecificForce, SensorOutputs};

/// The motion of the body at one instant, at the reference point O.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyMotion {
    /// Specific force at O.
    pub f_o: BodySpecificForce<f64>,
    /// Angular rate.
    pub omega: BodyRate<f64>,
    /// Angular acceleration.
    pub omega_dot: BodyAngularAccel<f64>,
}

/// The state of a single-axis rate table carrying the unit, seen in body axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableState {
    /// Direction of "up" (of the +1 g specific force at rest) in body axes; unit vector.
    pub up_b: [f64; 3],
    /// Table rate about the vertical, rad/s, signed (positive = right-handed about `up_b`).
    pub rate_rad_s: f64,
    /// Table angular acceleration about the vertical, rad/s².
    pub accel_rad_s2: f64,
    /// Position of the table's spin axis point P relative to O, body axes, metres (`docs/model.md` §4.5).
    pub centre_m: [f64; 3],
}

impl TableState {
    /// At rest with `up_b` up, spin axis through O.
    pub fn at_rest(up_b: [f64; 3]) -> TableState {
        TableState {
            up_b,
            rate_rad_s: 0.0,
            accel_rad_s2: 0.0,
            centre_m: [0.0; 3],
        }
    }

    /// The body's motion at O. The spin axis is the vertical, so gravity is constant in body axes;
    /// O moves on a circle about P: `f_O = g·up − W p` with `W = [ω̇×] + [ω×]²` (paper eq. 10–11).
    pub fn motion(&self, gravity_m_s2: f64) -> BodyMotion {
        let omega = self.up_b.map(|u| u * self.rate_rad_s);
        let omega_dot = self.up_b.map(|u| u * self.accel_rad_s2);
        let w_p = linalg::mat_vec(&linalg::lever_matrix(&omega, &omega_dot), &self.centre_m);
        BodyMotion {
            f_o: BodySpecificForce {
                m_s2: core::array::from_fn(|j| gravity_m_s2 * self.up_b[j] - w_p[j]),
            },
            omega: BodyRate { rad_s: omega },
            omega_dot: BodyAngularAccel { rad_s2: omega_dot },
        }
    }
}

/// A unit's forward model: `u_i = row_i(M)·(f_O + W r_i)/g + u_i0` (paper eq. 13 with `M = K·A`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForwardModel {
    /// `M = K·A`, output unit per g.
    pub m_out_per_g: RowMajor3,
    /// Zero-bias outputs.
    pub zero_bias_out: [f64; 3],
    /// Lever arms relative to O, metres.
    pub lever_arms: LeverArms,
    /// g used to convert m/s² to g, m/s².
    pub gravity_m_s2: f64,
}

impl ForwardModel {
    /// The model of a calibrated unit (angles normalised as in [`crate::StaticParams::to_fitted`]).
    pub fn new(cal: &Calibration) -> Result<ForwardModel, ParamsError> {
        let (fitted, _) = cal.statics.to_fitted()?;
        Ok(ForwardModel::from_fitted(
            &fitted,
            cal.lever_arms,
            cal.gravity_m_s2,
        ))
    }

    /// The model from the fitted form.
    pub fn from_fitted(fitted: &FittedStatic, lever_arms: LeverArms, gravity_m_s2: f64) -> Self {
        ForwardModel {
            m_out_per_g: fitted.m_out_per_g,
            zero_bias_out: fitted.zero_bias_out,
            lever_arms,
            gravity_m_s2,
        }
    }

    /// Noise-free outputs for a motion.
    pub fn outputs(&self, motion: &BodyMotion) -> SensorOutputs<f64> {
        let w = linalg::lever_matrix(&motion.omega.rad_s, &motion.omega_dot.rad_s2);
        let raw = core::array::from_fn(|i| {
            let w_r = linalg::mat_vec(&w, &self.lever_arms.r_m[i]);
            let f_i: [f64; 3] = core::array::from_fn(|j| motion.f_o.m_s2[j] + w_r[j]);
            linalg::dot(&self.m_out_per_g[i], &f_i) / self.gravity_m_s2 + self.zero_bias_out[i]
        });
        SensorOutputs { raw }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::tests::{expected, paper_unit};

    #[test]
    fn x_up_bias_and_scale_only_matches_table2_before() {
        // Remove only bias and scale (no misalignment) from the x-up outputs: paper Table 2 "before".
        let cal = paper_unit();
        let model = ForwardModel::new(&cal).unwrap();
        let u = model.outputs(&TableState::at_rest([1.0, 0.0, 0.0]).motion(cal.gravity_m_s2));
        let want = expected().x_up_bias_scale_only_g;
        for i in 0..3 {
            let got = (u.raw[i] - cal.statics.zero_bias_out[i]) / cal.statics.scale_out_per_g[i];
            assert!(
                (got - want[i]).abs() < 1e-6,
                "axis {i}: {got} vs {}",
                want[i]
            );
        }
        // Table 2's printed y and z before compensation: 0.01299 and −0.00911 g.
        let y = (u.raw[1] - cal.statics.zero_bias_out[1]) / cal.statics.scale_out_per_g[1];
        let z = (u.raw[2] - cal.statics.zero_bias_out[2]) / cal.statics.scale_out_per_g[2];
        assert!((y - 0.01299).abs() < 1e-5 && (z + 0.00911).abs() < 1e-5);
    }

    #[test]
    fn table_centre_offset_moves_the_centripetal_term() {
        // Spinning about z through P = (0.1, 0, 0) m: O circles P, so its centripetal acceleration
        // ω²·0.1 = 0.4 m/s² points from O to P (+x); specific force = that acceleration + g·up.
        let t = TableState {
            up_b: [0.0, 0.0, 1.0],
            rate_rad_s: 2.0,
            accel_rad_s2: 0.0,
            centre_m: [0.1, 0.0, 0.0],
        };
        let m = t.motion(9.8);
        assert!((m.f_o.m_s2[0] - 0.4).abs() < 1e-12);
        assert!(m.f_o.m_s2[1].abs() < 1e-12);
        assert!((m.f_o.m_s2[2] - 9.8).abs() < 1e-12);
        assert_eq!(m.omega.rad_s, [0.0, 0.0, 2.0]);
    }
}
