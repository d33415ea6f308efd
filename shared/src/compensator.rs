//! Per-sample compensation: the inverse model of `docs/model.md` §3 (paper eq. 16–17).
//!
//! Built once from a [`Calibration`] (settings → precomputed state → one call per sample, as in x-io
//! Fusion): every square root, trigonometric function and division happens in [`Compensator::new`],
//! in `f64`, and the per-sample call is straight-line `f32` multiply-adds with no branch on data.
//!
//! Per sample, with `k_i d_i = ω̇·p_i + (a_i·ω)(q_i·ω) − |ω|² s_i` (`docs/model.md` §10):
//!
//! ```text
//! f_O = g·K_A · (U − u0 − K d)          K_A = (K A)⁻¹, the exact inverse (never a transpose)
//! ```
//!
//! Operation count of [`Compensator::compensate`]: `U − u0` 3 subtractions; `|ω|²` 3; per axis
//! `ω̇·p_i` 3, `a_i·ω` 3, `q_i·ω` 3, two products and one subtraction, and the subtraction from `U − u0`
//! (12 per axis, 36); `K_A·v` 9. Total 51 multiply-adds (48 fused-multiply-add-able), against the ~50 of
//! `docs/model.md` §10. The static-only path [`Compensator::compensate_static`] is 12.

use crate::linalg::{self, RowMajor3};
use crate::params::{Calibration, ParamsError};
use crate::units::{BodyAngularAccel, BodyRate, BodySpecificForce, SensorOutputs};

/// Which lever-arm terms the per-sample path applies (`docs/model.md` §6: the ω̇ term must be switchable).
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    postcard::experimental::max_size::MaxSize,
)]
pub enum LeverMode {
    /// Static compensation only (no gyro needed).
    Off,
    /// Centripetal and cross terms from ω; the tangential ω̇ term off (the paper's eq. 17 with ω̇ = 0).
    RateOnly,
    /// All terms, with ω̇ from a filtered estimator.
    RateAndAcceleration,
}

/// Why a calibration cannot be turned into a compensator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CompensatorError {
    /// The parameters themselves are unusable.
    Params(ParamsError),
    /// `K·A` is singular or too badly conditioned to invert (1-norm condition number given).
    IllConditioned {
        /// ‖M‖₁‖M⁻¹‖₁ (infinite when singular).
        condition: f64,
    },
    /// The gravity value is not a plausible local gravity (m/s²).
    Gravity,
}

impl core::fmt::Display for CompensatorError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            CompensatorError::Params(e) => e.fmt(f),
            CompensatorError::IllConditioned { condition } => write!(
                f,
                "K·A is singular or ill-conditioned (condition number {condition:.3e}, limit {MAX_CONDITION:.0})"
            ),
            CompensatorError::Gravity => write!(
                f,
                "local gravity outside {MIN_GRAVITY_M_S2}..{MAX_GRAVITY_M_S2} m/s²"
            ),
        }
    }
}

/// Largest accepted 1-norm condition number of `K·A`. A near-orthogonal unit has about 1.1; 100 means
/// sensing axes within a few degrees of each other, which no usable unit has.
pub const MAX_CONDITION: f64 = 100.0;
/// Plausible local gravity range, m/s² (Earth's surface spans 9.76..9.84).
pub const MIN_GRAVITY_M_S2: f64 = 9.7;
/// See [`MIN_GRAVITY_M_S2`].
pub const MAX_GRAVITY_M_S2: f64 = 9.9;

/// Precomputed state of the inverse model. `f32` throughout, fixed size, `Copy`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Compensator {
    /// `u0`, output unit.
    zero_bias_out: [f32; 3],
    /// `g·(K A)⁻¹`, m/s² per output unit, row-major.
    ka_m_s2_per_out: [[f32; 3]; 3],
    /// `a_i`, unit sensing directions.
    a: [[f32; 3]; 3],
    /// `p_i = k_i (r_i × a_i)/g`, output unit per rad/s².
    p: [[f32; 3]; 3],
    /// `q_i = k_i r_i / g`, output unit per (rad/s)² per unit of `a_i·ω`.
    q: [[f32; 3]; 3],
    /// `s_i = k_i (a_i·r_i)/g`, output unit per (rad/s)².
    s: [f32; 3],
    mode: LeverMode,
}

