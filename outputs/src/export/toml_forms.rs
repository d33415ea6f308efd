//! The conversions of [`super::convert`] as TOML (`--format plain|fusion|all`), each with a comment
//! header that states its convention.

use super::{convert, Conversions, ExportError, ExportFormat};
use shared::Calibration;

const HEADER_PLAIN: &str = "\
# Plain matrices (paper eq. 16): f_b[g] = K_A·U − ∇_b − f_L^b, with f_L^b = K_A·(K d),
# (K d)_i = row_i(K_A⁻¹)·(W r_i)/g and W = [ω̇×] + [ω×]². K_A in g per output unit, row-major;
# ∇_b in g; lever_arms_m row i = r_i (m, body axes, from the reference point).
";
const HEADER_FUSION: &str = "\
# x-io Fusion FusionModelInertial: f[g] = misalignment·((U − offset) ∘ sensitivity).
# misalignment = A⁻¹ (row-major), sensitivity = 1/k_i (g per output unit), offset = u0. No lever arms:
# static compensation only.
";
const HEADER_KALIBR: &str = "\
# Kalibr-style scale-misalignment-size-effect model, general form, in the body frame:
# u_i = row_i(m)·(f + W r_i) + bias_i, m = K·A/g (output unit per m/s², row-major), bias = u0,
# rx, ry, rz = sensing points of the x, y, z accelerometers (m). Solve for f (m/s²).
";

/// The calibration's conversions as TOML; `format` is one of `Plain`, `Fusion`, `All` (any other
/// format gives all three).
pub fn render(calibration: &Calibration, format: ExportFormat) -> Result<String, ExportError> {
    let c: Conversions = convert(calibration)?;
    let ser = |r: Result<String, toml::ser::Error>| r.map_err(ExportError::Toml);
    Ok(match format {
        ExportFormat::Plain => format!("{HEADER_PLAIN}{}", ser(toml::to_string(&c.plain))?),
        ExportFormat::Fusion => format!("{HEADER_FUSION}{}", ser(toml::to_string(&c.fusion))?),
        _ => format!(
            "{HEADER_PLAIN}{HEADER_FUSION}{HEADER_KALIBR}{}",
            ser(toml::to_string(&c))?
        ),
    })
}

/// [`render`] with the lever-arm components the calibration's plan did not determine
/// (`lever_arms_observable = false` in `[uncertainty]`) written as `nan` and named in a comment: a
/// consumer must not take an undetermined component (often exactly 0) for a measurement.
pub(crate) fn render_marked(
    calibration: &Calibration,
    format: ExportFormat,
    observable: Option<&[[bool; 3]; 3]>,
) -> Result<String, ExportError> {
    let mut cal = *calibration;
    let mut names = Vec::new();
    if let Some(obs) = observable {
        for i in 0..3 {
            for j in 0..3 {
                if !obs[i][j] {
                    cal.lever_arms.r_m[i][j] = f64::NAN;
                    names.push(format!("r{}{}", i + 1, shared::params::axis_name(j)));
                }
            }
        }
    }
    let text = super::temperature_not_held(calibration, "these forms") + &render(&cal, format)?;
    if names.is_empty() {
        return Ok(text);
    }
    Ok(format!(
        "# NOT DETERMINED by the calibration's plan, written as nan (not a measurement): {}\n{text}",
        names.join(", ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::{FusionStyle, PlainMatrices};
    use estimator::unit_file::UnitFile;
    use shared::forward::{BodyMotion, ForwardModel};
    use shared::{BodyAngularAccel, BodyRate, BodySpecificForce};

    /// Each exported form, read back from its TOML, compensates like the device's compensator.
    #[test]
    fn every_exported_form_reads_back_and_compensates_the_same() {
        let cal = UnitFile::paper_unit().to_calibration().unwrap();
        let plain: PlainMatrices =
            toml::from_str(&render(&cal, ExportFormat::Plain).unwrap()).unwrap();
        let fusion: FusionStyle =
            toml::from_str(&render(&cal, ExportFormat::Fusion).unwrap()).unwrap();
        let all: Conversions = toml::from_str(&render(&cal, ExportFormat::All).unwrap()).unwrap();
        assert_eq!(all, convert(&cal).unwrap());
        assert_eq!((&plain, &fusion), (&all.plain, &all.fusion));
        let kalibr = all.kalibr;
        let model = ForwardModel::new(&cal).unwrap();
        let g = cal.gravity_m_s2;
        for k in 0..50 {
            let x = k as f64;
            let f = [9.0 * (0.3 * x).sin(), -4.0 + 0.1 * x, 9.8 * (0.2 * x).cos()];
            let motion = BodyMotion {
                f_o: BodySpecificForce { m_s2: f },
                omega: BodyRate {
                    rad_s: [3.0 * (0.5 * x).cos(), 1.0, -0.02 * x],
                },
                omega_dot: BodyAngularAccel {
                    rad_s2: [0.0, 4.0 * (0.1 * x).sin(), 2.0],
                },
            };
            let u = model.outputs(&motion).raw;
            let (w, wd) = (motion.omega.rad_s, motion.omega_dot.rad_s2);
            let p = plain.compensate(u, w, wd);
            let kk = kalibr.compensate(u, w, wd);
            let still = BodyMotion {
                omega: BodyRate::default(),
                omega_dot: BodyAngularAccel::default(),
                ..motion
            };
            let fu = fusion
                .compensate_static_g(model.outputs(&still).raw)
                .map(|v| v * g);
            for j in 0..3 {
                assert!(
                    (p[j] - f[j]).abs() < 1e-9,
                    "plain {j}: {} vs {}",
                    p[j],
                    f[j]
                );
                assert!((kk[j] - f[j]).abs() < 1e-9, "kalibr {j}");
                assert!((fu[j] - f[j]).abs() < 1e-9, "fusion {j}");
            }
        }
    }
}
