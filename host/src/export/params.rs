//! PX4 and ArduPilot accelerometer parameters.
//!
//! Both autopilots correct each axis alone, in the sensor frame, before their board rotation:
//! PX4 `Correct()`: `a = R·((a_m − CAL_ACC0_xOFF) ∘ CAL_ACC0_xSCALE)`; ArduPilot
//! `_rotate_and_correct_accel`: `a = R·((a_m − INS_ACCOFFS) ∘ INS_ACCSCAL)`, with `a_m` the driver's
//! reading in m/s² (here `a_m = c·U`, `c` the driver's scale, [`super::ExportInput::driver_scale`]).
//! Our inverse model is `f = g·(K·A)⁻¹·(U − u0)` (`docs/model.md` §3), so the closest per-axis form
//! keeps the diagonal of `g·(K·A)⁻¹`: `offset_i = c·u0_i`, `scale_i = g·[(K·A)⁻¹]_ii / c`.
//!
//! What neither can hold, and each file says so with the size of what is dropped: the
//! cross-axis terms of `(K·A)⁻¹` (misalignment; bounded here by the largest row sum of the dropped
//! terms at 1 g), the per-axis sensing points (size effect) and the lever-arm compensation, the device
//! id the parameters belong to (the autopilot's own id of the sensor, which only the vehicle knows),
//! and any temperature model (PX4's `TC_A*`, ArduPilot's `INS_TCAL*` are separate calibrations).

use super::{ExportError, ExportInput};
use shared::linalg;
use std::fmt::Write as _;

/// Per-axis offsets (m/s²) and scales for an autopilot, and what the per-axis form drops.
#[derive(Clone, Debug, PartialEq)]
pub struct PerAxis {
    /// Offsets, m/s², in the driver's reading.
    pub offset_m_s2: [f64; 3],
    /// Scales (dimensionless).
    pub scale: [f64; 3],
    /// Largest error of the dropped cross-axis terms at 1 g on any axis, g.
    pub dropped_cross_axis_g: f64,
}

/// The per-axis form of `input`.
pub fn per_axis(input: &ExportInput<'_>) -> Result<PerAxis, ExportError> {
    let (fitted, _) = input.cal.statics.to_fitted()?;
    let inv = linalg::inverse(&fitted.m_out_per_g).ok_or(ExportError::Params(
        shared::params::ParamsError::DegenerateAxis { axis: 0 },
    ))?;
    let c = input.driver_scale();
    let g = input.cal.gravity_m_s2;
    // (K·A)⁻¹ = D + E with D its diagonal; dropping E leaves E·(U − u0) = E·D⁻¹·f/g per axis.
    let dropped = (0..3)
        .map(|i| {
            (0..3)
                .filter(|&j| j != i)
                .map(|j| (inv[i][j] / inv[j][j]).abs())
                .sum::<f64>()
        })
        .fold(0.0, f64::max);
    Ok(PerAxis {
        offset_m_s2: fitted.zero_bias_out.map(|v| v * c),
        scale: std::array::from_fn(|i| g * inv[i][i] / c),
        dropped_cross_axis_g: dropped,
    })
}

fn caveats(w: &mut String, input: &ExportInput<'_>, p: &PerAxis, tool: &str) {
    let c = input.driver_scale();
    let _ = writeln!(
        w,
        "# Accelerometer calibration for {tool} (host export). Assumes the driver reports a_m = c*U m/s^2\n\
         # with c = {c:?} m/s^2 per output unit, sensor axes = our body axes (board rotation: none).\n\
         # NOT HELD by these parameters (apply them elsewhere, or accept the error):\n\
         # - cross-axis (misalignment) terms: up to {:.3} mg at 1 g on the worst axis;\n\
         # - the per-axis sensing points and the lever-arm (size-effect) compensation;\n\
         # - the device id of the sensor (set it on the vehicle: UNDETERMINED here);\n\
         # - any temperature model.",
        p.dropped_cross_axis_g * 1e3
    );
}

/// Values as the autopilots store them (IEEE single precision), shortest form.
fn f32_text(v: f64) -> String {
    format!("{}", v as f32)
}

