//! The calibration parameters, in the paper's form and in the fitted form (`docs/model.md` §4.2).
//!
//! The paper's form is what people read and compare (Table 1: zero bias, scale factor, nine
//! installation angles; Table 3: lever arms). The fitted form `M = K·A` is what an estimator fits and
//! what the compensator inverts. The nine angles carry only six independent values, because each
//! sensing direction `a_i` is a unit vector; converting to the fitted form therefore normalises each
//! row and reports how far the input was from unit length.

use crate::linalg::{self, RowMajor3};
use crate::sensor_models::{GyroCorrection, TemperatureModel};
use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

/// What the accelerometer outputs are measured in. Files spell it "V", "LSB", "m/s2" or "g" (the names only matter
/// to self-describing formats: postcard encodes the variant's index).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum OutputUnit {
    /// Analog parts read by an ADC and converted to volts (the paper's MS9005.D).
    #[serde(rename = "V")]
    Volts,
    /// Raw counts of a digital part or of the ADC (least significant bits).
    #[serde(rename = "LSB")]
    Lsb,
    /// A logger's output already in m/s², kept as recorded so that bias and scale stay in the
    /// logger's unit (a hand-held recording imported by `host segment`). Appended: older blobs keep
    /// their variant indices.
    #[serde(rename = "m/s2")]
    MetresPerSecondSquared,
    /// A logger's output in g (standard gravity), kept as recorded.
    #[serde(rename = "g")]
    StandardGravity,
}

impl OutputUnit {
    /// Short unit name for reports and files ("V", "LSB", "m/s2" or "g").
    pub fn symbol(self) -> &'static str {
        match self {
            OutputUnit::Volts => "V",
            OutputUnit::Lsb => "LSB",
            OutputUnit::MetresPerSecondSquared => "m/s2",
            OutputUnit::StandardGravity => "g",
        }
    }
}

/// The static parameters in the paper's form (Table 1), one row per accelerometer `i = x, y, z`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StaticParams {
    /// Unit of the outputs, of the zero biases and of the scale factors' numerators.
    pub output_unit: OutputUnit,
    /// Zero-bias output `u_i0 = k_i·B_i`, in the output unit.
    pub zero_bias_out: [f64; 3],
    /// Scale factor `k_i`, output unit per g.
    pub scale_out_per_g: [f64; 3],
    /// `θ_ij`: angle between sensing axis `i` and body axis `j`, degrees (row-major).
    pub installation_angles_deg: RowMajor3,
}

/// The static parameters in the fitted form: `U = M f/g + u0` with `M = K·A` (`docs/model.md` §4.2).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FittedStatic {
    /// Unit of the outputs.
    pub output_unit: OutputUnit,
    /// `M = K·A`, row `i` = `k_i a_i`, output unit per g (row-major).
    pub m_out_per_g: RowMajor3,
    /// Zero-bias outputs `u0`, in the output unit.
    pub zero_bias_out: [f64; 3],
}

/// How far the rows of a direction-cosine matrix read from angles were from unit length
/// (`docs/model.md` §4.2: paper Table 1 row 2 has ‖a_2‖ = 1.0000483).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Normalisation {
    /// ‖(cos θ_i1, cos θ_i2, cos θ_i3)‖ before normalising, per accelerometer.
    pub row_norms: [f64; 3],
}

impl Normalisation {
    /// Largest |‖a_i‖ − 1| over the three rows.
    pub fn max_deviation(&self) -> f64 {
        self.row_norms
            .iter()
            .map(|n| libm::fabs(n - 1.0))
            .fold(0.0, f64::max)
    }

    /// True when the angles were inconsistent beyond rounding of their printed digits (1e-6):
    /// callers should warn the user that the diagonal angles will change on the way back.
    pub fn needs_warning(&self) -> bool {
        self.max_deviation() > 1e-6
    }
}

/// Why a set of parameters cannot be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamsError {
    /// A value is NaN or infinite.
    NonFinite,
    /// Accelerometer `axis` has a zero (or vanishing) scale factor or sensing direction.
    DegenerateAxis {
        /// 0 = x, 1 = y, 2 = z.
        axis: u8,
    },
    /// Accelerometer `axis` has an installation angle beyond ±`crate::trig::MAX_ANGLE_DEG`
    /// (about 2²⁰·90°), where the cosine is refused (`crate::trig::cos_moderate`); a real
    /// unit's angles lie in 0..180°.
    AngleOutOfRange {
        /// 0 = x, 1 = y, 2 = z.
        axis: u8,
    },
}

