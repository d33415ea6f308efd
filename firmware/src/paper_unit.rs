//! The paper's unit (`reference/paper-unit.toml`, Tables 1 and 3): the QEMU board's virtual unit and
//! the source of the on-target test vectors. A PC test checks these constants against the file.

use shared::{Calibration, GyroCorrection, TemperatureModel, UnitId};

/// Unit identifier of the QEMU board's virtual unit (reported by `Identify`; blobs are bound to it).
pub const QEMU_UNIT_ID: UnitId = UnitId(*b"QEMU-AN386-1");

/// Standard gravity of the reference file, m/s².
pub const GRAVITY_M_S2: f64 = 9.80665;

/// Table 1 and Table 3 of the paper as a [`Calibration`] (volts; lever arms about the table axis):
/// `shared::params::PAPER_UNIT`, which a shared test checks against the reference file.
pub fn calibration() -> Calibration {
    shared::params::PAPER_UNIT
}

/// A typical MEMS gyro's errors (0.5 % scale, 0.5° misalignment, 0.5 °/s bias; docs/model.md §8): the
/// gyro of the on-target test vectors and the benchmark.
pub fn typical_gyro() -> GyroCorrection {
    let m = 0.5f64.to_radians();
    let b = 0.5f64.to_radians();
    GyroCorrection {
        matrix: [[1.005, m, -m], [-m, 0.995, m], [m, -m, 1.005]],
        bias_rad_s: [b, -b, 0.6 * b],
    }
}

/// A thermal model of the size a MEMS accelerometer shows (docs/model.md §9): zero-bias tempco
/// 0.3 mg/°C at the paper's 0.4 V/g (1.2·10⁻⁴ V/°C) with a quadratic term, scale tempco 150 ppm/°C,
/// gyro bias drift 0.01 °/s/°C, referred to 25 °C and valid over −20..60 °C.
pub fn typical_thermal_model() -> TemperatureModel {
    let gyro_drift = 0.01f64.to_radians();
    TemperatureModel {
        reference_c: 25.0,
        valid_range_c: [-20.0, 60.0],
        zero_bias_out_per_c: [
            [1.2e-4, 1.5e-6, 0.0],
            [-1.1e-4, 1.0e-6, 0.0],
            [1.3e-4, -1.2e-6, 0.0],
        ],
        scale_rel_per_c: [[150e-6, 0.0, 0.0], [-140e-6, 0.0, 0.0], [160e-6, 0.0, 0.0]],
        gyro_bias_rad_s_per_c: Some([
            [gyro_drift, 0.0, 0.0],
            [-gyro_drift, 0.0, 0.0],
            [0.5 * gyro_drift, 0.0, 0.0],
        ]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// All numbers of a TOML section's arrays, in order (the file is simple: `key = [..]` lines).
    fn numbers(section: &str, key: &str) -> std::vec::Vec<f64> {
        let text = include_str!("../../reference/paper-unit.toml");
        let start = text.find(&std::format!("[{section}]")).unwrap();
        let body = &text[start..];
        let k = body.find(&std::format!("{key} = [")).unwrap();
        let mut depth = 0;
        let mut out = std::string::String::new();
        for ch in body[k..].chars().skip(key.len() + 4) {
            match ch {
                '[' => depth += 1,
                ']' if depth == 0 => break,
                ']' => depth -= 1,
                _ => out.push(ch),
            }
        }
        out.lines()
            .map(|l| l.split('#').next().unwrap())
            .flat_map(|l| l.split(','))
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(|s| s.parse().unwrap())
            .collect()
    }

    #[test]
    fn constants_match_the_reference_file() {
        let c = calibration();
        assert_eq!(
            numbers("static", "zero_bias_v"),
            c.statics.zero_bias_out.to_vec()
        );
        assert_eq!(
            numbers("static", "scale_v_per_g"),
            c.statics.scale_out_per_g.to_vec()
        );
        let angles: std::vec::Vec<f64> = c
            .statics
            .installation_angles_deg
            .iter()
            .flatten()
            .copied()
            .collect();
        assert_eq!(numbers("static", "installation_angles_deg"), angles);
        let arms: std::vec::Vec<f64> = c.lever_arms.r_m.iter().flatten().copied().collect();
        assert_eq!(numbers("dynamic", "lever_arms_m"), arms);
        assert!(include_str!("../../reference/paper-unit.toml").contains("g_m_s2 = 9.80665"));
    }
}