/// A copy of a [`Compensator`]'s precomputed constants (see its fields for the meaning of each).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompensatorConstants {
    /// `u0`, output unit.
    pub zero_bias_out: [f32; 3],
    /// `g·(K A)⁻¹`, m/s² per output unit, row-major.
    pub ka_m_s2_per_out: [[f32; 3]; 3],
    /// `a_i`, unit sensing directions.
    pub a: [[f32; 3]; 3],
    /// `p_i = k_i (r_i × a_i)/g`, zero unless the ω̇ term is on.
    pub p: [[f32; 3]; 3],
    /// `q_i = k_i r_i / g`, zero when the lever terms are off.
    pub q: [[f32; 3]; 3],
    /// `s_i = k_i (a_i·r_i)/g`, zero when the lever terms are off.
    pub s: [f32; 3],
}

impl Compensator {
    /// Precomputes the inverse model. Fails on unusable parameters instead of producing NaN later.
    pub fn new(cal: &Calibration, mode: LeverMode) -> Result<Compensator, CompensatorError> {
        let g = cal.gravity_m_s2;
        if !(MIN_GRAVITY_M_S2..=MAX_GRAVITY_M_S2).contains(&g) {
            return Err(CompensatorError::Gravity);
        }
        let (fitted, _) = cal.statics.to_fitted().map_err(CompensatorError::Params)?;
        let (k, a) = fitted.decompose().map_err(CompensatorError::Params)?;
        if !cal.lever_arms.r_m.iter().flatten().all(|v| v.is_finite()) {
            return Err(CompensatorError::Params(ParamsError::NonFinite));
        }
        let condition = linalg::condition_number_1(&fitted.m_out_per_g);
        let inv = match linalg::inverse(&fitted.m_out_per_g) {
            Some(inv) if condition <= MAX_CONDITION => inv,
            _ => return Err(CompensatorError::IllConditioned { condition }),
        };
        let lever_on = mode != LeverMode::Off;
        let tangential_on = mode == LeverMode::RateAndAcceleration;
        let r = &cal.lever_arms.r_m;
        let scale = |i: usize, on: bool| if on { k[i] / g } else { 0.0 };
        let p: RowMajor3 = core::array::from_fn(|i| {
            linalg::cross(&r[i], &a[i]).map(|v| v * scale(i, tangential_on))
        });
        let q: RowMajor3 = core::array::from_fn(|i| r[i].map(|v| v * scale(i, lever_on)));
        let s: [f64; 3] = core::array::from_fn(|i| linalg::dot(&a[i], &r[i]) * scale(i, lever_on));
        let to32 = |m: &RowMajor3| m.map(|row| row.map(|v| v as f32));
        Ok(Compensator {
            zero_bias_out: fitted.zero_bias_out.map(|v| v as f32),
            ka_m_s2_per_out: to32(&inv.map(|row| row.map(|v| v * g))),
            a: to32(&a),
            p: to32(&p),
            q: to32(&q),
            s: s.map(|v| v as f32),
            mode,
        })
    }

    /// The lever-arm mode this compensator was built with.
    pub fn mode(&self) -> LeverMode {
        self.mode
    }

    /// Specific force at the reference point from outputs, gyro rate and angular acceleration
    /// (paper eq. 16). With [`LeverMode::Off`] the gyro inputs have no effect (their constants are 0).
    #[inline]
    pub fn compensate(
        &self,
        u: &SensorOutputs,
        omega: &BodyRate,
        omega_dot: &BodyAngularAccel,
    ) -> BodySpecificForce {
        let w = &omega.rad_s;
        let wd = &omega_dot.rad_s2;
        let w2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
        let v: [f32; 3] = core::array::from_fn(|i| {
            let p = &self.p[i];
            let q = &self.q[i];
            let a = &self.a[i];
            let tangential = wd[0] * p[0] + wd[1] * p[1] + wd[2] * p[2];
            let a_w = a[0] * w[0] + a[1] * w[1] + a[2] * w[2];
            let q_w = q[0] * w[0] + q[1] * w[1] + q[2] * w[2];
            let k_d = tangential + a_w * q_w - w2 * self.s[i];
            u.raw[i] - self.zero_bias_out[i] - k_d
        });
        self.apply_ka(&v)
    }