/// A QGroundControl parameter file for PX4 (`vehicle component name value type`, type 9 = float).
pub fn render_px4(input: &ExportInput<'_>) -> Result<String, ExportError> {
    let p = per_axis(input)?;
    let mut s = String::new();
    caveats(&mut s, input, &p, "PX4");
    let _ = writeln!(
        s,
        "# CAL_ACC0_ID: UNDETERMINED (PX4's device id of this accelerometer); set it before loading.\n\
         #\n# Vehicle-Id\tComponent-Id\tName\tValue\tType"
    );
    for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
        let _ = writeln!(
            s,
            "1\t1\tCAL_ACC0_{axis}OFF\t{}\t9",
            f32_text(p.offset_m_s2[i])
        );
    }
    for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
        let _ = writeln!(s, "1\t1\tCAL_ACC0_{axis}SCALE\t{}\t9", f32_text(p.scale[i]));
    }
    Ok(s)
}

/// An ArduPilot parameter file (`NAME,VALUE`, as Mission Planner saves and loads).
pub fn render_ardupilot(input: &ExportInput<'_>) -> Result<String, ExportError> {
    let p = per_axis(input)?;
    let mut s = String::new();
    caveats(&mut s, input, &p, "ArduPilot");
    let _ = writeln!(
        s,
        "# INS_ACCSCAL_* must lie in 0.8..1.2 for ArduPilot to accept them."
    );
    for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
        let _ = writeln!(s, "INS_ACCOFFS_{axis},{}", f32_text(p.offset_m_s2[i]));
    }
    for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
        let _ = writeln!(s, "INS_ACCSCAL_{axis},{}", f32_text(p.scale[i]));
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::unit_file::UnitFile;
    use shared::forward::{BodyMotion, ForwardModel};
    use shared::{BodyAngularAccel, BodyRate, BodySpecificForce};
    use std::collections::HashMap;

    /// Reads `name → value` from either file format, the way each loader splits a line.
    fn parse(text: &str, px4: bool) -> HashMap<String, f64> {
        text.lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
            .map(|l| {
                if px4 {
                    let f: Vec<&str> = l.split('\t').collect();
                    assert_eq!(f.len(), 5, "{l}");
                    assert_eq!(f[4], "9");
                    (f[2].to_string(), f[3].parse().unwrap())
                } else {
                    let (n, v) = l.split_once(',').unwrap();
                    (n.to_string(), v.parse().unwrap())
                }
            })
            .collect()
    }

    #[test]
    fn both_files_parse_and_correct_within_the_stated_bound() {
        let unit = UnitFile::paper_unit();
        let cal = unit.to_calibration().unwrap();
        let input = ExportInput::for_tests(&unit, cal);
        let p = per_axis(&input).unwrap();
        let c = input.driver_scale();
        let model = ForwardModel::new(&cal).unwrap();
        let g = cal.gravity_m_s2;
        for (px4, text) in [
            (true, render_px4(&input).unwrap()),
            (false, render_ardupilot(&input).unwrap()),
        ] {
            assert!(text.contains("UNDETERMINED"));
            let v = parse(&text, px4);
            let (off, scl) = if px4 {
                (
                    ["CAL_ACC0_XOFF", "CAL_ACC0_YOFF", "CAL_ACC0_ZOFF"],
                    ["CAL_ACC0_XSCALE", "CAL_ACC0_YSCALE", "CAL_ACC0_ZSCALE"],
                )
            } else {
                (
                    ["INS_ACCOFFS_X", "INS_ACCOFFS_Y", "INS_ACCOFFS_Z"],
                    ["INS_ACCSCAL_X", "INS_ACCSCAL_Y", "INS_ACCSCAL_Z"],
                )
            };
            assert_eq!(v.len(), 6);
            let mut worst_g = 0.0f64;
            for up in [
                [1.0, 0.0, 0.0],
                [0.0, -1.0, 0.0],
                [0.0, 0.0, 1.0],
                [0.6, 0.0, -0.8],
            ] {
                let f = up.map(|x| x * g);
                let u = model
                    .outputs(&BodyMotion {
                        f_o: BodySpecificForce { m_s2: f },
                        omega: BodyRate::default(),
                        omega_dot: BodyAngularAccel::default(),
                    })
                    .raw;
                for i in 0..3 {
                    let corrected = (c * u[i] - v[off[i]]) * v[scl[i]];
                    worst_g = worst_g.max((corrected - f[i]).abs() / g);
                }
            }
            // The stated bound holds (plus the f32 rounding of the stored values), and is not vacuous:
            // the paper unit's ~1° misalignments cost tens of mg in this form.
            assert!(
                worst_g <= p.dropped_cross_axis_g + 1e-5,
                "{worst_g} > {}",
                p.dropped_cross_axis_g
            );
            assert!(
                worst_g > 0.3 * p.dropped_cross_axis_g && worst_g > 5e-3,
                "{worst_g}"
            );
        }
    }
}