impl core::fmt::Display for ParamsError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ParamsError::NonFinite => write!(f, "a calibration value is NaN or infinite"),
            ParamsError::DegenerateAxis { axis } => write!(
                f,
                "accelerometer {} has a zero scale factor or sensing direction",
                axis_name(*axis as usize)
            ),
            ParamsError::AngleOutOfRange { axis } => write!(
                f,
                "accelerometer {} has an installation angle beyond ±{}°",
                axis_name(*axis as usize),
                crate::trig::MAX_ANGLE_DEG
            ),
        }
    }
}

/// Lets a host error name this one as its `source()`.
impl core::error::Error for ParamsError {}

/// "x", "y" or "z".
pub fn axis_name(i: usize) -> &'static str {
    ["x", "y", "z"].get(i).copied().unwrap_or("?")
}

fn all_finite(values: impl IntoIterator<Item = f64>) -> bool {
    values.into_iter().all(f64::is_finite)
}

impl StaticParams {
    /// Zero bias `B_i = u_i0 / k_i` in g (paper eq. 1).
    pub fn bias_g(&self) -> [f64; 3] {
        core::array::from_fn(|i| self.zero_bias_out[i] / self.scale_out_per_g[i])
    }

    /// The unit sensing directions `a_i` (rows of `A`) from the angles, normalised (`docs/model.md` §4.2).
    /// The cosines are `libm::cos`'s bits (`crate::trig::cos_moderate`); an angle beyond
    /// ±`crate::trig::MAX_ANGLE_DEG` is refused ([`ParamsError::AngleOutOfRange`]).
    pub fn sensing_directions(&self) -> Result<(RowMajor3, Normalisation), ParamsError> {
        let flat = self.installation_angles_deg.iter().flatten().copied();
        if !all_finite(flat) {
            return Err(ParamsError::NonFinite);
        }
        let mut a = [[0.0; 3]; 3];
        let mut row_norms = [0.0; 3];
        for i in 0..3 {
            let mut raw = [0.0; 3];
            for j in 0..3 {
                let deg = self.installation_angles_deg[i][j];
                raw[j] = crate::trig::cos_moderate(deg.to_radians())
                    .filter(|_| libm::fabs(deg) <= crate::trig::MAX_ANGLE_DEG)
                    .ok_or(ParamsError::AngleOutOfRange { axis: i as u8 })?;
            }
            let n = linalg::norm(&raw);
            if n < 1e-9 {
                return Err(ParamsError::DegenerateAxis { axis: i as u8 });
            }
            row_norms[i] = n;
            a[i] = raw.map(|c| c / n);
        }
        Ok((a, Normalisation { row_norms }))
    }

    /// The fitted form `M = K·A`, `u0` (normalising `A`'s rows).
    pub fn to_fitted(&self) -> Result<(FittedStatic, Normalisation), ParamsError> {
        let finite = all_finite(
            self.zero_bias_out
                .iter()
                .chain(&self.scale_out_per_g)
                .copied(),
        );
        if !finite {
            return Err(ParamsError::NonFinite);
        }
        let (a, normalisation) = self.sensing_directions()?;
        for (i, k) in self.scale_out_per_g.iter().enumerate() {
            if libm::fabs(*k) < 1e-12 {
                return Err(ParamsError::DegenerateAxis { axis: i as u8 });
            }
        }
        let m = core::array::from_fn(|i| a[i].map(|c| c * self.scale_out_per_g[i]));
        Ok((
            FittedStatic {
                output_unit: self.output_unit,
                m_out_per_g: m,
                zero_bias_out: self.zero_bias_out,
            },
            normalisation,
        ))
    }
}

impl FittedStatic {
    /// `k_i = ‖row_i(M)‖` and `a_i = row_i(M)/k_i` (`docs/model.md` §4.2).
    pub fn decompose(&self) -> Result<([f64; 3], RowMajor3), ParamsError> {
        if !all_finite(
            self.m_out_per_g
                .iter()
                .flatten()
                .chain(&self.zero_bias_out)
                .copied(),
        ) {
            return Err(ParamsError::NonFinite);
        }
        let mut k = [0.0; 3];
        let mut a = [[0.0; 3]; 3];
        for i in 0..3 {
            k[i] = linalg::norm(&self.m_out_per_g[i]);
            if k[i] < 1e-12 {
                return Err(ParamsError::DegenerateAxis { axis: i as u8 });
            }
            a[i] = self.m_out_per_g[i].map(|c| c / k[i]);
        }
        Ok((k, a))
    }