    /// Static-only compensation, `f_O = g·K_A (U − u0)` (paper eq. 6): no gyro needed.
    #[inline]
    pub fn compensate_static(&self, u: &SensorOutputs) -> BodySpecificForce {
        let v: [f32; 3] = core::array::from_fn(|i| u.raw[i] - self.zero_bias_out[i]);
        self.apply_ka(&v)
    }

    /// The precomputed `f32` constants, for code generators that reproduce this per-sample path in
    /// another language (the host's C export) and must hold exactly these values.
    pub fn constants(&self) -> CompensatorConstants {
        CompensatorConstants {
            zero_bias_out: self.zero_bias_out,
            ka_m_s2_per_out: self.ka_m_s2_per_out,
            a: self.a,
            p: self.p,
            q: self.q,
            s: self.s,
        }
    }

    #[inline(always)]
    fn apply_ka(&self, v: &[f32; 3]) -> BodySpecificForce {
        let m = &self.ka_m_s2_per_out;
        BodySpecificForce {
            m_s2: core::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forward::{BodyMotion, ForwardModel, TableState};
    use crate::params::tests::{expected, paper_unit};
    use crate::params::{LeverArms, OutputUnit, ReferencePoint, StaticParams};
    use proptest::prelude::*;

    fn f32_inputs(
        u: &SensorOutputs<f64>,
        m: &BodyMotion,
    ) -> (SensorOutputs, BodyRate, BodyAngularAccel) {
        (
            SensorOutputs {
                raw: u.raw.map(|v| v as f32),
            },
            BodyRate {
                rad_s: m.omega.rad_s.map(|v| v as f32),
            },
            BodyAngularAccel {
                rad_s2: m.omega_dot.rad_s2.map(|v| v as f32),
            },
        )
    }

    /// Independent f64 reference of the inverse model: solve `(K A) f = U − u0 − K d` by LU, with
    /// `d_i = a_i·W r_i` straight from eq. 11 (no precomputed constants).
    fn reference_inverse(cal: &Calibration, u: &SensorOutputs<f64>, m: &BodyMotion) -> [f64; 3] {
        let (fitted, _) = cal.statics.to_fitted().unwrap();
        let (k, a) = fitted.decompose().unwrap();
        let w = linalg::lever_matrix(&m.omega.rad_s, &m.omega_dot.rad_s2);
        let g = cal.gravity_m_s2;
        let rhs = nalgebra::Vector3::from_fn(|i, _| {
            let d = linalg::dot(&a[i], &linalg::mat_vec(&w, &cal.lever_arms.r_m[i])) / g;
            u.raw[i] - fitted.zero_bias_out[i] - k[i] * d
        });
        let f = linalg::to_na(&fitted.m_out_per_g).lu().solve(&rhs).unwrap();
        [f[0] * g, f[1] * g, f[2] * g]
    }

    #[test]
    fn k_a_and_nabla_b_match_the_reference_values() {
        let cal = paper_unit();
        let e = expected();
        let (fitted, _) = cal.statics.to_fitted().unwrap();
        let ka = linalg::inverse(&fitted.m_out_per_g).unwrap();
        let nabla = linalg::mat_vec(&ka, &fitted.zero_bias_out);
        for i in 0..3 {
            for j in 0..3 {
                assert!(
                    (ka[i][j] - e.k_a_g_per_v[i][j]).abs() < 1e-7,
                    "K_A[{i}][{j}]"
                );
            }
            assert!((nabla[i] - e.nabla_b_g[i]).abs() < 1e-7, "nabla_b[{i}]");
        }
        // And the f32 compensator holds g·K_A.
        let c = Compensator::new(&cal, LeverMode::Off).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let want = e.k_a_g_per_v[i][j] * cal.gravity_m_s2;
                assert!(
                    (f64::from(c.ka_m_s2_per_out[i][j]) - want).abs() < 2e-6 * want.abs().max(1.0)
                );
            }
        }
    }

