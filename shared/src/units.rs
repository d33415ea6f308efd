//! Quantities with their unit and frame in the type and field names.
//!
//! Body axes are the unit's orthogonal b-frame; sensor axes are the three (non-orthogonal) sensing
//! directions `a_i` (`docs/model.md` §1). Each type is generic over the float so that the
//! host can use `f64` and the device `f32` (the default) with the same names.

use serde::{Deserialize, Serialize};

/// The three accelerometer outputs `U = (u_x, u_y, u_z)`, one per *sensor* axis, in the calibration's
/// output unit ([`crate::OutputUnit`]: volts or ADC counts).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SensorOutputs<T = f32> {
    /// Output of accelerometer x, y, z in the output unit.
    pub raw: [T; 3],
}

/// Angular rate `ω` of the body, in body axes, rad/s.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BodyRate<T = f32> {
    /// ω in body axes, rad/s.
    pub rad_s: [T; 3],
}

/// Angular acceleration `ω̇` of the body, in body axes, rad/s².
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BodyAngularAccel<T = f32> {
    /// ω̇ in body axes, rad/s².
    pub rad_s2: [T; 3],
}

/// Specific force (`docs/model.md` §5: +1 g up at rest), in body axes, m/s².
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BodySpecificForce<T = f32> {
    /// Specific force in body axes, m/s².
    pub m_s2: [T; 3],
}

impl BodySpecificForce<f64> {
    /// The same force in units of `gravity_m_s2` (host-side helper; the device never divides).
    pub fn in_g(&self, gravity_m_s2: f64) -> [f64; 3] {
        self.m_s2.map(|v| v / gravity_m_s2)
    }
}

impl BodySpecificForce<f32> {
    /// Widened to `f64`.
    pub fn to_f64(&self) -> BodySpecificForce<f64> {
        BodySpecificForce {
            m_s2: self.m_s2.map(f64::from),
        }
    }
}

/// Identifier of one physical accelerometer unit (the STM32's 96-bit unique device ID on the board,
/// a fixed value on the simulators). A calibration is bound to it (`blob`).
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Hash,
    Serialize,
    Deserialize,
    postcard::experimental::max_size::MaxSize,
)]
pub struct UnitId(pub [u8; 12]);

impl core::fmt::Display for UnitId {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        for b in self.0 {
            write!(f, "{b:02x}")?;
        }
        Ok(())
    }
}

impl UnitId {
    /// Parses the 24-hex-digit form written by `Display`.
    pub fn parse_hex(s: &str) -> Option<UnitId> {
        let bytes = s.trim().as_bytes();
        if bytes.len() != 24 {
            return None;
        }
        let mut out = [0u8; 12];
        for (i, pair) in bytes.chunks(2).enumerate() {
            let hi = (pair[0] as char).to_digit(16)?;
            let lo = (pair[1] as char).to_digit(16)?;
            out[i] = (hi * 16 + lo) as u8;
        }
        Some(UnitId(out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_id_hex_round_trip() {
        let id = UnitId([0, 1, 2, 0xab, 0xcd, 0xef, 9, 8, 7, 6, 5, 0xff]);
        let s = std::format!("{id}");
        assert_eq!(s, "000102abcdef0908070605ff");
        assert_eq!(UnitId::parse_hex(&s), Some(id));
        assert_eq!(UnitId::parse_hex("00"), None);
        assert_eq!(UnitId::parse_hex("zz0102abcdef090807060500"), None);
    }
}