    /// The paper's form: `θ_ij = acos(a_ij)` in degrees.
    pub fn to_paper(&self) -> Result<StaticParams, ParamsError> {
        let (k, a) = self.decompose()?;
        let angles = a.map(|row| row.map(|c| libm::acos(c.clamp(-1.0, 1.0)).to_degrees()));
        Ok(StaticParams {
            output_unit: self.output_unit,
            zero_bias_out: self.zero_bias_out,
            scale_out_per_g: k,
            installation_angles_deg: angles,
        })
    }
}

/// Lever arms of the three sensing points (paper Table 3), relative to the reference point O.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct LeverArms {
    /// Row `i` = `r_i`, position of accelerometer `i`'s sensing point relative to O, body axes, metres.
    pub r_m: RowMajor3,
}

impl LeverArms {
    /// The same sensing points seen from a new origin at `new_origin_m` (in the current frame):
    /// `r_i' = r_i − o`. Rotations measure `r_i − p` for the table centre p (`docs/model.md` §4.5), so this is
    /// how an estimate made about the table centre is moved to the reference the user wants.
    pub fn re_referenced(&self, new_origin_m: [f64; 3]) -> LeverArms {
        LeverArms {
            r_m: self
                .r_m
                .map(|r| core::array::from_fn(|j| r[j] - new_origin_m[j])),
        }
    }

    /// Centroid of the three sensing points.
    pub fn centroid_m(&self) -> [f64; 3] {
        core::array::from_fn(|j| (self.r_m[0][j] + self.r_m[1][j] + self.r_m[2][j]) / 3.0)
    }
}

/// Which point the compensated specific force refers to (`docs/model.md` §4.5). The lever arms in a
/// [`Calibration`] are always relative to this point.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
pub enum ReferencePoint {
    /// The point of the body on the table's spin axis during calibration (the paper's assumption p = 0).
    TableAxis,
    /// The centroid of the three sensing points (free of the table's centre: only `r_i − r_j` are used).
    Centroid,
    /// A point the user gave, in body axes relative to the table-axis point, metres.
    BodyPoint {
        /// Its position relative to the table-axis point, body axes, metres.
        offset_m: [f64; 3],
    },
}

/// A complete calibration: what the host estimates and the device applies.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Biases, scale factors and installation angles.
    pub statics: StaticParams,
    /// Sensing-point positions relative to `reference`.
    pub lever_arms: LeverArms,
    /// What the lever arms are relative to.
    pub reference: ReferencePoint,
    /// Local gravity used to express the output in m/s², m/s².
    pub gravity_m_s2: f64,
    /// The gyro's correction `w = G·ω_body + b` (docs/model.md §8); `None`: a perfect gyro.
    #[serde(default)]
    pub gyro: Option<GyroCorrection>,
    /// How the zero biases, scale factors and gyro bias move with temperature (docs/model.md §9);
    /// `None`: constant.
    #[serde(default)]
    pub temperature: Option<TemperatureModel>,
}