    fn spin_error_mg(rate_deg_s: f64) -> [f64; 3] {
        let cal = paper_unit();
        let model = ForwardModel::new(&cal).unwrap();
        let mut t = TableState::at_rest([1.0, 0.0, 0.0]);
        t.rate_rad_s = rate_deg_s.to_radians();
        let motion = t.motion(cal.gravity_m_s2);
        let u = model.outputs(&motion);
        let c = Compensator::new(&cal, LeverMode::Off).unwrap();
        let (u32_, _, _) = f32_inputs(&u, &motion);
        let f = c.compensate_static(&u32_).to_f64();
        core::array::from_fn(|j| (f.m_s2[j] - motion.f_o.m_s2[j]).abs() / cal.gravity_m_s2 * 1e3)
    }

    #[test]
    fn static_only_spin_errors_match_the_reference() {
        let e = expected();
        for (rate, want) in [
            (100.0, e.x_up_spin_error_mg_100dps),
            (200.0, e.x_up_spin_error_mg_200dps),
        ] {
            let got = spin_error_mg(rate);
            for j in 0..3 {
                // The reference values are printed to 1 µg (0.001 mg); f32 adds < 1 µg.
                assert!(
                    (got[j] - want[j]).abs() < 2e-3,
                    "{rate} °/s axis {j}: {got:?} vs {want:?}"
                );
            }
        }
    }

    #[test]
    fn full_compensation_removes_the_spin_error() {
        let cal = paper_unit();
        let model = ForwardModel::new(&cal).unwrap();
        let mut t = TableState::at_rest([1.0, 0.0, 0.0]);
        t.rate_rad_s = 200f64.to_radians();
        let motion = t.motion(cal.gravity_m_s2);
        let (u, w, wd) = f32_inputs(&model.outputs(&motion), &motion);
        let f = Compensator::new(&cal, LeverMode::RateOnly)
            .unwrap()
            .compensate(&u, &w, &wd);
        for j in 0..3 {
            // f32 of a 2.4 V output resolves ~0.3 µg; allow 2 µg.
            let err_g = (f64::from(f.m_s2[j]) - motion.f_o.m_s2[j]) / cal.gravity_m_s2;
            assert!(err_g.abs() < 2e-6, "axis {j}: {err_g}");
        }
    }

    #[test]
    fn mode_off_ignores_the_gyro_and_rate_only_ignores_omega_dot() {
        let cal = paper_unit();
        let u = SensorOutputs {
            raw: [2.8, 2.4, 2.4],
        };
        let w = BodyRate {
            rad_s: [3.0, -1.0, 0.5],
        };
        let wd = BodyAngularAccel {
            rad_s2: [40.0, 10.0, -20.0],
        };
        let off = Compensator::new(&cal, LeverMode::Off).unwrap();
        assert_eq!(off.compensate(&u, &w, &wd), off.compensate_static(&u));
        let rate = Compensator::new(&cal, LeverMode::RateOnly).unwrap();
        assert_eq!(
            rate.compensate(&u, &w, &wd),
            rate.compensate(&u, &w, &BodyAngularAccel::default())
        );
        let full = Compensator::new(&cal, LeverMode::RateAndAcceleration).unwrap();
        assert_ne!(full.compensate(&u, &w, &wd), rate.compensate(&u, &w, &wd));
    }

    #[test]
    fn unusable_calibrations_are_refused() {
        let mut cal = paper_unit();
        cal.gravity_m_s2 = f64::NAN;
        assert_eq!(
            Compensator::new(&cal, LeverMode::Off).unwrap_err(),
            CompensatorError::Gravity
        );
        let mut cal = paper_unit();
        cal.statics.installation_angles_deg[1] = cal.statics.installation_angles_deg[0];
        assert!(matches!(
            Compensator::new(&cal, LeverMode::Off).unwrap_err(),
            CompensatorError::IllConditioned { .. }
        ));
        let mut cal = paper_unit();
        cal.lever_arms.r_m[2][1] = f64::INFINITY;
        assert!(matches!(
            Compensator::new(&cal, LeverMode::RateOnly),
            Err(CompensatorError::Params(_))
        ));
    }

