//! The paper's unit (`reference/paper-unit.toml`, Tables 1 and 3): the QEMU board's virtual unit and
//! the source of the on-target test vectors. A PC test checks these constants against the file.

use shared::{Calibration, TemperatureModel, UnitId};

/// Unit identifier of the QEMU board's virtual unit (reported by `Identify`; blobs are bound to it).
pub const QEMU_UNIT_ID: UnitId = UnitId(*b"QEMU-AN386-1");

/// Standard gravity of the reference file, m/s².
pub const GRAVITY_M_S2: f64 = 9.80665;

/// Table 1 and Table 3 of the paper as a [`Calibration`] (volts; lever arms about the table axis):
/// `shared::params::PAPER_UNIT`, which a shared test checks against the reference file.
pub fn calibration() -> Calibration {
    shared::params::PAPER_UNIT
}

/// The paper's unit with the MEMS-sized tempcos of `host/units/thermal-mems.toml` (bias 0.25..0.35
/// mg/°C plus a quadratic term, scale 100..150 ppm/°C), valid over −20..60 °C as a soak calibration
/// would make it: the heated virtual unit of the temperature tests, and its calibration. A PC test
/// checks the coefficients against the file.
pub fn hot_calibration() -> Calibration {
    let mut cal = calibration();
    cal.temperature = Some(TemperatureModel {
        reference_c: 25.0,
        valid_range_c: [-20.0, 60.0],
        zero_bias_out_per_c: [
            [1.18488e-4, 3.9496e-7, 0.0],
            [-9.952e-5, -3.18464e-7, 0.0],
            [1.40084e-4, 2.40144e-7, 0.0],
        ],
        scale_rel_per_c: [[1.5e-4, 0.0, 0.0], [-1.2e-4, 0.0, 0.0], [1.0e-4, 0.0, 0.0]],
        gyro_bias_rad_s_per_c: None,
    });
    cal
}

#[cfg(test)]
mod tests {
    use super::*;

    /// All numbers of a TOML section's arrays, in order (the file is simple: `key = [..]` lines).
    fn numbers(section: &str, key: &str) -> std::vec::Vec<f64> {
        numbers_in(
            include_str!("../../reference/paper-unit.toml"),
            section,
            key,
        )
    }

    #[test]
    fn hot_unit_matches_the_host_unit_file() {
        let text = include_str!("../../host/units/thermal-mems.toml");
        let th = hot_calibration().temperature.unwrap();
        let flat = |m: [[f64; 3]; 3]| m.iter().flatten().copied().collect::<std::vec::Vec<_>>();
        assert_eq!(
            numbers_in(text, "temperature", "zero_bias_out_per_c"),
            flat(th.zero_bias_out_per_c)
        );
        assert_eq!(
            numbers_in(text, "temperature", "scale_rel_per_c"),
            flat(th.scale_rel_per_c)
        );
    }

    fn numbers_in(text: &str, section: &str, key: &str) -> std::vec::Vec<f64> {
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