/// The paper's unit (Table 1 and Table 3; `reference/paper-unit.toml`, checked by a test): volts,
/// lever arms about the table axis, standard gravity. The default truth of every simulator.
pub const PAPER_UNIT: Calibration = Calibration {
    statics: StaticParams {
        output_unit: OutputUnit::Volts,
        zero_bias_out: [2.405098, 2.380978, 2.435503],
        scale_out_per_g: [0.39496, 0.39808, 0.40024],
        installation_angles_deg: [
            [0.75997, 90.71425, 89.74038],
            [89.25516, 0.74486, 90.5630],
            [90.52202, 89.17706, 0.97456],
        ],
    },
    lever_arms: LeverArms {
        r_m: [
            [-0.00834, -0.00042, -0.00132],
            [-0.00256, -0.00893, -0.00026],
            [-0.00060, -0.00050, -0.00824],
        ],
    },
    reference: ReferencePoint::TableAxis,
    gravity_m_s2: crate::STANDARD_GRAVITY_M_S2,
    gyro: None,
    temperature: None,
};

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The paper's unit, read from the reference file (independent truth for the tests).
    pub fn paper_unit() -> Calibration {
        #[derive(serde::Deserialize)]
        struct File {
            g_m_s2: f64,
            #[serde(rename = "static")]
            statics: Static,
            dynamic: Dynamic,
        }
        #[derive(serde::Deserialize)]
        struct Static {
            zero_bias_v: [f64; 3],
            scale_v_per_g: [f64; 3],
            installation_angles_deg: RowMajor3,
        }
        #[derive(serde::Deserialize)]
        struct Dynamic {
            lever_arms_m: RowMajor3,
        }
        let text = include_str!("../../reference/paper-unit.toml");
        let f: File = toml::from_str(text).expect("reference file parses");
        Calibration {
            statics: StaticParams {
                output_unit: OutputUnit::Volts,
                zero_bias_out: f.statics.zero_bias_v,
                scale_out_per_g: f.statics.scale_v_per_g,
                installation_angles_deg: f.statics.installation_angles_deg,
            },
            lever_arms: LeverArms {
                r_m: f.dynamic.lever_arms_m,
            },
            reference: ReferencePoint::TableAxis,
            gravity_m_s2: f.g_m_s2,
            gyro: None,
            temperature: None,
        }
    }

    /// The `[expected]` table of the reference file.
    #[derive(serde::Deserialize)]
    pub struct Expected {
        pub x_up_bias_scale_only_g: [f64; 3],
        pub x_up_spin_error_mg_100dps: [f64; 3],
        pub x_up_spin_error_mg_200dps: [f64; 3],
        pub k_a_g_per_v: RowMajor3,
        pub nabla_b_g: [f64; 3],
    }

    pub fn expected() -> Expected {
        #[derive(serde::Deserialize)]
        struct File {
            expected: Expected,
        }
        let f: File = toml::from_str(include_str!("../../reference/paper-unit.toml")).unwrap();
        f.expected
    }

    #[test]
    fn reference_copy_matches_shared_reference_when_present() {
        // The repo carries a copy so that it builds alone; when the team's shared/ is beside it, they agree.
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../shared/reference/paper-unit.toml"
        );
        if let Ok(original) = std::fs::read_to_string(path) {
            assert_eq!(original, include_str!("../../reference/paper-unit.toml"));
        }
    }

    #[test]
    fn the_built_in_paper_unit_is_the_reference_file() {
        assert_eq!(PAPER_UNIT, paper_unit());
    }

    #[test]
    fn table1_row2_is_flagged_and_normalised() {
        let cal = paper_unit();
        let (_, norm) = cal.statics.sensing_directions().unwrap();
        assert!(
            (norm.row_norms[1] - 1.0000483).abs() < 2e-7,
            "{:?}",
            norm.row_norms
        );
        assert!(norm.needs_warning());
        // The diagonal angle implied by the off-diagonal ones (docs/model.md §4.2): ≈ 0.934°, not 0.745°.
        let back = cal.statics.to_fitted().unwrap().0.to_paper().unwrap();
        assert!((back.installation_angles_deg[1][1] - 0.934).abs() < 1e-3);
    }

    #[test]
    fn fitted_round_trip_is_exact_for_consistent_angles() {
        let cal = paper_unit();
        let fitted = cal.statics.to_fitted().unwrap().0;
        let paper = fitted.to_paper().unwrap();
        let again = paper.to_fitted().unwrap();
        assert!(!again.1.needs_warning());
        for i in 0..3 {
            for j in 0..3 {
                assert!((again.0.m_out_per_g[i][j] - fitted.m_out_per_g[i][j]).abs() < 1e-12);
            }
        }
        assert_eq!(paper.scale_out_per_g, fitted.decompose().unwrap().0);
    }

    #[test]
    fn degenerate_inputs_are_typed_errors() {
        let mut s = paper_unit().statics;
        s.scale_out_per_g[2] = 0.0;
        assert_eq!(
            s.to_fitted().unwrap_err(),
            ParamsError::DegenerateAxis { axis: 2 }
        );
        s.scale_out_per_g[2] = f64::NAN;
        assert_eq!(s.to_fitted().unwrap_err(), ParamsError::NonFinite);
        let mut s = paper_unit().statics;
        s.installation_angles_deg[0] = [90.0, 90.0, 90.0];
        assert_eq!(
            s.to_fitted().unwrap_err(),
            ParamsError::DegenerateAxis { axis: 0 }
        );
        // The largest accepted angle, and just beyond it.
        let mut s = paper_unit().statics;
        s.installation_angles_deg[2][1] = -crate::trig::MAX_ANGLE_DEG;
        assert!(s.to_fitted().is_ok());
        s.installation_angles_deg[2][1] = crate::trig::MAX_ANGLE_DEG * 1.000_001;
        assert_eq!(
            s.to_fitted().unwrap_err(),
            ParamsError::AngleOutOfRange { axis: 2 }
        );
        s.installation_angles_deg[2][1] = 1e300;
        assert_eq!(
            s.to_fitted().unwrap_err(),
            ParamsError::AngleOutOfRange { axis: 2 }
        );
    }

    #[test]
    fn re_referencing_to_the_centroid_zeroes_the_centroid() {
        let arms = paper_unit().lever_arms;
        let c = arms.re_referenced(arms.centroid_m()).centroid_m();
        assert!(c.iter().all(|v| v.abs() < 1e-18));
    }
}