    /// A random but plausible unit: biases, scales in V/g or LSB/g, axes tilted up to 3°, lever arms up
    /// to 3 cm.
    pub(crate) fn arb_unit() -> impl Strategy<Value = Calibration> {
        let lsb = any::<bool>();
        (
            lsb,
            prop::array::uniform3(-1.0f64..1.0),
            prop::array::uniform3(0.8f64..1.25),
            prop::array::uniform3(prop::array::uniform3(-3.0f64..3.0)),
            prop::array::uniform3(prop::array::uniform3(-0.03f64..0.03)),
            9.78f64..9.83,
        )
            .prop_map(|(lsb, bias, scale, tilt, r, g)| {
                let (unit, k0, u00) = if lsb {
                    (OutputUnit::Lsb, 4096.0, 0.0)
                } else {
                    (OutputUnit::Volts, 0.4, 2.5)
                };
                let k0_bias = if lsb { 200.0 } else { 0.1 };
                let angles = core::array::from_fn(|i| {
                    core::array::from_fn(|j| if i == j { 0.0 } else { 90.0 + tilt[i][j] })
                });
                // Make the rows consistent unit vectors: build them from cosines, then read angles back.
                let statics = StaticParams {
                    output_unit: unit,
                    zero_bias_out: bias.map(|b| u00 + b * k0_bias),
                    scale_out_per_g: scale.map(|s| s * k0),
                    installation_angles_deg: angles,
                };
                let statics = statics.to_fitted().unwrap().0.to_paper().unwrap();
                Calibration {
                    statics,
                    lever_arms: LeverArms { r_m: r },
                    reference: ReferencePoint::TableAxis,
                    gravity_m_s2: g,
                }
            })
    }

    /// Random motion: any specific force up to 3 g, rates up to 600 °/s, ω̇ up to 50 rad/s².
    fn arb_motion() -> impl Strategy<Value = BodyMotion> {
        (
            prop::array::uniform3(-30.0f64..30.0),
            prop::array::uniform3(-10.5f64..10.5),
            prop::array::uniform3(-50.0f64..50.0),
        )
            .prop_map(|(f, w, wd)| BodyMotion {
                f_o: BodySpecificForce { m_s2: f },
                omega: BodyRate { rad_s: w },
                omega_dot: BodyAngularAccel { rad_s2: wd },
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

        /// Forward model then f32 compensation returns the motion's specific force.
        ///
        /// Bound: the f32 path rounds each output to 2⁻²⁴ relative. For outputs up to |U| ≈ 3 V
        /// (or 2¹⁵ LSB) and ~60 operations, the error stays below 4·10⁻⁶ of the full-scale specific force
        /// (30 m/s² plus the lever term ω²r ≈ 3.3 m/s²); we assert 2·10⁻⁴ m/s² (20 µg).
        #[test]
        fn forward_then_f32_inverse_round_trips(cal in arb_unit(), motion in arb_motion()) {
            let model = ForwardModel::new(&cal).unwrap();
            let u = model.outputs(&motion);
            let (u32_, w, wd) = f32_inputs(&u, &motion);
            let f = Compensator::new(&cal, LeverMode::RateAndAcceleration).unwrap().compensate(&u32_, &w, &wd);
            for j in 0..3 {
                let err = (f64::from(f.m_s2[j]) - motion.f_o.m_s2[j]).abs();
                prop_assert!(err < 2e-4, "axis {} err {} m/s²", j, err);
            }
        }

        /// The f32 compensator against the independent f64 reference on the same (f32-representable)
        /// inputs: same bound as above, so the precomputed cheap form is the same model as eq. 16.
        #[test]
        fn f32_matches_f64_reference(cal in arb_unit(), motion in arb_motion()) {
            let model = ForwardModel::new(&cal).unwrap();
            let u = model.outputs(&motion);
            let (u32_, w, wd) = f32_inputs(&u, &motion);
            let u_rounded = SensorOutputs { raw: u32_.raw.map(f64::from) };
            let m_rounded = BodyMotion {
                f_o: motion.f_o,
                omega: BodyRate { rad_s: w.rad_s.map(f64::from) },
                omega_dot: BodyAngularAccel { rad_s2: wd.rad_s2.map(f64::from) },
            };
            let want = reference_inverse(&cal, &u_rounded, &m_rounded);
            let got = Compensator::new(&cal, LeverMode::RateAndAcceleration).unwrap().compensate(&u32_, &w, &wd);
            for j in 0..3 {
                prop_assert!((f64::from(got.m_s2[j]) - want[j]).abs() < 2e-4);
            }
        }
    }
}
